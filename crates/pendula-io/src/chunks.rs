//! The chunk files of a grid computed with a checkpoint (`sweep --checkpoint`, `fractal
//! --checkpoint`): the cells are computed a chunk at a time, and each finished chunk's values
//! (little-endian float64, cell after cell) are appended to `FILE.chunks` beside the
//! checkpoint FILE ([`data_path`]), which lists the chunks done, in the order of their values
//! in that file, with the CRC-32 of each ([`fields`]). A resumed run reads them back, checked
//! ([`read_done`]).

use std::io::Read;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use crate::{Result, caused, invalid};

/// The values file of checkpoint `path`: `path` with `.chunks` appended.
pub fn data_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".chunks");
    PathBuf::from(name)
}

/// Cells per chunk for `cells` cells on `threads` threads: about 256 chunks, each large
/// enough to keep every thread busy (the ensemble engine hands out 256 members at a time).
pub fn chunk_size(cells: usize, threads: usize) -> usize {
    cells.div_ceil(256).max(1024 * threads).div_ceil(256) * 256
}

/// How a grid is cut: `cells` cells of `width` values each, in chunks of `chunk` cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// Cells in all.
    pub cells: usize,
    /// Values per cell.
    pub width: usize,
    /// Cells per chunk (the last may hold fewer).
    pub chunk: usize,
}

impl Layout {
    /// The number of chunks.
    pub fn count(&self) -> usize {
        self.cells.div_ceil(self.chunk)
    }

    /// The cells of chunk `index`.
    pub fn range(&self, index: usize) -> Range<usize> {
        index * self.chunk..((index + 1) * self.chunk).min(self.cells)
    }
}

/// A finished chunk's `values` as the values file holds them, and their CRC-32.
pub fn encode(values: &[f64]) -> (Vec<u8>, u32) {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let crc = crc32fast::hash(&bytes);
    (bytes, crc)
}

/// The checkpoint's fields that describe the chunks: the layout and the chunks `done`
/// (index, CRC-32), in the order of their values in the values file.
pub fn fields(layout: &Layout, done: &[(usize, u32)]) -> Value {
    json!({
        "cells": layout.cells,
        "width": layout.width,
        "chunk": layout.chunk,
        "chunks_done": done.len(),
        "chunks": layout.count(),
        "done": done,
    })
}

/// Reads the chunks `done` back from the values file `data` (named `data_path`, of the
/// checkpoint named `name`) into `out` (cells × width values), each checked against its
/// CRC-32: which chunks are done, and the bytes they take (what follows them was written
/// after the checkpoint, and is computed again).
pub fn read_done(
    data: &mut impl Read,
    layout: &Layout,
    done: &[(usize, u32)],
    out: &mut [f64],
    name: &str,
    data_path: &Path,
) -> Result<(Vec<bool>, u64)> {
    let (width, count) = (layout.width, layout.count());
    let mut finished = vec![false; count];
    let mut length = 0u64;
    for &(index, crc) in done {
        if index >= count || std::mem::replace(&mut finished[index], true) {
            return Err(invalid!("the checkpoint {name} lists chunk {index} twice or out of range"));
        }
        let range = layout.range(index);
        let mut bytes = vec![0u8; range.len() * width * 8];
        data.read_exact(&mut bytes).map_err(|e| {
            caused(
                format!("{} is shorter than its checkpoint {name} says: it was cut", data_path.display()),
                &e,
            )
        })?;
        if crc32fast::hash(&bytes) != crc {
            return Err(invalid!(
                "chunk {index} in {} does not match its checkpoint {name} (checksum): it was changed",
                data_path.display()
            ));
        }
        for (o, b) in out[range.start * width..range.end * width].iter_mut().zip(bytes.chunks_exact(8)) {
            *o = f64::from_le_bytes(b.try_into().expect("8 bytes"));
        }
        length += bytes.len() as u64;
    }
    Ok((finished, length))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finished_chunks_read_back_checked() {
        let layout = Layout { cells: 5, width: 2, chunk: 2 };
        assert_eq!((layout.count(), layout.range(2)), (3, 4..5));
        let values: Vec<f64> = (0..10).map(|i| i as f64 * 0.5 - 1.0).collect();
        // Chunks 2 and 0 done, in that order in the file.
        let (c2, crc2) = encode(&values[8..10]);
        let (c0, crc0) = encode(&values[0..4]);
        let file = [c2.clone(), c0].concat();
        let done = [(2, crc2), (0, crc0)];
        let mut out = vec![f64::NAN; 10];
        let name = "run.ckpt";
        let (finished, length) =
            read_done(&mut file.as_slice(), &layout, &done, &mut out, name, Path::new("run.ckpt.chunks"))
                .expect("intact chunks");
        assert_eq!(finished, [true, false, true]);
        assert_eq!(length as usize, file.len());
        assert_eq!(&out[..4], &values[..4]);
        assert_eq!(&out[8..], &values[8..]);
        assert!(out[4..8].iter().all(|v| v.is_nan()));
        let f = fields(&layout, &done);
        assert_eq!(f["chunks"], 3);
        assert_eq!(f["done"], json!([[2, crc2], [0, crc0]]));
        // A changed byte, a cut file, a chunk listed twice: each refused, naming it.
        let mut changed = file.clone();
        changed[0] ^= 1;
        let read = |bytes: &[u8], done: &[(usize, u32)]| {
            read_done(&mut &bytes[..], &layout, done, &mut out.clone(), name, Path::new("run.ckpt.chunks"))
                .unwrap_err()
                .to_string()
        };
        assert!(read(&changed, &done).contains("chunk 2 in run.ckpt.chunks does not match"));
        assert!(read(&file[..20], &done).contains("is shorter than its checkpoint run.ckpt says"));
        assert!(read(&file, &[(2, crc2), (2, crc2)]).contains("lists chunk 2 twice or out of range"));
        assert_eq!(data_path(Path::new("a/run.ckpt")), Path::new("a/run.ckpt.chunks"));
        // 10^6 cells: about 256 chunks (245) of a multiple of 256 cells.
        assert_eq!(chunk_size(1_000_000, 2), 4_096);
        assert_eq!(chunk_size(1_000, 2), 2_048);
    }
}
