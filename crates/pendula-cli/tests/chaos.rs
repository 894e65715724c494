//! The chaos commands end to end: `fractal` (array layout, flags, determinism across thread
//! counts, bad input), `lyapunov` (summary keys, spectrum, presets) and bad input, which
//! must exit with 2 and leave no file.

use ndarray::{ArrayD, IxDyn};
use ndarray_npy::ReadNpyExt;
use tempfile::TempDir;

use crate::util::{files, json, pendula};

/// Runs `args` in an empty directory: exit code 2 and nothing written; returns stderr.
fn refused(args: &[&str]) -> String {
    let dir = TempDir::new().unwrap();
    let out = pendula(dir.path(), args).code(2);
    assert!(files(dir.path()).is_empty(), "{args:?} left files");
    String::from_utf8_lossy(&out.get_output().stderr).into_owned()
}

#[test]
fn fractal_writes_times_flags_and_pictures_the_same_on_any_thread_count() {
    let dir = TempDir::new().unwrap();
    let args = |out: &'static str, threads: &'static str| {
        vec![
            "fractal",
            "--grid",
            "theta1=-pi:pi:48",
            "--grid",
            "theta2=-pi:pi:32",
            "--t-max",
            "10",
            "--threads",
            threads,
            "--out",
            out,
        ]
    };
    pendula(dir.path(), &[args("one.npy", "1"), vec!["--summary", "one.json"]].concat()).success();
    // Two threads even on a one-core machine, where more threads than cores need --allow-large.
    pendula(dir.path(), &[args("two.npy", "2"), vec!["--allow-large"]].concat()).success();
    for name in ["one.npy", "one.png", "one-converged.npy", "one-converged.png", "one.json"] {
        assert!(dir.path().join(name).is_file(), "{name} missing");
    }
    let one = std::fs::read(dir.path().join("one.npy")).unwrap();
    assert_eq!(one, std::fs::read(dir.path().join("two.npy")).unwrap(), "thread count changed the result");
    let times = ArrayD::<f64>::read_npy(&one[..]).unwrap();
    assert_eq!(times.shape(), &[32, 48]);
    let flags =
        ArrayD::<u8>::read_npy(std::fs::File::open(dir.path().join("one-converged.npy")).unwrap()).unwrap();
    assert_eq!(flags.shape(), &[32, 48]);
    let summary = json(&dir.path().join("one.json"));
    let unconverged = flags.iter().filter(|f| **f == 0).count();
    assert_eq!(summary["unconverged"], unconverged);
    assert_eq!(summary["pixels"], 48 * 32);
    // The centre pixel (θ₁ ≈ θ₂ ≈ 0) cannot flip; flip times lie in (0, t-max], some early.
    assert!(times[IxDyn(&[16, 24])].is_nan());
    assert!(times.iter().filter(|t| t.is_finite()).all(|t| *t > 0.0 && *t <= 10.0));
    assert!(times.iter().any(|t| *t < 1.0));
}

#[test]
fn fractal_bad_input_exits_2_and_writes_nothing() {
    let cases: &[&[&str]] = &[
        &["fractal", "--grid", "omega1=0:1:4"],
        &["fractal", "--grid", "theta1=1:0:4"],
        &["fractal", "--t-max", "0"],
        &["fractal", "--dt", "-0.1"],
        &["fractal", "--method", "gauss-legendre-4"],
        &["fractal", "--set", "damping=0.1"],
        &["fractal", "--set", "theta1=1"],
        &["fractal", "--out", "f.csv"],
        &["fractal", "--tolerance", "nan"],
        &["fractal", "--method", "tao-4", "--dt", "0.1"],
    ];
    for args in cases {
        let stderr = refused(args);
        assert!(
            stderr.contains("invalid") || stderr.contains("unknown") || stderr.contains("binding"),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn lyapunov_summary_and_spectrum() {
    let dir = TempDir::new().unwrap();
    pendula(
        dir.path(),
        &[
            "lyapunov",
            "--preset",
            "baker-gollub-chaotic-1.5",
            "--dt",
            "0.01",
            "--t-end",
            "500",
            "--transient",
            "100",
            "--spectrum",
            "--out-dir",
            "out",
            "--summary",
            "s.json",
        ],
    )
    .success();
    let s = json(&dir.path().join("s.json"));
    assert_eq!(s["system"], "driven-pendulum");
    let spectrum: Vec<f64> =
        s["tables"]["exponents"].as_array().unwrap().iter().map(|e| e["value"].as_f64().unwrap()).collect();
    assert_eq!(spectrum.len(), 2);
    assert!((spectrum[0] + spectrum[1] + 0.5).abs() < 1e-6, "sum {spectrum:?} must be -1/q");
    assert!(s["lambda_max"].as_f64().unwrap() > 0.0 && s["uncertainty"].as_f64().unwrap() > 0.0);
    assert!(dir.path().join("out/lyapunov.csv").is_file() && dir.path().join("out/lyapunov.png").is_file());
}

#[test]
fn lyapunov_bad_input_exits_2() {
    for args in [
        &["lyapunov", "--method", "tao-4"][..],
        &["lyapunov", "--t-end", "1"],
        &["lyapunov", "--dt", "0"],
        &["lyapunov", "--preset", "nope"],
        &["lyapunov", "pendulum", "--preset", "baker-gollub-chaotic"],
    ] {
        refused(args);
    }
}

#[test]
fn poincare_writes_the_section() {
    let dir = TempDir::new().unwrap();
    pendula(
        dir.path(),
        &[
            "poincare",
            "--energy",
            "-12",
            "--count",
            "4",
            "--t-end",
            "40",
            "--out-dir",
            "out",
            "--summary",
            "s.json",
        ],
    )
    .success();
    let s = json(&dir.path().join("s.json"));
    assert!(s["crossings"].as_u64().unwrap() > 4 * 5);
    assert!(s["max_energy_error"].as_f64().unwrap() < 1e-6);
    let csv = std::fs::read_to_string(dir.path().join("out/poincare.csv")).unwrap();
    assert!(csv.starts_with("orbit,t,theta2,p2,theta1,p1"), "{}", &csv[..40]);
    assert!(dir.path().join("out/poincare.png").is_file());
    // The symplectic route: fixed steps of Gauss–Legendre.
    pendula(
        dir.path(),
        &[
            "poincare",
            "--count",
            "2",
            "--t-end",
            "10",
            "--method",
            "gauss-legendre-4",
            "--dt",
            "0.002",
            "--out-dir",
            "gl",
        ],
    )
    .success();
}

#[test]
fn poincare_bad_input_exits_2() {
    for args in [
        &["poincare", "--section", "omega1=0"][..],
        &["poincare", "--count", "0"],
        &["poincare", "pendulum"],
        &["poincare", "--method", "rk4"],
        &["poincare", "--energy", "-100"],
        &["poincare", "--set", "damping=0.2"],
        &["poincare", "--t-end", "-1"],
    ] {
        refused(args);
    }
}

#[test]
fn bifurcation_csv_is_the_same_on_any_thread_count() {
    let dir = TempDir::new().unwrap();
    for (threads, out) in [("1", "one"), ("2", "two")] {
        pendula(
            dir.path(),
            &[
                "bifurcation",
                "--param",
                "drive_amplitude=1.0:1.5:40",
                "--samples",
                "20",
                "--transient",
                "300",
                "--threads",
                threads,
                // Two threads even on a one-core machine (more than the cores need it).
                "--allow-large",
                "--out-dir",
                out,
            ],
        )
        .success();
    }
    let one = std::fs::read_to_string(dir.path().join("one/bifurcation.csv")).unwrap();
    assert_eq!(one, std::fs::read_to_string(dir.path().join("two/bifurcation.csv")).unwrap());
    assert!(one.starts_with("drive_amplitude,sample,theta,omega\n"));
    assert_eq!(one.lines().count(), 1 + 40 * 20);
    assert!(dir.path().join("one/bifurcation.png").is_file());
    // The scalar path, for a driven double pendulum.
    pendula(
        dir.path(),
        &[
            "bifurcation",
            "double",
            "--set",
            "drive_frequency=3",
            "--set",
            "damping=0.5",
            "--param",
            "drive_amplitude=0:10:6",
            "--samples",
            "5",
            "--transient",
            "20",
            "--out-dir",
            "double",
        ],
    )
    .success();
    let csv = std::fs::read_to_string(dir.path().join("double/bifurcation.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 6 * 5);
}

#[test]
fn bifurcation_bad_input_exits_2() {
    for args in [
        &["bifurcation", "--param", "theta=0:1:4"][..],
        &["bifurcation", "--param", "q=2:1:4"],
        &["bifurcation", "double", "--param", "drive_amplitude=0:1:4"],
        &["bifurcation", "double"],
        &["bifurcation", "chain", "--param", "g=1:2:3"],
        &["bifurcation", "--samples", "0"],
        &["bifurcation", "--steps-per-period", "2"],
        &["bifurcation", "--variable", "p"],
        &["bifurcation", "--param", "drive_frequency=-1:1:4"],
    ] {
        refused(args);
    }
}

#[test]
fn chain_members_shape_sweeps_and_trajectories() {
    let dir = TempDir::new().unwrap();
    pendula(
        dir.path(),
        &["sweep", "chain", "--set", "links=3", "--grid", "theta3=-1:1:4", "--t-end", "1", "--out", "c.npy"],
    )
    .success();
    let a = ArrayD::<f64>::read_npy(std::fs::File::open(dir.path().join("c.npy")).unwrap()).unwrap();
    assert_eq!(a.shape(), &[4, 6]);
    pendula(dir.path(), &["simulate", "chain", "--set", "links=4", "--t-end", "1", "--out", "t.csv"])
        .success();
    let csv = std::fs::read_to_string(dir.path().join("t.csv")).unwrap();
    assert!(
        csv.starts_with("t,theta1,theta2,theta3,theta4,omega1,omega2,omega3,omega4,energy\n"),
        "{}",
        &csv[..80]
    );
    for args in [
        &["sweep", "chain", "--grid", "links=1:3:3", "--out", "x.npy"][..],
        &["simulate", "chain", "--set", "links=9"],
    ] {
        refused(args);
    }
}
