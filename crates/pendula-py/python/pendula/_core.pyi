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
    energy_error: bool = False,
    progress: Optional[Callable[[int], None]] = None,
) -> tuple[npt.NDArray[np.float64], str]: ...

# The fractal (`crates/pendula-py/src/study.rs`), wrapped by `pendula.study`; the other
# studies run through `run_study` (`crates/pendula-py/src/studies.rs`).

def fractal(
    system: CoreSystem,
    theta1: tuple[float, float, int],
    theta2: tuple[float, float, int],
    t_max: float,
    method: str,
    dt: float,
    tolerance: float,
    threads: Optional[int] = None,
    progress: Optional[Callable[[int], None]] = None,
    pixels: Optional[tuple[int, int]] = None,
    times: Optional[tuple[list[float], list[float]]] = None,
) -> dict[str, Any]: ...

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

# `pendula.sweep` (`crates/pendula-py/src/sweep.rs`): the library's sweep, the CLI's.

def sweep(
    system: str,
    set: list[tuple[str, float]],
    axes: list[tuple[str, float, float, int]],
    method: str,
    dt: float,
    steps: Optional[int],
    t_end: Optional[float],
    until: Optional[str],
    records: list[str],
    shard: tuple[int, int],
    threads: Optional[int] = None,
    progress: Optional[Callable[[int], None]] = None,
    cells: Optional[tuple[int, int]] = None,
) -> dict[str, Any]: ...

def serve() -> str: ...

def defaults() -> dict[str, dict[str, Any]]: ...
def auto_method(system: Any) -> tuple[str, str]: ...
def dense_at(
    ts: np.ndarray,
    states: np.ndarray,
    f: np.ndarray,
    steps: Optional[np.ndarray],
    coefficients: Optional[np.ndarray],
    tq: np.ndarray,
) -> np.ndarray: ...
def bisect(h: float, t: float, sign: float, g: Callable[[float], float]) -> float: ...
def studies() -> list[dict[str, Any]]: ...
def run_study(
    name: str,
    values: list[tuple[str, Any]],
    set: list[tuple[str, float]],
    progress: Optional[Callable[[int], Any]] = None,
) -> dict[str, Any]: ...
