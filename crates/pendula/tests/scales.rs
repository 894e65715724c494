//! Energy scales, the energy balance of forced runs, the bounded/growing verdict and the
//! order estimate of convergence studies, against closed forms and synthetic series whose
//! answer is known by construction.

use pendula::analysis::{EnergyBalance, Growth, OrderEstimate, estimate_order, growth, roundoff_floor};
use pendula::integrator::explicit_rk::RK4;
use pendula::model::CATALOGUE;
use pendula::{End, RunSpec};

#[test]
fn ref_double_pendulum_scale_is_the_well_depth_to_horizontal() {
    let values = pendula::model::find("double").unwrap().values(&[]).unwrap();
    let model = values.build();
    // From (90°, 90°) E(0) = 0 J (to rounding): relative to |E(0)| any error is infinite.
    let y = [std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2, 0.0, 0.0];
    assert!(model.energy(0.0, &y).abs() < 1e-12);
    // (m1 + m2) g l1 + m2 g l2 = 2 · 9.81 + 9.81 = 29.43 J.
    assert!((model.energy_scale(&y) - 29.43).abs() < 1e-12);
    // The default (120°, −10°) lies above the horizontal position: E(0) − V_min is larger.
    let y0 = values.initial_state();
    let above = model.energy(0.0, y0) - model.energy(0.0, &[0.0; 4]);
    assert!((model.energy_scale(y0) - above).abs() < 1e-12 && above > 29.43);
}

#[test]
fn every_system_declares_a_scale_far_from_zero_even_at_rest() {
    for info in CATALOGUE {
        let values = info.values(&[]).unwrap();
        let model = values.build();
        let rest = vec![0.0; values.initial_state().len()];
        for y in [values.initial_state(), &rest[..]] {
            let scale = model.energy_scale(y);
            assert!(scale.is_finite() && scale >= 0.1, "{}: scale {scale} at {y:?}", info.name);
        }
        assert!(!info.energy_scale.is_empty() && model.time_scale() > 0.0);
    }
}

/// max |balance| / scale and max |E − E(0)| / scale of an RK4 run.
fn balance_of(system: &str, set: &[(&str, f64)], h: f64, t_end: f64) -> (f64, f64) {
    let settings: Vec<(String, f64)> = set.iter().map(|(n, v)| ((*n).to_owned(), *v)).collect();
    let values = pendula::model::find(system).unwrap().values(&settings).unwrap();
    let model = values.build();
    let mut balance = EnergyBalance::new(&*model, values.initial_state());
    let spec = RunSpec { t0: 0.0, h, end: End::Time(t_end) };
    model.solve(&RK4, values.initial_state(), &spec, &mut balance).unwrap();
    assert!(balance.forced);
    let change = (balance.last - balance.initial).abs() / balance.scale;
    (balance.max_rel(), change)
}

#[test]
fn energy_balance_of_damped_and_driven_runs_stays_at_the_integrators_error() {
    for (system, set) in [
        ("double", vec![("damping", 0.1)]),
        ("double", vec![("damping", 0.15), ("drive_amplitude", 2.5), ("drive_frequency", 1.7)]),
        ("pendulum", vec![("damping", 0.3), ("drive_amplitude", 1.2), ("drive_frequency", 2.0)]),
        ("oscillator", vec![("c", 0.2), ("drive_amplitude", 1.0), ("drive_frequency", 1.0)]),
        ("driven-pendulum", vec![]),
    ] {
        let (coarse, change) = balance_of(system, &set, 2e-3, 10.0);
        let (fine, _) = balance_of(system, &set, 1e-3, 10.0);
        // The energy itself changes by a sizeable share of its scale ...
        assert!(change > 1e-2, "{system} {set:?}: E changed by only {change}");
        // ... while the balance stays at RK4's error, and falls as h⁴ does (16× for h/2).
        assert!(coarse < 1e-7, "{system} {set:?}: balance {coarse}");
        assert!(coarse / fine > 8.0, "{system} {set:?}: {coarse} then {fine}");
    }
}

#[test]
fn growth_tells_a_drift_from_a_bounded_oscillation() {
    let t: Vec<f64> = (0..1000).map(|k| k as f64 * 0.1).collect();
    let drift: Vec<f64> = t.iter().map(|t| 1e-6 * t + 1e-8 * (3.0 * t).sin()).collect();
    let bounded: Vec<f64> = t.iter().map(|t| 1e-3 * (2.0 * t).sin() * (0.3 * t).cos()).collect();
    let random_walk_free: Vec<f64> = t.iter().map(|t| 1e-3 * (t * t).sin()).collect();
    assert_eq!(growth(&t, &drift), Some(Growth::Growing));
    assert_eq!(growth(&t, &bounded), Some(Growth::Bounded));
    assert_eq!(growth(&t, &random_walk_free), Some(Growth::Bounded));
    assert_eq!(growth(&t[..5], &drift[..5]), None);
    // A random walk's √t growth is growth too.
    let diffusing: Vec<f64> = t.iter().map(|t| 1e-6 * t.sqrt() * (1.0 + 0.1 * (7.0 * t).sin())).collect();
    assert_eq!(growth(&t, &diffusing), Some(Growth::Growing));
    // A bounded error that sets a new record late in the run (the orbit reaching a faster
    // region for the first time), once, is not a drift.
    let late_record: Vec<f64> =
        t.iter().map(|&t| (1e-4 + if t > 80.0 { 1.5e-4 } else { 0.0 }) * (2.0 * t).sin()).collect();
    assert_eq!(growth(&t, &late_record), Some(Growth::Bounded));
}

#[test]
fn estimate_order_fits_the_straight_stretch_and_names_saturation_and_round_off() {
    let t_end = 1.0;
    let hs: Vec<f64> = (0..12).map(|k| 0.1 / 2f64.powi(k)).collect();
    // error = min(1, 3 h⁴) + rounding: saturated at the largest steps, floor at the smallest.
    let errors: Vec<f64> = hs.iter().map(|h| (3.0 * h.powi(4)).min(1.0) + 1e-17 * (t_end / h)).collect();
    match estimate_order(&hs, &errors, 1.0, t_end, f64::EPSILON) {
        OrderEstimate::Fitted { order, points, .. } => {
            assert!((order - 4.0).abs() < 0.05 && points >= 3, "{order} over {points}")
        }
        other => panic!("{other:?}"),
    }
    let saturated = vec![0.5; hs.len()];
    let s = estimate_order(&hs, &saturated, 1.0, t_end, f64::EPSILON);
    assert_eq!(s, OrderEstimate::Saturated);
    assert_eq!(s.label(), "step too large");
    let rounding: Vec<f64> = hs.iter().map(|h| 5.0 * roundoff_floor(t_end / h)).collect();
    let r = estimate_order(&hs, &rounding, 1.0, t_end, f64::EPSILON);
    assert_eq!(r, OrderEstimate::RoundOff);
    assert_eq!(r.label(), "saturated at round-off");
    // A zigzag (local slopes 3, 1, 3, …) far above the floor has no straight stretch of three.
    let bent: Vec<f64> =
        hs.iter().enumerate().map(|(k, h)| if k % 2 == 0 { h * h } else { 0.5 * h * h }).collect();
    assert_eq!(estimate_order(&hs, &bent, 1.0, t_end, f64::EPSILON), OrderEstimate::Irregular);
}

/// error = h⁴ + 50 h⁶ (a pre-asymptotic head: local slopes 5.7, 5.2, 4.6 at the largest
/// steps), saturated above 1% of the state, on a floor of the reference's accuracy with
/// rounding's alternating sign: the fit finds the order of the asymptotic range and only there.
#[test]
fn estimate_order_finds_the_asymptotic_order_between_a_preasymptotic_head_and_a_floor() {
    let (t_end, scale) = (2.0, 5.0);
    let accuracy = 1e-14;
    let floor = accuracy * scale;
    let hs: Vec<f64> = (0..14).map(|k| 0.5 / 2f64.powi(k)).collect();
    let truth = |h: f64| h.powi(4) + 50.0 * h.powi(6);
    let errors: Vec<f64> = hs
        .iter()
        .enumerate()
        .map(|(k, &h)| (truth(h) + if k % 2 == 0 { floor } else { -0.5 * floor }).abs().min(1.0))
        .collect();
    match estimate_order(&hs, &errors, scale, t_end, accuracy) {
        OrderEstimate::Fitted { order, points, h_min, h_max } => {
            assert!((order - 4.0).abs() < 0.05, "{order} over {points}");
            // Only steps whose error is 10 times the floor or more, and where h⁴ dominates
            // (50 h⁶ below 10% of h⁴: h < 0.045).
            assert!(truth(h_min) > 10.0 * floor, "{h_min}");
            assert!(50.0 * h_max.powi(2) < 0.1, "{h_max}");
            assert!(points >= 4, "{points}");
        }
        other => panic!("{other:?}"),
    }
    // An order-8 curve that reaches the floor while its slope still falls from 12 to 9 (a
    // cancelling head): too large a step for its asymptotic range, which lies below the floor.
    let steep = |h: f64| 1e-2 * h.powi(8) + 1e3 * h.powi(12);
    let hs8: Vec<f64> = (0..14).map(|k| 0.125 / 2f64.sqrt().powi(k)).collect();
    let errors8: Vec<f64> = hs8.iter().map(|&h| steep(h).max(floor)).collect();
    let e = estimate_order(&hs8, &errors8, scale, t_end, accuracy);
    assert_eq!(e, OrderEstimate::Preasymptotic, "{errors8:?}");
    assert_eq!(e.label(), "step too large");
    assert!(e.reason().unwrap().starts_with("step too large: "));
}

/// Where rounding is larger than the floor's model: a smallest step whose error is lifted
/// by 30% (a slope of 1.6 into it, Tao's maps round more than an ulp a step) is left out of
/// the fit; errors that level off at 2·10⁻¹³ (above the model's 10⁻¹⁴, as a long chain's do)
/// set the floor the fit keeps 10 times away from.
#[test]
fn estimate_order_leaves_out_steps_that_rounding_disturbs() {
    let (t_end, accuracy) = (2.0, 1e-14);
    let hs: Vec<f64> = (0..12).map(|k| 5e-3 / 2f64.powi(k)).collect();
    let mut lifted: Vec<f64> = hs.iter().map(|h| 2.0 * h * h).collect();
    *lifted.last_mut().unwrap() *= 1.3;
    match estimate_order(&hs, &lifted, 1.0, t_end, accuracy) {
        OrderEstimate::Fitted { order, h_min, .. } => {
            assert!((order - 2.0).abs() < 1e-9, "{order}");
            assert_eq!(h_min, hs[hs.len() - 2]);
        }
        other => panic!("{other:?}"),
    }
    let level = 2e-13;
    let hs5: Vec<f64> = (0..14).map(|k| 0.1 / 2f64.powi(k)).collect();
    let truth = |h: f64| 1e-3 * h.powi(5);
    let plateau: Vec<f64> =
        hs5.iter().enumerate().map(|(k, &h)| truth(h) + level * if k % 2 == 0 { 1.0 } else { 0.4 }).collect();
    match estimate_order(&hs5, &plateau, 1.0, t_end, accuracy) {
        OrderEstimate::Fitted { order, h_min, points, .. } => {
            assert!((order - 5.0).abs() < 0.05, "{order} over {points}");
            assert!(plateau[hs5.iter().position(|h| *h == h_min).unwrap()] > 10.0 * 0.4 * level, "{h_min}");
        }
        other => panic!("{other:?}"),
    }
}
