//! The library's one error type, and the two helpers its messages use: [`suggestions`] for
//! names that are close to a misspelt one, and [`Short`] for floats written for people.
//!
//! # Messages
//!
//! Messages help the user: name lookups in the library (`system::find`, `integrator::find`,
//! `find_preset`, `SystemInfo::quantity`, `EventSpec::parse`) carry the closest valid names
//! (`error::suggestions`, Damerau–Levenshtein with strsim), floats in messages are printed to at
//! most 10 significant digits (`error::Short`: `t = 9.2 s`, not 9.200000000000001), and `config.rs`
//! warns when a bare angle exceeds a full turn (`theta1=120` is radians; did you mean `120deg`?).

use std::fmt;

/// Everything that can go wrong in pendula, with the values that explain it.
///
/// Invalid input is reported before any work is done; numerical failures carry the
/// simulated time `t` (s) at which they happened.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No system of this name is in [`crate::model::CATALOGUE`].
    #[error("unknown system `{name}`{}; valid systems: {valid}", did_you_mean(.suggestions))]
    UnknownSystem {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
        /// The valid names closest to `name` (see [`suggestions`]); empty when none is close.
        suggestions: Vec<String>,
    },
    /// No method of this name is in [`crate::integrator::METHODS`].
    #[error("unknown method `{name}`{}; valid methods: {valid}", did_you_mean(.suggestions))]
    UnknownMethod {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
        /// The valid names closest to `name` (see [`suggestions`]); empty when none is close.
        suggestions: Vec<String>,
    },
    /// No preset of this name is in [`crate::system::driven::PRESETS`].
    #[error("unknown preset `{name}`{}; valid presets: {valid}", did_you_mean(.suggestions))]
    UnknownPreset {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
        /// The valid names closest to `name` (see [`suggestions`]); empty when none is close.
        suggestions: Vec<String>,
    },
    /// The system has no parameter or state variable of this name.
    #[error("unknown name `{name}` for system `{system}`{}; valid names: {valid}", did_you_mean(.suggestions))]
    UnknownName {
        /// The system.
        system: &'static str,
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
        /// The valid names closest to `name` (see [`suggestions`]); empty when none is close.
        suggestions: Vec<String>,
    },
    /// A value is outside the range its quantity allows.
    #[error("invalid value {} for `{name}`: {allowed}", Short(*.value))]
    InvalidValue {
        /// The parameter, variable or option.
        name: String,
        /// The offending value.
        value: f64,
        /// What is allowed, in words.
        allowed: &'static str,
    },
    /// The method needs structure the system does not have.
    #[error("{method} needs {needs}; {reason}; try {suggestion}")]
    UnmetRequirement {
        /// The method's name.
        method: &'static str,
        /// What the method needs, in words.
        needs: &'static str,
        /// Why the system lacks it, in words.
        reason: String,
        /// Methods that do apply.
        suggestion: String,
    },
    /// The state stopped being finite: the method is unstable at this step size, or the
    /// motion is singular.
    #[error("the state became non-finite at t = {} s (try a smaller step)", Short(*.t))]
    NonFinite {
        /// Time of the first non-finite state, s.
        t: f64,
    },
    /// A member of an ensemble (a sweep's cell, a fractal's pixel) stopped being finite.
    #[error("member {member}: the state became non-finite at t = {} s (try a smaller step)", Short(*.t))]
    NonFiniteMember {
        /// Index of the member.
        member: usize,
        /// Time of the first non-finite state, s.
        t: f64,
    },
    /// One run of many, named by what sets it apart (`drive_amplitude = 1.2`), stopped being
    /// finite.
    #[error("{place}: the state became non-finite at t = {} s (try a smaller step)", Short(*.t))]
    NonFiniteIn {
        /// Which run, in words.
        place: String,
        /// Time of the first non-finite state, s.
        t: f64,
    },
    /// The step-size controller asked for a step below the minimum.
    #[error(
        "the step size fell to h = {} s at t = {} s, below the minimum (loosen the tolerances or lower the smallest step allowed)",
        Short(*.h),
        Short(*.t)
    )]
    StepSizeTooSmall {
        /// Time, s.
        t: f64,
        /// The step size proposed, s.
        h: f64,
    },
    /// The iteration that solves an implicit step did not converge (Gauss–Legendre: neither
    /// Newton nor, after it, fixed-point iteration).
    #[error(
        "the implicit step at t = {} s did not converge (Newton where a Jacobian exists, then {iterations} fixed-point iterations; try a smaller step)",
        Short(*.t)
    )]
    NewtonDidNotConverge {
        /// Time at the start of the failing step, s.
        t: f64,
        /// Iterations performed.
        iterations: usize,
    },
    /// The run was interrupted (its cancel flag set by another thread, for a Ctrl-C).
    #[error("the run was interrupted")]
    Interrupted,
    /// A saved run state ([`crate::checkpoint`]) does not fit what restores it: a different
    /// method, system or dimension, or words missing or left over.
    #[error("the saved state of {part} does not fit: {reason}")]
    BadCheckpoint {
        /// What was being restored (the run, a stepper, an observer).
        part: &'static str,
        /// What does not fit, in words.
        reason: String,
    },
    /// An observer could not take a state of the run (its output failed) and ended the run
    /// ([`crate::observe::Stop::Failed`]): its message, and its error as the source.
    #[error(transparent)]
    Observer(ObserverFailure),
    /// No study of this name is in [`crate::study::STUDIES`].
    #[error("unknown study `{name}`{}; valid studies: {valid}", did_you_mean(.suggestions))]
    UnknownStudy {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
        /// The valid names closest to `name`; empty when none is close.
        suggestions: Vec<String>,
    },
    /// The study takes no parameter of this name.
    #[error("unknown parameter `{name}` for study `{study}`{}; valid parameters: {valid}", did_you_mean(.suggestions))]
    UnknownInput {
        /// The study.
        study: &'static str,
        /// The name given.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
        /// The valid names closest to `name`; empty when none is close.
        suggestions: Vec<String>,
    },
    /// A value of the wrong kind (a name where a number belongs, a fraction for a count).
    #[error("invalid value `{value}` for `{name}`: {allowed}")]
    InvalidInput {
        /// The parameter.
        name: String,
        /// The offending value, as given (clipped).
        value: String,
        /// What is allowed, in words.
        allowed: String,
    },
    /// A run would cost more than its budget ([`crate::study::Budget`]) allows.
    #[error("{what} would {} {} {}, over the limit of {}", cost.verb(), Short(*.amount), cost.unit(), Short(*.limit))]
    TooLarge {
        /// What would run, in words.
        what: String,
        /// What is counted.
        cost: Cost,
        /// How much of it.
        amount: f64,
        /// The limit.
        limit: f64,
    },
    /// A value refused with a reason that depends on it (a step above a method's limit, in
    /// words of the parameter the user gave).
    #[error("invalid value {} for `{name}`: {why}", Short(*.value))]
    OutOfRange {
        /// The parameter.
        name: String,
        /// The offending value.
        value: f64,
        /// Why it is refused and what is allowed, in words.
        why: String,
    },
    /// An error of one part of a larger computation (the reference run of an accuracy
    /// study), with that part named; its kind is its source's.
    #[error("{context}: {inner}")]
    In {
        /// The part, in words.
        context: String,
        /// What went wrong there (not a `source`: the message already carries it).
        inner: Box<Error>,
    },
}

/// What a [`crate::study::Budget`] counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cost {
    /// Integration steps of one system.
    Steps,
    /// Values in a report's tables.
    Values,
    /// Steps of one system on the ensemble engine's SIMD lanes.
    LaneSteps,
}

impl Cost {
    /// The verb of a refusal: "would take 2e12 steps", "would hold 4e9 values".
    pub fn verb(self) -> &'static str {
        match self {
            Cost::Steps | Cost::LaneSteps => "take",
            Cost::Values => "hold",
        }
    }

    /// What is counted, plural.
    pub fn unit(self) -> &'static str {
        match self {
            Cost::Steps => "steps",
            Cost::Values => "table values",
            Cost::LaneSteps => "steps on SIMD lanes",
        }
    }
}

/// The error with which an observer ended a run ([`Error::Observer`]): shared, so that the
/// library error stays `Clone`; equal only to itself (its clones).
#[derive(Debug, Clone)]
pub struct ObserverFailure(std::sync::Arc<dyn std::error::Error + Send + Sync>);

impl ObserverFailure {
    /// The failure `err`.
    pub fn new(err: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        ObserverFailure(std::sync::Arc::from(err.into()))
    }

    /// The observer's own error.
    pub fn error(&self) -> &(dyn std::error::Error + Send + Sync + 'static) {
        &*self.0
    }
}

impl PartialEq for ObserverFailure {
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Its message is the observer's error's; its source is that error itself, so that a chain
/// of causes walked from the run's error reaches the observer's (and what it wraps).
impl fmt::Display for ObserverFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for ObserverFailure {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&*self.0)
    }
}

/// A library error about the step `h`, with the step named as studies call it: `dt`.
pub fn step_named_dt(e: Error) -> Error {
    match e {
        Error::InvalidValue { name, value, allowed } if name == "h" => {
            Error::InvalidValue { name: "dt".into(), value, allowed }
        }
        e => e,
    }
}

impl Error {
    /// Whether this is the failure of one run that a study reports beside its other runs —
    /// a step that blew up, did not converge, or was refused (Tao's maps above ω h = 1, a
    /// method the system cannot run) — rather than a reason to end the study.
    pub fn is_per_run(&self) -> bool {
        matches!(
            self,
            Error::NonFinite { .. }
                | Error::NewtonDidNotConverge { .. }
                | Error::InvalidValue { .. }
                | Error::OutOfRange { .. }
                | Error::UnmetRequirement { .. }
        )
    }

    /// Whether this is a numerical failure of a run (the CLI's exit 1), not a refusal of
    /// the input.
    pub fn is_numerical(&self) -> bool {
        if let Error::In { inner, .. } = self {
            return inner.is_numerical();
        }
        matches!(
            self,
            Error::NonFinite { .. }
                | Error::NonFiniteIn { .. }
                | Error::NewtonDidNotConverge { .. }
                | Error::StepSizeTooSmall { .. }
        )
    }

    /// [`Error::UnknownName`] for `name` among `valid`, with its suggestions.
    pub fn unknown_name<'a>(
        system: &'static str,
        name: &str,
        valid: impl IntoIterator<Item = &'a str>,
    ) -> Self {
        let valid: Vec<&str> = valid.into_iter().collect();
        Error::UnknownName {
            system,
            name: name.to_owned(),
            valid: valid.join(", "),
            suggestions: suggestions(name, valid.iter().copied()),
        }
    }
}

/// A number in a table: four decimals, or four significant digits in exponent form below
/// 1e-3 and from 1e5 ("-" for a non-finite one).
pub fn short(v: f64) -> String {
    if !v.is_finite() {
        "-".into()
    } else if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// The candidates closest to a misspelt `name`, best first (ties in the candidates' order), at
/// most three; empty when none is close.
///
/// Closeness is the Damerau–Levenshtein distance (an insertion, deletion, substitution or swap
/// of neighbours each count 1), case ignored: `pendulm` → `pendulum`, `rk5` → `rk4`, `thta` →
/// `theta`, `RK4` → `rk4`. A candidate is close when at most a third of its characters (at
/// least one) must change and it keeps at least one: replacing every character of `x` by `v`
/// is no spelling mistake. Only the candidates at the smallest distance are kept.
pub fn suggestions<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let name = name.to_lowercase();
    let mut best: Vec<(usize, &str)> = candidates
        .into_iter()
        .map(|c| (strsim::damerau_levenshtein(&name, &c.to_lowercase()), c))
        .filter(|&(d, c)| {
            let len = c.chars().count();
            d <= (len / 3).max(1) && d < len
        })
        .collect();
    let Some(min) = best.iter().map(|&(d, _)| d).min() else { return Vec::new() };
    best.retain(|&(d, _)| d == min);
    best.into_iter().take(3).map(|(_, c)| c.to_owned()).collect()
}

/// ` (did you mean `a`?)`, ` (did you mean `a` or `b`?)`, or nothing: the hint the
/// unknown-name errors print after the name, for messages that make their own.
pub fn did_you_mean(suggestions: &[String]) -> String {
    let quoted: Vec<String> = suggestions.iter().map(|s| format!("`{s}`")).collect();
    match quoted.split_last() {
        None => String::new(),
        Some((last, [])) => format!(" (did you mean {last}?)"),
        Some((last, rest)) => format!(" (did you mean {} or {last}?)", rest.join(", ")),
    }
}

/// What the user typed, quoted in a message: at most `max` characters, the rest elided with
/// `…`, so that a 300-digit number or a pasted paragraph cannot drown the message.
pub fn clip(text: &str, max: usize) -> String {
    match text.char_indices().nth(max.saturating_sub(1)) {
        Some((end, _)) if text.chars().count() > max => format!("{}…", &text[..end]),
        _ => text.to_owned(),
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

/// A count for people: whole numbers up to 10⁶ in full, larger ones as `1.2e14`.
pub fn approx(x: f64) -> String {
    if x.is_finite() && x.abs() < 1e6 { format!("{}", x.round()) } else { sci(x) }
}

/// A float for a message: at most 10 significant digits, in the shortest form that reads back
/// as the rounded value, so that 9.200000000000001 prints as `9.2` and 0.1 + 0.2 as `0.3`.
/// Magnitudes below 1e-4 or from 1e15 take an exponent (`1.5e-7`); non-finite values print as
/// Rust does (`NaN`, `inf`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Short(pub f64);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if !v.is_finite() || v == 0.0 {
            return write!(f, "{v}");
        }
        // Round to 10 significant digits, then let Rust print the shortest form of that.
        let rounded: f64 = format!("{v:.9e}").parse().map_err(|_| fmt::Error)?;
        if (1e-4..1e15).contains(&rounded.abs()) { write!(f, "{rounded}") } else { write!(f, "{rounded:e}") }
    }
}
