//! Fallible observers: an observer that cannot take a state (its output failed) ends the run
//! with `Error::Observer`, carrying its own error, on every run loop (the fixed-step loop,
//! the double pendulum's RK4 trajectory kernel, the adaptive loop), through tuples and the
//! event wrapper; an observer that has seen enough still ends the run as stopped.

use std::error::Error as _;
use std::ops::ControlFlow;

use pendula::checkpoint::{Leg, Pause};
use pendula::control::Tolerances;
use pendula::events::{EndAtEvent, EventLocator, EventSpec};
use pendula::integrator::{self, Method};
use pendula::observe::{Flow, Observer, Sample, Stop, StopWhen};
use pendula::{End, Error, Outcome, Report, RunSpec, Stepping};

use crate::support::values;

/// Fails at the state of step `at` (or at the run's last state) with an I/O error; counts
/// the states it saw.
struct FailAt {
    at: Option<u64>,
    seen: u64,
}

impl Observer for FailAt {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        self.seen += 1;
        if self.at.map_or(s.last, |at| s.step == at) {
            return ControlFlow::Break(Stop::failed(std::io::Error::other("the disk went away")));
        }
        ControlFlow::Continue(())
    }
}

/// The run's error is the observer's: its message, and its error as the source.
fn assert_observer_failure(result: Result<Leg<Report>, Error>, context: &str) {
    let err = match result {
        Err(err) => err,
        Ok(leg) => panic!("{context}: the run went on past its observer's failure: {leg:?}"),
    };
    assert!(matches!(err, Error::Observer(_)), "{context}: {err:?}");
    assert_eq!(err.to_string(), "the disk went away", "{context}");
    let source = err.source().unwrap_or_else(|| panic!("{context}: no source"));
    let io = source.downcast_ref::<std::io::Error>().unwrap_or_else(|| panic!("{context}: {source:?}"));
    assert_eq!(io.kind(), std::io::ErrorKind::Other, "{context}");
}

fn fixed(h: f64, t_end: f64) -> Stepping<'static> {
    Stepping::Fixed(RunSpec { t0: 0.0, h, end: End::Time(t_end) })
}

/// The catalogued `system` on its defaults, with RK4 at step `h` to `t_end`, shown to `observer`.
fn rk4(system: &str, h: f64, t_end: f64, observer: &mut dyn Observer) -> Result<Leg<Report>, Error> {
    let v = values(system, &[]);
    v.build().solve_fastest(
        &integrator::explicit_rk::RK4,
        v.initial_state(),
        &fixed(h, t_end),
        observer,
        None,
        &Pause::NEVER,
    )
}

#[test]
fn a_failing_observer_ends_every_run_loop_with_its_error() {
    let tol = Tolerances { rtol: 1e-8, atol: 1e-8, h_min: 0.0, h_max: f64::INFINITY };
    let cases: [(&str, &Method, Stepping<'_>); 5] = [
        // The double pendulum's RK4: its own trajectory kernel.
        ("double", &integrator::explicit_rk::RK4, fixed(0.01, 1.0)),
        ("pendulum", &integrator::explicit_rk::RK4, fixed(0.01, 1.0)),
        ("chain", &integrator::partitioned::VERLET, fixed(0.01, 1.0)),
        ("double", &integrator::gauss_legendre::GAUSS_LEGENDRE_4, fixed(0.01, 1.0)),
        ("double", &integrator::embedded::DOPRI5, Stepping::Adaptive { t_end: 1.0, h0: None, tol: &tol }),
    ];
    for (system, method, stepping) in cases {
        let v = values(system, &[]);
        let model = v.build();
        for at in [Some(0), Some(7), None] {
            let context = format!("{system} {} failing at {at:?}", method.name);
            let mut observer = FailAt { at, seen: 0 };
            let result =
                model.solve_fastest(method, v.initial_state(), &stepping, &mut observer, None, &Pause::NEVER);
            assert_observer_failure(result, &context);
            // Nothing is shown after the failure.
            if let Some(at) = at {
                assert_eq!(observer.seen, at + 1, "{context}");
            }
        }
    }
}

#[test]
fn having_seen_enough_still_stops_the_run_without_error() {
    let mut enough = StopWhen(|s: &Sample<'_>| s.step == 5);
    let leg = rk4("double", 0.01, 1.0, &mut enough).unwrap();
    let Leg::Done(report) = leg else { panic!("paused") };
    assert_eq!(report.outcome, Outcome::Stopped { steps: 5, t: 0.05 });
}

/// In a tuple a failure outranks having seen enough, whichever comes first.
#[test]
fn a_failure_outranks_enough_in_a_tuple() {
    for first in [false, true] {
        let enough = StopWhen(|s: &Sample<'_>| s.step == 3);
        let failing = FailAt { at: Some(3), seen: 0 };
        let result = if first {
            rk4("pendulum", 0.01, 1.0, &mut (failing, enough))
        } else {
            rk4("pendulum", 0.01, 1.0, &mut (enough, failing))
        };
        assert_observer_failure(result, &format!("failing observer first: {first}"));
    }
}

/// The event wrapper shows the terminal event to the observer inside as the run's last
/// state; that observer's failure there is the run's error, not a stop.
#[test]
fn a_failure_at_a_terminal_event_is_the_runs_error() {
    let v = values("double", &[]);
    let model = v.build();
    let specs = vec![EventSpec::parse("zero:theta2", &*model, true).unwrap()];
    let mut wrapped =
        EndAtEvent { events: EventLocator::new(&*model, specs.clone()), inner: FailAt { at: None, seen: 0 } };
    let result = rk4("double", 0.001, 10.0, &mut wrapped);
    assert_observer_failure(result, "failing at the event");
    // Control: the same event with an observer that does not fail stops the run there.
    let mut quiet = EndAtEvent { events: EventLocator::new(&*model, specs), inner: pendula::observe::Ignore };
    let leg = rk4("double", 0.001, 10.0, &mut quiet).unwrap();
    let Leg::Done(report) = leg else { panic!("paused") };
    assert!(matches!(report.outcome, Outcome::Stopped { .. }), "{:?}", report.outcome);
}
