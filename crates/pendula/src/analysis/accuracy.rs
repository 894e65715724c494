//! The accuracy studies over several methods — convergence (error against step) and
//! work-precision (error against cost) — as every front end runs them: each method at its
//! steps (fixed-step methods) or tolerances (embedded pairs, in work-precision), against one
//! reference state. A run that fails or is refused ([`Error::is_per_run`]: a large step
//! blowing up, Tao's maps above ω h = 1, a Newton failure) drops its point, the method
//! keeps the points of its other runs and says why, and the study goes on; any other error
//! ends it.
//!
//! The front ends phrase a dropped run in their own words (the CLI's step is `h`, Python's
//! `dt`), so the failure is kept as the step and the library error.

use crate::Error;
use crate::analysis::convergence::{
    OrderEstimate, Reference, WorkPoint, convergence_errors, estimate_order, work_precision,
    work_precision_adaptive,
};
use crate::integrator::Method;
use crate::model::DynModel;

/// A dropped run: its method, the step (s) or, for an embedded pair in work-precision, the
/// tolerance it ran at, and why it failed.
#[derive(Debug, Clone)]
pub struct Dropped {
    /// The method that ran.
    pub method: &'static Method,
    /// The step, s, or the tolerance ([`Dropped::adaptive`]).
    pub x: f64,
    /// Whether `x` is a tolerance (an embedded pair's run) rather than a step.
    pub adaptive: bool,
    /// The library's reason.
    pub error: Error,
}

impl Dropped {
    /// Why it was dropped, with the step named `dt` as the studies' parameters name it (the
    /// run loop's `h`), and Tao's refusal as the largest `dt` allowed.
    pub fn why(&self) -> Error {
        if self.adaptive {
            return self.error.clone();
        }
        if let Error::InvalidValue { .. } = self.error
            && let Some(refusal) = crate::integrator::tao::step_refusal(self.method, self.x)
        {
            return refusal;
        }
        crate::error::step_named_dt(self.error.clone())
    }

    /// Where (`dt` or `tol`) and why it was dropped: `at dt = 0.01: …`.
    pub fn note(&self) -> String {
        format!(
            "at {} = {}: {}",
            if self.adaptive { "tol" } else { "dt" },
            crate::error::Short(self.x),
            self.why()
        )
    }
}

/// The problem both studies solve: `model` from `y0` to `t_end`, against the state
/// `reference` there.
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    /// The system.
    pub model: &'a dyn DynModel,
    /// The initial state.
    pub y0: &'a [f64],
    /// The end time, s.
    pub t_end: f64,
    /// The reference state at `t_end`.
    pub reference: &'a Reference,
}

/// What a convergence study found for one method.
#[derive(Debug, Clone)]
pub struct MethodConvergence {
    /// The method.
    pub method: &'static Method,
    /// The steps that gave an error, s.
    pub hs: Vec<f64>,
    /// The max-norm error at the end time of each.
    pub errors: Vec<f64>,
    /// What the order fit found.
    pub estimate: OrderEstimate,
    /// The dropped runs, in the order they ran.
    pub dropped: Vec<Dropped>,
}

impl MethodConvergence {
    /// The fitted order, if there is one.
    pub fn order(&self) -> Option<f64> {
        self.estimate.order()
    }

    /// The table's note: the fit's range (its steps in the front end's `short` form), or why
    /// there is no order; a dropped run follows, as `failure` phrases it.
    pub fn note(&self, short: impl Fn(f64) -> String, failure: impl Fn(&Dropped) -> String) -> String {
        let failure = self.dropped.last().map(failure);
        match (&self.estimate, failure) {
            (OrderEstimate::Fitted { points, h_min, h_max, .. }, _) => {
                format!("fitted over {points} steps, {} .. {}", short(*h_min), short(*h_max))
            }
            (e, None) => e.reason().unwrap_or_default().to_owned(),
            (_, Some(f)) if self.hs.is_empty() => f,
            (e, Some(f)) => format!("{}; {f}", e.reason().unwrap_or_default()),
        }
    }
}

/// What a work-precision study found for one method.
#[derive(Debug, Clone)]
pub struct MethodWork {
    /// The method.
    pub method: &'static Method,
    /// One point per run that finished.
    pub points: Vec<WorkPoint>,
    /// The dropped runs, in the order they ran.
    pub dropped: Vec<Dropped>,
}

/// A run's result, or `None` with the run added to `dropped` when it failed on its own
/// ([`Error::is_per_run`]) at step or tolerance `x`.
fn kept<T>(
    run: Result<T, Error>,
    method: &'static Method,
    x: f64,
    adaptive: bool,
    dropped: &mut Vec<Dropped>,
) -> Result<Option<T>, Error> {
    match run {
        Ok(v) => Ok(Some(v)),
        Err(error) if error.is_per_run() => {
            dropped.push(Dropped { method, x, adaptive, error });
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

/// The first dropped run of a study whose every method lost every point: what its front end
/// reports as the study's error. `None` when some run gave a point.
pub fn all_dropped<'a>(
    produced: bool,
    dropped: impl IntoIterator<Item = &'a [Dropped]>,
) -> Option<&'a Dropped> {
    if produced { None } else { dropped.into_iter().find_map(|d| d.first()) }
}

/// Whether no method has a run to do: every ladder is empty (and, in work-precision, no
/// embedded pair runs its tolerances). Front ends refuse such a study before any run.
pub fn nothing_to_run(
    methods: &[&'static Method],
    ladder: impl Fn(&Method) -> Vec<f64>,
    tolerances: bool,
) -> bool {
    !methods.iter().any(|m| (tolerances && m.adaptive()) || !ladder(m).is_empty())
}

/// The convergence study: each method at the steps `ladder` gives it, on the `problem`,
/// its errors against the reference and the order fitted where they are in the asymptotic
/// range ([`estimate_order`]). `done` is called after each method (for progress).
///
/// # Errors
/// The first error of a run that is not a per-run failure ([`Error::is_per_run`]).
pub fn convergence_study(
    problem: &Problem<'_>,
    methods: &[&'static Method],
    ladder: impl Fn(&Method) -> Vec<f64>,
    mut done: impl FnMut(),
) -> Result<Vec<MethodConvergence>, Error> {
    let Problem { model, y0, t_end, reference } = *problem;
    let scale = reference.scale();
    let mut results = Vec::with_capacity(methods.len());
    for &method in methods {
        let (mut hs, mut errors, mut dropped) = (Vec::new(), Vec::new(), Vec::new());
        for h in ladder(method) {
            // Large steps may be refused or blow up where smaller ones work: keep going.
            let run = convergence_errors(model, method, y0, t_end, &[h], &reference.state);
            if let Some(e) = kept(run, method, h, false, &mut dropped)? {
                hs.push(h);
                errors.push(e[0]);
            }
        }
        let estimate = estimate_order(&hs, &errors, scale, t_end, reference.accuracy);
        results.push(MethodConvergence { method, hs, errors, estimate, dropped });
        done();
    }
    Ok(results)
}

/// The work-precision study: fixed-step methods at the steps `ladder` gives them, embedded
/// pairs at `tolerances` (rtol = atol), from `y0` to `t_end`, each point's error against
/// `reference` and its cost ([`work_precision`], [`work_precision_adaptive`]). `done` is
/// called after each method.
///
/// # Errors
/// The first error of a run that is not a per-run failure ([`Error::is_per_run`]).
pub fn work_precision_study(
    problem: &Problem<'_>,
    methods: &[&'static Method],
    ladder: impl Fn(&Method) -> Vec<f64>,
    tolerances: &[f64],
    mut done: impl FnMut(),
) -> Result<Vec<MethodWork>, Error> {
    let Problem { model, y0, t_end, reference } = *problem;
    let mut results = Vec::with_capacity(methods.len());
    for &method in methods {
        let adaptive = method.adaptive();
        let xs = if adaptive { tolerances.to_vec() } else { ladder(method) };
        let (mut points, mut dropped) = (Vec::new(), Vec::new());
        for x in xs {
            let point = if adaptive {
                work_precision_adaptive(model, method, y0, t_end, &[x], &reference.state)
            } else {
                work_precision(model, method, y0, t_end, &[x], &reference.state)
            };
            points.extend(kept(point, method, x, adaptive, &mut dropped)?.into_iter().flatten());
        }
        results.push(MethodWork { method, points, dropped });
        done();
    }
    Ok(results)
}
