//! `--checkpoint` and `pendula resume` end to end, on real processes: a run interrupted by
//! SIGINT at a random moment (delays from a seeded generator) and resumed writes the same
//! bytes and the same summary as a run never interrupted — for rk4 (the double pendulum's
//! fast path), gauss-legendre-4, tao-4 and adaptive dop853, each with events, 20 times; for
//! sweeps and fractals too. Checkpoints that cannot be continued are refused naming the file
//! (exit 2), a numerical failure on resume is exit 1 naming the time, and nothing is left
//! behind but the checkpoint and its partial file, and after the resume not even those.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use tempfile::TempDir;

use crate::util::{binary, files};

/// Runs `pendula args` in `dir` to its end.
fn run(dir: &Path, args: &[&str]) -> Output {
    binary().args(args).current_dir(dir).output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// splitmix64: the delays' generator, seeded so that a failure can be replayed.
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        (z ^ (z >> 31)) as f64 / u64::MAX as f64
    }
}

/// Starts `pendula args` in `dir`, waits until `started` exists (the run registered for
/// checkpoints and opened its files), waits `delay` more, sends SIGINT, and returns how the
/// process ended.
fn interrupt(dir: &Path, args: &[&str], started: &Path, delay: Duration) -> Output {
    let mut child =
        binary().args(args).current_dir(dir).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let begin = Instant::now();
    while !started.exists() && child.try_wait().unwrap().is_none() {
        assert!(begin.elapsed() < Duration::from_secs(30), "{args:?}: {} never appeared", started.display());
        std::thread::sleep(Duration::from_millis(1));
    }
    std::thread::sleep(delay);
    // The run may have ended by now (a delay near its end): then there is nothing to signal.
    if child.try_wait().unwrap().is_none() {
        let kill = Command::new("kill").args(["-s", "INT", &child.id().to_string()]).status().unwrap();
        assert!(kill.success());
    }
    child.wait_with_output().unwrap()
}

/// Whole files equal, byte for byte (reporting the first difference, not the contents).
fn assert_same_bytes(a: &Path, b: &Path, what: &str) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    if x != y {
        let at = x.iter().zip(&y).position(|(p, q)| p != q).unwrap_or(x.len().min(y.len()));
        panic!(
            "{what}: {} ({} bytes) and {} ({} bytes) differ at byte {at}",
            a.display(),
            x.len(),
            b.display(),
            y.len()
        );
    }
}

/// A summary without its wall time (which differs from run to run).
fn summary(path: &Path) -> serde_json::Value {
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    doc.as_object_mut().unwrap().remove("wall_s");
    doc
}

/// One method's case: arguments (without --out and --summary) and the output's extension.
struct Case {
    name: &'static str,
    args: &'static [&'static str],
    ext: &'static str,
}

const TRIALS: usize = 20;

/// The test: SIGINT at a random moment, then `resume`, 20 times per method, gives
/// the trajectory file and the summary (its `final` state, events, energy, counts) of the
/// run never interrupted. Periodic checkpoints (--checkpoint-every) are written on the way,
/// so the signal lands between them and after them. A trial whose run ended before its
/// signal still must match; the test asks that some trials of every method were interrupted.
#[test]
fn resume_after_sigint_gives_the_same_bytes() {
    let cases = [
        Case {
            name: "rk4",
            args: &[
                "--method",
                "rk4",
                "--dt",
                "0.001",
                "--t-end",
                "150",
                "--every",
                "3",
                "--event",
                "flip",
                "--event",
                "zero:theta2",
                "--checkpoint-every",
                "9",
            ],
            ext: "csv",
        },
        Case {
            name: "gauss-legendre-4",
            args: &[
                "--method",
                "gauss-legendre-4",
                "--dt",
                "0.01",
                "--t-end",
                "800",
                "--event",
                "zero:theta1",
                "--checkpoint-every",
                "47",
            ],
            ext: "npy",
        },
        Case {
            name: "tao-4",
            args: &[
                "--method",
                "tao-4",
                "--dt",
                "0.002",
                "--t-end",
                "150",
                "--event",
                "section:theta1=0+",
                "--checkpoint-every",
                "11",
            ],
            ext: "csv",
        },
        Case {
            name: "dop853",
            args: &[
                "--method",
                "dop853",
                "--rtol",
                "1e-11",
                "--atol",
                "1e-11",
                "--t-end",
                "2000",
                "--event",
                "flip",
                "--event",
                "zero:theta2",
                "--checkpoint-every",
                "130",
            ],
            ext: "npy",
        },
    ];
    std::thread::scope(|scope| {
        for (k, case) in cases.iter().enumerate() {
            scope.spawn(move || trials(case, 0x5eed_0000 + k as u64));
        }
    });
}

fn trials(case: &Case, seed: u64) {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let with = |out: &str, summary: &str, extra: &[&str]| -> Vec<String> {
        let mut a = vec!["simulate".to_owned(), "double".to_owned()];
        a.extend(case.args.iter().map(|s| s.to_string()));
        a.extend(["--out".into(), out.to_owned(), "--summary".into(), summary.to_owned()]);
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    // The reference, without --checkpoint (--checkpoint-every needs it: dropped here).
    let reference_out = format!("reference.{}", case.ext);
    let mut reference = with(&reference_out, "reference.json", &[]);
    let every = reference.iter().position(|a| a == "--checkpoint-every").unwrap();
    reference.drain(every..every + 2);
    let begin = Instant::now();
    let out = run(d, &reference.iter().map(String::as_str).collect::<Vec<_>>());
    // Only to size the delays: the signal lands within the first 60% of a run this long.
    let duration = begin.elapsed();
    assert!(out.status.success(), "{}: {}", case.name, stderr(&out));
    let mut rng = Rng(seed);
    let mut interrupted = 0;
    for trial in 0..TRIALS {
        let (out_name, json, ckpt) =
            (format!("t{trial}.{}", case.ext), format!("t{trial}.json"), format!("t{trial}.ckpt"));
        let args = with(&out_name, &json, &["--checkpoint", &ckpt]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let partial = d.join(format!("{out_name}.partial"));
        let delay = duration.mul_f64(0.6 * rng.uniform());
        let first = interrupt(d, &args, &partial, delay);
        let name = format!("{} trial {trial} (seed {seed:#x}, SIGINT {delay:?} after the start)", case.name);
        match first.status.code() {
            Some(130) => {
                interrupted += 1;
                let said = stderr(&first);
                assert!(
                    said.contains("checkpoint written to") && said.contains("pendula resume"),
                    "{name}: {said}"
                );
                // Left behind: the checkpoint and the partial trajectory, nothing else.
                let mut left = files(d);
                left.retain(|f| f.starts_with(&format!("t{trial}.")));
                assert_eq!(left, vec![ckpt.clone(), format!("{out_name}.partial")], "{name}");
                let resumed = run(d, &["resume", &ckpt]);
                assert!(resumed.status.success(), "{name}: {}", stderr(&resumed));
            }
            Some(0) => {}
            other => panic!("{name}: exit {other:?}: {}", stderr(&first)),
        }
        assert_same_bytes(&d.join(&reference_out), &d.join(&out_name), &name);
        let (a, b) = (summary(&d.join("reference.json")), summary(&d.join(&json)));
        assert_eq!(a["final"], b["final"], "{name}: final state");
        assert_eq!(a, b, "{name}: summary");
        let mut left = files(d);
        left.retain(|f| f.starts_with(&format!("t{trial}.")));
        let mut expected = vec![json.clone(), out_name.clone()];
        expected.sort();
        assert_eq!(left, expected, "{name}: the checkpoint and partial file are gone");
        std::fs::remove_file(d.join(&out_name)).unwrap();
    }
    eprintln!("{}: {interrupted} of {TRIALS} runs interrupted and resumed", case.name);
    assert!(interrupted > 0, "{}: no run was interrupted (all ended before their signal)", case.name);
}

/// dopri5 with --output-dt (rows from the dense output), and on the driven oscillator (the
/// energy balance's work integral) until a terminal event (--stop-on-event, at t ≈ 491 s);
/// rk4 on the damped pendulum (general path) with --plot (the kept rows read back from the
/// partial trajectory): resumed from a checkpoint, the run stopped by SIGINT sent as soon as
/// its first periodic checkpoint exists.
#[test]
fn resumed_grids_terminal_events_and_plots_match() {
    let cases: [&[&str]; 3] = [
        &[
            "double",
            "--method",
            "dopri5",
            "--rtol",
            "1e-10",
            "--atol",
            "1e-10",
            "--t-end",
            "600",
            "--output-dt",
            "0.01",
            "--event",
            "zero:theta1",
        ],
        &[
            "oscillator",
            "--set",
            "drive_amplitude=0.02",
            "--set",
            "drive_frequency=1",
            "--method",
            "dopri5",
            "--rtol",
            "1e-12",
            "--atol",
            "1e-12",
            "--t-end",
            "5000",
            "--output-dt",
            "0.002",
            "--event",
            "section:x=5",
            "--stop-on-event",
        ],
        &[
            "pendulum",
            "--set",
            "damping=0.05",
            "--method",
            "rk4",
            "--dt",
            "0.0005",
            "--t-end",
            "400",
            "--every",
            "2",
        ],
    ];
    for (k, case) in cases.iter().enumerate() {
        let dir = TempDir::new().unwrap();
        let d = dir.path();
        let plot: &[&str] = if k == 2 { &["--plot", "p.png"] } else { &[] };
        let whole = [&["simulate"], *case, &["--out", "whole.csv", "--summary", "whole.json"], plot].concat();
        let reference = run(d, &whole);
        assert!(reference.status.success(), "{case:?}: {}", stderr(&reference));
        if k == 2 {
            std::fs::rename(d.join("p.png"), d.join("whole.png")).unwrap();
        }
        let parts = [
            &["simulate"],
            *case,
            &[
                "--out",
                "part.csv",
                "--summary",
                "part.json",
                "--checkpoint",
                "c.ckpt",
                "--checkpoint-every",
                "1",
            ],
            plot,
        ]
        .concat();
        let first = interrupt(d, &parts, &d.join("c.ckpt"), Duration::ZERO);
        match first.status.code() {
            Some(130) => {
                let resumed = run(d, &["resume", "c.ckpt"]);
                assert!(resumed.status.success(), "{case:?}: {}", stderr(&resumed));
            }
            Some(0) => {}
            other => panic!("{case:?}: exit {other:?}: {}", stderr(&first)),
        }
        assert_same_bytes(&d.join("whole.csv"), &d.join("part.csv"), &format!("{case:?}"));
        assert_eq!(summary(&d.join("whole.json")), summary(&d.join("part.json")), "{case:?}");
        if k == 2 {
            assert_same_bytes(&d.join("whole.png"), &d.join("p.png"), "the plot");
        }
        assert!(!d.join("c.ckpt").exists() && !d.join("part.csv.partial").exists());
    }
}

/// A sweep and a fractal interrupted between chunks and resumed compute only the chunks
/// missing and write the bytes of the run never interrupted (and the fractal's pictures).
#[test]
fn sweeps_and_fractals_resume_to_the_same_bytes() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    // 256 x 256 cells in 64 chunks, some 1 s (sweep) and 2.5 s (fractal) on one thread: the
    // signal lands between chunks also on a fast machine (at 64 x 64, 4 chunks ran in less
    // than the 150 ms the signal waits, and the run had ended before it came).
    fn sweep(out: &str) -> Vec<String> {
        let args = "sweep --grid theta1=-pi:pi:256 --grid theta2=-pi:pi:256 --steps 2000 --threads 1 --record final,flip-time";
        args.split(' ').map(str::to_owned).chain(["--out".into(), out.to_owned()]).collect()
    }
    fn fractal(out: &str) -> Vec<String> {
        let args = "fractal --grid theta1=-pi:pi:256 --grid theta2=-pi:pi:256 --t-max 30 --threads 1";
        args.split(' ').map(str::to_owned).chain(["--out".into(), out.to_owned()]).collect()
    }
    type Make = fn(&str) -> Vec<String>;
    let commands: [(&str, Make, &[&str]); 2] = [
        ("sweep", sweep, &[".npy"]),
        ("fractal", fractal, &[".npy", ".png", "-converged.npy", "-converged.png"]),
    ];
    for (name, make, suffixes) in commands {
        let whole = make(&format!("{name}-whole.npy"));
        let reference = run(d, &whole.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(reference.status.success(), "{name}: {}", stderr(&reference));
        let ckpt = format!("{name}.ckpt");
        let mut args = make(&format!("{name}-part.npy"));
        args.extend(["--checkpoint".to_owned(), ckpt.clone()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        // The values file appears with the first checkpoint; the signal comes a chunk or two later.
        let first = interrupt(d, &args, &d.join(format!("{ckpt}.chunks")), Duration::from_millis(150));
        assert_eq!(first.status.code(), Some(130), "{name}: {}", stderr(&first));
        let said = stderr(&first);
        assert!(
            said.contains("chunks done")
                && said.contains(&format!("pendula resume {}", d.join(&ckpt).display())),
            "{said}"
        );
        assert!(!d.join(format!("{name}-part.npy")).exists());
        let resumed = run(d, &["resume", &ckpt]);
        assert!(resumed.status.success(), "{name}: {}", stderr(&resumed));
        for s in suffixes {
            assert_same_bytes(&d.join(format!("{name}-whole{s}")), &d.join(format!("{name}-part{s}")), name);
        }
        assert!(!d.join(&ckpt).exists() && !d.join(format!("{ckpt}.chunks")).exists(), "{:?}", files(d));
    }
}

/// Writes a checkpoint of a GL-4 run stopped by SIGINT and returns its directory; the run
/// takes long enough that the signal lands mid-way.
fn interrupted_run(args: &[&str]) -> (TempDir, PathBuf) {
    let dir = TempDir::new().unwrap();
    let first = interrupt(dir.path(), args, &dir.path().join("out.csv.partial"), Duration::from_millis(50));
    assert_eq!(first.status.code(), Some(130), "{}", stderr(&first));
    let path = dir.path().join("run.ckpt");
    (dir, path)
}

const LONG: &[&str] = &[
    "simulate",
    "double",
    "--method",
    "gauss-legendre-4",
    "--dt",
    "0.01",
    "--t-end",
    "5000",
    "--out",
    "out.csv",
    "--checkpoint",
    "run.ckpt",
];

/// A checkpoint that cannot be continued is refused with exit 2, naming the file and why:
/// missing, corrupt (a byte changed), of another format version, its partial trajectory
/// changed or cut, its arguments now validating to another request.
#[test]
fn checkpoints_that_cannot_be_continued_are_refused() {
    let refused = |dir: &Path, path: &Path, says: &str| {
        let out = run(dir, &["resume", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        let said = stderr(&out);
        assert!(said.contains(&path.display().to_string()) || said.contains("out.csv.partial"), "{said}");
        assert!(said.contains(says), "expected `{says}` in: {said}");
    };
    let (dir, path) = interrupted_run(LONG);
    let d = dir.path();
    refused(d, &d.join("none.ckpt"), "cannot read the checkpoint");
    let good = std::fs::read(&path).unwrap();
    let mut corrupt = good.clone();
    let at = corrupt.len() / 2;
    corrupt[at] ^= 1;
    std::fs::write(&path, &corrupt).unwrap();
    refused(d, &path, "do not match its checksum");
    let text = String::from_utf8(good.clone()).unwrap();
    std::fs::write(&path, text.replacen("pendula-checkpoint 1 ", "pendula-checkpoint 2 ", 1)).unwrap();
    refused(d, &path, "format version 2, and this pendula");
    std::fs::write(&path, b"hello\n").unwrap();
    refused(d, &path, "does not start with `pendula-checkpoint`");
    std::fs::write(&path, &good).unwrap();
    // The partial trajectory changed, then cut short.
    let partial = d.join("out.csv.partial");
    let rows = std::fs::read(&partial).unwrap();
    let mut changed = rows.clone();
    changed[100] = if changed[100] == b'1' { b'2' } else { b'1' };
    std::fs::write(&partial, &changed).unwrap();
    refused(d, &path, "does not match its checkpoint (checksum)");
    std::fs::write(&partial, &rows[..10]).unwrap();
    refused(d, &path, "cut short");
    // Still whole: it resumes, after all that.
    std::fs::write(&partial, &rows).unwrap();
    let out = run(d, &["resume", "run.ckpt"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(files(d), vec!["out.csv"]);

    // A scenario file changed since the checkpoint.
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.toml"), "dt = 0.01\nt_end = 5000.0\n").unwrap();
    let args = [
        "simulate",
        "double",
        "--method",
        "gauss-legendre-4",
        "--scenario",
        "s.toml",
        "--out",
        "out.csv",
        "--checkpoint",
        "run.ckpt",
    ];
    let first = interrupt(d, &args, &d.join("out.csv.partial"), Duration::from_millis(50));
    assert_eq!(first.status.code(), Some(130), "{}", stderr(&first));
    std::fs::write(d.join("s.toml"), "dt = 0.02\nt_end = 5000.0\n").unwrap();
    refused(d, &d.join("run.ckpt"), "was written for another request");
}

/// A run that fails after its checkpoint (explicit Euler on the oscillator grows until it
/// overflows) fails again on resume: exit 1 naming the time, and the checkpoint and the
/// partial trajectory are removed with it.
#[test]
fn a_numerical_failure_on_resume_is_exit_1_naming_the_time() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let args = [
        "simulate",
        "oscillator",
        "--method",
        "euler",
        // 0.02 s: the state overflows after some 3.5 million steps (0.1 s), so that the
        // interrupt lands before the failure (at 0.1 s it came within milliseconds of the
        // partial file appearing, and the interrupt often came too late).
        "--dt",
        "0.02",
        "--steps",
        "100000000",
        "--every",
        "1000",
        "--out",
        "out.npy",
        "--checkpoint",
        "run.ckpt",
    ];
    let whole = run(d, &args[..args.len() - 2]);
    assert_eq!(whole.status.code(), Some(1), "{}", stderr(&whole));
    let said = stderr(&whole);
    assert!(said.contains("non-finite at t = "), "{said}");
    let first = interrupt(d, &args, &d.join("out.npy.partial"), Duration::ZERO);
    assert_eq!(first.status.code(), Some(130), "{}", stderr(&first));
    let resumed = run(d, &["resume", "run.ckpt"]);
    assert_eq!(resumed.status.code(), Some(1), "{}", stderr(&resumed));
    // The same failure, at the same time.
    let time = |s: &str| s.split("non-finite at t = ").nth(1).unwrap().split(' ').next().unwrap().to_owned();
    assert_eq!(time(&stderr(&resumed)), time(&said));
    assert_eq!(files(d), Vec::<String>::new());
}

/// The flags are checked before any work: --checkpoint-every finite and > 0 and only with
/// --checkpoint, the checkpoint not one of the outputs nor `-`, no trajectory on stdout, no
/// existing checkpoint overwritten; nothing is written.
#[test]
fn checkpoint_flags_are_checked() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let base = ["simulate", "--steps", "10"];
    let cases: &[(&[&str], &str)] = &[
        (
            &["--checkpoint", "c", "--checkpoint-every", "0"],
            "invalid --checkpoint-every 0: must be finite and > 0",
        ),
        (&["--checkpoint", "c", "--checkpoint-every", "inf"], "invalid --checkpoint-every inf"),
        (&["--checkpoint", "c", "--checkpoint-every", "soon"], "invalid value `soon` for --checkpoint-every"),
        (&["--checkpoint-every", "1"], "--checkpoint"),
        (&["--checkpoint", "o.csv"], "it is also the --out file"),
        (&["--checkpoint", "o.csv.partial"], "it is also the --out partial"),
        (&["--checkpoint", "s.json", "--summary", "s.json"], "it is also the --summary file"),
        (&["--checkpoint", "-"], "invalid --checkpoint -"),
        (&["--checkpoint", "c", "--out", "-"], "--checkpoint needs the trajectory in a file"),
        (&["--checkpoint", "c", "--every", "0", "--plot", "p.png"], "--every 0 writes none"),
    ];
    for (extra, says) in cases {
        let out_flag: &[&str] = if extra.contains(&"--out") { &[] } else { &["--out", "o.csv"] };
        let out = run(d, &[&base[..], extra, out_flag].concat());
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(says), "{extra:?}: expected `{says}` in {}", stderr(&out));
        assert_eq!(files(d), Vec::<String>::new(), "{extra:?}");
    }
    std::fs::write(d.join("c"), "x").unwrap();
    let out = run(d, &[&base[..], &["--out", "o.csv", "--checkpoint", "c"]].concat());
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("it exists (from a run interrupted earlier?)"), "{}", stderr(&out));
    assert_eq!(files(d), vec!["c"]);
    assert_eq!(std::fs::read(d.join("c")).unwrap(), b"x");
    for command in [
        &["sweep", "--grid", "theta1=0:1:4", "--steps", "2", "--checkpoint", "sweep.npy"][..],
        &[
            "fractal",
            "--grid",
            "theta1=0:1:4",
            "--grid",
            "theta2=0:1:4",
            "--t-max",
            "1",
            "--out",
            "f.npy",
            "--checkpoint",
            "f.png",
        ],
    ] {
        let out = run(d, command);
        assert_eq!(out.status.code(), Some(2), "{command:?}: {}", stderr(&out));
        assert!(stderr(&out).contains("it is also the --out"), "{}", stderr(&out));
    }
    assert_eq!(files(d), vec!["c"]);
}

/// A checkpointing run never interrupted writes what a run without --checkpoint writes and
/// leaves no checkpoint. Two SIGINTs in a row end the process at once (the second does not
/// wait for the checkpoint): what is left is nothing, or a whole checkpoint with its partial
/// trajectory, which resumes to the same bytes — never a half-written checkpoint.
#[test]
fn checkpointing_runs_end_clean() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let base = ["simulate", "double", "--method", "tao-4", "--dt", "0.002", "--t-end", "60", "--out"];
    assert!(run(d, &[&base[..], &["a.npy"]].concat()).status.success());
    let with = [&base[..], &["b.npy", "--checkpoint", "c.ckpt", "--checkpoint-every", "0.5"]].concat();
    assert!(run(d, &with).status.success());
    assert_same_bytes(&d.join("a.npy"), &d.join("b.npy"), "with --checkpoint");
    assert_eq!(files(d), vec!["a.npy", "b.npy"]);
    std::fs::remove_file(d.join("b.npy")).unwrap();
    for delay in [0, 20, 60] {
        let child = binary().args(&with).current_dir(d).stderr(Stdio::piped()).spawn().unwrap();
        while !d.join("b.npy.partial").exists() {
            std::thread::sleep(Duration::from_millis(1));
        }
        std::thread::sleep(Duration::from_millis(delay));
        for _ in 0..2 {
            let _ = Command::new("kill").args(["-s", "INT", &child.id().to_string()]).status();
        }
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(130), "{}", stderr(&out));
        let left = files(d);
        if left == ["a.npy", "b.npy.partial", "c.ckpt"] {
            let resumed = run(d, &["resume", "c.ckpt"]);
            assert!(resumed.status.success(), "{}", stderr(&resumed));
            assert_same_bytes(&d.join("a.npy"), &d.join("b.npy"), "resumed after two signals");
            std::fs::remove_file(d.join("b.npy")).unwrap();
        } else {
            assert_eq!(left, vec!["a.npy"], "delay {delay} ms: {}", stderr(&out));
        }
    }
}
