//! The energy error along a run: its series, its secular drift rate and its envelope.

use std::ops::ControlFlow;

use crate::observe::{Observer, Sample};

/// The relative energy error (E − E₀)/|E₀|, or the absolute error E − E₀ (J) when E₀ = 0.
pub fn relative_error(e: f64, e0: f64) -> f64 {
    if e0 == 0.0 { e - e0 } else { (e - e0) / e0.abs() }
}

/// Relative energy error (E − E₀)/|E₀| sampled along a run, every `every`-th step.
#[derive(Debug, Clone)]
pub struct EnergySeries<F> {
    energy: F,
    every: u64,
    e0: Option<f64>,
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Relative energy error at each sample (absolute error, J, when E₀ = 0).
    pub error: Vec<f64>,
    /// max |error| over every step, sampled or not.
    pub max_abs: f64,
}

impl<F: FnMut(f64, &[f64]) -> f64> EnergySeries<F> {
    /// Samples `energy(t, y)` every `every` steps (≥ 1) and at the last step.
    pub fn new(energy: F, every: u64) -> Self {
        EnergySeries { energy, every: every.max(1), e0: None, t: Vec::new(), error: Vec::new(), max_abs: 0.0 }
    }
}

impl<F: FnMut(f64, &[f64]) -> f64> Observer for EnergySeries<F> {
    fn observe(&mut self, s: &Sample<'_>) -> ControlFlow<()> {
        let e = (self.energy)(s.t, s.y);
        let e0 = *self.e0.get_or_insert(e);
        let err = relative_error(e, e0);
        self.max_abs = self.max_abs.max(err.abs());
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
