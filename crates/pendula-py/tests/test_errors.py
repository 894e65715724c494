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
    with pytest.raises(pendula.InvalidValueError, match=r"t_span \(1, 0\)"):
        pendula.solve("double", (1, 0))
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
