"""Solving a scene: `solve`, which returns a `Solution` (per-patch arrays, report, trace,
pictures)."""

from __future__ import annotations

from typing import Optional

from . import _native
from ._native import Scene, Solution
from ._progress import Progress


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
