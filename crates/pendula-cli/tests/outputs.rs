//! Outputs end to end, on real processes: SIGINT, SIGTERM and SIGHUP leave no temporary file, no
//! directory made for the run and an existing output intact (simulate, sweep, fractal, animate
//! and a study command); `.npy` trajectories stream to the same values as CSV; `--summary -`
//! puts parseable JSON alone on stdout for every kind of command; a study directory re-run
//! holds only the new run's files.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ndarray::Array2;
use ndarray_npy::ReadNpyExt;
use tempfile::TempDir;

use crate::util::{PRECIOUS, binary, precious};

/// Names of the files under `dir`, recursively, relative to it, sorted.
fn tree(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                out.push(path.strip_prefix(root).unwrap().to_string_lossy().into_owned());
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// Temporary files (`.pendula-*.part`) anywhere under `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    tree(dir).into_iter().filter(|n| n.ends_with(".part")).collect()
}

/// Runs `pendula args` in `dir`, waits until it has created a temporary file (it is then
/// past its start and busy with the work), sends `signal` with /bin/kill and returns the exit
/// code.
fn interrupt(dir: &Path, args: &[&str], signal: &str) -> Option<i32> {
    let mut child =
        binary().args(args).current_dir(dir).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let start = Instant::now();
    while temporaries(dir).is_empty() {
        assert!(start.elapsed() < Duration::from_secs(20), "no temporary file appeared for {args:?}");
        assert!(child.try_wait().unwrap().is_none(), "{args:?} ended before the signal");
        std::thread::sleep(Duration::from_millis(5));
    }
    // Well into the work.
    std::thread::sleep(Duration::from_millis(300));
    assert!(child.try_wait().unwrap().is_none(), "{args:?} ended before the signal");
    let kill = Command::new("kill").args(["-s", signal, &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(&format!("interrupted by SIG{signal}")), "{args:?}: {stderr}");
    out.status.code()
}

// 10^8 rows, some 15 GB of CSV: over the output limit, asked for on purpose (it is
// interrupted long before), hence --allow-large.
const LONG_SIMULATE: [&str; 6] = ["simulate", "double", "--t-end", "100000", "--allow-large", "--out"];

#[test]
fn sigint_during_a_csv_simulate_leaves_the_existing_file_intact() {
    let dir = TempDir::new().unwrap();
    let existing = precious(dir.path(), "big.csv");
    let code = interrupt(dir.path(), &[&LONG_SIMULATE[..], &["big.csv"]].concat(), "INT");
    assert_eq!(code, Some(130));
    assert_eq!(temporaries(dir.path()), Vec::<String>::new());
    assert_eq!(std::fs::read(existing).unwrap(), PRECIOUS);
    assert_eq!(tree(dir.path()), ["big.csv"]);
}

#[test]
fn sigterm_during_an_npy_simulate_leaves_nothing() {
    let dir = TempDir::new().unwrap();
    let code = interrupt(dir.path(), &[&LONG_SIMULATE[..], &["big.npy"]].concat(), "TERM");
    assert_eq!(code, Some(143));
    assert_eq!(tree(dir.path()), Vec::<String>::new());
}

#[test]
fn sigterm_during_a_csv_simulate_with_a_summary_file() {
    let dir = TempDir::new().unwrap();
    let existing = precious(dir.path(), "run.json");
    let args = [&LONG_SIMULATE[..], &["big.csv", "--summary", "run.json"]].concat();
    assert_eq!(interrupt(dir.path(), &args, "TERM"), Some(143));
    assert_eq!(tree(dir.path()), ["run.json"]);
    assert_eq!(std::fs::read(existing).unwrap(), PRECIOUS);
}

#[test]
fn sigint_during_a_sweep_leaves_the_existing_array_intact() {
    let dir = TempDir::new().unwrap();
    let existing = precious(dir.path(), "sweep.npy");
    let args = ["sweep", "--grid", "theta1=-3:3:64", "--t-end", "100000", "--threads", "1"];
    assert_eq!(interrupt(dir.path(), &args, "INT"), Some(130));
    assert_eq!(tree(dir.path()), ["sweep.npy"]);
    assert_eq!(std::fs::read(existing).unwrap(), PRECIOUS);
}

#[test]
fn sigterm_during_a_fractal_leaves_the_existing_picture_intact() {
    let dir = TempDir::new().unwrap();
    let existing = precious(dir.path(), "pendula-out/fractal/fractal.png");
    let args = ["fractal", "--grid", "theta1=-3:3:64", "--grid", "theta2=-3:3:64", "--t-max", "100000"];
    assert_eq!(interrupt(dir.path(), &args, "TERM"), Some(143));
    assert_eq!(tree(dir.path()), ["pendula-out/fractal/fractal.png"]);
    assert_eq!(std::fs::read(existing).unwrap(), PRECIOUS);
}

#[test]
fn sigterm_during_a_sweep_shard_leaves_the_existing_array_and_description_intact() {
    let dir = TempDir::new().unwrap();
    let array = precious(dir.path(), "part.npy");
    let description = precious(dir.path(), "part.npy.json");
    let args = [
        "sweep",
        "--grid",
        "theta1=-3:3:64",
        "--t-end",
        "100000",
        "--threads",
        "1",
        "--shard",
        "1/2",
        "--out",
        "part.npy",
    ];
    assert_eq!(interrupt(dir.path(), &args, "TERM"), Some(143));
    assert_eq!(tree(dir.path()), ["part.npy", "part.npy.json"]);
    assert_eq!(std::fs::read(array).unwrap(), PRECIOUS);
    assert_eq!(std::fs::read(description).unwrap(), PRECIOUS);
}

/// The study directory the run created (two levels) goes with its temporary files.
#[test]
fn sigint_during_a_fractal_leaves_no_file_and_no_directory_it_made() {
    let dir = TempDir::new().unwrap();
    let args = [
        "fractal",
        "--grid",
        "theta1=-3:3:64",
        "--grid",
        "theta2=-3:3:64",
        "--t-max",
        "100000",
        "--out-dir",
        "new/f",
    ];
    assert_eq!(interrupt(dir.path(), &args, "INT"), Some(130));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "{:?}", tree(dir.path()));
}

const LONG_ANIMATE: [&str; 7] = ["animate", "pendulum", "--t-end", "100000", "--fps", "1", "--allow-large"];

#[test]
fn sigint_during_an_animation_leaves_the_existing_gif_intact() {
    let dir = TempDir::new().unwrap();
    let existing = precious(dir.path(), "a.gif");
    let args = [&LONG_ANIMATE[..], &["--out", "a.gif"]].concat();
    assert_eq!(interrupt(dir.path(), &args, "INT"), Some(130));
    assert_eq!(tree(dir.path()), ["a.gif"]);
    assert_eq!(std::fs::read(existing).unwrap(), PRECIOUS);
}

/// The default output's directory, made for the run, goes too.
#[test]
fn sigterm_during_an_animation_leaves_nothing() {
    let dir = TempDir::new().unwrap();
    assert_eq!(interrupt(dir.path(), &LONG_ANIMATE, "TERM"), Some(143));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "{:?}", tree(dir.path()));
}

#[test]
fn sighup_during_a_study_command_leaves_its_directory_and_summary_intact() {
    let dir = TempDir::new().unwrap();
    let figure = precious(dir.path(), "c/energy.png");
    let summary = precious(dir.path(), "s.json");
    let args = [
        "compare",
        "double",
        "--methods",
        "rk4",
        "--t-end",
        "100000",
        "--out-dir",
        "c",
        "--summary",
        "s.json",
    ];
    assert_eq!(interrupt(dir.path(), &args, "HUP"), Some(129));
    assert_eq!(tree(dir.path()), ["c/energy.png", "s.json"]);
    assert_eq!(std::fs::read(figure).unwrap(), PRECIOUS);
    assert_eq!(std::fs::read(summary).unwrap(), PRECIOUS);
}

/// The .npy trajectory (streamed, header written last) holds the CSV's rows exactly: CSV
/// prints each number in its shortest round-trip form.
#[test]
fn npy_trajectory_streams_the_csv_values() {
    let dir = TempDir::new().unwrap();
    for out in ["a.csv", "a.npy"] {
        let status = binary()
            .args(["simulate", "double", "--dt", "0.01", "--t-end", "3.005", "--every", "7", "--out", out])
            .current_dir(dir.path())
            .stderr(Stdio::null())
            .status()
            .unwrap();
        assert!(status.success());
    }
    let csv = std::fs::read_to_string(dir.path().join("a.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next().unwrap(), "t,theta1,theta2,omega1,omega2,energy");
    let rows: Vec<Vec<f64>> =
        lines.map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect()).collect();
    // 301 steps (the last one shortened): steps 0, 7, …, 294 and the last.
    assert_eq!(rows.len(), 44);
    let bytes = std::fs::read(dir.path().join("a.npy")).unwrap();
    let header = usize::from(u16::from_le_bytes([bytes[8], bytes[9]])) + 10;
    assert_eq!(header % 64, 0, "NPY 1.0 aligns the data to 64 bytes");
    assert_eq!(bytes.len(), header + 44 * 6 * 8);
    let npy = Array2::<f64>::read_npy(&bytes[..]).unwrap();
    assert_eq!(npy.dim(), (44, 6));
    for (i, row) in rows.iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            assert_eq!(npy[[i, j]].to_bits(), v.to_bits(), "row {i} column {j}");
        }
    }
    assert_eq!(npy[[43, 0]], 3.005);
}

/// Runs `pendula args` in `dir`; stdout must be one JSON document, and what the command says
/// for people is on stderr.
fn summary_on_stdout(dir: &Path, args: &[&str]) -> (serde_json::Value, String) {
    let out = binary().args(args).args(["--summary", "-"]).current_dir(dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{args:?}: {stderr}");
    let doc = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!("{args:?}: stdout is not JSON ({e}): {}", String::from_utf8_lossy(&out.stdout))
    });
    (doc, stderr)
}

#[test]
fn summary_dash_is_json_on_stdout_for_every_kind_of_command() {
    let dir = TempDir::new().unwrap();
    let (doc, stderr) =
        summary_on_stdout(dir.path(), &["simulate", "pendulum", "--t-end", "1", "--every", "0"]);
    assert_eq!(doc["system"], "pendulum");
    assert!(stderr.contains("energy:"), "{stderr}");

    let (doc, stderr) = summary_on_stdout(
        dir.path(),
        &["stability", "oscillator", "--methods", "euler,verlet", "--t-end", "10", "--out-dir", "s"],
    );
    let rows = doc["tables"]["stability"].as_array().unwrap();
    assert!(
        rows.iter().any(|r| r["method"] == "verlet" && r["largest_stable_dt"].as_f64().is_some()),
        "{doc}"
    );
    // The table went to stderr.
    assert!(stderr.contains("largest_stable_dt (s)"), "{stderr}");

    let (doc, _) = summary_on_stdout(dir.path(), &["sweep", "--grid", "theta1=0:1:4", "--t-end", "0.1"]);
    assert_eq!(doc["shape"], serde_json::json!([4, 4]));

    let (doc, stderr) = summary_on_stdout(
        dir.path(),
        &["fractal", "--grid", "theta1=-3:3:8", "--grid", "theta2=-3:3:8", "--t-max", "1", "--out-dir", "f"],
    );
    assert_eq!(doc["pixels"], 64);
    assert!(stderr.contains("fractal 8x8"), "{stderr}");
    // Nothing named `-` anywhere.
    assert!(tree(dir.path()).iter().all(|n| !n.ends_with('-')), "{:?}", tree(dir.path()));
}

#[test]
fn fractal_writes_into_its_study_directory_by_default() {
    let dir = TempDir::new().unwrap();
    let status = binary()
        .args(["fractal", "--grid", "theta1=-3:3:8", "--grid", "theta2=-3:3:8", "--t-max", "1"])
        .current_dir(dir.path())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(
        tree(dir.path()),
        [
            "pendula-out/fractal/.pendula-fractal.files",
            "pendula-out/fractal/fractal-converged.npy",
            "pendula-out/fractal/fractal-converged.png",
            "pendula-out/fractal/fractal.npy",
            "pendula-out/fractal/fractal.npy.json",
            "pendula-out/fractal/fractal.png",
        ]
    );
}

/// `compare` on one system and method set, then on another into the same directory: only the
/// second run's files are left, beside a file of the user's and another command's.
#[test]
fn a_rerun_removes_the_earlier_runs_files_and_nothing_else() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("c");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("phase_euler.png"), "mine too, same name as pendula's").unwrap();
    let compare = |system: &str, methods: &str| {
        let status = binary()
            .args(["compare", system, "--methods", methods, "--t-end", "1", "--out-dir", "c"])
            .current_dir(dir.path())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .unwrap();
        assert!(status.success());
        tree(&out)
    };
    let first = compare("double", "rk4,verlet");
    assert!(first.contains(&"phase_verlet.svg".to_owned()), "{first:?}");
    // Another command's run in the same directory is not compare's to tidy.
    let status = binary()
        .args(["stability", "oscillator", "--methods", "euler", "--t-end", "10", "--out-dir", "c"])
        .current_dir(dir.path())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    let second = compare("pendulum", "euler");
    let expected = [
        ".pendula-compare.files",
        ".pendula-stability.files",
        "energy.png",
        "energy.svg",
        "notes.txt",
        "phase_euler.png",
        "phase_euler.svg",
        "stability.csv",
        "stability.png",
        "stability.svg",
        "summary.csv",
        "trajectory.png",
        "trajectory.svg",
    ];
    assert_eq!(second, expected);
    assert_eq!(std::fs::read_to_string(out.join("notes.txt")).unwrap(), "mine");
    let manifest = std::fs::read_to_string(out.join(".pendula-compare.files")).unwrap();
    assert!(!manifest.contains("rk4") && manifest.contains("phase_euler.svg"), "{manifest}");
}
