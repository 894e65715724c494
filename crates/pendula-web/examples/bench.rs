//! Measures `pendula serve`: frames per second delivered to each session and the server's
//! CPU per session (double pendulum, rk4 and gauss-legendre-4, 1 and 10 sessions at once), and
//! the fractal explorer's time to its first coarse map and to the whole 512² map (t_max 100 s).
//!
//! `cargo run --release -p pendula-web --example bench -- target/release/pendula`
//! (the server runs as its own process, so that its CPU time is its own: /proc/PID/stat).

use std::io::BufRead;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::json;
use tokio_tungstenite::connect_async;
use tokio_tungstenite::tungstenite::Message;

/// The server's user + system CPU time, s.
fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("the server's /proc entry");
    // Fields after the command name (in parentheses, which may hold spaces).
    let rest = &stat[stat.rfind(')').expect("a stat line") + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields[11].parse::<f64>().unwrap() + fields[12].parse::<f64>().unwrap();
    ticks / 100.0 // USER_HZ, 100 on Linux
}

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() {
    let pendula = std::env::args().nth(1).unwrap_or_else(|| "target/release/pendula".into());
    let mut child = Command::new(&pendula)
        .args(["serve", "--port", "0", "--max-sessions", "64"])
        .stdout(Stdio::piped())
        .spawn()
        .expect("pendula serve starts");
    let mut line = String::new();
    // Kept open to the end: the server's stdout stays a live pipe.
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    stdout.read_line(&mut line).unwrap();
    let url = line.split_whitespace().find(|w| w.starts_with("http://")).expect("the URL").to_owned();
    let ws_url = url.replacen("http://", "ws://", 1).replacen("/?token=", "/ws?token=", 1);
    let pid = child.id();
    println!(
        "| method | speed (simulated s per s) | sessions | frames/s per session (min … max) | server CPU per session, % of a core |"
    );
    println!("|---|---|---|---|---|");
    for method in ["rk4", "gauss-legendre-4"] {
        for (speed, sessions) in [(1.0, 1usize), (1.0, 10), (100.0, 1), (100.0, 10)] {
            let mut sockets = Vec::new();
            for _ in 0..sessions {
                let (mut ws, _) = connect_async(&ws_url).await.unwrap();
                let cmd = json!({"cmd": "configure", "method": method, "dt": 0.01, "speed": speed});
                ws.send(Message::Text(cmd.to_string().into())).await.unwrap();
                sockets.push(ws);
            }
            // Read for a second first: the frames sent while the sessions were opened are not
            // counted.
            let settle = Instant::now() + Duration::from_secs(1);
            futures_util::future::join_all(sockets.iter_mut().map(|ws| async move {
                while tokio::time::timeout(settle.saturating_duration_since(Instant::now()), ws.next())
                    .await
                    .is_ok()
                {}
            }))
            .await;
            let window = Duration::from_secs(8);
            let cpu0 = cpu_seconds(pid);
            let begin = Instant::now();
            let counts = futures_util::future::join_all(sockets.iter_mut().map(|ws| async move {
                let end = begin + window;
                let mut n = 0u32;
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
            let wall = begin.elapsed().as_secs_f64();
            let cpu = cpu_seconds(pid) - cpu0;
            let rates: Vec<f64> = counts.iter().map(|&n| f64::from(n) / wall).collect();
            let (lo, hi) = rates.iter().fold((f64::MAX, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
            println!(
                "| {method} | {speed} | {sessions} | {lo:.1} … {hi:.1} | {:.2} |",
                100.0 * cpu / wall / sessions as f64
            );
            for mut ws in sockets {
                let _ = ws.close(None).await;
            }
            tokio::time::sleep(Duration::from_millis(300)).await;
        }
    }
    // The fractal: the time from the command to each level's frame.
    let (mut ws, _) = connect_async(&ws_url).await.unwrap();
    let begin = Instant::now();
    let cmd = json!({"cmd": "fractal", "size": 512, "t_max": 100});
    ws.send(Message::Text(cmd.to_string().into())).await.unwrap();
    println!();
    println!("| fractal level (t_max 100 s, rk4, dt 0.01 s) | seconds after the command |");
    println!("|---|---|");
    while let Some(Ok(m)) = ws.next().await {
        if let Message::Binary(b) = m {
            let v: Vec<f64> =
                b.chunks_exact(8).take(11).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect();
            if v[0] == 2.0 {
                let flags = if v[9] == 1.0 { " with convergence flags (dt/2 run)" } else { "" };
                println!("| {}²{flags} | {:.3} |", v[2], begin.elapsed().as_secs_f64());
                if v[10] == 1.0 {
                    break;
                }
            }
        }
    }
    let serve_full = begin.elapsed().as_secs_f64();
    let _ = child.kill();
    let _ = child.wait();
    // The same map by `pendula fractal` (its defaults: 512², t_max 100 s, rk4, dt 0.01 s and
    // the dt/2 check), in the same run: what the progressive levels cost on top.
    let dir = std::env::temp_dir().join(format!("pendula-bench-web-{}", std::process::id()));
    let begin = Instant::now();
    let status = Command::new(&pendula)
        .args(["fractal", "--out-dir"])
        .arg(&dir)
        .stderr(Stdio::null())
        .stdout(Stdio::null())
        .status()
        .expect("pendula fractal runs");
    let cli = begin.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(status.success(), "pendula fractal failed");
    println!();
    println!(
        "the whole 512² map: serve {serve_full:.3} s, `pendula fractal` {cli:.3} s (files included): ratio {:.2}",
        serve_full / cli
    );
}
