//! Periods from zero crossings of a state variable, located by cubic Hermite interpolation
//! between steps (error O(h⁴), with the derivative from the right-hand side).

use std::ops::ControlFlow;

use crate::integrator::Method;
use crate::system::DynModel;
use crate::{End, Error, RunSpec};

use crate::observe::{Observer, Sample};

/// Which zero crossings count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// From negative to non-negative.
    Rising,
    /// From positive to non-positive.
    Falling,
    /// Either.
    Both,
}

/// Records the times at which component `index` of the state crosses zero.
pub struct ZeroCrossings<'a> {
    model: &'a dyn DynModel,
    index: usize,
    direction: Direction,
    previous: Option<(f64, f64, f64)>,
    scratch: Vec<f64>,
    /// Crossing times, s.
    pub times: Vec<f64>,
    /// Stop after this many crossings.
    pub limit: usize,
}

impl<'a> ZeroCrossings<'a> {
    /// Watches component `index` of `model`'s state; stops the run after `limit` crossings.
    pub fn new(model: &'a dyn DynModel, index: usize, direction: Direction, limit: usize) -> Self {
        ZeroCrossings {
            model,
            index,
            direction,
            previous: None,
            scratch: vec![0.0; model.info().state.len()],
            times: Vec::new(),
            limit,
        }
    }
}

impl Observer for ZeroCrossings<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> ControlFlow<()> {
        self.model.rhs(s.t, s.y, &mut self.scratch);
        let (x1, d1) = (s.y[self.index], self.scratch[self.index]);
        if let Some((t0, x0, d0)) = self.previous {
            let (up, down) = (x0 < 0.0 && x1 >= 0.0, x0 > 0.0 && x1 <= 0.0);
            let crossed = match self.direction {
                Direction::Rising => up,
                Direction::Falling => down,
                Direction::Both => up || down,
            };
            if crossed {
                self.times.push(hermite_root(t0, x0, d0, s.t, x1, d1));
                if self.times.len() >= self.limit {
                    return ControlFlow::Break(());
                }
            }
        }
        self.previous = Some((s.t, x1, d1));
        ControlFlow::Continue(())
    }
}

/// The root in [t0, t1] of the cubic Hermite interpolant of (x0, d0) and (x1, d1), with
/// x0 and x1 of opposite signs, by bisection safeguarded Newton.
fn hermite_root(t0: f64, x0: f64, d0: f64, t1: f64, x1: f64, d1: f64) -> f64 {
    let h = t1 - t0;
    let p = |s: f64| {
        let (h00, h10, h01, h11) = (
            2.0 * s.powi(3) - 3.0 * s * s + 1.0,
            s.powi(3) - 2.0 * s * s + s,
            -2.0 * s.powi(3) + 3.0 * s * s,
            s.powi(3) - s * s,
        );
        h00 * x0 + h10 * h * d0 + h01 * x1 + h11 * h * d1
    };
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    let sign_lo = x0.signum();
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if p(mid).signum() == sign_lo {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-16 {
            break;
        }
    }
    t0 + 0.5 * (lo + hi) * h
}

/// The period of an oscillation from `y0`: the time from the first to the third zero
/// crossing of state component `index` (one full oscillation), integrated with `method` at
/// step `h` up to `t_max`. `None` if fewer than three crossings happen by then.
pub fn measure_period(
    model: &dyn DynModel,
    method: &Method,
    y0: &[f64],
    index: usize,
    h: f64,
    t_max: f64,
) -> Result<Option<f64>, Error> {
    let mut crossings = ZeroCrossings::new(model, index, Direction::Both, 3);
    let spec = RunSpec { t0: 0.0, h, end: End::Time(t_max) };
    model.solve(method, y0, &spec, &mut crossings)?;
    Ok(match crossings.times.as_slice() {
        [a, _, b] => Some(b - a),
        _ => None,
    })
}
