//! `pendula bifurcation`: a stroboscopic orbit diagram — the state once per drive period
//! after a transient, against a swept parameter. The damped, driven pendulum runs on the
//! ensemble engine's SIMD lanes (`pendula::ensemble::driven`); other driven systems run the
//! scalar RK4 per parameter value, in parallel. Either way the result does not depend on
//! the thread count.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use pendula::analysis::strobe::{OrbitDiagramSpec, orbit_diagram};
use pendula_viz::{Figure, Kind, Scale, palette, pretty, unit, with_unit};
use serde_json::json;

use crate::args::{Defaults, PresetArg, SystemArg, ThreadsArg};
use crate::commands::sweep::{parse_axis, refuse_set_and_swept};
use crate::limits::{self, Cost, Estimate};
use crate::parse::parse_count;
use crate::study::{self, OutDir, num};

#[derive(Debug, Clone, Args)]
pub struct BifurcationArgs {
    #[command(flatten)]
    pub system: SystemArg,
    /// The swept parameter: NAME=LO:HI:N, N cell centres as in `pendula sweep`.
    #[arg(long, value_name = "NAME=LO:HI:N")]
    pub param: Option<String>,
    #[command(flatten)]
    pub preset: PresetArg,
    /// Time discarded before sampling, s, rounded up to whole drive periods.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub transient: Option<String>,
    /// Samples (drive periods) per parameter value, 1 to 10^6.
    #[arg(long, value_name = "N")]
    pub samples: Option<String>,
    /// RK4 steps per drive period, 4 to 10^6.
    #[arg(long, value_name = "M")]
    pub steps_per_period: Option<String>,
    /// The state variable plotted against the parameter [default: the first velocity].
    #[arg(long, value_name = "NAME")]
    pub variable: Option<String>,
    #[command(flatten)]
    pub threads: ThreadsArg,
    #[command(flatten)]
    pub common: study::Common,
}

/// What bifurcation runs on without a system or preset named.
pub const DEFAULTS: Defaults = crate::args::Defaults::of(
    &pendula::study::defaults::BIFURCATION,
    &[("system", "A driven system; with --preset, the preset's.")],
);

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &["bifurcation.csv", "bifurcation.png", "bifurcation.svg"];

pub fn run(args: &BifurcationArgs) -> Result<()> {
    // Validate everything first.
    let (info, base) = study::preset_settings(
        args.system.system.as_deref(),
        args.preset.name.as_deref(),
        &args.common.set.items,
        DEFAULTS.system,
    )?;
    let system = info.name;
    if info.quantity("drive_frequency").is_err() {
        bail!("invalid system `{system}`: bifurcation needs a driven system (a drive_frequency parameter)");
    }
    let default_param = (system == "driven-pendulum").then_some(DEFAULTS.of.text("param"));
    let Some(param_text) = args.param.as_deref().or(default_param) else {
        bail!("--param NAME=LO:HI:N is required for {system}");
    };
    let axis =
        parse_axis(info, "--param", default_param.unwrap_or("drive_amplitude=0.9:1.5:400"), param_text)?;
    if !info.parameters.iter().any(|q| q.name == axis.name) {
        bail!(
            "invalid --param `{}`: `{}` is not a parameter of {system}",
            crate::parse::clip(param_text),
            axis.name
        );
    }
    refuse_set_and_swept(
        &args.common.set.items,
        &[param_text.to_owned()],
        std::slice::from_ref(&axis),
        "--param",
    )?;
    let transient = DEFAULTS.non_negative("transient", &args.transient, "a time in seconds")?;
    let samples = match &args.samples {
        Some(t) => parse_count("--samples", t, 1, limits::MAX_SAMPLES, "samples")? as usize,
        None => DEFAULTS.of.count("samples") as usize,
    };
    let m = match &args.steps_per_period {
        Some(t) => parse_count("--steps-per-period", t, 4, limits::MAX_STEPS_PER_PERIOD, "steps")? as u32,
        None => DEFAULTS.of.count("steps_per_period") as u32,
    };
    let threads = args.threads.resolve(args.common.large.allow_large)?;
    // What it costs, before the values are made: every value's transient and samples, at the
    // fastest drive along the axis (its most periods), and its rows in memory and in the CSV.
    let simd = pendula::ensemble::driven::runs(info);
    let drive = |i: usize| {
        let mut s = base.clone();
        s.push((axis.name.clone(), axis.centre(i)));
        // A start whose energy overflows is refused here, before its cost is estimated.
        let values = info.values(&s)?;
        values.check_energy().map(|()| values.get("drive_frequency"))
    };
    let w = drive(0)?.max(drive(axis.n - 1)?);
    let periods = (transient * w / (2.0 * std::f64::consts::PI)).ceil() + samples as f64;
    let n = axis.n as f64;
    let rows = n * samples as f64;
    let dim = info.state.len() as f64;
    limits::check(
        "bifurcation",
        args.common.large.allow_large,
        &[
            Estimate::new(
                if simd { Cost::LaneSteps } else { Cost::Steps },
                n * periods * m as f64,
                format!("{} values x {} drive periods x {m} steps", limits::round(n), limits::round(periods)),
            ),
            // Per sample: the state, its CSV row (a few strings) and the figure's point.
            Estimate::new(
                Cost::Memory,
                rows * (dim * 8.0 + (2.0 + dim) * 56.0 + 16.0),
                format!("{} samples", limits::round(rows)),
            ),
            Estimate::new(
                Cost::Output,
                rows * (2.0 + dim) * limits::CSV_BYTES_PER_VALUE,
                format!("{} CSV rows", limits::round(rows)),
            ),
        ],
    )?;
    // Every value's parameters, validated (a drive frequency > 0 included).
    let all: Vec<pendula::system::Values> = (0..axis.n)
        .map(|i| {
            let mut s = base.clone();
            s.push((axis.name.clone(), axis.centre(i)));
            info.values(&s)
        })
        .collect::<Result<_, _>>()?;
    let dim = all[0].info().state.len();
    let state = all[0].info().state;
    let variable = match &args.variable {
        Some(name) => state.iter().position(|q| q.name == name).with_context(|| {
            format!(
                "invalid --variable `{name}`{}; valid: {}",
                pendula::error::did_you_mean(&pendula::error::suggestions(
                    name,
                    state.iter().map(|q| q.name)
                )),
                state.iter().map(|q| q.name).collect::<Vec<_>>().join(", ")
            )
        })?,
        None => dim / 2,
    };
    if let Some(v) = all.iter().find(|v| v.get("drive_frequency") <= 0.0) {
        bail!(
            "invalid drive_frequency {}: a stroboscopic diagram needs a drive (set drive_frequency > 0)",
            pendula::error::Short(v.get("drive_frequency"))
        );
    }
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "bifurcation", FILES)?;
    let summary = args.common.summary.open()?;

    let pool =
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().context("cannot start the threads")?;
    let begin = Instant::now();
    let spec = OrbitDiagramSpec { transient, samples, steps_per_period: m };
    let data = pool.install(|| orbit_diagram(&all, &spec)).map_err(|e| match e {
        pendula::Error::NonFiniteMember { member, t } => anyhow::Error::new(pendula::Error::NonFinite { t })
            .context(format!("{} = {}", axis.name, pendula::error::Short(axis.centre(member)))),
        other => anyhow::Error::new(other),
    })?;
    let wall = begin.elapsed().as_secs_f64();

    let mut header = vec![axis.name.as_str(), "sample"];
    header.extend(state.iter().map(|q| q.name));
    let mut rows = Vec::with_capacity(axis.n * samples);
    let mut points = Vec::with_capacity(axis.n * samples);
    for (i, chunk) in data.chunks_exact(samples * dim).enumerate() {
        let p = axis.centre(i);
        for (s, y) in chunk.chunks_exact(dim).enumerate() {
            let mut row = vec![num(p), s.to_string()];
            row.extend(y.iter().map(|v| num(*v)));
            rows.push(row);
            points.push((p, y[variable]));
        }
    }
    out.csv("bifurcation.csv", &header, &rows)?;
    let tu = info.time_unit();
    let v_unit = unit(state[variable].unit);
    let fig = Figure::new(
        format!(
            "{system}: {samples} samples per value after t = {} (RK4, {m} steps/period)",
            with_unit(transient, tu)
        ),
        // The symbol of the system's own text and presets (g for Baker and Gollub's drive).
        pendula_viz::system_axis_label(info.name, &axis.name, info.quantity(&axis.name)?.unit),
        format!(
            "{} at drive phase 0 ({})",
            pretty(state[variable].name),
            if v_unit.is_empty() { "dimensionless".to_owned() } else { v_unit }
        ),
    )
    .scales(Scale::Linear, Scale::Linear)
    .with("", palette(1), Kind::Dots, points);
    out.figure("bifurcation", &fig)?;
    sayln!(
        summary,
        "{system}: {} values of {} in [{}, {}], {samples} samples each after t = {}; {} [{wall:.2} s, {threads} threads]",
        axis.n,
        axis.name,
        pendula::error::Short(axis.lo),
        pendula::error::Short(axis.hi),
        with_unit(transient, tu),
        if simd { "simd lanes (ensemble engine)" } else { "scalar RK4 per value" }
    );
    // The summary and the files appear together or not at all.
    out.finish_with(
        summary,
        &json!({
            "system": system, "param": {"name": axis.name, "lo": axis.lo, "hi": axis.hi, "n": axis.n},
            "transient": transient, "samples": samples, "steps_per_period": m,
            "kernel": if simd { "simd lanes (ensemble engine)" } else { "scalar, per value" },
            "threads": threads, "wall_s": wall,
        }),
    )?;
    Ok(())
}
