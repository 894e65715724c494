//! The shard file format: a sweep's or a fractal's .npy array (written with its length and
//! CRC-32) and its JSON description beside it (FILE.npy.json), as `sweep --shard` and
//! `fractal --shard` write them and `merge` and `plot` read them.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::limits;
use crate::output::AtomicFile;
use crate::sink::Tally;

/// The format of a shard's description (FILE.npy.json), in `pendula_sweep`. Format 2 added
/// `data` (the .npy file's length and CRC-32, which `merge` checks); readers ignore keys they
/// do not know, so adding one needs no new format, and changing one does.
pub const SHARD_FORMAT: u64 = 2;

/// What [`write_npy`] wrote: the file's length and CRC-32.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Written {
    pub bytes: u64,
    pub crc32: u32,
}

/// The length and CRC-32 of what `reader` holds, read to its end.
pub fn checksum(mut reader: impl std::io::Read) -> std::io::Result<Written> {
    let mut sink = Tally::new(std::io::sink());
    std::io::copy(&mut reader, &mut sink)?;
    let (bytes, crc32) = sink.written();
    Ok(Written { bytes, crc32 })
}

/// Writes `data` as a .npy array of `shape` into `file`; its length and checksum.
pub(crate) fn write_npy<T: ndarray_npy::WritableElement>(
    file: &AtomicFile,
    shape: &[usize],
    data: &[T],
) -> Result<Written> {
    use ndarray_npy::WriteNpyExt;
    use std::io::Write;
    let array =
        ndarray::ArrayViewD::from_shape(ndarray::IxDyn(shape), data).expect("the shape fits the data");
    // Counted under the buffer: the bytes that reach the file.
    let mut w = std::io::BufWriter::new(Tally::new(file.handle()?));
    array.write_npy(&mut w).map_err(|e| match e {
        // The file's own error, which names it.
        ndarray_npy::WriteNpyError::Io(io) => anyhow::Error::new(io),
        other => anyhow::Error::new(other),
    })?;
    w.flush()?;
    let (bytes, crc32) = w.get_ref().written();
    Ok(Written { bytes, crc32 })
}

pub(crate) fn write_json(file: &AtomicFile, doc: &serde_json::Value) -> Result<()> {
    use std::io::Write;
    let mut w = std::io::BufWriter::new(file.handle()?);
    serde_json::to_writer_pretty(&mut w, doc)?;
    writeln!(w)?;
    w.into_inner().map_err(|e| e.into_error())?;
    Ok(())
}

/// Reads a shard's description (FILE.npy.json).
pub fn read_description(npy: &Path) -> Result<serde_json::Value> {
    let path = PathBuf::from(format!("{}.json", npy.display()));
    let text = read_capped(&path, limits::MAX_DESCRIPTION_BYTES).with_context(|| {
        format!("cannot read {} (the shard's description, written by sweep --shard)", path.display())
    })?;
    serde_json::from_slice(&text).with_context(|| format!("invalid shard description {}", path.display()))
}

/// The bytes of the file at `path`, at most `cap` of them: a larger file (or an endless one,
/// /dev/zero) is an error, found without reading it whole.
pub(crate) fn read_capped(path: &Path, cap: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?.take(cap + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(std::io::Error::other(format!(
            "it is larger than {}, more than a description holds",
            limits::bytes(cap as f64)
        )));
    }
    Ok(bytes)
}
