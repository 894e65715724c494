//! Lyapunov exponents (Benettin with QR) against published and closed-form values: the
//! Lorenz system's largest exponent (Sprott 2003), the spectrum's sum where the trace of the
//! Jacobian is constant (Lorenz, the driven pendulum), the ±λ pairing of a Hamiltonian
//! system (the double pendulum), and the sign of λ₁ in Baker and Gollub's regimes.

use pendula::analysis::{Lyapunov, LyapunovSpec, lyapunov};
use pendula::integrator::explicit_rk::RK4;
use pendula::system::{AsSystem, System};

use crate::support::values;

/// The Lorenz system x' = σ(y − x), y' = x(ρ − z) − y, z' = xy − βz: the standard test of
/// Lyapunov codes (here only, not in the catalogue).
struct Lorenz {
    sigma: f64,
    rho: f64,
    beta: f64,
}

impl System for Lorenz {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&self, _t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = self.sigma * (y[1] - y[0]);
        d[1] = y[0] * (self.rho - y[2]) - y[1];
        d[2] = y[0] * y[1] - self.beta * y[2];
    }
    fn jacobian(&self, _t: f64, y: &[f64], j: &mut [f64]) -> bool {
        j.copy_from_slice(&[
            -self.sigma,
            self.sigma,
            0.0,
            self.rho - y[2],
            -1.0,
            -y[0],
            y[1],
            y[0],
            -self.beta,
        ]);
        true
    }
}

fn spec(h: f64, transient: f64, t_end: f64, count: usize) -> LyapunovSpec {
    LyapunovSpec { h, transient, t_end, renormalise: 0.5, count, blocks: 10 }
}

fn show(name: &str, l: &Lyapunov) {
    eprintln!("{name}: {:?} ± {:?}", l.exponents, l.uncertainty);
}

#[test]
fn ref_lorenz_largest_exponent_and_spectrum_sum() {
    let lorenz = Lorenz { sigma: 10.0, rho: 28.0, beta: 8.0 / 3.0 };
    let l = lyapunov(&lorenz, &RK4, &[1.0, 1.0, 20.0], &spec(0.005, 20.0, 2000.0, 3)).unwrap();
    show("lorenz", &l);
    // Published: λ = (0.9056, 0, −14.5723) for σ = 10, ρ = 28, β = 8/3 (J. C. Sprott, Chaos and
    // Time-Series Analysis, Oxford University Press 2003, appendix A.4.1).
    let published = 0.9056;
    assert!(
        (l.exponents[0] - published).abs() <= 2.0 * l.uncertainty[0] && l.uncertainty[0] < 0.02,
        "λ₁ = {} ± {}, published {published}",
        l.exponents[0],
        l.uncertainty[0]
    );
    assert!(l.exponents[1].abs() < 0.01, "λ₂ = {}", l.exponents[1]);
    // The trace of the Jacobian is −(σ + 1 + β) everywhere: the exponents sum to it, up to
    // RK4's truncation error in the tangent flow's determinant (measured 6e-6 at h = 5 ms).
    let sum: f64 = l.exponents.iter().sum();
    assert!((sum + 13.0 + 2.0 / 3.0).abs() < 1e-4, "Σλ = {sum}");
}

#[test]
fn ref_driven_pendulum_spectrum_sums_to_minus_one_over_q() {
    let v = values("driven-pendulum", &[]);
    let model = v.build();
    let l = lyapunov(&AsSystem(&*model), &RK4, v.initial_state(), &spec(0.01, 100.0, 3000.0, 2)).unwrap();
    show("driven pendulum g = 1.5", &l);
    let sum = l.exponents[0] + l.exponents[1];
    assert!((sum + 0.5).abs() < 1e-6, "Σλ = {sum}, trace −1/q = −0.5");
    assert!(
        l.exponents[0] > 5.0 * l.uncertainty[0],
        "chaotic regime: λ₁ = {} ± {}",
        l.exponents[0],
        l.uncertainty[0]
    );
}

#[test]
fn baker_gollub_presets_have_the_expected_sign() {
    for preset in pendula::system::driven::PRESETS {
        let settings: Vec<(&str, f64)> = preset.settings.to_vec();
        let v = values(preset.system, &settings);
        let model = v.build();
        let l = lyapunov(&AsSystem(&*model), &RK4, v.initial_state(), &spec(0.01, 300.0, 3000.0, 1)).unwrap();
        show(preset.name, &l);
        let chaotic = preset.description.contains("chaotic");
        let (lambda, err) = (l.exponents[0], l.uncertainty[0]);
        if chaotic {
            assert!(lambda > 3.0 * err && lambda > 0.05, "{}: λ₁ = {lambda} ± {err}", preset.name);
        } else {
            assert!(lambda < -5.0 * err, "{}: λ₁ = {lambda} ± {err}", preset.name);
        }
    }
}

#[test]
fn double_pendulum_spectrum_pairs_plus_and_minus() {
    let v = values("double", &[]);
    let model = v.build();
    let l = lyapunov(&AsSystem(&*model), &RK4, v.initial_state(), &spec(0.002, 10.0, 1000.0, 4)).unwrap();
    show("double", &l);
    let e = &l.exponents;
    assert!(e[0] > 0.5, "chaotic: λ₁ = {}", e[0]);
    assert!((e[0] + e[3]).abs() < 1e-2, "λ₁ + λ₄ = {}", e[0] + e[3]);
    assert!((e[1] + e[2]).abs() < 1e-2, "λ₂ + λ₃ = {}", e[1] + e[2]);
}

#[test]
fn bad_requests_are_errors() {
    let lorenz = Lorenz { sigma: 10.0, rho: 28.0, beta: 8.0 / 3.0 };
    let y0 = [1.0, 1.0, 20.0];
    for bad in [
        spec(0.0, 0.0, 10.0, 1),
        spec(0.01, -1.0, 10.0, 1),
        spec(0.01, 0.0, 10.0, 4),
        spec(0.01, 0.0, 10.0, 0),
    ] {
        assert!(lyapunov(&lorenz, &RK4, &y0, &bad).is_err(), "{bad:?}");
    }
    let tao = pendula::integrator::find("tao-4").unwrap();
    let err = lyapunov(&lorenz, tao, &y0, &spec(0.01, 0.0, 10.0, 1)).unwrap_err();
    assert!(err.to_string().contains("rk4"), "{err}");
}
