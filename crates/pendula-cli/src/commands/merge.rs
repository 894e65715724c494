//! `pendula merge`: assembles the shards of one sweep (`pendula sweep --shard K/N`) into
//! the full array, bitwise equal to the unsharded run. Refuses shards of different sweeps,
//! missing or repeated shards.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use ndarray_npy::ReadNpyExt;

use crate::output::AtomicFile;

#[derive(Debug, Clone, Args)]
pub struct MergeArgs {
    /// The shards' .npy files (each with its FILE.npy.json description).
    #[arg(required = true, value_name = "SHARD.npy")]
    pub shards: Vec<PathBuf>,
    /// The full array.
    #[arg(long, value_name = "FILE.npy")]
    pub out: PathBuf,
    #[arg(long, help = crate::limits::ALLOW_LARGE_HELP)]
    pub allow_large: bool,
}

pub fn run(args: &MergeArgs) -> Result<()> {
    let out = AtomicFile::create(&args.out, "--out")?;
    let mut parts = Vec::new();
    for path in &args.shards {
        let d = super::sweep::read_description(path)?;
        let field =
            |k: &str| d.get(k).cloned().with_context(|| format!("{}.json has no `{k}`", path.display()));
        let number = |k: &str| -> Result<usize> {
            field(k)?
                .as_u64()
                .map(|v| v as usize)
                .with_context(|| format!("{}.json: `{k}` is not a count", path.display()))
        };
        parts.push((
            path.clone(),
            field("fingerprint")?,
            field("shape")?,
            number("shard")?,
            number("shards")?,
            number("offset")?,
            number("count")?,
        ));
    }
    let (first_path, fingerprint, shape, _, shards, _, _) = parts[0].clone();
    for (path, f, s, _, n, _, _) in &parts {
        if *f != fingerprint || *s != shape || *n != shards {
            bail!(
                "{} is a shard of another sweep than {} (its grid, method or records differ)",
                path.display(),
                first_path.display()
            );
        }
    }
    // More shards than files: one is missing (found without a table of `shards` entries,
    // whose count comes from a file).
    if shards > parts.len() {
        let missing = (1..=shards).find(|k| !parts.iter().any(|p| p.3 == *k)).unwrap_or(shards);
        bail!("shard {missing}/{shards} is missing: give all {shards} shards");
    }
    let mut seen = vec![false; shards];
    for (path, _, _, k, _, _, _) in &parts {
        if *k == 0 || *k > shards || std::mem::replace(&mut seen[k - 1], true) {
            bail!("{}: shard {k} of {shards} is given twice or out of range", path.display());
        }
    }
    if let Some(missing) = seen.iter().position(|s| !s) {
        bail!("shard {}/{shards} is missing: give all {shards} shards", missing + 1);
    }
    let shape: Vec<usize> =
        serde_json::from_value(shape).context("invalid shape in the shard description")?;
    let columns = *shape.last().context("empty shape")?;
    // The descriptions' shape is what the array will hold, in memory and then on disk:
    // checked (and counted without overflow) before anything is allocated.
    let total = shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d)).with_context(|| {
        format!("{}.json: its shape {shape:?} has more values than can be counted", first_path.display())
    })?;
    let bytes = total as f64 * 8.0;
    let how = format!("{} values of shape {shape:?}", crate::limits::round(total as f64));
    crate::limits::check(
        "merge",
        args.allow_large,
        &[
            crate::limits::Estimate::new(crate::limits::Cost::Memory, bytes, how.clone()),
            crate::limits::Estimate::new(crate::limits::Cost::Output, bytes, how),
        ],
    )?;
    for (path, _, _, _, _, offset, count) in &parts {
        if offset.checked_add(*count).and_then(|end| end.checked_mul(columns)).is_none_or(|end| end > total) {
            bail!(
                "{}: its cells {offset} .. {offset} + {count} lie outside the array of shape {shape:?}",
                path.display()
            );
        }
        // The shard's header must hold what its description says, before it is read.
        let claim = crate::limits::npy_claim(path)?;
        if claim.shape != [*count, columns] || claim.item != 8 {
            bail!(
                "{}: shape {:?} of {}-byte values, its description says ({count}, {columns}) float64",
                path.display(),
                claim.shape,
                claim.item
            );
        }
    }
    let mut data = Vec::new();
    data.try_reserve_exact(total).map_err(|_| {
        anyhow::anyhow!("cannot allocate {} for the merged array", crate::limits::bytes(bytes))
    })?;
    data.resize(total, f64::NAN);
    for (path, _, _, _, _, offset, count) in &parts {
        let file = std::fs::File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
        let array = ndarray::Array2::<f64>::read_npy(std::io::BufReader::new(file))
            .with_context(|| format!("{} is not a float64 shard array", path.display()))?;
        if array.dim() != (*count, columns) {
            bail!("{}: shape {:?}, its description says ({count}, {columns})", path.display(), array.dim());
        }
        let values = array.as_standard_layout();
        data[offset * columns..(offset + count) * columns]
            .copy_from_slice(values.as_slice().expect("standard layout"));
    }
    crate::commands::sweep::write_npy(&out, &shape, &data)?;
    out.commit()?;
    eprintln!("merged {} shards into {} {:?}", parts.len(), args.out.display(), shape);
    Ok(())
}
