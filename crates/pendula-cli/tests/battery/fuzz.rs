//! The fuzz harness's end-to-end part (the in-process part is `tests/fuzz/`): command lines
//! of every command, cheap valid requests mutated by proptest (a fixed seed) with hostile
//! values and edited input files, run through the real binary, each in a fresh directory.
//! Every run must end with exit 0, 1 or 2 — or, past its time, end on SIGTERM with 143 —
//! with no panic on stderr and no temporary file left behind.
//!
//! `PENDULA_FUZZ_CASES / 300` runs (333 by default; `PENDULA_FUZZ_CASES=10000000` gives
//! 33 333), two at a time.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::{Index, select};
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};

use crate::util::binary;

/// How long a run may take before it is interrupted (SIGTERM): valid requests are cheap,
/// but a mutation may make one long.
const TIME_LIMIT: Duration = Duration::from_secs(2);

/// How long an interrupted run may take to clean up and exit.
const GRACE: Duration = Duration::from_secs(10);

/// Cheap valid requests, one or more per command (the in-process harness's, `tests/fuzz/argv.rs`).
const BASELINES: &[&str] = &[
    "simulate --steps 100 --out t2.csv",
    "simulate pendulum --method dopri5 --t-end 1 --out t2.npy --summary s.json",
    "simulate --method tao-2 --binding 50 --steps 10 --every 0 --event flip --event zero:theta1",
    "simulate oscillator --method dop853 --t-end 2 --output-dt 0.5 --rtol 1e-8 --plot p.png",
    "simulate --scenario s.toml --steps 10",
    "sweep --grid theta1=0:1:4 --steps 10 --out g2.npy",
    "sweep pendulum --grid theta=0:1:3 --t-end 0.1 --record final,energy-error --shard 1/2 --out h.npy",
    "fractal --grid theta1=0:1:4 --grid theta2=0:1:4 --t-max 0.1 --out-dir fr",
    "bifurcation --param drive_amplitude=1:1.5:3 --transient 0 --samples 2 --steps-per-period 4",
    "compare oscillator --dt 0.1 --t-end 1 --methods rk4,verlet",
    "convergence --t-end 0.5 --levels 2 --methods rk4",
    "stability --t-end 0.5 --methods euler",
    "work-precision --t-end 0.5 --methods rk4 --levels 2 --tol-levels 2",
    "period --dt 0.01 --max-amplitude 10",
    "animate --t-end 0.1 --fps 5 --size 160x160 --out a.gif",
    "divergence --t-end 0.1 --dt 0.01",
    "lyapunov --t-end 1 --transient 0 --renormalise 0.05 --dt 0.01",
    "poincare --count 1 --t-end 10",
    "plot t.csv --out p.png",
    "plot g.npy --out q.png",
    "plot t.npy --phase --energy --out r.svg",
    "merge s1.npy s2.npy --out m.npy",
    "report --gallery-list",
    "list methods",
    "completions bash",
    "man --out-dir man",
];

/// Values for flags: the edges of floats and counts, what Rust's parser reads silently as
/// something else, names misspelt, and paths inside the run's directory.
const VALUES: &[&str] = &[
    "",
    "0",
    "-0",
    "-1",
    "1",
    "2",
    "3",
    "0.5",
    "1e-3",
    "1e-320",
    "1e-400",
    "1e308",
    "1e400",
    "-1e400",
    "nan",
    "inf",
    "-inf",
    "0x10",
    "1,5",
    "٣",
    "😀",
    "10000000000000",
    "10000000000001",
    "18446744073709551616",
    "99999999999999999999",
    "1e3",
    "120deg",
    "pi",
    "-pi",
    "2*pi",
    "nandeg",
    "-",
    "--",
    "double",
    "pendulm",
    "rk4",
    "RK4",
    "dopri5",
    "tao-4",
    "gauss-legendre-6",
    "flip",
    "flip+",
    "zero:theta1",
    "section:theta1=0+",
    "section:theta1=nan",
    "zero:nope",
    "theta1=1e400",
    "theta1=0:1:0",
    "theta1=1:0:4",
    "theta1=0:1:99999999999999999999",
    "m1=1e300",
    "l=1e-13",
    "links=0",
    "links=65",
    "theta1",
    "rk4,rk4",
    "rk4,,verlet",
    "final,final",
    "0/0",
    "3/2",
    "1/18446744073709551616",
    "10x10",
    "0x0",
    "99999x99999",
    "t2.csv",
    "t.csv",
    "t.npy",
    "s.toml",
    "out/",
    "dir",
    "no/such/dir/x.csv",
    "/dev/null",
    "x.txt",
    "p.svg",
    "s1.npy",
    "s2.npy.json",
    ".",
    "a b.csv",
];

/// The files every run's directory starts with: made once by the real binary.
const FILES: &[&str] =
    &["s.toml", "t.csv", "t.npy", "g.npy", "g.json", "s1.npy", "s1.npy.json", "s2.npy", "s2.npy.json"];

/// A change to a command line, or to one of its input files.
#[derive(Debug, Clone)]
enum Mutation {
    /// A flag's value (the token after a `--flag`) replaced.
    Value(Index, String),
    /// A flag of any command added with a value.
    Add(String, String),
    Remove(Index),
    Duplicate(Index),
    Insert(Index, String),
    /// A byte of an input file changed (flipped, or the file cut there).
    File(Index, Index, u8),
}

fn mutation(flags: Vec<String>) -> BoxedStrategy<Mutation> {
    let value = prop_oneof![
        8 => select(VALUES).prop_map(str::to_owned),
        1 => "\\PC{0,12}",
        1 => any::<f64>().prop_map(|x| x.to_string()),
    ]
    .boxed();
    prop_oneof![
        6 => (any::<Index>(), value.clone()).prop_map(|(i, v)| Mutation::Value(i, v)),
        3 => (select(flags), value.clone()).prop_map(|(f, v)| Mutation::Add(f, v)),
        1 => any::<Index>().prop_map(Mutation::Remove),
        1 => any::<Index>().prop_map(Mutation::Duplicate),
        1 => (any::<Index>(), value).prop_map(|(i, v)| Mutation::Insert(i, v)),
        2 => (any::<Index>(), any::<Index>(), any::<u8>()).prop_map(|(f, at, b)| Mutation::File(f, at, b)),
    ]
    .boxed()
}

/// The long flags any command takes, from `--help` of each.
fn flags() -> Vec<String> {
    let mut flags = Vec::new();
    for sub in BASELINES.iter().map(|b| b.split_whitespace().next().unwrap()) {
        let out = binary().args([sub, "--help"]).output().unwrap();
        for word in String::from_utf8_lossy(&out.stdout).split_whitespace() {
            let word = word.trim_end_matches([',', '=']);
            if word.starts_with("--")
                && word.len() > 2
                && word[2..].chars().all(|c| c.is_ascii_lowercase() || c == '-')
            {
                flags.push(word.to_owned());
            }
        }
    }
    flags.sort();
    flags.dedup();
    flags
}

/// One run: a baseline and its mutations, applied.
fn case(base: &str, mutations: &[Mutation], template: &Path, dir: &Path) -> Vec<String> {
    let mut argv: Vec<String> = base.split_whitespace().map(str::to_owned).collect();
    for name in FILES {
        std::fs::copy(template.join(name), dir.join(name)).unwrap();
    }
    std::fs::create_dir(dir.join("dir")).unwrap();
    for m in mutations {
        let n = argv.len();
        match m {
            Mutation::Value(at, v) => {
                let slots: Vec<usize> = (1..n).filter(|&i| argv[i - 1].starts_with("--")).collect();
                if !slots.is_empty() {
                    argv[slots[at.index(slots.len())]] = v.clone();
                }
            }
            Mutation::Add(flag, v) => argv.extend([flag.clone(), v.clone()]),
            Mutation::Remove(at) if n > 1 => {
                argv.remove(1 + at.index(n - 1));
            }
            Mutation::Duplicate(at) if n > 1 => {
                let i = 1 + at.index(n - 1);
                argv.insert(i, argv[i].clone());
            }
            Mutation::Insert(at, v) => argv.insert(1 + at.index(n), v.clone()),
            Mutation::File(file, at, b) => {
                let path = dir.join(FILES[file.index(FILES.len())]);
                let mut bytes = std::fs::read(&path).unwrap();
                if !bytes.is_empty() {
                    let i = at.index(bytes.len());
                    match b % 4 {
                        0 => bytes.truncate(i),
                        _ => bytes[i] ^= 1 << (b % 8),
                    }
                }
                std::fs::write(&path, bytes).unwrap();
            }
            _ => {}
        }
    }
    argv
}

/// Files under `dir` that a run must not leave: the temporary files of `output.rs`.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if entry.file_type().is_ok_and(|t| t.is_dir()) {
            found.extend(temporaries(&path));
        } else if name.starts_with(".pendula-") && name.ends_with(".part") {
            found.push(path);
        }
    }
    found
}

/// What a run came to: its exit code, whether it was interrupted, its stderr.
struct Ran {
    code: Option<i32>,
    interrupted: bool,
    stderr: String,
}

fn run(argv: &[String], dir: &Path) -> Ran {
    let mut child = binary()
        .args(argv)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = child.stderr.take().unwrap();
    let drain = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = err.read_to_end(&mut v);
        v
    });
    let start = Instant::now();
    let mut interrupted = false;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        let waited = start.elapsed();
        if !interrupted && waited > TIME_LIMIT {
            // As a user's Ctrl-C would: the run must clean up and exit 143.
            let _ = Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
            interrupted = true;
        }
        if waited > TIME_LIMIT + GRACE {
            let _ = child.kill();
            break child.wait().unwrap();
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stderr = String::from_utf8_lossy(&drain.join().unwrap()).into_owned();
    Ran { code: status.code(), interrupted, stderr }
}

/// Makes [`FILES`] with the real binary.
fn template() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("s.toml"),
        "system = \"pendulum\"\ndt = 0.01\nsteps = 10\n[set]\ntheta = \"30deg\"\n",
    )
    .unwrap();
    for args in [
        "simulate --steps 20 --out t.csv",
        "simulate --steps 20 --out t.npy",
        "sweep --grid theta1=0:1:3 --grid theta2=0:1:2 --steps 5 --out g.npy --summary g.json",
        "sweep --grid theta1=0:1:4 --steps 10 --shard 1/2 --out s1.npy",
        "sweep --grid theta1=0:1:4 --steps 10 --shard 2/2 --out s2.npy",
    ] {
        let out = binary().args(args.split_whitespace()).current_dir(d).output().unwrap();
        assert!(out.status.success(), "{args}: {}", String::from_utf8_lossy(&out.stderr));
    }
    dir
}

#[test]
fn the_binary_ends_every_mutated_request_cleanly() {
    let total: u64 =
        std::env::var("PENDULA_FUZZ_CASES").ok().and_then(|t| t.trim().parse().ok()).unwrap_or(100_000);
    let cases = u32::try_from(total / 300).unwrap_or(u32::MAX).max(1);
    let template = template();
    let flags = flags();
    let began = Instant::now();
    let counts = std::sync::Mutex::new([0u64; 5]);
    // Two runners, each with its half of the cases and its own seed.
    let failures: Vec<String> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..2u8)
            .map(|half| {
                let (flags, template, counts) = (flags.clone(), template.path(), &counts);
                scope.spawn(move || {
                    let strategy = (select(BASELINES), vec(mutation(flags), 0..4));
                    let config = Config {
                        cases: cases.div_ceil(2),
                        failure_persistence: None,
                        max_shrink_iters: 64,
                        ..Config::default()
                    };
                    let mut seed = *b"pendula fuzz, end to end, seed 1";
                    seed[31] ^= half;
                    let mut runner =
                        TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
                    runner
                        .run(&strategy, |(base, mutations)| {
                            let dir = tempfile::tempdir().unwrap();
                            let argv = case(base, &mutations, template, dir.path());
                            let ran = run(&argv, dir.path());
                            let left = temporaries(dir.path());
                            let code = ran.code.unwrap_or(-1);
                            let slot = match code {
                                0 => 0,
                                1 => 1,
                                2 => 2,
                                _ if ran.interrupted => 3,
                                _ => 4,
                            };
                            counts.lock().unwrap()[slot] += 1;
                            let clean_exit = matches!(code, 0..=2) || (ran.interrupted && code == 143);
                            let panicked =
                                ran.stderr.contains("panicked") || ran.stderr.contains("RUST_BACKTRACE");
                            if !clean_exit || panicked || !left.is_empty() {
                                return Err(TestCaseError::fail(format!(
                                    "`pendula {}`: exit {:?}{}{}{}\n  stderr: {}",
                                    argv.join(" "),
                                    ran.code,
                                    if ran.interrupted { " (interrupted)" } else { "" },
                                    if panicked { ", panicked" } else { "" },
                                    if left.is_empty() { String::new() } else { format!(", left {left:?}") },
                                    ran.stderr.chars().take(2000).collect::<String>()
                                )));
                            }
                            Ok(())
                        })
                        .err()
                        .map(|e| e.to_string())
                })
            })
            .collect();
        handles.into_iter().filter_map(|h| h.join().unwrap()).collect()
    });
    let [ok, failed, refused, interrupted, other] = counts.into_inner().unwrap();
    let _ = std::io::Write::write_all(
        &mut std::io::stderr(),
        format!(
            "fuzz end to end: {} runs in {:.1} s: {ok} exit 0, {failed} exit 1, {refused} exit 2, {interrupted} interrupted past {TIME_LIMIT:?} (exit 143), {other} otherwise; {}\n",
            ok + failed + refused + interrupted + other,
            began.elapsed().as_secs_f64(),
            if failures.is_empty() { "no panic" } else { "FAILED" }
        )
        .as_bytes(),
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
