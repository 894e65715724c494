//! Explicit Runge–Kutta methods, each a Butcher tableau.

use super::{Method, Requirement, Scheme, Stepper};
use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};
use crate::num::Num;
use crate::system::System;

/// A Butcher tableau with weights b over a common denominator, so that the update is
/// y + (h / denominator) Σ bᵢ kᵢ, summed left to right.
#[derive(Debug, Clone, Copy)]
pub struct Tableau {
    /// Nodes cᵢ.
    pub c: &'static [f64],
    /// Strictly lower triangular coefficients aᵢⱼ (row i has i entries).
    pub a: &'static [&'static [f64]],
    /// Weight numerators bᵢ.
    pub b: &'static [f64],
    /// Common denominator of the weights.
    pub denominator: f64,
}

/// Explicit (forward) Euler: y + h f(t, y). Order 1, one evaluation per step.
///
/// # References
/// E. Hairer, S. P. Nørsett, G. Wanner, *Solving ODEs I*, §I.7; paper §7.1, (110).
pub static EULER: Method = Method {
    name: "euler",
    title: "explicit Euler",
    order: 1,
    requirement: Requirement::Any,
    symplectic: false,
    symmetric: false,
    description: "explicit Euler, 1 evaluation per step; energy grows on oscillators",
    reference: "Hairer, Norsett, Wanner, Solving ODEs I, §I.7; paper §7.1",
    scheme: Scheme::ExplicitRk(&Tableau { c: &[0.0], a: &[&[]], b: &[1.0], denominator: 1.0 }),
};

/// The classical fourth-order Runge–Kutta method. Order 4, four evaluations per step.
///
/// The paper's §7.2 misprints k₄ and drops k₄ from its code's update (ERRATA); this is the
/// classical method.
///
/// # References
/// E. Hairer, S. P. Nørsett, G. Wanner, *Solving ODEs I*, §II.1, Table 1.2 (left).
pub static RK4: Method = Method {
    name: "rk4",
    title: "classical Runge-Kutta",
    order: 4,
    requirement: Requirement::Any,
    symplectic: false,
    symmetric: false,
    description: "classical Runge-Kutta, 4 evaluations per step; slow secular energy drift",
    reference: "Hairer, Norsett, Wanner, Solving ODEs I, §II.1, Table 1.2",
    scheme: Scheme::ExplicitRk(&Tableau {
        c: &[0.0, 1.0 / 2.0, 1.0 / 2.0, 1.0],
        a: &[&[], &[1.0 / 2.0], &[0.0, 1.0 / 2.0], &[0.0, 0.0, 1.0]],
        b: &[1.0, 2.0, 2.0, 1.0],
        denominator: 6.0,
    }),
};

/// Steps an explicit Runge–Kutta tableau; owns its stage buffers.
#[derive(Debug, Clone)]
pub struct ExplicitRk {
    tableau: &'static Tableau,
    plan: Plan,
    k: Vec<f64>,
    stage: Vec<f64>,
}

impl ExplicitRk {
    /// A stepper for systems of dimension `dim`.
    pub fn new(tableau: &'static Tableau, dim: usize) -> Self {
        ExplicitRk {
            tableau,
            plan: plan(tableau.a),
            k: vec![0.0; tableau.b.len() * dim],
            stage: vec![0.0; dim],
        }
    }
}

/// The stages of an explicit tableau (rows `a`, nodes `c`) from (t, y) with step h: stage i
/// is kᵢ = f(t + cᵢ h, y + h Σⱼ aᵢⱼ kⱼ), stored at `k[i n .. (i + 1) n]`, `f` writing the
/// right-hand side at a stage's time and state. Stages before `first` are taken as already in
/// `k` (first same as last).
///
/// Written once over every number type: `f64` for the scalar integrators, the lanes of the
/// ensemble engine (`crate::ensemble`), where `madd` may fuse. In `f64` a stage is
/// y + h Σ aᵢⱼ kⱼ with the sum from 0 left to right, zero coefficients skipped. States of 2
/// and 4 components (the pendulums, the oscillator) take a path with fixed-size arrays that
/// the compiler unrolls; the arithmetic, and so the result, is the same on both paths.
/// The right-hand side a stage evaluates: f(t, y) into `dydt`. Closures are one; the ensemble
/// engine's is a struct whose method is inlined into its kernel, so that what it tracks (how
/// far the sine and cosine arguments reach) stays in registers.
pub(crate) trait StageRhs<T> {
    /// Writes f(t, y) into `dydt`.
    fn eval(&mut self, t: f64, y: &[T], dydt: &mut [T]);
}

impl<T, F: FnMut(f64, &[T], &mut [T])> StageRhs<T> for F {
    #[inline(always)]
    fn eval(&mut self, t: f64, y: &[T], dydt: &mut [T]) {
        self(t, y, dydt);
    }
}

#[allow(clippy::too_many_arguments)] // the tableau's parts and the stepper's buffers, all needed
#[inline(always)]
pub(crate) fn explicit_stages<T: Num, F: StageRhs<T>>(
    a: &[&[f64]],
    plan: &[Row],
    c: &[f64],
    first: usize,
    k: &mut [T],
    stage: &mut [T],
    f: &mut F,
    t: f64,
    h: f64,
    y: &[T],
) {
    match y.len() {
        2 | 4 => {
            let plan = &plan[..a.len()];
            if y.len() == 2 {
                fixed_stages::<T, F, 2, _>(
                    a,
                    plan,
                    c,
                    first,
                    k.as_chunks_mut().0,
                    f,
                    t,
                    h,
                    y.try_into().expect("2"),
                )
            } else {
                fixed_stages::<T, F, 4, _>(
                    a,
                    plan,
                    c,
                    first,
                    k.as_chunks_mut().0,
                    f,
                    t,
                    h,
                    y.try_into().expect("4"),
                )
            }
        }
        n => {
            for (i, (row, c)) in a.iter().zip(c).enumerate().skip(first) {
                let (done, rest) = k.split_at_mut(i * n);
                let plan = plan.get(i).copied().unwrap_or(Row::Sum);
                for (j, s) in stage.iter_mut().enumerate() {
                    *s = match plan {
                        Row::Single(l, a) => T::splat(a * h).madd(done[l * n + j], y[j]),
                        Row::Sum => {
                            let mut acc = T::splat(0.0);
                            for (l, &a) in row[..i].iter().enumerate() {
                                if a != 0.0 {
                                    acc = T::splat(a).madd(done[l * n + j], acc);
                                }
                            }
                            T::splat(h).madd(acc, y[j])
                        }
                    };
                }
                f.eval(t + c * h, stage, &mut rest[..n]);
            }
        }
    }
}

/// [`explicit_stages`] for states of N components, stage i in `k[i]`, from row i of `a` (its
/// first i coefficients). A lane kernel passes the tableau as fixed-size arrays, and as many
/// stages as its method has, constants there: the loops unroll.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn fixed_stages<T: Num, F: StageRhs<T>, const N: usize, R: AsRef<[f64]>>(
    a: &[R],
    plan: &[Row],
    c: &[f64],
    first: usize,
    k: &mut [[T; N]],
    f: &mut F,
    t: f64,
    h: f64,
    y: &[T; N],
) {
    for i in first..a.len().min(k.len()) {
        let (done, rest) = k.split_at_mut(i);
        let row = &a[i].as_ref()[..i];
        // Loops, not `array::from_fn`: kernels compiled for an instruction set inline these
        // functions, and from_fn's closure, left out of line, lost the fused multiply-adds.
        let mut stage = *y;
        if let Row::Single(l, a) = plan[i] {
            let factor = T::splat(a * h);
            for j in 0..N {
                stage[j] = factor.madd(done[l][j], y[j]);
            }
        } else {
            let mut acc = [T::splat(0.0); N];
            for (l, &a) in row.iter().enumerate() {
                // Zero coefficients are skipped: adding 0 · k would be exact for finite k, but
                // costs the time of the term.
                if a != 0.0 {
                    for j in 0..N {
                        acc[j] = T::splat(a).madd(done[l][j], acc[j]);
                    }
                }
            }
            for j in 0..N {
                stage[j] = T::splat(h).madd(acc[j], y[j]);
            }
        }
        f.eval(t + c[i] * h, &stage, &mut rest[0]);
    }
}

/// How a stage's state is formed from its row of the tableau.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Row {
    /// The row's one nonzero coefficient aᵢₗ (index l), a power of two (RK4's ½ and 1,
    /// Euler's and Heun's 1): then h (a k) = (a h) k exactly, and the stage y + (a h) kₗ is one
    /// multiply-add per component, with the same result as the sum.
    Single(usize, f64),
    /// y + h Σ aᵢⱼ kⱼ, the sum from 0 left to right, zero coefficients skipped.
    Sum,
}

impl Row {
    /// The form of the stage whose row (its coefficients before the diagonal) is `row`.
    #[inline(always)]
    pub(crate) fn of(row: &[f64]) -> Row {
        let mut found = None;
        for (l, &a) in row.iter().enumerate() {
            if a != 0.0 {
                if found.is_some() {
                    return Row::Sum;
                }
                found = Some((l, a));
            }
        }
        match found {
            // A normal number with an all-zero significand: ±2ᵉ.
            Some((l, a)) if a.is_normal() && a.to_bits() & ((1 << 52) - 1) == 0 => Row::Single(l, a),
            _ => Row::Sum,
        }
    }
}

/// The most stages whose forms a [`Plan`] holds (DOP853 has 16 with its dense output's).
const MAX_PLANNED: usize = 16;

/// The forms of a tableau's stages, [`Row::of`] each row: planned once, when a stepper is
/// made, not at every step. Rows past [`MAX_PLANNED`] are sums.
pub(crate) type Plan = [Row; MAX_PLANNED];

/// The [`Plan`] of the rows `a`.
pub(crate) fn plan(a: &[&[f64]]) -> Plan {
    let mut plan = [Row::Sum; MAX_PLANNED];
    for (i, (p, row)) in plan.iter_mut().zip(a).enumerate() {
        *p = Row::of(&row[..i]);
    }
    plan
}

/// y += scale Σᵢ bᵢ kᵢ (the sum from b₀ k₀, left to right), over every number type; states of
/// 2 and 4 components with fixed-size arrays (the same arithmetic).
#[inline(always)]
pub(crate) fn explicit_update<T: Num>(b: &[f64], k: &[T], scale: f64, y: &mut [T]) {
    match y.len() {
        2 => {
            let y: &mut [T; 2] = y.try_into().expect("2");
            fixed_update::<T, 2>(b, k.as_chunks().0, scale, &y.clone(), y)
        }
        4 => {
            let y: &mut [T; 4] = y.try_into().expect("4");
            fixed_update::<T, 4>(b, k.as_chunks().0, scale, &y.clone(), y)
        }
        n => {
            for (j, yj) in y.iter_mut().enumerate() {
                let mut acc = if b[0] == 1.0 { k[j] } else { T::splat(b[0]) * k[j] };
                for (i, &b) in b.iter().enumerate().skip(1) {
                    acc = T::splat(b).madd(k[i * n + j], acc);
                }
                *yj = T::splat(scale).madd(acc, *yj);
            }
        }
    }
}

impl<S: System + ?Sized> Stepper<S> for ExplicitRk {
    fn step(&mut self, system: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        let tab = self.tableau;
        let mut f = |t: f64, y: &[f64], dydt: &mut [f64]| system.rhs(t, y, dydt);
        explicit_stages(tab.a, &self.plan, tab.c, 0, &mut self.k, &mut self.stage, &mut f, t, h, y);
        explicit_update(tab.b, &self.k, h / tab.denominator, y);
        Ok(())
    }
}

/// [`explicit_update`] for states of N components, stage i in `k[i]`, from `y` into `out`
/// (every component written: a caller whose `out` is not `y` copies nothing first).
#[inline(always)]
pub(crate) fn fixed_update<T: Num, const N: usize>(
    b: &[f64],
    k: &[[T; N]],
    scale: f64,
    y: &[T; N],
    out: &mut [T; N],
) {
    let mut acc = k[0];
    // b₀ = 1 (RK4, Euler): b₀ k₀ is k₀ itself, without the product.
    if b[0] != 1.0 {
        for j in 0..N {
            acc[j] = T::splat(b[0]) * k[0][j];
        }
    }
    for (i, ki) in k.iter().enumerate().skip(1) {
        for j in 0..N {
            acc[j] = T::splat(b[i]).madd(ki[j], acc[j]);
        }
    }
    for j in 0..N {
        out[j] = T::splat(scale).madd(acc[j], y[j]);
    }
}

/// Nothing is carried from step to step: every stage is recomputed from the step's start.
impl Snapshot for ExplicitRk {
    fn save(&self, _: &mut Words) {}
    fn restore(&mut self, _: &mut Reader<'_>) -> Result<(), Error> {
        Ok(())
    }
}
