//! `pendula merge`: assembles the shards of one sweep (`pendula sweep --shard K/N`) into
//! the full array, bitwise equal to the unsharded run. Nothing in a shard is taken on trust:
//! each description (FILE.npy.json) must be of a format this pendula reads, its offset and
//! extent must be those of its shard of the grid, and its data must have the length and the
//! CRC-32 written with it; shards of different sweeps, repeated or missing shards, and
//! truncated or corrupted files are refused, naming which. The output may not be one of the
//! inputs, nor stdout.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use ndarray_npy::ReadNpyExt;
use serde_json::Value;

use crate::args::LargeArg;
use crate::output::{AtomicFile, claim_input};
use crate::shards::{SHARD_FORMAT, Written, checksum, read_description};

#[derive(Debug, Clone, Args)]
pub struct MergeArgs {
    /// The shards' .npy files (each with its FILE.npy.json description).
    #[arg(required = true, value_name = "SHARD.npy")]
    pub shards: Vec<PathBuf>,
    /// The full array (a new path: not one of the shards).
    #[arg(long, value_name = "FILE.npy")]
    pub out: PathBuf,
    #[command(flatten)]
    pub large: LargeArg,
}

/// One shard, as its description states it.
pub struct Shard {
    pub path: PathBuf,
    pub fingerprint: Value,
    pub shape: Vec<usize>,
    pub k: usize,
    pub n: usize,
    pub offset: usize,
    pub count: usize,
    pub data: Written,
    /// Whether the CPU that computed it had fused multiply-adds (absent in older shards).
    pub fma: Option<bool>,
}

/// The description's path, for messages.
fn json_of(path: &Path) -> String {
    format!("{}.json", path.display())
}

/// Reads and checks the description of the shard at `path` against itself: a known format,
/// every field present, an offset and extent that are its shard's of the grid.
pub fn describe(path: &Path) -> Result<Shard> {
    let d = read_description(path)?;
    let json = json_of(path);
    match d.get("pendula_sweep").and_then(Value::as_u64) {
        Some(SHARD_FORMAT) => {}
        Some(1) => bail!(
            "{json} is a shard description of format 1, which has no checksum of the data to check the shard against: run that shard again with this pendula"
        ),
        Some(v) => bail!(
            "{json} is a shard description of format {v}, written by a newer pendula: this one reads format {SHARD_FORMAT}"
        ),
        None => bail!("{json} is not a sweep shard's description (it has no `pendula_sweep` format number)"),
    }
    let field = |k: &str| d.get(k).cloned().with_context(|| format!("{json} has no `{k}`"));
    let count_of = |v: Value, k: &str| -> Result<usize> {
        v.as_u64()
            .and_then(|v| usize::try_from(v).ok())
            .with_context(|| format!("{json}: `{k}` is not a count"))
    };
    let number = |k: &str| count_of(field(k)?, k);
    let shape: Vec<usize> = serde_json::from_value(field("shape")?)
        .with_context(|| format!("{json}: `shape` is not a list of counts"))?;
    let data = field("data")?;
    let bytes =
        data.get("bytes").and_then(Value::as_u64).with_context(|| format!("{json}: no `data.bytes`"))?;
    let crc32 = data
        .get("crc32")
        .and_then(Value::as_str)
        .and_then(|t| u32::from_str_radix(t, 16).ok())
        .with_context(|| format!("{json}: no `data.crc32` (8 hexadecimal digits)"))?;
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
    .with_context(|| format!("{json}: `shape` {:?} is not a grid's shape", shard.shape))?;
    let (k, n) = (shard.k, shard.n);
    if !(1 <= k && k <= n && n <= cells) {
        bail!("{json}: shard {k} of {n} is not a shard of a grid of {cells} cells");
    }
    // The slices `sweep` cuts: N contiguous ones, as equal as possible. In u128, as `sweep`
    // counts them: k × cells overflows usize for a description's huge grid cut in many shards.
    let slice = |k: usize| (k as u128 * cells as u128 / n as u128) as usize;
    let (start, end) = (slice(k - 1), slice(k));
    if (shard.offset, shard.count) != (start, end - start) {
        bail!(
            "{json}: the description says cells {} to {} (offset {}, count {}), but shard {k}/{n} of {cells} cells is cells {start} to {end}: the description does not match the grid",
            shard.offset,
            shard.offset.saturating_add(shard.count),
            shard.offset,
            shard.count
        );
    }
    Ok(shard)
}

/// Checks that the shard's file is the one its description was written with: its length,
/// then its CRC-32 (`shards`, the sweep's count, for the message).
pub(crate) fn verify_data(s: &Shard, shards: usize) -> Result<()> {
    let file = std::fs::File::open(&s.path).with_context(|| format!("cannot read {}", s.path.display()))?;
    let len = file.metadata().with_context(|| format!("cannot read {}", s.path.display()))?.len();
    if len != s.data.bytes {
        bail!(
            "{} is {len} bytes, but its description {} says {}: the file is truncated or not the shard described",
            s.path.display(),
            json_of(&s.path),
            s.data.bytes
        );
    }
    let found = checksum(std::io::BufReader::new(file))
        .with_context(|| format!("cannot read {}", s.path.display()))?;
    if found != s.data {
        bail!(
            "{}: its CRC-32 is {:08x}, but its description {} says {:08x}: the file is corrupted or not the shard described (shard {}/{shards})",
            s.path.display(),
            found.crc32,
            json_of(&s.path),
            s.data.crc32,
            s.k
        );
    }
    Ok(())
}

pub fn run(args: &MergeArgs) -> Result<()> {
    if args.out == Path::new("-") {
        bail!("invalid --out -: merge writes a .npy file, not stdout; give FILE.npy");
    }
    if args.out.extension().and_then(|e| e.to_str()) != Some("npy") {
        bail!("invalid --out {}: merge writes .npy", args.out.display());
    }
    // The inputs first: an output onto one of them is refused before anything is read.
    for path in &args.shards {
        claim_input(path, "input shard")?;
        claim_input(Path::new(&json_of(path)), "shard description")?;
    }
    let out = AtomicFile::create(&args.out, "--out")?;
    let (shape, data, parts, _) = gather(&args.shards, args.large.allow_large)?;
    crate::shards::write_npy(&out, &shape, &data)?;
    out.commit()?;
    eprintln!("merged {parts} shards into {} {:?}", args.out.display(), shape);
    Ok(())
}

/// The whole array of the shards at `paths` (claimed as inputs by the caller), checked as
/// `merge` checks them: its shape, its values, the number of shards and their fingerprint.
pub(crate) fn gather(paths: &[PathBuf], allow_large: bool) -> Result<(Vec<usize>, Vec<f64>, usize, Value)> {
    let parts = paths.iter().map(|p| describe(p)).collect::<Result<Vec<_>>>()?;
    let first = &parts[0];
    for s in &parts {
        if s.fingerprint != first.fingerprint || s.shape != first.shape || s.n != first.n {
            bail!(
                "{} is a shard of another sweep than {} (its grid, method or records differ)",
                s.path.display(),
                first.path.display()
            );
        }
    }
    // Shards from CPUs that round differently (with and without FMA) are each right, and
    // together not bitwise what one machine computes: said, not refused (nothing is lost).
    if let (Some(a), Some(b)) =
        (parts.iter().find(|s| s.fma == Some(true)), parts.iter().find(|s| s.fma == Some(false)))
    {
        eprintln!(
            "warning: {} was computed on a CPU with fused multiply-adds and {} on one without: they round differently, so the merged array is not bitwise what one machine computes",
            a.path.display(),
            b.path.display()
        );
    }
    let shards = first.n;
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
        bail!(
            "shard{} {}{more} {} missing: give all {shards} shards",
            if absent > 1 { "s" } else { "" },
            named.join(", "),
            if absent > 1 { "are" } else { "is" }
        );
    }
    let mut seen: Vec<Option<&Path>> = vec![None; shards];
    for s in &parts {
        if let Some(other) = seen[s.k - 1].replace(&s.path) {
            bail!(
                "{} and {} are both shard {}/{shards}: give each shard once",
                other.display(),
                s.path.display(),
                s.k
            );
        }
    }
    let missing: Vec<String> =
        (1..=shards).filter(|k| seen[k - 1].is_none()).map(|k| format!("{k}/{shards}")).collect();
    if !missing.is_empty() {
        bail!(
            "shard{} {} {} missing: give all {shards} shards",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", "),
            if missing.len() > 1 { "are" } else { "is" }
        );
    }
    let shape = first.shape.clone();
    let columns = *shape.last().expect("a checked shape");
    // The descriptions' shape is what the array will hold, in memory and then on disk:
    // checked (and counted without overflow) before anything is read or allocated.
    let total = shape.iter().try_fold(1_usize, |t, &a| t.checked_mul(a)).with_context(|| {
        format!("{}: its shape {shape:?} has more values than can be counted", json_of(&first.path))
    })?;
    let bytes = total as f64 * 8.0;
    let how = format!("{} values of shape {shape:?}", crate::limits::round(total as f64));
    crate::limits::check(
        "merge",
        allow_large,
        &[
            crate::limits::Estimate::new(crate::limits::Cost::Memory, bytes, how.clone()),
            crate::limits::Estimate::new(crate::limits::Cost::Output, bytes, how),
        ],
    )?;
    // Each file is the one its description was written with: its length, then its checksum,
    // before its contents are believed.
    for s in &parts {
        verify_data(s, shards)?;
    }
    for s in &parts {
        // The shard's header must hold what its description says, before it is read.
        let claim = crate::limits::npy_claim(&s.path)?;
        if claim.shape != [s.count, columns] || claim.item != 8 {
            bail!(
                "{}: shape {:?} of {}-byte values, its description says ({}, {columns}) float64",
                s.path.display(),
                claim.shape,
                claim.item,
                s.count
            );
        }
    }
    let mut data = Vec::new();
    data.try_reserve_exact(total).map_err(|_| {
        anyhow::anyhow!("cannot allocate {} for the merged array", crate::limits::bytes(bytes))
    })?;
    data.resize(total, f64::NAN);
    for s in &parts {
        let file =
            std::fs::File::open(&s.path).with_context(|| format!("cannot read {}", s.path.display()))?;
        let array = ndarray::Array2::<f64>::read_npy(std::io::BufReader::new(file))
            .with_context(|| format!("{} is not a float64 shard array", s.path.display()))?;
        if array.dim() != (s.count, columns) {
            bail!(
                "{}: shape {:?}, its description says ({}, {columns})",
                s.path.display(),
                array.dim(),
                s.count
            );
        }
        let values = array.as_standard_layout();
        data[s.offset * columns..(s.offset + s.count) * columns]
            .copy_from_slice(values.as_slice().expect("standard layout"));
    }
    Ok((shape, data, parts.len(), parts[0].fingerprint.clone()))
}

/// `--check` (sweep's, fractal's): whether `out` holds shard `(k, n)` of the run of this
/// `fingerprint` and `shape`, written by this pendula, intact.
pub(crate) fn check(out: &Path, fingerprint: &str, shape: &[usize], (k, n): (usize, usize)) -> Result<()> {
    let json = format!("{}.json", out.display());
    if !out.exists() {
        bail!("shard {k}/{n}: {} does not exist", out.display());
    }
    let shard = describe(out).with_context(|| format!("shard {k}/{n}"))?;
    if shard.fingerprint != fingerprint || shard.shape != shape {
        bail!(
            "shard {k}/{n}: {} is a shard of another run (its grid, method or records differ)",
            out.display()
        );
    }
    if (shard.k, shard.n) != (k, n) {
        bail!("shard {k}/{n}: {} is shard {}/{} of this sweep", out.display(), shard.k, shard.n);
    }
    // Another pendula may round differently in the last bits: its shard is computed again, so
    // that the merged array is one build's.
    let version = crate::shards::read_description(out)?
        .get("pendula")
        .and_then(serde_json::Value::as_str)
        .map(str::to_owned);
    if version.as_deref() != Some(env!("CARGO_PKG_VERSION")) {
        bail!(
            "shard {k}/{n}: {json} was written by pendula {}, not by this one ({})",
            version.as_deref().unwrap_or("(unstated)"),
            env!("CARGO_PKG_VERSION")
        );
    }
    verify_data(&shard, n)?;
    eprintln!(
        "shard {k}/{n}: {} holds it, intact ({} bytes, CRC-32 {:08x})",
        out.display(),
        shard.data.bytes,
        shard.data.crc32
    );
    Ok(())
}
