//! `convergence` and `work-precision`: the accuracy studies over several methods (paper
//! §7.3, §8.3), run by [`crate::analysis::accuracy`] against one reference state — the exact
//! solution, or dop853 at tolerance 1e-14.
//!
//! - **convergence**: the global error at `t_end` against the step, on log-log axes, and the
//!   order fitted where the errors are in the asymptotic range (between saturation and the
//!   round-off floor, on a straight stretch), found without reference to the declared order;
//!   a method with no such range is reported with the reason.
//! - **work-precision**: the same errors against what they cost — right-hand-side
//!   evaluations and wall time — with the adaptive pairs (dopri5, dop853) over tolerances, as
//!   DiffEqDevTools' `WorkPrecisionSet`.
//!
//! On defaults the horizon and the steps are chosen per system and per method: the horizon
//! is the system's study horizon (a few small-oscillation periods, short of chaos's
//! growth), and each method runs a ladder of halved steps that starts where its order needs
//! it and stops at a cost cap. The steps may be given instead, the same for every method:
//! as a list (`dts`) or as a geometric ladder (`dt_min`, `dt_max`, `levels`).

use super::prelude::*;
use crate::Error;
use crate::analysis::{self, Dropped, MethodConvergence, Problem, Reference, WorkPoint};
use crate::error::{Short, short};
use crate::integrator::Method;
use crate::system::Values;

/// The convergence study's entry in [`super::STUDIES`].
pub const CONVERGENCE: Study = Study {
    name: "convergence",
    about: "Global error against step size on log-log axes, and the fitted order of each method",
    params: &[Param::system("oscillator", &[]), METHODS, DTS, DT_MIN, DT_MAX, LEVELS, T_END],
    files: &["convergence", "orders", "fits"],
    run: convergence,
};

/// The work-precision study's entry in [`super::STUDIES`].
pub const WORK_PRECISION: Study = Study {
    name: "work-precision",
    about: "Error against cost (right-hand-side evaluations and wall time) for each method over its steps or tolerances",
    params: &[
        Param::system("pendulum", &[]),
        METHODS,
        DTS,
        DT_MIN,
        DT_MAX,
        LEVELS,
        TOLS,
        Param {
            name: "tol_max",
            help: "The loosest tolerance (rtol = atol) of the adaptive methods (dopri5, dop853)",
            kind: Kind::Real { default: 1e-3, unit: Unit::None, domain: Domain::Positive },
        },
        Param {
            name: "tol_min",
            help: "The tightest tolerance, at least 1e-15 (round-off)",
            kind: Kind::Real { default: 1e-12, unit: Unit::None, domain: Domain::Positive },
        },
        Param {
            name: "tol_levels",
            help: "The number of tolerances, geometrically spaced",
            kind: Kind::Count { default: 10, min: 2, max: MAX_LEVELS, of: "tolerances" },
        },
        T_END,
    ],
    files: &["work_precision", "costs", "work_precision_evals", "work_precision_time"],
    run: work_precision,
};

/// The most steps (or tolerances) of a ladder: beyond it the runs only repeat the curve.
const MAX_LEVELS: u64 = 30;

/// The largest step of a given ladder when only its smallest step or its length is given, s.
const LADDER_DT_MAX: f64 = 0.05;

/// The error whose cost work-precision's table quotes.
const TARGET_ERROR: f64 = 1e-6;

const METHODS: Param = Param::methods();

const DTS: Param = Param {
    name: "dts",
    help: "The steps, the same for every method (not with `dt_min`, `dt_max`, `levels`)",
    kind: Kind::Reals {
        unit: Unit::Time,
        domain: Domain::Positive,
        none: "each method's own ladder of halved steps, or the ladder `dt_min`, `dt_max`, `levels` when one of them is given",
    },
};

const DT_MIN: Param = Param {
    name: "dt_min",
    help: "The smallest step of a geometric ladder, the same for every method",
    kind: Kind::Optional { unit: Unit::Time, domain: Domain::Positive, none: "`dt_max` / 2^(`levels` - 1)" },
};

const DT_MAX: Param = Param {
    name: "dt_max",
    help: "The largest step of a geometric ladder",
    kind: Kind::Optional {
        unit: Unit::Time,
        domain: Domain::Positive,
        none: "0.05 when `dt_min` or `levels` is given; without any of them (or `dts`) each method runs its own ladder of halved steps, from where its order needs it to a cost cap",
    },
};

const LEVELS: Param = Param {
    name: "levels",
    help: "The number of steps of a geometric ladder",
    kind: Kind::Count { default: 5, min: 2, max: MAX_LEVELS, of: "step sizes" },
};

const TOLS: Param = Param {
    name: "tols",
    help: "The tolerances (rtol = atol) of the adaptive methods, each from 1e-15 (round-off) to 1 (not with `tol_max`, `tol_min`, `tol_levels`)",
    kind: Kind::Reals {
        unit: Unit::None,
        domain: Domain::Positive,
        none: "`tol_levels` tolerances from `tol_max` to `tol_min`, geometric",
    },
};

const T_END: Param = Param {
    name: "t_end",
    help: "The end time at which the error is measured",
    kind: Kind::Optional {
        unit: Unit::Time,
        domain: Domain::Positive,
        none: "the system's study horizon, a few small-oscillation periods (short of chaos's growth)",
    },
};

/// What both studies run: the system, its methods, their steps and the end time.
struct Setup {
    values: Values,
    methods: Vec<&'static Method>,
    /// The steps of every method, when given; `None`: each method's own ladder.
    given: Option<Vec<f64>>,
    t_end: f64,
    time_scale: f64,
}

impl Setup {
    /// Reads and checks the system, the end time and the steps (and, in work-precision, the
    /// tolerances, read by `tolerances` after the steps), then the methods.
    fn read(args: &Args<'_>, tolerances: impl FnOnce() -> Result<(), Error>) -> Result<Setup, Error> {
        let values = args.system("system")?;
        let t_end = match args.optional("t_end")? {
            Some(t) => t,
            None => analysis::study_horizon(&values),
        };
        let ladder = ["dt_min", "dt_max", "levels"].iter().any(|n| args.is_given(n));
        let given = match args.reals("dts")? {
            Some(dts) if ladder => {
                return Err(Error::InvalidInput {
                    name: "dts".into(),
                    value: crate::error::clip(&Input::Numbers(dts).to_string(), 60),
                    allowed:
                        "give the steps as `dts` or as a ladder (`dt_min`, `dt_max`, `levels`), not both"
                            .into(),
                });
            }
            Some(dts) => {
                for h in &dts {
                    fits("dts", *h, t_end)?;
                }
                Some(dts)
            }
            None if ladder => Some(geometric(args, t_end)?),
            None => None,
        };
        tolerances()?;
        let model = values.build();
        let methods = args.methods("methods", &*model)?;
        let time_scale = model.time_scale();
        drop(model);
        let setup = Setup { values, methods, given, t_end, time_scale };
        if analysis::nothing_to_run(&setup.methods, |m| setup.ladder(m), false) {
            return Err(Error::InvalidInput {
                name: "t_end".into(),
                value: Short(t_end).to_string(),
                allowed: "no step of the methods' default ladders fits within their cost caps (at most 2e6 steps a run); give a shorter `t_end`, or the steps (`dts`, or `dt_min`, `dt_max`, `levels`)".into(),
            });
        }
        Ok(setup)
    }

    /// The steps `method` runs.
    fn ladder(&self, method: &Method) -> Vec<f64> {
        match &self.given {
            Some(hs) => hs.clone(),
            None => analysis::method_ladder(method, self.time_scale, self.t_end),
        }
    }

    /// Refuses the study over `budget`: `runs` steps (`how` says of what), and the reference
    /// run's (none where the model has an exact solution; else dop853 at tolerance 1e-14, at
    /// least [`super::ADAPTIVE_STEPS_PER_PERIOD`] steps a period).
    fn afford(&self, budget: &Budget, runs: f64, how: String) -> Result<(), Error> {
        let model = self.values.build();
        let y0 = self.values.initial_state();
        let reference = if model.exact(self.t_end, y0).is_some() {
            0.0
        } else {
            super::adaptive_steps(self.t_end, super::motion_period(&*model, y0), f64::INFINITY)
        };
        let what = format!("{how}, and {} for the reference run", crate::error::approx(reference));
        budget.afford(runs + reference, what)
    }

    /// The steps of a fixed-step run to the end time.
    fn steps(&self, h: f64) -> f64 {
        (self.t_end / h).ceil().max(1.0)
    }

    /// The reference state at the end time.
    fn reference(&self) -> Result<Reference, Error> {
        let model = self.values.build();
        analysis::reference_state(&*model, self.values.initial_state(), self.t_end).map_err(|e| Error::In {
            context: format!(
                "the reference run (dop853 at tolerance {:e} to t = {}{}) failed",
                analysis::REFERENCE_TOLERANCE,
                Short(self.t_end),
                unit_suffix(self.values.info().time_unit())
            ),
            inner: Box::new(e),
        })
    }

    /// The inputs as the study ran them.
    fn inputs(&self, args: &Args<'_>) -> Result<Vec<(&'static str, Input)>, Error> {
        let none = || Input::Name("none".into());
        let names: Vec<&str> = self.methods.iter().map(|m| m.name).collect();
        let ladder = ["dt_min", "dt_max", "levels"].iter().any(|n| args.is_given(n));
        let (dts, dt_min, dt_max, levels) = match &self.given {
            Some(hs) if ladder => (
                none(),
                Input::Number(hs[hs.len() - 1]),
                Input::Number(hs[0]),
                Input::Number(hs.len() as f64),
            ),
            Some(hs) => (Input::Numbers(hs.clone()), none(), none(), none()),
            None => (none(), none(), none(), none()),
        };
        Ok(vec![
            ("system", Input::Name(self.values.info().name.into())),
            ("methods", Input::Name(names.join(","))),
            ("dts", dts),
            ("dt_min", dt_min),
            ("dt_max", dt_max),
            ("levels", levels),
        ])
    }

    /// The opening sentence: what was measured against what.
    fn opening(&self, reference: &Reference) -> String {
        let info = self.values.info();
        format!(
            "{}: error at t = {}{} against the {}",
            info.name,
            short(self.t_end),
            unit_suffix(info.time_unit()),
            reference.source
        )
    }
}

/// The geometric ladder of `dt_min`, `dt_max` and `levels`, largest step first.
fn geometric(args: &Args<'_>, t_end: f64) -> Result<Vec<f64>, Error> {
    let levels = args.count("levels")? as usize;
    let dt_max = args.optional("dt_max")?.unwrap_or(LADDER_DT_MAX);
    let dt_min = args.optional("dt_min")?.unwrap_or(dt_max / 2f64.powi(levels as i32 - 1));
    if dt_min >= dt_max {
        return Err(Error::InvalidInput {
            name: "dt_min".into(),
            value: Short(dt_min).to_string(),
            allowed: format!("must be smaller than `dt_max` {}", Short(dt_max)),
        });
    }
    fits("dt_min", dt_min, t_end)?;
    Ok((0..levels).map(|i| dt_max * (dt_min / dt_max).powf(i as f64 / (levels - 1) as f64)).collect())
}

/// Refuses a step `h` (given as `name`) too small for a run to `t_end` (10^13 steps).
fn fits(name: &str, h: f64, t_end: f64) -> Result<(), Error> {
    super::schedule(h, t_end).map(|_| ()).map_err(|e| match e {
        Error::InvalidInput { value, allowed, .. } => {
            Error::InvalidInput { name: name.into(), value, allowed }
        }
        Error::InvalidValue { value, allowed, .. } => {
            Error::InvalidValue { name: name.into(), value, allowed }
        }
        e => e,
    })
}

/// The error of a study whose every run was dropped: a numerical failure named as the
/// first one (exit 1 from the CLI), or the refusal of the first step.
fn every_run_dropped<'a>(
    produced: bool,
    dropped: impl IntoIterator<Item = &'a [Dropped]>,
) -> Result<(), Error> {
    match analysis::all_dropped(produced, dropped) {
        Some(first) if first.error.is_numerical() => Err(Error::In {
            context: format!("every run failed; the first, {} {}", first.method.name, first.note()),
            inner: Box::new(first.why()),
        }),
        Some(first) => Err(first.why()),
        None => Ok(()),
    }
}

/// ", fixed steps" for an embedded pair (dopri5, dop853): a convergence study runs it at
/// fixed steps, without its error control, so its curve measures the order of the formula it
/// advances with, not its behaviour at a tolerance (that is work-precision's).
fn fixed_steps(method: &Method) -> &'static str {
    if method.adaptive() { ", fixed steps" } else { "" }
}

fn convergence(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&CONVERGENCE, inputs)?;
    let s = Setup::read(&args, || Ok(()))?;
    let (runs, levels) = s.methods.iter().fold((0.0, 0), |(n, k), m| {
        let hs = s.ladder(m);
        (n + hs.iter().map(|h| s.steps(*h)).sum::<f64>(), k + hs.len())
    });
    let tu = s.values.info().time_unit();
    s.afford(
        budget,
        runs,
        format!("{levels} runs of {} methods to t = {}{}", s.methods.len(), Short(s.t_end), unit_suffix(tu)),
    )?;
    let reference = s.reference()?;
    let model = s.values.build();
    let problem =
        Problem { model: &*model, y0: s.values.initial_state(), t_end: s.t_end, reference: &reference };
    let results = analysis::convergence_study(&problem, &s.methods, |m| s.ladder(m), || ())?;
    every_run_dropped(results.iter().any(|r| !r.hs.is_empty()), results.iter().map(|r| &r.dropped[..]))?;

    let per_point = |f: &dyn Fn(&MethodConvergence, usize) -> f64| -> Vec<f64> {
        results.iter().flat_map(|r| (0..r.hs.len()).map(move |i| f(r, i))).collect()
    };
    let points = Table {
        name: "convergence",
        shown: false,
        columns: vec![
            Column::text(
                "method",
                results.iter().flat_map(|r| r.hs.iter().map(|_| r.method.name.to_owned())).collect(),
            ),
            Column::numbers("dt", tu, per_point(&|r, i| r.hs[i])),
            Column::numbers("error", "", per_point(&|r, i| r.errors[i])),
        ],
    };
    let names = || results.iter().map(|r| r.method.name.to_owned()).collect::<Vec<_>>();
    let fitted = |f: fn(&analysis::OrderEstimate) -> Option<f64>| -> Vec<f64> {
        results.iter().map(|r| f(&r.estimate).unwrap_or(f64::NAN)).collect()
    };
    let orders = Table {
        name: "orders",
        shown: true,
        columns: vec![
            Column::text("method", names()),
            Column::whole("declared_order", results.iter().map(|r| f64::from(r.method.order)).collect()),
            Column::numbers("fitted_order", "", fitted(|e| e.order())).printed_to(3),
            Column::text("note", results.iter().map(|r| r.note(short, Dropped::note)).collect()),
        ],
    };
    use analysis::OrderEstimate::Fitted;
    let fits = Table {
        name: "fits",
        shown: false,
        columns: vec![
            Column::text("method", names()),
            Column::whole(
                "points",
                fitted(|e| match e {
                    Fitted { points, .. } => Some(*points as f64),
                    _ => Some(0.0),
                }),
            ),
            Column::numbers(
                "dt_min",
                tu,
                fitted(|e| match e {
                    Fitted { h_min, .. } => Some(*h_min),
                    _ => None,
                }),
            ),
            Column::numbers(
                "dt_max",
                tu,
                fitted(|e| match e {
                    Fitted { h_max, .. } => Some(*h_max),
                    _ => None,
                }),
            ),
            Column::text("label", results.iter().map(|r| r.estimate.label()).collect()),
            Column::text(
                "reason",
                results.iter().map(|r| r.estimate.reason().unwrap_or("").to_owned()).collect(),
            ),
            Column::text(
                "failure",
                results.iter().map(|r| r.dropped.last().map(Dropped::note).unwrap_or_default()).collect(),
            ),
        ],
    };
    let n_fitted = results.iter().filter(|r| r.order().is_some()).count();
    let fits_sentence = if n_fitted == 1 && results.len() == 1 {
        "The method has an order fitted in the asymptotic range".to_owned()
    } else if n_fitted == results.len() {
        format!("Each of the {n_fitted} methods has an order fitted in the asymptotic range")
    } else {
        format!(
            "{n_fitted} of {} methods have an order fitted in the asymptotic range; the table says why the others have none",
            results.len()
        )
    };
    let summary = vec![s.opening(&reference), fits_sentence];
    let plot = convergence_plot(&s, &results, reference.source);
    let mut report_inputs = s.inputs(&args)?;
    report_inputs.push(("t_end", Input::Number(s.t_end)));
    Ok(Report {
        study: CONVERGENCE.name,
        inputs: report_inputs,
        summary,
        numbers: vec![Number {
            key: "fitted_methods",
            value: n_fitted as f64,
            unit: "",
            about: "the methods with an order fitted in the asymptotic range",
        }],
        texts: vec![("reference", reference.source.to_owned())],
        tables: vec![points, orders, fits],
        plots: vec![plot],
    })
}

/// Error against step on log-log axes, with guides of slope 1, 2 and 4.
fn convergence_plot(s: &Setup, results: &[MethodConvergence], reference: &str) -> Plot {
    let info = s.values.info();
    let tu = info.time_unit();
    let mut series: Vec<Line> = results
        .iter()
        .filter(|r| !r.hs.is_empty())
        .map(|r| {
            Line::of_method(
                r.method.name,
                format!("{}{} ({})", r.method.name, fixed_steps(r.method), r.estimate.label()),
                Style::LineMarkers,
                r.hs.iter().zip(&r.errors).map(|(h, e)| [*h, *e]).collect(),
            )
        })
        .collect();
    let all_h = results.iter().flat_map(|r| r.hs.iter().copied());
    let (h0, h1) = all_h.fold((f64::NEG_INFINITY, f64::INFINITY), |(a, b), h| (a.max(h), b.min(h)));
    if h0.is_finite() && h1 < h0 {
        // Near the median error at each method's first step, so that the guides sit among the
        // data, and a factor 30 below it, so that no guide hides a method lying on it.
        let mut firsts: Vec<f64> =
            results.iter().filter_map(|r| r.errors.first().copied()).filter(|e| *e > 0.0).collect();
        firsts.sort_by(f64::total_cmp);
        let anchor = firsts.get(firsts.len() / 2).copied().unwrap_or(1.0) / 30.0;
        // Guides end where the data does: below the smallest error they would only stretch the
        // axis. Dense points: a dashed line is interpolated in data coordinates, which bends on
        // log axes.
        let floor = results
            .iter()
            .flat_map(|r| r.errors.iter().copied())
            .filter(|e| *e > 0.0)
            .fold(f64::INFINITY, f64::min);
        for p in [1, 2, 4] {
            let c = anchor / h0.powi(p);
            let line = (0..=24)
                .map(|k| h0 * (h1 / h0).powf(f64::from(k) / 24.0))
                .map(|h| [h, c * h.powi(p)])
                .filter(|[_, e]| *e >= floor)
                .collect();
            series.push(Line::new(format!("slope {p}"), Style::Guide, line));
        }
    }
    Plot::lines(
        "convergence",
        format!(
            "{}: global error at t = {}{}, against the {reference}",
            info.name,
            sig(s.t_end),
            unit_suffix(tu)
        ),
        Axis { label: "step size h".into(), unit: tu.into(), log: true },
        Axis { label: "max |y(t) − y_ref(t)|".into(), unit: super::state_units(info), log: true },
        series,
    )
}

fn work_precision(inputs: &Inputs, budget: &Budget) -> Result<Report, Error> {
    let args = Args::new(&WORK_PRECISION, inputs)?;
    let mut tols = Vec::new();
    let s = Setup::read(&args, || {
        tols = tolerances(&args)?;
        Ok(())
    })?;
    let model = s.values.build();
    let period = super::motion_period(&*model, s.values.initial_state());
    // Fixed-step methods run their steps; the adaptive ones are estimated per tolerance.
    let runs: f64 = s
        .methods
        .iter()
        .map(|m| {
            if m.adaptive() {
                tols.len() as f64 * super::adaptive_steps(s.t_end, period, f64::INFINITY)
            } else {
                s.ladder(m).iter().map(|h| s.steps(*h)).sum()
            }
        })
        .sum();
    let tu = s.values.info().time_unit();
    s.afford(
        budget,
        runs,
        format!("the runs of {} methods to t = {}{}", s.methods.len(), Short(s.t_end), unit_suffix(tu)),
    )?;
    let reference = s.reference()?;
    let problem =
        Problem { model: &*model, y0: s.values.initial_state(), t_end: s.t_end, reference: &reference };
    let results = analysis::work_precision_study(&problem, &s.methods, |m| s.ladder(m), &tols, || ())?;
    every_run_dropped(results.iter().any(|r| !r.points.is_empty()), results.iter().map(|r| &r.dropped[..]))?;

    let all = |f: fn(&WorkPoint) -> f64| -> Vec<f64> {
        results.iter().flat_map(|r| r.points.iter().map(f)).collect()
    };
    let points = Table {
        name: "work_precision",
        shown: false,
        columns: vec![
            Column::text(
                "method",
                results.iter().flat_map(|r| r.points.iter().map(|_| r.method.name.to_owned())).collect(),
            ),
            // For adaptive runs `dt` is the mean accepted step and `tol` the tolerance.
            Column::numbers("dt", tu, all(|p| p.h)),
            Column::numbers("tol", "", all(|p| p.tol.unwrap_or(f64::NAN))),
            Column::numbers("error", "", all(|p| p.error)),
            Column::whole("rhs_evals", all(|p| p.rhs_evals as f64)),
            Column::numbers("wall_s", "s", all(|p| p.wall_s)),
        ],
    };
    // For each method: the fewest evaluations that reach the target error, if any run did.
    let best: Vec<Option<&WorkPoint>> = results
        .iter()
        .map(|r| r.points.iter().filter(|p| p.error <= TARGET_ERROR).min_by_key(|p| p.rhs_evals))
        .collect();
    let costs = Table {
        name: "costs",
        shown: true,
        columns: vec![
            Column::text("method", results.iter().map(|r| r.method.name.to_owned()).collect()),
            Column::whole(
                "evals_to_target",
                best.iter().map(|b| b.map_or(f64::NAN, |p| p.rhs_evals as f64)).collect(),
            ),
            Column::text(
                "at",
                best.iter()
                    .map(|b| match b {
                        Some(WorkPoint { tol: Some(tol), .. }) => format!("tol {}", short(*tol)),
                        Some(p) => format!("dt {}", short(p.h)),
                        None => "-".to_owned(),
                    })
                    .collect(),
            ),
            Column::numbers(
                "smallest_error",
                "",
                results
                    .iter()
                    .map(|r| r.points.iter().map(|p| p.error).fold(f64::INFINITY, f64::min))
                    .collect(),
            ),
            Column::text(
                "failure",
                results.iter().map(|r| r.dropped.last().map(Dropped::note).unwrap_or_default()).collect(),
            ),
        ],
    };
    let mut summary = vec![s.opening(&reference)];
    let cheapest = results
        .iter()
        .zip(&best)
        .filter_map(|(r, b)| b.map(|p| (r.method.name, p)))
        .min_by_key(|(_, p)| p.rhs_evals);
    summary.push(match cheapest {
        Some((m, p)) => format!(
            "To bring the error to {} or below the cheapest is {m}, with {} right-hand-side evaluations",
            Short(TARGET_ERROR),
            p.rhs_evals
        ),
        None => format!("No run brought the error to {} or below", Short(TARGET_ERROR)),
    });
    let title = format!(
        "{}: work-precision at t = {}{}, against the {}",
        s.values.info().name,
        sig(s.t_end),
        unit_suffix(tu),
        reference.source
    );
    let plot = |name: &'static str, x: Axis, cost: fn(&WorkPoint) -> f64| {
        let series = results
            .iter()
            .map(|r| {
                Line::of_method(
                    r.method.name,
                    r.method.name,
                    Style::LineMarkers,
                    r.points.iter().map(|p| [cost(p), p.error]).collect(),
                )
            })
            .collect();
        let y = Axis {
            label: "max |y(t) − y_ref(t)|".into(),
            unit: super::state_units(s.values.info()),
            log: true,
        };
        Plot::lines(name, title.clone(), x, y, series)
    };
    let plots = vec![
        plot(
            "work_precision_evals",
            Axis { label: "right-hand-side evaluations".into(), unit: String::new(), log: true },
            |p| p.rhs_evals as f64,
        ),
        plot("work_precision_time", Axis { label: "wall time".into(), unit: "s".into(), log: true }, |p| {
            p.wall_s
        }),
    ];
    let mut report_inputs = s.inputs(&args)?;
    let given_tols = args.reals("tols")?.is_some();
    report_inputs.extend([
        ("tols", if given_tols { Input::Numbers(tols.clone()) } else { Input::Name("none".into()) }),
        ("tol_max", Input::Number(tols[0])),
        ("tol_min", Input::Number(tols[tols.len() - 1])),
        ("tol_levels", Input::Number(tols.len() as f64)),
        ("t_end", Input::Number(s.t_end)),
    ]);
    Ok(Report {
        study: WORK_PRECISION.name,
        inputs: report_inputs,
        summary,
        numbers: vec![Number {
            key: "target_error",
            value: TARGET_ERROR,
            unit: "",
            about: "the error whose cost the table quotes",
        }],
        texts: vec![("reference", reference.source.to_owned())],
        tables: vec![points, costs],
        plots,
    })
}

/// The tolerances of the adaptive methods, loosest first: `tols`, or `tol_levels` of them
/// from `tol_max` to `tol_min`, geometric.
fn tolerances(args: &Args<'_>) -> Result<Vec<f64>, Error> {
    let round_off = |name: &str, tol: f64| -> Result<(), Error> {
        if (crate::control::MIN_RTOL..1.0).contains(&tol) {
            Ok(())
        } else {
            Err(Error::InvalidInput {
                name: name.into(),
                value: Short(tol).to_string(),
                allowed: format!(
                    "a tolerance in [{:e}, 1) (a smaller one is below round-off)",
                    crate::control::MIN_RTOL
                ),
            })
        }
    };
    if let Some(tols) = args.reals("tols")? {
        if let Some(other) = ["tol_max", "tol_min", "tol_levels"].into_iter().find(|n| args.is_given(n)) {
            return Err(Error::InvalidInput {
                name: "tols".into(),
                value: crate::error::clip(&Input::Numbers(tols).to_string(), 60),
                allowed: format!("give the tolerances as `tols` or as a ladder (`{other}`), not both"),
            });
        }
        for tol in &tols {
            round_off("tols", *tol)?;
        }
        return Ok(tols);
    }
    let levels = args.count("tol_levels")? as usize;
    let (hi, lo) = (args.real("tol_max")?, args.real("tol_min")?);
    round_off("tol_max", hi)?;
    if lo >= hi {
        return Err(Error::InvalidInput {
            name: "tol_min".into(),
            value: Short(lo).to_string(),
            allowed: format!("must be smaller than `tol_max` {}", Short(hi)),
        });
    }
    round_off("tol_min", lo)?;
    Ok(analysis::tolerance_ladder(hi, lo, levels))
}
