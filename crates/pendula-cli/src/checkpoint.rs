//! Checkpoint files (`--checkpoint FILE`, `pendula resume FILE`): the format is
//! [`pendula_io::checkpoint`]'s; here they are written atomically among the run's outputs,
//! removed when the run ends, and their paths checked against the command's outputs.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::output::{AtomicFile, Guard};

pub use pendula_io::checkpoint::{Checkpoint, f64_from_hex, fingerprint, hex_f64, hex_words};

/// Writes a checkpoint for `body` to `path` (which the run claimed with
/// [`crate::output::claim_regular`]), atomically; `also` runs in the same step for an
/// interrupt as the rename (it keeps the partial file the checkpoint refers to). A failed
/// write names `--checkpoint` and the path ([`crate::output::WriteError`]).
pub fn write(
    path: &Path,
    body: &serde_json::Value,
    also: impl FnOnce(&mut Guard<'_>) -> Result<()>,
) -> Result<()> {
    let bytes = pendula_io::checkpoint::encode(body);
    let file = AtomicFile::recreate(path, "--checkpoint")?;
    {
        use std::io::Write;
        let mut handle = file.handle()?;
        handle.write_all(&bytes)?;
        handle.flush()?;
        handle.sync_data()?;
    }
    AtomicFile::commit_with(vec![file], also)
}

/// Removes a finished run's checkpoint (absent is fine: the run never paused).
pub fn remove(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("cannot remove the checkpoint {}", path.display()))
        }
        _ => Ok(()),
    }
}

/// The checkpoint flags of `simulate`, `sweep` and `fractal`, checked before any file is
/// opened: the file must not be `-`, a directory, nor any of the command's outputs (by name;
/// the writer's claims also catch the same file under other names, a FIFO or a device,
/// [`crate::output::claim_regular`]). Returns the path as given, which write errors name
/// ([`absolute`] for the messages that say how to continue, from any directory).
pub fn check_path(checkpoint: &Path, outputs: &[(&str, &Path)]) -> Result<PathBuf> {
    if checkpoint.as_os_str() == "-" {
        bail!("invalid --checkpoint -: a checkpoint is a file (e.g. run.ckpt)");
    }
    if checkpoint.is_dir() {
        bail!("invalid --checkpoint {}: it is a directory", checkpoint.display());
    }
    let path = absolute(checkpoint);
    for (flag, output) in outputs {
        if absolute(output) == path {
            bail!(
                "invalid --checkpoint {}: it is also the {flag} file; give it a name of its own",
                checkpoint.display()
            );
        }
    }
    Ok(checkpoint.to_owned())
}

/// `path` from the root (as it is, if the working directory cannot be read): what the
/// messages name to continue a run with `pendula resume`, from any directory.
pub fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_owned())
}
