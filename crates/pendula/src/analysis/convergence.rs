//! Global error against step size, and the order fitted to it.

use crate::control::Tolerances;
use crate::integrator::embedded::DOP853;
use crate::integrator::{Method, Scheme};
use crate::model::DynModel;
use crate::observe::Ignore;
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

impl Reference {
    /// The size errors against it are judged by: the largest |component| of the state, at
    /// least 1 ([`estimate_order`]'s `scale`).
    pub fn scale(&self) -> f64 {
        self.state.iter().fold(1.0_f64, |m, v| m.max(v.abs()))
    }
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

/// What a convergence study found for one method.
#[derive(Debug, Clone, PartialEq)]
pub enum OrderEstimate {
    /// An order fitted over `points` consecutive steps from `h_min` to `h_max` (s), where the
    /// errors lie between the saturation level and the round-off floor and the log-log curve
    /// is straight.
    Fitted {
        /// The least-squares slope.
        order: f64,
        /// Points in the fit.
        points: usize,
        /// Smallest step in the fit, s.
        h_min: f64,
        /// Largest step in the fit, s.
        h_max: f64,
    },
    /// Every error is at or above the saturation level: the steps are too large for the
    /// asymptotic range (or chaos has amplified the errors to the size of the motion).
    Saturated,
    /// Every usable error is at the round-off floor: the method is exact to rounding at
    /// these steps (a high order, or a problem it solves exactly).
    RoundOff,
    /// Too few points between saturation and round-off, or no straight stretch of three.
    Irregular,
}

impl OrderEstimate {
    /// The fitted order, if there is one.
    pub fn order(&self) -> Option<f64> {
        match self {
            OrderEstimate::Fitted { order, .. } => Some(*order),
            _ => None,
        }
    }

    /// Why there is no order, in words; `None` when fitted.
    pub fn reason(&self) -> Option<&'static str> {
        match self {
            OrderEstimate::Fitted { .. } => None,
            OrderEstimate::Saturated => Some("saturated: every error is as large as the motion"),
            OrderEstimate::RoundOff => Some("round-off floor: the errors are rounding, not truncation"),
            OrderEstimate::Irregular => {
                Some("no straight stretch of 3 steps between saturation and round-off")
            }
        }
    }
}

/// Errors at or above this share of the state's size are saturated: no longer small, so
/// not in the asymptotic range where error ≈ C hᵖ.
pub const SATURATION: f64 = 1e-2;

/// The round-off floor of a run of `steps` steps, relative to the state's size: each step
/// adds rounding errors of a few ulp, which accumulate like a random walk; a hundredfold
/// margin keeps errors that rounding disturbs out of the fit.
pub fn roundoff_floor(steps: f64) -> f64 {
    100.0 * f64::EPSILON * steps.max(1.0).sqrt()
}

/// The largest spread of local slopes (between consecutive points) that still counts as a
/// straight line in log-log coordinates.
const STRAIGHT: f64 = 0.2;

/// Estimates the order of convergence from errors at steps `hs` (largest first, as a
/// ladder), without reference to the method's declared order: the points between
/// [`SATURATION`] × `scale` and the round-off floor ([`roundoff_floor`] × `scale`, at each
/// point's number of steps over `t_end`) are candidates; the longest run of consecutive
/// candidates that ends at the smallest usable step (the most asymptotic) and reaches up to
/// larger steps while the local slopes differ by at most 0.2 is fitted by least squares,
/// when it has at least 3 points.
pub fn estimate_order(hs: &[f64], errors: &[f64], scale: f64, t_end: f64) -> OrderEstimate {
    let usable: Vec<bool> = hs
        .iter()
        .zip(errors)
        .map(|(h, e)| *e < SATURATION * scale && *e > roundoff_floor(t_end / h) * scale && e.is_finite())
        .collect();
    if !usable.iter().any(|u| *u) {
        let small = |e: f64| e < SATURATION * scale;
        let saturated = errors.iter().all(|e| !small(*e));
        let at_floor =
            hs.iter().zip(errors).all(|(h, e)| *e <= roundoff_floor(t_end / h) * scale || !small(*e));
        return if saturated {
            OrderEstimate::Saturated
        } else if at_floor {
            OrderEstimate::RoundOff
        } else {
            OrderEstimate::Irregular
        };
    }
    let slope = |i: usize| (errors[i] / errors[i + 1]).ln() / (hs[i] / hs[i + 1]).ln();
    // The asymptotic range is at small steps: the stretch ends at the smallest usable step
    // and grows towards larger ones while it stays straight.
    let end = usable.iter().rposition(|u| *u).expect("some point is usable");
    let mut start = end;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    while start > 0 && usable[start - 1] {
        let s = slope(start - 1);
        let (nlo, nhi) = (lo.min(s), hi.max(s));
        if nhi - nlo > STRAIGHT {
            break;
        }
        (lo, hi) = (nlo, nhi);
        start -= 1;
    }
    let best = (end + 1 - start >= 3).then_some((start, end));
    let Some((start, end)) = best else {
        return OrderEstimate::Irregular;
    };
    match fit_order(&hs[start..=end], &errors[start..=end]) {
        Some(fit) => OrderEstimate::Fitted {
            order: fit.order,
            points: end + 1 - start,
            h_min: hs[end],
            h_max: hs[start],
        },
        None => OrderEstimate::Irregular,
    }
}

/// The default ladder of steps for a method of `order` on a model of time scale T: halvings
/// from a start that shrinks with the order's need for accuracy (order 1 from T/64, orders
/// 2 and 3 from T/32, higher orders from T/16), and no larger than `h_limit` (a method's own
/// limit, such as Tao's ω h ≤ 1), down to where a run would take more steps over `t_end` than
/// a cap that grows as the order falls (2·10⁶ for order 1, 10⁶ for order 2, 2·10⁵ above:
/// low orders need small steps to reach their asymptotic range and are cheap per step), at
/// most `levels` steps.
pub fn default_ladder(time_scale: f64, order: u32, t_end: f64, levels: usize, h_limit: f64) -> Vec<f64> {
    let (divisor, max_steps) = match order {
        0 | 1 => (64.0, 2e6),
        2 => (32.0, 1e6),
        3 => (32.0, 2e5),
        _ => (16.0, 2e5),
    };
    let start = (time_scale / divisor).min(t_end / 4.0).min(h_limit);
    (0..levels).map(|k| start / 2f64.powi(k as i32)).take_while(|h| t_end / h <= max_steps).collect()
}

/// Most rungs of a method's default ladder ([`method_ladder`]).
pub const DEFAULT_LEVELS: usize = 14;

/// The horizon of an accuracy study on `values`' system: its `study_periods`
/// small-oscillation periods (its time scale), short of chaos's growth, s.
pub fn study_horizon(values: &crate::system::Values) -> f64 {
    values.info().study_periods * values.build().time_scale()
}

/// The default steps of `method` on a model of time scale `time_scale` (s) to `t_end` (s):
/// [`default_ladder`] of [`DEFAULT_LEVELS`] rungs at the method's order, starting inside the
/// method's own limit (Tao's maps are defined only for ω h ≤ 1).
pub fn method_ladder(method: &Method, time_scale: f64, t_end: f64) -> Vec<f64> {
    let limit = match method.scheme {
        Scheme::Tao(t) => 1.0 / t.binding,
        _ => f64::INFINITY,
    };
    default_ladder(time_scale, method.order, t_end, DEFAULT_LEVELS, limit)
}

/// `levels` tolerances from `loosest` to `tightest`, geometrically spaced, both ends exactly
/// as given: the tolerances a work-precision study runs an adaptive pair at.
pub fn tolerance_ladder(loosest: f64, tightest: f64, levels: usize) -> Vec<f64> {
    (0..levels)
        .map(|i| {
            if i + 1 == levels {
                tightest
            } else {
                loosest * (tightest / loosest).powf(i as f64 / (levels - 1) as f64)
            }
        })
        .collect()
}
