"""pendula.solve's continuous solution (sol, t_eval), events and progress: against closed
forms, scipy at a tighter tolerance, and the CLI's event locator."""

import math
import pickle

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pendula
from conftest import ctrl_c_latency, summary


def _reference(system, t_end):
    return solve_ivp(
        lambda t, y: system.rhs(t, y), (0, t_end), system.y0, method="DOP853",
        rtol=1e-13, atol=1e-13, dense_output=True,
    ).sol


def test_hermite_dense_output_of_rk4_is_fourth_order():
    # Off the grid (a third of the way into steps), sol's error against an independent
    # reference falls as h⁴, like the integration's own error on the grid.
    system = pendula.System("double")
    ref = _reference(system, 2.0)
    dts = [0.02, 0.01, 0.005]
    dense_errors, grid_errors = [], []
    for dt in dts:
        sol = pendula.solve(system, (0, 2), method="rk4", dt=dt, dense_output=True)
        assert sol.sol.order == 3 and sol.sol.coefficients is None
        off = sol.t[:-1] + dt / 3
        dense_errors.append(np.max(np.abs(sol.sol(off) - ref(off))))
        grid_errors.append(np.max(np.abs(sol.y - ref(sol.t))))
        # On the grid, sol is the integration itself.
        assert np.array_equal(sol.sol(sol.t[5]), sol.y[:, 5])
    slope = np.polyfit(np.log(dts), np.log(dense_errors), 1)[0]
    assert 3.7 < slope < 4.3, (dense_errors, slope)
    # The interpolant's error is of the integration's order: its ratio to the error on the
    # grid stays bounded as h falls (about 4 here: the cubic's constant is the larger).
    ratios = [d / g for d, g in zip(dense_errors, grid_errors)]
    assert max(ratios) < 10 and ratios[-1] < 1.2 * ratios[0], ratios


@pytest.mark.parametrize("method, order", [("dop853", 7), ("dopri5", 4)])
def test_adaptive_dense_output_is_the_methods_own(method, order):
    system = pendula.System("double")
    ref = _reference(system, 10.0)
    sol = pendula.solve(system, (0, 10), method=method, rtol=1e-10, atol=1e-10, dense_output=True)
    assert sol.sol.order == order and sol.sol.coefficients is not None
    # Midpoints of every step: no worse than the integration's own error at the steps.
    mid = 0.5 * (sol.t[1:] + sol.t[:-1])
    dense_error = np.max(np.abs(sol.sol(mid) - ref(mid)))
    grid_error = np.max(np.abs(sol.y - ref(sol.t)))
    assert dense_error < 3 * grid_error + 1e-9, (dense_error, grid_error)
    # The same interpolant as the one the library's event locator uses: the first step's
    # end is exact.
    assert np.allclose(sol.sol(sol.t[1]), sol.y[:, 1], rtol=0, atol=1e-14)


def test_t_eval_samples_the_continuous_solution():
    system = pendula.System("double")
    full = pendula.solve(system, (0, 5), method="dop853", rtol=1e-10, atol=1e-10, dense_output=True)
    t_eval = np.linspace(0, 5, 101)
    at = pendula.solve(system, (0, 5), method="dop853", rtol=1e-10, atol=1e-10, t_eval=t_eval)
    assert np.array_equal(at.t, t_eval) and at.y.shape == (4, 101) and at.sol is None
    assert np.array_equal(at.y, full.sol(t_eval))
    assert at.steps == full.steps and at.nfev == full.nfev
    with pytest.raises(pendula.InvalidValueError, match="t_eval value 6.0"):
        pendula.solve(system, (0, 5), t_eval=[1.0, 6.0])
    with pytest.raises(pendula.InvalidValueError, match="increasing"):
        pendula.solve(system, (0, 5), t_eval=[2.0, 1.0])


def test_events_match_the_cli(cli, tmp_path):
    events = ["flip", "section:theta1=0+", "zero:omega2"]
    sol = pendula.solve("double", (0, 20), method="rk4", dt=1e-3, events=events)
    args = ["simulate", "double", "--method", "rk4", "--dt", "1e-3", "--t-end", "20", "--summary", "s.json"]
    for e in events:
        args += ["--event", e]
    cli(args, tmp_path)
    found = summary(tmp_path / "s.json")["events"]
    assert sol.event_names == events
    for name, te, ye in zip(events, sol.t_events, sol.y_events):
        theirs = [e for e in found if e["name"] == name]
        assert len(te) == len(theirs) > 0, name
        assert list(te) == [e["t"] for e in theirs]
        assert [list(y) for y in ye] == [[e["state"][n] for n in sol.names] for e in theirs]
    assert len(sol.t_events[0]) == 1  # a flip counts once


def test_callable_events_on_the_oscillator_match_the_closed_form():
    # x = cos t: zeros at (k + ½)π; falling ones at even k.
    def x(t, y):
        return y[0]

    def falling(t, y):
        return y[0]

    falling.direction = -1
    sol = pendula.solve("oscillator", (0, 20), method="rk4", dt=1e-3, events=[x, falling, "zero:x"])
    exact = (np.arange(6) + 0.5) * math.pi
    assert np.max(np.abs(sol.t_events[0] - exact)) < 1e-9
    assert np.max(np.abs(sol.t_events[1] - exact[::2])) < 1e-9
    # The library's locator on the same run: the same crossings.
    assert np.max(np.abs(sol.t_events[0] - sol.t_events[2])) < 1e-11
    assert sol.event_names == ["x", "falling", "zero:x"]


def test_a_terminal_event_ends_the_run_there():
    def quarter(t, y):
        return y[0]

    quarter.terminal = True
    sol = pendula.solve("oscillator", (0, 20), method="rk4", dt=1e-3, events=quarter)
    assert sol.status == 1 and sol.success and "terminal event" in sol.message
    assert abs(sol.t[-1] - math.pi / 2) < 1e-9 and sol.t[-1] == sol.t_events[0][0]
    assert np.array_equal(sol.y[:, -1], sol.y_events[0][0])
    # The library's terminal event, as --stop-on-event.
    lib = pendula.solve("double", (0, 20), method="rk4", dt=1e-3, events="flip", stop_on_event=True)
    assert lib.status == 1 and lib.t[-1] == lib.t_events[0][0] < 20
    with pytest.raises(pendula.UnknownNameError, match="theta1"):
        pendula.solve("double", (0, 1), events="zero:theta")


def test_progress_reports_the_time_reached(capfd):
    seen = []
    pendula.solve("double", (0, 60), method="dop853", rtol=1e-12, atol=1e-12, progress=seen.append)
    assert seen and all(0 <= t <= 60 for t in seen) and seen == sorted(seen)
    pendula.solve("double", (0, 1), method="rk4", progress=True)
    err = capfd.readouterr().err
    assert "100.0%" in err or "it/s" in err or "s/s" in err, err


def test_a_solution_with_its_dense_output_pickles():
    sol = pendula.solve("double", (0, 3), method="dop853", dense_output=True, events="section:theta1=0+")
    back = pickle.loads(pickle.dumps(sol))
    t = np.linspace(0, 3, 17)
    assert np.array_equal(back.sol(t), sol.sol(t)) and np.array_equal(back.y, sol.y)
    assert np.array_equal(back.t_events[0], sol.t_events[0]) and back.event_names == sol.event_names


@pytest.mark.parametrize("method", ["dop853", "rk4", "gauss-legendre-4"])
def test_ctrl_c_interrupts_a_long_solve_quickly(method):
    # Runs of minutes; SIGINT after 0.3 s must end each within 0.2 s (the run takes the GIL
    # back about every 20 ms to let Python's handlers run).
    tight = None if method != "dop853" else 1e-12
    latency = ctrl_c_latency(
        lambda: pendula.solve("double", (0, 1e6), method=method, dt=1e-3, rtol=tight, atol=tight), after=0.3
    )
    assert latency < 0.2, latency


def test_an_exception_in_the_progress_callback_ends_the_run():
    def fail(t):
        raise RuntimeError(f"stop at {t}")

    with pytest.raises(RuntimeError, match="stop at"):
        pendula.solve("double", (0, 1e4), method="rk4", progress=fail)


def test_counted_runs_report_progress(capfd):
    # Ensembles count members, sweeps cells, fractals pixels; the last count is the total.
    seen = {"members": [], "cells": [], "pixels": []}
    y0s = np.zeros((5000, 4))
    y0s[:, 0] = np.linspace(-3, 3, 5000)
    pendula.ensemble("double", y0s, steps=3000, dt=1e-3, progress=seen["members"].append)
    pendula.sweep("double", ["theta1=-3:3:60", "theta2=-3:3:50"], steps=3000, shard=(2, 3), progress=seen["cells"].append)
    pendula.fractal(theta1=(-3, 3, 40), theta2=(-3, 3, 30), t_max=10, progress=seen["pixels"].append)
    for kind, total in (("members", 5000), ("cells", 1000), ("pixels", 1200)):
        assert seen[kind][-1] == total and seen[kind] == sorted(seen[kind]), (kind, seen[kind][:5])
        assert len(seen[kind]) >= 2, kind  # counts arrived while the run went on
    pendula.ensemble("double", y0s[:100], steps=10, progress=True)
    assert "100 of 100 members" in capfd.readouterr().err
