//! Several methods on one problem at equal cost or equal step (paper §7.3, §8.3, Figures 6
//! and 7): each method's energy error, its growth (bounded or drifting), its trajectory and
//! its cost, and when a growing error passes a bounded one (the crossovers). `pendula
//! compare` and the report present it; the numbers are made here.
//!
//! By default every method gets the same cost — the same number of right-hand-side
//! evaluations per simulated second — and its step is chosen to spend it, so that the
//! comparison is fair: the lesson of §8 (symplectic methods keep the energy error bounded,
//! RK4's drifts) is a statement about long runs at equal work.

use std::ops::ControlFlow;
use std::time::Instant;

use crate::analysis::{EnergySeries, Growth, drift_rate, envelope, first_exceeding, growth};
use crate::error::short;
use crate::integrator::Method;
use crate::observe::{Every, Flow, Observer, Recorder, Sample};
use crate::system::Values;
use crate::{End, Error, RunSpec};

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
    /// The method's name.
    pub method: &'static str,
    /// Its step, s.
    pub h: f64,
    /// Steps taken.
    pub steps: u64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Evaluations counting each Jacobian as one per state variable: the cost compared.
    pub cost: u64,
    /// Wall time of the run, s.
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
    pub error: Option<Error>,
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
pub const EARLY: f64 = 20.0;

/// Samples kept per series: enough for a smooth curve, few enough for a light SVG.
pub const SAMPLES: u64 = 2000;

/// A run whose energy error exceeds the energy scale itself is stopped there: beyond it the
/// motion has nothing to do with the system's (explicit Euler within seconds at coarse steps).
pub const GIVE_UP: f64 = 1.0;

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
    T_END_BY_SYSTEM.iter().find(|(s, _)| *s == system).map_or(T_END_OTHERWISE, |(_, t)| *t)
}

/// The end times of [`default_t_end`] by system, s.
pub const T_END_BY_SYSTEM: &[(&str, f64)] = &[("double", 2000.0)];

/// The end time of [`default_t_end`] for the other systems, s.
pub const T_END_OTHERWISE: f64 = 500.0;

/// When a growing method's error passes a bounded method's largest error.
pub struct Crossover {
    /// The method whose error grows (rk4).
    pub growing: &'static str,
    /// The method whose error stays bounded.
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
pub const WINDOWS: usize = 300;

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
            return ControlFlow::Break(crate::observe::Stop::Enough);
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
fn cost(report: &crate::simulate::Report, dim: usize) -> u64 {
    report.rhs_evals + report.jacobian_evals * dim as u64
}

/// The step at which `method` spends `per_second` evaluations per simulated second: exact
/// for explicit methods (a fixed number per step); for implicit ones, whose iterations per
/// step depend on the step, refined from pilot runs over the first `pilot` seconds.
///
/// # Errors
/// The pilot run's.
pub fn equal_cost_step(values: &Values, method: &Method, per_second: f64, pilot: f64) -> Result<f64, Error> {
    let model = values.build();
    let dim = values.initial_state().len();
    let mut h = 1.0 / per_second;
    for _ in 0..4 {
        let spec = RunSpec { t0: 0.0, h, end: End::Time(pilot.max(h)) };
        let report = model.solve(method, values.initial_state(), &spec, &mut crate::observe::Ignore)?;
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
///
/// # Errors
/// A step that does not fit the end time ([`RunSpec::schedule`]), or a failure that is not
/// one of the run's own ([`Error::is_per_run`]).
pub fn compare_one(values: &Values, method: &'static Method, steps: Steps, t_end: f64) -> Result<Run, Error> {
    let h = match steps {
        Steps::Equal(h) => Ok(h),
        Steps::EqualCost(n) => equal_cost_step(values, method, n, t_end.min(20.0)),
    };
    let failed = |h: f64, reason: String, error: Option<Error>| Run {
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
        error,
        energy: Vec::new(),
        trajectory: Vec::new(),
        early: Vec::new(),
        stopped_energy: Vec::new(),
    };
    let h = match h {
        Ok(h) => h,
        Err(e) if e.is_per_run() => {
            return Ok(Run {
                failed: Some(status(&e)),
                ..failed(f64::NAN, format!("pilot run: {e}"), Some(e))
            });
        }
        Err(e) => return Err(e),
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
        Err(e) if e.is_per_run() => {
            return Ok(Run { wall_s, failed: Some(status(&e)), ..failed(h, e.to_string(), Some(e)) });
        }
        Err(e) => return Err(e),
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
fn status(e: &Error) -> &'static str {
    match e {
        Error::InvalidValue { .. } | Error::UnmetRequirement { .. } => "refused",
        _ => "failed",
    }
}
