"""Radiative heat transfer: `thermal`, with boundary conditions from a dict or a `bc.csv`."""

from __future__ import annotations

from typing import Any, Optional

from . import _native
from ._native import Scene
from ._progress import Progress


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
