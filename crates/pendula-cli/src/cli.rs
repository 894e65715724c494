//! The command line as clap sees it: strings and numbers, nothing checked beyond syntax.

use std::path::PathBuf;

use clap::{Parser, Subcommand};

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

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Integrate one system with one method and write its trajectory and a summary.
    #[command(mut_args(|a| crate::config::SIMULATE.document(a)))]
    Simulate(Box<SimulateArgs>),
    /// Compare methods on one problem: energy error, trajectories, phase portraits, cost.
    #[command(mut_arg("set", |a| a.help(SET_COMPARE)))]
    #[command(mut_args(|a| crate::commands::compare::DEFAULTS.document(a)))]
    Compare(Box<crate::commands::compare::CompareArgs>),
    /// Global error against step size, with the fitted order of each method.
    #[command(mut_arg("set", |a| a.help(SET_CONVERGENCE)))]
    #[command(mut_args(|a| crate::commands::convergence::DEFAULTS.document(a)))]
    Convergence(Box<crate::commands::convergence::ConvergenceArgs>),
    /// The largest stable step of each method.
    #[command(mut_arg("set", |a| a.help(SET_STABILITY)))]
    #[command(mut_args(|a| crate::commands::stability::DEFAULTS.document(a)))]
    Stability(Box<crate::commands::stability::StabilityArgs>),
    /// Error against cost (rhs evaluations, wall time) of each method over a range of steps.
    #[command(mut_arg("set", |a| a.help(SET_WORK_PRECISION)))]
    #[command(mut_args(|a| crate::commands::work_precision::DEFAULTS.document(a)))]
    WorkPrecision(Box<crate::commands::work_precision::WorkPrecisionArgs>),
    /// The simple pendulum's period against amplitude: simulated, exact and small-angle.
    #[command(mut_arg("set", |a| a.help(SET_PERIOD)))]
    #[command(mut_args(|a| crate::commands::period::DEFAULTS.document(a)))]
    Period(Box<crate::commands::period::PeriodArgs>),
    /// The oscillator's damping regimes and forced resonance, exact and simulated.
    #[command(mut_arg("set", |a| a.help(SET_OSCILLATOR_REGIMES)))]
    OscillatorRegimes(Box<crate::commands::regimes::RegimesArgs>),
    /// Animate a pendulum (GIF, or MP4 with ffmpeg), optionally beside a nearby start.
    #[command(mut_args(|a| crate::commands::animate::DEFAULTS.document(a)))]
    Animate(Box<crate::commands::animate::AnimateArgs>),
    /// The library's studies (`pendula::study::STUDIES`), one subcommand each.
    #[command(flatten)]
    Study(crate::studies::StudyCommand),
    /// Distance between two trajectories started close together, and its growth rate.
    #[command(mut_arg("set", |a| a.help(SET_DIVERGENCE)))]
    #[command(mut_args(|a| crate::commands::divergence::DEFAULTS.document(a)))]
    Divergence(Box<crate::commands::divergence::DivergenceArgs>),
    /// Lyapunov exponents from the variational equations (Benettin, QR), with a convergence
    /// plot of the running estimate and an uncertainty.
    #[command(mut_arg("set", |a| a.help(SET_LYAPUNOV)))]
    #[command(mut_args(|a| crate::commands::lyapunov::DEFAULTS.document(a)))]
    Lyapunov(Box<crate::commands::lyapunov::LyapunovArgs>),
    /// Poincare section of a conservative two-degree-of-freedom system: orbits on a fixed-energy
    /// surface and their crossings of a section, located by events.
    #[command(mut_arg("set", |a| a.help(SET_POINCARE)))]
    #[command(mut_args(|a| crate::commands::poincare::DEFAULTS.document(a)))]
    Poincare(Box<crate::commands::poincare::PoincareArgs>),
    /// Stroboscopic orbit diagram of a driven system against a swept parameter (SIMD lanes for
    /// the driven pendulum).
    #[command(mut_arg("set", |a| a.help(SET_BIFURCATION)))]
    #[command(mut_args(|a| crate::commands::bifurcation::DEFAULTS.document(a)))]
    Bifurcation(Box<crate::commands::bifurcation::BifurcationArgs>),
    /// Time to the first flip of the double pendulum released from rest over (theta1, theta2),
    /// on the ensemble engine, with a per-pixel convergence flag from a run at half the step.
    #[command(mut_args(|a| crate::commands::fractal::DEFAULTS.document(a)))]
    Fractal(Box<crate::commands::fractal::FractalArgs>),
    /// Integrate a grid of initial states or parameters in parallel (SIMD lanes for every
    /// system with an explicit Runge-Kutta method, and for separable systems with the explicit
    /// symplectic methods) into one .npy array, or one shard of it.
    #[command(mut_args(|a| crate::commands::sweep::DEFAULTS.document(a)))]
    Sweep(Box<crate::commands::sweep::SweepArgs>),
    /// Assemble the shards of a sweep into the full array.
    Merge(Box<crate::commands::merge::MergeArgs>),
    /// Continue a run of simulate, sweep or fractal from its --checkpoint FILE: the outputs
    /// are byte-identical to an uninterrupted run's.
    Resume(Box<crate::commands::resume::ResumeArgs>),
    /// Plot a pendula CSV or .npy file: time series, a phase portrait, the energy error, or
    /// a heat map of a sweep or fractal grid.
    Plot(Box<crate::commands::plot::PlotArgs>),
    /// The pendulum lab in the browser: live simulation, energy, integrator race, butterfly
    /// mode, graphs and the flip-fractal explorer, computed by this program on this machine
    /// (prints the page's URL, with its access token).
    Serve(Box<crate::commands::serve::ServeArgs>),
    /// The paper's whole numerical study as one self-contained HTML page.
    Report(Box<crate::commands::report::ReportArgs>),
    /// List the systems, the methods or the presets, with parameters, units, defaults,
    /// requirements and sources.
    List {
        /// What to list.
        what: ListWhat,
    },
    /// Print a completion script for SHELL on stdout, e.g. `pendula completions bash >
    /// ~/.local/share/bash-completion/completions/pendula`.
    Completions {
        /// The shell to complete in.
        shell: clap_complete::Shell,
    },
    /// Write the man pages: pendula.1 on stdout, or with --out-dir one page per command
    /// (pendula.1, pendula-simulate.1, ...), e.g. `pendula man --out-dir ~/.local/share/man/man1`.
    Man {
        /// Directory for the pages [default: pendula.1 on stdout].
        #[arg(long, value_name = "DIR")]
        out_dir: Option<PathBuf>,
    },
}

// `--set` help for each study command: the example names quantities of the system that
// command runs by default (tests/cli.rs runs every example on that system).
const SET_COMPARE: &str = "Set a parameter or initial-state variable of the system, e.g. `--set theta1=90deg \
--set m2=2` for the double pendulum (angles: `deg` or `pi` suffix; bare numbers are radians).";
const SET_CONVERGENCE: &str = "Set a parameter or initial-state variable of the system, e.g. `--set c=0.5` \
(the oscillator's damping, kg/s) or `--set x=0.2` (m).";
const SET_STABILITY: &str = "Set a parameter or initial-state variable of the system, e.g. `--set theta=30deg` \
for the pendulum (angles: `deg` or `pi` suffix; bare numbers are radians).";
const SET_WORK_PRECISION: &str = "Set a parameter or initial-state variable of the system, e.g. \
`--set theta=90deg` for the pendulum (angles: `deg` or `pi` suffix; bare numbers are radians).";
const SET_PERIOD: &str = "Set a parameter of the simple pendulum, e.g. `--set l=2` (m) or `--set g=1.62` \
(m/s^2); the amplitude is swept (--max-amplitude) from rest.";
const SET_OSCILLATOR_REGIMES: &str = "Set a parameter of the oscillator, e.g. `--set k=4` (N/m) or `--set m=2` (kg); \
the damping, the drive and the start are the study's own.";
const SET_DIVERGENCE: &str = "Set a parameter or initial-state variable of the system, e.g. `--set \
theta1=120deg --set m2=2` for the double pendulum (bare angles are radians).";
const SET_LYAPUNOV: &str = "Set a parameter or initial-state variable, over the preset if one is given: \
e.g. `--set theta1=120deg` for the double pendulum, `--set q=4` for a driven-pendulum preset.";
const SET_POINCARE: &str = "Set a parameter of the system, e.g. `--set m2=2` (kg) for the double \
pendulum; every orbit starts on the energy surface (--energy).";
const SET_BIFURCATION: &str = "Set a parameter over the preset or the defaults, e.g. `--set q=4` \
(the driven pendulum's quality factor) or `--set drive_frequency=0.5`.";
