//! `round-trip`: time reversibility. A run to t = T and back to 0 with the step negated
//! (−dt) ends where it started for an exact solution; a symmetric method ([`Method::symmetric`]:
//! Störmer–Verlet, the Gauss–Legendre methods, the Yoshida compositions) undoes each step
//! exactly in exact arithmetic, so only round-off, grown by the dynamics, is left; a method
//! that is not symmetric (RK4) leaves its truncation error of both ways. The report gives the
//! distance in state space between the forward and the backward run at the same times
//! (about 2000 samples) and the distance at which the return ends from the start.
//!
//! Reference: E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
//! §II.3 (symmetric methods) and §V.1.

use super::prelude::*;
use crate::analysis::divergence::state_distance;
use crate::error::Short;
use crate::integrator::Method;
use crate::observe::{Every, Recorder};
use crate::{End, Error, RunSpec};

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "round-trip",
    about: "Time reversibility: a run to t_end and back with the step negated, and how far from its start it returns",
    params: &[
        Param::system("pendulum", &[]),
        Param::method("verlet"),
        Param::time("dt", "The step size (the way back steps with -dt)", 0.01),
        Param::time("t_end", "How far the run goes before it turns back", 20.0),
    ],
    files: &["round-trip"],
    run,
};

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let (values, method, dt, t_end) = Args::new(&STUDY, inputs)?.one_run()?;
    let forward = RunSpec { t0: 0.0, h: dt, end: End::Time(t_end) };
    let schedule = super::schedule(dt, t_end)?;
    budget.afford(2.0 * schedule.steps as f64, format!("2 runs of {} steps", schedule.steps))?;
    let model = values.build();
    let info = values.info();
    let n = values.initial_state().len();
    let every = (schedule.steps / 2000).max(1);
    // Every `every`-th state, and the last state (which the thinning may not keep).
    let record = |y0: &[f64], spec: &RunSpec| -> Result<(Vec<f64>, Vec<f64>), Error> {
        let mut rec = Every { n: every, inner: Recorder::default() };
        let report = model.solve(method, y0, spec, &mut rec)?;
        Ok((rec.inner.rows, report.state))
    };
    let (there, end) = record(values.initial_state(), &forward)?;
    let (back, home) = record(&end, &RunSpec { t0: t_end, h: -dt, end: End::Time(0.0) })?;
    // Rows of (t, state), paired where the two runs were at the same time.
    let rows_there: Vec<&[f64]> = there.chunks_exact(n + 1).collect();
    let rows_back: Vec<&[f64]> = back.chunks_exact(n + 1).collect();
    let (mut t, mut distance) = (Vec::new(), Vec::new());
    for a in &rows_there {
        if let Some(b) = rows_back.iter().find(|b| (b[0] - a[0]).abs() <= 1e-9 * dt) {
            t.push(a[0]);
            distance.push(state_distance(&a[1..], &b[1..]));
        }
    }
    let returned = state_distance(&home, values.initial_state());

    let tu = info.time_unit();
    let summary = vec![
        format!(
            "{}, {} at dt = {}{}, to t = {}{} and back with -dt: it returns {} from its start (the state-space distance, |y(0) after the round trip - y(0)|)",
            info.name,
            method.name,
            Short(dt),
            unit_suffix(tu),
            Short(t_end),
            unit_suffix(tu),
            sig(returned)
        ),
        symmetry(method),
    ];
    let label = "distance |Δy| in state space";
    let positive: Vec<[f64; 2]> =
        t.iter().zip(&distance).filter(|(_, d)| **d > 0.0).map(|(t, d)| [*t, *d]).collect();
    let plot = Plot::lines(
        "round-trip",
        format!(
            "{}: there and back again ({}, dt = {}{})",
            info.name,
            method.name,
            Short(dt),
            unit_suffix(tu)
        ),
        Axis { label: "t".into(), unit: tu.into(), log: false },
        Axis { label: label.into(), unit: super::state_units(info), log: true },
        vec![Line::new("forward vs backward run", Style::Solid, positive)],
    );
    Ok(Report {
        study: STUDY.name,
        inputs: run_inputs(&values, method, dt, t_end),
        summary,
        numbers: vec![
            Number {
                key: "return_error",
                value: returned,
                unit: "",
                about: "|y(0) after the round trip - y(0)|",
            },
            Number {
                key: "max_distance",
                value: distance.iter().copied().fold(0.0, f64::max),
                unit: "",
                about: "the largest distance of the two runs at the same time",
            },
        ],
        texts: Vec::new(),
        tables: vec![Table {
            name: "round-trip",
            shown: false,
            columns: vec![Column::numbers("t", tu, t), Column::numbers("distance", "", distance)],
        }],
        plots: vec![plot],
    })
}

/// What the method's symmetry means for the round trip, as a fact of the method.
fn symmetry(method: &Method) -> String {
    if method.symmetric {
        format!(
            "{} is symmetric: a step with -dt undoes a step with dt in exact arithmetic, so what is left is round-off, grown by the dynamics",
            method.name
        )
    } else {
        format!(
            "{} is not symmetric: a step with -dt does not undo a step with dt, so what is left includes its truncation error of both ways",
            method.name
        )
    }
}
