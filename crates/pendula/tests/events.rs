//! Event location on the Hermite interpolant between steps.

use pendula::events::{EventLocator, EventSpec};
use pendula::integrator::explicit_rk::RK4;
use pendula::{End, Error, Outcome, RunSpec};

use crate::support::values;

/// Zero crossings of θ from 170° at rest, RK4 at h = 1 ms: the first and third are one
/// period apart, and the period equals mpmath's 4 √(l/g) K(sin 85°) to 1e-9.
#[test]
fn ref_zero_events_give_the_exact_period() {
    let v = values("pendulum", &[("theta", 170f64.to_radians())]);
    let model = v.build();
    let spec = EventSpec::parse("zero:theta", &*model, false).unwrap();
    let mut events = EventLocator::new(&*model, vec![spec]);
    let run = RunSpec { t0: 0.0, h: 1e-3, end: End::Time(12.0) };
    model.solve(&RK4, v.initial_state(), &run, &mut events).unwrap();
    assert!(events.found.len() >= 4);
    let period = events.found[2].t - events.found[0].t;
    assert!((period / 4.893524274105486164 - 1.0).abs() < 1e-9, "{period}");
    for e in &events.found {
        assert!(e.state[0].abs() < 1e-10, "theta at the event: {}", e.state[0]);
    }
}

/// The same period from dop853's adaptive steps at rtol = atol = 1e-12: the events are
/// located on its order-7 dense output (steps of ~0.1 s, where a cubic Hermite interpolant
/// would be off by ~1e-6), and the period is exact to 1e-9 relative, as the integrators issue
/// asks; also with dopri5's order-4 dense output (steps of ~5 ms) to 1e-8.
#[test]
fn ref_zero_events_on_dense_output_give_the_exact_period() {
    use pendula::control::Tolerances;
    use pendula::integrator::embedded::{DOP853, DOPRI5};
    let v = values("pendulum", &[("theta", 170f64.to_radians())]);
    let model = v.build();
    let exact = 4.893524274105486164;
    for (method, tol, allowed, min_mean_step) in [(&DOP853, 1e-12, 1e-9, 0.02), (&DOPRI5, 1e-12, 1e-8, 0.002)]
    {
        let spec = EventSpec::parse("zero:theta", &*model, false).unwrap();
        let mut events = EventLocator::new(&*model, vec![spec]);
        let tol = Tolerances { rtol: tol, atol: tol, h_min: 0.0, h_max: f64::INFINITY };
        let report = model.solve_adaptive(method, v.initial_state(), 12.0, None, &tol, &mut events).unwrap();
        assert!(events.found.len() >= 4);
        let period = events.found[2].t - events.found[0].t;
        let mean_step = 12.0 / report.outcome.steps() as f64;
        eprintln!("{}: period error {:.2e}, mean step {mean_step:.3} s", method.name, period / exact - 1.0);
        assert!((period / exact - 1.0).abs() < allowed, "{}: {period}", method.name);
        assert!(mean_step > min_mean_step, "{} took small steps: {mean_step}", method.name);
        for e in &events.found {
            assert!(e.state[0].abs() < 1e-9, "theta at the event: {}", e.state[0]);
        }
    }
}

/// Directions: `zero:theta+` keeps the upward crossings only (one per period, θ' > 0 there),
/// `zero:theta-` the downward ones; `section:theta=0.5-` the downward passes through 0.5.
#[test]
fn directed_events_keep_one_crossing_per_period() {
    let v = values("pendulum", &[("theta", 170f64.to_radians())]);
    let model = v.build();
    let run = RunSpec { t0: 0.0, h: 1e-3, end: End::Time(12.0) };
    let period = 4.893524274105486164;
    for (text, sign) in [("zero:theta+", 1.0), ("zero:theta-", -1.0), ("section:theta=0.5-", -1.0)] {
        let spec = EventSpec::parse(text, &*model, false).unwrap();
        let mut events = EventLocator::new(&*model, vec![spec]);
        model.solve(&RK4, v.initial_state(), &run, &mut events).unwrap();
        // Within 12 s (2.45 periods): 2 or 3 of each kind, one period apart.
        assert!((2..=3).contains(&events.found.len()), "{text}: {:?}", events.found);
        for pair in events.found.windows(2) {
            assert!(((pair[1].t - pair[0].t) / period - 1.0).abs() < 1e-9, "{text}");
        }
        for e in &events.found {
            assert_eq!(e.name, text);
            assert!(e.state[1] * sign > 0.0, "{text}: omega {}", e.state[1]);
        }
    }
}

/// The double pendulum from (120°, −10°) flips once: the flip event is recorded once, at a
/// state where an angle is ±π, and the same at half the step (chaos amplifies only round-off
/// and the O(h⁴) error at this early time).
#[test]
fn flip_is_located_once_and_stops_when_terminal() {
    let v = values("double", &[]);
    let model = v.build();
    let flip_at = |h: f64, terminal: bool| {
        let spec = EventSpec::parse("flip", &*model, terminal).unwrap();
        let mut events = EventLocator::new(&*model, vec![spec]);
        let run = RunSpec { t0: 0.0, h, end: End::Time(30.0) };
        let report = model.solve(&RK4, v.initial_state(), &run, &mut events).unwrap();
        (events.found, report.outcome)
    };
    let (found, outcome) = flip_at(1e-3, false);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(matches!(outcome, Outcome::ReachedEnd { .. }));
    let e = &found[0];
    let pi = std::f64::consts::PI;
    assert!(e.state[..2].iter().any(|a| (a.abs() - pi).abs() < 1e-9), "{:?}", e.state);
    let (finer, stopped) = flip_at(5e-4, true);
    assert!((finer[0].t - e.t).abs() < 1e-8, "{} vs {}", finer[0].t, e.t);
    let Outcome::Stopped { t, .. } = stopped else { panic!("{stopped:?}") };
    assert!(t >= finer[0].t && t - finer[0].t <= 5e-4);
}

#[test]
fn event_names_are_checked() {
    let v = values("oscillator", &[]);
    let model = v.build();
    assert!(matches!(EventSpec::parse("zero:y", &*model, false), Err(Error::UnknownName { .. })));
    assert!(matches!(EventSpec::parse("flip", &*model, false), Err(Error::UnknownName { .. })));
    // A value that is no number is an error in the spec, named whole with what is allowed
    // (it was an `InvalidValue` that printed "invalid value NaN").
    let e = EventSpec::parse("section:x=abc", &*model, false).unwrap_err();
    assert!(matches!(e, Error::UnknownName { .. }), "{e:?}");
    let text = e.to_string();
    assert!(
        text.contains("`section:x=abc`") && text.contains("`abc` is not a number") && !text.contains("NaN"),
        "{text}"
    );
    let e = EventSpec::parse("section:x=0.5++", &*model, false).unwrap_err().to_string();
    assert!(e.contains("did you mean `section:x=0.5+`"), "{e}");
    assert!(EventSpec::parse("section:x=0.5", &*model, false).is_ok());
}

/// The continuous solution from recorded steps reproduces a cubic exactly on Hermite steps
/// (y = t³ − 2t, y' = 3t² − 2), forward and on a run backward in time, and evaluates a
/// step's dense coefficients where given (r₀ + θ r₁: a line).
#[test]
fn ref_the_continuous_solution_is_exact_for_a_cubic_and_uses_dense_steps() {
    use pendula::events::Continuous;
    let y = |t: f64| t * t * t - 2.0 * t;
    let dy = |t: f64| 3.0 * t * t - 2.0;
    for ts in [vec![0.0, 0.3, 0.7, 1.5, 2.0], vec![2.0, 1.5, 0.7, 0.3, 0.0]] {
        let states: Vec<f64> = ts.iter().map(|&t| y(t)).collect();
        let f: Vec<f64> = ts.iter().map(|&t| dy(t)).collect();
        let c = Continuous { ts: &ts, states: &states, f: &f, dense: None };
        for t in [0.0, 0.1, 0.3, 0.55, 1.0, 1.9, 2.0] {
            let mut out = [0.0];
            c.at(t, &mut out);
            assert!((out[0] - y(t)).abs() < 1e-13, "t = {t}: {} against {}", out[0], y(t));
        }
    }
    // One step from t = 1 of size 2 whose dense output is 5 + θ·4 (θ = (t − 1)/2).
    let (ts, states, f) = ([1.0, 3.0], [5.0, 9.0], [0.0, 0.0]);
    let (steps, coefficients) = ([1.0, 2.0], [5.0, 4.0]);
    let c = Continuous { ts: &ts, states: &states, f: &f, dense: Some((&steps, &coefficients)) };
    let mut out = [0.0];
    c.at(2.0, &mut out);
    assert_eq!(out[0], 7.0);
}
