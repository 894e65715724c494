"""pendula's studies against the CLI's study commands (an independent front end over the same
library: the same inputs must give the same numbers, most of them bit for bit), plus physics
each can be checked against without the code under test: a regular orbit's Lyapunov exponent
is 0 and a Hamiltonian flow's spectrum sums to 0; crossings lie on the section and the energy
surface; the energy forbids flips below the upright rods' potential; a damped, weakly driven
pendulum settles on a period-1 orbit; rk4 converges at order 4; a linear system's separation
decays at its damping rate."""

import csv
import math
import pickle

import numpy as np
import pytest

import pendula
from conftest import ctrl_c_latency, summary


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def floats(rows, cols=None):
    return np.array([[float(v) for v in (r if cols is None else [r[c] for c in cols])] for r in rows])


def test_lyapunov_equals_the_cli_and_a_regular_orbit_has_exponent_zero(cli, tmp_path):
    # Defaults: the double pendulum, rk4, dt 1 ms, 200 s after a 10 s transient.
    cli(["lyapunov", "--out-dir", "o", "--summary", "s.json"], tmp_path)
    s = summary(tmp_path / "s.json")
    r = pendula.lyapunov()
    assert (r.lambda_max, r.uncertainty) == (s["lambda_max"], s["uncertainty"])
    assert (r.method, r.dt, r.t_end, r.transient, r.renormalise) == (
        s["method"], s["dt"], s["t_end"], s["transient"], s["renormalise"])
    header, rows = read_csv(tmp_path / "o" / "lyapunov.csv")
    assert header == ["t", "lambda1"]
    np.testing.assert_array_equal(floats(rows), np.column_stack([r.t, r.running]))
    assert r.spectrum is None
    # The spectrum of a chaotic orbit, and the physics: a Hamiltonian flow keeps phase-space
    # volume, so the exponents sum to 0; the pendulum is integrable, so its orbit's exponent
    # is 0 (the estimate decays as ln t / t), far below the double pendulum's.
    cli(["lyapunov", "--spectrum", "--t-end", "40", "--transient", "2", "--summary", "s2.json",
         "--out-dir", "o2"], tmp_path)
    s2 = summary(tmp_path / "s2.json")
    spec = pendula.lyapunov(spectrum=True, t_end=40, transient=2)
    assert spec.spectrum.tolist() == [e["value"] for e in s2["tables"]["exponents"]]
    assert spec.spectrum_uncertainty.tolist() == [e["uncertainty"] for e in s2["tables"]["exponents"]]
    assert abs(spec.spectrum.sum()) < 1e-3 * spec.spectrum[0], spec.spectrum
    regular = pendula.lyapunov("pendulum")
    assert abs(regular.lambda_max) < math.log(regular.t_end) / regular.t_end
    assert r.lambda_max > 20 * abs(regular.lambda_max)


def test_poincare_equals_the_cli_and_crossings_lie_on_the_section(cli, tmp_path):
    cli(["poincare", "--count", "4", "--t-end", "30", "--out-dir", "o", "--summary", "s.json"], tmp_path)
    s = summary(tmp_path / "s.json")
    r = pendula.poincare(count=4, t_end=30)
    assert r.crossings == s["crossings"]
    _, orbit_rows = read_csv(tmp_path / "o" / "orbits.csv")
    per_orbit = [int(float(row[1])) for row in orbit_rows]
    assert list(r.crossings_per_orbit) == per_orbit
    assert r.max_energy_error == s["max_energy_error"]
    header, rows = read_csv(tmp_path / "o" / "poincare.csv")
    assert header == ["orbit", "t", "theta2", "p2", "theta1", "p1"]
    np.testing.assert_array_equal(floats(rows, [0]).ravel(), r.orbit)
    np.testing.assert_array_equal(floats(rows, [1, 2, 3, 4, 5]),
                                  np.column_stack([r.t, r.q, r.p, r.states[:, 0], r.states[:, 2]]))
    # On the section θ₁ = 0 (mod 2π), crossing upwards, on the energy surface H = −15 J.
    double = pendula.System("double")
    y = double.from_momenta(r.states.T)
    assert np.all(np.abs(np.remainder(y[0] + np.pi, 2 * np.pi) - np.pi) < 1e-9)
    assert np.all(y[2] > 0)
    assert np.max(np.abs(double.energy(y) + 15.0)) < 1e-6
    assert [len(t) for t, _ in r.orbits()] == per_orbit
    # Each orbit starts on the surface too.
    assert np.max(np.abs(double.energy(r.initial.T) + 15.0)) < 1e-9


def test_fractal_equals_the_cli_byte_for_byte_and_the_energy_forbids_flips(cli, tmp_path):
    # 384 pixels: more than one slice (256 pixels a thread) with one thread.
    cli(["fractal", "--grid", "theta1=-3:3:24", "--grid", "theta2=-3:3:16", "--t-max", "10",
         "--out", "f.npy", "--summary", "s.json"], tmp_path)
    s = summary(tmp_path / "s.json")
    r = pendula.fractal(theta1=(-3, 3, 24), theta2=(-3, 3, 16), t_max=10, threads=1)
    flips = np.load(tmp_path / "f.npy")
    assert r.flip_time.shape == flips.shape == (16, 24)
    assert r.flip_time.tobytes() == flips.tobytes()
    np.testing.assert_array_equal(r.converged, np.load(tmp_path / "f-converged.npy").astype(bool))
    for key in ["flipped", "forbidden_by_energy", "unconverged", "unconverged_share", "pixels", "dt_check"]:
        assert getattr(r, key) == s[key], key
    assert list(r.shape) == s["shape"]
    two = pendula.fractal(theta1=(-3, 3, 24), theta2=(-3, 3, 16), t_max=10, threads=2)
    assert two.flip_time.tobytes() == r.flip_time.tobytes()
    # Released from rest with E = −2g cos θ₁ − g cos θ₂ below −g (the least potential with a
    # rod upright, unit masses and lengths), neither rod can pass ±π.
    g1, g2 = np.meshgrid(r.theta1_centres, r.theta2_centres)
    forbidden = -2 * 9.81 * np.cos(g1) - 9.81 * np.cos(g2) < -9.81
    assert forbidden.sum() == r.forbidden_by_energy > 0
    assert np.all(np.isnan(r.flip_time[forbidden]))
    assert np.all(r.flip_time[np.isfinite(r.flip_time)] <= 10)


def test_bifurcation_equals_the_cli_on_two_systems_and_settles_on_period_one(cli, tmp_path):
    cli(["bifurcation", "--param", "drive_amplitude=1.0:1.5:16", "--transient", "100", "--samples", "10",
         "--out-dir", "o", "--summary", "s.json"], tmp_path)
    s = summary(tmp_path / "s.json")
    r = pendula.bifurcation(param=("drive_amplitude", 1.0, 1.5, 16), transient=100, samples=10)
    assert r.kernel == s["tables"]["run"][0]["kernel"] == "simd lanes (ensemble engine)"
    header, rows = read_csv(tmp_path / "o" / "bifurcation.csv")
    assert header == ["drive_amplitude", "sample", "theta", "omega"]
    ours = np.column_stack([np.repeat(r.values, 10), np.tile(np.arange(10), 16), r.samples.reshape(-1, 2)])
    np.testing.assert_array_equal(floats(rows), ours)
    # Another system on the same lanes: the pendulum, driven, with damping.
    cli(["bifurcation", "pendulum", "--set", "drive_frequency=2", "--set", "damping=0.5", "--param",
         "drive_amplitude=0.5:2:6", "--transient", "30", "--samples", "5", "--out-dir", "p",
         "--summary", "p.json"], tmp_path)
    p = summary(tmp_path / "p.json")
    scalar = pendula.bifurcation(pendula.System("pendulum", drive_frequency=2, damping=0.5),
                                 param=("drive_amplitude", 0.5, 2, 6), transient=30, samples=5)
    assert scalar.kernel == p["tables"]["run"][0]["kernel"] == "simd lanes (ensemble engine)"
    _, rows = read_csv(tmp_path / "p" / "bifurcation.csv")
    np.testing.assert_array_equal(floats(rows, [2, 3]), scalar.samples.reshape(-1, 2))
    # Baker–Gollub (q = 2, ω_D = 2/3): at weak drive the motion settles, at the decay rate
    # 1/(2q) = 0.25/s, onto an orbit of the drive's period: every sample the same.
    weak = pendula.bifurcation(param=("drive_amplitude", 0.3, 0.6, 3), transient=150, samples=8)
    assert np.ptp(weak.samples, axis=1).max() < 1e-9
    assert np.ptp(weak.samples[:, 0, 0]) > 0.01  # and the orbits differ with the drive


def test_convergence_equals_the_cli_and_orders_match_the_declared(cli, tmp_path):
    # Defaults: the oscillator against its exact solution, every method on its own ladder.
    cli(["convergence", "--out-dir", "o", "--summary", "s.json"], tmp_path)
    s = summary(tmp_path / "s.json")
    r = pendula.convergence()
    assert (r.t_end, r.reference) == (s["t_end"], s["reference"])
    assert r.orders == {row["method"]: row["fitted_order"] for row in s["tables"]["orders"]}
    _, rows = read_csv(tmp_path / "o" / "convergence.csv")
    assert {m: d.tolist() for m, d in r.dt.items()} == {
        m: [float(row[1]) for row in rows if row[0] == m] for m in dict.fromkeys(row[0] for row in rows)
    }
    for m in r.methods:
        theirs = [float(row[2]) for row in rows if row[0] == m.method]
        assert m.error.tolist() == theirs, m.method
    declared = {m.name: m.order for m in pendula.catalogue().methods}
    fitted = {m: o for m, o in r.orders.items() if o is not None}
    assert abs(fitted["rk4"] - 4) < 0.1
    assert all(abs(o - declared[m]) < 0.3 for m, o in fitted.items()), fitted
    # Given steps, the same for every method (the CLI's geometric range, read back).
    cli(["convergence", "pendulum", "--methods", "rk4,euler", "--dt-max", "0.1", "--levels", "4", "--t-end", "2",
         "--out-dir", "g", "--summary", "g.json"], tmp_path)
    g = summary(tmp_path / "g.json")
    _, rows = read_csv(tmp_path / "g" / "convergence.csv")
    given = pendula.convergence("pendulum", methods="rk4,euler", dts=[float(row[1]) for row in rows if row[0] == "rk4"], t_end=2)
    assert given.orders == {row["method"]: row["fitted_order"] for row in g["tables"]["orders"]}
    assert given.reference == g["reference"]
    assert [m.method for m in given.methods] == ["rk4", "euler"]


def test_work_precision_equals_the_cli(cli, tmp_path):
    cli(["work-precision", "--methods", "rk4,dopri5,verlet", "--out-dir", "o", "--summary", "s.json"], tmp_path)
    s = summary(tmp_path / "s.json")
    r = pendula.work_precision(methods=["rk4", "dopri5", "verlet"])
    assert (r.t_end, r.reference) == (s["t_end"], s["reference"])
    header, rows = read_csv(tmp_path / "o" / "work_precision.csv")
    assert header == ["method", "dt", "tol", "error", "rhs_evals", "wall_s"]
    assert [m.method for m in r.methods] == list(dict.fromkeys(row[0] for row in rows))
    for m in r.methods:
        points = [row for row in rows if row[0] == m.method]
        assert m.dt.tolist() == [float(p[1]) for p in points]
        assert [None if math.isnan(t) else t for t in m.tol] == [float(p[2]) if p[2] else None for p in points]
        assert m.error.tolist() == [float(p[3]) for p in points]
        assert m.rhs_evals.tolist() == [int(p[4]) for p in points]
        assert np.all(m.wall_s > 0)
    # The default tolerances: 10 from 1e-3 to 1e-12.
    tols = r["dopri5"].tol
    assert len(tols) == 10 and (tols[0], tols[-1]) == (1e-3, 1e-12)


def test_divergence_equals_the_cli_and_a_linear_separation_decays_at_the_damping_rate(cli, tmp_path):
    cli(["divergence", "--out-dir", "o", "--summary", "s.json"], tmp_path)
    s = summary(tmp_path / "s.json")
    r = pendula.divergence()
    assert r.growth_rate == s["growth_rate"]
    assert list(r.fit_window) == [s["fit_start"], s["fit_end"]]
    assert (r.variable, r.delta, r.saturation, r.t_end) == (s["variable"], s["delta"], s["saturation"], s["t_end"])
    _, rows = read_csv(tmp_path / "o" / "divergence.csv")
    np.testing.assert_array_equal(floats(rows), np.column_stack([r.t, r.distance]))
    # The damped oscillator is linear: the separation is a solution, its envelope decaying as
    # e^(−c t / 2m) — a fitted rate of −c/2m = −0.1 /s.
    damped = pendula.divergence(pendula.System("oscillator", c=0.2), delta=1e-3, t_end=60, saturation=1)
    assert abs(damped.growth_rate + 0.1) < 0.005, damped.growth_rate


def test_bad_input_names_the_value_and_what_is_allowed():
    with pytest.raises(pendula.InvalidValueError, match=r"`dt`: must be at most `renormalise` \(0.5 s"):
        pendula.lyapunov(dt=0.6)
    with pytest.raises(pendula.InvalidValueError, match=r"`t_end`: at least 20 re-orthonormalisations"):
        pendula.lyapunov(t_end=5)
    with pytest.raises(pendula.UnsuitableMethodError, match="verlet"):
        pendula.lyapunov("pendulum", method="verlet", t_end=20)
    with pytest.raises(pendula.UnsuitableMethodError, match="degree of freedom"):
        pendula.poincare("pendulum")
    with pytest.raises(pendula.InvalidValueError, match="not an angle of double; valid: theta1, theta2"):
        pendula.poincare(section="omega1")
    with pytest.raises(pendula.InvalidValueError, match="`count`: 1 to 10000"):
        pendula.poincare(count=0)
    with pytest.raises(pendula.InvalidValueError, match="takes fixed steps: give `dt`"):
        pendula.poincare(method="rk4")
    with pytest.raises(pendula.UnsuitableMethodError, match="euler, rk4, tao-2, tao-4"):
        pendula.fractal(method="dop853", theta1=(-1, 1, 2), theta2=(-1, 1, 2))
    with pytest.raises(pendula.InvalidValueError, match="double pendulum"):
        pendula.fractal("pendulum")
    with pytest.raises(pendula.InvalidValueError, match="theta1"):
        pendula.fractal(theta1=(1, -1, 4))
    with pytest.raises(pendula.InvalidValueError, match="needs a driven system"):
        pendula.bifurcation("chain", param=("g", 1, 2, 3))
    with pytest.raises(pendula.InvalidValueError, match="give `param`"):
        pendula.bifurcation("pendulum")
    with pytest.raises(pendula.UnknownNameError, match="variable"):
        pendula.bifurcation(variable="phi", param=("drive_amplitude", 1, 2, 2))
    with pytest.raises(pendula.InvalidValueError, match="drive_frequency"):
        pendula.bifurcation("pendulum", param=("drive_amplitude", 1, 2, 2), samples=1, transient=1)
    with pytest.raises(pendula.InvalidValueError, match="listed twice"):
        pendula.convergence(methods="rk4,rk4")
    with pytest.raises(pendula.UnknownNameError, match="rk5"):
        pendula.convergence(methods=["rk5"])
    with pytest.raises(pendula.InvalidValueError, match="`dts`"):
        pendula.convergence(dts=[0.1, -0.1])
    with pytest.raises(pendula.InvalidValueError, match="`tols`"):
        pendula.work_precision(tols=[1e-20])
    with pytest.raises(pendula.InvalidValueError, match="`delta`: a finite separation, not 0"):
        pendula.divergence(delta=0)
    with pytest.raises(pendula.InvalidValueError, match="`saturation`"):
        pendula.divergence(saturation=1e-12)
    with pytest.raises(pendula.UnknownNameError, match="phi"):
        pendula.divergence(variable="phi")
    with pytest.raises(pendula.InvalidValueError, match="`dt`"):
        pendula.divergence(dt=-1)


def test_results_pickle_plot_and_show_a_table():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    results = [
        pendula.lyapunov("pendulum", t_end=20, transient=1),
        pendula.poincare(count=2, t_end=10),
        pendula.fractal(theta1=(-3, 3, 8), theta2=(-3, 3, 8), t_max=3),
        pendula.bifurcation(param=("drive_amplitude", 1.0, 1.5, 4), transient=10, samples=3),
        pendula.convergence(methods="rk4,verlet"),
        pendula.work_precision(methods="rk4", tols=[1e-4, 1e-6]),
        pendula.divergence(t_end=3),
    ]
    for r in results:
        back = pickle.loads(pickle.dumps(r))
        assert type(back) is type(r) and back.system == r.system
        for name, value in vars(r).items():
            if isinstance(value, np.ndarray):
                assert getattr(back, name).tobytes() == value.tobytes(), name
        assert "<table>" in r._repr_html_()
        fig, ax = plt.subplots()
        assert r.plot(ax) is ax
        assert ax.has_data(), type(r).__name__
        plt.close(fig)
    conv = pickle.loads(pickle.dumps(results[4]))
    assert conv.orders == results[4].orders
    # Versioned: the form names the class and its fields, and a future version is refused.
    reduced = results[6].__reduce__()
    assert reduced[1][:2] == (1, "DivergenceResult") and "growth_rate" in reduced[1][2]
    with pytest.raises(pendula.PendulaError, match="version 2"):
        reduced[0](2, *reduced[1][1:])


def test_ctrl_c_interrupts_a_long_fractal_quickly():
    # A 512² map to 100 s (tens of CPU-seconds); SIGINT after 0.5 s must end it within 0.2 s.
    latency = ctrl_c_latency(
        lambda: pendula.fractal(theta1=(-math.pi, math.pi, 512), theta2=(-math.pi, math.pi, 512), t_max=100),
        after=0.5,
    )
    assert latency < 0.2, latency
