"""``Solution.animate()``: a run drawn and encoded as a GIF by pendula's own animation code (the
one behind ``pendula animate``), shown inline by Jupyter, no matplotlib needed."""

from __future__ import annotations

import base64
import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import _core
from .errors import InvalidValueError

if TYPE_CHECKING:
    from . import Solution


class Animation:
    """A GIF: ``data`` (its bytes), ``frames``, ``fps``, ``size`` (pixels). Jupyter shows it
    inline (``_repr_html_``); ``save(path)`` writes it."""

    def __init__(self, data: bytes, frames: int, fps: int, size: tuple[int, int]):
        self.data = data
        self.frames = frames
        self.fps = fps
        self.size = size

    def _repr_html_(self) -> str:
        b64 = base64.b64encode(self.data).decode("ascii")
        return f'<img src="data:image/gif;base64,{b64}" width="{self.size[0]}" height="{self.size[1]}"/>'

    def save(self, path: str | os.PathLike) -> None:
        """Writes the GIF to ``path`` whole or not at all (a temporary file renamed)."""
        path = Path(path)
        if path.suffix.lower() != ".gif":
            raise InvalidValueError(f"invalid path {str(path)!r}: animations are written as .gif")
        fd, tmp = tempfile.mkstemp(dir=path.parent or ".", prefix=f".{path.name}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(self.data)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise

    def __repr__(self) -> str:
        return f"<Animation: {self.frames} frames at {self.fps} fps, {self.size[0]}x{self.size[1]}, {len(self.data)} bytes GIF>"


def _pretty(name: str) -> str:
    """theta1 → θ₁, omega → ω."""
    for word, letter in (("theta", "θ"), ("omega", "ω")):
        name = name.replace(word, letter)
    return name.translate(str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉"))


def _lengths(solution: Solution, links: int) -> list[float]:
    p = solution.system.params
    if "l1" in p:
        return [p[f"l{i + 1}"] for i in range(links)]
    if "l" in p:
        return [p["l"]] * links
    return [1.0] * links  # dimensionless (the driven pendulum): unit length


_ANIMATE = _core.defaults()["animate"]
_SIZE = tuple(int(x) for x in _ANIMATE["size"].split("x"))


def animate(solution: Solution, *, fps: int = _ANIMATE["fps"], speed: float = 1.0, size: tuple[int, int] = _SIZE) -> Animation:
    """The run as an animation: one frame every ``speed``/``fps`` s of simulated time (the
    state from ``sol`` when the solution has it, else the nearest recorded step), the rods
    and bobs with a fading trail, the time and the relative energy error on a log gauge."""
    if not (isinstance(fps, int) and 1 <= fps <= 50):
        raise InvalidValueError(f"invalid fps {fps!r}: 1 to 50 frames a second (GIF delays are whole centiseconds)")
    if not (np.isfinite(speed) and speed > 0):
        raise InvalidValueError(f"invalid speed {speed!r}: a finite number > 0 (simulated seconds per second)")
    # The angles lead the state (θ₁ … θₙ, then the rates); a chain's count is its own.
    links = sum(1 for name in solution.names if name.startswith("theta"))
    if links == 0:
        raise InvalidValueError(f"`{solution.system.name}` has no angles to draw: animate draws pendulums")
    t = solution.t
    if len(t) < 1:
        raise InvalidValueError("the solution has no samples to animate")
    # A run backward in time (t_span=(10, 0)) plays as it ran: from t0 down to t_end.
    d = 1.0 if t[-1] >= t[0] else -1.0
    times = np.arange(t[0], t[-1] + d * 1e-12, d * speed / fps)
    if len(times) > 10_000:
        raise InvalidValueError(
            f"{len(times)} frames: at most 10000 (raise speed, lower fps, or animate a shorter run)"
        )
    if solution.sol is not None:
        states = solution.sol(times).T
    elif len(t) == 1:
        states = np.repeat(solution.states[:1], len(times), axis=0)
    else:
        i = np.clip(np.searchsorted(d * t, d * times), 1, len(t) - 1)
        i = i - (d * (times - t[i - 1]) < d * (t[i] - times))
        states = solution.states[i]
    angles = np.ascontiguousarray(states[:, None, :links])
    energy = solution.system.energy(states.T)
    scale = solution.energy_scale
    errors = np.ascontiguousarray(((energy - energy[0]) / scale)[:, None])
    title = f"{solution.system.name}, {solution.method}"
    start = ", ".join(
        f"{_pretty(name)} = {np.degrees(v):.4g}°" for name, v in zip(solution.names[:links], states[0])
    )
    data = _core.animation_gif(
        title, _lengths(solution, links), np.ascontiguousarray(times), angles, errors, [start], fps, int(size[0]), int(size[1])
    )
    return Animation(data, len(times), fps, (int(size[0]), int(size[1])))
