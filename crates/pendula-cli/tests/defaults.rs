//! The study commands on their defaults, for every catalogued system: they finish, and every
//! order they print is within ±0.15 of the declared one or carries a stated reason.

use std::path::Path;

use assert_cmd::Command;
use pendula::model::CATALOGUE;
use tempfile::TempDir;

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn convergence_on_defaults_fits_every_declared_order_or_says_why() {
    for info in CATALOGUE {
        let dir = TempDir::new().unwrap();
        let out = Command::cargo_bin("pendula")
            .unwrap()
            .current_dir(dir.path())
            .args(["convergence", info.name, "--out-dir", "c", "--summary", "s.json"])
            .assert()
            .success();
        let s = json(&dir.path().join("s.json"));
        let orders = s["orders"].as_object().unwrap();
        assert!(orders.len() >= 5, "{}: only {} methods", info.name, orders.len());
        let mut fitted = 0;
        for (method, order) in orders {
            let declared = pendula::integrator::find(method).unwrap().order as f64;
            let note = s["notes"][method].as_str().unwrap();
            match order.as_f64() {
                Some(o) => {
                    assert!(
                        (o - declared).abs() <= 0.15,
                        "{}: {method} fitted {o}, declared {declared}",
                        info.name
                    );
                    fitted += 1;
                }
                None => assert!(
                    ["saturated", "round-off", "no straight stretch", "did not converge", "non-finite"]
                        .iter()
                        .any(|r| note.contains(r)),
                    "{}: {method} has no order and no reason: {note:?}",
                    info.name
                ),
            }
        }
        // The studies measure: at least half the methods get an order on every system.
        assert!(fitted * 2 >= orders.len(), "{}: {fitted} of {} fitted", info.name, orders.len());
        let stdout = String::from_utf8(out.get_output().stdout.clone()).unwrap();
        assert!(stdout.contains("fitted order") && stdout.contains("note"), "{stdout}");
    }
}

#[test]
fn work_precision_on_defaults_finishes_for_every_system() {
    for info in CATALOGUE {
        let dir = TempDir::new().unwrap();
        Command::cargo_bin("pendula")
            .unwrap()
            .current_dir(dir.path())
            .args(["work-precision", info.name, "--out-dir", "w", "--summary", "s.json"])
            .assert()
            .success();
        let s = json(&dir.path().join("s.json"));
        for (method, points) in s["methods"].as_object().unwrap() {
            let points = points.as_array().unwrap();
            assert!(!points.is_empty(), "{}: {method} has no point", info.name);
            assert!(
                points.iter().all(|p| p["error"].as_f64().unwrap().is_finite()),
                "{}: {method}",
                info.name
            );
        }
    }
}

/// `compare` at its default cost runs every method made for each system — for the double
/// pendulum Tao's explicit maps among them, which at 700 evaluations per second were refused
/// (their steps above 1/w) — and refuses none. The horizon is shortened: whether a method is
/// refused depends on its step, which the cost alone fixes.
#[test]
fn compare_at_its_default_cost_refuses_no_method() {
    for info in CATALOGUE {
        let dir = TempDir::new().unwrap();
        Command::cargo_bin("pendula")
            .unwrap()
            .current_dir(dir.path())
            .args(["compare", info.name, "--t-end", "5", "--out-dir", "c", "--summary", "s.json"])
            .assert()
            .success();
        let s = json(&dir.path().join("s.json"));
        assert_eq!(s["steps"]["evals_per_second"], 3000.0, "the default cost");
        let methods = s["methods"].as_object().unwrap();
        if info.name == "double" {
            assert!(methods.contains_key("tao-2") && methods.contains_key("tao-4"), "{methods:?}");
        }
        for (method, m) in methods {
            assert_eq!(m["status"], "completed", "{} {method}: {m}", info.name);
        }
    }
}
