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


def ctrl_c_latency(run, after):
    """Seconds from a SIGINT, sent `after` s into `run()`, to the KeyboardInterrupt it must
    raise. A process started in the background by a non-interactive shell (as CI may be)
    begins with SIGINT ignored, and Python then leaves it so: the handler a terminal's Python
    has is installed for the run."""
    import signal
    import threading
    import time

    sent = []

    def interrupt():
        time.sleep(after)
        sent.append(time.perf_counter())
        signal.raise_signal(signal.SIGINT)

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        threading.Thread(target=interrupt).start()
        with pytest.raises(KeyboardInterrupt):
            run()
        return time.perf_counter() - sent[0]
    finally:
        signal.signal(signal.SIGINT, previous)
