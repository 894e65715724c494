//! `pendula sweep`, `pendula merge` and `fractal --shard` end to end: the grid's layout and
//! cell centres, recorded columns, bitwise determinism across thread counts, shards merged
//! back to the unsharded array (and the fractal drawn from its shards), `--check` and
//! `--emit-slurm`, the scalar path for other systems and methods, and bad input.

use std::path::Path;

use ndarray::ArrayD;
use ndarray_npy::ReadNpyExt;
use tempfile::TempDir;

use crate::util::{files, pendula};

fn load(path: &Path) -> ArrayD<f64> {
    ArrayD::<f64>::read_npy(std::fs::File::open(path).unwrap()).unwrap()
}

/// Two axes: shape (N2, N1, 4), the first axis fastest, at the cell centres; with a step of
/// 1e-9 s the final state is the initial one to ~1e-8.
#[test]
fn grid_layout_and_cell_centres() {
    let dir = TempDir::new().unwrap();
    pendula(
        dir.path(),
        &[
            "sweep",
            "--grid",
            "theta1=-90deg:90deg:3",
            "--grid",
            "theta2=0:pi:2",
            "--dt",
            "1e-9",
            "--steps",
            "1",
        ],
    )
    .success();
    let a = load(&dir.path().join("sweep.npy"));
    assert_eq!(a.shape(), &[2, 3, 4]);
    let pi = std::f64::consts::PI;
    for j in 0..2 {
        for i in 0..3 {
            let t1 = -pi / 2.0 + (i as f64 + 0.5) * pi / 3.0;
            let t2 = (j as f64 + 0.5) * pi / 2.0;
            assert!((a[[j, i, 0]] - t1).abs() < 1e-8, "theta1 at [{j}, {i}]: {}", a[[j, i, 0]]);
            assert!((a[[j, i, 1]] - t2).abs() < 1e-8, "theta2 at [{j}, {i}]: {}", a[[j, i, 1]]);
        }
    }
}

/// The bench's W3 layout at a small size: --threads 1 and 2 give the same bytes, and so do
/// three shards merged; a missing or foreign shard is refused.
#[test]
fn threads_and_shards_give_the_same_bytes() {
    let dir = TempDir::new().unwrap();
    let base = [
        "sweep",
        "--method",
        "rk4",
        "--dt",
        "1e-2",
        "--steps",
        "300",
        "--grid",
        "theta1=-pi:pi:37",
        "--grid",
    ];
    let grid2 = "theta2=-pi:pi:23";
    let run = |extra: &[&str]| {
        let mut args: Vec<&str> = base.to_vec();
        args.push(grid2);
        args.extend_from_slice(extra);
        pendula(dir.path(), &args).success();
    };
    run(&["--threads", "1", "--out", "one.npy"]);
    // Two threads even on a one-core machine, where more threads than cores need --allow-large.
    run(&["--threads", "2", "--allow-large", "--out", "two.npy"]);
    for k in 1..=3 {
        let shard = format!("{k}/3");
        let out = format!("part{k}.npy");
        run(&["--shard", &shard, "--out", &out]);
    }
    let bytes = |name: &str| std::fs::read(dir.path().join(name)).unwrap();
    assert_eq!(bytes("one.npy"), bytes("two.npy"));
    assert_eq!(load(&dir.path().join("one.npy")).shape(), &[23, 37, 4]);
    pendula(dir.path(), &["merge", "part3.npy", "part1.npy", "part2.npy", "--out", "merged.npy"]).success();
    assert_eq!(bytes("merged.npy"), bytes("one.npy"));

    pendula(dir.path(), &["merge", "part1.npy", "part2.npy", "--out", "bad.npy"])
        .code(2)
        .stderr(predicates::str::contains("shard 3/3 is missing"));
    run(&["--shard", "1/3", "--out", "other.npy", "--record", "final,flip-time"]);
    pendula(dir.path(), &["merge", "other.npy", "part2.npy", "part3.npy", "--out", "bad.npy"])
        .code(2)
        .stderr(predicates::str::contains("another sweep"));
    assert!(!dir.path().join("bad.npy").exists());
}

/// Recorded columns: final, flip-time, energy-error in the order asked; --until flip stops
/// each cell at its flip; the simple pendulum (scalar path) flips exactly when it has the
/// energy to pass the top: ω₀² > 4 g / l.
#[test]
fn records_and_the_scalar_path() {
    let dir = TempDir::new().unwrap();
    pendula(
        dir.path(),
        &[
            "sweep",
            "pendulum",
            "--grid",
            "omega=4:8:8",
            "--set",
            "theta=0",
            "--dt",
            "1e-3",
            "--t-end",
            "5",
            "--until",
            "flip",
            "--record",
            "flip-time,energy-error,final",
        ],
    )
    .success();
    let a = load(&dir.path().join("sweep.npy"));
    assert_eq!(a.shape(), &[8, 4]);
    let threshold = (4.0 * 9.81_f64).sqrt(); // 6.26 rad/s
    for i in 0..8 {
        let omega = 4.0 + (i as f64 + 0.5) * 0.5;
        let flipped = !a[[i, 0]].is_nan();
        assert_eq!(flipped, omega > threshold, "omega {omega}: flip time {}", a[[i, 0]]);
        assert!(a[[i, 1]].abs() < 1e-6, "energy error {}", a[[i, 1]]);
        if flipped {
            assert!(a[[i, 2]].abs() > std::f64::consts::PI, "stopped past the top: {}", a[[i, 2]]);
        }
    }
    // A symplectic method on the double pendulum goes through the scalar path.
    pendula(
        dir.path(),
        &[
            "sweep",
            "double",
            "--method",
            "tao-4",
            "--dt",
            "2e-3",
            "--steps",
            "100",
            "--grid",
            "theta1=0:1:4",
            "--out",
            "t.npy",
        ],
    )
    .success();
    assert_eq!(load(&dir.path().join("t.npy")).shape(), &[4, 4]);
}

#[test]
fn bad_input_is_refused_with_exit_2_and_no_file() {
    for (args, needle) in [
        (&["sweep", "--grid", "phi=0:1:4"][..], "unknown name `phi`"),
        (&["sweep", "--grid", "theta1=0:1:0"][..], "number of cells must be >= 1"),
        (&["sweep", "--grid", "theta1=1:0:4"][..], "need finite LO < HI"),
        (&["sweep", "--grid", "theta1=0:1"][..], "expected NAME=LO:HI:N"),
        (&["sweep", "--grid", "theta1=0:1:4", "--grid", "theta1=0:2:4"][..], "given twice"),
        (&["sweep", "--grid", "l2=-1:1:4"][..], "l2"),
        (
            &["sweep", "--grid", "theta1=0:1:4", "--record", "speed"][..],
            "expected final, flip-time or energy-error",
        ),
        (&["sweep", "--grid", "theta1=0:1:4", "--shard", "0/2"][..], "--shard"),
        (&["sweep", "--grid", "theta1=0:1:4", "--shard", "5/5"][..], "more shards than the 4 cells"),
        (&["sweep", "--grid", "theta1=0:1:4", "--until", "rest"][..], "expected flip"),
        (&["sweep", "oscillator", "--grid", "x=0:1:4", "--until", "flip"][..], "no angle"),
        (&["sweep", "--grid", "theta1=0:1:4", "--threads", "0"][..], "--threads"),
        (&["sweep", "--grid", "theta1=0:1:4", "--out", "a.csv"][..], "writes .npy"),
        (&["sweep", "--grid", "theta1=0:1:4", "--method", "yoshida-4"][..], "separable"),
        (&["sweep", "--grid", "theta1=0:1:4", "--method", "dopri5"][..], "fixed steps"),
    ] {
        let dir = TempDir::new().unwrap();
        pendula(dir.path(), args).code(2).stderr(predicates::str::contains(needle));
        assert_eq!(files(dir.path()), Vec::<String>::new(), "{args:?} left files behind");
    }
}

/// `--shard K/N --check`: exit 0 for the shard this sweep wrote, and 2 naming what is wrong
/// for a missing file, another shard, another sweep, and a truncated or corrupted file;
/// nothing is computed or written.
#[test]
fn check_finds_missing_foreign_and_damaged_shards() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let run = ["sweep", "pendulum", "--grid", "theta=0:1:8", "--steps", "10"];
    let with = |extra: &[&'static str]| [&run[..], extra].concat();
    pendula(d, &with(&["--shard", "2/3", "--out", "s.npy", "--check"]))
        .code(2)
        .stderr(predicates::str::contains("shard 2/3: s.npy does not exist"));
    assert!(files(d).is_empty(), "--check wrote {:?}", files(d));
    pendula(d, &with(&["--shard", "2/3", "--out", "s.npy"])).success();
    pendula(d, &with(&["--shard", "2/3", "--out", "s.npy", "--check"]))
        .success()
        .stderr(predicates::str::contains("shard 2/3: s.npy holds it, intact"));
    pendula(d, &with(&["--shard", "1/3", "--out", "s.npy", "--check"]))
        .code(2)
        .stderr(predicates::str::contains("s.npy is shard 2/3 of this sweep"));
    pendula(d, &[&run[..4], &["--steps", "11", "--shard", "2/3", "--out", "s.npy", "--check"]].concat())
        .code(2)
        .stderr(predicates::str::contains("is a shard of another run"));
    let bytes = std::fs::read(d.join("s.npy")).unwrap();
    let mut flipped = bytes.clone();
    *flipped.last_mut().unwrap() ^= 1;
    std::fs::write(d.join("s.npy"), &flipped).unwrap();
    pendula(d, &with(&["--shard", "2/3", "--out", "s.npy", "--check"]))
        .code(2)
        .stderr(predicates::str::contains("the file is corrupted"));
    std::fs::write(d.join("s.npy"), &bytes[..bytes.len() - 8]).unwrap();
    pendula(d, &with(&["--shard", "2/3", "--out", "s.npy", "--check"]))
        .code(2)
        .stderr(predicates::str::contains("the file is truncated"));
    // Without --shard there is no shard to check.
    pendula(d, &with(&["--check"])).code(2).stderr(predicates::str::contains("--shard"));
}

/// `--emit-slurm N` writes only the script (no array), whose run reproduces the sweep's own
/// flags; its flags' bad values are refused with exit 2, naming them, and no file is left.
#[test]
fn emit_slurm_writes_the_script_and_refuses_bad_flags() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let run =
        ["sweep", "double", "--grid", "theta1=-pi:pi:4", "--set", "m2=2", "--steps", "5", "--out", "g.npy"];
    let with = |extra: &[&'static str]| [&run[..], extra].concat();
    for (extra, says) in [
        (&["--emit-slurm", "0"][..], "invalid value `0` for --emit-slurm"),
        (&["--emit-slurm", "5"], "invalid --emit-slurm 5: more shards than the 4 cells"),
        (&["--emit-slurm", "2", "--partition", "a;rm"], "invalid --partition `a;rm`"),
        (&["--emit-slurm", "2", "--time", "1h"], "invalid --time `1h`"),
        (&["--emit-slurm", "2", "--cpus", "0"], "invalid value `0` for --cpus"),
        (&["--cpus", "2"], "--emit-slurm"),
        (&["--emit-slurm", "2", "--shard", "1/2"], "cannot be used with"),
    ] {
        pendula(d, &with(extra)).code(2).stderr(predicates::str::contains(says));
        assert!(files(d).is_empty(), "{extra:?} left {:?}", files(d));
    }
    pendula(d, &with(&["--emit-slurm", "2", "--partition", "short", "--time", "0-01:00:00", "--cpus", "3"]))
        .success();
    assert_eq!(files(d), ["g.slurm"]);
    let script = std::fs::read_to_string(d.join("g.slurm")).unwrap();
    for line in [
        "#SBATCH --partition=short",
        "#SBATCH --time=0-01:00:00",
        "#SBATCH --cpus-per-task=3",
        "run() { \"$PENDULA\" sweep 'double' '--steps' '5' '--grid' 'theta1=-pi:pi:4' '--set' 'm2=2' \"$@\"; }",
        "N=2",
        "--dependency=\"afterok:$array\" --kill-on-invalid-dep=yes",
    ] {
        assert!(script.contains(line), "the script lacks {line:?}:\n{script}");
    }
    // The script is valid bash, and refuses being given to sbatch as a job.
    let syntax = std::process::Command::new("bash").arg("-n").arg(d.join("g.slurm")).status().unwrap();
    assert!(syntax.success());
    let as_job =
        std::process::Command::new("bash").arg(d.join("g.slurm")).env("SLURM_JOB_ID", "1").output().unwrap();
    assert_eq!(as_job.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&as_job.stderr).contains("not sbatch"));
}

/// `fractal --shard K/N` and `--merge-shards`: the four files drawn from three shards are
/// the unsharded fractal's, byte for byte; shards of another fractal are refused, naming
/// one; `pendula merge` reads them as a (n2, n1, 2) array of the flip times; `--emit-slurm`
/// writes a script that draws with `--merge-shards`.
#[test]
fn fractal_shards_draw_the_same_files() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let run = ["fractal", "--grid", "theta1=-3:3:20", "--grid", "theta2=-3:3:15", "--t-max", "6"];
    let with = |extra: &[&'static str]| [&run[..], extra].concat();
    pendula(d, &with(&["--out", "whole.npy"])).success();
    for (k, out) in [("1/3", "s1.npy"), ("2/3", "s2.npy"), ("3/3", "s3.npy")] {
        pendula(d, &with(&["--shard", k, "--out", out])).success();
        pendula(d, &with(&["--shard", k, "--out", out, "--check"])).success();
    }
    pendula(d, &with(&["--merge-shards", "s3.npy", "s1.npy", "s2.npy", "--out", "drawn.npy"])).success();
    for (a, b) in [
        ("whole.npy", "drawn.npy"),
        ("whole.png", "drawn.png"),
        ("whole-converged.npy", "drawn-converged.npy"),
        ("whole-converged.png", "drawn-converged.png"),
    ] {
        assert_eq!(std::fs::read(d.join(a)).unwrap(), std::fs::read(d.join(b)).unwrap(), "{a} and {b}");
    }
    let other = ["fractal", "--grid", "theta1=-3:3:20", "--grid", "theta2=-3:3:15", "--t-max", "7"];
    pendula(d, &[&other[..], &["--merge-shards", "s1.npy", "s2.npy", "s3.npy", "--out", "x.npy"]].concat())
        .code(2)
        .stderr(predicates::str::contains("s1.npy is a shard of another fractal"));
    assert!(!d.join("x.npy").exists() && !d.join("x.png").exists());
    pendula(d, &with(&["--merge-shards", "s1.npy", "s2.npy", "--out", "x.npy"]))
        .code(2)
        .stderr(predicates::str::contains("shard 3/3 is missing"));
    pendula(d, &["merge", "s1.npy", "s2.npy", "s3.npy", "--out", "raw.npy"]).success();
    let raw = load(&d.join("raw.npy"));
    let whole = load(&d.join("whole.npy"));
    assert_eq!(raw.shape(), &[15, 20, 2]);
    for (r, w) in raw.index_axis(ndarray::Axis(2), 0).iter().zip(whole.iter()) {
        assert!(r.to_bits() == w.to_bits(), "{r} against {w}");
    }
    pendula(d, &with(&["--shard", "1/3"])).code(2).stderr(predicates::str::contains("--out"));
    pendula(d, &with(&["--emit-slurm", "3", "--out", "f.npy"])).success();
    let script = std::fs::read_to_string(d.join("f.slurm")).unwrap();
    assert!(script.contains("run --merge-shards \"$SHARDS\"/shard-{1..3}.npy --out \"$OUT\""), "{script}");
}

/// Shards computed on CPUs that round differently (with and without fused multiply-adds, as
/// their descriptions say) are merged with a warning naming one of each: the array is right,
/// but not bitwise what one machine computes.
#[test]
fn merging_shards_from_fma_and_plain_cpus_warns() {
    use predicates::prelude::*;
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let run = ["sweep", "pendulum", "--grid", "theta=0:1:6", "--steps", "10"];
    for (k, out) in [("1/2", "a.npy"), ("2/2", "b.npy")] {
        pendula(d, &[&run[..], &["--shard", k, "--out", out]].concat()).success();
    }
    pendula(d, &["merge", "a.npy", "b.npy", "--out", "same.npy"])
        .success()
        .stderr(predicates::str::contains("warning").not());
    let path = d.join("b.npy.json");
    let mut doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let fma = doc["fma"].as_bool().expect("the description says whether the CPU had FMA");
    doc["fma"] = serde_json::Value::Bool(!fma);
    std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    pendula(d, &["merge", "a.npy", "b.npy", "--out", "mixed.npy"])
        .success()
        .stderr(predicates::str::contains("round differently"))
        .stderr(predicates::str::contains("a.npy").and(predicates::str::contains("b.npy")));
    assert_eq!(std::fs::read(d.join("same.npy")).unwrap(), std::fs::read(d.join("mixed.npy")).unwrap());
}
