//! `simulate`'s settings: its flags ([`SimulateArgs`]) and scenario files become a checked
//! [`SimulateConfig`], with the values parsed by `parse`, the layer below. Every error names
//! the offending value and what is allowed.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::Args;
use pendula::control::Tolerances;
use pendula::error::Short;
use pendula::integrator::{self, Method};
use pendula::system::{self, SystemInfo, Values};
use pendula::{End, RunSpec};

use crate::args::{LargeArg, PresetArg, SetArgs, SummaryArg};
use crate::limits::{self, Cost, Estimate};
use crate::parse::{
    Unusable, binding_step, clip, count, flag_error, float, parse_count, parse_float, parse_settings,
    preset_settings, schedule, toml_value,
};

/// `simulate`'s flags as clap reads them (also stored in its checkpoints, to resume it).
#[derive(Debug, Clone, Args, serde::Serialize, serde::Deserialize)]
pub struct SimulateArgs {
    #[command(flatten)]
    #[serde(flatten)]
    pub system: crate::args::SystemArg,
    #[command(flatten)]
    #[serde(flatten)]
    pub stepping: crate::args::MethodArgs,
    #[command(flatten)]
    #[serde(flatten)]
    pub end: crate::args::EndArg,
    /// Number of steps, instead of --t-end: 1 to 10^13.
    #[arg(long, allow_hyphen_values = true, value_name = "N", conflicts_with = "t_end")]
    pub steps: Option<String>,
    /// Binding constant ω of tao-2 and tao-4, 1/s: larger holds the two copies closer on
    /// chaotic orbits; binding * dt must be <= 1.
    #[arg(long, value_name = "OMEGA", allow_hyphen_values = true)]
    pub binding: Option<String>,
    /// Relative tolerance of adaptive methods (dopri5, dop853), from 1e-15 (below that the
    /// error estimate is round-off) to 1.
    #[arg(long, value_name = "X", allow_hyphen_values = true)]
    pub rtol: Option<String>,
    /// Absolute tolerance of adaptive methods, >= 0; with 0, a component that
    /// stays exactly 0 meets it (a state at rest does not stall the controller).
    #[arg(long, value_name = "X", allow_hyphen_values = true)]
    pub atol: Option<String>,
    /// Smallest step an adaptive method may take, s; below it the run fails (exit 1); never
    /// below 16 ε t_end, which the end time cannot resolve.
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub h_min: Option<String>,
    /// Largest step an adaptive method may take, s [default: unbounded].
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub h_max: Option<String>,
    #[command(flatten)]
    #[serde(flatten)]
    pub set: SetArgs,
    #[command(flatten)]
    #[serde(flatten)]
    pub preset: PresetArg,
    /// TOML scenario with the same names (keys system, method, dt, t_end or steps, every,
    /// out, summary, and a `[set]` table); flags override it. At most 1 MiB, arrays and
    /// tables nested at most 16 deep.
    #[arg(long, value_name = "FILE.toml")]
    pub scenario: Option<PathBuf>,
    /// Write every N-th step (and the last); 0 writes no trajectory. The
    /// trajectory may take at most 1 GiB (--allow-large lifts it).
    #[arg(long, allow_hyphen_values = true, value_name = "N")]
    pub every: Option<String>,
    /// Adaptive methods: write rows at t = 0, H, 2H, … and the last state, from the method's
    /// dense output, instead of at the irregular steps.
    #[arg(long, allow_hyphen_values = true, value_name = "H", conflicts_with_all = ["every", "t_eval"])]
    pub output_dt: Option<String>,
    /// Adaptive methods: write rows at these increasing times, s (comma-separated), and the
    /// last state, from the dense output; without --t-end the run ends at the last of them.
    #[arg(long, allow_hyphen_values = true, value_name = "T1,T2,...", conflicts_with = "every")]
    pub t_eval: Option<String>,
    /// Also draw the run: time series of the positions, a phase portrait of the first one
    /// and the energy error, as FILE.png or FILE.svg (`pendula plot` draws a saved run).
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
    /// Trajectory output: FILE.csv, FILE.npy, or `-` for CSV on stdout
    /// [default: trajectory.csv].
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    #[serde(flatten)]
    pub summary: SummaryArg,
    /// Locate events and list them in the summary: `flip` (an angle passes ±π the first
    /// time), `zero:NAME` (a state variable crosses 0), `section:NAME=VALUE` (for an angle,
    /// VALUE + 2 pi k: the angle is on a circle); a trailing `+`
    /// or `-` keeps only upward or downward crossings (`section:theta1=0+`).
    #[arg(long = "event", value_name = "SPEC")]
    pub events: Vec<String>,
    /// End the run at the first event.
    #[arg(long)]
    pub stop_on_event: bool,
    /// Write the run's whole state to FILE every --checkpoint-every seconds of simulated
    /// time and when interrupted (SIGINT, SIGTERM, SIGHUP), so that `pendula resume FILE`
    /// continues it to the same bits; meanwhile the trajectory is written to OUT.partial,
    /// and both are removed when the run ends.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Simulated seconds between checkpoints [default: only when interrupted].
    #[arg(long, value_name = "T", allow_hyphen_values = true, requires = "checkpoint")]
    pub checkpoint_every: Option<String>,
    #[command(flatten)]
    #[serde(flatten)]
    pub large: LargeArg,
}

/// What simulate runs without arguments or scenario file: the library's defaults of a run.
pub const SIMULATE: crate::args::Defaults = crate::args::Defaults::of(
    &pendula::study::defaults::SIMULATE,
    &[
        (
            "dt",
            "For adaptive methods the first step to try. The run may take at most 10^11 steps (10^13 with --allow-large).",
        ),
        ("t_end", "The last step is shortened to land on it."),
        ("set", "For example `--set theta1=120deg --set m2=2`."),
    ],
);
/// Default trajectory file.
pub const DEFAULT_OUT: &str = "trajectory.csv";

/// Where the trajectory goes.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// CSV on standard output.
    Stdout,
    /// A CSV file.
    Csv(PathBuf),
    /// A NumPy .npy file (2-D float64).
    Npy(PathBuf),
}

/// A validated `simulate` request.
#[derive(Debug, Clone)]
pub struct SimulateConfig {
    pub values: Values,
    pub method: Method,
    pub spec: RunSpec,
    /// Adaptive steps with these tolerances (methods with an error estimate).
    pub tolerances: Option<Tolerances>,
    /// The first step of an adaptive run, when `--dt` was given.
    pub first_step: Option<f64>,
    /// Write every n-th step; `None` writes no trajectory.
    pub every: Option<u64>,
    pub out: Option<Output>,
    pub summary: Option<PathBuf>,
    /// Rows on this grid from the dense output (`--output-dt`, `--t-eval`; adaptive only).
    pub grid: Option<pendula::observe::Grid>,
    /// Draw the run into this PNG or SVG (`--plot`).
    pub plot: Option<PathBuf>,
    /// Write checkpoints (`--checkpoint`, `--checkpoint-every`).
    pub checkpoint: Option<Checkpoints>,
}

/// Where and how often a run writes checkpoints.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoints {
    /// The checkpoint file, as given (`pendula resume` gives it from the root).
    pub path: PathBuf,
    /// Simulated seconds between checkpoints; `None`: only when interrupted.
    pub every: Option<f64>,
}

pub use pendula_io::scenario::Scenario;

fn read_scenario(path: &Path) -> Result<Scenario> {
    Ok(pendula_io::scenario::read(path)?)
}

/// The scenario in `bytes`, the contents of the file `name` ([`pendula_io::scenario::parse`]:
/// the fuzz harness, `tests/fuzz/`, calls it with generated files).
pub fn parse_scenario(bytes: Vec<u8>, name: &str) -> Result<Scenario> {
    Ok(pendula_io::scenario::parse(bytes, name)?)
}

/// Validates `simulate`'s arguments (and scenario file) into a [`SimulateConfig`].
pub fn simulate(args: &SimulateArgs) -> Result<SimulateConfig> {
    let scenario = match &args.scenario {
        Some(path) => read_scenario(path)?,
        None => Scenario::default(),
    };
    simulate_with(args, scenario)
}

/// [`simulate`] with the scenario file already read: the flags override `scenario`.
pub fn simulate_with(args: &SimulateArgs, scenario: Scenario) -> Result<SimulateConfig> {
    let preset = args.preset.name.as_deref().map(system::driven::find_preset).transpose()?;
    let system_name = args
        .system
        .system
        .clone()
        .or(scenario.system)
        .or_else(|| preset.map(|p| p.system.to_owned()))
        .unwrap_or_else(|| SIMULATE.system.into());
    let info: &'static SystemInfo = pendula::model::find(&system_name)?;
    let mut method = *integrator::find(
        args.stepping
            .method
            .as_deref()
            .or(scenario.method.as_deref())
            .unwrap_or(SIMULATE.method.expect("a default method")),
    )?;
    if let Some(text) = &args.binding {
        let omega = parse_float("--binding", text, "a number > 0, in 1/s")?;
        method = method.with_binding(omega).map_err(|e| flag_error(e, &[("binding", "--binding")]))?;
    }

    let mut settings = match preset {
        Some(p) => preset_settings(info, p)?,
        None => Vec::new(),
    };
    for (name, value) in &scenario.set {
        let q = info.quantity(name)?;
        settings.push((name.clone(), toml_value(name, value, q)?));
    }
    settings.extend(parse_settings(info, &args.set.items)?);
    let values = info.values(&settings)?;

    let given_dt = match &args.stepping.dt {
        Some(text) => Some(parse_float("--dt", text, "a step size in seconds")?),
        None => scenario.dt,
    };
    let h = given_dt.unwrap_or(SIMULATE.dt.expect("a default step"));
    let t_eval = args.t_eval.as_deref().map(parse_times).transpose()?;
    let end = match (&args.end.t_end, &args.steps) {
        (Some(t), _) => End::Time(parse_float("--t-end", t, "an end time in seconds")?),
        (None, Some(n)) => End::Steps(parse_count("--steps", n, 1, limits::MAX_STEPS, "steps")?),
        (None, None) => match (scenario.t_end, scenario.steps) {
            (_, Some(n)) => End::Steps(n),
            (t, None) => End::Time(
                t.or_else(|| t_eval.as_ref().and_then(|v| v.last().copied()))
                    .unwrap_or(SIMULATE.t_end.expect("a default end")),
            ),
        },
    };
    let spec = RunSpec { t0: 0.0, h, end };
    // Name where each value came from: a flag, or the scenario file.
    let dt_flag = if args.stepping.dt.is_none() && scenario.dt.is_some() { "dt" } else { "--dt" };
    let end_flag = match (&args.end.t_end, &args.steps, end) {
        (Some(_), _, _) => "--t-end",
        (None, Some(_), _) => "--steps",
        (None, None, End::Steps(_)) => "steps",
        (None, None, End::Time(_)) if scenario.t_end.is_some() => "t_end",
        (None, None, End::Time(_)) => "--t-end",
    };
    // An adaptive run's --dt is only its first step: it does not count the run's steps
    // (estimated below), and is checked only as a step.
    let checked = match (method.adaptive(), end) {
        (true, End::Time(t)) if t.is_finite() && t > 0.0 && h.is_finite() && h > 0.0 => {
            RunSpec { h: t, ..spec }
        }
        _ => spec,
    };
    schedule(&checked, dt_flag, end_flag)?;
    binding_step(&method, h, dt_flag)?;
    let number = |flag: &str, text: &Option<String>, file: Option<f64>, default: f64| -> Result<f64> {
        Ok(match text {
            // The largest step is unbounded by default, and may be said so.
            Some(t)
                if flag == "--h-max" && float(t) == Err(Unusable::Infinite) && !t.trim().starts_with('-') =>
            {
                f64::INFINITY
            }
            Some(t) => parse_float(flag, t, "a number")?,
            None => file.unwrap_or(default),
        })
    };
    let asked = args.rtol.is_some() || args.atol.is_some() || args.h_min.is_some() || args.h_max.is_some();
    let tolerances = if method.adaptive() || asked {
        let tol = Tolerances {
            rtol: number("--rtol", &args.rtol, scenario.rtol, SIMULATE.of.number("rtol"))?,
            atol: number("--atol", &args.atol, scenario.atol, SIMULATE.of.number("atol"))?,
            h_min: number("--h-min", &args.h_min, scenario.h_min, SIMULATE.of.number("h_min"))?,
            h_max: number("--h-max", &args.h_max, scenario.h_max, f64::INFINITY)?,
        };
        tol.validate().map_err(|e| {
            let from_file = |flag: &str, given: &Option<String>| {
                if given.is_none() {
                    flag.trim_start_matches("--").replace('-', "_")
                } else {
                    flag.to_owned()
                }
            };
            flag_error(
                e,
                &[
                    ("rtol", &from_file("--rtol", &args.rtol)),
                    ("atol", &from_file("--atol", &args.atol)),
                    ("h-min", &from_file("--h-min", &args.h_min)),
                    ("h-max", &from_file("--h-max", &args.h_max)),
                ],
            )
        })?;
        if !method.adaptive() {
            bail!(
                "--rtol, --atol, --h-min and --h-max apply to adaptive methods (dopri5, dop853); {} takes fixed steps (--dt)",
                method.name
            );
        }
        if let End::Steps(_) = end {
            bail!("--steps applies to fixed steps; {} is adaptive: give --t-end", method.name);
        }
        Some(tol)
    } else {
        None
    };

    let adaptive = tolerances.is_some();
    let grid = match (&args.output_dt, t_eval) {
        (Some(text), _) => {
            let dt = parse_float("--output-dt", text, "a time step in seconds")?;
            if dt <= 0.0 {
                bail!("invalid --output-dt {}: must be finite and > 0 (s)", clip(text));
            }
            Some(pendula::observe::Grid::Spacing(dt))
        }
        (None, Some(times)) => {
            if let End::Time(t_end) = end
                && let Some(&late) = times.iter().find(|&&t| t > t_end)
            {
                bail!("invalid --t-eval: {} is after --t-end {}", Short(late), Short(t_end));
            }
            Some(pendula::observe::Grid::Times(times))
        }
        (None, None) => None,
    };
    if grid.is_some() && !adaptive {
        bail!(
            "--output-dt and --t-eval apply to adaptive methods (dopri5, dop853), which have dense output; {} takes fixed steps: thin its rows with --every N",
            method.name
        );
    }
    let every = match &args.every {
        Some(text) => parse_count("--every", text, 0, limits::MAX_STEPS, "steps")?,
        None => scenario.every.unwrap_or(SIMULATE.of.count("every")),
    };
    let every = (every > 0).then_some(every);
    let out = match every {
        None => None,
        Some(_) => Some(output(args.out.clone().or(scenario.out).unwrap_or_else(|| DEFAULT_OUT.into()))?),
    };
    let summary = args.summary.path.clone().or(scenario.summary);
    if matches!(out, Some(Output::Stdout)) && summary.as_deref() == Some(Path::new("-")) {
        bail!("--out - and --summary - would both write to stdout: give one of them a file");
    }
    let plot = args.plot.clone();
    if let Some(p) = &plot {
        crate::parse::check_image_path(p, "--plot")?;
    }
    for (i, e) in args.events.iter().enumerate() {
        if args.events[..i].iter().any(|f| f.trim() == e.trim()) {
            bail!("invalid --event {}: it is given twice; give each event once", clip(e));
        }
    }
    limits::check(
        "simulate",
        args.large.allow_large,
        &simulate_estimates(&values, &spec, &tolerances, every, &grid, &out, plot.is_some())?,
    )?;
    let checkpoint = checkpoints(args, out.as_ref(), summary.as_deref(), plot.as_deref())?;
    Ok(SimulateConfig {
        values,
        method,
        spec,
        tolerances,
        first_step: given_dt,
        every,
        out,
        summary,
        grid,
        plot,
        checkpoint,
    })
}

/// `--checkpoint FILE` and `--checkpoint-every T`, checked against the outputs.
fn checkpoints(
    args: &SimulateArgs,
    out: Option<&Output>,
    summary: Option<&Path>,
    plot: Option<&Path>,
) -> Result<Option<Checkpoints>> {
    let Some(file) = &args.checkpoint else { return Ok(None) };
    let every = match &args.checkpoint_every {
        Some(text) => {
            // NaN, 1e400 and the like are refused as every float is; infinity as a time.
            let t = match float(text) {
                Err(Unusable::Infinite) => f64::INFINITY,
                _ => parse_float("--checkpoint-every", text, "a time in seconds")?,
            };
            if !(t.is_finite() && t > 0.0) {
                bail!(
                    "invalid --checkpoint-every {}: must be finite and > 0 (simulated seconds between checkpoints)",
                    clip(text.trim())
                );
            }
            Some(t)
        }
        None => None,
    };
    let mut outputs: Vec<(&str, PathBuf)> = Vec::new();
    match out {
        Some(Output::Stdout) => bail!(
            "--checkpoint needs the trajectory in a file: rows written to stdout cannot be taken back on resume; give --out FILE.csv or FILE.npy"
        ),
        Some(Output::Csv(p) | Output::Npy(p)) => {
            outputs.push(("--out", p.clone()));
            outputs.push(("--out partial (OUT.partial)", crate::output::PartialFile::path_of(p)));
        }
        None if plot.is_some() => bail!(
            "--plot with --checkpoint draws from the trajectory file, and --every 0 writes none: drop --every 0, or draw the finished run with `pendula plot`"
        ),
        None => {}
    }
    outputs.extend(summary.filter(|s| *s != Path::new("-")).map(|s| ("--summary", s.to_owned())));
    outputs.extend(plot.map(|p| ("--plot", p.to_owned())));
    let named: Vec<(&str, &Path)> = outputs.iter().map(|(f, p)| (*f, p.as_path())).collect();
    let path = crate::checkpoint::check_path(file, &named)?;
    Ok(Some(Checkpoints { path, every }))
}

/// What a `simulate` run costs: its steps (for an adaptive run a lower estimate), the bytes
/// of its trajectory, and with `--plot` the rows it keeps in memory to draw.
fn simulate_estimates(
    values: &Values,
    spec: &RunSpec,
    tolerances: &Option<Tolerances>,
    every: Option<u64>,
    grid: &Option<pendula::observe::Grid>,
    out: &Option<Output>,
    plot: bool,
) -> Result<Vec<Estimate>> {
    use pendula::observe::Grid;
    let (steps, t_end, how) = match (tolerances, spec.end) {
        (Some(tol), End::Time(t_end)) => {
            let period = limits::motion_period(&*values.build(), values.initial_state());
            let steps = limits::adaptive_steps(t_end, period, tol.h_max);
            let how = format!(
                "at least {} adaptive steps per period of {} s over {} s",
                limits::ADAPTIVE_STEPS_PER_PERIOD,
                Short(period),
                Short(t_end)
            );
            (steps, t_end, how)
        }
        _ => {
            let schedule = spec.schedule()?;
            let how = format!("{} steps of {} s", count(schedule.steps), Short(spec.h));
            (schedule.steps as f64, schedule.t_end, how)
        }
    };
    let columns = (values.info().state.len() + 2) as f64;
    // Rows: the grid's, or every n-th step and the last; a plot without a trajectory keeps
    // every step.
    let rows = |every: Option<u64>| match (grid, every) {
        (Some(Grid::Spacing(dt)), _) => t_end / dt + 2.0,
        (Some(Grid::Times(times)), _) => times.len() as f64 + 1.0,
        (None, Some(n)) => steps / n as f64 + 2.0,
        (None, None) => 0.0,
    };
    let written = rows(every);
    let per_value = match out {
        Some(Output::Npy(_)) => 8.0,
        Some(_) => limits::CSV_BYTES_PER_VALUE,
        None => 0.0,
    };
    let mut estimates = vec![
        Estimate::new(Cost::Steps, steps, how),
        Estimate::new(
            Cost::Output,
            written * columns * per_value,
            format!("{} rows of {columns} values (thin them with --every N)", limits::round(written)),
        ),
    ];
    if plot {
        let kept = rows(every.or(Some(1)));
        estimates.push(Estimate::new(
            Cost::Memory,
            kept * columns * 8.0,
            format!("{} rows of {columns} values kept for --plot", limits::round(kept)),
        ));
    }
    Ok(estimates)
}

/// `--t-eval T1,T2,...`: finite, non-negative, strictly increasing times in seconds.
fn parse_times(text: &str) -> Result<Vec<f64>> {
    let times: Vec<f64> = text
        .split(',')
        .map(|t| parse_float("--t-eval", t, "comma-separated times in seconds, e.g. 0,0.5,1"))
        .collect::<Result<_, _>>()?;
    if let Some(bad) = times.iter().find(|t| !(t.is_finite() && **t >= 0.0)) {
        bail!("invalid --t-eval: {} is not a time >= 0 s", Short(*bad));
    }
    if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
        bail!("invalid --t-eval: the times must increase ({} then {})", Short(w[0]), Short(w[1]));
    }
    Ok(times)
}

fn output(path: PathBuf) -> Result<Output> {
    if path.as_os_str() == "-" {
        return Ok(Output::Stdout);
    }
    match path.extension().and_then(|e| e.to_str()) {
        Some("csv") => Ok(Output::Csv(path)),
        Some("npy") => Ok(Output::Npy(path)),
        // A FIFO or device (/dev/null) has no extension to follow: it takes CSV, in place.
        _ if crate::output::is_special(&path) => Ok(Output::Csv(path)),
        _ => bail!(
            "invalid --out `{}`: the format follows the extension; use .csv, .npy, or - for CSV on stdout (a FIFO or device takes CSV)",
            path.display()
        ),
    }
}
