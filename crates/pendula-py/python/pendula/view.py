"""``pendula.view``: a system or a run opened in the browser lab (``pendula serve``'s page,
served by this process on a free loopback port), shown inline in Jupyter as an IFrame."""

from __future__ import annotations

import html
import json
import urllib.parse

from . import _core
from .errors import InvalidValueError

__all__ = ["view", "View"]


class View:
    """The lab opened on a system: ``url`` (token and state included) and, in Jupyter, the page
    itself in an IFrame of ``width`` × ``height`` pixels."""

    def __init__(self, url: str, width: int, height: int):
        self.url = url
        self.width = width
        self.height = height

    def _repr_html_(self) -> str:
        src = html.escape(self.url, quote=True)
        return (f'<iframe src="{src}" width="{self.width}" height="{self.height}" '
                f'style="border: 1px solid #ccc"></iframe>')

    def __repr__(self) -> str:
        return f"View({self.url!r})"

    def __str__(self) -> str:
        return self.url


def view(obj=None, *, method: str | None = None, dt: float | None = None, width: int = 1100,
         height: int = 760) -> View:
    """Opens ``obj`` in the lab: a :class:`~pendula.System` (its parameters and start), a
    :class:`~pendula.Solution` (its system, method and, for fixed steps, step), a system's
    name, or nothing (the lab's own start). ``method`` and ``dt`` override. The lab checks
    everything as its page would: a method that does not apply is refused on the page."""
    from . import Solution, System  # the package imports this module first

    share: dict = {}
    system = None
    if isinstance(obj, Solution):
        system = obj.system
        share["method"] = obj.method
        if not obj.adaptive and len(obj.t) > 1:
            share["dt"] = abs(float(obj.t[1] - obj.t[0]))  # a step size, also of a backward run
    elif isinstance(obj, System):
        system = obj
    elif isinstance(obj, str):
        system = System(obj)
    elif obj is not None:
        raise InvalidValueError(f"cannot view {type(obj).__name__}: a System, a Solution, a system's name or None")
    if system is not None:
        names = set(system.names)
        values = system.params
        share["system"] = system.name
        share["params"] = {k: v for k, v in values.items() if k not in names}
        share["state"] = {k: values[k] for k in system.names}
    if isinstance(obj, Solution) and len(obj.t):
        # The run's own start (a `y0` given to solve), not the system's default one.
        share["state"] = {k: float(v) for k, v in zip(obj.names, obj.states[0])}
    if method is not None:
        share["method"] = str(method)
    if dt is not None:
        share["dt"] = float(dt)
    for key in ("width", "height"):
        value = locals()[key]
        if not (isinstance(value, int) and 100 <= value <= 10000):
            raise InvalidValueError(f"invalid value {value!r} for `{key}`: pixels, 100 to 10000")
    url = _core.serve()
    if share:
        url += "#" + urllib.parse.quote(json.dumps(share), safe="")
    return View(url, width, height)
