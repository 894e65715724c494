"""Sweeps and flip fractals on a Dask cluster: the grid cut into parts, each part computed on
a worker by the package (the GIL released, so a worker's threads all run), and the parts put
together into exactly the array the local call returns, byte for byte.

>>> from dask.distributed import Client, LocalCluster
>>> client = Client(LocalCluster(n_workers=2, host="127.0.0.1"))
>>> f = pendula.distributed.fractal(client, theta1=(-3.14, 3.14, 1024), theta2=(-3.14, 3.14, 1024))

Any Dask client works: a LocalCluster, a scheduler you started, or dask-jobqueue's Slurm and
PBS clusters. A part whose worker dies is computed again by Dask on another worker; a part's
numbers depend only on its cells, so the result is the same bytes. Needs ``distributed``.
"""

from __future__ import annotations

import math
from typing import Any, Optional, Tuple

import numpy as np

from . import _core
from .errors import InvalidValueError
from .study import FractalResult, _axis, _float, _fractal_result, _system, _threads
from .sweep import SweepResult, merge
from .sweep import sweep as _local_sweep


def _parts(client: Any, cells: int, chunks: Optional[int]) -> int:
    """How many parts: ``chunks``, or four per worker thread (so that a slow or lost worker
    holds up a small share), at most one per cell."""
    if chunks is None:
        threads = sum(client.nthreads().values()) or 1
        chunks = 4 * threads
    if not (isinstance(chunks, int) and chunks >= 1):
        raise InvalidValueError(f"invalid chunks {chunks!r}: a whole number >= 1")
    return max(1, min(chunks, cells))


def sweep(client: Any, system: Any, grid: Any, *, chunks: Optional[int] = None, **kwargs: Any) -> SweepResult:
    """:func:`pendula.sweep` on ``client``'s workers: the grid cut into ``chunks`` shards
    (default: four per worker thread), each computed by ``pendula.sweep(..., shard=(k,
    chunks))`` on a worker, and merged (:func:`pendula.merge`), which checks that they are the
    parts of one sweep. Takes ``pendula.sweep``'s arguments except ``shard``; the result equals
    the local call's byte for byte."""
    if "shard" in kwargs:
        raise InvalidValueError("invalid argument `shard`: a distributed sweep cuts the grid itself (`chunks`)")
    # Bad input raises on a worker and again here, as the same exception.
    cells = _cells(grid)
    n = _parts(client, cells, chunks)
    futures = [client.submit(_local_sweep, system, grid, shard=(k, n), pure=False, **kwargs) for k in range(1, n + 1)]
    return merge(client.gather(futures))


def _cells(grid: Any) -> int:
    from .sweep import _axes

    return math.prod(a[3] for a in _axes(grid))


def _fractal_part(system, theta1, theta2, t_max, method, dt, tolerance, threads, pixels):
    raw = _core.fractal(system._core, theta1, theta2, t_max, method, dt, tolerance, threads, None, pixels)
    return raw["flip_time"], raw["flip_time_half_step"]


def fractal(
    client: Any,
    system: Any = "double",
    *,
    theta1: Tuple[float, float, int] = (-math.pi, math.pi, 512),
    theta2: Tuple[float, float, int] = (-math.pi, math.pi, 512),
    t_max: float = 100.0,
    method: str = "rk4",
    dt: float = 0.01,
    tolerance: float = 0.01,
    threads: Optional[int] = None,
    chunks: Optional[int] = None,
) -> FractalResult:
    """:func:`pendula.fractal` on ``client``'s workers: the map's pixels (row-major) cut into
    ``chunks`` runs (default: four per worker thread), each computed on a worker with
    ``threads`` threads (default: all of the worker's cores), and put together into the same
    result as the local call, byte for byte (flip times at dt and dt/2, the converged mask,
    the count forbidden by energy)."""
    system = _system(system)
    t1, t2 = _axis("theta1", theta1), _axis("theta2", theta2)
    args = (t1, t2, _float("t_max", t_max), str(method), _float("dt", dt), _float("tolerance", tolerance), _threads(threads))
    # Every check the local call makes, before any part is sent: a one-pixel part here.
    _fractal_part(system, *args, (0, 1))
    pixels = t1[2] * t2[2]
    n = _parts(client, pixels, chunks)
    bounds = [(k * pixels // n, (k + 1) * pixels // n) for k in range(n)]
    futures = [client.submit(_fractal_part, system, *args, b, pure=False) for b in bounds]
    parts = client.gather(futures)
    at_h = np.concatenate([p[0] for p in parts])
    at_half = np.concatenate([p[1] for p in parts])
    raw = _core.fractal(system._core, *args, None, None, (at_h.tolist(), at_half.tolist()))
    return _fractal_result(system, raw, t1, t2, dt, t_max, tolerance)
