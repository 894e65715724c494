//! The command line as clap sees it: strings and numbers, nothing checked beyond syntax.

use std::path::PathBuf;

use clap::{Args, CommandFactory, Parser, Subcommand};

use crate::config::SimulateArgs;
use crate::list::ListWhat;

/// Simple, double and harmonic pendulums with verified, structure-preserving integrators.
#[derive(Debug, Parser)]
#[command(name = "pendula", version, after_help = EXIT_CODES)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

pub const EXIT_CODES: &str = "Exit codes: 0 success; 1 the run failed (non-finite state, implicit \
step did not converge, adaptive step fell below its minimum) or its environment did (a full disk, \
quota or I/O error while writing; the message names the path, and no earlier file is replaced); 2 \
invalid input (arguments, values, scenario file, shards, a checkpoint that is missing, corrupt or \
for another request, an output path that cannot be written or that is another output's, a request \
over the limits without --allow-large); 130, 143, 129 interrupted by SIGINT, SIGTERM, SIGHUP \
(unfinished files removed; with --checkpoint, the checkpoint written first, for `pendula resume`).";

/// One command's entry in the list ([`COMMANDS`]): its name, the files it writes in its study
/// directory, and cheap valid requests.
#[derive(Debug)]
pub struct CommandInfo {
    /// Its name on the command line; empty for the library's studies (one subcommand each,
    /// listed by [`pendula::study::STUDIES`], but for those with a command of their own:
    /// [`crate::studies::OWN_COMMANDS`]).
    pub name: &'static str,
    /// The files it writes in its study directory (`*` stands for any text: compare's phase
    /// portraits are named after the methods). A `--summary` or other output of the run that
    /// would be one of them is refused before the run, and so is a directory in their place.
    pub files: &'static [&'static str],
    /// Valid requests that cost milliseconds (without `pendula`): mutated by the fuzz harness
    /// (`tests/fuzz/`), they reach the command's later checks.
    pub examples: &'static [&'static str],
}

/// The commands, declared once each: the doc and clap attributes of the variant, its arguments,
/// the function that runs it, its files and examples. The clap enum [`Command`], its dispatch
/// ([`Command::run`]) and [`COMMANDS`] are derived from this one list; completions and man
/// pages from clap's definition; the fuzz harness's requests from [`COMMANDS`].
macro_rules! commands {
    ($(
        $(#[$meta:meta])*
        $name:literal $variant:ident($args:ty) => $run:expr,
        files: $files:expr, examples: $examples:expr;
    )*) => {
        #[derive(Debug, Subcommand)]
        pub enum Command {
            $( $(#[$meta])* $variant($args), )*
        }

        impl Command {
            /// Runs the command (within the output scope [`dispatch`] opens).
            pub(crate) fn run(&self) -> anyhow::Result<()> {
                match self {
                    $( Command::$variant(args) => ($run)(args), )*
                }
            }
        }

        /// Every command, in the order of [`Command`].
        pub const COMMANDS: &[CommandInfo] =
            &[$( CommandInfo { name: $name, files: $files, examples: $examples }, )*];
    };
}

use crate::commands::{animate, compare, fractal, merge, plot, report, resume, serve, sweep};

commands! {
    /// Integrate one system with one method and write its trajectory and a summary.
    #[command(mut_args(|a| crate::config::SIMULATE.document(a)))]
    "simulate" Simulate(Box<SimulateArgs>) => crate::simulate::run,
    files: &[],
    examples: &[
        "simulate --steps 100 --out t.csv",
        "simulate pendulum --method dopri5 --t-end 1 --out t.npy --summary s.json",
        "simulate --method tao-2 --binding 50 --steps 10 --every 0 --event flip --event zero:theta1",
        "simulate oscillator --method dop853 --t-end 2 --output-dt 0.5 --rtol 1e-8 --atol 0 --h-max 1",
        "simulate driven-pendulum --preset baker-gollub-chaotic --steps 10 --set q=4 --plot p.png",
        "simulate chain --set links=3 --steps 5 --t-eval 0,0.5 --method dopri5",
    ];
    /// Compare methods on one problem: energy error, trajectories, phase portraits, cost.
    #[command(mut_arg("set", |a| a.help(SET_COMPARE)))]
    #[command(mut_args(|a| compare::DEFAULTS.document(a)))]
    "compare" Compare(Box<compare::CompareArgs>) => compare::run,
    files: compare::FILES,
    examples: &["compare oscillator --dt 0.1 --t-end 1 --methods rk4,verlet"];
    /// Animate a pendulum (GIF, or MP4 with ffmpeg), optionally beside a nearby start.
    #[command(mut_args(|a| animate::DEFAULTS.document(a)))]
    "animate" Animate(Box<animate::AnimateArgs>) => animate::run,
    files: &[],
    examples: &["animate --t-end 0.1 --fps 5 --size 160x160 --out a.gif"];
    /// The library's studies (`pendula::study::STUDIES`), one subcommand each.
    #[command(flatten)]
    "" Study(crate::studies::StudyCommand) => crate::studies::StudyCommand::run,
    files: &[],
    examples: &[];
    /// Time to the first flip of the double pendulum released from rest over (theta1, theta2),
    /// on the ensemble engine, with a per-pixel convergence flag from a run at half the step.
    #[command(mut_args(|a| fractal::DEFAULTS.document(a)))]
    "fractal" Fractal(Box<fractal::FractalArgs>) => fractal::run,
    files: fractal::FILES,
    examples: &["fractal --grid theta1=0:1:4 --grid theta2=0:1:4 --t-max 0.1 --out-dir fr"];
    /// Integrate a grid of initial states or parameters in parallel (SIMD lanes for every
    /// system with an explicit Runge-Kutta method, and for separable systems with the explicit
    /// symplectic methods) into one .npy array, or one shard of it.
    #[command(mut_args(|a| sweep::DEFAULTS.document(a)))]
    "sweep" Sweep(Box<sweep::SweepArgs>) => sweep::run,
    files: &[],
    examples: &[
        "sweep --grid theta1=0:1:4 --steps 10 --out g.npy",
        "sweep pendulum --grid theta=0:1:3 --grid l=1:2:2 --t-end 0.1 --record final,energy-error --shard 1/2",
    ];
    /// Assemble the shards of a sweep into the full array.
    "merge" Merge(Box<merge::MergeArgs>) => merge::run,
    files: &[],
    examples: &["merge s1.npy s2.npy --out m.npy"];
    /// Continue a run of simulate, sweep or fractal from its --checkpoint FILE: the outputs
    /// are byte-identical to an uninterrupted run's.
    "resume" Resume(Box<resume::ResumeArgs>) => resume::run,
    files: &[],
    examples: &[];
    /// Plot a pendula CSV or .npy file: time series, a phase portrait, the energy error, or
    /// a heat map of a sweep or fractal grid.
    "plot" Plot(Box<plot::PlotArgs>) => plot::run,
    files: &[],
    examples: &["plot t.csv --out p.png"];
    /// The pendulum lab in the browser: live simulation, energy, integrator race, butterfly
    /// mode, graphs and the flip-fractal explorer, computed by this program on this machine
    /// (prints the page's URL, with its access token).
    "serve" Serve(Box<serve::ServeArgs>) => serve::run,
    files: &[],
    examples: &[];
    /// The paper's whole numerical study as one self-contained HTML page.
    "report" Report(Box<report::ReportArgs>) => |args: &report::ReportArgs| report::run(args, run_line),
    files: report::FILES,
    examples: &["report --out-dir r"];
    /// List the systems, the methods or the presets, with parameters, units, defaults,
    /// requirements and sources.
    "list" List(ListArgs) => |args: &ListArgs| crate::list::run(args.what),
    files: &[],
    examples: &["list systems"];
    /// Print a completion script for SHELL on stdout, e.g. `pendula completions bash >
    /// ~/.local/share/bash-completion/completions/pendula`.
    "completions" Completions(CompletionsArgs) => |args: &CompletionsArgs| crate::generate::completions(Cli::command(), args.shell),
    files: &[],
    examples: &["completions bash"];
    /// Write the man pages: pendula.1 on stdout, or with --out-dir one page per command
    /// (pendula.1, pendula-simulate.1, ...), e.g. `pendula man --out-dir ~/.local/share/man/man1`.
    "man" Man(ManArgs) => |args: &ManArgs| crate::generate::man(Cli::command(), args.out_dir.as_deref()),
    files: crate::generate::FILES,
    examples: &[];
}

/// Runs one parsed command (the report runs others through it).
pub fn dispatch(command: &Command) -> anyhow::Result<()> {
    // The outputs this command claims; two of them that are the same file are refused.
    let _outputs = crate::output::scope();
    command.run()
}

/// `pendula ARGS...` parsed and run (the report runs its commands so); clap's error when the
/// arguments do not parse.
fn run_line(args: &[String]) -> anyhow::Result<()> {
    dispatch(&Cli::try_parse_from(args)?.command)
}

/// `pendula list`'s argument.
#[derive(Debug, Args)]
pub struct ListArgs {
    /// What to list.
    pub what: ListWhat,
}

/// `pendula completions`' argument.
#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell to complete in.
    pub shell: clap_complete::Shell,
}

/// `pendula man`'s argument.
#[derive(Debug, Args)]
pub struct ManArgs {
    /// Directory for the pages [default: pendula.1 on stdout].
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
}

// `--set` help for each study command: the example names quantities of the system that
// command runs by default (tests/cli.rs runs every example on that system).
const SET_COMPARE: &str = "Set a parameter or initial-state variable of the system, e.g. `--set theta1=90deg \
--set m2=2` for the double pendulum (angles: `deg` or `pi` suffix; bare numbers are radians).";
#[cfg(test)]
mod tests {
    use clap::{CommandFactory, Parser};

    use super::{COMMANDS, Cli};

    /// The list names every subcommand clap knows, once, in clap's order; the library's
    /// studies come in where its empty entry stands.
    #[test]
    fn the_list_of_commands_is_clap_s_list_of_subcommands() {
        let clap: Vec<String> = Cli::command().get_subcommands().map(|c| c.get_name().to_owned()).collect();
        let listed: Vec<String> = COMMANDS
            .iter()
            .flat_map(|c| match c.name {
                "" => crate::studies::registered().map(|s| s.name.to_owned()).collect(),
                name => vec![name.to_owned()],
            })
            .collect();
        assert_eq!(clap, listed);
        for c in COMMANDS {
            for example in c.examples {
                assert!(example.split(' ').next() == Some(c.name), "{example} is not {}'s", c.name);
                Cli::try_parse_from(std::iter::once("pendula").chain(example.split(' '))).unwrap();
            }
        }
    }
}
