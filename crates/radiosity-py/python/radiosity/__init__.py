"""Diffuse global illumination and view factors by the radiosity method, from Python.

The engine is the Rust library `radiosity`; this package drives it and hands results to NumPy.
Meshing, form factors, solves and rendering run with the GIL released.

    import radiosity
    s = radiosity.solve(radiosity.builtin("cornell"), patches=2000)
    s.radiosity          # (N, 3) NumPy array
    s.render(256, 256)   # (256, 256, 3) float32 radiance
"""

from __future__ import annotations

from typing import Any, Callable, Optional, Tuple, Union

import numpy as np

from . import _native
from ._native import Scene, Solution, builtin, load, methods

__all__ = [
    "Scene",
    "Solution",
    "builtin",
    "load",
    "solve",
    "form_factors",
    "solve_system",
    "methods",
    "thermal",
]

Progress = Optional[Callable[[str, int, int], Any]]


def solve(
    scene: Scene,
    solver: str = "progressive",
    patches: int = 10000,
    tolerance: float = 0.01,
    seed: int = 1,
    threads: Optional[int] = None,
    form_factor_method: str = "monte-carlo",
    rays: int = 256,
    max_iterations: Optional[int] = None,
    trace: bool = False,
    progress: Progress = None,
    omega: float = 1.1,
    photons: int = 1000,
    iteration_rays: int = 16,
    gather_rays: int = 0,
    resolution: int = 128,
    samples: int = 16,
    link_error: float = 2e-5,
) -> Solution:
    """Solve `scene` as `radiosity solve` does: about `patches` patches, form factors by
    `form_factor_method` (Monte Carlo rows on demand with `rays` rays for an average shooter;
    `resolution` and `samples` for the projection methods), `solver` until the unshot energy is
    `tolerance` of the emitted energy (`omega` for sor, `photons` for stochastic,
    `iteration_rays` and `gather_rays`, the final gathering's rays per patch, 0 for none, for
    stochastic-jacobi). `solver="hierarchical"` refines elements and links
    instead of meshing (`link_error`; `patches` and the form-factor options are then unused);
    its leaves are the solution's patches. Same seed, same numbers as the CLI.
    `progress(stage, done, total)` is called now and then; an exception it raises, or Ctrl-C,
    stops the solve at its next iteration and is raised."""
    return _native.solve(
        scene,
        solver=solver,
        patches=patches,
        tolerance=tolerance,
        seed=seed,
        threads=threads,
        form_factor_method=form_factor_method,
        rays=rays,
        max_iterations=max_iterations,
        trace=trace,
        progress=progress,
        omega=omega,
        photons=photons,
        iteration_rays=iteration_rays,
        gather_rays=gather_rays,
        resolution=resolution,
        samples=samples,
        link_error=link_error,
    )


def form_factors(
    scene: Scene,
    method: str = "monte-carlo",
    patches: Optional[int] = None,
    faces: bool = False,
    rays: int = 1_000_000,
    resolution: int = 128,
    samples: int = 16,
    seed: int = 1,
    with_areas: bool = False,
):
    """The view-factor matrix F of `scene` (rows per patch, or per input face with
    `faces=True`): a `scipy.sparse.csr_matrix` when SciPy is installed, else the CSR arrays
    `(data, indices, indptr, shape)`. With `with_areas=True`, `(F, areas)`."""
    data, indices, indptr, shape, areas = _native.form_factors_csr(
        scene,
        method=method,
        patches=patches,
        faces=faces,
        rays=rays,
        resolution=resolution,
        samples=samples,
        seed=seed,
    )
    try:
        import scipy.sparse as sp

        f: Any = sp.csr_matrix((data, indices.astype(np.int64), indptr.astype(np.int64)), shape=shape)
    except ImportError:
        f = (data, indices, indptr, shape)
    return (f, areas) if with_areas else f


def _csr(f: Any, n: int) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR arrays (float64 data, int64 indices and indptr) of a SciPy sparse matrix or a dense
    array."""
    if hasattr(f, "tocsr"):
        c = f.tocsr()
        if c.shape != (n, n):
            raise ValueError(f"F: shape {c.shape}; expected ({n}, {n}) for {n} areas")
        return (
            np.asarray(c.data, dtype=np.float64),
            np.asarray(c.indices, dtype=np.int64),
            np.asarray(c.indptr, dtype=np.int64),
        )
    a = np.asarray(f, dtype=np.float64)
    if a.shape != (n, n):
        raise ValueError(f"F: shape {a.shape}; expected ({n}, {n}) for {n} areas")
    rows, cols = np.nonzero(a)
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.add.at(indptr, rows + 1, 1)
    return a[rows, cols], cols.astype(np.int64), np.cumsum(indptr)


def solve_system(
    F: Any,
    area: Any,
    reflectance: Any,
    emission: Any,
    solver: str = "gauss-seidel",
    tolerance: float = 1e-6,
    max_iterations: Optional[int] = None,
    seed: int = 1,
    trace: bool = True,
    progress: Progress = None,
) -> Tuple[np.ndarray, Optional[dict]]:
    """Solve `B = E + diag(ρ) F B` for a matrix you bring (SciPy sparse or dense NumPy, N × N),
    areas (N,), reflectance and emission (N,) or (N, 3). Returns `B` (N, 3) and, with
    `trace=True`, the eq. 22 trace as a dict of arrays (`iteration`, `seconds`, `error`,
    `unshot`)."""
    area = np.ascontiguousarray(area, dtype=np.float64)
    if area.ndim != 1:
        raise ValueError(f"area: shape {area.shape}; expected (N,)")
    data, indices, indptr = _csr(F, area.shape[0])
    return _native.solve_system_csr(
        np.ascontiguousarray(data),
        np.ascontiguousarray(indices),
        np.ascontiguousarray(indptr),
        area,
        np.ascontiguousarray(reflectance, dtype=np.float64),
        np.ascontiguousarray(emission, dtype=np.float64),
        solver=solver,
        tolerance=tolerance,
        max_iterations=max_iterations,
        seed=seed,
        trace=trace,
        progress=progress,
    )


_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048}


def thermal(
    scene: Scene,
    boundaries: Any,
    unit: str = "m",
    environment: float = 0.0,
    enclosure: str = "auto",
    patches: Optional[int] = None,
    max_edge: Optional[float] = None,
    form_factor_method: str = "monte-carlo",
    rays: Optional[int] = None,
    seed: int = 1,
    linear_solver: str = "auto",
    progress: Progress = None,
) -> dict:
    """Radiative heat transfer, as `radiosity thermal`: `boundaries` maps each surface name
    (material, or View3D surface) to a dict with `emissivity` (optional: the scene's own),
    and `temperature` (K) or `flux` (W/m², net leaving) or neither (adiabatic); or it is the
    path of a `bc.csv` (header `name,emissivity,temperature,flux`). `unit` is what a scene
    unit is (m, cm, mm, in, ft); `environment` the surroundings' temperature, K. One patch per
    face unless `patches` or `max_edge`. `linear_solver` is auto, direct (LU), iterative
    (BiCGSTAB) or jacobi. Returns `{"surfaces": {name: {area, emissivity,
    temperature, flux, power}}, "patches": {centre, area, surface, temperature, flux,
    radiosity, irradiation}, "info": {...}}`."""
    if unit not in _UNITS:
        raise ValueError(f"unit '{unit}': one of {', '.join(_UNITS)}")
    if isinstance(boundaries, (str, bytes)) or hasattr(boundaries, "__fspath__"):
        import csv

        with open(boundaries, newline="", encoding="utf-8-sig") as fh:
            rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
        if not rows or [c.strip().lower() for c in rows[0]] != ["name", "emissivity", "temperature", "flux"]:
            raise ValueError(f"{boundaries}: the header must be 'name,emissivity,temperature,flux'")
        num = lambda x: float(x) if x.strip() else None  # noqa: E731
        items = [(r[0].strip(), num(r[1]), num(r[2]), num(r[3])) for r in rows[1:]]
    else:
        items = []
        for name, b in boundaries.items():
            unknown = set(b) - {"emissivity", "temperature", "flux"}
            if unknown:
                raise ValueError(f"boundaries['{name}']: unknown keys {sorted(unknown)}")
            items.append((name, b.get("emissivity"), b.get("temperature"), b.get("flux")))
    return _native.thermal(
        scene,
        items,
        unit=_UNITS[unit],
        environment=environment,
        enclosure=enclosure,
        patches=patches,
        max_edge=max_edge,
        form_factor_method=form_factor_method,
        rays=rays,
        seed=seed,
        linear_solver=linear_solver,
        progress=progress,
    )
