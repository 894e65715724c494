//! Stroboscopic samples of a driven system on the scalar path: the state once per drive
//! period, after a transient — the section of the extended phase space at drive phase 0.
//! (The damped, driven pendulum also runs on the ensemble engine:
//! [`crate::ensemble::driven`].)

use std::ops::ControlFlow;

use crate::integrator::Method;
use crate::model::DynModel;
use crate::observe::{Flow, Observer, Sample};
use crate::{End, Error, RunSpec};

/// Keeps the state every `every` steps once `from` steps have passed.
struct Strobe {
    every: u64,
    from: u64,
    rows: Vec<f64>,
}

impl Observer for Strobe {
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
    let mut strobe = Strobe { every, from: every * (transient_periods + 1), rows: Vec::new() };
    model.solve(method, y0, &spec, &mut strobe)?;
    Ok(strobe.rows)
}
