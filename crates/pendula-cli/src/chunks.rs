//! Grids in chunks with a checkpoint (`sweep --checkpoint`, `fractal --checkpoint`): the
//! cells are computed a chunk at a time, and each finished chunk's values are appended to
//! `FILE.chunks` beside the checkpoint FILE, which then lists the chunks done with the
//! CRC-32 of each (the files' format is [`pendula_io::chunks`]'s). An interrupt ends the run after the chunk in progress (exit 128 + the
//! signal); `pendula resume FILE` reads the finished chunks back, checks them, computes the
//! others, and writes the same bytes as a run never interrupted (a cell's result does not
//! depend on which cells are computed with it). Both files are removed when the run ends.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
pub use pendula_io::chunks::chunk_size;
use pendula_io::chunks::{Layout, data_path};
use serde_json::{Value, json};

use crate::checkpoint::Checkpoint;
use crate::output::{Guard, OutFile};

/// A chunked run's checkpoint and its values file.
pub struct Chunks {
    path: PathBuf,
    data_path: PathBuf,
    data: OutFile,
    /// What every version of the checkpoint repeats: command, arguments, fingerprint.
    base: Value,
    /// Cells in all, values per cell, cells per chunk.
    cells: usize,
    width: usize,
    chunk: usize,
    /// Chunks done, in the order their values are in the file, with their CRC-32.
    done: Vec<(usize, u32)>,
    /// Whether a checkpoint refers to the values file (else an interrupt removes it).
    listed: bool,
}

impl Chunks {
    /// Claims the checkpoint `path` and its values file as outputs of the run, before any
    /// work: regular files, neither of them another output (nor a FIFO, a device, `-`).
    pub fn claim(path: &Path) -> Result<()> {
        crate::output::claim_regular(path, "--checkpoint", "a checkpoint")?;
        crate::output::claim_regular(&data_path(path), "--checkpoint", "a checkpoint's finished chunks")?;
        Ok(())
    }

    /// Starts a chunked run of `cells` cells of `width` values each: an empty values file
    /// and a checkpoint with no chunk done. `base` is what the checkpoint repeats (command,
    /// working directory, arguments, fingerprint).
    pub fn start(path: &Path, base: Value, cells: usize, width: usize, chunk: usize) -> Result<Self> {
        if path.exists() {
            bail!(
                "invalid --checkpoint {}: it exists (from a run interrupted earlier?): continue that run with `pendula resume {}`, or remove the file to start again",
                crate::checkpoint::absolute(path).display(),
                crate::checkpoint::absolute(path).display()
            );
        }
        let data_path = data_path(path);
        let data = crate::output::together(|guard| guard.create_listed(&data_path))
            .map_err(|e| crate::output::WriteError::new("--checkpoint", &data_path, e))?;
        let data = OutFile::new(data, "--checkpoint", &data_path);
        let mut chunks = Chunks {
            path: path.to_owned(),
            data_path,
            data,
            base,
            cells,
            width,
            chunk,
            done: Vec::new(),
            listed: true,
        };
        chunks.write()?;
        Ok(chunks)
    }

    /// Continues a chunked run from its checkpoint: checks the fingerprint and the values
    /// file, fills `out` (cells × width values) with the chunks done, and says which are.
    pub fn resume(
        checkpoint: &Checkpoint,
        fingerprint: &str,
        width: usize,
        out: &mut [f64],
    ) -> Result<(Self, Vec<bool>)> {
        checkpoint.check_fingerprint(fingerprint)?;
        let name = checkpoint.path.display();
        let cells: usize = checkpoint.get("cells")?;
        let chunk: usize = checkpoint.get("chunk")?;
        let done: Vec<(usize, u32)> = checkpoint.get("done")?;
        if cells * width != out.len() || checkpoint.get::<usize>("width")? != width || chunk == 0 {
            bail!(
                "the checkpoint {name} is of another grid ({cells} cells of {width} values in chunks of {chunk})"
            );
        }
        let data_path = data_path(&checkpoint.path);
        let mut data = File::options().read(true).write(true).open(&data_path).with_context(|| {
            format!("cannot open {}, the finished chunks of the checkpoint {name}", data_path.display())
        })?;
        let layout = Layout { cells, width, chunk };
        let (finished, length) =
            pendula_io::chunks::read_done(&mut data, &layout, &done, out, &name.to_string(), &data_path)?;
        // Values appended after the checkpoint was written are computed again.
        let mut data = OutFile::new(data, "--checkpoint", &data_path);
        data.set_len(length)?;
        data.seek(SeekFrom::End(0))?;
        let base = json!({
            "command": checkpoint.field("command")?,
            "pendula": env!("CARGO_PKG_VERSION"),
            "cwd": checkpoint.field("cwd")?,
            "args": checkpoint.field("args")?,
            "fingerprint": fingerprint,
        });
        let chunks = Chunks {
            path: checkpoint.path.clone(),
            data_path,
            data,
            base,
            cells,
            width,
            chunk,
            done,
            listed: false,
        };
        Ok((chunks, finished))
    }

    /// How the grid is cut.
    fn layout(&self) -> Layout {
        Layout { cells: self.cells, width: self.width, chunk: self.chunk }
    }

    /// The number of chunks.
    pub fn count(&self) -> usize {
        self.layout().count()
    }

    /// The cells of chunk `index`.
    pub fn range(&self, index: usize) -> Range<usize> {
        self.layout().range(index)
    }

    /// Records chunk `index` as done with these values (its cells' × width): appends them,
    /// makes them durable, and rewrites the checkpoint.
    pub fn record(&mut self, index: usize, values: &[f64]) -> Result<()> {
        let (bytes, crc) = pendula_io::chunks::encode(values);
        self.data.write_all(&bytes)?;
        self.data.sync_data()?;
        self.done.push((index, crc));
        self.write()
    }

    /// Rewrites the checkpoint with the chunks done; from the first one on, the values file
    /// is kept with it.
    fn write(&mut self) -> Result<()> {
        let mut body = self.base.clone();
        let fields = pendula_io::chunks::fields(&self.layout(), &self.done);
        for (k, v) in fields.as_object().expect("an object") {
            body[k] = v.clone();
        }
        let data_path = self.data_path.clone();
        let listed = &mut self.listed;
        crate::checkpoint::write(&self.path, &body, |guard| {
            guard.forget(&data_path);
            *listed = false;
            Ok(())
        })
    }

    /// Computes the chunks not `done` in order with `compute(cells, values)` into `data`
    /// (cells × width values), recording each; stops before the next chunk when interrupted
    /// ([`crate::output::Interrupted`]; the caller registers the run with
    /// [`crate::output::Checkpointing`] before it starts). A computation that fails (a non-finite state)
    /// would fail again on resume: the checkpoint and its values are then removed.
    pub fn run(
        mut self,
        done: &[bool],
        data: &mut [f64],
        mut compute: impl FnMut(Range<usize>, &mut [f64]) -> Result<()>,
    ) -> Result<Self> {
        assert_eq!(done.len(), self.count(), "one flag per chunk");
        for (index, _) in done.iter().enumerate().filter(|(_, done)| !**done) {
            if let Some(signal) = crate::output::interrupted_by() {
                return Err(self.interrupted(signal).into());
            }
            let cells = self.range(index);
            let values = &mut data[cells.start * self.width..cells.end * self.width];
            if let Err(e) = compute(cells, values) {
                self.abandon();
                return Err(e);
            }
            self.record(index, values)?;
        }
        Ok(self)
    }

    /// The message of an interrupt: what is kept and how to continue.
    fn interrupted(&self, signal: i32) -> crate::output::Interrupted {
        crate::output::Interrupted {
            signal,
            message: format!(
                "{} of {} chunks done, kept in {} and {}; continue with `pendula resume {}`",
                self.done.len(),
                self.count(),
                crate::checkpoint::absolute(&self.path).display(),
                crate::checkpoint::absolute(&self.data_path).display(),
                crate::checkpoint::absolute(&self.path).display()
            ),
        }
    }

    /// The run is complete: removes the checkpoint and the values file (in the step that
    /// puts the outputs in place).
    pub fn finish(mut self, guard: &mut Guard<'_>) -> Result<()> {
        guard.forget(&self.data_path);
        self.listed = false;
        crate::checkpoint::remove(&self.path)?;
        crate::checkpoint::remove(&self.data_path)
    }

    /// The run failed: removes both, since continuing would fail the same way.
    pub fn abandon(mut self) {
        crate::output::together(|guard| guard.forget(&self.data_path));
        self.listed = false;
        let _ = std::fs::remove_file(&self.path);
        let _ = std::fs::remove_file(&self.data_path);
    }
}

impl Drop for Chunks {
    /// A values file that no checkpoint refers to yet (the first checkpoint could not be
    /// written: a full disk) is of no use: removed, as an interrupt would.
    fn drop(&mut self) {
        if self.listed {
            crate::output::together(|guard| guard.forget(&self.data_path));
            let _ = std::fs::remove_file(&self.data_path);
        }
    }
}
