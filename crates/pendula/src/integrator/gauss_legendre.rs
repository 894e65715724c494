//! Gauss–Legendre collocation: the s-stage implicit Runge–Kutta methods of order 2s. They
//! are symplectic for every Hamiltonian system, separable or not, and symmetric; on a system
//! with a Hamiltonian form pendula runs them on (q, p), where symplecticity holds.
//!
//! The stage equations Zᵢ = h Σⱼ aᵢⱼ f(t + cⱼ h, y + Zⱼ) are solved to round-off by Newton
//! iteration when the system has a Jacobian ([`System::jacobian`]: analytic, or by
//! num-dual). First simplified Newton (Hairer, Wanner, *Solving ODEs II*, §IV.8): one
//! Jacobian, taken at the step's predicted midpoint and kept across steps while the
//! iteration contracts fast, and one LU factorisation of I − h A ⊗ J per step size; the
//! iteration starts from the previous step's collocation polynomial, extrapolated (Hairer,
//! Lubich, Wanner, *GNI*, §VIII.6.1), and stops when the remaining correction, predicted from
//! the contraction rate, is below one ulp. If that stops contracting, full Newton, which
//! factorises I − h (A ⊗ I) diag(J(Y₁) … J(Yₛ)) in every iteration. Without a Jacobian, or
//! when Newton fails, fixed-point iteration is used, which converges while h ‖∂f/∂y‖ is below
//! about 1. When both fail the step is [`Error::NewtonDidNotConverge`], naming the time. The
//! new state is y + Σ dᵢ Zᵢ with dᵀ = bᵀ A⁻¹ (the collocation polynomial at the step's end),
//! which needs no further evaluations of f.
//!
//! On the chaotic double pendulum at h = 0.02 s this costs about 12.3 evaluations per step
//! (a Jacobian counting as one per state variable); starting from the constant slope with a
//! fresh Jacobian at the step's start every step, and evaluating f once more for the update,
//! cost 20.8.
//!
//! # References
//! - E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., §II.1.3
//!   (Table 1.4), §VI.4 (symplecticity), §VIII.6 (implementation).
//! - J. C. Butcher, "Implicit Runge–Kutta processes", Math. Comp. 18 (1964) 50–64.
//! - E. Hairer, G. Wanner, *Solving ODEs II*, 2nd ed., §IV.8 (simplified Newton iteration).

use super::{Method, Requirement, Scheme, Stepper};
use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};
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

/// A kept Jacobian is refreshed for the next step when simplified Newton contracted by less
/// than this factor per iteration. Measured on the chaotic double pendulum at h = 0.02 s,
/// evaluations per step (a Jacobian counting n): 13.5 refreshing every step, 12.45 at 0.001,
/// 12.27 at 0.002, 12.37 at 0.005, 13.9 at 0.02.
const REFRESH_RATE: f64 = 0.002;

/// How the stage equations were solved in the last step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solver {
    /// Simplified Newton iteration (one Jacobian, kept across steps while it serves), in
    /// this many iterations.
    SimplifiedNewton(usize),
    /// Full Newton iteration (Jacobians at every stage and iteration), in this many
    /// iterations, after simplified Newton stopped contracting.
    Newton(usize),
    /// Fixed-point iteration, in this many iterations (no Jacobian, or Newton failed).
    FixedPoint(usize),
}

/// Steps an [`ImplicitTableau`] by Newton iteration (fixed-point iteration as the fallback);
/// owns its buffers.
///
/// Between steps it keeps what makes the next one cheap (Hairer, Lubich, Wanner §VIII.6):
/// the last step's stage increments, whose collocation polynomial, extrapolated, is the next
/// step's starting guess; and the Jacobian with the LU factors of the Newton matrix, reused
/// while simplified Newton contracts fast. Both only shape the starting point and the path
/// of the iteration, which is always taken to round-off, so a step's result is the
/// collocation solution whatever was kept; the kept data is used only when the step starts
/// where the last one ended (same time, same state, bit for bit).
#[derive(Debug, Clone)]
pub struct Collocation {
    tableau: &'static ImplicitTableau,
    /// Update weights dᵢ with y₁ = y₀ + Σ dᵢ Zᵢ (dᵀ = bᵀ A⁻¹; the collocation polynomial at
    /// the step's end), which saves the s evaluations of y₀ + h Σ bᵢ f(Yᵢ).
    d: Vec<f64>,
    /// Simplified Newton stops when the predicted remaining correction is below this:
    /// ε / Σ |dᵢ|, one ulp of the new state.
    stop: f64,
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
    /// What the last step left for the next one.
    kept: Kept,
    /// How the last step's stage equations were solved.
    pub last_solver: Option<Solver>,
}

/// What one step leaves for the next.
#[derive(Debug, Clone)]
struct Kept {
    /// Whether `z` holds the last step's converged increments, taken with `h` from a step
    /// that ended at `t_end` in the state `y_end`.
    stages: bool,
    h: f64,
    t_end: f64,
    y_end: Vec<f64>,
    /// Whether `jac` (first block) and `lu` hold a Jacobian and the factors of the
    /// simplified-Newton matrix for the step `lu_h`, and whether the Jacobian should be
    /// refreshed before the next step.
    jacobian: bool,
    lu_h: f64,
    refresh: bool,
}

impl Collocation {
    /// A stepper for systems of dimension `dim`.
    pub fn new(tableau: &'static ImplicitTableau, dim: usize) -> Self {
        let s = tableau.b.len();
        let big = s * dim;
        let d: Vec<f64> = (0..s).map(|j| lagrange(tableau.c, j, 1.0)).collect();
        Collocation {
            tableau,
            stop: f64::EPSILON / d.iter().map(|x| x.abs()).sum::<f64>(),
            d,
            z: vec![0.0; big],
            f: vec![0.0; big],
            stage: vec![0.0; dim],
            jac: vec![0.0; s * dim * dim],
            lu: vec![0.0; big * big],
            pivots: vec![0; big],
            residual: vec![0.0; big],
            newton: true,
            kept: Kept {
                stages: false,
                h: 0.0,
                t_end: 0.0,
                y_end: vec![0.0; dim],
                jacobian: false,
                lu_h: 0.0,
                refresh: false,
            },
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

    /// Whether this step starts where the last one ended, so that what it kept applies.
    fn continues(&self, t: f64, y: &[f64]) -> bool {
        // Times are recomputed from step indices by the run loop, so they may differ from the
        // kept t + h in the last bit; the state must be the one the last step produced.
        self.kept.stages
            && (t - self.kept.t_end).abs() <= 1e-9 * self.kept.h.abs()
            && y == self.kept.y_end.as_slice()
    }

    /// The starting guess: the last step's collocation polynomial extrapolated to this
    /// step's nodes when the step continues the last one (error O(hˢ⁺¹) instead of O(h²)),
    /// else the constant slope f(t, y).
    fn start<S: System + ?Sized>(&mut self, system: &S, t: f64, h: f64, y: &[f64]) {
        if !self.continues(t, y) {
            self.initial_guess(system, t, h, y);
            return;
        }
        // u(t₀ + θ h₀) − y₀ = Σⱼ Zⱼ Lⱼ(θ) on the last step; the new increments are
        // u(t₁ + cᵢ h) − u(t₁), with θ = 1 + cᵢ h / h₀.
        let n = y.len();
        let c = self.tableau.c;
        let s = c.len();
        let ratio = h / self.kept.h;
        let mut w = [[0.0; 3]; 3];
        for (i, row) in w.iter_mut().enumerate().take(s) {
            for (j, wij) in row.iter_mut().enumerate().take(s) {
                *wij = lagrange(c, j, 1.0 + c[i] * ratio) - self.d[j];
            }
        }
        for k in 0..n {
            let mut old = [0.0; 3];
            for (j, o) in old.iter_mut().enumerate().take(s) {
                *o = self.z[j * n + k];
            }
            for (i, row) in w.iter().enumerate().take(s) {
                self.z[i * n + k] = (0..s).map(|j| row[j] * old[j]).sum();
            }
        }
    }

    /// Solves the stage equations by simplified Newton iteration from the increments in
    /// `z`, with the kept Jacobian when there is one (a fresh J(t, y) otherwise): returns
    /// the iterations taken and the last contraction rate, or `None` if it diverged or
    /// stopped contracting before round-off (or there is no Jacobian).
    fn solve_simplified<S: System + ?Sized>(
        &mut self,
        system: &S,
        t: f64,
        h: f64,
        y: &[f64],
    ) -> Option<(usize, f64)> {
        let n = y.len();
        if !self.kept.jacobian {
            // J at the guess's midpoint y + Σ bᵢ Zᵢ ≈ y(t + h/2): the stages lie on either side
            // of it, so the frozen Jacobian is off by half as much as J(t, y) would be.
            for (j, st) in self.stage.iter_mut().enumerate() {
                let mut acc = 0.0;
                for (i, b) in self.tableau.b.iter().enumerate() {
                    acc += b * self.z[i * n + j];
                }
                *st = y[j] + acc;
            }
            if !system.jacobian(t + 0.5 * h, &self.stage, &mut self.jac[..n * n]) {
                return None;
            }
            self.kept.jacobian = true;
            self.kept.lu_h = f64::NAN;
        }
        if self.kept.lu_h != h {
            let s = self.tableau.b.len();
            for k in 1..s {
                self.jac.copy_within(..n * n, k * n * n);
            }
            if !self.factor_newton_matrix(h, n) {
                self.kept.jacobian = false;
                return None;
            }
            self.kept.lu_h = h;
        }
        let mut previous = f64::INFINITY;
        let mut rate = 0.0;
        for iteration in 1..=MAX_SIMPLIFIED_ITERATIONS {
            let delta = self.newton_update(system, t, h, y);
            if !delta.is_finite() {
                return None;
            }
            if iteration > 1 {
                rate = delta / previous;
            }
            // Linear contraction at `rate` leaves about rate / (1 − rate) · delta to go; once
            // that, times Σ |dᵢ|, is below one ulp, the update would not change.
            if converged(delta, previous)
                || (iteration > 1 && rate < 0.5 && rate / (1.0 - rate) * delta <= self.stop)
            {
                return Some((iteration, rate));
            }
            // Simplified Newton contracts linearly; if it stops contracting, give up early.
            if iteration > 1 && rate > 0.5 {
                return None;
            }
            previous = delta;
        }
        None
    }

    /// Solves the stage equations by full Newton iteration from the constant-slope guess,
    /// factorising I − h (A ⊗ I) diag(J(Y₁) … J(Yₛ)) in every iteration: returns the
    /// iterations taken, or `None`. Simplified Newton is cheap and enough at ordinary steps;
    /// on a fast-rotating pendulum, whose Jacobian turns with the angles within one step,
    /// only this converges at large steps.
    fn solve_full<S: System + ?Sized>(&mut self, system: &S, t: f64, h: f64, y: &[f64]) -> Option<usize> {
        let n = y.len();
        // The stage Jacobians overwrite the kept one and its factors.
        self.kept.jacobian = false;
        self.initial_guess(system, t, h, y);
        let mut previous = f64::INFINITY;
        for iteration in 1..=MAX_NEWTON_ITERATIONS {
            for (k, c) in self.tableau.c.iter().enumerate() {
                for (j, st) in self.stage.iter_mut().enumerate() {
                    *st = y[j] + self.z[k * n + j];
                }
                if !system.jacobian(t + c * h, &self.stage, &mut self.jac[k * n * n..(k + 1) * n * n]) {
                    return None;
                }
            }
            if !self.factor_newton_matrix(h, n) {
                return None;
            }
            let delta = self.newton_update(system, t, h, y);
            if !delta.is_finite() {
                return None;
            }
            if converged(delta, previous) {
                return Some(iteration);
            }
            previous = delta;
        }
        None
    }

    /// One Newton correction with the factors in `lu`: the residual G = Z − h (A ⊗ I) F at
    /// the current increments, then M ΔZ = −G. Returns the largest correction relative to
    /// 1 + |y|.
    fn newton_update<S: System + ?Sized>(&mut self, system: &S, t: f64, h: f64, y: &[f64]) -> f64 {
        let n = y.len();
        let s = self.tableau.b.len();
        self.evaluate(system, t, h, y);
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
        delta
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

    /// Solves the stage equations by fixed-point iteration from the constant-slope guess:
    /// returns the iterations taken, or `None` if it did not reach round-off.
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
            if converged(delta, previous) {
                return Some(iteration);
            }
            previous = delta;
        }
        None
    }

    /// Solves the stage equations for the step from (t, y): simplified Newton from the
    /// extrapolated guess with the kept Jacobian; if that fails, again with a fresh
    /// Jacobian; then full Newton; then fixed-point iteration.
    fn solve_stages<S: System + ?Sized>(&mut self, system: &S, t: f64, h: f64, y: &[f64]) -> Option<Solver> {
        if self.newton {
            if self.kept.refresh {
                self.kept.jacobian = false;
                self.kept.refresh = false;
            }
            let fresh = !self.kept.jacobian;
            self.start(system, t, h, y);
            let mut result = self.solve_simplified(system, t, h, y);
            if result.is_none() && !fresh {
                self.kept.jacobian = false;
                self.start(system, t, h, y);
                result = self.solve_simplified(system, t, h, y);
            }
            if let Some((iterations, rate)) = result {
                self.kept.refresh = rate > REFRESH_RATE;
                return Some(Solver::SimplifiedNewton(iterations));
            }
            if let Some(iterations) = self.solve_full(system, t, h, y) {
                return Some(Solver::Newton(iterations));
            }
        }
        self.solve_fixed_point(system, t, h, y).map(Solver::FixedPoint)
    }
}

/// Converged to round-off: the update vanished, or stopped shrinking at round-off level.
fn converged(delta: f64, previous: f64) -> bool {
    delta <= f64::EPSILON || (delta >= previous && delta < 1e-12)
}

/// The Lagrange basis polynomial of node cⱼ over the nodes {0, c₁, …, cₛ}, at θ.
fn lagrange(c: &[f64], j: usize, theta: f64) -> f64 {
    let mut value = theta / c[j];
    for (k, ck) in c.iter().enumerate() {
        if k != j {
            value *= (theta - ck) / (c[j] - ck);
        }
    }
    value
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
        self.last_solver = self.solve_stages(system, t, h, y);
        if self.last_solver.is_none() {
            self.kept.stages = false;
            return Err(Error::NewtonDidNotConverge { t, iterations: MAX_ITERATIONS });
        }
        for (j, yj) in y.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (i, d) in self.d.iter().enumerate() {
                acc += d * self.z[i * n + j];
            }
            *yj += acc;
        }
        self.kept.stages = true;
        self.kept.h = h;
        self.kept.t_end = t + h;
        self.kept.y_end.copy_from_slice(y);
        Ok(())
    }
}

/// Everything one step leaves for the next: the stage increments and derivatives, the kept
/// Jacobian and the LU factors with their pivots, the flags and step sizes they belong to,
/// and how the last step was solved. The starting guess and the path of the Newton
/// iteration depend on them, and so does the round-off of the converged stages.
impl Snapshot for Collocation {
    fn save(&self, out: &mut Words) {
        out.f64s(&self.z);
        out.f64s(&self.f);
        out.f64s(&self.jac);
        out.f64s(&self.lu);
        out.usizes(&self.pivots);
        out.bool(self.newton);
        let k = &self.kept;
        out.bool(k.stages);
        out.f64(k.h);
        out.f64(k.t_end);
        out.f64s(&k.y_end);
        out.bool(k.jacobian);
        out.f64(k.lu_h);
        out.bool(k.refresh);
        let (kind, iterations) = match self.last_solver {
            None => (0, 0),
            Some(Solver::SimplifiedNewton(i)) => (1, i),
            Some(Solver::Newton(i)) => (2, i),
            Some(Solver::FixedPoint(i)) => (3, i),
        };
        out.u64(kind);
        out.u64(iterations as u64);
    }
    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        from.f64s_into(&mut self.z)?;
        from.f64s_into(&mut self.f)?;
        from.f64s_into(&mut self.jac)?;
        from.f64s_into(&mut self.lu)?;
        let m = self.pivots.len();
        from.usizes_into(&mut self.pivots, m)?;
        self.newton = from.bool()?;
        let k = &mut self.kept;
        k.stages = from.bool()?;
        k.h = from.f64()?;
        k.t_end = from.f64()?;
        from.f64s_into(&mut k.y_end)?;
        k.jacobian = from.bool()?;
        k.lu_h = from.f64()?;
        k.refresh = from.bool()?;
        let kind = from.u64()?;
        let iterations = from.usize()?;
        self.last_solver = match kind {
            0 => None,
            1 => Some(Solver::SimplifiedNewton(iterations)),
            2 => Some(Solver::Newton(iterations)),
            3 => Some(Solver::FixedPoint(iterations)),
            _ => {
                return Err(Error::BadCheckpoint {
                    part: "the Gauss-Legendre stepper",
                    reason: format!("unknown solver kind {kind}"),
                });
            }
        };
        Ok(())
    }
}
