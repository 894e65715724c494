//! Periods from zero crossings of a state variable, located by [`crate::events`] on the
//! cubic Hermite interpolant between steps (error O(h⁴)).

use crate::events::{Direction, EventKind, EventLocator, EventSpec};
use crate::integrator::Method;
use crate::model::DynModel;
use crate::{End, Error, RunSpec};

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
    let zero = EventSpec {
        name: "zero".into(),
        kind: EventKind::Zero { index },
        direction: Direction::Both,
        terminal: false,
    };
    let mut events = EventLocator::new(model, vec![zero]);
    let spec = RunSpec { t0: 0.0, h, end: End::Time(t_max) };
    model.solve(method, y0, &spec, &mut events)?;
    Ok(match events.found.as_slice() {
        [a, _, b, ..] => Some(b.t - a.t),
        _ => None,
    })
}
