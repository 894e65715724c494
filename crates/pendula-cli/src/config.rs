//! Validation: command-line strings and scenario files become a checked [`SimulateConfig`].
//! Every error names the offending value and what is allowed.

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use pendula::control::Tolerances;
use pendula::error::Short;
use pendula::integrator::{self, Method, Scheme};
use pendula::system::{self, Quantity, SystemInfo, Values};
use pendula::{End, RunSpec};

use crate::cli::SimulateArgs;
use crate::limits::{self, Cost, Estimate};

/// What simulate runs without arguments or scenario file.
pub const SIMULATE: crate::args::Defaults = crate::args::Defaults {
    system: "double",
    method: Some("rk4"),
    dt: Some(1e-3),
    t_end: Some(10.0),
    notes: &[
        (
            "dt",
            "For adaptive methods the first step to try. The run may take at most 10^11 steps (10^13 with --allow-large).",
        ),
        ("t_end", "The last step is shortened to land on it."),
        ("set", "For example `--set theta1=120deg --set m2=2`."),
    ],
};
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

pub(crate) use pendula_io::scenario::Scenario;

fn read_scenario(path: &Path) -> Result<Scenario> {
    Ok(pendula_io::scenario::read(path)?)
}

/// The scenario in `bytes`, the contents of the file `name` ([`pendula_io::scenario::parse`]:
/// the fuzz harness, `src/fuzz/`, calls it with generated files).
#[cfg(test)]
pub(crate) fn parse_scenario(bytes: Vec<u8>, name: &str) -> Result<Scenario> {
    Ok(pendula_io::scenario::parse(bytes, name)?)
}

pub use pendula_io::value::{Unusable, check_scale, clip, count, float, parse_count, parse_float};

/// Parses a number ([`pendula_io::value::parse_value`]), warning on stderr when a bare
/// number for an angle exceeds a full turn.
pub fn parse_value(name: &str, text: &str, quantity: Option<&Quantity>) -> Result<f64> {
    let value = pendula_io::value::parse_value(name, text, quantity)?;
    if quantity.is_some_and(|q| q.is_angle()) && pendula_io::value::is_bare(text) {
        warn_radians(name, text.trim(), value);
    }
    Ok(value)
}

#[cfg(test)]
thread_local! {
    /// Set by the fuzz harness (`src/fuzz/`) on its threads: its millions of generated
    /// values would fill the test's captured output with warnings, and the list of values
    /// warned about once with their texts.
    pub(crate) static QUIET_WARNINGS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether warnings and notes on stderr are silenced: only ever on the fuzz harness's
/// threads, in the unit tests.
pub(crate) fn quiet() -> bool {
    #[cfg(test)]
    return QUIET_WARNINGS.get();
    #[cfg(not(test))]
    false
}

/// Warns on stderr, once per name and value, when a bare number for an angle exceeds a full
/// turn: `theta1=120` is far more likely 120° than 19 turns. It is a warning, not an error,
/// because spun-up starts (several turns) are legitimate.
fn warn_radians(name: &str, text: &str, value: f64) {
    use std::sync::Mutex;
    static WARNED: Mutex<Vec<(String, String)>> = Mutex::new(Vec::new());
    if !(value.abs() > std::f64::consts::TAU && value.is_finite()) {
        return;
    }
    if quiet() {
        return;
    }
    let key = (name.to_owned(), text.to_owned());
    let mut warned = WARNED.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if warned.contains(&key) {
        return;
    }
    warned.push(key);
    let turns = value / std::f64::consts::TAU;
    // Every value quoted in at most 20 characters: `theta1=1e300` must not print 300 digits.
    let turns = if turns.abs() < 1e6 { format!("{turns:.1}") } else { Short(turns).to_string() };
    let text = pendula::error::clip(text, 20);
    eprintln!("warning: {name}={text} is {} rad ({turns} turns); did you mean {text}deg?", Short(value));
}

fn toml_value(name: &str, value: &toml::Value, quantity: &Quantity) -> Result<f64> {
    match value {
        toml::Value::Float(f) => number_value(name, *f, quantity),
        toml::Value::Integer(i) => number_value(name, *i as f64, quantity),
        toml::Value::String(s) => parse_value(name, s, Some(quantity)),
        other => bail!(
            "invalid value {} for `{name}` in the scenario's [set]: expected a number or a string like \"120deg\"",
            clip(&other.to_string())
        ),
    }
}

/// A scenario's bare number: radians for an angle, so it gets the same warning as `--set`;
/// masses and lengths within 10^12 times their defaults ([`check_scale`]), as from `--set`.
fn number_value(name: &str, value: f64, quantity: &Quantity) -> Result<f64> {
    let text = Short(value).to_string();
    if value != 0.0 && value.abs() < f64::MIN_POSITIVE {
        bail!("invalid value {text} for `{name}` in the scenario's [set]: {}", Unusable::Underflow);
    }
    if quantity.is_angle() {
        warn_radians(name, &text, value);
    }
    check_scale(name, &text, value, quantity)?;
    Ok(value)
}

/// An example `--set` item for `info`: its first angle in degrees, else its first parameter.
pub fn set_example(info: &SystemInfo) -> String {
    match info.state.iter().find(|q| q.is_angle()) {
        Some(q) => format!("{}=120deg", q.name),
        None => {
            info.parameters.first().map_or_else(String::new, |q| format!("{}={}", q.name, q.default * 2.0))
        }
    }
}

/// Parses `--set NAME=VALUE` items against a system's quantities. A name set twice is
/// refused, naming both: which one was meant is not ours to guess.
pub fn parse_settings(info: &SystemInfo, items: &[String]) -> Result<Vec<(String, f64)>> {
    let mut seen: Vec<(&str, &str)> = Vec::new();
    items
        .iter()
        .map(|item| {
            let (name, text) = item.split_once('=').ok_or_else(|| {
                anyhow!("invalid --set `{}`: expected NAME=VALUE, e.g. {}", clip(item), set_example(info))
            })?;
            let name = name.trim();
            let q = info.quantity(name)?;
            if let Some((_, first)) = seen.iter().find(|(n, _)| *n == name) {
                bail!("`{name}` is set twice: --set {} and --set {}; give it once", clip(first), clip(item));
            }
            seen.push((name, item));
            Ok((name.to_owned(), parse_value(name, text, Some(q))?))
        })
        .collect()
}

/// Refuses `--set` items that name a quantity the command sets itself (`owned`, with why),
/// instead of overriding them silently.
pub fn refuse_settings(items: &[String], owned: &[&str], why: &str) -> Result<()> {
    for item in items {
        let name = item.split_once('=').map_or(item.as_str(), |(n, _)| n).trim();
        if owned.contains(&name) {
            bail!("invalid --set {}: {why}", clip(item));
        }
    }
    Ok(())
}

/// The settings of `preset`, which must be for the system `info`.
pub fn preset_settings(info: &SystemInfo, preset: &system::driven::Preset) -> Result<Vec<(String, f64)>> {
    if preset.system != info.name {
        bail!(
            "invalid --preset `{}`: it is for the system {}, not {}",
            preset.name,
            preset.system,
            info.name
        );
    }
    Ok(preset.settings.iter().map(|(n, v)| ((*n).to_owned(), *v)).collect())
}

/// An optional floating-point flag: parsed when given, `default` otherwise.
pub fn f64_arg(flag: &str, text: Option<&str>, default: f64, expected: &str) -> Result<f64> {
    text.map_or(Ok(default), |t| Ok(parse_float(flag, t, expected)?))
}

/// A float given to `flag` that must be finite and > 0 (a step, a time span), or `default`.
pub fn positive_arg(flag: &str, text: Option<&str>, default: f64, expected: &str) -> Result<f64> {
    let v = f64_arg(flag, text, default, expected)?;
    if v <= 0.0 {
        bail!("invalid value `{}` for {flag}: must be > 0 ({expected})", clip(text.unwrap_or("")));
    }
    Ok(v)
}

/// [`RunSpec::schedule`], its errors naming the flags the step and the end came from
/// (`--dt-min` for a convergence study's smallest step); a name without `--` is a scenario
/// file's key (`t_end`).
pub fn schedule(spec: &RunSpec, dt_flag: &str, end_flag: &str) -> Result<pendula::simulate::Schedule> {
    spec.schedule().map_err(|e| match e {
        pendula::Error::InvalidValue { name, value, allowed } => {
            let flag = match name.as_str() {
                "h" => dt_flag,
                "t_end" | "steps" => end_flag,
                _ => return anyhow::Error::new(pendula::Error::InvalidValue { name, value, allowed }),
            };
            // Too many steps is the step and the end together: both are named.
            let with = match (name.as_str(), spec.end) {
                ("h", End::Time(t)) if allowed.contains("10^13") => format!(" to {end_flag} {}", Short(t)),
                _ => String::new(),
            };
            if flag.starts_with("--") {
                anyhow!("invalid {flag} {}: {allowed}{with}", Short(value))
            } else {
                anyhow!("invalid {flag} = {} in the scenario file: {allowed}{with}", Short(value))
            }
        }
        other => other.into(),
    })
}

/// Tao's maps are stable for ω h ≤ 1 ([`pendula::integrator::tao::check_binding_step`]):
/// checked before the run, in the flags' words (the library names the quantities).
pub fn binding_step(method: &pendula::integrator::Method, h: f64, dt_flag: &str) -> Result<()> {
    let Scheme::Tao(scheme) = method.scheme else { return Ok(()) };
    if pendula::integrator::tao::check_binding_step(&scheme, h).is_err() {
        bail!(
            "invalid binding * dt = {} (--binding {} 1/s, {dt_flag} {} s): Tao's methods are unstable above binding * dt = 1: lower --binding or {dt_flag} (for chaotic motion keep binding near 200 and dt <= 5 ms)",
            Short(scheme.binding * h),
            Short(scheme.binding),
            Short(h)
        );
    }
    Ok(())
}

/// A library error about a quantity (`rtol`), renamed to the flag or key it came from
/// (`("rtol", "--rtol")`); other errors pass unchanged.
pub fn flag_error(e: pendula::Error, names: &[(&str, &str)]) -> anyhow::Error {
    match e {
        pendula::Error::InvalidValue { name, value, allowed } => {
            match names.iter().find(|(n, _)| *n == name) {
                Some((_, flag)) if flag.starts_with("--") => {
                    anyhow!("invalid {flag} {}: {allowed}", Short(value))
                }
                Some((_, key)) => anyhow!("invalid {key} = {} in the scenario file: {allowed}", Short(value)),
                None => pendula::Error::InvalidValue { name, value, allowed }.into(),
            }
        }
        other => other.into(),
    }
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
pub(crate) fn simulate_with(args: &SimulateArgs, scenario: Scenario) -> Result<SimulateConfig> {
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
    let checked = match (matches!(method.scheme, Scheme::Embedded(_)), end) {
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
    let tolerances = if matches!(method.scheme, Scheme::Embedded(_)) || asked {
        let tol = Tolerances {
            rtol: number("--rtol", &args.rtol, scenario.rtol, 1e-6)?,
            atol: number("--atol", &args.atol, scenario.atol, 1e-6)?,
            h_min: number("--h-min", &args.h_min, scenario.h_min, 0.0)?,
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
        if !matches!(method.scheme, Scheme::Embedded(_)) {
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
        None => scenario.every.unwrap_or(1),
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
        crate::commands::plot::check_image_path(p, "--plot")?;
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
