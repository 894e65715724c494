"""The example notebook (examples/paper-study.ipynb) runs, and its checks hold: each claim
in its text is followed by an assert on the numbers beside it."""

import os
from pathlib import Path

import nbformat
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[3]


def test_the_paper_study_notebook_runs(tmp_path):
    nb = nbformat.read(ROOT / "examples" / "paper-study.ipynb", as_version=4)
    env_figures = os.environ.get("PENDULA_FIGURES")
    os.environ["PENDULA_FIGURES"] = str(tmp_path / "figures")
    try:
        NotebookClient(nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    finally:
        if env_figures is None:
            os.environ.pop("PENDULA_FIGURES")
        else:
            os.environ["PENDULA_FIGURES"] = env_figures
    names = sorted(p.name for p in (tmp_path / "figures").iterdir())
    assert names == ["convergence.png", "divergence.png", "energy-four-methods.png", "fractal.png", "period-amplitude.png"]
    # The animation cell's output is a GIF shown inline.
    html = [o["data"].get("text/html", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs if "data" in o]
    assert any(h.startswith('<img src="data:image/gif;base64,') for h in html)
