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
    assert!(matches!(EventSpec::parse("section:x=abc", &*model, false), Err(Error::InvalidValue { .. })));
    assert!(EventSpec::parse("section:x=0.5", &*model, false).is_ok());
}
