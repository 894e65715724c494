//! Shard files as the CLI writes and reads them: a sweep's or a fractal's .npy array (written
//! with its length and CRC-32) and its JSON description beside it (FILE.npy.json), as
//! `sweep --shard` and `fractal --shard` write them and `merge` and `plot` read them. The format
//! itself — the .npy writer, the description's fields and their checks — is `pendula_io`'s
//! ([`pendula_io::npy`], [`pendula_io::shard`]); this module only puts it through the CLI's
//! writer ([`AtomicFile`]).

use std::path::Path;

use anyhow::Result;

use crate::output::AtomicFile;

pub use pendula_io::npy::{Written, checksum};
pub use pendula_io::shard::SHARD_FORMAT;
pub(crate) use pendula_io::shard::read_capped;

/// Writes `data` as a .npy array of `shape` into `file`; its length and checksum.
pub(crate) fn write_npy<T: pendula_io::npy::Element>(
    file: &AtomicFile,
    shape: &[usize],
    data: &[T],
) -> Result<Written> {
    let mut w = std::io::BufWriter::new(file.handle()?);
    // An error is the file's own, which names it.
    let written = pendula_io::npy::write(&mut w, shape, data)?;
    w.into_inner().map_err(|e| e.into_error())?;
    Ok(written)
}

pub(crate) fn write_json(file: &AtomicFile, doc: &serde_json::Value) -> Result<()> {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(file.handle()?);
    serde_json::to_writer_pretty(&mut w, doc)?;
    writeln!(w)?;
    w.into_inner().map_err(|e| e.into_error())?;
    Ok(())
}

/// Reads a shard's description (FILE.npy.json): see [`pendula_io::shard::read_description`].
pub fn read_description(npy: &Path) -> Result<serde_json::Value> {
    Ok(pendula_io::shard::read_description(npy)?)
}
