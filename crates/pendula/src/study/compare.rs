//! `compare`: several methods on one problem at equal cost or equal step (paper §7.3, §8.3,
//! Figures 6 and 7) — each method's energy error, its growth, its cost, and when a growing
//! error passes a bounded one ([`crate::analysis::compare`]).
//!
//! [`Spec::read`] checks the inputs and the work before any run, [`Spec::run`] runs the
//! methods in parallel (one per core, in the order given) and returns a [`Comparison`]: what
//! every front end presents. The registry's report ([`STUDY`]) carries its table, its
//! sentences and the energy plot; `pendula compare` writes the same comparison as the files
//! it always has (`summary.csv`, the energy, trajectory and phase figures, which `pendula
//! report` reads).

use rayon::prelude::*;

use super::prelude::*;
use crate::Error;
use crate::analysis::compare::{
    Crossover, DEFAULT_EVALS_PER_SECOND, Run, Steps, WINDOWS, compare_one, crossovers, default_t_end,
};
use crate::analysis::{EnergyBalance, Growth, envelope};
use crate::error::{Short, short};
use crate::integrator::Method;
use crate::system::Values;

/// The study's entry in [`super::STUDIES`].
pub const STUDY: Study = Study {
    name: "compare",
    about: "Several methods on one problem at equal cost: energy error, its growth, cost, and when a growing error passes a bounded one",
    params: &[
        Param::system("double", &[]),
        Param::methods(),
        Param {
            name: "evals_per_second",
            help: "The cost given to every method: right-hand-side evaluations per simulated second (a Jacobian counts as one evaluation per state variable); each method's step is chosen to spend it",
            kind: Kind::Real {
                default: DEFAULT_EVALS_PER_SECOND,
                unit: Unit::None,
                domain: Domain::Positive,
            },
        },
        Param {
            name: "dt",
            help: "One step size for every method instead of equal cost",
            kind: Kind::Optional {
                unit: Unit::Time,
                domain: Domain::Positive,
                none: "equal cost, `evals_per_second`",
            },
        },
        Param {
            name: "t_end",
            help: "The end time",
            kind: Kind::Optional {
                unit: Unit::Time,
                domain: Domain::Positive,
                none: "2000 s for the double pendulum (RK4's drift passes the bounded errors), 500 otherwise",
            },
        },
    ],
    files: &["compare", "energy"],
    run,
};

/// A comparison, checked: the system, its methods, how their steps are chosen, the end time.
pub struct Spec {
    /// The system.
    pub values: Values,
    /// The methods, in the order given.
    pub methods: Vec<&'static Method>,
    /// Equal step or equal cost.
    pub steps: Steps,
    /// The end time, s.
    pub t_end: f64,
}

/// What a comparison found.
pub struct Comparison {
    /// What ran.
    pub spec: Spec,
    /// One run per method, in the order given.
    pub runs: Vec<Run>,
    /// When RK4's growing error passes each bounded one.
    pub crossovers: Vec<Crossover>,
    /// The energy scale the errors are relative to (the system's unit of energy).
    pub energy_scale: f64,
}

impl Spec {
    /// Reads and checks the inputs of [`STUDY`] (`args`): the system, the steps, the end
    /// time, the methods, and the work against `budget` — nothing runs before all are checked.
    ///
    /// # Errors
    /// The first input that is not allowed, named; [`Error::TooLarge`] over the budget.
    pub fn read(args: &Args<'_>, budget: &Budget) -> Result<Spec, Error> {
        let values = args.system("system")?;
        let steps = match args.optional("dt")? {
            Some(_) if args.is_given("evals_per_second") => {
                return Err(Error::InvalidInput {
                    name: "dt".into(),
                    value: "given".into(),
                    allowed: "one step for every method, or equal cost with `evals_per_second`: not both"
                        .into(),
                });
            }
            Some(h) => Steps::Equal(h),
            None => Steps::EqualCost(args.real("evals_per_second")?),
        };
        let t_end = match args.optional("t_end")? {
            Some(t) => t,
            None => default_t_end(values.info().name),
        };
        let model = values.build();
        let methods = args.methods("methods", &*model)?;
        drop(model);
        // What it costs: at one step, every method's steps; at equal cost, every method's
        // evaluations, each counted as a step (a step costs at least one).
        let per_method = match steps {
            Steps::Equal(h) => (t_end / h).ceil().max(1.0),
            Steps::EqualCost(n) => (t_end * n).ceil(),
        };
        let how = match steps {
            Steps::Equal(h) => format!(
                "{} methods x {} steps of {} s",
                methods.len(),
                crate::error::approx(per_method),
                Short(h)
            ),
            Steps::EqualCost(n) => {
                format!("{} methods x {} evaluations/s x {} s", methods.len(), Short(n), Short(t_end))
            }
        };
        budget.afford(methods.len() as f64 * per_method, how)?;
        match steps {
            Steps::Equal(h) => {
                super::schedule(h, t_end)?;
            }
            Steps::EqualCost(n) if per_method > crate::simulate::MAX_STEPS => {
                return Err(Error::InvalidInput {
                    name: "t_end".into(),
                    value: Short(t_end).to_string(),
                    allowed: format!("at {} evaluations per second it is more than 10^13 steps", Short(n)),
                });
            }
            Steps::EqualCost(_) => {}
        }
        Ok(Spec { values, methods, steps, t_end })
    }

    /// Runs every method, in parallel, `done` called after each (for progress).
    ///
    /// # Errors
    /// An error that is not one run's own; when every method failed and one numerically,
    /// that failure ([`Error::In`] naming the first such method).
    pub fn run(self, done: impl Fn() + Sync) -> Result<Comparison, Error> {
        let runs = self
            .methods
            .par_iter()
            .map(|method| {
                let run = compare_one(&self.values, method, self.steps, self.t_end);
                done();
                run
            })
            .collect::<Result<Vec<_>, Error>>()?;
        // Every method failed and one numerically: the run's failure, not a table of failures
        // with empty figures.
        if runs.iter().all(|r| r.failed.is_some())
            && let Some(first) = runs.iter().find(|r| r.failed == Some("failed"))
        {
            let context = format!("every method failed; the first, {}", first.method);
            return Err(match first.error.clone() {
                Some(e) => Error::In { context, inner: Box::new(e) },
                None => Error::InvalidInput {
                    name: "methods".into(),
                    value: first.method.into(),
                    allowed: first.failure.clone().unwrap_or_default(),
                },
            });
        }
        let energy_scale = self.values.build().energy_scale(self.values.initial_state());
        Ok(Comparison { crossovers: crossovers(&runs), runs, energy_scale, spec: self })
    }
}

impl Comparison {
    /// The opening sentence: the quantity compared, over what, how the steps were chosen,
    /// and the energy scale the errors are relative to.
    pub fn opening(&self) -> String {
        let Spec { values, steps, t_end, .. } = &self.spec;
        let info = values.info();
        format!(
            "{}: {} over {t_end} {}, {}; relative to the energy scale {} {} ({})",
            info.name,
            EnergyBalance::new(&*values.build(), values.initial_state()).quantity(),
            info.time_unit(),
            match steps {
                Steps::Equal(h) => format!("every method at h = {h}"),
                Steps::EqualCost(n) =>
                    format!("every method at the same cost, {n} evaluations per unit time"),
            },
            short(self.energy_scale),
            info.energy_unit(),
            info.energy_scale,
        )
    }
}

/// A run's growth in a word, or `failed`/`refused` for a run without a result.
pub fn growth_word(r: &Run) -> &'static str {
    r.failed.unwrap_or_else(|| r.growth.map_or("", Growth::word))
}

fn run(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&STUDY, inputs)?;
    let c = Spec::read(&args, budget)?.run(|| ())?;
    let info = c.spec.values.info();
    let (tu, eu) = (info.time_unit(), info.energy_unit());
    let runs = &c.runs;
    let numbers = |f: fn(&Run) -> f64| runs.iter().map(f).collect::<Vec<f64>>();
    // A failed run's counts are missing.
    let counts = |f: fn(&Run) -> u64| -> Vec<f64> {
        runs.iter().map(|r| if r.failed.is_some() { f64::NAN } else { f(r) as f64 }).collect()
    };
    let table = Table {
        name: "compare",
        shown: true,
        columns: vec![
            Column::text("method", runs.iter().map(|r| r.method.to_owned()).collect()),
            Column::numbers("dt", tu, numbers(|r| r.h)),
            Column::whole("steps", counts(|r| r.steps)),
            Column::whole("rhs_evals", counts(|r| r.rhs_evals)),
            Column::whole("cost_evals", counts(|r| r.cost)),
            Column::numbers("wall_s", "s", numbers(|r| r.wall_s)),
            Column::numbers("max_rel_energy_error", "", numbers(|r| r.max_rel_energy_error)),
            Column::numbers("max_abs_energy_error", eu, numbers(|r| r.max_abs_energy_error)),
            Column::numbers("drift_rate", info.rate_unit(), numbers(|r| r.drift_rate)),
            Column::text("growth", runs.iter().map(|r| growth_word(r).to_owned()).collect()),
            Column::text("failure", runs.iter().map(|r| r.failure.clone().unwrap_or_default()).collect()),
        ],
    };
    let mut summary = vec![c.opening()];
    summary.extend(c.crossovers.iter().map(|x| x.sentence(tu)));
    let how = match c.spec.steps {
        Steps::Equal(h) => format!("h = {}{}", Short(h), unit_suffix(tu)),
        Steps::EqualCost(n) => format!("equal cost, {} evaluations per unit time", Short(n)),
    };
    // |error| crosses zero every oscillation; on a log axis its envelope reads better.
    let series = runs
        .iter()
        .filter(|r| !r.energy.is_empty())
        .map(|r| {
            let (t, e): (Vec<f64>, Vec<f64>) = r.energy.iter().copied().unzip();
            let label = match c.spec.steps {
                Steps::Equal(_) => r.method.to_owned(),
                Steps::EqualCost(_) => format!("{} (h = {}{})", r.method, sig(r.h), unit_suffix(tu)),
            };
            Line::of_method(
                r.method,
                label,
                Style::Solid,
                envelope(&t, &e, WINDOWS).iter().map(|(t, e)| [*t, *e]).collect(),
            )
        })
        .collect();
    let plot = Plot::lines(
        "energy",
        format!("{}: relative energy error (envelope), {how}", info.name),
        Axis { label: "t".into(), unit: tu.into(), log: false },
        Axis { label: "max |E(t) − E(0)| / energy scale".into(), unit: String::new(), log: true },
        series,
    );
    let (steps_in, dt_in) = match c.spec.steps {
        Steps::Equal(h) => (Input::Name("none".into()), Input::Number(h)),
        Steps::EqualCost(n) => (Input::Number(n), Input::Name("none".into())),
    };
    let names: Vec<&str> = c.spec.methods.iter().map(|m| m.name).collect();
    Ok(Report {
        study: STUDY.name,
        inputs: vec![
            ("system", Input::Name(info.name.into())),
            ("methods", Input::Name(names.join(","))),
            ("evals_per_second", steps_in),
            ("dt", dt_in),
            ("t_end", Input::Number(c.spec.t_end)),
        ],
        summary,
        numbers: vec![Number {
            key: "energy_scale",
            value: c.energy_scale,
            unit: eu,
            about: "the energy scale the errors are relative to",
        }],
        texts: Vec::new(),
        tables: vec![table],
        plots: vec![plot],
    })
}
