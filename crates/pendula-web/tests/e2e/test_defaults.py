"""The library's default run is the first run everywhere: the lab's first run of the double
pendulum, `pendula simulate` and `pendula.solve("double", ...)` given nothing but the end time
end in the same state."""

import os
import subprocess

import numpy as np

from conftest import open_lab


def test_the_labs_first_run_is_the_clis_and_pythons(browser, server, tmp_path):
    import pendula

    page = open_lab(browser, server)
    config = page.evaluate("({method: lab.config.method, dt: lab.config.dt, system: lab.config.system})")
    assert config == {"method": "rk4", "dt": 1e-3, "system": "double"}, config
    # Paused after the run has taken some steps: a pause sent before the first hundred
    # (a fresh machine's slow first page) would leave it short of them for good.
    page.wait_for_function("lab.frame && lab.frame.steps > 100", timeout=15000)
    page.evaluate("lab.send({cmd: 'pause'})")
    page.wait_for_function("lab.frame && lab.frame.paused", timeout=15000)
    frame = page.evaluate("({t: lab.frame.t, steps: lab.frame.steps, state: lab.frame.tracks[0].state})")
    t = frame["t"]
    assert abs(t - frame["steps"] * 1e-3) < 1e-9, frame
    page.close()

    cli = os.environ.get("PENDULA_CLI", "target/debug/pendula")
    out = tmp_path / "run.csv"
    subprocess.run([cli, "simulate", "--t-end", repr(t), "--out", str(out)], check=True, capture_output=True)
    with open(out) as f:
        header = f.readline().strip().split(",")
        last = f.readlines()[-1].strip().split(",")
    row = dict(zip(header, map(float, last)))
    by_cli = np.array([row[n] for n in ("theta1", "theta2", "omega1", "omega2")])

    sol = pendula.solve("double", (0, t))
    assert sol.method == "rk4" and len(sol.t) == frame["steps"] + 1, (sol.method, len(sol.t))
    np.testing.assert_array_equal(sol.y[:, -1], by_cli)
    np.testing.assert_allclose(frame["state"], by_cli, rtol=0, atol=1e-12)
