//! `energy-budget`: the energy balance of one run. Damping and drives change a system's
//! energy E by the work W(t) = ∫₀ᵗ P dt of its non-conservative forces (P =
//! [`crate::system::Model::power`]), so E(t) − E(0) − W(t) vanishes along every exact
//! solution; what a run leaves of it is the integrator's error. The report gives E, W and
//! the balance against t (about 2000 samples), and the largest |balance| in the system's
//! energy unit and against its energy scale ([`crate::system::Model::energy_scale`]).
//!
//! W is integrated by Simpson's rule on each step, with the midpoint from the step's cubic
//! Hermite interpolant ([`crate::analysis::EnergyBalance`]).

use std::ops::ControlFlow;

use super::prelude::*;
use crate::analysis::EnergyBalance;
use crate::error::Short;
use crate::observe::{Flow, Observer, Sample};
use crate::{End, Error, RunSpec};

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "energy-budget",
    about: "The energy balance E(t) - E(0) - W(t) of one run: the energy, the work of damping and drive, and what the integrator leaves of their balance",
    params: &[
        // A damped double pendulum: the forces do work, so each term of the budget shows.
        Param::system("double", &[("damping", 0.1)]),
        Param::method("rk4"),
        Param::time("dt", "The step size", 1e-3),
        Param::time("t_end", "The end time", 20.0),
    ],
    files: &["energy-budget", "energy-balance"],
    run,
};

/// About how many rows the table keeps.
const SAMPLES: u64 = 2000;

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let (values, method, dt, t_end) = Args::new(&STUDY, inputs)?.one_run()?;
    let spec = RunSpec { t0: 0.0, h: dt, end: End::Time(t_end) };
    let schedule = super::schedule(dt, t_end)?;
    budget.afford(schedule.steps as f64, format!("a run of {} steps", schedule.steps))?;
    let model = values.build();
    let info = values.info();

    let y0 = values.initial_state();
    let mut watch = Watch {
        balance: EnergyBalance::new(&*model, y0),
        every: (schedule.steps / SAMPLES).max(1),
        rows: [Vec::new(), Vec::new(), Vec::new(), Vec::new()],
    };
    model.solve(method, y0, &spec, &mut watch)?;
    let Watch { balance, rows: [t, energy, work, error], .. } = watch;

    let (eu, tu) = (info.energy_unit(), info.time_unit());
    let change: Vec<f64> = energy.iter().map(|e| e - balance.initial).collect();
    let system = describe(&values);
    let mut summary = vec![format!(
        "{system}, {} at dt = {}{} to t = {}{}: E went from {} {eu} to {} {eu}; the non-conservative forces did W = {} {eu} of work",
        method.name,
        Short(dt),
        unit_suffix(tu),
        Short(t_end),
        unit_suffix(tu),
        sig(balance.initial),
        sig(balance.last),
        sig(balance.work),
    )];
    summary.push(if balance.forced {
        format!(
            "The balance E(t) - E(0) - W(t), zero along exact solutions, stays within {} {eu} ({} of the energy scale {} {eu}): the integrator's error",
            sig(balance.max_abs),
            sig(balance.max_rel()),
            sig(balance.scale)
        )
    } else {
        format!(
            "No damping or drive: W = 0 and the balance is the energy error, within {} {eu} ({} of the energy scale {} {eu})",
            sig(balance.max_abs),
            sig(balance.max_rel()),
            sig(balance.scale)
        )
    });
    let numbers = vec![
        Number { key: "initial_energy", value: balance.initial, unit: eu, about: "E(0)" },
        Number { key: "final_energy", value: balance.last, unit: eu, about: "E at the end" },
        Number { key: "work", value: balance.work, unit: eu, about: "W at the end" },
        Number { key: "max_balance", value: balance.max_abs, unit: eu, about: "max |E(t) - E(0) - W(t)|" },
        Number { key: "energy_scale", value: balance.scale, unit: eu, about: "the energy scale" },
        Number {
            key: "max_balance_rel",
            value: balance.max_rel(),
            unit: "",
            about: "max |balance| / energy scale",
        },
    ];
    let points = |ys: &[f64]| -> Vec<[f64; 2]> { t.iter().zip(ys).map(|(t, y)| [*t, *y]).collect() };
    let time = Axis { label: "t".into(), unit: tu.into(), log: false };
    let plots = vec![
        Plot::lines(
            "energy-budget",
            format!("{system}: energy change and work ({})", method.name),
            time.clone(),
            Axis { label: "energy".into(), unit: eu.into(), log: false },
            vec![
                Line::new("E(t) - E(0)", Style::Solid, points(&change)),
                Line::new("W(t)", Style::Dashed, points(&work)),
            ],
        ),
        Plot::lines(
            "energy-balance",
            format!(
                "{system}: balance E(t) - E(0) - W(t) ({}, dt = {}{})",
                method.name,
                Short(dt),
                unit_suffix(tu)
            ),
            time,
            Axis { label: "E - E(0) - W".into(), unit: eu.into(), log: false },
            vec![Line::new("balance", Style::Solid, points(&error))],
        ),
    ];
    let table = Table {
        name: "energy-budget",
        shown: false,
        columns: vec![
            Column::numbers("t", tu, t),
            Column::numbers("energy", eu, energy),
            Column::numbers("work", eu, work),
            Column::numbers("balance", eu, error),
        ],
    };
    Ok(Report {
        study: STUDY.name,
        inputs: run_inputs(&values, method, dt, t_end),
        summary,
        numbers,
        texts: Vec::new(),
        tables: vec![table],
        plots,
    })
}

/// The system's name with the settings that differ from its catalogue defaults.
fn describe(values: &crate::system::Values) -> String {
    let info = values.info();
    let changed: Vec<String> = info
        .parameters
        .iter()
        .filter(|q| values.get(q.name) != q.default)
        .map(|q| format!("{} = {}{}", q.name, Short(values.get(q.name)), unit_suffix(q.unit)))
        .collect();
    if changed.is_empty() { info.name.to_owned() } else { format!("{} ({})", info.name, changed.join(", ")) }
}

/// Tracks the balance at every step and keeps (t, E, W, balance) every `every` steps and at
/// the end.
struct Watch<'a> {
    balance: EnergyBalance<'a>,
    every: u64,
    rows: [Vec<f64>; 4],
}

impl Observer for Watch<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        let error = self.balance.track(s.t, s.y, s.energy);
        if s.step.is_multiple_of(self.every) || s.last {
            for (row, v) in self.rows.iter_mut().zip([s.t, self.balance.last, self.balance.work, error]) {
                row.push(v);
            }
        }
        ControlFlow::Continue(())
    }
}
