"""pendula.solve: the CLI's numbers, scipy's shape and accuracy, exact solutions."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pendula
from conftest import summary


@pytest.mark.parametrize("method", ["auto", "rk4", "dop853"])
def test_solve_prints_the_state_the_cli_computes(cli, tmp_path, method):
    sol = pendula.solve("double", (0, 10), method=method)
    used = sol.method
    cli(["simulate", "double", "--method", used, "--summary", "s.json", "--out", "run.csv"], tmp_path)
    final = summary(tmp_path / "s.json")["final"]
    assert final["t"] == sol.t[-1] == 10.0
    for k, name in enumerate(sol.names):
        assert sol.y[k, -1] == final[name], (name, sol.y[k, -1], final[name])
    if method == "auto":
        assert used == "tao-4" and "Hamiltonian" in sol.method_note


def test_dop853_agrees_with_scipy():
    system = pendula.System("double")
    sol = pendula.solve(system, (0, 10), method="dop853", rtol=1e-12, atol=1e-12)
    assert sol.adaptive and sol.success and sol.status == 0
    ref = solve_ivp(lambda t, y: system.rhs(t, y), (0, 10), system.y0, method="DOP853", rtol=1e-13, atol=1e-13)
    assert np.max(np.abs(sol.y[:, -1] - ref.y[:, -1])) < 1e-8
    # Fewer evaluations than scipy at a tighter tolerance would be suspicious; far fewer
    # is what an equal method at a looser tolerance gives.
    assert 0 < sol.nfev < ref.nfev


def test_solution_shape_and_views():
    sol = pendula.solve("pendulum", (0, 2), method="rk4", dt=0.01)
    assert sol.t.shape == (201,) and sol.y.shape == (2, 201) and sol.states.shape == (201, 2)
    assert np.shares_memory(sol.y, sol.states)
    assert sol.names == ["theta", "omega"]
    assert sol.steps == 200 and sol.nfev == 800 and sol.rejected == 0
    assert math.isclose(sol.t[-1], 2.0)


def test_exact_oscillator_and_fourth_order():
    # x(t) = cos(√(k/m) t) from x = 1, v = 0; yoshida-4's error falls 16× per halving.
    errors = []
    for dt in (0.02, 0.01):
        sol = pendula.solve("oscillator", (0, 10), method="yoshida-4", dt=dt)
        errors.append(abs(sol.y[0, -1] - math.cos(10.0)))
    order = math.log2(errors[0] / errors[1])
    assert 3.8 < order < 4.2, (errors, order)


def test_energy_error_against_the_scale():
    sol = pendula.solve("double", (0, 20), method="tao-4", dt=1e-3)
    e = sol.energy
    assert e.shape == sol.t.shape
    scale = sol.energy_scale
    # The double pendulum's scale: the potential energy from hanging to both rods
    # horizontal, (m1 + m2) g l1 + m2 g l2 = 29.43 J with the defaults, or the initial
    # energy above the minimum −29.43 J (V = 0 at the pivot) when that is larger.
    assert math.isclose(scale, max(29.43, e[0] + 29.43), rel_tol=1e-12)
    assert scale > 29.43  # the default start, θ = (120°, −10°) at rest, is above it
    assert np.allclose(sol.energy_error, (e - e[0]) / scale)
    drift = sol.drift()
    assert drift["envelope"] < 1e-4 and abs(drift["rate"]) < 1e-6


def test_system_equations_vectorised():
    p = pendula.System("pendulum", l=2.0)
    y = np.array([[0.3, 1.0, -2.0], [0.0, 0.5, 1.5]])
    d = p.rhs(0.0, y)
    assert np.allclose(d[0], y[1]) and np.allclose(d[1], -9.81 / 2.0 * np.sin(y[0]), rtol=1e-15)
    # V = −m g l cos θ (zero at the pivot's height), m = 1 kg.
    assert np.allclose(p.energy(y), 0.5 * 4.0 * y[1] ** 2 - 9.81 * 2.0 * np.cos(y[0]), rtol=1e-14)
    z = p.to_momenta(y)
    assert np.allclose(z[1], 4.0 * y[1]) and np.allclose(p.from_momenta(z), y)
    assert p.separable and not pendula.System("double").separable


def test_catalogue():
    cat = pendula.catalogue()
    names = [s.name for s in cat.systems]
    assert names[:3] == ["oscillator", "pendulum", "double"]
    double = cat.system("double")
    assert [q.name for q in double.state] == ["theta1", "theta2", "omega1", "omega2"]
    assert double.conservative and not double.separable
    m1 = double.parameters[0]
    assert (m1.name, m1.unit, m1.default) == ("m1", "kg", 1.0)
    methods = {m.name: m for m in cat.methods}
    assert methods["verlet"].symplectic and methods["verlet"].order == 2
    assert methods["dop853"].adaptive and not methods["rk4"].adaptive
