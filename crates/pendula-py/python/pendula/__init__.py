"""pendula for Python: the pendulum laboratory's library — systems, verified integrators,
SIMD ensembles — with numpy arrays in and out.

>>> import pendula
>>> sol = pendula.solve("double", (0, 10))
>>> sol.y[:, -1]            # (θ₁, θ₂, ω₁, ω₂) at t = 10 s, rad and rad/s

Units are SI (angles in radians from the downward vertical); the Baker–Gollub driven
pendulum is dimensionless. Every computation releases the GIL.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from . import _core
from .errors import (
    IntegrationError,
    InvalidValueError,
    NewtonError,
    NonFiniteStateError,
    PendulaError,
    StepSizeTooSmallError,
    UnknownNameError,
    UnsuitableMethodError,
)

__version__ = _core.__version__

__all__ = [
    "catalogue",
    "System",
    "Solution",
    "solve",
    "ensemble",
    "EnsembleResult",
    "PendulaError",
    "UnknownNameError",
    "InvalidValueError",
    "UnsuitableMethodError",
    "IntegrationError",
    "NonFiniteStateError",
    "StepSizeTooSmallError",
    "NewtonError",
]

#: The version of the pickled forms of System, Solution and EnsembleResult.
PICKLE_VERSION = 1


@dataclass(frozen=True)
class Quantity:
    """A parameter or state variable: name, SI unit, default, allowed values."""

    name: str
    unit: str
    default: float
    domain: str
    description: str
    angle: bool


@dataclass(frozen=True)
class SystemInfo:
    """A catalogued system: its parameters and state with units, whether it is separable
    and conservative (with its default values)."""

    name: str
    description: str
    dimensionless: bool
    energy_scale: str
    parameters: tuple[Quantity, ...]
    state: tuple[Quantity, ...]
    separable: bool
    conservative: bool


@dataclass(frozen=True)
class MethodInfo:
    """A catalogued integration method."""

    name: str
    title: str
    order: int
    symplectic: bool
    symmetric: bool
    adaptive: bool
    requirement: str
    description: str
    reference: str


@dataclass(frozen=True)
class Catalogue:
    """Every system and method pendula knows."""

    systems: tuple[SystemInfo, ...]
    methods: tuple[MethodInfo, ...]

    def system(self, name: str) -> SystemInfo:
        for s in self.systems:
            if s.name == name:
                return s
        System(name)  # raises UnknownNameError with the valid names
        raise AssertionError(name)


def catalogue() -> Catalogue:
    """The catalogue: systems (parameters with units, defaults and domains; state names;
    separable; conservative) and methods (order, symplectic, symmetric, requirement)."""
    raw = _core.catalogue()
    systems = tuple(
        SystemInfo(
            name=s["name"],
            description=s["description"],
            dimensionless=s["dimensionless"],
            energy_scale=s["energy_scale"],
            parameters=tuple(Quantity(**q) for q in s["parameters"]),
            state=tuple(Quantity(**q) for q in s["state"]),
            separable=s["separable"],
            conservative=s["conservative"],
        )
        for s in raw["systems"]
    )
    methods = tuple(MethodInfo(**m) for m in raw["methods"])
    return Catalogue(systems, methods)


def _as_columns(y: Any, n: int) -> tuple[np.ndarray, bool]:
    a = np.asarray(y, dtype=np.float64)
    if a.ndim == 1:
        return np.ascontiguousarray(a.reshape(-1, 1)), True
    if a.ndim == 2:
        return np.ascontiguousarray(a), False
    raise InvalidValueError(f"a state array must have shape ({n},) or ({n}, k); got shape {a.shape}")


class System:
    """A catalogued system with parameter and initial-state values by name (the rest at
    their defaults): ``System("double", m2=2.0, theta1=2.0)``.

    Pickles portably (its name and values, versioned), so multiprocessing and Dask can ship
    it.
    """

    __slots__ = ("_core",)

    def __init__(self, name: str, **params: float):
        settings = []
        for k, v in params.items():
            try:
                settings.append((str(k), float(v)))
            except (TypeError, ValueError):
                raise InvalidValueError(f"invalid value {v!r} for `{k}`: a number") from None
        self._core = _core.CoreSystem(str(name), settings)

    @property
    def name(self) -> str:
        """The catalogue name."""
        return self._core.name

    @property
    def params(self) -> dict[str, float]:
        """Every parameter and initial-state value by name (SI units)."""
        return dict(self._core.values())

    @property
    def names(self) -> list[str]:
        """The state's names, e.g. ``['theta1', 'theta2', 'omega1', 'omega2']``."""
        return list(self._core.names)

    @property
    def y0(self) -> np.ndarray:
        """The initial state from the values."""
        return np.array(self._core.initial_state())

    @property
    def separable(self) -> bool:
        """Whether H = T(p) + V(q): explicit splittings (verlet, yoshida-*) apply."""
        return self._core.separable

    @property
    def hamiltonian(self) -> bool:
        """Whether the system has a Hamiltonian form (no damping)."""
        return self._core.hamiltonian

    @property
    def conservative(self) -> bool:
        """Whether the energy is conserved (Hamiltonian and not driven)."""
        return self._core.conservative()[0]

    @property
    def dimensionless(self) -> bool:
        """Whether the system is dimensionless (no units)."""
        return self._core.dimensionless

    def rhs(self, t: float, y: Any) -> np.ndarray:
        """dy/dt at time t (s) for a state y of shape (n,) or states of shape (n, k)
        (vectorised, as scipy's ``vectorized=True``)."""
        cols, flat = _as_columns(y, len(self.names))
        out = self._core.rhs(float(t), cols)
        return out[:, 0] if flat else out

    def energy(self, y: Any, t: float = 0.0) -> float | np.ndarray:
        """The mechanical energy T + V (J) of a state (n,) or of states (n, k)."""
        cols, flat = _as_columns(y, len(self.names))
        e = self._core.energy(float(t), cols)
        return float(e[0]) if flat else e

    def energy_scale(self, y0: Any = None) -> float:
        """The scale relative energy errors from ``y0`` are taken against (J)."""
        y0 = self.y0 if y0 is None else np.asarray(y0, dtype=np.float64)
        return self._core.energy_scale(list(map(float, y0)))[0]

    def to_momenta(self, y: Any) -> np.ndarray:
        """(q, q') → (q, p) for a state (n,) or states (n, k)."""
        cols, flat = _as_columns(y, len(self.names))
        out = self._core.to_momenta(cols)
        return out[:, 0] if flat else out

    def from_momenta(self, z: Any) -> np.ndarray:
        """(q, p) → (q, q') for a state (n,) or states (n, k)."""
        cols, flat = _as_columns(z, len(self.names))
        out = self._core.from_momenta(cols)
        return out[:, 0] if flat else out

    def __reduce__(self):
        return (_system_from_pickle, (PICKLE_VERSION, self.name, self.params))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, System) and (self.name, self.params) == (other.name, other.params)

    def __hash__(self) -> int:
        return hash((self.name, tuple(self.params.items())))

    def __repr__(self) -> str:
        changed = {k: v for k, v in self.params.items() if v != _defaults(self.name).get(k)}
        args = "".join(f", {k}={v!r}" for k, v in changed.items())
        return f"System({self.name!r}{args})"


def _defaults(name: str) -> dict[str, float]:
    info = catalogue().system(name)
    return {q.name: q.default for q in info.parameters + info.state}


def _system_from_pickle(version: int, name: str, params: Mapping[str, float]) -> System:
    if version != PICKLE_VERSION:
        raise PendulaError(f"a pickled System of version {version}; this pendula reads version {PICKLE_VERSION}")
    return System(name, **params)


def _system(system: System | str) -> System:
    if isinstance(system, System):
        return system
    if isinstance(system, str):
        return System(system)
    raise InvalidValueError(f"invalid system {system!r}: a System or a catalogue name")


def auto_method(system: System) -> tuple[str, str]:
    """The method ``method="auto"`` picks for ``system``, and why: a symplectic explicit
    method where the system has a Hamiltonian form (yoshida-4 when separable, tao-4
    otherwise: bounded energy error on long runs), else adaptive dop853."""
    if system.separable:
        return "yoshida-4", "separable Hamiltonian: explicit symplectic, order 4"
    if system.hamiltonian:
        return "tao-4", "non-separable Hamiltonian: explicit symplectic (Tao), order 4"
    return "dop853", "not Hamiltonian (damped): adaptive, order 8"


class Solution:
    """A run, in scipy's shape: ``t`` (k,), ``y`` (n_state, k), ``nfev``, ``status``,
    ``message``, ``success``; plus ``states`` (k, n_state; the same memory as ``y``),
    ``names``, ``energy`` (J), ``energy_error`` (relative to the system's energy scale),
    ``method``, ``steps``, ``rejected``."""

    def __init__(self, system: System, raw: Mapping[str, Any], method_note: str | None = None):
        self.system = system
        self.t: np.ndarray = raw["t"]
        self.states: np.ndarray = raw["states"]
        self.method: str = raw["method"]
        self.method_note = method_note
        self.adaptive: bool = raw["adaptive"]
        self.nfev = raw["nfev"]
        self.steps = raw["steps"]
        self.rejected = raw["rejected"]
        error = raw["error"]
        self.status = 0 if error is None else -1
        self.message = "the run reached the end of the interval" if error is None else str(error[0])
        self.success = error is None

    @property
    def y(self) -> np.ndarray:
        """The states as columns, (n_state, k): a view of ``states``."""
        return self.states.T

    @property
    def names(self) -> list[str]:
        return self.system.names

    @property
    def energy(self) -> np.ndarray:
        """E(t) = T + V at every step, J."""
        return self.system.energy(self.y) if len(self.t) else np.empty(0)

    @property
    def energy_scale(self) -> float:
        """The energy scale of the run's start, J (see ``System.energy_scale``)."""
        return self.system.energy_scale(self.states[0])

    @property
    def energy_error(self) -> np.ndarray:
        """(E(t) − E(0)) / energy scale: the relative energy error."""
        e = self.energy
        return (e - e[0]) / self.energy_scale

    def drift(self) -> dict[str, float]:
        """The energy error's secular rate (least-squares slope, 1/s) and envelope (max
        |relative error|)."""
        err = self.energy_error
        slope = float(np.polyfit(self.t, err, 1)[0]) if len(self.t) > 1 else float("nan")
        return {"rate": slope, "envelope": float(np.max(np.abs(err))) if len(err) else float("nan")}

    def to_pandas(self):
        """A DataFrame with column ``t`` and one column per state variable (pandas needed)."""
        import pandas as pd

        frame = pd.DataFrame(self.states, columns=self.names)
        frame.insert(0, "t", self.t)
        return frame

    def plot(self, ax=None):
        """The positions against time (matplotlib needed); returns the axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots()
        n = len(self.names) // 2
        unit = "" if self.system.dimensionless else " (s)"
        for k in range(n):
            ax.plot(self.t, self.states[:, k], label=self.names[k])
        ax.set_xlabel("t" + unit)
        ax.legend()
        ax.set_title(f"{self.system.name}, {self.method}")
        return ax

    def _repr_html_(self) -> str:
        rows = [
            ("system", self.system.name),
            ("method", self.method + (f" (auto: {self.method_note})" if self.method_note else "")),
            ("steps", self.steps),
            ("rhs evaluations", self.nfev),
            ("t", f"{self.t[0]:g} … {self.t[-1]:g}" if len(self.t) else "-"),
            ("status", self.message),
        ]
        body = "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows)
        return f"<table>{body}</table>"

    def __repr__(self) -> str:
        return f"<Solution {self.system.name} {self.method}: {len(self.t)} samples, {self.message}>"

    def __reduce__(self):
        raw = {
            "t": self.t,
            "states": self.states,
            "method": self.method,
            "adaptive": self.adaptive,
            "nfev": self.nfev,
            "steps": self.steps,
            "rejected": self.rejected,
            "error": None if self.success else (self.message, None),
        }
        return (_solution_from_pickle, (PICKLE_VERSION, self.system, raw, self.method_note))


def _solution_from_pickle(version, system, raw, note):
    if version != PICKLE_VERSION:
        raise PendulaError(f"a pickled Solution of version {version}; this pendula reads version {PICKLE_VERSION}")
    return Solution(system, raw, note)


def solve(
    system: System | str,
    t_span: Sequence[float],
    y0: Any = None,
    *,
    method: str = "auto",
    dt: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
) -> Solution:
    """Integrates ``system`` over ``t_span = (t0, t_end)`` (s) from ``y0`` (default: the
    system's initial state) with ``method`` (a name from ``catalogue().methods``, or
    ``"auto"``: see :func:`auto_method`), fixed steps ``dt`` (s; default 1e-3, as the CLI)
    or, for an embedded pair (dopri5, dop853), adaptive steps with ``rtol``, ``atol``
    (default 1e-6 each, as the CLI; ``dt`` is then the first step to try). Every accepted
    step is recorded.

    Raises a ``ValueError`` subclass for bad input and :class:`IntegrationError` (with the
    time and the partial solution) when the run fails.
    """
    system = _system(system)
    try:
        t0, t_end = (float(v) for v in t_span)
    except (TypeError, ValueError):
        raise InvalidValueError(f"invalid t_span {t_span!r}: a pair (t0, t_end) of numbers in seconds") from None
    y0 = system.y0 if y0 is None else np.asarray(y0, dtype=np.float64).reshape(-1)
    if len(y0) != len(system.names):
        raise InvalidValueError(f"invalid y0 of {len(y0)} values: the `{system.name}` state is {system.names}")
    note = None
    if method == "auto":
        method, note = auto_method(system)
        if method == "dop853":
            rtol = 1e-10 if rtol is None else rtol
            atol = 1e-10 if atol is None else atol
    raw = _core.solve(system._core, str(method), t0, t_end, list(map(float, y0)), dt, rtol, atol)
    solution = Solution(system, raw, note)
    if raw["error"] is not None:
        error, t = raw["error"]
        error.t = t
        error.solution = solution
        raise error
    return solution


class EnsembleResult:
    """An ensemble's results: ``final`` (m, n_state), ``flip_time`` (m,; NaN where no
    angle passed ±π), ``names``, ``kernel`` (which engine ran it)."""

    def __init__(self, system: System, data: np.ndarray, method: str, kernel: str):
        self.system = system
        self.data = data
        self.method = method
        self.kernel = kernel

    @property
    def names(self) -> list[str]:
        return self.system.names

    @property
    def final(self) -> np.ndarray:
        return self.data[:, : len(self.names)]

    @property
    def flip_time(self) -> np.ndarray:
        return self.data[:, len(self.names)]

    def __reduce__(self):
        return (_ensemble_from_pickle, (PICKLE_VERSION, self.system, self.data, self.method, self.kernel))

    def __repr__(self) -> str:
        return f"<EnsembleResult {self.system.name} {self.method}: {len(self.data)} members on {self.kernel}>"


def _ensemble_from_pickle(version, system, data, method, kernel):
    if version != PICKLE_VERSION:
        raise PendulaError(f"a pickled EnsembleResult of version {version}; this pendula reads version {PICKLE_VERSION}")
    return EnsembleResult(system, data, method, kernel)


def ensemble(
    system: System | str,
    y0s: Any,
    t_end: float | None = None,
    *,
    params: Mapping[str, Any] | None = None,
    method: str = "rk4",
    dt: float = 1e-3,
    steps: int | None = None,
    until: str | None = None,
    threads: int | None = None,
) -> EnsembleResult:
    """Integrates m members of ``system`` from the rows of ``y0s`` (m, n_state), with
    per-member parameters ``params`` ({name: array of m}), ``steps`` steps of ``dt`` (or to
    ``t_end``, s) on the SIMD lanes and all cores (``threads``). ``until="flip"`` stops each
    member at its first flip. Results are bitwise identical whatever the thread count.
    """
    system = _system(system)
    y0s = np.ascontiguousarray(np.atleast_2d(np.asarray(y0s, dtype=np.float64)))
    m = y0s.shape[0]
    names = list(params or {})
    p = np.empty((m, len(names)))
    for k, name in enumerate(names):
        col = np.broadcast_to(np.asarray(params[name], dtype=np.float64), (m,))
        p[:, k] = col
    if steps is None:
        if t_end is None:
            raise InvalidValueError("give t_end (s) or steps")
        if not (math.isfinite(t_end) and t_end > 0):
            raise InvalidValueError(f"invalid value {t_end} for `t_end`: a finite time > 0")
        steps = max(1, round(t_end / dt))
    if until not in (None, "flip"):
        raise InvalidValueError(f"invalid value {until!r} for `until`: None or 'flip'")
    data, kernel = _core.ensemble(system._core, y0s, names, p, str(method), float(dt), int(steps), until == "flip", threads)
    return EnsembleResult(system, data, method, kernel)
