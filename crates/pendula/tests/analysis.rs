//! The analyses against closed forms.

use pendula::analysis::{self, StabilityCriterion};
use pendula::integrator::explicit_rk::{EULER, RK4};
use pendula::integrator::find;
use pendula::system::Values;

use crate::support::values;

#[test]
fn fit_order_recovers_a_power_law() {
    let hs = [0.1, 0.05, 0.025, 0.0125];
    let errors: Vec<f64> = hs.iter().map(|h: &f64| 3.0 * h.powi(4)).collect();
    let fit = analysis::fit_order(&hs, &errors).unwrap();
    assert!((fit.order - 4.0).abs() < 1e-12 && (fit.log_constant - 3f64.ln()).abs() < 1e-10);
    assert!(analysis::fit_order(&hs, &[1.0, 0.0, 1.0, 1.0]).is_none());
}

#[test]
fn drift_rate_and_envelope() {
    let t: Vec<f64> = (0..1001).map(|k| k as f64 * 0.1).collect();
    let e: Vec<f64> = t.iter().map(|t| 2e-6 * t + 1e-4 * (3.0 * t).sin()).collect();
    assert!((analysis::drift_rate(&t, &e) - 2e-6).abs() < 2e-7);
    let env = analysis::envelope(&t, &e, 10);
    assert_eq!(env.len(), 10);
    assert!(env[9].1 > env[0].1);
}

fn pendulum_at(deg: f64) -> Values {
    values("pendulum", &[("theta", deg.to_radians())])
}

/// The simulated period at 170° (first to third zero crossing, Hermite-located) equals
/// 4 √(l/g) K(sin 85°) (mpmath: 4.893524274105486164 s) to 1e-8.
#[test]
fn ref_simulated_period_at_170_degrees() {
    let v = pendulum_at(170.0);
    let model = v.build();
    let period = analysis::measure_period(&*model, &RK4, v.initial_state(), 0, 1e-3, 20.0).unwrap().unwrap();
    assert!((period / 4.893524274105486164 - 1.0).abs() < 1e-8, "{period}");
}

/// Explicit Euler on the undamped oscillator (ω = 1) multiplies the energy by exactly
/// 1 + h² per step, so its energy error stays within 10% over 10 s iff
/// ⌈10/h⌉ ln(1 + h²) ≤ ln 1.1: h* ≈ 0.00953.
#[test]
fn ref_largest_stable_step_of_euler_on_the_oscillator() {
    let v = values("oscillator", &[]);
    let model = v.build();
    let criterion = StabilityCriterion { t_end: 10.0, max_rel_energy_error: 0.1 };
    let h = analysis::largest_stable_step(&*model, &EULER, v.initial_state(), 1e-4, 1.0, &criterion)
        .unwrap()
        .unwrap();
    let grows = |h: f64| (10.0 / h).ceil() * (1.0 + h * h).ln() > 1.1f64.ln();
    let (mut lo, mut hi) = (1e-4, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if grows(mid) { hi = mid } else { lo = mid }
    }
    assert!((h / lo - 1.0).abs() < 0.02, "bisection {h} vs closed form {lo}");
    // Verlet on the oscillator is stable up to its linear stability limit h < 2/ω.
    let verlet = analysis::largest_stable_step(
        &*model,
        find("verlet").unwrap(),
        v.initial_state(),
        1e-3,
        3.0,
        &criterion,
    )
    .unwrap()
    .unwrap();
    assert!(verlet < 2.0, "{verlet}");
}

#[test]
fn reference_state_is_exact_where_possible() {
    let v = values("oscillator", &[("c", 0.3)]);
    let model = v.build();
    let r = analysis::reference_state(&*model, v.initial_state(), 5.0).unwrap();
    assert_eq!(r.source, "exact solution");
    let d = values("double", &[]);
    let model = d.build();
    let r = analysis::reference_state(&*model, d.initial_state(), 2.0).unwrap();
    assert!(r.source.starts_with("dop853"), "{}", r.source);
    // mpmath's value (see conformance.rs, problem A).
    let want =
        [1.1528016719796439749, -0.46715839071399934831, -0.056676482593218044406, 5.8056603694950057652];
    let err = r.state.iter().zip(want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(err < 1e-12, "{err:e}");
}

/// A separation that stays at 10⁻⁹ for 2 s (not yet turned along the unstable direction)
/// and then grows as e^(0.9 (t − 2)): fitted from the start the rate comes out low; from
/// above 10⁻⁸ it is the exponential's, 0.9.
#[test]
fn growth_rate_between_leaves_out_the_start() {
    let t: Vec<f64> = (0..3000).map(|k| k as f64 * 0.01).collect();
    let distance = t.iter().map(|&t| if t < 2.0 { 1e-9 } else { 1e-9 * (0.9 * (t - 2.0)).exp() }).collect();
    let d = analysis::Divergence { t, distance };
    let whole = analysis::growth_rate(&d, 1e-2).unwrap();
    let window = analysis::growth_rate_between(&d, 1e-8, 1e-2).unwrap();
    assert!((window.rate - 0.9).abs() < 1e-9, "{}", window.rate);
    assert!(window.t_start > 2.0 + (10f64).ln() / 0.9 - 0.02, "{}", window.t_start);
    assert!(whole.rate < window.rate - 0.02 && whole.t_start == 0.0, "{whole:?}");
    // Both stop before the distance first passes the saturation.
    assert_eq!(whole.t_end, window.t_end);
    assert!(window.t_end < 2.0 + (1e7f64).ln() / 0.9);
}
