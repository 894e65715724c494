//! Divergence of nearby trajectories: the distance between a run and a copy started `delta`
//! away in one state variable, against time, and the exponential rate fitted to its growth
//! (a finite-time estimate of the largest Lyapunov exponent, without renormalisation).

use crate::integrator::Method;
use crate::model::DynModel;
use crate::observe::{Every, Recorder};
use crate::{Error, RunSpec};

/// The distance between two runs, sampled.
#[derive(Debug, Clone, PartialEq)]
pub struct Divergence {
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Euclidean distance of the two states at those times (state units mixed: rad and rad/s
    /// for the pendulums).
    pub distance: Vec<f64>,
}

/// Whether a separation `delta` survives being added to a state variable at `start`: at a
/// large value the floats are further apart than it, and the two runs would start (nearly)
/// at the same state. It survives when (start + δ) − start is δ to 1e-3.
pub fn survives_rounding(start: f64, delta: f64) -> bool {
    (((start + delta) - start) - delta).abs() <= 1e-3 * delta.abs()
}

/// About how many samples of a run [`sample_every`] keeps.
pub const SAMPLES: u64 = 2000;

/// The thinning that keeps about [`SAMPLES`] samples of a run of `steps` steps, whatever
/// the step: every (steps / 2000)-th step, at least every step.
pub fn sample_every(steps: u64) -> u64 {
    (steps / SAMPLES).max(1)
}

/// Runs `model` from `y0` and from `y0` with `delta` added to state variable `index`, with the
/// same method and steps, keeping every `every`-th step.
///
/// # Errors
/// Those of the runs.
pub fn divergence(
    model: &dyn DynModel,
    method: &Method,
    y0: &[f64],
    index: usize,
    delta: f64,
    spec: &RunSpec,
    every: u64,
) -> Result<Divergence, Error> {
    let n = y0.len();
    let mut y1 = y0.to_vec();
    y1[index] += delta;
    let run = |y: &[f64]| -> Result<Vec<f64>, Error> {
        let mut rec = Every { n: every.max(1), inner: Recorder::default() };
        model.solve(method, y, spec, &mut rec)?;
        Ok(rec.inner.rows)
    };
    let (a, b) = (run(y0)?, run(&y1)?);
    let (mut t, mut distance) = (Vec::new(), Vec::new());
    for (ra, rb) in a.chunks_exact(n + 1).zip(b.chunks_exact(n + 1)) {
        t.push(ra[0]);
        distance.push(state_distance(&ra[1..], &rb[1..]));
    }
    Ok(Divergence { t, distance })
}

/// The Euclidean distance of two states, as [`Divergence::distance`] measures it (state
/// units mixed: rad and rad/s for the pendulums).
pub fn state_distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

/// A fitted exponential rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrowthFit {
    /// The slope of ln(distance) against t, 1/s.
    pub rate: f64,
    /// The fit's time window, s.
    pub t_start: f64,
    /// End of the window, s.
    pub t_end: f64,
    /// The fitted line's ln(distance) at t = 0 (ln of the distance's unit): the line is
    /// ln d = `intercept` + `rate`·t, which a plot draws over the window.
    pub intercept: f64,
}

/// Least-squares slope of ln(distance) against t over the samples before the distance first
/// exceeds `saturation` (where the separation stops growing exponentially); `None` with fewer
/// than three usable samples.
pub fn growth_rate(d: &Divergence, saturation: f64) -> Option<GrowthFit> {
    growth_rate_between(d, 0.0, saturation)
}

/// [`growth_rate`] over the samples above `from` only (and before the distance first exceeds
/// `saturation`): a window that leaves out the start, where the separation has not yet
/// turned along the most unstable direction and grows at other rates (the lab's butterfly
/// mode fits from 100 times its offset to 0.1).
pub fn growth_rate_between(d: &Divergence, from: f64, saturation: f64) -> Option<GrowthFit> {
    let end = d.distance.iter().position(|&x| x > saturation).unwrap_or(d.distance.len());
    let (ts, ls): (Vec<f64>, Vec<f64>) = d.t[..end]
        .iter()
        .zip(&d.distance[..end])
        .filter(|(_, x)| **x > from.max(0.0))
        .map(|(t, x)| (*t, x.ln()))
        .unzip();
    if ts.len() < 3 {
        return None;
    }
    let n = ts.len() as f64;
    let (mt, ml) = (ts.iter().sum::<f64>() / n, ls.iter().sum::<f64>() / n);
    let stt: f64 = ts.iter().map(|t| (t - mt) * (t - mt)).sum();
    let stl: f64 = ts.iter().zip(&ls).map(|(t, l)| (t - mt) * (l - ml)).sum();
    let rate = stl / stt;
    Some(GrowthFit { rate, t_start: ts[0], t_end: ts[ts.len() - 1], intercept: ml - rate * mt })
}
