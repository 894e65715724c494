//! The value syntax: numbers as typed, angles with a `deg` or `pi` suffix, grid axes
//! `NAME=LO:HI:N` and counts. Every error names the offending value, clipped ([`clip`]), and
//! what is allowed; `name` and `flag` arguments are the caller's spelling of the setting
//! (`theta1`, `--grid`), so that the message speaks the user's language.

use pendula::error::Short;
use pendula::sweep::Axis;
use pendula::system::{self, Quantity, SystemInfo};

use crate::{Result, invalid};

/// Cells along one axis of a grid (sweep, fractal, bifurcation): the grid's size is limited
/// by its work and its bytes; this only keeps the product representable.
pub const MAX_AXIS_CELLS: u64 = 1_000_000_000;

/// Marks the `deg` suffix (its factor is applied as (deg · π) / 180).
const DEGREE: f64 = std::f64::consts::PI / 180.0;

/// Parses a number: a float, optionally with a `deg` or `pi` suffix when `quantity` is an
/// angle (`120deg`, `-0.5pi`, `pi`, `2*pi`), in radians; a mass or a length is checked
/// against its default ([`check_scale`]).
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
        return Err(invalid!(
            "invalid value `{text}` for `{name}`: the deg and pi suffixes are only for angles; `{name}` is in {unit}"
        ));
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
            invalid!("invalid value `{}` for `{name}`: {what}", clip(text))
        })?,
    };
    // (deg · π) / 180, the same rounding as the catalogue's defaults and the benchmark spec.
    let value = if factor == DEGREE { value * pi / 180.0 } else { value * factor };
    if let Some(q) = quantity {
        check_scale(name, text, value, q)?;
    }
    Ok(value)
}

/// Whether `text` is a bare number, without a `deg` or `pi` suffix: for an angle, radians
/// as typed, which a front end may question when they exceed a full turn (`theta1=120` is
/// far more likely 120° than 19 turns).
pub fn is_bare(text: &str) -> bool {
    let t = text.trim();
    !(t.ends_with("deg") || t.ends_with("pi"))
}

/// How far from its default a mass or a length may be: beyond 10¹² times (or below 10⁻¹²
/// times) the energies, products of masses, lengths and g, overflow or vanish in round-off
/// against the other terms, and the run's numbers mean nothing.
const SCALE_RANGE: f64 = 1e12;

/// Refuses a mass or a length (a positive parameter in kg or m) more than 10¹² times away
/// from its default; `text` is the value as given.
pub fn check_scale(name: &str, text: &str, value: f64, q: &Quantity) -> Result<()> {
    let scaled = matches!(q.unit, "kg" | "m") && q.domain == system::Domain::Positive && q.default > 0.0;
    if scaled && value > 0.0 && value.is_finite() {
        let ratio = value / q.default;
        if !(1.0 / SCALE_RANGE..=SCALE_RANGE).contains(&ratio) {
            let kind = if q.unit == "kg" { "mass" } else { "length" };
            return Err(invalid!(
                "invalid value `{}` for `{name}`: a {kind} must be within 10^12 times its default {} {u} (from {} to {} {u}); beyond that the energies overflow or vanish in round-off",
                clip(text),
                Short(q.default),
                sci(q.default / SCALE_RANGE),
                sci(q.default * SCALE_RANGE),
                u = q.unit,
            ));
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
        Unusable::NotANumber => invalid!("invalid value `{}` for {flag}: expected {expected}", clip(text)),
        other => invalid!("invalid value `{}` for {flag}: {other}", clip(text)),
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
        .map_err(|_| invalid!("invalid value `{}` for {flag}: expected {range}", clip(text)))?;
    if !(min..=max).contains(&n) {
        return Err(invalid!("invalid value `{}` for {flag}: expected {range}", clip(text)));
    }
    Ok(n)
}

/// An axis `NAME=LO:HI:N` of a grid over the quantities of `info`, given to `flag`
/// (`--grid`, `--param`); `example` shows the form in the error. LO and HI are values
/// ([`parse_value`]), N a count of cells from 1 to [`MAX_AXIS_CELLS`]; the bounds are
/// checked by [`check_bounds`] or by the library's validation of the grid.
pub fn parse_axis_text(info: &SystemInfo, flag: &str, example: &str, text: &str) -> Result<Axis> {
    let bad = || invalid!("invalid {flag} `{}`: expected NAME=LO:HI:N, e.g. {example}", clip(text));
    let (name, range) = text.split_once('=').ok_or_else(bad)?;
    let name = name.trim();
    let q = info.quantity(name)?;
    let parts: Vec<&str> = range.split(':').collect();
    let [lo, hi, n] = parts[..] else { return Err(bad()) };
    let (lo, hi) = (parse_value(name, lo, Some(q))?, parse_value(name, hi, Some(q))?);
    let n = parse_count(flag, n, 0, MAX_AXIS_CELLS, "cells")? as usize;
    if n == 0 {
        return Err(invalid!("invalid {flag} `{}`: the number of cells must be >= 1", clip(text)));
    }
    Ok(Axis { name: name.to_owned(), lo, hi, n })
}

/// Refuses an axis parsed from `text` (given to `flag`) whose bounds are not finite with
/// LO < HI.
pub fn check_bounds(flag: &str, text: &str, axis: &Axis) -> Result<()> {
    let (lo, hi) = (axis.lo, axis.hi);
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(invalid!(
            "invalid {flag} `{}`: need finite LO < HI (got {} and {})",
            clip(text),
            Short(lo),
            Short(hi)
        ));
    }
    Ok(())
}

/// An axis `NAME=LO:HI:N` given to `flag`: [`parse_axis_text`], then [`check_bounds`].
pub fn parse_axis(info: &SystemInfo, flag: &str, example: &str, text: &str) -> Result<Axis> {
    let axis = parse_axis_text(info, flag, example, text)?;
    check_bounds(flag, text, &axis)?;
    Ok(axis)
}

/// An example axis for `info`: its first angle over a turn, else its first state variable.
pub fn axis_example(info: &SystemInfo) -> String {
    match info.state.iter().find(|q| q.is_angle()) {
        Some(q) => format!("{}=-pi:pi:256", q.name),
        None => format!("{}=-1:1:256", info.state[0].name),
    }
}

pub use pendula::error::{count, sci};

/// Bytes for people: `512 B`, `1.5 MiB`, `3 GiB`, `2.3e6 TiB`.
pub fn bytes(x: f64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = x;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    let shown = if !v.is_finite() || v >= 1e6 {
        sci(v)
    } else if v.fract() == 0.0 || v >= 100.0 {
        format!("{v:.0}")
    } else {
        // Three significant digits: 29.8 GiB, 1.5 KiB.
        let decimals = if v >= 10.0 { 1 } else { 2 };
        format!("{v:.decimals$}").trim_end_matches('0').trim_end_matches('.').to_owned()
    };
    format!("{shown} {}", UNITS[unit])
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

    fn double() -> &'static SystemInfo {
        pendula::model::find("double").expect("the double pendulum is catalogued")
    }

    #[test]
    fn angles_take_deg_and_pi_in_radians() {
        let pi = std::f64::consts::PI;
        let theta = double().quantity("theta1").expect("an angle");
        let v = |text: &str| parse_value("theta1", text, Some(theta)).expect(text);
        assert_eq!(v("120deg"), 120.0 * pi / 180.0);
        assert_eq!(v("pi"), pi);
        assert_eq!(v("-pi"), -pi);
        assert_eq!(v("+pi"), pi);
        assert_eq!(v("2*pi"), 2.0 * pi);
        assert_eq!(v(" -0.5pi "), -0.5 * pi);
        assert_eq!(v("1.5"), 1.5);
        assert!(is_bare("1.5") && !is_bare("2*pi") && !is_bare("120deg"));
        let e = parse_value("theta1", "fast", Some(theta)).unwrap_err().to_string();
        assert_eq!(
            e,
            "invalid value `fast` for `theta1`: expected a number (radians), or degrees with a deg suffix (120deg)"
        );
    }

    #[test]
    fn suffixes_are_for_angles_only_and_scales_are_bounded() {
        let m1 = double().quantity("m1").expect("a mass");
        let e = parse_value("m1", "2pi", Some(m1)).unwrap_err().to_string();
        assert_eq!(
            e,
            "invalid value `2pi` for `m1`: the deg and pi suffixes are only for angles; `m1` is in kg"
        );
        let e = parse_value("dt", "pi", None).unwrap_err().to_string();
        assert!(e.contains("only for angles"), "{e}");
        let e = parse_value("m1", "1e13", Some(m1)).unwrap_err().to_string();
        assert!(
            e.contains("a mass must be within 10^12 times its default 1 kg (from 1e-12 to 1e12 kg)"),
            "{e}"
        );
        assert_eq!(parse_value("m1", "2", Some(m1)).expect("a mass"), 2.0);
        let e = parse_value("m1", "nan", Some(m1)).unwrap_err().to_string();
        assert_eq!(e, "invalid value `nan` for `m1`: NaN is not a number; a finite value is needed");
    }

    #[test]
    fn axes_are_name_lo_hi_n() {
        let info = double();
        let example = axis_example(info);
        assert_eq!(example, "theta1=-pi:pi:256");
        let a = parse_axis(info, "--grid", &example, "theta1=-pi:pi:7").expect("an axis");
        assert_eq!(
            a,
            Axis { name: "theta1".into(), lo: -std::f64::consts::PI, hi: std::f64::consts::PI, n: 7 }
        );
        let e = |text: &str| parse_axis(info, "--grid", &example, text).unwrap_err().to_string();
        assert_eq!(
            e("theta1=0:1"),
            "invalid --grid `theta1=0:1`: expected NAME=LO:HI:N, e.g. theta1=-pi:pi:256"
        );
        assert_eq!(e("theta1=0:1:0"), "invalid --grid `theta1=0:1:0`: the number of cells must be >= 1");
        assert_eq!(e("theta1=1:0:4"), "invalid --grid `theta1=1:0:4`: need finite LO < HI (got 1 and 0)");
        assert!(e("thetaa=0:1:4").contains("thetaa"));
        // Without the bounds check, the library's validation of the grid has the last word.
        let unchecked = parse_axis_text(info, "grid", &example, "theta1=1:0:4").expect("an axis");
        assert_eq!((unchecked.lo, unchecked.hi), (1.0, 0.0));
    }
}
