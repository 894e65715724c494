"""The library's studies (``pendula::study::STUDIES``), one function each.

Every study the library registers is offered here as ``pendula.<name>`` (``energy-budget``
as :func:`pendula.energy_budget`) and through :func:`study`; each returns a
:class:`StudyReport`. The parameters, their defaults, units and checks are the library's:
this module only spells them as keyword arguments and presents the report (matplotlib for
its plots). A study added to the library appears here with no Python code.
"""

from __future__ import annotations

import html
import inspect
import dataclasses
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Optional

import numpy as np

from . import _core

__all__ = ["StudyReport", "study", "FUNCTIONS", "install"]


@dataclass(frozen=True, eq=False)
class StudyReport:
    """What a study found: ``summary`` (sentences), ``numbers`` (by key, with ``units``),
    ``texts`` (words by key), ``tables`` (name → column → array, with ``columns_units``),
    ``plots`` (drawn by :meth:`plot`), and the ``inputs`` as the run used them (defaults
    filled in)."""

    study: str
    inputs: Mapping[str, Any]
    summary: tuple
    numbers: Mapping[str, float]
    units: Mapping[str, str]
    tables: Mapping[str, Mapping[str, np.ndarray]]
    columns_units: Mapping[str, Mapping[str, str]]
    plots: tuple
    #: The names of the tables short enough to print whole (``str`` prints them).
    shown: tuple = ()
    #: The words a caption quotes, by key (``reference``: what errors are measured against).
    texts: Mapping[str, str] = dataclasses.field(default_factory=dict)
    #: (table, column) → the decimals ``str`` prints (a fitted order to 3); arrays keep every digit.
    decimals: Mapping[tuple, int] = dataclasses.field(default_factory=dict)

    def __str__(self) -> str:
        parts = ["\n".join(self.summary)]
        for name in self.shown:
            columns = self.tables[name]
            units = self.columns_units[name]
            header = [f"{c} ({units[c]})" if units[c] else c for c in columns]
            # Numbers as the CSV writes them (shortest round trip; a missing one empty),
            # right-aligned; text (a method, a note) left-aligned.
            numeric = [isinstance(c, np.ndarray) for c in columns.values()]
            # A whole column (an index, a count) as integers, as the CSV writes it.
            whole = [isinstance(c, np.ndarray) and c.dtype.kind == "i" for c in columns.values()]
            places = [self.decimals.get((name, c)) for c in columns]

            def cell(v, n, w, d):
                if not n:
                    return str(v)
                if w:
                    return str(int(v))
                if np.isnan(v):
                    return ""
                return repr(float(v)) if d is None else f"{v:.{d}f}"

            rows = [[cell(v, n, w, d) for v, n, w, d in zip(values, numeric, whole, places)] for values in zip(*columns.values())]
            widths = [max([len(h)] + [len(r[i]) for r in rows]) for i, h in enumerate(header)]
            align = lambda t, w, n: t.rjust(w) if n else t.ljust(w)  # noqa: E731
            lines = ["  ".join(align(h, w, n) for h, w, n in zip(header, widths, numeric)).rstrip()]
            lines += ["  ".join(align(v, w, n) for v, w, n in zip(r, widths, numeric)).rstrip() for r in rows]
            parts.append("\n".join(lines))
        return "\n\n".join(parts)

    def plot(self, name: Optional[str] = None, ax=None):
        """Draws the plot ``name`` (the first when None) on ``ax`` (a new figure's when None);
        returns the axes (matplotlib needed)."""
        plots = {p["name"]: p for p in self.plots}
        if name is None:
            name = self.plots[0]["name"]
        if name not in plots:
            from .errors import UnknownNameError

            raise UnknownNameError(f"unknown plot `{name}`; valid plots: {', '.join(plots)}")
        p = plots[name]
        if ax is None:
            import matplotlib.pyplot as plt

            ax = plt.figure().gca()
        if p["bars"]:
            # A bar chart: one bar a category, top to bottom, hatched where the value is a
            # method's refusal rather than a measurement.
            bars = p["bars"][::-1]
            for i, b in enumerate(bars):
                if b["value"] is not None:
                    ax.barh(i, b["value"], fill=not b["refused"], hatch="//" if b["refused"] else None)
                if b["note"]:
                    ax.annotate(b["note"], (b["value"] or (p["limits"] or (1, 1))[0], i), xytext=(4, 0), textcoords="offset points", va="center")
            ax.set_yticks(range(len(bars)), [b["label"] for b in bars])
            a = p["x"]
            ax.set_xlabel(a["label"] + (f" ({a['unit']})" if a["unit"] else ""))
            ax.set_xscale("log" if a["log"] else "linear")
            if p["limits"]:
                ax.set_xlim(*p["limits"])
            ax.set_title(p["title"])
            return ax
        styles = {"solid": "-", "dashed": "--", "points": "o", "line-markers": "o-", "dots": "."}
        for s in p["series"]:
            if s["style"] == "guide":
                # A guide, not data: thin, dashed, grey, named at its end rather than in the legend.
                ax.plot(s["x"], s["y"], "--", color="0.6", linewidth=0.8)
                if len(s["x"]):
                    ax.annotate(s["label"], (s["x"][-1], s["y"][-1]), color="0.4", fontsize="small")
                continue
            ax.plot(s["x"], s["y"], styles[s["style"]], label=s["label"])
        for axis, set_label, set_scale in (("x", ax.set_xlabel, ax.set_xscale), ("y", ax.set_ylabel, ax.set_yscale)):
            a = p[axis]
            set_label(a["label"] + (f" ({a['unit']})" if a["unit"] else ""))
            set_scale("log" if a["log"] else "linear")
        ax.set_title(p["title"])
        if p["legend"]:
            ax.legend()
        return ax

    def _repr_html_(self) -> str:
        rows = "".join(
            f"<tr><td>{html.escape(k)}</td><td>{v:.6g} {html.escape(self.units[k])}</td></tr>" for k, v in self.numbers.items()
        )
        text = "".join(f"<p>{html.escape(s)}</p>" for s in self.summary)
        return f"<b>{html.escape(self.study)}</b>{text}<table>{rows}</table>"


def study(name: str, system: Any = None, *, progress: Any = None, **params: Any) -> StudyReport:
    """Runs the library study ``name`` (see :data:`FUNCTIONS` for their names) on ``system``
    (a :class:`pendula.System`, a catalogue name, or None for the study's default) with its
    parameters as keyword arguments; unknown names raise :class:`UnknownNameError` with the
    valid ones, values out of range :class:`InvalidValueError`."""
    # A list of methods may come as a sequence: the library reads them comma-separated.
    # Other sequences (a convergence study's steps) go as lists of numbers.
    def value(v: Any) -> Any:
        if isinstance(v, (list, tuple)) and all(isinstance(x, str) for x in v):
            return ",".join(v)
        if isinstance(v, (list, tuple, np.ndarray)):
            return [float(x) for x in np.asarray(v, dtype=np.float64).reshape(-1)]
        return v

    values = [(k, value(v)) for k, v in params.items()]
    settings: list = []
    if system is not None:
        from . import System

        if isinstance(system, System):
            # What the System changed from the catalogue's defaults: a study that sets part of
            # the state itself (period's amplitudes) refuses only what the user set.
            settings = [(k, float(v)) for k, v in system._changed().items()]
            system = system.name
        values.insert(0, ("system", system))
    raw = _core.run_study(name, values, settings, progress)
    return StudyReport(
        study=raw["study"],
        inputs=raw["inputs"],
        summary=tuple(raw["summary"]),
        numbers=raw["numbers"],
        units=raw["units"],
        tables=raw["tables"],
        columns_units=raw["columns_units"],
        plots=tuple(raw["plots"]),
        shown=tuple(raw["shown"]),
        texts=raw["texts"],
        decimals=raw["decimals"],
    )


def _function(entry: Mapping[str, Any]) -> Callable[..., StudyReport]:
    """The function of one registered study, its signature and docstring from the
    registry's parameters (defaults and units included)."""
    name = entry["name"]

    def run(system: Any = None, **params: Any) -> StudyReport:
        return study(name, system, **params)

    unit = {"time": "s (none for a dimensionless system)", "": ""}
    lines = [entry["about"] + ".", "", "Parameters (defaults are the library's):"]
    parameters = []
    for p in entry["params"]:
        u = unit.get(p.get("unit", ""), p.get("unit", ""))
        if p["kind"] == "fixed-system":
            lines.append(f"    {p['name']}: the {p['default']} system only (a pendula.System of it sets its parameters) [default: {p['default_text']}]")
        else:
            lines.append(f"    {p['name']}: {p['help']}{', ' + u if u else ''} [default: {p['default_text']}]")
        positional = p["kind"] in ("system", "fixed-system")
        kind = inspect.Parameter.POSITIONAL_OR_KEYWORD if positional else inspect.Parameter.KEYWORD_ONLY
        parameters.append(inspect.Parameter(p["name"], kind, default=None))
    parameters.append(inspect.Parameter("progress", inspect.Parameter.KEYWORD_ONLY, default=None))
    lines += ["", "Returns a :class:`pendula.StudyReport`; ``pendula study`` and the lab run the same study."]
    run.__name__ = run.__qualname__ = name.replace("-", "_")
    run.__doc__ = "\n".join(lines)
    run.__signature__ = inspect.Signature(parameters, return_annotation=StudyReport)  # type: ignore[attr-defined]
    return run


#: Every registered study's function, by Python name (``energy_budget``).
FUNCTIONS = {e["name"].replace("-", "_"): _function(e) for e in _core.studies()}


def install(namespace: dict) -> list:
    """Adds each study's function to ``namespace`` (the package's) under its Python name,
    except where the name is already defined: a study that keeps a hand-written function
    (one returning its own result class) keeps it. Returns the names added."""
    added = [name for name in FUNCTIONS if name not in namespace]
    for name in added:
        namespace[name] = FUNCTIONS[name]
    return added
