//! `period`: the simple pendulum's period against amplitude — simulated (zero crossings
//! located on the interpolant, [`crate::analysis::measure_period`]), exact
//! 4 √(l/g) K(sin(θ₀/2)) and small-angle 2π √(l/g) (paper §3; ERRATA on the harmonic
//! approximation). Amplitudes run in 5° steps from rest up to `max_amplitude`.

use std::f64::consts::PI;

use super::prelude::*;
use crate::Error;
use crate::analysis::measure_period;
use crate::error::Short;
use crate::system::Model;
use crate::system::pendulum::Pendulum;

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "period",
    about: "The simple pendulum's period against amplitude: simulated, exact and small-angle",
    params: &[
        Param::fixed_system("pendulum"),
        Param::method("rk4"),
        Param::time("dt", "The step size of the simulated periods", 1e-3),
        Param {
            name: "max_amplitude",
            help: "The largest amplitude, from 5 to below 180 degrees (at 180 the pendulum balances upright and never swings back); amplitudes run in 5-degree steps up to it",
            kind: Kind::Real { default: 175.0, unit: Unit::Fixed("deg"), domain: Domain::Positive },
        },
    ],
    files: &["period", "period_error"],
    run,
};

/// The amplitude step, degrees (and the smallest amplitude).
const STEP_DEG: f64 = 5.0;

/// How many exact periods each run lasts: enough for the three zero crossings of one
/// period however the simulated period errs.
const PERIODS_RUN: f64 = 2.5;

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&STUDY, inputs)?;
    let base = args.system("system")?;
    let method = args.method("method")?;
    let dt = args.real("dt")?;
    let max = args.real("max_amplitude")?;
    if !(STEP_DEG..180.0).contains(&max) {
        return Err(Error::InvalidInput {
            name: "max_amplitude".into(),
            value: Short(max).to_string(),
            allowed: "from 5 (the first amplitude) to below 180 degrees; the period is of a libration, and at 180 the pendulum balances upright and never swings back".into(),
        });
    }
    if let Some((name, _)) = inputs.set.iter().find(|(n, _)| base.info().state.iter().any(|q| q.name == n)) {
        return Err(Error::InvalidInput {
            name: "set".into(),
            value: name.clone(),
            allowed: "parameters only: period releases the pendulum from rest at each of its amplitudes"
                .into(),
        });
    }
    super::schedule(dt, 1.0)?;
    let amplitudes: Vec<f64> = (1..).map(|k| STEP_DEG * k as f64).take_while(|a| *a <= max + 1e-9).collect();
    let pendulum = Pendulum::from_values(&base);
    let steps: f64 =
        amplitudes.iter().map(|a| (PERIODS_RUN * pendulum.period(radians(*a)) / dt).ceil()).sum();
    budget.afford(
        steps,
        format!("{} amplitudes x {PERIODS_RUN} periods at dt = {} s", amplitudes.len(), Short(dt)),
    )?;

    let settings = |a: f64| {
        let mut s = inputs.set.clone();
        s.extend([("theta".to_owned(), radians(a)), ("omega".to_owned(), 0.0)]);
        s
    };
    let (mut simulated, mut exact) = (Vec::new(), Vec::new());
    for &a in &amplitudes {
        let values = base.info().values(&settings(a))?;
        let pendulum = Pendulum::from_values(&values);
        let t_exact = pendulum.period(values.initial_state()[0]);
        let model = values.build();
        let found = measure_period(&*model, method, values.initial_state(), 0, dt, PERIODS_RUN * t_exact)?;
        simulated.push(found.unwrap_or(f64::NAN));
        exact.push(t_exact);
    }
    let small = pendulum.small_angle_period();
    let small_angle = vec![small; amplitudes.len()];

    let rel = |a: &[f64]| -> Vec<f64> { a.iter().zip(&exact).map(|(x, e)| (x / e - 1.0).abs()).collect() };
    let (sim_error, small_error) = (rel(&simulated), rel(&small_angle));
    let missing = simulated.iter().filter(|t| t.is_nan()).count();
    let worst = sim_error.iter().copied().filter(|e| !e.is_nan()).fold(0.0, f64::max);
    let last = amplitudes.len() - 1;
    let mut summary = vec![if missing == 0 {
        format!(
            "The simple pendulum released from rest at {} to {} degrees: {} at dt = {} s gives the period within {} (relative) of the exact 4 sqrt(l/g) K(sin(theta0/2)) at every amplitude",
            amplitudes[0],
            amplitudes[last],
            method.name,
            Short(dt),
            sig(worst)
        )
    } else {
        format!(
            "The simple pendulum released from rest at {} to {} degrees: {} at dt = {} s found no full period at {missing} of the {} amplitudes; where it found one, it is within {} (relative) of the exact period",
            amplitudes[0],
            amplitudes[last],
            method.name,
            Short(dt),
            amplitudes.len(),
            sig(worst)
        )
    }];
    summary.push(format!(
        "The small-angle period 2 pi sqrt(l/g) = {} s falls short of the exact period by a fraction {} at {} degrees and {} at {} degrees, where the exact period is {} s",
        sig(small),
        sig(small_error[0]),
        amplitudes[0],
        sig(small_error[last]),
        amplitudes[last],
        sig(exact[last])
    ));
    let numbers = vec![
        Number {
            key: "max_rel_error_simulated",
            value: worst,
            unit: "",
            about: "max |T(simulated) / T(exact) - 1|",
        },
        Number { key: "small_angle_period", value: small, unit: "s", about: "2 pi sqrt(l/g)" },
        Number {
            key: "exact_period_at_max",
            value: exact[last],
            unit: "s",
            about: "the exact period at the largest amplitude",
        },
    ];
    let degrees = Axis { label: "amplitude θ₀".into(), unit: "degrees".into(), log: false };
    let points = |ys: &[f64]| -> Vec<[f64; 2]> { amplitudes.iter().zip(ys).map(|(a, y)| [*a, *y]).collect() };
    let plots = vec![
        Plot::lines(
            "period",
            "Simple pendulum: period against amplitude",
            degrees.clone(),
            Axis { label: "period T".into(), unit: "s".into(), log: false },
            vec![
                Line::new("exact 4√(l/g) K(sin(θ₀/2))", Style::Solid, points(&exact)),
                Line::new(format!("simulated ({})", method.name), Style::Points, points(&simulated)),
                Line::new("small-angle 2π√(l/g)", Style::Dashed, points(&small_angle)),
            ],
        ),
        Plot::lines(
            "period_error",
            "Simple pendulum: deviation from the exact period",
            degrees,
            Axis { label: "|T / T(exact) − 1|".into(), unit: String::new(), log: true },
            vec![
                Line::new(format!("simulated ({})", method.name), Style::LineMarkers, points(&sim_error)),
                Line::new("small-angle approximation", Style::LineMarkers, points(&small_error)),
            ],
        ),
    ];
    let table = Table {
        name: "period",
        shown: true,
        columns: vec![
            Column::numbers("amplitude_deg", "deg", amplitudes),
            Column::numbers("simulated", "s", simulated),
            Column::numbers("exact", "s", exact),
            Column::numbers("small_angle", "s", small_angle),
        ],
    };
    let inputs = vec![
        ("system", Input::Name(base.info().name.into())),
        ("method", Input::Name(method.name.into())),
        ("dt", Input::Number(dt)),
        ("max_amplitude", Input::Number(max)),
    ];
    Ok(Report { study: STUDY.name, inputs, summary, numbers, texts: Vec::new(), tables: vec![table], plots })
}

/// Degrees to radians as the value syntax reads `5deg`: (deg · π) / 180.
fn radians(deg: f64) -> f64 {
    deg * PI / 180.0
}
