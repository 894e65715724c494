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
    /// Its own error relative to [`Reference::scale`], as far as it is known: a few ulp for
    /// an exact solution, [`REFERENCE_TOLERANCE`] for the dop853 reference (whose global error
    /// on the pendulums over a few seconds is 10⁻¹⁴ … 3·10⁻¹⁴ of the state). Errors measured
    /// against the reference are no smaller than this, whatever the method: part of the floor
    /// [`estimate_order`] keeps out of its fits.
    pub accuracy: f64,
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
        return Ok(Reference { state, source: "exact solution", accuracy: f64::EPSILON });
    }
    let tol =
        Tolerances { rtol: REFERENCE_TOLERANCE, atol: REFERENCE_TOLERANCE, h_min: 0.0, h_max: f64::INFINITY };
    let state = model.solve_adaptive(&DOP853, y0, t_end, None, &tol, &mut Ignore)?.state;
    Ok(Reference { state, source: "dop853 reference at tolerance 1e-14", accuracy: REFERENCE_TOLERANCE })
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
    /// Every error below saturation is within [`FLOOR_MARGIN`] of the floor (rounding and the
    /// reference's own error): the method is exact to rounding at these steps (a high order,
    /// or a problem it solves exactly).
    RoundOff,
    /// The errors reach the floor before the log-log curve straightens: the local slopes
    /// still change at the last error above the floor, so every step that shows truncation
    /// is still too large for the asymptotic range (a high order whose error falls by orders
    /// of magnitude a step, from saturation to the floor within a few steps).
    Preasymptotic,
    /// No straight stretch of 3 points between saturation and the floor, and no floor
    /// reached either: a curve that bends or zigzags (cancelling error terms, too few steps).
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

    /// Why there is no order, in a sentence; `None` when fitted. It begins with
    /// [`OrderEstimate::label`].
    pub fn reason(&self) -> Option<&'static str> {
        match self {
            OrderEstimate::Fitted { .. } => None,
            OrderEstimate::Saturated => {
                Some("step too large: every error is 1% of the state or more, outside the asymptotic range")
            }
            OrderEstimate::RoundOff => Some(
                "saturated at round-off: every error is within 10x of the floor (rounding and the reference's accuracy), not truncation",
            ),
            OrderEstimate::Preasymptotic => Some(
                "step too large: the errors reach the round-off floor while the log-log slope still changes; the asymptotic range lies below the floor",
            ),
            OrderEstimate::Irregular => {
                Some("irregular: no straight stretch of 3 steps between saturation and round-off")
            }
        }
    }

    /// A few words for a legend: the order, or why there is none ("step too large",
    /// "saturated at round-off", "irregular").
    pub fn label(&self) -> String {
        match self {
            OrderEstimate::Fitted { order, .. } => format!("order {order:.2}"),
            other => other.reason().and_then(|r| r.split(':').next()).unwrap_or_default().to_owned(),
        }
    }
}

/// Errors at or above this share of the state's size are saturated: no longer small, so
/// not in the asymptotic range where error ≈ C hᵖ.
pub const SATURATION: f64 = 1e-2;

/// The round-off floor of a run of `steps` steps, relative to the state's size: each step
/// adds rounding errors of about an ulp, which accumulate like a random walk (on the double
/// pendulum the errors of rk4 and the Gauss–Legendre methods level off at 1–3 times this).
pub fn roundoff_floor(steps: f64) -> f64 {
    f64::EPSILON * steps.max(1.0).sqrt()
}

/// How far above the floor (the larger of [`roundoff_floor`] and the reference's accuracy)
/// an error must lie to enter a fit: there rounding changes it by at most 10%.
pub const FLOOR_MARGIN: f64 = 10.0;

/// How much the local slopes (between consecutive points) of a stretch may differ, beyond
/// what rounding explains, for the stretch to count as straight in log-log coordinates:
/// every local slope lies within this of the fitted order.
pub const STRAIGHT: f64 = 0.1;

/// The least ratio of the largest to the smallest step of a fitted stretch: 3 points of a
/// ladder of halvings, 4 of one of √2 steps. Over a shorter stretch a bend of the log-log
/// curve cannot be told from its slope.
pub const MIN_SPAN: f64 = 2.0 * std::f64::consts::SQRT_2;

/// Estimates the order of convergence from errors at steps `hs` (largest first, as a
/// ladder), without reference to the method's declared order.
///
/// The candidates are the points whose error lies below [`SATURATION`] × `scale` and at
/// least [`FLOOR_MARGIN`] times above the floor F: the larger of [`roundoff_floor`] (at each
/// point's number of steps over `t_end`) and `accuracy` (the reference's own relative error,
/// [`Reference::accuracy`]), times `scale`. Each local slope is known to within what rounding
/// may do to its two errors (ln(1 + F/e) each, over the ln of the step ratio) plus
/// [`STRAIGHT`]/2. The asymptotic range is at the small steps: the stretch of consecutive
/// candidates that ends at the smallest one and reaches up to larger steps while all of its
/// local slopes agree within those bounds is fitted by least squares, when it has at least
/// 3 points and spans a factor [`MIN_SPAN`] in step. (A smallest candidate within 100 F whose slope is flatter than the next one's,
/// beyond both bounds, is touched by the floor and left out: rounding only adds error.)
/// Without such a stretch, the estimate says why: every error saturated, every error at
/// the floor, the floor reached while the slope still changes
/// ([`OrderEstimate::Preasymptotic`]), or an irregular curve.
pub fn estimate_order(hs: &[f64], errors: &[f64], scale: f64, t_end: f64, accuracy: f64) -> OrderEstimate {
    let model = |i: usize| roundoff_floor(t_end / hs[i]).max(accuracy) * scale;
    let small = |e: f64| e < SATURATION * scale;
    let candidate =
        |i: usize, floor: f64| errors[i].is_finite() && small(errors[i]) && errors[i] > FLOOR_MARGIN * floor;
    // Where the errors level off at steps below the last candidate, that level (the lower
    // median of those errors) is the floor measured: the model's random walk and the reference's
    // nominal accuracy can fall short of it (a long chain rounds more, and its reference is
    // less accurate).
    let observed = match (0..hs.len()).rposition(|i| candidate(i, model(i))) {
        Some(last) => {
            let mut below: Vec<f64> =
                errors[last + 1..].iter().copied().filter(|e| e.is_finite() && small(*e)).collect();
            below.sort_by(f64::total_cmp);
            // A level takes two points at least (one may still hold some truncation error).
            if below.len() >= 2 { below[(below.len() - 1) / 2] } else { 0.0 }
        }
        None => 0.0,
    };
    let floor = |i: usize| model(i).max(observed);
    let at_floor = |i: usize| errors[i] <= FLOOR_MARGIN * floor(i);
    let usable: Vec<bool> = (0..hs.len()).map(|i| candidate(i, floor(i))).collect();
    if !usable.iter().any(|u| *u) {
        let saturated = errors.iter().all(|e| !small(*e));
        let rounding = (0..hs.len()).all(|i| at_floor(i) || !small(errors[i]));
        return if saturated {
            OrderEstimate::Saturated
        } else if rounding {
            OrderEstimate::RoundOff
        } else {
            OrderEstimate::Irregular
        };
    }
    // The local slope from point i to i + 1, and the interval it is known to lie in.
    let slope = |i: usize| (errors[i] / errors[i + 1]).ln() / (hs[i] / hs[i + 1]).ln();
    let noise = |i: usize| (1.0 + floor(i) / errors[i]).ln();
    let bounds = |i: usize| {
        let half = (noise(i) + noise(i + 1)) / (hs[i] / hs[i + 1]).ln().abs() + 0.5 * STRAIGHT;
        (slope(i) - half, slope(i) + half)
    };
    let last = usable.iter().rposition(|u| *u).expect("some point is usable");
    let mut end = last;
    while end >= 2
        && usable[end - 1]
        && usable[end - 2]
        && errors[end] <= 100.0 * floor(end)
        && bounds(end - 1).1 < bounds(end - 2).0
    {
        end -= 1;
    }
    // The asymptotic range is at small steps: the stretch ends at the smallest usable step
    // and grows towards larger ones while its slopes' intervals share a point.
    let mut start = end;
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    while start > 0 && usable[start - 1] {
        let (a, b) = bounds(start - 1);
        if a.max(lo) > b.min(hi) {
            break;
        }
        (lo, hi) = (a.max(lo), b.min(hi));
        start -= 1;
    }
    if end + 1 - start < 3 || hs[start] / hs[end] < MIN_SPAN * (1.0 - 1e-9) {
        let reached_floor = last > end || (end + 1..hs.len()).any(at_floor);
        return if reached_floor { OrderEstimate::Preasymptotic } else { OrderEstimate::Irregular };
    }
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
/// (for orders 6 and up, steps √2 apart: their error falls 64-fold or more a halving, and
/// would cross the range between saturation and the round-off floor in two or three
/// halvings, too few points for a fit) from a start that shrinks with the order's need for
/// accuracy (order 1 from T/64, orders 2 and 3 from T/32, higher orders from T/16), and no
/// larger than `h_limit` (a method's own limit, such as Tao's ω h ≤ 1), down to where a run
/// would take more steps over `t_end` than a cap that grows as the order falls (2·10⁶ for
/// order 1, 10⁶ for order 2, 2·10⁵ above: low orders need small steps to reach their
/// asymptotic range and are cheap per step), at most `levels` steps.
pub fn default_ladder(time_scale: f64, order: u32, t_end: f64, levels: usize, h_limit: f64) -> Vec<f64> {
    let (divisor, max_steps) = match order {
        0 | 1 => (64.0, 2e6),
        2 => (32.0, 1e6),
        3 => (32.0, 2e5),
        _ => (16.0, 2e5),
    };
    let start = (time_scale / divisor).min(t_end / 4.0).min(h_limit);
    let ratio: f64 = if order >= 6 { std::f64::consts::SQRT_2 } else { 2.0 };
    (0..levels).map(|k| start / ratio.powi(k as i32)).take_while(|h| t_end / h <= max_steps).collect()
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
