//! `pendula divergence`: the distance between two trajectories started `--delta` apart, on a
//! log scale against time, with the exponential growth rate fitted before it saturates.

use anyhow::{Result, bail};
use clap::Args;
use pendula::analysis::{divergence, growth_rate_between};
use pendula::{End, RunSpec};
use pendula_viz::{Figure, Kind, Scale, axis_label, number, palette, pretty, with_unit};
use serde_json::json;

use pendula::error::Short;

use crate::args::{Defaults, EndArg, MethodArgs, SystemArg};
use crate::study::{self, Common, OutDir, num};

#[derive(Debug, Clone, Args)]
pub struct DivergenceArgs {
    #[command(flatten)]
    pub system: SystemArg,
    /// The initial separation, added to the first state variable (or `--variable`).
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub delta: Option<String>,
    /// The state variable to perturb [default: the first, e.g. theta1].
    #[arg(long, value_name = "NAME")]
    pub variable: Option<String>,
    #[command(flatten)]
    pub stepping: MethodArgs,
    #[command(flatten)]
    pub end: EndArg,
    /// The fit uses the distances before they first exceed this.
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub saturation: Option<String>,
    /// The fit uses only the distances above this, leaving out the start, where the
    /// separation has not yet turned along the most unstable direction.
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub fit_from: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// What divergence runs without arguments.
pub const DEFAULTS: Defaults = crate::args::Defaults::of(&pendula::study::defaults::DIVERGENCE, &[]);

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &["divergence.csv", "divergence.png", "divergence.svg"];

pub fn run(args: &DivergenceArgs) -> Result<()> {
    let system = args.system.name(&DEFAULTS);
    let values = study::values(system, &args.common.set.items)?;
    let info = values.info();
    let delta = DEFAULTS.number("delta", &args.delta, "a separation")?;
    if delta == 0.0 {
        bail!("invalid --delta 0: the two trajectories must start apart (a separation not 0)");
    }
    let saturation = DEFAULTS.number("saturation", &args.saturation, "a distance")?;
    if saturation <= delta.abs() {
        bail!(
            "invalid --saturation {}: must be finite and larger than |delta| = {}",
            Short(saturation),
            Short(delta.abs())
        );
    }
    let fit_from = DEFAULTS.number("fit_from", &args.fit_from, "a distance")?;
    if !(fit_from >= 0.0 && fit_from < saturation) {
        bail!(
            "invalid --fit-from {}: must be finite, >= 0 and smaller than --saturation {}",
            Short(fit_from),
            Short(saturation)
        );
    }
    let index = match &args.variable {
        None => 0,
        Some(name) => info.state.iter().position(|q| q.name == name).ok_or_else(|| {
            pendula::Error::unknown_name(info.name, name, info.state.iter().map(|q| q.name))
        })?,
    };
    let start = values.initial_state()[index];
    if !pendula::analysis::divergence::survives_rounding(start, delta) {
        let spacing = (start.abs() * f64::EPSILON).max(f64::MIN_POSITIVE);
        bail!(
            "invalid --delta {}: added to {} = {} it is lost in rounding (floats there are {} apart); use a larger --delta or a smaller start",
            crate::limits::sci(delta),
            info.state[index].name,
            crate::limits::sci(start),
            crate::limits::sci(spacing)
        );
    }
    let method = args.stepping.method(&DEFAULTS)?;
    let h = args.stepping.dt(&DEFAULTS)?;
    let t_end = args.end.t_end(&DEFAULTS)?;
    let spec = RunSpec { t0: 0.0, h, end: End::Time(t_end) };
    let schedule = crate::parse::schedule(&spec, "--dt", "--t-end")?;
    crate::limits::check(
        "divergence",
        args.common.large.allow_large,
        &[crate::limits::Estimate::new(
            crate::limits::Cost::Steps,
            2.0 * schedule.steps as f64,
            format!("2 runs x {} steps", crate::limits::round(schedule.steps as f64)),
        )],
    )?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "divergence", FILES)?;
    let summary = args.common.summary.open()?;
    let model = values.build();
    let every = pendula::analysis::divergence::sample_every(schedule.steps);
    let d = divergence(&*model, method, values.initial_state(), index, delta, &spec, every)?;
    let fit = growth_rate_between(&d, fit_from, saturation);

    let rows: Vec<Vec<String>> = d.t.iter().zip(&d.distance).map(|(t, x)| vec![num(*t), num(*x)]).collect();
    out.csv("divergence.csv", &["t", "distance"], &rows)?;
    let variable = info.state[index].name;
    let (tu, ru) = (info.time_unit(), info.rate_unit());
    match fit {
        Some(f) => sayln!(
            summary,
            "{system}: separation {delta:e} in {variable}; growth rate {} fitted over t = {:.2} … {}",
            with_unit(format!("{:.4}", f.rate), ru),
            f.t_start,
            with_unit(format!("{:.2}", f.t_end), tu)
        ),
        None => sayln!(
            summary,
            "{system}: separation {delta:e} in {variable}; too few samples below --saturation to fit"
        ),
    }
    let mut fig = Figure::new(
        format!(
            "{system}: divergence of trajectories {} apart in {} ({})",
            number(delta),
            pretty(variable),
            method.name
        ),
        axis_label("t", tu),
        distance_label(info),
    )
    .scales(Scale::Linear, Scale::Log);
    let positive: Vec<(f64, f64)> =
        d.t.iter().zip(&d.distance).filter(|(_, x)| **x > 0.0).map(|(t, x)| (*t, *x)).collect();
    fig = fig.with("distance", palette(1), Kind::Line, positive);
    if let Some(f) = fit {
        // The fitted line through the fit window's mean, drawn over the window.
        let (t0, t1) = (f.t_start, f.t_end);
        let mean_log = {
            let window: Vec<f64> =
                d.t.iter()
                    .zip(&d.distance)
                    .filter(|(t, x)| **t >= t0 && **t <= t1 && **x > 0.0)
                    .map(|(_, x)| x.ln())
                    .collect();
            window.iter().sum::<f64>() / window.len().max(1) as f64
        };
        let tm = 0.5 * (t0 + t1);
        let line = |t: f64| (mean_log + f.rate * (t - tm)).exp();
        fig = fig.with(
            format!("fit: rate {}", with_unit(format!("{:.3}", f.rate), ru)),
            palette(0),
            Kind::Dashed,
            (0..=50).map(|k| t0 + (t1 - t0) * k as f64 / 50.0).map(|t| (t, line(t))).collect(),
        );
    }
    out.figure("divergence", &fig)?;
    // The summary and the files appear together or not at all.
    out.finish_with(
        summary,
        &json!({
            "system": system, "method": method.name, "dt": h, "t_end": t_end,
            "delta": delta, "variable": variable, "saturation": saturation, "fit_from": fit_from,
            "growth_rate": fit.map(|f| f.rate),
            "fit_window": fit.map(|f| [f.t_start, f.t_end]),
        }),
    )?;
    Ok(())
}

/// The label of the distance axis: the Euclidean norm of the difference of the two states,
/// whose components have the state's units (angles and angular velocities mixed, for the
/// double pendulum), so its unit is theirs combined as plain numbers.
pub fn distance_label(info: &pendula::system::SystemInfo) -> String {
    let mut units: Vec<String> = Vec::new();
    for q in info.state {
        let u = pendula_viz::unit(q.unit);
        if !u.is_empty() && !units.contains(&u) {
            units.push(u);
        }
    }
    match units.as_slice() {
        [] => "distance |Δy| in state space (dimensionless)".to_owned(),
        [one] => format!("distance |Δy| in state space ({one})"),
        many => format!("distance |Δy| in state space ({} combined)", many.join(" and ")),
    }
}
