//! Numbers the equations of motion are written over, once: [`Num`], implemented by
//!
//! - `f64`, the **reference arithmetic**: IEEE operations in the order written and the
//!   platform's (glibc's) sine and cosine, so that the double pendulum's right-hand side is
//!   bit for bit the benchmark's C reference (`shared/bench/SPEC.md`);
//! - [`num_dual::Dual64`], for Jacobians by forward-mode automatic differentiation: its value
//!   parts are computed with exactly the `f64` operations;
//! - [`Lanes`], the **engine arithmetic**: `N` values advanced together (16 in the ensemble
//!   engine, [`crate::ensemble::LANES`]; 1 for the single-trajectory fast path), with the
//!   branch-free sine and cosine of [`trig`], fused multiply-adds where the CPU has them
//!   (`FMA`), and one reciprocal for two quotients. A member computed in lane `i` of a group
//!   has exactly the bits it has alone in `Lanes<1, FMA, WIDE>`: lanes never interact.
//!
//! A system's right-hand side, energy and Hamiltonian gradient are generic over `Num`
//! (`system::double`), so the scalar integrators, the Jacobians and the SIMD kernels run one
//! implementation.

pub mod trig;

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A number type the equations of motion are written over (see the module documentation).
///
/// The one required method is [`Num::splat`]; the others have the reference arithmetic's
/// defaults, which a type overrides where its arithmetic differs.
pub trait Num:
    Copy
    + Send
    + Sync
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The constant `x` (in every lane; with zero derivative).
    fn splat(x: f64) -> Self;

    /// sin x and cos x.
    fn sin_cos(self) -> (Self, Self);

    /// sin x (a type may use a cheaper polynomial than [`Num::sin_cos`]'s).
    #[inline(always)]
    fn sin(self) -> Self {
        self.sin_cos().0
    }

    /// cos x.
    #[inline(always)]
    fn cos(self) -> Self {
        self.sin_cos().1
    }

    /// self · b + c: a product and a sum (the reference), or one fused operation.
    #[inline(always)]
    fn madd(self, b: Self, c: Self) -> Self {
        self * b + c
    }

    /// (a / d, b / d): two divisions (the reference), or one reciprocal and two products.
    #[inline(always)]
    fn div2(a: Self, b: Self, d: Self) -> (Self, Self) {
        (a / d, b / d)
    }

    /// Whether the value is zero (in every lane; with zero derivative): for terms that vanish
    /// for most systems (damping, drives), skipped then at the cost of one test.
    fn is_zero(self) -> bool;

    /// √x.
    fn sqrt(self) -> Self;

    /// |x| (the value part's, for dual numbers: used for bounds, not differentiated).
    fn abs(self) -> Self;

    /// The larger of the two (lane by lane), by a comparison: a NaN `self` gives `other`.
    fn max(self, other: Self) -> Self;
}

impl Num for f64 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        (self.sin(), self.cos())
    }
    #[inline(always)]
    fn sin(self) -> Self {
        f64::sin(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        f64::cos(self)
    }
    #[inline(always)]
    fn is_zero(self) -> bool {
        self == 0.0
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        if self > other { self } else { other }
    }
}

impl Num for num_dual::Dual64 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        num_dual::Dual64::from(x)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        num_dual::DualNum::sin_cos(&self)
    }
    #[inline(always)]
    fn is_zero(self) -> bool {
        self.re == 0.0 && self.eps == 0.0
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        num_dual::DualNum::sqrt(&self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        if self.re < 0.0 { -self } else { self }
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        if self.re > other.re { self } else { other }
    }
}

/// `N` f64 values advanced together with the engine arithmetic (see the module
/// documentation): the polynomial sine and cosine of [`trig`] — when `WIDE`, correct for every
/// finite argument; when not, for |x| ≤ [`trig::FAST_RANGE`] only, branch-free (kernels track
/// how far their angles reach and run again `WIDE` when needed) — fused multiply-adds when
/// `FMA` (only where the CPU has them: elsewhere `mul_add` is a slow library call), and one
/// reciprocal for two quotients (division is the slowest vector operation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanes<const N: usize, const FMA: bool, const WIDE: bool>(pub [f64; N]);

impl<const N: usize, const FMA: bool, const WIDE: bool> Lanes<N, FMA, WIDE> {
    /// Lane by lane: `f` of each lane.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        let mut out = self.0;
        for v in &mut out {
            *v = f(*v);
        }
        Lanes(out)
    }

    /// Lane by lane: `f` of each pair of lanes.
    #[inline(always)]
    pub fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let mut out = self.0;
        for (v, w) in out.iter_mut().zip(other.0) {
            *v = f(*v, w);
        }
        Lanes(out)
    }
}

macro_rules! lane_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl<const N: usize, const FMA: bool, const WIDE: bool> $trait for Lanes<N, FMA, WIDE> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, other: Self) -> Self {
                self.zip(other, |a, b| a $op b)
            }
        }
    };
}

lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl<const N: usize, const FMA: bool, const WIDE: bool> Neg for Lanes<N, FMA, WIDE> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|a| -a)
    }
}

impl<const N: usize, const FMA: bool, const WIDE: bool> Num for Lanes<N, FMA, WIDE> {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Lanes([x; N])
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let mut s = [0.0; N];
        let mut c = [0.0; N];
        for i in 0..N {
            (s[i], c[i]) = trig::sin_cos_with::<FMA, WIDE>(self.0[i]);
        }
        (Lanes(s), Lanes(c))
    }
    #[inline(always)]
    fn sin(self) -> Self {
        self.map(trig::sin_with::<FMA, WIDE>)
    }
    #[inline(always)]
    fn madd(self, b: Self, c: Self) -> Self {
        let mut out = c.0;
        for ((o, x), y) in out.iter_mut().zip(self.0).zip(b.0) {
            *o = trig::madd::<FMA>(x, y, *o);
        }
        Lanes(out)
    }
    #[inline(always)]
    fn div2(a: Self, b: Self, d: Self) -> (Self, Self) {
        let inverse = Self::splat(1.0) / d;
        (a * inverse, b * inverse)
    }
    #[inline(always)]
    fn is_zero(self) -> bool {
        self.0.iter().fold(true, |zero, &x| zero & (x == 0.0))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.map(f64::abs)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        self.zip(other, |a, b| if a > b { a } else { b })
    }
}
