//! The `pendula` binary end to end: outputs, and every invalid input with its message, exit
//! code, and no file left behind.

// Reference values are pasted with the digits their source printed.
#![allow(clippy::excessive_precision)]

use std::path::Path;

use predicates::prelude::*;
use tempfile::TempDir;

use crate::util::{files, pendula_in, svg_texts};

/// `simulate double --method rk4` takes the ensemble engine's single-trajectory kernel
/// (polynomial sine/cosine): at t = 10 s it is within 1e-10 of the bench's C reference (glibc;
/// the library's general path matches it bit for bit, tests/schedule.rs), as the bench's own
/// check allows for another sine; its energy error is as small as the general path's.
#[test]
fn fast_rk4_path_agrees_with_the_c_reference() {
    let dir = TempDir::new().unwrap();
    let out = pendula_in(dir.path())
        .args(["simulate", "double", "--method", "rk4", "--dt", "1e-3", "--t-end", "10", "--every", "0"])
        .args(["--summary", "-"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let s: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let reference = [-0.80261226093658078, -2.4815017590829602, -1.9522459590552914, -2.3287480204624753];
    for (name, want) in ["theta1", "theta2", "omega1", "omega2"].iter().zip(reference) {
        let got = s["final"][name].as_f64().unwrap();
        assert!((got - want).abs() < 1e-10, "{name}: {got} vs {want}");
    }
    assert_eq!(s["rhs_evals"], 40_000);
    let de = s["energy"]["max_abs_error"].as_f64().unwrap();
    assert!(de > 1e-9 && de < 1e-7, "{de}");
}

/// An angle far beyond the lanes' fast sine range, θ₁ = 1e17 rad, takes their exact reduction:
/// the rk4 fast path integrates it (it failed as non-finite after one step) and lands within
/// 1e-12 of mpmath's RK4 of the same run (`reference/huge_angle.py`: 1e17 cannot move in
/// doubles, an ulp there being 16 rad, so the run holds sin θ₁ = sin(θ₁ − θ₂) = sin 1e17 and
/// cos(θ₁ − θ₂) = cos 1e17 fixed; measured 4e-15 apart). The initial energy, through cos 1e17,
/// agrees as well.
#[test]
fn rk4_integrates_a_huge_angle() {
    let dir = TempDir::new().unwrap();
    let out = pendula_in(dir.path())
        .args(["simulate", "double", "--set", "theta1=1e17", "--method", "rk4", "--steps", "1000"])
        .args(["--dt", "1e-3", "--summary", "-"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let s: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(s["final"]["theta1"].as_f64(), Some(1e17));
    let reference = [0.0097752685823722570745, 3.9271890392764978593, -2.6229390247970755927];
    for (name, want) in ["theta2", "omega1", "omega2"].iter().zip(reference) {
        let got = s["final"][name].as_f64().unwrap();
        assert!((got - want).abs() < 1e-12, "{name}: {got} vs {want}");
    }
    let e0 = s["energy"]["initial"].as_f64().unwrap();
    assert!((e0 - 7.7136707241497529614).abs() < 1e-13, "initial energy {e0}");
}

#[test]
fn default_run_writes_trajectory_csv() {
    let dir = TempDir::new().unwrap();
    pendula_in(dir.path())
        .arg("simulate")
        .assert()
        .success()
        .stderr(predicate::str::contains("double with rk4: 10000 steps"));
    let text = std::fs::read_to_string(dir.path().join("trajectory.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,theta1,theta2,omega1,omega2,energy"));
    let first: Vec<f64> = lines.next().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    assert_eq!(
        first[..5],
        [0.0, 120f64 * std::f64::consts::PI / 180.0, -10f64 * std::f64::consts::PI / 180.0, 0.0, 0.0]
    );
    assert_eq!(text.lines().count(), 1 + 10_001);
    assert_eq!(text.lines().last().unwrap().split(',').next(), Some("10.0"));
}

#[test]
fn summary_json_has_the_documented_keys() {
    let dir = TempDir::new().unwrap();
    pendula_in(dir.path())
        .args(["simulate", "pendulum", "--method", "verlet", "--dt", "0.01", "--t-end", "2.005"])
        .args(["--set", "theta=170deg", "--every", "0", "--summary", "s.json"])
        .assert()
        .success();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
    for key in
        ["system", "method", "parameters", "dt", "steps", "rhs_evals", "t_end", "final", "energy", "wall_s"]
    {
        assert!(s.get(key).is_some(), "missing {key}");
    }
    assert_eq!(s["system"], "pendulum");
    assert_eq!(s["steps"], 201);
    assert_eq!(s["t_end"], 2.005);
    assert_eq!(s["final"]["t"], 2.005);
    // Explicit Verlet reuses its last force: one evaluation per step, plus the first.
    assert_eq!(s["rhs_evals"], 202);
    for key in ["initial", "final", "max_abs_error", "max_rel_error"] {
        assert!(s["energy"][key].is_f64(), "energy.{key}");
    }
    assert!(!dir.path().join("trajectory.csv").exists(), "--every 0 writes no trajectory");
}

#[test]
fn adaptive_run_reports_accepted_and_rejected_steps() {
    let dir = TempDir::new().unwrap();
    pendula_in(dir.path())
        .args([
            "simulate", "double", "--method", "dopri5", "--rtol", "1e-10", "--atol", "1e-10", "--t-end", "10",
        ])
        .args(["--every", "0", "--summary", "s.json"])
        .assert()
        .success();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
    assert_eq!(s["final"]["t"], 10.0);
    assert!(s["steps_accepted"].as_u64().unwrap() > 100);
    assert!(s["steps_rejected"].is_u64());
    assert!(s["rhs_evals"].as_u64().unwrap() >= 6 * s["steps_accepted"].as_u64().unwrap());
    assert!(s["dt"].is_null());
    // The bench's long-double reference at t = 10 s (shared/bench/SPEC.md, W2).
    let reference =
        [-0.80261199633036104544, -2.4815018039172568802, -1.9522456761809047925, -2.3287508056909700408];
    for (name, want) in ["theta1", "theta2", "omega1", "omega2"].iter().zip(reference) {
        let got = s["final"][name].as_f64().unwrap();
        assert!((got - want).abs() < 1e-5, "{name}: {got} vs {want}");
    }
}

#[test]
fn events_are_listed_in_the_summary() {
    let dir = TempDir::new().unwrap();
    pendula_in(dir.path())
        .args(["simulate", "pendulum", "--set", "theta=170deg", "--t-end", "12", "--event", "zero:theta"])
        .args(["--every", "0", "--summary", "s.json"])
        .assert()
        .success();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
    let events = s["events"].as_array().unwrap();
    assert!(events.len() >= 4);
    assert_eq!(events[0]["name"], "zero:theta");
    let period = events[2]["t"].as_f64().unwrap() - events[0]["t"].as_f64().unwrap();
    assert!((period / 4.893_524_274_105_486 - 1.0).abs() < 1e-9, "{period}");
    assert!(events[0]["state"]["theta"].as_f64().unwrap().abs() < 1e-10);

    pendula_in(dir.path())
        .args(["simulate", "double", "--t-end", "30", "--event", "flip", "--stop-on-event"])
        .args(["--every", "0", "--summary", "f.json"])
        .assert()
        .success();
    let f: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("f.json")).unwrap()).unwrap();
    let flips = f["events"].as_array().unwrap();
    assert_eq!(flips.len(), 1);
    let t_flip = flips[0]["t"].as_f64().unwrap();
    assert!(f["final"]["t"].as_f64().unwrap() - t_flip <= 1e-3 + 1e-12, "the run stops at the flip");
}

/// tao-4 with its binding constant: the default (200) and `--binding` go into the summary;
/// a binding where the map is unstable (ω h > 1), on a method without one, or not > 0 is
/// refused with exit code 2 and no file.
#[test]
fn tao_binding_is_a_checked_option() {
    let dir = TempDir::new().unwrap();
    pendula_in(dir.path())
        .args([
            "simulate",
            "double",
            "--method",
            "tao-4",
            "--t-end",
            "2",
            "--every",
            "0",
            "--summary",
            "a.json",
        ])
        .assert()
        .success();
    let a: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("a.json")).unwrap()).unwrap();
    assert_eq!(a["binding"], 200.0);
    assert!(a["energy"]["max_abs_error"].as_f64().unwrap() < 1e-3);
    pendula_in(dir.path())
        .args(["simulate", "double", "--method", "tao-2", "--binding", "50", "--dt", "0.01", "--t-end", "1"])
        .args(["--every", "0", "--summary", "b.json"])
        .assert()
        .success();
    let b: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("b.json")).unwrap()).unwrap();
    assert_eq!(b["binding"], 50.0);
    rejects(&["simulate", "--method", "tao-4", "--dt", "0.01"], &["binding * dt", "unstable above"]);
    rejects(&["simulate", "--method", "rk4", "--binding", "50"], &["binding", "tao-2 and tao-4 only"]);
    rejects(&["simulate", "--method", "tao-4", "--binding", "0"], &["binding", "> 0"]);
    rejects(&["simulate", "--method", "tao-4", "--binding", "abc"], &["--binding", "abc"]);
}

/// The integrators issue's check through the CLI: the period at 170° from `zero:theta` events
/// of dop853 at tight tolerance (located on its dense output) equals the exact one to 1e-9,
/// with the summary on stdout (`--summary -`).
#[test]
fn dop853_events_give_the_period_with_the_summary_on_stdout() {
    let dir = TempDir::new().unwrap();
    let out = pendula_in(dir.path())
        .args(["simulate", "pendulum", "--set", "theta=170deg", "--method", "dop853", "--rtol", "1e-12"])
        .args(["--atol", "1e-12", "--t-end", "12", "--event", "zero:theta", "--every", "0", "--summary", "-"])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let s: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let events = s["events"].as_array().unwrap();
    let period = events[2]["t"].as_f64().unwrap() - events[0]["t"].as_f64().unwrap();
    assert!((period / 4.893_524_274_105_486 - 1.0).abs() < 1e-9, "{period}");
    assert!(s["steps_accepted"].as_u64().unwrap() < 1000, "large adaptive steps");
    assert_eq!(files(dir.path()), Vec::<String>::new(), "no file named `-`");
    rejects(
        &["simulate", "--out", "-", "--summary", "-"],
        &["--out - and --summary - would both write to stdout"],
    );
}

#[test]
fn npy_output_has_rows_and_columns() {
    let dir = TempDir::new().unwrap();
    pendula_in(dir.path())
        .args(["simulate", "oscillator", "--steps", "100", "--every", "10", "--out", "x.npy"])
        .assert()
        .success();
    let a: ndarray::Array2<f64> = ndarray_npy::read_npy(dir.path().join("x.npy")).unwrap();
    assert_eq!(a.shape(), &[11, 4]);
    assert_eq!(a[[0, 1]], 1.0);
    assert!((a[[10, 0]] - 0.1).abs() < 1e-15);
}

#[test]
fn stdout_output_and_scenario_with_override() {
    let dir = TempDir::new().unwrap();
    std::fs::write(
        dir.path().join("s.toml"),
        "system = \"double\"\nmethod = \"verlet\"\ndt = 0.01\nsteps = 10\n[set]\ntheta1 = \"90deg\"\nm2 = 2\n",
    )
    .unwrap();
    let out = pendula_in(dir.path())
        .args([
            "simulate",
            "--scenario",
            "s.toml",
            "--set",
            "m2=3",
            "--steps",
            "4",
            "--out",
            "-",
            "--summary",
            "s.json",
        ])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8(out).unwrap();
    assert_eq!(text.lines().count(), 1 + 5);
    assert!(text.lines().nth(1).unwrap().starts_with("0.0,1.5707963267948966,-0.17453292519943295,0.0,0.0,"));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
    assert_eq!(s["method"], "verlet");
    assert_eq!(s["parameters"]["m2"], 3.0);
    assert_eq!(s["steps"], 4);
}

#[test]
fn list_shows_systems_and_methods() {
    let dir = TempDir::new().unwrap();
    pendula_in(dir.path()).args(["list", "systems"]).assert().success().stdout(
        predicate::str::contains("double")
            .and(predicate::str::contains("m/s^2"))
            .and(predicate::str::contains("120deg")),
    );
    pendula_in(dir.path()).args(["list", "methods"]).assert().success().stdout(
        predicate::str::contains("symplectic-euler")
            .and(predicate::str::contains("verlet"))
            .and(predicate::str::contains("rk4")),
    );
}

/// Runs `args` in an empty directory: exit code 2, the message contains every `needles`,
/// and the directory is still empty.
fn rejects(args: &[&str], needles: &[&str]) {
    rejects_with(args, needles, 2, &[]);
}

fn rejects_with(args: &[&str], needles: &[&str], code: i32, setup: &[(&str, &str)]) {
    let dir = TempDir::new().unwrap();
    for (name, text) in setup {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let before = files(dir.path());
    let assert = pendula_in(dir.path()).args(args).assert().code(code);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    for needle in needles {
        assert!(stderr.contains(needle), "{args:?}: `{needle}` not in: {stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(files(dir.path()), before, "{args:?} left files behind");
}

#[test]
fn non_positive_length_and_mass() {
    rejects(&["simulate", "pendulum", "--set", "l=-1"], &["-1", "`l`", "> 0"]);
    rejects(&["simulate", "double", "--set", "m2=0"], &["0", "`m2`", "> 0"]);
    rejects(&["simulate", "double", "--set", "l1=-0.5", "--out", "x.csv"], &["`l1`", "> 0"]);
}

#[test]
fn non_positive_dt_and_t_end() {
    rejects(&["simulate", "--dt", "0"], &["dt", "> 0"]);
    rejects(&["simulate", "--dt", "-0.1"], &["-0.1", "dt", "> 0"]);
    rejects(&["simulate", "--t-end", "-5"], &["-5", "t-end", "> 0"]);
    rejects(&["simulate", "--t-end", "0"], &["t-end", "> 0"]);
    rejects(&["simulate", "--steps", "0"], &["steps", ">= 1"]);
}

#[test]
fn nan_and_infinite_values() {
    rejects(&["simulate", "--set", "m1=nan"], &["NaN", "`m1`", "finite"]);
    rejects(&["simulate", "--set", "theta1=inf"], &["inf", "`theta1`", "finite"]);
    rejects(&["simulate", "--dt", "NaN"], &["NaN", "dt", "finite"]);
    rejects(&["simulate", "--t-end", "inf"], &["inf", "t-end", "finite"]);
}

#[test]
fn unknown_system_method_and_parameter_list_the_valid_names() {
    rejects(&["simulate", "triple"], &["unknown system `triple`", "oscillator, pendulum, double"]);
    rejects(
        &["simulate", "--method", "rk5"],
        &["unknown method `rk5`", "euler, rk4, symplectic-euler, verlet"],
    );
    rejects(
        &["simulate", "double", "--set", "theta3=1"],
        &["unknown name `theta3`", "m1, m2, l1, l2, g, damping, drive_amplitude, drive_frequency, theta1"],
    );
}

#[test]
fn unknown_events_are_rejected() {
    rejects(&["simulate", "pendulum", "--event", "zero:phi"], &["unknown name `phi`", "theta, omega"]);
    rejects(&["simulate", "oscillator", "--event", "flip"], &["flip", "no angle"]);
    rejects(
        &["simulate", "--event", "crossing"],
        &["`crossing`", "flip, zero:NAME[+|-], section:NAME=VALUE[+|-]"],
    );
    rejects(&["simulate", "--event", "flip+"], &["`flip+`", "flip has no direction"]);
}

#[test]
fn tolerance_flags_need_an_adaptive_method() {
    rejects(&["simulate", "--method", "rk4", "--rtol", "1e-8"], &["--rtol", "adaptive", "rk4"]);
    rejects(&["simulate", "--method", "dopri5", "--steps", "10"], &["--steps", "dopri5", "--t-end"]);
    rejects(&["simulate", "--method", "dopri5", "--rtol", "0"], &["rtol", "> 0"]);
    rejects(&["simulate", "--method", "dopri5", "--h-min", "1", "--h-max", "0.5"], &["h-max", "h-min"]);
}

#[test]
fn unparsable_values() {
    rejects(&["simulate", "--set", "theta1=abc"], &["`abc`", "theta1", "number", "deg"]);
    rejects(&["simulate", "--set", "theta1"], &["NAME=VALUE"]);
    rejects(&["simulate", "--set", "m1=2deg"], &["`m1`", "only for angles", "kg"]);
    rejects(&["simulate", "--dt", "fast"], &["`fast`", "--dt"]);
    rejects(&["simulate", "--steps", "1.5"], &["`1.5`", "--steps"]);
    rejects(&["simulate", "--every", "-1"], &["`-1`", "--every"]);
    rejects(&["simulate", "--t-end", "1", "--steps", "3"], &["cannot be used with"]);
}

#[test]
fn malformed_toml_names_its_line() {
    rejects_with(
        &["simulate", "--scenario", "bad.toml"],
        &["bad.toml", "line 3"],
        2,
        &[("bad.toml", "system = \"double\"\ndt = 0.01\nt_end = = 4\n")],
    );
    rejects_with(
        &["simulate", "--scenario", "typo.toml"],
        &["typo.toml", "unknown field `tend`"],
        2,
        &[("typo.toml", "tend = 4\n")],
    );
    rejects_with(
        &["simulate", "--scenario", "set.toml"],
        &["`theta9`"],
        2,
        &[("set.toml", "[set]\ntheta9 = 1\n")],
    );
    rejects(&["simulate", "--scenario", "missing.toml"], &["missing.toml"]);
}

#[test]
fn unwritable_output_paths() {
    rejects(&["simulate", "--out", "no/such/dir/x.csv"], &["--out", "no/such/dir/x.csv"]);
    rejects(&["simulate", "--summary", "no/such/dir/s.json"], &["--summary", "no/such/dir/s.json"]);
    rejects(&["simulate", "--out", "x.txt"], &["x.txt", ".csv, .npy"]);
}

#[test]
fn output_path_that_is_a_directory() {
    let dir = TempDir::new().unwrap();
    std::fs::create_dir(dir.path().join("d.csv")).unwrap();
    pendula_in(dir.path())
        .args(["simulate", "--out", "d.csv"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("directory"));
    assert_eq!(files(dir.path()), ["d.csv"]);
}

#[test]
fn unmet_requirement_is_explained() {
    rejects(
        &["simulate", "double", "--method", "yoshida-6"],
        &["yoshida-6 needs a separable Hamiltonian", "`double`", "not separable", "verlet"],
    );
    rejects(
        &["simulate", "pendulum", "--method", "verlet", "--set", "damping=0.3"],
        &["verlet", "Hamiltonian", "damping = 0.3", "try rk4"],
    );
}

/// A run whose state overflows fails with exit code 1, names the time, and writes nothing.
#[test]
fn non_finite_state_names_the_time_and_leaves_no_file() {
    rejects_with(
        &[
            "simulate",
            "oscillator",
            "--method",
            "euler",
            "--set",
            "k=1e300",
            "--dt",
            "1",
            "--out",
            "x.csv",
            "--summary",
            "s.json",
        ],
        &["non-finite", "t = 3 s"],
        1,
        &[],
    );
}

/// Existing data is not replaced by a failed run.
#[test]
fn failed_run_keeps_the_previous_file() {
    let dir = TempDir::new().unwrap();
    std::fs::write(dir.path().join("x.csv"), "precious").unwrap();
    pendula_in(dir.path())
        .args([
            "simulate",
            "oscillator",
            "--method",
            "euler",
            "--set",
            "k=1e300",
            "--dt",
            "1",
            "--out",
            "x.csv",
        ])
        .assert()
        .code(1);
    assert_eq!(std::fs::read_to_string(dir.path().join("x.csv")).unwrap(), "precious");
    assert_eq!(files(dir.path()), ["x.csv"]);
}

/// Stderr of a run that must fail with `code`.
fn stderr_of(args: &[&str], code: i32) -> String {
    let dir = TempDir::new().unwrap();
    let out = pendula_in(dir.path()).args(args).assert().code(code);
    String::from_utf8_lossy(&out.get_output().stderr).into_owned()
}

/// A misspelt name gets the valid name one edit away, and still the full list, exit 2.
#[test]
fn unknown_names_suggest_the_closest_valid_name() {
    let cases: &[(&[&str], &str)] = &[
        (&["simulate", "pendulm"], "unknown system `pendulm` (did you mean `pendulum`?)"),
        (&["simulate", "--method", "rk5"], "unknown method `rk5` (did you mean `rk4`?)"),
        (&["simulate", "--method", "RK4"], "(did you mean `rk4`?)"),
        (
            &["simulate", "pendulum", "--set", "thta=1"],
            "unknown name `thta` for system `pendulum` (did you mean `theta`?)",
        ),
        (&["simulate", "--preset", "baker-gollub-chaotc"], "(did you mean `baker-gollub-chaotic`?)"),
        (
            &["simulate", "pendulum", "--event", "zero:thta"],
            "unknown name `thta` for system `pendulum` (did you mean `theta`?)",
        ),
        (&["simulate", "--event", "flp"], "unknown name `flp` for system `double` (did you mean `flip`?)"),
        (&["simulate", "pendulum", "--event", "zeros:theta"], "(did you mean `zero:theta`?)"),
        (&["compare", "--methods", "euler,verlett"], "(did you mean `verlet`?)"),
        (&["sweep", "--grid", "theta=0:1:4"], "(did you mean `theta1` or `theta2`?)"),
        (&["sweep", "--grid", "theta1=0:1:2", "--record", "flip_time"], "(did you mean `flip-time`?)"),
        (&["poincare", "--section", "theta3=0"], "(did you mean `theta1` or `theta2`?)"),
        (&["bifurcation", "--variable", "omgea"], "(did you mean `omega`?)"),
    ];
    for (args, needle) in cases {
        let stderr = stderr_of(args, 2);
        assert!(stderr.contains(needle), "{args:?}: `{needle}` not in: {stderr}");
        assert!(
            stderr.contains("valid") || stderr.contains("expected"),
            "{args:?}: the valid names are gone: {stderr}"
        );
    }
    // Nothing is close to `triple` (four edits from `double`): no guess.
    let stderr = stderr_of(&["simulate", "triple"], 2);
    assert!(!stderr.contains("did you mean"), "{stderr}");
}

/// A bare angle beyond a full turn is radians, as documented, with a warning that names
/// the likelier degrees; within a turn, or with `deg`, there is none.
#[test]
fn bare_angle_beyond_a_turn_warns_once() {
    let run = |set: &str| {
        let dir = TempDir::new().unwrap();
        let out = pendula_in(dir.path())
            .args(["simulate", "double", "--steps", "1", "--every", "0", "--set", set])
            .assert()
            .success();
        String::from_utf8_lossy(&out.get_output().stderr).into_owned()
    };
    let stderr = run("theta1=120");
    // 120 / (2π) = 19.0986 turns.
    let warning = "warning: theta1=120 is 120 rad (19.1 turns); did you mean 120deg?";
    assert_eq!(stderr.matches(warning).count(), 1, "{stderr}");
    for quiet in ["theta1=2", "theta1=120deg", "theta1=-6.28", "m1=120"] {
        assert!(!run(quiet).contains("warning"), "{quiet}");
    }
    let dir = TempDir::new().unwrap();
    std::fs::write(dir.path().join("s.toml"), "[set]\ntheta2 = -30\n").unwrap();
    pendula_in(dir.path())
        .args(["simulate", "--scenario", "s.toml", "--steps", "1", "--every", "0"])
        .assert()
        .success()
        .stderr(predicate::str::contains("warning: theta2=-30 is -30 rad (-4.8 turns)"));
}

/// Times in messages are rounded for reading: Euler at h = 0.7 on the double pendulum
/// overflows at a step k where k · 0.7 in floating point is 7.699999999999999; the message
/// says t = 7.7 s (a whole number of steps, in at most 10 significant digits).
#[test]
fn non_finite_time_is_printed_short() {
    let stderr = stderr_of(
        &["simulate", "double", "--method", "euler", "--dt", "0.7", "--t-end", "100000", "--every", "0"],
        1,
    );
    let t = stderr.split("t = ").nth(1).and_then(|r| r.split(" s").next()).expect(&stderr);
    let k = t.parse::<f64>().unwrap() / 0.7;
    assert!((k - k.round()).abs() < 1e-9, "{t} is no whole number of steps: {stderr}");
    let digits = t.replace('.', "");
    assert!(digits.trim_start_matches('0').len() <= 10, "{t} is not short: {stderr}");
}

/// The resonance peak of the forced oscillator is where d/dΩ of 1/√((1 − r²)² + (2ζr)²)
/// vanishes: r = √(1 − 2ζ²), for ζ = 0.7 √0.02 = 0.141421..., with X k/F = 1/(2ζ√(1 − ζ²)).
#[test]
fn ref_resonance_peak_is_the_closed_form() {
    let dir = TempDir::new().unwrap();
    let out = pendula_in(dir.path())
        .args(["oscillator-regimes", "--out-dir", "r", "--summary", "r.json"])
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&out.get_output().stdout).into_owned();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("r.json")).unwrap()).unwrap();
    let peaks = s["tables"]["peaks"].as_array().unwrap();
    assert_eq!(peaks.len(), 4);
    for p in peaks {
        let zeta = p["zeta"].as_f64().unwrap();
        let ratio = p["drive_ratio"].as_f64().unwrap();
        assert!((ratio - (1.0 - 2.0 * zeta * zeta).sqrt()).abs() < 1e-12, "{p}");
        let amplitude = 1.0 / (2.0 * zeta * (1.0 - zeta * zeta).sqrt());
        assert!((p["amplitude_exact"].as_f64().unwrap() / amplitude - 1.0).abs() < 1e-12, "{p}");
        let simulated = p["amplitude_simulated"].as_f64().unwrap();
        assert!((simulated / amplitude - 1.0).abs() < 1e-6, "{p}");
    }
    let row = stdout.lines().find(|l| l.trim_start().starts_with("0.7 ")).expect(&stdout);
    assert!(row.contains("0.1414"), "{row}");
}

/// `--param` is named as `--param`, not as sweep's `--grid`.
#[test]
fn bifurcation_param_errors_name_param() {
    for param in ["1.5:1.5:1", "drive_amplitude=1.5:1.5:1", "drive_amplitude=1:1.5:x"] {
        let stderr = stderr_of(&["bifurcation", "--param", param], 2);
        assert!(
            stderr.contains(&format!("invalid --param `{param}`")) || stderr.contains("for --param"),
            "{stderr}"
        );
        assert!(!stderr.contains("--grid"), "{stderr}");
    }
}

/// The driven pendulum has no energy surface to cut: that is the error, not the section.
#[test]
fn poincare_of_the_driven_pendulum_says_why() {
    let stderr = stderr_of(&["poincare", "driven-pendulum"], 2);
    for needle in [
        "poincare needs a conservative system with two degrees of freedom",
        "1 degree of freedom",
        "damped",
        "no conserved energy surface",
    ] {
        assert!(stderr.contains(needle), "`{needle}` not in {stderr}");
    }
    assert!(!stderr.contains("--section"), "{stderr}");
}

/// A convergence study's smallest step is `--dt-min`, and is named so.
#[test]
fn step_range_errors_name_dt_min() {
    let stderr = stderr_of(&["convergence", "--dt-min", "1e-14", "--dt-max", "0.1", "--t-end", "1000"], 2);
    assert!(stderr.contains("invalid --dt-min 1e-14"), "{stderr}");
}

/// A value from a scenario file is named by its key there, one from a flag by the flag.
#[test]
fn schedule_errors_name_the_source_of_the_value() {
    rejects_with(
        &["simulate", "--scenario", "s.toml"],
        &["invalid t_end = -1 in the scenario file", "> 0"],
        2,
        &[("s.toml", "t_end = -1.0\n")],
    );
    rejects_with(
        &["simulate", "--scenario", "s.toml"],
        &["invalid dt = 0 in the scenario file"],
        2,
        &[("s.toml", "dt = 0.0\n")],
    );
    rejects_with(
        &["simulate", "--scenario", "s.toml", "--t-end", "-2"],
        &["invalid --t-end -2"],
        2,
        &[("s.toml", "t_end = 5.0\n")],
    );
}

/// The `--set` examples in each study command's help are for the system that command runs
/// (the one it defaults to, or the preset the help names): each runs on that system.
#[test]
fn set_help_examples_belong_to_the_command() {
    let commands: &[(&str, &[(&str, &str)])] = &[
        ("compare", &[("--set theta1=90deg --set m2=2", "double")]),
        ("convergence", &[("--set m=2", "oscillator")]),
        ("stability", &[("--set m=2", "pendulum")]),
        ("work-precision", &[("--set m=2", "pendulum")]),
        ("period", &[("--set m=2", "pendulum")]),
        ("energy-budget", &[("--set m1=2", "double")]),
        ("round-trip", &[("--set m=2", "pendulum")]),
        ("oscillator-regimes", &[("--set m=2", "oscillator")]),
        ("divergence", &[("--set m1=2", "double")]),
        ("lyapunov", &[("--set m1=2", "double"), ("--set q=4", "driven-pendulum")]),
        ("poincare", &[("--set m1=2", "double")]),
        ("bifurcation", &[("--set q=4", "driven-pendulum")]),
    ];
    let dir = TempDir::new().unwrap();
    for (command, examples) in commands {
        let out = pendula_in(dir.path()).args([command, "--help"]).assert().success();
        let help = String::from_utf8_lossy(&out.get_output().stdout)
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        // The --set paragraph: from its flag to the next one, --out-dir (both from study::Common).
        let paragraph = help.split("--set <NAME=VALUE> ").nth(1).expect(&help);
        let paragraph = paragraph.split(" --out-dir <DIR>").next().unwrap();
        let spans: Vec<&str> =
            paragraph.split('`').skip(1).step_by(2).filter(|s| s.starts_with("--set ")).collect();
        let listed: Vec<&str> = examples.iter().map(|(e, _)| *e).collect();
        assert_eq!(spans, listed, "{command}: {paragraph}");
        for (example, system) in *examples {
            let mut args = vec!["simulate", system, "--steps", "1", "--every", "0"];
            args.extend(example.split(' '));
            pendula_in(dir.path()).args(&args).assert().success();
        }
    }
}

/// Completion scripts for every shell clap_complete knows, naming the subcommands.
#[test]
fn completions_name_the_subcommands() {
    let dir = TempDir::new().unwrap();
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let out = pendula_in(dir.path()).args(["completions", shell]).assert().success();
        let script = String::from_utf8_lossy(&out.get_output().stdout).into_owned();
        for sub in ["simulate", "oscillator-regimes", "bifurcation", "completions", "method"] {
            assert!(script.contains(sub), "{shell}: no `{sub}`");
        }
    }
    assert_eq!(files(dir.path()), Vec::<String>::new());
    rejects(&["completions", "tcsh"], &["tcsh", "bash"]);
}

/// `man` prints the top page, or writes one roff page per command.
#[test]
fn man_pages_are_roff_for_every_command() {
    let dir = TempDir::new().unwrap();
    let out = pendula_in(dir.path()).arg("man").assert().success();
    let page = String::from_utf8_lossy(&out.get_output().stdout).into_owned();
    assert!(page.starts_with(".ie \\n(.g .ds Aq") || page.contains(".TH pendula 1"), "{page}");
    assert!(page.contains(".TH pendula 1") && page.contains("simulate"), "{page}");
    pendula_in(dir.path())
        .args(["man", "--out-dir", "man1"])
        .assert()
        .success()
        .stderr(predicate::str::contains("man1"));
    // The hidden manifest (which lets a re-run remove pages of commands that are gone) aside.
    let pages: Vec<String> =
        files(&dir.path().join("man1")).into_iter().filter(|f| f != ".pendula-man.files").collect();
    for name in ["pendula.1", "pendula-simulate.1", "pendula-oscillator-regimes.1", "pendula-man.1"] {
        assert!(pages.contains(&name.to_owned()), "{name} not in {pages:?}");
    }
    // One page per command and nothing else (no temporary files).
    let help = pendula_in(dir.path()).arg("--help").assert().success();
    let help = String::from_utf8_lossy(&help.get_output().stdout).into_owned();
    let commands = help
        .split("Commands:")
        .nth(1)
        .unwrap()
        .split("Options:")
        .next()
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("  ") && !l.starts_with("   ") && !l.trim_start().starts_with("help "))
        .count();
    assert_eq!(pages.len(), commands + 1, "{pages:?}");
    let simulate = std::fs::read_to_string(dir.path().join("man1/pendula-simulate.1")).unwrap();
    assert!(simulate.contains(".TH pendula-simulate 1") && simulate.contains("\\-\\-method"), "{simulate}");
}

/// Runs `pendula` in `dir` with `args`, expecting success, and returns the JSON summary it
/// printed on stdout (`--summary -`).
fn summary_of(dir: &Path, args: &[&str]) -> serde_json::Value {
    let out = pendula_in(dir).args(args).args(["--summary", "-"]).assert().success();
    serde_json::from_slice(&out.get_output().stdout).unwrap()
}

/// The last data row of a CSV file, as numbers.
fn last_row(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines().last().unwrap().split(',').map(|v| v.parse().unwrap()).collect()
}

/// `--stop-on-event` ends the run at the event itself: the pendulum released at rest from
/// 170° first passes θ = 0 at a quarter period, √(l/g) K(sin 85°) = 1.2233810685263715 s
/// (mpmath's period 4.893524274105486164 s over 4, as in the library's event tests). Both
/// an adaptive run (dop853 at 1e-13, located on its dense output) and a fixed-step one
/// (rk4, dt = 0.5 ms, on the cubic Hermite interpolant) end there to 1e-12 s: the summary's
/// t_end is the event's time (not the end of the step past it, up to a step later), its
/// `final` the event's state (θ ≈ 0), and so is the trajectory's last row.
#[test]
fn ref_stop_on_event_ends_at_the_event_time() {
    let quarter = 4.893524274105486164 / 4.0;
    for method in [
        &["--method", "dop853", "--rtol", "1e-13", "--atol", "1e-13"][..],
        &["--method", "rk4", "--dt", "5e-4"],
    ] {
        let dir = TempDir::new().unwrap();
        let mut args = vec!["simulate", "pendulum", "--set", "theta=170deg", "--t-end", "5"];
        args.extend_from_slice(method);
        args.extend_from_slice(&["--event", "zero:theta", "--stop-on-event", "--out", "t.csv"]);
        let s = summary_of(dir.path(), &args);
        let t_end = s["t_end"].as_f64().unwrap();
        assert!((t_end - quarter).abs() < 1e-12, "{method:?}: t_end {t_end} vs {quarter}");
        assert_eq!(s["events"][0]["t"].as_f64(), Some(t_end), "{method:?}");
        assert_eq!(s["final"]["t"].as_f64(), Some(t_end));
        let theta = s["final"]["theta"].as_f64().unwrap();
        assert!(theta.abs() < 1e-11, "{method:?}: final theta {theta}");
        let row = last_row(&dir.path().join("t.csv"));
        assert_eq!((row[0], row[1]), (t_end, theta), "{method:?}: the last row is the event");
    }
}

/// The fractal's flip times (ensemble engine, RK4 at dt = 0.01 s, and tao-4) are where `simulate`'s
/// flip event finds them with the same method and step (the scalar Hermite location): to
/// 1e-9 s at pixels that flip early (the engine's sine and cosine differ from glibc's by
/// ≤ 2 ulp, which a chaotic orbit amplifies over time). Before the flip times were
/// interpolated on the Hermite cubic they were off by up to ~5e-5 s.
#[test]
fn fractal_flip_times_agree_with_simulate_flip_events() {
    let dir = TempDir::new().unwrap();
    for (a, b) in [(-3.0_f64, -3.0_f64), (3.0, 0.5), (-2.5, 3.0)] {
        let axis = |name: &str, c: f64| format!("{name}={}:{}:1", c - 0.01, c + 0.01);
        pendula_in(dir.path())
            .args(["fractal", "--grid", &axis("theta1", a), "--grid", &axis("theta2", b), "--t-max", "5"])
            .args(["--out", "f.npy"])
            .assert()
            .success();
        let image: ndarray::Array2<f64> = ndarray_npy::read_npy(dir.path().join("f.npy")).unwrap();
        let fractal = image[[0, 0]];
        let s = summary_of(
            dir.path(),
            &[
                "simulate",
                "double",
                "--set",
                &format!("theta1={a}"),
                "--set",
                &format!("theta2={b}"),
                "--method",
                "rk4",
                "--dt",
                "0.01",
                "--t-end",
                "5",
                "--event",
                "flip",
                "--every",
                "0",
            ],
        );
        let event = s["events"][0]["t"].as_f64().unwrap();
        assert!(event < 2.0, "({a}, {b}) should flip early: {event}");
        assert!((fractal - event).abs() < 1e-9, "({a}, {b}): fractal {fractal} vs simulate {event}");
    }
    // Tao's map too: the lanes' θ' = ∂H/∂p at the ends of the step, as the scalar path shows.
    pendula_in(dir.path())
        .args(["fractal", "--method", "tao-4", "--dt", "0.004", "--t-max", "5", "--out", "t.npy"])
        .args(["--grid", "theta1=-3.01:-2.99:1", "--grid", "theta2=-3.01:-2.99:1"])
        .assert()
        .success();
    let image: ndarray::Array2<f64> = ndarray_npy::read_npy(dir.path().join("t.npy")).unwrap();
    let s = summary_of(
        dir.path(),
        &[
            "simulate",
            "double",
            "--set",
            "theta1=-3",
            "--set",
            "theta2=-3",
            "--method",
            "tao-4",
            "--dt",
            "0.004",
            "--t-end",
            "5",
            "--event",
            "flip",
            "--every",
            "0",
        ],
    );
    let event = s["events"][0]["t"].as_f64().unwrap();
    assert!((image[[0, 0]] - event).abs() < 1e-9, "tao-4: fractal {} vs simulate {event}", image[[0, 0]]);
}

/// `--output-dt`: an adaptive run's rows at t = 0, H, 2H, … and t_end exactly, from the
/// dense output; dopri5's (rtol 1e-6) agree with dop853's at 1e-12 on the same grid
/// (`--t-eval`) to the tolerance; and the run's statistics do not change.
#[test]
fn output_dt_writes_rows_on_the_grid_from_dense_output() {
    let dir = TempDir::new().unwrap();
    let run = |args: &[&str], out: &str| {
        pendula_in(dir.path())
            .args(["simulate", "pendulum", "--set", "theta=2", "--t-end", "2.1"])
            .args(args)
            .args(["--out", out])
            .assert()
            .success();
        let text = std::fs::read_to_string(dir.path().join(out)).unwrap();
        text.lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect::<Vec<Vec<f64>>>()
    };
    let coarse = run(&["--method", "dopri5", "--output-dt", "0.25"], "a.csv");
    let times: Vec<f64> = coarse.iter().map(|r| r[0]).collect();
    let mut expected: Vec<f64> = (0..9).map(|k| k as f64 * 0.25).collect();
    expected.push(2.1);
    assert_eq!(times, expected);
    let fine = run(
        &[
            "--method",
            "dop853",
            "--rtol",
            "1e-12",
            "--atol",
            "1e-12",
            "--t-eval",
            "0,0.25,0.5,0.75,1,1.25,1.5,1.75,2,2.1",
        ],
        "b.csv",
    );
    assert_eq!(fine.iter().map(|r| r[0]).collect::<Vec<_>>(), expected);
    for (a, b) in coarse.iter().zip(&fine) {
        assert!((a[1] - b[1]).abs() < 1e-4 && (a[2] - b[2]).abs() < 1e-4, "{a:?} vs {b:?}");
    }
    // The grid is not the steps: dopri5 at rtol 1e-6 takes more than 10 steps here.
    let steps = run(&["--method", "dopri5"], "c.csv").len();
    assert!(steps > 10, "{steps}");
}

#[test]
fn output_grid_flags_are_checked() {
    rejects(
        &["simulate", "--method", "rk4", "--output-dt", "0.1"],
        &["--output-dt", "adaptive", "rk4", "--every"],
    );
    rejects(&["simulate", "--method", "verlet", "--t-eval", "0,1"], &["adaptive", "verlet"]);
    rejects(&["simulate", "--method", "dopri5", "--output-dt", "0"], &["--output-dt 0", "> 0"]);
    rejects(&["simulate", "--method", "dopri5", "--output-dt", "-0.5"], &["--output-dt -0.5", "> 0"]);
    rejects(&["simulate", "--method", "dopri5", "--output-dt", "abc"], &["`abc`", "--output-dt"]);
    rejects(&["simulate", "--method", "dopri5", "--t-eval", "1,0.5"], &["--t-eval", "increase"]);
    rejects(
        &["simulate", "--method", "dopri5", "--t-eval", "0,20", "--t-end", "10"],
        &["--t-eval", "20", "after"],
    );
    rejects(&["simulate", "--method", "dopri5", "--output-dt", "0.1", "--every", "2"], &["--every"]);
    rejects(&["simulate", "--plot", "p.jpg"], &["--plot", "p.jpg", ".png or .svg"]);
}

/// `simulate --plot` draws three stacked panels (time series, phase portrait, energy error)
/// from the run's rows; `pendula plot` draws the saved trajectory (CSV or .npy) and a
/// fractal's grid.
#[test]
fn simulate_plot_and_pendula_plot_write_pictures() {
    let dir = TempDir::new().unwrap();
    let size = |name: &str| {
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(dir.path().join(name)).unwrap()));
        let info = decoder.read_info().unwrap();
        (info.info().width, info.info().height)
    };
    pendula_in(dir.path())
        .args(["simulate", "double", "--t-end", "3", "--out", "t.csv", "--plot", "run.png"])
        .assert()
        .success();
    assert_eq!(size("run.png"), (960, 3 * 480));
    pendula_in(dir.path())
        .args(["plot", "t.csv", "--phase", "--energy", "--out", "two.png"])
        .assert()
        .success();
    assert_eq!(size("two.png"), (960, 2 * 480));
    pendula_in(dir.path()).args(["plot", "t.csv", "--y", "omega1", "--out", "one.svg"]).assert().success();
    let svg = std::fs::read_to_string(dir.path().join("one.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("omega1"));
    pendula_in(dir.path()).args(["simulate", "double", "--t-end", "1", "--out", "t.npy"]).assert().success();
    pendula_in(dir.path()).args(["plot", "t.npy", "--phase"]).assert().success();
    assert_eq!(size("t-plot.png"), (960, 600));
    pendula_in(dir.path())
        .args([
            "fractal",
            "--grid",
            "theta1=-pi:pi:8",
            "--grid",
            "theta2=-pi:pi:8",
            "--t-max",
            "2",
            "--out",
            "f.npy",
        ])
        .assert()
        .success();
    pendula_in(dir.path()).args(["plot", "f.npy"]).assert().success();
    assert_eq!(size("f-plot.png"), (900, 760));
}

/// `plot` draws the tables of `compare` and `stability` as one bar per method (the method
/// column as the bar labels, a refused method's note saying so), and `convergence`'s as one
/// line per method (the methods as the legend).
#[test]
fn plot_draws_the_method_tables() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let methods = ["euler", "rk4", "verlet", "tao-2"];
    pendula_in(d)
        .args([
            "compare",
            "pendulum",
            "--methods",
            "euler,rk4,verlet",
            "--dt",
            "0.05",
            "--t-end",
            "20",
            "--out-dir",
            "c",
        ])
        .assert()
        .success();
    pendula_in(d).args(["plot", "c/summary.csv", "--out", "compare.svg"]).assert().success();
    let texts = svg_texts(&d.join("compare.svg"));
    for m in &methods[..3] {
        assert!(texts.iter().any(|t| t == m), "{m} is a bar label: {texts:?}");
    }
    assert!(texts.iter().any(|t| t == "max_rel_energy_error"), "the value axis: {texts:?}");
    assert!(
        texts.iter().any(|t| t.contains("growing")) && texts.iter().any(|t| t.contains("bounded")),
        "{texts:?}"
    );
    // Another column on request; a text column is not one to draw.
    pendula_in(d)
        .args(["plot", "c/summary.csv", "--y", "drift_rate", "--out", "drift.svg"])
        .assert()
        .success();
    assert!(svg_texts(&d.join("drift.svg")).iter().any(|t| t == "drift_rate"));
    pendula_in(d).args(["plot", "c/summary.csv", "--y", "growth"]).assert().code(2).stderr(
        predicate::str::contains("not a numeric column `growth`").and(predicate::str::contains("drift_rate")),
    );

    pendula_in(d)
        .args([
            "stability",
            "double",
            "--methods",
            "euler,rk4,verlet,tao-2",
            "--t-end",
            "2",
            "--out-dir",
            "s",
        ])
        .assert()
        .success();
    pendula_in(d).args(["plot", "s/stability.csv", "--out", "stability.svg"]).assert().success();
    let texts = svg_texts(&d.join("stability.svg"));
    for m in methods {
        assert!(texts.iter().any(|t| t == m), "{m} is a bar label: {texts:?}");
    }
    assert!(texts.iter().any(|t| t.contains("refused")), "tao-2 is refused above 1/binding: {texts:?}");

    pendula_in(d)
        .args(["convergence", "oscillator", "--methods", "euler,rk4,verlet", "--out-dir", "v"])
        .assert()
        .success();
    pendula_in(d).args(["plot", "v/convergence.csv", "--out", "convergence.svg"]).assert().success();
    let texts = svg_texts(&d.join("convergence.svg"));
    for m in &methods[..3] {
        assert_eq!(texts.iter().filter(|t| t == m).count(), 1, "{m} once in the legend: {texts:?}");
    }
    assert!(texts.iter().any(|t| t == "dt") && texts.iter().any(|t| t == "error"), "{texts:?}");
}

/// `fractal` and `sweep` write a description beside their arrays (FILE.npy.json), from
/// which `plot` names the axes and the colour bar, with units.
#[test]
fn plot_names_grids_from_their_descriptions() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    pendula_in(d)
        .args([
            "fractal",
            "--grid",
            "theta1=-3:3:12",
            "--grid",
            "theta2=-3:3:10",
            "--t-max",
            "2",
            "--out",
            "f.npy",
        ])
        .assert()
        .success();
    let description: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("f.npy.json")).unwrap()).unwrap();
    assert_eq!(description["axis_units"], serde_json::json!(["rad", "rad"]));
    assert_eq!(description["units"][0], "s");
    pendula_in(d).args(["plot", "f.npy", "--out", "f.svg"]).assert().success();
    let texts = svg_texts(&d.join("f.svg"));
    for label in ["θ₁ (rad)", "θ₂ (rad)", "time to first flip (s)"] {
        assert!(texts.iter().any(|t| t == label), "{label}: {texts:?}");
    }
    assert!(!texts.iter().any(|t| t.contains("index")), "{texts:?}");
    pendula_in(d).args(["plot", "f-converged.npy", "--out", "c.svg"]).assert().success();
    let texts = svg_texts(&d.join("c.svg"));
    for label in ["θ₁ (rad)", "θ₂ (rad)", "converged (1) or not (0)"] {
        assert!(texts.iter().any(|t| t == label), "{label}: {texts:?}");
    }

    pendula_in(d)
        .args([
            "sweep",
            "--grid",
            "theta1=0:2:6",
            "--grid",
            "omega1=0:1:5",
            "--t-end",
            "0.5",
            "--out",
            "s.npy",
        ])
        .assert()
        .success();
    pendula_in(d).args(["plot", "s.npy", "--y", "omega2", "--out", "s.svg"]).assert().success();
    let texts = svg_texts(&d.join("s.svg"));
    for label in ["θ₁ (rad)", "ω₁ (rad/s)", "ω₂ (rad/s)"] {
        assert!(texts.iter().any(|t| t == label), "{label}: {texts:?}");
    }
    // A dimensionless system's sweep says so, with the symbol its presets use.
    pendula_in(d)
        .args([
            "sweep",
            "driven-pendulum",
            "--grid",
            "drive_amplitude=0.5:1.5:4",
            "--grid",
            "q=1:3:3",
            "--t-end",
            "1",
            "--out",
            "g.npy",
        ])
        .assert()
        .success();
    pendula_in(d).args(["plot", "g.npy", "--out", "g.svg"]).assert().success();
    let texts = svg_texts(&d.join("g.svg"));
    for label in ["drive amplitude g (dimensionless)", "q (dimensionless)", "θ (rad)"] {
        assert!(texts.iter().any(|t| t == label), "{label}: {texts:?}");
    }
}

#[test]
fn plot_bad_input_exits_2_and_writes_nothing() {
    let csv = "t,theta,omega,energy\n0,1,0,-4.9\n0.1,0.9,-1,-4.9\n";
    let setup = [("t.csv", csv)];
    rejects_with(
        &["plot", "t.csv", "--y", "phi"],
        &["unknown column `phi`", "t, theta, omega, energy"],
        2,
        &setup,
    );
    rejects_with(&["plot", "t.csv", "--x", "time"], &["unknown column `time`", "theta"], 2, &setup);
    rejects_with(&["plot", "t.csv", "--out", "t.jpg"], &["--out", ".png or .svg"], 2, &setup);
    rejects_with(&["plot", "t.csv", "--system", "triple"], &["triple", "double"], 2, &setup);
    let table = [("d.csv", "t,distance\n0,1e-9\n1,2e-9\n")];
    rejects_with(&["plot", "d.csv", "--phase"], &["--phase", "t, distance"], 2, &table);
    rejects_with(&["plot", "d.csv", "--energy"], &["--energy", "t, distance"], 2, &table);
    rejects_with(&["plot", "x.csv", "--y", "a"], &["x.csv"], 2, &[("x.csv", "a,b\n1,oops\n")]);
    rejects(&["plot", "missing.csv"], &["missing.csv"]);
    rejects_with(&["plot", "t.txt"], &["t.txt", ".csv and .npy"], 2, &[("t.txt", csv)]);
}

/// `pendula serve`: prints the lab's URL (loopback, with a token), serves the page and its
/// script, and refuses a bad address or a busy port with exit code 2, naming them.
#[test]
fn serve_prints_its_url_and_serves_the_page() {
    use std::io::{BufRead, Read, Write};
    let dir = TempDir::new().unwrap();
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("pendula"))
        .args(["serve", "--port", "0"])
        .current_dir(dir.path())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .unwrap_or_else(|| panic!("{line}"))
        .to_owned();
    let rest = url.strip_prefix("http://127.0.0.1:").unwrap_or_else(|| panic!("loopback by default: {url}"));
    let (port, token) = rest.split_once("/?token=").unwrap();
    assert_eq!(token.len(), 32, "a 128-bit token in hex: {token}");
    let get = |path: &str| {
        let mut s = std::net::TcpStream::connect(format!("127.0.0.1:{port}")).unwrap();
        write!(s, "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n").unwrap();
        let mut body = String::new();
        s.read_to_string(&mut body).unwrap();
        body
    };
    let page = get("/");
    assert!(page.starts_with("HTTP/1.1 200") && page.contains("<canvas"), "{}", &page[..page.len().min(300)]);
    assert!(get("/app.js").contains("WebSocket"));
    assert!(get("/etc/passwd").starts_with("HTTP/1.1 404"), "no files served");
    // A busy port and a bad address: exit 2, named.
    pendula_in(dir.path()).args(["serve", "--port", port]).assert().code(2).stderr(
        predicate::str::contains(format!("127.0.0.1:{port}")).and(predicate::str::contains("--port")),
    );
    pendula_in(dir.path())
        .args(["serve", "--host", "localhost:80"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("\"localhost:80\" for --host"));
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(files(dir.path()).is_empty(), "serving writes nothing");
}

/// A reader that goes away (`pendula simulate --out - | head`) ends every command that can
/// write to stdout quietly with exit 0, as ripgrep does: no `Broken pipe` error, no exit 2
/// (which means invalid input), and no file left behind. The pipe's read end is closed before
/// the command writes anything, so that every write to it fails, whatever its size.
#[test]
fn a_closed_pipe_ends_every_command_quietly() {
    let commands: &[&[&str]] = &[
        &["simulate", "--out", "-"],
        &["simulate", "--every", "0", "--summary", "-"],
        &["sweep", "--grid", "theta1=0:1:8", "--t-end", "1", "--out", "s.npy", "--summary", "-"],
        &["fractal", "--grid", "theta1=0:1:16", "--grid", "theta2=0:1:16", "--t-max", "1", "--summary", "-"],
        &["stability", "pendulum", "--methods", "rk4", "--t-end", "10", "--summary", "-"],
        &["divergence", "--t-end", "5", "--summary", "-"],
        &["list", "methods"],
        &["completions", "bash"],
        &["man"],
    ];
    for args in commands {
        let dir = TempDir::new().unwrap();
        let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("pendula"))
            .args(*args)
            .current_dir(dir.path())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "pendula {}: {stderr}", args.join(" "));
        assert!(
            !stderr.contains("error:") && !stderr.contains("Broken pipe"),
            "pendula {}: {stderr}",
            args.join(" ")
        );
        // Outputs finished before the pipe closed may stay (the sweep's .npy); no temporary.
        let left = files(dir.path());
        let temporary =
            left.iter().filter(|f| f.starts_with('.') || f.contains("tmp") || f.contains("partial"));
        assert_eq!(temporary.count(), 0, "pendula {} left temporary files: {left:?}", args.join(" "));
    }
}

/// `--threads` takes any count up to a few per core, so that even a 2-core machine can show
/// that results do not depend on it: more threads than cores warn (they only take turns) and
/// give the same bytes; beyond four per core without `--allow-large` is refused.
#[test]
fn more_threads_than_cores_warn_and_give_the_same_bytes() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let dir = TempDir::new().unwrap();
    let mut outputs = Vec::new();
    for threads in [1, 2, cores + 1] {
        let out = format!("s{threads}.npy");
        let run = pendula_in(dir.path())
            .args(["sweep", "--grid", "theta1=0:3:24", "--grid", "theta2=0:3:16", "--t-end", "3"])
            .args(["--threads", &threads.to_string(), "--out", &out])
            .assert()
            .success();
        let stderr = String::from_utf8_lossy(&run.get_output().stderr).into_owned();
        let warned =
            stderr.contains(&format!("--threads {threads} is more than this machine's {cores} cores"));
        assert_eq!(warned, threads > cores, "threads {threads} on {cores} cores: {stderr}");
        outputs.push(std::fs::read(dir.path().join(out)).unwrap());
    }
    assert!(outputs.windows(2).all(|w| w[0] == w[1]), "the same bytes on 1, 2 and {} threads", cores + 1);
    let most = 4 * cores;
    pendula_in(dir.path())
        .args(["sweep", "--grid", "theta1=0:3:4", "--threads", &(most + 1).to_string()])
        .assert()
        .code(2)
        .stderr(predicate::str::contains(format!("give 1 to {most}")));
}

/// A warning quotes each value in at most 20 characters: `theta1=1e300` (radians, where
/// degrees were likely meant) must not print a 300-digit count of turns.
#[test]
fn warnings_quote_values_briefly() {
    let dir = TempDir::new().unwrap();
    let long = "1".repeat(60);
    for value in ["1e300", long.as_str()] {
        let run = pendula_in(dir.path())
            .args(["simulate", "pendulum", "--steps", "1", "--every", "0", "--out", "t.csv"])
            .args(["--set", &format!("theta={value}")])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        let warning =
            stderr.lines().find(|l| l.starts_with("warning:")).unwrap_or_else(|| panic!("{stderr}"));
        assert!(warning.contains("did you mean"), "{warning}");
        let longest = warning.split(|c: char| c.is_whitespace() || c == '(' || c == ')').map(str::len).max();
        assert!(longest.unwrap() <= 30, "a value quoted in more than 20 characters: {warning}");
    }
}

/// A refused method's message suggests only methods that accept that system as set, and
/// each of them runs: on the damped pendulum (no Hamiltonian) no symplectic method applies,
/// so none is offered "to stay symplectic"; on the double pendulum (not separable) the
/// symplectic methods that apply are.
#[test]
fn a_refusal_suggests_only_methods_that_run() {
    let dir = TempDir::new().unwrap();
    for (system, set, refused) in [
        ("pendulum", "damping=0.1", "yoshida-4"),
        ("double", "m2=1", "yoshida-4"),
        ("pendulum", "damping=0.1", "tao-4"),
    ] {
        let out = pendula_in(dir.path())
            .args(["simulate", system, "--method", refused, "--set", set, "--steps", "10", "--every", "0"])
            .assert()
            .code(2);
        let stderr = String::from_utf8_lossy(&out.get_output().stderr).into_owned();
        let tried = stderr.split("; try ").nth(1).unwrap_or_else(|| panic!("no suggestion: {stderr}"));
        let names: Vec<&str> = tried.split(" (").next().unwrap().split(", ").map(str::trim).collect();
        assert!(names.len() >= 2, "{stderr}");
        for name in &names {
            pendula_in(dir.path())
                .args(["simulate", system, "--method", name, "--set", set, "--t-end", "0.05", "--every", "0"])
                .assert()
                .success();
        }
        if system == "pendulum" {
            for never in ["tao-4", "verlet", "symplectic-euler", "stay symplectic"] {
                assert!(!tried.contains(never), "{never} offered for the damped pendulum: {stderr}");
            }
        } else {
            assert!(tried.contains("stay symplectic") && names.contains(&"gauss-legendre-4"), "{stderr}");
        }
    }
}

/// `pendula serve` without `--port` listens on 8485; when another program holds it, it takes
/// the next free port and says so on stderr (as Jupyter does), while `--port 8485` given
/// explicitly stays an error (exit 2, naming the address).
#[test]
fn serve_takes_the_next_port_when_the_default_is_busy() {
    use std::io::{BufRead, Read};
    const DEFAULT: u16 = 8485;
    let dir = TempDir::new().unwrap();
    // Held for the whole test. Where another program holds it already, it is busy all the same.
    let _holder = match std::net::TcpListener::bind(("127.0.0.1", DEFAULT)) {
        Ok(l) => Some(l),
        Err(e) if e.kind() == std::io::ErrorKind::AddrInUse => None,
        Err(e) => panic!("cannot bind 127.0.0.1:{DEFAULT}: {e}"),
    };
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("pendula"))
        .arg("serve")
        .current_dir(dir.path())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    let mut stderr = String::new();
    child.stderr.take().unwrap().read_to_string(&mut stderr).unwrap();
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .unwrap_or_else(|| panic!("{line} {stderr}"));
    let port: u16 = url
        .strip_prefix("http://127.0.0.1:")
        .and_then(|r| r.split_once('/'))
        .and_then(|(p, _)| p.parse().ok())
        .unwrap_or_else(|| panic!("{url}"));
    assert!((DEFAULT + 1..DEFAULT + 10).contains(&port), "a successor of {DEFAULT}, not {port}");
    assert!(
        stderr.contains(&format!("{DEFAULT} "))
            && stderr.contains(&format!("serving on port {port} instead")),
        "the move is said: {stderr:?}"
    );
    pendula_in(dir.path()).args(["serve", "--port", &DEFAULT.to_string()]).assert().code(2).stderr(
        predicate::str::contains(format!("127.0.0.1:{DEFAULT}")).and(predicate::str::contains("--port")),
    );
}
