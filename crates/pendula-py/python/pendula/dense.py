"""The continuous solution of a run (``Solution.sol``), event location for Python callables on
it, and the progress bar of long runs."""

from __future__ import annotations

import math
import sys
import time
from typing import Any, Callable, Optional

import numpy as np

from . import _core
from .errors import InvalidValueError, PendulaError

#: The version of DenseOutput's pickled form.
DENSE_PICKLE_VERSION = 1


class DenseOutput:
    """``sol(t)``: the state at any time t (s) within the run, from one step's interpolant.

    Where the method has its own dense output (the adaptive pairs: dop853 of order 7,
    dopri5 of order 4, Hairer's polynomials) it is that; else the cubic Hermite interpolant
    through the state and its derivative at both ends of the step (error O(h⁴), order 3).
    ``order`` says which. ``sol(t)`` takes a number, giving the state (n_state,), or an
    array of times (m,), giving (n_state, m) as scipy's ``OdeSolution``. A run backward in
    time (``t_span=(10, 0)``) has decreasing ``ts``; ``t_min`` < ``t_max`` either way.
    """

    def __init__(
        self,
        t: np.ndarray,
        states: np.ndarray,
        f: np.ndarray,
        steps: np.ndarray | None = None,
        coefficients: np.ndarray | None = None,
        order: int = 3,
    ):
        self.ts = t
        self.states = states
        self.f = f
        self.steps = steps
        self.coefficients = coefficients
        #: The interpolant's order: its local error is O(h^(order + 1)).
        self.order = order

    @property
    def t_min(self) -> float:
        """The earliest time covered, s (the start of a run backward in time)."""
        return float(min(self.ts[0], self.ts[-1]))

    @property
    def t_max(self) -> float:
        """The latest time covered, s."""
        return float(max(self.ts[0], self.ts[-1]))

    def __call__(self, t: Any) -> np.ndarray:
        tq = np.asarray(t, dtype=np.float64)
        scalar = tq.ndim == 0
        tq = np.atleast_1d(tq).reshape(-1)
        slack = 1e-12 * max(1.0, abs(self.t_min), abs(self.t_max))
        bad = ~np.isfinite(tq) | (tq < self.t_min - slack) | (tq > self.t_max + slack)
        if bad.any():
            v = tq[np.argmax(bad)]
            raise InvalidValueError(f"invalid time {v}: sol covers [{self.t_min}, {self.t_max}] s")
        out = self._at(np.clip(tq, self.t_min, self.t_max))
        return out[:, 0] if scalar else out

    def _at(self, tq: np.ndarray) -> np.ndarray:
        # The library's continuous solution (pendula::events::Continuous): the step's own
        # dense output, or the cubic Hermite interpolant.
        c = np.ascontiguousarray
        dense = self.coefficients is not None
        return _core.dense_at(
            c(self.ts, dtype=np.float64),
            c(self.states, dtype=np.float64),
            c(self.f, dtype=np.float64),
            c(self.steps, dtype=np.float64) if dense else None,
            c(self.coefficients, dtype=np.float64) if dense else None,
            c(tq, dtype=np.float64),
        )

    def __reduce__(self):
        return (
            _dense_from_pickle,
            (DENSE_PICKLE_VERSION, self.ts, self.states, self.f, self.steps, self.coefficients, self.order),
        )

    def __repr__(self) -> str:
        kind = "cubic Hermite" if self.coefficients is None else "the method's dense output"
        return f"<DenseOutput on [{self.t_min:g}, {self.t_max:g}] s, {kind}, order {self.order}>"


def _dense_from_pickle(version, t, states, f, steps, coefficients, order):
    if version != DENSE_PICKLE_VERSION:
        raise PendulaError(
            f"a pickled DenseOutput of version {version}; this pendula reads version {DENSE_PICKLE_VERSION}"
        )
    return DenseOutput(t, states, f, steps, coefficients, order)


def locate(g: Callable[[float, np.ndarray], float], sol: DenseOutput, t: np.ndarray, y: np.ndarray):
    """The crossings of zero of ``g(t, y)`` along a run (scipy's event convention:
    ``g.direction`` > 0 counts rising crossings only, < 0 falling only, 0 both), each
    bisected on the step's interpolant by the library's own locator (``pendula::events::bisect``:
    to 1e-13 relative in t, absolute below 1 s). On a run backward in time ``t`` decreases,
    and rising means rising as the run goes (scipy's convention). Returns a list of (t, state)."""
    direction = float(getattr(g, "direction", 0.0))
    found = []
    values = np.array([float(g(float(ti), yi)) for ti, yi in zip(t, y)])
    for k in range(1, len(t)):
        a, b = values[k - 1], values[k]
        up, down = a < 0.0 and b >= 0.0, a > 0.0 and b <= 0.0
        if not ((up and direction >= 0) or (down and direction <= 0)):
            continue
        t0, t1 = float(t[k - 1]), float(t[k])
        h = t1 - t0
        s = _core.bisect(h, t1, math.copysign(1.0, a), lambda s: float(g(t0 + s * h, sol(t0 + s * h))))
        te = t0 + s * h
        found.append((te, sol(te)))
    return found


#: A call whose run is estimated to take at least this long (s) shows a bar by default.
AUTO_SECONDS = 3.0
#: The estimate is made once the run has gone this long (s): earlier, start-up costs (threads,
#: first allocations) make the rate of progress a poor guide.
AUTO_AFTER = 0.5


def interactive(stream: Any = None) -> bool:
    """Whether someone is likely watching: ``stream`` (default ``sys.stderr``) is a terminal,
    or the code runs in a Jupyter kernel (where stderr is not a terminal, yet shows)."""
    stream = sys.stderr if stream is None else stream
    try:
        if stream is not None and stream.isatty():
            return True
    except (AttributeError, ValueError, OSError):
        pass
    shell = sys.modules.get("IPython")
    if shell is None or "ipykernel" not in sys.modules:
        return False
    try:
        ip = shell.get_ipython()
    except Exception:  # noqa: BLE001 (any failure: not a notebook)
        return False
    return ip is not None and hasattr(ip, "kernel")


def estimate_seconds(elapsed: float, fraction: Optional[float]) -> float:
    """The run's whole duration as its progress so far suggests (s): elapsed / fraction done;
    the time elapsed (a lower bound) where the fraction is unknown (None) or still 0."""
    if fraction is None or fraction <= 0.0:
        return elapsed
    return elapsed / min(fraction, 1.0)


def show_bar(progress: Any, estimated: float, watched: bool) -> bool:
    """The rule for the bar: ``progress=True`` always shows it, ``False`` never; the default
    (``None``) shows it where someone is watching (``watched``: a terminal or a notebook,
    see :func:`interactive`) and the run is estimated to take ``AUTO_SECONDS`` (3 s) or more."""
    if progress is True:
        return True
    if progress is None:
        return watched and estimated >= AUTO_SECONDS
    return False


def check_progress(progress: Any, what: str) -> None:
    """Refuses a ``progress`` other than None, True, False or a callable."""
    if progress is None or isinstance(progress, bool) or callable(progress):
        return
    raise InvalidValueError(
        f"invalid value {progress!r} for `progress`: None (a bar where a terminal or notebook shows "
        f"one and the call is estimated to take {AUTO_SECONDS:g} s or more), True, False or a callable of {what}"
    )


class Progress:
    """A bar for a run from t0 to t_end (either way in time), or a count of members, cells,
    pixels from 0 to a total (``label=None``): tqdm's (``tqdm.auto``: terminal or notebook)
    when tqdm is installed, else a line on stderr redrawn in place.

    With ``auto=True`` (``progress=None``, the default) nothing shows until the run has gone
    ``AUTO_AFTER`` s and :func:`show_bar` says that its estimated duration calls for a bar;
    a run that ends sooner prints nothing."""

    def __init__(
        self,
        t0: float,
        t_end: float,
        unit: str = "s",
        desc: str = "pendula",
        label: Optional[str] = "t",
        auto: bool = False,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.t0, self.span = t0, abs(t_end - t0)
        # +1 forward, -1 for a run backward in time: progress is the distance run.
        self.direction = -1.0 if t_end < t0 else 1.0
        self.unit = unit
        self.desc = desc
        self.label = label
        self.clock = clock
        self.started = clock()
        self.bar = None
        self.shown = False
        self.done = 0
        if not auto:
            self._show()

    def _show(self) -> None:
        self.shown = True
        try:
            from tqdm.auto import tqdm
        except ImportError:
            self.bar = None
        else:
            # A time bar: the simulated time run, to 4 digits (not 95.39100000000002/600.0).
            unit = f" {self.unit}" if self.unit else ""
            fmt = None if self.label is None else "{l_bar}{bar}| {n:.4g}/{total:.4g}" + unit + " [{elapsed}<{remaining}]"
            self.bar = tqdm(total=self.span, unit=self.unit or "it", desc=self.desc, leave=False, bar_format=fmt)

    def __call__(self, t: float) -> None:
        # The distance run; whole counts stay whole (a bar of members reads 12/300, not 12.0/300).
        done = min(max(t - self.t0 if self.direction > 0 else self.t0 - t, 0), self.span)
        if not self.shown:
            elapsed = self.clock() - self.started
            fraction = done / self.span if self.span > 0 else None
            if elapsed < AUTO_AFTER or not show_bar(None, estimate_seconds(elapsed, fraction), True):
                return
            self._show()
            self.done = 0
        if self.bar is not None:
            self.bar.update(done - self.done)
        else:
            filled = int(30 * done / self.span) if self.span > 0 else 30
            share = 100 * done / self.span if self.span > 0 else 100.0
            where = (
                f"{self.label} = {self.t0 + self.direction * done:.4g}{' ' + self.unit if self.unit else ''}"
                if self.label
                else f"{done:.0f} of {self.span:.0f} {self.unit}"
            )
            sys.stderr.write(f"\r{self.desc}: [{'#' * filled}{'.' * (30 - filled)}] {share:5.1f}%  {where}")
            sys.stderr.flush()
        self.done = done

    def close(self, t: float | None) -> None:
        """Ends the bar at time t (None: where it was, for a run that raised); a bar never
        shown stays unshown."""
        if not self.shown:
            return
        if t is not None:
            self(t)
        if self.bar is not None:
            self.bar.close()
        else:
            sys.stderr.write("\n")
            sys.stderr.flush()


def time_bar(progress: Any, t0: float, t_end: float, unit: str, desc: str) -> tuple[Any, Optional[Progress]]:
    """What a run over time calls with the time reached: a bar for ``progress=True``, a bar
    that shows itself if the run proves long for the default ``None`` where someone watches,
    the user's callable, or None; and the bar to close afterwards."""
    check_progress(progress, "the time reached")
    if progress is True or (progress is None and interactive()):
        bar = Progress(t0, t_end, unit=unit, desc=desc, auto=progress is None)
        return bar, bar
    if callable(progress) and not isinstance(progress, bool):
        return progress, None
    return None, None


def counter(progress: Any, total: int, unit: str, desc: str = "pendula") -> tuple[Any, Progress | None]:
    """What a counted run (members, cells, pixels) calls with its count: a bar for
    ``progress=True``, a bar that shows itself if the run proves long for the default
    ``None`` where someone watches, the user's callable, or None; and the bar to close
    afterwards."""
    check_progress(progress, "the count")
    if progress is True or (progress is None and interactive()):
        bar = Progress(0, total, unit=unit, desc=desc, label=None, auto=progress is None)
        return bar, bar
    if callable(progress) and not isinstance(progress, bool):
        return progress, None
    return None, None


def counted(progress: Any, total: int, unit: str, run: Callable[[Any], Any], desc: str = "pendula") -> Any:
    """``run(tick)`` with the progress of ``counter``; the bar ends at ``total`` when the run
    returns (where it was, when it raised), and a callable hears ``total`` last."""
    tick, bar = counter(progress, total, unit, desc)
    try:
        out = run(tick)
    except BaseException:
        if bar is not None:
            bar.close(None)
        raise
    if bar is not None:
        bar.close(total)
    elif tick is not None:
        tick(total)
    return out


class Elapsed:
    """A line for a call whose work is not counted (the studies): its name and the time it
    has taken, tqdm's when tqdm is installed, else a line on stderr redrawn in place. With
    ``auto=True`` (``progress=None``) it appears once the call has taken ``AUTO_SECONDS``
    (the time elapsed is then the estimate: a lower bound)."""

    def __init__(self, desc: str, auto: bool = False, clock: Callable[[], float] = time.monotonic):
        self.desc = desc
        self.clock = clock
        self.started = clock()
        self.auto = auto
        self.shown = False
        self.bar = None
        self.said = -1  # the whole seconds the fallback line last said
        if not auto:
            self._show()

    def _show(self) -> None:
        self.shown = True
        try:
            from tqdm.auto import tqdm
        except ImportError:
            self.bar = None
        else:
            self.bar = tqdm(total=None, desc=self.desc, bar_format="{desc}: working, {elapsed} elapsed", leave=False)

    def __call__(self, _count: Any = None) -> None:
        elapsed = self.clock() - self.started
        if not self.shown:
            if not show_bar(None, estimate_seconds(elapsed, None), True):
                return
            self._show()
        if self.bar is not None:
            self.bar.update(0)  # redrawn at tqdm's pace, with the time elapsed
        elif int(elapsed) != self.said:
            self.said = int(elapsed)
            sys.stderr.write(f"\r{self.desc}: working, {self.said} s elapsed")
            sys.stderr.flush()

    def close(self) -> None:
        """Ends the line with the time taken; a line never shown stays unshown."""
        if not self.shown:
            return
        if self.bar is not None:
            self.bar.close()
        else:
            sys.stderr.write(f"\r{self.desc}: done in {self.clock() - self.started:.1f} s\n")
            sys.stderr.flush()


def timed(progress: Any, desc: str, run: Callable[[Any], Any]) -> Any:
    """``run(tick)`` for a call whose work is not counted: ``tick`` is an :class:`Elapsed`
    line for ``progress=True``, or for the default ``None`` where someone watches (it then
    appears once the call has taken 3 s); the user's callable, given the seconds elapsed;
    or None."""
    check_progress(progress, "the seconds elapsed")
    line: Optional[Elapsed] = None
    if progress is True or (progress is None and interactive()):
        line = Elapsed(desc, auto=progress is None)
        tick: Any = line
    elif callable(progress) and not isinstance(progress, bool):
        started = time.monotonic()
        tick = lambda _count: progress(time.monotonic() - started)  # noqa: E731
    else:
        tick = None
    try:
        return run(tick)
    finally:
        if line is not None:
            line.close()
