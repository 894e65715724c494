//! `pendula lyapunov`: the largest Lyapunov exponent, or the whole spectrum, from the
//! variational equations with periodic re-orthonormalisation (Benettin), its running
//! estimate as a convergence plot, and an uncertainty from batch means.

use anyhow::{Result, bail};
use clap::Args;
use pendula::analysis::lyapunov::Mismatch;
use pendula::analysis::{LyapunovSpec, lyapunov};
use pendula::system::AsSystem;
use pendula_viz::{Figure, Kind, Scale, axis_label, palette, pretty, with_unit};
use serde_json::json;

use crate::args::{Defaults, EndArg, MethodArgs, PresetArg, SystemArg};
use pendula::error::Short;

use crate::study::{self, Common, OutDir, num};

#[derive(Debug, Clone, Args)]
pub struct LyapunovArgs {
    #[command(flatten)]
    pub system: SystemArg,
    #[command(flatten)]
    pub preset: PresetArg,
    #[command(flatten)]
    pub stepping: MethodArgs,
    #[command(flatten)]
    pub end: EndArg,
    /// Time run first and discarded, s.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub transient: Option<String>,
    /// Interval between re-orthonormalisations, s.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub renormalise: Option<String>,
    /// All exponents (QR re-orthonormalisation of as many tangent vectors as the state has).
    #[arg(long)]
    pub spectrum: bool,
    #[command(flatten)]
    pub common: Common,
}

/// What lyapunov runs without arguments.
pub const DEFAULTS: Defaults = crate::args::Defaults::of(
    &pendula::study::defaults::LYAPUNOV,
    &[
        ("system", "With --preset, the preset's system."),
        (
            "method",
            "For the state and its tangent vectors: an explicit Runge–Kutta method, an embedded pair at fixed steps, or Gauss–Legendre.",
        ),
        ("t_end", "The time over which the exponents are averaged."),
    ],
);

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &["lyapunov.csv", "lyapunov.png", "lyapunov.svg"];

pub fn run(args: &LyapunovArgs) -> Result<()> {
    let values = study::preset_values(
        args.system.system.as_deref(),
        args.preset.name.as_deref(),
        &args.common.set.items,
        DEFAULTS.system,
    )?;
    let info = values.info();
    let system = info.name;
    let method = args.stepping.method(&DEFAULTS)?;
    let h = args.stepping.positive_dt(&DEFAULTS)?;
    let t_end = args.end.positive_t_end(&DEFAULTS)?;
    let transient = DEFAULTS.non_negative("transient", &args.transient, "a time in seconds")?;
    let renormalise = DEFAULTS.positive("renormalise", &args.renormalise, "a time in seconds")?;
    let dim = info.state.len();
    let count = if args.spectrum { dim } else { 1 };
    let spec = LyapunovSpec { h, transient, t_end, renormalise, count, blocks: 10 };
    // The step is checked first, so that a step longer than the interval is blamed on --dt
    // (the library, seeing both, names the interval).
    match spec.mismatch() {
        Some(Mismatch::StepOverInterval) => bail!(
            "invalid --dt {}: must be at most --renormalise {} s (the tangent vectors are re-orthonormalised that often, at whole steps)",
            Short(h),
            Short(renormalise)
        ),
        Some(Mismatch::TooFewIntervals) => bail!(
            "invalid --t-end {}: at least {} re-orthonormalisations (every --renormalise {} s) are needed for the uncertainty",
            Short(t_end),
            pendula::analysis::lyapunov::MIN_INTERVALS,
            Short(renormalise)
        ),
        None => {}
    }
    let names =
        [("h", "--dt"), ("t_end", "--t-end"), ("transient", "--transient"), ("renormalise", "--renormalise")];
    let whole = pendula::RunSpec { t0: 0.0, h, end: pendula::End::Time(transient + t_end) };
    crate::parse::schedule(&whole, "--dt", "--t-end")?;
    // What it costs: the state and its `count` tangent vectors over the transient and the
    // averaging time, and the running estimate's rows (one per re-orthonormalisation).
    let steps = crate::limits::steps(transient + t_end, h) * (1 + count) as f64;
    let rows = t_end / renormalise;
    crate::limits::check(
        "lyapunov",
        args.common.large.allow_large,
        &[
            crate::limits::Estimate::new(
                crate::limits::Cost::Steps,
                steps,
                format!(
                    "{} tangent vectors and the state x {} steps",
                    count,
                    crate::limits::round(crate::limits::steps(transient + t_end, h))
                ),
            ),
            crate::limits::Estimate::new(
                crate::limits::Cost::Output,
                rows * (1 + count) as f64 * crate::limits::CSV_BYTES_PER_VALUE,
                format!("{} rows of the running estimate", crate::limits::round(rows)),
            ),
        ],
    )?;
    // The outputs before the work: a path that cannot be written fails first.
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "lyapunov", FILES)?;
    let summary = args.common.summary.open()?;
    let model = values.build();
    let result = lyapunov(&AsSystem(&*model), method, values.initial_state(), &spec)
        .map_err(|e| crate::parse::flag_error(e, &names))?;

    let names: Vec<String> = (1..=count).map(|j| format!("lambda{j}")).collect();
    let mut header = vec!["t"];
    header.extend(names.iter().map(String::as_str));
    let rows: Vec<Vec<String>> =
        result.running.chunks_exact(count + 1).map(|r| r.iter().map(|v| num(*v)).collect()).collect();
    out.csv("lyapunov.csv", &header, &rows)?;

    let (lambda, err) = (result.exponents[0], result.uncertainty[0]);
    let (tu, ru) = (info.time_unit(), info.rate_unit());
    sayln!(
        summary,
        "{system} ({}, dt = {}, {} after a {} transient):",
        method.name,
        with_unit(h, tu),
        with_unit(t_end, tu),
        with_unit(transient, tu)
    );
    for (j, (l, e)) in result.exponents.iter().zip(&result.uncertainty).enumerate() {
        sayln!(summary, "  lambda{} = {}", j + 1, with_unit(format!("{l:.5} ± {e:.5}"), ru));
    }
    if args.spectrum {
        sayln!(summary, "  sum = {}", with_unit(format!("{:.3e}", result.exponents.iter().sum::<f64>()), ru));
    }

    let mut fig = Figure::new(
        format!("{system}: running Lyapunov estimate ({}, dt = {})", method.name, with_unit(h, tu)),
        format!("time after the transient, {}", axis_label("t", tu)),
        format!("exponent, {}", axis_label("lambda", ru)),
    )
    .scales(Scale::Linear, Scale::Linear);
    for j in 0..count {
        let series: Vec<(f64, f64)> =
            result.running.chunks_exact(count + 1).map(|r| (r[0], r[1 + j])).collect();
        fig = fig.with(
            format!(
                "{} = {}",
                pretty(&format!("lambda{}", j + 1)),
                with_unit(format!("{:.4} ± {:.4}", result.exponents[j], result.uncertainty[j]), ru)
            ),
            palette(j),
            Kind::Line,
            series,
        );
    }
    let band = |v: f64| vec![(0.0, v), (t_end, v)];
    fig = fig.with("λ₁ ± uncertainty", palette(0), Kind::Dashed, band(lambda + err)).with(
        "",
        palette(0),
        Kind::Dashed,
        band(lambda - err),
    );
    out.figure("lyapunov", &fig)?;
    // The summary and the files appear together or not at all.
    out.finish_with(summary,
        &json!({
            "system": system, "method": method.name, "dt": h, "t_end": t_end,
            "transient": transient, "renormalise": renormalise,
            "parameters": values.parameters().map(|(n, v)| (n.to_owned(), json!(v))).collect::<serde_json::Map<_, _>>(),
            "lambda_max": lambda, "uncertainty": err,
            "spectrum": args.spectrum.then(|| result.exponents.clone()),
            "spectrum_uncertainty": args.spectrum.then(|| result.uncertainty.clone()),
        }),
    )?;
    Ok(())
}
