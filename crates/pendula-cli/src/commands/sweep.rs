//! `pendula sweep`: one system integrated from every cell of a grid over parameters and
//! initial-state variables, in parallel, into one .npy array — whole, or one deterministic
//! shard of it (`--shard K/N`, assembled by `pendula merge`).
//!
//! Where the library's `ensemble_path` says so — every system with an explicit Runge–Kutta
//! method, separable systems with the explicit partitioned methods, the free double pendulum
//! with Tao's map — the cells run on the SIMD ensemble engine (`pendula::ensemble`);
//! everything else runs the scalar integrators cell by cell, also in parallel. Either way a
//! cell's result does not depend on the thread count or the sharding.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use pendula::ensemble::engine::{LaneOutcome, LaneSpec};
use pendula::ensemble::{self, BatchSpec};
use pendula::error::{Short, did_you_mean, suggestions};
use pendula::integrator::{self, Method};
use pendula::model::EnsemblePath;
use pendula::observe::{Observer, Sample};
use pendula::system::{SystemInfo, Values};
use pendula::{End, RunSpec};
use rayon::prelude::*;
use serde_json::json;

use crate::args::{Defaults, EndArg, LargeArg, MethodArgs, SetArgs, SummaryArg, SystemArg, ThreadsArg};
use crate::checkpoint::Checkpoint;
use crate::chunks::{Chunks, chunk_size};
use crate::config::{clip, parse_count, parse_settings, parse_value};
use crate::limits::{self, Cost, Estimate};
use crate::output::AtomicFile;
use crate::sink::Tally;

#[derive(Debug, Clone, Args, serde::Serialize, serde::Deserialize)]
pub struct SweepArgs {
    #[command(flatten)]
    #[serde(flatten)]
    pub system: SystemArg,
    /// An axis: NAME=LO:HI:N samples the N cell centres LO + (i + 1/2)(HI - LO)/N of a
    /// parameter or initial-state variable (`pi` and `deg` accepted for angles). Repeat for
    /// more axes; the first varies fastest in the output.
    #[arg(long = "grid", value_name = "NAME=LO:HI:N", required = true)]
    pub grids: Vec<String>,
    #[command(flatten)]
    #[serde(flatten)]
    pub set: SetArgs,
    #[command(flatten)]
    #[serde(flatten)]
    pub stepping: MethodArgs,
    /// Number of steps, 1 to 10^13 (the sweep's cells x steps at most 10^13 on the SIMD
    /// engine, 10^11 on the scalar path, without --allow-large).
    #[arg(long, value_name = "N", conflicts_with = "t_end")]
    pub steps: Option<String>,
    #[command(flatten)]
    #[serde(flatten)]
    pub end: EndArg,
    /// Stop each cell when it first flips (an angle passes ±π): `flip`.
    #[arg(long, value_name = "EVENT")]
    pub until: Option<String>,
    /// What to record per cell, comma-separated, in this order along the last axis: `final`
    /// (the state, one column per variable), `flip-time` (s, NaN if no flip),
    /// `energy-error` (E_end − E_0, J) [default: final].
    #[arg(long, value_name = "LIST")]
    pub record: Option<String>,
    #[command(flatten)]
    #[serde(flatten)]
    pub threads: ThreadsArg,
    /// Compute only shard K of N (K = 1 … N): a contiguous slice of the cells, written with a
    /// FILE.json description for `pendula merge`.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Output .npy file [default: sweep.npy].
    #[arg(long, value_name = "FILE.npy")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    #[serde(flatten)]
    pub summary: SummaryArg,
    /// Compute the cells in chunks and keep the finished ones in FILE (and FILE.chunks), so
    /// that an interrupted sweep continues with `pendula resume FILE`, computing only the
    /// chunks missing; both files are removed when the sweep ends.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    #[command(flatten)]
    #[serde(flatten)]
    pub large: LargeArg,
}

/// One axis of the grid.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Axis {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
    pub n: usize,
}

impl Axis {
    pub(crate) fn centre(&self, i: usize) -> f64 {
        self.lo + (i as f64 + 0.5) * (self.hi - self.lo) / self.n as f64
    }
}

/// A recorded quantity.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Record {
    Final,
    FlipTime,
    EnergyError,
}

/// The validated sweep.
struct Sweep {
    info: &'static SystemInfo,
    base: Vec<(String, f64)>,
    axes: Vec<Axis>,
    method: &'static Method,
    h: f64,
    steps: u64,
    until_flip: bool,
    records: Vec<Record>,
    columns: Vec<String>,
    shard: (usize, usize),
}

impl Sweep {
    fn cells(&self) -> usize {
        self.axes.iter().map(|a| a.n).product()
    }

    /// The values of cell `index` (flattened, first axis fastest).
    fn values(&self, index: usize) -> Result<Values, pendula::Error> {
        let mut settings = self.base.clone();
        let mut rest = index;
        for axis in &self.axes {
            settings.push((axis.name.clone(), axis.centre(rest % axis.n)));
            rest /= axis.n;
        }
        self.info.values(&settings)
    }

    /// The output's shape: the axes, slowest first, then the columns.
    fn shape(&self) -> Vec<usize> {
        let mut shape: Vec<usize> = self.axes.iter().rev().map(|a| a.n).collect();
        shape.push(self.columns.len());
        shape
    }

    /// Cells [start, end) of this shard: N contiguous slices as equal as possible.
    fn range(&self) -> (usize, usize) {
        let (k, n) = self.shard;
        // In u128: k × cells overflows usize for large grids cut in many shards.
        let (k, n, cells) = (k as u128, n as u128, self.cells() as u128);
        (((k - 1) * cells / n) as usize, (k * cells / n) as usize)
    }

    /// A digest of everything that determines the full array, so that `merge` refuses
    /// shards of different sweeps.
    fn fingerprint(&self) -> String {
        let text = format!(
            "{}|{:?}|{:?}|{}|{:e}|{}|{}|{:?}",
            self.info.name,
            self.base,
            self.axes,
            self.method.name,
            self.h,
            self.steps,
            self.until_flip,
            self.records
        );
        // FNV-1a, 64 bits: a label, not a security measure.
        let hash = text
            .bytes()
            .fold(0xcbf2_9ce4_8422_2325_u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
        format!("{hash:016x}")
    }
}

/// An example `--grid` axis for `info`: its first angle over a turn, else its first state
/// variable.
pub(crate) fn grid_example(info: &SystemInfo) -> String {
    match info.state.iter().find(|q| q.is_angle()) {
        Some(q) => format!("{}=-pi:pi:256", q.name),
        None => format!("{}=-1:1:256", info.state[0].name),
    }
}

/// Parses an axis `NAME=LO:HI:N` given to `flag` (`--grid`, or bifurcation's `--param`);
/// `example` shows the form in the error.
pub(crate) fn parse_axis(info: &'static SystemInfo, flag: &str, example: &str, text: &str) -> Result<Axis> {
    let bad = || anyhow!("invalid {flag} `{}`: expected NAME=LO:HI:N, e.g. {example}", clip(text));
    let (name, range) = text.split_once('=').ok_or_else(bad)?;
    let name = name.trim();
    let q = info.quantity(name)?;
    let parts: Vec<&str> = range.split(':').collect();
    let [lo, hi, n] = parts[..] else { return Err(bad()) };
    let (lo, hi) = (parse_value(name, lo, Some(q))?, parse_value(name, hi, Some(q))?);
    let n = parse_count(flag, n, 0, limits::MAX_AXIS_CELLS, "cells")? as usize;
    if n == 0 {
        bail!("invalid {flag} `{}`: the number of cells must be >= 1", clip(text));
    }
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        bail!("invalid {flag} `{}`: need finite LO < HI (got {} and {})", clip(text), Short(lo), Short(hi));
    }
    Ok(Axis { name: name.to_owned(), lo, hi, n })
}

fn parse(args: &SweepArgs) -> Result<Sweep> {
    let family = pendula::model::find(args.system.name(&DEFAULTS))?;
    let base = parse_settings(family, &args.set.items)?;
    // A family (the chain) resolves to the member the settings choose; an axis may not
    // change the member, since the state's size would change from cell to cell.
    let info = family.values(&base)?.info();
    let axes = args
        .grids
        .iter()
        .map(|g| parse_axis(info, "--grid", &grid_example(info), g))
        .collect::<Result<Vec<_>>>()?;
    for a in &axes {
        for v in [a.centre(0), a.centre(a.n - 1)] {
            let mut settings = base.clone();
            settings.push((a.name.clone(), v));
            if !std::ptr::eq(family.values(&settings)?.info(), info) {
                bail!(
                    "invalid --grid `{}`: it changes the size of the state; run one sweep per value",
                    a.name
                );
            }
        }
    }
    for (i, a) in axes.iter().enumerate() {
        if axes[..i].iter().any(|b| b.name == a.name) {
            bail!("invalid --grid: `{}` is given twice", a.name);
        }
    }
    refuse_set_and_swept(&args.set.items, &args.grids, &axes, "--grid")?;
    // The cell count must be a number the sweep can index (its work and bytes are checked
    // below): 10^15 cells are 8 PB of results.
    let cells: f64 = axes.iter().map(|a| a.n as f64).product();
    if cells > 1e15 {
        bail!(
            "sweep: the grid has {} cells ({}), more than any machine can hold; use fewer cells",
            limits::round(cells),
            axes.iter().map(|a| a.n.to_string()).collect::<Vec<_>>().join(" x ")
        );
    }
    let method = args.stepping.method(&DEFAULTS)?;
    if matches!(method.scheme, integrator::Scheme::Embedded(_)) {
        bail!("sweep takes fixed steps: {} runs here as a fixed-step method only with --dt", method.name);
    }
    let h = args.stepping.dt(&DEFAULTS)?;
    let end = match &args.steps {
        Some(text) => End::Steps(parse_count("--steps", text, 1, limits::MAX_STEPS, "steps")?),
        None => End::Time(args.end.t_end(&DEFAULTS)?),
    };
    let end_flag = if args.steps.is_some() { "--steps" } else { "--t-end" };
    let schedule = crate::config::schedule(&RunSpec { t0: 0.0, h, end }, "--dt", end_flag)?;
    if schedule.last_h != h {
        bail!(
            "invalid --t-end {}: it must be a whole number of steps of --dt {}",
            Short(schedule.t_end),
            Short(h)
        );
    }
    let until_flip = match args.until.as_deref() {
        None => false,
        Some("flip") if info.state.iter().any(|q| q.is_angle()) => true,
        Some("flip") => bail!("invalid --until flip: the `{}` system has no angle", info.name),
        Some(other) => {
            bail!("invalid --until `{other}`{}: expected flip", did_you_mean(&suggestions(other, ["flip"])))
        }
    };
    let mut records = Vec::new();
    for name in args.record.as_deref().unwrap_or("final").split(',').map(str::trim) {
        let record = match name {
            "final" => Record::Final,
            "flip-time" if info.state.iter().any(|q| q.is_angle()) => Record::FlipTime,
            "flip-time" => bail!("invalid --record flip-time: the `{}` system has no angle", info.name),
            "energy-error" => Record::EnergyError,
            other => bail!(
                "invalid --record `{other}`{}: expected final, flip-time or energy-error",
                did_you_mean(&suggestions(other, ["final", "flip-time", "energy-error"]))
            ),
        };
        if records.contains(&record) {
            bail!("invalid --record: `{name}` is given twice");
        }
        records.push(record);
    }
    let mut columns = Vec::new();
    for r in &records {
        match r {
            Record::Final => columns.extend(info.state.iter().map(|q| q.name.to_owned())),
            Record::FlipTime => columns.push("flip_time".into()),
            Record::EnergyError => columns.push("energy_error".into()),
        }
    }
    let shard = match &args.shard {
        None => (1, 1),
        Some(text) => {
            let bad = || anyhow!("invalid --shard `{text}`: expected K/N with 1 <= K <= N, e.g. 3/8");
            let (k, n) = text.split_once('/').ok_or_else(bad)?;
            let (k, n): (usize, usize) =
                (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
            if !(1 <= k && k <= n) {
                return Err(bad());
            }
            (k, n)
        }
    };
    let sweep =
        Sweep { info, base, axes, method, h, steps: schedule.steps, until_flip, records, columns, shard };
    if sweep.shard.1 > sweep.cells() {
        bail!("invalid --shard {}/{}: more shards than the {} cells", shard.0, shard.1, sweep.cells());
    }
    // Every cell's values are in their domains if the extreme cell centres are (the
    // domains are intervals): check both corners now, before any work.
    sweep.values(0)?;
    sweep.values(sweep.cells() - 1)?;
    // What it costs, before any of it: the steps of every cell of this shard, and the array
    // (held whole in memory, then written).
    let (start, end) = sweep.range();
    let cells = (end - start) as f64;
    let bytes = cells * sweep.columns.len() as f64 * 8.0;
    let how = format!("{} cells x {} bytes", limits::round(cells), sweep.columns.len() * 8);
    limits::check(
        "sweep",
        args.large.allow_large,
        &[
            Estimate::new(
                if matches!(path(&sweep)?, EnsemblePath::Scalar) { Cost::Steps } else { Cost::LaneSteps },
                cells * sweep.steps as f64,
                format!("{} cells x {} steps", limits::round(cells), limits::round(sweep.steps as f64)),
            ),
            Estimate::new(Cost::Output, bytes, how.clone()),
            Estimate::new(Cost::Memory, bytes, how),
        ],
    )?;
    // A method that needs what the system lacks is refused now, on one step of one cell.
    let probe = sweep.values(0)?;
    probe
        .build()
        .solve(
            method,
            probe.initial_state(),
            &RunSpec { t0: 0.0, h, end: End::Steps(1) },
            &mut pendula::observe::Ignore,
        )
        // A numerical failure in that step is the first cell's, and named so (exit 1).
        .map_err(|e| {
            let numerical = crate::study::numerical(&e);
            let e = anyhow::Error::new(e);
            if numerical { e.context("cell 0 of the sweep") } else { e }
        })?;
    Ok(sweep)
}

/// Watches a scalar run for the first flip (linear interpolation of |θ| within the step).
struct FlipWatch {
    angles: Vec<usize>,
    previous: Vec<f64>,
    t_previous: f64,
    flip_time: f64,
    stop: bool,
}

impl Observer for FlipWatch {
    fn observe(&mut self, s: &Sample<'_>) -> pendula::observe::Flow {
        use std::f64::consts::PI;
        if s.step > 0 && self.flip_time.is_nan() {
            let mut fraction = f64::INFINITY;
            for (&i, &old) in self.angles.iter().zip(&self.previous) {
                let (a, b) = (old.abs(), s.y[i].abs());
                if a <= PI && b > PI {
                    fraction = fraction.min((PI - a) / (b - a));
                }
            }
            if fraction.is_finite() {
                self.flip_time = self.t_previous + fraction * (s.t - self.t_previous);
                if self.stop {
                    return std::ops::ControlFlow::Break(pendula::observe::Stop::Enough);
                }
            }
        }
        for (p, &i) in self.previous.iter_mut().zip(&self.angles) {
            *p = s.y[i];
        }
        self.t_previous = s.t;
        std::ops::ControlFlow::Continue(())
    }
}

/// What sweep runs without arguments.
pub const DEFAULTS: Defaults = Defaults {
    system: "double",
    method: Some("rk4"),
    dt: Some(0.01),
    t_end: Some(10.0),
    notes: &[("set", "The same for every cell, e.g. `--set m2=2`.")],
};

pub fn run(args: &SweepArgs) -> Result<()> {
    execute(args, None)
}

/// Runs a sweep from the start, or `resumed` from its checkpoint (`pendula resume`).
pub(crate) fn execute(args: &SweepArgs, resumed: Option<Checkpoint>) -> Result<()> {
    let sweep = parse(args)?;
    let threads = args.threads.resolve(args.large.allow_large)?;
    let out_path = args.out.clone().unwrap_or_else(|| PathBuf::from("sweep.npy"));
    if out_path == Path::new("-") {
        bail!("invalid --out -: sweep writes a .npy file, not stdout; give FILE.npy");
    }
    if out_path.extension().and_then(|e| e.to_str()) != Some("npy") {
        bail!("invalid --out {}: sweep writes .npy", out_path.display());
    }
    let sharded = sweep.shard != (1, 1);
    let side_path = PathBuf::from(format!("{}.json", out_path.display()));
    let checkpoint = match &args.checkpoint {
        Some(c) => {
            let mut outputs =
                vec![("--out", out_path.as_path()), ("--out (shard description)", side_path.as_path())];
            outputs.extend(args.summary.path.as_deref().map(|s| ("--summary", s)));
            Some(crate::checkpoint::check_path(c, &outputs)?)
        }
        None => None,
    };
    let out_file = AtomicFile::create(&out_path, "--out")?;
    let side_file =
        if sharded { Some(AtomicFile::create(&side_path, "--out (shard description)")?) } else { None };
    let summary = args.summary.open()?;
    if let Some(c) = &checkpoint {
        Chunks::claim(c)?;
    }

    let (start, end) = sweep.range();
    let cols = sweep.columns.len();
    // Its size was checked against the limits (or allowed); a failed allocation is an error,
    // not an abort.
    let mut data = Vec::new();
    data.try_reserve_exact((end - start) * cols).map_err(|_| {
        anyhow!("cannot allocate {} for the sweep's array", limits::bytes(((end - start) * cols * 8) as f64))
    })?;
    data.resize((end - start) * cols, 0.0_f64);
    let pool =
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().context("cannot start the threads")?;
    let begin = Instant::now();
    let engine = path(&sweep)?;
    let progress = Progress::new((end - start) as u64);
    let compute = |cells: std::ops::Range<usize>, data: &mut [f64]| {
        pool.install(|| match engine {
            EnsemblePath::Scalar => run_scalar(&sweep, start + cells.start, data, &progress),
            lanes => run_lanes(&sweep, lanes, start + cells.start, data, &progress),
        })
    };
    let chunks = match checkpoint {
        None => {
            compute(0..end - start, &mut data)?;
            None
        }
        Some(path) => {
            let _registered = crate::output::Checkpointing::start();
            let fingerprint = format!("{}|fma {}", sweep.fingerprint(), ensemble::has_fma());
            let chunks = match resumed {
                Some(c) => {
                    let (chunks, done) = Chunks::resume(&c, &fingerprint, cols, &mut data)?;
                    let cells: usize =
                        (0..chunks.count()).filter(|&i| done[i]).map(|i| chunks.range(i).len()).sum();
                    progress.advance(cells as u64);
                    (chunks, done)
                }
                None => {
                    let base = json!({
                        "command": "sweep",
                        "pendula": env!("CARGO_PKG_VERSION"),
                        "cwd": std::env::current_dir().context("cannot read the working directory")?,
                        "args": args,
                        "fingerprint": fingerprint,
                    });
                    let count = end - start;
                    let chunks = Chunks::start(&path, base, count, cols, chunk_size(count, threads))?;
                    let done = vec![false; chunks.count()];
                    (chunks, done)
                }
            };
            let (chunks, done) = chunks;
            Some(chunks.run(&done, &mut data, compute).inspect_err(|_| progress.bar.finish_and_clear())?)
        }
    };
    progress.bar.finish_and_clear();
    let wall_s = begin.elapsed().as_secs_f64();

    let mut shape = sweep.shape();
    if sharded {
        shape = vec![end - start, cols];
    }
    let written = write_npy(&out_file, &shape, &data)?;
    let description = json!({
        "pendula_sweep": SHARD_FORMAT,
        "system": sweep.info.name,
        "method": sweep.method.name,
        "dt": sweep.h,
        "steps": sweep.steps,
        "axes": sweep.axes.iter().map(|a| json!({"name": a.name, "lo": a.lo, "hi": a.hi, "n": a.n})).collect::<Vec<_>>(),
        "columns": sweep.columns,
        "shape": sweep.shape(),
        "shard": sweep.shard.0,
        "shards": sweep.shard.1,
        "offset": start,
        "count": end - start,
        "fingerprint": sweep.fingerprint(),
        "data": { "bytes": written.bytes, "crc32": format!("{:08x}", written.crc32) },
        "kernel": match engine {
            EnsemblePath::DoubleKernel(_) => "simd lanes (the double pendulum's kernel)",
            EnsemblePath::Engine(_) => "simd lanes (ensemble engine)",
            EnsemblePath::Scalar => "scalar, per cell",
        },
        "threads": threads,
        "wall_s": wall_s,
    });
    let mut files = vec![out_file];
    if let Some(f) = side_file {
        write_json(&f, &description)?;
        files.push(f);
    }
    // The array, its shard description and the summary appear together or not at all, and
    // a finished sweep's checkpoint goes in the same step.
    summary.write_then(&description, files, |guard| chunks.map_or(Ok(()), |c| c.finish(guard)))?;
    eprintln!(
        "{}: {} cells{} with {} ({} steps of {} s) on {threads} threads in {wall_s:.3} s -> {} {:?}{}",
        sweep.info.name,
        end - start,
        if sharded {
            format!(" (shard {}/{} of {})", sweep.shard.0, sweep.shard.1, sweep.cells())
        } else {
            String::new()
        },
        sweep.method.name,
        sweep.steps,
        Short(sweep.h),
        out_path.display(),
        shape,
        if sharded { format!(" and {}", side_path.display()) } else { String::new() },
    );
    Ok(())
}

/// The engine the sweep runs on, as the library decides it for the method, the base values
/// and the swept quantities.
fn path(sweep: &Sweep) -> Result<EnsemblePath> {
    let swept: Vec<&str> = sweep.axes.iter().map(|a| a.name.as_str()).collect();
    Ok(pendula::model::ensemble_path(sweep.method, &sweep.values(0)?, &swept))
}

/// Refuses a quantity both set (`--set NAME=…`) and swept (`flag NAME=…`), naming both: the
/// axis would override the setting without a word.
pub(crate) fn refuse_set_and_swept(
    set: &[String],
    swept: &[String],
    axes: &[Axis],
    flag: &str,
) -> Result<()> {
    for (axis, text) in axes.iter().zip(swept) {
        if let Some(item) = set.iter().find(|i| i.split_once('=').is_some_and(|(n, _)| n.trim() == axis.name))
        {
            bail!(
                "`{}` is both set and swept: --set {} and {flag} {}; give one",
                axis.name,
                clip(item),
                clip(text)
            );
        }
    }
    Ok(())
}

/// Writes a row of results: the recorded columns (`energy_error` is called only if needed).
fn store(sweep: &Sweep, state: &[f64], flip_time: f64, energy_error: impl FnOnce() -> f64, row: &mut [f64]) {
    let mut c = 0;
    let mut energy_error = Some(energy_error);
    for r in &sweep.records {
        match r {
            Record::Final => {
                row[c..c + state.len()].copy_from_slice(state);
                c += state.len();
            }
            Record::FlipTime => {
                row[c] = flip_time;
                c += 1;
            }
            Record::EnergyError => {
                row[c] = energy_error.take().map_or(f64::NAN, |f| f());
                c += 1;
            }
        }
    }
}

/// A progress bar over the cells (invisible off a terminal), advanced in steps of 1024 cells
/// so that counting costs nothing measurable.
struct Progress {
    bar: indicatif::ProgressBar,
    done: std::sync::atomic::AtomicU64,
}

impl Progress {
    fn new(cells: u64) -> Self {
        Progress { bar: crate::study::progress(cells, "sweep"), done: std::sync::atomic::AtomicU64::new(0) }
    }

    /// Counts cells done before (a resumed sweep's finished chunks).
    fn advance(&self, cells: u64) {
        let n = self.done.fetch_add(cells, std::sync::atomic::Ordering::Relaxed) + cells;
        self.bar.set_position(n);
    }

    fn cell_done(&self) {
        let n = self.done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if n.is_multiple_of(1024) {
            self.bar.set_position(n);
        }
    }
}

/// The cells on lanes: every cell's values (parameters then state, in the catalogue's order)
/// from the first cell's and the axes, without an allocation per cell.
fn run_lanes(
    sweep: &Sweep,
    path: EnsemblePath,
    start: usize,
    data: &mut [f64],
    progress: &Progress,
) -> Result<()> {
    let cols = sweep.columns.len();
    let count = data.len() / cols;
    let first = sweep.values(0)?;
    // The member's entry (for the chain, the one with its links): its quantities' order.
    let info = first.info();
    let base: Vec<f64> =
        first.parameters().map(|(_, v)| v).chain(first.initial_state().iter().copied()).collect();
    let slots: Vec<usize> = sweep
        .axes
        .iter()
        .map(|a| info.quantities().position(|q| q.name == a.name).expect("a checked name"))
        .collect();
    let np = info.parameters.len();
    let fill = |i: usize, v: &mut [f64]| {
        v.copy_from_slice(&base);
        let mut rest = start + i;
        for (axis, &slot) in sweep.axes.iter().zip(&slots) {
            v[slot] = axis.centre(rest % axis.n);
            rest /= axis.n;
        }
    };
    let store_row = |i: usize, state: &[f64], flip_time: f64, row: &mut [f64]| {
        // The energy error (if recorded) from the cell's own model: built only then.
        let energy = || {
            let mut v = base.clone();
            fill(i, &mut v);
            let settings: Vec<(String, f64)> =
                info.quantities().map(|q| q.name.to_owned()).zip(v.iter().copied()).collect();
            info.values(&settings).map_or(f64::NAN, |values| {
                let model = values.build();
                model.energy(0.0, state) - model.energy(0.0, &v[np..])
            })
        };
        store(sweep, state, flip_time, energy, row);
        progress.cell_done();
    };
    let failed = |member: usize, t: f64| {
        anyhow::Error::new(pendula::Error::NonFinite { t })
            .context(format!("cell {} of the sweep", start + member))
    };
    let track_flips = sweep.records.contains(&Record::FlipTime);
    match path {
        EnsemblePath::DoubleKernel(method) => {
            let spec = BatchSpec {
                method,
                h: sweep.h,
                steps: sweep.steps,
                stop_at_flip: sweep.until_flip,
                track_flips,
            };
            ensemble::run_values(count, &fill, &spec, data, cols, &store_row).map_err(|e| match e {
                pendula::Error::NonFiniteMember { member, t } => failed(member, t),
                other => anyhow::Error::new(other),
            })
        }
        EnsemblePath::Engine(method) => {
            let spec = LaneSpec {
                method,
                h: sweep.h,
                steps: sweep.steps,
                stop_at_flip: sweep.until_flip,
                track_flips,
                cancel: None,
            };
            let store = |i: usize, o: &LaneOutcome, row: &mut [f64]| {
                store_row(i, &o.state[..info.state.len()], o.flip_time, row)
            };
            first.build().ensemble(info, count, &fill, &spec, data, cols, &store).map_err(|e| match e {
                pendula::Error::NonFiniteMember { member, t } => failed(member, t),
                other => anyhow::Error::new(other),
            })
        }
        EnsemblePath::Scalar => unreachable!("scalar sweeps run in run_scalar"),
    }
}

fn run_scalar(sweep: &Sweep, start: usize, data: &mut [f64], progress: &Progress) -> Result<()> {
    let cols = sweep.columns.len();
    let angles: Vec<usize> =
        sweep.info.state.iter().enumerate().filter(|(_, q)| q.is_angle()).map(|(i, _)| i).collect();
    let spec = RunSpec { t0: 0.0, h: sweep.h, end: End::Steps(sweep.steps) };
    data.par_chunks_mut(cols).enumerate().try_for_each(|(i, row)| -> Result<()> {
        let v = sweep.values(start + i)?;
        let model = v.build();
        let mut watch = FlipWatch {
            previous: vec![0.0; angles.len()],
            angles: angles.clone(),
            t_previous: 0.0,
            flip_time: f64::NAN,
            stop: sweep.until_flip,
        };
        let report = model
            .solve(sweep.method, v.initial_state(), &spec, &mut watch)
            .with_context(|| format!("cell {} of the sweep", start + i))?;
        let energy = || model.energy(0.0, &report.state) - model.energy(0.0, v.initial_state());
        store(sweep, &report.state, watch.flip_time, energy, row);
        progress.cell_done();
        Ok(())
    })
}

/// The format of a shard's description (FILE.npy.json), in `pendula_sweep`. Format 2 added
/// `data` (the .npy file's length and CRC-32, which `merge` checks); readers ignore keys they
/// do not know, so adding one needs no new format, and changing one does.
pub const SHARD_FORMAT: u64 = 2;

/// What [`write_npy`] wrote: the file's length and CRC-32.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Written {
    pub bytes: u64,
    pub crc32: u32,
}

/// The length and CRC-32 of what `reader` holds, read to its end.
pub(crate) fn checksum(mut reader: impl std::io::Read) -> std::io::Result<Written> {
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
