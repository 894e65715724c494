//! The largest stable step of a method on a problem, by bisection.

use std::ops::ControlFlow;

use super::energy::EnergyBalance;
use crate::integrator::Method;
use crate::model::DynModel;
use crate::observe::{Flow, Observer, Sample, Stop};
use crate::{End, Error, RunSpec};

/// When a run counts as stable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityCriterion {
    /// Length of the test run, s.
    pub t_end: f64,
    /// Largest allowed relative energy error at any step, against the system's energy scale
    /// (the energy balance error for damped or driven systems; see [`EnergyBalance`]).
    pub max_rel_energy_error: f64,
}

/// Stops a run as soon as the energy error exceeds the bound.
struct Guard<'a> {
    balance: EnergyBalance<'a>,
    bound: f64,
    exceeded: bool,
}

impl Observer for Guard<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        let error = self.balance.track(s.t, s.y, s.energy);
        if error.abs() > self.bound * self.balance.scale {
            self.exceeded = true;
            return ControlFlow::Break(Stop::Enough);
        }
        ControlFlow::Continue(())
    }
}

/// Whether `method` at step `h` stays finite with a bounded energy error.
pub fn is_stable(
    model: &dyn DynModel,
    method: &Method,
    y0: &[f64],
    h: f64,
    criterion: &StabilityCriterion,
) -> Result<bool, Error> {
    // Tao's maps are refused (unstable) above ω h = 1: that is instability, not an error.
    if let crate::integrator::Scheme::Tao(tao) = method.scheme
        && crate::integrator::tao::check_binding_step(&tao, h).is_err()
    {
        return Ok(false);
    }
    let balance = EnergyBalance::new(model, y0);
    let mut guard = Guard { balance, bound: criterion.max_rel_energy_error, exceeded: false };
    let spec = RunSpec { t0: 0.0, h, end: End::Time(criterion.t_end) };
    match model.solve(method, y0, &spec, &mut guard) {
        Ok(_) => Ok(!guard.exceeded),
        Err(Error::NonFinite { .. } | Error::NewtonDidNotConverge { .. }) => Ok(false),
        Err(e) => Err(e),
    }
}

/// The largest step `method` accepts at all, s, when it has such a limit: Tao's maps refuse
/// ω h > 1 (ω the binding constant). A refusal is not an instability, and studies report it
/// as what it is.
pub fn accepted_step_limit(method: &Method) -> Option<f64> {
    match method.scheme {
        crate::integrator::Scheme::Tao(tao) => Some(1.0 / tao.binding),
        _ => None,
    }
}

/// The largest step in [`h_min`, `h_max`] (capped at [`accepted_step_limit`]) at which the run is stable, by bisection in log h
/// to 1% (`None` if even `h_min` is unstable; `h_max` if it is stable).
///
/// Stability is not always monotone in h (a method can be stable again at a larger step in
/// a resonance window); bisection finds one boundary between a stable `h_min` and an
/// unstable `h_max`.
pub fn largest_stable_step(
    model: &dyn DynModel,
    method: &Method,
    y0: &[f64],
    h_min: f64,
    h_max: f64,
    criterion: &StabilityCriterion,
) -> Result<Option<f64>, Error> {
    let h_max = accepted_step_limit(method).map_or(h_max, |limit| h_max.min(limit));
    if !is_stable(model, method, y0, h_min, criterion)? {
        return Ok(None);
    }
    if is_stable(model, method, y0, h_max, criterion)? {
        return Ok(Some(h_max));
    }
    let (mut lo, mut hi) = (h_min, h_max);
    while hi / lo > 1.01 {
        let mid = (lo * hi).sqrt();
        if is_stable(model, method, y0, mid, criterion)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Some(lo))
}
