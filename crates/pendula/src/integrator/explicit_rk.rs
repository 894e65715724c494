//! Explicit Runge–Kutta methods, each a Butcher tableau.

use super::{Method, Requirement, Scheme, Stepper};
use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};
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
    k: Vec<f64>,
    stage: Vec<f64>,
}

impl ExplicitRk {
    /// A stepper for systems of dimension `dim`.
    pub fn new(tableau: &'static Tableau, dim: usize) -> Self {
        ExplicitRk { tableau, k: vec![0.0; tableau.b.len() * dim], stage: vec![0.0; dim] }
    }
}

/// The stages of an explicit tableau (rows `a`, nodes `c`) from (t, y) with step h: stage i
/// is kᵢ = f(t + cᵢ h, y + h Σⱼ aᵢⱼ kⱼ), stored at `k[i n .. (i + 1) n]`. Stages before
/// `first` are taken as already in `k` (first same as last).
///
/// States of 2 and 4 components (every built-in system) take a path with fixed-size arrays
/// that the compiler unrolls; the arithmetic, and so the result, is the same on both paths.
#[allow(clippy::too_many_arguments)] // the tableau's parts and the stepper's buffers, all needed
pub(super) fn explicit_stages<S: System + ?Sized>(
    a: &[&[f64]],
    c: &[f64],
    first: usize,
    k: &mut [f64],
    stage: &mut [f64],
    system: &S,
    t: f64,
    h: f64,
    y: &[f64],
) {
    match y.len() {
        2 => fixed_stages::<S, 2>(a, c, first, k, system, t, h, y),
        4 => fixed_stages::<S, 4>(a, c, first, k, system, t, h, y),
        n => {
            for (i, (row, c)) in a.iter().zip(c).enumerate().skip(first) {
                let (done, rest) = k.split_at_mut(i * n);
                for (j, s) in stage.iter_mut().enumerate() {
                    let mut acc = 0.0;
                    for (l, &a) in row.iter().enumerate() {
                        if a != 0.0 {
                            acc += a * done[l * n + j];
                        }
                    }
                    *s = y[j] + h * acc;
                }
                system.rhs(t + c * h, stage, &mut rest[..n]);
            }
        }
    }
}

/// [`explicit_stages`] for states of N components.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn fixed_stages<S: System + ?Sized, const N: usize>(
    a: &[&[f64]],
    c: &[f64],
    first: usize,
    k: &mut [f64],
    system: &S,
    t: f64,
    h: f64,
    y: &[f64],
) {
    let y: &[f64; N] = y.try_into().expect("N components");
    for (i, (row, c)) in a.iter().zip(c).enumerate().skip(first) {
        let (done, rest) = k.split_at_mut(i * N);
        let mut acc = [0.0; N];
        for (l, &a) in row.iter().enumerate() {
            // Zero coefficients are skipped: adding 0 · k would be exact for finite k, but
            // costs the time of the term.
            if a != 0.0 {
                let kl: &[f64; N] = done[l * N..(l + 1) * N].try_into().expect("N components");
                for j in 0..N {
                    acc[j] += a * kl[j];
                }
            }
        }
        let stage: [f64; N] = std::array::from_fn(|j| y[j] + h * acc[j]);
        system.rhs(t + c * h, &stage, &mut rest[..N]);
    }
}

impl<S: System + ?Sized> Stepper<S> for ExplicitRk {
    fn step(&mut self, system: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        let tab = self.tableau;
        explicit_stages(tab.a, tab.c, 0, &mut self.k, &mut self.stage, system, t, h, y);
        let scale = h / tab.denominator;
        match y.len() {
            2 => fixed_update::<2>(tab.b, &self.k, scale, y),
            4 => fixed_update::<4>(tab.b, &self.k, scale, y),
            n => {
                for (j, yj) in y.iter_mut().enumerate() {
                    let mut acc = tab.b[0] * self.k[j];
                    for (i, &b) in tab.b.iter().enumerate().skip(1) {
                        acc += b * self.k[i * n + j];
                    }
                    *yj += scale * acc;
                }
            }
        }
        Ok(())
    }
}

/// y += scale Σᵢ bᵢ kᵢ for states of N components (the same arithmetic as the general path).
#[inline(always)]
fn fixed_update<const N: usize>(b: &[f64], k: &[f64], scale: f64, y: &mut [f64]) {
    let y: &mut [f64; N] = y.try_into().expect("N components");
    let k0: &[f64; N] = k[..N].try_into().expect("N components");
    let mut acc: [f64; N] = std::array::from_fn(|j| b[0] * k0[j]);
    for (i, &bi) in b.iter().enumerate().skip(1) {
        let ki: &[f64; N] = k[i * N..(i + 1) * N].try_into().expect("N components");
        for j in 0..N {
            acc[j] += bi * ki[j];
        }
    }
    for j in 0..N {
        y[j] += scale * acc[j];
    }
}

/// Nothing is carried from step to step: every stage is recomputed from the step's start.
impl Snapshot for ExplicitRk {
    fn save(&self, _: &mut Words) {}
    fn restore(&mut self, _: &mut Reader<'_>) -> Result<(), Error> {
        Ok(())
    }
}
