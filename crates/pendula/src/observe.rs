//! Observers: who watches a run. The run loop shows each step to an [`Observer`], which may
//! end the run by returning [`ControlFlow::Break`] with a [`Stop`]: [`Stop::Enough`] (the run
//! ends as stopped) or [`Stop::Failed`] (the observer could not take the state, a write that
//! failed: the run ends with [`Error::Observer`], the failure as its source). Recording,
//! thinning, energy tracking and early stopping are observers, composed with tuples.

use std::ops::ControlFlow;

use crate::Error;
use crate::error::ObserverFailure;

use crate::checkpoint::{Pause, Reader, Snapshot, Words};

/// One state of a run, as an observer sees it.
#[derive(Debug, Clone, Copy)]
pub struct Sample<'a> {
    /// Steps taken so far (0 for the initial state).
    pub step: u64,
    /// Time, s.
    pub t: f64,
    /// State in the system's coordinates.
    pub y: &'a [f64],
    /// Whether this is the last step of the run.
    pub last: bool,
    /// The continuous solution over the step that ended here, when the method provides one
    /// and an observer asked for it ([`Observer::wants_dense`]); in the same coordinates as
    /// `y`.
    pub dense: Option<DenseStep<'a>>,
    /// The system's energy at this state, J, when the integrator computed it on the way
    /// (the double pendulum's fast RK4 path); observers that track energy use it.
    pub energy: Option<f64>,
}

impl<'a> Sample<'a> {
    /// A sample without dense output.
    pub fn new(step: u64, t: f64, y: &'a [f64], last: bool) -> Self {
        Sample { step, t, y, last, dense: None, energy: None }
    }
}

/// The dense output of one step from t₀ to t₀ + h: the polynomial
/// y(t₀ + θh) = r₀ + θ(r₁ + (1−θ)(r₂ + θ(r₃ + (1−θ)(r₄ + …)))) of Hairer's DOPRI5 and DOP853
/// codes, whose coefficients rᵢ (one row of the state's length each) the method computed.
///
/// # References
/// E. Hairer, S. P. Nørsett, G. Wanner, *Solving ODEs I*, §II.6.
#[derive(Debug, Clone, Copy)]
pub struct DenseStep<'a> {
    /// Start of the step, s.
    pub t0: f64,
    /// Size of the step, s.
    pub h: f64,
    coefficients: &'a [f64],
}

impl<'a> DenseStep<'a> {
    /// The step from t₀ of size h with coefficients r₀, r₁, … stored one after the other.
    pub fn new(t0: f64, h: f64, coefficients: &'a [f64]) -> Self {
        DenseStep { t0, h, coefficients }
    }

    /// The coefficients r₀, r₁, … one row of the state's length after the other (a
    /// caller that keeps the continuous solution past the step, such as Python's `sol`).
    pub fn coefficients(&self) -> &'a [f64] {
        self.coefficients
    }

    /// The state at time t (within the step for the method's accuracy), into `out`.
    pub fn at(&self, t: f64, out: &mut [f64]) {
        let n = out.len();
        let terms = self.coefficients.len() / n;
        let theta = (t - self.t0) / self.h;
        let factor = [theta, 1.0 - theta];
        for (j, o) in out.iter_mut().enumerate() {
            // Horner from the innermost term: after rᵢ comes θ for even i, 1 − θ for odd i.
            let mut acc = self.coefficients[(terms - 1) * n + j];
            for i in (0..terms - 1).rev() {
                acc = self.coefficients[i * n + j] + factor[i % 2] * acc;
            }
            *o = acc;
        }
    }
}

/// Why an observer ends a run before its end.
#[derive(Debug)]
pub enum Stop {
    /// It has seen what it needed: the run ends as [`crate::Outcome::Stopped`].
    Enough,
    /// It could not take the state (its output failed): the run ends with
    /// [`Error::Observer`], which carries this failure.
    Failed(ObserverFailure),
}

impl Stop {
    /// A failure of the observer from any error (an I/O error, an `anyhow::Error`).
    pub fn failed(err: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Stop {
        Stop::Failed(ObserverFailure::new(err))
    }

    /// `Ok` when the observer had enough, the run's error when it failed.
    ///
    /// # Errors
    /// [`Error::Observer`] for [`Stop::Failed`].
    pub fn into_result(self) -> Result<(), Error> {
        match self {
            Stop::Enough => Ok(()),
            Stop::Failed(failure) => Err(Error::Observer(failure)),
        }
    }
}

/// What an observer says after seeing a state: go on, or [`Stop`] and why.
pub type Flow = ControlFlow<Stop>;

/// Watches a run step by step.
pub trait Observer {
    /// Sees one state; `Break` ends the run early: as [`crate::Outcome::Stopped`] with
    /// [`Stop::Enough`], as the error [`Error::Observer`] with [`Stop::Failed`].
    fn observe(&mut self, sample: &Sample<'_>) -> Flow;

    /// Whether this observer uses [`Sample::dense`]; methods that must spend evaluations on
    /// dense output (DOP853) do so only then.
    fn wants_dense(&self) -> bool {
        false
    }
}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        (**self).observe(sample)
    }
    fn wants_dense(&self) -> bool {
        (**self).wants_dense()
    }
}

impl<A: Observer, B: Observer> Observer for (A, B) {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        let a = self.0.observe(sample);
        let b = self.1.observe(sample);
        // A failure outranks having seen enough; the first observer's, if both failed.
        match (a, b) {
            (ControlFlow::Continue(()), ControlFlow::Continue(())) => ControlFlow::Continue(()),
            (ControlFlow::Break(Stop::Failed(f)), _) | (_, ControlFlow::Break(Stop::Failed(f))) => {
                ControlFlow::Break(Stop::Failed(f))
            }
            _ => ControlFlow::Break(Stop::Enough),
        }
    }
    fn wants_dense(&self) -> bool {
        self.0.wants_dense() || self.1.wants_dense()
    }
}

/// Ignores everything.
#[derive(Debug, Clone, Copy, Default)]
pub struct Ignore;

impl Observer for Ignore {
    fn observe(&mut self, _: &Sample<'_>) -> Flow {
        ControlFlow::Continue(())
    }
}

/// An observer from a closure.
#[derive(Debug, Clone, Copy)]
pub struct FromFn<F>(pub F);

impl<F: FnMut(&Sample<'_>) -> Flow> Observer for FromFn<F> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        (self.0)(sample)
    }
}

/// Passes on the initial state, every `n`-th step, and the last step.
#[derive(Debug, Clone)]
pub struct Every<O> {
    /// Keep steps 0, n, 2n, …; n ≥ 1.
    pub n: u64,
    /// Who sees the kept steps.
    pub inner: O,
}

impl<O: Observer> Observer for Every<O> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        if self.n == 1 {
            self.inner.observe(sample)
        } else if sample.step.is_multiple_of(self.n) || sample.last {
            // The dense output covers only the last step, not all since the last kept one.
            self.inner.observe(&Sample { dense: None, ..*sample })
        } else {
            ControlFlow::Continue(())
        }
    }
    fn wants_dense(&self) -> bool {
        self.n == 1 && self.inner.wants_dense()
    }
}

/// Records (t, y) rows into one flat vector.
#[derive(Debug, Clone, Default)]
pub struct Recorder {
    /// Rows of 1 + dim values each: t, then the state.
    pub rows: Vec<f64>,
}

impl Observer for Recorder {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        self.rows.push(sample.t);
        self.rows.extend_from_slice(sample.y);
        ControlFlow::Continue(())
    }
}

/// Energy statistics of a run, J.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EnergyStats {
    /// Energy of the first state seen.
    pub initial: f64,
    /// Energy of the last state seen.
    pub last: f64,
    /// max |E(t) − E(0)| over the states seen.
    pub max_abs_error: f64,
}

impl EnergyStats {
    /// `max_abs_error / scale`: relative to an energy scale, such as the system's
    /// ([`crate::system::Model::energy_scale`]), never to |E(0)|, which may vanish.
    pub fn max_rel_error(&self, scale: f64) -> f64 {
        self.max_abs_error / scale
    }
}

/// Tracks the error of an energy function along a run.
#[derive(Debug, Clone)]
pub struct EnergyTracker<F> {
    energy: F,
    stats: Option<EnergyStats>,
}

impl<F: FnMut(f64, &[f64]) -> f64> EnergyTracker<F> {
    /// Tracks `energy(t, y)`.
    pub fn new(energy: F) -> Self {
        EnergyTracker { energy, stats: None }
    }

    /// Evaluates the energy at (t, y), adds it to the statistics, and returns it.
    pub fn track(&mut self, t: f64, y: &[f64]) -> f64 {
        let e = (self.energy)(t, y);
        self.record(e);
        e
    }

    /// Adds an energy computed elsewhere to the statistics.
    pub fn record(&mut self, e: f64) {
        let stats = self.stats.get_or_insert(EnergyStats { initial: e, last: e, max_abs_error: 0.0 });
        stats.last = e;
        stats.max_abs_error = stats.max_abs_error.max((e - stats.initial).abs());
    }

    /// Statistics so far (all zero before the first state).
    pub fn stats(&self) -> EnergyStats {
        self.stats.unwrap_or_default()
    }
}

impl<F: FnMut(f64, &[f64]) -> f64> Observer for EnergyTracker<F> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        match sample.energy {
            Some(e) => self.record(e),
            None => {
                self.track(sample.t, sample.y);
            }
        }
        ControlFlow::Continue(())
    }
}

/// Stops the run at the first state for which the predicate holds.
#[derive(Debug, Clone)]
pub struct StopWhen<F>(pub F);

impl<F: FnMut(&Sample<'_>) -> bool> Observer for StopWhen<F> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        if (self.0)(sample) { ControlFlow::Break(Stop::Enough) } else { ControlFlow::Continue(()) }
    }
}

/// The times a [`Resample`] passes on.
#[derive(Debug, Clone, PartialEq)]
pub enum Grid {
    /// t₀, t₀ + h, t₀ + 2h, … from the run's first time t₀ (h > 0, s).
    Spacing(f64),
    /// These times, increasing, s.
    Times(Vec<f64>),
}

/// Passes on the states at the times of a [`Grid`] instead of at the ends of the steps,
/// from each step's dense output ([`Sample::dense`]), and the run's last state (its end, or
/// the event that stopped it) as the last. For `Grid::Spacing` the first state is passed on
/// as t₀; grid times within 1e-12 (relative) of the last state's time merge with it.
///
/// Only steps with dense output (the adaptive pairs' `dopri5` and `dop853`) have states
/// between their ends: in a step without it, grid times are skipped.
#[derive(Debug, Clone)]
pub struct Resample<O> {
    grid: Grid,
    /// Index of the next grid time to pass on.
    next: u64,
    /// The run's first time, once seen.
    origin: Option<f64>,
    y: Vec<f64>,
    /// Who sees the grid's states.
    pub inner: O,
}

impl<O> Resample<O> {
    /// Resamples a run of a system of `dim` state variables onto `grid`.
    pub fn new(grid: Grid, dim: usize, inner: O) -> Self {
        Resample { grid, next: 0, origin: None, y: vec![0.0; dim], inner }
    }

    /// Grid time k, if there is one.
    fn time(&self, k: u64) -> Option<f64> {
        match &self.grid {
            // k h, not a running sum: no drift over many points.
            Grid::Spacing(h) => Some(self.origin.unwrap_or(0.0) + k as f64 * h),
            Grid::Times(times) => usize::try_from(k).ok().and_then(|k| times.get(k).copied()),
        }
    }
}

impl<O: Observer> Observer for Resample<O> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        let t = sample.t;
        let merge = 1e-12 * t.abs().max(1.0);
        let Some(_) = self.origin else {
            self.origin = Some(t);
            // Times before the start are not in the run.
            while self.time(self.next).is_some_and(|tk| tk < t - merge) {
                self.next += 1;
            }
            if sample.last || self.time(self.next).is_some_and(|tk| tk <= t + merge) {
                self.next += 1;
                return self.inner.observe(&Sample { dense: None, ..*sample });
            }
            return ControlFlow::Continue(());
        };
        // Grid times inside the step; at the run's last state, not those that merge with it.
        let bound = if sample.last { t - merge } else { t };
        while let Some(tk) = self.time(self.next).filter(|tk| *tk <= bound) {
            self.next += 1;
            let Some(dense) = &sample.dense else { continue };
            dense.at(tk, &mut self.y);
            let at = Sample { t: tk, y: &self.y, last: false, dense: None, energy: None, ..*sample };
            self.inner.observe(&at)?;
        }
        if sample.last {
            while self.time(self.next).is_some_and(|tk| tk <= t + merge) {
                self.next += 1;
            }
            return self.inner.observe(&Sample { dense: None, ..*sample });
        }
        ControlFlow::Continue(())
    }

    fn wants_dense(&self) -> bool {
        true
    }
}

/// The index of the next grid time and the run's first time (the observer inside saves its
/// own state).
impl<O> Snapshot for Resample<O> {
    fn save(&self, out: &mut Words) {
        out.u64(self.next);
        out.opt_f64(self.origin);
    }

    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        self.next = from.u64()?;
        self.origin = from.opt_f64()?;
        Ok(())
    }
}

/// An observer that shows every sample to `inner` and then, after a sample that did not end
/// the run and is neither its first (the initial state) nor its last, asks a [`crate::checkpoint::Pause`]
/// whether to pause there: if so it ends the run and says so (`paused`). Loops that can pause run with it around their observer, and
/// without it (the same loop) when they never pause.
pub(crate) struct Pausing<'a, 'p, O: ?Sized> {
    inner: &'a mut O,
    pause: &'a Pause<'p>,
    /// Whether the run was ended here to pause.
    pub(crate) paused: bool,
}

impl<'a, 'p, O: ?Sized> Pausing<'a, 'p, O> {
    pub(crate) fn new(inner: &'a mut O, pause: &'a Pause<'p>) -> Self {
        Pausing { inner, pause, paused: false }
    }

    /// The observer inside, for a loop that never pauses.
    pub(crate) fn inner(&mut self) -> &mut O {
        self.inner
    }
}

impl<O: Observer + ?Sized> Observer for Pausing<'_, '_, O> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        self.inner.observe(sample)?;
        // Not at the initial state: a run resumed from step 0 would show it again.
        if sample.step > 0 && !sample.last && self.pause.due(sample.t) {
            self.paused = true;
            return ControlFlow::Break(Stop::Enough);
        }
        ControlFlow::Continue(())
    }
    fn wants_dense(&self) -> bool {
        self.inner.wants_dense()
    }
}
