"""pendula.ensemble: the sweep's bytes, thread-count independence, pickling, the GIL and
Ctrl-C."""

import pickle
import threading
import time

import numpy as np
import pytest

import pendula
from conftest import ctrl_c_latency


def centres(lo, hi, n):
    # As `pendula sweep` computes its cell centres: lo + (i + ½)(hi − lo)/n.
    return np.array([lo + (i + 0.5) * (hi - lo) / n for i in range(n)])


def test_ensemble_equals_the_sweep_byte_for_byte(cli, tmp_path):
    cli(
        ["sweep", "double", "--grid", "theta1=-3:3:37", "--grid", "theta2=-2:2:23", "--dt", "0.01",
         "--steps", "300", "--record", "final,flip-time", "--out", "sweep.npy"],
        tmp_path,
    )
    sweep = np.load(tmp_path / "sweep.npy")
    assert sweep.shape == (23, 37, 5)
    t1, t2 = centres(-3, 3, 37), centres(-2, 2, 23)
    g1, g2 = np.meshgrid(t1, t2)  # theta1 fastest, as the sweep lays it out
    y0s = np.stack([g1.ravel(), g2.ravel(), np.zeros(g1.size), np.zeros(g1.size)], axis=1)
    r = pendula.ensemble("double", y0s, method="rk4", dt=0.01, steps=300, record=("final", "flip-time"))
    assert r.kernel.startswith("simd lanes")
    assert r.data.tobytes() == sweep.reshape(-1, 5).tobytes()
    # Parameters per member: the sweep over m2 with theta1 fixed, every record, in the
    # sweep's order (the energy error from each member's own masses).
    cli(["sweep", "double", "--grid", "m2=0.5:3:40", "--set", "theta1=2", "--dt", "0.01", "--steps", "200",
         "--record", "energy-error,final,flip-time", "--out", "m2.npy"], tmp_path)
    m2 = np.load(tmp_path / "m2.npy")
    y0 = pendula.System("double", theta1=2).y0
    r = pendula.ensemble("double", np.tile(y0, (40, 1)), params={"m2": centres(0.5, 3, 40)}, dt=0.01, steps=200,
                         record="energy-error,final,flip-time")
    assert r.data.tobytes() == m2.tobytes()
    assert r.columns == ["energy_error", "theta1", "theta2", "omega1", "omega2", "flip_time"]
    # Independently: E_end − E_0 from the member's System.
    for k in (0, 17, 39):
        member = pendula.System("double", m2=centres(0.5, 3, 40)[k], theta1=2)
        assert r.energy_error[k] == member.energy(r.final[k]) - member.energy(y0)
    default = pendula.ensemble("double", y0s[:10], dt=0.01, steps=20)
    assert default.records == ("final",) and default.data.shape == (10, 4)
    with pytest.raises(pendula.InvalidValueError, match="was not recorded"):
        default.flip_time
    with pytest.raises(pendula.InvalidValueError, match="did you mean 'flip-time'"):
        pendula.ensemble("double", y0s[:10], dt=0.01, steps=20, record="flip_time")


def test_threads_do_not_change_the_bits_and_results_pickle():
    rng = np.random.default_rng(3)
    y0s = np.column_stack([rng.uniform(-3, 3, (1000, 2)), np.zeros((1000, 2))])
    kw = dict(t_end=3, dt=0.01, until="flip", record=("final", "flip-time", "energy-error"))
    one = pendula.ensemble("double", y0s, threads=1, **kw)
    two = pendula.ensemble("double", y0s, threads=2, **kw)
    assert one.data.tobytes() == two.data.tobytes()
    assert np.isnan(one.flip_time).any() and (~np.isnan(one.flip_time)).any()
    back = pickle.loads(pickle.dumps(one))
    assert back.data.tobytes() == one.data.tobytes() and back.system == one.system and back.records == one.records
    s = pendula.System("double", m2=2.5, theta1=1.0)
    assert pickle.loads(pickle.dumps(s)) == s
    sol = pendula.solve(s, (0, 1), method="rk4")
    again = pickle.loads(pickle.dumps(sol))
    assert again.y.tobytes() == sol.y.tobytes() and again.method == "rk4"


def test_bad_ensemble_input():
    with pytest.raises(pendula.InvalidValueError, match="y0s has 2 columns"):
        pendula.ensemble("double", np.zeros((3, 2)), steps=10)
    with pytest.raises(pendula.InvalidValueError, match="member 1: invalid value -1 for `m2`"):
        pendula.ensemble("double", np.zeros((3, 4)), params={"m2": [1.0, -1.0, 2.0]}, steps=10)
    with pytest.raises(pendula.UnknownNameError, match="`mass`"):
        pendula.ensemble("double", np.zeros((3, 4)), params={"mass": 1.0}, steps=10)


def _work():
    rng = np.random.default_rng(5)
    return np.column_stack([rng.uniform(-1, 1, (4096, 2)), np.zeros((4096, 2))])


def test_the_gil_is_released():
    # While one Python thread runs an ensemble of about half a second, this thread keeps
    # running Python: with the GIL held through the run it would stand still for all of it.
    # Measured as the longest pause between this thread's clock readings during the run,
    # which is independent of how loaded the machine is (a speed-up of two threads over two
    # runs in a row was measured before, and fell to 1.3 whenever other builds shared the
    # two cores).
    y0s = _work()
    run = lambda: pendula.ensemble("double", y0s, steps=6000, dt=0.001, threads=1)  # noqa: E731
    run()
    done = threading.Event()
    worker = threading.Thread(target=lambda: (run(), done.set()))
    readings = []
    start = time.perf_counter()
    worker.start()
    while not done.is_set():
        readings.append(time.perf_counter())
    worker.join()
    duration = time.perf_counter() - start
    longest = max(b - a for a, b in zip([start] + readings, readings + [time.perf_counter()]))
    assert duration > 0.1, duration
    assert len(readings) > 1000 and longest < 0.5 * duration, (len(readings), longest, duration)


def test_ctrl_c_interrupts_a_long_ensemble_quickly():
    # About 100 s of work on two cores; SIGINT after 0.5 s must end it within 0.2 s.
    y0s = np.zeros((1_000_000, 4))
    y0s[:, 0] = np.linspace(-1, 1, len(y0s))
    latency = ctrl_c_latency(lambda: pendula.ensemble("double", y0s, steps=10_000, dt=0.001), after=0.5)
    assert latency < 0.2, latency
