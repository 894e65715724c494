//! `pendula sweep`: one system integrated from every cell of a grid over parameters and
//! initial-state variables, in parallel, into one .npy array — whole, or one deterministic
//! shard of it (`--shard K/N`, assembled by `pendula merge`).
//!
//! The computation is the library's ([`pendula::sweep`]): the validated sweep, its
//! cells on the SIMD lanes where `ensemble_path` says so and the scalar integrators cell by
//! cell otherwise, a cell's result independent of the thread count and the sharding (Python's
//! `pendula.sweep` runs the same code). This command parses the flags into it, checks the
//! limits, and writes the array, the shard's description, the summary and the checkpoint.
//!
//! # Shards, merge and the checks
//!
//! The CLI's `sweep` (`crates/pendula-cli/src/commands/sweep.rs`) parses its flags into it, checks
//! the limits and writes the array or a shard with its description (format `SHARD_FORMAT`, with the
//! data's length and CRC-32, the pendula version, and whether the CPU had FMA, which changes the
//! kernels' rounding: `merge` warns when given both kinds), its checkpoint and summary; Python's
//! `pendula.sweep` (`crates/pendula-py/src/sweep.rs`, `crates/pendula-py/python/pendula/sweep.py`)
//! runs the same code and writes the same bytes, so shards of either merge with the other's
//! `merge`; `merge` (`crates/pendula-cli/src/commands/merge.rs`) checks every shard's description
//! against the grid and its data against the checksum, then assembles them; `sweep --shard K/N
//! --check` runs the same checks on one shard against the sweep its flags describe (and the pendula
//! version).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use pendula::ensemble;
use pendula::error::{Short, did_you_mean, suggestions};
use pendula::model::EnsemblePath;
pub(crate) use pendula::sweep::Axis;
use pendula::sweep::{CellError, Record, RecordError, Sweep, SweepSpec};
use pendula::system::SystemInfo;
use pendula::{End, RunSpec};
use serde_json::json;

use crate::args::{Defaults, EndArg, LargeArg, MethodArgs, SetArgs, SummaryArg, SystemArg, ThreadsArg};
use crate::checkpoint::Checkpoint;
use crate::chunks::{Chunks, chunk_size};
use crate::limits::{self, Cost, Estimate};
use crate::output::AtomicFile;
use crate::parse::{clip, parse_count, parse_settings};
use crate::shards::{write_json, write_npy};

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
    /// With --shard: check that --out already holds this shard of this sweep, intact (its
    /// description's grid, method, records and pendula version; the file's length and CRC-32),
    /// computing nothing: exit 0 if so, else 2 naming what is wrong.
    #[arg(long, requires = "shard", conflicts_with_all = ["checkpoint", "summary"])]
    #[serde(default)]
    pub check: bool,
    #[command(flatten)]
    #[serde(flatten)]
    pub slurm: crate::slurm::SlurmArgs,
    #[command(flatten)]
    #[serde(flatten)]
    pub large: LargeArg,
}

/// An example `--grid` axis for `info`: its first angle over a turn, else its first state
/// variable.
pub(crate) fn grid_example(info: &SystemInfo) -> String {
    pendula_io::value::axis_example(info)
}

/// Parses an axis `NAME=LO:HI:N` given to `flag` (`--grid`, or bifurcation's `--param`);
/// `example` shows the form in the error.
pub(crate) fn parse_axis(info: &'static SystemInfo, flag: &str, example: &str, text: &str) -> Result<Axis> {
    Ok(pendula_io::value::parse_axis(info, flag, example, text)?)
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
    if method.adaptive() {
        bail!("sweep takes fixed steps: {} runs here as a fixed-step method only with --dt", method.name);
    }
    let h = args.stepping.dt(&DEFAULTS)?;
    let end = match &args.steps {
        Some(text) => End::Steps(parse_count("--steps", text, 1, limits::MAX_STEPS, "steps")?),
        None => End::Time(args.end.t_end(&DEFAULTS)?),
    };
    let end_flag = if args.steps.is_some() { "--steps" } else { "--t-end" };
    let schedule = crate::parse::schedule(&RunSpec { t0: 0.0, h, end }, "--dt", end_flag)?;
    if schedule.last_h != h {
        bail!(
            "invalid --t-end {}: it must be a whole number of steps of --dt {}",
            Short(schedule.t_end),
            Short(h)
        );
    }
    let until_flip = match args.until.as_deref() {
        None => false,
        Some("flip") if pendula::sweep::has_angle(info) => true,
        Some("flip") => bail!("invalid --until flip: the `{}` system has no angle", info.name),
        Some(other) => {
            bail!("invalid --until `{other}`{}: expected flip", did_you_mean(&suggestions(other, ["flip"])))
        }
    };
    let names = args.record.as_deref().unwrap_or("final").split(',').map(str::trim);
    let records = Record::parse_list(names, info).map_err(|e| match e {
        RecordError::Unknown { name, suggestions } => anyhow::anyhow!(
            "invalid --record `{name}`{}: expected {}",
            did_you_mean(&suggestions),
            pendula::sweep::record_names()
        ),
        RecordError::NoAngle => {
            anyhow::anyhow!("invalid --record flip-time: the `{}` system has no angle", info.name)
        }
        RecordError::Twice(name) => anyhow::anyhow!("invalid --record: `{name}` is given twice"),
    })?;
    let cells: usize = axes.iter().map(|a| a.n).product();
    let shard = match &args.shard {
        None => (1, 1),
        Some(text) => parse_shard(text, cells)?,
    };
    // The flags' own checks above name the flags; the library's checks the rest (the
    // corners of the grid in their domains, the method's requirement) in its words.
    let sweep = SweepSpec {
        system: family,
        set: base,
        axes,
        method,
        h,
        steps: schedule.steps,
        until_flip,
        records,
        shard,
    }
    .validate()?;
    // What it costs, before any of it: the steps of every cell of this shard, and the array
    // (held whole in memory, then written).
    let (start, end) = sweep.range();
    let cells = (end - start) as f64;
    let bytes = cells * sweep.columns().len() as f64 * 8.0;
    let how = format!("{} cells x {} bytes", limits::round(cells), sweep.columns().len() * 8);
    limits::check(
        "sweep",
        args.large.allow_large,
        &[
            Estimate::new(
                if matches!(sweep.path(), EnsemblePath::Scalar) { Cost::Steps } else { Cost::LaneSteps },
                cells * sweep.spec().steps as f64,
                format!(
                    "{} cells x {} steps",
                    limits::round(cells),
                    limits::round(sweep.spec().steps as f64)
                ),
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
            let numerical = e.is_numerical();
            let e = anyhow::Error::new(e);
            if numerical { e.context("cell 0 of the sweep") } else { e }
        })?;
    Ok(sweep)
}

/// What sweep runs without arguments.
pub const DEFAULTS: Defaults = crate::args::Defaults::of(
    &pendula::study::defaults::SWEEP,
    &[("set", "The same for every cell, e.g. `--set m2=2`.")],
);

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
    if args.check {
        return crate::commands::merge::check(
            &out_path,
            &sweep.fingerprint(),
            &sweep.shape(),
            sweep.spec().shard,
        );
    }
    if args.slurm.emit_slurm.is_some() {
        return emit_slurm(args, &sweep, &out_path);
    }
    let sharded = sweep.spec().shard != (1, 1);
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
    // The description beside the array (its axes, columns and units, for `plot`; for a
    // shard, also what `merge` checks), whole or sharded.
    let side_file = AtomicFile::create(
        &side_path,
        if sharded { "--out (shard description)" } else { "--out (description)" },
    )?;
    let summary = args.summary.open()?;
    if let Some(c) = &checkpoint {
        Chunks::claim(c)?;
    }

    let (start, end) = sweep.range();
    let cols = sweep.columns().len();
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
    let progress = Progress::new((end - start) as u64);
    let compute = |cells: std::ops::Range<usize>, data: &mut [f64]| {
        pool.install(|| sweep.compute(start + cells.start, data, None, &|| progress.cell_done()))
            .map_err(cell_error)
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
    let run = pendula_io::shard::RunFacts {
        cells: (start, end),
        data: Some(written),
        fma: ensemble::has_fma(),
        threads,
        wall_s,
    };
    let description = pendula_io::shard::sweep_description(&sweep, &run);
    write_json(&side_file, &description)?;
    let files = vec![out_file, side_file];
    // The array, its description and the summary appear together or not at all, and
    // a finished sweep's checkpoint goes in the same step.
    summary.write_then(&description, files, |guard| chunks.map_or(Ok(()), |c| c.finish(guard)))?;
    eprintln!(
        "{}: {} cells{} with {} ({} steps of {} s) on {threads} threads in {wall_s:.3} s -> {} {:?} and {}",
        sweep.info().name,
        end - start,
        if sharded {
            format!(" (shard {}/{} of {})", sweep.spec().shard.0, sweep.spec().shard.1, sweep.cells())
        } else {
            String::new()
        },
        sweep.spec().method.name,
        sweep.spec().steps,
        Short(sweep.spec().h),
        out_path.display(),
        shape,
        side_path.display(),
    );
    Ok(())
}

/// `--emit-slurm N`: the Slurm script that computes this sweep in N shards and merges them.
fn emit_slurm(args: &SweepArgs, sweep: &Sweep, out: &Path) -> Result<()> {
    let mut run = crate::slurm::Argv(args.system.system.iter().cloned().collect());
    run.value("method", &args.stepping.method)
        .value("dt", &args.stepping.dt)
        .value("steps", &args.steps)
        .value("t-end", &args.end.t_end)
        .value("until", &args.until)
        .value("record", &args.record)
        .each("grid", &args.grids)
        .each("set", &args.set.items)
        .switch("allow-large", args.large.allow_large);
    // The script must compute this sweep: its arguments, parsed again, give the same one.
    let again = parse(&run.parse_again::<SweepArgs>("sweep", &["--shard", "1/1"])?)?;
    if again.fingerprint() != sweep.fingerprint() {
        bail!("internal error: the Slurm script's arguments describe another sweep");
    }
    let plan = crate::slurm::Plan {
        command: "sweep",
        args: run.0,
        allow_large: args.large.allow_large,
        out,
        cells: sweep.cells(),
        merge_flag: None,
    };
    let script = crate::slurm::emit(&args.slurm, &plan)?;
    eprintln!(
        "wrote {}: {} cells in {} shards as a Slurm job array, then their merge into {}; submit with `bash {} --wait`",
        script.display(),
        sweep.cells(),
        args.slurm.emit_slurm.as_deref().unwrap_or_default().trim(),
        out.display(),
        script.display()
    );
    Ok(())
}

/// `--shard K/N` of `cells` cells (sweep's, fractal's): 1 <= K <= N <= cells.
pub(crate) fn parse_shard(text: &str, cells: usize) -> Result<(usize, usize)> {
    let bad = || anyhow!("invalid --shard `{}`: expected K/N with 1 <= K <= N, e.g. 3/8", clip(text));
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let (k, n): (usize, usize) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
    if !(1 <= k && k <= n) {
        return Err(bad());
    }
    if n > cells {
        bail!("invalid --shard {k}/{n}: more shards than the {cells} cells");
    }
    Ok((k, n))
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

/// A cell's failure in the sweep's words: "cell N of the sweep" around the library's error.
fn cell_error(e: CellError) -> anyhow::Error {
    match e.cell {
        Some(c) => anyhow::Error::new(e.error).context(format!("cell {c} of the sweep")),
        None => anyhow::Error::new(e.error),
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

pub(crate) use pendula_io::shard::quantity_unit;
