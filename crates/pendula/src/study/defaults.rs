//! What each study runs when the user gives nothing, declared once for every front end:
//! the CLI's flags (their `[default: …]` help is written from here and their conversion
//! falls back to the same values), Python's keyword defaults (`_core.defaults()`) and the
//! lab. A study ported onto [`crate::study::STUDIES`] declares its defaults in its
//! [`crate::study::Param`]s instead; the ones here belong to the studies that still have
//! their own commands.
//!
//! Each value is named as the CLI's argument id and Python's keyword (`steps_per_period`,
//! not `--steps-per-period`), in its unit of [`crate::system`]'s conventions (SI, radians).

use crate::simulate::defaults as run;

/// A default value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// A real number, in the parameter's unit.
    Number(f64),
    /// A whole number.
    Count(u64),
    /// A text (an axis `NAME=LO:HI:N`, a size `WxH`).
    Text(&'static str),
    /// A number that depends on the system: `(system, value)` pairs, and the value for
    /// every other system.
    PerSystem(&'static [(&'static str, f64)], f64),
}

impl Value {
    /// The value for `system` (a [`Value::PerSystem`]'s entry, or its value otherwise);
    /// `None` for a text.
    pub fn number_for(&self, system: &str) -> Option<f64> {
        match *self {
            Value::Number(v) => Some(v),
            Value::Count(n) => Some(n as f64),
            Value::Text(_) => None,
            Value::PerSystem(of, otherwise) => {
                Some(of.iter().find(|(s, _)| *s == system).map_or(otherwise, |(_, v)| *v))
            }
        }
    }
}

impl std::fmt::Display for Value {
    /// As a user would type it: the shortest form of a number ([`crate::error::Short`]).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Number(v) => write!(f, "{}", crate::error::Short(*v)),
            Value::Count(n) => write!(f, "{n}"),
            Value::Text(t) => f.write_str(t),
            Value::PerSystem(of, otherwise) => {
                for (system, v) in of.iter() {
                    write!(f, "{} for {system}, ", crate::error::Short(*v))?;
                }
                write!(f, "{} otherwise", crate::error::Short(*otherwise))
            }
        }
    }
}

/// One study-specific default: its name, value, and why it is this value when that needs
/// saying (shown after it: "[default: -15, regular and chaotic orbits side by side]").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Default {
    /// The argument's name (CLI id, Python keyword).
    pub name: &'static str,
    /// The value.
    pub value: Value,
    /// Why, or "".
    pub why: &'static str,
}

const fn num(name: &'static str, v: f64) -> Default {
    Default { name, value: Value::Number(v), why: "" }
}

const fn count(name: &'static str, n: u64) -> Default {
    Default { name, value: Value::Count(n), why: "" }
}

/// A study's defaults: the shared ones (system, method, step, end time; `None` where the
/// study chooses per method or takes none) and its own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Defaults {
    /// The study (its CLI command).
    pub study: &'static str,
    /// The system run when none is named.
    pub system: &'static str,
    /// The method.
    pub method: Option<&'static str>,
    /// The step, s.
    pub dt: Option<f64>,
    /// The end time, s.
    pub t_end: Option<f64>,
    /// The study's own defaults.
    pub values: &'static [Default],
}

impl Defaults {
    /// The study's own default `name`.
    ///
    /// # Panics
    /// When the study declares no default of that name: a front end asking for one is a
    /// programming error, caught by the tests that run every study on its defaults.
    pub fn get(&self, name: &str) -> Value {
        match self.values.iter().find(|d| d.name == name) {
            Some(d) => d.value,
            None => panic!("the study `{}` declares no default `{name}`", self.study),
        }
    }

    /// [`Defaults::get`] of a number.
    pub fn number(&self, name: &str) -> f64 {
        match self.get(name) {
            Value::Number(v) => v,
            Value::Count(n) => n as f64,
            other => panic!("the default `{name}` of `{}` is {other:?}, not a number", self.study),
        }
    }

    /// [`Defaults::get`] of a whole number.
    pub fn count(&self, name: &str) -> u64 {
        match self.get(name) {
            Value::Count(n) => n,
            other => panic!("the default `{name}` of `{}` is {other:?}, not a count", self.study),
        }
    }

    /// [`Defaults::get`] of a text.
    pub fn text(&self, name: &str) -> &'static str {
        match self.get(name) {
            Value::Text(t) => t,
            other => panic!("the default `{name}` of `{}` is {other:?}, not a text", self.study),
        }
    }
}

/// One run (`pendula simulate`, `pendula.solve`, the lab): [`crate::simulate::defaults`].
pub const SIMULATE: Defaults = Defaults {
    study: "simulate",
    system: run::SYSTEM,
    method: Some(run::METHOD),
    dt: Some(run::DT),
    t_end: Some(run::T_END),
    values: &[
        num("binding", crate::integrator::tao::DEFAULT_BINDING),
        num("rtol", run::RTOL),
        num("atol", run::ATOL),
        num("h_min", 0.0),
        count("every", 1),
    ],
};

/// An ensemble over a grid of initial states or parameters.
pub const SWEEP: Defaults = Defaults {
    study: "sweep",
    system: "double",
    method: Some("rk4"),
    dt: Some(0.01),
    t_end: Some(10.0),
    values: &[],
};

/// Several methods at equal cost ([`crate::analysis::compare`]); its end time depends on the
/// system ([`crate::analysis::compare::default_t_end`]).
pub const COMPARE: Defaults = Defaults {
    study: "compare",
    system: "double",
    method: None,
    dt: None,
    t_end: None,
    values: &[
        Default {
            name: "evals_per_second",
            value: Value::Number(crate::analysis::compare::DEFAULT_EVALS_PER_SECOND),
            why: "i.e. RK4 at h = 1/750 s, where tao-4's step stays below 1/(its binding constant)",
        },
        Default {
            name: "t_end",
            value: Value::PerSystem(
                crate::analysis::compare::T_END_BY_SYSTEM,
                crate::analysis::compare::T_END_OTHERWISE,
            ),
            why: "where on the double pendulum, at the default cost, RK4's drift has passed the bounded errors of gauss-legendre-4 and -6 (those of the low-order methods only far beyond, extrapolated)",
        },
    ],
};

/// The flip fractal of the double pendulum ([`crate::analysis::fractal`]).
pub const FRACTAL: Defaults = Defaults {
    study: "fractal",
    system: "double",
    method: Some("rk4"),
    dt: Some(0.01),
    t_end: None,
    values: &[
        Default { name: "grid", value: Value::Text("theta1=-pi:pi:512 and theta2=-pi:pi:512"), why: "" },
        num("t_max", 100.0),
        num("tolerance", 0.01),
    ],
};

/// An animation of one run.
pub const ANIMATE: Defaults = Defaults {
    study: "animate",
    system: run::SYSTEM,
    method: Some(run::METHOD),
    dt: Some(run::DT),
    t_end: Some(run::T_END),
    values: &[count("fps", 30), Default { name: "size", value: Value::Text("480x480"), why: "" }],
};

/// Every study's defaults, in the CLI's order.
pub static ALL: &[&Defaults] = &[&SIMULATE, &COMPARE, &ANIMATE, &FRACTAL, &SWEEP];
