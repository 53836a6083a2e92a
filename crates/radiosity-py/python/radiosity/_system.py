"""Solving a linear system you bring: `B = E + diag(ρ) F B` for a SciPy sparse or dense F."""

from __future__ import annotations

from typing import Any, Optional, Tuple

import numpy as np

from . import _native
from ._progress import Progress


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
