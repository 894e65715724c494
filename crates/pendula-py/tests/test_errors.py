"""Every error class, with a message that names the value and what is allowed."""

import pytest

import pendula
from pendula import errors


def test_unknown_names_list_the_valid_ones():
    with pytest.raises(pendula.UnknownNameError, match="did you mean `verlet`") as e:
        pendula.solve("double", (0, 1), method="verlt")
    assert isinstance(e.value, ValueError) and isinstance(e.value, pendula.PendulaError)
    with pytest.raises(pendula.UnknownNameError, match="valid systems: oscillator"):
        pendula.System("dubble")
    with pytest.raises(pendula.UnknownNameError, match="`m3`.*valid names: m1, m2"):
        pendula.System("double", m3=1.0)


def test_invalid_values_name_the_value_and_the_domain():
    with pytest.raises(pendula.InvalidValueError, match="-1 for `m1`"):
        pendula.System("double", m1=-1.0)
    with pytest.raises(pendula.InvalidValueError, match="-0.1 for `dt`"):
        pendula.solve("double", (0, 1), method="rk4", dt=-0.1)
    with pytest.raises(pendula.InvalidValueError, match=r"t_span \(1, 1\)"):
        pendula.solve("double", (1, 1))
    with pytest.raises(pendula.InvalidValueError, match="rtol and atol"):
        pendula.solve("double", (0, 1), method="rk4", rtol=1e-6)
    with pytest.raises(pendula.InvalidValueError, match="y0 of 3 values"):
        pendula.solve("double", (0, 1), y0=[1, 2, 3])


def test_unsuitable_methods_carry_the_suggestion():
    with pytest.raises(pendula.UnsuitableMethodError, match="not separable.*try gauss-legendre-4"):
        pendula.solve("double", (0, 1), method="yoshida-4")
    with pytest.raises(pendula.UnsuitableMethodError, match="damping = 0.2"):
        pendula.solve(pendula.System("pendulum", damping=0.2), (0, 1), method="verlet")


def test_a_failed_run_names_the_time_and_keeps_the_steps():
    stiff = pendula.System("oscillator", k=1e6)
    with pytest.raises(pendula.NonFiniteStateError, match="non-finite at t = ") as e:
        pendula.solve(stiff, (0, 20), method="euler", dt=0.01)
    err = e.value
    assert isinstance(err, pendula.IntegrationError) and isinstance(err, RuntimeError)
    assert 0 < err.t <= 20
    sol = err.solution
    assert not sol.success and sol.status == -1 and len(sol.t) > 1 and sol.t[-1] < err.t
    assert set(errors.__all__) >= {"StepSizeTooSmallError", "NewtonError"}


BAD_SOLVES = [
    # (arguments, the argument the message must name)
    (dict(t_span=(0, 1e8), method="rk4", dt=1e-6), "`dt`"),  # more than 10^13 steps
    (dict(t_span=(0, 1), method="rk4", dt=0.0), "`dt`"),
    (dict(t_span=(0, 1), method="rk4", dt=float("nan")), "`dt`"),
    (dict(t_span=(0, 1), method="dop853", dt=-1e-3), "`dt`"),
    (dict(t_span=(0, 1), method="tao-4", dt=0.01), "`dt`"),  # w dt > 1
    (dict(t_span=(float("nan"), 1)), "t_span"),
    (dict(t_span=(0, float("inf"))), "t_span"),
    (dict(t_span=(2, 2)), "t_span"),
    (dict(t_span=(0, 1), method="dop853", rtol=1e-20), "`rtol`"),
    (dict(t_span=(0, 1), method="dop853", rtol=0.0), "`rtol`"),
    (dict(t_span=(0, 1), method="dop853", atol=-1.0), "`atol`"),
    (dict(t_span=(0, 1), t_eval=[0.5, 2.0]), "t_eval"),
    (dict(t_span=(0, 1), t_eval=[0.5, 0.2]), "t_eval"),
    (dict(t_span=(0, 1), events=[3]), "event"),
    (dict(t_span=(0, 1), events="zero:theta"), "theta1"),
    (dict(t_span=(0, 1), progress="yes"), "`progress`"),
    (dict(t_span=(0, 1), y0=[0.0, float("nan"), 0.0, 0.0]), "`y0`"),
]


@pytest.mark.parametrize("kwargs, name", BAD_SOLVES, ids=[f"{n}-{i}" for i, (_, n) in enumerate(BAD_SOLVES)])
def test_solve_errors_name_the_python_argument(kwargs, name):
    """Each message names the argument as `solve` spells it: dt, not the library's h;
    t_span, not t0 or t_end; and never a quantity Python cannot set."""
    with pytest.raises(ValueError) as e:
        pendula.solve("double", **kwargs)
    message = str(e.value)
    assert name in message, message
    for internal in ("`h`", " h =", "w h", "`t0`", "`t_end`", "h-min", "binding constant or"):
        assert internal not in message, message


def test_the_tao_step_limit_is_said_in_dt():
    with pytest.raises(pendula.InvalidValueError) as e:
        pendula.solve("double", (0, 1), method="tao-4", dt=0.01)
    assert str(e.value) == (
        "invalid value 0.01 for `dt`: tao-4 is unstable above w dt = 1 (its binding constant "
        "w = 200 1/s): a dt of at most 0.005 s"
    )
    # At the limit it runs.
    assert pendula.solve("double", (0, 0.1), method="tao-4", dt=0.005).success


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: pendula.ensemble("double", [[1, 0, 0, 0]], steps=10, dt=-1e-3), "`dt`"),
        (lambda: pendula.ensemble("double", [[1, 0, 0, 0]], t_end=-1.0), "`t_end`"),
        (lambda: pendula.sweep("double", ["theta1=-1:1:4"], dt=0.0, steps=10), "`dt`"),
        (lambda: pendula.fractal(theta1=(-1, 1, 4), theta2=(-1, 1, 4), dt=-0.01, t_max=1), "`dt`"),
        (lambda: pendula.lyapunov("double", dt=-0.01), "`dt`"),
    ],
)
def test_other_calls_name_their_arguments(call, name):
    with pytest.raises(ValueError) as e:
        call()
    assert name in str(e.value) and "`h`" not in str(e.value), str(e.value)


def test_study_notes_name_dt_and_the_largest_tao_step():
    """A step of a study's ladder that Tao's limit refuses is noted as `dt` (the argument is
    `dts`) with the largest step allowed, not as h and the binding constant."""
    why = (
        "invalid value 0.01 for `dt`: tao-4 is unstable above w dt = 1 (its binding constant "
        "w = 200 1/s): a dt of at most 0.005 s"
    )
    c = pendula.convergence("double", methods=["tao-4"], dts=[0.01, 0.002, 0.001, 0.0005], t_end=2.0)
    assert c.methods[0].failure == f"at dt = 0.01: {why}"
    assert list(c.methods[0].dt) == [0.002, 0.001, 0.0005]
    w = pendula.work_precision("double", methods=["tao-4"], dts=[0.01, 0.001], tols=[1e-6], t_end=2.0)
    assert w.methods[0].failure == f"at dt = 0.01: {why}"
    # Every step refused: the call fails with the same words.
    with pytest.raises(pendula.InvalidValueError) as e:
        pendula.convergence("double", methods=["tao-4"], dts=[0.01], t_end=2.0)
    assert str(e.value) == why
