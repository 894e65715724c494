//! `pendula compare`: several methods on one problem — energy error, trajectories, phase
//! portraits and cost (paper §7.3, §8.3, Figures 6 and 7).
//!
//! By default every method gets the same cost — the same number of right-hand-side
//! evaluations per simulated second — and its step is chosen to spend it, so that the
//! comparison is fair: the lesson of §8 (symplectic methods keep the energy error bounded,
//! RK4's drifts) is a statement about long runs at equal work. `--dt` gives every method the
//! same step instead.

use std::ops::ControlFlow;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use pendula::analysis::{EnergySeries, Growth, drift_rate, envelope, first_exceeding, growth};
use pendula::integrator::Method;
use pendula::observe::{Every, Flow, Observer, Recorder, Sample};
use pendula::system::Values;
use pendula::{End, RunSpec};
use pendula_viz::{Figure, Kind, Scale, axis_label, method_style, pretty, with_unit};
use rayon::prelude::*;
use serde_json::json;

use pendula::error::Short;

use crate::args::{Defaults, SystemArg};
use crate::limits::{self, Cost, Estimate, round};
use crate::parse::positive_arg;
use crate::study::{self, Common, OutDir, num, refusal, short};

#[derive(Debug, Clone, Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub system: SystemArg,
    /// Comma-separated methods [default: every method that applies].
    #[arg(long, value_name = "LIST")]
    pub methods: Option<String>,
    /// The cost given to every method: right-hand-side evaluations per simulated second
    /// (a Jacobian counts as one evaluation per state variable); each method's step is
    /// chosen to spend it [default: 3000, i.e. RK4 at h = 1/750 s, where tao-4's step stays
    /// below 1/(its binding constant)].
    #[arg(long, value_name = "N", conflicts_with = "dt", allow_hyphen_values = true)]
    pub evals_per_second: Option<String>,
    /// One step size for every method instead of equal cost, s.
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub dt: Option<String>,
    /// End time, s [default: 2000 for the double pendulum (where, at the default cost, RK4's
    /// drift passes the bounded errors of gauss-legendre-4 and -6; those of the low-order
    /// methods only far beyond, extrapolated), 500 otherwise].
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_end: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// How each method's step is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Steps {
    /// The same step for every method, s.
    Equal(f64),
    /// The same cost: this many evaluations per simulated second.
    EqualCost(f64),
}

/// One method's run.
pub struct Run {
    pub method: &'static str,
    /// Its step, s.
    pub h: f64,
    pub steps: u64,
    pub rhs_evals: u64,
    /// Evaluations counting each Jacobian as one per state variable: the cost compared.
    pub cost: u64,
    pub wall_s: f64,
    /// max |error| / energy scale.
    pub max_rel_energy_error: f64,
    /// max |error|, J.
    pub max_abs_energy_error: f64,
    /// Slope of the relative error, 1/s.
    pub drift_rate: f64,
    /// Bounded or growing, from the series.
    pub growth: Option<Growth>,
    /// Where it failed or was refused, if it did.
    pub failure: Option<String>,
    /// `failed` (a numerical failure) or `refused` (the method does not run at this step)
    /// when the run has no result: its counts and errors are then not numbers to show.
    pub failed: Option<&'static str>,
    /// The library's error of a failed run.
    pub error: Option<pendula::Error>,
    /// (t, |relative error|) samples.
    pub energy: Vec<(f64, f64)>,
    /// Rows (t, state…) over the whole run, thinned to about [`SAMPLES`]: the phase portrait.
    pub trajectory: Vec<f64>,
    /// Rows over the first [`EARLY`] time units, thinned to about [`SAMPLES`]: the trajectory
    /// figure, where the whole run's thinned samples would be too sparse to draw a curve.
    pub early: Vec<f64>,
    /// (t, |relative error|) of a run stopped early ([`GIVE_UP`]), 2000 to 4000 samples over
    /// its own span up to the step that stopped it: the energy figure's panel.
    pub stopped_energy: Vec<(f64, f64)>,
}

/// The span of the trajectory figure, s (or time units).
const EARLY: f64 = 20.0;

/// Samples kept per series: enough for a smooth curve, few enough for a light SVG.
const SAMPLES: u64 = 2000;

/// A run whose energy error exceeds the energy scale itself is stopped there: beyond it the
/// motion has nothing to do with the system's (explicit Euler within seconds at coarse steps).
const GIVE_UP: f64 = 1.0;

/// The default cost, evaluations per simulated second (RK4 at h = 1/750 s): the least round
/// cost at which every method made for the double pendulum runs, Tao's explicit maps
/// included. tao-4 spends 12 evaluations a step, so its step is 4 ms and its binding constant
/// times its step, w h = 0.8 at the default w = 200 1/s, stays below 1, where the maps are
/// stable; at 700 (its step 17 ms, w h = 3.4) tao-4 and tao-2 (5.7 ms) were refused. At
/// this cost the Gauss–Legendre methods' steps are 1.4–3.6 ms, well below the 16 ms at which
/// gauss-legendre-4 still kept a bounded error on the default chaotic orbit.
pub const DEFAULT_EVALS_PER_SECOND: f64 = 3000.0;

/// The default end time, s: on the double pendulum long enough, at the default cost, for
/// RK4's secular drift to pass the bounded errors of gauss-legendre-4 (at about 140 s) and -6
/// (within seconds), and short enough that every method's run, 6·10⁶ evaluations, takes a few
/// seconds (all eleven about 10 s on 2 cores). The low-order symplectic methods' bounded
/// errors are larger than RK4's at this cost; when RK4 would pass them is printed as an
/// extrapolation from its fitted drift (10⁶ s and more): a run of 100 000 s at 700
/// evaluations per second shows RK4 passing Verlet at about 83 000 s (the report's Figure 7).
pub fn default_t_end(system: &str) -> f64 {
    if system == "double" { 2000.0 } else { 500.0 }
}

/// What compare runs on without a system named (its methods and steps are its own).
pub const DEFAULTS: Defaults = Defaults { system: "double", method: None, dt: None, t_end: None, notes: &[] };

pub fn run(args: &CompareArgs) -> Result<()> {
    let system = args.system.name(&DEFAULTS);
    let values = study::values(system, &args.common.set.items)?;
    let steps = match &args.dt {
        Some(text) => Steps::Equal(positive_arg("--dt", Some(text), 0.0, "a step size in seconds")?),
        None => Steps::EqualCost(positive_arg(
            "--evals-per-second",
            args.evals_per_second.as_deref(),
            DEFAULT_EVALS_PER_SECOND,
            "a number of evaluations per second > 0",
        )?),
    };
    let t_end =
        positive_arg("--t-end", args.t_end.as_deref(), default_t_end(system), "an end time in seconds")?;
    let model = values.build();
    let methods = study::methods(args.methods.as_deref(), &*model, None)?;
    // What it costs: at one step, every method's steps; at equal cost, every method's
    // evaluations, each counted as a step (a step costs at least one).
    let per_method = match steps {
        Steps::Equal(h) => limits::steps(t_end, h),
        Steps::EqualCost(n) => (t_end * n).ceil(),
    };
    let how = match steps {
        Steps::Equal(h) => {
            format!("{} methods x {} steps of {} s", methods.len(), round(per_method), Short(h))
        }
        Steps::EqualCost(n) => {
            format!("{} methods x {} evaluations/s x {} s", methods.len(), Short(n), Short(t_end))
        }
    };
    limits::check(
        "compare",
        args.common.large.allow_large,
        &[Estimate::new(Cost::Steps, methods.len() as f64 * per_method, how)],
    )?;
    match steps {
        Steps::Equal(h) => {
            crate::parse::schedule(&RunSpec { t0: 0.0, h, end: End::Time(t_end) }, "--dt", "--t-end")?;
        }
        Steps::EqualCost(n) if per_method > limits::MAX_STEPS as f64 => anyhow::bail!(
            "invalid --t-end {}: at {} evaluations per second it is more than 10^13 steps",
            Short(t_end),
            Short(n)
        ),
        Steps::EqualCost(_) => {}
    }
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "compare")?;
    let summary = args.common.summary.open()?;

    let bar = study::progress(methods.len() as u64, "compare");
    // The methods' runs are independent: one per core, in the order given.
    let runs = methods
        .par_iter()
        .map(|method| {
            let run = compare_one(&values, method, steps, t_end);
            bar.inc(1);
            run
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish_and_clear();
    // Every method failed and one numerically: the run's failure (exit 1), not a table of
    // failures with empty figures.
    if runs.iter().all(|r| r.failed.is_some()) && runs.iter().any(|r| r.failed == Some("failed")) {
        let first = runs.iter().find(|r| r.failed == Some("failed")).expect("one failed");
        let context = format!("compare: every method failed; the first, {}", first.method);
        return Err(match first.error.clone() {
            Some(e) => anyhow::Error::new(e).context(context),
            None => anyhow::anyhow!("{context}: {}", first.failure.as_deref().unwrap_or("")),
        });
    }

    let header = [
        "method",
        "dt",
        "steps",
        "rhs_evals",
        "cost_evals",
        "wall_s",
        "max_rel_energy_error",
        "max_abs_energy_error",
        "drift_rate",
        "growth",
        "failure",
    ];
    let rows: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            // A failed run's counts are left empty and its growth says `failed`.
            let count = |n: u64| if r.failed.is_some() { String::new() } else { n.to_string() };
            vec![
                r.method.to_owned(),
                num(r.h),
                count(r.steps),
                count(r.rhs_evals),
                count(r.cost),
                num(r.wall_s),
                num(r.max_rel_energy_error),
                num(r.max_abs_energy_error),
                num(r.drift_rate),
                r.failed.unwrap_or_else(|| r.growth.map_or("", Growth::word)).to_owned(),
                r.failure.clone().unwrap_or_default(),
            ]
        })
        .collect();
    out.csv("summary.csv", &header, &rows)?;
    let model_scale = model.energy_scale(values.initial_state());
    let info = values.info();
    let eu = info.energy_unit();
    sayln!(
        summary,
        "{system}: {} over {t_end} {}, {}; relative to the energy scale {} {eu} ({})",
        pendula::analysis::EnergyBalance::new(&*model, values.initial_state()).quantity(),
        info.time_unit(),
        match steps {
            Steps::Equal(h) => format!("every method at h = {h}"),
            Steps::EqualCost(n) => format!("every method at the same cost, {n} evaluations per unit time"),
        },
        short(model_scale),
        info.energy_scale,
    );
    let shown: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            vec![
                r.method.to_owned(),
                short(r.h),
                if r.failed.is_some() { "-".to_owned() } else { r.cost.to_string() },
                format!("{:.3}", r.wall_s),
                short(r.max_rel_energy_error),
                short(r.drift_rate),
                r.failed.unwrap_or_else(|| r.growth.map_or("-", Growth::word)).to_owned(),
                r.failure.clone().unwrap_or_default(),
            ]
        })
        .collect();
    say!(
        summary,
        "{}",
        study::table(
            &["method", "dt", "cost (evals)", "wall s", "max rel. error", "drift 1/s", "error", "note"],
            &shown
        )
    );
    let crossings = crossovers(&runs);
    for c in &crossings {
        sayln!(summary, "{}", c.sentence(info.time_unit()));
    }

    for (name, figure) in figures(&values, &runs, steps, t_end) {
        out.figure(&name, &figure)?;
    }
    let doc = json!({
        "system": system,
        "steps": match steps {
            Steps::Equal(h) => json!({ "mode": "equal step", "dt": h }),
            Steps::EqualCost(n) => json!({ "mode": "equal cost", "evals_per_second": n }),
        },
        "t_end": t_end,
        "energy_scale": model_scale,
        "energy_scale_definition": info.energy_scale,
        "methods": runs.iter().map(|r| (r.method.to_owned(), json!({
            "status": r.failed.unwrap_or("completed"),
            "dt": r.h,
            "steps": r.failed.is_none().then_some(r.steps),
            "rhs_evals": r.failed.is_none().then_some(r.rhs_evals),
            "cost_evals": r.failed.is_none().then_some(r.cost),
            "wall_s": r.wall_s,
            "max_rel_energy_error": r.max_rel_energy_error, "max_abs_energy_error": r.max_abs_energy_error,
            "drift_rate": r.drift_rate, "growth": r.growth.map(Growth::word), "failure": r.failure,
        }))).collect::<serde_json::Map<_, _>>(),
        "crossovers": crossings.iter().map(|c| json!({
            "growing": c.growing, "bounded": c.bounded, "bound": c.bound, "t": c.t,
            "t_extrapolated": c.extrapolated(), "drift_rate": c.drift_rate,
        })).collect::<Vec<_>>(),
    });
    // The summary and the files appear together or not at all.
    out.finish_with(summary, &doc)?;
    Ok(())
}

/// When a growing method's error passes a bounded method's largest error.
pub struct Crossover {
    pub growing: &'static str,
    pub bounded: &'static str,
    /// The bounded method's largest relative error.
    pub bound: f64,
    /// The first envelope window (centre time) where the growing error exceeds it; `None`
    /// when it does not within the run.
    pub t: Option<f64>,
    /// The end of the growing method's run.
    pub t_end: f64,
    /// The growing method's fitted drift rate of the relative error, 1/time.
    pub drift_rate: f64,
}

impl Crossover {
    /// When the growing error would reach the bound at its fitted drift rate, for a
    /// crossover beyond the run: bound / |drift rate| (the error grows about linearly in t).
    pub fn extrapolated(&self) -> Option<f64> {
        (self.t.is_none() && self.drift_rate.is_finite() && self.drift_rate != 0.0)
            .then(|| self.bound / self.drift_rate.abs())
            .filter(|t| *t > self.t_end)
    }

    /// One sentence, checked against the numbers it is made of.
    pub fn sentence(&self, time_unit: &str) -> String {
        let rate_unit = if time_unit.is_empty() { String::new() } else { format!(" 1/{time_unit}") };
        match (self.t, self.extrapolated()) {
            (Some(t), _) => format!(
                "crossover: {}'s growing error passes {}'s bounded error ({}) at t ≈ {} {time_unit}",
                self.growing,
                self.bounded,
                short(self.bound),
                round_time(t)
            ),
            (None, Some(t)) => format!(
                "crossover: {}'s growing error stays below {}'s bounded error ({}) up to t = {} {time_unit}; \
                 at its fitted drift ({}{rate_unit}) it would pass it at t ≈ {} {time_unit} (extrapolated)",
                self.growing,
                self.bounded,
                short(self.bound),
                round_time(self.t_end),
                short(self.drift_rate),
                round_sig(t)
            ),
            (None, None) => format!(
                "crossover: {}'s growing error stays below {}'s bounded error ({}) up to t = {} {time_unit}",
                self.growing,
                self.bounded,
                short(self.bound),
                round_time(self.t_end)
            ),
        }
    }
}

/// An extrapolated time to two significant digits: the drift rate it comes from is a fit.
pub fn round_sig(t: f64) -> String {
    if !(t.is_finite() && t > 0.0) {
        return short(t);
    }
    let unit = 10f64.powi(t.log10().floor() as i32 - 1);
    format!("{:.0}", (t / unit).round() * unit)
}

/// A time read off the envelope's windows, to the second above 10 s: the windows are wider
/// than that, so more digits would claim a precision the estimate does not have.
pub fn round_time(t: f64) -> String {
    if t >= 10.0 { format!("{t:.0}") } else { short(t) }
}

/// Windows of the energy-error envelope in figures and crossovers.
const WINDOWS: usize = 300;

/// For RK4 (the growing method of §7.3), when its error passes each bounded method's.
pub fn crossovers(runs: &[Run]) -> Vec<Crossover> {
    let Some(rk4) = runs.iter().find(|r| r.method == "rk4" && r.growth == Some(Growth::Growing)) else {
        return Vec::new();
    };
    let (t, e): (Vec<f64>, Vec<f64>) = rk4.energy.iter().copied().unzip();
    let env = envelope(&t, &e, WINDOWS);
    runs.iter()
        .filter(|r| r.growth == Some(Growth::Bounded) && r.failure.is_none())
        .map(|r| Crossover {
            growing: rk4.method,
            bounded: r.method,
            bound: r.max_rel_energy_error,
            t: first_exceeding(&env, r.max_rel_energy_error),
            t_end: t.last().copied().unwrap_or(0.0),
            drift_rate: rk4.drift_rate,
        })
        .collect()
}

/// Stops a run once its relative energy error passes [`GIVE_UP`].
struct GiveUp<'a, 'b> {
    series: &'a mut EnergySeries<'b>,
    stopped_at: Option<f64>,
    /// The error over the run's own span, however short, for the panel of a stopped run.
    own: OwnSpan,
}

impl Observer for GiveUp<'_, '_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        let _ = self.series.observe(s);
        self.own.push(s.t, self.series.last.abs());
        if self.series.max_abs > GIVE_UP {
            // The step that stopped it ends the panel's curve, on its stride or not.
            if self.own.points.last().is_none_or(|p| p.0 < s.t) {
                self.own.points.push((s.t, self.series.last.abs()));
            }
            self.stopped_at = Some(s.t);
            return ControlFlow::Break(pendula::observe::Stop::Enough);
        }
        ControlFlow::Continue(())
    }
}

/// Samples of a series that keep between [`SAMPLES`] and twice as many, evenly spaced, over
/// whatever span the run turns out to have: every sample until there are 2 · SAMPLES, then
/// every other one kept and the stride doubled. (The energy series is thinned for the whole
/// planned run, which leaves a run stopped early with a handful of samples.)
#[derive(Default)]
struct OwnSpan {
    stride: u64,
    seen: u64,
    points: Vec<(f64, f64)>,
}

impl OwnSpan {
    fn push(&mut self, t: f64, e: f64) {
        let stride = self.stride.max(1);
        if self.seen.is_multiple_of(stride) {
            if self.points.len() >= 2 * SAMPLES as usize {
                let kept: Vec<(f64, f64)> = self.points.iter().copied().step_by(2).collect();
                self.points = kept;
                self.stride = 2 * stride;
            }
            if self.seen.is_multiple_of(self.stride.max(1)) {
                self.points.push((t, e));
            }
        }
        self.seen += 1;
    }
}

/// The cost of a run: evaluations, a Jacobian counting one per state variable.
fn cost(report: &pendula::simulate::Report, dim: usize) -> u64 {
    report.rhs_evals + report.jacobian_evals * dim as u64
}

/// The step at which `method` spends `per_second` evaluations per simulated second: exact
/// for explicit methods (a fixed number per step); for implicit ones, whose iterations per
/// step depend on the step, refined from pilot runs over the first `pilot` seconds.
pub fn equal_cost_step(values: &Values, method: &Method, per_second: f64, pilot: f64) -> Result<f64> {
    let model = values.build();
    let dim = values.initial_state().len();
    let mut h = 1.0 / per_second;
    for _ in 0..4 {
        let spec = RunSpec { t0: 0.0, h, end: End::Time(pilot.max(h)) };
        let report = model.solve(method, values.initial_state(), &spec, &mut pendula::observe::Ignore)?;
        let per_step = cost(&report, dim) as f64 / report.outcome.steps() as f64;
        let next = per_step / per_second;
        let settled = (next / h - 1.0).abs() < 0.01;
        h = next;
        if settled {
            break;
        }
    }
    Ok(h)
}

/// Runs one method, keeping ~2000 samples of its energy error and trajectory. A run that
/// fails numerically (Euler blowing up, a Newton failure) or is refused at its step (Tao's
/// maps above ω h = 1) is reported with the library's reason, not fatal.
pub fn compare_one(values: &Values, method: &'static Method, steps: Steps, t_end: f64) -> Result<Run> {
    let h = match steps {
        Steps::Equal(h) => Ok(h),
        Steps::EqualCost(n) => equal_cost_step(values, method, n, t_end.min(20.0)),
    };
    let failed = |h: f64, reason: String| Run {
        method: method.name,
        h,
        steps: 0,
        rhs_evals: 0,
        cost: 0,
        wall_s: 0.0,
        max_rel_energy_error: f64::NAN,
        max_abs_energy_error: f64::NAN,
        drift_rate: f64::NAN,
        growth: None,
        failure: Some(reason),
        failed: Some("failed"),
        error: None,
        energy: Vec::new(),
        trajectory: Vec::new(),
        early: Vec::new(),
        stopped_energy: Vec::new(),
    };
    let h = match h {
        Ok(h) => h,
        Err(e) => {
            let status = status(&e);
            let error = e.downcast_ref::<pendula::Error>().cloned();
            return refusal(e).map(|reason| Run {
                failed: Some(status),
                error,
                ..failed(f64::NAN, format!("pilot run: {reason}"))
            });
        }
    };
    let model = values.build();
    let spec = RunSpec { t0: 0.0, h, end: End::Time(t_end) };
    let total = spec.schedule()?.steps;
    let every = (total / SAMPLES).max(1);
    let mut energy = EnergySeries::new(&*model, values.initial_state(), every);
    let mut traj = Every { n: every, inner: Recorder::default() };
    let early_steps = (t_end.min(EARLY) / h).ceil() as u64;
    let mut early = Until {
        t_max: EARLY,
        inner: Every { n: (early_steps / SAMPLES).max(1), inner: Recorder::default() },
    };
    let start = Instant::now();
    let mut guard = GiveUp { series: &mut energy, stopped_at: None, own: OwnSpan::default() };
    let result =
        model.solve(method, values.initial_state(), &spec, &mut (&mut guard, &mut (&mut traj, &mut early)));
    let wall_s = start.elapsed().as_secs_f64();
    let stopped_at = guard.stopped_at;
    let stopped_energy =
        if stopped_at.is_some() { std::mem::take(&mut guard.own.points) } else { Vec::new() };
    let dim = values.initial_state().len();
    let (steps, rhs_evals, cost, failure) = match result {
        Ok(report) => (
            report.outcome.steps(),
            report.rhs_evals,
            cost(&report, dim),
            stopped_at
                .map(|t| format!("stopped at t = {}: the energy error exceeded the energy scale", short(t))),
        ),
        // A failed run has no result: it is reported as failed, with the library's reason
        // and time, and no counts or errors that would read as one.
        Err(e) => {
            let error = Some(e.clone());
            let e = anyhow::Error::new(e);
            let status = status(&e);
            return Ok(Run { wall_s, failed: Some(status), error, ..failed(h, refusal(e)?) });
        }
    };
    let scale = energy.balance.scale;
    Ok(Run {
        method: method.name,
        h,
        steps,
        rhs_evals,
        cost,
        wall_s,
        max_rel_energy_error: energy.max_abs,
        max_abs_energy_error: energy.max_abs * scale,
        drift_rate: drift_rate(&energy.t, &energy.error),
        // A run stopped for its error has grown past everything else, whatever its shape.
        growth: if stopped_at.is_some() { Some(Growth::Growing) } else { growth(&energy.t, &energy.error) },
        failure,
        failed: None,
        error: None,
        energy: energy.t.iter().copied().zip(energy.error.iter().map(|e| e.abs())).collect(),
        trajectory: traj.inner.rows,
        early: early.inner.inner.rows,
        stopped_energy,
    })
}

/// Passes on the samples up to `t_max` and ignores the rest.
struct Until<O> {
    t_max: f64,
    inner: O,
}

impl<O: Observer> Observer for Until<O> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        if s.t <= self.t_max {
            let _ = self.inner.observe(s);
        }
        ControlFlow::Continue(())
    }
}

/// `failed` for a numerical failure, `refused` for a method that does not run there.
fn status(e: &anyhow::Error) -> &'static str {
    match e.downcast_ref::<pendula::Error>() {
        Some(pendula::Error::InvalidValue { .. } | pendula::Error::UnmetRequirement { .. }) => "refused",
        _ => "failed",
    }
}

/// The energy figure's panel for the runs stopped early for their error (Euler within
/// seconds at a coarse step): each over its own span, which on the whole run's time axis is
/// a streak at t ≈ 0. `None` when no run stopped.
pub fn stopped_panel(system: &str, runs: &[Run], steps: Steps, tu: &str, y_label: &str) -> Option<Figure> {
    let stopped: Vec<&Run> = runs.iter().filter(|r| r.stopped_energy.len() > 1).collect();
    let span = stopped.iter().filter_map(|r| r.stopped_energy.last()).map(|p| p.0).fold(0.0, f64::max);
    if stopped.is_empty() || span <= 0.0 {
        return None;
    }
    let names: Vec<&str> = stopped.iter().map(|r| r.method).collect();
    let mut panel = Figure::new(
        format!(
            "{system}: {} over its own run, to t = {}, where its error reached the energy scale",
            names.join(", "),
            with_unit(pendula_viz::number(span), tu)
        ),
        axis_label("t", tu),
        y_label,
    )
    .scales(Scale::Linear, Scale::Log);
    for r in stopped {
        let label = match steps {
            Steps::Equal(_) => format!(
                "{} (stopped at t = {})",
                r.method,
                with_unit(pendula_viz::number(r.stopped_energy.last()?.0), tu)
            ),
            Steps::EqualCost(_) => format!(
                "{} (h = {}, stopped at t = {})",
                r.method,
                with_unit(pendula_viz::number(r.h), tu),
                with_unit(pendula_viz::number(r.stopped_energy.last()?.0), tu)
            ),
        };
        let (t, e): (Vec<f64>, Vec<f64>) = r.stopped_energy.iter().copied().unzip();
        // An envelope over its own span when it has many samples; every sample when few.
        let points = if t.len() > 2 * WINDOWS {
            // The envelope's points sit at its windows' centres: from the first sample to the
            // one that stopped the run, as the curve itself.
            let mut env = envelope(&t, &e, WINDOWS);
            env.insert(0, r.stopped_energy[0]);
            env.push(*r.stopped_energy.last()?);
            env
        } else {
            r.stopped_energy.clone()
        };
        panel = panel.with_style(label, method_style(r.method), Kind::Line, points);
    }
    Some(panel.with(
        "error = energy scale: the run is stopped",
        pendula_viz::GUIDE,
        Kind::Dashed,
        vec![(0.0, GIVE_UP), (span, GIVE_UP)],
    ))
}

/// Energy error envelope, early trajectories, and one phase portrait per method.
pub fn figures(values: &Values, runs: &[Run], steps: Steps, t_end: f64) -> Vec<(String, Figure)> {
    let info = values.info();
    let dim = info.state.len();
    let n = dim / 2;
    let system = info.name;
    let (q, v) = (&info.state[0], &info.state[n]);
    let angle = q.is_angle();
    let tu = info.time_unit();
    let scale = values.build().energy_scale(values.initial_state());
    let how = match steps {
        Steps::Equal(h) => format!("h = {}", with_unit(h, tu)),
        Steps::EqualCost(n) => format!(
            "equal cost, {} evaluations/{}",
            pendula_viz::number(n),
            if tu.is_empty() { "unit time" } else { tu }
        ),
    };
    // |error| crosses zero every oscillation; on a log axis its envelope reads better.
    let mut energy = Figure::new(
        format!("{system}: relative energy error (envelope), {how}"),
        axis_label("t", tu),
        format!(
            "max |E(t) − E(0)| / energy scale ({})",
            with_unit(pendula_viz::number(scale), info.energy_unit())
        ),
    )
    .scales(Scale::Linear, Scale::Log);
    let t_show = t_end.min(EARLY);
    let mut trajectory = Figure::new(
        format!("{system}: {} against time, {how}", pretty(q.name)),
        axis_label("t", tu),
        axis_label(q.name, q.unit),
    );
    let mut figures = Vec::new();
    for r in runs.iter().filter(|r| !r.energy.is_empty()) {
        let style = method_style(r.method);
        let label = match steps {
            Steps::Equal(_) => r.method.to_owned(),
            Steps::EqualCost(_) => format!("{} (h = {})", r.method, with_unit(pendula_viz::number(r.h), tu)),
        };
        let (t, e): (Vec<f64>, Vec<f64>) = r.energy.iter().copied().unzip();
        energy = energy.with_style(label.clone(), style, Kind::Line, envelope(&t, &e, WINDOWS));
        let rows = r.trajectory.chunks(dim + 1);
        trajectory = trajectory.with_style(
            label,
            style,
            Kind::Line,
            r.early.chunks(dim + 1).take_while(|row| row[0] <= t_show).map(|row| (row[0], row[1])).collect(),
        );
        let wrap = |x: f64| if angle { pendula::system::wrap_angle(x) } else { x };
        let q_label = axis_label(q.name, q.unit);
        let phase = Figure::new(
            format!(
                "{system}: phase portrait with {}, h = {}, t ≤ {}",
                r.method,
                with_unit(pendula_viz::number(r.h), tu),
                with_unit(pendula_viz::number(t_end), tu)
            ),
            if angle { format!("{q_label}, wrapped to [−π, π)") } else { q_label },
            axis_label(v.name, v.unit),
        )
        .with(
            r.method,
            style.color,
            Kind::Dots,
            rows.map(|row| (wrap(row[1]), row[1 + n])).collect(),
        );
        figures.push((format!("phase_{}", r.method), phase));
    }
    if let Some(panel) = stopped_panel(system, runs, steps, tu, &energy.y_label) {
        energy = energy.with_panel(panel);
    }
    // Every method may have failed before its first step (all refused): no curves to draw.
    if !energy.series.is_empty() {
        figures.insert(0, ("trajectory".to_owned(), trajectory));
        figures.insert(0, ("energy".to_owned(), energy));
    }
    figures
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Euler at h = 0.05 s on the pendulum is stopped within seconds of a 500 s run: the
    /// energy figure's panel draws it over its own span, from its first sample to the step
    /// that stopped it, with a legend entry; a method that ran to the end is not in it.
    #[test]
    fn the_energy_figure_shows_a_stopped_run_over_its_own_span() {
        let values = crate::study::values("pendulum", &[]).unwrap();
        let steps = Steps::Equal(0.05);
        let runs: Vec<Run> = ["euler", "verlet"]
            .iter()
            .map(|m| compare_one(&values, pendula::integrator::find(m).unwrap(), steps, 500.0).unwrap())
            .collect();
        let (euler, verlet) = (&runs[0], &runs[1]);
        let stop = euler.stopped_energy.last().unwrap().0;
        assert!(stop > 1.0 && stop < 10.0, "stopped at {stop}");
        assert!(euler.failure.as_deref().unwrap().contains("stopped at t = "), "{:?}", euler.failure);
        assert!(verlet.stopped_energy.is_empty() && verlet.failure.is_none());
        // Every step of its short run (64 steps, about 13 of them in the thinned series).
        assert!(euler.stopped_energy.len() as f64 >= stop / 0.05, "{}", euler.stopped_energy.len());

        let figures = figures(&values, &runs, steps, 500.0);
        let energy = &figures.iter().find(|(n, _)| n == "energy").unwrap().1;
        // On the main chart Euler's curve covers under 1% of the 500 s axis: the streak.
        let main = energy.series.iter().find(|s| s.label == "euler").unwrap();
        assert!(main.points.iter().all(|p| p.0 <= stop + 0.05 && p.0 < 0.01 * 500.0));
        let panel = energy.panel.as_ref().expect("a panel for the stopped run");
        assert_eq!(panel.x_label, energy.x_label);
        assert_eq!(panel.y_label, energy.y_label);
        let curve = panel.series.iter().find(|s| s.label.starts_with("euler (stopped at t = ")).unwrap();
        let (x0, x1) =
            curve.points.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
        assert_eq!(x0, euler.stopped_energy[0].0);
        assert_eq!(x1, stop);
        assert!(x0 <= 0.05, "{x0}");
        // Its error grows over the panel to the energy scale, where the run was stopped.
        assert!(curve.points[0].1 < 0.1 && curve.points.last().unwrap().1 > GIVE_UP);
        assert!(panel.series.iter().all(|s| !s.label.starts_with("verlet")));
        // Nothing stopped, no panel.
        let figures = figures_of_verlet(&values, &runs[1..], steps);
        assert!(figures.panel.is_none());
    }

    fn figures_of_verlet(values: &Values, runs: &[Run], steps: Steps) -> Figure {
        figures(values, runs, steps, 500.0).into_iter().find(|(n, _)| n == "energy").unwrap().1
    }
}
