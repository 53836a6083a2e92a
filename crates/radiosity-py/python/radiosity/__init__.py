"""Diffuse global illumination and view factors by the radiosity method, from Python.

The engine is the Rust library `radiosity`; this package drives it and hands results to NumPy.
Meshing, form factors, solves and rendering run with the GIL released.

    import radiosity
    s = radiosity.solve(radiosity.builtin("cornell"), patches=2000)
    s.radiosity          # (N, 3) NumPy array
    s.render(256, 256)   # (256, 256, 3) float32 radiance
"""

from . import _native
from ._native import Scene, Solution, builtin, lighting, load, methods, read_photometry
from ._progress import Progress  # the progress callback's type (in __init__.pyi too)
from ._solve import solve
from ._system import solve_system
from ._thermal import thermal
from ._view_factors import form_factors

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
    "lighting",
    "read_photometry",
]

# Documented (help(), pydoc) as the package's own, where they were defined before the split.
for _f in (solve, form_factors, solve_system, thermal):
    _f.__module__ = __name__
del _f
