"""The lab as a person uses it, in headless Chromium: what the issue's "done when" lists."""

import math
import subprocess

from conftest import open_lab


def config(page):
    return page.evaluate("lab.config")


def wait_config(page, condition, timeout=10000):
    """Waits until the server's last config satisfies `condition` (a JS expression on `c`)."""
    page.wait_for_function(f"(() => {{ const c = lab.config; return {condition}; }})()", timeout=timeout)
    return config(page)


def test_the_page_loads_and_frames_move_the_canvas(lab, shots):
    assert lab.title()
    n0 = lab.evaluate("lab.framesReceived")
    before = lab.evaluate("document.getElementById('sim-canvas').toDataURL()")
    lab.wait_for_timeout(500)
    after = lab.evaluate("document.getElementById('sim-canvas').toDataURL()")
    assert lab.evaluate("lab.framesReceived") > n0 + 5, "frames arrive"
    assert before != after, "the canvas changes"
    t = lab.evaluate("lab.frame.t")
    assert t > 0.3
    # The energy panel shows the three energies with units.
    lab.wait_for_timeout(1500)
    lab.screenshot(path=str(shots / "simulation.png"))


def test_dragging_a_bob_sets_the_state_the_server_reports(lab):
    lab.evaluate("lab.send({cmd: 'pause'})")
    lab.wait_for_function("lab.frame.paused")
    lab.wait_for_timeout(100)
    held = lab.evaluate("lab.frame.tracks[0].state[0]")
    bobs = lab.evaluate("lab.bobClientPositions()")
    assert len(bobs) == 2
    (x1, y1), (x2, y2) = (bobs[0]["x"], bobs[0]["y"]), (bobs[1]["x"], bobs[1]["y"])
    rod = math.hypot(x2 - x1, y2 - y1)
    # Drag the second bob to straight out to the right of the first: θ₂ = +90°.
    lab.mouse.move(x2, y2)
    lab.mouse.down()
    lab.mouse.move((x1 + x2) / 2 + rod / 2, (y1 + y2) / 2, steps=5)
    lab.mouse.move(x1 + rod, y1, steps=5)
    lab.mouse.up()
    c = wait_config(lab, "Math.abs(c.state[1].value - Math.PI / 2) < 0.05")
    theta1 = c["state"][0]["value"]
    assert abs(theta1 - held) < 1e-9, "the first rod stays where it was"
    assert [s["value"] for s in c["state"][2:]] == [0.0, 0.0], "velocities zeroed"
    # The frames report the new start.
    lab.wait_for_function("lab.frame && lab.frame.t === 0 && Math.abs(lab.frame.tracks[0].state[1] - Math.PI/2) < 0.05")


def test_verlet_runs_implicitly_and_yoshida_is_refused_with_the_librarys_reason(lab):
    lab.select_option("#method", "verlet")
    wait_config(lab, "c.method === 'verlet'")
    lab.wait_for_function("lab.frame.t > 0.5")
    lab.select_option("#method", "yoshida-4")
    lab.wait_for_function("lab.errors.length > 0")
    message = lab.evaluate("lab.errors[lab.errors.length - 1]")
    assert "yoshida-4" in message and "separable" in message, message
    assert lab.is_visible("#error") and "separable" in lab.inner_text("#error")
    assert config(lab)["method"] == "verlet", "the refused method never runs"


def test_the_race_shows_rk4_drifting_and_gauss_legendre_bounded_over_1000_s(lab, shots):
    lab.evaluate("lab.send({cmd: 'configure', mode: 'race', methods: ['euler', 'rk4', 'verlet', 'gauss-legendre-4'],"
                 " dt: 0.01, speed: 250})")
    c = wait_config(lab, "c.mode === 'race' && c.tracks.length === 4")
    labels = [t["label"] for t in c["tracks"]]
    assert labels == ["euler", "rk4", "verlet", "gauss-legendre-4"]
    lab.wait_for_function("lab.frame.t >= 1000 && lab.frame.tracks.length === 4", timeout=60000)
    history = lab.evaluate("lab.energyHistory")

    def median(k, lo, hi):
        # Medians over each half: a linear drift triples them, a bounded error leaves them
        # alike, whichever instants the frames sampled on the chaotic orbit.
        values = sorted(e for t, e in history[k] if lo <= t < hi)
        return values[len(values) // 2]

    rk_early, rk_late = median(1, 0, 500), median(1, 500, 2000)
    gl_early, gl_late = median(3, 0, 500), median(3, 500, 2000)
    eu_late = median(0, 500, 2000)
    print(f"medians: rk4 {rk_early:.2e} -> {rk_late:.2e}; gauss-legendre-4 {gl_early:.2e} -> {gl_late:.2e}")
    assert rk_late > 2.5 * rk_early, "RK4's energy error grows"
    assert 0.5 < gl_late / gl_early < 2, "Gauss-Legendre's stays bounded"
    assert gl_late < rk_late / 100 < eu_late / 100, "and the order: Gauss-Legendre, RK4, Euler"
    lab.screenshot(path=str(shots / "race.png"))


def test_butterfly_mode_measures_the_growth_of_the_separation(lab, shots):
    lab.evaluate("lab.send({cmd: 'configure', mode: 'butterfly', count: 6, delta: 1e-9, method: 'rk4', speed: 4})")
    wait_config(lab, "c.mode === 'butterfly' && c.tracks.length === 6")
    lab.wait_for_function("lab.frame.t > 25 && lab.growthRate !== null", timeout=30000)
    rate = lab.evaluate("lab.growthRate")
    assert 0.3 < rate < 5, rate
    lab.screenshot(path=str(shots / "butterfly.png"))


def test_graphs_show_the_time_series_phase_portrait_and_a_live_poincare_section(lab, shots):
    lab.evaluate("lab.send({cmd: 'configure', mode: 'single', poincare: true, speed: 20,"
                 " state: {theta1: 0.9, theta2: 0.3, omega1: 0, omega2: 0}})")
    wait_config(lab, "c.poincare === true")
    lab.click("#tab-graphs")
    lab.wait_for_function("lab.frame.t > 60", timeout=30000)
    points = lab.evaluate("lab.poincarePoints.length")
    assert points > 10, points
    lab.screenshot(path=str(shots / "graphs.png"))


def test_clicking_a_fractal_pixel_starts_that_pendulum(lab, shots):
    lab.click("#tab-fractal")
    lab.fill("#fractal-size", "128")
    lab.fill("#fractal-tmax", "30")
    lab.click("#fractal-start")
    lab.wait_for_function("lab.fractal && lab.fractal.final", timeout=60000)
    f = lab.evaluate("({n1: lab.fractal.n1, n2: lab.fractal.n2, t1: lab.fractal.theta1, t2: lab.fractal.theta2,"
                     " hasFlags: lab.fractal.hasFlags, frames: lab.fractalFrames})")
    assert f["n1"] == f["n2"] == 128 and f["hasFlags"] and f["frames"] >= 3, f
    lab.check("#fractal-overlay")
    lab.wait_for_timeout(300)
    lab.screenshot(path=str(shots / "fractal.png"))
    # A pixel that flips early (before chaos could amplify the rounding differences between
    # the map's lanes and the single run) and whose flip time converged at dt/2.
    i, j, t_map = lab.evaluate("""(() => {
        const f = lab.fractal;
        for (let j = 0; j < f.n2; j++) for (let i = 0; i < f.n1; i++) {
            const k = j * f.n1 + i, t = f.times[k];
            if (i > 80 && t > 2 && t < 6 && f.flags[k] === 1) return [i, j, t];
        }
        return null;
    })()""")
    p = lab.evaluate(f"lab.fractalPixelClient({i}, {j})")
    lab.mouse.click(p["x"], p["y"])
    theta1 = f["t1"][0] + (i + 0.5) * (f["t1"][1] - f["t1"][0]) / f["n1"]
    theta2 = f["t2"][0] + (j + 0.5) * (f["t2"][1] - f["t2"][0]) / f["n2"]
    c = wait_config(lab, f"Math.abs(c.state[0].value - {theta1}) < 1e-12 && Math.abs(c.state[1].value - {theta2}) < 1e-12")
    assert [s["value"] for s in c["state"][2:]] == [0.0, 0.0]
    assert c["mode"] == "single" and c["method"] == "rk4" and c["dt"] == 0.01, "the map's method and step"
    assert lab.is_visible("#view-sim")
    # The pendulum, run on: its first flip is the one the map shows for that pixel.
    lab.evaluate("lab.send({cmd: 'speed', value: 20})")
    lab.wait_for_function("Number.isFinite(lab.frame.tracks[0].flipTime)", timeout=20000)
    t_run = lab.evaluate("lab.frame.tracks[0].flipTime")
    print(f"pixel ({i}, {j}): the map's flip at {t_map:.9f} s, the run's at {t_run:.9f} s")
    assert abs(t_run - t_map) < 1e-6
    assert "the map: first flip at" in lab.inner_text("#sim-info")
    lab.screenshot(path=str(shots / "fractal-pixel.png"))


def test_the_share_url_reopens_the_same_view(browser, server, lab):
    lab.evaluate("lab.send({cmd: 'configure', method: 'gauss-legendre-4', dt: 0.005, params: {m2: 2.5, l1: 0.8},"
                 " state: {theta1: 1.234, theta2: -0.5, omega1: 0.25}, speed: 0.5})")
    c = wait_config(lab, "c.method === 'gauss-legendre-4' && c.params[1].value === 2.5")
    url = lab.evaluate("lab.shareUrl()")
    assert "#" in url and "token=" in url
    other = open_lab(browser, url)
    try:
        d = wait_config(other, "c.method === 'gauss-legendre-4'")
        assert d["share"] == c["share"]
        assert d["state"][0]["value"] == 1.234 and d["params"][1]["value"] == 2.5
    finally:
        other.close()


def test_exports_give_the_command_that_reproduces_the_run(lab, tmp_path, shots):
    import os
    lab.evaluate("lab.send({cmd: 'configure', mode: 'single', method: 'rk4', dt: 0.01, state: {theta1: 1.0, theta2: 0.5}})")
    c = wait_config(lab, "c.state[0].value === 1.0 && c.mode === 'single'")
    lab.click("#tab-export")
    lab.click("#export-command")
    shown = lab.inner_text("pre")
    assert c["command"] in shown
    lab.screenshot(path=str(shots / "export.png"))
    # The command runs as printed (the CLI's own flags), and the TOML is a valid scenario.
    cli = os.environ.get("PENDULA_CLI", "target/debug/pendula")
    args = c["command"].split()[1:]
    run = subprocess.run([cli, *args, "--out", str(tmp_path / "run.csv")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    (tmp_path / "s.toml").write_text(c["toml"])
    run = subprocess.run([cli, "simulate", "--scenario", str(tmp_path / "s.toml"), "--out", str(tmp_path / "s.csv")],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "run.csv").read_text() == (tmp_path / "s.csv").read_text()
    with lab.expect_download() as d:
        lab.click("#export-csv")
    text = pathlib_read(d.value.path())
    header = text.splitlines()[0]
    assert header.startswith("t") and "theta1" in header, header


def pathlib_read(path):
    with open(path) as f:
        return f.read()


def test_a_websocket_from_another_origin_is_refused(browser, server):
    page = browser.new_page()
    try:
        page.goto("about:blank")
        ws_url = server.replace("http://", "ws://").replace("/?token=", "/ws?token=")
        # about:blank has an opaque origin ("null"): not this server's page.
        outcome = page.evaluate("""url => new Promise(done => {
            const ws = new WebSocket(url);
            ws.onopen = () => done('open');
            ws.onerror = () => done('refused');
        })""", ws_url)
        assert outcome == "refused"
    finally:
        page.close()


def test_python_view_opens_a_system_in_the_lab(browser):
    import pendula
    import pytest

    v = pendula.view(pendula.System("double", theta1=1.1, m2=1.5), method="verlet")
    assert "<iframe" in v._repr_html_() and v.url.startswith("http://127.0.0.1:")
    page = open_lab(browser, v.url)
    try:
        c = wait_config(page, "c.method === 'verlet'")
        assert c["state"][0]["value"] == 1.1 and c["params"][1]["value"] == 1.5
    finally:
        page.close()
    assert pendula.view().url.split("#")[0] == v.url.split("#")[0], "one lab per process"
    with pytest.raises(ValueError, match="cannot view int"):
        pendula.view(3)


def test_every_catalogued_system_runs_and_is_drawn(lab, shots):
    bodies = {"oscillator": 1, "pendulum": 1, "double": 2, "chain": 3, "driven-pendulum": 1}
    systems = [s["name"] for s in lab.evaluate("lab.hello.systems")]
    assert sorted(systems) == sorted(bodies)
    for name in systems:
        lab.select_option("#system", name)
        c = wait_config(lab, f"c.system === '{name}'")
        lab.wait_for_function("lab.frame && lab.frame.t > 0.3 && lab.frame.tracks[0].state.length === "
                              f"{len(c['state'])}", timeout=10000)
        assert len(lab.evaluate("lab.bobClientPositions()")) == bodies[name], name
        # Dimensionless systems show no units; the others their SI units.
        assert (c["time_unit"] == "") == (name == "driven-pendulum"), name
        lab.screenshot(path=str(shots / f"system-{name}.png"))


def test_a_damped_system_shows_an_energy_change_not_an_error(lab):
    lab.evaluate("lab.send({cmd: 'configure', system: 'pendulum', params: {damping: 0.3}})")
    wait_config(lab, "c.system === 'pendulum' && c.conserves_energy === false")
    assert "not conserved" in lab.inner_text("#energy-err-label")
    lab.evaluate("lab.send({cmd: 'configure', params: {damping: 0}})")
    wait_config(lab, "c.conserves_energy === true")
    assert "not conserved" not in lab.inner_text("#energy-err-label")


def test_the_graph_menus_follow_a_change_of_system(lab):
    lab.click("#tab-graphs")
    lab.select_option("#phase-x", "1")
    lab.select_option("#phase-y", "3")
    lab.click("#tab-sim")
    lab.select_option("#system", "pendulum")
    wait_config(lab, "c.system === 'pendulum'")
    assert lab.evaluate("[document.getElementById('phase-x').value, document.getElementById('phase-y').value]") \
        == ["0", "1"], "theta against omega, not omega against omega"


def test_a_refused_speed_puts_the_field_back(lab):
    lab.fill("#speed", "1e9")
    lab.dispatch_event("#speed", "change")
    lab.wait_for_function("lab.errors.some(e => e.includes('speed = 1000000000'))")
    assert lab.input_value("#speed") == "1"
    assert lab.evaluate("lab.config.speed") == 1


def test_step_is_offered_only_while_paused_and_the_oscillator_has_no_angles(lab):
    # The controls follow the frames, drawn at the display's next refresh.
    lab.wait_for_function("lab.frame && !lab.frame.paused && document.getElementById('step').disabled")
    lab.click("#pause")
    lab.wait_for_function("lab.frame.paused && !document.getElementById('step').disabled")
    lab.select_option("#system", "oscillator")
    wait_config(lab, "c.system === 'oscillator'")
    hint = lab.inner_text("#state-hint")
    assert "block" in hint and "degrees" not in hint
