//! Writing results: files appear whole or not at all, and trajectories stream as CSV or
//! collect into a .npy array.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use ndarray::Array2;
use ndarray_npy::WriteNpyExt;
use tempfile::NamedTempFile;

use crate::config::Output;

/// A file written under a temporary name in its final directory and renamed into place by
/// [`AtomicFile::commit`]; dropped uncommitted, it vanishes. Creating it checks that the
/// path can be written before any work is done.
#[derive(Debug)]
pub struct AtomicFile {
    temp: NamedTempFile,
    path: PathBuf,
}

impl AtomicFile {
    /// Creates the temporary file beside `path`; `flag` names the option for messages.
    pub fn create(path: &Path, flag: &str) -> Result<Self> {
        if path.is_dir() {
            bail!("cannot write {flag} {}: it is a directory", path.display());
        }
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let mut builder = tempfile::Builder::new();
        builder.prefix(".pendula-").suffix(".part");
        // Results are for reading: rw-r--r-- (less the umask), not the temporary file's 0600.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
        let temp =
            builder.tempfile_in(dir).with_context(|| format!("cannot write {flag} {}", path.display()))?;
        Ok(AtomicFile { temp, path: path.to_owned() })
    }

    /// A second handle on the temporary file, for streaming into it.
    pub fn handle(&self) -> Result<File> {
        self.temp.reopen().with_context(|| format!("cannot write {}", self.path.display()))
    }

    /// The temporary file's path, for external writers (ffmpeg).
    pub fn temp_path(&self) -> &Path {
        self.temp.path()
    }

    /// Renames the finished file into place.
    pub fn commit(self) -> Result<()> {
        let path = self.path;
        self.temp.persist(&path).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(())
    }
}

/// Where trajectory rows go.
pub enum Sink {
    /// Nowhere (`--every 0`).
    Discard,
    /// CSV rows, streamed.
    Csv(Box<csv::Writer<Box<dyn Write>>>),
    /// Rows collected for one .npy array of `columns` columns.
    Npy { rows: Vec<f64>, columns: usize },
}

impl Sink {
    /// A sink for `output` with these column names; `file` is the open output file.
    pub fn new(output: Option<&Output>, file: Option<&AtomicFile>, columns: &[&str]) -> Result<Self> {
        let writer: Box<dyn Write> = match output {
            None => return Ok(Sink::Discard),
            Some(Output::Npy(_)) => {
                return Ok(Sink::Npy { rows: Vec::new(), columns: columns.len() });
            }
            Some(Output::Stdout) => Box::new(std::io::stdout().lock()),
            Some(Output::Csv(_)) => Box::new(file.expect("a CSV file output has a file").handle()?),
        };
        let mut csv = csv::WriterBuilder::new().buffer_capacity(1 << 16).from_writer(writer);
        csv.write_record(columns)?;
        Ok(Sink::Csv(Box::new(csv)))
    }

    /// Writes one row.
    pub fn row(&mut self, values: impl Iterator<Item = f64>) -> Result<()> {
        match self {
            Sink::Discard => {}
            Sink::Npy { rows, .. } => rows.extend(values),
            Sink::Csv(w) => {
                let mut buf = ryu::Buffer::new();
                for v in values {
                    w.write_field(buf.format(v))?;
                }
                w.write_record(None::<&[u8]>)?;
            }
        }
        Ok(())
    }

    /// Flushes CSV, or writes the collected .npy array into `file`.
    pub fn finish(self, file: Option<&AtomicFile>) -> Result<()> {
        match self {
            Sink::Discard => {}
            Sink::Csv(mut w) => w.flush()?,
            Sink::Npy { rows, columns } => {
                let n = rows.len() / columns;
                let array = Array2::from_shape_vec((n, columns), rows).expect("rows are whole");
                let file = file.expect("a .npy output has a file").handle()?;
                let mut writer = BufWriter::new(file);
                array.write_npy(&mut writer)?;
                writer.flush()?;
            }
        }
        Ok(())
    }
}
