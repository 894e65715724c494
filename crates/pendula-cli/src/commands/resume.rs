//! `pendula resume FILE`: continues a run of `simulate`, `sweep` or `fractal` from the
//! checkpoint it wrote with `--checkpoint FILE`, in the working directory and with the
//! arguments it was started with, so that its outputs are byte-identical to those of a run
//! never interrupted. The checkpoint (and a simulation's `OUT.partial`, a sweep's or
//! fractal's `FILE.chunks`) is removed when the run ends; an interrupted resume writes a new
//! checkpoint to the same file.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;

use crate::checkpoint::Checkpoint;

#[derive(Debug, Clone, Args)]
pub struct ResumeArgs {
    /// The checkpoint: the --checkpoint FILE of simulate, sweep or fractal.
    #[arg(value_name = "FILE")]
    pub checkpoint: PathBuf,
    /// Write the JSON summary here instead of where the run would have (`-`: on stdout).
    #[arg(long, value_name = "FILE.json")]
    pub summary: Option<PathBuf>,
    /// Run even where the saved arguments are over this machine's limits (more threads than
    /// its cores, say); the run was checked against them where it started. The saved
    /// arguments' own --allow-large holds without it.
    #[arg(long)]
    pub allow_large: bool,
}

pub fn run(args: &ResumeArgs) -> Result<()> {
    let checkpoint = Checkpoint::read(&args.checkpoint)?;
    let command: String = checkpoint.get("command")?;
    let cwd: PathBuf = checkpoint.get("cwd")?;
    // A summary path given here is relative to where `resume` runs, not to the run's folder.
    let summary = args.summary.as_ref().map(|s| {
        if s.as_os_str() == "-" { s.clone() } else { std::path::absolute(s).unwrap_or_else(|_| s.clone()) }
    });
    std::env::set_current_dir(&cwd).with_context(|| {
        format!("cannot resume {}: its run's folder {} is gone", checkpoint.path.display(), cwd.display())
    })?;
    let path = checkpoint.path.clone();
    match command.as_str() {
        "simulate" => {
            let mut a: crate::config::SimulateArgs = checkpoint.get("args")?;
            a.checkpoint = Some(path);
            a.summary.path = summary.or(a.summary.path);
            a.large.allow_large |= args.allow_large;
            let resumed = crate::run_state::Resumed::load(checkpoint)?;
            crate::simulate::execute(&a, Some(resumed))
        }
        "sweep" => {
            let mut a: super::sweep::SweepArgs = checkpoint.get("args")?;
            a.checkpoint = Some(path);
            a.summary.path = summary.or(a.summary.path);
            a.large.allow_large |= args.allow_large;
            super::sweep::execute(&a, Some(checkpoint))
        }
        "fractal" => {
            let mut a: super::fractal::FractalArgs = checkpoint.get("args")?;
            a.checkpoint = Some(path);
            a.summary.path = summary.or(a.summary.path);
            a.large.allow_large |= args.allow_large;
            super::fractal::execute(&a, Some(checkpoint))
        }
        other => bail!(
            "{} is a checkpoint of `{other}`, which this pendula cannot resume (simulate, sweep, fractal)",
            checkpoint.path.display()
        ),
    }
}
