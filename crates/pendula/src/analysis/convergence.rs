//! Global error against step size, and the order fitted to it.

use crate::integrator::{Method, explicit_rk::RK4};
use crate::observe::Ignore;
use crate::system::DynModel;
use crate::{End, Error, RunSpec};

/// A least-squares line through (ln h, ln error).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrderFit {
    /// The slope: the measured order of convergence.
    pub order: f64,
    /// ln of the error constant C in error ≈ C hᵖ.
    pub log_constant: f64,
}

/// Fits error ≈ C hᵖ by least squares in log-log coordinates; `None` with fewer than two
/// points or a non-positive error.
pub fn fit_order(hs: &[f64], errors: &[f64]) -> Option<OrderFit> {
    if hs.len() < 2 || hs.len() != errors.len() || errors.iter().any(|e| !(*e > 0.0 && e.is_finite())) {
        return None;
    }
    let xs: Vec<f64> = hs.iter().map(|h| h.ln()).collect();
    let ys: Vec<f64> = errors.iter().map(|e| e.ln()).collect();
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    let order = sxy / sxx;
    Some(OrderFit { order, log_constant: my - order * mx })
}

/// A reference final state and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// The state at the end time.
    pub state: Vec<f64>,
    /// How it was obtained, for tables and reports.
    pub source: &'static str,
}

/// The state at `t_end` from `y0`: the exact solution where the model has one, otherwise
/// RK4 at h_fine and h_fine/2 combined by Richardson extrapolation (error O(h_fine⁵)).
pub fn reference_state(
    model: &dyn DynModel,
    y0: &[f64],
    t_end: f64,
    h_fine: f64,
) -> Result<Reference, Error> {
    if let Some(state) = model.exact(t_end, y0) {
        return Ok(Reference { state, source: "exact solution" });
    }
    let run = |h: f64| -> Result<Vec<f64>, Error> {
        let spec = RunSpec { t0: 0.0, h, end: End::Time(t_end) };
        Ok(model.solve(&RK4, y0, &spec, &mut Ignore)?.state)
    };
    let (coarse, fine) = (run(h_fine)?, run(h_fine / 2.0)?);
    let state = coarse.iter().zip(&fine).map(|(c, f)| f + (f - c) / 15.0).collect();
    Ok(Reference { state, source: "RK4-Richardson reference" })
}

/// Max-norm error at `t_end` of `method` at each step size in `hs`, against `reference`.
pub fn convergence_errors(
    model: &dyn DynModel,
    method: &Method,
    y0: &[f64],
    t_end: f64,
    hs: &[f64],
    reference: &[f64],
) -> Result<Vec<f64>, Error> {
    Ok(work_precision(model, method, y0, t_end, hs, reference)?.into_iter().map(|p| p.error).collect())
}

/// One run of a work-precision study.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorkPoint {
    /// Step size, s.
    pub h: f64,
    /// Max-norm error at the end time.
    pub error: f64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Wall-clock time of the run, s (noisy: compare methods measured together).
    pub wall_s: f64,
}

/// Error and cost of `method` at each step size in `hs`: what a work-precision diagram
/// plots (DiffEqDevTools' `WorkPrecisionSet` for fixed-step methods).
pub fn work_precision(
    model: &dyn DynModel,
    method: &Method,
    y0: &[f64],
    t_end: f64,
    hs: &[f64],
    reference: &[f64],
) -> Result<Vec<WorkPoint>, Error> {
    hs.iter()
        .map(|&h| {
            let spec = RunSpec { t0: 0.0, h, end: End::Time(t_end) };
            let start = std::time::Instant::now();
            let report = model.solve(method, y0, &spec, &mut Ignore)?;
            let wall_s = start.elapsed().as_secs_f64();
            let error = report.state.iter().zip(reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            Ok(WorkPoint { h, error, rhs_evals: report.rhs_evals, wall_s })
        })
        .collect()
}
