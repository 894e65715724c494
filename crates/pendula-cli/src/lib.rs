//! The `pendula` command as a library target: parse → validate → run → write. The binary
//! (`src/main.rs`) only calls [`run`]; the integration tests under `tests/` (one test binary)
//! drive [`dispatch`] and the readers of user input in process, through the modules made
//! public for them.
//!
//! # How it is built
//!
//! The CLI: `crates/pendula-cli/src/cli.rs` (clap, strings only; the argument groups several
//! commands share — the system, `--set`, `--preset`, `--method` with `--dt`, `--t-end`,
//! `--threads`, `--summary`, `--allow-large` — are declared once in
//! `crates/pendula-cli/src/args.rs` and flattened into each command's arguments; each command
//! states its defaults, and a sentence of its own for a shared flag, once in a `Defaults`, from
//! which both its help text (`mut_args(… .document(a))` on its variant) and the groups' conversion
//! take them) → `crates/pendula-cli/src/config.rs` (validation into a `SimulateConfig`; every error
//! names the value and what is allowed; values are read by `crates/pendula-cli/src/parse.rs`, the CLI's bottom layer: floats by `parse::float`, which refuses what
//! Rust's parser turns silently into inf, a subnormal or 0, and integers by `parse_count` with
//! their range; scenario files are capped in size and nesting before the TOML parser sees them) →
//! `crates/pendula-cli/src/simulate.rs` (run, then write; its observers — rows, energy, events,
//! progress — in `crates/pendula-cli/src/watch.rs`) with `crates/pendula-cli/src/output.rs`, the
//! one writer of every output (`AtomicFile`). It resolves the path first: a regular file (a symlink
//! followed to its target) is written under a temporary name beside it and renamed into place, so a
//! failed run leaves nothing and replaces nothing; a FIFO or device is written in place, never
//! replaced; a directory, a path ending in `/`, a socket and `-` where stdout is not taken are
//! refused. Every output is *claimed* in the run's list (`output::scope`, one per dispatched
//! command, so `report`'s inner runs have their own): two that are one file (device and inode where
//! it exists, directory and name otherwise; a character device may be shared), one onto a study
//! directory's own names (`cli::COMMANDS`, claimed by `OutDir`) or onto an input (`claim_input`:
//! merge's shards, plot's file) are refused before any work. Write errors are `WriteError`s, naming
//! the option and the user's path with the OS error; a full disk, quota or I/O error exits 1,
//! everything else 2. Every live temporary file and every directory created for a run
//! (`CreatedDirs`, removed again if the run fails) is in a process-wide list, which the interrupt
//! thread — signal-hook, for SIGINT, SIGTERM and SIGHUP — empties, killing a registered ffmpeg
//! child first, before exiting 128 + the signal; creating, renaming and cleaning up hold the list's
//! lock, so an interrupt never leaves a half file nor removes a finished one. Trajectories stream
//! (`crates/pendula-cli/src/sink.rs`): CSV rows, and .npy rows behind a fixed-size header rewritten
//! with the row count at the end (spooled in an unnamed temporary file for a FIFO), every byte
//! counted and checksummed on the way. Exit codes: 0 success, 1 the computation or the environment
//! failed, 2 invalid input, 128 + the signal interrupted. Before any work every command states what
//! it was asked for — pendulum-steps, bytes written, bytes held — and
//! `crates/pendula-cli/src/limits.rs` (the limits, stated once, and `--threads`) refuses it over
//! the limits unless `--allow-large`; sizes that come from files (.npy headers, shard descriptions)
//! are checked against the file before anything is allocated. Every first change a command makes
//! outside itself (a claim, a directory, a temporary file) passes `output::first_change`, where, on
//! a thread of the fuzz harness only (`crates/pendula-cli/tests/fuzz/`: proptest, a fixed seed,
//! calling the CLI's library target), the command stops: millions of generated command lines, scenarios, .npy headers, shards and plot
//! inputs are so validated without running; the hardening battery
//! (`crates/pendula-cli/tests/battery/`) runs hostile requests through the real binary.
//!
//! # Where checkpoint state lives
//!
//! `crates/pendula-cli/src/checkpoint.rs` writes the file
//! format, `pendula_io::checkpoint`'s (a header line with the format, its version and the CRC-32 of the rest; JSON with the
//! command, working directory, arguments, a fingerprint of the validated request, and state as
//! hexadecimal bit patterns; written through the writer, `AtomicFile::recreate`, at every pause).
//! `crates/pendula-cli/src/run_state.rs` is what a `simulate` checkpoint holds — the library's
//! `RunState`, the observers' words, the rows written, and the trajectory's length, row count and
//! CRC-32 — while the trajectory itself is the visible `OUT.partial` beside the output
//! (`PartialFile` in `crates/pendula-cli/src/output.rs`, removed by an interrupt until a checkpoint
//! refers to it, renamed into place at the end with the plot and the summary). The checkpoint,
//! `OUT.partial` and `FILE.chunks` are claimed like every output (`output::claim_regular`): regular
//! files only (no FIFO, device, directory or `-`), never another output of the run. For a
//! checkpointing run the interrupt thread only sets the flag the run loop polls (`Checkpointing`,
//! `pause_flag`); the run writes its checkpoint and ends with `Interrupted` (exit 128 + the
//! signal); a second signal exits at once, as without checkpoints.
//! `crates/pendula-cli/src/chunks.rs` is the chunked form for `sweep` and `fractal`: finished
//! chunks' values appended to `FILE.chunks`, each chunk's CRC-32 listed in the checkpoint.
//! `crates/pendula-cli/src/commands/resume.rs` reads a checkpoint, returns to its working directory
//! and arguments, and hands it to `simulate`, `sweep` or `fractal`, which validate the arguments
//! again (limits included).
//!
//! # Tests
//!
//! The CLI's tests (`crates/pendula-cli/tests/cli.rs`) run the binary on every invalid input and
//! check message, exit code and that no output file is left behind;
//! `crates/pendula-cli/tests/study.rs` checks the study commands' headline numbers, files and
//! errors, and pins small runs with insta snapshots; `crates/pendula-cli/tests/chaos.rs` does the
//! same for lyapunov, poincare, fractal and bifurcation. `crates/pendula-cli/tests/battery/mod.rs`
//! runs hostile requests to every command, each in a fresh directory that must be left byte for
//! byte as its setup left it (`crates/pendula-cli/tests/battery/writes.rs`: FIFOs and private
//! device nodes, colliding outputs, directories, `-`, lying or corrupted shards);
//! `crates/pendula-cli/tests/outputs.rs` interrupts runs with signals, and
//! `crates/pendula-cli/tests/full_disk.rs` (as root) runs every writing command on a full 64 KiB
//! tmpfs; `crates/pendula-cli/tests/resume.rs` interrupts real processes with SIGINT at random
//! moments and compares the resumed outputs byte for byte with uninterrupted runs.

// First: its `say!` and `sayln!` macros are used by the modules after it.
#[macro_use]
mod study;

#[doc(hidden)]
pub mod args;
mod checkpoint;
mod chunks;
#[doc(hidden)]
pub mod cli;
#[doc(hidden)]
pub mod commands;
#[doc(hidden)]
pub mod config;
mod generate;
#[doc(hidden)]
pub mod limits;
mod list;
#[doc(hidden)]
pub mod output;
#[doc(hidden)]
pub mod parse;
mod run_state;
#[doc(hidden)]
pub mod shards;
mod simulate;
mod sink;
mod slurm;
mod studies;
mod watch;

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;

use cli::Cli;
pub use cli::dispatch;

/// The command: parses the process's arguments, runs the command they name, prints an error
/// and turns it into the exit status (2 for what the user can fix, 1 for a numerical or
/// environment failure, 128 + the signal for an interrupted run that wrote its checkpoint).
pub fn run() -> ExitCode {
    let cli = Cli::parse();
    // Without it an interrupt would still leave no partial output file, only a stray
    // temporary one: worth a warning, not a refusal.
    if let Err(err) = output::on_interrupt() {
        let _ = writeln!(std::io::stderr(), "warning: {err:#}");
    }
    let result = dispatch(&cli.command);
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            if is_broken_pipe(&err) {
                return ExitCode::SUCCESS;
            }
            // Stopped by an interrupt after writing its checkpoint: not a failure of the run.
            if let Some(i) = err.downcast_ref::<output::Interrupted>() {
                let _ = writeln!(std::io::stderr(), "{i}");
                return ExitCode::from(u8::try_from(128 + i.signal).unwrap_or(130));
            }
            let _ = writeln!(std::io::stderr(), "error: {}", message(&err));
            ExitCode::from(exit_code(&err))
        }
    }
}

/// 1 when the computation itself failed or the environment did (a full disk while writing),
/// 2 for everything the user can fix in the input.
fn exit_code(err: &anyhow::Error) -> u8 {
    if output::WriteError::find(err).is_some_and(output::WriteError::environment) {
        return 1;
    }
    match err.downcast_ref::<pendula::Error>() {
        Some(e) if e.is_numerical() => 1,
        _ => 2,
    }
}

/// The error and its causes, `: `-separated as anyhow's `{:#}` prints them, without a cause
/// that only repeats the end of the message before it (a CSV or NPY writer's error wrapping a
/// [`output::WriteError`] prints it, then gives it as its source); at most [`MAX_MESSAGE`]
/// bytes.
pub fn message(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if parts.last().is_some_and(|last| last.ends_with(&text)) {
            continue;
        }
        parts.push(text);
    }
    elide(parts.join(": "))
}

/// The longest message printed. Values are clipped where a message quotes them
/// (`parse::clip`), but paths are quoted whole, and an argument may hold 128 KiB (Linux's
/// limit): a message quoting such a path twice would bury its reason.
pub const MAX_MESSAGE: usize = 4096;

/// `text`, or when longer than [`MAX_MESSAGE`] its beginning and its end (where the reason
/// usually is: `…: File name too long`) with the middle elided.
fn elide(text: String) -> String {
    if text.len() <= MAX_MESSAGE {
        return text;
    }
    let head = text.floor_char_boundary(MAX_MESSAGE / 2);
    let tail = text.ceil_char_boundary(text.len() - MAX_MESSAGE / 4);
    format!("{} … ({} bytes elided) … {}", &text[..head], tail - head, &text[tail..])
}

/// A reader that went away (`pendula simulate --out - | head`) is not an error: the command
/// ends quietly with exit 0, as ripgrep does (temporary files are removed as for any run that
/// ends early). The pipe's error may come bare, inside a CSV error, inside the writer's
/// `WriteError` (which names the option and path, and holds the OS error as data), or as the
/// cause of a trajectory row that could not be written (which ended the run).
fn is_broken_pipe(err: &anyhow::Error) -> bool {
    let broken = |e: &std::io::Error| e.kind() == std::io::ErrorKind::BrokenPipe;
    output::WriteError::find(err).is_some_and(|w| broken(w.os_error()))
        || err.chain().any(|e| {
            e.downcast_ref::<std::io::Error>().is_some_and(broken)
                || e.downcast_ref::<csv::Error>()
                    .is_some_and(|e| matches!(e.kind(), csv::ErrorKind::Io(io) if broken(io)))
                || e.downcast_ref::<output::RowFailure>().is_some_and(|row| is_broken_pipe(&row.0))
        })
}

#[cfg(test)]
mod tests {
    use super::{MAX_MESSAGE, elide};

    #[test]
    fn long_messages_keep_their_beginning_and_their_end() {
        assert_eq!(elide("short".into()), "short");
        let path = "é".repeat(70_000);
        let long = elide(format!("cannot write --out {path}: File name too long (os error 36)"));
        assert!(long.len() <= MAX_MESSAGE, "{} bytes", long.len());
        assert!(long.starts_with("cannot write --out éé"), "{long}");
        assert!(long.ends_with("File name too long (os error 36)"), "{long}");
        assert!(long.contains("bytes elided"), "{long}");
    }
}
