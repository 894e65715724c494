//! A `simulate` run's checkpoint: what it holds, how it is written between two steps, and
//! how `pendula resume` reads it back.
//!
//! Besides the arguments (see [`crate::checkpoint`]) it holds the run's [`RunState`] (step,
//! time, state in the stepper's coordinates, the stepper's and the controller's memory, the
//! evaluation counters), the observers' states — the event locator (events so far, its
//! previous sample), the energy balance (running maximum, work integral), the resampling
//! grid's position — the rows written, the trajectory file's length, row count and CRC-32,
//! the time of the next checkpoint, and the wall time spent so far (which the summary adds
//! up). The trajectory itself stays in `OUT.partial` beside the output.

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow};
use pendula::checkpoint::{RunState, Snapshot};
use serde_json::{Value, json};

use crate::checkpoint::{Checkpoint, f64_from_hex, hex_f64, hex_words};
use crate::config::SimulateArgs;
use crate::config::SimulateConfig;
use crate::output::PartialFile;
use crate::sink::Position;
use crate::watch::Watch;

/// Where a run paused, and when it pauses next.
pub struct Saved {
    /// The run's state.
    pub run: RunState,
    /// Simulated time of the next checkpoint, s (∞: only when interrupted).
    pub next_checkpoint: f64,
}

/// A `simulate` checkpoint read back.
pub struct Resumed {
    /// The file.
    pub checkpoint: Checkpoint,
    saved_run: RunState,
    next_checkpoint: f64,
    events: pendula::checkpoint::Words,
    energy: pendula::checkpoint::Words,
    rows: pendula::checkpoint::Words,
    writer_rows: u64,
    /// The trajectory file's position and its partial file.
    pub out: Option<(Position, PathBuf)>,
    /// Wall time of the earlier legs, s.
    pub wall_s: f64,
}

impl Resumed {
    /// Reads a `simulate` checkpoint's state.
    pub fn load(checkpoint: Checkpoint) -> Result<Self> {
        let run = RunState::from_words(&checkpoint.words("run")?)
            .with_context(|| format!("the checkpoint {} is invalid", checkpoint.path.display()))?;
        let next: String = checkpoint.get("next_checkpoint")?;
        let out: Option<Value> = checkpoint.get("out")?;
        let out = match out {
            None => None,
            Some(v) => {
                let partial: PathBuf = serde_json::from_value(v["partial"].clone()).with_context(|| {
                    format!("the checkpoint {} has an invalid `out`", checkpoint.path.display())
                })?;
                let position: Position = serde_json::from_value(v).with_context(|| {
                    format!("the checkpoint {} has an invalid `out`", checkpoint.path.display())
                })?;
                Some((position, partial))
            }
        };
        Ok(Resumed {
            saved_run: run,
            next_checkpoint: f64_from_hex(&next)
                .with_context(|| format!("the checkpoint {} is invalid", checkpoint.path.display()))?,
            events: checkpoint.words("events")?,
            energy: checkpoint.words("energy")?,
            rows: checkpoint.words("rows")?,
            writer_rows: checkpoint.get("writer_rows")?,
            out,
            wall_s: checkpoint.get("wall_s")?,
            checkpoint,
        })
    }

    /// The error for a checkpoint that does not fit the run its arguments describe.
    pub fn mismatch(&self, what: &str) -> anyhow::Error {
        anyhow!("the checkpoint {} does not fit its run: it lacks {what}", self.checkpoint.path.display())
    }

    /// Restores the observers and the rows written, and hands back where the run paused.
    pub fn restore(&self, watch: &mut Watch<'_>) -> Result<Saved> {
        let context = || format!("the checkpoint {} does not fit its run", self.checkpoint.path.display());
        watch.events.restore_all(&self.events, "the event locator").with_context(context)?;
        watch.energy.restore_all(&self.energy, "the energy balance").with_context(context)?;
        let rows = &mut watch.rows;
        rows.restore_all(&self.rows, "the rows").with_context(context)?;
        rows.writer().rows = self.writer_rows;
        Ok(Saved { run: self.saved_run.clone(), next_checkpoint: self.next_checkpoint })
    }
}

/// A digest of the validated request, so that a checkpoint is continued only by the same
/// one (floats in Rust's shortest round-trip form: the digest changes with any bit).
pub fn fingerprint(config: &SimulateConfig, args: &SimulateArgs) -> String {
    let c = config;
    let binding = match c.method.scheme {
        pendula::integrator::Scheme::Tao(t) => Some(t.binding),
        _ => None,
    };
    let text = format!(
        "{}|{:?}|{:?}|{}|{binding:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{}",
        c.values.info().name,
        c.values.parameters().collect::<Vec<_>>(),
        c.values.initial_state(),
        c.method.name,
        c.spec,
        c.tolerances,
        c.first_step,
        c.every,
        c.out,
        c.grid,
        c.plot,
        c.checkpoint.as_ref().map(|k| k.every),
        args.events,
        args.stop_on_event,
    );
    crate::checkpoint::fingerprint(&text)
}

/// Writes the checkpoint of a run paused `at`: flushes the trajectory and records its
/// length and checksum, saves the observers, and writes the file; `partial` (the
/// trajectory) is kept with it from then on.
pub fn write(
    path: &std::path::Path,
    args: &SimulateArgs,
    fingerprint: &str,
    at: &Saved,
    watch: &mut Watch<'_>,
    partial: Option<&mut PartialFile>,
    wall_s: f64,
) -> Result<()> {
    let writer = watch.rows.writer();
    let writer_rows = writer.rows;
    let position = writer.sink.position(writer_rows)?;
    if let Some(p) = &partial {
        p.sync()?;
    }
    let out = partial.as_ref().map(|p| {
        json!({
            "partial": p.path(),
            "bytes": position.bytes,
            "rows": position.rows,
            "crc32": position.crc32,
        })
    });
    let cwd = std::env::current_dir().context("cannot read the working directory")?;
    let body = json!({
        "command": "simulate",
        "pendula": env!("CARGO_PKG_VERSION"),
        "cwd": cwd,
        "args": args,
        "fingerprint": fingerprint,
        "t": at.run.t,
        "steps": at.run.steps,
        "wall_s": wall_s,
        "next_checkpoint": hex_f64(at.next_checkpoint),
        "run": hex_words(&at.run.to_words()),
        "events": hex_words(&watch.events.snapshot()),
        "energy": hex_words(&watch.energy.snapshot()),
        "rows": hex_words(&watch.rows.snapshot()),
        "writer_rows": writer_rows,
        "out": out,
    });
    crate::checkpoint::write(path, &body, |guard| {
        if let Some(p) = partial {
            p.keep(guard);
        }
        Ok(())
    })
}
