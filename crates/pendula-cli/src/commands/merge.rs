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
}

pub fn run(args: &MergeArgs) -> Result<()> {
    if args.out == std::path::Path::new("-") {
        bail!("invalid --out -: merge writes a .npy file, not stdout; give FILE.npy");
    }
    // The inputs first: an output onto one of them is refused before anything is read.
    for path in &args.shards {
        crate::output::claim_input(path, "input shard")?;
        crate::output::claim_input(
            std::path::Path::new(&format!("{}.json", path.display())),
            "shard description",
        )?;
    }
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
    let total: usize = shape.iter().product();
    let mut data = vec![f64::NAN; total];
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
