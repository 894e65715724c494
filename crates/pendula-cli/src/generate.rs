//! `pendula completions SHELL` and `pendula man`: shell completion scripts and roff man pages,
//! both generated from the clap definition in `cli.rs`, which hands it over, so they cannot fall out of date.

use std::path::Path;

use anyhow::Result;
use clap_complete::Shell;

use crate::study::OutDir;

/// The files `man --out-dir` writes (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &["pendula*.1"];

/// Writes the completion script of `command` (the CLI's, from clap) for `shell` to stdout.
pub fn completions(mut command: clap::Command, shell: Shell) -> Result<()> {
    // Through a buffer: clap_complete panics on a failed write, and a closed pipe
    // (`pendula completions bash | head`) is no failure.
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut command, "pendula", &mut script);
    std::io::Write::write_all(&mut std::io::stdout().lock(), &script)?;
    Ok(())
}

/// Writes `pendula.1` to stdout, or, given a directory, one page per command into it
/// (`pendula.1`, `pendula-simulate.1`, ...), each file whole or not at all.
pub fn man(command: clap::Command, out_dir: Option<&Path>) -> Result<()> {
    let mut command = command.disable_help_subcommand(true);
    // Building fills in what the pages show: subcommands' display names (pendula-simulate),
    // versions, and the generated help and version flags.
    command.build();
    let Some(dir) = out_dir else {
        let mut page = Vec::new();
        clap_mangen::Man::new(command).render(&mut page)?;
        std::io::Write::write_all(&mut std::io::stdout().lock(), &page)?;
        return Ok(());
    };
    let mut out = OutDir::new(Some(dir), "man", FILES)?;
    write_pages(&command, &mut out)?;
    out.finish()?;
    Ok(())
}

fn write_pages(command: &clap::Command, out: &mut OutDir) -> Result<()> {
    for sub in command.get_subcommands().filter(|s| !s.is_hide_set()) {
        write_pages(sub, out)?;
    }
    let man = clap_mangen::Man::new(command.clone());
    let mut page = Vec::new();
    man.render(&mut page)?;
    out.write(&man.get_filename(), &page)?;
    Ok(())
}
