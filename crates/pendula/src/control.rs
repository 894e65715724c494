//! Step-size control for embedded pairs, kept apart from the methods (as in diffrax and
//! OrdinaryDiffEq): a PI controller on the scaled error norm.

use crate::Error;

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
        check("rtol", self.rtol, self.rtol.is_finite() && self.rtol > 0.0, "must be finite and > 0")?;
        check("atol", self.atol, self.atol.is_finite() && self.atol >= 0.0, "must be finite and >= 0")?;
        check("h-min", self.h_min, self.h_min.is_finite() && self.h_min >= 0.0, "must be finite and >= 0")?;
        check("h-max", self.h_max, self.h_max > self.h_min, "must be > h-min")
    }
}

/// The PI step-size controller of Hairer's DOPRI5 (Gustafsson's, with β = 0.04): the next
/// step is h · (1/err)^(1/q − 0.75 β) · err_prev^β · 0.9, clamped to [h/5, 10 h], where q is
/// the error estimate's order + 1.
///
/// # References
/// Hairer, Nørsett, Wanner, *Solving ODEs I*, §IV.2 (PI control) and the DOPRI5 code.
#[derive(Debug, Clone, Copy)]
pub struct PiController {
    expo: f64,
    beta: f64,
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
    /// A controller for an error estimate of order `error_order`.
    pub fn new(error_order: u32) -> Self {
        let beta = 0.04;
        PiController { expo: 1.0 / (error_order as f64 + 1.0) - 0.75 * beta, beta, previous: 1e-4 }
    }

    /// Judges a step of size h whose scaled error norm was `err`.
    pub fn judge(&mut self, h: f64, err: f64) -> Verdict {
        const SAFE: f64 = 0.9;
        let err = if err.is_finite() { err } else { f64::MAX };
        let fac11 = err.powf(self.expo);
        if err <= 1.0 {
            let fac = (fac11 / self.previous.powf(self.beta) / SAFE).clamp(0.1, 5.0);
            self.previous = err.max(1e-4);
            Verdict::Accept(h / fac)
        } else {
            Verdict::Reject(h / (fac11 / SAFE).min(5.0))
        }
    }
}
