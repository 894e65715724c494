//! Global error against step size, and the order fitted to it.

use crate::control::Tolerances;
use crate::integrator::Method;
use crate::integrator::embedded::DOP853;
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

/// Tolerance of the DOP853 reference runs.
pub const REFERENCE_TOLERANCE: f64 = 1e-14;

/// The state at `t_end` from `y0`: the exact solution where the model has one, otherwise
/// dop853 at rtol = atol = [`REFERENCE_TOLERANCE`] (global error ~1e-13 on the pendulums over
/// tens of seconds; checked against mpmath in the tests).
pub fn reference_state(model: &dyn DynModel, y0: &[f64], t_end: f64) -> Result<Reference, Error> {
    if let Some(state) = model.exact(t_end, y0) {
        return Ok(Reference { state, source: "exact solution" });
    }
    let tol =
        Tolerances { rtol: REFERENCE_TOLERANCE, atol: REFERENCE_TOLERANCE, h_min: 0.0, h_max: f64::INFINITY };
    let state = model.solve_adaptive(&DOP853, y0, t_end, None, &tol, &mut Ignore)?.state;
    Ok(Reference { state, source: "dop853 reference at tolerance 1e-14" })
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
    /// Step size, s; for an adaptive run, the mean accepted step.
    pub h: f64,
    /// Tolerance (rtol = atol) of an adaptive run; `None` for a fixed step.
    pub tol: Option<f64>,
    /// Max-norm error at the end time.
    pub error: f64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Wall time of one run, s: the median of runs repeated for at least 20 ms (at most
    /// 101 runs), so that fast runs are not timed at the clock's resolution.
    pub wall_s: f64,
}

/// Median wall time of `run`, repeated until 20 ms have passed (at least once, at most 101
/// times), and the last run's result.
fn timed<T>(mut run: impl FnMut() -> Result<T, Error>) -> Result<(T, f64), Error> {
    let mut times = Vec::new();
    let begin = std::time::Instant::now();
    loop {
        let start = std::time::Instant::now();
        let out = run()?;
        times.push(start.elapsed().as_secs_f64());
        if begin.elapsed().as_secs_f64() >= 0.02 || times.len() >= 101 {
            times.sort_by(f64::total_cmp);
            return Ok((out, times[times.len() / 2]));
        }
    }
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
            let (report, wall_s) = timed(|| model.solve(method, y0, &spec, &mut Ignore))?;
            let error = max_diff(&report.state, reference);
            Ok(WorkPoint { h, tol: None, error, rhs_evals: report.rhs_evals, wall_s })
        })
        .collect()
}

/// Error and cost of an adaptive `method` at each tolerance in `tols` (rtol = atol): the
/// work-precision points of an embedded pair.
pub fn work_precision_adaptive(
    model: &dyn DynModel,
    method: &Method,
    y0: &[f64],
    t_end: f64,
    tols: &[f64],
    reference: &[f64],
) -> Result<Vec<WorkPoint>, Error> {
    tols.iter()
        .map(|&tol| {
            let tolerances = Tolerances { rtol: tol, atol: tol, h_min: 0.0, h_max: f64::INFINITY };
            let (report, wall_s) =
                timed(|| model.solve_adaptive(method, y0, t_end, None, &tolerances, &mut Ignore))?;
            let error = max_diff(&report.state, reference);
            let h = t_end / report.outcome.steps().max(1) as f64;
            Ok(WorkPoint { h, tol: Some(tol), error, rhs_evals: report.rhs_evals, wall_s })
        })
        .collect()
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}
