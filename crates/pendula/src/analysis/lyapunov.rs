//! Lyapunov exponents by Benettin's method: the state and k tangent vectors advance
//! together under the variational equations v' = J(t, y) v, and every `renormalise` seconds
//! the tangent vectors are re-orthonormalised by QR (modified Gram–Schmidt); the logarithms
//! of R's diagonal, summed over time, give the k largest exponents.
//!
//! References: G. Benettin, L. Galgani, A. Giorgilli and J.-M. Strelcyn, *Meccanica* 15,
//! 9–20 and 21–30 (1980); I. Shimada and T. Nagashima, *Prog. Theor. Phys.* 61, 1605 (1979);
//! the uncertainty is the standard error of batch means (consecutive blocks of the run).

use crate::Error;
use crate::integrator::embedded::EmbeddedRk;
use crate::integrator::explicit_rk::ExplicitRk;
use crate::integrator::gauss_legendre::Collocation;
use crate::integrator::{Method, Scheme, Stepper};
use crate::system::System;

/// The largest state the tangent system supports (the 8-link chain's 16).
pub const MAX_DIM: usize = 16;

/// The variational system: y = (x, v₁, …, v_k), x' = f(t, x), vⱼ' = J(t, x) vⱼ, with the
/// Jacobian of the model (analytic or by num-dual). Its right-hand side allocates nothing.
pub struct Tangent<'a> {
    /// The system.
    pub model: &'a dyn System,
    /// Dimension of the model's state.
    pub n: usize,
    /// Number of tangent vectors.
    pub k: usize,
}

impl System for Tangent<'_> {
    fn dim(&self) -> usize {
        self.n * (1 + self.k)
    }

    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        let n = self.n;
        let (x, v) = y.split_at(n);
        let (dx, dv) = dydt.split_at_mut(n);
        self.model.rhs(t, x, dx);
        let mut jac = [0.0; MAX_DIM * MAX_DIM];
        self.model.jacobian(t, x, &mut jac[..n * n]);
        for (vj, dvj) in v.chunks_exact(n).zip(dv.chunks_exact_mut(n)) {
            for (row, d) in dvj.iter_mut().enumerate() {
                *d = jac[row * n..(row + 1) * n].iter().zip(vj).map(|(a, b)| a * b).sum();
            }
        }
    }
}

/// How to run a Lyapunov computation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LyapunovSpec {
    /// Step size, s.
    pub h: f64,
    /// Time simulated before the exponents are accumulated (the tangent vectors still align
    /// during it), s.
    pub transient: f64,
    /// Time over which the exponents are accumulated, s.
    pub t_end: f64,
    /// Interval between re-orthonormalisations, s (rounded to whole steps).
    pub renormalise: f64,
    /// Number of exponents (1: the largest; the state's dimension: the whole spectrum).
    pub count: usize,
    /// Number of consecutive blocks for the batch-means uncertainty (≥ 2).
    pub blocks: usize,
}

/// The fewest re-orthonormalisations an averaging time must hold: the batch-means
/// uncertainty needs that many intervals.
pub const MIN_INTERVALS: f64 = 20.0;

/// Why a Lyapunov spec's step, interval and averaging time do not fit together
/// ([`LyapunovSpec::mismatch`]); the front ends phrase it in their arguments' names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mismatch {
    /// The step is longer than the interval between re-orthonormalisations.
    StepOverInterval,
    /// The averaging time holds fewer than [`MIN_INTERVALS`] intervals.
    TooFewIntervals,
}

impl LyapunovSpec {
    /// The first way the step, the interval and the averaging time do not fit, in the
    /// order a user fixes them: the step is blamed before the interval.
    pub fn mismatch(&self) -> Option<Mismatch> {
        if self.h > self.renormalise {
            Some(Mismatch::StepOverInterval)
        } else if self.t_end / self.renormalise < MIN_INTERVALS {
            Some(Mismatch::TooFewIntervals)
        } else {
            None
        }
    }
}

/// The result of [`lyapunov`].
#[derive(Debug, Clone, PartialEq)]
pub struct Lyapunov {
    /// The exponents, largest first, 1/s.
    pub exponents: Vec<f64>,
    /// Standard error of each exponent from the spread of its block estimates, 1/s.
    pub uncertainty: Vec<f64>,
    /// The running estimates after each re-orthonormalisation: rows of (t since the end of
    /// the transient, λ₁, …, λ_k).
    pub running: Vec<f64>,
}

/// The `count` largest Lyapunov exponents of `model` (a catalogued one through
/// [`crate::system::AsSystem`]) from `y0`, by Benettin's method with
/// `method` (an explicit Runge–Kutta method, an embedded pair used at fixed steps, or
/// Gauss–Legendre) on the variational equations.
///
/// # Errors
/// [`Error::InvalidValue`] for a bad spec; [`Error::UnmetRequirement`] for a method that
/// is not a one-step ODE method (symplectic splittings need a Hamiltonian form, which the
/// variational system lacks) or a model without a Jacobian; the run's errors (non-finite
/// state, with its time).
pub fn lyapunov(
    model: &dyn System,
    method: &Method,
    y0: &[f64],
    spec: &LyapunovSpec,
) -> Result<Lyapunov, Error> {
    let n = y0.len();
    let invalid = |name: &str, value: f64, allowed: &'static str| Error::InvalidValue {
        name: name.into(),
        value,
        allowed,
    };
    if !(spec.h.is_finite() && spec.h > 0.0) {
        return Err(invalid("h", spec.h, "must be finite and > 0"));
    }
    if !(spec.t_end.is_finite() && spec.t_end > 0.0) {
        return Err(invalid("t_end", spec.t_end, "must be finite and > 0"));
    }
    if !(spec.transient.is_finite() && spec.transient >= 0.0) {
        return Err(invalid("transient", spec.transient, "must be finite and >= 0"));
    }
    if !(spec.renormalise.is_finite() && spec.renormalise >= spec.h && spec.renormalise <= spec.t_end) {
        return Err(invalid(
            "renormalise",
            spec.renormalise,
            "must be at least one step and at most the run's length t_end",
        ));
    }
    if spec.count == 0 || spec.count > n {
        return Err(invalid("count", spec.count as f64, "must be from 1 to the state's dimension"));
    }
    if n > MAX_DIM {
        return Err(invalid("dimension", n as f64, "must be at most 16"));
    }
    let mut probe = [0.0; MAX_DIM * MAX_DIM];
    if !model.jacobian(0.0, y0, &mut probe[..n * n]) {
        return Err(Error::UnmetRequirement {
            method: "lyapunov",
            needs: "the system's Jacobian",
            reason: "this system provides none".into(),
            suggestion: "pendula divergence".into(),
        });
    }
    let tangent = Tangent { model, n, k: spec.count };
    let dim = tangent.dim();
    let steps_per_block = (spec.renormalise / spec.h).round().max(1.0) as u64;
    let unmet = || Error::UnmetRequirement {
        method: method.name,
        needs: "a Hamiltonian form",
        reason: "the variational equations are integrated as one ODE, which has none".into(),
        suggestion: "rk4, dop853 or gauss-legendre-4".into(),
    };
    let mut stepper: Box<dyn Stepper<Tangent<'_>>> = match method.scheme {
        Scheme::ExplicitRk(t) => Box::new(ExplicitRk::new(t, dim)),
        Scheme::Embedded(t) => Box::new(EmbeddedRk::new(t, dim)),
        Scheme::Collocation(t) => Box::new(Collocation::new(t, dim)),
        _ => return Err(unmet()),
    };

    // Initial tangent vectors: orthonormal, none along a coordinate axis alone (a generic
    // start), by Gram–Schmidt of (1, 1, …), (1, 2, …), …
    let mut y = vec![0.0; dim];
    y[..n].copy_from_slice(y0);
    for j in 0..spec.count {
        for i in 0..n {
            y[n * (1 + j) + i] = if i == j { 2.0 } else { 1.0 };
        }
    }
    let mut logs = vec![0.0; spec.count];
    orthonormalise(n, &mut y[n..], &mut logs);

    let transient_steps = (spec.transient / spec.h).round() as u64;
    let renorms = ((spec.t_end / spec.h).round() as u64).div_ceil(steps_per_block).max(1);
    let mut t = 0.0;
    let mut step_index: u64 = 0;
    let mut advance = |y: &mut [f64], steps: u64| -> Result<(), Error> {
        for _ in 0..steps {
            stepper.step(&tangent, t, spec.h, y)?;
            step_index += 1;
            t = step_index as f64 * spec.h;
            if y.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFinite { t });
            }
        }
        Ok(())
    };
    // The transient, re-orthonormalising as usual but discarding the growth.
    let mut done = 0;
    while done < transient_steps {
        let steps = steps_per_block.min(transient_steps - done);
        advance(&mut y, steps)?;
        orthonormalise(n, &mut y[n..], &mut logs);
        done += steps;
    }

    let k = spec.count;
    let mut sums = vec![0.0; k];
    let mut per_interval = Vec::with_capacity(renorms as usize * k);
    let mut running = Vec::with_capacity(renorms as usize * (k + 1));
    let interval = steps_per_block as f64 * spec.h;
    for r in 1..=renorms {
        advance(&mut y, steps_per_block)?;
        orthonormalise(n, &mut y[n..], &mut logs);
        let elapsed = r as f64 * interval;
        running.push(elapsed);
        for j in 0..k {
            sums[j] += logs[j];
            per_interval.push(logs[j]);
            running.push(sums[j] / elapsed);
        }
    }
    let total = renorms as f64 * interval;
    let exponents: Vec<f64> = sums.iter().map(|s| s / total).collect();
    let uncertainty = (0..k).map(|j| batch_error(&per_interval, k, j, interval, spec.blocks)).collect();
    Ok(Lyapunov { exponents, uncertainty, running })
}

/// The standard error of exponent `j` from `blocks` consecutive blocks of its per-interval
/// logarithms (`k` per interval): std(block means) / √blocks.
fn batch_error(per_interval: &[f64], k: usize, j: usize, interval: f64, blocks: usize) -> f64 {
    let intervals = per_interval.len() / k;
    let blocks = blocks.clamp(2, intervals.max(2));
    let size = intervals / blocks;
    if size == 0 {
        return f64::NAN;
    }
    let means: Vec<f64> = (0..blocks)
        .map(|b| {
            (b * size..(b + 1) * size).map(|i| per_interval[i * k + j]).sum::<f64>()
                / (size as f64 * interval)
        })
        .collect();
    let mean = means.iter().sum::<f64>() / blocks as f64;
    let var = means.iter().map(|m| (m - mean) * (m - mean)).sum::<f64>() / (blocks - 1) as f64;
    (var / blocks as f64).sqrt()
}

/// Modified Gram–Schmidt on the vectors (consecutive runs of `n` values): orthonormalises
/// them in place and writes ln ‖·‖ of each before its normalisation (R's diagonal) to `logs`.
fn orthonormalise(n: usize, vectors: &mut [f64], logs: &mut [f64]) {
    for (j, log) in logs.iter_mut().enumerate() {
        let (done, rest) = vectors.split_at_mut(j * n);
        let v = &mut rest[..n];
        for q in done.chunks_exact(n) {
            let dot: f64 = q.iter().zip(v.iter()).map(|(a, b)| a * b).sum();
            for (vi, qi) in v.iter_mut().zip(q) {
                *vi -= dot * qi;
            }
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        *log = norm.ln();
        for vi in v.iter_mut() {
            *vi /= norm;
        }
    }
}
