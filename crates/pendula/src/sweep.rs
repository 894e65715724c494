//! Sweeps: one system integrated from every cell of a grid over parameters and
//! initial-state variables ([`SweepSpec`] → [`Sweep`]), each cell's result a row of recorded
//! columns ([`Record`]). This is what `pendula sweep` and Python's `pendula.sweep` compute;
//! they parse their own arguments, and write, shard and merge files themselves.
//!
//! Where [`crate::model::ensemble_path`] says so the cells run on the SIMD lanes of the
//! [`crate::ensemble::engine`]; everything else runs the scalar integrators cell by cell ([`run_scalar`]), in parallel on rayon's current pool.
//! Either way a cell's result depends on its values alone: the output is bitwise the same
//! for any thread count, any range of cells computed at a time (shards, checkpoint chunks)
//! and any cancellation check.
//!
//! Cells are numbered row-major with the *first* axis fastest: cell `i` has index
//! `i mod n₀` on axis 0, `(i / n₀) mod n₁` on axis 1, and so on; the natural array shape is
//! therefore the axes slowest first, then the columns ([`Sweep::shape`]).
//!
//! # Who runs it
//!
//! A sweep's computation is the library's, `crates/pendula/src/sweep.rs` (above `model` and
//! `ensemble`, which it drives): `SweepSpec` (system, set values, axes, method, step, steps,
//! until-flip, records, shard) validated into a `Sweep`, whose `compute` fills a range of cells
//! (rows of the recorded columns) on the engine or, where `ensemble_path` says `Scalar`, with the
//! scalar integrators per cell (`run_scalar`, also Python's `ensemble` scalar path), bit for bit
//! the same for any threads, range or cancel flag.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use crate::ensemble::engine::{LaneOutcome, LaneSpec, Members, Rows};
use crate::integrator::{Method, Scheme};
use crate::model::EnsemblePath;
use crate::observe::{Flow, Observer, Sample, Stop};
use crate::system::{SystemInfo, Values};
use crate::{End, Error, RunSpec};

/// The most cells a sweep may have: 10¹⁵ cells of one column are 8 PB of results, more
/// than any machine holds, and fewer than a `usize` (and an f64) counts exactly.
pub const MAX_CELLS: f64 = 1e15;

/// One axis of the grid: `n` cells over [`lo`, `hi`] of one parameter or initial-state
/// variable, sampled at the cell centres ([`Axis::centre`]), in the quantity's unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The quantity's catalogue name.
    pub name: String,
    /// The lower edge of the first cell (the quantity's unit: rad, kg, m, …).
    pub lo: f64,
    /// The upper edge of the last cell.
    pub hi: f64,
    /// The number of cells, at least 1.
    pub n: usize,
}

impl Axis {
    /// The centre of cell `i`: lo + (i + ½)(hi − lo)/n.
    pub fn centre(&self, i: usize) -> f64 {
        self.lo + (i as f64 + 0.5) * (self.hi - self.lo) / self.n as f64
    }
}

/// A quantity recorded per cell.
// The variants' names are part of the fingerprint ([`Sweep::fingerprint`]): renaming one
// makes shards of older runs unmergeable with new ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Record {
    /// The state at the end (or where the cell stopped at its flip): one column per
    /// variable, named as the catalogue names them.
    Final,
    /// The time of the first flip (an angle passes ±π), s, or NaN: column `flip_time`.
    FlipTime,
    /// E_end − E_0, J (dimensionless for dimensionless systems): column `energy_error`.
    EnergyError,
}

impl Record {
    /// Every record, in the order front-ends list them.
    pub const ALL: [Record; 3] = [Record::Final, Record::FlipTime, Record::EnergyError];

    /// The name front-ends give it: `final`, `flip-time`, `energy-error`.
    pub fn name(self) -> &'static str {
        match self {
            Record::Final => "final",
            Record::FlipTime => "flip-time",
            Record::EnergyError => "energy-error",
        }
    }

    /// The record named `name` ([`Record::name`]), if any.
    pub fn from_name(name: &str) -> Option<Record> {
        Record::ALL.into_iter().find(|r| r.name() == name)
    }

    /// The records named, in order, for a sweep of `info`: each known, each once, and
    /// `flip-time` only where the system has an angle. The front ends phrase the
    /// [`RecordError`] in their own spelling.
    ///
    /// # Errors
    /// The first name that is unknown, given twice, or needs an angle the system lacks.
    pub fn parse_list<'a>(
        names: impl IntoIterator<Item = &'a str>,
        info: &SystemInfo,
    ) -> Result<Vec<Record>, RecordError> {
        let mut records = Vec::new();
        for name in names {
            let record = Record::from_name(name).ok_or_else(|| RecordError::Unknown {
                name: name.to_owned(),
                suggestions: crate::error::suggestions(name, Record::ALL.map(Record::name)),
            })?;
            if record == Record::FlipTime && !has_angle(info) {
                return Err(RecordError::NoAngle);
            }
            if records.contains(&record) {
                return Err(RecordError::Twice(name.to_owned()));
            }
            records.push(record);
        }
        Ok(records)
    }
}

/// Whether a sweep of `info` can stop at a flip (and record its time): the system has an
/// angle.
pub fn has_angle(info: &SystemInfo) -> bool {
    info.state.iter().any(|q| q.is_angle())
}

/// Why a list of records was refused ([`Record::parse_list`]).
#[derive(Debug, Clone, PartialEq)]
pub enum RecordError {
    /// No record has this name; the valid names closest to it.
    Unknown {
        /// The name given.
        name: String,
        /// The closest valid names (see [`crate::error::suggestions`]).
        suggestions: Vec<String>,
    },
    /// `flip-time` for a system without an angle.
    NoAngle,
    /// The record was named twice (the name as given).
    Twice(String),
}

/// The valid records ([`Record::ALL`]) in the words of an error: "final, flip-time or
/// energy-error".
pub fn record_names() -> String {
    let names = Record::ALL.map(Record::name);
    format!("{} or {}", names[..names.len() - 1].join(", "), names[names.len() - 1])
}

/// What a sweep computes, as given: [`SweepSpec::validate`] checks it into a [`Sweep`].
#[derive(Debug, Clone)]
pub struct SweepSpec {
    /// The system (a family, such as the chain, resolves to the member `set` chooses).
    pub system: &'static SystemInfo,
    /// Values the same for every cell, by name, in the order given (the fingerprint keeps
    /// the order); the rest at their defaults.
    pub set: Vec<(String, f64)>,
    /// The axes, the first varying fastest.
    pub axes: Vec<Axis>,
    /// A fixed-step method.
    pub method: &'static Method,
    /// Step size, s.
    pub h: f64,
    /// Number of steps, from t = 0.
    pub steps: u64,
    /// Stop each cell at its first flip (front-ends refuse it on a system without angles).
    pub until_flip: bool,
    /// The recorded columns, in order (front-ends refuse repeats).
    pub records: Vec<Record>,
    /// Shard K of N, (K, N) with 1 ≤ K ≤ N: cells [`Sweep::range`]; (1, 1) for all.
    pub shard: (usize, usize),
}

/// A validated sweep: its cells' values are in their domains, its method applies to its
/// system with fixed steps, its shard is one of its grid.
#[derive(Debug, Clone)]
pub struct Sweep {
    spec: SweepSpec,
    /// The member of the family the values choose: every cell's.
    info: &'static SystemInfo,
    columns: Vec<String>,
}

impl SweepSpec {
    /// Checks the description before any work.
    ///
    /// # Errors
    /// [`Error::UnknownName`] for a quantity the system lacks; [`Error::InvalidValue`] for a
    /// value out of its domain (set, or at a corner of the grid), an empty grid or axis,
    /// `lo ≥ hi`, an axis given twice, set and swept, or one that changes the member of a
    /// family, more than [`MAX_CELLS`] cells, a step or step count
    /// [`RunSpec::schedule`] refuses, no records, or a shard not of the grid;
    /// [`Error::UnmetRequirement`] for an adaptive method, or one the system does not meet.
    pub fn validate(self) -> Result<Sweep, Error> {
        let family = self.system;
        let info = family.values(&self.set)?.info();
        let invalid =
            |name: String, value: f64, allowed: &'static str| Error::InvalidValue { name, value, allowed };
        if self.axes.is_empty() {
            return Err(invalid("axes".into(), 0.0, "at least one axis"));
        }
        for (i, a) in self.axes.iter().enumerate() {
            info.quantity(&a.name)?;
            if a.n == 0 {
                return Err(invalid(format!("n of the {} axis", a.name), 0.0, "at least 1 cell"));
            }
            if !a.lo.is_finite() {
                return Err(invalid(format!("lo of the {} axis", a.name), a.lo, "a finite number"));
            }
            if !(a.hi.is_finite() && a.lo < a.hi) {
                return Err(invalid(format!("hi of the {} axis", a.name), a.hi, "a finite number above lo"));
            }
            if self.axes[..i].iter().any(|b| b.name == a.name) {
                return Err(invalid(a.name.clone(), a.lo, "one axis per quantity; this one is swept twice"));
            }
            if let Some((_, v)) = self.set.iter().find(|(n, _)| *n == a.name) {
                return Err(invalid(a.name.clone(), *v, "set or swept, not both"));
            }
            // An axis may not change the member, since the state's size would change from
            // cell to cell.
            for v in [a.centre(0), a.centre(a.n - 1)] {
                let mut settings = self.set.clone();
                settings.push((a.name.clone(), v));
                if !std::ptr::eq(family.values(&settings)?.info(), info) {
                    return Err(invalid(
                        a.name.clone(),
                        v,
                        "a value that keeps the size of the state (run one sweep per value)",
                    ));
                }
            }
        }
        let cells: f64 = self.axes.iter().map(|a| a.n as f64).product();
        if cells > MAX_CELLS {
            return Err(invalid("cells".into(), cells, "at most 10^15 cells in a sweep"));
        }
        if let Scheme::Embedded(_) = self.method.scheme {
            return Err(Error::UnmetRequirement {
                method: self.method.name,
                needs: "adaptive steps",
                reason: "a sweep takes fixed steps".into(),
                suggestion: "a fixed-step method (rk4, gauss-legendre-4)".into(),
            });
        }
        RunSpec { t0: 0.0, h: self.h, end: End::Steps(self.steps) }.schedule()?;
        if self.records.is_empty() {
            return Err(invalid("records".into(), 0.0, "at least one of final, flip-time, energy-error"));
        }
        let (k, n) = self.shard;
        if !(1 <= k && k <= n) {
            return Err(invalid("shard".into(), k as f64, "K of K/N, 1 to N"));
        }
        if n as f64 > cells {
            return Err(invalid("shards".into(), n as f64, "at most the number of cells"));
        }
        let mut columns = Vec::new();
        for r in &self.records {
            match r {
                Record::Final => columns.extend(info.state.iter().map(|q| q.name.to_owned())),
                Record::FlipTime => columns.push("flip_time".into()),
                Record::EnergyError => columns.push("energy_error".into()),
            }
        }
        let sweep = Sweep { spec: self, info, columns };
        // Every cell's values are in their domains if the extreme cell centres are (the
        // domains are intervals): both corners, before any work.
        let first = sweep.values(0)?;
        sweep.values(sweep.cells() - 1)?;
        first.build().check(sweep.spec.method)?;
        Ok(sweep)
    }
}

/// A failed computation: the library's error and, when one cell (member) failed, its index.
#[derive(Debug, Clone, PartialEq)]
pub struct CellError {
    /// The cell's index (a sweep's: in the whole grid), if the error is one cell's.
    pub cell: Option<usize>,
    /// What went wrong; a cell's non-finite state is [`Error::NonFinite`] with its time.
    pub error: Error,
}

impl CellError {
    /// The error alone, a cell's non-finite state as [`Error::NonFiniteMember`].
    pub fn into_error(self) -> Error {
        match (self.cell, self.error) {
            (Some(member), Error::NonFinite { t }) => Error::NonFiniteMember { member, t },
            (_, e) => e,
        }
    }
}

impl std::fmt::Display for CellError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.cell {
            Some(c) => write!(f, "cell {c}: {}", self.error),
            None => self.error.fmt(f),
        }
    }
}

impl std::error::Error for CellError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

impl Sweep {
    /// The description it was validated from.
    pub fn spec(&self) -> &SweepSpec {
        &self.spec
    }

    /// The member of the system's family every cell runs.
    pub fn info(&self) -> &'static SystemInfo {
        self.info
    }

    /// The columns' names, in order (a row per cell).
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The number of cells of the whole grid.
    pub fn cells(&self) -> usize {
        self.spec.axes.iter().map(|a| a.n).product()
    }

    /// The values of cell `index` (first axis fastest).
    ///
    /// # Errors
    /// As [`SystemInfo::values`] (never for a cell of the grid: its corners were checked).
    pub fn values(&self, index: usize) -> Result<Values, Error> {
        let mut settings = self.spec.set.clone();
        let mut rest = index;
        for axis in &self.spec.axes {
            settings.push((axis.name.clone(), axis.centre(rest % axis.n)));
            rest /= axis.n;
        }
        self.info.values(&settings)
    }

    /// The whole array's shape: the axes, slowest first, then the columns.
    pub fn shape(&self) -> Vec<usize> {
        let mut shape: Vec<usize> = self.spec.axes.iter().rev().map(|a| a.n).collect();
        shape.push(self.columns.len());
        shape
    }

    /// Cells [start, end) of the shard: N contiguous slices as equal as possible, shard K
    /// being cells ⌊(K−1)·cells/N⌋ to ⌊K·cells/N⌋.
    pub fn range(&self) -> (usize, usize) {
        let (k, n) = self.spec.shard;
        // In u128: k × cells overflows usize for large grids cut in many shards.
        let (k, n, cells) = (k as u128, n as u128, self.cells() as u128);
        (((k - 1) * cells / n) as usize, (k * cells / n) as usize)
    }

    /// A digest (16 hexadecimal digits) of everything that determines the whole array, so
    /// that merging refuses shards of different sweeps. The shard is not part of it.
    pub fn fingerprint(&self) -> String {
        let s = &self.spec;
        // The text hashed is fixed: shards written by other builds carry its digest.
        let text = format!(
            "{}|{:?}|{:?}|{}|{:e}|{}|{}|{:?}",
            self.info.name, s.set, s.axes, s.method.name, s.h, s.steps, s.until_flip, s.records
        );
        // FNV-1a, 64 bits: a label, not a security measure.
        let hash = text
            .bytes()
            .fold(0xcbf2_9ce4_8422_2325_u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
        format!("{hash:016x}")
    }

    /// The engine the cells run on, as [`crate::model::ensemble_path`] decides it for the
    /// method and the first cell's values.
    pub fn path(&self) -> EnsemblePath {
        let first = self.values(0).expect("a validated sweep's first cell");
        crate::model::ensemble_path(self.spec.method, &first)
    }

    /// The engine's description, for people and descriptions of the output.
    pub fn kernel(&self) -> &'static str {
        match self.path() {
            EnsemblePath::Engine(_) => "simd lanes (ensemble engine)",
            EnsemblePath::Scalar => "scalar, per cell",
        }
    }

    /// Computes cells `start ..` into `out`, one row of [`Sweep::columns`] per cell
    /// (`out.len()` a multiple of the column count), in parallel on rayon's current pool;
    /// `done` is called once per finished cell (a progress count). When `cancel` is set (by
    /// another thread) the computation stops with [`Error::Interrupted`], `out` then
    /// incomplete: at the next lane group on the engine, the next cell on the scalar path.
    ///
    /// # Errors
    /// A cell's failure ([`Error::NonFinite`], a scalar method's own) with its index in the
    /// grid; [`Error::Interrupted`].
    pub fn compute(
        &self,
        start: usize,
        out: &mut [f64],
        cancel: Option<&AtomicBool>,
        done: &(dyn Fn() + Sync),
    ) -> Result<(), CellError> {
        let cols = self.columns.len();
        let count = out.len() / cols;
        let bare = |error: Error| CellError { cell: None, error };
        let first = self.values(0).map_err(bare)?;
        // The member's entry (for the chain, the one with its links): its quantities' order.
        let info = first.info();
        let base: Vec<f64> =
            first.parameters().map(|(_, v)| v).chain(first.initial_state().iter().copied()).collect();
        let slots: Vec<usize> = self
            .spec
            .axes
            .iter()
            .map(|a| info.quantities().position(|q| q.name == a.name).expect("a checked name"))
            .collect();
        let np = info.parameters.len();
        // Every cell's values from the first cell's and the axes, without an allocation.
        let fill = |i: usize, v: &mut [f64]| {
            v.copy_from_slice(&base);
            let mut rest = start + i;
            for (axis, &slot) in self.spec.axes.iter().zip(&slots) {
                v[slot] = axis.centre(rest % axis.n);
                rest /= axis.n;
            }
        };
        let store_row = |i: usize, state: &[f64], flip_time: f64, row: &mut [f64]| {
            // The energy error (if recorded) from the cell's own model: built only then.
            let energy = || {
                let mut v = base.clone();
                fill(i, &mut v);
                info.values(&settings(info, &v)).map_or(f64::NAN, |values| {
                    let model = values.build();
                    model.energy(0.0, state) - model.energy(0.0, &v[np..])
                })
            };
            self.store(state, flip_time, energy, row);
            done();
        };
        // The lanes name a failing member by its index in the run.
        let lanes_error = |e: Error| match e {
            Error::NonFiniteMember { member, t } => {
                CellError { cell: Some(start + member), error: Error::NonFinite { t } }
            }
            other => bare(other),
        };
        let (h, steps, until_flip) = (self.spec.h, self.spec.steps, self.spec.until_flip);
        let track_flips = self.spec.records.contains(&Record::FlipTime);
        let members = Members { info, count, values: &fill };
        match self.path() {
            EnsemblePath::Engine(method) => {
                let spec = LaneSpec { method, h, steps, stop_at_flip: until_flip, track_flips, cancel };
                let store = |i: usize, o: &LaneOutcome, row: &mut [f64]| {
                    store_row(i, &o.state[..info.state.len()], o.flip_time, row)
                };
                first
                    .build()
                    .ensemble(&members, &spec, Rows { out, len: cols, store: &store })
                    .map_err(lanes_error)
            }
            EnsemblePath::Scalar => {
                let spec =
                    ScalarSpec { method: self.spec.method, h, steps, stop_at_flip: until_flip, cancel };
                run_scalar(&members, &spec, Rows { out, len: cols, store: &store_row })
                    .map_err(|e| CellError { cell: e.cell.map(|c| start + c), error: e.error })
            }
        }
    }

    /// Writes a row of results: the recorded columns (`energy_error` is called only if
    /// needed).
    fn store(&self, state: &[f64], flip_time: f64, energy_error: impl FnOnce() -> f64, row: &mut [f64]) {
        let mut c = 0;
        let mut energy_error = Some(energy_error);
        for r in &self.spec.records {
            match r {
                Record::Final => {
                    row[c..c + state.len()].copy_from_slice(state);
                    c += state.len();
                }
                Record::FlipTime => {
                    row[c] = flip_time;
                    c += 1;
                }
                Record::EnergyError => {
                    row[c] = energy_error.take().map_or(f64::NAN, |f| f());
                    c += 1;
                }
            }
        }
    }
}

/// The settings that give a member of `info` the values `v` (every quantity, in the
/// catalogue's order).
fn settings(info: &SystemInfo, v: &[f64]) -> Vec<(String, f64)> {
    info.quantities().map(|q| q.name.to_owned()).zip(v.iter().copied()).collect()
}

/// Stores member i's final state and flip time into its row.
pub type StoreValues<'a, T> = dyn Fn(usize, &[f64], f64, &mut [T]) + Sync + 'a;

/// What [`run_scalar`] runs: every member `steps` fixed steps of `h` with `method`.
#[derive(Debug, Clone, Copy)]
pub struct ScalarSpec<'a> {
    /// The method (any the members meet; an embedded pair takes its fixed steps).
    pub method: &'static Method,
    /// Step size, s.
    pub h: f64,
    /// Number of steps, from t = 0.
    pub steps: u64,
    /// Stop a member at its first flip (an angle passes ±π).
    pub stop_at_flip: bool,
    /// When set (by another thread: a Ctrl-C), members not yet started are skipped and the
    /// run ends with [`Error::Interrupted`].
    pub cancel: Option<&'a AtomicBool>,
}

/// Runs the `members` one scalar run each, in parallel on rayon's current pool: member i's
/// final state and first flip time (s, NaN if none: where the cubic Hermite interpolant of
/// an angle passes ±π within the step, as on the lanes) stored by `rows.store(i, state,
/// flip_time, row)` into its row. The ensemble's scalar path, for methods without lanes.
///
/// # Errors
/// A failing member's (the first to fail, not always the lowest index): its values out of their
/// domains, the method's requirement unmet, a non-finite state ([`Error::NonFinite`]), an
/// implicit step that did not converge; [`Error::Interrupted`].
pub fn run_scalar(
    members: &Members<'_>,
    spec: &ScalarSpec<'_>,
    rows: Rows<'_, f64, StoreValues<'_, f64>>,
) -> Result<(), CellError> {
    let Members { info, count, values: member } = *members;
    let Rows { out, len: row_len, store } = rows;
    let angles: Vec<usize> =
        info.state.iter().enumerate().filter(|(_, q)| q.is_angle()).map(|(i, _)| i).collect();
    let run = RunSpec { t0: 0.0, h: spec.h, end: End::Steps(spec.steps) };
    let width = info.quantities().count();
    let np = info.parameters.len();
    out[..count * row_len].par_chunks_mut(row_len).enumerate().try_for_each(|(i, row)| {
        if spec.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(CellError { cell: None, error: Error::Interrupted });
        }
        let mut v = vec![0.0; width];
        member(i, &mut v);
        let values = info.values(&settings(info, &v)).map_err(|error| CellError { cell: None, error })?;
        let mut watch = FlipWatch {
            previous: vec![[0.0; 2]; angles.len()],
            angles: &angles,
            t_previous: 0.0,
            flip_time: f64::NAN,
            stop: spec.stop_at_flip,
        };
        let report = values
            .build()
            .solve(spec.method, &v[np..], &run, &mut watch)
            .map_err(|error| CellError { cell: Some(i), error })?;
        store(i, &report.state, watch.flip_time, row);
        Ok(())
    })
}

/// Watches a scalar run for the first flip: where the cubic Hermite interpolant of an angle
/// that crossed (its values and rates, the velocities `dim / 2` further on, at both ends of
/// the step) passes ±π — the rule of the lanes ([`crate::ensemble::engine`]) and of the
/// event locator, so that a sweep's `flip_time` does not depend on which path ran it.
struct FlipWatch<'a> {
    angles: &'a [usize],
    /// The angles' values and rates at the end of the previous step.
    previous: Vec<[f64; 2]>,
    t_previous: f64,
    flip_time: f64,
    stop: bool,
}

impl Observer for FlipWatch<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        use std::f64::consts::PI;
        let rate = s.y.len() / 2;
        if s.step > 0 && self.flip_time.is_nan() {
            let h = s.t - self.t_previous;
            let mut fraction = f64::INFINITY;
            for (&i, &[a, da]) in self.angles.iter().zip(&self.previous) {
                let (b, db) = (s.y[i], s.y[i + rate]);
                if a.abs() <= PI && b.abs() > PI {
                    fraction = fraction.min(crate::events::hermite_crossing(
                        h,
                        s.t,
                        [a, da],
                        [b, db],
                        PI.copysign(b),
                    ));
                }
            }
            if fraction.is_finite() {
                self.flip_time = self.t_previous + fraction * h;
                if self.stop {
                    return Flow::Break(Stop::Enough);
                }
            }
        }
        for (p, &i) in self.previous.iter_mut().zip(self.angles) {
            *p = [s.y[i], s.y[i + rate]];
        }
        self.t_previous = s.t;
        Flow::Continue(())
    }
}
