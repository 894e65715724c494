//! Embedded Runge–Kutta pairs: two solutions of different orders from the same stages,
//! whose difference estimates the local error for step-size control
//! ([`crate::control::PiController`]). With a fixed step they are ordinary explicit methods
//! of the higher order.
//!
//! # References
//! - J. R. Dormand, P. J. Prince, "A family of embedded Runge–Kutta formulae", J. Comput.
//!   Appl. Math. 6 (1980) 19–26.
//! - E. Hairer, S. P. Nørsett, G. Wanner, *Solving ODEs I*, §II.4 (Table 5.2) and §II.5.

use super::{Method, Requirement, Scheme, Stepper};
use crate::Error;
use crate::system::System;

/// The tableau of an embedded pair.
#[derive(Debug, Clone, Copy)]
pub struct EmbeddedTableau {
    /// Nodes cᵢ.
    pub c: &'static [f64],
    /// Strictly lower triangular coefficients aᵢⱼ (row i has i entries).
    pub a: &'static [&'static [f64]],
    /// Weights of the propagated solution (order [`Method::order`]).
    pub b: &'static [f64],
    /// Weights of the embedded solution, of order `error_order`.
    pub b_hat: &'static [f64],
    /// Order of the embedded solution.
    pub error_order: u32,
    /// The last stage is f at the new point (first same as last), reused by the next step.
    pub fsal: bool,
}

/// Dormand–Prince 5(4): 7 stages, 6 evaluations per accepted step (FSAL), order 5 with an
/// order-4 error estimate.
///
/// Requirements: none.
///
/// # References
/// Dormand & Prince (1980); Hairer, Nørsett, Wanner, *Solving ODEs I*, Table II.5.2.
pub static DOPRI5: Method = Method {
    name: "dopri5",
    title: "Dormand-Prince 5(4)",
    order: 5,
    requirement: Requirement::Any,
    symplectic: false,
    symmetric: false,
    description: "adaptive Dormand-Prince 5(4) with a PI step-size controller (--rtol, --atol)",
    reference: "Dormand & Prince, J. Comput. Appl. Math. 6 (1980) 19; Hairer, Norsett, Wanner, Table II.5.2",
    scheme: Scheme::Embedded(&EmbeddedTableau {
        c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
        a: &[
            &[],
            &[1.0 / 5.0],
            &[3.0 / 40.0, 9.0 / 40.0],
            &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
            &[19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0],
            &[9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0],
            &[35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
        ],
        b: &[35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0],
        b_hat: &[
            5179.0 / 57600.0,
            0.0,
            7571.0 / 16695.0,
            393.0 / 640.0,
            -92097.0 / 339200.0,
            187.0 / 2100.0,
            1.0 / 40.0,
        ],
        error_order: 4,
        fsal: true,
    }),
};

/// Steps an embedded pair; owns its stage buffers, the candidate and its error estimate.
#[derive(Debug, Clone)]
pub struct EmbeddedRk {
    tableau: &'static EmbeddedTableau,
    k: Vec<f64>,
    stage: Vec<f64>,
    /// The candidate solution of the last attempt.
    candidate: Vec<f64>,
    /// The error estimate of the last attempt (propagated minus embedded solution).
    error: Vec<f64>,
    /// k₁ holds f(t, y) for this (t, y) from the previous accepted step.
    first_stage: Option<f64>,
}

impl EmbeddedRk {
    /// A stepper for systems of dimension `dim`.
    pub fn new(tableau: &'static EmbeddedTableau, dim: usize) -> Self {
        EmbeddedRk {
            tableau,
            k: vec![0.0; tableau.b.len() * dim],
            stage: vec![0.0; dim],
            candidate: vec![0.0; dim],
            error: vec![0.0; dim],
            first_stage: None,
        }
    }

    /// Tries a step from (t, y) of size h: computes the candidate and its error estimate,
    /// leaving `y` unchanged.
    pub fn attempt<S: System + ?Sized>(&mut self, system: &S, t: f64, h: f64, y: &[f64]) {
        let tab = self.tableau;
        let n = y.len();
        let first = usize::from(self.first_stage == Some(t));
        super::explicit_rk::explicit_stages(
            tab.a,
            tab.c,
            first,
            &mut self.k,
            &mut self.stage,
            system,
            t,
            h,
            y,
        );
        for (j, yj) in y.iter().enumerate() {
            let (mut high, mut low) = (0.0, 0.0);
            for (i, (b, bh)) in tab.b.iter().zip(tab.b_hat).enumerate() {
                high += b * self.k[i * n + j];
                low += bh * self.k[i * n + j];
            }
            self.candidate[j] = yj + h * high;
            self.error[j] = h * (high - low);
        }
    }

    /// The scaled RMS norm of the last error estimate: √(mean (eᵢ / (atol + rtol max(|yᵢ|,
    /// |ŷᵢ|)))²) (Hairer, Nørsett, Wanner §II.4, (4.11)); ≤ 1 means acceptable.
    pub fn error_norm(&self, y: &[f64], rtol: f64, atol: f64) -> f64 {
        let sum: f64 = y
            .iter()
            .zip(&self.candidate)
            .zip(&self.error)
            .map(|((a, b), e)| {
                let scale = atol + rtol * a.abs().max(b.abs());
                (e / scale) * (e / scale)
            })
            .sum();
        (sum / y.len() as f64).sqrt()
    }

    /// Takes the candidate: `y` becomes it, and with FSAL its last stage becomes the next
    /// step's first at `t_new`.
    pub fn accept(&mut self, y: &mut [f64], t_new: f64) {
        y.copy_from_slice(&self.candidate);
        let n = y.len();
        let s = self.tableau.b.len();
        if self.tableau.fsal {
            self.k.copy_within((s - 1) * n..s * n, 0);
            self.first_stage = Some(t_new);
        } else {
            self.first_stage = None;
        }
    }
}

impl<S: System + ?Sized> Stepper<S> for EmbeddedRk {
    fn step(&mut self, system: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        // With a fixed step the FSAL stage is reused only if this step starts where the last
        // ended, which `first_stage` records.
        self.attempt(system, t, h, y);
        self.accept(y, t + h);
        Ok(())
    }
}
