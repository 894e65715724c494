//! The WebSocket protocol against a real server on a loopback port: refusals leave the
//! session alive, the token and the origin are checked, the physics streamed is the library's,
//! and 20 sessions at once stay responsive.

use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream, connect_async};

type Ws = WebSocketStream<MaybeTlsStream<TcpStream>>;

/// A server on a free loopback port, serving until the test's runtime ends.
async fn server(limits: pendula_web::Limits) -> (String, String) {
    let options = pendula_web::Options { port: 0, limits, ..Default::default() };
    let server = pendula_web::bind(options).await.unwrap();
    let (addr, token) = (server.addr().to_string(), server.token().to_owned());
    tokio::spawn(server.run(std::future::pending()));
    (addr, token)
}

async fn connect(addr: &str, token: &str) -> Ws {
    connect_async(format!("ws://{addr}/ws?token={token}")).await.expect("the WebSocket opens").0
}

/// The next text message of `kind`, skipping frames and other messages (at most `within`).
async fn next_text(ws: &mut Ws, kind: &str, within: Duration) -> Value {
    let deadline = Instant::now() + within;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let m = tokio::time::timeout(left, ws.next())
            .await
            .unwrap_or_else(|_| panic!("no {kind} message in {within:?}"));
        if let Some(Ok(Message::Text(t))) = m {
            let v: Value = serde_json::from_str(t.as_str()).unwrap();
            if v["type"] == kind {
                return v;
            }
        } else if m.is_none() {
            panic!("the connection closed while waiting for {kind}");
        }
    }
}

/// The next binary frame of kind `k` (1: simulation, 2: fractal), as f64 values.
async fn next_frame(ws: &mut Ws, k: f64, within: Duration) -> Vec<f64> {
    let deadline = Instant::now() + within;
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let m = tokio::time::timeout(left, ws.next())
            .await
            .unwrap_or_else(|_| panic!("no frame of kind {k} in {within:?}"));
        match m {
            Some(Ok(Message::Binary(b))) => {
                assert_eq!(b.len() % 8, 0, "a frame is whole f64 values");
                let v: Vec<f64> =
                    b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect();
                if v[0] == k {
                    return v;
                }
            }
            Some(Ok(_)) => {}
            other => panic!("the connection ended while waiting for a frame: {other:?}"),
        }
    }
}

async fn send(ws: &mut Ws, v: Value) {
    ws.send(Message::Text(v.to_string().into())).await.unwrap();
}

const SEC: Duration = Duration::from_secs(1);

/// A simulation frame's time and the first track's state (see PROTOCOL.md).
fn time_and_state(frame: &[f64]) -> (f64, Vec<f64>) {
    let d = frame[4] as usize;
    (frame[2], frame[7..7 + d].to_vec())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_session_starts_with_hello_config_and_moving_frames() {
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    let hello = next_text(&mut ws, "hello", 5 * SEC).await;
    let systems: Vec<&str> =
        hello["systems"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(systems, ["oscillator", "pendulum", "double", "chain", "driven-pendulum"]);
    let config = next_text(&mut ws, "config", 5 * SEC).await;
    assert_eq!(config["system"], "double");
    assert_eq!(config["method"], "rk4");
    let (t1, y1) = time_and_state(&next_frame(&mut ws, 1.0, 5 * SEC).await);
    tokio::time::sleep(Duration::from_millis(300)).await;
    let (t2, y2) = time_and_state(&next_frame(&mut ws, 1.0, 5 * SEC).await);
    assert!(t2 > t1, "time advances: {t1} then {t2}");
    assert_ne!(y1, y2, "the pendulum moves");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_commands_get_an_error_frame_and_the_session_lives_on() {
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    let cases: Vec<(&str, &str)> = vec![
        ("{not json", "not JSON"),
        ("[1, 2]", "JSON object"),
        (r#"{"cmd":"configur"}"#, "unknown variant `configur`"),
        (r#"{"cmd":"configure","sytem":"double"}"#, "unknown field `sytem`"),
        (r#"{"cmd":"configure","system":"dubble"}"#, "double"),
        (r#"{"cmd":"configure","method":"rk5"}"#, "rk4"),
        (r#"{"cmd":"configure","params":{"m1":-2}}"#, "m1"),
        (r#"{"cmd":"configure","params":{"mass":2}}"#, "mass"),
        (r#"{"cmd":"configure","state":{"theta1":1e9}}"#, "theta1"),
        (r#"{"cmd":"configure","dt":0}"#, "dt = 0"),
        (r#"{"cmd":"configure","dt":"fast"}"#, "invalid type"),
        (r#"{"cmd":"speed","value":1e6}"#, "speed = 1000000"),
        (r#"{"cmd":"set_state","positions":[1]}"#, "1 positions given"),
        (r#"{"cmd":"configure","mode":"race","methods":["rk4"]}"#, "2 to 4"),
        (r#"{"cmd":"configure","mode":"butterfly","count":1000}"#, "count = 1000"),
        (r#"{"cmd":"fractal","size":100000}"#, "size = 100000"),
        (r#"{"cmd":"fractal","t_max":1e9}"#, "t_max"),
        (r#"{"cmd":"fractal","theta1":[1,1]}"#, "theta1"),
        (r#"{"cmd":"fractal","method":"verlet"}"#, "euler, rk4, tao-2, tao-4"),
    ];
    for (text, expected) in cases {
        ws.send(Message::Text(text.into())).await.unwrap();
        let error = next_text(&mut ws, "error", 5 * SEC).await;
        let message = error["message"].as_str().unwrap();
        assert!(message.contains(expected), "{text}: {message:?} should mention {expected:?}");
    }
    // Still alive, and still the first configuration.
    send(&mut ws, json!({"cmd": "configure", "state": {"theta1": 0.5}})).await;
    let config = next_text(&mut ws, "config", 5 * SEC).await;
    assert_eq!(config["state"][0]["value"], 0.5);
    assert_eq!(config["params"][0]["value"], 1.0, "m1 unchanged by the refused commands");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_explicit_splitting_on_the_double_pendulum_is_refused_and_verlet_runs_implicitly() {
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    send(&mut ws, json!({"cmd": "configure", "method": "yoshida-4"})).await;
    let error = next_text(&mut ws, "error", 5 * SEC).await;
    let message = error["message"].as_str().unwrap();
    assert!(message.contains("yoshida-4") && message.contains("separable"), "{message}");
    send(&mut ws, json!({"cmd": "configure", "method": "verlet", "speed": 10})).await;
    let config = next_text(&mut ws, "config", 5 * SEC).await;
    assert_eq!(config["method"], "verlet");
    // Frames sent before the change may still be queued: read on until t passes 1 s.
    let begin = Instant::now();
    while next_frame(&mut ws, 1.0, 5 * SEC).await[2] < 1.0 {
        assert!(begin.elapsed() < 10 * SEC, "verlet runs");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_streamed_states_are_the_librarys_run() {
    // Paused, then stepped: the frame's state after n steps is `pendula::solve`'s.
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    send(&mut ws, json!({"cmd": "pause"})).await;
    send(&mut ws, json!({"cmd": "configure", "method": "gauss-legendre-4", "dt": 0.05, "state": {"theta1": 2.0, "theta2": -0.5}})).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    for _ in 0..10 {
        send(&mut ws, json!({"cmd": "step"})).await;
    }
    let mut frame = next_frame(&mut ws, 1.0, 5 * SEC).await;
    while frame[6] < 10.0 {
        frame = next_frame(&mut ws, 1.0, 5 * SEC).await;
    }
    let (t, y) = time_and_state(&frame);
    let values = pendula::model::find("double")
        .unwrap()
        .values(&[("theta1".into(), 2.0), ("theta2".into(), -0.5)])
        .unwrap();
    let model = values.build();
    let method = pendula::integrator::find("gauss-legendre-4").unwrap();
    let mut last = pendula::observe::Recorder::default();
    let spec = pendula::RunSpec { t0: 0.0, h: 0.05, end: pendula::End::Steps(10) };
    model.solve(method, values.initial_state(), &spec, &mut last).unwrap();
    let row = &last.rows[last.rows.len() - 5..];
    let (t_ref, y_ref) = (row[0], row[1..].to_vec());
    assert!((t - t_ref).abs() < 1e-12, "{t} vs {t_ref}");
    assert_eq!(y, y_ref, "the same bits as one uninterrupted run");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_race_shows_rk4_drifting_and_gauss_legendre_bounded_over_1000_s() {
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    send(
        &mut ws,
        json!({"cmd": "configure", "mode": "race", "methods": ["rk4", "gauss-legendre-4"], "dt": 0.01, "speed": 250}),
    )
    .await;
    let config = next_text(&mut ws, "config", 5 * SEC).await;
    assert_eq!(config["tracks"].as_array().unwrap().len(), 2);
    // (t, rk4's error, gauss-legendre's error) along the run.
    let mut series: Vec<(f64, f64, f64)> = Vec::new();
    let begin = Instant::now();
    while series.last().is_none_or(|s| s.0 < 1000.0) {
        assert!(begin.elapsed() < 60 * SEC, "1000 simulated seconds in a minute");
        let f = next_frame(&mut ws, 1.0, 5 * SEC).await;
        let d = f[4] as usize;
        let err = |k: usize| f[7 + k * (d + 4) + d + 2];
        series.push((f[2], err(0), err(1)));
    }
    // Medians over each half of the run: a linear drift triples them (c·250 s against c·750 s), a bounded error leaves them alike; the median, unlike the largest
    // value, does not depend on which instants the frames happened to sample on a chaotic orbit.
    let median_in = |a: f64, b: f64, k: usize| {
        let mut v: Vec<f64> =
            series.iter().filter(|s| s.0 >= a && s.0 < b).map(|s| if k == 0 { s.1 } else { s.2 }).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (rk_early, rk_late) = (median_in(0.0, 500.0, 0), median_in(500.0, 2000.0, 0));
    let (gl_early, gl_late) = (median_in(0.0, 500.0, 1), median_in(500.0, 2000.0, 1));
    eprintln!(
        "median energy errors, t < 500 s then t > 500 s: rk4 {rk_early:.2e} -> {rk_late:.2e}; gauss-legendre-4 {gl_early:.2e} -> {gl_late:.2e}"
    );
    // Measured: rk4's medians grow 3.4-fold; gauss-legendre-4's change by 0.66 to 1.55.
    assert!(rk_late > 2.5 * rk_early, "rk4's energy error grows");
    assert!(gl_late < 2.0 * gl_early && gl_early < 2.0 * gl_late, "gauss-legendre-4's stays bounded");
    assert!(gl_late < rk_late, "and below rk4's");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_fractal_comes_coarse_first_then_whole_with_flags_equal_to_the_librarys() {
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    let begin = Instant::now();
    send(&mut ws, json!({"cmd": "fractal", "size": 64, "t_max": 20})).await;
    let first = next_frame(&mut ws, 2.0, 30 * SEC).await;
    eprintln!("first level {}² after {:.3} s", first[2], begin.elapsed().as_secs_f64());
    assert_eq!((first[2], first[9], first[10]), (32.0, 0.0, 0.0), "32², no flags, not final");
    let last = next_frame(&mut ws, 2.0, 60 * SEC).await;
    assert_eq!((last[2], last[9], last[10]), (64.0, 1.0, 1.0), "64², flags, final");
    // The library's fractal of the same spec.
    use pendula::analysis::fractal::{FractalSpec, GridAxis, flip_fractal};
    use pendula::system::Model;
    let pi = std::f64::consts::PI;
    let axis = GridAxis { lo: -pi, hi: pi, n: 64 };
    let pendulum = pendula::system::double::DoublePendulum::from_values(
        &pendula::model::find("double").unwrap().values(&[]).unwrap(),
    );
    let spec = FractalSpec {
        pendulum,
        theta1: axis,
        theta2: axis,
        t_max: 20.0,
        h: 0.01,
        method: pendula::ensemble::engine::LaneMethod::of(&pendula::integrator::explicit_rk::RK4).unwrap(),
        tolerance: 0.01,
    };
    let reference = flip_fractal(&spec).unwrap();
    let n = 64 * 64;
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    assert!(last[12..12 + n].iter().zip(&reference.flip_time).all(|(a, b)| same(*a, *b)));
    let flags: Vec<bool> = last[12 + n..12 + 2 * n].iter().map(|f| *f == 1.0).collect();
    assert_eq!(flags, reference.converged);
    next_text(&mut ws, "fractal_done", 5 * SEC).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_socket_without_the_token_or_from_another_origin_is_refused() {
    let (addr, token) = server(Default::default()).await;
    let status = |r: Result<_, tokio_tungstenite::tungstenite::Error>| match r {
        Err(tokio_tungstenite::tungstenite::Error::Http(response)) => response.status().as_u16(),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => 101,
    };
    assert_eq!(status(connect_async(format!("ws://{addr}/ws")).await), 403, "no token");
    assert_eq!(status(connect_async(format!("ws://{addr}/ws?token=00{token}")).await), 403, "wrong token");
    let with = |origin: &str, host: Option<&str>| {
        let mut request = format!("ws://{addr}/ws?token={token}").into_client_request().unwrap();
        request.headers_mut().insert("origin", origin.parse().unwrap());
        if let Some(h) = host {
            request.headers_mut().insert("host", h.parse().unwrap());
        }
        request
    };
    assert_eq!(status(connect_async(with("http://evil.example", None)).await), 403, "foreign origin");
    let rebinding = "evil.example:80";
    assert_eq!(
        status(connect_async(with("http://evil.example:80", Some(rebinding))).await),
        403,
        "DNS rebinding"
    );
    assert_eq!(
        status(connect_async(with(&format!("http://{addr}"), None)).await),
        101,
        "the page's own origin"
    );
}

/// The status of a plain `GET path` (no upgrade), and its body.
async fn plain_get(addr: &str, path: &str) -> (u16, String) {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut s = TcpStream::connect(addr).await.unwrap();
    let request = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    s.write_all(request.as_bytes()).await.unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).await.unwrap();
    let status = text.split_whitespace().nth(1).and_then(|c| c.parse().ok()).unwrap_or(0);
    (status, text)
}

/// The page's question after a refused WebSocket (the browser hides the refusal's status): a
/// plain GET of /ws says 403 for a wrong token, 503 for a full server and 426 when a WebSocket
/// would be accepted, and counts no session.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plain_get_of_the_socket_says_why_a_websocket_would_be_refused() {
    let limits = pendula_web::Limits { max_sessions: 1, ..Default::default() };
    let (addr, token) = server(limits).await;
    let (status, body) = plain_get(&addr, &format!("/ws?token=00{token}")).await;
    assert_eq!(status, 403);
    assert!(body.contains("the token printed by `pendula serve`"), "{body}");
    assert_eq!(plain_get(&addr, "/ws").await.0, 403, "no token");
    for _ in 0..3 {
        assert_eq!(plain_get(&addr, &format!("/ws?token={token}")).await.0, 426, "no session is counted");
    }
    let _only = connect(&addr, &token).await;
    assert_eq!(plain_get(&addr, &format!("/ws?token={token}")).await.0, 503);
}

/// Without an explicit port the server walks from the default to the next free port.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_default_port_moves_on_when_busy_and_an_explicit_one_does_not() {
    let first = pendula_web::DEFAULT_PORT;
    // Held here, or by another program already: busy either way.
    let _holder = std::net::TcpListener::bind(("127.0.0.1", first));
    let (server, busy) = pendula_web::bind_default(Default::default()).await.unwrap();
    let port = server.addr().port();
    assert!(busy.first() == Some(&first) && busy.last() == Some(&(port - 1)), "{busy:?} then {port}");
    assert!(port < first + pendula_web::DEFAULT_PORT_TRIES);
    let explicit = pendula_web::bind(pendula_web::Options { port: first, ..Default::default() }).await;
    let err = explicit.err().expect("an explicit busy port is an error");
    assert!(err.to_string().contains(&format!("127.0.0.1:{first}")), "{err}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sessions_beyond_the_limit_are_refused_and_a_closed_one_frees_its_place() {
    let limits = pendula_web::Limits { max_sessions: 2, ..Default::default() };
    let (addr, token) = server(limits).await;
    let a = connect(&addr, &token).await;
    let _b = connect(&addr, &token).await;
    match connect_async(format!("ws://{addr}/ws?token={token}")).await {
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => assert_eq!(r.status().as_u16(), 503),
        other => panic!("a third session: {other:?}"),
    }
    drop(a);
    let begin = Instant::now();
    loop {
        if connect_async(format!("ws://{addr}/ws?token={token}")).await.is_ok() {
            break;
        }
        assert!(begin.elapsed() < 5 * SEC, "the closed session's place is freed");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn twenty_sessions_at_once_stay_responsive() {
    let (addr, token) = server(Default::default()).await;
    let mut sockets = Vec::new();
    for _ in 0..20 {
        let mut ws = connect(&addr, &token).await;
        next_text(&mut ws, "config", 5 * SEC).await;
        sockets.push(ws);
    }
    // Every session answers a command and keeps its frames coming.
    let begin = Instant::now();
    let mut answers = Vec::new();
    for (k, ws) in sockets.iter_mut().enumerate() {
        send(ws, json!({"cmd": "configure", "state": {"theta1": 0.1 * k as f64}})).await;
    }
    for (k, ws) in sockets.iter_mut().enumerate() {
        let config = next_text(ws, "config", 5 * SEC).await;
        assert_eq!(config["state"][0]["value"], 0.1 * k as f64);
        answers.push(begin.elapsed());
    }
    let slowest = answers.iter().max().unwrap();
    eprintln!("20 sessions: every configure answered within {slowest:?}");
    assert!(*slowest < 2 * SEC);
    // Frames: count what each receives over one second.
    let window = Duration::from_secs(1);
    let counts = futures_util::future::join_all(sockets.iter_mut().map(|ws| async move {
        let end = Instant::now() + window;
        let mut n = 0;
        while let Ok(Some(Ok(m))) =
            tokio::time::timeout(end.saturating_duration_since(Instant::now()), ws.next()).await
        {
            if matches!(m, Message::Binary(_)) {
                n += 1;
            }
        }
        n
    }))
    .await;
    eprintln!("frames per session in 1 s: {counts:?}");
    assert!(counts.iter().all(|&n| n >= 10), "every session gets at least 10 frames a second: {counts:?}");
}

/// The fractal threads of this process, counted by name: the session's own, not the runtime's
/// workers nor a thread pool started by another test.
fn fractal_threads() -> usize {
    let tasks = std::fs::read_dir("/proc/self/task").expect("Linux's /proc");
    let named = |t: std::fs::DirEntry| std::fs::read_to_string(t.path().join("comm")).ok();
    tasks
        .filter_map(|t| named(t.ok()?))
        .filter(|comm| comm.trim_end() == pendula_web::FRACTAL_THREAD_NAME)
        .count()
}

/// Runs the test `name` alone in a child process of this test binary (`PENDULA_ALONE` set), so
/// that what it measures of the process (its threads) is not shared with tests running beside
/// it; true in that child, where the caller runs the test's body.
fn alone(name: &str) -> bool {
    if std::env::var_os("PENDULA_ALONE").is_some() {
        return true;
    }
    let exe = std::env::current_exe().unwrap();
    let out = std::process::Command::new(exe)
        .args(["--exact", name, "--nocapture", "--test-threads=1"])
        .env("PENDULA_ALONE", "1")
        .output()
        .unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{name}, alone in its own process, failed:\n{text}");
    // A filter that matched nothing would pass: the test must have run.
    assert!(text.contains("1 passed"), "{name} did not run alone:\n{text}");
    false
}

#[test]
fn a_flood_of_fractal_requests_computes_only_the_newest_on_one_thread() {
    if alone("a_flood_of_fractal_requests_computes_only_the_newest_on_one_thread") {
        // The engine's thread pool, named and started here: started lazily by the first map,
        // its workers would take the fractal thread's name (Linux threads inherit it) and be
        // counted as fractal threads.
        rayon::ThreadPoolBuilder::new().thread_name(|i| format!("rayon-{i}")).build_global().unwrap();
        let runtime =
            tokio::runtime::Builder::new_multi_thread().worker_threads(2).enable_all().build().unwrap();
        runtime.block_on(flood_of_fractal_requests());
    }
}

async fn flood_of_fractal_requests() {
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    let before = fractal_threads();
    for k in 0..200 {
        send(&mut ws, json!({"cmd": "fractal", "size": 64, "t_max": 10.0 + k as f64})).await;
    }
    let during = fractal_threads();
    assert!(during <= before + 1, "one fractal thread per session: {before} fractal threads, then {during}");
    // The session still answers at once, and the map that arrives whole is the last one asked.
    send(&mut ws, json!({"cmd": "configure", "state": {"theta1": 0.25}})).await;
    next_text(&mut ws, "config", 2 * SEC).await;
    loop {
        let f = next_frame(&mut ws, 2.0, 60 * SEC).await;
        let now = fractal_threads();
        assert!(now <= before + 1, "one fractal thread per session: {before} fractal threads, then {now}");
        if f[10] == 1.0 {
            assert_eq!((f[1], f[4]), (200.0, 209.0), "job 200, t_max 209 s");
            break;
        }
        assert!(f[1] == 200.0 || f[1] == 1.0, "levels of the first or the last job only: job {}", f[1]);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_simulation_keeps_the_speed_asked() {
    // Simulated seconds per wall second, measured on the frames as they arrive. (Rounding each
    // frame up to a whole step made speed 1 run at 1.19, and speeds below 0.6 all at 0.59.)
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    for speed in [1.0, 0.1, 3.0] {
        send(&mut ws, json!({"cmd": "configure", "system": "pendulum", "dt": 0.01, "speed": speed})).await;
        next_text(&mut ws, "config", 5 * SEC).await;
        // Frames queued before the change are skipped: start from one with t < 0.1.
        let mut first = next_frame(&mut ws, 1.0, 5 * SEC).await;
        while first[2] > 0.1 {
            first = next_frame(&mut ws, 1.0, 5 * SEC).await;
        }
        let begin = Instant::now();
        let mut last = first.clone();
        while begin.elapsed() < 3 * SEC {
            last = next_frame(&mut ws, 1.0, 5 * SEC).await;
        }
        let rate = (last[2] - first[2]) / begin.elapsed().as_secs_f64();
        eprintln!("speed {speed}: {rate:.3} simulated s per s");
        assert!((rate / speed - 1.0).abs() < 0.08, "speed {speed} ran at {rate}");
    }
}

/// Every study of the library's registry is offered in `hello`, runs with the library's
/// result, and refuses bad input and runs over the limit with the library's message.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_librarys_studies_run_in_the_lab_with_the_librarys_results() {
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    let hello = next_text(&mut ws, "hello", 5 * SEC).await;
    let names: Vec<&str> =
        hello["studies"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    let registry: Vec<&str> = pendula::study::STUDIES.iter().map(|s| s.name).collect();
    assert_eq!(names, registry);
    send(&mut ws, json!({"cmd": "study", "name": "energy-budget", "inputs": {"t_end": 2, "system": "pendulum"}, "set": {"damping": 0.3}})).await;
    let got = next_text(&mut ws, "study", 10 * SEC).await;
    let inputs =
        pendula::study::Inputs::default().name("system", "pendulum").number("t_end", 2.0).set("damping", 0.3);
    let report =
        (pendula::study::find("energy-budget").unwrap().run)(&inputs, &pendula::study::Budget::UNLIMITED)
            .unwrap();
    for n in &report.numbers {
        let shown = got["numbers"].as_array().unwrap().iter().find(|x| x["key"] == n.key).unwrap();
        assert_eq!(shown["value"].as_f64(), Some(n.value), "{}", n.key);
    }
    assert_eq!(got["summary"][0].as_str(), Some(report.summary[0].as_str()));
    let png = got["plots"][0]["png"].as_str().unwrap();
    assert!(png.starts_with("iVBORw0KGgo"), "a PNG, base64-encoded");
    for (request, expected) in [
        (json!({"cmd": "study", "name": "energy-budgte"}), "did you mean `energy-budget`"),
        (json!({"cmd": "study", "name": "energy-budget", "inputs": {"dt": -1}}), "invalid value -1 for `dt`"),
        (json!({"cmd": "study", "name": "energy-budget", "inputs": {"t_end": 1e9}}), "over the limit"),
        (
            json!({"cmd": "study", "name": "energy-budget", "inputs": {"dt": [1]}}),
            "for `dt`: one number, not a list",
        ),
        (json!({"cmd": "study", "name": "energy-budget", "inputs": {"dt": {"a": 1}}}), "a number or a name"),
    ] {
        send(&mut ws, request.clone()).await;
        let error = next_text(&mut ws, "error", 5 * SEC).await;
        let message = error["message"].as_str().unwrap();
        assert!(message.contains(expected), "{request}: {message:?} should mention {expected:?}");
    }
}

/// The butterfly's growth rate is the library's: `growth_rate_between` over the distance of
/// pendulum 1 from pendulum 0 — the same rule `pendula divergence` applies — equal to the bit
/// to the fit of the two runs replayed here on the lab's integrator path, and to rounding to
/// `pendula::analysis::divergence` (the reference integrator `pendula divergence` runs).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_butterflys_growth_rate_is_the_librarys_fit_of_the_same_run() {
    use pendula::analysis::divergence::{divergence, growth_rate_between, state_distance};
    use pendula::checkpoint::Pause;
    use pendula::observe::{Every, Recorder};
    use pendula::{End, RunSpec, Stepping};

    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    send(
        &mut ws,
        json!({"cmd": "configure", "mode": "butterfly", "count": 3, "delta": 1e-9, "method": "rk4", "dt": 0.01, "speed": 50}),
    )
    .await;
    next_text(&mut ws, "config", 5 * SEC).await;
    let begin = Instant::now();
    let growth = loop {
        assert!(begin.elapsed() < 60 * SEC, "the fit is final within a minute");
        let g = next_text(&mut ws, "growth", 30 * SEC).await;
        if g["final"] == true {
            break g;
        }
    };
    let f = |k: &str| growth[k].as_f64().unwrap_or_else(|| panic!("{k} in {growth}"));
    let (rate, every) = (f("rate"), growth["every"].as_u64().unwrap());
    assert_eq!((f("fit_from"), f("saturation")), (100.0 * 1e-9, 0.1), "from 100 δ to 0.1");
    assert!(0.3 < rate && rate < 5.0, "the double pendulum's rate: {rate}");

    let values = pendula::model::find("double").unwrap().values(&[]).unwrap();
    let model = values.build();
    let rk4 = pendula::integrator::find("rk4").unwrap();
    let y0 = values.initial_state().to_vec();
    let mut y1 = y0.clone();
    y1[0] += 1e-9;
    // The lab's runs: its integrator path and schedule, uninterrupted, to past the window.
    let t_past = f("t_end") + 1.0;
    let stepping = Stepping::Fixed(RunSpec { t0: 0.0, h: 0.01, end: End::Time(1e6) });
    let run = |y: &[f64]| {
        let mut rec = Every { n: every, inner: Recorder::default() };
        model.solve_fastest(rk4, y, &stepping, &mut rec, None, &Pause { at: t_past, flag: None }).unwrap();
        rec.inner.rows
    };
    let (a, b) = (run(&y0), run(&y1));
    let (t, distance) = a
        .chunks_exact(5)
        .zip(b.chunks_exact(5))
        .map(|(ra, rb)| (ra[0], state_distance(&ra[1..], &rb[1..])))
        .unzip();
    let replay = pendula::analysis::Divergence { t, distance };
    let fit = growth_rate_between(&replay, f("fit_from"), 0.1).unwrap();
    assert_eq!(
        (rate, f("t_start"), f("t_end"), f("intercept")),
        (fit.rate, fit.t_start, fit.t_end, fit.intercept),
        "the library's fit of the lab's runs"
    );

    // `pendula divergence double --method rk4 --dt 0.01 --delta 1e-9 --fit-from 1e-7
    // --saturation 0.1 --t-end 30`: the reference integrator's rounding differs from the
    // fast path's by about 1e-16 relative, which the chaos amplifies as it amplifies δ; the
    // rates agree to about 1e-16/1e-9.
    let spec = RunSpec { t0: 0.0, h: 0.01, end: End::Time(30.0) };
    let d = divergence(&*model, rk4, &y0, 0, 1e-9, &spec, every).unwrap();
    let cli = growth_rate_between(&d, 1e-7, 0.1).unwrap();
    eprintln!(
        "lab {rate} over {}..{}; pendula divergence {} over {}..{}",
        f("t_start"),
        f("t_end"),
        cli.rate,
        cli.t_start,
        cli.t_end
    );
    assert!((rate - cli.rate).abs() <= 1e-6 * cli.rate.abs(), "lab {rate}, pendula divergence {}", cli.rate);
    assert_eq!((f("t_start"), f("t_end")), (cli.t_start, cli.t_end), "the same window");
}

/// Only the butterfly measures a growth rate: a single run sends no `growth` message.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_single_run_sends_no_growth_rate() {
    let (addr, token) = server(Default::default()).await;
    let mut ws = connect(&addr, &token).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    send(&mut ws, json!({"cmd": "configure", "speed": 50})).await;
    next_text(&mut ws, "config", 5 * SEC).await;
    let until = Instant::now() + 2 * SEC;
    while Instant::now() < until {
        if let Ok(Some(Ok(Message::Text(t)))) = tokio::time::timeout(SEC, ws.next()).await {
            let v: Value = serde_json::from_str(t.as_str()).unwrap();
            assert_ne!(v["type"], "growth", "{v}");
        }
    }
}

/// The page's script is ES modules linked by the browser: index.html loads the entry as a
/// module, and every module it imports, directly or not, is served with a JavaScript type (a
/// browser refuses a module of any other type); every file under `assets/js/` is one of them.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_script_is_es_modules_each_served_as_javascript() {
    let (addr, _) = server(Default::default()).await;
    let (status, page) = plain_get(&addr, "/").await;
    assert_eq!(status, 200);
    assert!(page.contains(r#"<script type="module" src="/app.js"></script>"#), "{page}");
    let mut todo = vec!["/app.js".to_owned()];
    let mut served = std::collections::BTreeSet::new();
    while let Some(path) = todo.pop() {
        if !served.insert(path.clone()) {
            continue;
        }
        let (status, response) = plain_get(&addr, &path).await;
        assert_eq!(status, 200, "{path}");
        let (head, body) = response.split_once("\r\n\r\n").unwrap();
        assert!(head.to_lowercase().contains("content-type: text/javascript"), "{path}: {head}");
        let dir = &path[..path.rfind('/').unwrap() + 1];
        for import in body.lines().filter_map(|l| l.strip_prefix("import ")) {
            let target = import.split(" from '").nth(1).and_then(|t| t.strip_suffix("';")).unwrap();
            let target =
                target.strip_prefix("./").unwrap_or_else(|| panic!("{path}: a relative import: {import}"));
            todo.push(format!("{dir}{target}"));
        }
    }
    let on_disk: std::collections::BTreeSet<String> =
        std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/js"))
            .unwrap()
            .map(|e| format!("/js/{}", e.unwrap().file_name().to_string_lossy()))
            .collect();
    let imported: std::collections::BTreeSet<String> =
        served.iter().filter(|p| p.starts_with("/js/")).cloned().collect();
    assert_eq!(imported, on_disk, "every module is imported and served");
    assert!(served.len() > 10, "{served:?}");
}
