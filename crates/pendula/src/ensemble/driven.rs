//! Stroboscopic sampling of many damped, driven pendulums ([`DrivenPendulum`]): the typed
//! front of the engine's stroboscopic runs ([`super::engine::stroboscopic`]), each member
//! stepping its own drive period / `steps_per_period` with RK4, sampled once per period
//! after its transient — the Poincaré section of the extended phase space at phase 0.

use crate::Error;
use crate::system::Model;
use crate::system::driven::DrivenPendulum;

/// One member: a driven pendulum, its start (θ, ω), and how many whole periods to discard.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrivenMember {
    /// The pendulum.
    pub pendulum: DrivenPendulum,
    /// Initial (θ, ω).
    pub state: [f64; 2],
    /// Drive periods run before the first sample.
    pub transient_periods: u64,
}

/// How to sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StroboSpec {
    /// RK4 steps per drive period (M ≥ 4).
    pub steps_per_period: u32,
    /// Samples per member, one per period after its transient.
    pub samples: usize,
}

/// Samples every member: `out[(member · samples + s) · 2 ..]` receives (θ, ω) of sample s.
///
/// # Errors
/// The first member (in index order) whose state became non-finite, with the time.
///
/// # Panics
/// If `out` does not hold members × samples × 2 values or `steps_per_period < 4`.
pub fn stroboscopic(members: &[DrivenMember], spec: &StroboSpec, out: &mut [f64]) -> Result<(), Error> {
    assert!(spec.steps_per_period >= 4, "at least 4 steps per period");
    let values = |i: usize, v: &mut [f64]| {
        let DrivenMember { pendulum: p, state, .. } = members[i];
        v.copy_from_slice(&[p.q, p.drive_amplitude, p.drive_frequency, state[0], state[1]]);
    };
    let periods = |i: usize| {
        let m = &members[i];
        (2.0 * std::f64::consts::PI / m.pendulum.drive_frequency, m.transient_periods)
    };
    let strobe = super::engine::Strobe {
        steps_per_period: spec.steps_per_period,
        samples: spec.samples,
        periods: &periods,
        cancel: None,
    };
    let members =
        super::engine::Members { info: DrivenPendulum::INFO, count: members.len(), values: &values };
    super::engine::stroboscopic::<DrivenPendulum>(&members, &strobe, out)
}
