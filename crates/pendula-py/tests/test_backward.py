"""Runs backward in time, as scipy's solve_ivp does them: ``t_span=(10, 0)`` starts at
t = 10 s and ends at t = 0, with steps of size ``dt`` (the direction is t_span's). Checked
against closed forms (the driven, damped oscillator, whose drive must be evaluated at the
true, decreasing times), against scipy's own backward runs, and by going there and back."""

import io
import math

import numpy as np
import pytest

import pendula

# The driven, damped oscillator m x'' + c x' + k x = F cos(W t): a closed form with a
# time-dependent drive and damping, so a backward run that used the wrong time or the wrong
# sign of a step misses it.
M, K, C, F, W = 1.0, 4.0, 0.2, 1.0, 1.3


def oscillator(**over):
    values = dict(m=M, k=K, c=C, drive_amplitude=F, drive_frequency=W)
    values.update(over)
    return pendula.System("oscillator", **values)


def exact(t, t1, x1, v1, c=C, f=F):
    """x(t), v(t) of the oscillator through (x1, v1) at t1, for times t either side of t1."""
    t = np.asarray(t, dtype=float)
    d = K - M * W * W
    den = d * d + (c * W) ** 2
    a, b = f * d / den, f * c * W / den

    def particular(s):
        return a * np.cos(W * s) + b * np.sin(W * s), -a * W * np.sin(W * s) + b * W * np.cos(W * s)

    xp1, vp1 = particular(t1)
    g = c / (2 * M)
    wd = math.sqrt(K / M - g * g)
    c1 = x1 - xp1
    c2 = (v1 - vp1 + g * c1) / wd
    s = t - t1
    e = np.exp(-g * s)
    xh = e * (c1 * np.cos(wd * s) + c2 * np.sin(wd * s))
    vh = -g * xh + e * wd * (-c1 * np.sin(wd * s) + c2 * np.cos(wd * s))
    xp, vp = particular(t)
    return np.array([xh + xp, vh + vp])


Y10 = np.array([0.7, -0.4])  # the state at t = 10 s


@pytest.mark.parametrize("method", ["rk4", "gauss-legendre-4", "dopri5", "dop853"])
def test_a_backward_run_of_the_driven_damped_oscillator_is_the_closed_form(method):
    system = oscillator()
    tight = {"rtol": 1e-11, "atol": 1e-11} if method.startswith("dop") else {"dt": 1e-3}
    sol = pendula.solve(system, (10, 0), Y10, method=method, **tight)
    assert sol.success and sol.t[0] == 10 and sol.t[-1] == 0
    assert np.all(np.diff(sol.t) < 0), "t runs from 10 down to 0"
    error = np.max(np.abs(sol.y - exact(sol.t, 10.0, *Y10)))
    assert error < 1e-9, error
    # Not the closed form of a run forward from the same state, nor of an undriven system.
    assert np.max(np.abs(exact(0.0, 10.0, *Y10, f=0.0) - sol.y[:, -1])) > 0.1


def test_a_backward_fixed_step_run_keeps_the_methods_order():
    """rk4 backward: halving dt divides the error at t = 0 by about 2⁴."""
    system = oscillator()
    errors = []
    for dt in (0.1, 0.05, 0.025):
        sol = pendula.solve(system, (10, 0), Y10, method="rk4", dt=dt)
        assert len(sol.t) == round(10 / dt) + 1
        errors.append(np.max(np.abs(sol.y[:, -1] - exact(0.0, 10.0, *Y10))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 4) < 0.3), (errors, orders)


@pytest.mark.parametrize(
    "system, method, dt, retraces",
    [
        # Symmetric one-step maps undo their own steps: back to the start up to round-off.
        (pendula.System("pendulum", theta=2.0), "verlet", 1e-3, True),
        (pendula.System("pendulum", theta=2.0), "yoshida-4", 1e-3, True),
        (pendula.System("double"), "gauss-legendre-4", 1e-3, True),
        # Tao's maps are symmetric on the doubled phase space, but a run starts its second
        # copy afresh: back to the start to the method's accuracy. So does rk4 (not symmetric).
        (pendula.System("double"), "tao-4", 1e-3, False),
        (pendula.System("pendulum", theta=2.0), "rk4", 1e-3, False),
        (pendula.System("pendulum", theta=2.0, damping=0.3), "rk4", 1e-3, False),
        (pendula.System("driven-pendulum"), "rk4", 1e-2, False),
    ],
    ids=lambda v: v if isinstance(v, str) else None,
)
def test_there_and_back_recovers_the_start(system, method, dt, retraces):
    forward = pendula.solve(system, (0, 5), method=method, dt=dt)
    back = pendula.solve(system, (5, 0), forward.y[:, -1], method=method, dt=dt)
    assert back.t[-1] == 0 and len(back.t) == len(forward.t)
    assert np.allclose(back.t[::-1], forward.t, rtol=0, atol=1e-12)
    gap = np.max(np.abs(back.y[:, -1] - system.y0))
    # The forward run's own error, against dop853 at 1e-13.
    reference = pendula.solve(system, (0, 5), method="dop853", rtol=1e-13, atol=1e-13)
    accuracy = np.max(np.abs(forward.y[:, -1] - reference.y[:, -1]))
    if retraces:
        assert gap < 1e-10 and gap < 0.01 * accuracy, (gap, accuracy)
    else:
        assert gap < 3 * accuracy + 1e-12, (gap, accuracy)
    # The backward run passes through the forward run's states at the same times.
    assert np.max(np.abs(back.y[:, ::-1] - forward.y)) < 3 * accuracy + 1e-10


@pytest.mark.parametrize("system", ["driven-pendulum", "oscillator"])
def test_adaptive_there_and_back_from_a_nonzero_start(system):
    """From t0 = 3 s (adaptive runs started at 0 only) to 8 s and back: the drive is
    cos(W t) at the true times both ways."""
    s = oscillator() if system == "oscillator" else pendula.System(system)
    forward = pendula.solve(s, (3, 8), method="dop853", rtol=1e-12, atol=1e-12)
    back = pendula.solve(s, (8, 3), forward.y[:, -1], method="dop853", rtol=1e-12, atol=1e-12)
    assert back.t[0] == 8 and back.t[-1] == 3
    assert np.max(np.abs(back.y[:, -1] - s.y0)) < 1e-9


def test_backward_runs_agree_with_scipy():
    """The driven pendulum backward with dop853 against scipy's solve_ivp(DOP853) backward,
    from the same state (the equations are pendula's, the integrator scipy's)."""
    scipy_integrate = pytest.importorskip("scipy.integrate")
    s = pendula.System("driven-pendulum")
    y20 = np.array([0.3, -0.8])
    ref = scipy_integrate.solve_ivp(s.rhs, (20, 12), y20, method="DOP853", rtol=1e-12, atol=1e-12, dense_output=True)
    sol = pendula.solve(s, (20, 12), y20, method="dop853", rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(sol.y[:, -1] - ref.y[:, -1])) < 1e-8
    mid = np.linspace(20, 12, 9)
    rk4 = pendula.solve(s, (20, 12), y20, method="rk4", dt=1e-3, t_eval=mid)
    assert np.array_equal(rk4.t, mid)
    assert np.max(np.abs(rk4.y - ref.sol(mid))) < 1e-9


@pytest.mark.parametrize("method", ["rk4", "dop853"])
def test_dense_output_and_t_eval_on_a_backward_run(method):
    system = oscillator()
    tol = {"rtol": 1e-12, "atol": 1e-12} if method == "dop853" else {"dt": 1e-3}
    sol = pendula.solve(system, (10, 0), Y10, method=method, dense_output=True, **tol)
    assert (sol.sol.t_min, sol.sol.t_max) == (0.0, 10.0)
    ts = np.linspace(0, 10, 101)
    assert np.max(np.abs(sol.sol(ts) - exact(ts, 10.0, *Y10))) < 1e-9
    assert np.max(np.abs(sol.sol(3.3) - exact(3.3, 10.0, *Y10))) < 1e-9
    with pytest.raises(pendula.InvalidValueError, match="sol covers"):
        sol.sol(10.5)
    # t_eval in the run's direction: decreasing.
    down = np.linspace(10, 0, 41)
    sampled = pendula.solve(system, (10, 0), Y10, method=method, t_eval=down, **tol)
    assert np.array_equal(sampled.t, down)
    assert np.max(np.abs(sampled.y - exact(down, 10.0, *Y10))) < 1e-9
    with pytest.raises(pendula.InvalidValueError, match="t_eval.*decreasing"):
        pendula.solve(system, (10, 0), Y10, method=method, t_eval=down[::-1], **tol)


def zero_crossings(t1, x1, v1, lo, hi):
    """The times in (lo, hi) where the closed form's x crosses 0, each with its velocity."""
    ts = np.linspace(lo, hi, 200001)
    x = exact(ts, t1, x1, v1)[0]
    out = []
    for i in np.nonzero(np.sign(x[:-1]) != np.sign(x[1:]))[0]:
        a, b = ts[i], ts[i + 1]
        for _ in range(60):
            m = 0.5 * (a + b)
            if np.sign(exact(m, t1, x1, v1)[0]) == np.sign(exact(a, t1, x1, v1)[0]):
                a = m
            else:
                b = m
        out.append((0.5 * (a + b), exact(0.5 * (a + b), t1, x1, v1)[1]))
    return out


@pytest.mark.parametrize("method", ["rk4", "dop853"])
def test_events_on_a_backward_run_are_the_closed_forms_in_the_runs_order(method):
    system = oscillator()
    tol = {"rtol": 1e-12, "atol": 1e-12} if method == "dop853" else {"dt": 1e-3}

    def g(t, y):
        return y[0]

    g.direction = 1.0  # x rising as the run goes, i.e. as t decreases: v < 0 there

    sol = pendula.solve(system, (10, 0), Y10, method=method, events=["zero:x", "zero:x+", g], **tol)
    crossings = zero_crossings(10.0, *Y10, 0.0, 10.0)
    assert len(crossings) >= 4
    every = sorted((t for t, _ in crossings), reverse=True)
    rising = sorted((t for t, v in crossings if v < 0), reverse=True)
    assert len(sol.t_events[0]) == len(every) and len(sol.t_events[1]) == len(rising) >= 2
    assert np.max(np.abs(sol.t_events[0] - every)) < 1e-8
    assert np.max(np.abs(sol.t_events[1] - rising)) < 1e-8
    assert np.max(np.abs(sol.t_events[2] - rising)) < 1e-8
    assert np.all(np.diff(sol.t_events[0]) < 0), "in the run's order: decreasing"
    assert np.max(np.abs(sol.y_events[1][:, 0])) < 1e-8 and np.all(sol.y_events[1][:, 1] < 0)

    # A terminal event ends the backward run there.
    stop = pendula.solve(system, (10, 0), Y10, method=method, events="zero:x", stop_on_event=True, **tol)
    assert stop.status == 1 and stop.t[-1] == stop.t_events[0][0]
    assert abs(stop.t[-1] - every[0]) < 1e-8 and np.all(stop.t >= stop.t[-1])


def test_a_terminal_callable_event_on_a_backward_run_keeps_t_eval_before_it():
    system = oscillator()

    def g(t, y):
        return y[0]

    g.terminal = True
    first = max(t for t, _ in zero_crossings(10.0, *Y10, 0.0, 10.0))
    down = np.linspace(10, 0, 101)
    sol = pendula.solve(system, (10, 0), Y10, method="dop853", rtol=1e-12, atol=1e-12, events=g, t_eval=down)
    assert sol.status == 1 and abs(sol.t_events[0][0] - first) < 1e-8
    assert np.array_equal(sol.t, down[down >= sol.t_events[0][0]])


def test_the_step_is_a_size_and_the_direction_is_t_spans():
    system = oscillator()
    with pytest.raises(pendula.InvalidValueError, match=r"-0\.01 for `dt`.*direction comes from t_span"):
        pendula.solve(system, (10, 0), Y10, method="rk4", dt=-0.01)
    with pytest.raises(pendula.InvalidValueError, match=r"t_span \(3, 3\)"):
        pendula.solve(system, (3, 3), Y10, method="rk4")


def test_a_backward_solution_animates_and_views_as_it_ran():
    """animate() plays a backward run from t0 down to t_end (it had no frames: times were
    taken increasing), and view() brings the step size, not a negative step."""
    import json
    import urllib.parse

    from PIL import Image

    sol = pendula.solve("pendulum", (2, 0), method="rk4", dt=0.01)
    gif = sol.animate(fps=10)
    assert gif.frames == 21
    image = Image.open(io.BytesIO(gif.data))
    assert image.n_frames == 21
    share = json.loads(urllib.parse.unquote(pendula.view(sol).url.split("#")[1]))
    assert share["dt"] == pytest.approx(0.01) and share["method"] == "rk4"
