"""Type stubs of the extension module `pendula._core` (see `crates/pendula-py/src/lib.rs`)."""

from typing import Callable, Any, Optional

import numpy as np
import numpy.typing as npt

__version__: str

def catalogue() -> dict[str, list[dict[str, Any]]]: ...

class CoreSystem:
    def __new__(cls, name: str, params: list[tuple[str, float]]) -> "CoreSystem": ...
    @property
    def name(self) -> str: ...
    @property
    def names(self) -> list[str]: ...
    @property
    def separable(self) -> bool: ...
    @property
    def hamiltonian(self) -> bool: ...
    @property
    def dimensionless(self) -> bool: ...
    def values(self) -> list[tuple[str, float]]: ...
    def initial_state(self) -> list[float]: ...
    def conservative(self) -> tuple[bool, Optional[str]]: ...
    def energy_scale(self, y0: list[float]) -> tuple[float, str]: ...
    def rhs(self, t: float, y: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    def energy(self, t: float, y: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    def to_momenta(self, y: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    def from_momenta(self, z: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...

def solve(
    system: CoreSystem,
    method: str,
    t0: float,
    t_end: float,
    y0: list[float],
    dt: Optional[float] = None,
    rtol: Optional[float] = None,
    atol: Optional[float] = None,
    dense: bool = False,
    events: list[str] = ...,
    stop_on_event: bool = False,
    progress: Optional[Callable[[float], None]] = None,
) -> dict[str, Any]: ...
def ensemble(
    system: CoreSystem,
    y0s: npt.NDArray[np.float64],
    param_names: list[str],
    params: npt.NDArray[np.float64],
    method: str,
    dt: float,
    steps: int,
    until_flip: bool,
    threads: Optional[int] = None,
) -> tuple[npt.NDArray[np.float64], str]: ...

# `Solution.animate()` (`crates/pendula-py/src/animate.rs`).

def animation_gif(
    title: str,
    lengths: list[float],
    t: npt.NDArray[np.float64],
    angles: npt.NDArray[np.float64],
    energy_error: npt.NDArray[np.float64],
    labels: list[str],
    fps: int,
    width: int,
    height: int,
) -> bytes: ...
