"""pendula for Python: the pendulum laboratory's library — systems, verified integrators,
SIMD ensembles — with numpy arrays in and out.

>>> import pendula
>>> sol = pendula.solve("double", (0, 10))
>>> sol.y[:, -1]            # (θ₁, θ₂, ω₁, ω₂) at t = 10 s, rad and rad/s

Units are SI (angles in radians from the downward vertical); the Baker–Gollub driven
pendulum is dimensionless. Every computation releases the GIL.
"""

from __future__ import annotations

import difflib
import html
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from . import _core
from .dense import DenseOutput, counted, locate, time_bar
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
from .study import (
    BifurcationResult,
    ConvergenceResult,
    DivergenceResult,
    FractalResult,
    LyapunovResult,
    MethodConvergence,
    MethodWork,
    PoincareResult,
    WorkPrecisionResult,
    bifurcation,
    convergence,
    divergence,
    fractal,
    lyapunov,
    poincare,
    work_precision,
)

from .sweep import SweepResult, merge, sweep
from .studies import FUNCTIONS as _STUDIES, StudyReport, install as _install_studies, study

# One function per library study (pendula::study::STUDIES): `energy_budget`, ...
_install_studies(globals())
from . import distributed  # noqa: E402  (after the names it uses)
from .view import View, view  # noqa: E402

__version__ = _core.__version__

__all__ = [
    "catalogue",
    "System",
    "Solution",
    "DenseOutput",
    "solve",
    "ensemble",
    "EnsembleResult",
    "sweep",
    "merge",
    "SweepResult",
    "lyapunov",
    "LyapunovResult",
    "poincare",
    "PoincareResult",
    "fractal",
    "FractalResult",
    "bifurcation",
    "BifurcationResult",
    "convergence",
    "ConvergenceResult",
    "MethodConvergence",
    "work_precision",
    "WorkPrecisionResult",
    "MethodWork",
    "divergence",
    "DivergenceResult",
    "view",
    "View",
    "study",
    "StudyReport",
    *_STUDIES,
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
    def info(self) -> SystemInfo:
        """The system's catalogue entry: parameters and state with units and domains."""
        return catalogue().system(self.name)

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

    def _changed(self) -> dict[str, float]:
        """The values that differ from the catalogue's defaults: what was set."""
        defaults = _defaults(self.name)
        return {k: v for k, v in self.params.items() if v != defaults.get(k)}

    def __repr__(self) -> str:
        args = "".join(f", {k}={v!r}" for k, v in self._changed().items())
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
    otherwise: bounded energy error on long runs), else adaptive dop853 (the library's rule,
    ``pendula::model::auto_method``)."""
    return _core.auto_method(system._core)


class Solution:
    """A run, in scipy's shape: ``t`` (k,), ``y`` (n_state, k), ``sol`` (the continuous
    solution, with ``dense_output=True``), ``t_events`` / ``y_events`` (with ``events``),
    ``nfev``, ``status`` (0: reached the end, 1: a terminal event, -1: failed), ``message``,
    ``success``; plus ``states`` (k, n_state; the same memory as ``y``), ``names``,
    ``energy`` (J), ``energy_error`` (relative to the system's energy scale), ``method``,
    ``steps``, ``rejected``."""

    def __init__(
        self,
        system: System,
        *,
        t: np.ndarray,
        states: np.ndarray,
        method: str,
        method_note: str | None = None,
        adaptive: bool = False,
        nfev: int | None = None,
        steps: int = 0,
        rejected: int | None = None,
        status: int = 0,
        message: str = "the run reached the end of the interval",
        sol: DenseOutput | None = None,
        t_events: list[np.ndarray] | None = None,
        y_events: list[np.ndarray] | None = None,
        event_names: list[str] | None = None,
    ):
        self.system = system
        self.t: np.ndarray = t
        self.states: np.ndarray = states
        self.method = method
        self.method_note = method_note
        self.adaptive = adaptive
        self.nfev = nfev
        self.steps = steps
        self.rejected = rejected
        self.status = status
        self.message = message
        self.sol = sol
        self.t_events = t_events
        self.y_events = y_events
        #: The events' names, in the order of ``t_events`` (the spec, or the callable's name).
        self.event_names = event_names

    @property
    def success(self) -> bool:
        """Whether the run reached its end or a terminal event (status ≥ 0)."""
        return self.status >= 0

    @property
    def y(self) -> np.ndarray:
        """The states as columns, (n_state, k): a view of ``states``."""
        return self.states.T

    @property
    def names(self) -> list[str]:
        return self.system.names

    @property
    def energy(self) -> np.ndarray:
        """E(t) = T + V at every sample, J."""
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

    def animate(self, *, fps: int = 30, speed: float = 1.0, size: tuple[int, int] = (480, 480)):
        """The run as an animated GIF (an :class:`~pendula.animation.Animation`, shown inline
        in Jupyter; ``.save("run.gif")``), drawn by pendula's own animation code: one frame
        every ``speed``/``fps`` s of simulated time, rods, bobs, a fading trail, the time and
        the relative energy error on a log gauge. Systems with angles only."""
        from .animation import animate

        return animate(self, fps=fps, speed=speed, size=size)

    def _repr_html_(self) -> str:
        rows = [
            ("system", self.system.name),
            ("method", self.method + (f" (auto: {self.method_note})" if self.method_note else "")),
            ("steps", self.steps),
            ("rhs evaluations", self.nfev),
            ("t", f"{self.t[0]:g} … {self.t[-1]:g}" if len(self.t) else "-"),
            ("status", self.message),
        ]
        if self.t_events is not None:
            for name, te in zip(self.event_names, self.t_events):
                rows.append((f"event {html.escape(name)}", f"{len(te)} (first at {te[0]:g})" if len(te) else "0"))
        body = "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows)
        return f"<table>{body}</table>"

    def __repr__(self) -> str:
        return f"<Solution {self.system.name} {self.method}: {len(self.t)} samples, {self.message}>"

    def __reduce__(self):
        fields = {
            k: getattr(self, k)
            for k in (
                "t", "states", "method", "method_note", "adaptive", "nfev", "steps", "rejected",
                "status", "message", "sol", "t_events", "y_events", "event_names",
            )
        }
        return (_solution_from_pickle, (PICKLE_VERSION, self.system, fields))


def _solution_from_pickle(version, system, fields):
    if version != PICKLE_VERSION:
        raise PendulaError(f"a pickled Solution of version {version}; this pendula reads version {PICKLE_VERSION}")
    return Solution(system, **fields)


def _event_name(g: Any) -> str:
    return str(getattr(g, "__name__", None) or repr(g))


def solve(
    system: System | str,
    t_span: Sequence[float],
    y0: Any = None,
    *,
    method: str | None = None,
    dt: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    t_eval: Any = None,
    dense_output: bool = False,
    events: Any = None,
    stop_on_event: bool = False,
    progress: bool | None | Callable[[float], None] = None,
) -> Solution:
    """Integrates ``system`` over ``t_span = (t0, t_end)`` (s) from ``y0`` (default: the
    system's initial state) with ``method`` (a name from ``catalogue().methods``, or
    ``"auto"``: see :func:`auto_method`), fixed steps ``dt`` (s) or, for an embedded pair
    (dopri5, dop853), adaptive steps with ``rtol``, ``atol`` (``dt`` is then the first step
    to try). What is not given takes the library's defaults of a run
    (``_core.SIMULATE_DEFAULTS``: rk4, dt = 1e-3 s, rtol = atol = 1e-6), the same as
    ``pendula simulate``'s and the lab's first run, so all three end in the same state.

    With ``t_end < t0`` the run goes backward in time, as scipy's ``solve_ivp`` does:
    ``t_span=(10, 0)`` starts from ``y0`` at t = 10 s and ends at t = 0, every method
    stepping with ``-dt`` (the drive of a driven system is evaluated at the true, decreasing
    times). As in scipy, ``dt`` is a step *size* (> 0) and ``t_span`` gives the direction; ``t``,
    ``t_eval`` and ``t_events`` then run from t0 down to t_end.

    The solution holds every accepted step, or with ``t_eval`` (times in ``t_span``, in the
    run's direction: increasing, or decreasing on a backward run) the states at those
    times, from the continuous solution. ``dense_output=True``
    keeps that continuous solution as ``sol``: the method's own dense output where it has
    one (dop853: order 7, dopri5: order 4), else the cubic Hermite interpolant of each step.

    ``events``: the CLI's event specs — ``"flip"`` (an angle passes ±π, once),
    ``"zero:NAME"``, ``"section:NAME=VALUE"`` (a trailing ``+``/``-`` keeps rising or
    falling crossings) — located by the library exactly as ``pendula simulate --event``,
    and with ``stop_on_event=True`` the first ends the run; or scipy-style callables
    ``g(t, y)`` with optional ``terminal`` and ``direction`` attributes, located on the
    continuous solution. ``t_events[i]`` (times, s) and ``y_events[i]`` (states) follow the
    order of ``events``.

    ``progress``: by default (None) a bar shows when stderr is a terminal or the call runs in
    a notebook and the run proves long (estimated from its progress after 0.5 s to take 3 s
    or more); ``True`` always shows it, ``False`` never; a callable is called with the time
    reached instead, about every 20 ms. The bar is tqdm's (``tqdm.auto``) when tqdm is
    installed (``pip install pendula[progress]``), else a line on stderr.

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
    if method is None:
        method = _core.SIMULATE_DEFAULTS["method"]
    if method == "auto":
        method, note = auto_method(system)
        if method == "dop853":
            rtol = 1e-10 if rtol is None else rtol
            atol = 1e-10 if atol is None else atol
    if events is None:
        event_list: list[Any] = []
    elif isinstance(events, str) or callable(events):
        event_list = [events]
    else:
        event_list = list(events)
    for e in event_list:
        if not (isinstance(e, str) or callable(e)):
            raise InvalidValueError(f"invalid event {e!r}: a spec such as 'flip' or 'section:theta1=0+', or a callable g(t, y)")
    specs = [e for e in event_list if isinstance(e, str)]
    callables = [e for e in event_list if not isinstance(e, str)]
    # +1 forward in time, -1 backward (t_span = (10, 0)).
    direction = -1.0 if t_end < t0 else 1.0
    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=np.float64).reshape(-1)
        lo, hi = min(t0, t_end), max(t0, t_end)
        outside = ~np.isfinite(t_eval) | (t_eval < lo) | (t_eval > hi)
        if outside.any():
            raise InvalidValueError(f"invalid t_eval value {t_eval[np.argmax(outside)]}: times within t_span ({t0:g}, {t_end:g}) s")
        if np.any(direction * np.diff(t_eval) <= 0):
            order = "increasing" if direction > 0 else "decreasing (t_span runs backward)"
            raise InvalidValueError(f"invalid t_eval: the times must be {order}, as t_span ({t0:g}, {t_end:g}) runs")
    bar, bar_to_close = time_bar(progress, t0, t_end, "" if system.dimensionless else "s", f"solve {system.name}")
    dense = dense_output or t_eval is not None or bool(callables)
    try:
        raw = _core.solve(
            system._core, str(method), t0, t_end, list(map(float, y0)), dt, rtol, atol,
            dense, specs, bool(stop_on_event), bar,
        )
    except BaseException:
        if bar_to_close is not None:
            bar_to_close.close(None)
        raise
    t, states = raw["t"], raw["states"]
    # The bar's last word is where the run ended (a short run may never have been ticked).
    if bar_to_close is not None:
        bar_to_close.close(float(t[-1]) if len(t) else None)
    elif bar is not None and len(t):
        bar(float(t[-1]))
    sol = None
    if dense and len(t):
        coefficients = raw.get("dense_coefficients")
        order = 3 if coefficients is None else raw["dense_order"]
        sol = DenseOutput(t, states, raw["f"], raw.get("dense_steps"), coefficients, order)
    status, message = 0, "the run reached the end of the interval"
    if raw["stopped"] is not None:
        status, message = 1, f"a terminal event ({raw['stopped']}) ended the run at t = {t[-1]:g}"
    found: dict[int, list[tuple[float, np.ndarray]]] = {i: [] for i in range(len(event_list))}
    for name, te, ye in raw["events"]:
        found[event_list.index(name)].append((te, np.asarray(ye)))
    # Callables, on the continuous solution; the first terminal one ends the run there.
    for e in callables:
        i = event_list.index(e)
        found[i] = locate(e, sol, t, states)
        if getattr(e, "terminal", False) and found[i] and direction * found[i][0][0] < direction * t[-1]:
            te, ye = found[i][0]
            keep = direction * t < direction * te
            t = np.append(t[keep], te)
            states = np.vstack([states[keep], ye[None, :]])
            status, message = 1, f"a terminal event ({_event_name(e)}) ended the run at t = {te:g}"
    if status == 1:
        # Events after the run's end did not happen.
        for i in found:
            found[i] = [(te, ye) for te, ye in found[i] if direction * te <= direction * t[-1]]
    t_events = y_events = names = None
    if event_list:
        names = [e if isinstance(e, str) else _event_name(e) for e in event_list]
        t_events = [np.array([te for te, _ in found[i]]) for i in range(len(event_list))]
        y_events = [
            np.array([ye for _, ye in found[i]]).reshape(-1, len(y0)) for i in range(len(event_list))
        ]
    if t_eval is not None and sol is not None:
        t = t_eval[direction * t_eval <= direction * t[-1]]
        states = np.ascontiguousarray(sol(t).T) if len(t) else np.empty((0, len(y0)))
    if not dense_output:
        sol = None
    error = raw["error"]
    if error is not None:
        status, message = -1, str(error[0])
    solution = Solution(
        system, t=t, states=states, method=raw["method"], method_note=note, adaptive=raw["adaptive"],
        nfev=raw["nfev"], steps=raw["steps"], rejected=raw["rejected"], status=status, message=message,
        sol=sol, t_events=t_events, y_events=y_events, event_names=names,
    )
    if error is not None:
        exc, t_fail = error
        exc.t = t_fail
        exc.solution = solution
        raise exc
    return solution


class EnsembleResult:
    """An ensemble's results: ``data`` (m, columns), the recorded columns in the order of
    ``records`` (as ``pendula sweep --record`` writes them), named by ``columns``; by name
    ``final`` (m, n_state), ``flip_time`` (m,; s, NaN where no angle passed ±π) and
    ``energy_error`` (m,; E_end − E_0, J); ``kernel`` (which engine ran it)."""

    def __init__(self, system: System, data: np.ndarray, method: str, kernel: str, records: Sequence[str] = ("final", "flip-time")):
        self.system = system
        self.data = data
        self.method = method
        self.kernel = kernel
        self.records = tuple(records)

    @property
    def names(self) -> list[str]:
        return self.system.names

    @property
    def columns(self) -> list[str]:
        """The names of ``data``'s columns."""
        out: list[str] = []
        for r in self.records:
            out += self.names if r == "final" else [r.replace("-", "_")]
        return out

    def _column(self, record: str) -> slice:
        if record not in self.records:
            raise InvalidValueError(f"`{record}` was not recorded: pass record=(..., {record!r}) to ensemble()")
        start = 0
        for r in self.records:
            width = len(self.names) if r == "final" else 1
            if r == record:
                return slice(start, start + width)
            start += width
        raise AssertionError(record)

    @property
    def final(self) -> np.ndarray:
        """The final states, (m, n_state)."""
        return self.data[:, self._column("final")]

    @property
    def flip_time(self) -> np.ndarray:
        """The first flip time of each member, s (NaN: none)."""
        return self.data[:, self._column("flip-time")][:, 0]

    @property
    def energy_error(self) -> np.ndarray:
        """E_end − E_0 of each member, J (dimensionless for dimensionless systems)."""
        return self.data[:, self._column("energy-error")][:, 0]

    def __reduce__(self):
        return (_ensemble_from_pickle, (PICKLE_VERSION, self.system, self.data, self.method, self.kernel, self.records))

    def __repr__(self) -> str:
        return f"<EnsembleResult {self.system.name} {self.method}: {len(self.data)} members on {self.kernel}>"


def _ensemble_from_pickle(version, system, data, method, kernel, records=("final", "flip-time")):
    if version != PICKLE_VERSION:
        raise PendulaError(f"a pickled EnsembleResult of version {version}; this pendula reads version {PICKLE_VERSION}")
    return EnsembleResult(system, data, method, kernel, records)


def ensemble(
    system: System | str,
    y0s: Any,
    t_end: float | None = None,
    *,
    params: Mapping[str, Any] | None = None,
    method: str = "rk4",
    dt: float = 1e-3,
    steps: int | None = None,
    record: Sequence[str] | str = ("final",),
    until: str | None = None,
    threads: int | None = None,
    progress: bool | None | Callable[[int], None] = None,
) -> EnsembleResult:
    """Integrates m members of ``system`` from the rows of ``y0s`` (m, n_state), with
    per-member parameters ``params`` ({name: array of m}), ``steps`` steps of ``dt`` (or to
    ``t_end``, s) on the SIMD lanes where the method has them, else one scalar run per member
    (``kernel`` says which), on all cores (``threads``). ``until="flip"`` stops each member
    at its first flip. ``record``: what ``data`` holds per member, in this order, as
    ``pendula sweep --record``: ``"final"`` (the state), ``"flip-time"`` (s, NaN if no flip),
    ``"energy-error"`` (E_end − E_0, J). Results are bitwise identical whatever the thread
    count. ``progress``: a bar of the members done, by default (None) where a terminal or
    notebook shows it and the run is estimated to take 3 s or more; ``True`` always,
    ``False`` never; a callable gets the count instead.
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
    records = tuple(r.strip() for r in record.split(",")) if isinstance(record, str) else tuple(record)
    allowed = ("final", "flip-time", "energy-error")
    for r in records:
        if r not in allowed:
            close = difflib.get_close_matches(str(r), allowed, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise InvalidValueError(f"invalid record {r!r}{hint}: one of {', '.join(allowed)}")
    if not records or len(set(records)) != len(records):
        raise InvalidValueError(f"invalid record {record!r}: each of {', '.join(allowed)} at most once, at least one")
    raw, kernel = counted(
        progress, m, "members",
        lambda tick: _core.ensemble(
            system._core, y0s, names, p, str(method), float(dt), int(steps), until == "flip", threads,
            "energy-error" in records, tick,
        ),
        desc=f"ensemble {system.name}",
    )
    n = len(system.names)
    parts = {"final": raw[:, :n], "flip-time": raw[:, n : n + 1], "energy-error": raw[:, n + 1 : n + 2]}
    data = raw if records == ("final", "flip-time") else np.ascontiguousarray(np.hstack([parts[r] for r in records]))
    return EnsembleResult(system, data, method, kernel, records)
