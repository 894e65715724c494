//! What watches a `simulate` run: the rows written ([`Writer`] behind [`Rows`]), the progress
//! bar, and, with the event locator and the energy balance, the [`Watch`] a checkpoint saves.

use std::ops::ControlFlow;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use pendula::analysis::EnergyBalance;
use pendula::checkpoint::{Snapshot, Words};
use pendula::events::EventLocator;
use pendula::observe::{Every, Flow, Observer, Resample, Sample, Stop};

use crate::output::RowFailure;
use crate::sink::Sink;

/// Writes the states it is shown as rows (t, state, energy), and keeps them for `--plot`.
pub(crate) struct Writer<'a> {
    pub(crate) model: &'a dyn pendula::model::DynModel,
    pub(crate) sink: Sink,
    pub(crate) rows: u64,
    /// The rows, flat, when the run is to be drawn.
    pub(crate) kept: Option<Vec<f64>>,
}

impl Observer for Writer<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        let e = s.energy.unwrap_or_else(|| self.model.energy(s.t, s.y));
        let row = || std::iter::once(s.t).chain(s.y.iter().copied()).chain(std::iter::once(e));
        if let Err(err) = self.sink.row(row()) {
            // The run ends with this error (`pendula::Error::Observer`, whose cause it is).
            return ControlFlow::Break(Stop::failed(RowFailure(err)));
        }
        if let Some(kept) = &mut self.kept {
            kept.extend(row());
        }
        self.rows += 1;
        ControlFlow::Continue(())
    }
}

/// A progress bar over simulated time (stderr, drawn only on a terminal) for runs longer
/// than half a second, looked at every 4096 steps: a per-step check of one bit pattern.
pub(crate) struct Progress {
    bar: Option<ProgressBar>,
    start: Instant,
    t0: f64,
    span: f64,
}

/// What watches a run: the event locator, the energy balance, the rows, the progress bar.
/// For each leg of the run they are put together as a chain of observers, the rows behind a
/// `dyn Observer` (see [`Rows`]).
pub(crate) struct Watch<'a> {
    pub(crate) events: EventLocator<'a>,
    pub(crate) energy: EnergyBalance<'a>,
    pub(crate) rows: Rows<'a>,
    pub(crate) progress: Progress,
}

/// Ticks of the bar from t0 to t_end.
const PROGRESS_TICKS: u64 = 1000;

impl Progress {
    pub(crate) fn new(t0: f64, t_end: f64) -> Self {
        Progress { bar: None, start: Instant::now(), t0, span: t_end - t0 }
    }

    fn at(&mut self, step: u64, t: f64) {
        if !step.is_multiple_of(4096) {
            return;
        }
        let bar = match &self.bar {
            Some(bar) => bar,
            // A short run finishes before a bar would be read: none is drawn.
            None if self.start.elapsed().as_secs_f64() < 0.5 => return,
            None => {
                let bar = ProgressBar::new(PROGRESS_TICKS);
                bar.set_style(
                    ProgressStyle::with_template("simulate [{bar:30}] {percent:>3}% {elapsed} (eta {eta})")
                        .expect("valid template")
                        .progress_chars("=> "),
                );
                self.bar.insert(bar)
            }
        };
        let done = ((t - self.t0) / self.span).clamp(0.0, 1.0);
        bar.set_position((done * PROGRESS_TICKS as f64) as u64);
    }

    pub(crate) fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Which rows go to the writer: those on a time grid (`--output-dt`, `--t-eval`), every
/// N-th step's and the last, or none (then the writer is not called at all: it would
/// evaluate the energy at every step for nothing). Each leg of a run shows its samples to
/// the one in use (not to the enum, whose dispatch cost 25 instructions a step, measured).
pub(crate) enum Rows<'a> {
    Grid(Resample<Writer<'a>>),
    Every(Every<Writer<'a>>),
    None(Writer<'a>),
}

impl<'a> Rows<'a> {
    pub(crate) fn writer(&mut self) -> &mut Writer<'a> {
        match self {
            Rows::Grid(r) => &mut r.inner,
            Rows::Every(e) => &mut e.inner,
            Rows::None(w) => w,
        }
    }

    pub(crate) fn into_writer(self) -> Writer<'a> {
        match self {
            Rows::Grid(r) => r.inner,
            Rows::Every(e) => e.inner,
            Rows::None(w) => w,
        }
    }
}

/// The grid's position (the other kinds keep none: `Every` counts steps from the samples).
impl Snapshot for Rows<'_> {
    fn save(&self, out: &mut Words) {
        if let Rows::Grid(r) = self {
            r.save(out);
        }
    }
    fn restore(&mut self, from: &mut pendula::checkpoint::Reader<'_>) -> Result<(), pendula::Error> {
        match self {
            Rows::Grid(r) => r.restore(from),
            _ => Ok(()),
        }
    }
}

impl Observer for Progress {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        self.at(s.step, s.t);
        ControlFlow::Continue(())
    }
}
