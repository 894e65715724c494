//! Step-size control for embedded pairs, kept apart from the methods (as in diffrax and
//! OrdinaryDiffEq): a PI controller on the scaled error norm.

use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};

/// The smallest relative tolerance: about 4.5 ε. Below it the error estimate is round-off,
/// which no step size can bring under the tolerance.
pub const MIN_RTOL: f64 = 1e-15;

/// Tolerances and step bounds of an adaptive run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance, in the state's units.
    pub atol: f64,
    /// Smallest step allowed, s; a smaller proposal is [`Error::StepSizeTooSmall`].
    pub h_min: f64,
    /// Largest step allowed, s.
    pub h_max: f64,
}

impl Tolerances {
    /// Checks the values.
    pub fn validate(&self) -> Result<(), Error> {
        let check = |name: &str, v: f64, ok: bool, allowed| {
            if ok { Ok(()) } else { Err(Error::InvalidValue { name: name.to_owned(), value: v, allowed }) }
        };
        check(
            "rtol",
            self.rtol,
            (MIN_RTOL..=1.0).contains(&self.rtol),
            "must be > 0, at least 1e-15 (a smaller relative tolerance is below round-off) and at most 1",
        )?;
        check("atol", self.atol, self.atol.is_finite() && self.atol >= 0.0, "must be finite and >= 0")?;
        check("h-min", self.h_min, self.h_min.is_finite() && self.h_min >= 0.0, "must be finite and >= 0")?;
        check("h-max", self.h_max, self.h_max > self.h_min, "must be > h-min")
    }
}

/// The parameters of a [`PiController`], part of each embedded pair's data (Hairer's codes
/// use different ones for DOPRI5 and DOP853).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlParams {
    /// Exponent α on the current error: 1/q − (weight) β for an error estimate of order q − 1.
    pub alpha: f64,
    /// Exponent β on the previous step's error (0: a plain I controller).
    pub beta: f64,
    /// Safety factor on the proposed step.
    pub safety: f64,
    /// Smallest factor by which a step may shrink.
    pub min_factor: f64,
    /// Largest factor by which a step may grow.
    pub max_factor: f64,
}

/// DOPRI5's defaults: α = 1/5 − 0.75 β, β = 0.04, safety 0.9, factors in [0.2, 10].
pub const DOPRI5_CONTROL: ControlParams =
    ControlParams { alpha: 0.2 - 0.75 * 0.04, beta: 0.04, safety: 0.9, min_factor: 0.2, max_factor: 10.0 };

/// DOP853's defaults: α = 1/8, β = 0, safety 0.9, factors in [0.333, 6].
pub const DOP853_CONTROL: ControlParams =
    ControlParams { alpha: 1.0 / 8.0, beta: 0.0, safety: 0.9, min_factor: 0.333, max_factor: 6.0 };

/// The PI step-size controller of Hairer's DOPRI5 and DOP853 (Gustafsson's): the next step
/// is h · safety · err^(−α) · err_prev^β, the factor clamped to [min_factor, max_factor];
/// a rejected step shrinks by safety · err^(−α), at most to min_factor h.
///
/// # References
/// Hairer, Nørsett, Wanner, *Solving ODEs I*, §II.4 and §IV.2 (PI control), and the DOPRI5
/// and DOP853 codes.
#[derive(Debug, Clone, Copy)]
pub struct PiController {
    params: ControlParams,
    previous: f64,
}

/// The controller's verdict on an attempted step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict {
    /// Keep the step; try this size next.
    Accept(f64),
    /// Redo the step with this smaller size.
    Reject(f64),
}

impl PiController {
    /// A controller with these parameters.
    pub fn new(params: &ControlParams) -> Self {
        PiController { params: *params, previous: 1e-4 }
    }

    /// Judges a step of size h whose scaled error norm was `err`.
    pub fn judge(&mut self, h: f64, err: f64) -> Verdict {
        let ControlParams { alpha, beta, safety, min_factor, max_factor } = self.params;
        let err = if err.is_finite() { err } else { f64::MAX };
        // The step shrinks by `fac`: h / fac (the form of Hairer's codes).
        let fac11 = err.powf(alpha);
        if err <= 1.0 {
            let fac = (fac11 / self.previous.powf(beta) / safety).clamp(1.0 / max_factor, 1.0 / min_factor);
            self.previous = err.max(1e-4);
            Verdict::Accept(h / fac)
        } else {
            Verdict::Reject(h / (fac11 / safety).min(1.0 / min_factor))
        }
    }
}

/// The previous step's error, which the PI controller's next proposal depends on.
impl Snapshot for PiController {
    fn save(&self, out: &mut Words) {
        out.f64(self.previous);
    }
    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        self.previous = from.f64()?;
        Ok(())
    }
}
