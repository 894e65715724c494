"""pendula's studies — the analyses the CLI's study commands run, on the same library, with
the same defaults: a call with defaults computes what ``pendula <command>`` computes with
defaults.

=====================  ==============================  ===========================
function               CLI command                     result
=====================  ==============================  ===========================
:func:`lyapunov`       ``pendula lyapunov``            :class:`LyapunovResult`
:func:`poincare`       ``pendula poincare``            :class:`PoincareResult`
:func:`fractal`        ``pendula fractal``             :class:`FractalResult`
:func:`bifurcation`    ``pendula bifurcation``         :class:`BifurcationResult`
:func:`convergence`    ``pendula convergence``         :class:`ConvergenceResult`
:func:`work_precision` ``pendula work-precision``      :class:`WorkPrecisionResult`
:func:`divergence`     ``pendula divergence``          :class:`DivergenceResult`
=====================  ==============================  ===========================

Each result is a frozen dataclass of numpy arrays and numbers (the numbers of the CLI's
``--summary`` JSON, by the same names where they fit), with ``plot(ax=None)`` (matplotlib,
imported only then) and an HTML summary for notebooks; it pickles as plain data with a
version (its fields by name), so multiprocessing and Dask can ship it.
Units are SI: times in s, rates in 1/s, energies in J, angles in rad.
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, Optional, Sequence, Tuple

import numpy as np

from . import _core
from .dense import counted, timed
from .errors import InvalidValueError, PendulaError, UnknownNameError

#: Every study's defaults, declared once in the library (``pendula::study::defaults``): the
#: signatures below take theirs from here, so that each equals its CLI flag's.
_DEFAULTS = _core.defaults()
#: The defaults of the studies on the library's registry (pendula::study::STUDIES), by study
#: and parameter; a hand-written function over one of them takes its defaults from here.
_REGISTRY = {e["name"]: {p["name"]: p["default"] for p in e["params"]} for e in _core.studies()}
#: The flip fractal's default grid, the library's text ("theta1=-pi:pi:512 and …") read by
#: the one value parser: {axis name: (lo, hi, n)}.
_FRACTAL_GRID = {
    a[0]: tuple(a[1:]) for a in (_core.parse_axis("double", [], t) for t in _DEFAULTS["fractal"]["grid"].split(" and "))
}
#: The Poincaré section on defaults, the registry's `NAME=VALUE` text read by the one value
#: parser (`deg` and `pi` accepted): (angle, value in rad).
_SECTION_NAME, _SECTION_VALUE = _REGISTRY["poincare"]["section"].split("=", 1)
_POINCARE_SECTION = (_SECTION_NAME, _core.parse_value("double", _SECTION_NAME, _SECTION_VALUE))

if TYPE_CHECKING:
    from . import System

__all__ = [
    "lyapunov",
    "poincare",
    "fractal",
    "bifurcation",
    "convergence",
    "work_precision",
    "divergence",
    "LyapunovResult",
    "PoincareResult",
    "FractalResult",
    "BifurcationResult",
    "ConvergenceResult",
    "MethodConvergence",
    "WorkPrecisionResult",
    "MethodWork",
    "DivergenceResult",
]


def _system(system: "System | str") -> "System":
    from . import _system as as_system

    return as_system(system)


def _float(name: str, value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InvalidValueError(f"invalid value {value!r} for `{name}`: a number") from None


def _int(name: str, value: Any, lo: int, hi: int, what: str) -> int:
    try:
        n = operator.index(value)
    except TypeError:
        raise InvalidValueError(f"invalid value {value!r} for `{name}`: a whole number of {what}, {lo} to {hi}") from None
    if not lo <= n <= hi:
        raise InvalidValueError(f"invalid value {n} for `{name}`: {lo} to {hi} {what}")
    return n


def _threads(threads: Any) -> Optional[int]:
    return None if threads is None else _int("threads", threads, 1, 1024, "threads")


def _axis(name: str, axis: Any) -> Tuple[float, float, int]:
    try:
        lo, hi, n = axis
    except (TypeError, ValueError):
        raise InvalidValueError(f"invalid {name} {axis!r}: (lo, hi, n), n cell centres between lo and hi") from None
    return _float(name, lo), _float(name, hi), _int(name, n, 1, 1 << 20, "cells")


def _names(methods: Any) -> Optional[list]:
    if methods is None:
        return None
    if isinstance(methods, str):
        return [m.strip() for m in methods.split(",")]
    return [str(m) for m in methods]


def _steps(name: str, values: Any) -> Optional[list]:
    if values is None:
        return None
    a = np.asarray(values, dtype=np.float64).reshape(-1)
    return [float(v) for v in a]


def _table(title: str, rows: Sequence[Tuple[str, Any]]) -> str:
    body = "".join(f"<tr><th style='text-align:left'>{k}</th><td>{v}</td></tr>" for k, v in rows)
    return f"<table><caption>{title}</caption>{body}</table>"


def _axes(ax):
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots()
    return ax


def _time_unit(system: "System") -> str:
    return "" if system.dimensionless else " (s)"


# Lyapunov exponents ------------------------------------------------------------------


#: The version of the studies' pickled forms.
STUDY_PICKLE_VERSION = 1


class _Pickled:
    """Pickles a result as its class name and its fields by name, with a version: portable
    across builds, never raw memory."""

    def __reduce__(self):
        return (_from_pickle, (STUDY_PICKLE_VERSION, type(self).__name__, {f.name: getattr(self, f.name) for f in fields(self)}))


def _from_pickle(version: int, name: str, values: dict):
    if version != STUDY_PICKLE_VERSION:
        raise PendulaError(f"a pickled {name} of version {version}; this pendula reads version {STUDY_PICKLE_VERSION}")
    cls = globals().get(name)
    if not (isinstance(cls, type) and issubclass(cls, _Pickled)):
        raise PendulaError(f"a pickled study result of unknown kind {name!r}")
    return cls(**values)


@dataclass(frozen=True, eq=False)
class LyapunovResult(_Pickled):
    """The largest Lyapunov exponent (or the spectrum) by Benettin's method.

    ``lambda_max`` and its ``uncertainty`` (standard error of 10 batch means) in 1/s;
    ``spectrum`` and ``spectrum_uncertainty`` (all exponents, largest first, 1/s) when asked
    for, else None; the running estimate: ``t`` (s after the transient, one per
    re-orthonormalisation) and ``running`` (len(t), k) in 1/s.
    """

    system: "System"
    method: str
    dt: float
    t_end: float
    transient: float
    renormalise: float
    lambda_max: float
    uncertainty: float
    spectrum: Optional[np.ndarray]
    spectrum_uncertainty: Optional[np.ndarray]
    t: np.ndarray
    running: np.ndarray

    def plot(self, ax=None):
        """The running estimates against time, with λ₁ ± its uncertainty dashed; returns
        the axes (matplotlib needed)."""
        ax = _axes(ax)
        for j in range(self.running.shape[1]):
            ax.plot(self.t, self.running[:, j], label=f"λ{j + 1}")
        for v in (self.lambda_max - self.uncertainty, self.lambda_max + self.uncertainty):
            ax.axhline(v, linestyle="--", color="C0", linewidth=0.8)
        ax.set_xlabel("time after the transient" + _time_unit(self.system))
        ax.set_ylabel("exponent" + ("" if self.system.dimensionless else " (1/s)"))
        ax.set_title(f"{self.system.name}: running Lyapunov estimate ({self.method}, dt = {self.dt:g})")
        ax.legend()
        return ax

    def _repr_html_(self) -> str:
        rows = [
            ("system", self.system.name),
            ("method", f"{self.method}, dt = {self.dt:g} s"),
            ("t_end", f"{self.t_end:g} s after a {self.transient:g} s transient"),
            ("λ_max", f"{self.lambda_max:.5f} ± {self.uncertainty:.5f} 1/s"),
        ]
        if self.spectrum is not None:
            rows += [(f"λ{j + 1}", f"{v:.5f} ± {e:.5f} 1/s") for j, (v, e) in enumerate(zip(self.spectrum, self.spectrum_uncertainty))]
        return _table("Lyapunov exponents", rows)


def lyapunov(
    system: "System | str" = _REGISTRY["lyapunov"]["system"],
    *,
    method: str = _REGISTRY["lyapunov"]["method"],
    dt: float = _REGISTRY["lyapunov"]["dt"],
    t_end: float = _REGISTRY["lyapunov"]["t_end"],
    transient: float = _REGISTRY["lyapunov"]["transient"],
    renormalise: float = _REGISTRY["lyapunov"]["renormalise"],
    spectrum: bool = False,
    progress: Any = None,
) -> LyapunovResult:
    """The largest Lyapunov exponent of ``system`` (a System or a catalogue name) from its
    initial state, or the whole ``spectrum``, the library's ``lyapunov`` study (as ``pendula
    lyapunov``): the state and its tangent vectors by ``method`` (an explicit Runge–Kutta
    method, an embedded pair at fixed steps, or Gauss–Legendre) at steps ``dt`` (s), a
    ``transient`` (s) discarded, then averaged over ``t_end`` (s) with re-orthonormalisation
    every ``renormalise`` (s; at least 20 of them). :func:`pendula.study` ``("lyapunov",
    ...)`` returns the same as a :class:`StudyReport`.

    ``progress``: by default (None) a line with the time elapsed appears where a terminal or
    notebook shows it, once the call has taken 3 s; ``True`` shows it from the start,
    ``False`` never; a callable gets the seconds elapsed, about every 20 ms.
    """
    system = _system(system)
    values = [
        ("system", system.name),
        ("method", str(method)),
        ("dt", _float("dt", dt)),
        ("t_end", _float("t_end", t_end)),
        ("transient", _float("transient", transient)),
        ("renormalise", _float("renormalise", renormalise)),
        ("spectrum", bool(spectrum)),
    ]
    settings = [(k, float(v)) for k, v in system._changed().items()]
    raw = timed(progress, f"lyapunov {system.name}", lambda tick: _core.run_study("lyapunov", values, settings, tick))
    running, exponents = raw["tables"]["lyapunov"], raw["tables"]["exponents"]
    return LyapunovResult(
        system=system,
        method=raw["inputs"]["method"],
        dt=float(dt),
        t_end=float(t_end),
        transient=float(transient),
        renormalise=float(renormalise),
        lambda_max=float(raw["numbers"]["lambda_max"]),
        uncertainty=float(raw["numbers"]["uncertainty"]),
        spectrum=exponents["value"] if spectrum else None,
        spectrum_uncertainty=exponents["uncertainty"] if spectrum else None,
        t=running["t"],
        running=np.column_stack([v for k, v in running.items() if k != "t"]),
    )


# Poincaré sections -------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PoincareResult(_Pickled):
    """A Poincaré section: every crossing of ``section`` = ``value`` (rad, rising) by
    ``count`` orbits of energy ``energy`` (J), in orbit order.

    Per crossing: ``orbit`` (its orbit's index), ``t`` (s), ``states`` (canonical
    (q₁, q₂, p₁, p₂): rad and kg m²/s; the other angle wrapped as ``q``), ``q`` and ``p`` (the other angle, wrapped into
    [−π, π), and its momentum: the section's picture). ``initial`` (count, 4): each orbit's
    start (positions, velocities). ``crossings``, ``crossings_per_orbit`` and
    ``max_energy_error`` (J, the largest |H − E| at a crossing).
    """

    system: "System"
    method: str
    energy: float
    count: int
    section: str
    value: float
    t_end: float
    other: str
    orbit: np.ndarray
    t: np.ndarray
    states: np.ndarray
    q: np.ndarray
    p: np.ndarray
    initial: np.ndarray
    crossings_per_orbit: Tuple[int, ...]
    max_energy_error: float

    @property
    def crossings(self) -> int:
        """Crossings of all orbits together."""
        return len(self.t)

    def orbits(self) -> list:
        """Per orbit, (t, states) of its crossings."""
        return [(self.t[self.orbit == k], self.states[self.orbit == k]) for k in range(self.count)]

    def plot(self, ax=None):
        """The section: the other angle against its momentum, one colour per orbit;
        returns the axes (matplotlib needed)."""
        ax = _axes(ax)
        ax.scatter(self.q, self.p, c=self.orbit, s=2, cmap="tab20")
        ax.set_xlabel(f"{self.other} (rad)")
        ax.set_ylabel(f"p{self.other[5:]}")
        ax.set_title(f"{self.system.name}: {self.section} = {self.value:g} (rising), E = {self.energy:g}")
        return ax

    def _repr_html_(self) -> str:
        return _table(
            "Poincaré section",
            [
                ("system", self.system.name),
                ("method", self.method),
                ("section", f"{self.section} = {self.value:g} rad, rising"),
                ("energy", f"{self.energy:g} J"),
                ("orbits", f"{self.count}, each {self.t_end:g} s"),
                ("crossings", self.crossings),
                ("max |H − E|", f"{self.max_energy_error:.2e} J"),
            ],
        )


def poincare(
    system: "System | str" = _REGISTRY["poincare"]["system"],
    *,
    energy: float = _REGISTRY["poincare"]["energy"],
    count: int = _REGISTRY["poincare"]["count"],
    section: str = _POINCARE_SECTION[0],
    value: float = _POINCARE_SECTION[1],
    t_end: float = _REGISTRY["poincare"]["t_end"],
    method: str = _REGISTRY["poincare"]["method"],
    dt: Optional[float] = None,
    tol: float = _REGISTRY["poincare"]["tol"],
    progress: Any = None,
) -> PoincareResult:
    """A Poincaré section of a conservative two-degree-of-freedom ``system`` (the double
    pendulum, or the chain with links=2), the library's ``poincare`` study (as ``pendula
    poincare``): ``count`` orbits (1 to 10000) started on the surface H = ``energy`` (J) on
    the section (R2 sequence), each followed for ``t_end`` (s), their crossings of
    ``section`` = ``value`` (an angle, rad, mod 2π) with that angle increasing located on
    the dense output. ``method`` adaptive (dop853, dopri5) at rtol = atol = ``tol``, or
    fixed steps ``dt`` (s) for any method. The system's initial-state values are not used.
    :func:`pendula.study` ``("poincare", section="theta1=0", ...)`` returns the same as a
    :class:`StudyReport`.

    ``progress``: by default (None) a line with the time elapsed appears where a terminal or
    notebook shows it, once the call has taken 3 s; ``True`` shows it from the start,
    ``False`` never; a callable gets the seconds elapsed, about every 20 ms.
    """
    system = _system(system)
    values = [
        ("system", system.name),
        ("energy", _float("energy", energy)),
        ("count", _int("count", count, 1, 10_000, "orbits")),
        # The section as the library reads it: NAME=VALUE, the value's shortest exact digits.
        ("section", f"{section}={_float('value', value)!r}"),
        ("t_end", _float("t_end", t_end)),
        ("method", str(method)),
        ("tol", _float("tol", tol)),
    ]
    if dt is not None:
        values.append(("dt", _float("dt", dt)))
    settings = [(k, float(v)) for k, v in system._changed().items()]
    raw = timed(progress, f"poincare {system.name}", lambda tick: _core.run_study("poincare", values, settings, tick))
    crossings, orbits = raw["tables"]["poincare"], raw["tables"]["orbits"]
    names = list(crossings)
    other, section_name = names[2], names[4]
    # Canonical (q₁, q₂, p₁, p₂) at each crossing: the section's angle as integrated, the
    # other one wrapped into [−π, π) as the section's picture shows it.
    angle = {section_name: crossings[section_name], other: crossings[other]}
    momentum = {"p" + section_name[5:]: crossings[names[5]], "p" + other[5:]: crossings[names[3]]}
    states = np.column_stack([angle["theta1"], angle["theta2"], momentum["p1"], momentum["p2"]])
    state_names = [n for n in orbits if n not in ("orbit", "crossings")]
    return PoincareResult(
        system=system,
        method=raw["inputs"]["method"],
        energy=float(energy),
        count=int(count),
        section=str(section),
        value=float(value),
        t_end=float(t_end),
        other=other,
        orbit=crossings["orbit"].astype(np.int64),
        t=crossings["t"],
        states=states,
        q=crossings[other],
        p=crossings[names[3]],
        initial=np.column_stack([orbits[n] for n in state_names]),
        crossings_per_orbit=tuple(int(c) for c in orbits["crossings"]),
        max_energy_error=float(raw["numbers"]["max_energy_error"]),
    )


# The flip fractal --------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class FractalResult(_Pickled):
    """The flip fractal: ``flip_time`` (n₂, n₁; θ₁ fastest, the layout of fractal.npy) the
    time to the first flip from rest (s; NaN: none by ``t_max`` or forbidden by energy), the
    same at dt/2 (``flip_time_half_step``), ``converged`` (bool, as fractal-converged.npy):
    both agree within ``tolerance`` s. Axes ``theta1``, ``theta2`` ((lo, hi, n), rad; the
    cell centres in ``theta1_centres``, ``theta2_centres``).
    """

    system: "System"
    method: str
    dt: float
    t_max: float
    tolerance: float
    theta1: Tuple[float, float, int]
    theta2: Tuple[float, float, int]
    flip_time: np.ndarray
    flip_time_half_step: np.ndarray
    converged: np.ndarray
    forbidden_by_energy: int
    theta1_centres: np.ndarray
    theta2_centres: np.ndarray

    @property
    def dt_check(self) -> float:
        """The convergence check's step, s."""
        return self.dt / 2

    @property
    def shape(self) -> Tuple[int, int]:
        return self.flip_time.shape

    @property
    def pixels(self) -> int:
        return self.flip_time.size

    @property
    def flipped(self) -> int:
        """Pixels that flip before ``t_max``."""
        return int(np.isfinite(self.flip_time).sum())

    @property
    def unconverged(self) -> int:
        return int((~self.converged).sum())

    @property
    def unconverged_share(self) -> float:
        return self.unconverged / self.pixels

    def plot(self, ax=None):
        """The flip times on a log colour scale (black: no flip); returns the axes
        (matplotlib needed)."""
        import matplotlib
        from matplotlib.colors import LogNorm

        ax = _axes(ax)
        cmap = matplotlib.colormaps["viridis"].with_extremes(bad="black")
        data = np.ma.masked_invalid(self.flip_time)
        finite = self.flip_time[np.isfinite(self.flip_time)]
        norm = LogNorm(vmin=max(finite.min(), self.dt), vmax=finite.max()) if finite.size else None
        image = ax.imshow(
            data,
            origin="lower",
            extent=(self.theta1[0], self.theta1[1], self.theta2[0], self.theta2[1]),
            cmap=cmap,
            norm=norm,
            aspect="auto",
            interpolation="nearest",
        )
        ax.figure.colorbar(image, ax=ax, label="time to first flip (s)")
        ax.set_xlabel("θ₁ (rad)")
        ax.set_ylabel("θ₂ (rad)")
        ax.set_title(f"double pendulum: time to first flip from rest ({self.method}, dt = {self.dt:g} s)")
        return ax

    def _repr_html_(self) -> str:
        return _table(
            "flip fractal",
            [
                ("grid", f"{self.shape[1]} × {self.shape[0]} (θ₁ × θ₂)"),
                ("method", f"{self.method}, dt = {self.dt:g} s and {self.dt_check:g} s"),
                ("t_max", f"{self.t_max:g} s"),
                ("flipped", self.flipped),
                ("forbidden by energy", self.forbidden_by_energy),
                ("unconverged", f"{self.unconverged} ({100 * self.unconverged_share:.2f}%)"),
            ],
        )


def fractal(
    system: "System | str" = _DEFAULTS["fractal"]["system"],
    *,
    theta1: Tuple[float, float, int] = _FRACTAL_GRID["theta1"],
    theta2: Tuple[float, float, int] = _FRACTAL_GRID["theta2"],
    t_max: float = _DEFAULTS["fractal"]["t_max"],
    method: str = _DEFAULTS["fractal"]["method"],
    dt: float = _DEFAULTS["fractal"]["dt"],
    tolerance: float = _DEFAULTS["fractal"]["tolerance"],
    threads: Optional[int] = None,
    progress: Any = None,
) -> FractalResult:
    """The double pendulum's flip fractal, as ``pendula fractal``: released from rest at the
    cell centres of ``theta1`` × ``theta2`` ((lo, hi, n), rad), the time to the first flip
    (either rod past ±π) up to ``t_max`` (s), on the ensemble engine with ``method`` (euler,
    rk4, tao-2 or tao-4) at ``dt`` (s) and again at dt/2 for the per-pixel convergence flag
    (agreement within ``tolerance`` s). ``system``: the double pendulum with its parameters
    (undamped, undriven); its initial-state values are not used. All cores unless
    ``threads``; the result does not depend on them. Ctrl-C stops it within a slice of
    pixels. ``progress``: a bar of the pixels done, by default (None) where a terminal or notebook
    shows it and the run is estimated to take 3 s or more; ``True`` always, ``False`` never;
    a callable gets the count instead.
    """
    system = _system(system)
    t1, t2 = _axis("theta1", theta1), _axis("theta2", theta2)
    raw = counted(
        progress,
        t1[2] * t2[2],
        "pixels",
        lambda tick: _core.fractal(
            system._core,
            t1,
            t2,
            _float("t_max", t_max),
            str(method),
            _float("dt", dt),
            _float("tolerance", tolerance),
            _threads(threads),
            tick,
        ),
        desc=f"fractal {system.name}",
    )
    return _fractal_result(system, raw, t1, t2, dt, t_max, tolerance)


def _fractal_result(system, raw, t1, t2, dt, t_max, tolerance) -> FractalResult:
    return FractalResult(
        system=system,
        method=raw["method"],
        dt=float(dt),
        t_max=float(t_max),
        tolerance=float(tolerance),
        theta1=t1,
        theta2=t2,
        flip_time=raw["flip_time"],
        flip_time_half_step=raw["flip_time_half_step"],
        converged=raw["converged"],
        forbidden_by_energy=int(raw["forbidden"]),
        theta1_centres=raw["theta1_centres"],
        theta2_centres=raw["theta2_centres"],
    )


# Bifurcation diagrams ----------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class BifurcationResult(_Pickled):
    """A stroboscopic orbit diagram: for each value of ``param`` (``values``, the cell
    centres), ``samples`` (n, samples, n_state): the state at drive phase 0 once per drive
    period after the transient (angles wrapped into [−π, π), rad; velocities rad/s).
    ``variable`` is the state variable plotted; ``kernel`` the engine that ran it.
    """

    system: "System"
    param: Tuple[str, float, float, int]
    transient: float
    steps_per_period: int
    variable: str
    names: Tuple[str, ...]
    values: np.ndarray
    samples: np.ndarray
    kernel: str

    @property
    def points(self) -> Tuple[np.ndarray, np.ndarray]:
        """(parameter, variable) of every sample, flattened: the diagram's dots."""
        k = self.names.index(self.variable)
        n, s = self.samples.shape[:2]
        return np.repeat(self.values, s), self.samples[:, :, k].reshape(n * s)

    def plot(self, ax=None):
        """The diagram: the variable at drive phase 0 against the parameter; returns the
        axes (matplotlib needed)."""
        ax = _axes(ax)
        x, y = self.points
        ax.plot(x, y, ",", color="C1")
        ax.set_xlabel(self.param[0])
        ax.set_ylabel(f"{self.variable} at drive phase 0")
        ax.set_title(f"{self.system.name}: {self.samples.shape[1]} samples per value (RK4, {self.steps_per_period} steps/period)")
        return ax

    def _repr_html_(self) -> str:
        name, lo, hi, n = self.param
        return _table(
            "orbit diagram",
            [
                ("system", self.system.name),
                ("param", f"{name}: {n} values in [{lo:g}, {hi:g}]"),
                ("transient", f"{self.transient:g} s"),
                ("samples", f"{self.samples.shape[1]} per value"),
                ("steps per period", self.steps_per_period),
                ("kernel", self.kernel),
            ],
        )


def bifurcation(
    system: "System | str" = _REGISTRY["bifurcation"]["system"],
    *,
    param: Optional[Tuple[str, float, float, int]] = None,
    transient: float = _REGISTRY["bifurcation"]["transient"],
    samples: int = _REGISTRY["bifurcation"]["samples"],
    steps_per_period: int = _REGISTRY["bifurcation"]["steps_per_period"],
    variable: Optional[str] = None,
    threads: Optional[int] = None,
    progress: Any = None,
) -> BifurcationResult:
    """A stroboscopic orbit diagram of a driven ``system``, the library's ``bifurcation``
    study (as ``pendula bifurcation``): ``param`` = (name, lo, hi, n) swept over n cell
    centres (default for the driven pendulum: ("drive_amplitude", 1.0, 1.5, 800); required
    for other systems), the other values the system's; per value, ``samples`` (1 to 10^6)
    states once per drive period after ``transient`` (s, rounded up to whole periods), RK4
    at ``steps_per_period`` (4 to 10^6). ``variable``: the state variable the plot shows
    (default: the first velocity). All cores unless ``threads``; the result does not depend
    on them. :func:`pendula.study` ``("bifurcation", param="drive_amplitude=1:1.5:800",
    ...)`` returns the same as a :class:`StudyReport`.

    ``progress``: by default (None) a line with the time elapsed appears where a terminal or
    notebook shows it, once the call has taken 3 s; ``True`` shows it from the start,
    ``False`` never; a callable gets the seconds elapsed, about every 20 ms.
    """
    system = _system(system)
    values = [
        ("system", system.name),
        ("transient", _float("transient", transient)),
        ("samples", _int("samples", samples, 1, 1_000_000, "samples")),
        ("steps_per_period", _int("steps_per_period", steps_per_period, 4, 1_000_000, "steps")),
    ]
    if param is not None:
        try:
            name, lo, hi, n = param
        except (TypeError, ValueError):
            raise InvalidValueError(f"invalid param {param!r}: (name, lo, hi, n)") from None
        # The axis as the library reads it: NAME=LO:HI:N, the bounds' shortest exact digits.
        values.append(("param", f"{name}={_float('param', lo)!r}:{_float('param', hi)!r}:{_int('param', n, 1, 1 << 24, 'values')}"))
    if variable is not None:
        values.append(("variable", str(variable)))
    if threads is not None:
        values.append(("threads", _threads(threads)))
    settings = [(k, float(v)) for k, v in system._changed().items()]
    raw = timed(progress, f"bifurcation {system.name}", lambda tick: _core.run_study("bifurcation", values, settings, tick))
    table, n = raw["tables"]["bifurcation"], int(raw["numbers"]["n"])
    names = tuple(system.names)
    columns = list(table)
    per_value = len(table["sample"]) // n
    return BifurcationResult(
        system=system,
        param=(columns[0], raw["numbers"]["lo"], raw["numbers"]["hi"], n),
        transient=float(transient),
        steps_per_period=int(steps_per_period),
        variable=raw["inputs"]["variable"],
        names=names,
        values=table[columns[0]][::per_value].copy(),
        samples=np.stack([table[q] for q in names], axis=-1).reshape(n, per_value, len(names)),
        kernel=raw["tables"]["run"]["kernel"][0],
    )


# Convergence orders ------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class MethodConvergence(_Pickled):
    """One method's convergence: its steps ``dt`` (s) and max-norm errors ``error`` at the
    end time; ``order`` fitted over ``fit`` = (points, h_min, h_max) in the asymptotic range,
    or None with the ``reason``; ``failure``: why steps are missing (the library's message),
    if any are; ``note``: the fit's range or why there is no order, and ``label``: the
    order or the reason's first words (the library's wording for tables and legends)."""

    method: str
    dt: np.ndarray
    error: np.ndarray
    order: Optional[float]
    fit: Optional[Tuple[int, float, float]]
    reason: Optional[str]
    failure: Optional[str]
    note: str = ""
    label: str = ""


@dataclass(frozen=True, eq=False)
class ConvergenceResult(_Pickled):
    """A convergence study: per method (``methods``, in order) errors against steps and the
    fitted order; ``t_end`` (s) and the ``reference`` the errors are against. ``orders``,
    ``dt``, ``notes``: dicts by method name."""

    system: "System"
    t_end: float
    reference: str
    methods: Tuple[MethodConvergence, ...]

    def __getitem__(self, method: str) -> MethodConvergence:
        for m in self.methods:
            if m.method == method:
                return m
        raise KeyError(method)

    @property
    def orders(self) -> dict:
        return {m.method: m.order for m in self.methods}

    @property
    def dt(self) -> dict:
        return {m.method: m.dt for m in self.methods}

    @property
    def notes(self) -> dict:
        return {m.method: m.note for m in self.methods}

    def plot(self, ax=None):
        """Error against step on log-log axes, one line per method; returns the axes
        (matplotlib needed)."""
        ax = _axes(ax)
        for m in self.methods:
            if len(m.dt):
                ax.loglog(m.dt, m.error, marker="o", markersize=3, label=f"{m.method} ({m.label})")
        ax.set_xlabel("step size h" + _time_unit(self.system))
        ax.set_ylabel("max |y(t) − y_ref(t)|")
        unit = "" if self.system.dimensionless else " s"
        ax.set_title(f"{self.system.name}: global error at t = {self.t_end:.4g}{unit}, against the {self.reference}")
        ax.legend(fontsize="small")
        return ax

    def _repr_html_(self) -> str:
        head = "<tr><th>method</th><th>fitted order</th><th>note</th></tr>"
        body = "".join(
            f"<tr><td>{m.method}</td><td>{'-' if m.order is None else f'{m.order:.3f}'}</td><td>{m.note}</td></tr>"
            for m in self.methods
        )
        caption = f"{self.system.name}: error at t = {self.t_end:.4g} s against the {self.reference}"
        return f"<table><caption>{caption}</caption>{head}{body}</table>"


def convergence(
    system: "System | str" = _REGISTRY["convergence"]["system"],
    *,
    methods: "Sequence[str] | str | None" = None,
    dts: Any = None,
    t_end: Optional[float] = None,
    progress: Any = None,
) -> ConvergenceResult:
    """The order of convergence of ``methods`` (names, or a comma-separated string; default:
    every method that applies) on ``system``, the library's ``convergence`` study (as
    ``pendula convergence``): the max-norm error at ``t_end`` (s; default: the system's study
    horizon, a few small-oscillation periods) against the exact solution or a dop853
    reference at tolerance 1e-14, at the steps ``dts`` (s; default: each method's own ladder
    of halved steps), and the order fitted where the errors are in the asymptotic range. A
    method that fails at some step keeps the errors of the others and says why
    (``failure``). :func:`pendula.study` ``("convergence", ...)`` takes the geometric ladder
    (``dt_min``, ``dt_max``, ``levels``) too.

    ``progress``: by default (None) a line with the time elapsed appears where a terminal or
    notebook shows it, once the call has taken 3 s; ``True`` shows it from the start,
    ``False`` never; a callable gets the seconds elapsed, about every 20 ms.
    """
    system = _system(system)
    values = _accuracy_inputs(system, methods, dts, t_end)
    settings = [(k, float(v)) for k, v in system._changed().items()]
    raw = timed(progress, f"convergence {system.name}", lambda tick: _core.run_study("convergence", values, settings, tick))
    points, orders, fits = (raw["tables"][t] for t in ("convergence", "orders", "fits"))
    methods_out = []
    for i, m in enumerate(orders["method"]):
        mine = np.array([name == m for name in points["method"]], dtype=bool)
        fitted = not math.isnan(orders["fitted_order"][i])
        methods_out.append(
            MethodConvergence(
                method=m,
                dt=points["dt"][mine].copy(),
                error=points["error"][mine].copy(),
                order=float(orders["fitted_order"][i]) if fitted else None,
                fit=(int(fits["points"][i]), float(fits["dt_min"][i]), float(fits["dt_max"][i])) if fitted else None,
                reason=fits["reason"][i] or None,
                failure=fits["failure"][i] or None,
                note=orders["note"][i],
                label=fits["label"][i],
            )
        )
    return ConvergenceResult(
        system=system,
        t_end=float(raw["inputs"]["t_end"]),
        reference=raw["texts"]["reference"],
        methods=tuple(methods_out),
    )


def _accuracy_inputs(system: "System", methods: Any, dts: Any, t_end: Any) -> list:
    """The inputs of an accuracy study (convergence, work-precision) that are given."""
    values: list = [("system", system.name)]
    if methods is not None:
        values.append(("methods", ",".join(_names(methods))))
    if dts is not None:
        values.append(("dts", _steps("dts", dts)))
    if t_end is not None:
        values.append(("t_end", _float("t_end", t_end)))
    return values


# Work-precision diagrams -------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class MethodWork(_Pickled):
    """One method's work-precision points: ``dt`` (s; for an adaptive run the mean accepted
    step), ``tol`` (rtol = atol of an adaptive run, NaN for fixed steps), ``error`` (max norm
    at the end time), ``rhs_evals``, ``wall_s`` (s, median of repeated runs); ``failure``:
    why points are missing, if any are."""

    method: str
    dt: np.ndarray
    tol: np.ndarray
    error: np.ndarray
    rhs_evals: np.ndarray
    wall_s: np.ndarray
    failure: Optional[str]


@dataclass(frozen=True, eq=False)
class WorkPrecisionResult(_Pickled):
    """A work-precision study: per method (``methods``) error against cost, at ``t_end``
    (s) against the ``reference``."""

    system: "System"
    t_end: float
    reference: str
    methods: Tuple[MethodWork, ...]

    def __getitem__(self, method: str) -> MethodWork:
        for m in self.methods:
            if m.method == method:
                return m
        raise KeyError(method)

    def plot(self, ax=None, cost: str = "rhs_evals"):
        """Error against cost (``"rhs_evals"`` or ``"wall_s"``) on log-log axes; returns the
        axes (matplotlib needed)."""
        if cost not in ("rhs_evals", "wall_s"):
            raise InvalidValueError(f"invalid cost {cost!r}: 'rhs_evals' or 'wall_s'")
        ax = _axes(ax)
        for m in self.methods:
            if len(m.error):
                ax.loglog(getattr(m, cost), m.error, marker="o", markersize=3, label=m.method)
        ax.set_xlabel("right-hand-side evaluations" if cost == "rhs_evals" else "wall time (s)")
        ax.set_ylabel("max |y(t) − y_ref(t)|")
        ax.set_title(f"{self.system.name}: work-precision at t = {self.t_end:.4g}, against the {self.reference}")
        ax.legend(fontsize="small")
        return ax

    def _repr_html_(self) -> str:
        head = "<tr><th>method</th><th>rhs evals for error ≤ 1e-6</th><th>smallest error</th><th>note</th></tr>"
        rows = []
        for m in self.methods:
            reach = m.error <= 1e-6
            best = str(int(m.rhs_evals[reach].min())) if reach.any() else "-"
            smallest = f"{m.error.min():.3e}" if len(m.error) else "-"
            rows.append(f"<tr><td>{m.method}</td><td>{best}</td><td>{smallest}</td><td>{m.failure or ''}</td></tr>")
        caption = f"{self.system.name}: error at t = {self.t_end:.4g} s against the {self.reference}"
        return f"<table><caption>{caption}</caption>{head}{''.join(rows)}</table>"


def work_precision(
    system: "System | str" = _REGISTRY["work-precision"]["system"],
    *,
    methods: "Sequence[str] | str | None" = None,
    dts: Any = None,
    tols: Any = None,
    t_end: Optional[float] = None,
    progress: Any = None,
) -> WorkPrecisionResult:
    """Error against cost of ``methods`` (default: every method that applies) on
    ``system``, the library's ``work-precision`` study (as ``pendula work-precision``):
    fixed-step methods at the steps ``dts`` (s; default: each method's own ladder), the
    adaptive pairs (dopri5, dop853) at the tolerances ``tols`` (rtol = atol; default: 10 from
    1e-3 to 1e-12, geometric), the error at ``t_end`` (s; default: the system's study horizon)
    against the exact solution or a dop853 reference. Wall times are medians of runs repeated
    for at least 20 ms.

    ``progress``: by default (None) a line with the time elapsed appears where a terminal or
    notebook shows it, once the call has taken 3 s; ``True`` shows it from the start,
    ``False`` never; a callable gets the seconds elapsed, about every 20 ms.
    """
    system = _system(system)
    values = _accuracy_inputs(system, methods, dts, t_end)
    if tols is not None:
        values.append(("tols", _steps("tols", tols)))
    settings = [(k, float(v)) for k, v in system._changed().items()]
    raw = timed(progress, f"work-precision {system.name}", lambda tick: _core.run_study("work-precision", values, settings, tick))
    points, costs = raw["tables"]["work_precision"], raw["tables"]["costs"]
    out = []
    for i, m in enumerate(costs["method"]):
        mine = np.array([name == m for name in points["method"]], dtype=bool)
        out.append(
            MethodWork(
                method=m,
                **{k: np.asarray(points[k])[mine].copy() for k in ("dt", "tol", "error", "rhs_evals", "wall_s")},
                failure=costs["failure"][i] or None,
            )
        )
    return WorkPrecisionResult(
        system=system,
        t_end=float(raw["inputs"]["t_end"]),
        reference=raw["texts"]["reference"],
        methods=tuple(out),
    )


# Divergence of nearby trajectories ---------------------------------------------------


@dataclass(frozen=True, eq=False)
class DivergenceResult(_Pickled):
    """The distance between two runs started ``delta`` apart in ``variable``: ``t`` (s)
    and ``distance`` (Euclidean, state units mixed) at about 2000 samples; the exponential
    ``growth_rate`` (1/s) fitted over ``fit_window`` (s), before the distance first exceeds
    ``saturation`` (None when too few samples lie below it)."""

    system: "System"
    method: str
    dt: float
    t_end: float
    delta: float
    variable: str
    saturation: float
    t: np.ndarray
    distance: np.ndarray
    growth_rate: Optional[float]
    fit_window: Optional[Tuple[float, float]]

    def plot(self, ax=None):
        """The distance on a log scale against time, with the fitted line; returns the axes
        (matplotlib needed)."""
        ax = _axes(ax)
        keep = self.distance > 0
        ax.semilogy(self.t[keep], self.distance[keep], label="distance")
        if self.growth_rate is not None:
            t0, t1 = self.fit_window
            window = keep & (self.t >= t0) & (self.t <= t1)
            mean_log = np.log(self.distance[window]).mean()
            ts = np.linspace(t0, t1, 51)
            ax.semilogy(ts, np.exp(mean_log + self.growth_rate * (ts - 0.5 * (t0 + t1))), "--", label=f"fit: rate {self.growth_rate:.3f}")
        ax.set_xlabel("t" + _time_unit(self.system))
        ax.set_ylabel("distance in state space")
        ax.set_title(f"{self.system.name}: divergence of trajectories {self.delta:g} apart in {self.variable} ({self.method})")
        ax.legend()
        return ax

    def _repr_html_(self) -> str:
        rate = "too few samples below saturation" if self.growth_rate is None else f"{self.growth_rate:.4f} 1/s"
        window = "-" if self.fit_window is None else f"{self.fit_window[0]:.2f} … {self.fit_window[1]:.2f} s"
        return _table(
            "divergence",
            [
                ("system", self.system.name),
                ("method", f"{self.method}, dt = {self.dt:g} s, to {self.t_end:g} s"),
                ("separation", f"{self.delta:g} in {self.variable}"),
                ("growth rate", rate),
                ("fit window", window),
            ],
        )


def divergence(
    system: "System | str" = _REGISTRY["divergence"]["system"],
    *,
    method: str = _REGISTRY["divergence"]["method"],
    dt: float = _REGISTRY["divergence"]["dt"],
    t_end: float = _REGISTRY["divergence"]["t_end"],
    delta: float = _REGISTRY["divergence"]["delta"],
    variable: Optional[str] = None,
    saturation: float = _REGISTRY["divergence"]["saturation"],
    fit_from: float = _REGISTRY["divergence"]["fit_from"],
    progress: Any = None,
) -> DivergenceResult:
    """The divergence of nearby trajectories, the library's ``divergence`` study (as
    ``pendula divergence``): ``system`` from its initial state and from the same with
    ``delta`` added to ``variable`` (default: the first state variable), both by ``method``
    at steps ``dt`` (s) to ``t_end`` (s); the distance at about 2000 samples and the
    exponential growth rate (1/s) fitted to ln(distance) above ``fit_from`` and before it
    first exceeds ``saturation`` — a finite-time estimate of the largest Lyapunov exponent.
    :func:`pendula.study` ``("divergence", ...)`` returns the same as a :class:`StudyReport`.

    ``progress``: by default (None) a line with the time elapsed appears where a terminal or
    notebook shows it, once the call has taken 3 s; ``True`` shows it from the start,
    ``False`` never; a callable gets the seconds elapsed, about every 20 ms.
    """
    system = _system(system)
    values = [
        ("system", system.name),
        ("method", str(method)),
        ("dt", _float("dt", dt)),
        ("t_end", _float("t_end", t_end)),
        ("delta", _float("delta", delta)),
        ("saturation", _float("saturation", saturation)),
        ("fit_from", _float("fit_from", fit_from)),
    ]
    if variable is not None:
        values.append(("variable", str(variable)))
    settings = [(k, float(v)) for k, v in system._changed().items()]
    raw = timed(progress, f"divergence {system.name}", lambda tick: _core.run_study("divergence", values, settings, tick))
    n, table = raw["numbers"], raw["tables"]["divergence"]
    fitted = not math.isnan(n["growth_rate"])
    return DivergenceResult(
        system=system,
        method=raw["inputs"]["method"],
        dt=float(dt),
        t_end=float(t_end),
        delta=float(delta),
        variable=raw["inputs"]["variable"],
        saturation=float(saturation),
        t=table["t"],
        distance=table["distance"],
        growth_rate=n["growth_rate"] if fitted else None,
        fit_window=(n["fit_start"], n["fit_end"]) if fitted else None,
    )
