"""The Studies view: every study of the library's registry, a form from its parameters, and
its report — the same numbers and sentences as Python's and the CLI's."""

import pendula

from conftest import open_lab


def test_a_study_runs_from_its_form_with_the_librarys_report(browser, server, shots):
    page = open_lab(browser, server)
    page.click("#tab-studies")
    names = page.eval_on_selector_all("#study-name option", "os => os.map(o => o.value)")
    assert names == [s["name"] for s in pendula._core.studies()]
    page.select_option("#study-name", "energy-budget")
    # The form shows each parameter's default, the library's, as its placeholder.
    assert page.get_attribute("[data-param=t_end]", "placeholder") == "20 s"
    assert page.get_attribute("[data-param=dt]", "placeholder") == "0.001 s"
    page.fill("[data-param=t_end]", "2")
    page.click("#study-run")
    page.wait_for_function("lab.study && lab.study.study === 'energy-budget'", timeout=15000)
    shown = page.eval_on_selector_all(".study-summary", "ps => ps.map(p => p.textContent)")
    report = pendula.energy_budget(t_end=2)
    assert shown == list(report.summary)
    numbers = page.evaluate("Object.fromEntries(lab.study.numbers.map(n => [n.key, n.value]))")
    assert numbers == dict(report.numbers)
    page.wait_for_function("[...document.querySelectorAll('img.study-plot')].every(i => i.complete && i.naturalWidth > 0)")
    assert page.eval_on_selector_all("img.study-plot", "is => is.length") == len(report.plots)
    page.screenshot(path=str(shots / "studies.png"), full_page=True)

    page.fill("[data-param=dt]", "-1")
    page.click("#study-run")
    page.wait_for_function("document.getElementById('study-status').textContent.startsWith('Refused')", timeout=15000)
    assert any("invalid value -1 for `dt`" in e for e in page.evaluate("lab.errors")), page.evaluate("lab.errors")
    assert not page.js_errors, page.js_errors
    page.close()


def test_a_short_table_is_shown_and_a_fixed_system_has_no_field(browser, server, shots):
    page = open_lab(browser, server)
    page.click("#tab-studies")
    page.select_option("#study-name", "period")
    # period runs the simple pendulum only: no system to choose.
    assert page.query_selector("[data-param=system]") is None
    page.fill("[data-param=max_amplitude]", "30")
    page.click("#study-run")
    page.wait_for_function("lab.study && lab.study.study === 'period'", timeout=15000)
    report = pendula.period(max_amplitude=30)
    rows = page.eval_on_selector_all(
        "table.study-table tr", "rs => rs.map(r => [...r.children].map(c => c.textContent))"
    )
    assert rows[0] == ["amplitude_deg (deg)", "simulated (s)", "exact (s)", "small_angle (s)"]
    assert [float(r[0]) for r in rows[1:]] == list(report.tables["period"]["amplitude_deg"])
    exact = [float(r[2]) for r in rows[1:]]
    assert all(abs(a / b - 1) < 1e-5 for a, b in zip(exact, report.tables["period"]["exact"]))
    page.screenshot(path=str(shots / "studies-period.png"), full_page=True)
    assert not page.js_errors, page.js_errors
    page.close()


def test_a_switch_is_a_checkbox_and_a_preset_a_list(browser, server, shots):
    page = open_lab(browser, server)
    page.click("#tab-studies")
    page.select_option("#study-name", "lyapunov")
    assert page.get_attribute("[data-param=spectrum]", "type") == "checkbox"
    presets = page.eval_on_selector_all("[data-param=preset] option", "os => os.map(o => o.value)")
    assert "baker-gollub-chaotic-1.5" in presets and presets[0] == ""
    page.select_option("[data-param=preset]", "baker-gollub-chaotic-1.5")
    page.check("[data-param=spectrum]")
    for name, value in (("dt", "0.01"), ("t_end", "100"), ("transient", "0")):
        page.fill(f"[data-param={name}]", value)
    page.click("#study-run")
    page.wait_for_function("lab.study && lab.study.study === 'lyapunov'", timeout=15000)
    # The preset picked the system; the spectrum of the damped driven pendulum (q = 2) has
    # two exponents summing to -1/q, as the library's study finds them from Python.
    report = pendula.study("lyapunov", preset="baker-gollub-chaotic-1.5", spectrum=True, dt=0.01, t_end=100, transient=0)
    assert page.evaluate("lab.study.inputs") == dict(report.inputs)
    rows = page.eval_on_selector_all(
        "table.study-table tr", "rs => rs.map(r => [...r.children].map(c => c.textContent))"
    )
    assert [r[0] for r in rows[1:]] == ["lambda1", "lambda2"]
    assert abs(sum(float(r[1]) for r in rows[1:]) + 0.5) < 1e-6
    page.screenshot(path=str(shots / "studies-lyapunov.png"), full_page=True)
    assert not page.js_errors, page.js_errors
    page.close()


def test_a_list_of_steps_is_a_text_field_read_as_numbers(browser, server, shots):
    page = open_lab(browser, server)
    page.click("#tab-studies")
    page.select_option("#study-name", "convergence")
    # The steps are a list: typed comma-separated, read by the library as numbers.
    assert page.get_attribute("[data-param=dts]", "data-kind") == "reals"
    page.fill("[data-param=methods]", "rk4,verlet")
    page.fill("[data-param=dts]", "0.1, 0.05, 0.025, 0.0125")
    page.fill("[data-param=t_end]", "2")
    page.click("#study-run")
    page.wait_for_function("lab.study && lab.study.study === 'convergence'", timeout=15000)
    report = pendula.convergence(methods="rk4,verlet", dts=[0.1, 0.05, 0.025, 0.0125], t_end=2)
    assert page.evaluate("lab.study.inputs.dts") == [0.1, 0.05, 0.025, 0.0125]
    assert page.evaluate("lab.study.texts.reference") == report.reference == "exact solution"
    orders = page.evaluate(
        "(() => { const t = lab.study.tables.find(t => t.name === 'orders');"
        " const col = n => t.columns.find(c => c.name === n).values;"
        " return Object.fromEntries(col('method').map((m, i) => [m, col('fitted_order')[i]])); })()"
    )
    assert orders == report.orders
    assert abs(orders["rk4"] - 4) < 0.1 and abs(orders["verlet"] - 2) < 0.1
    page.screenshot(path=str(shots / "studies-convergence.png"), full_page=True)
    # A step that is not a number is refused by name.
    page.fill("[data-param=dts]", "0.1, fast")
    page.click("#study-run")
    page.wait_for_function("document.getElementById('study-status').textContent.startsWith('Refused')", timeout=15000)
    assert any("`dts`" in e and "numbers" in e for e in page.evaluate("lab.errors")), page.evaluate("lab.errors")
    assert not page.js_errors, page.js_errors
    page.close()


def test_compare_runs_in_the_lab_as_in_python(browser, server, shots):
    page = open_lab(browser, server)
    page.click("#tab-studies")
    page.select_option("#study-name", "compare")
    page.select_option("[data-param=system]", "pendulum")
    for name, value in (("methods", "rk4,verlet"), ("evals_per_second", "40"), ("t_end", "300")):
        page.fill(f"[data-param={name}]", value)
    page.fill("#study-set", "theta=2.6")
    page.click("#study-run")
    page.wait_for_function("lab.study && lab.study.study === 'compare'", timeout=15000)
    report = pendula.compare(pendula.System("pendulum", theta=2.6), methods="rk4,verlet", evals_per_second=40, t_end=300)
    shown = page.eval_on_selector_all(".study-summary", "ps => ps.map(p => p.textContent)")
    assert shown == list(report.summary)
    growth = page.evaluate("lab.study.tables[0].columns.find(c => c.name === 'growth').values")
    assert growth == list(report.tables["compare"]["growth"]) == ["growing", "bounded"]
    page.wait_for_function("[...document.querySelectorAll('img.study-plot')].every(i => i.complete && i.naturalWidth > 0)")
    page.screenshot(path=str(shots / "studies-compare.png"), full_page=True)
    assert not page.js_errors, page.js_errors
    page.close()
