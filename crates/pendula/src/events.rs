//! Event location: times where a function g(t, y) of the state crosses zero, found between
//! steps by bisection to ~1e-13 relative in t on the step's interpolant: the method's own
//! dense output when it has one (dopri5: order 4, dop853: order 7, on adaptive runs), else
//! the cubic Hermite interpolant of the step (the state and its derivative at both ends).
//!
//! The Hermite interpolant's error is O(h⁴): with RK4 at h = 1 ms an event time is good to
//! about 1e-12 s. With adaptive steps the dense output keeps the error near the tolerance.
//!
//! # References
//! E. Hairer, S. P. Nørsett, G. Wanner, *Solving ODEs I*, §II.6 (dense output) and §II.6.4
//! (event location).
//!
//! # In a run
//!
//! Event location (`flip`, `zero:NAME`, `section:NAME=VALUE`, periodic in 2π on angles) is an
//! observer, `crates/pendula/src/events.rs`: it brackets sign changes between steps and bisects on
//! the step's interpolant — the method's dense output (`Sample::dense`, a `DenseStep` from
//! `crates/pendula/src/observe.rs`) on adaptive runs, else the cubic Hermite interpolant. Observers
//! say whether they need dense output (`Observer::wants_dense`), so DOP853 spends its 3 extra
//! evaluations per step only then. `EndAtEvent` (same file) wraps the locator and another observer,
//! which at a terminal event sees the event's time and state as the run's last sample, so `simulate
//! --stop-on-event` ends at the event. `observe::Resample` passes on states on a time grid
//! (`--output-dt`, `--t-eval`) from the steps' dense output.

use std::ops::ControlFlow;

use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};
use crate::observe::{DenseStep, Flow, Observer, Sample, Stop};
use crate::system::DynSystem;

/// Which crossings of zero count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// From negative to non-negative.
    Rising,
    /// From positive to non-positive.
    Falling,
    /// Either.
    Both,
}

/// What an event watches.
#[derive(Debug, Clone, PartialEq)]
pub enum EventKind {
    /// Any angle of the state passes ±π for the first time (the pendulum flips over).
    Flip,
    /// State variable `index` crosses zero.
    Zero {
        /// Index in the state vector.
        index: usize,
    },
    /// State variable `index` crosses `value` (a Poincaré section); for an angle, any of
    /// value + 2πk (the angle is a point on a circle).
    Section {
        /// Index in the state vector.
        index: usize,
        /// The section's value, in the variable's unit.
        value: f64,
        /// Whether the variable is an angle, so that the section repeats every 2π.
        periodic: bool,
    },
}

/// An event to locate.
#[derive(Debug, Clone, PartialEq)]
pub struct EventSpec {
    /// Name, as reported (`flip`, `zero:theta`, `section:theta1=0`).
    pub name: String,
    /// What it watches.
    pub kind: EventKind,
    /// Which crossings count.
    pub direction: Direction,
    /// Stop the run at the first occurrence.
    pub terminal: bool,
}

impl EventSpec {
    /// Parses `flip`, `zero:NAME` or `section:NAME=VALUE` against the state variable names of
    /// `model`; angles of `Flip` are the variables in rad. A trailing `+` or `-` on `zero` and
    /// `section` keeps only rising or falling crossings (`section:theta1=0+`: θ₁ passes 0
    /// upwards, as a Poincaré section usually wants).
    pub fn parse(text: &str, model: &dyn DynSystem, terminal: bool) -> Result<Self, Error> {
        let (body, direction) = match text.strip_suffix('+') {
            Some(body) if text != "flip" => (body, Direction::Rising),
            _ => match text.strip_suffix('-') {
                Some(body) => (body, Direction::Falling),
                None => (text, Direction::Both),
            },
        };
        let mut spec = Self::parse_kind(body, text, model, terminal)?;
        if direction != Direction::Both && spec.kind == EventKind::Flip {
            return Err(Error::UnknownName {
                system: model.info().name,
                name: text.to_owned(),
                valid: "flip, zero:NAME[+|-], section:NAME=VALUE[+|-] (flip has no direction)".into(),
                suggestions: vec!["flip".into()],
            });
        }
        spec.direction = direction;
        Ok(spec)
    }

    fn parse_kind(text: &str, full: &str, model: &dyn DynSystem, terminal: bool) -> Result<Self, Error> {
        let state = model.info().state;
        let index_of = |name: &str| {
            state
                .iter()
                .position(|q| q.name == name)
                .ok_or_else(|| Error::unknown_name(model.info().name, name, state.iter().map(|q| q.name)))
        };
        let kind = if text == "flip" {
            if !state.iter().any(|q| q.is_angle()) {
                return Err(Error::UnknownName {
                    system: model.info().name,
                    name: "flip".into(),
                    valid: "zero:NAME, section:NAME=VALUE (this system has no angle)".into(),
                    suggestions: Vec::new(),
                });
            }
            EventKind::Flip
        } else if let Some(name) = text.strip_prefix("zero:") {
            EventKind::Zero { index: index_of(name)? }
        } else if let Some(rest) = text.strip_prefix("section:") {
            let (name, value) = rest.split_once('=').ok_or_else(|| Error::UnknownName {
                system: model.info().name,
                name: text.to_owned(),
                valid: "flip, zero:NAME[+|-], section:NAME=VALUE[+|-]".into(),
                suggestions: Vec::new(),
            })?;
            let value: f64 = value.trim().parse().map_err(|_| {
                // `section:theta1=0++`: a direction written twice, or junk after the number;
                // the spec with one direction is the likely intent.
                let number = value.trim().trim_end_matches(['+', '-']);
                let suggestions = match number.parse::<f64>() {
                    Ok(_) if !number.is_empty() => {
                        let sign = if full.ends_with('-') { "-" } else { "+" };
                        vec![format!("section:{name}={number}{sign}")]
                    }
                    _ => Vec::new(),
                };
                Error::UnknownName {
                    system: model.info().name,
                    name: full.to_owned(),
                    valid: format!(
                        "section:NAME=VALUE with VALUE a number, then at most one + or - (`{}` is not a number)",
                        crate::error::clip(value.trim(), 20)
                    ),
                    suggestions,
                }
            })?;
            if !value.is_finite() {
                return Err(Error::InvalidValue { name: text.to_owned(), value, allowed: "must be finite" });
            }
            let index = index_of(name)?;
            EventKind::Section { index, value, periodic: state[index].is_angle() }
        } else {
            // A misspelt kind keeps what follows it: `zeros:theta` → `zero:theta`.
            let candidates: Vec<String> = match text.split_once(':') {
                Some((_, rest)) => vec![format!("zero:{rest}"), format!("section:{rest}")],
                None => vec!["flip".into()],
            };
            return Err(Error::UnknownName {
                system: model.info().name,
                name: text.to_owned(),
                valid: "flip, zero:NAME[+|-], section:NAME=VALUE[+|-]".into(),
                suggestions: crate::error::suggestions(text, candidates.iter().map(String::as_str)),
            });
        };
        Ok(EventSpec { name: full.to_owned(), kind, direction: Direction::Both, terminal })
    }
}

/// One located event.
#[derive(Debug, Clone, PartialEq)]
pub struct EventRecord {
    /// The event's name.
    pub name: String,
    /// Time, s.
    pub t: f64,
    /// State at that time (interpolated).
    pub state: Vec<f64>,
}

/// An observer that locates events between the steps it sees.
pub struct EventLocator<'a> {
    model: &'a dyn DynSystem,
    specs: Vec<EventSpec>,
    /// Flip events already seen (they count once).
    flipped: Vec<bool>,
    previous: Option<(f64, Vec<f64>, Vec<f64>)>,
    f: Vec<f64>,
    /// The events found, in time order per step.
    pub found: Vec<EventRecord>,
    /// Index in `found` of the terminal event that ended the run.
    stopped: Option<usize>,
}

impl<'a> EventLocator<'a> {
    /// Locates `specs` along a run of `model`.
    pub fn new(model: &'a dyn DynSystem, specs: Vec<EventSpec>) -> Self {
        let n = model.info().state.len();
        let flipped = vec![false; specs.len()];
        EventLocator {
            model,
            specs,
            flipped,
            previous: None,
            f: vec![0.0; n],
            found: Vec::new(),
            stopped: None,
        }
    }

    /// The terminal event that ended the run (its time and interpolated state), if one did.
    pub fn stopped_at(&self) -> Option<&EventRecord> {
        self.stopped.map(|i| &self.found[i])
    }

    /// The event functions of spec `k` at state y (several for `Flip`: θ − π and θ + π per
    /// angle).
    fn values(&self, k: usize, y: &[f64], out: &mut Vec<f64>) {
        out.clear();
        match &self.specs[k].kind {
            EventKind::Flip => {
                for (q, v) in self.model.info().state.iter().zip(y) {
                    if q.is_angle() {
                        out.push(v - std::f64::consts::PI);
                        out.push(v + std::f64::consts::PI);
                    }
                }
            }
            EventKind::Zero { index } => out.push(y[*index]),
            // sin(θ − v) vanishes at v + 2πk and also at v + π + 2πk; those are dropped
            // where the event is located (cos(θ − v) < 0 there).
            EventKind::Section { index, value, periodic: true } => out.push((y[*index] - value).sin()),
            EventKind::Section { index, value, periodic: false } => out.push(y[*index] - value),
        }
    }
}

/// The cubic Hermite basis (h₀₀, h₁₀, h₀₁, h₁₁) at fraction s of a step.
fn hermite_basis(s: f64) -> [f64; 4] {
    let (s2, s3) = (s * s, s * s * s);
    [2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2]
}

/// The cubic Hermite interpolant at fraction s of a step of size h, through the states `y0`,
/// `y1` and their derivatives `f0`, `f1` at its ends (error O(h⁴)): the continuous solution of
/// a method without dense output of its own.
pub fn hermite(s: f64, h: f64, y0: &[f64], f0: &[f64], y1: &[f64], f1: &[f64], out: &mut [f64]) {
    let [h00, h10, h01, h11] = hermite_basis(s);
    for (i, o) in out.iter_mut().enumerate() {
        *o = h00 * y0[i] + h10 * h * f0[i] + h01 * y1[i] + h11 * h * f1[i];
    }
}

/// Bisection for the fraction s ∈ [0, 1] of a step of size h, ending at time t, where g
/// changes sign; `sign` is g's sign at s = 0. It stops when the bracket is 1e-13 relative
/// in time (absolute below t = 1 s), or at round-off in s. The locator's, and Python's for
/// its callable events.
pub fn bisect(h: f64, t: f64, sign: f64, mut g: impl FnMut(f64) -> f64) -> f64 {
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    while (hi - lo) * h.abs() > 1e-13 * t.abs().max(1.0) && hi - lo > f64::EPSILON {
        let mid = 0.5 * (lo + hi);
        if g(mid).signum() == sign {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The fraction s ∈ [0, 1] of a step of size h, ending at time t, where the cubic Hermite
/// interpolant of one variable — (value, rate) `start` at the beginning of the step and
/// `end` at its end — crosses `level`: the locator's bisection on one variable, for the
/// ensemble engine's flip times. The end value must lie strictly beyond `level`, the start
/// value on the other side or on it.
pub(crate) fn hermite_crossing(h: f64, t: f64, start: [f64; 2], end: [f64; 2], level: f64) -> f64 {
    let sign = -(end[0] - level).signum();
    bisect(h, t, sign, |s| {
        let [h00, h10, h01, h11] = hermite_basis(s);
        h00 * start[0] + h10 * h * start[1] + h01 * end[0] + h11 * h * end[1] - level
    })
}

/// A run's continuous solution from its recorded steps: each step's own dense output where
/// the method has one ([`DenseStep`], Hairer's form), else the cubic Hermite interpolant
/// ([`hermite`]) through the states and their derivatives at both ends. What Python's
/// `Solution.sol` evaluates.
#[derive(Debug, Clone, Copy)]
pub struct Continuous<'a> {
    /// The times of the recorded states, s: increasing, or decreasing on a run backward.
    pub ts: &'a [f64],
    /// The states, one row of the state's length per time.
    pub states: &'a [f64],
    /// Their derivatives f(t, y), as `states`.
    pub f: &'a [f64],
    /// Per step between consecutive times, the method's dense output: (t₀, h) pairs, and
    /// the coefficients r₀, r₁, … of each step one after the other; `None`: Hermite.
    pub dense: Option<(&'a [f64], &'a [f64])>,
}

impl Continuous<'_> {
    /// The state at time t into `out` (the state's length): on the step containing t, a
    /// time beyond the run's ends on its first or last step.
    pub fn at(&self, t: f64, out: &mut [f64]) {
        let (n, count) = (out.len(), self.ts.len());
        if count < 2 {
            out.copy_from_slice(&self.states[..n]);
            return;
        }
        // The last time at or before t (in the run's direction), on a step [i, i + 1].
        let d = if self.ts[count - 1] >= self.ts[0] { 1.0 } else { -1.0 };
        let i = self.ts.partition_point(|&x| d * x <= d * t).saturating_sub(1).min(count - 2);
        match self.dense {
            Some((steps, coefficients)) => {
                let per = coefficients.len() / (count - 1);
                DenseStep::new(steps[2 * i], steps[2 * i + 1], &coefficients[i * per..(i + 1) * per])
                    .at(t, out)
            }
            None => {
                let (t0, t1) = (self.ts[i], self.ts[i + 1]);
                let (now, next) = (i * n..(i + 1) * n, (i + 1) * n..(i + 2) * n);
                let (y0, y1) = (&self.states[now.clone()], &self.states[next.clone()]);
                hermite((t - t0) / (t1 - t0), t1 - t0, y0, &self.f[now], y1, &self.f[next], out);
            }
        }
    }
}

impl EventLocator<'_> {
    /// The state at fraction s of the step from the previous sample to `sample`.
    fn interpolate(&self, sample: &Sample<'_>, s: f64, out: &mut [f64]) {
        let (t0, y0, f0) = self.previous.as_ref().expect("a previous state");
        let h = sample.t - t0;
        match &sample.dense {
            Some(dense) => dense.at(t0 + s * h, out),
            None => hermite(s, h, y0, f0, sample.y, &self.f, out),
        }
    }
}

impl Observer for EventLocator<'_> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        // `simulate` always carries a locator: with nothing to watch it costs nothing per step.
        if self.specs.is_empty() {
            return ControlFlow::Continue(());
        }
        if sample.dense.is_none() {
            self.model.rhs(sample.t, sample.y, &mut self.f);
        }
        let mut stop = false;
        if let Some((t0, y0, _)) = &self.previous {
            let (t0, h) = (*t0, sample.t - *t0);
            let (mut g0, mut g1, mut g) = (Vec::new(), Vec::new(), Vec::new());
            let mut at = vec![0.0; y0.len()];
            let mut hits: Vec<EventRecord> = Vec::new();
            let mut terminal: Vec<bool> = Vec::new();
            for k in 0..self.specs.len() {
                if self.flipped[k] {
                    continue;
                }
                self.values(k, y0, &mut g0);
                self.values(k, sample.y, &mut g1);
                let mut first: Option<f64> = None;
                for (m, (a, b)) in g0.iter().zip(&g1).enumerate() {
                    let (up, down) = (*a < 0.0 && *b >= 0.0, *a > 0.0 && *b <= 0.0);
                    let counts = match self.specs[k].direction {
                        Direction::Rising => up,
                        Direction::Falling => down,
                        Direction::Both => up || down,
                    };
                    if !counts {
                        continue;
                    }
                    // Bisection on the fraction s of the step: g(s) changes sign in [0, 1].
                    let s = bisect(h, sample.t, a.signum(), |mid| {
                        self.interpolate(sample, mid, &mut at);
                        self.values(k, &at, &mut g);
                        g[m]
                    });
                    if let EventKind::Section { index, value, periodic: true } = self.specs[k].kind {
                        self.interpolate(sample, s, &mut at);
                        if (at[index] - value).cos() < 0.0 {
                            continue;
                        }
                    }
                    first = Some(first.map_or(s, |f: f64| f.min(s)));
                }
                if let Some(s) = first {
                    self.interpolate(sample, s, &mut at);
                    hits.push(EventRecord {
                        name: self.specs[k].name.clone(),
                        t: t0 + s * h,
                        state: at.clone(),
                    });
                    if matches!(self.specs[k].kind, EventKind::Flip) {
                        self.flipped[k] = true;
                    }
                    terminal.push(self.specs[k].terminal);
                }
            }
            // In the run's time order (decreasing t on a run backward in time); the run ends
            // at the first terminal event, so later ones in the same step did not happen.
            let mut order: Vec<usize> = (0..hits.len()).collect();
            let d = h.signum();
            order.sort_by(|&a, &b| (d * hits[a].t).total_cmp(&(d * hits[b].t)));
            for i in order {
                self.found.push(hits[i].clone());
                if terminal[i] {
                    self.stopped = Some(self.found.len() - 1);
                    stop = true;
                    break;
                }
            }
        }
        match &mut self.previous {
            Some((t, y, f)) => {
                *t = sample.t;
                y.copy_from_slice(sample.y);
                f.copy_from_slice(&self.f);
            }
            None => self.previous = Some((sample.t, sample.y.to_vec(), self.f.clone())),
        }
        if stop { ControlFlow::Break(Stop::Enough) } else { ControlFlow::Continue(()) }
    }

    fn wants_dense(&self) -> bool {
        !self.specs.is_empty()
    }
}

/// Shows `inner` every state of a run, except that when a terminal event of `events` ends
/// the run, `inner` sees the event instead of the end of the step that contains it: the
/// event's time and interpolated state, marked `last`, with the step's dense output (which
/// covers it). A recorder's last row and an energy tracker's last energy are then the
/// event's, and the run ends where the event happens rather than up to a step later.
pub struct EndAtEvent<'a, O> {
    /// The events; a terminal one ends the run.
    pub events: EventLocator<'a>,
    /// Who sees the states.
    pub inner: O,
}

impl<O: Observer> Observer for EndAtEvent<'_, O> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        // The locator breaks only at a terminal event, which it then reports.
        if self.events.observe(sample).is_break() {
            if let Some(e) = self.events.stopped_at() {
                let at = Sample { t: e.t, y: &e.state, last: true, energy: None, ..*sample };
                // The event ends the run either way; only a failure to take it matters.
                if let ControlFlow::Break(Stop::Failed(f)) = self.inner.observe(&at) {
                    return ControlFlow::Break(Stop::Failed(f));
                }
            }
            return ControlFlow::Break(Stop::Enough);
        }
        self.inner.observe(sample)
    }

    fn wants_dense(&self) -> bool {
        self.events.wants_dense() || self.inner.wants_dense()
    }
}

/// The events found so far (each as its spec's index, time and state), which flips have
/// happened, the terminal event if one ended the run, and the previous sample with its
/// derivative, which the next step's crossings are bracketed and interpolated against.
impl Snapshot for EventLocator<'_> {
    fn save(&self, out: &mut Words) {
        out.u64(self.specs.len() as u64);
        for &f in &self.flipped {
            out.bool(f);
        }
        out.bool(self.previous.is_some());
        if let Some((t, y, f)) = &self.previous {
            out.f64(*t);
            out.f64s(y);
            out.f64s(f);
        }
        out.f64s(&self.f);
        out.u64(self.found.len() as u64);
        for e in &self.found {
            let k = self.specs.iter().position(|s| s.name == e.name).expect("an event of these specs");
            out.u64(k as u64);
            out.f64(e.t);
            out.f64s(&e.state);
        }
        out.bool(self.stopped.is_some());
        out.u64(self.stopped.unwrap_or(0) as u64);
    }

    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        let bad = |reason: String| Error::BadCheckpoint { part: "the event locator", reason };
        let specs = from.usize()?;
        if specs != self.specs.len() {
            return Err(bad(format!("{specs} events were watched, here {}", self.specs.len())));
        }
        for f in &mut self.flipped {
            *f = from.bool()?;
        }
        let n = self.f.len();
        self.previous = if from.bool()? {
            let t = from.f64()?;
            let (mut y, mut f) = (vec![0.0; n], vec![0.0; n]);
            from.f64s_into(&mut y)?;
            from.f64s_into(&mut f)?;
            Some((t, y, f))
        } else {
            None
        };
        from.f64s_into(&mut self.f)?;
        let found = from.usize()?;
        self.found.clear();
        for _ in 0..found {
            let k = from.usize()?;
            let spec = self.specs.get(k).ok_or_else(|| bad(format!("event {k} of {specs}")))?;
            let t = from.f64()?;
            let mut state = vec![0.0; n];
            from.f64s_into(&mut state)?;
            self.found.push(EventRecord { name: spec.name.clone(), t, state });
        }
        let stopped = from.bool()?;
        let index = from.usize()?;
        if stopped && index >= self.found.len() {
            return Err(bad(format!("the terminal event {index} of {}", self.found.len())));
        }
        self.stopped = stopped.then_some(index);
        Ok(())
    }
}
