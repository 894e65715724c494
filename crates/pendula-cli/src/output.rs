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
//! after (and leaves the finished file alone). Trajectories stream to disk as CSV or .npy, so
//! memory does not grow with the run's length.

use std::ffi::OsString;
use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, ExitStatus};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use anyhow::{Context, Result, bail};

use crate::config::Output;

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

/// Starts the thread that turns SIGINT, SIGTERM and SIGHUP (the terminal closed) into a clean
/// exit: children killed, temporary files and the directories created for them removed, exit status 130, 143 or 129 (128 + the
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
                // Innermost first; a directory that holds anything stays.
                for dir in live.dirs.iter().rev() {
                    let _ = std::fs::remove_dir(dir);
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
    fn new(flag: &str, path: &Path, source: io::Error) -> Self {
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

    /// The write error in `err`'s chain, if any (also inside an `io::Error`).
    pub fn find(err: &anyhow::Error) -> Option<&WriteError> {
        err.chain().find_map(|e| {
            e.downcast_ref::<WriteError>().or_else(|| {
                e.downcast_ref::<io::Error>().and_then(|io| io.get_ref()?.downcast_ref::<WriteError>())
            })
        })
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
/// first output has been checked by then, and nothing written. In the unit tests' build a
/// thread may stop its command here ([`validate_only`]): the fuzz harness (`src/fuzz/`)
/// so validates millions of generated requests without running them.
fn first_change() -> Result<()> {
    #[cfg(test)]
    if VALIDATE_ONLY.get() {
        return Err(Validated.into());
    }
    Ok(())
}

#[cfg(test)]
thread_local! {
    static VALIDATE_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Stops this thread's commands at their first output ([`first_change`]) with [`Validated`]
/// (`on`), or lets them run (`!on`). Tests only.
#[cfg(test)]
pub(crate) fn validate_only(on: bool) {
    VALIDATE_ONLY.set(on);
}

/// The error of a command stopped by [`validate_only`]: its input was accepted.
#[cfg(test)]
#[derive(Debug)]
pub(crate) struct Validated;

#[cfg(test)]
impl std::fmt::Display for Validated {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("validated; stopped before the first output")
    }
}

#[cfg(test)]
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
        let Resolved { target, special } = resolve(path, flag)?;
        let place = Place::of(&target).map_err(|e| WriteError::new(flag, path, e))?;
        claim(Claim { held: Held::File { place, owner }, flag: flag.to_owned(), path: path.to_owned() })?;
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
    pub fn commit_all(mut files: Vec<AtomicFile>) -> Result<()> {
        let result = {
            let mut live = live();
            files.iter_mut().try_for_each(|f| f.rename(&mut live))
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

/// A handle on an [`AtomicFile`]: its write errors are [`WriteError`]s, which name the output.
/// Handles share the file's position (a FIFO's each open it anew).
pub struct OutFile {
    file: File,
    flag: String,
    path: PathBuf,
}

impl OutFile {
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
        csv.write_record(columns).map_err(csv_error)?;
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
                    w.write_field(buf.format(v)).map_err(csv_error)?;
                }
                w.write_record(None::<&[u8]>).map_err(csv_error)?;
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

/// A CSV writer's error as the writer's own when it is one ([`WriteError`], which names the
/// output, and is what the exit code looks for).
fn csv_error(e: csv::Error) -> anyhow::Error {
    let text = e.to_string();
    match e.into_kind() {
        csv::ErrorKind::Io(io) => io.into(),
        _ => anyhow::anyhow!(text),
    }
}

/// A 2-D little-endian float64 array in NPY format 1.0, streamed row by row: the header is
/// written first with room for any row count, and rewritten with the real one at the end.
/// Into a FIFO, which cannot seek, the rows are spooled in an unnamed temporary file (gone
/// with the process, however it ends) and follow the final header at the end.
pub struct NpyRows {
    out: BufWriter<OutFile>,
    /// The rows, when `out` cannot seek.
    spool: Option<BufWriter<File>>,
    columns: usize,
    rows: u64,
    header_len: usize,
}

impl NpyRows {
    /// Starts the array in `file` (at its start).
    pub fn new(mut file: OutFile, columns: usize) -> Result<Self> {
        // The header's size for the longest row count; every header is padded to it.
        let header_len = npy_header(u64::MAX, columns, 0).len();
        let seekable = file.stream_position().is_ok();
        let mut out = BufWriter::with_capacity(1 << 16, file);
        let spool = if seekable {
            out.write_all(&npy_header(0, columns, header_len))?;
            None
        } else {
            let spool = tempfile::tempfile()
                .context("cannot spool the .npy rows for a FIFO in the temporary directory")?;
            Some(BufWriter::with_capacity(1 << 16, spool))
        };
        Ok(NpyRows { out, spool, columns, rows: 0, header_len })
    }

    /// Appends one row of `columns` values.
    pub fn row(&mut self, values: impl Iterator<Item = f64>) -> Result<()> {
        let w: &mut dyn Write = match &mut self.spool {
            Some(spool) => spool,
            None => &mut self.out,
        };
        let mut n = 0;
        for v in values {
            w.write_all(&v.to_le_bytes())?;
            n += 1;
        }
        debug_assert_eq!(n, self.columns, "a row has one value per column");
        self.rows += 1;
        Ok(())
    }

    /// Writes the header with the final shape.
    pub fn finish(self) -> Result<()> {
        let header = npy_header(self.rows, self.columns, self.header_len);
        let mut out = self.out;
        match self.spool {
            Some(spool) => {
                let mut spool = spool.into_inner().map_err(|e| e.into_error())?;
                spool.seek(SeekFrom::Start(0))?;
                out.write_all(&header)?;
                io::copy(&mut spool, &mut out)?;
                out.flush()?;
            }
            None => {
                let mut file = out.into_inner().map_err(|e| e.into_error())?;
                file.seek(SeekFrom::Start(0))?;
                file.write_all(&header)?;
                file.flush()?;
            }
        }
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
    use super::{matches, npy_header};

    #[test]
    fn study_names_match_with_one_wildcard() {
        let names = ["summary.csv", "phase_*.png"];
        let m = |n: &str| matches(&names, std::ffi::OsStr::new(n));
        assert!(m("summary.csv") && m("phase_rk4.png") && m("phase_.png"));
        assert!(!m("summary.json") && !m("phase_rk4.svg") && !m("phase.png") && !m("xphase_rk4.png"));
    }

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
