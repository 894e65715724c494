//! Command-line values and arguments: numbers (`120deg`, `pi`, counts), `--set NAME=VALUE`
//! settings, step and end-time schedules, and the echo of a bad value in a message — the bottom
//! of the CLI's layers, used by every command and by `simulate`'s settings (`config`). Every
//! error names the offending value and what is allowed.

use std::path::Path;

use anyhow::{Result, anyhow, bail};
use pendula::error::Short;
use pendula::integrator::Scheme;
use pendula::system::{self, Quantity, SystemInfo};
use pendula::{End, RunSpec};

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
        _ => float(number).map_err(|why| {
            let what = match why {
                Unusable::NotANumber => format!(
                    "expected a number{}",
                    if angle { " (radians), or degrees with a deg suffix (120deg)" } else { "" }
                ),
                other => other.to_string(),
            };
            anyhow!("invalid value `{}` for `{name}`: {what}", clip(text))
        })?,
    };
    if factor == 1.0 && angle {
        warn_radians(name, t, value);
    }
    // (deg · π) / 180, the same rounding as the catalogue's defaults and the benchmark spec.
    let value = if factor == DEGREE { value * pi / 180.0 } else { value * factor };
    if let Some(q) = quantity {
        check_scale(name, text, value, q)?;
    }
    Ok(value)
}

/// How far from its default a mass or a length may be: beyond 10¹² times (or below 10⁻¹²
/// times) the energies, products of masses, lengths and g, overflow or vanish in round-off
/// against the other terms, and the run's numbers mean nothing.
const SCALE_RANGE: f64 = 1e12;

/// Refuses a mass or a length (a positive parameter in kg or m) more than [`SCALE_RANGE`]
/// times away from its default; `text` is the value as given.
pub fn check_scale(name: &str, text: &str, value: f64, q: &Quantity) -> Result<()> {
    let scaled = matches!(q.unit, "kg" | "m") && q.domain == system::Domain::Positive && q.default > 0.0;
    if scaled && value > 0.0 && value.is_finite() {
        let ratio = value / q.default;
        if !(1.0 / SCALE_RANGE..=SCALE_RANGE).contains(&ratio) {
            let kind = if q.unit == "kg" { "mass" } else { "length" };
            bail!(
                "invalid value `{}` for `{name}`: a {kind} must be within 10^12 times its default {} {u} (from {} to {} {u}); beyond that the energies overflow or vanish in round-off",
                clip(text),
                Short(q.default),
                sci(q.default / SCALE_RANGE),
                sci(q.default * SCALE_RANGE),
                u = q.unit,
            );
        }
    }
    Ok(())
}

/// Why a text is no usable float.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unusable {
    /// Not a number at all (`fast`).
    NotANumber,
    /// `nan`.
    NaN,
    /// `inf`, `-infinity`.
    Infinite,
    /// A number beyond f64's range, which Rust reads as infinity (`1e400`).
    Overflow,
    /// A number below the smallest normal float, which Rust reads as a subnormal with
    /// fewer digits (`1e-320`) or as 0 (`1e-400`).
    Underflow,
}

impl std::fmt::Display for Unusable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Unusable::NotANumber => "not a number",
            Unusable::NaN => "NaN is not a number; a finite value is needed",
            Unusable::Infinite => "must be finite",
            Unusable::Overflow => "beyond the largest float (about 1.8e308); must be finite",
            Unusable::Underflow => {
                "below the smallest normal float (about 2.2e-308), where digits are lost or the value becomes 0"
            }
        })
    }
}

/// Reads a float as typed, refusing NaN, infinities and numbers beyond f64's range, which
/// Rust's parser turns silently into infinity, a subnormal or 0.
pub fn float(text: &str) -> std::result::Result<f64, Unusable> {
    let t = text.trim();
    let v: f64 = t.parse().map_err(|_| Unusable::NotANumber)?;
    let bare = t.trim_start_matches(['+', '-']).to_ascii_lowercase();
    if v.is_nan() {
        return Err(Unusable::NaN);
    }
    if v.is_infinite() {
        return Err(if bare == "inf" || bare == "infinity" {
            Unusable::Infinite
        } else {
            Unusable::Overflow
        });
    }
    let mantissa = bare.split('e').next().unwrap_or("");
    let nonzero = mantissa.chars().any(|c| ('1'..='9').contains(&c));
    if (v != 0.0 && v.abs() < f64::MIN_POSITIVE) || (v == 0.0 && nonzero) {
        return Err(Unusable::Underflow);
    }
    Ok(v)
}

/// A float given to `flag`: see [`float`]; the error names the flag, the text as typed and
/// what was `expected`.
pub fn parse_float(flag: &str, text: &str, expected: &str) -> Result<f64> {
    float(text).map_err(|why| match why {
        Unusable::NotANumber => anyhow!("invalid value `{}` for {flag}: expected {expected}", clip(text)),
        other => anyhow!("invalid value `{}` for {flag}: {other}", clip(text)),
    })
}

/// A whole number given to `flag`, from `min` to `max`; `what` names the unit (`steps`).
/// Text that is no whole number, or one beyond the range (`99999999999999999999`), is
/// refused with the range.
pub fn parse_count(flag: &str, text: &str, min: u64, max: u64, what: &str) -> Result<u64> {
    let range = format!("a whole number of {what}, >= {} and <= {}", count(min), count(max));
    let n: u64 = text
        .trim()
        .parse()
        .map_err(|_| anyhow!("invalid value `{}` for {flag}: expected {range}", clip(text)))?;
    if !(min..=max).contains(&n) {
        bail!("invalid value `{}` for {flag}: expected {range}", clip(text));
    }
    Ok(n)
}

/// A count for a message: in full up to a million, as a power of ten (`10^13`) or with an
/// exponent beyond.
pub fn count(n: u64) -> String {
    if n < 1_000_000 {
        return n.to_string();
    }
    let digits = n.to_string();
    if digits.starts_with('1') && digits[1..].bytes().all(|b| b == b'0') {
        format!("10^{}", digits.len() - 1)
    } else {
        sci(n as f64)
    }
}

/// A large or small number to 4 significant digits with an exponent: `1e13`, `7.864e19`.
pub fn sci(x: f64) -> String {
    if !x.is_finite() {
        return "unboundedly many".to_owned();
    }
    let text = format!("{x:.3e}");
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let mantissa =
        if mantissa.contains('.') { mantissa.trim_end_matches('0').trim_end_matches('.') } else { mantissa };
    format!("{mantissa}e{exponent}")
}

/// The user's text for a message: at most 40 characters, and how long the rest was, so that
/// a megabyte of input is never echoed back.
pub fn clip(text: &str) -> String {
    const KEEP: usize = 40;
    match text.char_indices().nth(KEEP) {
        None => text.to_owned(),
        Some((cut, _)) => format!("{}… ({} bytes in all)", &text[..cut], text.len()),
    }
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
/// masses and lengths within [`SCALE_RANGE`] of their defaults, as from `--set`.
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
    text.map_or(Ok(default), |t| parse_float(flag, t, expected))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_beyond_f64_are_refused_as_what_they_are() {
        assert_eq!(float("1e400"), Err(Unusable::Overflow));
        assert_eq!(float("-1e400"), Err(Unusable::Overflow));
        assert_eq!(float("inf"), Err(Unusable::Infinite));
        assert_eq!(float("-Infinity"), Err(Unusable::Infinite));
        assert_eq!(float("NaN"), Err(Unusable::NaN));
        assert_eq!(float("1e-320"), Err(Unusable::Underflow));
        assert_eq!(float("1e-400"), Err(Unusable::Underflow));
        assert_eq!(float("fast"), Err(Unusable::NotANumber));
        // Zero written any way is zero, and the extremes of the normal range are numbers.
        for zero in ["0", "-0.0", "0e-400", "0.000e5"] {
            assert_eq!(float(zero), Ok(0.0), "{zero}");
        }
        assert_eq!(float("2.2250738585072014e-308"), Ok(f64::MIN_POSITIVE));
        assert_eq!(float("1.7976931348623157e308"), Ok(f64::MAX));
    }

    #[test]
    fn echoes_are_clipped() {
        assert_eq!(clip("short"), "short");
        let long = clip(&"x".repeat(1 << 20));
        assert!(long.len() < 80 && long.contains("1048576 bytes"), "{long}");
        assert_eq!(count(10_000_000_000_000), "10^13");
        assert_eq!(count(12_345), "12345");
    }
}
