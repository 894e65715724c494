//! `divergence`: the distance between two trajectories started `delta` apart in one state
//! variable, on a log scale against time, with the exponential growth rate fitted before it
//! saturates ([`mod@crate::analysis::divergence`], [`crate::analysis::growth_rate_between`]): a
//! finite-time estimate of the largest Lyapunov exponent (paper §1).

use super::prelude::*;
use crate::Error;
use crate::analysis::divergence::{divergence, growth_rate_between, sample_every, survives_rounding};
use crate::error::Short;
use crate::{End, RunSpec};

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "divergence",
    about: "The distance between two trajectories started close together, and its growth rate",
    params: &[
        Param::system("double", &[]),
        Param::method("rk4"),
        Param::time("dt", "The step size", 1e-3),
        Param::time("t_end", "The end time", 30.0),
        Param {
            name: "delta",
            help: "The initial separation, added to the state variable `variable`",
            kind: Kind::Real { default: 1e-9, unit: Unit::None, domain: Domain::Finite },
        },
        Param {
            name: "variable",
            help: "The state variable to perturb",
            kind: Kind::Variable { velocity: false },
        },
        Param {
            name: "saturation",
            help: "The fit uses the distances before they first exceed this",
            kind: Kind::Real { default: 1e-2, unit: Unit::None, domain: Domain::Positive },
        },
        Param {
            name: "fit_from",
            help: "The fit uses only the distances above this, leaving out the start, where the separation has not yet turned along the most unstable direction",
            kind: Kind::Real { default: 0.0, unit: Unit::None, domain: Domain::NonNegative },
        },
    ],
    files: &["divergence"],
    run,
};

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&STUDY, inputs)?;
    let (values, method, dt, t_end) = args.one_run()?;
    let info = values.info();
    let delta = args.real("delta")?;
    if delta == 0.0 {
        return Err(Error::InvalidValue {
            name: "delta".into(),
            value: delta,
            allowed: "a finite separation, not 0 (the two runs must start apart)",
        });
    }
    let saturation = args.real("saturation")?;
    if saturation <= delta.abs() {
        return Err(Error::InvalidInput {
            name: "saturation".into(),
            value: Short(saturation).to_string(),
            allowed: format!("finite and larger than |delta| = {}", Short(delta.abs())),
        });
    }
    let fit_from = args.real("fit_from")?;
    if fit_from >= saturation {
        return Err(Error::InvalidValue {
            name: "fit_from".into(),
            value: fit_from,
            allowed: "must be finite, >= 0 and smaller than saturation",
        });
    }
    let index = args.variable("variable", info)?;
    let start = values.initial_state()[index];
    if !survives_rounding(start, delta) {
        let spacing = (start.abs() * f64::EPSILON).max(f64::MIN_POSITIVE);
        return Err(Error::InvalidInput {
            name: "delta".into(),
            value: format!("{delta:e}"),
            allowed: format!(
                "added to {} = {start:e} it is lost in rounding (floats there are {spacing:.3e} apart); use a larger delta or a smaller start",
                info.state[index].name
            ),
        });
    }
    let spec = RunSpec { t0: 0.0, h: dt, end: End::Time(t_end) };
    let schedule = super::schedule(dt, t_end)?;
    budget.afford(2.0 * schedule.steps as f64, format!("2 runs x {} steps", schedule.steps))?;

    let model = values.build();
    let d = divergence(
        &*model,
        method,
        values.initial_state(),
        index,
        delta,
        &spec,
        sample_every(schedule.steps),
    )?;
    let fit = growth_rate_between(&d, fit_from, saturation);
    let variable = info.state[index].name;
    let (tu, ru) = (info.time_unit(), info.rate_unit());
    let mut summary = vec![format!(
        "{}: two runs {} apart in {variable}, {} at dt = {}{} to t = {}{}",
        info.name,
        Short(delta),
        method.name,
        Short(dt),
        unit_suffix(tu),
        Short(t_end),
        unit_suffix(tu)
    )];
    summary.push(match fit {
        Some(f) => format!(
            "Their distance grows at a fitted rate of {}{} over t = {} … {}{}, before it first exceeds {}",
            sig(f.rate),
            unit_suffix(ru),
            sig(f.t_start),
            sig(f.t_end),
            unit_suffix(tu),
            Short(saturation)
        ),
        None => format!(
            "Too few samples between {} and {} (the saturation) to fit a growth rate",
            Short(fit_from),
            Short(saturation)
        ),
    });
    let mut series = vec![Line::new(
        "distance",
        Style::Solid,
        d.t.iter().zip(&d.distance).filter(|(_, x)| **x > 0.0).map(|(t, x)| [*t, *x]).collect(),
    )];
    if let Some(f) = fit {
        // The fitted line ln d = intercept + rate·t, drawn over the fit window.
        let line = |t: f64| (f.intercept + f.rate * t).exp();
        let ts = (0..=50).map(|k| f.t_start + (f.t_end - f.t_start) * f64::from(k) / 50.0);
        series.push(Line::new(
            format!("fit: rate {}{}", sig(f.rate), unit_suffix(ru)),
            Style::Dashed,
            ts.map(|t| [t, line(t)]).collect(),
        ));
    }
    let plot = Plot::lines(
        "divergence",
        format!(
            "{}: divergence of trajectories {} apart in {variable} ({})",
            info.name,
            Short(delta),
            method.name
        ),
        Axis { label: "t".into(), unit: tu.into(), log: false },
        Axis { label: "distance |Δy| in state space".into(), unit: super::state_units(info), log: true },
        series,
    );
    let nan = f64::NAN;
    let numbers = vec![
        Number {
            key: "growth_rate",
            value: fit.map_or(nan, |f| f.rate),
            unit: ru,
            about: "the fitted exponential rate",
        },
        Number {
            key: "fit_start",
            value: fit.map_or(nan, |f| f.t_start),
            unit: tu,
            about: "the fit window's start",
        },
        Number {
            key: "fit_end",
            value: fit.map_or(nan, |f| f.t_end),
            unit: tu,
            about: "the fit window's end",
        },
    ];
    let table = Table {
        name: "divergence",
        shown: false,
        columns: vec![Column::numbers("t", tu, d.t), Column::numbers("distance", "", d.distance)],
    };
    Ok(Report {
        study: STUDY.name,
        inputs: vec![
            ("system", Input::Name(info.name.into())),
            ("method", Input::Name(method.name.into())),
            ("dt", Input::Number(dt)),
            ("t_end", Input::Number(t_end)),
            ("delta", Input::Number(delta)),
            ("variable", Input::Name(variable.into())),
            ("saturation", Input::Number(saturation)),
            ("fit_from", Input::Number(fit_from)),
        ],
        summary,
        numbers,
        texts: Vec::new(),
        tables: vec![table],
        plots: vec![plot],
    })
}
