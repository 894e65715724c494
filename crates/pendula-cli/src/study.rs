//! What the study commands (compare, the registry's studies, report) share: their common
//! arguments, the output directory, tables and progress.
//!
//! # Shared parts
//!
//! What they share (arguments, output directory, tables, progress bars) is in
//! `crates/pendula-cli/src/study.rs`: `OutDir` (the directory, with a per-command manifest of the
//! files written there, so that a re-run removes its previous run's leftovers and nothing else; its
//! files are staged under temporary names and renamed together, with the summary, by `finish_with`,
//! so a failed run replaces none of them) and `Summary` (`--summary FILE` or `-`; with `-`,
//! `say!`/`sayln!` move the command's human output from stdout to stderr).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use pendula::system::Values;
use pendula_viz::Figure;

use crate::parse::parse_settings;

/// `print!` for a command's human output, through its [`Summary`]: `say!(summary, "...")`.
macro_rules! say {
    ($summary:expr, $($arg:tt)*) => { $summary.say(format_args!($($arg)*)) };
}

/// `println!` for a command's human output, through its [`Summary`].
macro_rules! sayln {
    ($summary:expr, $($arg:tt)*) => { $summary.say(format_args!("{}\n", format_args!($($arg)*))) };
}
use crate::args::{LargeArg, SetArgs, SummaryArg};
use crate::output::{AtomicFile, CreatedDirs};

// The summary's opening, beside the summary: `args` declares the flag, below this module.
impl SummaryArg {
    /// Opens it ([`Summary::open`]): a path that cannot be written fails before the work.
    pub fn open(&self) -> Result<Summary> {
        Summary::open(self.path.as_deref())
    }
}

/// Arguments every study command takes.
#[derive(Debug, Clone, Args)]
pub struct Common {
    #[command(flatten)]
    pub set: SetArgs,
    /// Directory for CSV, PNG and SVG outputs [default: pendula-out/<command>].
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    #[command(flatten)]
    pub summary: SummaryArg,
    #[command(flatten)]
    pub large: LargeArg,
}

/// Validated system values from a name and `--set` items.
pub fn values(system: &str, set: &[String]) -> Result<Values> {
    let info = pendula::model::find(system)?;
    let values = info.values(&parse_settings(info, set)?)?;
    values.check_energy()?;
    Ok(values)
}

/// The output directory: created if needed (and removed again if the run fails or is refused
/// before writing anything into it). Its files are written under temporary names as the run
/// goes and renamed into place together when it ends ([`OutDir::finish`]): a failed run —
/// also for want of disk space — replaces none of an earlier run's files. A hidden manifest per
/// command (`.pendula-<command>.files`) lists the files that command wrote there; when a run
/// finishes, the files of the previous run's manifest that this run did not write are
/// removed, so no figure of another system or method set stays beside the new ones. Only
/// files named in a manifest are ever removed.
pub struct OutDir {
    path: PathBuf,
    manifest: String,
    /// Names in the previous run's manifest.
    previous: Vec<String>,
    /// This run's files, written and waiting for [`OutDir::finish`], by name.
    pending: Vec<(String, AtomicFile)>,
    /// The directory's id in the run's list of outputs.
    id: u64,
    /// Directories created for it, removed again unless the run finishes.
    created: Option<CreatedDirs>,
}

impl OutDir {
    /// `--out-dir`, or `pendula-out/<command>`: created, checked writable, and claimed with
    /// `names`, the files the command writes there (its entry in `cli::COMMANDS`).
    pub fn new(dir: Option<&Path>, command: &str, names: &[&str]) -> Result<Self> {
        let path = dir.map_or_else(|| Path::new("pendula-out").join(command), Path::to_path_buf);
        if path == Path::new("-") {
            bail!("invalid --out-dir -: a directory of files cannot go to stdout; give a directory");
        }
        if path.exists() && !path.is_dir() {
            bail!("cannot write --out-dir {}: it is a file, not a directory", path.display());
        }
        let created = CreatedDirs::create(&path, "--out-dir")?;
        // Fail now, not after the work, if the directory cannot be written.
        crate::output::probe(&path, "--out-dir")?;
        // A registry study's files: its tables' CSV and its plots' PNG and SVG, by stem.
        // A directory in the place of one of the command's files is refused now too.
        if let Ok(entries) = std::fs::read_dir(&path) {
            for entry in entries.flatten() {
                let name = entry.file_name();
                if entry.path().is_dir() && crate::output::matches(names, &name) {
                    bail!(
                        "cannot write --out-dir {}: {} is a directory where {command} writes a file; move it or choose another directory",
                        path.display(),
                        entry.path().display()
                    );
                }
            }
        }
        let manifest = format!(".pendula-{command}.files");
        // The manifest is one of the directory's files too.
        let claimed = names.iter().map(|n| (*n).to_owned()).chain([manifest.clone()]).collect();
        let id = crate::output::claim_dir(&path, "--out-dir", command, claimed)?;
        // A missing or unreadable manifest means nothing to tidy.
        let previous: Vec<String> = std::fs::read_to_string(path.join(&manifest))
            .map(|text| text.lines().filter(|n| plain_name(n)).map(str::to_owned).collect())
            .unwrap_or_default();
        Ok(OutDir { path, manifest, previous, pending: Vec::new(), id, created: Some(created) })
    }

    /// Where the files go.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A file `name` in the directory, to be written and then given to [`OutDir::commit`].
    pub fn file(&self, name: &str) -> Result<AtomicFile> {
        AtomicFile::create_in(&self.path.join(name), "--out-dir", Some(self.id))
    }

    /// Hands over finished files of this directory, to be renamed into place together by
    /// [`OutDir::finish`].
    pub fn commit(&mut self, files: Vec<AtomicFile>) -> Result<()> {
        for file in files {
            let name =
                file.path().file_name().expect("a file in the directory").to_string_lossy().into_owned();
            // The same name written again: the later file wins.
            self.pending.retain(|(n, _)| *n != name);
            self.pending.push((name, file));
        }
        Ok(())
    }

    /// Writes `bytes` to `name` in the directory (in place when [`OutDir::finish`] runs).
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf> {
        let file = self.file(name)?;
        file.write_all(bytes)?;
        let path = file.path().to_owned();
        self.commit(vec![file])?;
        Ok(path)
    }

    /// Writes `name.png` and `name.svg`.
    pub fn figure(&mut self, name: &str, figure: &Figure) -> Result<()> {
        self.write(&format!("{name}.png"), &figure.png()?)?;
        self.write(&format!("{name}.svg"), figure.svg()?.as_bytes())?;
        Ok(())
    }

    /// Writes a CSV file from a header and rows of fields.
    pub fn csv(&mut self, name: &str, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
        self.csv_rows(name, header, rows.iter().cloned())
    }

    /// [`OutDir::csv`] with the rows made one at a time as they are written: a long table
    /// is held once, as its CSV bytes, not also as strings.
    pub fn csv_rows(
        &mut self,
        name: &str,
        header: &[&str],
        rows: impl IntoIterator<Item = Vec<String>>,
    ) -> Result<()> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(header)?;
        for row in rows {
            w.write_record(&row)?;
        }
        self.write(name, &w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?)?;
        Ok(())
    }

    /// A manifest listing `names`, written but not yet in place.
    fn manifest_file(&self, names: &[&str]) -> Result<AtomicFile> {
        let file = self.file(&self.manifest)?;
        let mut text = names.join("\n");
        text.push('\n');
        file.write_all(text.as_bytes())?;
        Ok(file)
    }

    /// Ends a successful run: this run's files are renamed into place together, with a
    /// manifest that lists them and the previous run's (so that an interrupt between the two
    /// steps leaves nothing untidied); then the previous run's files that this one did not
    /// write are removed, the manifest becomes this run's files, and stderr is told.
    pub fn finish(self) -> Result<()> {
        self.finish_inner(None, |_| Ok(()))
    }

    /// [`OutDir::finish`], with the run's summary: its file is renamed into place together
    /// with the directory's files, and JSON for stdout is printed after them.
    pub fn finish_with(self, summary: Summary, doc: &serde_json::Value) -> Result<()> {
        self.finish_then(summary, doc, |_| Ok(()))
    }

    /// [`OutDir::finish_with`], and `also` in the step that renames the files into place
    /// ([`AtomicFile::commit_with`]): a finished run's checkpoint removed.
    pub fn finish_then(
        self,
        summary: Summary,
        doc: &serde_json::Value,
        also: impl FnOnce(&mut crate::output::Guard<'_>) -> Result<()>,
    ) -> Result<()> {
        let (file, stdout) = summary.stage(doc)?;
        self.finish_inner(file, also)?;
        print_json(stdout)
    }

    fn finish_inner(
        mut self,
        summary: Option<AtomicFile>,
        also: impl FnOnce(&mut crate::output::Guard<'_>) -> Result<()>,
    ) -> Result<()> {
        let pending = std::mem::take(&mut self.pending);
        let written: Vec<&str> = pending.iter().map(|(n, _)| n.as_str()).collect();
        let mut listed = self.previous.iter().map(String::as_str).collect::<Vec<_>>();
        listed.extend(written.iter().filter(|n| !self.previous.iter().any(|p| p == *n)));
        // Every file is written before anything is renamed: a full disk fails here, with no
        // earlier file replaced.
        let during = self.manifest_file(&listed)?;
        let after = self.manifest_file(&written)?;
        let count = written.len();
        let stale: Vec<String> =
            self.previous.iter().filter(|n| !written.contains(&n.as_str())).cloned().collect();
        let mut files = vec![during];
        files.extend(pending.into_iter().map(|(_, f)| f));
        files.extend(summary);
        AtomicFile::commit_with(files, also)?;
        if let Some(created) = self.created.take() {
            created.keep();
        }
        let mut removed = 0;
        for name in &stale {
            let path = self.path.join(name);
            // A file only: whatever else has taken the name is not ours, nor is a file
            // that another output of this run wrote.
            if path.symlink_metadata().is_ok_and(|m| m.is_file())
                && !crate::output::claimed_by_another(&path, self.id)
                && std::fs::remove_file(&path).is_ok()
            {
                removed += 1;
            }
        }
        after.commit()?;
        let stale = match removed {
            0 => String::new(),
            n => format!(" (removed {n} stale files of an earlier run)"),
        };
        if !QUIET.load(std::sync::atomic::Ordering::Relaxed) {
            eprintln!("wrote {count} files to {}{stale}", self.path.display());
        }
        Ok(())
    }
}

/// A bare file name, as manifests hold: no directory, nothing hidden (manifests, temporary
/// files).
fn plain_name(name: &str) -> bool {
    !name.is_empty() && !name.starts_with('.') && !name.contains(['/', '\\'])
}

/// Where `--summary` goes: nowhere, a file (opened before the work, so that a path that
/// cannot be written fails first), or stdout for `-`. Every command that takes `--summary`
/// opens it with [`Summary::open`] and prints what is for people with [`Summary::say`],
/// which goes to stderr when stdout carries the JSON, so that stdout parses.
/// Set while `report` runs other commands: their tables and file counts would bury its own.
pub static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

pub struct Summary {
    target: Target,
}

enum Target {
    None,
    Stdout,
    File(AtomicFile),
}

impl Summary {
    /// Opens `--summary`: `-` is stdout.
    pub fn open(path: Option<&Path>) -> Result<Self> {
        let target = match path {
            None => Target::None,
            Some(p) if p == Path::new("-") => {
                crate::output::claim_stdout("--summary")?;
                Target::Stdout
            }
            Some(p) => Target::File(AtomicFile::create(p, "--summary")?),
        };
        Ok(Summary { target })
    }

    /// Whether the JSON goes to stdout.
    pub fn on_stdout(&self) -> bool {
        matches!(self.target, Target::Stdout)
    }

    /// The summary file, if there is one.
    pub fn path(&self) -> Option<&Path> {
        match &self.target {
            Target::File(f) => Some(f.path()),
            _ => None,
        }
    }

    /// Prints `text` for people: on stdout, or on stderr when stdout carries the JSON. A
    /// reader that went away is not an error. [`say!`] and [`sayln!`] call it as `print!`
    /// and `println!` would.
    pub fn say(&self, text: std::fmt::Arguments<'_>) {
        use std::io::Write as _;
        if QUIET.load(std::sync::atomic::Ordering::Relaxed) {
            return;
        }
        let _ = if self.on_stdout() {
            std::io::stderr().lock().write_fmt(text)
        } else {
            std::io::stdout().lock().write_fmt(text)
        };
    }

    /// Writes the JSON, and renames it into place together with the run's `files`: all of
    /// them appear, or none; then `also`, in the same step for an interrupt
    /// ([`AtomicFile::commit_with`]): a checkpointing run's partial trajectory renamed into
    /// place, its checkpoint removed. JSON for stdout is printed once the files are in place.
    pub fn write_then(
        self,
        doc: &serde_json::Value,
        mut files: Vec<AtomicFile>,
        also: impl FnOnce(&mut crate::output::Guard<'_>) -> Result<()>,
    ) -> Result<()> {
        let (file, stdout) = self.stage(doc)?;
        files.extend(file);
        AtomicFile::commit_with(files, also)?;
        print_json(stdout)
    }

    /// The JSON, written into the summary file (not yet in place) or kept for stdout.
    fn stage(self, doc: &serde_json::Value) -> Result<(Option<AtomicFile>, Option<Vec<u8>>)> {
        let mut text = serde_json::to_vec_pretty(doc)?;
        text.push(b'\n');
        match self.target {
            Target::None => Ok((None, None)),
            Target::Stdout => Ok((None, Some(text))),
            Target::File(file) => {
                file.write_all(&text)?;
                Ok((Some(file), None))
            }
        }
    }
}

/// Prints a line for people once the summary is written: on stdout, or on stderr when stdout
/// carried the JSON (`on_stdout`, from [`Summary::on_stdout`]), as [`Summary::say`] does.
pub fn say_after(on_stdout: bool, text: &str) {
    use std::io::Write as _;
    if QUIET.load(std::sync::atomic::Ordering::Relaxed) {
        return;
    }
    let _ = if on_stdout {
        writeln!(std::io::stderr().lock(), "{text}")
    } else {
        writeln!(std::io::stdout().lock(), "{text}")
    };
}

/// Prints a staged summary on stdout.
fn print_json(text: Option<Vec<u8>>) -> Result<()> {
    if let Some(text) = text {
        std::io::Write::write_all(&mut std::io::stdout().lock(), &text)?;
    }
    Ok(())
}

/// A progress bar on stderr for `n` units of work. On a terminal it is redrawn in place; when
/// stderr is a pipe or a file (`pendula compare 2>&1 | tee log`) it becomes a line now and
/// then ([`ProgressLines`]), so that a long run shows signs of life there too.
pub fn progress(n: u64, what: &str) -> ProgressBar {
    use std::io::IsTerminal;
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(n)
    } else {
        let lines = ProgressLines { start: std::time::Instant::now(), last: std::sync::Mutex::new(None) };
        ProgressBar::with_draw_target(Some(n), indicatif::ProgressDrawTarget::term_like(Box::new(lines)))
    };
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {elapsed}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_owned());
    bar
}

/// Progress as plain lines on stderr, for a stderr that is no terminal: none in the first
/// [`ProgressLines::QUIET`] (short runs, and the tests' runs, print nothing), then at most one
/// every [`ProgressLines::EVERY`].
#[derive(Debug)]
struct ProgressLines {
    start: std::time::Instant,
    /// When the last line was written.
    last: std::sync::Mutex<Option<std::time::Instant>>,
}

impl ProgressLines {
    const QUIET: std::time::Duration = std::time::Duration::from_secs(2);
    const EVERY: std::time::Duration = std::time::Duration::from_secs(5);

    fn line(&self, text: &str) -> std::io::Result<()> {
        let now = std::time::Instant::now();
        let mut last = self.last.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let due = match *last {
            None => now.duration_since(self.start) >= Self::QUIET,
            Some(t) => now.duration_since(t) >= Self::EVERY,
        };
        if due && !text.trim().is_empty() && !crate::parse::quiet() {
            *last = Some(now);
            use std::io::Write;
            writeln!(std::io::stderr(), "{}", text.trim_end())?;
        }
        Ok(())
    }
}

/// Only what is written counts; the cursor's moves, which redraw a bar in place, do not.
impl indicatif::TermLike for ProgressLines {
    fn width(&self) -> u16 {
        100
    }
    fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn write_line(&self, text: &str) -> std::io::Result<()> {
        self.line(text)
    }
    fn write_str(&self, text: &str) -> std::io::Result<()> {
        self.line(text)
    }
    fn clear_line(&self) -> std::io::Result<()> {
        Ok(())
    }
    fn flush(&self) -> std::io::Result<()> {
        Ok(())
    }
}

/// A plain-text table with aligned columns: numbers right-aligned, so that their digits line
/// up; text (names, notes) left-aligned and, in the last column, never padded, so that one
/// long note does not widen every row.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for row in rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.chars().count());
        }
    }
    // A column is numeric when every cell is a number, a bound on one (`< 0.001`, `>= 1`) or
    // empty (`-`, ``).
    let numeric = |c: &str| {
        let c = c.trim_start_matches(['<', '>', '=', ' ']);
        c.is_empty() || c == "-" || c.parse::<f64>().is_ok()
    };
    let right: Vec<bool> =
        (0..widths.len()).map(|i| rows.iter().all(|r| r.get(i).is_none_or(|c| numeric(c)))).collect();
    let mut out = String::new();
    let line = |out: &mut String, cells: &mut dyn Iterator<Item = &str>| {
        let parts: Vec<String> = cells
            .zip(widths.iter().zip(&right))
            .map(|(c, (w, right))| if *right { format!("{c:>w$}") } else { format!("{c:<w$}") })
            .collect();
        let _ = writeln!(out, "{}", parts.join("  ").trim_end());
    };
    line(&mut out, &mut header.iter().copied());
    for row in rows {
        line(&mut out, &mut row.iter().map(String::as_str));
    }
    out
}

/// A number for tables and CSV: shortest round-trip form.
pub fn num(v: f64) -> String {
    if v.is_finite() { ryu::Buffer::new().format(v).to_owned() } else { String::new() }
}

pub use pendula::error::short;
