"""Sweeps and flip fractals on a Dask cluster: the grid cut into parts, each part computed on
a worker by the package (the GIL released, so a worker's threads all run), and the parts put
together into exactly the array the local call returns, byte for byte.

>>> from dask.distributed import Client, LocalCluster
>>> client = Client(LocalCluster(n_workers=2, host="127.0.0.1"))
>>> f = pendula.distributed.fractal(client, theta1=(-3.14, 3.14, 1024), theta2=(-3.14, 3.14, 1024))

For grids larger than memory, :func:`sweep_array` is the sweep as a lazy ``dask.array``
whose blocks are computed when asked for (``da.to_npy_stack``, ``to_zarr``, a slice's
``compute()``), on whatever scheduler is current.

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
from .sweep import DEFAULT_DT as _DEFAULT_DT
from .sweep import SweepResult, merge
from .sweep import sweep as _local_sweep


def _parts(client: Any, cells: int, chunks: Optional[int]) -> int:
    """How many parts: ``chunks``, or sixteen per worker thread, at most one per cell. Parts
    differ in cost (a fractal's pixels that never flip run to t_max), and the run ends with
    its slowest part: with four per thread the last part left a worker idle for up to a
    tenth of a 1024² fractal (distributed/local 0.99 and 1.17 in two runs; BENCHMARKS.md).
    Smaller parts leave a shorter tail, and a slow or lost worker holds up a smaller share."""
    if chunks is None:
        threads = sum(client.nthreads().values()) or 1
        chunks = 16 * threads
    if not (isinstance(chunks, int) and chunks >= 1):
        raise InvalidValueError(f"invalid chunks {chunks!r}: a whole number >= 1")
    return max(1, min(chunks, cells))


def sweep(client: Any, system: Any, grid: Any, *, chunks: Optional[int] = None, **kwargs: Any) -> SweepResult:
    """:func:`pendula.sweep` on ``client``'s workers: the grid cut into ``chunks`` shards
    (default: sixteen per worker thread), each computed by ``pendula.sweep(..., shard=(k,
    chunks))`` on a worker, and merged (:func:`pendula.merge`), which checks that they are the
    parts of one sweep. Takes ``pendula.sweep``'s arguments except ``shard``; the result equals
    the local call's byte for byte."""
    if "shard" in kwargs:
        raise InvalidValueError("invalid argument `shard`: a distributed sweep cuts the grid itself (`chunks`)")
    # Bad input raises on a worker and again here, as the same exception.
    cells = _cells(system, grid, kwargs.get("set"))
    n = _parts(client, cells, chunks)
    futures = [client.submit(_local_sweep, system, grid, shard=(k, n), pure=False, **kwargs) for k in range(1, n + 1)]
    return merge(client.gather(futures))


def sweep_array(system: Any, grid: Any, *, rows: Optional[int] = None, threads: Optional[int] = None, **kwargs: Any):
    """:func:`pendula.sweep` as a lazy ``dask.array.Array`` of the sweep's shape (the last
    grid axis first, the first axis and then the recorded columns last), in blocks of
    ``rows`` rows along its first axis (default: blocks of about 64 MiB), each computed by
    the package when Dask asks for it (``map_blocks``): a block is a contiguous run of cells,
    the same bytes as in the local sweep. Write it with ``dask.array.to_npy_stack`` (one
    ``.npy`` per block) or ``to_zarr``; take a slice and ``compute()`` it, and only its blocks
    are computed. Takes ``pendula.sweep``'s arguments except ``shard`` and ``progress``;
    ``threads`` per block (default: the worker's cores)."""
    import dask.array as da

    for name in ("shard", "progress"):
        if name in kwargs:
            raise InvalidValueError(f"invalid argument `{name}`: sweep_array computes its blocks when Dask asks")
    from .sweep import _arguments

    args = _arguments(
        system,
        grid,
        kwargs.pop("set", None),
        kwargs.pop("method", "rk4"),
        kwargs.pop("dt", _DEFAULT_DT),
        kwargs.pop("steps", None),
        kwargs.pop("t_end", None),
        kwargs.pop("until", None),
        kwargs.pop("record", ("final",)),
    )
    if kwargs:
        raise InvalidValueError(f"invalid argument `{next(iter(kwargs))}` for sweep_array")
    threads = _threads(threads)
    # Every check the whole sweep makes, on its first cell, here and now.
    first = _core.sweep(*args, (1, 1), 1, None, (0, 1))
    shape = tuple(int(n) for n in first["shape"])
    per_row = math.prod(shape[1:])
    if rows is None:
        rows = max(1, (64 << 20) // (8 * per_row))
    if not (isinstance(rows, int) and rows >= 1):
        raise InvalidValueError(f"invalid rows {rows!r}: a whole number >= 1")
    inner = per_row // shape[-1]
    blocks = tuple(min(rows, shape[0] - r) for r in range(0, shape[0], rows))

    def block(block_info=None):
        (r0, r1) = block_info[None]["array-location"][0]
        out = _core.sweep(*args, (1, 1), threads, None, (r0 * inner, r1 * inner))
        return out["data"].reshape((r1 - r0,) + shape[1:])

    return da.map_blocks(
        block,
        chunks=(blocks,) + tuple((n,) for n in shape[1:]),
        dtype=np.float64,
        meta=np.empty((0,) * len(shape)),
        name=f"pendula-sweep-{first['fingerprint']}-{rows}",
    )


def _cells(system: Any, grid: Any, set: Any) -> int:
    from .sweep import _axes, _settings

    return math.prod(a[3] for a in _axes(*_settings(system, set), grid))


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
    ``chunks`` runs (default: sixteen per worker thread), each computed on a worker with
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
