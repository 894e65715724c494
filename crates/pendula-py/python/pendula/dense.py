"""The continuous solution of a run (``Solution.sol``), event location for Python callables on
it, and the progress bar of long runs."""

from __future__ import annotations

import math
import sys
from typing import Any, Callable

import numpy as np

from .errors import InvalidValueError, PendulaError

#: The version of DenseOutput's pickled form.
DENSE_PICKLE_VERSION = 1


class DenseOutput:
    """``sol(t)``: the state at any time t (s) within the run, from one step's interpolant.

    Where the method has its own dense output (the adaptive pairs: dop853 of order 7,
    dopri5 of order 4, Hairer's polynomials) it is that; else the cubic Hermite interpolant
    through the state and its derivative at both ends of the step (error O(h⁴), order 3).
    ``order`` says which. ``sol(t)`` takes a number, giving the state (n_state,), or an
    array of times (m,), giving (n_state, m) as scipy's ``OdeSolution``.
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
        return float(self.ts[0])

    @property
    def t_max(self) -> float:
        return float(self.ts[-1])

    def __call__(self, t: Any) -> np.ndarray:
        tq = np.asarray(t, dtype=np.float64)
        scalar = tq.ndim == 0
        tq = np.atleast_1d(tq).reshape(-1)
        slack = 1e-12 * max(1.0, abs(self.t_max))
        bad = ~np.isfinite(tq) | (tq < self.t_min - slack) | (tq > self.t_max + slack)
        if bad.any():
            v = tq[np.argmax(bad)]
            raise InvalidValueError(f"invalid time {v}: sol covers [{self.t_min}, {self.t_max}] s")
        out = self._at(np.clip(tq, self.t_min, self.t_max))
        return out[:, 0] if scalar else out

    def _at(self, tq: np.ndarray) -> np.ndarray:
        if len(self.ts) == 1:
            return np.repeat(self.states[0][:, None], len(tq), axis=1)
        i = np.clip(np.searchsorted(self.ts, tq, side="right") - 1, 0, len(self.ts) - 2)
        if self.coefficients is not None:
            # Hairer's form: r₀ + θ(r₁ + (1−θ)(r₂ + θ(r₃ + …))), θ = (t − t₀)/h.
            t0, h = self.steps[i, 0], self.steps[i, 1]
            theta = ((tq - t0) / h)[:, None]
            c = self.coefficients[i]
            terms = c.shape[1]
            acc = c[:, terms - 1, :]
            for j in range(terms - 2, -1, -1):
                acc = c[:, j, :] + (theta if j % 2 == 0 else 1.0 - theta) * acc
            return acc.T
        t0, t1 = self.ts[i], self.ts[i + 1]
        h = (t1 - t0)[:, None]
        s = ((tq - t0) / (t1 - t0))[:, None]
        s2, s3 = s * s, s * s * s
        y = (
            (2 * s3 - 3 * s2 + 1) * self.states[i]
            + (s3 - 2 * s2 + s) * h * self.f[i]
            + (-2 * s3 + 3 * s2) * self.states[i + 1]
            + (s3 - s2) * h * self.f[i + 1]
        )
        return y.T

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
    bisected on the step's interpolant to 1e-13 relative in t (absolute below 1 s), as the
    library locates its own events. Returns a list of (t, state)."""
    direction = float(getattr(g, "direction", 0.0))
    found = []
    values = np.array([float(g(float(ti), yi)) for ti, yi in zip(t, y)])
    for k in range(1, len(t)):
        a, b = values[k - 1], values[k]
        up, down = a < 0.0 and b >= 0.0, a > 0.0 and b <= 0.0
        if not ((up and direction >= 0) or (down and direction <= 0)):
            continue
        lo, hi = float(t[k - 1]), float(t[k])
        sign = math.copysign(1.0, a)
        while hi - lo > 1e-13 * max(1.0, abs(hi)):
            mid = 0.5 * (lo + hi)
            if mid in (lo, hi):
                break
            if math.copysign(1.0, float(g(mid, sol(mid)))) == sign:
                lo = mid
            else:
                hi = mid
        te = 0.5 * (lo + hi)
        found.append((te, sol(te)))
    return found


class Progress:
    """A bar for a run from t0 to t_end (or a count of members, cells, pixels from 0 to a
    total, with ``label=None``): tqdm's (``tqdm.auto``: terminal or notebook) when tqdm is
    installed, else a line on stderr redrawn in place."""

    def __init__(self, t0: float, t_end: float, unit: str = "s", desc: str = "pendula", label: str | None = "t"):
        self.t0, self.span = t0, t_end - t0
        self.unit = unit
        self.label = label
        try:
            from tqdm.auto import tqdm
        except ImportError:
            self.bar = None
        else:
            self.bar = tqdm(total=self.span, unit=unit or "it", desc=desc, leave=False)
        self.done = 0.0

    def __call__(self, t: float) -> None:
        done = min(max(t - self.t0, 0.0), self.span)
        if self.bar is not None:
            self.bar.update(done - self.done)
        else:
            filled = int(30 * done / self.span) if self.span > 0 else 30
            share = 100 * done / self.span if self.span > 0 else 100.0
            where = (
                f"{self.label} = {done + self.t0:.4g}{' ' + self.unit if self.unit else ''}"
                if self.label
                else f"{done:.0f} of {self.span:.0f} {self.unit}"
            )
            sys.stderr.write(f"\r[{'#' * filled}{'.' * (30 - filled)}] {share:5.1f}%  {where}")
            sys.stderr.flush()
        self.done = done

    def close(self, t: float | None) -> None:
        """Ends the bar at time t (None: where it was, for a run that raised)."""
        if t is not None:
            self(t)
        if self.bar is not None:
            self.bar.close()
        else:
            sys.stderr.write("\n")
            sys.stderr.flush()


def counter(progress: Any, total: int, unit: str) -> tuple[Any, Progress | None]:
    """What a counted run (members, cells, pixels) calls with its count: a bar for
    ``progress=True``, the user's callable, or None; and the bar to close afterwards."""
    if progress is True:
        bar = Progress(0, total, unit=unit, label=None)
        return bar, bar
    if progress is False or progress is None:
        return None, None
    if callable(progress):
        return progress, None
    raise InvalidValueError(f"invalid value {progress!r} for `progress`: True, False or a callable of the count")


def counted(progress: Any, total: int, unit: str, run: Callable[[Any], Any]) -> Any:
    """``run(tick)`` with the progress of ``counter``; the bar ends at ``total`` when the run
    returns (where it was, when it raised), and a callable hears ``total`` last."""
    tick, bar = counter(progress, total, unit)
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
