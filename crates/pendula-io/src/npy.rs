//! NumPy `.npy` arrays, C order, little-endian: whole arrays of float64 or bytes
//! ([`write()`]), and 2-D float64 arrays streamed row by row behind a header of fixed length
//! ([`streamed_header`]), rewritten with the row count when the rows are done.
//!
//! Every byte written is counted and checksummed on the way ([`Tally`]): a shard's
//! description records its file's length and CRC-32 ([`Written`]), and a checkpoint how much
//! of a streamed trajectory is on disk.
//!
//! A file read is first checked for what its header claims ([`claim`]): a reader allocates
//! what the header says, and a header that claims 10¹⁵ values would abort the process.
//!
//! The two headers differ as numpy's writers do: a whole array's dictionary is
//! `{'descr': '<f8', 'fortran_order': False, 'shape': (7, 11, 4)}`, padded with at least one
//! space to a multiple of 64 bytes (format 1.0, or 2.0 when longer than 65535 bytes); a
//! streamed array's ends in `, }` as `numpy.save` writes it, and is padded to the length of
//! the longest row count's header, so that the final count fits in place.

use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};

use crate::value::clip;
use crate::{Result, invalid};

/// The format's alignment of the data: the header's length is a multiple of it.
const ALIGN: usize = 64;
/// Magic string and format version 1.0.
const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// A value an array holds: its type's descriptor and its little-endian bytes.
pub trait Element: Copy {
    /// numpy's type descriptor (`<f8`).
    const DESCR: &'static str;
    /// Appends the value's bytes.
    fn extend(self, out: &mut Vec<u8>);
}

impl Element for f64 {
    const DESCR: &'static str = "<f8";
    fn extend(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl Element for u8 {
    const DESCR: &'static str = "|u1";
    fn extend(self, out: &mut Vec<u8>) {
        out.push(self);
    }
}

/// What was written: a file's length in bytes and its CRC-32.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Written {
    /// Bytes.
    pub bytes: u64,
    /// CRC-32 (IEEE) of the bytes.
    pub crc32: u32,
}

/// A writer that counts the bytes through it and their CRC-32.
pub struct Tally<W> {
    inner: W,
    bytes: u64,
    crc: crc32fast::Hasher,
}

impl<W> Tally<W> {
    /// Counting from nothing.
    pub fn new(inner: W) -> Self {
        Tally { inner, bytes: 0, crc: crc32fast::Hasher::new() }
    }

    /// Counting on from `bytes` bytes already written, whose checksum `crc` holds (a file
    /// continued where a checkpoint left it).
    pub fn resume(inner: W, bytes: u64, crc: crc32fast::Hasher) -> Self {
        Tally { inner, bytes, crc }
    }

    /// The bytes written through it so far and their CRC-32.
    pub fn written(&self) -> (u64, u32) {
        (self.bytes, self.crc.clone().finalize())
    }

    /// The writer underneath.
    pub fn get_ref(&self) -> &W {
        &self.inner
    }

    /// The writer underneath, with what was counted.
    pub fn into_parts(self) -> (W, u64, crc32fast::Hasher) {
        (self.inner, self.bytes, self.crc)
    }
}

impl<W: Write> Write for Tally<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// The length and CRC-32 of what `reader` holds, read to its end.
pub fn checksum(mut reader: impl Read) -> io::Result<Written> {
    let mut sink = Tally::new(io::sink());
    io::copy(&mut reader, &mut sink)?;
    let (bytes, crc32) = sink.written();
    Ok(Written { bytes, crc32 })
}

/// The header of a whole C-order array of `T` of `shape`: format 1.0, or 2.0 when the
/// dictionary does not fit 1.0's two-byte length; `None` when it fits neither (a shape of
/// some hundred million axes).
pub fn header<T: Element>(shape: &[usize]) -> Option<Vec<u8>> {
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let tuple = match dims.len() {
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    };
    let dict = format!("{{'descr': '{}', 'fortran_order': False, 'shape': {tuple}}}", T::DESCR);
    [(1u8, 2usize), (2, 4)].into_iter().find_map(|(major, size)| {
        let prefix = MAGIC.len() + 2 + size;
        // At least one space of padding, then the newline.
        let unpadded = prefix + dict.len() + 1;
        let total = unpadded + ALIGN - unpadded % ALIGN;
        let length = total - prefix;
        let length = match size {
            2 => u16::try_from(length).ok()?.to_le_bytes().to_vec(),
            _ => u32::try_from(length).ok()?.to_le_bytes().to_vec(),
        };
        Some(frame(major, &length, &dict, total))
    })
}

/// The header of a streamed 2-D float64 array of (rows, columns): format 1.0, its length
/// `min_len` bytes or the next multiple of 64 (pass the length of `streamed_header(u64::MAX,
/// columns, 0)`, so that every row count's header has the same length).
pub fn streamed_header(rows: u64, columns: usize, min_len: usize) -> Vec<u8> {
    let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {columns}), }}");
    // 6 bytes of magic, 2 of version, 2 of length, the dictionary and its newline.
    let unpadded = 10 + dict.len() + 1;
    let total = (unpadded.div_ceil(ALIGN).max(1) * ALIGN).max(min_len);
    let length = u16::try_from(total - 10).expect("a short header").to_le_bytes();
    frame(1, &length, &dict, total)
}

/// A 2-D little-endian float64 array in NPY format 1.0, streamed row by row into `W`: the
/// header ([`streamed_header`]) is written first with room for any row count, and rewritten
/// with the real one at the end. Into a file that cannot seek (a FIFO), the rows go to a
/// spool file the caller gives (an unnamed temporary file) and follow the final header at the
/// end. Every byte that reaches `W` is counted ([`Tally`]).
pub struct Rows<W: Write + Seek> {
    out: BufWriter<Tally<W>>,
    /// The rows, when `out` cannot seek.
    spool: Option<BufWriter<File>>,
    columns: usize,
    rows: u64,
    header_len: usize,
}

impl<W: Write + Seek> Rows<W> {
    /// Starts the array in `file` (at its start); `spool` receives the rows when `file`
    /// cannot seek.
    pub fn new(file: W, columns: usize, spool: Option<File>) -> io::Result<Self> {
        // The header's size for the longest row count; every header is padded to it.
        let header_len = streamed_header_len(columns);
        let mut out = BufWriter::with_capacity(1 << 16, Tally::new(file));
        if spool.is_none() {
            out.write_all(&streamed_header(0, columns, header_len))?;
        }
        let spool = spool.map(|f| BufWriter::with_capacity(1 << 16, f));
        Ok(Rows { out, spool, columns, rows: 0, header_len })
    }

    /// Continues an array of `rows` rows whose bytes so far `file` has counted (a file
    /// continued where a checkpoint left it).
    pub fn resume(file: Tally<W>, columns: usize, rows: u64) -> Self {
        let header_len = streamed_header_len(columns);
        Rows { out: BufWriter::with_capacity(1 << 16, file), spool: None, columns, rows, header_len }
    }

    /// Appends one row of `columns` values.
    pub fn row(&mut self, values: impl Iterator<Item = f64>) -> io::Result<()> {
        let w: &mut dyn Write = match &mut self.spool {
            Some(spool) => spool,
            None => &mut self.out,
        };
        let mut n = 0;
        for v in values {
            w.write_all(&v.to_le_bytes())?;
            n += 1;
        }
        debug_assert_eq!(n, self.columns, "a row has one value per column");
        self.rows += 1;
        Ok(())
    }

    /// Flushes the rows to the file and says how many bytes it holds and their CRC-32.
    ///
    /// # Panics
    /// When the rows are spooled: a file that cannot seek has no position to record.
    pub fn position(&mut self) -> io::Result<(u64, u32)> {
        assert!(self.spool.is_none(), "a checkpointed trajectory is a regular file");
        self.out.flush()?;
        Ok(self.out.get_ref().written())
    }

    /// Writes the header with the final shape.
    pub fn finish(self) -> io::Result<()> {
        let header = streamed_header(self.rows, self.columns, self.header_len);
        let mut out = self.out;
        match self.spool {
            Some(spool) => {
                let mut spool = spool.into_inner().map_err(|e| e.into_error())?;
                spool.seek(SeekFrom::Start(0))?;
                out.write_all(&header)?;
                io::copy(&mut spool, &mut out)?;
                out.flush()?;
            }
            None => {
                let mut file = out.into_inner().map_err(|e| e.into_error())?.into_parts().0;
                file.seek(SeekFrom::Start(0))?;
                file.write_all(&header)?;
                file.flush()?;
            }
        }
        Ok(())
    }
}

/// The length of every streamed header of `columns` columns: the longest row count's.
pub fn streamed_header_len(columns: usize) -> usize {
    streamed_header(u64::MAX, columns, 0).len()
}

/// Magic, version `major`.0, the encoded `length`, the dictionary, spaces to `total - 1`
/// bytes and the newline.
fn frame(major: u8, length: &[u8], dict: &str, total: usize) -> Vec<u8> {
    let mut header = Vec::with_capacity(total);
    header.extend_from_slice(MAGIC);
    header.extend_from_slice(&[major, 0]);
    header.extend_from_slice(length);
    header.extend_from_slice(dict.as_bytes());
    header.resize(total - 1, b' ');
    header.push(b'\n');
    header
}

/// Writes `data`, a C-order array of `shape`, as a `.npy` file into `w` (unbuffered: give it
/// a buffered writer); what was written.
///
/// # Panics
/// When `shape`'s product is not `data`'s length.
pub fn write<T: Element>(w: impl Write, shape: &[usize], data: &[T]) -> io::Result<Written> {
    assert_eq!(shape.iter().product::<usize>(), data.len(), "the shape fits the data");
    let header = header::<T>(shape)
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "a shape too long for a .npy header"))?;
    let mut w = Tally::new(w);
    w.write_all(&header)?;
    let mut buf = Vec::with_capacity(1 << 16);
    for chunk in data.chunks(8192) {
        buf.clear();
        chunk.iter().for_each(|v| v.extend(&mut buf));
        w.write_all(&buf)?;
    }
    w.flush()?;
    let (bytes, crc32) = w.written();
    Ok(Written { bytes, crc32 })
}

/// What a .npy file's header says it holds, checked against the file's length before
/// anything is allocated: a reader allocates what the header claims, and a header that
/// claims 10¹⁵ values would abort the process.
#[derive(Debug, Clone, PartialEq)]
pub struct Claim {
    /// The array's shape.
    pub shape: Vec<usize>,
    /// Bytes per value (8 for float64, 1 for uint8).
    pub item: usize,
}

impl Claim {
    /// The number of values.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether it holds no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Reads and checks the header of the .npy at `path` (format 1, 2 or 3): the values its
/// shape and type claim must be what the file holds after the header.
pub fn claim(path: &std::path::Path) -> Result<Claim> {
    let name = path.display();
    let file = std::fs::File::open(path).map_err(|e| invalid!("cannot read {name}: {e}"))?;
    let length = file.metadata().map_err(|e| invalid!("cannot read {name}: {e}"))?.len();
    claim_from(file, length, &name.to_string())
}

/// [`claim`] of the .npy `file`, `length` bytes long, named `name` in messages (a file held
/// in memory).
pub fn claim_from(mut file: impl std::io::Read, length: u64, name: &str) -> Result<Claim> {
    let bad = |why: &str| invalid!("{name} is not a valid .npy file: {why}");
    let mut head = [0u8; 12];
    file.read_exact(&mut head[..10]).map_err(|_| bad("too short for a header"))?;
    if &head[..6] != b"\x93NUMPY" {
        return Err(bad("no NUMPY magic"));
    }
    let (header_len, prefix) = match head[6] {
        1 => (u16::from_le_bytes([head[8], head[9]]) as u64, 10),
        2 | 3 => {
            file.read_exact(&mut head[10..12]).map_err(|_| bad("too short for a header"))?;
            (u32::from_le_bytes([head[8], head[9], head[10], head[11]]) as u64, 12)
        }
        v => return Err(bad(&format!("unknown format version {v}"))),
    };
    if prefix + header_len > length {
        return Err(bad("its header is longer than the file"));
    }
    if header_len > MAX_NPY_HEADER {
        return Err(bad(&format!(
            "its header is longer than {}",
            crate::value::bytes(MAX_NPY_HEADER as f64)
        )));
    }
    let mut header = head[..prefix as usize].to_vec();
    header.resize((prefix + header_len) as usize, 0);
    file.read_exact(&mut header[prefix as usize..]).map_err(|_| bad("its header is cut short"))?;
    // The reader's parser backtracks, taking twice as long for every level of nesting: a
    // header of 200 bytes nested 30 deep would take days. numpy writes 2 levels (a dict and
    // its shape tuple), a few more for structured types.
    if let Some(depth) = nesting_beyond(&header[prefix as usize..], MAX_NPY_NESTING) {
        return Err(bad(&format!(
            "its header nests {depth} deep, more than {MAX_NPY_NESTING} (numpy writes 2 or 3)"
        )));
    }
    // The header as the reader (ndarray-npy) parses it, which allocates what its shape says:
    // a parse of our own could find another shape than the reader's (a key given twice, a
    // key inside a string), and pass a file whose reading then allocates 10^15 values.
    let header = ndarray_npy::npy::header::Header::from_reader(&mut header.as_slice()).map_err(|e| {
        let why = e.to_string();
        bad(&format!("its header: {}", clip(why.lines().next().unwrap_or(""))))
    })?;
    let descr = header
        .type_descriptor
        .as_string()
        .ok_or_else(|| bad(&format!("unknown value type `{}`", clip(&header.type_descriptor.to_string()))))?;
    let item: usize = descr
        .trim_start_matches(|c: char| !c.is_ascii_digit())
        .parse()
        .map_err(|_| bad(&format!("unknown value type `{}`", clip(descr))))?;
    if item == 0 {
        // Any count of them fits in no data: the count could not be checked.
        return Err(bad(&format!("its values (`{}`) take no bytes", clip(descr))));
    }
    let shape = header.shape;
    // The array library counts the lengths of the non-empty axes, and refuses (the reader
    // unwraps: a panic) a shape whose count is beyond isize, even with no values: (0, 2^63).
    let counted = shape.iter().filter(|&&d| d != 0).try_fold(1u128, |n, &d| n.checked_mul(d as u128));
    if counted.is_none_or(|n| n > isize::MAX as u128) {
        return Err(bad(&format!(
            "its header claims a shape {} beyond counting",
            clip(&format!("{shape:?}"))
        )));
    }
    let values = shape.iter().try_fold(1u128, |n, &d| n.checked_mul(d as u128));
    let data = length - prefix - header_len;
    match values.and_then(|v| v.checked_mul(item as u128)) {
        Some(bytes) if bytes == data as u128 => Ok(Claim { shape, item }),
        Some(bytes) => Err(bad(&format!(
            "its header claims {} values of {item} bytes ({}), but the file holds {} after the header",
            clip(&format!("{shape:?}")),
            crate::value::bytes(bytes as f64),
            crate::value::bytes(data as f64)
        ))),
        None => {
            Err(bad(&format!("its header claims a shape {} beyond counting", clip(&format!("{shape:?}")))))
        }
    }
}

/// Bytes of a .npy header: numpy writes about 100 (padded to a multiple of 64).
const MAX_NPY_HEADER: u64 = 1 << 20;

/// Nesting of brackets in a .npy header: see [`claim_from`].
const MAX_NPY_NESTING: usize = 8;

/// The depth of `(`, `[` and `{` in a Python literal (outside its strings), if it goes
/// beyond `max`.
fn nesting_beyond(text: &[u8], max: usize) -> Option<usize> {
    let (mut depth, mut quote, mut escaped) = (0usize, None, false);
    for &b in text {
        match quote {
            Some(q) => {
                if escaped {
                    escaped = false;
                } else if b == b'\\' {
                    escaped = true;
                } else if b == q {
                    quote = None;
                }
            }
            None => match b {
                b'\'' | b'"' => quote = Some(b),
                b'(' | b'[' | b'{' => {
                    depth += 1;
                    if depth > max {
                        return Some(depth);
                    }
                }
                b')' | b']' | b'}' => depth = depth.saturating_sub(1),
                _ => {}
            },
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_headers_are_aligned_and_of_one_length() {
        let long = streamed_header(u64::MAX, 6, 0).len();
        assert_eq!(long % 64, 0);
        let short = streamed_header(3, 6, long);
        assert_eq!(short.len(), long);
        assert_eq!(&short[..8], b"\x93NUMPY\x01\x00");
        assert_eq!(usize::from(u16::from_le_bytes([short[8], short[9]])), long - 10);
        assert!(short.ends_with(b" \n"));
    }

    #[test]
    fn whole_arrays_have_numpys_header() {
        let h = header::<f64>(&[7, 11, 4]).expect("a short header");
        let dict = b"{'descr': '<f8', 'fortran_order': False, 'shape': (7, 11, 4)}";
        assert_eq!(h.len(), 128);
        assert_eq!(&h[..8], b"\x93NUMPY\x01\x00");
        assert_eq!(u16::from_le_bytes([h[8], h[9]]), 118);
        assert_eq!(&h[10..10 + dict.len()], dict);
        assert!(h[10 + dict.len()..127].iter().all(|&b| b == b' ') && h[127] == b'\n');
        // A 1-D shape is a one-tuple; bytes are `|u1`.
        let h = header::<u8>(&[5]).expect("a short header");
        assert!(
            String::from_utf8_lossy(&h).contains("{'descr': '|u1', 'fortran_order': False, 'shape': (5,)} ")
        );
        // A dictionary that ends exactly on the boundary is padded by a whole 64 bytes.
        for n in 0..200 {
            let h = header::<f64>(&[n, 3]).expect("a short header");
            assert_eq!(h.len() % 64, 0);
            assert_eq!(h[h.len() - 2], b' ');
        }
    }

    /// The bytes ndarray-npy writes, which the CLI wrote before this writer (sweeps, merges,
    /// fractals): every file stays byte-identical.
    #[test]
    fn regress_whole_arrays_are_ndarray_npys_bytes() {
        use ndarray_npy::WriteNpyExt;
        fn theirs<T: ndarray_npy::WritableElement>(shape: &[usize], data: &[T]) -> Vec<u8> {
            let mut out = Vec::new();
            let a = ndarray::ArrayViewD::from_shape(ndarray::IxDyn(shape), data).expect("the shape fits");
            a.write_npy(&mut out).expect("in memory");
            out
        }
        let shapes: Vec<Vec<usize>> = (0..300)
            .map(|n| vec![n, 4])
            .chain([vec![3], vec![7, 11, 6], vec![1, 1, 1, 1, 1, 1, 1, 2], vec![123_456_789, 0], vec![]])
            .chain((0..40).map(|n| vec![2; n % 13].into_iter().chain([n]).collect()))
            .collect();
        for shape in &shapes {
            let data: Vec<f64> = (0..shape.iter().product::<usize>()).map(|i| i as f64 * 0.1 - 3.0).collect();
            let mut mine = Vec::new();
            write(&mut mine, shape, &data).expect("in memory");
            assert_eq!(mine, theirs(shape, &data), "{shape:?}");
            let bytes: Vec<u8> = (0..data.len()).map(|i| i as u8).collect();
            let mut mine = Vec::new();
            write(&mut mine, shape, &bytes).expect("in memory");
            assert_eq!(mine, theirs(shape, &bytes), "{shape:?} of u8");
        }
    }

    /// A .npy file (format 1) of `header` and `data`.
    fn npy(header: &str, data: &[u8]) -> Vec<u8> {
        let header = format!("{header}\n");
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        bytes.extend((header.len() as u16).to_le_bytes());
        bytes.extend(header.bytes());
        bytes.extend(data);
        bytes
    }

    fn claim(bytes: &[u8]) -> crate::Result<Claim> {
        claim_from(bytes, bytes.len() as u64, "x.npy")
    }

    #[test]
    fn npy_headers_are_read_as_the_reader_reads_them() {
        let plain = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 1), }";
        assert_eq!(claim(&npy(plain, &[0; 16])).unwrap(), Claim { shape: vec![2, 1], item: 8 });
        // A key given twice is the last one's, as ndarray-npy (and Python) take it: the
        // shape checked is the one allocated for.
        let twice = "{'descr': '<f8', 'fortran_order': False, 'shape': (1,), 'shape': (1000000000000000,), }";
        let err = claim(&npy(twice, &[0; 8])).unwrap_err().to_string();
        assert!(err.contains("[1000000000000000]"), "{err}");
        // No values, but an axis that the array library cannot count (its reader panicked).
        let empty = "{'descr': '<f8', 'fortran_order': False, 'shape': (0, 9223372036854775808), }";
        assert!(claim(&npy(empty, &[])).unwrap_err().to_string().contains("beyond counting"));
        // Values of no bytes cannot be counted against the data.
        let empty = "{'descr': '|V0', 'fortran_order': False, 'shape': (100000000000,), }";
        assert!(claim(&npy(empty, &[])).unwrap_err().to_string().contains("take no bytes"));
    }

    #[test]
    fn npy_header_nesting_is_counted_outside_strings() {
        assert_eq!(nesting_beyond(b"{'shape': (1, 2)}", 2), None);
        assert_eq!(nesting_beyond(b"{'x': ((1,),)}", 2), Some(3));
        assert_eq!(nesting_beyond(b"{'x': '((((', \"[[[\\\"[[\"}", 1), None);
        let deep = format!(
            "{{'descr': '<f8', 'fortran_order': False, 'shape': (1,), 'x': {}1{}}}",
            "{1: ".repeat(40),
            "}".repeat(40)
        );
        let err = claim(&npy(&deep, &[0; 8])).unwrap_err().to_string();
        assert!(err.contains("nests 9 deep"), "{err}");
    }

    #[test]
    fn streamed_rows_end_as_a_whole_array_with_its_row_count() {
        let mut file = io::Cursor::new(Vec::new());
        let mut rows = Rows::new(&mut file, 2, None).expect("in memory");
        rows.row([1.0, 2.0].into_iter()).expect("in memory");
        let (bytes, _) = rows.position().expect("in memory");
        assert_eq!(bytes as usize, streamed_header_len(2) + 16);
        rows.row([3.0, 4.0].into_iter()).expect("in memory");
        rows.finish().expect("in memory");
        let out = file.into_inner();
        assert_eq!(&out[..streamed_header_len(2)], streamed_header(2, 2, streamed_header_len(2)));
        assert_eq!(out.len(), streamed_header_len(2) + 32);
        // Spooled (a FIFO): the same bytes.
        let spool = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(std::env::temp_dir().join(format!("pendula-io-spool-{}", std::process::id())));
        let spool = spool.expect("a temporary file");
        let mut fifo = io::Cursor::new(Vec::new());
        let mut rows = Rows::new(&mut fifo, 2, Some(spool)).expect("in memory");
        rows.row([1.0, 2.0].into_iter()).expect("in memory");
        rows.row([3.0, 4.0].into_iter()).expect("in memory");
        rows.finish().expect("in memory");
        let _ = std::fs::remove_file(
            std::env::temp_dir().join(format!("pendula-io-spool-{}", std::process::id())),
        );
        assert_eq!(fifo.into_inner(), out);
    }

    #[test]
    fn writes_count_their_bytes_and_crc() {
        let mut out = Vec::new();
        let w = write(&mut out, &[2, 3], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).expect("in memory");
        assert_eq!(w.bytes as usize, out.len());
        // 10 bytes of prefix and 58 of dictionary: padded to 128.
        assert_eq!(out.len(), 128 + 48);
        assert_eq!(&out[128..136], &1.0f64.to_le_bytes());
        assert_eq!(checksum(out.as_slice()).expect("in memory"), w);
        assert_eq!(w.crc32, crc32fast::hash(&out));
    }
}
