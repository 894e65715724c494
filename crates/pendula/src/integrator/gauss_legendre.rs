//! Gauss–Legendre collocation: the s-stage implicit Runge–Kutta methods of order 2s. They
//! are symplectic for every Hamiltonian system, separable or not, and symmetric; on a system
//! with a Hamiltonian form pendula runs them on (q, p), where symplecticity holds.
//!
//! The stage equations Zᵢ = h Σⱼ aᵢⱼ f(t + cⱼ h, y + Zⱼ) are solved by fixed-point
//! iteration to round-off (the update stops shrinking or vanishes), which converges when
//! h ‖∂f/∂y‖ is below about 1; beyond that the step fails with
//! [`Error::NewtonDidNotConverge`], naming the time.
//!
//! # References
//! - E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., §II.1.3
//!   (Table 1.4), §VI.4 (symplecticity), §VIII.6 (implementation).
//! - J. C. Butcher, "Implicit Runge–Kutta processes", Math. Comp. 18 (1964) 50–64.

use super::{Method, Requirement, Scheme, Stepper};
use crate::Error;
use crate::system::System;

/// The Butcher tableau of a fully implicit Runge–Kutta method.
#[derive(Debug, Clone, Copy)]
pub struct ImplicitTableau {
    /// Nodes cᵢ.
    pub c: &'static [f64],
    /// Coefficients aᵢⱼ, full s × s.
    pub a: &'static [&'static [f64]],
    /// Weights bᵢ.
    pub b: &'static [f64],
}

/// √3 and √15 to double precision (sqrt is not const).
const SQRT_3: f64 = 1.732_050_807_568_877_3;
const SQRT_15: f64 = 3.872_983_346_207_417;
const S3: f64 = SQRT_3 / 6.0;
const S15: f64 = SQRT_15;

/// Gauss–Legendre with one stage: the implicit midpoint rule, order 2.
///
/// Requirements: none (symplectic on a Hamiltonian form).
///
/// # References
/// Hairer, Lubich, Wanner, *Geometric Numerical Integration*, §II.1.3.
pub static GAUSS_LEGENDRE_2: Method = Method {
    name: "gauss-legendre-2",
    title: "implicit midpoint (Gauss-Legendre, 1 stage)",
    order: 2,
    requirement: Requirement::Any,
    symplectic: true,
    symmetric: true,
    description: "implicit midpoint rule; symplectic on any Hamiltonian system (run on (q, p))",
    reference: "Hairer, Lubich, Wanner, Geometric Numerical Integration, §II.1.3",
    scheme: Scheme::Collocation(&ImplicitTableau { c: &[1.0 / 2.0], a: &[&[1.0 / 2.0]], b: &[1.0] }),
};

/// Gauss–Legendre with two stages, order 4.
///
/// Requirements: none (symplectic on a Hamiltonian form).
///
/// # References
/// Hairer, Lubich, Wanner, *Geometric Numerical Integration*, Table II.1.4 (left).
pub static GAUSS_LEGENDRE_4: Method = Method {
    name: "gauss-legendre-4",
    title: "Gauss-Legendre, 2 stages",
    order: 4,
    requirement: Requirement::Any,
    symplectic: true,
    symmetric: true,
    description: "2-stage Gauss collocation; symplectic on any Hamiltonian system (run on (q, p))",
    reference: "Hairer, Lubich, Wanner, Geometric Numerical Integration, Table II.1.4",
    scheme: Scheme::Collocation(&ImplicitTableau {
        c: &[1.0 / 2.0 - S3, 1.0 / 2.0 + S3],
        a: &[&[1.0 / 4.0, 1.0 / 4.0 - S3], &[1.0 / 4.0 + S3, 1.0 / 4.0]],
        b: &[1.0 / 2.0, 1.0 / 2.0],
    }),
};

/// Gauss–Legendre with three stages, order 6.
///
/// Requirements: none (symplectic on a Hamiltonian form).
///
/// # References
/// Hairer, Lubich, Wanner, *Geometric Numerical Integration*, Table II.1.4 (right).
pub static GAUSS_LEGENDRE_6: Method = Method {
    name: "gauss-legendre-6",
    title: "Gauss-Legendre, 3 stages",
    order: 6,
    requirement: Requirement::Any,
    symplectic: true,
    symmetric: true,
    description: "3-stage Gauss collocation; symplectic on any Hamiltonian system (run on (q, p))",
    reference: "Hairer, Lubich, Wanner, Geometric Numerical Integration, Table II.1.4",
    scheme: Scheme::Collocation(&ImplicitTableau {
        c: &[1.0 / 2.0 - S15 / 10.0, 1.0 / 2.0, 1.0 / 2.0 + S15 / 10.0],
        a: &[
            &[5.0 / 36.0, 2.0 / 9.0 - S15 / 15.0, 5.0 / 36.0 - S15 / 30.0],
            &[5.0 / 36.0 + S15 / 24.0, 2.0 / 9.0, 5.0 / 36.0 - S15 / 24.0],
            &[5.0 / 36.0 + S15 / 30.0, 2.0 / 9.0 + S15 / 15.0, 5.0 / 36.0],
        ],
        b: &[5.0 / 18.0, 4.0 / 9.0, 5.0 / 18.0],
    }),
};

/// Iteration cap for the stage equations.
const MAX_ITERATIONS: usize = 200;

/// Steps an [`ImplicitTableau`] by fixed-point iteration; owns its buffers.
#[derive(Debug, Clone)]
pub struct Collocation {
    tableau: &'static ImplicitTableau,
    /// Stage increments Zᵢ (s × n).
    z: Vec<f64>,
    /// Stage derivatives f(t + cᵢ h, y + Zᵢ) (s × n).
    f: Vec<f64>,
    stage: Vec<f64>,
}

impl Collocation {
    /// A stepper for systems of dimension `dim`.
    pub fn new(tableau: &'static ImplicitTableau, dim: usize) -> Self {
        let s = tableau.b.len();
        Collocation { tableau, z: vec![0.0; s * dim], f: vec![0.0; s * dim], stage: vec![0.0; dim] }
    }

    /// f at every stage for the current increments.
    fn evaluate<S: System + ?Sized>(&mut self, system: &S, t: f64, h: f64, y: &[f64]) {
        let n = y.len();
        for (i, c) in self.tableau.c.iter().enumerate() {
            for (j, s) in self.stage.iter_mut().enumerate() {
                *s = y[j] + self.z[i * n + j];
            }
            system.rhs(t + c * h, &self.stage, &mut self.f[i * n..(i + 1) * n]);
        }
    }
}

impl<S: System + ?Sized> Stepper<S> for Collocation {
    fn step(&mut self, system: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        let n = y.len();
        let tab = self.tableau;
        // Start from Zᵢ = cᵢ h f(t, y), the increments of the constant-slope guess.
        system.rhs(t, y, &mut self.stage);
        for (i, c) in tab.c.iter().enumerate() {
            for j in 0..n {
                self.z[i * n + j] = c * h * self.stage[j];
            }
        }
        let mut previous = f64::INFINITY;
        let mut converged = false;
        for _ in 0..MAX_ITERATIONS {
            self.evaluate(system, t, h, y);
            let mut delta = 0.0_f64;
            for (i, row) in tab.a.iter().enumerate() {
                for (j, yj) in y.iter().enumerate() {
                    let mut acc = 0.0;
                    for (k, a) in row.iter().enumerate() {
                        acc += a * self.f[k * n + j];
                    }
                    let new = h * acc;
                    let old = &mut self.z[i * n + j];
                    delta = delta.max((new - *old).abs() / (1.0 + yj.abs()));
                    *old = new;
                }
            }
            if !delta.is_finite() {
                break;
            }
            // Converged: the update vanished, or stopped shrinking at round-off level.
            if delta <= f64::EPSILON || (delta >= previous && delta < 1e-12) {
                converged = true;
                break;
            }
            previous = delta;
        }
        if !converged {
            return Err(Error::NewtonDidNotConverge { t, iterations: MAX_ITERATIONS });
        }
        self.evaluate(system, t, h, y);
        for (j, yj) in y.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (i, b) in tab.b.iter().enumerate() {
                acc += b * self.f[i * n + j];
            }
            *yj += h * acc;
        }
        Ok(())
    }
}
