//! `pendula serve`: an interactive pendulum lab in the browser, the physics in Rust.
//!
//! A small axum server: the page (HTML, its script as ES modules, and styles, embedded in the
//! binary) and one WebSocket per page, over which the server streams the simulation as binary
//! frames and the page sends JSON commands (the protocol: `crates/pendula-web/PROTOCOL.md`).
//! Each session runs its pendulums on a thread of its own with the library's integrators,
//! paced to the wall clock (`src/session.rs`); the fractal explorer runs the ensemble engine on
//! every core (`src/fractal.rs`).
//!
//! Safe by default: it binds 127.0.0.1; the WebSocket needs the random token printed in the
//! URL and refuses other origins (and, on loopback, host names that are not loopback ones, so
//! that a DNS-rebinding page cannot reach it); every request's work is bounded ([`Limits`]);
//! no request touches the file system.
//!
//! # How it is built
//!
//! The browser lab, `crates/pendula-web` (protocol: `crates/pendula-web/PROTOCOL.md`):
//! `crates/pendula-web/src/lib.rs` is the axum server — the page, script and styles
//! (`crates/pendula-web/assets/`) embedded by `include_str!`, the checks before a WebSocket is
//! accepted (token, `Origin`, loopback `Host`, the session limit) and one session per socket: a
//! reader task that parses each JSON command (`session::Command`, serde), a thread that runs the
//! session, and a writer task that sends what the thread leaves in the session's `Outbox` (texts in
//! order; the newest simulation frame and fractal level only: latest wins, so a slow page never
//! queues work). `crates/pendula-web/src/config.rs` validates a `configure` against the catalogue
//! and the method registry (the library's `SystemInfo::values` and `DynModel::check`, so the page
//! shows the library's own refusals) and says what the page needs back: quantities with units and
//! domains, how to draw the system (from the catalogue's naming: each angle a rod of the length and
//! mass named by its suffix, a position in metres a spring), the share object, the equivalent
//! `pendula simulate` command and scenario. `crates/pendula-web/src/session.rs` paces the tracks
//! (one per pendulum: single, race, butterfly) to the wall clock: each frame continues every
//! track's run with `DynModel::solve_fastest` from its paused `RunState` to the simulated time the
//! clock asks for (at most `Limits::max_steps_per_frame` steps), bit for bit the uninterrupted run,
//! with the event locator (flips; the Poincaré section) saved and restored between legs by its
//! `Snapshot`. `crates/pendula-web/src/fractal.rs` computes the flip map level by level with
//! `analysis::fractal::flip_times_at` (one step size; the last level also at dt/2 for the
//! convergence flags), one map at a time across sessions, cancelled by a newer request or a closed
//! page. `pendula serve` (`crates/pendula-cli/src/commands/serve.rs`: `pendula_web::bind_default`
//! on `DEFAULT_PORT` 8485 or the next free of its successors when no `--port` is given, `bind` on
//! an explicit one) and Python's `pendula.view` (`crates/pendula-py/src/serve.rs`,
//! `crates/pendula-py/python/pendula/view.py`: one lab per process on any free port, an IFrame in
//! Jupyter) start it. The page (`crates/pendula-web/assets/app.js`) lays out every legend in a band
//! above its plot's data area and records both boxes (`lab.geometry`), bounds the pendulums' trails
//! by simulated time, composes the PNG export from the redrawn canvases under a title and captions,
//! and after a failed WebSocket asks `GET /ws` plainly why (a wrong token ends the retries). Tested
//! by `crates/pendula-web/tests/protocol.rs` (a real server on a loopback port, a WebSocket client)
//! and `crates/pendula-web/tests/e2e/` (Playwright driving Debian's headless Chromium,
//! `scripts/test-web`).

use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use axum::Router;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Query, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use serde_json::{Value, json};

mod config;
mod fractal;
mod session;
mod study;

pub use config::Mode;
pub use fractal::THREAD_NAME as FRACTAL_THREAD_NAME;

/// What one session may ask of the server.
#[derive(Debug, Clone)]
pub struct Limits {
    /// Sessions at once (pages open); more are refused with 503.
    pub max_sessions: usize,
    /// Simulation frames per second sent to a page.
    pub max_fps: f64,
    /// Simulated seconds per wall second.
    pub max_speed: f64,
    /// Pendulums in butterfly mode.
    pub max_tracks: usize,
    /// Methods in a race.
    pub max_race: usize,
    /// Integration steps per frame, all of a session's pendulums together: a speed the
    /// server cannot keep up with makes the simulation fall behind the clock, not the server.
    pub max_steps_per_frame: u64,
    /// Pixels per side of a fractal map.
    pub max_fractal_size: usize,
    /// Longest fractal horizon, s.
    pub max_t_max: f64,
    /// Largest command accepted, bytes.
    pub max_message_bytes: usize,
    /// Integration steps of one `study` request (the study's own estimate, checked before
    /// it runs): about a second of work.
    pub max_study_steps: u64,
    /// Table values of one `study` answer (a running estimate's rows, say), checked before
    /// it runs: the answer stays a few megabytes.
    pub max_study_values: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_sessions: 32,
            max_fps: 60.0,
            max_speed: 1000.0,
            max_tracks: 16,
            max_race: 4,
            max_steps_per_frame: 50_000,
            max_fractal_size: 1024,
            max_t_max: 1000.0,
            max_message_bytes: 64 * 1024,
            max_study_steps: 2_000_000,
            max_study_values: 200_000,
        }
    }
}

/// The lab's default port, 8485. Chosen because no common tool uses it: IANA lists 8475–8499
/// as unassigned, nmap's table of ports seen open on the Internet has none of 8485–8499, and it
/// is none of the defaults a scientist's machine is likely to run (Jupyter 8888, Dask's
/// dashboard and RStudio Server 8787, Django and `python -m http.server` 8000, Flask 5000,
/// Streamlit 8501, Dash 8050, Bokeh 5006, TensorBoard 6006, Gradio 7860, Ray's dashboard 8265,
/// Vite 5173, the usual 8080/8081/8088/8888/9000); nor are 8486–8494, the ports tried after
/// it when it is busy ([`DEFAULT_PORT_TRIES`]).
pub const DEFAULT_PORT: u16 = 8485;

/// How many ports [`bind_default`] tries, [`DEFAULT_PORT`] and the ones after it (8485–8494),
/// before it gives up: a bounded walk, as Jupyter's (which tries 50).
pub const DEFAULT_PORT_TRIES: u16 = 10;

/// The server's options.
#[derive(Debug, Clone)]
pub struct Options {
    /// Address to bind (127.0.0.1 unless told otherwise).
    pub host: IpAddr,
    /// Port (0: any free one; [`DEFAULT_PORT`] by default).
    pub port: u16,
    /// The token the WebSocket asks for (a random one when `None`).
    pub token: Option<String>,
    /// Limits on each session's work.
    pub limits: Limits,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            host: IpAddr::from([127, 0, 0, 1]),
            port: DEFAULT_PORT,
            token: None,
            limits: Limits::default(),
        }
    }
}

/// The state every handler shares.
struct App {
    token: String,
    limits: Limits,
    sessions: AtomicUsize,
    loopback: bool,
}

/// What a session's thread and its WebSocket writer share.
pub(crate) struct Shared {
    pub(crate) outbox: Mutex<session::Outbox>,
    pub(crate) notify: tokio::sync::Notify,
}

/// A bound server, not yet serving.
pub struct Server {
    listener: tokio::net::TcpListener,
    app: Arc<App>,
}

/// Binds the server's socket (it must be called inside a tokio runtime).
///
/// # Errors
/// When the address cannot be bound (in use, not permitted), naming it.
pub async fn bind(options: Options) -> std::io::Result<Server> {
    let addr = SocketAddr::new(options.host, options.port);
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .map_err(|e| std::io::Error::new(e.kind(), format!("cannot listen on {addr}: {e}")))?;
    let token = options.token.unwrap_or_else(random_token);
    let app = Arc::new(App {
        token,
        limits: options.limits,
        sessions: AtomicUsize::new(0),
        loopback: options.host.is_loopback(),
    });
    Ok(Server { listener, app })
}

/// Binds [`DEFAULT_PORT`] (whatever `options.port` says), or when another program holds it the
/// first free one of the [`DEFAULT_PORT_TRIES`] − 1 after it, as Jupyter does; returns the
/// server and the busy ports passed over (empty when the default was free), so that the
/// caller can say where it went instead. A port asked for explicitly is bound with [`bind`]:
/// taking another one then would surprise the user who chose it.
///
/// # Errors
/// When every port tried is in use (naming the range), or at the first error that is not
/// "address in use" (a host that is not this machine's, say), naming the address.
pub async fn bind_default(options: Options) -> std::io::Result<(Server, Vec<u16>)> {
    let mut busy = Vec::new();
    for port in DEFAULT_PORT..DEFAULT_PORT + DEFAULT_PORT_TRIES {
        match bind(Options { port, ..options.clone() }).await {
            Ok(server) => return Ok((server, busy)),
            Err(e) if e.kind() == std::io::ErrorKind::AddrInUse => busy.push(port),
            Err(e) => return Err(e),
        }
    }
    let last = DEFAULT_PORT + DEFAULT_PORT_TRIES - 1;
    Err(std::io::Error::new(
        std::io::ErrorKind::AddrInUse,
        format!("cannot listen on {}: ports {DEFAULT_PORT} to {last} are all in use", options.host),
    ))
}

impl Server {
    /// The address bound.
    pub fn addr(&self) -> SocketAddr {
        self.listener.local_addr().expect("a bound socket has an address")
    }

    /// The token the WebSocket asks for.
    pub fn token(&self) -> &str {
        &self.app.token
    }

    /// The page's URL, token included.
    pub fn url(&self) -> String {
        let addr = self.addr();
        let host = match addr.ip() {
            IpAddr::V6(ip) => format!("[{ip}]"),
            IpAddr::V4(ip) if ip.is_unspecified() => "127.0.0.1".into(),
            ip => ip.to_string(),
        };
        format!("http://{host}:{}/?token={}", addr.port(), self.app.token)
    }

    /// Serves until `shutdown` completes.
    ///
    /// # Errors
    /// As axum's server.
    pub async fn run(
        self,
        shutdown: impl std::future::Future<Output = ()> + Send + 'static,
    ) -> std::io::Result<()> {
        let mut router =
            Router::new().route("/", get(page)).route("/style.css", get(styles)).route("/ws", get(socket));
        for &(path, body) in SCRIPTS {
            router = router.route(
                path,
                get(move |State(app): State<Arc<App>>, headers: HeaderMap| async move {
                    script(&app, &headers, body)
                }),
            );
        }
        let router = router
            .fallback(|| async { (StatusCode::NOT_FOUND, "not found: the lab is at /") })
            .with_state(self.app);
        axum::serve(self.listener, router).with_graceful_shutdown(shutdown).await
    }
}

const INDEX: &str = include_str!("../assets/index.html");
/// The page's script, ES modules that the browser links itself (no bundler): the entry
/// `/app.js`, which index.html loads as `<script type="module">`, and the modules it imports
/// under `/js/` (relative imports, so the paths here are the files' paths under `assets/`).
const SCRIPTS: &[(&str, &str)] = &[
    ("/app.js", include_str!("../assets/app.js")),
    ("/js/connection.js", include_str!("../assets/js/connection.js")),
    ("/js/drawing.js", include_str!("../assets/js/drawing.js")),
    ("/js/messages.js", include_str!("../assets/js/messages.js")),
    ("/js/plots.js", include_str!("../assets/js/plots.js")),
    ("/js/share.js", include_str!("../assets/js/share.js")),
    ("/js/state.js", include_str!("../assets/js/state.js")),
    ("/js/tabs.js", include_str!("../assets/js/tabs.js")),
    ("/js/util.js", include_str!("../assets/js/util.js")),
    ("/js/view-export.js", include_str!("../assets/js/view-export.js")),
    ("/js/view-fractal.js", include_str!("../assets/js/view-fractal.js")),
    ("/js/view-graphs.js", include_str!("../assets/js/view-graphs.js")),
    ("/js/view-sim.js", include_str!("../assets/js/view-sim.js")),
    ("/js/view-studies.js", include_str!("../assets/js/view-studies.js")),
    ("/js/views.js", include_str!("../assets/js/views.js")),
];
const STYLES: &str = include_str!("../assets/style.css");

async fn page(State(app): State<Arc<App>>, headers: HeaderMap) -> Response {
    if let Err(refusal) = check_host(&app, &headers) {
        return refusal.into_response();
    }
    ([(header::CONTENT_TYPE, "text/html; charset=utf-8"), (header::CACHE_CONTROL, "no-store")], INDEX)
        .into_response()
}

/// One of [`SCRIPTS`]: a browser runs a module only when it comes with a JavaScript type.
fn script(app: &App, headers: &HeaderMap, body: &'static str) -> Response {
    if let Err(refusal) = check_host(app, headers) {
        return refusal.into_response();
    }
    ([(header::CONTENT_TYPE, "text/javascript; charset=utf-8")], body).into_response()
}

async fn styles(State(app): State<Arc<App>>, headers: HeaderMap) -> Response {
    if let Err(refusal) = check_host(&app, &headers) {
        return refusal.into_response();
    }
    ([(header::CONTENT_TYPE, "text/css; charset=utf-8")], STYLES).into_response()
}

/// On loopback, the `Host` must name a loopback address: a page whose own name resolves to
/// 127.0.0.1 (DNS rebinding) is refused before it can read anything.
fn check_host(app: &App, headers: &HeaderMap) -> Result<(), (StatusCode, String)> {
    if !app.loopback {
        return Ok(());
    }
    let host = headers.get(header::HOST).and_then(|h| h.to_str().ok()).unwrap_or("");
    let name = match host.rsplit_once(':') {
        Some((name, port)) if port.chars().all(|c| c.is_ascii_digit()) => name,
        _ => host,
    };
    let loopback = name == "localhost"
        || name
            .trim_start_matches('[')
            .trim_end_matches(']')
            .parse::<IpAddr>()
            .is_ok_and(|ip| ip.is_loopback());
    if loopback {
        Ok(())
    } else {
        Err((StatusCode::FORBIDDEN, format!("host {host:?} is not a loopback address: use 127.0.0.1")))
    }
}

#[derive(serde::Deserialize)]
struct TokenQuery {
    token: Option<String>,
}

/// The WebSocket: the token, the origin and the session limit are checked before the
/// upgrade. A plain GET (no upgrade) gets the same refusals, or 426 when all is well: a
/// browser hides a refused upgrade's status from the page, so the page asks again this way to
/// tell a wrong token (403: retrying cannot help) from a full server (503: it may) or a
/// stopped one (no answer).
async fn socket(
    State(app): State<Arc<App>>,
    headers: HeaderMap,
    Query(query): Query<TokenQuery>,
    ws: Result<WebSocketUpgrade, axum::extract::ws::rejection::WebSocketUpgradeRejection>,
) -> Response {
    if let Err(refusal) = check_host(&app, &headers) {
        return refusal.into_response();
    }
    let token_ok = query.token.as_deref().is_some_and(|t| same(t.as_bytes(), app.token.as_bytes()));
    if !token_ok {
        return (StatusCode::FORBIDDEN, "a WebSocket needs the token printed by `pendula serve`")
            .into_response();
    }
    // Browsers send the page's origin with every WebSocket: one from any other page (another
    // site open in the same browser) is refused.
    if let Some(origin) = headers.get(header::ORIGIN) {
        let host = headers.get(header::HOST).and_then(|h| h.to_str().ok()).unwrap_or("");
        if origin.to_str().ok() != Some(&format!("http://{host}")) {
            return (
                StatusCode::FORBIDDEN,
                format!("WebSocket from origin {origin:?} refused: only this server's own page may connect"),
            )
                .into_response();
        }
    }
    let Ok(ws) = ws else {
        // A question, not a session: nothing is counted.
        if app.sessions.load(Ordering::SeqCst) >= app.limits.max_sessions {
            return (
                StatusCode::SERVICE_UNAVAILABLE,
                format!("{} sessions are open, the most this server takes", app.limits.max_sessions),
            )
                .into_response();
        }
        return (StatusCode::UPGRADE_REQUIRED, "the token is right: this address takes a WebSocket")
            .into_response();
    };
    let sessions = app.sessions.fetch_add(1, Ordering::SeqCst);
    if sessions >= app.limits.max_sessions {
        app.sessions.fetch_sub(1, Ordering::SeqCst);
        return (
            StatusCode::SERVICE_UNAVAILABLE,
            format!("{} sessions are open, the most this server takes", app.limits.max_sessions),
        )
            .into_response();
    }
    let limits = app.limits.clone();
    ws.max_message_size(limits.max_message_bytes).on_upgrade(move |socket| async move {
        serve_session(socket, limits).await;
        app.sessions.fetch_sub(1, Ordering::SeqCst);
    })
}

/// Compares without stopping at the first difference (the token is a secret).
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

fn random_token() -> String {
    let mut bytes = [0u8; 16];
    getrandom::fill(&mut bytes).expect("the operating system's random numbers");
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Runs one session: a reader (commands in), the session's thread, a writer (frames out).
async fn serve_session(socket: WebSocket, limits: Limits) {
    use futures_util::{SinkExt, StreamExt};
    let (mut sink, mut stream) = socket.split();
    let shared = Arc::new(Shared {
        outbox: Mutex::new(session::Outbox::default()),
        notify: tokio::sync::Notify::new(),
    });
    let (tx, rx) = std::sync::mpsc::channel();
    let thread_shared = shared.clone();
    let sim = std::thread::Builder::new()
        .name("pendula-session".into())
        .spawn(move || session::run(rx, thread_shared, limits))
        .expect("a thread for the session");
    let writer_shared = shared.clone();
    let writer = tokio::spawn(async move {
        loop {
            writer_shared.notify.notified().await;
            loop {
                let (fractal, texts, growth, frame) = {
                    let mut outbox = writer_shared.outbox.lock().expect("outbox");
                    let frame = outbox.frame.take().map(|mut f| {
                        f.push(outbox.poincare.len() as f64);
                        for p in outbox.poincare.drain(..) {
                            f.extend(p);
                        }
                        f
                    });
                    (outbox.fractal.take(), std::mem::take(&mut outbox.texts), outbox.growth.take(), frame)
                };
                if fractal.is_none() && texts.is_empty() && growth.is_none() && frame.is_none() {
                    break;
                }
                // The fractal level before the texts (its `fractal_done` follows it); the texts
                // (a `config`) before the growth fit and the frame computed after them.
                let mut messages: Vec<Message> = Vec::new();
                messages.extend(fractal.map(|f| Message::Binary(bytes(&f).into())));
                messages.extend(texts.into_iter().map(|t| Message::Text(t.into())));
                messages.extend(growth.map(|g| Message::Text(g.into())));
                messages.extend(frame.map(|f| Message::Binary(bytes(&f).into())));
                for m in messages {
                    if sink.send(m).await.is_err() {
                        return;
                    }
                }
            }
        }
    });
    while let Some(Ok(message)) = stream.next().await {
        let inbound = match message {
            Message::Text(text) => parse(text.as_str()),
            Message::Binary(_) => session::Inbound::Malformed {
                message: "binary messages are not commands: send JSON text".into(),
                command: None,
            },
            Message::Close(_) => break,
            _ => continue,
        };
        if tx.send(inbound).is_err() {
            break;
        }
    }
    // The page is gone: the session's thread sees its inbox closed and ends, its fractal
    // is cancelled, and the writer stops.
    drop(tx);
    writer.abort();
    let _ = tokio::task::spawn_blocking(move || sim.join()).await;
}

/// A command, or why the text is not one (naming its `cmd` when it has one).
fn parse(text: &str) -> session::Inbound {
    match serde_json::from_str::<session::Command>(text) {
        Ok(c) => session::Inbound::Command(Box::new(c)),
        Err(e) => {
            let value: Option<Value> = serde_json::from_str(text).ok();
            let command =
                value.as_ref().and_then(|v| v.get("cmd")).and_then(Value::as_str).map(str::to_owned);
            let message = match &value {
                None => format!("not JSON: {e}"),
                Some(v) if !v.is_object() => "a command is a JSON object with \"cmd\"".to_owned(),
                Some(_) => format!("invalid command: {e}"),
            };
            session::Inbound::Malformed { message, command }
        }
    }
}

fn bytes(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// The `hello` message: the catalogue's systems, the method registry and the limits.
pub(crate) fn hello(limits: &Limits) -> Value {
    let systems: Vec<Value> = pendula::model::CATALOGUE
        .iter()
        .map(|e| json!({"name": e.name, "description": e.description, "dimensionless": e.dimensionless}))
        .collect();
    let methods: Vec<Value> = pendula::integrator::METHODS
        .iter()
        .map(|m| json!({"name": m.name, "title": m.title, "order": m.order}))
        .collect();
    // The fractal's default method first: the page's selector starts on it.
    let default = pendula::study::defaults::FRACTAL.method.unwrap_or("rk4");
    let mut fractal_methods = pendula::analysis::fractal::methods();
    fractal_methods.sort_by_key(|m| *m != default);
    json!({
        "type": "hello",
        "version": env!("CARGO_PKG_VERSION"),
        "systems": systems,
        "methods": methods,
        "fractal_methods": fractal_methods,
        "studies": crate::study::list(),
        "limits": {
            "max_speed": limits.max_speed, "max_fps": limits.max_fps, "max_tracks": limits.max_tracks,
            "max_race": limits.max_race, "max_fractal_size": limits.max_fractal_size, "max_t_max": limits.max_t_max,
        },
    })
}
