//! Tao's explicit symplectic integrators for non-separable Hamiltonians, in an extended
//! phase space.
//!
//! H(q, p) is copied onto two pairs, (q, p) and (x, y), bound by a harmonic term:
//! H̄ = H(q, y) + H(x, p) + ω ½(|q − x|² + |p − y|²). Each of the three parts has an exact,
//! explicit flow: H_A = H(q, y) moves p and x, H_B = H(x, p) moves q and y, and the binding
//! term rotates the differences (q − x, p − y) by the angle 2ωδ. The symmetric composition
//! φ_A(δ/2) φ_B(δ/2) φ_C(δ) φ_B(δ/2) φ_A(δ/2) is `tao-2` (order 2); Yoshida's triple jump of
//! it is `tao-4` (order 4). Both are explicit, symplectic in the extended space, and
//! symmetric, and need only ∂H/∂q and ∂H/∂p. The stepper keeps the copy (x, y) from step to
//! step and shows (q, p).
//!
//! # Trade-offs of the binding constant ω
//! The copies drift apart at the rate the dynamics separates nearby orbits; a larger ω holds
//! them together but adds error terms that grow with ω h, so that the asymptotic order needs
//! ω h small (tao-4 reaches order 4 below ω h ≈ 0.25 and falls to ~1.5 at ω h = 1 … 10) and
//! the map becomes unstable beyond ω h ≈ 1, which [`crate::solve`] refuses. A smaller ω allows
//! larger steps, but on a chaotic orbit the copies then separate and the energy error grows.
//! Measured over 10⁶ steps of tao-4 on the double pendulum from (120°, −10°), max |ΔE| in the
//! first → last tenth: ω = 200 keeps it bounded for h = 0.5 … 5 ms (1.1e-5 → 1.2e-5 J at
//! 0.5 ms, 4.1e-2 → 4.0e-2 J at 5 ms); ω = 100 drifts (5.7e-4 → 2.0e-3 J at 1 ms); ω ≤ 50 lets
//! the copies separate (errors of 13–28 J). Hence the default ω = [`DEFAULT_BINDING`] = 200,
//! for steps up to 5 ms. On regular (non-chaotic) motion a smaller ω (10 … 50) is enough and
//! allows larger steps (`--binding`). For steps of 10 ms or more on a chaotic orbit, prefer
//! gauss-legendre-4 (implicit, no copies).
//!
//! # References
//! - M. Tao, "Explicit symplectic approximation of nonseparable Hamiltonians: algorithm and
//!   long time performance", Phys. Rev. E 94 (2016) 043303, (2)–(6).
//! - H. Yoshida, Phys. Lett. A 150 (1990) 262 (the triple jump).

use super::composition::YOSHIDA_4_WEIGHTS;
use super::{Method, Requirement, Scheme, Stepper};
use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};
use crate::error::Short;
use crate::num::Num;
use crate::system::Hamiltonian;

/// The binding constant ω used unless another is given, 1/s.
pub const DEFAULT_BINDING: f64 = 200.0;

/// A Tao method: compositions of the second-order extended-phase-space map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaoScheme {
    /// Weights of the symmetric composition of the second-order map (Σ = 1).
    pub weights: &'static [f64],
    /// The binding constant ω, 1/s.
    pub binding: f64,
}

/// Tao's second-order map. Requirements: a Hamiltonian form (separable or not).
///
/// # References
/// Tao, Phys. Rev. E 94 (2016) 043303, (5).
pub static TAO_2: Method = Method {
    name: "tao-2",
    title: "Tao extended phase space, order 2",
    order: 2,
    requirement: Requirement::HamiltonianExplicit,
    symplectic: true,
    symmetric: true,
    description: "explicit symplectic for non-separable H (two bound copies; binding constant w, default 200, needs w h <= 1)",
    reference: "Tao, Phys. Rev. E 94 (2016) 043303",
    scheme: Scheme::Tao(TaoScheme { weights: &[1.0], binding: DEFAULT_BINDING }),
};

/// Tao's map composed by Yoshida's triple jump. Requirements: a Hamiltonian form.
///
/// # References
/// Tao, Phys. Rev. E 94 (2016) 043303, (6); Yoshida, Phys. Lett. A 150 (1990) 262.
pub static TAO_4: Method = Method {
    name: "tao-4",
    title: "Tao extended phase space, order 4 (triple jump)",
    order: 4,
    requirement: Requirement::HamiltonianExplicit,
    symplectic: true,
    symmetric: true,
    description: "triple jump of tao-2: explicit, symplectic, order 4; needs w h well below 1 (binding constant times step)",
    reference: "Tao, Phys. Rev. E 94 (2016) 043303; Yoshida, Phys. Lett. A 150 (1990) 262",
    scheme: Scheme::Tao(TaoScheme { weights: &YOSHIDA_4_WEIGHTS, binding: DEFAULT_BINDING }),
};

/// The largest ω h the Tao maps are run at: beyond it they are unstable.
pub const MAX_BINDING_STEP: f64 = 1.0;

/// Checks ω h ≤ [`MAX_BINDING_STEP`] for a run with step h.
pub fn check_binding_step(scheme: &TaoScheme, h: f64) -> Result<(), Error> {
    let product = scheme.binding * h.abs();
    if product > MAX_BINDING_STEP {
        return Err(Error::InvalidValue {
            name: format!(
                "w h (binding constant w = {} 1/s, step h = {} s)",
                Short(scheme.binding),
                Short(h)
            ),
            value: product,
            allowed: "Tao's methods are unstable above w h = 1 (binding constant times step size): lower the binding constant or the step (for chaotic motion keep w near 200 and h <= 5 ms)",
        });
    }
    Ok(())
}

/// The refusal of a step `dt` above a Tao method's limit, in the words of a user who gave
/// the step as `dt` (not the run loop's ω h): the largest step allowed, with the binding
/// constant it follows from. `None` when `method` is not Tao's or `dt` is within its limit.
pub fn step_refusal(method: &Method, dt: f64) -> Option<Error> {
    let Scheme::Tao(scheme) = &method.scheme else { return None };
    check_binding_step(scheme, dt).err()?;
    Some(Error::OutOfRange {
        name: "dt".into(),
        value: dt.abs(),
        why: format!(
            "{} is unstable above w dt = 1 (its binding constant w = {} 1/s): a dt of at most {} s",
            method.name,
            Short(scheme.binding),
            Short(MAX_BINDING_STEP / scheme.binding)
        ),
    })
}

impl Method {
    /// This method with binding constant ω (Tao's methods only).
    ///
    /// # Errors
    /// [`Error::InvalidValue`] when ω is not finite and > 0 or the method has no binding
    /// constant.
    pub fn with_binding(&self, omega: f64) -> Result<Method, Error> {
        let invalid = |allowed| Error::InvalidValue { name: "binding".into(), value: omega, allowed };
        let Scheme::Tao(scheme) = self.scheme else {
            return Err(invalid("the binding constant applies to tao-2 and tao-4 only"));
        };
        if !(omega.is_finite() && omega > 0.0) {
            return Err(invalid("the binding constant must be finite and > 0"));
        }
        Ok(Method { scheme: Scheme::Tao(TaoScheme { binding: omega, ..scheme }), ..*self })
    }
}

/// One step of size `h` from time `t` of `scheme` on (q, p) and its copy (x, y) (each of
/// length n), over any number type: Tao's three flows, written once, for the scalar stepper
/// ([`TaoStepper`]), the ensemble engine's lanes and its one-lane reference. `gradient(t, q,
/// p, dq, dp)` writes ∂H/∂q and ∂H/∂p at (t, q, p) (both are needed by each of the flows
/// H_A = H(q, y) and H_B = H(x, p)); `dq` and `dp` are its scratch (length n). Every partial
/// flow of a second-order map is taken at that map's midpoint time, which keeps a
/// time-dependent H symmetric and of order 2.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the scheme, the step, the four halves, the scratch, the gradient
pub fn tao_step<T: Num, G: Gradient<T>>(
    scheme: &TaoScheme,
    t: f64,
    h: f64,
    [q, p, x, y]: [&mut [T]; 4],
    dq: &mut [T],
    dp: &mut [T],
    gradient: &mut G,
) {
    let mut ts = t;
    for &w in scheme.weights {
        let d = w * h;
        let tm = ts + 0.5 * d;
        let half = T::splat(0.5 * d);
        // φ_A(δ/2) φ_B(δ/2) φ_C(δ) φ_B(δ/2) φ_A(δ/2), δ = w h.
        for phase in 0..5 {
            match phase {
                // H_A = H(q, y): p −= δ ∂H/∂q(q, y), x += δ ∂H/∂p(q, y).
                0 | 4 => {
                    gradient.gradient(tm, q, y, dq, dp);
                    for (p, &g) in p.iter_mut().zip(dq.iter()) {
                        *p = *p - half * g;
                    }
                    for (x, &g) in x.iter_mut().zip(dp.iter()) {
                        *x = *x + half * g;
                    }
                }
                // H_B = H(x, p): q += δ ∂H/∂p(x, p), y −= δ ∂H/∂q(x, p).
                1 | 3 => {
                    gradient.gradient(tm, x, p, dq, dp);
                    for (q, &g) in q.iter_mut().zip(dp.iter()) {
                        *q = *q + half * g;
                    }
                    for (y, &g) in y.iter_mut().zip(dq.iter()) {
                        *y = *y - half * g;
                    }
                }
                // ω H_C = ω ½(|q − x|² + |p − y|²): the sums stay, the differences rotate by
                // 2ωδ.
                _ => {
                    let (sin, cos) = (2.0 * scheme.binding * d).sin_cos();
                    let (sin, cos, one_half) = (T::splat(sin), T::splat(cos), T::splat(0.5));
                    for i in 0..q.len() {
                        let (sq, sp) = (q[i] + x[i], p[i] + y[i]);
                        let (dq, dp) = (q[i] - x[i], p[i] - y[i]);
                        let (rq, rp) = (cos * dq + sin * dp, -sin * dq + cos * dp);
                        q[i] = one_half * (sq + rq);
                        x[i] = one_half * (sq - rq);
                        p[i] = one_half * (sp + rp);
                        y[i] = one_half * (sp - rp);
                    }
                }
            }
        }
        ts += d;
    }
}

/// The gradient [`tao_step`] evaluates: ∂H/∂q into `dq` and ∂H/∂p into `dp` at (t, q, p).
/// Closures are gradients; a kernel compiled for an instruction set passes a type whose
/// method is kept in line (a closure's body, compiled out of line, loses the kernel's target
/// features: its fused multiply-adds become calls into libm).
pub trait Gradient<T> {
    /// Writes ∂H/∂q and ∂H/∂p at (t, q, p).
    fn gradient(&mut self, t: f64, q: &[T], p: &[T], dq: &mut [T], dp: &mut [T]);
}

impl<T, F: FnMut(f64, &[T], &[T], &mut [T], &mut [T])> Gradient<T> for F {
    #[inline(always)]
    fn gradient(&mut self, t: f64, q: &[T], p: &[T], dq: &mut [T], dp: &mut [T]) {
        self(t, q, p, dq, dp);
    }
}

/// Steps a [`TaoScheme`] on a Hamiltonian form ([`tao_step`]); owns the copy (x, y) and its
/// buffers.
#[derive(Debug, Clone)]
pub struct TaoStepper {
    scheme: TaoScheme,
    n: usize,
    /// The copy (x, y) of (q, p).
    x: Vec<f64>,
    y: Vec<f64>,
    /// The gradient's halves.
    dq: Vec<f64>,
    dp: Vec<f64>,
    /// The (q, p) this stepper returned last: a different state on entry restarts the copy.
    last: Vec<f64>,
}

impl TaoStepper {
    /// A stepper for Hamiltonian forms with n degrees of freedom.
    pub fn new(scheme: TaoScheme, n: usize) -> Self {
        TaoStepper {
            scheme,
            n,
            x: vec![0.0; n],
            y: vec![0.0; n],
            dq: vec![0.0; n],
            dp: vec![0.0; n],
            last: vec![f64::NAN; 2 * n],
        }
    }
}

impl TaoStepper {
    /// One step of the extended map on `state` = (q, p, x, y) (length 4n), which is
    /// symplectic for dq ∧ dp + dx ∧ dy: what the tests check.
    pub fn step_extended<S: Hamiltonian + ?Sized>(&mut self, system: &S, t: f64, h: f64, state: &mut [f64]) {
        let n = self.n;
        let (z, copy) = state.split_at_mut(2 * n);
        self.x.copy_from_slice(&copy[..n]);
        self.y.copy_from_slice(&copy[n..]);
        self.compose(system, t, h, z);
        copy[..n].copy_from_slice(&self.x);
        copy[n..].copy_from_slice(&self.y);
        self.last.copy_from_slice(z);
    }

    fn compose<S: Hamiltonian + ?Sized>(&mut self, system: &S, t: f64, h: f64, z: &mut [f64]) {
        let (q, p) = z.split_at_mut(self.n);
        let mut gradient = |t: f64, q: &[f64], p: &[f64], dq: &mut [f64], dp: &mut [f64]| {
            system.dh_dq(t, q, p, dq);
            system.dh_dp(t, q, p, dp);
        };
        tao_step(
            &self.scheme,
            t,
            h,
            [q, p, &mut self.x, &mut self.y],
            &mut self.dq,
            &mut self.dp,
            &mut gradient,
        );
    }
}

impl<S: Hamiltonian + ?Sized> Stepper<S> for TaoStepper {
    fn step(&mut self, system: &S, t: f64, h: f64, z: &mut [f64]) -> Result<(), Error> {
        if z != self.last.as_slice() {
            // A new trajectory (or one changed from outside): the copy starts equal to it.
            self.x.copy_from_slice(&z[..self.n]);
            self.y.copy_from_slice(&z[self.n..]);
        }
        self.compose(system, t, h, z);
        self.last.copy_from_slice(z);
        Ok(())
    }
}

/// The copy (x, y) and the state it belongs to (a different state on entry restarts the copy).
impl Snapshot for TaoStepper {
    fn save(&self, out: &mut Words) {
        out.f64s(&self.x);
        out.f64s(&self.y);
        out.f64s(&self.last);
    }
    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        from.f64s_into(&mut self.x)?;
        from.f64s_into(&mut self.y)?;
        from.f64s_into(&mut self.last)
    }
}
