import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def cli():
    """Runs the `pendula` CLI (built by the test command) and returns its summary JSON."""
    exe = os.environ.get("PENDULA_CLI", str(ROOT / "target" / "debug" / "pendula"))
    if not Path(exe).exists():
        subprocess.run(["cargo", "build", "-q", "-p", "pendula-cli"], cwd=ROOT, check=True)

    def run(args, tmp_path):
        subprocess.run([exe, *args], cwd=tmp_path, check=True, capture_output=True)

    return run


def summary(path):
    return json.loads(Path(path).read_text())
