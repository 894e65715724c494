//! `stability`: the largest stable step of each method (paper §7.3 "Stability"), by
//! bisection in log h ([`crate::analysis::largest_stable_step`]): the largest step at which
//! the relative energy error (against the system's energy scale; the energy balance for a
//! damped or driven system) stays within a bound over a run. Tao's maps refuse steps above
//! ω h = 1: that is a limit of the method's definition, reported as such, not a stability
//! result.

use super::prelude::*;
use crate::Error;
use crate::analysis::{StabilityCriterion, accepted_step_limit, largest_stable_step};
use crate::error::Short;
use crate::integrator::Method;

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "stability",
    about: "The largest stable step of each method",
    params: &[
        Param::system("pendulum", &[]),
        Param::methods(),
        Param::time("t_end", "The length of each test run", 20.0),
        Param {
            name: "max_energy_error",
            help: "The largest relative energy error (against the energy scale) for a run to count as stable",
            kind: Kind::Real { default: 0.1, unit: Unit::None, domain: Domain::Positive },
        },
    ],
    files: &["stability"],
    run,
};

/// The search range of the step, in the system's time unit.
pub const H_RANGE: (f64, f64) = (1e-5, 2.0);

/// How a method's largest stable step reads.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Found {
    /// Stable up to this step, and unstable just above it.
    Limit(f64),
    /// Stable at the top of the search range.
    AtMost(f64),
    /// Stable at every step it accepts: it refuses steps above this one.
    Refused(f64),
    /// Unstable at every step tried.
    Unstable,
}

impl Found {
    fn of(method: &Method, h: Option<f64>) -> Found {
        match (h, accepted_step_limit(method)) {
            (None, _) => Found::Unstable,
            (Some(h), Some(limit)) if h >= limit / 1.01 => Found::Refused(h),
            (Some(h), _) if h >= H_RANGE.1 => Found::AtMost(h),
            (Some(h), _) => Found::Limit(h),
        }
    }

    fn step(self) -> Option<f64> {
        match self {
            Found::Limit(h) | Found::AtMost(h) | Found::Refused(h) => Some(h),
            Found::Unstable => None,
        }
    }

    /// What the number means, when it is not plainly the stability limit (the CSV's note).
    fn note(self, method: &Method) -> String {
        match (self, accepted_step_limit(method)) {
            (Found::Refused(_), Some(limit)) => format!(
                "refused above h = {} s (binding * h <= 1): stable at every step it accepts",
                crate::error::short(limit)
            ),
            (Found::Unstable, _) => format!("unstable at every step tried, down to {} s", H_RANGE.0),
            _ => String::new(),
        }
    }

    /// The note beside its bar, in the system's time unit.
    fn label(self, method: &Method, tu: &str) -> Option<String> {
        // Bounds as given (0.005, 1e-5); a measured step to four significant digits.
        let bound = |x: f64| format!("{}{}", Short(x), unit_suffix(tu));
        let with = |x: f64| format!("{}{}", crate::error::short(x), unit_suffix(tu));
        match self {
            Found::Refused(_) => Some(format!(
                "refused above {} (binding · h ≤ 1); stable below",
                bound(accepted_step_limit(method).unwrap_or_default())
            )),
            Found::Unstable => Some(format!("unstable at every step tried (down to {})", bound(H_RANGE.0))),
            Found::AtMost(_) => Some(format!("≥ {} (the search limit)", bound(H_RANGE.1))),
            Found::Limit(h) => Some(with(h)),
        }
    }
}

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&STUDY, inputs)?;
    let values = args.system("system")?;
    let t_end = args.real("t_end")?;
    let bound = args.real("max_energy_error")?;
    super::schedule(1.0, t_end).map_err(|e| match e {
        Error::InvalidValue { name, value, allowed } if name == "dt" => {
            Error::InvalidValue { name: "t_end".into(), value, allowed }
        }
        e => e,
    })?;
    let model = values.build();
    let methods = args.methods("methods", &*model)?;
    // What it costs, at most: per method, the bisection's runs (both ends of the range, then
    // halvings of log h to 1%), each as long as a run at the smallest step.
    let runs = 2.0 + ((H_RANGE.1 / H_RANGE.0).ln() / 1.01f64.ln()).log2().ceil();
    let per_run = (t_end / H_RANGE.0).ceil();
    budget.afford(
        methods.len() as f64 * runs * per_run,
        format!(
            "{} methods x {runs} runs of up to {} steps (h down to {} s over {} s)",
            methods.len(),
            Short(per_run),
            H_RANGE.0,
            Short(t_end)
        ),
    )?;

    let criterion = StabilityCriterion { t_end, max_rel_energy_error: bound };
    let mut found = Vec::new();
    for method in &methods {
        let h =
            largest_stable_step(&*model, method, values.initial_state(), H_RANGE.0, H_RANGE.1, &criterion)?;
        found.push(Found::of(method, h));
    }

    let info = values.info();
    let tu = info.time_unit();
    let scale = model.energy_scale(values.initial_state());
    let mut summary = vec![format!(
        "{}: the largest step whose relative energy error (against the energy scale {}{}) stays <= {} over {}{} (searched {} .. {}{})",
        info.name,
        sig(scale),
        unit_suffix(info.energy_unit()),
        Short(bound),
        Short(t_end),
        unit_suffix(tu),
        Short(H_RANGE.0),
        Short(H_RANGE.1),
        unit_suffix(tu)
    )];
    let measured: Vec<(&Method, f64)> = methods
        .iter()
        .zip(&found)
        .filter_map(|(m, f)| match f {
            Found::Limit(h) | Found::AtMost(h) => Some((*m, *h)),
            _ => None,
        })
        .collect();
    let cmp = |a: &&(&Method, f64), b: &&(&Method, f64)| a.1.total_cmp(&b.1);
    // A method stable at the top of the search range has a limit at least that large.
    let step = |h: f64| {
        let at_least = if h >= H_RANGE.1 { "at least " } else { "" };
        format!("{at_least}{}{}", sig(h), unit_suffix(tu))
    };
    if let (Some(lo), Some(hi)) = (measured.iter().min_by(cmp), measured.iter().max_by(cmp)) {
        summary.push(format!(
            "The stable steps run from {} ({}) to {} ({})",
            step(lo.1),
            lo.0.name,
            step(hi.1),
            hi.0.name
        ));
    }
    let refused: Vec<&str> = methods
        .iter()
        .zip(&found)
        .filter(|(_, f)| matches!(f, Found::Refused(_)))
        .map(|(m, _)| m.name)
        .collect();
    if !refused.is_empty() {
        let (verb, they, their) = if refused.len() == 1 {
            ("refuses", "it accepts", "its")
        } else {
            ("refuse", "they accept", "their")
        };
        summary.push(format!(
            "{} {verb} steps above 1/binding: stable at every step {they}, a limit of {their} definition and not a stability result",
            refused.join(", ")
        ));
    }

    let bars: Vec<Bar> = methods
        .iter()
        .zip(&found)
        .map(|(m, f)| Bar {
            label: m.name.to_owned(),
            value: f.step(),
            note: f.label(m, tu),
            refused: matches!(f, Found::Refused(_)),
        })
        .collect();
    let plot = Plot {
        name: "stability",
        title: format!(
            "{}: largest stable step (relative energy error ≤ {} over {}{})",
            info.name,
            Short(bound),
            Short(t_end),
            unit_suffix(tu)
        ),
        x: Axis { label: "largest stable step h".into(), unit: tu.into(), log: true },
        y: Axis { label: "method".into(), unit: String::new(), log: false },
        series: Vec::new(),
        bars,
        limits: Some(H_RANGE),
        system: None,
        legend: false,
    };
    let table = Table {
        name: "stability",
        shown: true,
        columns: vec![
            Column::text("method", methods.iter().map(|m| m.name.to_owned()).collect()),
            Column::numbers(
                "largest_stable_dt",
                tu,
                found.iter().map(|f| f.step().unwrap_or(f64::NAN)).collect(),
            ),
            Column::text("note", methods.iter().zip(&found).map(|(m, f)| f.note(m)).collect()),
        ],
    };
    let (lo, hi) = measured.iter().fold((f64::NAN, f64::NAN), |(lo, hi), (_, h)| (lo.min(*h), hi.max(*h)));
    let numbers = vec![
        Number { key: "energy_scale", value: scale, unit: info.energy_unit(), about: "the energy scale" },
        Number {
            key: "smallest_measured_dt",
            value: lo,
            unit: tu,
            about: "the smallest measured stability limit",
        },
        Number {
            key: "largest_measured_dt",
            value: hi,
            unit: tu,
            about: "the largest measured stability limit",
        },
    ];
    let names = methods.iter().map(|m| m.name).collect::<Vec<_>>().join(",");
    Ok(Report {
        study: STUDY.name,
        inputs: vec![
            ("system", Input::Name(info.name.into())),
            ("methods", Input::Name(names)),
            ("t_end", Input::Number(t_end)),
            ("max_energy_error", Input::Number(bound)),
        ],
        summary,
        numbers,
        texts: Vec::new(),
        tables: vec![table],
        plots: vec![plot],
    })
}
