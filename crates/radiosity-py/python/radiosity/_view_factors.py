"""View factors: the form-factor matrix of a scene, as SciPy CSR when SciPy is installed."""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from . import _native
from ._native import Scene


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
