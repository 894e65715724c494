//! Tick positions and tick labels for linear and logarithmic axes, and the plotters
//! coordinate that uses them (plotters' own logarithmic key points label as few as one
//! value per axis).

use std::ops::Range;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};

/// Ticks of one axis: the labelled values, and the unlabelled minor ones between them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Ticks {
    /// Labelled ticks, ascending.
    pub major: Vec<f64>,
    /// Minor ticks (grid lines only), ascending; none coincides with a major tick.
    pub minor: Vec<f64>,
}

/// A "nice" step (1, 2 or 5 × 10ᵏ) close to `span / target`.
fn nice_step(span: f64, target: usize) -> f64 {
    let raw = span / target.max(1) as f64;
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    p * if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    }
}

/// Multiples of `step` inside `[lo, hi]`, computed as integer multiples so that they are
/// round (0.1 × 3, not 0.1 + 0.1 + 0.1).
fn multiples(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let (a, b) = ((lo / step - 1e-9).ceil() as i64, (hi / step + 1e-9).floor() as i64);
    (a..=b).map(|k| k as f64 * step).map(|v| if v.abs() < 1e-12 * step { 0.0 } else { v }).collect()
}

/// Ticks of a linear axis over `[lo, hi]`: about `target` labelled multiples of a nice
/// step, and minor ticks at a fifth (or a half, for a step of 2 × 10ᵏ) of it.
pub fn linear_ticks(lo: f64, hi: f64, target: usize) -> Ticks {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Ticks::default();
    }
    let step = nice_step(hi - lo, target);
    let major = multiples(lo, hi, step);
    let mantissa = (step / 10f64.powf(step.log10().floor())).round();
    let sub = if mantissa == 2.0 { step / 2.0 } else { step / 5.0 };
    let minor = multiples(lo, hi, sub)
        .into_iter()
        .filter(|v| major.iter().all(|m| (m - v).abs() > 1e-6 * sub))
        .collect();
    Ticks { major, minor }
}

/// Ticks of a base-10 logarithmic axis over `[lo, hi]` (both > 0):
/// - two decades or more: a label at every power of ten (every second or third one past 12
///   and 24 decades, the rest becoming minor ticks), minor ticks at 2 … 9 × 10ᵏ when there
///   are at most six decades;
/// - from a third of a decade to two: labels at 1, 2 and 5 × 10ᵏ, minor ticks at the rest
///   of 1 … 9 × 10ᵏ;
/// - less, or when that labels fewer than three values: the nice linear ticks of the range, so a range inside one decade still has
///   several readable labels.
pub fn log_ticks(lo: f64, hi: f64) -> Ticks {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Ticks::default();
    }
    let (a, b) = (lo.log10(), hi.log10());
    let span = b - a;
    if span < 0.5 {
        return linear_ticks(lo, hi, 5);
    }
    let inside = |v: f64| v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12);
    let (k0, k1) = (a.floor() as i32, b.ceil() as i32);
    let mut major = Vec::new();
    let mut minor = Vec::new();
    if span >= 2.0 {
        let every = if span > 24.0 {
            3
        } else if span > 12.0 {
            2
        } else {
            1
        };
        for k in k0..=k1 {
            let v = 10f64.powi(k);
            if inside(v) {
                if k.rem_euclid(every) == 0 { major.push(v) } else { minor.push(v) }
            }
            if span <= 6.0 {
                minor.extend((2..=9).map(|m| m as f64 * v).filter(|v| inside(*v)));
            }
        }
    } else {
        for k in k0..=k1 {
            let v = 10f64.powi(k);
            for m in 1..=9 {
                let x = m as f64 * v;
                if inside(x) {
                    if matches!(m, 1 | 2 | 5) { major.push(x) } else { minor.push(x) }
                }
            }
        }
    }
    if major.len() < 3 {
        // 1, 2 and 5 × 10ᵏ would label too few values (2.1 … 8.3 has only 5).
        return linear_ticks(lo, hi, 5);
    }
    minor.sort_by(f64::total_cmp);
    Ticks { major, minor }
}

/// Superscript digits and minus sign, for exponents.
fn superscript(n: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if n < 0 {
        s.push('⁻');
    }
    for c in n.unsigned_abs().to_string().chars() {
        s.push(DIGITS[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

/// A tick label: plain decimals in a moderate range (as many as `step`, the spacing of the
/// ticks, needs), m × 10ⁿ outside it; with `decades` (a log axis labelled at powers of
/// ten), every power of ten as 10ⁿ.
pub fn label(v: f64, step: f64, decades: bool) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { format!("{v}") };
    }
    let a = v.abs();
    let sign = if v < 0.0 { "−" } else { "" };
    let exponent = a.log10().floor() as i32;
    let exponent = if 10f64.powi(exponent + 1) <= a * (1.0 + 1e-12) { exponent + 1 } else { exponent };
    let mantissa = a / 10f64.powi(exponent);
    let power_of_ten = (mantissa - 1.0).abs() < 1e-9;
    if decades && power_of_ten {
        return format!("{sign}10{}", superscript(exponent));
    }
    if (1e-3..1e5).contains(&a) {
        return fixed(v, step);
    }
    scientific(v)
}

/// `v` as a plain decimal, with as many decimals as `step` (the spacing of the ticks)
/// needs, and at least those of the value.
fn fixed(v: f64, step: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { format!("{v}") };
    }
    let (a, sign) = (v.abs(), if v < 0.0 { "−" } else { "" });
    // Decimals from the step (a tick every 0.05 needs two), at least those of the value.
    let step = if step > 0.0 && step.is_finite() { step } else { a };
    let mut decimals = (-step.log10().floor()).max(0.0) as usize;
    while decimals < 6
        && ((a * 10f64.powi(decimals as i32)).round() / 10f64.powi(decimals as i32) - a).abs() > 1e-9 * a
    {
        decimals += 1;
    }
    format!("{sign}{a:.decimals$}")
}

/// `v` as m × 10ⁿ, or 10ⁿ when m is 1.
fn scientific(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { format!("{v}") };
    }
    let (a, sign) = (v.abs(), if v < 0.0 { "−" } else { "" });
    let exponent = a.log10().floor() as i32;
    let exponent = if 10f64.powi(exponent + 1) <= a * (1.0 + 1e-12) { exponent + 1 } else { exponent };
    let mantissa = a / 10f64.powi(exponent);
    if (mantissa - 1.0).abs() < 1e-9 {
        return format!("{sign}10{}", superscript(exponent));
    }
    let m = format!("{mantissa:.2}");
    let m = m.trim_end_matches('0').trim_end_matches('.');
    format!("{sign}{m}×10{}", superscript(exponent))
}

/// A value for titles and legends, to three significant digits: plain in a moderate range
/// (0.0123, 120), m × 10ⁿ or 10ⁿ outside it (2.5×10⁻⁹, 10⁻³).
pub fn number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return label(v, 1.0, false);
    }
    let a = v.abs();
    let digits = 10f64.powf(a.log10().floor() - 2.0);
    let rounded = (a / digits).round() * digits * v.signum();
    if (1e-3..1e5).contains(&a) {
        let decimals = (-digits.log10().round()).max(0.0) as usize;
        let s = format!("{:.decimals$}", rounded.abs());
        let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_owned() } else { s };
        return format!("{}{s}", if v < 0.0 { "−" } else { "" });
    }
    label(rounded, digits, true)
}

/// Whether `v` is 10ᵏ for a whole k.
pub(crate) fn is_power_of_ten(v: f64) -> bool {
    v > 0.0 && (v.log10() - v.log10().round()).abs() < 1e-9
}

/// The spacing of the labelled ticks that label formatting keys its decimals on: the
/// smallest gap between neighbours, or the value itself.
pub(crate) fn step_of(major: &[f64]) -> f64 {
    major.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min)
}

/// A plotters coordinate over `[lo, hi]`, linear or logarithmic, whose key points are the
/// given ticks: bold (labelled) at `major`, light at `minor`.
#[derive(Debug, Clone)]
pub(crate) struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
    pub ticks: Ticks,
}

impl Axis {
    pub fn new(range: Range<f64>, log: bool) -> Self {
        let ticks =
            if log { log_ticks(range.start, range.end) } else { linear_ticks(range.start, range.end, 8) };
        Axis { lo: range.start, hi: range.end, log, ticks }
    }

    /// The position of `v` in [0, 1] along the axis.
    pub fn fraction(&self, v: f64) -> f64 {
        if self.log {
            (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        }
    }

    /// The label of tick value `v`.
    pub fn label(&self, v: f64) -> String {
        // On a log axis each label keeps its own digits (0.005, 0.01, 0.02).
        let step = if self.log { v } else { step_of(&self.ticks.major) };
        // Within a billionth of the span of zero is zero (0.1 + 0.2 − 0.3 ≠ 0).
        if !self.log && v.abs() <= 1e-9 * (self.hi - self.lo) {
            return "0".into();
        }
        let decades = self.log && self.ticks.major.iter().all(|m| is_power_of_ten(*m));
        if decades {
            return label(v, step, true);
        }
        // One notation per axis: plain decimals when every labelled value reads well so, else
        // m × 10ⁿ for all (not 90000 followed by 10⁵).
        if self.plain() { fixed(v, step) } else { scientific(v) }
    }

    /// Whether every nonzero labelled value of this axis prints as a plain decimal:
    /// none below 10⁻³ nor at or above 10⁶ in magnitude.
    fn plain(&self) -> bool {
        self.ticks
            .major
            .iter()
            .map(|m| m.abs())
            .filter(|m| *m > 1e-9 * (self.hi - self.lo))
            .all(|m| (1e-3..1e6).contains(&m))
    }
}

impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let f = self.fraction(*value);
        let f = if f.is_finite() { f.clamp(-10.0, 10.0) } else { -10.0 };
        limit.0 + (f * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() { self.ticks.minor.clone() } else { self.ticks.major.clone() }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}
