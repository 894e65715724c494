//! Gauss–Legendre collocation: the s-stage implicit Runge–Kutta methods of order 2s. They
//! are symplectic for every Hamiltonian system, separable or not, and symmetric; on a system
//! with a Hamiltonian form pendula runs them on (q, p), where symplecticity holds.
//!
//! The stage equations Zᵢ = h Σⱼ aᵢⱼ f(t + cⱼ h, y + Zⱼ) are solved to round-off (the
//! update vanishes or stops shrinking) by Newton iteration when the system has a Jacobian
//! ([`System::jacobian`]: analytic, or by num-dual): first simplified Newton, with one
//! Jacobian J(t, y) and one LU factorisation of I − h A ⊗ J per step (Hairer, Wanner,
//! *Solving ODEs II*, §IV.8); if that stops contracting, full Newton, which factorises
//! I − h (A ⊗ I) diag(J(Y₁) … J(Yₛ)) in every iteration. Without a Jacobian, or when Newton fails, fixed-point iteration is used, which
//! converges while h ‖∂f/∂y‖ is below about 1. When both fail the step is
//! [`Error::NewtonDidNotConverge`], naming the time.
//!
//! # References
//! - E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., §II.1.3
//!   (Table 1.4), §VI.4 (symplecticity), §VIII.6 (implementation).
//! - J. C. Butcher, "Implicit Runge–Kutta processes", Math. Comp. 18 (1964) 50–64.
//! - E. Hairer, G. Wanner, *Solving ODEs II*, 2nd ed., §IV.8 (simplified Newton iteration).

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

/// Iteration cap of the fixed-point iteration.
const MAX_ITERATIONS: usize = 200;

/// Iteration cap of full Newton iteration (it converges in a few where it converges at all).
const MAX_NEWTON_ITERATIONS: usize = 30;

/// Iteration cap of simplified Newton iteration, before full Newton takes over.
const MAX_SIMPLIFIED_ITERATIONS: usize = 12;

/// How the stage equations were solved in the last step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solver {
    /// Simplified Newton iteration (one Jacobian per step), in this many iterations.
    SimplifiedNewton(usize),
    /// Full Newton iteration (Jacobians at every stage and iteration), in this many
    /// iterations, after simplified Newton stopped contracting.
    Newton(usize),
    /// Fixed-point iteration, in this many iterations (no Jacobian, or Newton failed).
    FixedPoint(usize),
}

/// Steps an [`ImplicitTableau`] by Newton iteration (fixed-point iteration as the fallback);
/// owns its buffers.
#[derive(Debug, Clone)]
pub struct Collocation {
    tableau: &'static ImplicitTableau,
    /// Stage increments Zᵢ (s × n).
    z: Vec<f64>,
    /// Stage derivatives f(t + cᵢ h, y + Zᵢ) (s × n).
    f: Vec<f64>,
    stage: Vec<f64>,
    /// ∂f/∂y at each stage (s × n × n).
    jac: Vec<f64>,
    /// LU factors of I − h A ⊗ J (sn × sn) and their row permutation.
    lu: Vec<f64>,
    pivots: Vec<usize>,
    /// Newton residual and correction (sn).
    residual: Vec<f64>,
    /// Whether to try Newton (cleared for systems without a Jacobian).
    newton: bool,
    /// How the last step's stage equations were solved.
    pub last_solver: Option<Solver>,
}

impl Collocation {
    /// A stepper for systems of dimension `dim`.
    pub fn new(tableau: &'static ImplicitTableau, dim: usize) -> Self {
        let s = tableau.b.len();
        let big = s * dim;
        Collocation {
            tableau,
            z: vec![0.0; big],
            f: vec![0.0; big],
            stage: vec![0.0; dim],
            jac: vec![0.0; s * dim * dim],
            lu: vec![0.0; big * big],
            pivots: vec![0; big],
            residual: vec![0.0; big],
            newton: true,
            last_solver: None,
        }
    }

    /// A stepper that uses fixed-point iteration only, even where a Jacobian exists.
    pub fn fixed_point_only(tableau: &'static ImplicitTableau, dim: usize) -> Self {
        Collocation { newton: false, ..Self::new(tableau, dim) }
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

    /// Zᵢ = cᵢ h f(t, y), the increments of the constant-slope guess.
    fn initial_guess<S: System + ?Sized>(&mut self, system: &S, t: f64, h: f64, y: &[f64]) {
        let n = y.len();
        system.rhs(t, y, &mut self.stage);
        for (i, c) in self.tableau.c.iter().enumerate() {
            for j in 0..n {
                self.z[i * n + j] = c * h * self.stage[j];
            }
        }
    }

    /// Solves the stage equations by Newton iteration: returns the iterations taken, or
    /// `None` if it diverged or did not reach round-off (or there is no Jacobian).
    ///
    /// Simplified Newton (`full` false) factorises I − h A ⊗ J(t, y) once per step; full
    /// Newton evaluates the Jacobian at every stage and factorises
    /// I − h (A ⊗ I) diag(J(Y₁) … J(Yₛ)) in every iteration. The first is cheap and enough at
    /// ordinary steps; on a fast-rotating pendulum, whose Jacobian turns with the angles
    /// within one step, only the second converges at large steps.
    fn solve_newton<S: System + ?Sized>(
        &mut self,
        system: &S,
        t: f64,
        h: f64,
        y: &[f64],
        full: bool,
    ) -> Option<usize> {
        let n = y.len();
        let s = self.tableau.b.len();
        if !system.jacobian(t, y, &mut self.jac[..n * n]) {
            return None;
        }
        if !full {
            for k in 1..s {
                self.jac.copy_within(..n * n, k * n * n);
            }
            if !self.factor_newton_matrix(h, n) {
                return None;
            }
        }
        self.initial_guess(system, t, h, y);
        let mut previous = f64::INFINITY;
        let cap = if full { MAX_NEWTON_ITERATIONS } else { MAX_SIMPLIFIED_ITERATIONS };
        for iteration in 1..=cap {
            self.evaluate(system, t, h, y);
            if full {
                for (k, c) in self.tableau.c.iter().enumerate() {
                    for (j, st) in self.stage.iter_mut().enumerate() {
                        *st = y[j] + self.z[k * n + j];
                    }
                    system.jacobian(t + c * h, &self.stage, &mut self.jac[k * n * n..(k + 1) * n * n]);
                }
                if !self.factor_newton_matrix(h, n) {
                    return None;
                }
            }
            // Residual G = Z − h (A ⊗ I) F; the correction solves M ΔZ = −G.
            for (i, row) in self.tableau.a.iter().enumerate() {
                for j in 0..n {
                    let mut acc = 0.0;
                    for (k, a) in row.iter().enumerate() {
                        acc += a * self.f[k * n + j];
                    }
                    self.residual[i * n + j] = h * acc - self.z[i * n + j];
                }
            }
            lu_solve(&self.lu, &self.pivots, &mut self.residual, s * n);
            let mut delta = 0.0_f64;
            for (i, dz) in self.residual.iter().enumerate() {
                self.z[i] += dz;
                delta = delta.max(dz.abs() / (1.0 + y[i % n].abs()));
            }
            if !delta.is_finite() {
                return None;
            }
            if delta <= f64::EPSILON || (delta >= previous && delta < 1e-12) {
                return Some(iteration);
            }
            // Simplified Newton contracts linearly; if it stops contracting, give up early.
            if !full && iteration > 1 && delta > 0.5 * previous {
                return None;
            }
            previous = delta;
        }
        None
    }

    /// Builds and factorises the Newton matrix: block (i, k) is δᵢₖ I − h aᵢₖ Jₖ, from the
    /// stage Jacobians in `jac`. False if singular.
    fn factor_newton_matrix(&mut self, h: f64, n: usize) -> bool {
        let big = self.tableau.b.len() * n;
        for (i, row) in self.tableau.a.iter().enumerate() {
            for (k, a) in row.iter().enumerate() {
                let jk = &self.jac[k * n * n..(k + 1) * n * n];
                for r in 0..n {
                    for col in 0..n {
                        let identity = if i == k && r == col { 1.0 } else { 0.0 };
                        self.lu[(i * n + r) * big + k * n + col] = identity - h * a * jk[r * n + col];
                    }
                }
            }
        }
        lu_factor(&mut self.lu, &mut self.pivots, big)
    }

    /// Solves the stage equations by fixed-point iteration: returns the iterations taken, or
    /// `None` if it did not reach round-off.
    fn solve_fixed_point<S: System + ?Sized>(
        &mut self,
        system: &S,
        t: f64,
        h: f64,
        y: &[f64],
    ) -> Option<usize> {
        let n = y.len();
        self.initial_guess(system, t, h, y);
        let mut previous = f64::INFINITY;
        for iteration in 1..=MAX_ITERATIONS {
            self.evaluate(system, t, h, y);
            let mut delta = 0.0_f64;
            for (i, row) in self.tableau.a.iter().enumerate() {
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
                return None;
            }
            // Converged: the update vanished, or stopped shrinking at round-off level.
            if delta <= f64::EPSILON || (delta >= previous && delta < 1e-12) {
                return Some(iteration);
            }
            previous = delta;
        }
        None
    }
}

/// LU factorisation with partial pivoting of the m × m row-major matrix `a`, in place;
/// `pivots[k]` is the row swapped with row k. False if the matrix is singular.
fn lu_factor(a: &mut [f64], pivots: &mut [usize], m: usize) -> bool {
    for k in 0..m {
        let p = (k..m).max_by(|&i, &j| a[i * m + k].abs().total_cmp(&a[j * m + k].abs())).unwrap_or(k);
        pivots[k] = p;
        if a[p * m + k] == 0.0 || !a[p * m + k].is_finite() {
            return false;
        }
        if p != k {
            for col in 0..m {
                a.swap(k * m + col, p * m + col);
            }
        }
        let pivot = a[k * m + k];
        for i in k + 1..m {
            let factor = a[i * m + k] / pivot;
            a[i * m + k] = factor;
            for col in k + 1..m {
                a[i * m + col] -= factor * a[k * m + col];
            }
        }
    }
    true
}

/// Solves L U x = P b in place (`x` holds b on entry) with the factors of [`lu_factor`].
fn lu_solve(lu: &[f64], pivots: &[usize], x: &mut [f64], m: usize) {
    for (k, &p) in pivots.iter().enumerate().take(m) {
        x.swap(k, p);
    }
    for i in 0..m {
        let mut acc = x[i];
        for k in 0..i {
            acc -= lu[i * m + k] * x[k];
        }
        x[i] = acc;
    }
    for i in (0..m).rev() {
        let mut acc = x[i];
        for k in i + 1..m {
            acc -= lu[i * m + k] * x[k];
        }
        x[i] = acc / lu[i * m + i];
    }
}

impl<S: System + ?Sized> Stepper<S> for Collocation {
    fn step(&mut self, system: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        let n = y.len();
        let newton = if self.newton {
            match self.solve_newton(system, t, h, y, false) {
                Some(k) => Some(Solver::SimplifiedNewton(k)),
                None => self.solve_newton(system, t, h, y, true).map(Solver::Newton),
            }
        } else {
            None
        };
        self.last_solver = match newton {
            Some(solver) => Some(solver),
            None => match self.solve_fixed_point(system, t, h, y) {
                Some(iterations) => Some(Solver::FixedPoint(iterations)),
                None => return Err(Error::NewtonDidNotConverge { t, iterations: MAX_ITERATIONS }),
            },
        };
        self.evaluate(system, t, h, y);
        for (j, yj) in y.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (i, b) in self.tableau.b.iter().enumerate() {
                acc += b * self.f[i * n + j];
            }
            *yj += h * acc;
        }
        Ok(())
    }
}
