//! A full disk, for real: every command that writes, with its outputs on a private 64 KiB
//! tmpfs filled to the last page, fails with exit 1 (the environment failed, see
//! `cli::EXIT_CODES`), says "No space left on device" naming the output's path, and leaves
//! every directory exactly as it was: no partial or temporary file, no new directory, and the
//! earlier file of the same name byte for byte. A private /dev/full (mknod c 1 7) is the
//! other route to the same error, for outputs that are single files.
//!
//! Mounting and mknod need root. Without it the tests print that they are skipped and pass:
//! acceptable only because CI runs as root (.ci/run on the project's machines), where they
//! run. `report` is left out: it writes through the same study directories, but only after
//! minutes of computation.

use std::path::{Path, PathBuf};
use std::process::Command;

use tempfile::TempDir;

use crate::util::{PRECIOUS, is_root, run, snapshot};

/// A 64 KiB tmpfs mounted on `path`, unmounted when dropped (also when a test fails).
struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(path: PathBuf) -> Self {
        std::fs::create_dir(&path).unwrap();
        run(Command::new("mount").args(["-t", "tmpfs", "-o", "size=64k", "tmpfs"]).arg(&path));
        Tmpfs(path)
    }

    /// Empties the disk, writes the earlier file `precious` (a path in it), and fills what
    /// is left with a file of its own, to the last byte.
    fn prepare(&self, precious: &str) {
        for entry in std::fs::read_dir(&self.0).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() { std::fs::remove_dir_all(path) } else { std::fs::remove_file(path) }.unwrap();
        }
        let path = self.0.join(precious);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, PRECIOUS).unwrap();
        let mut filler = std::fs::File::create(self.0.join("filler")).unwrap();
        let chunk = [0xa5_u8; 512];
        loop {
            if let Err(e) = std::io::Write::write_all(&mut filler, &chunk) {
                assert_eq!(e.raw_os_error(), Some(28), "filling the disk: {e}");
                break;
            }
        }
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let done = Command::new("umount").arg(&self.0).status().is_ok_and(|s| s.success());
        if !done {
            // Busy (a child still holds a file): detach it now, it goes when released.
            let _ = Command::new("umount").arg("-l").arg(&self.0).status();
        }
    }
}

/// Runs `pendula args` in `dir`, expecting a full-disk failure naming `path`; the problems.
fn fails_full(dir: &Path, args: &[&str], path: &str) -> Vec<String> {
    let before = snapshot(dir);
    let out = Command::new(env!("CARGO_BIN_EXE_pendula")).args(args).current_dir(dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let mut problems = Vec::new();
    if out.status.code() != Some(1) {
        problems.push(format!("exit {:?}, expected 1", out.status.code()));
    }
    for fragment in ["No space left on device", path] {
        if !stderr.contains(fragment) {
            problems.push(format!("stderr lacks {fragment:?}"));
        }
    }
    if stderr.contains(".part") || stderr.contains("panicked") {
        problems.push("stderr names a temporary file or a panic".into());
    }
    let after = snapshot(dir);
    for (path, contents) in &after {
        match before.get(path) {
            None => problems.push(format!("{} created", path.display())),
            Some(c) if c != contents => problems.push(format!("{} changed", path.display())),
            _ => {}
        }
    }
    for path in before.keys().filter(|p| !after.contains_key(*p)) {
        problems.push(format!("{} lost", path.display()));
    }
    problems
        .into_iter()
        .map(|p| format!("`pendula {}`: {p}\n  stderr: {}", args.join(" "), stderr.trim()))
        .collect()
}

/// Inputs on the ordinary disk: a trajectory for `plot`, two shards for `merge`.
fn inputs(dir: &Path) {
    let pendula = |args: &str| {
        run(Command::new(env!("CARGO_BIN_EXE_pendula")).args(args.split_whitespace()).current_dir(dir));
    };
    pendula("simulate pendulum --t-end 1 --out x.csv");
    for k in 1..=2 {
        pendula(&format!("sweep --grid theta1=0:1:4 --t-end 0.1 --shard {k}/2 --out p{k}.npy"));
    }
}

/// (arguments, the earlier file on the disk, what the message names): every command that
/// writes, its outputs on the full disk at `disk/`.
const CASES: &[(&str, &str, &str)] = &[
    ("simulate pendulum --t-end 10 --out disk/x.csv", "x.csv", "--out disk/x.csv"),
    ("simulate pendulum --t-end 10 --out disk/x.npy", "x.npy", "--out disk/x.npy"),
    ("simulate pendulum --t-end 1 --every 0 --summary disk/s.json", "s.json", "--summary disk/s.json"),
    // The trajectory, on the ordinary disk, is not written either.
    ("simulate pendulum --t-end 1 --out t.csv --plot disk/p.png", "p.png", "--plot disk/p.png"),
    ("compare pendulum --methods rk4 --t-end 1 --out-dir disk/c", "c/energy.png", "--out-dir disk/c/"),
    // The study directory, on the ordinary disk, is neither written nor left behind.
    (
        "stability oscillator --methods euler --t-end 10 --out-dir s --summary disk/s.json",
        "s.json",
        "--summary disk/s.json",
    ),
    (
        "stability oscillator --methods euler --t-end 10 --out-dir disk/s",
        "s/stability.csv",
        "--out-dir disk/s/",
    ),
    (
        "convergence oscillator --methods rk4 --levels 3 --out-dir disk/cv",
        "cv/convergence.png",
        "--out-dir disk/cv/",
    ),
    (
        "work-precision oscillator --methods rk4 --levels 3 --out-dir disk/w",
        "w/work_precision.csv",
        "--out-dir disk/w/",
    ),
    ("period --max-amplitude 20 --out-dir disk/p", "p/period.csv", "--out-dir disk/p/"),
    ("oscillator-regimes --out-dir disk/r", "r/regimes.png", "--out-dir disk/r/"),
    ("divergence --t-end 2 --out-dir disk/d", "d/divergence.csv", "--out-dir disk/d/"),
    ("lyapunov --t-end 20 --out-dir disk/l", "l/lyapunov.png", "--out-dir disk/l/"),
    ("poincare --energy -12 --count 2 --t-end 20 --out-dir disk/q", "q/poincare.csv", "--out-dir disk/q/"),
    (
        "bifurcation --param drive_amplitude=1.0:1.5:8 --samples 5 --transient 20 --out-dir disk/b",
        "b/bifurcation.png",
        "--out-dir disk/b/",
    ),
    // A study directory that the run creates is removed again.
    (
        "fractal --grid theta1=-3:3:16 --grid theta2=-3:3:16 --t-max 1 --out-dir disk/new",
        "f.png",
        "--out-dir disk/new/",
    ),
    (
        "fractal --grid theta1=-3:3:16 --grid theta2=-3:3:16 --t-max 1 --out disk/f.npy",
        "f.png",
        "--out disk/f",
    ),
    ("sweep --grid theta1=0:1:16 --t-end 0.1 --out disk/s.npy", "s.npy", "--out disk/s.npy"),
    ("sweep --grid theta1=0:1:16 --t-end 0.1 --shard 1/2 --out disk/h.npy", "h.npy.json", "--out disk/h.npy"),
    ("merge p1.npy p2.npy --out disk/m.npy", "m.npy", "--out disk/m.npy"),
    ("plot x.csv --out disk/x.png", "x.png", "--out disk/x.png"),
    ("animate pendulum --t-end 1 --out disk/a.gif", "a.gif", "--out disk/a.gif"),
    ("man --out-dir disk/man", "man/pendula.1", "--out-dir disk/man/"),
    // Checkpointing runs: the partial trajectory, the checkpoint or its chunk file on the full
    // disk; nothing is left, here nor on the ordinary disk.
    (
        "simulate pendulum --t-end 10 --out disk/x.csv --checkpoint c.ckpt --checkpoint-every 1",
        "x.csv",
        "--out disk/x.csv",
    ),
    (
        "simulate pendulum --t-end 10 --out t.csv --checkpoint disk/c.ckpt --checkpoint-every 1",
        "c.earlier",
        "--checkpoint disk/c.ckpt",
    ),
    (
        "sweep --grid theta1=0:1:16 --t-end 0.1 --out s.npy --checkpoint disk/c.ckpt",
        "c.earlier",
        "--checkpoint disk/c.ckpt",
    ),
    (
        "fractal --grid theta1=-3:3:16 --grid theta2=-3:3:16 --t-max 1 --out f.npy --checkpoint disk/c.ckpt",
        "c.earlier",
        "--checkpoint disk/c.ckpt",
    ),
];

#[test]
fn every_command_that_writes_reports_a_full_disk_and_replaces_nothing() {
    if !is_root() {
        eprintln!("skipped: mounting a tmpfs needs root (CI runs as root)");
        return;
    }
    let work = TempDir::new().unwrap();
    inputs(work.path());
    let disk = Tmpfs::mount(work.path().join("disk"));
    let mut problems = Vec::new();
    for (args, precious, path) in CASES {
        disk.prepare(precious);
        let args: Vec<&str> = args.split_whitespace().collect();
        problems.extend(fails_full(work.path(), &args, path));
    }
    drop(disk);
    assert!(problems.is_empty(), "{} problems:\n{}", problems.len(), problems.join("\n"));
}

/// Outputs that are single files, onto a private /dev/full (`full`), beside an earlier
/// trajectory `x.csv` that the failed run must not replace.
const ONTO_FULL: &[&str] = &[
    "simulate pendulum --t-end 1 --out full",
    "simulate pendulum --t-end 1 --out x.csv --summary full",
    "simulate pendulum --t-end 1 --out x.csv --plot full.png",
    "stability oscillator --methods euler --t-end 10 --out-dir s --summary full",
    "fractal --grid theta1=-3:3:8 --grid theta2=-3:3:8 --t-max 1 --summary full",
    "sweep --grid theta1=0:1:4 --t-end 0.1 --out full.npy",
    "merge p1.npy p2.npy --out full.npy",
    "plot x.csv --out full.png",
    "animate pendulum --t-end 0.5 --out full.gif",
];

#[test]
fn a_full_device_node_fails_each_single_file_output_and_stays_a_node() {
    if !is_root() {
        eprintln!("skipped: mknod needs root (CI runs as root)");
        return;
    }
    let work = TempDir::new().unwrap();
    inputs(work.path());
    for name in ["full", "full.png", "full.npy", "full.gif"] {
        run(Command::new("mknod").arg(work.path().join(name)).args(["c", "1", "7"]));
    }
    let mut problems = Vec::new();
    for args in ONTO_FULL {
        let args: Vec<&str> = args.split_whitespace().collect();
        let flag = args.iter().position(|a| a.starts_with("full")).map(|i| args[i - 1]).unwrap();
        let target = args.iter().find(|a| a.starts_with("full")).unwrap();
        problems.extend(fails_full(work.path(), &args, &format!("cannot write {flag} {target}")));
    }
    assert!(problems.is_empty(), "{} problems:\n{}", problems.len(), problems.join("\n"));
}
