//! Writing results, through one writer: every output of every command is an [`AtomicFile`]
//! (or stdout, where a command takes `-`).
//!
//! - A regular file, new or existing, is written under a temporary name in its directory and
//!   renamed into place when the run has succeeded: it appears whole or not at all, also when
//!   the run fails, the disk fills up, or SIGINT, SIGTERM or SIGHUP interrupts it, and an
//!   existing file of that name is replaced whole or left as it was. A symlink is followed:
//!   its target is what gets replaced.
//! - A path that exists and is neither a regular file nor a directory (a FIFO, a device) is
//!   written in place, never replaced (a socket is refused); a FIFO blocks until it has a
//!   reader, as a shell's redirection does.
//! - A directory where a file is expected, `-` where a command does not take it, and two
//!   outputs of one run that are the same file (the same device and inode where it exists,
//!   the same directory and name otherwise; a character device such as /dev/null may take
//!   several) are refused before any work: every output is *claimed* in the run's list of
//!   outputs ([`scope`]), as are a study directory's names ([`claim_dir`]) and the inputs that
//!   a command must not overwrite ([`claim_input`]).
//! - A failed write (a full disk) is a [`WriteError`]: it names the option and the path the
//!   user gave — never the temporary name — with the operating system's reason.
//!
//! Every temporary file and every directory created for a run is in a process-wide list
//! while it lives; the interrupt thread ([`on_interrupt`]) kills the child processes writing
//! into those files (ffmpeg), removes the files and the directories left empty, and exits
//! with 128 + the signal's number. Registering, renaming into place and cleaning up all hold
//! the list's lock, so an interrupt sees a file either before its rename (and removes it) or
//! after (and leaves the finished file alone). Trajectories stream to disk as CSV or .npy
//! ([`crate::sink`]), so memory does not grow with the run's length.
//!
//! A run that writes checkpoints (`--checkpoint`) registers itself ([`Checkpointing`]): the
//! first interrupt then only sets [`pause_flag`], which the run loop polls at every step;
//! the run writes its checkpoint and ends with [`Interrupted`] (exit 128 + the signal), its
//! partial trajectory ([`PartialFile`], visible as `OUT.partial`) kept for `pendula resume`.
//! A second interrupt ends the process at once, as without checkpoints: the checkpoint on
//! disk is then the last complete one, and a partial trajectory no checkpoint refers to yet
//! is removed. The checkpoint, the partial trajectory and a grid's `FILE.chunks` are claimed
//! like every other output ([`claim_regular`]): they must be regular files, and none of them
//! may be another output of the run.

use std::ffi::OsString;
use std::fs::{File, OpenOptions};
use std::io::{self, Seek, SeekFrom, Write};
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, ExitStatus};
use std::sync::atomic::{AtomicBool, AtomicI32, AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use anyhow::{Context, Result, bail};

/// What an interrupt must clean up.
struct Live {
    /// Temporary files not yet renamed into place.
    temps: Vec<PathBuf>,
    /// Directories created for outputs and not yet known to be kept, outermost first.
    dirs: Vec<PathBuf>,
    /// Child processes writing into them, with the ids handed out for them.
    children: Vec<(u64, Child)>,
    next_child: u64,
}

static LIVE: Mutex<Live> =
    Mutex::new(Live { temps: Vec::new(), dirs: Vec::new(), children: Vec::new(), next_child: 0 });

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
/// exit: children killed, temporary files and the directories created for them removed, exit
/// status 130, 143 or 129 (128 + the signal, as shells report it). During a checkpointing run
/// the first signal asks the run to pause and checkpoint instead ([`Checkpointing`]); a
/// second one exits at once.
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
                // Innermost first; a directory that holds anything stays.
                for dir in live.dirs.iter().rev() {
                    let _ = std::fs::remove_dir(dir);
                }
                let name = signal_name(signal);
                // Only when there were any: `pendula serve` writes none.
                let removed = if live.temps.is_empty() { "" } else { ": unfinished files removed" };
                let _ = writeln!(std::io::stderr(), "{clear}interrupted by {name}{removed}");
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

/// A row of the trajectory that could not be written: the sink's error, as the cause of the
/// run's `pendula::Error::Observer`. A type of its own, so that [`WriteError::find`] can
/// reach the write that failed through it (an `anyhow::Error` made into a boxed error hides
/// its own type).
#[derive(Debug)]
pub(crate) struct RowFailure(pub(crate) anyhow::Error);

impl std::fmt::Display for RowFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for RowFailure {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

/// A write that failed, named by the option and the path the user gave (never the temporary
/// file's name), with the operating system's reason: `cannot write --out big.csv: No space
/// left on device (os error 28)`. Its message is whole: it has no source.
#[derive(Debug)]
pub struct WriteError {
    flag: String,
    path: PathBuf,
    source: io::Error,
}

impl WriteError {
    /// The failed write of `path`, the output of option `flag`.
    pub fn new(flag: &str, path: &Path, source: io::Error) -> Self {
        WriteError { flag: flag.to_owned(), path: path.to_owned(), source: bare(source) }
    }

    /// Whether the environment failed rather than the request: a full disk, a quota, a
    /// file-size limit, an I/O error (exit 1, not 2).
    pub fn environment(&self) -> bool {
        matches!(
            self.source.kind(),
            io::ErrorKind::StorageFull | io::ErrorKind::QuotaExceeded | io::ErrorKind::FileTooLarge
        ) || self.source.raw_os_error() == Some(EIO)
    }

    /// The write error in `err`'s chain, if any (also inside an `io::Error`, or a trajectory
    /// row that could not be written, which ended the run).
    pub fn find(err: &anyhow::Error) -> Option<&WriteError> {
        err.chain().find_map(|e| {
            e.downcast_ref::<WriteError>()
                .or_else(|| {
                    e.downcast_ref::<io::Error>().and_then(|io| io.get_ref()?.downcast_ref::<WriteError>())
                })
                .or_else(|| e.downcast_ref::<RowFailure>().and_then(|row| WriteError::find(&row.0)))
        })
    }

    /// The operating system's error.
    pub fn os_error(&self) -> &io::Error {
        &self.source
    }

    fn into_io(self) -> io::Error {
        io::Error::new(self.source.kind(), self)
    }
}

/// Linux's EIO.
const EIO: i32 = 5;
/// Linux's ELOOP.
const ELOOP: i32 = 40;

impl std::fmt::Display for WriteError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot write {} {}: {}", self.flag, self.path.display(), self.source)
    }
}

impl std::error::Error for WriteError {}

/// The operating system's error alone: an error already naming the user's path is kept, and
/// any other wrapper (which could name a temporary file) is dropped for its OS error.
fn bare(e: io::Error) -> io::Error {
    if e.raw_os_error().is_some() || e.get_ref().is_some_and(|r| r.is::<WriteError>()) {
        return e;
    }
    let mut inner: Option<&(dyn std::error::Error + 'static)> =
        e.get_ref().map(|r| r as &(dyn std::error::Error + 'static));
    while let Some(err) = inner {
        if let Some(code) = err.downcast_ref::<io::Error>().and_then(io::Error::raw_os_error) {
            return io::Error::from_raw_os_error(code);
        }
        inner = err.source();
    }
    e
}

/// `path`'s directory (`.` for a bare name).
fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    }
}

/// Where an output goes.
struct Resolved {
    /// The file to replace or create (a symlink's target), or the node to write in place.
    target: PathBuf,
    /// For a node written in place, what it is.
    special: Option<&'static str>,
}

/// Resolves the output `path` given to `flag`, refusing what cannot take a file.
fn resolve(path: &Path, flag: &str) -> Result<Resolved> {
    if path == Path::new("-") {
        bail!("invalid {flag} -: this output cannot go to stdout; give a file name");
    }
    if path.as_os_str().is_empty() {
        bail!("invalid {flag}: the path is empty; give a file name");
    }
    if path.as_os_str().as_bytes().ends_with(b"/") || path.file_name().is_none() {
        bail!("invalid {flag} {}: it names a directory; give a file name", path.display());
    }
    let wrap = |e: io::Error| anyhow::Error::new(WriteError::new(flag, path, e));
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => {
            bail!("cannot write {flag} {}: it is a directory; give a file name", path.display())
        }
        Ok(m) if m.is_file() => {
            Ok(Resolved { target: std::fs::canonicalize(path).map_err(wrap)?, special: None })
        }
        Ok(m) => {
            let t = m.file_type();
            let kind = if t.is_fifo() {
                "FIFO"
            } else if t.is_char_device() {
                "character device"
            } else if t.is_block_device() {
                "block device"
            } else if t.is_socket() {
                bail!(
                    "cannot write {flag} {}: it is a socket, which takes no file; give a file, a FIFO or a device",
                    path.display()
                )
            } else {
                "special file"
            };
            Ok(Resolved { target: path.to_owned(), special: Some(kind) })
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            // A new file, or a dangling symlink: then its target is created.
            let target = follow(path).map_err(wrap)?;
            let dir = parent_of(&target);
            match std::fs::metadata(&dir) {
                Ok(m) if m.is_dir() => Ok(Resolved { target, special: None }),
                Ok(_) => {
                    bail!("cannot write {flag} {}: {} is not a directory", path.display(), dir.display())
                }
                Err(e) if e.kind() == io::ErrorKind::NotFound => {
                    bail!(
                        "cannot write {flag} {}: the directory {} does not exist",
                        path.display(),
                        dir.display()
                    )
                }
                Err(e) => Err(wrap(e)),
            }
        }
        Err(e) => Err(wrap(e)),
    }
}

/// Whether `path` (a symlink followed) is a FIFO, a device or a socket: neither a regular
/// file nor a directory, and written in place.
pub fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// The end of the chain of symlinks at `path` (the path itself when it is none).
fn follow(path: &Path) -> io::Result<PathBuf> {
    let mut p = path.to_owned();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&p)?;
                p = if link.is_absolute() { link } else { parent_of(&p).join(link) };
            }
            _ => return Ok(p),
        }
    }
    Err(io::Error::from_raw_os_error(ELOOP))
}

/// Which file a path is, for telling two outputs apart.
#[derive(Debug, Clone)]
struct Place {
    /// Device and inode of the file, where it exists.
    node: Option<(u64, u64)>,
    /// Device and inode of its directory, and its name there.
    dir: (u64, u64),
    name: OsString,
    /// A character device (/dev/null): several outputs may share it.
    shared: bool,
}

impl Place {
    fn of(target: &Path) -> io::Result<Place> {
        let meta = std::fs::metadata(target).ok();
        let dir = std::fs::metadata(parent_of(target))?;
        Ok(Place {
            node: meta.as_ref().map(|m| (m.dev(), m.ino())),
            dir: (dir.dev(), dir.ino()),
            name: target.file_name().map(OsString::from).unwrap_or_default(),
            shared: meta.is_some_and(|m| m.file_type().is_char_device()),
        })
    }

    fn same(&self, other: &Place) -> bool {
        (self.node.is_some() && self.node == other.node) || (self.dir == other.dir && self.name == other.name)
    }
}

/// What an output or input of the run holds.
enum Held {
    /// An output file; `owner`: the study directory it belongs to.
    File { place: Place, owner: Option<u64> },
    /// A file the run reads and must not overwrite.
    Input(Place),
    /// A study directory and the names its command writes there (`*` stands for any text).
    Dir { dir: (u64, u64), names: Vec<String>, id: u64, command: String },
    /// Standard output.
    Stdout,
}

struct Claim {
    held: Held,
    flag: String,
    path: PathBuf,
}

/// The claims of the runs in progress: one list per [`scope`] (`report` runs commands inside
/// its own).
static CLAIMS: Mutex<Vec<Vec<Claim>>> = Mutex::new(Vec::new());
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// Opens a fresh list of the outputs of one run, closed when the guard is dropped.
#[must_use = "the run's outputs are claimed while the guard lives"]
pub fn scope() -> Scope {
    CLAIMS.lock().unwrap_or_else(PoisonError::into_inner).push(Vec::new());
    Scope(())
}

/// The guard of [`scope`].
pub struct Scope(());

impl Drop for Scope {
    fn drop(&mut self) {
        CLAIMS.lock().unwrap_or_else(PoisonError::into_inner).pop();
    }
}

/// Whether `name` is one of `names` (`*` in a name stands for any text).
pub(crate) fn matches<S: AsRef<str>>(names: &[S], name: &std::ffi::OsStr) -> bool {
    let Some(name) = name.to_str() else { return false };
    names.iter().any(|n| match n.as_ref().split_once('*') {
        Some((pre, post)) => {
            name.len() >= pre.len() + post.len() && name.starts_with(pre) && name.ends_with(post)
        }
        None => name == n.as_ref(),
    })
}

/// Why `new` cannot be claimed beside `old`, if it cannot.
fn conflict(old: &Claim, new: &Claim) -> Option<String> {
    let (a, b) = (old, new);
    let same_file = || {
        format!(
            "{} {} and {} {} are the same file: one would overwrite the other; give them different paths",
            b.flag,
            b.path.display(),
            a.flag,
            a.path.display()
        )
    };
    let input = |output: &Claim, input: &Claim| {
        format!(
            "{} {} is the {} {}: writing it would destroy it; give another path",
            output.flag,
            output.path.display(),
            input.flag,
            input.path.display()
        )
    };
    let in_dir = |file: &Claim, dir: &Claim, command: &str| {
        format!(
            "{} {} is one of the files that {command} writes in {} {}: one would overwrite the other; give another name or directory",
            file.flag,
            file.path.display(),
            dir.flag,
            dir.path.display()
        )
    };
    match (&a.held, &b.held) {
        (Held::Stdout, Held::Stdout) => {
            Some(format!("{} - and {} - would both write to stdout: give one of them a file", a.flag, b.flag))
        }
        // A study directory's own file written twice: the later one wins.
        (Held::File { owner: Some(x), .. }, Held::File { owner: Some(y), .. }) if x == y => None,
        (Held::File { place: p, .. }, Held::File { place: q, .. }) => {
            (p.same(q) && !(p.shared && q.shared)).then(same_file)
        }
        (Held::Input(p), Held::File { place: q, .. }) => (p.same(q) && !q.shared).then(|| input(b, a)),
        (Held::File { place: p, .. }, Held::Input(q)) => (p.same(q) && !p.shared).then(|| input(a, b)),
        (Held::Dir { dir, names, id, command }, Held::File { place, owner })
        | (Held::File { place, owner }, Held::Dir { dir, names, id, command }) => {
            let file = if matches!(a.held, Held::File { .. }) { a } else { b };
            let dir_claim = if matches!(a.held, Held::Dir { .. }) { a } else { b };
            (*owner != Some(*id) && place.dir == *dir && matches(names, &place.name))
                .then(|| in_dir(file, dir_claim, command))
        }
        (Held::Dir { dir: d, .. }, Held::Dir { dir: e, .. }) => (d == e).then(|| {
            format!(
                "{} {} and {} {} are the same directory",
                b.flag,
                b.path.display(),
                a.flag,
                a.path.display()
            )
        }),
        _ => None,
    }
}

/// Every first change a run makes outside itself passes here: a claim in the run's list of
/// outputs, a directory or a temporary file created. Everything a command checks before its
/// first output has been checked by then, and nothing written. A thread may stop its command
/// here ([`validate_only`]): the fuzz harness (`tests/fuzz/`, which calls the library target)
/// so validates millions of generated requests without running them. The binary never sets
/// it: one thread-local read per output.
fn first_change() -> Result<()> {
    if VALIDATE_ONLY.get() {
        return Err(Validated.into());
    }
    Ok(())
}

thread_local! {
    static VALIDATE_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Stops this thread's commands at their first output ([`first_change`]) with [`Validated`]
/// (`on`), or lets them run (`!on`). Tests only.
pub fn validate_only(on: bool) {
    VALIDATE_ONLY.set(on);
}

/// The error of a command stopped by [`validate_only`]: its input was accepted.
#[derive(Debug)]
pub struct Validated;

impl std::fmt::Display for Validated {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("validated; stopped before the first output")
    }
}

impl std::error::Error for Validated {}

/// Adds `claim` to the current run's list, or says why it collides with one there.
fn claim(claim: Claim) -> Result<()> {
    first_change()?;
    let mut claims = CLAIMS.lock().unwrap_or_else(PoisonError::into_inner);
    if claims.is_empty() {
        claims.push(Vec::new());
    }
    let list = claims.last_mut().expect("a list");
    if let Some(why) = list.iter().find_map(|old| conflict(old, &claim)) {
        bail!(why);
    }
    list.push(claim);
    Ok(())
}

/// Claims stdout for `flag` (`-`): a second output on stdout is refused.
pub fn claim_stdout(flag: &str) -> Result<()> {
    claim(Claim { held: Held::Stdout, flag: flag.to_owned(), path: PathBuf::from("-") })
}

/// Claims `path` as an input that no output of the run may overwrite; `what` names it in
/// messages ("input shard"). A path that does not exist is left to the reader to report.
pub fn claim_input(path: &Path, what: &str) -> Result<()> {
    let Ok(place) = Place::of(path) else { return Ok(()) };
    if place.node.is_none() {
        return Ok(());
    }
    claim(Claim { held: Held::Input(place), flag: what.to_owned(), path: path.to_owned() })
}

/// Claims the study directory `dir` (`flag` names it) and the `names` that `command` writes
/// there; files of the directory's own are created with the returned id
/// ([`AtomicFile::create_in`]).
pub fn claim_dir(dir: &Path, flag: &str, command: &str, names: Vec<String>) -> Result<u64> {
    let meta = std::fs::metadata(dir).map_err(|e| WriteError::new(flag, dir, e))?;
    let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
    claim(Claim {
        held: Held::Dir { dir: (meta.dev(), meta.ino()), names, id, command: command.to_owned() },
        flag: flag.to_owned(),
        path: dir.to_owned(),
    })?;
    Ok(id)
}

/// Whether `path` is claimed by an output of the run other than the directory `owner`'s
/// (a study directory does not remove such a file as stale).
pub fn claimed_by_another(path: &Path, owner: u64) -> bool {
    let Ok(place) = Place::of(path) else { return false };
    let claims = CLAIMS.lock().unwrap_or_else(PoisonError::into_inner);
    claims.last().is_some_and(|list| {
        list.iter().any(|c| match &c.held {
            Held::File { place: p, owner: o } => *o != Some(owner) && p.same(&place),
            Held::Input(p) => p.same(&place),
            _ => false,
        })
    })
}

/// A name for a temporary file that no other process picks: random, from the standard
/// library's per-process random hash keys, the process id and a counter.
fn temp_name() -> String {
    use std::hash::{BuildHasher, Hasher};
    static COUNT: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u32(std::process::id());
    h.write_u64(COUNT.fetch_add(1, Ordering::Relaxed));
    format!(".pendula-{:016x}.part", h.finish())
}

/// Checks that the directory `dir` (of option `flag`) takes new files, before any work: a
/// temporary file is created there and removed at once.
pub fn probe(dir: &Path, flag: &str) -> Result<()> {
    first_change()?;
    let temp = dir.join(temp_name());
    let mut live = live();
    OpenOptions::new().write(true).create_new(true).open(&temp).map_err(|e| WriteError::new(flag, dir, e))?;
    live.temps.push(temp.clone());
    let _ = std::fs::remove_file(&temp);
    live.forget(&temp);
    Ok(())
}

/// Directories created for a run's outputs: removed again, if still empty, unless the run
/// keeps them ([`CreatedDirs::keep`]) — also by the interrupt thread — so that a refused or
/// failed run leaves no empty directory behind.
#[derive(Debug)]
pub struct CreatedDirs {
    /// Outermost first.
    dirs: Vec<PathBuf>,
}

impl CreatedDirs {
    /// Creates `path` and its missing parents (`flag` names it in messages).
    pub fn create(path: &Path, flag: &str) -> Result<Self> {
        if path == Path::new("-") {
            bail!("invalid {flag} -: a directory of files cannot go to stdout; give a directory");
        }
        let mut missing = Vec::new();
        let mut p = path;
        while !p.as_os_str().is_empty() && std::fs::symlink_metadata(p).is_err() {
            missing.push(p.to_owned());
            match p.parent() {
                Some(q) => p = q,
                None => break,
            }
        }
        missing.reverse();
        first_change()?;
        let mut live = live();
        live.dirs.extend(missing.iter().cloned());
        let created = CreatedDirs { dirs: missing };
        if let Err(e) = std::fs::create_dir_all(path) {
            drop(live);
            return Err(WriteError::new(flag, path, e).into());
        }
        Ok(created)
    }

    /// Keeps the directories (the run wrote its files).
    pub fn keep(mut self) {
        let dirs = std::mem::take(&mut self.dirs);
        live().dirs.retain(|d| !dirs.contains(d));
    }
}

impl Drop for CreatedDirs {
    fn drop(&mut self) {
        if self.dirs.is_empty() {
            return;
        }
        let mut live = live();
        for dir in self.dirs.iter().rev() {
            let _ = std::fs::remove_dir(dir);
        }
        live.dirs.retain(|d| !self.dirs.contains(d));
    }
}

/// An output file: a regular file written under a temporary name in its final directory and
/// renamed into place by [`AtomicFile::commit`] (dropped uncommitted, or interrupted, it
/// vanishes), or a FIFO or device written in place. Creating it resolves and checks the path
/// and claims it in the run's list of outputs, before any work is done.
#[derive(Debug)]
pub struct AtomicFile {
    /// The option, for messages.
    flag: String,
    /// The path as the user gave it, for messages.
    path: PathBuf,
    /// Where the file goes: the regular file to create or replace, or the node written in
    /// place.
    target: PathBuf,
    /// The open file (the temporary one, or the device); `None` for a FIFO (opened by each
    /// handle) and once committed.
    file: Option<File>,
    /// The temporary file, for a regular file until it is renamed onto `target`.
    temp: Option<PathBuf>,
}

impl AtomicFile {
    /// The output `path` of option `flag`.
    pub fn create(path: &Path, flag: &str) -> Result<Self> {
        Self::create_in(path, flag, None)
    }

    /// The output `path` of option `flag`; `owner`: the id of the study directory it belongs
    /// to ([`claim_dir`]), whose names it may take.
    pub fn create_in(path: &Path, flag: &str, owner: Option<u64>) -> Result<Self> {
        let resolved = resolve(path, flag)?;
        let place = Place::of(&resolved.target).map_err(|e| WriteError::new(flag, path, e))?;
        claim(Claim { held: Held::File { place, owner }, flag: flag.to_owned(), path: path.to_owned() })?;
        Self::open(path, flag, resolved)
    }

    /// A new version of the regular file `path`, which the run claimed with
    /// [`claim_regular`] (a checkpoint, rewritten at every pause): written under a temporary
    /// name and renamed into place as [`AtomicFile::create`]'s, without claiming it again.
    pub fn recreate(path: &Path, flag: &str) -> Result<Self> {
        let resolved = resolve(path, flag)?;
        if let Some(kind) = resolved.special {
            bail!("cannot write {flag} {}: it is a {kind} now; give a regular file", path.display());
        }
        Self::open(path, flag, resolved)
    }

    /// Opens the resolved output `path` of `flag`.
    fn open(path: &Path, flag: &str, Resolved { target, special }: Resolved) -> Result<Self> {
        let wrap = |e: io::Error| anyhow::Error::new(WriteError::new(flag, path, e));
        if let Some(kind) = special {
            // In place. A FIFO is opened when it is written, where it waits for its reader:
            // every other output is claimed before that. A device is opened now, so that
            // one that cannot be written fails before the work.
            let file = match kind {
                "FIFO" => None,
                _ => Some(OpenOptions::new().write(true).open(&target).map_err(wrap)?),
            };
            return Ok(AtomicFile { flag: flag.to_owned(), path: path.to_owned(), target, file, temp: None });
        }
        let dir = parent_of(&target);
        // Results are for reading: rw-r--r-- (less the umask), or an existing file's mode.
        let mode = std::fs::metadata(&target).map_or(0o644, |m| m.permissions().mode() & 0o7777);
        // Created and registered under the lock: an interrupt cannot fall between the two.
        let mut live = live();
        let mut attempts = 0;
        let (file, temp) = loop {
            let temp = dir.join(temp_name());
            match OpenOptions::new().read(true).write(true).create_new(true).mode(mode).open(&temp) {
                Ok(file) => break (file, temp),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && attempts < 100 => attempts += 1,
                Err(e) => return Err(wrap(e)),
            }
        };
        live.temps.push(temp.clone());
        Ok(AtomicFile {
            flag: flag.to_owned(),
            path: path.to_owned(),
            target,
            file: Some(file),
            temp: Some(temp),
        })
    }

    /// A handle on the file, for writing into it; its errors name the output.
    pub fn handle(&self) -> Result<OutFile> {
        let file = match &self.file {
            Some(file) => file.try_clone(),
            None => OpenOptions::new().write(true).open(&self.target),
        }
        .map_err(|e| WriteError::new(&self.flag, &self.path, e))?;
        Ok(OutFile { file, flag: self.flag.clone(), path: self.path.clone() })
    }

    /// Writes `bytes` into the file.
    pub fn write_all(&self, bytes: &[u8]) -> Result<()> {
        let mut out = self.handle()?;
        out.write_all(bytes)?;
        out.flush()?;
        Ok(())
    }

    /// The path that external writers (ffmpeg) write: the temporary file, or the node
    /// written in place.
    pub fn temp_path(&self) -> &Path {
        self.temp.as_deref().unwrap_or(&self.target)
    }

    /// The path as the user gave it.
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

    /// [`AtomicFile::commit_all`], then, once all are in place, `also` (which may rename a
    /// [`PartialFile`] into place or remove a finished run's checkpoint), as one step for an
    /// interrupt.
    pub fn commit_with(
        mut files: Vec<AtomicFile>,
        also: impl FnOnce(&mut Guard<'_>) -> Result<()>,
    ) -> Result<()> {
        let result = {
            let mut live = live();
            match files.iter_mut().try_for_each(|f| f.rename(&mut live)) {
                Ok(()) => also(&mut Guard(live)),
                Err(e) => Err(e),
            }
        };
        // Outside the lock: those not renamed remove their temporary files.
        drop(files);
        result
    }

    fn rename(&mut self, live: &mut Live) -> Result<()> {
        if let Some(temp) = &self.temp {
            std::fs::rename(temp, &self.target).map_err(|e| WriteError::new(&self.flag, &self.path, e))?;
            live.forget(temp);
            self.temp = None;
        }
        self.file = None;
        Ok(())
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            let mut live = live();
            let _ = std::fs::remove_file(&temp);
            live.forget(&temp);
        }
    }
}

/// A handle on an [`AtomicFile`] (or a [`PartialFile`]): its write errors are [`WriteError`]s,
/// which name the output. Handles share the file's position (a FIFO's each open it anew).
pub struct OutFile {
    file: File,
    flag: String,
    path: PathBuf,
}

impl OutFile {
    /// `file`, the output `path` of option `flag`.
    pub fn new(file: File, flag: &str, path: &Path) -> Self {
        OutFile { file, flag: flag.to_owned(), path: path.to_owned() }
    }

    /// Writes the file's contents to the disk (a checkpoint never refers to bytes that a
    /// crash could lose).
    pub fn sync_data(&self) -> io::Result<()> {
        self.file.sync_data().map_err(|e| self.annotate(e))
    }

    /// Cuts the file to `len` bytes.
    pub fn set_len(&self, len: u64) -> io::Result<()> {
        self.file.set_len(len).map_err(|e| self.annotate(e))
    }

    /// Whether it can seek (a FIFO cannot).
    pub fn seekable(&mut self) -> bool {
        self.file.stream_position().is_ok()
    }

    fn annotate(&self, e: io::Error) -> io::Error {
        if e.get_ref().is_some_and(|r| r.is::<WriteError>()) {
            return e;
        }
        WriteError::new(&self.flag, &self.path, e).into_io()
    }
}

impl Write for OutFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.file.write(buf).map_err(|e| self.annotate(e))
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush().map_err(|e| self.annotate(e))
    }
}

impl Seek for OutFile {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        self.file.seek(pos).map_err(|e| self.annotate(e))
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

/// Claims `path`, of option `flag`, as an output that the run itself writes and reads back
/// as a regular file (a checkpoint, a partial trajectory, a grid's finished chunks):
/// resolved and checked as [`AtomicFile::create`] does (`-`, a directory, a missing
/// directory refused; a symlink followed), refused when it is a FIFO, a device or a socket
/// (`what` says what the file is, for the message), and claimed in the run's list of
/// outputs, so that no other output of the run may be the same file. Returns the file it
/// names (a symlink followed).
pub fn claim_regular(path: &Path, flag: &str, what: &str) -> Result<PathBuf> {
    if path == Path::new("-") {
        bail!("invalid {flag} -: {what} is a file that pendula reads back, not stdout; give a file name");
    }
    let Resolved { target, special } = resolve(path, flag)?;
    if let Some(kind) = special {
        bail!(
            "cannot write {flag} {}: it is a {kind}, and {what} must be a regular file that pendula reads back; give a file name",
            path.display()
        );
    }
    let place = Place::of(&target).map_err(|e| WriteError::new(flag, path, e))?;
    claim(Claim { held: Held::File { place, owner: None }, flag: flag.to_owned(), path: path.to_owned() })?;
    Ok(target)
}

/// A trajectory written by a checkpointing run under a visible name beside the file it
/// becomes, `OUT.partial`, so that a checkpoint can refer to it and `pendula resume` continue
/// it. Until a checkpoint refers to it ([`PartialFile::keep`]) an interrupt removes it like a
/// temporary file; afterwards it stays with its checkpoint. [`PartialFile::finish`] renames
/// it into place.
#[derive(Debug)]
pub struct PartialFile {
    path: PathBuf,
    /// The file it becomes (`--out`, a symlink followed).
    target: PathBuf,
    /// The path as the user gave it, for messages.
    shown: PathBuf,
    /// Whether it is still in the interrupt's list (no checkpoint refers to it).
    listed: bool,
}

/// What the partial trajectory is, in messages.
const PARTIAL: &str = "with --checkpoint, the trajectory";

impl PartialFile {
    /// The partial file of `target`: `target` with `.partial` appended.
    pub fn path_of(target: &Path) -> PathBuf {
        let mut name = target.as_os_str().to_owned();
        name.push(".partial");
        PathBuf::from(name)
    }

    /// Claims the output `target` (of option `flag`) and its partial file, which must both be
    /// regular files (a FIFO or a device cannot be continued), as outputs of the run; nothing
    /// is created yet ([`PartialFile::create`]).
    pub fn claim(target: &Path, flag: &str) -> Result<Self> {
        let resolved = claim_regular(target, flag, PARTIAL)?;
        let path = Self::path_of(&resolved);
        claim_regular(&path, flag, PARTIAL)?;
        Ok(PartialFile { path, target: resolved, shown: target.to_owned(), listed: false })
    }

    /// [`PartialFile::claim`] for the partial file `recorded` that a checkpoint refers to,
    /// which must be the one beside `target`.
    pub fn claim_recorded(target: &Path, recorded: &Path, flag: &str) -> Result<Self> {
        let partial = Self::claim(target, flag)?;
        if std::path::absolute(&partial.path).ok() != std::path::absolute(recorded).ok() {
            bail!(
                "the partial trajectory {} that the checkpoint refers to is not beside {flag} {} ({} expected): was the output moved?",
                recorded.display(),
                target.display(),
                partial.path.display()
            );
        }
        Ok(partial)
    }

    /// Creates (or empties) the file; an interrupt removes it until a checkpoint refers to it.
    /// Its write errors name `--out` and the path the user gave, as a temporary file's do.
    pub fn create(&mut self) -> Result<OutFile> {
        let file = together(|guard| {
            let file = guard.create_listed(&self.path)?;
            self.listed = true;
            Ok::<_, io::Error>(file)
        })
        .map_err(|e| WriteError::new("--out", &self.shown, e))?;
        Ok(OutFile::new(file, "--out", &self.shown))
    }

    /// The path the user gave for the output it becomes, for messages.
    pub fn shown(&self) -> &Path {
        &self.shown
    }

    /// Opens the file as a checkpoint left it, for reading and appending.
    pub fn open(&self) -> Result<File> {
        File::options().read(true).write(true).open(&self.path).with_context(|| {
            format!(
                "cannot open the partial trajectory {} that the checkpoint refers to",
                self.path.display()
            )
        })
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
            .map_err(|e| WriteError::new("--out", &self.shown, e).into())
    }

    /// Renames the finished trajectory into place.
    pub fn finish(mut self, guard: &mut Guard<'_>) -> Result<()> {
        guard.0.forget(&self.path);
        self.listed = false;
        std::fs::rename(&self.path, &self.target).map_err(|e| WriteError::new("--out", &self.shown, e).into())
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

#[cfg(test)]
mod tests {
    use super::matches;

    #[test]
    fn study_names_match_with_one_wildcard() {
        let names = ["summary.csv", "phase_*.png"];
        let m = |n: &str| matches(&names, std::ffi::OsStr::new(n));
        assert!(m("summary.csv") && m("phase_rk4.png") && m("phase_.png"));
        assert!(!m("summary.json") && !m("phase_rk4.svg") && !m("phase.png") && !m("xphase_rk4.png"));
    }
}
