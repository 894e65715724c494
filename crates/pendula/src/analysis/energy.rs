//! The energy error along a run — against the system's energy scale, and as an energy
//! balance when damping or a drive does work — its series, its secular drift rate and its
//! envelope.

use std::ops::ControlFlow;

use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};
use crate::model::DynModel;
use crate::observe::{Flow, Observer, Sample};

/// The error of a run's energy, absolute (J, or the system's units when dimensionless) and
/// relative to the model's energy scale ([`crate::system::Model::energy_scale`]).
///
/// For a free system the error is E(t) − E(0). For a damped or driven one (not conserving
/// energy) it is the energy balance E(t) − E(0) − W(t), where W(t) = ∫₀ᵗ P dt is the work of
/// the non-conservative forces ([`crate::system::Model::power`]): exact solutions keep it at
/// zero, so what remains is the integrator's error. W is integrated step by step with
/// Simpson's rule, the midpoint state taken from the cubic Hermite interpolant of the step
/// (error O(h⁴) per unit time, below the error of every method of order ≤ 4 at the same
/// step, and far below the energy error of any usable run).
pub struct EnergyBalance<'a> {
    model: &'a dyn DynModel,
    /// The scale relative errors are taken against.
    pub scale: f64,
    /// Whether the tracked quantity is the energy balance (damping or drive present).
    pub forced: bool,
    /// Energy of the first state, E(0).
    pub initial: f64,
    /// Energy of the last state seen.
    pub last: f64,
    /// Work of the non-conservative forces up to the last state, W(t).
    pub work: f64,
    /// max |error| over the states seen, absolute.
    pub max_abs: f64,
    started: bool,
    previous: Vec<f64>,
    f_previous: Vec<f64>,
    f: Vec<f64>,
    mid: Vec<f64>,
    t_previous: f64,
    p_previous: f64,
}

impl<'a> EnergyBalance<'a> {
    /// Tracks a run of `model` from `y0`.
    pub fn new(model: &'a dyn DynModel, y0: &[f64]) -> Self {
        let n = y0.len();
        EnergyBalance {
            model,
            scale: model.energy_scale(y0),
            forced: model.conserves_energy().is_err(),
            initial: 0.0,
            last: 0.0,
            work: 0.0,
            max_abs: 0.0,
            started: false,
            previous: vec![0.0; n],
            f_previous: vec![0.0; n],
            f: vec![0.0; n],
            mid: vec![0.0; n],
            t_previous: 0.0,
            p_previous: 0.0,
        }
    }

    /// What the error measures, in words, for labels and summaries.
    pub fn quantity(&self) -> &'static str {
        if self.forced { "energy balance E(t) - E(0) - W(t)" } else { "energy error E(t) - E(0)" }
    }

    /// Adds the state (t, y) (with its energy when the integrator computed it) and returns
    /// its absolute error.
    pub fn track(&mut self, t: f64, y: &[f64], energy: Option<f64>) -> f64 {
        let e = energy.unwrap_or_else(|| self.model.energy(t, y));
        if self.forced {
            self.model.rhs(t, y, &mut self.f);
            let p = self.model.power(t, y);
            if self.started {
                let h = t - self.t_previous;
                // The cubic Hermite interpolant at the step's midpoint.
                for (i, m) in self.mid.iter_mut().enumerate() {
                    *m = 0.5 * (self.previous[i] + y[i]) + 0.125 * h * (self.f_previous[i] - self.f[i]);
                }
                let p_mid = self.model.power(self.t_previous + 0.5 * h, &self.mid);
                self.work += h / 6.0 * (self.p_previous + 4.0 * p_mid + p);
            }
            self.previous.copy_from_slice(y);
            self.f_previous.copy_from_slice(&self.f);
            self.t_previous = t;
            self.p_previous = p;
        }
        if !self.started {
            self.started = true;
            self.initial = e;
        }
        self.last = e;
        let error = e - self.initial - self.work;
        self.max_abs = self.max_abs.max(error.abs());
        error
    }

    /// max |error| / scale.
    pub fn max_rel(&self) -> f64 {
        self.max_abs / self.scale
    }
}

impl Observer for EnergyBalance<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        self.track(s.t, s.y, s.energy);
        ControlFlow::Continue(())
    }
}

/// The running values: E(0), the last energy, the work integral, the largest error, and
/// the previous state, derivative, time and power that the next Simpson step starts from.
impl Snapshot for EnergyBalance<'_> {
    fn save(&self, out: &mut Words) {
        for v in [self.initial, self.last, self.work, self.max_abs, self.t_previous, self.p_previous] {
            out.f64(v);
        }
        out.bool(self.started);
        out.f64s(&self.previous);
        out.f64s(&self.f_previous);
        out.f64s(&self.f);
    }

    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        for v in [
            &mut self.initial,
            &mut self.last,
            &mut self.work,
            &mut self.max_abs,
            &mut self.t_previous,
            &mut self.p_previous,
        ] {
            *v = from.f64()?;
        }
        self.started = from.bool()?;
        from.f64s_into(&mut self.previous)?;
        from.f64s_into(&mut self.f_previous)?;
        from.f64s_into(&mut self.f)
    }
}

/// The relative energy error (energy balance error for forced systems, see
/// [`EnergyBalance`]) sampled along a run, every `every`-th step.
pub struct EnergySeries<'a> {
    /// The tracker; its `scale` divides every error here.
    pub balance: EnergyBalance<'a>,
    every: u64,
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Relative error at each sample: error / scale.
    pub error: Vec<f64>,
    /// max |error| / scale over every step, sampled or not.
    pub max_abs: f64,
    /// The relative error at the latest step, sampled or not.
    pub last: f64,
}

impl<'a> EnergySeries<'a> {
    /// Samples the error of a run of `model` from `y0` every `every` steps (≥ 1) and at the
    /// last step.
    pub fn new(model: &'a dyn DynModel, y0: &[f64], every: u64) -> Self {
        EnergySeries {
            balance: EnergyBalance::new(model, y0),
            every: every.max(1),
            t: Vec::new(),
            error: Vec::new(),
            max_abs: 0.0,
            last: 0.0,
        }
    }
}

impl Observer for EnergySeries<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        let err = self.balance.track(s.t, s.y, s.energy) / self.balance.scale;
        self.max_abs = self.max_abs.max(err.abs());
        self.last = err;
        if s.step.is_multiple_of(self.every) || s.last {
            self.t.push(s.t);
            self.error.push(err);
        }
        ControlFlow::Continue(())
    }
}

/// Secular drift rate of a relative energy error series, 1/s: the least-squares slope of
/// error against time. Bounded oscillating errors give a rate near zero relative to their
/// amplitude divided by the run time; a drift gives its slope.
pub fn drift_rate(t: &[f64], error: &[f64]) -> f64 {
    let n = t.len() as f64;
    if t.len() < 2 {
        return 0.0;
    }
    let (mt, me) = (t.iter().sum::<f64>() / n, error.iter().sum::<f64>() / n);
    let stt: f64 = t.iter().map(|x| (x - mt) * (x - mt)).sum();
    let ste: f64 = t.iter().zip(error).map(|(x, e)| (x - mt) * (e - me)).sum();
    if stt == 0.0 { 0.0 } else { ste / stt }
}

/// The envelope max |error| over `windows` equal windows of the series: (window centre time,
/// max |error| in it).
pub fn envelope(t: &[f64], error: &[f64], windows: usize) -> Vec<(f64, f64)> {
    if t.is_empty() || windows == 0 {
        return Vec::new();
    }
    let (t0, t1) = (t[0], t[t.len() - 1]);
    let width = (t1 - t0) / windows as f64;
    let mut out: Vec<(f64, f64)> = (0..windows).map(|k| (t0 + (k as f64 + 0.5) * width, 0.0)).collect();
    for (ti, e) in t.iter().zip(error) {
        let k = if width > 0.0 { (((ti - t0) / width) as usize).min(windows - 1) } else { 0 };
        out[k].1 = out[k].1.max(e.abs());
    }
    out
}

/// Whether an energy error stays bounded or grows, judged from its series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Growth {
    /// The largest |error| so far stopped growing in at least one of the run's last two
    /// doublings of time: the error oscillates about levels the orbit had already visited
    /// (symplectic methods).
    Bounded,
    /// The largest |error| so far grew by [`GROWTH_FACTOR`] or more over each of the last
    /// two doublings of time, T/4 → T/2 → T: a secular drift (which doubles it each time),
    /// a random walk (√2 each time), or worse.
    Growing,
}

impl Growth {
    /// One word, for tables and sentences.
    pub fn word(self) -> &'static str {
        match self {
            Growth::Bounded => "bounded",
            Growth::Growing => "growing",
        }
    }
}

/// How much the largest error so far must grow over each of two doublings of time for
/// [`growth`] to call it growing: below a random walk's √2 and a drift's 2, above the 1 of a
/// bounded error.
pub const GROWTH_FACTOR: f64 = 1.3;

/// Judges a series of |error| (any scale) sampled at times `t` (see [`Growth`]); `None`
/// with fewer than ten samples or an error that is zero throughout the first quarter.
///
/// Why the largest error so far, at T/4, T/2 and T: on a chaotic orbit even a symplectic
/// method's error, h^p times a function of the state, rises and falls as the orbit wanders
/// into faster or slower regions, so the error of one stretch of the run against another's
/// says more about the orbit than about the method. A secular drift keeps raising the
/// largest error at every doubling of time; a bounded error stops raising it once the orbit
/// has been explored, and a new record late in the run (one doubling) is not enough to call
/// it growing.
pub fn growth(t: &[f64], error: &[f64]) -> Option<Growth> {
    if t.len() < 10 || t.len() != error.len() {
        return None;
    }
    let (t0, t1) = (t[0], t[t.len() - 1]);
    let largest_until = |fraction: f64| {
        let end = t0 + fraction * (t1 - t0);
        t.iter().zip(error).filter(|(ti, _)| **ti <= end).map(|(_, e)| e.abs()).fold(0.0, f64::max)
    };
    let (quarter, half, whole) = (largest_until(0.25), largest_until(0.5), largest_until(1.0));
    if quarter.is_nan() || quarter <= 0.0 {
        return None;
    }
    let grows = half >= GROWTH_FACTOR * quarter && whole >= GROWTH_FACTOR * half;
    Some(if grows { Growth::Growing } else { Growth::Bounded })
}

/// The first time at which an envelope (window centre, max |error|) exceeds `level`.
pub fn first_exceeding(envelope: &[(f64, f64)], level: f64) -> Option<f64> {
    envelope.iter().find(|(_, e)| *e > level).map(|(t, _)| *t)
}
