//! Studies as specs: what a user can ask for, written once for every front end.
//!
//! A study ([`Study`]) is data: its name, a sentence about it, its parameters ([`Param`]:
//! name, help, unit, default and domain, each declared once) and one `run` function that
//! validates [`Inputs`] against those parameters and returns a [`Report`] — the sentences of
//! its summary, the numbers a caption quotes, its tables and its plots, as plain values.
//! The registry [`STUDIES`] is the one list the CLI (one subcommand per entry, flags and
//! their `[default: …]` derived from the parameters), Python (`pendula.study(name, **kw)`
//! and one function per entry) and the lab (a form per entry) read; a new study is one file
//! here and its line in [`STUDIES`], and every front end offers it.
//!
//! The shape follows ripgrep's flag registry (`crates/core/flags/defs.rs`: each flag
//! declared once, everything else derived) and argmin's solvers (a problem, a state, a
//! result value; presentation elsewhere). Front ends map their spelling onto [`Inputs`]
//! (`--delta 1e-9`, `delta=1e-9`, `{"delta": 1e-9}`) and present the [`Report`]; parsing
//! the `120deg`/`pi` value syntax is a front end's (the format crate's) job, so inputs
//! arrive here as numbers and names.

pub mod accuracy;
pub mod bifurcation;
pub mod compare;
pub mod defaults;
pub mod divergence;
pub mod energy_budget;
pub mod lyapunov;
pub mod period;
pub mod poincare;
pub mod regimes;
pub mod round_trip;
pub mod stability;

use std::fmt;

use crate::Error;
use crate::error::{Short, suggestions};
use crate::integrator::{self, Method};
use crate::system::Values;

/// `x` to four significant digits, for sentences people read (tables and JSON keep every
/// digit): `0.1490`, `-25.15`, `1.469e-8`, `2.500e6`.
pub fn sig(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() {
        format!("{x}")
    } else if !(1e-3..1e5).contains(&a) {
        format!("{x:.3e}")
    } else {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    }
}

/// " s" for a unit, "" for none: a number and its unit in a sentence.
pub fn unit_suffix(unit: &str) -> String {
    if unit.is_empty() { String::new() } else { format!(" {unit}") }
}

/// The unit of a distance in `info`'s state space: the state's units, combined as plain
/// numbers when they differ (rad and rad/s for the pendulums).
pub fn state_units(info: &crate::system::SystemInfo) -> String {
    let mut units: Vec<&str> = Vec::new();
    for q in info.state {
        if !q.unit.is_empty() && q.unit != "1" && !units.contains(&q.unit) {
            units.push(q.unit);
        }
    }
    match units.as_slice() {
        [] => String::new(),
        [one] => (*one).to_owned(),
        many => format!("{} combined", many.join(" and ")),
    }
}

/// The steps of a run from 0 to `t_end` at step `dt`, with the run loop's checks; an error
/// about its step names the parameter `dt` (the run loop calls it `h`).
///
/// # Errors
/// Those of [`crate::RunSpec::schedule`].
pub fn schedule(dt: f64, t_end: f64) -> Result<crate::simulate::Schedule, Error> {
    let spec = crate::RunSpec { t0: 0.0, h: dt, end: crate::End::Time(t_end) };
    spec.schedule().map_err(|e| match e {
        // Too many steps is the step and the end together: both are named.
        Error::InvalidValue { name, value, allowed } if name == "h" && allowed.contains("10^13") => {
            Error::InvalidInput {
                name: "dt".into(),
                value: Short(value).to_string(),
                allowed: format!("{allowed} to `t_end` {}", Short(t_end)),
            }
        }
        e => step_named_dt(e),
    })
}

pub use crate::error::step_named_dt;

/// A lower estimate of an adaptive run's steps per small-oscillation period
/// (`Model::time_scale`): DOP853 takes about 40 at tolerance 1e-6 on the chaotic double
/// pendulum and 100 at 1e-10, DOPRI5 300 at 1e-10. A lower estimate refuses only runs
/// that are surely too large.
pub const ADAPTIVE_STEPS_PER_PERIOD: f64 = 20.0;

/// A lower estimate of an adaptive run's steps over `span` on a model of small-oscillation
/// period `period`, no fewer than `span / h_max`.
pub fn adaptive_steps(span: f64, period: f64, h_max: f64) -> f64 {
    // A period of 0 (a start whose energy overflows) is unboundedly many steps.
    let by_period = if period > 0.0 { span / period * ADAPTIVE_STEPS_PER_PERIOD } else { f64::INFINITY };
    by_period.max(span / h_max).max(1.0)
}

/// The period of the motion from `y0` on `model`, s, for estimates of adaptive steps: the
/// model's small-oscillation period, shortened for a start with more energy than the
/// system's scale at rest — the motion is then faster by about the square root of the
/// ratio (a pendulum spun up to K joules turns at a rate ∝ √K).
pub fn motion_period(model: &dyn crate::model::DynModel, y0: &[f64]) -> f64 {
    let rest = vec![0.0; y0.len()];
    let ratio = model.energy_scale(&rest) / model.energy_scale(y0);
    // NaN: a start whose energy overflows, whose motion has no period to speak of.
    model.time_scale() * if ratio.is_nan() { 0.0 } else { ratio.min(1.0).sqrt() }
}

/// Every study, in the order front ends list them.
pub const STUDIES: &[&Study] = &[
    &compare::STUDY,
    &accuracy::CONVERGENCE,
    &accuracy::WORK_PRECISION,
    &stability::STUDY,
    &period::STUDY,
    &regimes::STUDY,
    &divergence::STUDY,
    &lyapunov::STUDY,
    &poincare::STUDY,
    &bifurcation::STUDY,
    &energy_budget::STUDY,
    &round_trip::STUDY,
];

/// The study named `name`.
///
/// # Errors
/// [`Error::UnknownStudy`] with the valid names and the closest ones.
pub fn find(name: &str) -> Result<&'static Study, Error> {
    STUDIES.iter().copied().find(|s| s.name == name).ok_or_else(|| Error::UnknownStudy {
        name: name.to_owned(),
        valid: STUDIES.iter().map(|s| s.name).collect::<Vec<_>>().join(", "),
        suggestions: suggestions(name, STUDIES.iter().map(|s| s.name)),
    })
}

/// One study: what it is called, what it does, what it takes, and how it runs.
#[derive(Debug)]
pub struct Study {
    /// Its name, as a command and a key (`energy-budget`); Python spells it with `_`.
    pub name: &'static str,
    /// One sentence: what it shows.
    pub about: &'static str,
    /// Its parameters, in the order they are documented.
    pub params: &'static [Param],
    /// The stems of the tables (`.csv`) and plots (`.png`, `.svg`) its report holds, for
    /// front ends that list what a command writes before running it (a test checks them
    /// against the report on the defaults).
    pub files: &'static [&'static str],
    /// Validates `inputs` against [`Study::params`] (nothing is computed before every input
    /// is checked) and runs the study within `budget`.
    pub run: fn(&Inputs, &Budget) -> Result<Report, Error>,
}

impl Study {
    /// The parameter named `name`.
    pub fn param(&self, name: &str) -> Option<&'static Param> {
        self.params.iter().find(|p| p.name == name)
    }
}

/// One parameter of a study.
#[derive(Debug)]
pub struct Param {
    /// Its name: a flag `--name` (with `-` for `_`), a keyword `name`, a JSON field `name`.
    pub name: &'static str,
    /// What it sets, in a phrase (without its default, which front ends append).
    pub help: &'static str,
    /// What kind of value it takes, with its default and domain.
    pub kind: Kind,
}

impl Param {
    /// The system run, `default` with the settings `preset` over its defaults.
    pub const fn system(default: &'static str, preset: &'static [(&'static str, f64)]) -> Param {
        Param {
            name: "system",
            help: "The system to run",
            kind: Kind::System { default, preset, fixed: false, own_start: None },
        }
    }

    /// The system run, `default` unless named, whose parameters the user may set but not its
    /// start, which the study chooses (`why` says how).
    pub const fn system_parameters(default: &'static str, why: &'static str) -> Param {
        Param {
            name: "system",
            help: "The system to run",
            kind: Kind::System { default, preset: &[], fixed: false, own_start: Some(why) },
        }
    }

    /// The one system a study runs (period: the simple pendulum); its parameters are still
    /// the user's to set.
    pub const fn fixed_system(default: &'static str) -> Param {
        Param {
            name: "system",
            help: "The system it runs",
            kind: Kind::System { default, preset: &[], fixed: true, own_start: None },
        }
    }

    /// A preset of the driven systems' settings (`--preset baker-gollub-chaotic`), which
    /// also picks the system.
    pub const fn preset() -> Param {
        Param {
            name: "preset",
            help: "A named set of settings (`pendula list presets`); it also picks the system, and `set` applies over it",
            kind: Kind::Preset,
        }
    }

    /// The integration method.
    pub const fn method(default: &'static str) -> Param {
        Param { name: "method", help: "The integration method", kind: Kind::Method { default } }
    }

    /// The methods compared, comma-separated; every method that applies to the system when
    /// none is named.
    pub const fn methods() -> Param {
        Param { name: "methods", help: "The methods, comma-separated", kind: Kind::Methods }
    }

    /// A time `name` (s, or the system's time unit), > 0.
    pub const fn time(name: &'static str, help: &'static str, default: f64) -> Param {
        Param { name, help, kind: Kind::Real { default, unit: Unit::Time, domain: Domain::Positive } }
    }
}

/// The inputs of one run, as a report states them: `system`, `method`, `dt`, `t_end`.
pub fn run_inputs(values: &Values, method: &Method, dt: f64, t_end: f64) -> Vec<(&'static str, Input)> {
    vec![
        ("system", Input::Name(values.info().name.into())),
        ("method", Input::Name(method.name.into())),
        ("dt", Input::Number(dt)),
        ("t_end", Input::Number(t_end)),
    ]
}

/// What a study module needs of this one, in one import.
pub mod prelude {
    pub use super::{
        Args, Axis, Bar, Budget, Column, Domain, Input, Inputs, Kind, Line, Number, Param, Plot, Report,
        Study, Style, Table, Unit, run_inputs, sig, unit_suffix,
    };
}

/// What a parameter takes.
#[derive(Debug, Clone, Copy)]
pub enum Kind {
    /// A catalogued system's name ([`crate::model::find`]); the study's other inputs
    /// `set` its parameters and initial state.
    System {
        /// The system run when none is named.
        default: &'static str,
        /// Settings applied before the user's own when the default system runs (a damping
        /// that makes a budget worth showing, say); shown in the help.
        preset: &'static [(&'static str, f64)],
        /// Whether the study runs only its default system (front ends then offer no choice).
        fixed: bool,
        /// Why the user may not set the initial state, when the study starts its runs itself
        /// (`None`: the user may).
        own_start: Option<&'static str>,
    },
    /// A method of [`integrator::METHODS`].
    Method {
        /// The method run when none is named.
        default: &'static str,
    },
    /// Methods of [`integrator::METHODS`], comma-separated, each applying to the system and
    /// named once; every method that applies ([`crate::model::applicable`]) when none is named.
    Methods,
    /// A state variable of the system (`theta1`), by name; when none is named the first, or
    /// the first velocity (the state's second half) when `velocity`.
    Variable {
        /// Whether the default is the first velocity.
        velocity: bool,
    },
    /// A real number in a unit, within a domain.
    Real {
        /// The value when none is given.
        default: f64,
        /// Its unit (`s`, `1/s`; empty for a pure number). A time takes the system's time
        /// unit instead when [`Unit::Time`] is used.
        unit: Unit,
        /// The values allowed.
        domain: Domain,
    },
    /// A switch, off unless given (`--spectrum`; `spectrum=True`).
    Flag,
    /// A named set of a system's settings ([`crate::system::driven::PRESETS`]): it picks the
    /// system when none is named, and its settings come before the user's.
    Preset,
    /// Real numbers, a list, that may be left out (then the study does something else, which
    /// `none` says): the steps of a convergence study. Front ends take a list (`--dts
    /// 0.1,0.05`; `dts=[0.1, 0.05]`), or the same comma-separated as text.
    Reals {
        /// Their unit, as [`Kind::Real`]'s.
        unit: Unit,
        /// The values each may take.
        domain: Domain,
        /// What the study does without them, in a phrase (shown as their default).
        none: &'static str,
    },
    /// A real number that may be left out (then the study does something else, which
    /// `none` says: `adaptive steps at tol`).
    Optional {
        /// Its unit, as [`Kind::Real`]'s.
        unit: Unit,
        /// The values allowed when given.
        domain: Domain,
        /// What the study does without it, in a phrase (shown as its default).
        none: &'static str,
    },
    /// An angle of the system and a value of it, `NAME=VALUE` (rad): a Poincaré section.
    Section {
        /// The section when none is given.
        default: &'static str,
    },
    /// A parameter of the system swept over cells, `NAME=LO:HI:N` (N cell centres, as a
    /// sweep's axis).
    Axis {
        /// The axis when none is given, for one system (`None`: the user must give one).
        default: Option<(&'static str, &'static str)>,
    },
    /// The threads a parallel study runs on: all cores when not given (results do not
    /// depend on them).
    Threads,
    /// A whole number within bounds.
    Count {
        /// The value when none is given.
        default: u64,
        /// Smallest allowed.
        min: u64,
        /// Largest allowed.
        max: u64,
        /// What it counts, plural (`orbits`), for messages.
        of: &'static str,
    },
}

/// The unit of a real parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// A pure number.
    None,
    /// The system's time unit (s, or none for a dimensionless system).
    Time,
    /// A fixed unit.
    Fixed(&'static str),
}

/// The values a real parameter allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Domain {
    /// Finite and > 0.
    Positive,
    /// Finite and ≥ 0.
    NonNegative,
    /// Finite.
    Finite,
}

impl Domain {
    /// What is allowed, in words, for error messages.
    pub fn describe(self) -> &'static str {
        match self {
            Domain::Positive => "must be finite and > 0",
            Domain::NonNegative => "must be finite and >= 0",
            Domain::Finite => "must be finite",
        }
    }

    /// Whether `v` is allowed.
    pub fn contains(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Domain::Positive => v > 0.0,
                Domain::NonNegative => v >= 0.0,
                Domain::Finite => true,
            }
    }
}

impl Param {
    /// The default, as text for help and documentation (`rk4`, `0.001`, `double with
    /// damping=0.05`); front ends append it as `[default: …]` so that it is written once.
    pub fn default_text(&self) -> String {
        match self.kind {
            Kind::System { default, preset: [], .. } => default.to_owned(),
            Kind::System { default, preset, .. } => {
                let set: Vec<String> = preset.iter().map(|(n, v)| format!("{n}={}", Short(*v))).collect();
                format!("{default} with {}", set.join(", "))
            }
            Kind::Method { default } => default.to_owned(),
            Kind::Methods => "every method that applies".to_owned(),
            Kind::Variable { velocity: false } => "the first state variable".to_owned(),
            Kind::Variable { velocity: true } => "the first velocity".to_owned(),
            Kind::Real { default, .. } => Short(default).to_string(),
            Kind::Count { default, .. } => default.to_string(),
            Kind::Flag => "off".to_owned(),
            Kind::Optional { none, .. } | Kind::Reals { none, .. } => format!("none: {none}"),
            Kind::Section { default } => default.to_owned(),
            Kind::Axis { default: Some((system, text)) } => {
                format!("{text} for {system}; required otherwise")
            }
            Kind::Axis { default: None } => "none: required".to_owned(),
            Kind::Threads => "all cores".to_owned(),
            Kind::Preset => "none".to_owned(),
        }
    }

    /// What kind of value it takes, in one word, as front ends describe it to their users
    /// (Python's `studies()`, the lab's form): `system` (`fixed-system` for the one a study
    /// runs), `method`, `methods`, `variable`, `real`, `count`, `flag`, `preset`.
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            Kind::System { fixed: true, .. } => "fixed-system",
            Kind::System { .. } => "system",
            Kind::Method { .. } => "method",
            Kind::Methods => "methods",
            Kind::Variable { .. } => "variable",
            Kind::Real { .. } | Kind::Optional { .. } => "real",
            Kind::Reals { .. } => "reals",
            Kind::Section { .. } => "section",
            Kind::Axis { .. } => "axis",
            Kind::Threads => "count",
            Kind::Count { .. } => "count",
            Kind::Flag => "flag",
            Kind::Preset => "preset",
        }
    }

    /// The unit of a real parameter for `system`'s time unit (`""` for none).
    pub fn unit(&self, time_unit: &'static str) -> &'static str {
        match self.real_unit() {
            Some(Unit::Time) => time_unit,
            Some(Unit::Fixed(u)) => u,
            _ => "",
        }
    }

    /// The unit of a real parameter (given or optional); `None` for other kinds.
    pub fn real_unit(&self) -> Option<Unit> {
        match self.kind {
            Kind::Real { unit, .. } | Kind::Optional { unit, .. } | Kind::Reals { unit, .. } => Some(unit),
            _ => None,
        }
    }
}

/// One input value, as a front end read it.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// A number (a real or a count).
    Number(f64),
    /// A name (a system, a method).
    Name(String),
    /// A switch's state.
    Flag(bool),
    /// Numbers, a list.
    Numbers(Vec<f64>),
}

impl fmt::Display for Input {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Input::Number(v) => write!(f, "{}", Short(*v)),
            Input::Name(s) => f.write_str(s),
            Input::Flag(b) => write!(f, "{b}"),
            Input::Numbers(v) => {
                let items: Vec<String> = v.iter().map(|x| Short(*x).to_string()).collect();
                write!(f, "{}", items.join(","))
            }
        }
    }
}

/// What a user gave a study: values by parameter name, and settings of the system's
/// parameters and initial state (`--set m2=2`), applied in order after the study's preset.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Inputs {
    /// (parameter name, value), in the order given.
    pub values: Vec<(String, Input)>,
    /// (system quantity, value), in the order given.
    pub set: Vec<(String, f64)>,
}

impl Inputs {
    /// `self` with `name` set to the number `v`.
    pub fn number(mut self, name: &str, v: f64) -> Self {
        self.values.push((name.to_owned(), Input::Number(v)));
        self
    }

    /// `self` with `name` set to the numbers `v`.
    pub fn numbers(mut self, name: &str, v: &[f64]) -> Self {
        self.values.push((name.to_owned(), Input::Numbers(v.to_vec())));
        self
    }

    /// `self` with the switch `name` set to `on`.
    pub fn flag(mut self, name: &str, on: bool) -> Self {
        self.values.push((name.to_owned(), Input::Flag(on)));
        self
    }

    /// `self` with `name` set to the name `v`.
    pub fn name(mut self, name: &str, v: &str) -> Self {
        self.values.push((name.to_owned(), Input::Name(v.to_owned())));
        self
    }

    /// `self` with the system quantity `name` set to `v`.
    pub fn set(mut self, name: &str, v: f64) -> Self {
        self.set.push((name.to_owned(), v));
        self
    }
}

/// How much work a run may do: front ends that serve others (the lab) bound every request;
/// the CLI bounds a run unless `--allow-large`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// The most integration steps (of one system) a run may take; `None` for no limit.
    pub max_steps: Option<f64>,
    /// The most values a report's tables may hold (a long running estimate, say); `None`
    /// for no limit.
    pub max_values: Option<f64>,
    /// The most steps on the ensemble engine's SIMD lanes (each lane one system), which
    /// run many times faster than the scalar integrators; `None` for no limit.
    pub max_lane_steps: Option<f64>,
}

pub use crate::error::Cost;

impl Budget {
    /// No limit.
    pub const UNLIMITED: Budget = Budget { max_steps: None, max_values: None, max_lane_steps: None };

    /// Refuses a run of `steps` steps (`what` says what they are) over the limit.
    ///
    /// # Errors
    /// [`Error::TooLarge`] naming the cost and the limit.
    pub fn afford(&self, steps: f64, what: impl Into<String>) -> Result<(), Error> {
        Self::refuse(self.max_steps, Cost::Steps, steps, what)
    }

    /// Refuses a run of `steps` steps on the ensemble engine's lanes over the limit.
    ///
    /// # Errors
    /// [`Error::TooLarge`] naming the cost and the limit.
    pub fn afford_lanes(&self, steps: f64, what: impl Into<String>) -> Result<(), Error> {
        Self::refuse(self.max_lane_steps, Cost::LaneSteps, steps, what)
    }

    /// Refuses a report whose tables would hold `values` values over the limit.
    ///
    /// # Errors
    /// [`Error::TooLarge`] naming the cost and the limit.
    pub fn afford_values(&self, values: f64, what: impl Into<String>) -> Result<(), Error> {
        Self::refuse(self.max_values, Cost::Values, values, what)
    }

    fn refuse(limit: Option<f64>, cost: Cost, amount: f64, what: impl Into<String>) -> Result<(), Error> {
        match limit {
            // A NaN cost (from a NaN input that slipped through) is refused too.
            Some(limit) if amount.is_nan() || amount > limit => {
                Err(Error::TooLarge { what: what.into(), cost, amount, limit })
            }
            _ => Ok(()),
        }
    }
}

/// Inputs checked against a study's parameters: each value by name, its default when not
/// given, every name known.
#[derive(Debug)]
pub struct Args<'a> {
    study: &'static Study,
    inputs: &'a Inputs,
}

impl<'a> Args<'a> {
    /// Checks that every input names a parameter of `study` (else the valid names and the
    /// closest ones) and that no parameter is given twice.
    ///
    /// # Errors
    /// [`Error::UnknownInput`] for a name `study` does not take.
    pub fn new(study: &'static Study, inputs: &'a Inputs) -> Result<Self, Error> {
        for (name, _) in &inputs.values {
            if study.param(name).is_none() {
                return Err(Error::UnknownInput {
                    study: study.name,
                    name: name.clone(),
                    valid: study.params.iter().map(|p| p.name).collect::<Vec<_>>().join(", "),
                    suggestions: suggestions(name, study.params.iter().map(|p| p.name)),
                });
            }
        }
        Ok(Args { study, inputs })
    }

    fn given(&self, name: &str) -> Option<&'a Input> {
        // The last one given wins, as for repeated flags.
        self.inputs.values.iter().rev().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    /// Whether the user gave `name` (a study whose parameters act together, as a ladder's
    /// bounds and count, asks).
    pub fn is_given(&self, name: &str) -> bool {
        self.given(name).is_some()
    }

    /// The list parameter `name`: `None` when not given, else at least one value, each
    /// within its domain. Text is read as comma-separated numbers.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an empty list or text that is not numbers;
    /// [`Error::InvalidValue`] naming the first value outside the domain.
    ///
    /// # Panics
    /// When `name` is not a list parameter of the study.
    pub fn reals(&self, name: &str) -> Result<Option<Vec<f64>>, Error> {
        let Kind::Reals { domain, .. } = self.param(name).kind else {
            panic!("{name} is not a list parameter of {}", self.study.name)
        };
        let values = match self.given(name) {
            None => return Ok(None),
            Some(Input::Numbers(v)) => v.clone(),
            Some(Input::Number(v)) => vec![*v],
            Some(Input::Name(text)) => {
                text.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<Vec<f64>, _>>().map_err(
                    |_| Error::InvalidInput {
                        name: name.to_owned(),
                        value: crate::error::clip(text, 60),
                        allowed: "numbers, comma-separated".to_owned(),
                    },
                )?
            }
            Some(Input::Flag(b)) => {
                return Err(Error::InvalidInput {
                    name: name.to_owned(),
                    value: b.to_string(),
                    allowed: "numbers, not a bool".to_owned(),
                });
            }
        };
        if values.is_empty() {
            return Err(Error::InvalidInput {
                name: name.to_owned(),
                value: "[]".to_owned(),
                allowed: "at least one value".to_owned(),
            });
        }
        if let Some(v) = values.iter().find(|v| !domain.contains(**v)) {
            return Err(Error::InvalidValue { name: name.to_owned(), value: *v, allowed: domain.describe() });
        }
        Ok(Some(values))
    }

    fn param(&self, name: &str) -> &'static Param {
        self.study.param(name).unwrap_or_else(|| panic!("{} has no parameter {name}", self.study.name))
    }

    /// The real parameter `name`, checked against its domain.
    ///
    /// # Errors
    /// [`Error::InvalidValue`] outside the domain; [`Error::InvalidInput`] for a name where a
    /// number belongs.
    ///
    /// # Panics
    /// When `name` is not a real parameter of the study: a programming error in its file.
    pub fn real(&self, name: &str) -> Result<f64, Error> {
        let Kind::Real { default, domain, .. } = self.param(name).kind else {
            panic!("{name} is not a real parameter of {}", self.study.name)
        };
        let v = self.number(name)?.unwrap_or(default);
        if !domain.contains(v) {
            return Err(Error::InvalidValue { name: name.to_owned(), value: v, allowed: domain.describe() });
        }
        Ok(v)
    }

    /// The count parameter `name`, checked against its bounds.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a value that is not a whole number within the bounds.
    ///
    /// # Panics
    /// When `name` is not a count parameter of the study.
    pub fn count(&self, name: &str) -> Result<u64, Error> {
        let Kind::Count { default, min, max, of } = self.param(name).kind else {
            panic!("{name} is not a count parameter of {}", self.study.name)
        };
        let Some(v) = self.number(name)? else { return Ok(default) };
        if v.fract() != 0.0 || !(v >= min as f64 && v <= max as f64) {
            return Err(Error::InvalidInput {
                name: name.to_owned(),
                value: Short(v).to_string(),
                allowed: format!(
                    "expected a whole number of {of}, >= {} and <= {}",
                    crate::error::count(min),
                    crate::error::count(max)
                ),
            });
        }
        Ok(v as u64)
    }

    /// The optional real parameter `name`: `None` when not given, else checked against its
    /// domain.
    ///
    /// # Errors
    /// As [`Args::real`].
    ///
    /// # Panics
    /// When `name` is not an optional real parameter of the study.
    pub fn optional(&self, name: &str) -> Result<Option<f64>, Error> {
        let Kind::Optional { domain, .. } = self.param(name).kind else {
            panic!("{name} is not an optional parameter of {}", self.study.name)
        };
        match self.number(name)? {
            Some(v) if !domain.contains(v) => {
                Err(Error::InvalidValue { name: name.to_owned(), value: v, allowed: domain.describe() })
            }
            v => Ok(v),
        }
    }

    /// The axis parameter `name` on `info`: one of its parameters over `N` cells of
    /// `[LO, HI]`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for none given where the study has no default for `info`, text
    /// that is not `NAME=LO:HI:N`, a name that is not a parameter of the system, bounds not
    /// finite with LO < HI, or N not a whole number from 1 to 10^9.
    ///
    /// # Panics
    /// When `name` is not an axis parameter of the study.
    pub fn axis(&self, name: &str, info: &crate::system::SystemInfo) -> Result<crate::sweep::Axis, Error> {
        let Kind::Axis { default } = self.param(name).kind else {
            panic!("{name} is not an axis parameter of {}", self.study.name)
        };
        let given = self.text(name)?;
        let Some(text) = given.or(default.filter(|(s, _)| *s == info.name).map(|(_, t)| t)) else {
            return Err(Error::InvalidInput {
                name: name.to_owned(),
                value: "none".into(),
                allowed: format!("give `{name}` NAME=LO:HI:N for {}: the parameter to sweep", info.name),
            });
        };
        let invalid = |allowed: String| Error::InvalidInput {
            name: name.to_owned(),
            value: crate::error::clip(text, 60),
            allowed,
        };
        let parsed = text.split_once('=').and_then(|(q, range)| {
            let parts: Vec<&str> = range.split(':').map(str::trim).collect();
            let [lo, hi, n] = parts[..] else { return None };
            Some((q.trim(), lo.parse::<f64>().ok()?, hi.parse::<f64>().ok()?, n.parse::<usize>().ok()?))
        });
        let Some((q, lo, hi, n)) = parsed else {
            return Err(invalid("expected NAME=LO:HI:N, e.g. drive_amplitude=1.0:1.5:800".to_owned()));
        };
        let parameters = info.parameters.iter().map(|p| p.name);
        if !info.parameters.iter().any(|p| p.name == q) {
            return Err(invalid(format!(
                "`{}` is not a parameter of {}{}; valid: {}",
                crate::error::clip(q, 40),
                info.name,
                crate::error::did_you_mean(&suggestions(q, parameters.clone())),
                parameters.collect::<Vec<_>>().join(", ")
            )));
        }
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(invalid(format!("need finite LO < HI (got {} and {})", Short(lo), Short(hi))));
        }
        if !(1..=1_000_000_000).contains(&n) {
            return Err(invalid(format!("the number of cells must be from 1 to 10^9 (got {n})")));
        }
        Ok(crate::sweep::Axis { name: q.to_owned(), lo, hi, n })
    }

    /// The threads parameter `name`: `None` (all cores) when not given.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a value that is not a whole number from 1 to 1024.
    ///
    /// # Panics
    /// When `name` is not a threads parameter of the study.
    pub fn threads(&self, name: &str) -> Result<Option<usize>, Error> {
        let Kind::Threads = self.param(name).kind else {
            panic!("{name} is not a threads parameter of {}", self.study.name)
        };
        match self.number(name)? {
            None => Ok(None),
            Some(v) if v.fract() == 0.0 && (1.0..=1024.0).contains(&v) => Ok(Some(v as usize)),
            Some(v) => Err(Error::InvalidInput {
                name: name.to_owned(),
                value: Short(v).to_string(),
                allowed: "expected a whole number of threads, >= 1 and <= 1024".to_owned(),
            }),
        }
    }

    /// The section parameter `name` on `info`: the index of the angle it names and its
    /// value (rad).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for text that is not `NAME=VALUE`, a name that is not an
    /// angle of the system (with the valid ones and the closest), a value that is not a
    /// finite number.
    ///
    /// # Panics
    /// When `name` is not a section parameter of the study.
    pub fn section(&self, name: &str, info: &crate::system::SystemInfo) -> Result<(usize, f64), Error> {
        let Kind::Section { default } = self.param(name).kind else {
            panic!("{name} is not a section parameter of {}", self.study.name)
        };
        let text = self.text(name)?.unwrap_or(default);
        let invalid = |allowed: String| Error::InvalidInput {
            name: name.to_owned(),
            value: crate::error::clip(text, 40),
            allowed,
        };
        let Some((angle, value)) = text.split_once('=') else {
            return Err(invalid("expected NAME=VALUE, e.g. theta1=0".to_owned()));
        };
        let angle = angle.trim();
        let angles: Vec<&str> = info.state.iter().filter(|q| q.is_angle()).map(|q| q.name).collect();
        let Some(index) = info.state.iter().position(|q| q.name == angle && q.is_angle()) else {
            return Err(invalid(format!(
                "`{}` is not an angle of {}{}; valid: {}",
                crate::error::clip(angle, 40),
                info.name,
                crate::error::did_you_mean(&suggestions(angle, angles.iter().copied())),
                angles.join(", ")
            )));
        };
        match value.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok((index, v)),
            _ => Err(invalid(format!(
                "the value `{}` is not a finite number (rad)",
                crate::error::clip(value, 40)
            ))),
        }
    }

    fn number(&self, name: &str) -> Result<Option<f64>, Error> {
        match self.given(name) {
            None => Ok(None),
            Some(Input::Number(v)) => Ok(Some(*v)),
            Some(Input::Name(text)) => Err(Error::InvalidInput {
                name: name.to_owned(),
                value: crate::error::clip(text, 40),
                allowed: "a number".to_owned(),
            }),
            Some(Input::Flag(b)) => Err(Error::InvalidInput {
                name: name.to_owned(),
                value: b.to_string(),
                allowed: "a number, not a bool".to_owned(),
            }),
            Some(list @ Input::Numbers(_)) => Err(Error::InvalidInput {
                name: name.to_owned(),
                value: crate::error::clip(&list.to_string(), 40),
                allowed: "one number, not a list".to_owned(),
            }),
        }
    }

    fn text(&self, name: &str) -> Result<Option<&'a str>, Error> {
        match self.given(name) {
            None => Ok(None),
            Some(Input::Name(s)) => Ok(Some(s)),
            Some(other) => Err(Error::InvalidInput {
                name: name.to_owned(),
                value: other.to_string(),
                allowed: "a name".to_owned(),
            }),
        }
    }

    /// The preset parameter `name`: the preset's name, `None` when not given (checked by
    /// [`Args::system`], which applies it).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a number where the name belongs.
    ///
    /// # Panics
    /// When `name` is not a preset parameter of the study.
    pub fn preset(&self, name: &str) -> Result<Option<&'a str>, Error> {
        let Kind::Preset = self.param(name).kind else {
            panic!("{name} is not a preset parameter of {}", self.study.name)
        };
        self.text(name)
    }

    /// The switch `name`: on when given on.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a value that is not a switch's.
    ///
    /// # Panics
    /// When `name` is not a flag parameter of the study.
    pub fn flag(&self, name: &str) -> Result<bool, Error> {
        let Kind::Flag = self.param(name).kind else {
            panic!("{name} is not a flag parameter of {}", self.study.name)
        };
        match self.given(name) {
            None => Ok(false),
            Some(Input::Flag(on)) => Ok(*on),
            Some(other) => Err(Error::InvalidInput {
                name: name.to_owned(),
                value: other.to_string(),
                allowed: "on or off (a switch)".to_owned(),
            }),
        }
    }

    /// The method parameter `name`.
    ///
    /// # Errors
    /// [`Error::UnknownMethod`] for a name not in [`integrator::METHODS`].
    ///
    /// # Panics
    /// When `name` is not a method parameter of the study.
    pub fn method(&self, name: &str) -> Result<&'static Method, Error> {
        let Kind::Method { default } = self.param(name).kind else {
            panic!("{name} is not a method parameter of {}", self.study.name)
        };
        integrator::find(self.text(name)?.unwrap_or(default))
    }

    /// The methods parameter `name` for `model`: those named, or every one that applies.
    ///
    /// # Errors
    /// Those of [`crate::model::named_methods`], with the value named `name`.
    ///
    /// # Panics
    /// When `name` is not a methods parameter of the study.
    pub fn methods(
        &self,
        name: &str,
        model: &dyn crate::model::DynModel,
    ) -> Result<Vec<&'static Method>, Error> {
        let Kind::Methods = self.param(name).kind else {
            panic!("{name} is not a methods parameter of {}", self.study.name)
        };
        match self.text(name)? {
            Some(text) => crate::model::named_methods(model, text.split(',')).map_err(|e| match e {
                Error::InvalidInput { allowed, .. } => Error::InvalidInput {
                    name: name.to_owned(),
                    value: crate::error::clip(text, 80),
                    allowed,
                },
                e => e,
            }),
            None => Ok(crate::model::applicable(model, integrator::METHODS, None)),
        }
    }

    /// The variable parameter `name`: the index of the state variable of `info` it names, or
    /// its default's.
    ///
    /// # Errors
    /// [`Error::UnknownName`] naming the valid variables.
    ///
    /// # Panics
    /// When `name` is not a variable parameter of the study.
    pub fn variable(&self, name: &str, info: &crate::system::SystemInfo) -> Result<usize, Error> {
        let Kind::Variable { velocity } = self.param(name).kind else {
            panic!("{name} is not a variable parameter of {}", self.study.name)
        };
        match self.text(name)? {
            None => Ok(if velocity { info.state.len() / 2 } else { 0 }),
            Some(v) => info.state.iter().position(|q| q.name == v).ok_or_else(|| {
                match Error::unknown_name(info.name, v, info.state.iter().map(|q| q.name)) {
                    // Which names it takes: the state variables.
                    Error::UnknownName { system, name, valid, suggestions } => Error::UnknownName {
                        system,
                        name,
                        valid: format!("{valid} (the state variables)"),
                        suggestions,
                    },
                    e => e,
                }
            }),
        }
    }

    /// One run's inputs, as the parameters `system`, `method`, `dt` and `t_end` give them.
    ///
    /// # Errors
    /// As [`Args::system`], [`Args::method`] and [`Args::real`].
    pub fn one_run(&self) -> Result<(Values, &'static Method, f64, f64), Error> {
        Ok((self.system("system")?, self.method("method")?, self.real("dt")?, self.real("t_end")?))
    }

    /// The system parameter `name` with the study's preset (for its default system) and the
    /// user's settings applied, validated, its initial energy finite.
    ///
    /// # Errors
    /// [`Error::UnknownSystem`], and those of [`crate::system::SystemInfo::values`] and
    /// [`Values::check_energy`].
    ///
    /// # Panics
    /// When `name` is not a system parameter of the study.
    pub fn system(&self, name: &str) -> Result<Values, Error> {
        let Kind::System { default, preset, fixed, own_start } = self.param(name).kind else {
            panic!("{name} is not a system parameter of {}", self.study.name)
        };
        let mut given = self.text(name)?;
        // A named preset (of a study that takes one) picks the system, and its settings
        // come first.
        let mut settings: Vec<(String, f64)> = Vec::new();
        let named = self.study.params.iter().find(|p| matches!(p.kind, Kind::Preset));
        if let Some(p) = named
            && let Some(preset_name) = self.preset(p.name)?
        {
            let chosen = crate::system::driven::find_preset(preset_name)?;
            if let Some(system) = given.filter(|g| *g != chosen.system) {
                return Err(Error::InvalidInput {
                    name: p.name.to_owned(),
                    value: preset_name.to_owned(),
                    allowed: format!("it is for the system {}, not {system}", chosen.system),
                });
            }
            given = Some(chosen.system);
            settings.extend(chosen.settings.iter().map(|(n, v)| ((*n).to_owned(), *v)));
        }
        if let Some(other) = given.filter(|g| fixed && g != &default) {
            return Err(Error::InvalidInput {
                name: name.to_owned(),
                value: crate::error::clip(other, 40),
                allowed: format!("{default} only: {} runs no other system", self.study.name),
            });
        }
        let info = crate::model::find(given.unwrap_or(default))?;
        if let Some(why) = own_start
            && let Some((q, v)) =
                self.inputs.set.iter().find(|(n, _)| info.state.iter().any(|q| q.name == *n))
        {
            return Err(Error::InvalidInput {
                name: "set".into(),
                value: format!("{q}={}", Short(*v)),
                allowed: format!("{why}; set parameters only"),
            });
        }
        if given.is_none_or(|g| g == default) && settings.is_empty() {
            settings.extend(preset.iter().map(|(n, v)| ((*n).to_owned(), *v)));
        }
        settings.extend(self.inputs.set.iter().cloned());
        let values = info.values(&settings)?;
        values.check_energy()?;
        Ok(values)
    }
}

/// What a study found, as values every front end presents in its own way: the CLI prints
/// the summary, writes the tables as CSV and the plots as PNG and SVG, and a JSON summary of
/// the inputs and numbers; Python returns it as arrays and a dict; the lab draws it.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The study's name.
    pub study: &'static str,
    /// Every parameter's value as the run used it (defaults filled in), in declaration
    /// order, for summaries that say what ran.
    pub inputs: Vec<(&'static str, Input)>,
    /// The summary, one sentence a line, each checked against [`Report::numbers`].
    pub summary: Vec<String>,
    /// The numbers a caption or a summary quotes, by key, with units.
    pub numbers: Vec<Number>,
    /// The words a caption quotes, by key (`reference`: what errors are measured against).
    pub texts: Vec<(&'static str, String)>,
    /// Its tables.
    pub tables: Vec<Table>,
    /// Its plots.
    pub plots: Vec<Plot>,
}

impl Report {
    /// The number with key `key`.
    pub fn number(&self, key: &str) -> Option<f64> {
        self.numbers.iter().find(|n| n.key == key).map(|n| n.value)
    }

    /// The table named `name`.
    pub fn table(&self, name: &str) -> Option<&Table> {
        self.tables.iter().find(|t| t.name == name)
    }
}

/// A number a report quotes.
#[derive(Debug, Clone, PartialEq)]
pub struct Number {
    /// Its key (`max_balance`), as JSON and Python name it.
    pub key: &'static str,
    /// Its value.
    pub value: f64,
    /// Its unit (`J`; empty for a pure number).
    pub unit: &'static str,
    /// What it is, in a phrase.
    pub about: &'static str,
}

/// A table of equally long columns.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Its name, a file stem (`energy-budget` → `energy-budget.csv`).
    pub name: &'static str,
    /// Whether it is short enough to show whole: front ends that print (the CLI, Python's
    /// `str`) print it under the summary, and the CLI's JSON summary carries its rows; a long
    /// series (a time series) only goes to its file.
    pub shown: bool,
    /// Its columns, in order.
    pub columns: Vec<Column>,
}

impl Table {
    /// The number of rows.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, Column::len)
    }

    /// The column named `name`.
    pub fn column(&self, name: &str) -> Option<&Column> {
        self.columns.iter().find(|c| c.name == name)
    }
}

/// One column of a table.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Its name, a CSV header and a key (`balance`).
    pub name: &'static str,
    /// Its unit (`J`, `s`; empty for a pure number or text).
    pub unit: &'static str,
    /// Its values.
    pub values: Cells,
    /// Whether its numbers are whole (an index, a count): written as integers (`3`, not
    /// `3.0`).
    pub whole: bool,
    /// The decimals a printed table shows (a fitted order to 3); files keep every digit.
    pub decimals: Option<usize>,
}

impl Column {
    /// A column of numbers (NaN for a missing value).
    pub fn numbers(name: &'static str, unit: &'static str, values: Vec<f64>) -> Column {
        Column { name, unit, values: Cells::Numbers(values), whole: false, decimals: None }
    }

    /// A column of whole numbers (an orbit's index, a count of crossings), held as numbers;
    /// NaN for a missing one (written as an empty cell, `null`, or NaN in a float array).
    pub fn whole(name: &'static str, values: Vec<f64>) -> Column {
        debug_assert!(values.iter().all(|v| v.fract() == 0.0 || v.is_nan()));
        Column { name, unit: "", values: Cells::Numbers(values), whole: true, decimals: None }
    }

    /// A column of text (names, notes).
    pub fn text(name: &'static str, values: Vec<String>) -> Column {
        Column { name, unit: "", values: Cells::Text(values), whole: false, decimals: None }
    }

    /// This column, printed with `decimals` decimals (files keep every digit).
    pub fn printed_to(self, decimals: usize) -> Column {
        Column { decimals: Some(decimals), ..self }
    }

    /// Its numbers.
    ///
    /// # Panics
    /// For a text column: a programming error in a study or its test.
    pub fn as_numbers(&self) -> &[f64] {
        match &self.values {
            Cells::Numbers(v) => v,
            Cells::Text(_) => panic!("{} is a text column", self.name),
        }
    }

    /// The number of values.
    pub fn len(&self) -> usize {
        match &self.values {
            Cells::Numbers(v) => v.len(),
            Cells::Text(v) => v.len(),
        }
    }

    /// Whether it has no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The values of a [`Column`].
#[derive(Debug, Clone, PartialEq)]
pub enum Cells {
    /// Numbers (NaN for a missing value: an empty CSV cell, `null` in JSON, `None` in Python).
    Numbers(Vec<f64>),
    /// Text.
    Text(Vec<String>),
}

/// A plot: lines or points over two axes, as plain data (pendula-viz draws it).
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// Its name, a file stem.
    pub name: &'static str,
    /// Its title.
    pub title: String,
    /// The horizontal axis.
    pub x: Axis,
    /// The vertical axis.
    pub y: Axis,
    /// The lines and point sets, drawn in order.
    pub series: Vec<Line>,
    /// Its bars, for a bar chart (then `series` is empty): one a category, from top to
    /// bottom, their length on the axis [`Plot::x`].
    pub bars: Vec<Bar>,
    /// The range of the value axis shown (a search range, say); `None` fits the values.
    pub limits: Option<(f64, f64)>,
    /// The system whose quantity the horizontal axis is, when its symbol there differs from
    /// the catalogue's (the driven pendulum's drive amplitude is Baker and Gollub's g).
    pub system: Option<&'static str>,
    /// Whether the series' labels form a legend; without one (tens of orbits told apart by
    /// colour alone), each labelled series still takes the next colour.
    pub legend: bool,
}

impl Plot {
    /// A plot of lines and point sets (no bars, the value range fitted).
    pub fn lines(name: &'static str, title: impl Into<String>, x: Axis, y: Axis, series: Vec<Line>) -> Plot {
        Plot {
            name,
            title: title.into(),
            x,
            y,
            series,
            bars: Vec::new(),
            limits: None,
            system: None,
            legend: true,
        }
    }
}

/// One bar of a bar chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Bar {
    /// Its category (a method's name takes the method's colour).
    pub label: String,
    /// Its length; `None` draws none, only the note.
    pub value: Option<f64>,
    /// Text beside it (or in its place); `None` prints the value.
    pub note: Option<String>,
    /// The value is a limit of the method's definition, not a measurement: drawn empty and
    /// hatched.
    pub refused: bool,
}

/// An axis of a [`Plot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// The quantity, as a catalogue name or symbol (`t`, `E - E(0)`).
    pub label: String,
    /// Its unit (empty for a pure number; `rad and rad/s combined` for a distance in a state
    /// space of mixed units).
    pub unit: String,
    /// Whether the axis is logarithmic.
    pub log: bool,
}

/// One series of a [`Plot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// Its legend entry.
    pub label: String,
    /// How it is drawn.
    pub style: Style,
    /// Its points (x, y).
    pub points: Vec<[f64; 2]>,
    /// The method whose results it shows, if one: drawn in the method's colour and marker,
    /// as in every figure of it.
    pub method: Option<&'static str>,
}

impl Line {
    /// A series `label` drawn as `style` through `points`.
    pub fn new(label: impl Into<String>, style: Style, points: Vec<[f64; 2]>) -> Line {
        Line { label: label.into(), style, points, method: None }
    }

    /// A series of `method`'s results, in its colour and marker.
    pub fn of_method(
        method: &'static str,
        label: impl Into<String>,
        style: Style,
        points: Vec<[f64; 2]>,
    ) -> Line {
        Line { label: label.into(), style, points, method: Some(method) }
    }
}

/// How a [`Line`] is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// A solid line.
    Solid,
    /// A dashed line (fits, guides, references).
    Dashed,
    /// Markers only.
    Points,
    /// A line with a marker at each point (few points, each a measurement).
    LineMarkers,
    /// Small dots (thousands of points: a section's crossings).
    Dots,
    /// A guide, not data (a slope of reference): thin, dashed and grey, its label written
    /// at its end rather than in the legend.
    Guide,
}
