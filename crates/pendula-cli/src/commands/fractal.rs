//! `pendula fractal`: the double pendulum's flip fractal — the time to the first flip from
//! rest over a (θ₁, θ₂) grid, on the ensemble engine — with a per-pixel convergence flag
//! from a second run at half the step.
//!
//! Writes FILE.npy (float64, shape (N₂, N₁), θ₁ fastest as in `pendula sweep`, NaN where no
//! flip happens before --t-max), FILE.png (viridis, log time, colour bar; black: no flip),
//! FILE-converged.npy (uint8, 1 where the flip time moved by at most --tolerance between the
//! two steps), FILE-converged.png and FILE.npy.json (the description `plot` names the axes,
//! values and units by) in `--out-dir` (default `pendula-out/fractal/`, with
//! FILE = fractal) or beside `--out FILE.npy`; all files appear whole or not at all.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use pendula::analysis::fractal::{FractalSpec, GridAxis, assemble, flip_fractal_with_progress, flip_times};
use pendula_viz::{Heatmap, Rgb};
use serde_json::json;

use crate::args::{Defaults, LargeArg, MethodArgs, SetArgs, SummaryArg, ThreadsArg};
use crate::checkpoint::Checkpoint;
use crate::chunks::{Chunks, chunk_size};
use crate::commands::sweep::parse_axis;
use crate::shards::write_npy;
use pendula::error::Short;

use crate::limits::{self, Cost, Estimate};
use crate::output::AtomicFile;
use crate::parse::parse_settings;
use crate::study::OutDir;

#[derive(Debug, Clone, Args, serde::Serialize, serde::Deserialize)]
pub struct FractalArgs {
    /// An axis, theta1=LO:HI:N or theta2=LO:HI:N (cell centres, `pi` and `deg` accepted).
    #[arg(long = "grid", value_name = "NAME=LO:HI:N")]
    pub grids: Vec<String>,
    /// Longest time followed, s; no flip by then is NaN.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_max: Option<String>,
    #[command(flatten)]
    #[serde(flatten)]
    pub stepping: MethodArgs,
    /// A pixel is converged when its flip times at dt and dt/2 differ by at most this, s
    /// (and both or neither flip).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub tolerance: Option<String>,
    #[command(flatten)]
    #[serde(flatten)]
    pub set: SetArgs,
    #[command(flatten)]
    #[serde(flatten)]
    pub threads: ThreadsArg,
    /// Directory for fractal.npy, fractal.png, fractal-converged.npy and fractal-converged.png
    /// [default: pendula-out/fractal].
    #[arg(long, value_name = "DIR", conflicts_with = "out")]
    pub out_dir: Option<PathBuf>,
    /// Output .npy file instead, anywhere; the PNG and the convergence flags go beside it.
    #[arg(long, value_name = "FILE.npy")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    #[serde(flatten)]
    pub summary: SummaryArg,
    /// Compute the pixels in chunks and keep the finished ones in FILE (and FILE.chunks), so
    /// that an interrupted fractal continues with `pendula resume FILE`, computing only the
    /// chunks missing; both files are removed when the fractal is written.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Compute only shard K of N (K = 1 … N) of the pixels (row-major, θ₁ fastest): their
    /// flip times at dt and dt/2, shape (count, 2), into --out FILE.npy with a FILE.npy.json
    /// description; `fractal --merge-shards` with the same flags draws the fractal from all N.
    #[arg(long, value_name = "K/N", requires = "out", conflicts_with_all = ["checkpoint", "summary", "out_dir"])]
    pub shard: Option<String>,
    /// With --shard: check that --out already holds this shard of this fractal, intact (its
    /// description's grid, method, step, t-max, parameters and pendula version; the file's
    /// length and CRC-32), computing nothing: exit 0 if so, else 2 naming what is wrong.
    #[arg(long, requires = "shard")]
    #[serde(default)]
    pub check: bool,
    /// Draw the fractal from its N shards (`fractal --shard K/N` with the same flags) instead
    /// of computing it: the same files, byte for byte, as the fractal computed at once.
    #[arg(long, value_name = "SHARD.npy", num_args = 1.., conflicts_with_all = ["shard", "checkpoint"])]
    #[serde(default)]
    pub merge_shards: Vec<PathBuf>,
    #[command(flatten)]
    #[serde(flatten)]
    pub slurm: crate::slurm::SlurmArgs,
    #[command(flatten)]
    #[serde(flatten)]
    pub large: LargeArg,
}

/// `dir/stem.npy` → `dir/stem{suffix}`.
fn beside(path: &Path, suffix: &str) -> PathBuf {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("fractal");
    path.with_file_name(format!("{stem}{suffix}"))
}

/// What fractal runs without arguments (always on the double pendulum).
pub const DEFAULTS: Defaults = crate::args::Defaults::of(
    &pendula::study::defaults::FRACTAL,
    &[
        ("dt", "The convergence check runs at half of it."),
        ("method", "A method the ensemble engine runs on the double pendulum: euler, rk4, tao-2, tao-4."),
        ("set", "Parameters only (m1, m2, l1, l2, g): the pendulum starts at rest."),
    ],
);

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &["fractal.npy", "fractal.png", "fractal-converged.npy", "fractal-converged.png"];

pub fn run(args: &FractalArgs) -> Result<()> {
    execute(args, None)
}

/// The fractal the flags describe, validated: its spec, method and parameter values.
struct Parsed {
    spec: FractalSpec,
    method: &'static pendula::integrator::Method,
    values: pendula::system::Values,
}

impl Parsed {
    /// What identifies a shard's numbers: everything but the tolerance (which only judges
    /// them) and the threads (which change no bit).
    fn fingerprint(&self) -> String {
        let s = &self.spec;
        crate::checkpoint::fingerprint(&format!(
            "fractal|{:?}|{:?}|{:?}|{}|{:e}|{:e}",
            s.pendulum, s.theta1, s.theta2, self.method.name, s.h, s.t_max
        ))
    }

    /// The shards' shape: the grid, then the flip times at dt and dt/2.
    fn shape(&self) -> Vec<usize> {
        vec![self.spec.theta2.n, self.spec.theta1.n, 2]
    }
}

/// `--shard K/N`: the flip times of the shard's pixels at dt and dt/2, rows (count, 2), and
/// the shard's description, as `sweep --shard` writes them (so that `pendula merge` also
/// reads them).
fn write_shard(parsed: &Parsed, (k, n): (usize, usize), out: &Path, threads: usize) -> Result<()> {
    let spec = &parsed.spec;
    let pixels = spec.theta1.n * spec.theta2.n;
    // The slices `merge` expects: N contiguous ones, as equal as possible (in u128: k × pixels
    // may overflow usize).
    let slice = |k: usize| (k as u128 * pixels as u128 / n as u128) as usize;
    let (start, end) = (slice(k - 1), slice(k));
    let side_path = PathBuf::from(format!("{}.json", out.display()));
    let out_file = AtomicFile::create(out, "--out")?;
    let side_file = AtomicFile::create(&side_path, "--out (shard description)")?;
    let pool =
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().context("cannot start the threads")?;
    let begin = Instant::now();
    let bar = crate::study::progress(2 * (end - start) as u64, "fractal");
    let tick = |d: u64| bar.inc(d);
    let (at_h, at_half) =
        pool.install(|| flip_times(spec, start..end, &tick)).map_err(|e| pixel_error(spec, e))?;
    bar.finish_and_clear();
    let wall_s = begin.elapsed().as_secs_f64();
    let rows: Vec<f64> = at_h.iter().zip(&at_half).flat_map(|(a, b)| [*a, *b]).collect();
    let written = write_npy(&out_file, &[end - start, 2], &rows)?;
    let axis = |name: &str, a: &GridAxis| json!({"name": name, "lo": a.lo, "hi": a.hi, "n": a.n});
    let description = json!({
        "pendula_sweep": crate::shards::SHARD_FORMAT,
        "pendula": env!("CARGO_PKG_VERSION"),
        "command": "fractal",
        "system": "double",
        "method": parsed.method.name,
        "dt": spec.h,
        "t_max": spec.t_max,
        "parameters": parsed.values.parameters().map(|(n, v)| (n.to_owned(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "axes": [axis("theta1", &spec.theta1), axis("theta2", &spec.theta2)],
        "columns": ["flip_time", "flip_time_half_step"],
        "shape": parsed.shape(),
        "shard": k,
        "shards": n,
        "offset": start,
        "count": end - start,
        "fingerprint": parsed.fingerprint(),
        "data": { "bytes": written.bytes, "crc32": format!("{:08x}", written.crc32) },
        "fma": pendula::ensemble::has_fma(),
        "threads": threads,
        "wall_s": wall_s,
    });
    crate::shards::write_json(&side_file, &description)?;
    crate::study::Summary::open(None)?.write_then(&description, vec![out_file, side_file], |_| Ok(()))?;
    eprintln!(
        "fractal: pixels {start} to {end} (shard {k}/{n} of {pixels}) at dt = {} s and {} s on {threads} threads in {wall_s:.3} s -> {} and {}",
        Short(spec.h),
        Short(spec.h / 2.0),
        out.display(),
        side_path.display()
    );
    Ok(())
}

/// `--merge-shards`: the fractal from all N of its shards, which must be this fractal's.
fn from_shards(
    parsed: &Parsed,
    shards: &[PathBuf],
    allow_large: bool,
) -> Result<pendula::analysis::fractal::FlipFractal> {
    let (shape, data, _, fingerprint) = crate::commands::merge::gather(shards, allow_large)?;
    if fingerprint != parsed.fingerprint() || shape != parsed.shape() {
        bail!(
            "{} is a shard of another fractal than these flags describe (its grid, method, dt, t-max or parameters differ)",
            shards[0].display()
        );
    }
    let (at_h, at_half) = data.chunks_exact(2).map(|v| (v[0], v[1])).unzip();
    Ok(assemble(&parsed.spec, at_h, at_half))
}

/// `--emit-slurm N`: the Slurm script that computes this fractal in N shards and draws it
/// from them (`--merge-shards`).
fn emit_slurm(args: &FractalArgs, parsed: &Parsed) -> Result<()> {
    let mut run = crate::slurm::Argv::default();
    run.value("t-max", &args.t_max)
        .value("method", &args.stepping.method)
        .value("dt", &args.stepping.dt)
        .value("tolerance", &args.tolerance)
        .each("grid", &args.grids)
        .each("set", &args.set.items)
        .switch("allow-large", args.large.allow_large);
    // The script must draw this fractal: its arguments, parsed again, give the same one.
    let again = parse(&run.parse_again::<FractalArgs>("fractal", &[])?)?;
    if again.fingerprint() != parsed.fingerprint() || again.spec.tolerance != parsed.spec.tolerance {
        bail!("internal error: the Slurm script's arguments describe another fractal");
    }
    let out = args.out.clone().unwrap_or_else(|| PathBuf::from("fractal.npy"));
    let pixels = parsed.spec.theta1.n * parsed.spec.theta2.n;
    let plan = crate::slurm::Plan {
        command: "fractal",
        args: run.0,
        allow_large: args.large.allow_large,
        out: &out,
        cells: pixels,
        merge_flag: Some("--merge-shards"),
    };
    let script = crate::slurm::emit(&args.slurm, &plan)?;
    eprintln!(
        "wrote {}: {pixels} pixels in {} shards as a Slurm job array, then the fractal drawn from them into {} (and its images beside it); submit with `bash {} --wait`",
        script.display(),
        args.slurm.emit_slurm.as_deref().unwrap_or_default().trim(),
        out.display(),
        script.display()
    );
    Ok(())
}

/// A pixel's numerical failure (exit 1), named by its place in the grid, as in sweep.
fn pixel_error(spec: &FractalSpec, e: pendula::Error) -> anyhow::Error {
    match e {
        pendula::Error::NonFiniteMember { member, t } => {
            let (i, j) = (member % spec.theta1.n, member / spec.theta1.n);
            anyhow::Error::new(pendula::Error::NonFinite { t }).context(format!(
                "fractal pixel ({i}, {j}) at theta1 = {}, theta2 = {}",
                Short(spec.theta1.centre(i)),
                Short(spec.theta2.centre(j))
            ))
        }
        other => anyhow::Error::new(other),
    }
}

/// Parses and validates the flags that say which fractal, before any work.
fn parse(args: &FractalArgs) -> Result<Parsed> {
    let info = pendula::model::find("double")?;
    let settings = parse_settings(info, &args.set.items)?;
    for (name, _) in &settings {
        if info.state.iter().any(|q| q.name == *name) {
            bail!(
                "invalid --set {name}: the fractal starts from rest at the grid's angles; set parameters only"
            );
        }
    }
    let values = info.values(&settings)?;
    let mut theta1 = GridAxis { lo: -std::f64::consts::PI, hi: std::f64::consts::PI, n: 512 };
    let mut theta2 = theta1;
    let mut seen = Vec::new();
    for text in &args.grids {
        let axis = parse_axis(info, "--grid", "theta1=-pi:pi:512", text)?;
        let target = match axis.name.as_str() {
            "theta1" => &mut theta1,
            "theta2" => &mut theta2,
            other => bail!("invalid --grid `{text}`: the fractal's axes are theta1 and theta2, not {other}"),
        };
        if seen.contains(&axis.name) {
            bail!("invalid --grid: `{}` is given twice", axis.name);
        }
        *target = GridAxis { lo: axis.lo, hi: axis.hi, n: axis.n };
        seen.push(axis.name);
    }
    let t_max = DEFAULTS.positive("t_max", &args.t_max, "a time in seconds")?;
    let h = args.stepping.positive_dt(&DEFAULTS)?;
    let tolerance = DEFAULTS.non_negative("tolerance", &args.tolerance, "a time in seconds")?;
    let method = args.stepping.method(&DEFAULTS)?;
    // The library checks the fractal (pendula::analysis::fractal::FractalSpec::new); its
    // errors name the inputs, here spelled as flags.
    let flags = [
        ("dt", "--dt"),
        ("t_max", "--t-max"),
        ("tolerance", "--tolerance"),
        ("method", "--method"),
        ("set", "--set"),
        ("theta1", "--grid"),
        ("theta2", "--grid"),
    ];
    let spec = FractalSpec::new(&values, theta1, theta2, t_max, h, method, tolerance)
        .map_err(|e| crate::studies::respelled(e, &flags))?;
    Ok(Parsed { spec, method, values })
}

/// Draws the fractal from the start, or `resumed` from its checkpoint (`pendula resume`).
pub(crate) fn execute(args: &FractalArgs, resumed: Option<Checkpoint>) -> Result<()> {
    let parsed = parse(args)?;
    let (spec, method, values) = (parsed.spec, parsed.method, &parsed.values);
    let FractalSpec { theta1, theta2, t_max, h, tolerance, .. } = spec;
    let threads = args.threads.resolve(args.large.allow_large)?;
    if args.out.as_deref() == Some(Path::new("-")) {
        bail!("invalid --out -: the fractal is written as .npy and .png files, not to stdout; give FILE.npy");
    }
    // What it costs, before any of it: every pixel at dt and at dt/2 (the allowed ones stop
    // at their first flip, so this is an upper estimate), and per pixel its flip times, flags
    // and images in memory (some 64 bytes) and 9 bytes of .npy.
    let pixels = theta1.n as f64 * theta2.n as f64;
    let steps = limits::steps(t_max, h) + limits::steps(t_max, h / 2.0);
    let grid = format!("{} x {} pixels", theta1.n, theta2.n);
    limits::check(
        "fractal",
        args.large.allow_large,
        &[
            Estimate::new(
                Cost::LaneSteps,
                pixels * steps,
                format!("{grid} x {} steps", limits::round(steps)),
            ),
            Estimate::new(Cost::Memory, pixels * 64.0, format!("{grid} x 64 bytes")),
            Estimate::new(Cost::Output, pixels * 9.0, format!("{grid} x 9 bytes")),
        ],
    )?;
    if let Some(out) = &args.out
        && out.extension().and_then(|e| e.to_str()) != Some("npy")
    {
        bail!("invalid --out {}: the fractal is written as .npy", out.display());
    }
    if args.slurm.emit_slurm.is_some() {
        return emit_slurm(args, &parsed);
    }
    if let Some(text) = &args.shard {
        let out = args.out.as_deref().expect("clap requires --out with --shard");
        let shard = crate::commands::sweep::parse_shard(text, theta1.n * theta2.n)?;
        if args.check {
            return crate::commands::merge::check(out, &parsed.fingerprint(), &parsed.shape(), shard);
        }
        return write_shard(&parsed, shard, out, threads);
    }
    // Shards to draw from are inputs: an output onto one of them is refused before any is read.
    for path in &args.merge_shards {
        crate::output::claim_input(path, "input shard")?;
        crate::output::claim_input(Path::new(&format!("{}.json", path.display())), "shard description")?;
    }
    // An explicit --out is the user's path; otherwise the study's directory, tidied of an
    // earlier run's files like every study command's.
    let dir = match &args.out {
        Some(_) => None,
        None => Some(OutDir::new(args.out_dir.as_deref(), "fractal", FILES)?),
    };
    let names =
        ["fractal.npy", "fractal.png", "fractal-converged.npy", "fractal-converged.png", "fractal.npy.json"];
    let (paths, files): (Vec<PathBuf>, Vec<AtomicFile>) = match (&args.out, &dir) {
        (Some(out), _) => {
            let paths = [
                out.clone(),
                beside(out, ".png"),
                beside(out, "-converged.npy"),
                beside(out, "-converged.png"),
                beside(out, ".npy.json"),
            ];
            let files = paths.iter().map(|p| AtomicFile::create(p, "--out")).collect::<Result<_>>()?;
            (paths.to_vec(), files)
        }
        (None, Some(dir)) => {
            let files: Vec<AtomicFile> = names.iter().map(|n| dir.file(n)).collect::<Result<_>>()?;
            (names.iter().map(|n| dir.path().join(n)).collect(), files)
        }
        (None, None) => unreachable!("a directory when there is no --out"),
    };
    let summary = args.summary.open()?;
    let checkpoint = match &args.checkpoint {
        Some(c) => {
            let flag = if dir.is_some() { "--out-dir" } else { "--out" };
            let mut outputs: Vec<(&str, &Path)> = paths.iter().map(|p| (flag, p.as_path())).collect();
            outputs.extend(args.summary.path.as_deref().map(|s| ("--summary", s)));
            let path = crate::checkpoint::check_path(c, &outputs)?;
            Chunks::claim(&path)?;
            Some(path)
        }
        None => None,
    };

    let pool =
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().context("cannot start the threads")?;
    let begin = Instant::now();
    let bar = crate::study::progress(2 * (theta1.n * theta2.n) as u64, "fractal");
    let done = std::sync::atomic::AtomicU64::new(0);
    let tick = |n: u64| {
        let before = done.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        // Redraw every 4096 pixel-runs.
        if (before + n) / 4096 != before / 4096 {
            bar.set_position(before + n);
        }
    };
    let pixel_error = |e| pixel_error(&spec, e);
    let (fractal, chunks) = match checkpoint {
        _ if !args.merge_shards.is_empty() => {
            (from_shards(&parsed, &args.merge_shards, args.large.allow_large)?, None)
        }
        None => (pool.install(|| flip_fractal_with_progress(&spec, &tick)).map_err(pixel_error)?, None),
        Some(path) => {
            let _registered = crate::output::Checkpointing::start();
            let pixels = theta1.n * theta2.n;
            // Both flip times of each pixel, one after the other.
            let mut times = vec![f64::NAN; 2 * pixels];
            let fingerprint =
                crate::checkpoint::fingerprint(&format!("{spec:?}|fma {}", pendula::ensemble::has_fma()));
            let (chunks, done) = match resumed {
                Some(c) => {
                    let (chunks, done) = Chunks::resume(&c, &fingerprint, 2, &mut times)?;
                    tick(
                        2 * (0..chunks.count())
                            .filter(|&i| done[i])
                            .map(|i| chunks.range(i).len() as u64)
                            .sum::<u64>(),
                    );
                    (chunks, done)
                }
                None => {
                    let base = json!({
                        "command": "fractal",
                        "pendula": env!("CARGO_PKG_VERSION"),
                        "cwd": std::env::current_dir().context("cannot read the working directory")?,
                        "args": args,
                        "fingerprint": fingerprint,
                    });
                    let chunks = Chunks::start(&path, base, pixels, 2, chunk_size(pixels, threads))?;
                    let done = vec![false; chunks.count()];
                    (chunks, done)
                }
            };
            let compute = |cells: std::ops::Range<usize>, values: &mut [f64]| -> Result<()> {
                let (at_h, at_half) =
                    pool.install(|| flip_times(&spec, cells, &tick)).map_err(pixel_error)?;
                for ((v, a), b) in values.chunks_exact_mut(2).zip(at_h).zip(at_half) {
                    v.copy_from_slice(&[a, b]);
                }
                Ok(())
            };
            let chunks = chunks.run(&done, &mut times, compute).inspect_err(|_| bar.finish_and_clear())?;
            let (at_h, at_half) = times.chunks_exact(2).map(|v| (v[0], v[1])).unzip();
            (assemble(&spec, at_h, at_half), Some(chunks))
        }
    };
    bar.finish_and_clear();
    let wall = begin.elapsed().as_secs_f64();

    let (n1, n2) = (theta1.n, theta2.n);
    let pixels = n1 * n2;
    let unconverged = fractal.converged.iter().filter(|c| !**c).count();
    let flipped = fractal.flip_time.iter().filter(|t| t.is_finite()).count();
    let share = unconverged as f64 / pixels as f64;

    let [npy, png, flags_npy, flags_png, described] = <[AtomicFile; 5]>::try_from(files).expect("five files");
    write_npy(&npy, &[n2, n1], &fractal.flip_time)?;
    let flags: Vec<u8> = fractal.converged.iter().map(|c| u8::from(*c)).collect();
    write_npy(&flags_npy, &[n2, n1], &flags)?;
    let map = |title: String, bar: &str, values: Vec<f64>, log: bool, nan: Rgb| Heatmap {
        title,
        x_label: pendula_viz::axis_label("theta1", "rad"),
        y_label: pendula_viz::axis_label("theta2", "rad"),
        bar_label: bar.into(),
        x: (theta1.lo, theta1.hi),
        y: (theta2.lo, theta2.hi),
        nx: n1,
        ny: n2,
        values,
        log,
        nan_color: nan,
        categories: Vec::new(),
    };
    let picture = map(
        format!(
            "double pendulum: time to first flip from rest ({}, dt = {h} s; black: none by {t_max} s)",
            method.name
        ),
        "time to first flip (s)",
        fractal.flip_time.clone(),
        true,
        pendula_viz::BLACK,
    );
    let write_png = |file: &AtomicFile, map: &Heatmap| -> Result<()> {
        let bytes = match map.png() {
            Ok(b) => b,
            // Nothing flips at all: draw the flags' colours instead of failing.
            Err(pendula_viz::Error::Empty(_)) => {
                Heatmap { values: vec![0.0; map.values.len()], log: false, ..map.clone() }.png()?
            }
            Err(e) => return Err(e.into()),
        };
        file.write_all(&bytes)?;
        Ok(())
    };
    write_png(&png, &picture)?;
    // Two categories, two colours and a two-entry legend: a yes/no map has no scale.
    let flag_values: Vec<f64> = fractal.converged.iter().map(|c| if *c { 0.0 } else { 1.0 }).collect();
    let flags_map = Heatmap {
        categories: vec![
            ("converged".into(), pendula_viz::rgb(253, 231, 37)),
            ("not converged".into(), pendula_viz::rgb(68, 1, 84)),
        ],
        ..map(
            format!("converged pixels: flip time within {tolerance} s at dt = {h} s and {} s", h / 2.0),
            "at dt and dt/2",
            flag_values,
            false,
            pendula_viz::BLACK,
        )
    };
    flags_png.write_all(&flags_map.png()?)?;
    // The description beside the arrays (FILE.npy.json, as a sweep's): what `plot` names
    // their axes and values by.
    let description = json!({
        "pendula_description": 1,
        "pendula": env!("CARGO_PKG_VERSION"),
        "command": "fractal",
        "system": "double", "method": method.name, "dt": h, "dt_check": h / 2.0, "t_max": t_max,
        "tolerance": tolerance,
        "axes": [
            {"name": "theta1", "lo": theta1.lo, "hi": theta1.hi, "n": n1},
            {"name": "theta2", "lo": theta2.lo, "hi": theta2.hi, "n": n2},
        ],
        "axis_units": ["rad", "rad"],
        "columns": ["flip_time"],
        "units": ["s"],
        "labels": ["time to first flip"],
        "missing": format!("NaN: no flip by t_max = {t_max} s"),
        "converged": {
            "file": paths[2].file_name().map(|n| n.to_string_lossy().into_owned()),
            "columns": ["converged"],
            "labels": ["converged (1) or not (0)"],
            "meaning": format!("1 where the flip time moved by at most {tolerance} s between dt and dt/2"),
        },
        "shape": [n2, n1],
    });
    crate::shards::write_json(&described, &description)?;
    let doc = json!({
        "system": "double", "method": method.name, "dt": h, "dt_check": h / 2.0, "t_max": t_max,
        "tolerance": tolerance,
        "parameters": values.parameters().map(|(n, v)| (n.to_owned(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "axes": [
            {"name": "theta1", "lo": theta1.lo, "hi": theta1.hi, "n": n1},
            {"name": "theta2", "lo": theta2.lo, "hi": theta2.hi, "n": n2},
        ],
        "shape": [n2, n1],
        "pixels": pixels, "flipped": flipped, "forbidden_by_energy": fractal.forbidden,
        "unconverged": unconverged, "unconverged_share": share,
        "threads": threads, "wall_s": wall,
        "files": paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    });
    sayln!(
        summary,
        "fractal {n1}x{n2}, t-max {t_max} s, {} at dt = {h} s and {} s: {flipped} pixels flip, {} cannot (energy), {unconverged} unconverged ({:.2}%) [{wall:.1} s, {threads} threads]",
        method.name,
        h / 2.0,
        fractal.forbidden,
        100.0 * share
    );
    let wrote =
        format!("wrote {}", paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "));
    let on_stdout = summary.on_stdout();
    // The five files and the summary appear together or not at all, and a finished
    // fractal's checkpoint goes in the same step.
    let files = vec![npy, png, flags_npy, flags_png, described];
    let finish = |guard: &mut crate::output::Guard<'_>| chunks.map_or(Ok(()), |c| c.finish(guard));
    match dir {
        Some(mut dir) => {
            dir.commit(files)?;
            dir.finish_then(summary, &doc, finish)?;
        }
        None => summary.write_then(&doc, files, finish)?,
    }
    crate::study::say_after(on_stdout, &wrote);
    Ok(())
}
