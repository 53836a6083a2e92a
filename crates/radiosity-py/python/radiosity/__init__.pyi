from typing import Any, Callable, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

Progress = Optional[Callable[[str, int, int], Any]]

class Scene:
    @staticmethod
    def from_arrays(
        vertices: npt.ArrayLike,
        faces: npt.ArrayLike,
        reflectance: npt.ArrayLike,
        emission: npt.ArrayLike,
        name: str = "arrays",
    ) -> Scene: ...
    @property
    def name(self) -> str: ...
    @property
    def polygons(self) -> int: ...
    @property
    def materials(self) -> list[str]: ...

class Solution:
    @property
    def centres(self) -> np.ndarray: ...
    @property
    def normals(self) -> np.ndarray: ...
    @property
    def areas(self) -> np.ndarray: ...
    @property
    def radiosity(self) -> np.ndarray: ...
    @property
    def unshot(self) -> np.ndarray: ...
    @property
    def reflectance(self) -> np.ndarray: ...
    @property
    def emission(self) -> np.ndarray: ...
    @property
    def surfaces(self) -> np.ndarray: ...
    @property
    def info(self) -> dict[str, Any]: ...
    @property
    def trace(self) -> Optional[dict[str, np.ndarray]]: ...
    def render(
        self,
        width: int = 512,
        height: int = 512,
        spp: Optional[int] = None,
        integrator: str = "radiosity",
        seed: int = 1,
        progress: Progress = None,
    ) -> np.ndarray: ...
    def bake_lightmap(
        self,
        texel_size: Optional[float] = None,
        size: Optional[int] = None,
        direct: int = 16,
        indirect: int = 256,
        spacing: int = 4,
        denoise: Union[bool, float, None] = None,
        seed: int = 1,
    ) -> dict[str, Any]: ...
    def save(self, path: str) -> None: ...

def builtin(name: str) -> Scene: ...
def load(path: str, one_sided: bool = False) -> Scene: ...
def methods() -> dict[str, list[str]]: ...
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
) -> Solution: ...
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
) -> Any: ...
def solve_system(
    F: Any,
    area: npt.ArrayLike,
    reflectance: npt.ArrayLike,
    emission: npt.ArrayLike,
    solver: str = "gauss-seidel",
    tolerance: float = 1e-6,
    max_iterations: Optional[int] = None,
    seed: int = 1,
    trace: bool = True,
    progress: Progress = None,
) -> Tuple[np.ndarray, Optional[dict[str, np.ndarray]]]: ...
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
) -> dict[str, Any]: ...

def read_photometry(path: Any) -> dict:
    """An IES or EULUMDAT file: c_angles, gamma_angles, candela (C × γ), lumens, rated_flux,
    flux, source, warnings."""
    ...

def lighting(
    scene: Scene,
    luminaires: Any = None,
    points: Optional[np.ndarray] = None,
    grids: Any = (),
    unit: float = 1.0,
    up: str = "z",
    patches: int = 10000,
    tolerance: float = 1e-3,
    indirect_samples: int = 256,
    seed: int = 1,
    progress: Progress = None,
) -> dict:
    """Illuminance (lux) at points from a luminaire schedule, interreflection included:
    groups, illuminance (N,), by_group (N, G), direct (N,), patches, flux (G,)."""
    ...
