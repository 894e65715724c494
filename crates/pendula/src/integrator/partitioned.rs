//! Symplectic Euler and Störmer–Verlet on a Hamiltonian form (q, p).
//!
//! For a separable H = T(p) + V(t, q) both are explicit: they are the schemes of the
//! paper's §8. For a non-separable H (the double pendulum) they are the partitioned
//! Runge–Kutta methods that keep their symplecticity — symplectic Euler implicit in p, and
//! the generalized leapfrog (the Lobatto IIIA–IIIB pair) — and their implicit stage
//! equations are solved by fixed-point iteration to round-off. The paper's explicit
//! schemes applied to (θ, ω) of the double pendulum are neither symplectic nor symmetric
//! (ERRATA), so they are never used there.
//!
//! # References
//! E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed., Springer
//! 2006: §VI.3, (3.1) symplectic Euler and (3.4) Störmer–Verlet; §VIII.6 (fixed-point
//! iteration of implicit stages and its stopping rule).

use super::{Method, Requirement, Scheme, Stepper};
use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};
use crate::num::Num;
use crate::system::Hamiltonian;

/// Which partitioned scheme.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Partition {
    /// pₙ₊₁ = pₙ − h ∂H/∂q(qₙ, pₙ₊₁); qₙ₊₁ = qₙ + h ∂H/∂p(qₙ, pₙ₊₁).
    SymplecticEuler,
    /// p½ = pₙ − h/2 ∂H/∂q(qₙ, p½); qₙ₊₁ = qₙ + h/2 (∂H/∂p(qₙ, p½) + ∂H/∂p(qₙ₊₁, p½));
    /// pₙ₊₁ = p½ − h/2 ∂H/∂q(qₙ₊₁, p½).
    StormerVerlet,
    /// Störmer–Verlet steps of sizes wᵢ h in turn (Σ wᵢ = 1), on a separable H only: see
    /// [`super::composition`].
    Composition(&'static [f64]),
}

/// Symplectic Euler (Euler–Cromer): order 1, symplectic, one force evaluation per step when
/// H is separable.
///
/// Requirements: a Hamiltonian form; implicit in p when H is not separable.
///
/// # References
/// Hairer, Lubich, Wanner, *Geometric Numerical Integration*, §VI.3, (3.1); paper §8.1.
pub static SYMPLECTIC_EULER: Method = Method {
    name: "symplectic-euler",
    title: "symplectic Euler",
    order: 1,
    requirement: Requirement::Hamiltonian,
    symplectic: true,
    symmetric: false,
    description: "symplectic Euler on (q, p): explicit if separable, implicit in p otherwise",
    reference: "Hairer, Lubich, Wanner, Geometric Numerical Integration, §VI.3 (3.1); paper §8.1",
    scheme: Scheme::Partitioned(Partition::SymplecticEuler),
};

/// Störmer–Verlet (velocity Verlet, leapfrog): order 2, symplectic and symmetric, one force
/// evaluation per step when H is separable (the last one is reused; ERRATA on §8.3).
///
/// Requirements: a Hamiltonian form; the generalized (implicit) leapfrog when H is not
/// separable.
///
/// # References
/// Hairer, Lubich, Wanner, *Geometric Numerical Integration*, §VI.3, (3.4); paper §8.2.
pub static VERLET: Method = Method {
    name: "verlet",
    title: "Stormer-Verlet",
    order: 2,
    requirement: Requirement::Hamiltonian,
    symplectic: true,
    symmetric: true,
    description: "Stormer-Verlet on (q, p): velocity Verlet if separable, generalized leapfrog otherwise",
    reference: "Hairer, Lubich, Wanner, Geometric Numerical Integration, §VI.3 (3.4); paper §8.2",
    scheme: Scheme::Partitioned(Partition::StormerVerlet),
};

/// Iteration cap for the implicit stages; at h small enough for accuracy the iteration
/// contracts by a factor ≲ 0.1 and needs 10–20 iterations.
const MAX_ITERATIONS: usize = 100;

/// Steps a [`Partition`] scheme; owns its buffers.
#[derive(Debug, Clone)]
pub struct PartitionedStepper {
    scheme: Partition,
    /// ∂H/∂q at (`cached_t`, q) from the end of the previous step (explicit path only).
    force: Vec<f64>,
    cached: Option<f64>,
    cached_q: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
    x: Vec<f64>,
    next: Vec<f64>,
}

impl PartitionedStepper {
    /// A stepper for a Hamiltonian form with `dof` degrees of freedom (dimension 2·dof).
    pub fn new(scheme: Partition, dof: usize) -> Self {
        let v = || vec![0.0; dof];
        PartitionedStepper {
            scheme,
            force: v(),
            cached: None,
            cached_q: v(),
            a: v(),
            b: v(),
            x: v(),
            next: v(),
        }
    }

    /// ∂H/∂q(t, q) of a separable H, reusing the value from the end of the last step when
    /// (t, q) is unchanged (first same as last).
    fn separable_force<H: Hamiltonian + ?Sized>(&mut self, h: &H, t: f64, q: &[f64], p: &[f64]) {
        // The caller's t for this step and our t + h from the last may differ by rounding.
        let same_t = self.cached.is_some_and(|c| (c - t).abs() <= 4.0 * f64::EPSILON * t.abs().max(1.0));
        if !same_t || self.cached_q != q {
            h.dh_dq(t, q, p, &mut self.force);
        }
    }

    fn remember(&mut self, t: f64, q: &[f64]) {
        self.cached = Some(t);
        self.cached_q.copy_from_slice(q);
    }

    /// One explicit step on a separable H: Störmer–Verlet (`verlet`) or symplectic Euler.
    fn explicit<H: Hamiltonian + ?Sized>(&mut self, sys: &H, t: f64, h: f64, y: &mut [f64], verlet: bool) {
        let n = y.len() / 2;
        let (q, p) = y.split_at_mut(n);
        self.separable_force(sys, t, q, p);
        let kick = if verlet { 0.5 * h } else { h };
        for (pi, f) in p.iter_mut().zip(&self.force) {
            *pi -= kick * f;
        }
        sys.dh_dp(t, q, p, &mut self.a);
        for (qi, v) in q.iter_mut().zip(&self.a) {
            *qi += h * v;
        }
        if verlet {
            sys.dh_dq(t + h, q, p, &mut self.force);
            for (pi, f) in p.iter_mut().zip(&self.force) {
                *pi -= kick * f;
            }
            self.remember(t + h, q);
        } else {
            self.cached = None;
        }
    }

    fn implicit<H: Hamiltonian + ?Sized>(
        &mut self,
        sys: &H,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<(), Error> {
        let n = y.len() / 2;
        let (q, p) = y.split_at_mut(n);
        let kick = if self.scheme == Partition::SymplecticEuler { h } else { 0.5 * h };
        // P = p − kick ∂H/∂q(t, q, P)
        self.x.copy_from_slice(p);
        let Self { x, next, a, .. } = self;
        fixed_point(x, next, t, |x, out| {
            sys.dh_dq(t, q, x, a);
            for ((o, pi), f) in out.iter_mut().zip(p.iter()).zip(a.iter()) {
                *o = pi - kick * f;
            }
        })?;
        p.copy_from_slice(x);
        match self.scheme {
            Partition::SymplecticEuler => {
                sys.dh_dp(t, q, p, &mut self.a);
                for (qi, v) in q.iter_mut().zip(&self.a) {
                    *qi += h * v;
                }
            }
            Partition::StormerVerlet | Partition::Composition(_) => {
                // Q = q + h/2 (∂H/∂p(q, P) + ∂H/∂p(Q, P)), started from the explicit guess.
                sys.dh_dp(t, q, p, &mut self.a);
                let Self { x, next, a, b, .. } = self;
                for ((xi, qi), v) in x.iter_mut().zip(q.iter()).zip(a.iter()) {
                    *xi = qi + h * v;
                }
                fixed_point(x, next, t, |x, out| {
                    sys.dh_dp(t + h, x, p, b);
                    for (((o, qi), va), vb) in out.iter_mut().zip(q.iter()).zip(a.iter()).zip(b.iter()) {
                        *o = qi + kick * (va + vb);
                    }
                })?;
                q.copy_from_slice(x);
                sys.dh_dq(t + h, q, p, &mut self.a);
                for (pi, f) in p.iter_mut().zip(&self.a) {
                    *pi -= kick * f;
                }
            }
        }
        Ok(())
    }
}

/// Where [`kick_drift`] takes its accelerations from.
pub trait Accelerations<T> {
    /// Writes the accelerations at time `t` and positions `q` into `a`.
    fn accelerations(&mut self, t: f64, q: &[T], a: &mut [T]);
}

impl<T, F: FnMut(f64, &[T], &mut [T])> Accelerations<T> for F {
    fn accelerations(&mut self, t: f64, q: &[T], a: &mut [T]) {
        self(t, q, a);
    }
}

/// One step of `scheme` on a separable H = ½ q′ᵀ M q′ + V(t, q) whose mass matrix M is
/// constant, in the velocities q′ = M⁻¹ p: the same map as the (q, p) steps above (p = M q′
/// is linear), over any number type — the ensemble engine's lanes run it (kick–drift; there
/// the equations' right-hand side gives the accelerations, which for such a system do not
/// depend on q′).
///
/// `accel.accelerations(s, q, a)` writes the accelerations at time s and positions q (a
/// closure, or a type whose method is kept in line with its caller's instruction set: a
/// closure is compiled without the SIMD kernels' target features). For Störmer–Verlet
/// and compositions, `a` holds them at (t, q) on entry when `primed`, and at the step's end
/// on return, for the next step (first same as last: one evaluation per Verlet step, as the
/// (q, p) stepper's cache).
#[allow(clippy::too_many_arguments)] // the step, its state and where the forces come from
#[inline(always)]
pub fn kick_drift<T: Num>(
    scheme: Partition,
    t: f64,
    h: f64,
    q: &mut [T],
    v: &mut [T],
    a: &mut [T],
    primed: bool,
    accel: &mut impl Accelerations<T>,
) {
    let weights: &[f64] = match scheme {
        Partition::SymplecticEuler => {
            accel.accelerations(t, q, a);
            let h = T::splat(h);
            for (vi, ai) in v.iter_mut().zip(a.iter()) {
                *vi = h.madd(*ai, *vi);
            }
            for (qi, vi) in q.iter_mut().zip(v.iter()) {
                *qi = h.madd(*vi, *qi);
            }
            return;
        }
        Partition::StormerVerlet => &[1.0],
        Partition::Composition(weights) => weights,
    };
    if !primed {
        accel.accelerations(t, q, a);
    }
    let mut s = t;
    for w in weights {
        // The sizes and times the (q, p) stepper takes: w h, half of it, s + w h.
        let full = w * h;
        let kick = T::splat(0.5 * full);
        for (vi, ai) in v.iter_mut().zip(a.iter()) {
            *vi = kick.madd(*ai, *vi);
        }
        let drift = T::splat(full);
        for (qi, vi) in q.iter_mut().zip(v.iter()) {
            *qi = drift.madd(*vi, *qi);
        }
        s += full;
        accel.accelerations(s, q, a);
        for (vi, ai) in v.iter_mut().zip(a.iter()) {
            *vi = kick.madd(*ai, *vi);
        }
    }
}

/// Solves x = G(x) by fixed-point iteration, `x` holding the starting guess. Stops when the
/// update vanishes or stops shrinking at round-off level (Hairer, Lubich, Wanner §VIII.6).
fn fixed_point(
    x: &mut [f64],
    next: &mut [f64],
    t: f64,
    mut g: impl FnMut(&[f64], &mut [f64]),
) -> Result<(), Error> {
    let mut previous = f64::INFINITY;
    for _ in 0..MAX_ITERATIONS {
        g(x, next);
        let mut delta = 0.0_f64;
        for (a, b) in x.iter().zip(next.iter()) {
            delta = delta.max((a - b).abs() / (1.0 + b.abs()));
        }
        x.copy_from_slice(next);
        if !delta.is_finite() {
            break;
        }
        if delta <= f64::EPSILON || (delta >= previous && delta < 1e-12) {
            return Ok(());
        }
        previous = delta;
    }
    Err(Error::NewtonDidNotConverge { t, iterations: MAX_ITERATIONS })
}

impl<H: Hamiltonian + ?Sized> Stepper<H> for PartitionedStepper {
    fn step(&mut self, system: &H, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        match self.scheme {
            Partition::Composition(weights) => {
                // `solve` refuses non-separable systems for compositions (their requirement).
                debug_assert!(system.separable(), "a composition on a non-separable system");
                let mut s = t;
                for w in weights {
                    self.explicit(system, s, w * h, y, true);
                    s += w * h;
                }
                Ok(())
            }
            scheme if system.separable() => {
                self.explicit(system, t, h, y, scheme == Partition::StormerVerlet);
                Ok(())
            }
            _ => self.implicit(system, t, h, y),
        }
    }
}

/// The cached force and where it was taken: reusing it or not changes the evaluation count,
/// and on a time-dependent H (the drive) the last bits, since the cache matches times up to
/// rounding.
impl Snapshot for PartitionedStepper {
    fn save(&self, out: &mut Words) {
        out.f64s(&self.force);
        out.opt_f64(self.cached);
        out.f64s(&self.cached_q);
    }
    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        from.f64s_into(&mut self.force)?;
        self.cached = from.opt_f64()?;
        from.f64s_into(&mut self.cached_q)
    }
}
