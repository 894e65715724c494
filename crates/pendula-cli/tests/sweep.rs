//! `pendula sweep` and `pendula merge` end to end: the grid's layout and cell centres,
//! recorded columns, bitwise determinism across thread counts, shards merged back to the
//! unsharded array, the scalar path for other systems and methods, and bad input.

use std::path::Path;

use assert_cmd::Command;
use ndarray::ArrayD;
use ndarray_npy::ReadNpyExt;
use tempfile::TempDir;

fn pendula(dir: &Path, args: &[&str]) -> assert_cmd::assert::Assert {
    Command::cargo_bin("pendula").unwrap().current_dir(dir).args(args).assert()
}

fn load(path: &Path) -> ArrayD<f64> {
    ArrayD::<f64>::read_npy(std::fs::File::open(path).unwrap()).unwrap()
}

fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
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
