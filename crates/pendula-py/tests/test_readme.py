"""The README's Python example runs as printed, and says what it computes."""

import os
import re
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]


def test_the_readme_python_example_runs(tmp_path, monkeypatch):
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Python: `import pendula`", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)
    sol, r, s = scope["sol"], scope["r"], scope["s"]
    assert sol.t_events[0].size == 1 and len(sol.y_events[1]) > 0
    assert r.kernel.startswith("simd lanes") and np.isfinite(r.flip_time).any()
    assert (tmp_path / "part1.npy").exists() and (tmp_path / "part1.npy.json").exists()
    assert s.data.shape == (64 * 64 // 4, 1)
    assert os.environ["MPLBACKEND"] == "Agg"


def test_the_readme_python_comments_say_what_the_lines_compute(tmp_path, monkeypatch):
    """The first solve's lines, evaluated on that solve: the energy line is the largest
    |E − E₀|/scale (not the maximum of the signed error), the method and evaluation count
    are those printed, and the backward run retraces the steps to the start."""
    import pendula

    readme = (ROOT / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", readme.split("## Python: `import pendula`", 1)[1], re.S).group(1)
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
    assert "about 1e-3" in lines[next(expr for expr in lines if expr.startswith("back.t"))]
    assert 1e-4 < np.max(np.abs(gap)) < 1e-2, gap


def test_the_readme_dask_example_runs_and_is_the_local_result(tmp_path, monkeypatch):
    """The Python block of "Beyond one machine", as printed: a LocalCluster on loopback, the
    fractal, the sweep and the lazy sweep array, each equal to the local call's bytes."""
    import pytest

    pytest.importorskip("distributed")
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Beyond one machine: Slurm and Dask", 1)[1].split("\n## ", 1)[0]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    assert "LocalCluster" in code and 'host="127.0.0.1"' in code
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)
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
