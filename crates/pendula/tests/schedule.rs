//! The run loop's step schedule and failure reporting.

use pendula::integrator::explicit_rk::EULER;
use pendula::observe::{Recorder, StopWhen};
use pendula::{End, Error, Outcome, RunSpec};

use crate::support::values;

#[test]
fn whole_number_of_steps_keeps_every_step_at_h() {
    let s = RunSpec { t0: 0.0, h: 1e-3, end: End::Time(10.0) }.schedule().unwrap();
    assert_eq!((s.steps, s.last_h, s.t_end), (10_000, 1e-3, 10.0));
}

#[test]
fn last_step_is_shortened_to_land_on_t_end() {
    let v = values("oscillator", &[]);
    let model = v.build();
    let mut rec = Recorder::default();
    let spec = RunSpec { t0: 0.0, h: 0.3, end: End::Time(1.0) };
    let report = model.solve(&EULER, v.initial_state(), &spec, &mut rec).unwrap();
    assert_eq!(report.outcome, Outcome::ReachedEnd { steps: 4, t: 1.0 });
    let times: Vec<f64> = rec.rows.chunks(3).map(|r| r[0]).collect();
    assert_eq!(times.len(), 5);
    assert_eq!(times[4], 1.0);
    assert!((times[3] - 0.9).abs() < 1e-15);
}

#[test]
fn invalid_specs_are_errors() {
    for (spec, name) in [
        // The library names quantities (h, t_end), never the command line's flags.
        (RunSpec { t0: 0.0, h: 0.0, end: End::Time(1.0) }, "h"),
        (RunSpec { t0: 0.0, h: f64::NAN, end: End::Time(1.0) }, "h"),
        (RunSpec { t0: 0.0, h: 0.1, end: End::Time(-1.0) }, "t_end"),
        (RunSpec { t0: 0.0, h: 0.1, end: End::Time(f64::INFINITY) }, "t_end"),
        (RunSpec { t0: 0.0, h: 0.1, end: End::Steps(0) }, "steps"),
    ] {
        match spec.schedule() {
            Err(Error::InvalidValue { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{spec:?}: {other:?}"),
        }
    }
}

/// A count of steps beyond 10¹³ (days of work) is refused as a step count, as a horizon
/// beyond 10¹³ steps already was: `End::Steps(u64::MAX)` used to start a run of 10¹⁹ steps.
#[test]
fn more_than_ten_trillion_steps_are_refused() {
    let huge = RunSpec { t0: 0.0, h: 0.1, end: End::Steps(u64::MAX) };
    match huge.schedule() {
        Err(Error::InvalidValue { name, allowed, .. }) => {
            assert_eq!(name, "steps");
            assert!(allowed.contains("10^13"), "{allowed}");
        }
        other => panic!("{other:?}"),
    }
    assert!(RunSpec { t0: 0.0, h: 0.1, end: End::Steps(10_000_000_000_000) }.schedule().is_ok());
}

/// Explicit Euler on a stiff spring overflows; the error names the time it happened.
#[test]
fn non_finite_state_is_an_error_with_its_time() {
    let v = values("oscillator", &[("k", 1e300)]);
    let spec = RunSpec { t0: 0.0, h: 1.0, end: End::Time(100.0) };
    let err = v.build().solve(&EULER, v.initial_state(), &spec, &mut pendula::observe::Ignore).unwrap_err();
    // x₁ = 1, v₁ = −1e300; x₂ = 1 − 1e300, v₂ = −2e300; then k x₂ overflows.
    assert_eq!(err, Error::NonFinite { t: 3.0 });
}

#[test]
fn observer_can_stop_the_run() {
    let v = values("pendulum", &[]);
    let mut stop = StopWhen(|s: &pendula::observe::Sample<'_>| s.y[0] < 0.0);
    let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Time(10.0) };
    let report = v.build().solve(&EULER, v.initial_state(), &spec, &mut stop).unwrap();
    let Outcome::Stopped { t, .. } = report.outcome else { panic!("{report:?}") };
    // A quarter of the exact period at 60° (0.5401 s).
    assert!((t - 0.540).abs() < 0.01, "{t}");
}

#[test]
fn unmet_requirement_names_method_and_reason() {
    let v = values("pendulum", &[("damping", 0.5)]);
    let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Time(1.0) };
    let verlet = pendula::integrator::find("verlet").unwrap();
    let err = v.build().solve(verlet, v.initial_state(), &spec, &mut pendula::observe::Ignore).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("verlet") && msg.contains("damping = 0.5") && msg.contains("rk4"), "{msg}");
}

/// RK4 on the double pendulum from (120°, −10°) at h = 1e-3 to t = 10 s reproduces the C
/// reference of `shared/bench/SPEC.md` (glibc sin/cos, no FMA) bit for bit: same equations, same
/// expression order, same RK4 sums.
#[test]
fn ref_rk4_matches_the_benchmark_c_reference() {
    let v = values("double", &[]);
    let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Time(10.0) };
    let report = v
        .build()
        .solve(
            &pendula::integrator::explicit_rk::RK4,
            v.initial_state(),
            &spec,
            &mut pendula::observe::Ignore,
        )
        .unwrap();
    let reference = [-0.80261226093658078, -2.4815017590829602, -1.9522459590552914, -2.3287480204624753];
    if cfg!(all(target_os = "linux", target_env = "gnu", target_arch = "x86_64")) {
        assert_eq!(report.state, reference);
    } else {
        // Another libm rounds sin/cos differently; chaos amplifies that to ~1e-11 by t = 10 s.
        let diff = crate::support::max_diff(&report.state, &reference);
        assert!(diff < 1e-9, "{diff:e}");
    }
}

/// A negative step runs backward in time to an end before the start (scipy's `solve_ivp`
/// with `t_span = (t0, t_end)`, `t_end < t0`): whole steps of |h| and a last one that lands
/// on the end. A negative step toward a later end (or the start itself), or for a step
/// count, is a wrong step, as it always was.
#[test]
fn a_negative_step_runs_backward_to_an_earlier_end() {
    let s = RunSpec { t0: 10.0, h: -1e-3, end: End::Time(0.0) }.schedule().unwrap();
    assert_eq!((s.steps, s.last_h, s.t_end), (10_000, -1e-3, 0.0));
    let s = RunSpec { t0: 1.0, h: -0.3, end: End::Time(0.0) }.schedule().unwrap();
    assert_eq!((s.steps, s.t_end), (4, 0.0));
    assert!((s.last_h + 0.1).abs() < 1e-15, "{}", s.last_h);
    for (spec, name) in [
        (RunSpec { t0: 0.0, h: -0.1, end: End::Time(1.0) }, "h"),
        (RunSpec { t0: 1.0, h: -0.1, end: End::Time(1.0) }, "h"),
        (RunSpec { t0: 1.0, h: -0.1, end: End::Time(f64::NEG_INFINITY) }, "t_end"),
        (RunSpec { t0: 0.0, h: -0.1, end: End::Steps(10) }, "h"),
        (RunSpec { t0: 0.0, h: f64::NEG_INFINITY, end: End::Time(-1.0) }, "h"),
    ] {
        match spec.schedule() {
            Err(Error::InvalidValue { name: n, .. }) => assert_eq!(n, name, "{spec:?}"),
            other => panic!("{spec:?}: {other:?}"),
        }
    }
}

/// The driven, damped oscillator run backward from t₀ = 2 s to −1 s with RK4 is its exact
/// solution: the drive is evaluated at the true, decreasing times (a run that took t − t₀ or
/// −t instead would miss it by the drive's amplitude), and every recorded time decreases.
#[test]
fn a_backward_fixed_step_run_of_the_driven_oscillator_is_exact() {
    let v =
        values("oscillator", &[("c", 0.2), ("drive_amplitude", 1.0), ("drive_frequency", 1.3), ("k", 4.0)]);
    let model = v.build();
    let y0 = v.initial_state();
    let at2 = model.exact(2.0, y0).unwrap();
    let mut rec = Recorder::default();
    let spec = RunSpec { t0: 2.0, h: -1e-3, end: End::Time(-1.0) };
    let rk4 = pendula::integrator::find("rk4").unwrap();
    let report = model.solve(rk4, &at2, &spec, &mut rec).unwrap();
    assert_eq!(report.outcome, Outcome::ReachedEnd { steps: 3000, t: -1.0 });
    let times: Vec<f64> = rec.rows.chunks(3).map(|r| r[0]).collect();
    assert_eq!((times[0], times[3000]), (2.0, -1.0));
    assert!(times.windows(2).all(|w| w[1] < w[0]));
    let exact = model.exact(-1.0, y0).unwrap();
    let diff = crate::support::max_diff(&report.state, &exact);
    assert!(diff < 1e-11, "{diff:e}");
}
