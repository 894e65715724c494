"""The lab as a person uses it, in headless Chromium: what the issue's "done when" lists."""

import json
import math
import os
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
    # A bounded error's medians move either way by a factor on the chaotic orbit, depending on
    # the instants the frames sampled (fresh-clone CI runs measured 0.46 and 2.17); a linear
    # drift's ratio is 5 (the median of [500, 2000) against that of [0, 500)).
    assert 0.2 < gl_late / gl_early < 3, "Gauss-Legendre's stays bounded"
    assert gl_late < rk_late / 100 < eu_late / 100, "and the order: Gauss-Legendre, RK4, Euler"
    lab.screenshot(path=str(shots / "race.png"))


def test_butterfly_mode_measures_the_growth_of_the_separation(lab, shots, tmp_path):
    # At 10 ms (the first run's step is 1 ms): 30 s of samples stay under the session's 4096,
    # unthinned, as `pendula divergence` samples them.
    lab.evaluate("lab.send({cmd: 'configure', mode: 'butterfly', count: 6, delta: 1e-9, method: 'rk4', dt: 0.01, speed: 4})")
    c = wait_config(lab, "c.mode === 'butterfly' && c.tracks.length === 6")
    lab.wait_for_function("lab.frame.t > 25 && lab.growthRate !== null", timeout=30000)
    rate = lab.evaluate("lab.growthRate")
    assert 0.3 < rate < 5, rate
    lab.screenshot(path=str(shots / "butterfly.png"))
    # The rate shown is the one `pendula divergence` fits to the same run (the same system,
    # start, method, step and offset, over the window the lab reports): one rule, not two.
    lab.wait_for_function("lab.growth && lab.growth.final", timeout=30000)
    g = lab.evaluate("lab.growth")
    assert g["rate"] == rate and g["every"] == 1, g
    lab.wait_for_timeout(300)
    shown = lab.inner_text("#growth-rate")
    assert f"λ ≈ {rate:.3g} 1/s: the slope" in shown and f"t = {g['t_start']:.3g}…{g['t_end']:.3g} s" in shown, shown
    cli = os.environ.get("PENDULA_CLI", "target/debug/pendula")
    run = subprocess.run([cli, "divergence", c["system"], "--method", c["method"], "--dt", str(c["dt"]),
                          "--delta", str(c["delta"]), "--fit-from", repr(g["fit_from"]),
                          "--saturation", repr(g["saturation"]), "--t-end", "30",
                          "--out-dir", str(tmp_path), "--summary", "-"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert [summary["fit_start"], summary["fit_end"]] == [g["t_start"], g["t_end"]], (summary, g)
    # The CLI runs the reference integrator, the lab its fast path: their rounding differs by
    # about 1e-16, which the chaos amplifies as it amplifies δ = 1e-9.
    assert abs(summary["growth_rate"] - rate) <= 1e-6 * abs(rate), (summary["growth_rate"], rate)


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


# ----- issue 29: the lab as a newcomer met it ------------------------------------------------

def boxes_meet(a, b):
    return a["x"] < b["x"] + b["w"] and b["x"] < a["x"] + a["w"] and a["y"] < b["y"] + b["h"] and b["y"] < a["y"] + a["h"]


def inside(p, box):
    return box["x"] <= p["x"] <= box["x"] + box["w"] and box["y"] <= p["y"] <= box["y"] + box["h"]


def assert_legend_clear(page, canvas, labels):
    g = page.evaluate(f"lab.geometry('{canvas}')")
    assert g and g["legend"], f"{canvas} has a legend"
    assert g["legendTexts"] == labels, (canvas, g["legendTexts"])
    assert not boxes_meet(g["legend"], g["area"]), f"{canvas}: the legend {g['legend']} lies on the data's area {g['area']}"
    for p in g.get("newest", []):
        assert inside(p, g["area"]) and not inside(p, g["legend"]), (canvas, p, g)
    return g


def test_legends_never_cover_the_newest_data(lab, shots):
    lab.evaluate("lab.send({cmd: 'configure', mode: 'race', methods: ['euler', 'rk4', 'verlet', 'gauss-legendre-4'],"
                 " dt: 0.01, speed: 20})")
    c = wait_config(lab, "c.mode === 'race' && c.tracks.length === 4")
    labels = [t["label"] for t in c["tracks"]]
    lab.wait_for_function("lab.frame.t > 40 && lab.energyHistory.every(h => h.length > 50)", timeout=30000)
    lab.wait_for_timeout(300)
    g = assert_legend_clear(lab, "energy-plot", labels)
    # The newest points are at the right end of the energy plot: where the legend was.
    assert len(g["newest"]) == 4 and all(p["x"] > g["area"]["x"] + 0.9 * g["area"]["w"] for p in g["newest"]), g
    assert_legend_clear(lab, "sim-canvas", labels)
    lab.evaluate("lab.send({cmd: 'configure', mode: 'butterfly', count: 16, delta: 1e-9, method: 'rk4', speed: 4})")
    c = wait_config(lab, "c.mode === 'butterfly' && c.tracks.length === 16")
    lab.wait_for_function("lab.frame.t > 8 && lab.separation.length > 20", timeout=30000)
    lab.wait_for_timeout(300)
    assert_legend_clear(lab, "sim-canvas", [f"k={k}" for k in range(16)])
    assert_legend_clear(lab, "energy-plot", [f"k={k}" for k in range(16)])
    g = assert_legend_clear(lab, "separation-plot", [f"k={k}" for k in range(1, 16)])
    assert len(g["newest"]) == 15


def test_the_lab_fits_a_1024_by_768_projector(browser, server, shots):
    page = open_lab(browser, server, 1024, 768)
    try:
        fits = """(() => {
            const p = document.querySelector('.energy-panel').getBoundingClientRect();
            const e = document.querySelector('.energy-panel');
            return {scroll: document.documentElement.scrollWidth, body: document.body.scrollWidth,
                    right: p.right, inner: e.scrollWidth - e.clientWidth};
        })()"""
        for mode in ["single", "race", "butterfly"]:
            page.evaluate(f"lab.send({{cmd: 'configure', mode: '{mode}'}})")
            wait_config(page, f"c.mode === '{mode}'")
            page.wait_for_timeout(400)
            f = page.evaluate(fits)
            print(mode, f)
            assert f["scroll"] <= 1024 and f["body"] <= 1024, (mode, f)
            assert f["right"] <= 1024 and f["inner"] <= 0, f"{mode}: the Energy panel is cut: {f}"
            if mode == "race":
                page.screenshot(path=str(shots / "projector-1024x768.png"))
        for tab in ["graphs", "fractal", "export", "sim"]:
            page.click(f"#tab-{tab}")
            page.wait_for_timeout(200)
            width = page.evaluate("document.documentElement.scrollWidth")
            assert width <= 1024, (tab, width)
        assert page.js_errors == [], page.js_errors
    finally:
        page.close()


def test_the_integrator_menu_is_disabled_where_the_server_ignores_it(lab):
    disabled = """(() => ({method: document.getElementById('method').disabled,
        hint: !document.getElementById('method-hint').hidden,
        race: [...document.querySelectorAll('#race-methods input')].every(i => i.disabled),
        count: document.getElementById('count').disabled, delta: document.getElementById('delta').disabled}))()"""
    assert lab.evaluate(disabled) == {"method": False, "hint": False, "race": True, "count": True, "delta": True}
    lab.select_option("#mode", "race")
    c = wait_config(lab, "c.mode === 'race'")
    lab.wait_for_timeout(100)
    assert lab.evaluate(disabled) == {"method": True, "hint": True, "race": False, "count": True, "delta": True}
    # A race's tracks are the ticked methods, whatever the menu says.
    assert [t["method"] for t in c["tracks"]] == c["methods"]
    lab.select_option("#mode", "butterfly")
    c = wait_config(lab, "c.mode === 'butterfly'")
    lab.wait_for_timeout(100)
    assert lab.evaluate(disabled) == {"method": False, "hint": False, "race": True, "count": False, "delta": False}
    # A butterfly runs every pendulum with the menu's method: the menu stays on, and acts.
    lab.select_option("#method", "verlet")
    c = wait_config(lab, "c.method === 'verlet'")
    assert {t["method"] for t in c["tracks"]} == {"verlet"}


def test_a_malformed_share_link_gets_a_notice(browser, server):
    import json
    import urllib.parse
    page = open_lab(browser, server + "#" + urllib.parse.quote('{"method": "verlet", oops'))
    try:
        page.wait_for_function("lab.notices.length > 0")
        notice = page.evaluate("lab.notices[0]")
        assert "could not be read" in notice and "not JSON" in notice and "defaults" in notice, notice
        assert page.is_visible("#error") and "could not be read" in page.inner_text("#error")
        assert config(page)["method"] == "rk4", "the defaults"
    finally:
        page.close()
    share = {"method": "verlet", "colour": "red"}
    page = open_lab(browser, server + "#" + urllib.parse.quote(json.dumps(share)))
    try:
        wait_config(page, "c.method === 'verlet'")
        notice = page.evaluate("lab.notices[0]")
        assert '"colour"' in notice and "ignored" in notice and "others were applied" in notice, notice
    finally:
        page.close()


def test_a_wrong_token_stops_retrying_and_says_what_to_do(browser, server):
    page = browser.new_page()
    sockets = []
    page.on("websocket", lambda ws: sockets.append(ws.url))
    try:
        bad = server.replace("token=", "token=00")
        page.goto(bad)
        page.wait_for_function("lab.gaveUp", timeout=10000)
        # The old page retried after 1 s, 3 s, 5 s…: over 7 s it would have tried three times more.
        page.wait_for_timeout(7000)
        assert len(sockets) == 1 and page.evaluate("lab.socketAttempts") == 1, sockets
        assert "wrong access token" in page.inner_text("#status")
        message = page.inner_text("#error")
        assert "pendula serve" in message and "token" in message and "does not retry" in message, message
    finally:
        page.close()


def test_the_error_banner_overlays_the_page_without_moving_it(lab):
    before = lab.evaluate("[document.querySelector('main').getBoundingClientRect().top,"
                          " document.getElementById('method').getBoundingClientRect().top]")
    assert not lab.is_visible("#error")
    lab.select_option("#method", "yoshida-4")
    lab.wait_for_function("lab.errors.length > 0")
    assert lab.is_visible("#error")
    after = lab.evaluate("[document.querySelector('main').getBoundingClientRect().top,"
                         " document.getElementById('method').getBoundingClientRect().top]")
    assert after == before, (before, after)
    assert lab.evaluate("getComputedStyle(document.getElementById('error')).position") in ("fixed", "absolute")
    lab.click("#error-close")
    assert not lab.is_visible("#error")


def png_size(data):
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def test_the_png_export_has_a_title_axis_labels_and_legends(lab, shots):
    import base64
    lab.evaluate("lab.send({cmd: 'configure', mode: 'race', methods: ['euler', 'rk4', 'verlet'], dt: 0.01, speed: 10})")
    c = wait_config(lab, "c.mode === 'race' && c.tracks.length === 3")
    labels = [t["label"] for t in c["tracks"]]
    lab.wait_for_function("lab.frame.t > 10", timeout=20000)
    lab.click("#tab-export")
    with lab.expect_download() as d:
        lab.click("#export-png")
    data = open(d.value.path(), "rb").read()
    (shots / "export-race.png").write_bytes(data)
    e = lab.evaluate("lab.lastExport")
    assert png_size(data) == (e["width"], e["height"]), (png_size(data), e)
    panels = {p["canvas"]: p for p in e["panels"]}
    assert set(panels) == {"sim-canvas", "energy-plot"}, panels
    assert panels["sim-canvas"]["legend"] == labels
    energy = panels["energy-plot"]
    assert energy["xLabel"] == "t (s)" and energy["yLabel"] == "|E − E₀| / scale" and energy["legend"] == labels, energy
    assert "race of euler, rk4, verlet" in e["title"] and "t = " in e["title"], e["title"]
    # The title band holds text (dark pixels), which the bare canvases never had.
    dark = lab.evaluate("""async ([b64, rows]) => {
        const img = new Image();
        img.src = 'data:image/png;base64,' + b64;
        await img.decode();
        const c = document.createElement('canvas');
        c.width = img.width; c.height = img.height;
        const x = c.getContext('2d');
        x.drawImage(img, 0, 0);
        const d = x.getImageData(0, 0, img.width, rows).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) if (d[i] < 90 && d[i + 1] < 90 && d[i + 2] < 90) n++;
        return n;
    }""", [base64.b64encode(data).decode(), e["titleHeight"]])
    assert dark > 200, dark
    # A single run's picture gets its legend too (the method), for the PNG only.
    lab.evaluate("lab.send({cmd: 'configure', mode: 'single', method: 'rk4'})")
    wait_config(lab, "c.mode === 'single'")
    lab.wait_for_function("lab.frame.tracks.length === 1 && lab.frame.t > 1")
    e = lab.evaluate("(() => { lab.exportFigure(); return lab.lastExport; })()")
    assert {p["canvas"]: p["legend"] for p in e["panels"]} == {"sim-canvas": ["rk4"], "energy-plot": ["rk4"]}
    lab.click("#tab-sim")
    lab.wait_for_timeout(200)
    assert lab.evaluate("lab.geometry('sim-canvas').legend") is None, "on the page, no legend for one pendulum"


def test_race_trails_stay_readable_at_high_speed(lab, shots):
    lab.evaluate("lab.send({cmd: 'configure', mode: 'race', methods: ['euler', 'rk4', 'verlet', 'gauss-legendre-4'],"
                 " dt: 0.01, speed: 50})")
    wait_config(lab, "c.mode === 'race' && c.tracks.length === 4")
    lab.wait_for_function("lab.frame.t > 40", timeout=30000)
    lab.wait_for_timeout(500)
    trail = lab.evaluate("lab.trail")
    print("speed 50:", trail)
    # Frames come 50/60 s apart: no chord joins them, and the trail spans at most 3 s.
    assert trail["gap"] > 0.5 and trail["segments"] == 0, trail
    assert all(s <= 3 for s in trail["spans"]) and all(n <= 5 for n in trail["points"]), trail
    assert "trail as dots" in lab.inner_text("#sim-info")
    lab.screenshot(path=str(shots / "race-speed-50.png"))
    lab.evaluate("lab.send({cmd: 'speed', value: 1})")
    lab.wait_for_timeout(3500)
    trail = lab.evaluate("lab.trail")
    print("speed 1:", trail)
    assert trail["gap"] < 0.05 and trail["segments"] > 4 * 30, trail
    assert all(2 < s <= 3 for s in trail["spans"]), trail
    assert "trail as dots" not in lab.inner_text("#sim-info")
