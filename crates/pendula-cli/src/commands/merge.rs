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
use serde_json::Value;

use crate::args::LargeArg;
use crate::output::{AtomicFile, claim_input};

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

pub use pendula_io::shard::Shard;

/// The description's path, for messages.
fn json_of(path: &Path) -> String {
    format!("{}.json", path.display())
}

/// Reads and checks the description of the shard at `path` against itself
/// ([`pendula_io::shard::describe`]).
pub fn describe(path: &Path) -> Result<Shard> {
    Ok(pendula_io::shard::describe(path)?)
}

/// Checks that the shard's file is the one its description was written with
/// ([`pendula_io::shard::verify_data`]).
pub(crate) fn verify_data(s: &Shard, shards: usize) -> Result<()> {
    Ok(pendula_io::shard::verify_data(s, shards)?)
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
    pendula_io::shard::same_run(&parts)?;
    // Shards from CPUs that round differently (with and without FMA) are each right, and
    // together not bitwise what one machine computes: said, not refused (nothing is lost).
    if let Some((a, b)) = pendula_io::shard::fma_mixed(&parts) {
        eprintln!(
            "warning: {} was computed on a CPU with fused multiply-adds and {} on one without: they round differently, so the merged array is not bitwise what one machine computes",
            a.path.display(),
            b.path.display()
        );
    }
    let shards = first.n;
    pendula_io::shard::complete(&parts)?;
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
        pendula_io::shard::check_header(s, columns)?;
    }
    let mut data = Vec::new();
    data.try_reserve_exact(total).map_err(|_| {
        anyhow::anyhow!("cannot allocate {} for the merged array", crate::limits::bytes(bytes))
    })?;
    data.resize(total, f64::NAN);
    for s in &parts {
        let rows = pendula_io::shard::read_rows(s, columns)?;
        data[s.offset * columns..(s.offset + s.count) * columns].copy_from_slice(&rows);
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
