"""pendula.view: the browser lab served by this process (the page itself is driven in Chromium by
crates/pendula-web/tests/e2e, which opens a view there)."""

import json
import urllib.parse
import urllib.request

import pytest

import pendula


def test_view_serves_the_lab_with_the_system_in_the_url():
    v = pendula.view(pendula.System("pendulum", l=2.0, theta=0.5), method="verlet", dt=0.02)
    base, fragment = v.url.split("#")
    assert base.startswith("http://127.0.0.1:") and "token=" in base
    share = json.loads(urllib.parse.unquote(fragment))
    assert share == {"method": "verlet", "dt": 0.02, "system": "pendulum",
                     "params": {**{k: v for k, v in pendula.System("pendulum").params.items() if k not in ("theta", "omega")},
                                "l": 2.0},
                     "state": {"theta": 0.5, "omega": 0.0}}
    with urllib.request.urlopen(base, timeout=10) as r:
        page = r.read().decode()
    assert r.status == 200 and "<canvas" in page
    assert f'src="{v.url}"'.replace("&", "&amp;") in v._repr_html_()


def test_a_solution_brings_its_method_and_step():
    sol = pendula.solve("double", (0, 1), method="rk4", dt=0.05)
    v = pendula.view(sol)
    share = json.loads(urllib.parse.unquote(v.url.split("#")[1]))
    assert share["method"] == "rk4" and share["dt"] == pytest.approx(0.05)
    assert share["system"] == "double"


@pytest.mark.parametrize("args, message", [
    ((3,), "cannot view int"),
    (("dubble",), "dubble"),
    ((None,), None),
])
def test_bad_input_is_a_value_error(args, message):
    if message is None:
        with pytest.raises(ValueError, match="width"):
            pendula.view(*args, width=5)
    else:
        with pytest.raises(ValueError, match=message):
            pendula.view(*args)


def test_a_solution_opens_at_its_own_start():
    sol = pendula.solve("pendulum", (0, 1), [1.25, 0.5], method="verlet", dt=0.01)
    share = json.loads(urllib.parse.unquote(pendula.view(sol).url.split("#")[1]))
    assert share["state"] == {"theta": 1.25, "omega": 0.5}


def test_the_guides_view_example_runs():
    from test_readme import GUIDE, example

    code = example(GUIDE, "## The lab in the browser: `pendula serve`")
    # The last line is the notebook cell's value: keep it.
    lines = code.strip().splitlines()
    scope: dict = {}
    exec(compile("\n".join(lines[:-1]) + f"\nresult = {lines[-1]}", "docs/GUIDE.md", "exec"), scope)
    share = json.loads(urllib.parse.unquote(scope["result"].url.split("#")[1]))
    assert share["method"] == "gauss-legendre-4" and share["state"]["theta1"] == 2.0
    assert share["params"]["m2"] == 1.5
