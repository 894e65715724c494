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
