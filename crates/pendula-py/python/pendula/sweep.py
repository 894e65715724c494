"""pendula.sweep and pendula.merge: a system integrated from every cell of a grid over
parameters and initial-state variables — the library's sweep, the one `pendula sweep` runs —
and the assembly of its shards, as `pendula merge` assembles them.

The array is the CLI's, bit for bit: the axes slowest first (the first axis given varies
fastest), then the recorded columns; a shard ``K/N`` is ``(count, columns)``, a contiguous
slice of the cells. :meth:`SweepResult.save` writes the CLI's ``.npy`` bytes (and, for a
shard, its ``FILE.npy.json`` description), so shards from Python and from the CLI merge
together, either way.
"""

from __future__ import annotations

import html
import json
import math
import operator
import os
from pathlib import Path
from typing import Any, Iterable, Mapping, Optional, Union

import numpy as np

from . import _core
from .dense import counted
from .errors import InvalidValueError, PendulaError

__all__ = ["sweep", "merge", "SweepResult"]

#: The version of SweepResult's pickled form.
PICKLE_VERSION = 1

#: The shard description's format (`pendula_sweep`): format 2 has `data` (the .npy file's
#: length and CRC-32).
SHARD_FORMAT = _core.SHARD_FORMAT

#: What `pendula sweep` runs without those arguments.
_SWEEP = _core.defaults()["sweep"]
DEFAULT_DT = _SWEEP["dt"]
DEFAULT_T_END = _SWEEP["t_end"]


def _value(system: Optional[str], name: str, value: Any) -> float:
    """A number, or a string in the value syntax (``2``, ``-pi``, ``0.5pi``, ``2*pi``,
    ``120deg``: the suffixes for angles of ``system``, in radians), read by the format
    crate's parser; the library checks the domains."""
    if isinstance(value, str):
        return _core.parse_value(system, name, value)
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InvalidValueError(f"invalid value {value!r} for `{name}`: a number") from None


def _axes(system: str, settings: list, grid: Any) -> list:
    """[(name, lo, hi, n)] from {name: (lo, hi, n)} or ["NAME=LO:HI:N", ...], over the
    quantities of ``system`` with ``settings`` [(name, value)]."""
    if isinstance(grid, Mapping):
        items = list(grid.items())
    elif isinstance(grid, str):
        items = [grid]
    else:
        try:
            items = list(grid)
        except TypeError:
            raise InvalidValueError(f"invalid grid {grid!r}: {{name: (lo, hi, n)}} or ['NAME=LO:HI:N', ...]") from None
    axes = []
    for item in items:
        if isinstance(item, str):
            axes.append(_core.parse_axis(system, settings, item))
            continue
        try:
            name, (lo, hi, n) = item
        except (TypeError, ValueError):
            raise InvalidValueError(f"invalid grid axis {item!r}: name: (lo, hi, n)") from None
        try:
            n = operator.index(n)
        except TypeError:
            raise InvalidValueError(f"invalid n {n!r} for the {name} axis: a whole number of cells") from None
        if n < 1:
            raise InvalidValueError(f"invalid n {n} for the {name} axis: at least 1 cell")
        axes.append((str(name), _value(system, name, lo), _value(system, name, hi), n))
    if not axes:
        raise InvalidValueError("invalid grid: give at least one axis")
    return axes


def _shard(shard: Any) -> tuple:
    if shard is None:
        return (1, 1)
    try:
        k, n = map(int, shard.split("/")) if isinstance(shard, str) else map(operator.index, shard)
    except (TypeError, ValueError):
        raise InvalidValueError(f"invalid shard {shard!r}: (K, N) or 'K/N' with 1 <= K <= N, e.g. (3, 8)") from None
    if not 1 <= k <= n:
        raise InvalidValueError(f"invalid shard {shard!r}: (K, N) or 'K/N' with 1 <= K <= N, e.g. (3, 8)")
    return (k, n)


def _centres(lo: float, hi: float, n: int) -> np.ndarray:
    # The library's Axis::centre, lo + (i + ½)(hi − lo)/n, in the same order of operations.
    return lo + (np.arange(n) + 0.5) * (hi - lo) / n


class SweepResult:
    """A sweep's results, or one shard's.

    ``data``: the array as its ``.npy`` file holds it (``pendula_io``'s layout) — the axes slowest first, then the
    ``columns`` (state variables for ``final``, ``flip_time`` s, ``energy_error`` J); a
    shard's is ``(count, columns)``, cells ``offset`` … ``offset + count`` of the whole
    grid in order (first axis fastest). ``axes``: ((name, cell centres), …) in the order
    given. ``description``: what the CLI writes next to a shard (``FILE.npy.json``) and in
    its summary.
    """

    def __init__(self, data: np.ndarray, description: Mapping[str, Any]):
        self.data = data
        self._description = dict(description)
        self._data_info: Optional[dict] = None

    @property
    def columns(self) -> tuple:
        return tuple(self._description["columns"])

    @property
    def axes(self) -> tuple:
        return tuple((a["name"], _centres(a["lo"], a["hi"], a["n"])) for a in self._description["axes"])

    @property
    def shard(self) -> tuple:
        """(K, N): shard K of N; (1, 1) for a whole sweep."""
        return (self._description["shard"], self._description["shards"])

    @property
    def sharded(self) -> bool:
        return self.shard[1] > 1

    @property
    def kernel(self) -> str:
        return self._description["kernel"]

    @property
    def description(self) -> dict:
        """The description of the run, the one ``pendula sweep`` writes: system, method,
        dt (s), steps, axes and their units, columns and their units, the whole shape, the
        shard, its offset and count, the fingerprint `merge` matches, ``data`` (the .npy
        file's bytes and CRC-32), kernel, fma, threads, wall_s."""
        d = dict(self._description)
        if self._data_info is None:
            size, crc = _core.npy_written(np.ascontiguousarray(self.data, dtype="<f8"))
            self._data_info = {"bytes": size, "crc32": f"{crc:08x}"}
        # In the description's order of keys: `data` after the fingerprint.
        out = {}
        for k, v in d.items():
            out[k] = v
            if k == "fingerprint":
                out["data"] = dict(self._data_info)
        return out

    def save(self, path: Union[str, os.PathLike]) -> Path:
        """Writes the array to ``path`` (``.npy``) with the format crate's writer, the one
        ``pendula sweep`` writes with (the same bytes, header included); for a shard, its description to ``path + ".json"``, so that
        ``pendula merge`` (or :func:`merge`) assembles it."""
        path = Path(path)
        if path.suffix != ".npy":
            raise InvalidValueError(f"invalid path {str(path)!r}: a sweep is saved as .npy")
        _core.save_npy(path, np.ascontiguousarray(self.data, dtype="<f8"))
        if self.sharded:
            side = Path(f"{path}.json")
            side.write_text(json.dumps(self.description, indent=2) + "\n")
        return path

    def __reduce__(self):
        return (_sweep_from_pickle, (PICKLE_VERSION, self.data, self._description))

    def __repr__(self) -> str:
        d = self._description
        shard = f" shard {d['shard']}/{d['shards']}" if self.sharded else ""
        return f"<SweepResult {d['system']} {d['method']}{shard}: {d['count']} cells {self.data.shape} on {d['kernel']}>"

    def _repr_html_(self) -> str:
        d = self._description
        rows = [
            ("system", d["system"]),
            ("method", f"{d['method']}, {d['steps']} steps of {d['dt']:g} s"),
            ("axes", ", ".join(f"{a['name']} {a['lo']:g} … {a['hi']:g} ({a['n']})" for a in d["axes"])),
            ("columns", ", ".join(d["columns"])),
            ("shape", tuple(self.data.shape)),
            ("shard", f"{d['shard']}/{d['shards']} (cells {d['offset']} … {d['offset'] + d['count']})"),
            ("kernel", d["kernel"]),
            ("wall", f"{d['wall_s']:.3g} s on {d['threads']} threads"),
        ]
        body = "".join(f"<tr><th>{k}</th><td>{html.escape(str(v))}</td></tr>" for k, v in rows)
        return f"<table>{body}</table>"


def _sweep_from_pickle(version, data, description):
    if version != PICKLE_VERSION:
        raise PendulaError(f"a pickled SweepResult of version {version}; this pendula reads version {PICKLE_VERSION}")
    return SweepResult(data, description)


def sweep(
    system: Any,
    grid: Any,
    *,
    set: Optional[Mapping[str, Any]] = None,
    method: str = _SWEEP["method"],
    dt: float = DEFAULT_DT,
    steps: Optional[int] = None,
    t_end: Optional[float] = None,
    until: Optional[str] = None,
    record: Union[str, Iterable[str]] = ("final",),
    threads: Optional[int] = None,
    shard: Any = None,
    progress: Any = None,
) -> SweepResult:
    """Integrates ``system`` (a name, or a System: its values are the ``set`` ones) from
    every cell of ``grid`` — ``{name: (lo, hi, n)}`` or ``["NAME=LO:HI:N", ...]``, the
    first axis varying fastest, cells sampled at their centres lo + (i + ½)(hi − lo)/n —
    ``steps`` fixed steps of ``dt`` s (or to ``t_end`` s; 10 s if neither) with ``method``,
    all cores (``threads``). ``set``: values the same for every cell. ``until="flip"``
    stops each cell at its first flip. ``record``: ``final`` (the state), ``flip-time`` (s,
    NaN without a flip), ``energy-error`` (E_end − E_0, J), in that column order.
    ``shard=(K, N)`` or ``"K/N"`` computes shard K of N only (assemble them with
    :func:`merge`). Bitwise the CLI's ``pendula sweep``, for any thread count.
    ``progress``: a bar of the cells done, by default (None) where a terminal or notebook
    shows it and the run is estimated to take 3 s or more; ``True`` always, ``False`` never;
    a callable gets the count instead.
    """
    args = _arguments(system, grid, set, method, dt, steps, t_end, until, record)
    if threads is not None:
        threads = operator.index(threads)
        if threads < 1:
            raise InvalidValueError(f"invalid value {threads} for `threads`: at least 1")
    k, n = _shard(shard)
    cells = math.prod(a[3] for a in args[2])
    out = counted(
        progress,
        k * cells // n - (k - 1) * cells // n,
        "cells",
        lambda tick: _core.sweep(*args, (k, n), threads, tick),
        desc="sweep",
    )
    return _result(out)


def _arguments(system, grid, set, method, dt, steps, t_end, until, record) -> tuple:
    """The sweep's description as ``_core.sweep`` takes it (system, set, axes, method, dt,
    steps, t_end, until, records), from :func:`sweep`'s arguments; the library checks the
    rest."""
    system, settings = _settings(system, set)
    axes = _axes(system, settings, grid)
    if steps is not None and t_end is not None:
        raise InvalidValueError("give steps or t_end (s), not both")
    if steps is not None:
        try:
            steps = operator.index(steps)
        except TypeError:
            raise InvalidValueError(f"invalid value {steps!r} for `steps`: a whole number") from None
        if steps < 1:
            raise InvalidValueError(f"invalid value {steps} for `steps`: at least 1")
    elif t_end is None:
        t_end = DEFAULT_T_END
    records = [record] if isinstance(record, str) else list(record)
    # The CLI's comma-separated form too: "final,flip-time".
    records = [r.strip() for item in records for r in str(item).split(",")]
    t_end = None if t_end is None else _value(None, "t_end", t_end)
    return (system, settings, axes, str(method), _value(None, "dt", dt), steps, t_end, until, records)


def _settings(system: Any, set: Optional[Mapping[str, Any]]) -> tuple:
    """(the system's name, [(name, value)]) from a name or a System (its values where they
    differ from the defaults) and ``set``."""
    settings = []
    if not isinstance(system, str):
        # A System: its name, and its values where `set` does not say otherwise.
        if set:
            raise InvalidValueError("give the values in the System or in set=, not both")
        core = getattr(system, "_core", None)
        if core is None:
            raise InvalidValueError(f"invalid system {system!r}: a System or a catalogue name")
        defaults = dict(_core.CoreSystem(core.name, []).values())
        settings = [(n, v) for n, v in core.values() if v != defaults[n]]
        system = core.name
    system = str(system)
    settings += [(str(n), _value(system, n, v)) for n, v in (set or {}).items()]
    return system, settings


def _result(out: dict) -> SweepResult:
    data = out.pop("data")
    # The description every sharded run writes beside its array (pendula-io's), without
    # `data`, which the `description` property adds from the array.
    d = json.loads(out["description"])
    if d["shards"] == 1:
        data = data.reshape(d["shape"])
    return SweepResult(data, d)


def _load(path: Union[str, os.PathLike]) -> SweepResult:
    """A shard saved by :meth:`SweepResult.save` or ``pendula sweep --shard``: its
    description, then the file checked against the length and CRC-32 it gives."""
    text, data = _core.load_shard(os.fspath(path))
    d = json.loads(text)
    result = SweepResult(data, {k: v for k, v in d.items() if k != "data"})
    result._data_info = dict(d["data"])
    return result


def merge(shards: Iterable[Union[SweepResult, str, os.PathLike]]) -> SweepResult:
    """The whole sweep from all N of its shards (SweepResults, or ``.npy`` paths with their
    ``.json`` descriptions, from Python or the CLI), in any order: bitwise the unsharded
    run's. Shards of different sweeps, a shard given twice and missing shards are refused,
    naming which."""
    parts = []
    for s in shards:
        if isinstance(s, SweepResult):
            parts.append((f"shard {s.shard[0]}/{s.shard[1]}", s))
        else:
            parts.append((str(s), _load(s)))
    if not parts:
        raise InvalidValueError("merge: give the shards")
    # Shards held in memory are checked by their descriptions, as files are.
    _core.check_shards([(name, json.dumps(s.description)) for name, s in parts])
    f = parts[0][1]._description
    n = f["shards"]
    shape = [int(a) for a in f["shape"]]
    cols = shape[-1]
    whole = np.full((math.prod(shape[:-1]), cols), np.nan)
    for _, s in parts:
        d = s._description
        rows = np.asarray(s.data).reshape(-1, cols)
        if rows.shape[0] != d["count"]:
            raise InvalidValueError(f"shard {d['shard']}/{n}: {rows.shape[0]} cells, its description says {d['count']}")
        whole[d["offset"] : d["offset"] + d["count"]] = rows
    d = dict(f)
    d.pop("data", None)
    d.update(shard=1, shards=1, offset=0, count=whole.shape[0])
    d["wall_s"] = sum(s._description["wall_s"] for _, s in parts)
    return SweepResult(whole.reshape(shape), d)
