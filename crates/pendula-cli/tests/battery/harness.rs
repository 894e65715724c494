#![allow(dead_code)] // builders the classes use as they fill
//! The battery's runner: each case runs the real binary in a fresh directory, within 5 s and
//! 200 MB, and is checked for its exit code, a fragment of its message, and the directory's
//! state afterwards — by default exactly what the case's setup left there, byte for byte (no
//! partial file, no temporary file, nothing lost).

use std::io::{Read, Write};
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use crate::util::{binary, is_root, panic_text, snapshot};

/// Wall-clock limit of one case.
pub const TIME_LIMIT: Duration = Duration::from_secs(5);
/// Peak resident memory limit of one case, kB.
pub const MEMORY_LIMIT_KB: u64 = 200 * 1024;

type DirFn = Box<dyn Fn(&Path) + Send + Sync>;
type BytesFn = Box<dyn Fn(&[u8]) + Send + Sync>;

/// What the runner writes into a FIFO it reads once the case has exited, so that it knows
/// it has read everything the case wrote.
const FIFO_END: &[u8] = b"\n--end of the battery's FIFO--\n";

/// One request and what must come of it.
pub struct Case {
    pub name: String,
    pub args: Vec<String>,
    pub stdin: Option<Vec<u8>>,
    pub setup: Option<DirFn>,
    pub exit: i32,
    pub says: Vec<String>,
    /// Files (relative paths) the run may create or change; everything else must be as the
    /// setup left it. A path ending in `/` stands for everything under it.
    pub creates: Vec<String>,
    pub after: Option<DirFn>,
    /// FIFOs (relative paths, made by the setup) the runner reads while the case runs, and
    /// the check of what the case wrote into each.
    pub fifos: Vec<(String, BytesFn)>,
    /// Whether the case needs root (mknod); without it the case is skipped, and says so.
    pub root: bool,
    /// The most bytes stderr may hold (a message must not echo megabytes of input).
    pub max_stderr: Option<usize>,
}

impl Case {
    /// `pendula ARGS` (split on whitespace; use [`Case::arg`] for an argument with spaces).
    pub fn new(name: &str, args: &str) -> Self {
        Case {
            name: name.to_owned(),
            args: args.split_whitespace().map(str::to_owned).collect(),
            stdin: None,
            setup: None,
            exit: 2,
            says: Vec::new(),
            creates: Vec::new(),
            after: None,
            fifos: Vec::new(),
            root: false,
            max_stderr: None,
        }
    }

    /// One more argument, verbatim.
    pub fn arg(mut self, arg: impl Into<String>) -> Self {
        self.args.push(arg.into());
        self
    }

    /// The expected exit code (2 unless set).
    pub fn exit(mut self, code: i32) -> Self {
        self.exit = code;
        self
    }

    /// A fragment stderr must contain.
    pub fn says(mut self, fragment: &str) -> Self {
        self.says.push(fragment.to_owned());
        self
    }

    /// Prepares the directory before the run.
    pub fn setup(mut self, f: impl Fn(&Path) + Send + Sync + 'static) -> Self {
        self.setup = Some(Box::new(f));
        self
    }

    /// A file the run may create or replace.
    pub fn creates(mut self, path: &str) -> Self {
        self.creates.push(path.to_owned());
        self
    }

    /// Checks the directory after the run (in addition to the default check).
    pub fn after(mut self, f: impl Fn(&Path) + Send + Sync + 'static) -> Self {
        self.after = Some(Box::new(f));
        self
    }

    /// Reads the FIFO `path` (made by the setup) while the case runs, as a reader would, and
    /// checks what the case wrote into it.
    pub fn reads_fifo(mut self, path: &str, check: impl Fn(&[u8]) + Send + Sync + 'static) -> Self {
        self.fifos.push((path.to_owned(), Box::new(check)));
        self
    }

    /// The case needs root (its setup makes device nodes with mknod); it is skipped otherwise.
    pub fn needs_root(mut self) -> Self {
        self.root = true;
        self
    }

    /// At most `bytes` on stderr.
    pub fn brief(mut self, bytes: usize) -> Self {
        self.max_stderr = Some(bytes);
        self
    }

    /// Bytes on stdin.
    pub fn stdin(mut self, bytes: impl Into<Vec<u8>>) -> Self {
        self.stdin = Some(bytes.into());
        self
    }
}

/// Whether `creates` (a path, or a directory ending in `/`) allows `path`.
fn created(creates: &str, path: &Path) -> bool {
    match creates.strip_suffix('/') {
        Some(dir) => path.starts_with(dir),
        None => Path::new(creates) == path,
    }
}

/// Peak resident memory of a running process, kB (0 once it is gone).
fn peak_kb(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

/// A reader of a FIFO: opened read-write, so that neither the case's open nor this one
/// blocks, and drained on a thread until the end marker that [`FifoReader::finish`] writes.
struct FifoReader {
    marker: std::fs::File,
    thread: std::thread::JoinHandle<Vec<u8>>,
}

impl FifoReader {
    fn open(path: &Path) -> Self {
        let file = std::fs::OpenOptions::new().read(true).write(true).open(path).unwrap();
        let marker = file.try_clone().unwrap();
        let thread = std::thread::spawn(move || {
            let mut file = file;
            let mut got = Vec::new();
            let mut buf = [0; 1 << 16];
            while !got.ends_with(FIFO_END) {
                match file.read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => got.extend_from_slice(&buf[..n]),
                }
            }
            got.truncate(got.len().saturating_sub(FIFO_END.len()));
            got
        });
        FifoReader { marker, thread }
    }

    /// What the case wrote, once it has exited.
    fn finish(mut self) -> Vec<u8> {
        self.marker.write_all(FIFO_END).unwrap();
        self.thread.join().unwrap()
    }
}

/// Runs one case; the failure's description, or `None` when it passed.
pub fn run_one(case: &Case) -> Option<String> {
    if case.root && !is_root() {
        // CI runs as root; a developer's run without it says what it left out.
        eprintln!("skipped {} (needs root, for mknod)", case.name);
        return None;
    }
    let dir = tempfile::TempDir::new().unwrap();
    if let Some(setup) = &case.setup {
        setup(dir.path());
    }
    let before = snapshot(dir.path());
    let readers: Vec<FifoReader> =
        case.fifos.iter().map(|(p, _)| FifoReader::open(&dir.path().join(p))).collect();
    let mut child = binary()
        .args(&case.args)
        .current_dir(dir.path())
        .env("NO_COLOR", "1")
        .stdin(if case.stdin.is_some() { Stdio::piped() } else { Stdio::null() })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    if let (Some(bytes), Some(mut pipe)) = (&case.stdin, child.stdin.take()) {
        let _ = pipe.write_all(bytes);
    }
    // Drained on threads so that a chatty child never blocks on a full pipe.
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let out_thread = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = out.read_to_end(&mut v);
        v
    });
    let err_thread = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = err.read_to_end(&mut v);
        v
    });
    let start = Instant::now();
    let mut peak = 0;
    let status = loop {
        peak = peak.max(peak_kb(child.id()));
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if start.elapsed() > TIME_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let _stdout = out_thread.join().unwrap();
    let stderr = String::from_utf8_lossy(&err_thread.join().unwrap()).into_owned();
    let mut problems = Vec::new();
    for (reader, (path, check)) in readers.into_iter().zip(&case.fifos) {
        let got = reader.finish();
        if let Err(e) = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| check(&got))) {
            problems.push(format!("FIFO {path}: check failed: {}", panic_text(&*e)));
        }
    }
    match status {
        None => problems.push(format!("still running after {TIME_LIMIT:?}")),
        Some(s) if s.code() != Some(case.exit) => {
            problems.push(format!("exit {:?}, expected {}", s.code(), case.exit));
        }
        Some(_) => {}
    }
    if peak > MEMORY_LIMIT_KB {
        problems.push(format!("peak memory {} MB", peak / 1024));
    }
    for fragment in &case.says {
        if !stderr.contains(fragment.as_str()) {
            problems.push(format!("stderr lacks {fragment:?}"));
        }
    }
    if let Some(max) = case.max_stderr
        && stderr.len() > max
    {
        problems.push(format!("stderr holds {} bytes, more than {max}", stderr.len()));
    }
    if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") {
        problems.push("panicked".into());
    }
    let after = snapshot(dir.path());
    for (path, contents) in &after {
        let allowed = case.creates.iter().any(|c| created(c, path));
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if name.starts_with(".pendula-") && name.ends_with(".part") {
            problems.push(format!("temporary file {} left", path.display()));
        } else if !allowed && before.get(path) != Some(contents) {
            problems.push(format!(
                "{} {}",
                path.display(),
                if before.contains_key(path) { "changed" } else { "created" }
            ));
        }
    }
    for path in before.keys() {
        if !after.contains_key(path) && !case.creates.iter().any(|c| created(c, path)) {
            problems.push(format!("{} lost", path.display()));
        }
    }
    if problems.is_empty()
        && let Some(check) = &case.after
        && let Err(e) = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| check(dir.path())))
    {
        problems.push(format!("check failed: {}", panic_text(&*e)));
    }
    (!problems.is_empty()).then(|| {
        format!(
            "{} (`pendula {}`): {}\n  stderr: {}",
            case.name,
            case.args.join(" "),
            problems.join("; "),
            stderr.trim()
        )
    })
}

/// Runs the cases two at a time and fails with every case that failed.
pub fn run(cases: Vec<Case>) {
    let failures: Vec<String> = std::thread::scope(|scope| {
        let chunks: Vec<&[Case]> = cases.chunks(cases.len().div_ceil(2).max(1)).collect();
        let handles: Vec<_> = chunks
            .into_iter()
            .map(|chunk| scope.spawn(move || chunk.iter().filter_map(run_one).collect::<Vec<_>>()))
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
