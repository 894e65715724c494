//! Validation: command-line strings and scenario files become a checked [`SimulateConfig`].
//! Every error names the offending value and what is allowed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use pendula::control::Tolerances;
use pendula::error::Short;
use pendula::integrator::{self, Method, Scheme};
use pendula::system::{self, Quantity, SystemInfo, Values};
use pendula::{End, RunSpec};
use serde::Deserialize;

use crate::cli::SimulateArgs;

/// Default step size, s.
const DEFAULT_DT: f64 = 1e-3;
/// Default end time, s.
const DEFAULT_T_END: f64 = 10.0;
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
    /// The checkpoint file (absolute).
    pub path: PathBuf,
    /// Simulated seconds between checkpoints; `None`: only when interrupted.
    pub every: Option<f64>,
}

/// A scenario file: the same names as the flags.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct Scenario {
    system: Option<String>,
    method: Option<String>,
    dt: Option<f64>,
    #[serde(alias = "t-end")]
    t_end: Option<f64>,
    steps: Option<u64>,
    rtol: Option<f64>,
    atol: Option<f64>,
    #[serde(alias = "h-min")]
    h_min: Option<f64>,
    #[serde(alias = "h-max")]
    h_max: Option<f64>,
    every: Option<u64>,
    out: Option<PathBuf>,
    summary: Option<PathBuf>,
    #[serde(default)]
    set: BTreeMap<String, toml::Value>,
}

fn read_scenario(path: &Path) -> Result<Scenario> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read scenario file {}", path.display()))?;
    let scenario: Scenario =
        toml::from_str(&text).map_err(|e| anyhow!("invalid scenario file {}: {e}", path.display()))?;
    if scenario.t_end.is_some() && scenario.steps.is_some() {
        bail!("scenario file {} sets both t_end and steps; set one", path.display());
    }
    Ok(scenario)
}

/// Marks the `deg` suffix (its factor is applied as (deg · π) / 180).
const DEGREE: f64 = std::f64::consts::PI / 180.0;

/// Parses a number: a float, optionally with a `deg` or `pi` suffix when `quantity` is an
/// angle (`120deg`, `-0.5pi`, `pi`).
pub fn parse_value(name: &str, text: &str, quantity: Option<&Quantity>) -> Result<f64> {
    let t = text.trim();
    let angle = quantity.is_some_and(|q| q.is_angle());
    let pi = std::f64::consts::PI;
    let (number, factor) = if let Some(n) = t.strip_suffix("deg") {
        (n.trim(), DEGREE)
    } else if let Some(n) = t.strip_suffix("pi") {
        (n.trim().trim_end_matches('*'), pi)
    } else {
        (t, 1.0)
    };
    if factor != 1.0 && !angle {
        let unit = quantity.map_or("", |q| q.unit);
        bail!(
            "invalid value `{text}` for `{name}`: the deg and pi suffixes are only for angles; `{name}` is in {unit}"
        );
    }
    let value = match number {
        "" | "+" if factor == pi => 1.0,
        "-" if factor == pi => -1.0,
        _ => number.parse::<f64>().map_err(|_| {
            anyhow!(
                "invalid value `{text}` for `{name}`: expected a number{}",
                if angle { " (radians), or degrees with a deg suffix (120deg)" } else { "" }
            )
        })?,
    };
    if factor == 1.0 && angle {
        warn_radians(name, t, value);
    }
    // (deg · π) / 180, the same rounding as the catalogue's defaults and the benchmark spec.
    Ok(if factor == DEGREE { value * pi / 180.0 } else { value * factor })
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
    let key = (name.to_owned(), text.to_owned());
    let mut warned = WARNED.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if warned.contains(&key) {
        return;
    }
    warned.push(key);
    let turns = value / std::f64::consts::TAU;
    eprintln!("warning: {name}={text} is {} rad ({turns:.1} turns); did you mean {text}deg?", Short(value));
}

fn toml_value(name: &str, value: &toml::Value, quantity: &Quantity) -> Result<f64> {
    match value {
        toml::Value::Float(f) => number_value(name, *f, quantity),
        toml::Value::Integer(i) => number_value(name, *i as f64, quantity),
        toml::Value::String(s) => parse_value(name, s, Some(quantity)),
        other => bail!(
            "invalid value {other} for `{name}` in the scenario's [set]: expected a number or a string like \"120deg\""
        ),
    }
}

/// A scenario's bare number: radians for an angle, so it gets the same warning as `--set`.
fn number_value(name: &str, value: f64, quantity: &Quantity) -> Result<f64> {
    if quantity.is_angle() {
        warn_radians(name, &Short(value).to_string(), value);
    }
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

/// Parses `--set NAME=VALUE` items against a system's quantities.
pub fn parse_settings(info: &SystemInfo, items: &[String]) -> Result<Vec<(String, f64)>> {
    items
        .iter()
        .map(|item| {
            let (name, text) = item.split_once('=').ok_or_else(|| {
                anyhow!("invalid --set `{item}`: expected NAME=VALUE, e.g. {}", set_example(info))
            })?;
            let name = name.trim();
            let q = info.quantity(name)?;
            Ok((name.to_owned(), parse_value(name, text, Some(q))?))
        })
        .collect()
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

/// `--threads`: a whole number >= 1 when given, else every core.
pub fn parse_threads(text: Option<&str>) -> Result<usize> {
    match text {
        Some(text) => {
            let n: usize = parse_number("--threads", text, "a whole number of threads >= 1")?;
            if n == 0 {
                bail!("invalid --threads 0: need at least 1");
            }
            Ok(n)
        }
        None => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
    }
}

/// An optional floating-point flag: parsed when given, `default` otherwise.
pub fn f64_arg(flag: &str, text: Option<&str>, default: f64, expected: &str) -> Result<f64> {
    text.map_or(Ok(default), |t| parse_number(flag, t, expected))
}

/// Parses a number given to `flag`, naming the flag and what was expected on failure.
pub fn parse_number<T: std::str::FromStr>(flag: &str, text: &str, expected: &str) -> Result<T> {
    text.trim().parse().map_err(|_| anyhow!("invalid value `{text}` for {flag}: expected {expected}"))
}

/// [`RunSpec::schedule`], its errors naming the flags the step and the end came from
/// (`--dt-min` for a convergence study's smallest step); a name without `--` is a scenario
/// file's key (`t_end`).
pub fn schedule(spec: &RunSpec, dt_flag: &str, end_flag: &str) -> Result<pendula::simulate::Schedule> {
    spec.schedule().map_err(|e| match e {
        pendula::Error::InvalidValue { name, value, allowed } => {
            let flag = match name.as_str() {
                "dt" => dt_flag,
                "t-end" | "steps" => end_flag,
                _ => return anyhow::Error::new(pendula::Error::InvalidValue { name, value, allowed }),
            };
            if flag.starts_with("--") {
                anyhow!("invalid {flag} {}: {allowed}", Short(value))
            } else {
                anyhow!("invalid {flag} = {} in the scenario file: {allowed}", Short(value))
            }
        }
        other => other.into(),
    })
}

/// Validates `simulate`'s arguments (and scenario file) into a [`SimulateConfig`].
pub fn simulate(args: &SimulateArgs) -> Result<SimulateConfig> {
    let scenario = match &args.scenario {
        Some(path) => read_scenario(path)?,
        None => Scenario::default(),
    };
    let preset = args.preset.as_deref().map(system::driven::find_preset).transpose()?;
    let system_name = args
        .system
        .clone()
        .or(scenario.system)
        .or_else(|| preset.map(|p| p.system.to_owned()))
        .unwrap_or_else(|| "double".into());
    let info: &'static SystemInfo = system::find(&system_name)?;
    let mut method =
        *integrator::find(args.method.as_deref().or(scenario.method.as_deref()).unwrap_or("rk4"))?;
    if let Some(text) = &args.binding {
        let omega = parse_number("--binding", text, "a number > 0, in 1/s")?;
        method = method.with_binding(omega)?;
    }

    let mut settings = match preset {
        Some(p) => preset_settings(info, p)?,
        None => Vec::new(),
    };
    for (name, value) in &scenario.set {
        let q = info.quantity(name)?;
        settings.push((name.clone(), toml_value(name, value, q)?));
    }
    settings.extend(parse_settings(info, &args.set)?);
    let values = info.values(&settings)?;

    let given_dt = match &args.dt {
        Some(text) => Some(parse_number("--dt", text, "a step size in seconds")?),
        None => scenario.dt,
    };
    let h = given_dt.unwrap_or(DEFAULT_DT);
    let t_eval = args.t_eval.as_deref().map(parse_times).transpose()?;
    let end = match (&args.t_end, &args.steps) {
        (Some(t), _) => End::Time(parse_number("--t-end", t, "an end time in seconds")?),
        (None, Some(n)) => End::Steps(parse_number("--steps", n, "a whole number of steps >= 1")?),
        (None, None) => match (scenario.t_end, scenario.steps) {
            (_, Some(n)) => End::Steps(n),
            (t, None) => End::Time(
                t.or_else(|| t_eval.as_ref().and_then(|v| v.last().copied())).unwrap_or(DEFAULT_T_END),
            ),
        },
    };
    let spec = RunSpec { t0: 0.0, h, end };
    // Name where each value came from: a flag, or the scenario file.
    let dt_flag = if args.dt.is_none() && scenario.dt.is_some() { "dt" } else { "--dt" };
    let end_flag = match (&args.t_end, &args.steps, end) {
        (Some(_), _, _) => "--t-end",
        (None, Some(_), _) => "--steps",
        (None, None, End::Steps(_)) => "steps",
        (None, None, End::Time(_)) if scenario.t_end.is_some() => "t_end",
        (None, None, End::Time(_)) => "--t-end",
    };
    schedule(&spec, dt_flag, end_flag)?;
    let number = |flag: &str, text: &Option<String>, file: Option<f64>, default: f64| -> Result<f64> {
        Ok(match text {
            Some(t) => parse_number(flag, t, "a number")?,
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
        tol.validate()?;
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
            let dt: f64 = parse_number("--output-dt", text, "a time step in seconds")?;
            if !(dt.is_finite() && dt > 0.0) {
                bail!("invalid --output-dt {dt}: must be finite and > 0 (s)");
            }
            Some(pendula::observe::Grid::Spacing(dt))
        }
        (None, Some(times)) => {
            if let End::Time(t_end) = end
                && let Some(&late) = times.iter().find(|&&t| t > t_end)
            {
                bail!("invalid --t-eval: {late} is after --t-end {t_end}");
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
        Some(text) => parse_number("--every", text, "a whole number >= 0")?,
        None => scenario.every.unwrap_or(1),
    };
    let every = (every > 0).then_some(every);
    let out = match every {
        None => None,
        Some(_) => Some(output(args.out.clone().or(scenario.out).unwrap_or_else(|| DEFAULT_OUT.into()))?),
    };
    let summary = args.summary.clone().or(scenario.summary);
    if matches!(out, Some(Output::Stdout)) && summary.as_deref() == Some(Path::new("-")) {
        bail!("--out - and --summary - would both write to stdout: give one of them a file");
    }
    let plot = args.plot.clone();
    if let Some(p) = &plot {
        crate::commands::plot::check_image_path(p, "--plot")?;
    }
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
            let t: f64 = parse_number("--checkpoint-every", text, "a time in seconds")?;
            if !(t.is_finite() && t > 0.0) {
                bail!("invalid --checkpoint-every {}: must be finite and > 0 (simulated seconds)", Short(t));
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

/// `--t-eval T1,T2,...`: finite, non-negative, strictly increasing times in seconds.
fn parse_times(text: &str) -> Result<Vec<f64>> {
    let times: Vec<f64> = text
        .split(',')
        .map(|t| parse_number("--t-eval", t, "comma-separated times in seconds, e.g. 0,0.5,1"))
        .collect::<Result<_>>()?;
    if let Some(bad) = times.iter().find(|t| !(t.is_finite() && **t >= 0.0)) {
        bail!("invalid --t-eval: {bad} is not a time >= 0 s");
    }
    if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
        bail!("invalid --t-eval: the times must increase ({} then {})", w[0], w[1]);
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
        _ => bail!(
            "invalid --out `{}`: the format follows the extension; use .csv, .npy, or - for CSV on stdout",
            path.display()
        ),
    }
}
