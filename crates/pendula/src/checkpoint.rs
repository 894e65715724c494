//! Checkpoints: the exact state of a run between two steps, from which it continues bit for
//! bit as if it had never stopped.
//!
//! Everything a later step depends on is saved: the state in the coordinates the stepper
//! advances (on a Hamiltonian form, (q, p), not the (q, q') an observer sees: converting
//! back and forth is not exact), the step index (fixed-step times are recomputed from it),
//! the evaluation counters, and each stepper's own memory — Tao's copy (x, y), the
//! Gauss–Legendre stepper's kept stages, Jacobian, LU factors and refresh flag, the embedded
//! pairs' first-same-as-last derivative, the partitioned methods' cached force — and, for
//! adaptive runs, the next step size and the PI controller's error history. Observers with a
//! memory ([`crate::events::EventLocator`], [`crate::analysis::EnergyBalance`],
//! [`crate::observe::Resample`]) save theirs the same way.
//!
//! The format is a flat list of 64-bit words ([`Words`]): a float is its IEEE 754 bit
//! pattern, so every value — NaN payloads, infinities and −0 included — comes back exactly;
//! a flag is 0 or 1; a slice is its length, then its elements. [`Snapshot::restore`] reads
//! the words in the order [`Snapshot::save`] wrote them and refuses words that do not fit
//! (a wrong length, too few or too many words) with [`Error::BadCheckpoint`]. How the words
//! are stored on disk, versioned and checksummed is the caller's business (the CLI writes
//! them as hexadecimal in a checksummed JSON file).
//!
//! A run pauses at a step boundary when a [`Pause`] says so — at a simulated time, or when
//! an [`AtomicBool`] is set (an interrupt) — and hands back a [`RunState`]; started again
//! from it ([`crate::simulate::resume::solve_resumable`]) it takes the same steps, shows the
//! observer the same samples, and ends in the same bits.
//!
//! # References
//! H. Rein, D. S. Tamayo, "A new paradigm for reproducing and analyzing N-body simulations
//! of planetary systems", MNRAS 467 (2017) 2377 (REBOUND's Simulationarchive: restarts bit
//! for bit).
//!
//! # Who saves what
//!
//! `Snapshot` (save and restore as a flat list of 64-bit `Words`, floats as their bit patterns) is
//! implemented by every stepper — each in its family's file, next to the state it saves: Tao's
//! copy, the Gauss–Legendre stepper's kept stages, Jacobian, LU factors and flags, the embedded
//! pairs' first-same-as-last stage, the partitioned methods' cached force — by the PI controller
//! (`crates/pendula/src/control.rs`) and by the observers with a memory: the event locator
//! (`crates/pendula/src/events.rs`), the energy balance (`crates/pendula/src/analysis/energy.rs`)
//! and the resampler (`crates/pendula/src/observe.rs`).

use std::sync::atomic::{AtomicBool, Ordering};

use crate::Error;

/// State as a flat list of 64-bit words: floats as their bit patterns, flags as 0 or 1,
/// slices as their length followed by their elements.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Words(pub Vec<u64>);

impl Words {
    /// An empty list.
    pub fn new() -> Self {
        Words(Vec::new())
    }

    /// Appends a count or an index.
    pub fn u64(&mut self, v: u64) {
        self.0.push(v);
    }

    /// Appends a float, bit for bit.
    pub fn f64(&mut self, v: f64) {
        self.0.push(v.to_bits());
    }

    /// Appends a flag.
    pub fn bool(&mut self, v: bool) {
        self.0.push(u64::from(v));
    }

    /// Appends an optional float: a flag, then the value (0 when absent).
    pub fn opt_f64(&mut self, v: Option<f64>) {
        self.bool(v.is_some());
        self.f64(v.unwrap_or(0.0));
    }

    /// Appends a slice of floats: its length, then its elements.
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        self.0.extend(v.iter().map(|x| x.to_bits()));
    }

    /// Appends a slice of counts or indices: its length, then its elements.
    pub fn usizes(&mut self, v: &[usize]) {
        self.u64(v.len() as u64);
        self.0.extend(v.iter().map(|&x| x as u64));
    }

    /// Appends another list: its length, then its words.
    pub fn words(&mut self, v: &Words) {
        self.u64(v.0.len() as u64);
        self.0.extend_from_slice(&v.0);
    }
}

/// Reads [`Words`] back in the order they were written; every mismatch is an
/// [`Error::BadCheckpoint`] naming `part`.
#[derive(Debug)]
pub struct Reader<'a> {
    words: &'a [u64],
    at: usize,
    part: &'static str,
}

impl<'a> Reader<'a> {
    /// Reads `words`, the saved state of `part` (named in errors).
    pub fn new(words: &'a [u64], part: &'static str) -> Self {
        Reader { words, at: 0, part }
    }

    fn bad(&self, reason: String) -> Error {
        Error::BadCheckpoint { part: self.part, reason }
    }

    /// The next count or index.
    pub fn u64(&mut self) -> Result<u64, Error> {
        let v =
            *self.words.get(self.at).ok_or_else(|| self.bad(format!("it ends after {} words", self.at)))?;
        self.at += 1;
        Ok(v)
    }

    /// The next count, which must fit in memory.
    pub fn usize(&mut self) -> Result<usize, Error> {
        let v = self.u64()?;
        usize::try_from(v).map_err(|_| self.bad(format!("a count of {v} is too large")))
    }

    /// The next float.
    pub fn f64(&mut self) -> Result<f64, Error> {
        self.u64().map(f64::from_bits)
    }

    /// The next flag.
    pub fn bool(&mut self) -> Result<bool, Error> {
        match self.u64()? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(self.bad(format!("word {} should be a flag (0 or 1), not {v}", self.at - 1))),
        }
    }

    /// The next optional float.
    pub fn opt_f64(&mut self) -> Result<Option<f64>, Error> {
        let present = self.bool()?;
        let v = self.f64()?;
        Ok(present.then_some(v))
    }

    /// The length of the next slice, which must be `len`.
    fn length(&mut self, len: usize) -> Result<(), Error> {
        let saved = self.u64()?;
        if saved != len as u64 {
            return Err(self.bad(format!("a slice of {saved} values where {len} were expected")));
        }
        if self.words.len() - self.at < len {
            return Err(self.bad(format!("it ends inside a slice of {len} values")));
        }
        Ok(())
    }

    /// The next slice of floats, into `out` (of the saved length).
    pub fn f64s_into(&mut self, out: &mut [f64]) -> Result<(), Error> {
        self.length(out.len())?;
        for (o, w) in out.iter_mut().zip(&self.words[self.at..]) {
            *o = f64::from_bits(*w);
        }
        self.at += out.len();
        Ok(())
    }

    /// The next slice of floats, of any length up to the words left.
    pub fn f64s(&mut self) -> Result<Vec<f64>, Error> {
        let len = self.usize()?;
        if self.words.len() - self.at < len {
            return Err(self.bad(format!("it ends inside a slice of {len} values")));
        }
        let v = self.words[self.at..self.at + len].iter().map(|w| f64::from_bits(*w)).collect();
        self.at += len;
        Ok(v)
    }

    /// The next slice of counts or indices, into `out` (of the saved length); each must be
    /// below `bound`.
    pub fn usizes_into(&mut self, out: &mut [usize], bound: usize) -> Result<(), Error> {
        self.length(out.len())?;
        for o in out.iter_mut() {
            let v = self.usize()?;
            if v >= bound {
                return Err(self.bad(format!("index {v} is out of range (< {bound})")));
            }
            *o = v;
        }
        Ok(())
    }

    /// The next nested list.
    pub fn words(&mut self) -> Result<Words, Error> {
        let len = self.usize()?;
        if self.words.len() - self.at < len {
            return Err(self.bad(format!("it ends inside a list of {len} words")));
        }
        let v = Words(self.words[self.at..self.at + len].to_vec());
        self.at += len;
        Ok(v)
    }

    /// Checks that every word was read.
    pub fn finish(self) -> Result<(), Error> {
        if self.at == self.words.len() {
            Ok(())
        } else {
            Err(self.bad(format!("{} words are left over", self.words.len() - self.at)))
        }
    }
}

/// State that can be saved between two steps and restored exactly: steppers, the
/// step-size controller, observers with a memory.
pub trait Snapshot {
    /// Appends the state to `out`.
    fn save(&self, out: &mut Words);
    /// Restores the state [`Snapshot::save`] wrote into a value built the same way (same
    /// method, same dimension).
    ///
    /// # Errors
    /// [`Error::BadCheckpoint`] when the words do not fit.
    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error>;

    /// The state as a list of its own.
    fn snapshot(&self) -> Words {
        let mut out = Words::new();
        self.save(&mut out);
        out
    }

    /// Restores from a list that [`Snapshot::snapshot`] made, checking that every word is
    /// used; `part` names it in errors.
    ///
    /// # Errors
    /// As [`Snapshot::restore`].
    fn restore_all(&mut self, words: &Words, part: &'static str) -> Result<(), Error> {
        let mut reader = Reader::new(&words.0, part);
        self.restore(&mut reader)?;
        reader.finish()
    }
}

/// When a run pauses: after the first step that ends at or after `at`, or after the step
/// during which `flag` was set (after the first step when it was set before). Checked once per step: a comparison and a relaxed atomic
/// load.
#[derive(Debug, Clone, Copy)]
pub struct Pause<'a> {
    /// Simulated time, s (∞: never for this reason).
    pub at: f64,
    /// Set from another thread (an interrupt) to pause at the next step boundary.
    pub flag: Option<&'a AtomicBool>,
}

impl Pause<'_> {
    /// Never pauses.
    pub const NEVER: Pause<'static> = Pause { at: f64::INFINITY, flag: None };

    /// Whether to pause after a step that ended at time t.
    #[inline]
    pub fn due(&self, t: f64) -> bool {
        t >= self.at || self.flag.is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// Whether it never pauses.
    pub fn never(&self) -> bool {
        self.at == f64::INFINITY && self.flag.is_none()
    }
}

/// Where a paused run stands, with everything needed to continue it exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct RunState {
    /// Steps taken (accepted steps on adaptive runs).
    pub steps: u64,
    /// Time of the state, s.
    pub t: f64,
    /// The state, in the coordinates the stepper advances ((q, p) on a Hamiltonian form).
    pub y: Vec<f64>,
    /// Steps rejected so far (adaptive runs).
    pub rejected: u64,
    /// Evaluations so far: of f, of the halves ∂H/∂q and ∂H/∂p, and of Jacobians.
    pub evaluations: [u64; 3],
    /// The stepper's own state ([`Snapshot`]).
    pub stepper: Words,
    /// Adaptive runs: the next step size, whether the last step was rejected, and the
    /// controller's state; empty for fixed steps.
    pub control: Words,
}

impl RunState {
    /// All of it as one list of words.
    pub fn to_words(&self) -> Words {
        let mut w = Words::new();
        w.u64(self.steps);
        w.f64(self.t);
        w.f64s(&self.y);
        w.u64(self.rejected);
        for e in self.evaluations {
            w.u64(e);
        }
        w.words(&self.stepper);
        w.words(&self.control);
        w
    }

    /// Reads what [`RunState::to_words`] wrote.
    ///
    /// # Errors
    /// [`Error::BadCheckpoint`] when the words do not fit.
    pub fn from_words(words: &Words) -> Result<Self, Error> {
        let mut r = Reader::new(&words.0, "the run");
        let state = RunState {
            steps: r.u64()?,
            t: r.f64()?,
            y: r.f64s()?,
            rejected: r.u64()?,
            evaluations: [r.u64()?, r.u64()?, r.u64()?],
            stepper: r.words()?,
            control: r.words()?,
        };
        r.finish()?;
        Ok(state)
    }

    /// A fixed-step run's position after `steps` steps, at time t in state y (the stepper's
    /// state and the counters to be added).
    pub(crate) fn at(steps: u64, t: f64, y: &[f64]) -> Self {
        RunState {
            steps,
            t,
            y: y.to_vec(),
            rejected: 0,
            evaluations: [0; 3],
            stepper: Words::new(),
            control: Words::new(),
        }
    }

    /// Checks that the state has `dim` variables, all finite.
    pub(crate) fn check(&self, dim: usize) -> Result<(), Error> {
        let bad = |reason: String| Error::BadCheckpoint { part: "the run", reason };
        if self.steps == 0 {
            return Err(bad("it is at step 0: a run pauses after a step, not before the first".into()));
        }
        if self.y.len() != dim {
            return Err(bad(format!("a state of {} variables where the system has {dim}", self.y.len())));
        }
        if !self.t.is_finite() || self.y.iter().any(|v| !v.is_finite()) {
            return Err(bad("a non-finite time or state".into()));
        }
        Ok(())
    }
}

/// How a resumable run ended this time: at its end (or stopped by an observer), or paused.
#[derive(Debug, Clone, PartialEq)]
pub enum Leg<R> {
    /// The run is over.
    Done(R),
    /// The run paused; continue it from this state.
    Paused(RunState),
}
