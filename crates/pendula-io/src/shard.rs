//! Shards of a sweep (or a fractal) and their merge: the description written beside each
//! shard's `.npy` (FILE.npy.json, format [`SHARD_FORMAT`]), read and checked against itself
//! ([`describe`]), against the file it describes ([`verify_data`]: its length and CRC-32),
//! and against the other shards ([`same_run`], [`complete`]); then the shard's rows
//! ([`read_rows`]). Nothing in a shard is taken on trust: every refusal names the file and
//! what is wrong with it.

use std::path::{Path, PathBuf};

use pendula::sweep::Sweep;
use pendula::system::SystemInfo;
use serde_json::{Value, json};

use crate::npy::{Written, checksum};
use crate::{Result, caused, invalid};

/// The format of a shard's description (FILE.npy.json), in `pendula_sweep`. Format 2 added
/// `data` (the .npy file's length and CRC-32, which a merge checks); readers ignore keys they
/// do not know, so adding one needs no new format, and changing one does.
pub const SHARD_FORMAT: u64 = 2;

/// Bytes of a JSON description beside a .npy (a shard's, a sweep's or fractal's summary):
/// some hundred bytes per axis, and it is read whole.
pub const MAX_DESCRIPTION_BYTES: u64 = 1 << 20;

/// One shard, as its description states it.
#[derive(Debug, Clone)]
pub struct Shard {
    /// Its `.npy` file (named in messages).
    pub path: PathBuf,
    /// What identifies the run: shards of one run have the same one.
    pub fingerprint: Value,
    /// The whole run's shape: the grid's axes, slowest first, then the recorded columns.
    pub shape: Vec<usize>,
    /// Shard `k` of `n`.
    pub k: usize,
    /// The number of shards.
    pub n: usize,
    /// Its first cell.
    pub offset: usize,
    /// Its cells.
    pub count: usize,
    /// The length and CRC-32 of its `.npy` file.
    pub data: Written,
    /// Whether the CPU that computed it had fused multiply-adds (absent in older shards).
    pub fma: Option<bool>,
}

/// What the description of a sweep's run says beyond the sweep itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunFacts {
    /// The cells computed, [start, end) of the whole grid (a shard's, or all of them).
    pub cells: (usize, usize),
    /// The length and CRC-32 of the `.npy` file, when written.
    pub data: Option<Written>,
    /// Whether the CPU has fused multiply-adds.
    pub fma: bool,
    /// Worker threads.
    pub threads: usize,
    /// Wall-clock time of the computation, s.
    pub wall_s: f64,
}

/// The description of `sweep`'s run (FILE.npy.json beside the array, and the summary):
/// format, pendula version, system, method, dt (s), steps, axes and their units, columns
/// and their units, the whole shape, the shard, its offset and count, the fingerprint a
/// merge matches, `data` (when given), kernel, fma, threads, wall_s — in that order.
pub fn sweep_description(sweep: &Sweep, run: &RunFacts) -> Value {
    let spec = sweep.spec();
    let (start, end) = run.cells;
    let mut d = json!({
        "pendula_sweep": SHARD_FORMAT,
        "pendula": env!("CARGO_PKG_VERSION"),
        "system": sweep.info().name,
        "method": spec.method.name,
        "dt": spec.h,
        "steps": spec.steps,
        "axes": spec.axes.iter().map(|a| json!({"name": a.name, "lo": a.lo, "hi": a.hi, "n": a.n})).collect::<Vec<_>>(),
        // Units beside, not inside, `axes` and `columns`, whose entries keep their form.
        "axis_units": spec.axes.iter().map(|a| quantity_unit(sweep.info(), &a.name)).collect::<Vec<_>>(),
        "columns": sweep.columns(),
        "units": sweep.columns().iter().map(|c| quantity_unit(sweep.info(), c)).collect::<Vec<_>>(),
        "shape": sweep.shape(),
        "shard": spec.shard.0,
        "shards": spec.shard.1,
        "offset": start,
        "count": end - start,
        "fingerprint": sweep.fingerprint(),
    });
    let fields = d.as_object_mut().expect("an object");
    if let Some(w) = run.data {
        fields.insert("data".into(), json!({ "bytes": w.bytes, "crc32": format!("{:08x}", w.crc32) }));
    }
    fields.insert("kernel".into(), json!(sweep.kernel()));
    fields.insert("fma".into(), json!(run.fma));
    fields.insert("threads".into(), json!(run.threads));
    fields.insert("wall_s".into(), json!(run.wall_s));
    d
}

/// The unit of a swept quantity or recorded column of `info`, as the catalogue writes it
/// (`1` for a dimensionless one): a parameter's or state variable's own, seconds for a flip
/// time, the energy's for an energy error.
pub fn quantity_unit(info: &SystemInfo, name: &str) -> &'static str {
    let or_one = |u: &'static str| if u.is_empty() { "1" } else { u };
    match name {
        "flip_time" => or_one(info.time_unit()),
        "energy_error" => or_one(info.energy_unit()),
        _ => info.quantity(name).map_or("", |q| q.unit),
    }
}

/// The description's path, for messages.
fn json_of(path: &Path) -> String {
    format!("{}.json", path.display())
}

/// The bytes of the file at `path`, at most `cap` of them: a larger file (or an endless one,
/// /dev/zero) is an error, found without reading it whole.
pub fn read_capped(path: &Path, cap: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?.take(cap + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(std::io::Error::other(format!(
            "it is larger than {}, more than a description holds",
            crate::value::bytes(cap as f64)
        )));
    }
    Ok(bytes)
}

/// Reads the description of the shard at `npy` (FILE.npy.json).
pub fn read_description(npy: &Path) -> Result<Value> {
    let path = PathBuf::from(json_of(npy));
    let text = read_capped(&path, MAX_DESCRIPTION_BYTES).map_err(|e| {
        caused(
            format!("cannot read {} (the shard's description, written by sweep --shard)", path.display()),
            &e,
        )
    })?;
    serde_json::from_slice(&text)
        .map_err(|e| caused(format!("invalid shard description {}", path.display()), &e))
}

/// Reads the description of the shard at `path` and checks it against itself: a known
/// format, every field present, an offset and extent that are its shard's of the grid.
pub fn describe(path: &Path) -> Result<Shard> {
    describe_value(&read_description(path)?, path)
}

/// [`describe`] of the description `d` of the shard at `path` (or, for a shard held in
/// memory, named `path`).
pub fn describe_value(d: &Value, path: &Path) -> Result<Shard> {
    let json = json_of(path);
    match d.get("pendula_sweep").and_then(Value::as_u64) {
        Some(SHARD_FORMAT) => {}
        Some(1) => {
            return Err(invalid!(
                "{json} is a shard description of format 1, which has no checksum of the data to check the shard against: run that shard again with this pendula"
            ));
        }
        Some(v) => {
            return Err(invalid!(
                "{json} is a shard description of format {v}, written by a newer pendula: this one reads format {SHARD_FORMAT}"
            ));
        }
        None => {
            return Err(invalid!(
                "{json} is not a sweep shard's description (it has no `pendula_sweep` format number)"
            ));
        }
    }
    let field = |k: &str| d.get(k).cloned().ok_or_else(|| invalid!("{json} has no `{k}`"));
    let count_of = |v: Value, k: &str| -> Result<usize> {
        v.as_u64()
            .and_then(|v| usize::try_from(v).ok())
            .ok_or_else(|| invalid!("{json}: `{k}` is not a count"))
    };
    let number = |k: &str| count_of(field(k)?, k);
    let shape: Vec<usize> = serde_json::from_value(field("shape")?)
        .map_err(|e| caused(format!("{json}: `shape` is not a list of counts"), &e))?;
    let data = field("data")?;
    let bytes =
        data.get("bytes").and_then(Value::as_u64).ok_or_else(|| invalid!("{json}: no `data.bytes`"))?;
    let crc32 = data
        .get("crc32")
        .and_then(Value::as_str)
        .and_then(|t| u32::from_str_radix(t, 16).ok())
        .ok_or_else(|| invalid!("{json}: no `data.crc32` (8 hexadecimal digits)"))?;
    let shard = Shard {
        path: path.to_owned(),
        fingerprint: field("fingerprint")?,
        k: number("shard")?,
        n: number("shards")?,
        offset: number("offset")?,
        count: number("count")?,
        data: Written { bytes, crc32 },
        shape,
        fma: d.get("fma").and_then(Value::as_bool),
    };
    // The grid's cells (all axes; the last dimension is the recorded columns).
    let cells = match shard.shape.split_last() {
        Some((&columns, axes)) if columns >= 1 && !axes.is_empty() && axes.iter().all(|&a| a >= 1) => {
            axes.iter().try_fold(1_usize, |c, &a| c.checked_mul(a))
        }
        _ => None,
    }
    .ok_or_else(|| invalid!("{json}: `shape` {:?} is not a grid's shape", shard.shape))?;
    let (k, n) = (shard.k, shard.n);
    if !(1 <= k && k <= n && n <= cells) {
        return Err(invalid!("{json}: shard {k} of {n} is not a shard of a grid of {cells} cells"));
    }
    // The slices a sharded run cuts: N contiguous ones, as equal as possible. In u128, as
    // the run counts them: k × cells overflows usize for a description's huge grid cut in
    // many shards.
    let slice = |k: usize| (k as u128 * cells as u128 / n as u128) as usize;
    let (start, end) = (slice(k - 1), slice(k));
    if (shard.offset, shard.count) != (start, end - start) {
        return Err(invalid!(
            "{json}: the description says cells {} to {} (offset {}, count {}), but shard {k}/{n} of {cells} cells is cells {start} to {end}: the description does not match the grid",
            shard.offset,
            shard.offset.saturating_add(shard.count),
            shard.offset,
            shard.count
        ));
    }
    Ok(shard)
}

/// Checks that the shard's file is the one its description was written with: its length,
/// then its CRC-32 (`shards`, the run's count, for the message).
pub fn verify_data(s: &Shard, shards: usize) -> Result<()> {
    let cannot = |e: std::io::Error| caused(format!("cannot read {}", s.path.display()), &e);
    let file = std::fs::File::open(&s.path).map_err(cannot)?;
    let len = file.metadata().map_err(cannot)?.len();
    if len != s.data.bytes {
        return Err(invalid!(
            "{}: {len} bytes, but its description {} says {}: the file is truncated or not the shard described",
            s.path.display(),
            json_of(&s.path),
            s.data.bytes
        ));
    }
    let found = checksum(std::io::BufReader::new(file)).map_err(cannot)?;
    if found != s.data {
        return Err(invalid!(
            "{}: its CRC-32 is {:08x}, but its description {} says {:08x}: the file is corrupted or not the shard described (shard {}/{shards})",
            s.path.display(),
            found.crc32,
            json_of(&s.path),
            s.data.crc32,
            s.k
        ));
    }
    Ok(())
}

/// Refuses shards of different runs (another grid, method or records: another fingerprint,
/// shape or shard count than the first's).
pub fn same_run(parts: &[Shard]) -> Result<()> {
    let Some(first) = parts.first() else { return Ok(()) };
    for s in parts {
        if s.fingerprint != first.fingerprint || s.shape != first.shape || s.n != first.n {
            return Err(invalid!(
                "{} is a shard of another sweep than {} (its grid, method or records differ)",
                s.path.display(),
                first.path.display()
            ));
        }
    }
    Ok(())
}

/// Two shards of which one was computed with fused multiply-adds and the other without: they
/// round differently, so that together they are not bitwise what one machine computes.
pub fn fma_mixed(parts: &[Shard]) -> Option<(&Shard, &Shard)> {
    Some((parts.iter().find(|s| s.fma == Some(true))?, parts.iter().find(|s| s.fma == Some(false))?))
}

/// Refuses shards (of one run: [`same_run`]) that are not all N of them, each once: naming
/// the missing ones (five, and how many more) or the two files of one shard.
pub fn complete(parts: &[Shard]) -> Result<()> {
    let Some(first) = parts.first() else { return Ok(()) };
    let shards = first.n;
    let missing = |named: &[String], more: String, absent: usize| {
        invalid!(
            "shard{} {}{more} {} missing: give all {shards} shards",
            if absent > 1 { "s" } else { "" },
            named.join(", "),
            if absent > 1 { "are" } else { "is" }
        )
    };
    // More shards than files: some are missing, found without a table of `shards` entries
    // (their count comes from a file, and may be huge).
    if shards > parts.len() {
        let absent = shards - parts.iter().map(|p| p.k).collect::<std::collections::BTreeSet<_>>().len();
        let named: Vec<String> = (1..=shards)
            .filter(|k| !parts.iter().any(|p| p.k == *k))
            .take(5)
            .map(|k| format!("{k}/{shards}"))
            .collect();
        let more =
            if absent > named.len() { format!(" and {} more", absent - named.len()) } else { String::new() };
        return Err(missing(&named, more, absent));
    }
    let mut seen: Vec<Option<&Path>> = vec![None; shards];
    for s in parts {
        if let Some(other) = seen[s.k - 1].replace(&s.path) {
            return Err(invalid!(
                "{} and {} are both shard {}/{shards}: give each shard once",
                other.display(),
                s.path.display(),
                s.k
            ));
        }
    }
    let named: Vec<String> =
        (1..=shards).filter(|k| seen[k - 1].is_none()).map(|k| format!("{k}/{shards}")).collect();
    if !named.is_empty() {
        let absent = named.len();
        return Err(missing(&named, String::new(), absent));
    }
    Ok(())
}

/// Checks that the header of the shard's file claims what its description says, `(count,
/// columns)` float64, before it is read ([`crate::npy::claim`]).
pub fn check_header(s: &Shard, columns: usize) -> Result<()> {
    let claim = crate::npy::claim(&s.path)?;
    if claim.shape != [s.count, columns] || claim.item != 8 {
        return Err(invalid!(
            "{}: shape {:?} of {}-byte values, its description says ({}, {columns}) float64",
            s.path.display(),
            claim.shape,
            claim.item,
            s.count
        ));
    }
    Ok(())
}

/// The rows of the shard's file (checked by [`verify_data`] and [`check_header`] first),
/// `(count, columns)` float64 in C order.
pub fn read_rows(s: &Shard, columns: usize) -> Result<Vec<f64>> {
    use ndarray_npy::ReadNpyExt;
    let file =
        std::fs::File::open(&s.path).map_err(|e| caused(format!("cannot read {}", s.path.display()), &e))?;
    let array = ndarray::Array2::<f64>::read_npy(std::io::BufReader::new(file))
        .map_err(|e| caused(format!("{} is not a float64 shard array", s.path.display()), &e))?;
    if array.dim() != (s.count, columns) {
        return Err(invalid!(
            "{}: shape {:?}, its description says ({}, {columns})",
            s.path.display(),
            array.dim(),
            s.count
        ));
    }
    Ok(array.as_standard_layout().iter().copied().collect())
}
