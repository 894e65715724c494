//! `lyapunov`: the largest Lyapunov exponent, or the whole spectrum, from the variational
//! equations with periodic re-orthonormalisation (Benettin et al. 1980;
//! [`mod@crate::analysis::lyapunov`]), its running estimate as a convergence plot, and an
//! uncertainty from batch means.

use super::prelude::*;
use crate::Error;
use crate::analysis::lyapunov::{LyapunovSpec, MIN_INTERVALS, Mismatch, lyapunov};
use crate::error::{Short, approx};
use crate::system::AsSystem;

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "lyapunov",
    about: "The largest Lyapunov exponent, or all of them, from the variational equations (Benettin)",
    params: &[
        Param::system("double", &[]),
        Param::preset(),
        Param {
            name: "method",
            help: "The integration method, for the state and its tangent vectors: an explicit Runge–Kutta method, an embedded pair at fixed steps, or Gauss–Legendre",
            kind: Kind::Method { default: "rk4" },
        },
        Param::time("dt", "The step size", 1e-3),
        Param::time("t_end", "The time over which the exponents are averaged, after the transient", 200.0),
        Param {
            name: "transient",
            help: "Time run first and discarded",
            kind: Kind::Real { default: 10.0, unit: Unit::Time, domain: Domain::NonNegative },
        },
        Param::time("renormalise", "The interval between re-orthonormalisations", 0.5),
        Param {
            name: "spectrum",
            help: "All exponents (QR re-orthonormalisation of as many tangent vectors as the state has)",
            kind: Kind::Flag,
        },
    ],
    files: &["lyapunov", "exponents"],
    run,
};

/// The running estimates' column names, one per exponent (the largest state has
/// [`crate::analysis::lyapunov::MAX_DIM`] variables).
const LAMBDAS: [&str; crate::analysis::lyapunov::MAX_DIM] = [
    "lambda1", "lambda2", "lambda3", "lambda4", "lambda5", "lambda6", "lambda7", "lambda8", "lambda9",
    "lambda10", "lambda11", "lambda12", "lambda13", "lambda14", "lambda15", "lambda16",
];

/// λ with a subscript: `λ₁₂` for the 12th exponent.
fn lambda(j: usize) -> String {
    let digits: String = j
        .to_string()
        .chars()
        .map(|c| char::from_u32(0x2080 + c.to_digit(10).unwrap_or(0)).unwrap_or(c))
        .collect();
    format!("λ{digits}")
}

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&STUDY, inputs)?;
    let (values, method, h, t_end) = args.one_run()?;
    let info = values.info();
    let transient = args.real("transient")?;
    let renormalise = args.real("renormalise")?;
    let spectrum = args.flag("spectrum")?;
    let count = if spectrum { info.state.len() } else { 1 };
    let spec = LyapunovSpec { h, transient, t_end, renormalise, count, blocks: 10 };
    // The step is checked first, so that a step longer than the interval is blamed on `dt`
    // (the analysis, seeing both, names the interval).
    match spec.mismatch() {
        Some(Mismatch::StepOverInterval) => {
            return Err(Error::InvalidInput {
                name: "dt".into(),
                value: Short(h).to_string(),
                allowed: format!(
                    "must be at most `renormalise` ({} s; the tangent vectors are re-orthonormalised that often, at whole steps)",
                    Short(renormalise)
                ),
            });
        }
        Some(Mismatch::TooFewIntervals) => {
            return Err(Error::InvalidInput {
                name: "t_end".into(),
                value: Short(t_end).to_string(),
                allowed: format!(
                    "at least {MIN_INTERVALS} re-orthonormalisations (every `renormalise`, {} s) are needed for the uncertainty",
                    Short(renormalise)
                ),
            });
        }
        None => {}
    }
    let schedule = super::schedule(h, transient + t_end)?;
    // What it costs: the state and its `count` tangent vectors over the transient and the
    // averaging time, and the running estimate's rows (one per re-orthonormalisation).
    budget.afford(
        schedule.steps as f64 * (1 + count) as f64,
        format!("{count} tangent vectors and the state x {} steps", approx(schedule.steps as f64)),
    )?;
    let rows = t_end / renormalise;
    budget
        .afford_values(rows * (1 + count) as f64, format!("{} rows of the running estimate", approx(rows)))?;

    let model = values.build();
    let result =
        lyapunov(&AsSystem(&*model), method, values.initial_state(), &spec).map_err(super::step_named_dt)?;
    let (tu, ru) = (info.time_unit(), info.rate_unit());
    let with = |v: f64, u: &str| format!("{}{}", Short(v), unit_suffix(u));
    let mut summary = vec![format!(
        "{} ({}, dt = {}, {} after a {} transient):",
        info.name,
        method.name,
        with(h, tu),
        with(t_end, tu),
        with(transient, tu)
    )];
    for (j, (l, e)) in result.exponents.iter().zip(&result.uncertainty).enumerate() {
        summary.push(format!("  lambda{} = {l:.5} ± {e:.5}{}", j + 1, unit_suffix(ru)));
    }
    let sum: f64 = result.exponents.iter().sum();
    if spectrum {
        summary.push(format!("  sum = {}{}", sig(sum), unit_suffix(ru)));
    }

    let mut running: Vec<Vec<f64>> = vec![Vec::new(); count + 1];
    for row in result.running.chunks_exact(count + 1) {
        for (column, v) in running.iter_mut().zip(row) {
            column.push(*v);
        }
    }
    // Each exponent's running estimate, then (unlabelled, so in its colour) the largest
    // one's final value ± its uncertainty, dashed.
    let mut series = Vec::new();
    for j in 0..count {
        let (l, e) = (result.exponents[j], result.uncertainty[j]);
        let band = if j == 0 { ", dashed ± uncertainty" } else { "" };
        series.push(Line::new(
            format!("{} = {l:.4} ± {e:.4}{}{band}", lambda(j + 1), unit_suffix(ru)),
            Style::Solid,
            running[0].iter().zip(&running[j + 1]).map(|(t, v)| [*t, *v]).collect(),
        ));
        if j == 0 {
            for v in [l + e, l - e] {
                series.push(Line::new("", Style::Dashed, vec![[0.0, v], [t_end, v]]));
            }
        }
    }
    let plot = Plot::lines(
        "lyapunov",
        format!("{}: running Lyapunov estimate ({}, dt = {})", info.name, method.name, with(h, tu)),
        Axis { label: "time after the transient, t".into(), unit: tu.into(), log: false },
        Axis { label: "exponent λ".into(), unit: ru.into(), log: false },
        series,
    );
    let mut columns = vec![Column::numbers("t", tu, running.remove(0))];
    for (name, column) in LAMBDAS.iter().zip(running) {
        columns.push(Column::numbers(name, ru, column));
    }
    let exponents = Table {
        name: "exponents",
        shown: true,
        columns: vec![
            Column::text("exponent", LAMBDAS[..count].iter().map(|s| (*s).to_owned()).collect()),
            Column::numbers("value", ru, result.exponents.clone()),
            Column::numbers("uncertainty", ru, result.uncertainty.clone()),
        ],
    };
    let mut numbers = vec![
        Number { key: "lambda_max", value: result.exponents[0], unit: ru, about: "the largest exponent" },
        Number {
            key: "uncertainty",
            value: result.uncertainty[0],
            unit: ru,
            about: "the largest exponent's standard error, from 10 batch means",
        },
    ];
    if spectrum {
        numbers.push(Number { key: "sum", value: sum, unit: ru, about: "the exponents' sum" });
    }
    Ok(Report {
        study: STUDY.name,
        inputs: vec![
            ("system", Input::Name(info.name.into())),
            ("preset", Input::Name(args.preset("preset")?.unwrap_or("none").into())),
            ("method", Input::Name(method.name.into())),
            ("dt", Input::Number(h)),
            ("t_end", Input::Number(t_end)),
            ("transient", Input::Number(transient)),
            ("renormalise", Input::Number(renormalise)),
            ("spectrum", Input::Flag(spectrum)),
        ],
        summary,
        numbers,
        texts: Vec::new(),
        tables: vec![Table { name: "lyapunov", shown: false, columns }, exponents],
        plots: vec![plot],
    })
}
