//! Catalogue names and units as they are printed on figures: `theta1` → θ₁, `kg m^2/s` →
//! kg m²/s. One mapping, used by every figure.

/// Greek letters spelled out in catalogue names, and their symbols.
const GREEK: [(&str, &str); 12] = [
    ("theta", "θ"),
    ("omega", "ω"),
    ("lambda", "λ"),
    ("phi", "φ"),
    ("psi", "ψ"),
    ("zeta", "ζ"),
    ("alpha", "α"),
    ("beta", "β"),
    ("gamma", "γ"),
    ("delta", "δ"),
    ("tau", "τ"),
    ("mu", "μ"),
];

/// Names of parameters and their symbols.
const NAMED: [(&str, &str); 2] = [("drive_amplitude", "A"), ("drive_frequency", "Ω")];

/// Parameters whose symbol in a system differs from [`NAMED`]'s: the symbol its catalogue
/// description, presets and references use (Baker and Gollub's drive amplitude g and
/// frequency ω_D; the oscillator's driving force F).
const SYSTEM_NAMED: [(&str, &str, &str); 3] = [
    ("driven-pendulum", "drive_amplitude", "g"),
    ("driven-pendulum", "drive_frequency", "ω_D"),
    ("oscillator", "drive_amplitude", "F"),
];

fn subscript(digits: &str) -> String {
    digits.chars().map(|c| char::from_u32(0x2080 + c.to_digit(10).unwrap_or(0)).unwrap_or(c)).collect()
}

/// The symbol of a catalogue name: a spelled-out Greek letter becomes the letter, trailing
/// digits become subscripts (`theta1` → θ₁, `omega2` → ω₂, `lambda1` → λ₁, `p1` → p₁),
/// the drive's parameters become A and Ω; anything else is returned as it is.
pub fn pretty(name: &str) -> String {
    if let Some((_, s)) = NAMED.iter().find(|(n, _)| *n == name) {
        return (*s).to_owned();
    }
    let split = name.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    let (stem, digits) = name.split_at(split);
    if stem.is_empty() || !stem.chars().all(|c| c.is_ascii_alphabetic()) {
        return name.to_owned();
    }
    let stem = GREEK.iter().find(|(n, _)| *n == stem).map_or(stem, |(_, s)| *s);
    format!("{stem}{}", subscript(digits))
}

/// `text` with each word that is a Greek-letter catalogue name as its symbol (`section
/// theta1 = 0` → `section θ₁ = 0`); other words, method names with digits among them
/// (`dopri5`), as they are.
pub fn greek_words(text: &str) -> String {
    let greek = |word: &str| {
        let stem = word.trim_end_matches(|c: char| c.is_ascii_digit());
        GREEK.iter().any(|(n, _)| *n == stem)
    };
    text.split(' ').map(|w| if greek(w) { pretty(w) } else { w.to_owned() }).collect::<Vec<_>>().join(" ")
}

/// A unit as printed: `^2` and `^3` become superscripts, `*` a space; the catalogue's `1`
/// (a dimensionless quantity) becomes the empty string.
pub fn unit(unit: &str) -> String {
    if unit == "1" {
        return String::new();
    }
    unit.replace("^-1", "⁻¹").replace("^2", "²").replace("^3", "³").replace('*', " ")
}

/// The symbol of `name` in `system`: [`pretty`]'s, unless the system writes it otherwise
/// (the driven pendulum's drive amplitude is g, as in its description and presets).
pub fn symbol(system: &str, name: &str) -> String {
    SYSTEM_NAMED
        .iter()
        .find(|(s, n, _)| *s == system && *n == name)
        .map_or_else(|| pretty(name), |(_, _, symbol)| (*symbol).to_owned())
}

/// [`axis_label`] with the symbol `system` uses for `name` (see [`symbol`]):
/// `drive amplitude g (dimensionless)` for the driven pendulum.
pub fn system_axis_label(system: &str, name: &str, unit_text: &str) -> String {
    label_of(name, symbol(system, name), unit_text)
}

/// An axis label: the symbol and its unit in parentheses, `θ₁ (rad)`, or
/// `ω (dimensionless)` for a quantity without a unit (the catalogue's `1`, or the empty
/// unit of time in a dimensionless system). A name of several words keeps its words
/// before the symbol: `drive amplitude A (dimensionless)`.
pub fn axis_label(name: &str, unit_text: &str) -> String {
    label_of(name, pretty(name), unit_text)
}

fn label_of(name: &str, symbol: String, unit_text: &str) -> String {
    let symbol = if name.contains('_') && symbol != name {
        format!("{} {symbol}", name.replace('_', " "))
    } else {
        symbol
    };
    let u = unit(unit_text);
    if u.is_empty() { format!("{symbol} (dimensionless)") } else { format!("{symbol} ({u})") }
}

/// A value with its unit, `0.01 s`, or the value alone when the unit is empty or `1` (a
/// dimensionless system's times, rates and energies).
pub fn with_unit(value: impl std::fmt::Display, unit_text: &str) -> String {
    let u = unit(unit_text);
    if u.is_empty() { value.to_string() } else { format!("{value} {u}") }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn greek_words_in_a_title_become_symbols_and_nothing_else_changes() {
        assert_eq!(
            greek_words("double: section theta1 = 0 (dopri5), p1 beta"),
            "double: section θ₁ = 0 (dopri5), p1 β"
        );
    }

    #[test]
    fn names_become_symbols() {
        for (name, symbol) in [
            ("theta1", "θ₁"),
            ("omega2", "ω₂"),
            ("lambda1", "λ₁"),
            ("lambda12", "λ₁₂"),
            ("p1", "p₁"),
            ("theta", "θ"),
            ("x", "x"),
            ("drive_amplitude", "A"),
            ("drive_frequency", "Ω"),
            ("q", "q"),
            ("m1", "m₁"),
        ] {
            assert_eq!(pretty(name), symbol, "{name}");
        }
        assert_eq!(pretty("some_name"), "some_name");
    }

    #[test]
    fn units_print_with_superscripts_and_no_dimensionless_one() {
        assert_eq!(unit("kg m^2/s"), "kg m²/s");
        assert_eq!(unit("m/s^2"), "m/s²");
        assert_eq!(unit("1"), "");
        assert_eq!(axis_label("theta1", "rad"), "θ₁ (rad)");
        assert_eq!(axis_label("omega", "1"), "ω (dimensionless)");
        assert_eq!(axis_label("t", ""), "t (dimensionless)");
        assert_eq!(axis_label("t", "s"), "t (s)");
        assert_eq!(axis_label("drive_amplitude", "1"), "drive amplitude A (dimensionless)");
        assert_eq!(axis_label("some_name", "m"), "some_name (m)");
        assert_eq!(with_unit(0.01, "s"), "0.01 s");
        assert_eq!(with_unit(0.01, ""), "0.01");
        assert_eq!(with_unit(3, "1"), "3");
        assert_eq!(
            system_axis_label("driven-pendulum", "drive_amplitude", "1"),
            "drive amplitude g (dimensionless)"
        );
        assert_eq!(system_axis_label("double", "drive_amplitude", "N m"), "drive amplitude A (N m)");
        assert_eq!(system_axis_label("oscillator", "drive_amplitude", "N"), "drive amplitude F (N)");
        assert_eq!(system_axis_label("double", "theta1", "rad"), "θ₁ (rad)");
    }
}
