//! Long runs: on the double pendulum at h = 0.01 over 10⁶ steps, the symplectic methods
//! keep the energy error bounded while explicit Euler and RK4 drift.
//!
//! The measure is max |E − E₀| over the last tenth of the run against the first tenth: a
//! bounded error gives a ratio near 1, a linear drift a ratio near 10.

use std::ops::ControlFlow;

use pendula::integrator::{self, Method, Requirement, Scheme};
use pendula::model::DynModel;
use pendula::observe::{Flow, Observer, Sample};
use pendula::{End, Error, RunSpec};

use crate::support::values;

const STEPS: u64 = 1_000_000;

/// max |E − E₀| over the first and the last tenth of a run of `steps` steps.
pub(crate) struct Tenths<'a> {
    pub model: &'a dyn DynModel,
    pub steps: u64,
    pub e0: Option<f64>,
    pub first: f64,
    pub last: f64,
}

impl Observer for Tenths<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        let e = self.model.energy(s.t, s.y);
        let err = (e - *self.e0.get_or_insert(e)).abs();
        if s.step <= self.steps / 10 {
            self.first = self.first.max(err);
        }
        if s.step >= self.steps - self.steps / 10 {
            self.last = self.last.max(err);
        }
        ControlFlow::Continue(())
    }
}

/// (first-tenth error, last-tenth error) over `steps` steps of h = 0.01 from the default
/// state (120°, −10°), or the run's error.
fn tenths(method: &Method, steps: u64) -> Result<(f64, f64), Error> {
    tenths_at(method, 0.01, steps)
}

/// The same at step h.
fn tenths_at(method: &Method, h: f64, steps: u64) -> Result<(f64, f64), Error> {
    let values = values("double", &[]);
    let model = values.build();
    let mut obs = Tenths { model: &*model, steps, e0: None, first: 0.0, last: 0.0 };
    let spec = RunSpec { t0: 0.0, h, end: End::Steps(steps) };
    model.solve(method, values.initial_state(), &spec, &mut obs)?;
    eprintln!("{}: first tenth {:.3e} J, last tenth {:.3e} J", method.name, obs.first, obs.last);
    Ok((obs.first, obs.last))
}

/// Every symplectic method that applies to the double pendulum (all but the compositions,
/// which need a separable H) keeps its energy error bounded over 10⁶ steps: at h = 10 ms, and
/// Tao's maps at h = 2 ms with their default binding ω = 200 (ω h = 0.4).
#[test]
fn ref_symplectic_methods_keep_energy_bounded() {
    let mut checked = Vec::new();
    for method in
        integrator::METHODS.iter().filter(|m| m.symplectic && m.requirement != Requirement::Separable)
    {
        let h = if matches!(method.scheme, Scheme::Tao(_)) { 0.002 } else { 0.01 };
        let (first, last) = tenths_at(method, h, STEPS).unwrap();
        assert!(last <= 2.0 * first, "{}: {first:e} then {last:e}", method.name);
        checked.push(method.name);
    }
    assert_eq!(checked.len(), 7, "{checked:?}");
}

/// tao-4 at h = 10 ms: the default binding ω = 200 gives ω h = 2, refused (unstable).
#[test]
fn tao_refuses_an_unstable_binding() {
    let err = tenths_at(integrator::find("tao-4").unwrap(), 0.01, 10).unwrap_err();
    assert!(matches!(err, Error::InvalidValue { .. }), "{err:?}");
    assert!(err.to_string().contains("binding"), "{err}");
}

#[test]
fn ref_explicit_methods_drift() {
    // RK4 loses energy at a steady rate over the whole run.
    let (first, last) = tenths(&integrator::explicit_rk::RK4, STEPS).unwrap();
    assert!(last > 5.0 * first, "rk4: {first:e} then {last:e}");
    // Explicit Euler gains energy linearly over its first 10³ steps, then saturates near
    // 100 J (from 0.149 J) once the pendulum whirls: over 10⁶ steps both tenths are already
    // about a thousand times the initial energy and ~100 times Verlet's bounded error.
    let (first, last) = tenths(&integrator::explicit_rk::EULER, 1000).unwrap();
    assert!(last > 5.0 * first, "euler over 10^3 steps: {first:e} then {last:e}");
    let (first, _) = tenths(&integrator::explicit_rk::EULER, STEPS).unwrap();
    let (_, verlet) = tenths(integrator::find("verlet").unwrap(), STEPS).unwrap();
    assert!(first > 100.0 * verlet, "euler {first:e} vs verlet {verlet:e}");
}

/// Yoshida-6 on the simple pendulum from 60°: over 10⁶ steps of h = 0.01 the energy error is
/// bounded, and its size scales as h⁶ (halving h divides it by 2⁶ = 64, within 25%).
#[test]
fn ref_yoshida_6_energy_error_is_bounded_at_order_6() {
    let values = values("pendulum", &[]);
    let model = values.build();
    let method = integrator::find("yoshida-6").unwrap();
    let run = |h: f64, steps: u64| {
        let mut obs = Tenths { model: &*model, steps, e0: None, first: 0.0, last: 0.0 };
        let spec = RunSpec { t0: 0.0, h, end: End::Steps(steps) };
        model.solve(method, values.initial_state(), &spec, &mut obs).unwrap();
        (obs.first, obs.last)
    };
    let (first, last) = run(0.01, STEPS);
    eprintln!("yoshida-6: first tenth {first:.3e} J, last tenth {last:.3e} J");
    assert!(last <= 2.0 * first, "{first:e} then {last:e}");
    // Short runs over the same 100 s at h = 0.1 and 0.05 (errors far above round-off).
    let (coarse, fine) = (run(0.1, 1000).0.max(run(0.1, 1000).1), run(0.05, 2000).0.max(run(0.05, 2000).1));
    let ratio = coarse / fine;
    eprintln!("yoshida-6: max |dE| {coarse:.3e} J at h = 0.1, {fine:.3e} J at h = 0.05, ratio {ratio:.1}");
    assert!((ratio / 64.0 - 1.0).abs() < 0.25, "ratio {ratio}");
}
