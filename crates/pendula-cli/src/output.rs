//! Writing results: files appear whole or not at all — also when the run is interrupted by
//! SIGINT, SIGTERM or SIGHUP.
//!
//! Every [`AtomicFile`] registers its temporary path in a process-wide list while it lives;
//! the interrupt thread ([`on_interrupt`]) kills the child processes writing into those
//! files (ffmpeg), removes the files and exits with 128 + the signal's number. Registering,
//! renaming into place and cleaning up all hold the list's lock, so an interrupt sees a file
//! either before its rename (and removes it) or after (and leaves the finished file alone):
//! an existing file of the target's name is replaced whole or not at all.
//!
//! A run that writes checkpoints (`--checkpoint`) registers itself ([`Checkpointing`]): the
//! first interrupt then only sets [`pause_flag`], which the run loop polls at every step;
//! the run writes its checkpoint and ends with [`Interrupted`] (exit 128 + the signal), its
//! partial trajectory ([`PartialFile`], visible as `OUT.partial`) kept for `pendula resume`.
//! A second interrupt ends the process at once, as without checkpoints: the checkpoint on
//! disk is then the last complete one, and a partial trajectory no checkpoint refers to yet
//! is removed.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, ExitStatus};
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use anyhow::{Context, Result, bail};
use tempfile::NamedTempFile;

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

/// Whether a run that writes checkpoints is going ([`Checkpointing`]).
static CHECKPOINTING: AtomicBool = AtomicBool::new(false);
/// Set by the first interrupt during such a run: pause at the next step and checkpoint.
static PAUSE: AtomicBool = AtomicBool::new(false);
/// The signal that set [`PAUSE`].
static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// The flag a checkpointing run polls at every step (a relaxed load: nothing measurable).
pub fn pause_flag() -> &'static AtomicBool {
    &PAUSE
}

/// The signal that asked a checkpointing run to stop, if one did.
pub fn interrupted_by() -> Option<i32> {
    PAUSE.load(Ordering::SeqCst).then(|| SIGNAL.load(Ordering::SeqCst))
}

/// While it lives, the first interrupt asks the run to pause and checkpoint instead of
/// ending the process.
pub struct Checkpointing(());

impl Checkpointing {
    /// Registers the run.
    pub fn start() -> Self {
        CHECKPOINTING.store(true, Ordering::SeqCst);
        Checkpointing(())
    }
}

impl Drop for Checkpointing {
    fn drop(&mut self) {
        CHECKPOINTING.store(false, Ordering::SeqCst);
    }
}

/// The end of a run that an interrupt stopped after writing its checkpoint: exit 128 +
/// the signal, with a message saying how to continue.
#[derive(Debug)]
pub struct Interrupted {
    /// The signal's number.
    pub signal: i32,
    /// What was kept and how to continue.
    pub message: String,
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "interrupted by {}: {}", signal_name(self.signal), self.message)
    }
}

impl std::error::Error for Interrupted {}

fn signal_name(signal: i32) -> &'static str {
    use signal_hook::consts::{SIGINT, SIGTERM};
    match signal {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        _ => "SIGHUP",
    }
}

/// Starts the thread that turns SIGINT, SIGTERM and SIGHUP (the terminal closed) into a clean
/// exit: children killed, temporary files removed, exit status 130, 143 or 129 (128 + the
/// signal, as shells report it). During a checkpointing run the first signal asks the run
/// to pause and checkpoint instead ([`Checkpointing`]); a second one exits at once.
pub fn on_interrupt() -> Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])
        .context("cannot watch for interrupts")?;
    std::thread::Builder::new()
        .name("interrupt".into())
        .spawn(move || {
            // Clear a progress bar's line first when one may be drawn.
            let clear = if std::io::IsTerminal::is_terminal(&std::io::stderr()) { "\r\x1b[2K" } else { "" };
            for signal in signals.forever() {
                if CHECKPOINTING.load(Ordering::SeqCst) && !PAUSE.load(Ordering::SeqCst) {
                    SIGNAL.store(signal, Ordering::SeqCst);
                    PAUSE.store(true, Ordering::SeqCst);
                    let _ = writeln!(
                        std::io::stderr(),
                        "{clear}{}: finishing the step (or chunk) in progress to write a checkpoint (interrupt again to stop at once)",
                        signal_name(signal)
                    );
                    continue;
                }
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
                let name = signal_name(signal);
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
        Self::commit_with(files, |_| Ok(()))
    }

    /// [`AtomicFile::commit_all`], then `also` (which may keep a [`PartialFile`] or remove
    /// files), as one step for an interrupt.
    pub fn commit_with(
        files: Vec<AtomicFile>,
        also: impl FnOnce(&mut Guard<'_>) -> Result<()>,
    ) -> Result<()> {
        let mut live = live();
        for mut file in files {
            let temp = file.temp.take().expect("not yet committed");
            live.forget(temp.path());
            // On failure the error owns the temporary file, and dropping it removes it.
            temp.persist(&file.path).with_context(|| format!("cannot write {}", file.path.display()))?;
        }
        also(&mut Guard(live))
    }
}

/// The interrupt list, locked: what is done through it is one step for an interrupt.
pub struct Guard<'a>(MutexGuard<'a, Live>);

impl Guard<'_> {
    /// Takes `path` off the list: an interrupt no longer removes it.
    pub fn forget(&mut self, path: &Path) {
        self.0.forget(path);
    }

    /// Creates (or empties) `path`, which an interrupt removes until it is forgotten.
    pub fn create_listed(&mut self, path: &Path) -> std::io::Result<File> {
        let file = File::options().read(true).write(true).create(true).truncate(true).open(path)?;
        self.0.temps.push(path.to_owned());
        Ok(file)
    }
}

/// Runs `f` as one step for an interrupt.
pub fn together<R>(f: impl FnOnce(&mut Guard<'_>) -> R) -> R {
    f(&mut Guard(live()))
}

/// A trajectory written by a checkpointing run under a visible name beside its target,
/// `OUT.partial`, so that a checkpoint can refer to it and `pendula resume` continue it.
/// Until a checkpoint refers to it ([`PartialFile::keep`]) an interrupt removes it like a
/// temporary file; afterwards it stays with its checkpoint. [`PartialFile::finish`] renames
/// it into place.
#[derive(Debug)]
pub struct PartialFile {
    path: PathBuf,
    target: PathBuf,
    /// Whether it is still in the interrupt's list (no checkpoint refers to it).
    listed: bool,
}

impl PartialFile {
    /// The partial file of `target`: `target` with `.partial` appended.
    pub fn path_of(target: &Path) -> PathBuf {
        let mut name = target.as_os_str().to_owned();
        name.push(".partial");
        PathBuf::from(name)
    }

    /// Creates (or empties) the partial file of `target`; `flag` names the option for
    /// messages.
    pub fn create(target: &Path, flag: &str) -> Result<(Self, File)> {
        if target.is_dir() {
            bail!("cannot write {flag} {}: it is a directory", target.display());
        }
        let path = Self::path_of(target);
        let file = together(|guard| guard.create_listed(&path))
            .with_context(|| format!("cannot write {flag} {}", path.display()))?;
        Ok((PartialFile { path, target: target.to_owned(), listed: true }, file))
    }

    /// Opens the partial file `path` of `target` that a checkpoint refers to.
    pub fn reopen(target: &Path, path: &Path) -> Result<(Self, File)> {
        let file = File::options().read(true).write(true).open(path).with_context(|| {
            format!("cannot open the partial trajectory {} that the checkpoint refers to", path.display())
        })?;
        Ok((PartialFile { path: path.to_owned(), target: target.to_owned(), listed: false }, file))
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Takes it off the interrupt's list: a checkpoint now refers to it.
    pub fn keep(&mut self, guard: &mut Guard<'_>) {
        guard.0.forget(&self.path);
        self.listed = false;
    }

    /// Writes its contents to the disk, so that a checkpoint written next never refers to
    /// bytes that a crash could lose.
    pub fn sync(&self) -> Result<()> {
        File::open(&self.path)
            .and_then(|f| f.sync_data())
            .with_context(|| format!("cannot write {}", self.path.display()))
    }

    /// Renames the finished trajectory into place.
    pub fn finish(mut self, guard: &mut Guard<'_>) -> Result<()> {
        guard.0.forget(&self.path);
        self.listed = false;
        std::fs::rename(&self.path, &self.target)
            .with_context(|| format!("cannot write {}", self.target.display()))
    }

    /// Removes it (the run failed: nothing it wrote is of use).
    pub fn remove(mut self) {
        let mut live = live();
        live.forget(&self.path);
        self.listed = false;
        let _ = std::fs::remove_file(&self.path);
    }
}

impl Drop for PartialFile {
    fn drop(&mut self) {
        // Still listed: no checkpoint refers to it, so nothing can continue it.
        if self.listed {
            let mut live = live();
            live.forget(&self.path);
            let _ = std::fs::remove_file(&self.path);
        }
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
