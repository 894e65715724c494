"""The Python examples of README.md and docs/GUIDE.md run as printed, and say what they compute."""

import os
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[3]
GUIDE = ROOT / "docs" / "GUIDE.md"


def section(text, heading):
    """The part of a Markdown text under `heading` (a `##` or `###` line), up to the next such
    heading (a shell comment, `# …`, in a block is none)."""
    return re.split(r"\n##+ ", text.split(heading + "\n", 1)[1], maxsplit=1)[0]


def example(path, heading):
    """The first Python block under `heading` in the document at `path`."""
    return re.search(r"```python\n(.*?)```", section(path.read_text(), heading), re.S).group(1)


# The sections whose first Python block a test of its own runs, checking what it computes.
CHECKED = {
    "## Python: `import pendula`": "test_the_guides_python_example_runs",
    "### Beyond one machine: Slurm and Dask": "test_the_guides_dask_example_runs_and_is_the_local_result",
    "## The lab in the browser: `pendula serve`": "test_view.py::test_the_guides_view_example_runs",
}


def python_examples():
    """Every Python block of README.md and the guide: (document, line, code)."""
    found = []
    for path in (ROOT / "README.md", GUIDE):
        text = path.read_text()
        for match in re.finditer(r"^```python\n(.*?)^```", text, re.S | re.M):
            found.append((path.relative_to(ROOT).as_posix(), text[: match.start()].count("\n") + 1, match.group(1)))
    return found


@pytest.mark.parametrize("doc, line, code", python_examples(), ids=lambda v: str(v).split("\n")[0][:40])
def test_every_python_example_runs(doc, line, code, tmp_path, monkeypatch):
    """Each block runs as printed in a fresh directory (those of CHECKED by their own tests)."""
    if any(code == example(GUIDE, heading) for heading in CHECKED):
        pytest.skip("run by its own test, which checks what it computes")
    if "dask" in code:
        pytest.importorskip("distributed")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    exec(compile(code, f"{doc}:{line}", "exec"), {})


def test_the_checked_examples_are_in_the_guide():
    """Each section CHECKED names holds a Python block (so none of its tests reads nothing),
    and the README's quick start has one of its own, run above."""
    for heading in CHECKED:
        assert "import pendula" in example(GUIDE, heading), heading
    assert any(doc == "README.md" for doc, _, _ in python_examples())


def test_the_guides_python_example_runs(tmp_path, monkeypatch):
    code = example(GUIDE, "## Python: `import pendula`")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    scope: dict = {}
    exec(compile(code, "docs/GUIDE.md", "exec"), scope)
    sol, r, s = scope["sol"], scope["r"], scope["s"]
    assert sol.t_events[0].size == 1 and len(sol.y_events[1]) > 0
    assert r.kernel.startswith("simd lanes") and np.isfinite(r.flip_time).any()
    assert (tmp_path / "part1.npy").exists() and (tmp_path / "part1.npy.json").exists()
    assert s.data.shape == (64 * 64 // 4, 1)
    assert os.environ["MPLBACKEND"] == "Agg"


def test_the_guides_python_comments_say_what_the_lines_compute(tmp_path, monkeypatch):
    """The first solve's lines, evaluated on that solve: the energy line is the largest
    |E − E₀|/scale (not the maximum of the signed error), the method and evaluation count
    are those printed, and the backward run retraces the steps to the start."""
    import pendula

    code = example(GUIDE, "## Python: `import pendula`")
    lines = {line.split("#", 1)[0].strip(): line.split("#", 1)[1].strip() for line in code.splitlines() if "#" in line}
    sol = pendula.solve("double", (0, 10))
    scope = {"sol": sol, "np": np, "pendula": pendula}
    energy = next(expr for expr in lines if "energy_error" in expr)
    assert "max |E − E₀|/scale" in lines[energy]
    largest, drift = eval(energy, scope)
    assert largest == np.max(np.abs(sol.energy_error)) == drift["envelope"] > 0
    # On a run whose energy only falls (rk4 on the pendulum) the signed maximum is 0; the
    # line must still give the largest error.
    falling = pendula.solve("pendulum", (0, 10), method="rk4", dt=0.05)
    assert falling.energy_error.max() == 0 < np.max(np.abs(falling.energy_error))
    assert eval(energy, {"sol": falling})[0] == np.max(np.abs(falling.energy_error))
    method = next(expr for expr in lines if expr.startswith("sol.method"))
    shown = lines[method]
    name, _, nfev = eval(method, scope)
    assert repr(name) in shown and str(nfev) in shown, (shown, name, nfev)
    exec(next(expr for expr in lines if expr.startswith("back = ")), scope)
    end, gap = eval(next(expr for expr in lines if expr.startswith("back.t")), scope)
    assert end == 0.0 and scope["back"].t[0] == 10
    assert "about 1e-6" in lines[next(expr for expr in lines if expr.startswith("back.t"))]
    assert 1e-7 < np.max(np.abs(gap)) < 1e-5, gap


def test_the_guides_dask_example_runs_and_is_the_local_result(tmp_path, monkeypatch):
    """The Python block of "Beyond one machine", as printed: a LocalCluster on loopback, the
    fractal, the sweep and the lazy sweep array, each equal to the local call's bytes."""
    pytest.importorskip("distributed")
    code = example(GUIDE, "### Beyond one machine: Slurm and Dask")
    assert "LocalCluster" in code and 'host="127.0.0.1"' in code
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "docs/GUIDE.md", "exec"), scope)
    import pendula

    turn = scope["turn"]
    f = pendula.fractal(theta1=turn, theta2=turn, t_max=20)
    assert scope["f"].flip_time.tobytes() == f.flip_time.tobytes()
    s = pendula.sweep("double", {"theta1": turn, "theta2": turn}, steps=500)
    assert scope["s"].data.tobytes() == s.data.tobytes()
    stack = sorted(p.name for p in (tmp_path / "grid-stack").iterdir())
    assert stack == [f"{k}.npy" for k in range(8)] + ["info"]
    whole = np.concatenate([np.load(tmp_path / "grid-stack" / f"{k}.npy") for k in range(8)])
    assert whole.tobytes() == s.data.tobytes()
