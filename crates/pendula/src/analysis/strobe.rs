//! Stroboscopic samples of a driven system: the state once per drive period, after a
//! transient — the section of the extended phase space at drive phase 0. One run on the
//! scalar path ([`stroboscopic`]); an orbit diagram, many values at once, on the ensemble
//! engine's lanes ([`orbit_diagram`], [`crate::ensemble::engine::stroboscopic`]).

use std::ops::ControlFlow;

use crate::ensemble::engine::Strobe;
use crate::integrator::Method;
use crate::model::DynModel;
use crate::observe::{Flow, Observer, Sample};
use crate::system::Values;
use crate::{End, Error, RunSpec};

/// Keeps the state every `every` steps once `from` steps have passed.
struct Sampler {
    every: u64,
    from: u64,
    rows: Vec<f64>,
}

impl Observer for Sampler {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        if s.step >= self.from && s.step > 0 && s.step.is_multiple_of(self.every) {
            self.rows.extend_from_slice(s.y);
        }
        ControlFlow::Continue(())
    }
}

/// The state of `model` from `y0` after each of `samples` drive periods `period` (s) that
/// follow `transient_periods` periods, with `steps_per_period` fixed steps of `method` per
/// period: `samples` rows of the state, angles as integrated (not wrapped).
///
/// # Errors
/// Those of the run.
pub fn stroboscopic(
    model: &dyn DynModel,
    method: &Method,
    y0: &[f64],
    period: f64,
    steps_per_period: u32,
    transient_periods: u64,
    samples: usize,
) -> Result<Vec<f64>, Error> {
    let every = u64::from(steps_per_period);
    let steps = every * (transient_periods + samples as u64);
    let spec = RunSpec { t0: 0.0, h: period / f64::from(steps_per_period), end: End::Steps(steps) };
    let mut strobe = Sampler { every, from: every * (transient_periods + 1), rows: Vec::new() };
    model.solve(method, y0, &spec, &mut strobe)?;
    Ok(strobe.rows)
}

/// What an orbit diagram ([`orbit_diagram`]) samples for each parameter value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitDiagramSpec {
    /// Time discarded before the first sample, s, rounded up to whole drive periods.
    pub transient: f64,
    /// Samples (drive periods) per value.
    pub samples: usize,
    /// RK4 steps per drive period (≥ 4).
    pub steps_per_period: u32,
}

/// A stroboscopic orbit diagram: for each of `values` (one driven system, its parameters
/// varied along the diagram's axis), the state once per drive period 2π/`drive_frequency`
/// for `spec.samples` periods after ⌈transient / period⌉ periods, by RK4 at
/// `spec.steps_per_period` steps a period, from the values' initial state. Rows of the state
/// (values × samples rows), angles wrapped into [−π, π). Every system runs on the ensemble
/// engine's SIMD lanes ([`crate::ensemble::engine::stroboscopic`]), each value stepping its
/// own period, in parallel on rayon's current pool, with results that do not depend on its
/// size.
///
/// # Errors
/// [`Error::InvalidValue`] for a drive frequency that is not > 0, fewer than 4 steps a
/// period or a transient that is not finite and ≥ 0; [`Error::NonFiniteMember`] (member =
/// index into `values`).
pub fn orbit_diagram(values: &[Values], spec: &OrbitDiagramSpec) -> Result<Vec<f64>, Error> {
    if !(spec.transient.is_finite() && spec.transient >= 0.0) {
        return Err(Error::InvalidValue {
            name: "transient".into(),
            value: spec.transient,
            allowed: "must be finite and >= 0",
        });
    }
    if spec.steps_per_period < 4 {
        return Err(Error::InvalidValue {
            name: "steps_per_period".into(),
            value: f64::from(spec.steps_per_period),
            allowed: "must be at least 4",
        });
    }
    let mut periods = Vec::with_capacity(values.len());
    for v in values {
        let w = v.get("drive_frequency");
        if !(w.is_finite() && w > 0.0) {
            return Err(Error::InvalidValue {
                name: "drive_frequency".into(),
                value: w,
                allowed: "a stroboscopic diagram needs a drive: must be finite and > 0",
            });
        }
        let period = 2.0 * std::f64::consts::PI / w;
        periods.push((period, (spec.transient / period).ceil() as u64));
    }
    let Some(first) = values.first() else { return Ok(Vec::new()) };
    let info = first.info();
    // Every system's RK4 runs on the engine's lanes, each value stepping its own period.
    let quantities: Vec<&str> = info.quantities().map(|q| q.name).collect();
    let member = |i: usize, v: &mut [f64]| {
        for (slot, name) in v.iter_mut().zip(&quantities) {
            *slot = values[i].get(name);
        }
    };
    let strobe = Strobe {
        steps_per_period: spec.steps_per_period,
        samples: spec.samples,
        periods: &|i| periods[i],
        cancel: None,
    };
    let mut data = vec![0.0; values.len() * spec.samples * info.state.len()];
    let members = crate::ensemble::engine::Members { info, count: values.len(), values: &member };
    first.build().stroboscopic(&members, &strobe, &mut data)?;
    Ok(data)
}
