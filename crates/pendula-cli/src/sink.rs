//! Trajectories stream to disk as CSV rows, or as .npy rows behind a fixed-size header
//! rewritten with the row count at the end ([`pendula_io::npy::Rows`]), so memory does not
//! grow with the run's length.
//!
//! Every byte written is counted and checksummed (CRC-32) on the way, so that a checkpoint
//! can record how much of the trajectory is on disk ([`Sink::position`]); a resumed run
//! ([`Sink::resume`]) checks that prefix against its checksum, cuts off what was written
//! after the checkpoint, and appends from there — the file ends byte-identical to one
//! written in one go.
//!
//! Write errors name the output ([`crate::output::OutFile`]); into a FIFO, which cannot
//! seek, .npy rows are spooled in an unnamed temporary file and follow the final header.

use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;

use anyhow::{Context, Result, bail};
use pendula_io::npy::{Rows, Tally, streamed_header_len};

use crate::config::Output;
use crate::output::{OutFile, PartialFile};

/// How much of a trajectory file is written: its length, the rows in it, and the CRC-32 of
/// its bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Position {
    /// Bytes.
    pub bytes: u64,
    /// Data rows (the CSV header is not one).
    pub rows: u64,
    /// CRC-32 of the bytes.
    pub crc32: u32,
}

/// Where trajectory rows go.
pub enum Sink {
    /// Nowhere (`--every 0`).
    Discard,
    /// CSV rows, streamed.
    Csv(Box<csv::Writer<Tally<Box<dyn Write>>>>),
    /// Rows of a 2-D float64 .npy array, streamed.
    Npy(NpyRows),
}

impl Sink {
    /// A sink for `output` with these column names; `file` is the open output file.
    pub fn new(output: Option<&Output>, file: Option<OutFile>, columns: &[&str]) -> Result<Self> {
        let writer: Box<dyn Write> = match output {
            None => return Ok(Sink::Discard),
            Some(Output::Npy(_)) => {
                let file = file.expect("a .npy output has a file");
                return Ok(Sink::Npy(NpyRows::new(file, columns.len())?));
            }
            Some(Output::Stdout) => Box::new(std::io::stdout().lock()),
            Some(Output::Csv(_)) => Box::new(file.expect("a CSV file output has a file")),
        };
        let mut csv = csv_writer(Tally::new(writer));
        csv.write_record(columns).map_err(csv_error)?;
        Ok(Sink::Csv(Box::new(csv)))
    }

    /// A sink that continues the trajectory in the `partial` file (named by its path in
    /// messages about its contents; its write errors name `--out` and the output's path) at
    /// `at`: the first `at.bytes` bytes must have the recorded checksum; what follows them
    /// (rows written after the checkpoint) is cut off. Returns the rows already there
    /// (values, row after row) when `keep_rows`, for a plot.
    pub fn resume(
        output: &Output,
        partial: &PartialFile,
        columns: usize,
        at: &Position,
        keep_rows: bool,
    ) -> Result<(Self, Option<Vec<f64>>)> {
        let mut file = partial.open()?;
        let path = partial.path();
        let length = file.metadata().with_context(|| format!("cannot read {}", path.display()))?.len();
        if length < at.bytes {
            bail!(
                "the partial trajectory {} has {length} bytes; the checkpoint recorded {}: it was cut short",
                path.display(),
                at.bytes
            );
        }
        let mut prefix = Vec::new();
        (&mut file)
            .take(at.bytes)
            .read_to_end(&mut prefix)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let mut crc = crc32fast::Hasher::new();
        crc.update(&prefix);
        if crc.clone().finalize() != at.crc32 {
            bail!(
                "the partial trajectory {} does not match its checkpoint (checksum): it was changed",
                path.display()
            );
        }
        let mut file = OutFile::new(file, "--out", partial.shown());
        file.set_len(at.bytes)?;
        file.seek(SeekFrom::End(0))?;
        let rows = if keep_rows { Some(parse_rows(output, &prefix, columns, at.rows, path)?) } else { None };
        let tally = Tally::resume(file, at.bytes, crc);
        let sink = match output {
            Output::Npy(_) => Sink::Npy(NpyRows(Rows::resume(tally, columns, at.rows))),
            Output::Csv(_) => {
                let (file, bytes, crc) = tally.into_parts();
                Sink::Csv(Box::new(csv_writer(Tally::resume(Box::new(file) as Box<dyn Write>, bytes, crc))))
            }
            Output::Stdout => unreachable!("a checkpointed trajectory is a file"),
        };
        Ok((sink, rows))
    }

    /// Writes one row.
    pub fn row(&mut self, values: impl Iterator<Item = f64>) -> Result<()> {
        match self {
            Sink::Discard => {}
            Sink::Npy(npy) => npy.row(values)?,
            Sink::Csv(w) => {
                let mut buf = ryu::Buffer::new();
                for v in values {
                    w.write_field(buf.format(v)).map_err(csv_error)?;
                }
                w.write_record(None::<&[u8]>).map_err(csv_error)?;
            }
        }
        Ok(())
    }

    /// Flushes what is written to the file and says how much that is (`rows` rows).
    pub fn position(&mut self, rows: u64) -> Result<Position> {
        let tally = match self {
            Sink::Discard => return Ok(Position { bytes: 0, rows, crc32: 0 }),
            Sink::Csv(w) => {
                w.flush()?;
                w.get_ref().written()
            }
            Sink::Npy(npy) => npy.0.position()?,
        };
        Ok(Position { bytes: tally.0, rows, crc32: tally.1 })
    }

    /// Flushes the rows; for .npy, writes the final row count into the header.
    pub fn finish(self) -> Result<()> {
        match self {
            Sink::Discard => Ok(()),
            Sink::Csv(mut w) => Ok(w.flush()?),
            Sink::Npy(npy) => npy.finish(),
        }
    }
}

fn csv_writer<W: Write>(w: W) -> csv::Writer<W> {
    csv::WriterBuilder::new().buffer_capacity(1 << 16).from_writer(w)
}

/// A CSV writer's error as the writer's own when it is one ([`crate::output::WriteError`],
/// which names the output, and is what the exit code looks for).
fn csv_error(e: csv::Error) -> anyhow::Error {
    let text = e.to_string();
    match e.into_kind() {
        csv::ErrorKind::Io(io) => io.into(),
        _ => anyhow::anyhow!(text),
    }
}

/// The data rows of a trajectory file's first bytes (its header skipped), as flat values.
fn parse_rows(output: &Output, bytes: &[u8], columns: usize, rows: u64, path: &Path) -> Result<Vec<f64>> {
    let values: Vec<f64> = match output {
        Output::Npy(_) => {
            let header = streamed_header_len(columns);
            bytes
                .get(header..)
                .unwrap_or_default()
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
                .collect()
        }
        _ => {
            let mut reader = csv::ReaderBuilder::new().has_headers(true).from_reader(bytes);
            let mut values = Vec::new();
            for record in reader.records() {
                let record = record.with_context(|| format!("cannot read the rows of {}", path.display()))?;
                for field in &record {
                    values.push(
                        field.parse().with_context(|| format!("a value `{field}` in {}", path.display()))?,
                    );
                }
            }
            values
        }
    };
    if values.len() as u64 != rows * columns as u64 {
        bail!(
            "the partial trajectory {} holds {} values; the checkpoint recorded {rows} rows",
            path.display(),
            values.len()
        );
    }
    Ok(values)
}

/// Trajectory rows as a streamed .npy array ([`pendula_io::npy::Rows`]) into the output
/// file; into a FIFO, which cannot seek, the rows are spooled in an unnamed temporary file
/// (gone with the process, however it ends).
pub struct NpyRows(Rows<OutFile>);

impl NpyRows {
    /// Starts the array in `file` (at its start).
    pub fn new(mut file: OutFile, columns: usize) -> Result<Self> {
        let spool = if file.seekable() {
            None
        } else {
            Some(
                tempfile::tempfile()
                    .context("cannot spool the .npy rows for a FIFO in the temporary directory")?,
            )
        };
        Ok(NpyRows(Rows::new(file, columns, spool)?))
    }

    /// Appends one row of `columns` values.
    pub fn row(&mut self, values: impl Iterator<Item = f64>) -> Result<()> {
        Ok(self.0.row(values)?)
    }

    /// Writes the header with the final shape.
    pub fn finish(self) -> Result<()> {
        Ok(self.0.finish()?)
    }
}
