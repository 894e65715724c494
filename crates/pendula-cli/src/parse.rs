//! Command-line values and arguments: numbers (`120deg`, `pi`, counts), `--set NAME=VALUE`
//! settings, step and end-time schedules, and the echo of a bad value in a message — the bottom
//! of the CLI's layers, used by every command and by `simulate`'s settings (`config`). Every
//! error names the offending value and what is allowed. The value syntax itself is
//! [`pendula_io::value`]'s, shared with Python and the lab; this layer adds the command line's
//! own: `--set` items, flags' defaults, schedules, and the warning on stderr for an angle
//! given in radians that exceeds a full turn.

use std::path::Path;

use anyhow::{Result, anyhow, bail};
use pendula::error::Short;
use pendula::integrator::Scheme;
use pendula::system::{self, Quantity, SystemInfo};
use pendula::{End, RunSpec};

pub use pendula_io::value::{Unusable, check_scale, clip, count, float, parse_count, parse_float, sci};

/// Parses a number ([`pendula_io::value::parse_value`]: `120deg`, `-0.5pi`, `pi` for an
/// angle), warning on stderr when a bare number for an angle exceeds a full turn.
pub fn parse_value(name: &str, text: &str, quantity: Option<&Quantity>) -> Result<f64> {
    let value = pendula_io::value::parse_value(name, text, quantity)?;
    if quantity.is_some_and(|q| q.is_angle()) && pendula_io::value::is_bare(text) {
        warn_radians(name, text.trim(), value);
    }
    Ok(value)
}

thread_local! {
    /// Set by the fuzz harness (`tests/fuzz/`) on its threads: its millions of generated
    /// values would fill the test's captured output with warnings, and the list of values
    /// warned about once with their texts. The binary never sets it.
    pub static QUIET_WARNINGS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether warnings and notes on stderr are silenced: only ever on the fuzz harness's
/// threads.
pub(crate) fn quiet() -> bool {
    QUIET_WARNINGS.get()
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

pub(crate) fn toml_value(name: &str, value: &toml::Value, quantity: &Quantity) -> Result<f64> {
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

/// Checks that `path` names a PNG or SVG file; `flag` names the option.
pub fn check_image_path(path: &Path, flag: &str) -> Result<()> {
    if path == Path::new("-") {
        bail!("invalid {flag} -: a picture is written to a file, not stdout; give FILE.png or FILE.svg");
    }
    match path.extension().and_then(|e| e.to_str()) {
        Some("png" | "svg") => Ok(()),
        _ => bail!("invalid {flag} `{}`: the format follows the extension; use .png or .svg", path.display()),
    }
}
