//! The `pendula` command as a library target: parse → validate → run → write. The binary
//! (`src/main.rs`) only calls [`run`]; the integration tests under `tests/` (one test binary)
//! drive [`dispatch`] and the readers of user input in process, through the modules made
//! public for them.

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
mod watch;

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;

use cli::{Cli, Command};

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

/// Runs one parsed command (the report runs others through it).
pub fn dispatch(command: &Command) -> anyhow::Result<()> {
    // The outputs this command claims; two of them that are the same file are refused.
    let _outputs = output::scope();
    match command {
        Command::Simulate(args) => simulate::run(args),
        Command::Compare(args) => commands::compare::run(args),
        Command::Convergence(args) => commands::convergence::run(args),
        Command::Stability(args) => commands::stability::run(args),
        Command::WorkPrecision(args) => commands::work_precision::run(args),
        Command::Period(args) => commands::period::run(args),
        Command::OscillatorRegimes(args) => commands::regimes::run(args),
        Command::Animate(args) => commands::animate::run(args),
        Command::Report(args) => commands::report::run(args, run_line),
        Command::Sweep(args) => commands::sweep::run(args),
        Command::Divergence(args) => commands::divergence::run(args),
        Command::Lyapunov(args) => commands::lyapunov::run(args),
        Command::Fractal(args) => commands::fractal::run(args),
        Command::Bifurcation(args) => commands::bifurcation::run(args),
        Command::Poincare(args) => commands::poincare::run(args),
        Command::Merge(args) => commands::merge::run(args),
        Command::Resume(args) => commands::resume::run(args),
        Command::Plot(args) => commands::plot::run(args),
        Command::Serve(args) => commands::serve::run(args),
        Command::List { what } => list::run(*what),
        Command::Completions { shell } => generate::completions(*shell),
        Command::Man { out_dir } => generate::man(out_dir.as_deref()),
    }
}

/// `pendula ARGS...` parsed and run (the report runs its commands so); clap's error when the
/// arguments do not parse.
fn run_line(args: &[String]) -> anyhow::Result<()> {
    dispatch(&Cli::try_parse_from(args)?.command)
}

/// 1 when the computation itself failed or the environment did (a full disk while writing),
/// 2 for everything the user can fix in the input.
fn exit_code(err: &anyhow::Error) -> u8 {
    if output::WriteError::find(err).is_some_and(output::WriteError::environment) {
        return 1;
    }
    match err.downcast_ref::<pendula::Error>() {
        Some(
            pendula::Error::NonFinite { .. }
            | pendula::Error::NewtonDidNotConverge { .. }
            | pendula::Error::StepSizeTooSmall { .. },
        ) => 1,
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
