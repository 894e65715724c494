"""The library's study registry in Python: one function per study, its parameters, checks
and report the library's, and its numbers those `pendula STUDY` writes for the same inputs."""

import csv
import json
import math
import os
import subprocess

import numpy as np
import pytest

import pendula
import pendula.studies
from pendula import InvalidValueError, UnknownNameError


def test_every_registered_study_is_a_function_with_the_library_defaults_in_its_doc():
    for entry in pendula._core.studies():
        # The generated function (a hand-written one, such as divergence's, keeps the
        # package's name; its keyword defaults are checked against the registry below).
        assert hasattr(pendula, entry["name"].replace("-", "_"))
        f = pendula.studies.FUNCTIONS[entry["name"].replace("-", "_")]
        for p in entry["params"]:
            assert f"{p['name']}:" in f.__doc__ and f"[default: {p['default_text']}]" in f.__doc__
        assert entry["name"].replace("-", "_") in pendula.__all__


def test_a_generated_function_never_replaces_a_hand_written_one():
    kept = object()
    namespace = {"energy_budget": kept}
    added = pendula.studies.install(namespace)
    assert namespace["energy_budget"] is kept and "energy_budget" not in added
    assert set(added) == set(pendula.studies.FUNCTIONS) - {"energy_budget"}
    assert pendula.energy_budget is pendula.studies.FUNCTIONS["energy_budget"]


def test_energy_budget_balances_work_and_energy():
    r = pendula.energy_budget("pendulum", t_end=5.0, dt=1e-3)
    t = r.tables["energy-budget"]["t"]
    e, w, b = (r.tables["energy-budget"][k] for k in ("energy", "work", "balance"))
    assert t[-1] == 5.0
    np.testing.assert_allclose(b, e - e[0] - w, atol=1e-12)
    assert r.units["work"] == "J" and r.inputs["method"] == "rk4"
    assert "No damping or drive" in r.summary[1]
    damped = pendula.energy_budget(pendula.System("pendulum", damping=0.3), t_end=5.0)
    assert damped.numbers["work"] < -1.0
    assert damped.numbers["max_balance"] < 1e-9 * abs(damped.numbers["work"])


def test_bad_input_names_the_value_and_what_is_allowed():
    with pytest.raises(InvalidValueError, match=r"invalid value -1 for `dt`: must be finite and > 0"):
        pendula.energy_budget(dt=-1)
    with pytest.raises(UnknownNameError, match=r"did you mean `t_end`"):
        pendula.energy_budget(t_edn=3)
    with pytest.raises(UnknownNameError, match=r"did you mean `energy-budget`"):
        pendula.study("energy-budgte")
    with pytest.raises(InvalidValueError, match=r"`dt`"):
        pendula.energy_budget(dt="fast")
    with pytest.raises(InvalidValueError, match=r"not a bool"):
        pendula.energy_budget(dt=True)


def test_the_cli_reports_the_same_numbers(tmp_path):
    cli = os.environ.get("PENDULA_CLI", "target/debug/pendula")
    out = subprocess.run(
        [cli, "energy-budget", "--t-end", "3", "--summary", "-", "--out-dir", str(tmp_path)],
        capture_output=True, text=True, check=True,
    )
    doc = json.loads(out.stdout)
    r = pendula.energy_budget(t_end=3)
    for key, value in r.numbers.items():
        assert doc[key] == value, key
    assert out.stderr.splitlines()[:2] == list(r.summary)
    assert math.isclose(doc["t_end"], 3.0)


def test_compare_is_the_clis_comparison(tmp_path):
    """`pendula.compare` runs the library's spec that `pendula compare` presents: the same
    steps, counts, errors and growth as its summary.csv, the same opening sentence."""
    cli = os.environ.get("PENDULA_CLI", "target/debug/pendula")
    args = ["pendulum", "--methods", "rk4,verlet", "--evals-per-second", "40", "--t-end", "300"]
    out = subprocess.run(
        [cli, "compare", *args, "--out-dir", str(tmp_path / "c")], capture_output=True, text=True, check=True
    )
    r = pendula.compare("pendulum", methods="rk4,verlet", evals_per_second=40, t_end=300)
    assert out.stdout.splitlines()[0] == r.summary[0]
    with open(tmp_path / "c" / "summary.csv") as f:
        rows = list(csv.DictReader(f))
    table = r.tables["compare"]
    assert [row["method"] for row in rows] == list(table["method"])
    for i, row in enumerate(rows):
        for key in ("dt", "max_rel_energy_error", "max_abs_energy_error", "drift_rate"):
            assert float(row[key]) == table[key][i], key
        for key in ("steps", "rhs_evals", "cost_evals"):
            assert int(row[key]) == table[key][i], key
        assert row["growth"] == table["growth"][i]
    # RK4's energy error drifts; Verlet's, at the same cost, stays bounded.
    assert list(table["growth"]) == ["growing", "bounded"]
    assert abs(table["cost_evals"][1] / table["cost_evals"][0] - 1) < 0.05


def test_a_report_plots_with_matplotlib():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    r = pendula.energy_budget(t_end=1.0)
    ax = r.plot("energy-budget")
    assert [l.get_label() for l in ax.get_lines()] == ["E(t) - E(0)", "W(t)"]
    assert ax.get_xlabel() == "t (s)"
    with pytest.raises(UnknownNameError):
        r.plot("nope")
    # A bar chart: one bar a method, the refused one hollow and hatched, its note beside it.
    s = pendula.stability("pendulum", methods=["rk4", "tao-2"], t_end=2.0)
    ax = s.plot()
    assert [t.get_text() for t in ax.get_yticklabels()] == ["tao-2", "rk4"]
    hatched = [p for p in ax.patches if p.get_hatch()]
    assert len(hatched) == 1 and not hatched[0].get_fill()
    assert any("refused above" in t.get_text() for t in ax.texts)
    assert ax.get_xscale() == "log" and ax.get_xlim() == (1e-5, 2.0)


def test_every_study_signature_takes_its_defaults_from_the_library():
    # The keyword defaults of the hand-written study functions are the library's
    # (pendula::study::defaults), the same values the CLI's help states: none typed twice.
    import inspect

    from pendula import _core

    library = _core.defaults()
    checked = 0
    for name, study in [
        ("fractal", "fractal"),
        ("sweep", "sweep"),
    ]:
        for p in inspect.signature(getattr(pendula, name)).parameters.values():
            if p.name in library[study] and library[study][p.name] is not None and p.name not in ("section", "param") and p.default is not p.empty and p.default is not None:
                assert p.default == library[study][p.name], (name, p.name)
                checked += 1
    # Registry studies with hand-written functions take the registry's defaults.
    for name in ("divergence", "lyapunov", "poincare", "bifurcation", "convergence", "work-precision"):
        registry = {p["name"]: p["default"] for e in _core.studies() if e["name"] == name for p in e["params"]}
        for p in inspect.signature(getattr(pendula, name.replace("-", "_"))).parameters.values():
            # Poincaré's section is one parameter NAME=VALUE in the registry, two here.
            if p.default is not p.empty and p.default is not None and p.name not in ("progress", "section", "value"):
                assert p.default == registry[p.name], (name, p.name)
                checked += 1
    assert checked >= 25, checked
    poincare = pendula.poincare.__kwdefaults__
    registry = {p["name"]: p["default"] for e in _core.studies() if e["name"] == "poincare" for p in e["params"]}
    assert f"{poincare['section']}={poincare['value']:g}" == registry["section"]
    # The fractal's grid and the bifurcation's axis on defaults are the library's texts.
    for text in library["fractal"]["grid"].split(" and "):
        name, *axis = _core.parse_axis("double", [], text)
        assert pendula.fractal.__kwdefaults__[name] == tuple(axis), (name, axis)
    assert pendula.bifurcation(samples=1, transient=0, steps_per_period=4, progress=False).values.size == 800


def test_period_is_a_library_study_with_its_table_and_the_exact_reference():
    r = pendula.period(max_amplitude=170)
    t = r.tables["period"]
    k = list(t["amplitude_deg"]).index(170.0)
    # mpmath: 4 sqrt(l/g) K(sin 85 deg) for l = 1 m, g = 9.81 m/s^2.
    assert abs(t["exact"][k] - 4.893524274105486) < 1e-12
    assert abs(t["simulated"][k] / t["exact"][k] - 1) < 1e-6
    assert r.columns_units["period"]["simulated"] == "s"
    text = str(r)
    assert text.startswith(r.summary[0]) and "amplitude_deg (deg)" in text and "170.0" in text
    # Twice as long a pendulum: every period sqrt(2) times as long.
    longer = pendula.period(pendula.System("pendulum", l=2.0), max_amplitude=170)
    ratio = longer.tables["period"]["exact"][k] / t["exact"][k]
    assert abs(ratio - 2**0.5) < 1e-12
    with pytest.raises(pendula.InvalidValueError, match="pendulum only"):
        pendula.period("double")
    with pytest.raises(pendula.InvalidValueError, match="below 180"):
        pendula.period(max_amplitude=180)
