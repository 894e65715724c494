//! Writing results: files appear whole or not at all — also when the run is interrupted by
//! SIGINT, SIGTERM or SIGHUP — and trajectories stream to disk as CSV or .npy, so memory does not
//! grow with the run's length.
//!
//! Every [`AtomicFile`] registers its temporary path in a process-wide list while it lives;
//! the interrupt thread ([`on_interrupt`]) kills the child processes writing into those
//! files (ffmpeg), removes the files and exits with 128 + the signal's number. Registering,
//! renaming into place and cleaning up all hold the list's lock, so an interrupt sees a file
//! either before its rename (and removes it) or after (and leaves the finished file alone):
//! an existing file of the target's name is replaced whole or not at all.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, ExitStatus};
use std::sync::{Mutex, MutexGuard, PoisonError};

use anyhow::{Context, Result, bail};
use tempfile::NamedTempFile;

use crate::config::Output;

/// What an interrupt must clean up.
struct Live {
    /// Temporary files not yet renamed into place.
    temps: Vec<PathBuf>,
    /// Child processes writing into them, with the ids handed out for them.
    children: Vec<(u64, Child)>,
    next_child: u64,
}

static LIVE: Mutex<Live> = Mutex::new(Live { temps: Vec::new(), children: Vec::new(), next_child: 0 });

/// The list, also after a thread panicked holding it (the list itself is always whole).
fn live() -> MutexGuard<'static, Live> {
    LIVE.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Live {
    fn forget(&mut self, path: &Path) {
        self.temps.retain(|p| p != path);
    }
}

/// Starts the thread that turns SIGINT, SIGTERM and SIGHUP (the terminal closed) into a clean
/// exit: children killed, temporary files removed, exit status 130, 143 or 129 (128 + the
/// signal, as shells report it).
pub fn on_interrupt() -> Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])
        .context("cannot watch for interrupts")?;
    std::thread::Builder::new()
        .name("interrupt".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                // Held until the process ends: no file is created or renamed after this.
                let mut live = live();
                for (_, child) in &mut live.children {
                    // Killed and reaped first, so that it cannot recreate a file removed below.
                    let _ = child.kill();
                    let _ = child.wait();
                }
                for path in &live.temps {
                    let _ = std::fs::remove_file(path);
                }
                let name = match signal {
                    SIGINT => "SIGINT",
                    SIGTERM => "SIGTERM",
                    _ => "SIGHUP",
                };
                // Clear a progress bar's line first when one may be drawn.
                let clear =
                    if std::io::IsTerminal::is_terminal(&std::io::stderr()) { "\r\x1b[2K" } else { "" };
                let _ = writeln!(std::io::stderr(), "{clear}interrupted by {name}: unfinished files removed");
                std::process::exit(128 + signal);
            }
        })
        .context("cannot start the interrupt thread")?;
    Ok(())
}

/// A child process that an interrupt kills (ffmpeg writing into an [`AtomicFile`]); dropped
/// before it ends (the caller failed), it is killed too.
pub struct WatchedChild(u64);

impl WatchedChild {
    /// Spawns `command` and hands back its stdin (if piped); spawning and registering are one
    /// step for the interrupt thread.
    pub fn spawn(command: &mut Command) -> std::io::Result<(Self, Option<ChildStdin>)> {
        let mut live = live();
        let mut child = command.spawn()?;
        let stdin = child.stdin.take();
        let id = live.next_child;
        live.next_child += 1;
        live.children.push((id, child));
        Ok((WatchedChild(id), stdin))
    }

    /// Waits for the child to end (polling, so that an interrupt can still kill it).
    pub fn wait(self) -> std::io::Result<ExitStatus> {
        loop {
            {
                let mut live = live();
                let k = live.children.iter().position(|(id, _)| *id == self.0).expect("registered");
                if let Some(status) = live.children[k].1.try_wait()? {
                    live.children.remove(k);
                    return Ok(status);
                }
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }
}

impl Drop for WatchedChild {
    fn drop(&mut self) {
        let mut live = live();
        if let Some(k) = live.children.iter().position(|(id, _)| *id == self.0) {
            let (_, mut child) = live.children.remove(k);
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// A file written under a temporary name in its final directory and renamed into place by
/// [`AtomicFile::commit`]; dropped uncommitted, or interrupted, it vanishes. Creating it
/// checks that the path can be written before any work is done.
#[derive(Debug)]
pub struct AtomicFile {
    /// `None` once committed.
    temp: Option<NamedTempFile>,
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
        // Created and registered under the lock: an interrupt cannot fall between the two.
        let mut live = live();
        let temp =
            builder.tempfile_in(dir).with_context(|| format!("cannot write {flag} {}", path.display()))?;
        live.temps.push(temp.path().to_owned());
        Ok(AtomicFile { temp: Some(temp), path: path.to_owned() })
    }

    fn temp(&self) -> &NamedTempFile {
        self.temp.as_ref().expect("not yet committed")
    }

    /// A second handle on the temporary file, for streaming into it.
    pub fn handle(&self) -> Result<File> {
        self.temp().reopen().with_context(|| format!("cannot write {}", self.path.display()))
    }

    /// The temporary file's path, for external writers (ffmpeg).
    pub fn temp_path(&self) -> &Path {
        self.temp().path()
    }

    /// The path it will have.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Renames the finished file into place.
    pub fn commit(self) -> Result<()> {
        Self::commit_all(vec![self])
    }

    /// Renames several finished files into place as one step for an interrupt: all of them
    /// or none.
    pub fn commit_all(files: Vec<AtomicFile>) -> Result<()> {
        let mut live = live();
        for mut file in files {
            let temp = file.temp.take().expect("not yet committed");
            live.forget(temp.path());
            // On failure the error owns the temporary file, and dropping it removes it.
            temp.persist(&file.path).with_context(|| format!("cannot write {}", file.path.display()))?;
        }
        Ok(())
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            let mut live = live();
            live.forget(temp.path());
            drop(temp);
        }
    }
}

/// Where trajectory rows go.
pub enum Sink {
    /// Nowhere (`--every 0`).
    Discard,
    /// CSV rows, streamed.
    Csv(Box<csv::Writer<Box<dyn Write>>>),
    /// Rows of a 2-D float64 .npy array, streamed.
    Npy(NpyRows),
}

impl Sink {
    /// A sink for `output` with these column names; `file` is the open output file.
    pub fn new(output: Option<&Output>, file: Option<&AtomicFile>, columns: &[&str]) -> Result<Self> {
        let writer: Box<dyn Write> = match output {
            None => return Ok(Sink::Discard),
            Some(Output::Npy(_)) => {
                let file = file.expect("a .npy output has a file").handle()?;
                return Ok(Sink::Npy(NpyRows::new(file, columns.len())?));
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
            Sink::Npy(npy) => npy.row(values)?,
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

    /// Flushes the rows; for .npy, writes the final row count into the header.
    pub fn finish(self) -> Result<()> {
        match self {
            Sink::Discard => Ok(()),
            Sink::Csv(mut w) => Ok(w.flush()?),
            Sink::Npy(npy) => npy.finish(),
        }
    }
}

/// A 2-D little-endian float64 array in NPY format 1.0, streamed row by row: the header is
/// written first with room for any row count, and rewritten with the real one at the end.
pub struct NpyRows {
    out: BufWriter<File>,
    columns: usize,
    rows: u64,
    header_len: usize,
}

impl NpyRows {
    /// Starts the array in `file` (at its start).
    pub fn new(file: File, columns: usize) -> Result<Self> {
        // The header's size for the longest row count; every header is padded to it.
        let header_len = npy_header(u64::MAX, columns, 0).len();
        let mut out = BufWriter::with_capacity(1 << 16, file);
        out.write_all(&npy_header(0, columns, header_len))?;
        Ok(NpyRows { out, columns, rows: 0, header_len })
    }

    /// Appends one row of `columns` values.
    pub fn row(&mut self, values: impl Iterator<Item = f64>) -> Result<()> {
        let mut n = 0;
        for v in values {
            self.out.write_all(&v.to_le_bytes())?;
            n += 1;
        }
        debug_assert_eq!(n, self.columns, "a row has one value per column");
        self.rows += 1;
        Ok(())
    }

    /// Writes the header with the final shape.
    pub fn finish(self) -> Result<()> {
        let mut file = self.out.into_inner().map_err(|e| e.into_error())?;
        file.seek(SeekFrom::Start(0))?;
        file.write_all(&npy_header(self.rows, self.columns, self.header_len))?;
        file.flush()?;
        Ok(())
    }
}

/// The NPY 1.0 header of a C-order float64 array of shape (rows, columns): magic, version,
/// the length, and the dictionary padded with spaces and a newline so that the whole header
/// is `min_len` bytes or the next multiple of 64 (the format's alignment).
fn npy_header(rows: u64, columns: usize, min_len: usize) -> Vec<u8> {
    let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {columns}), }}");
    // 6 bytes of magic, 2 of version, 2 of length, the dictionary and its newline.
    let unpadded = 10 + dict.len() + 1;
    let total = unpadded.div_ceil(64).max(1) * 64;
    let total = total.max(min_len);
    let mut header = Vec::with_capacity(total);
    header.extend_from_slice(b"\x93NUMPY\x01\x00");
    header.extend_from_slice(&u16::try_from(total - 10).expect("a short header").to_le_bytes());
    header.extend_from_slice(dict.as_bytes());
    header.resize(total - 1, b' ');
    header.push(b'\n');
    header
}

#[cfg(test)]
mod tests {
    use super::npy_header;

    #[test]
    fn npy_headers_are_aligned_and_of_one_length() {
        let long = npy_header(u64::MAX, 6, 0).len();
        assert_eq!(long % 64, 0);
        let short = npy_header(3, 6, long);
        assert_eq!(short.len(), long);
        assert_eq!(&short[..8], b"\x93NUMPY\x01\x00");
        assert_eq!(usize::from(u16::from_le_bytes([short[8], short[9]])), long - 10);
        assert!(short.ends_with(b" \n"));
    }
}
