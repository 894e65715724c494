//! `pendula convergence`: global error against step size on log-log axes, and the fitted
//! order of each method (paper §7.3, §8.3).
//!
//! On defaults the horizon and the steps are chosen per system and per method: the horizon
//! is the system's `study_periods` small-oscillation periods (short of chaos's growth), and
//! each method runs a ladder of halved steps that starts where its order needs it and stops
//! at a cost cap. The order is fitted where the errors are in the asymptotic range — between
//! saturation and the round-off floor, on a straight stretch — found without reference to
//! the declared order; a method with no such range is reported with the reason.

use anyhow::Result;
use clap::Args;
use pendula::analysis::{self, MethodConvergence};
use pendula::integrator::Method;
use pendula::system::Values;
use pendula_viz::{Figure, GUIDE, Kind, Scale, axis_label, method_style, with_unit};
use serde_json::json;

use crate::args::Defaults;
use crate::study::{self, Common, Ladder, OutDir, default_t_end, num, short, steps_for};

#[derive(Debug, Clone, Args)]
pub struct ConvergenceArgs {
    #[command(flatten)]
    pub accuracy: crate::study::Accuracy,
    #[command(flatten)]
    pub common: Common,
}

/// Why a run was dropped, in the CLI's words: the step is `h`.
pub fn dropped(d: &analysis::Dropped) -> String {
    format!("at {} = {}: {}", if d.adaptive { "tol" } else { "h" }, short(d.x), d.error)
}

/// The table's note for one method ([`MethodConvergence::note`] in the CLI's words).
pub fn note(r: &MethodConvergence) -> String {
    r.note(short, dropped)
}

/// What convergence runs on without a system named (its methods and steps are its own).
pub const DEFAULTS: Defaults = crate::args::Defaults::of(&pendula::study::defaults::CONVERGENCE, &[]);

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &["convergence.csv", "convergence.png", "convergence.svg"];

pub fn run(args: &ConvergenceArgs) -> Result<()> {
    let system = args.accuracy.system.name(&DEFAULTS);
    let values = study::values(system, &args.common.set.items)?;
    let (ladder, t_end) = args.accuracy.steps.resolve_or_default(default_t_end(&values), &DEFAULTS)?;
    let model = values.build();
    let methods = args.accuracy.methods.resolve(&*model)?;
    let (runs, levels) = methods.iter().fold((0.0, 0), |(n, k), m| {
        let hs = steps_for(&values, m, &ladder, t_end);
        (n + hs.iter().map(|h| crate::limits::steps(t_end, *h)).sum::<f64>(), k + hs.len())
    });
    if analysis::nothing_to_run(&methods, |m| steps_for(&values, m, &ladder, t_end), false) {
        anyhow::bail!(
            "convergence: no step of the methods' default ladders fits --t-end {} within their cost caps (at most 2e6 steps a run); give a shorter --t-end, or the steps (--dt-min, --dt-max, --levels)",
            short(t_end)
        );
    }
    study::check_study(
        "convergence",
        args.common.large.allow_large,
        &values,
        t_end,
        runs,
        format!("{} runs of {} methods to t = {} s", levels, methods.len(), short(t_end)),
    )?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "convergence", FILES)?;
    let summary = args.common.summary.open()?;

    let (results, reference) = study_orders(&values, &methods, &ladder, t_end)?;

    let mut rows = Vec::new();
    for r in &results {
        for (h, e) in r.hs.iter().zip(&r.errors) {
            rows.push(vec![r.method.name.to_owned(), num(*h), num(*e)]);
        }
    }
    out.csv("convergence.csv", &["method", "dt", "error"], &rows)?;
    let unit = values.info().time_unit();
    sayln!(summary, "{system}: error at t = {} {unit} against the {}", short(t_end), reference.source);
    let shown: Vec<Vec<String>> = results
        .iter()
        .map(|r| {
            let declared = r.method.order.to_string();
            vec![
                r.method.name.to_owned(),
                declared,
                r.order().map_or("-".into(), |o| format!("{o:.3}")),
                note(r),
            ]
        })
        .collect();
    say!(summary, "{}", study::table(&["method", "declared order", "fitted order", "note"], &shown));
    out.figure("convergence", &figure(system, t_end, &results, reference.source))?;
    let orders: serde_json::Map<String, serde_json::Value> =
        results.iter().map(|r| (r.method.name.to_owned(), json!(r.order()))).collect();
    let notes: serde_json::Map<String, serde_json::Value> =
        results.iter().map(|r| (r.method.name.to_owned(), json!(note(r)))).collect();
    let dts: serde_json::Map<String, serde_json::Value> =
        results.iter().map(|r| (r.method.name.to_owned(), json!(r.hs))).collect();
    // The summary and the files appear together or not at all.
    out.finish_with(summary,
        &json!({ "system": system, "t_end": t_end, "reference": reference.source, "dt": dts, "orders": orders, "notes": notes }),
    )?;
    Ok(())
}

/// Errors and fitted orders of `methods` ([`analysis::convergence_study`]), against the
/// exact solution or a dop853 reference at tolerance 1e-14.
pub fn study_orders(
    values: &Values,
    methods: &[&'static Method],
    ladder: &Ladder,
    t_end: f64,
) -> Result<(Vec<MethodConvergence>, analysis::Reference)> {
    let model = values.build();
    let y0 = values.initial_state();
    let reference =
        analysis::reference_state(&*model, y0, t_end).map_err(|e| study::reference_failed(e, t_end))?;
    let bar = study::progress(methods.len() as u64, "convergence");
    let problem = analysis::Problem { model: &*model, y0, t_end, reference: &reference };
    let results = analysis::convergence_study(
        &problem,
        methods,
        |m| steps_for(values, m, ladder, t_end),
        || bar.inc(1),
    )?;
    bar.finish_and_clear();
    let produced = results.iter().any(|r| !r.hs.is_empty());
    let first = analysis::all_dropped(produced, results.iter().map(|r| &r.dropped[..]));
    study::all_failed("convergence", produced, first.map(|d| d.error.clone()))?;
    Ok((results, reference))
}

/// ", fixed steps" for an embedded pair (dopri5, dop853): a convergence study runs it at
/// fixed steps, without its error control, so its curve measures the order of the formula it
/// advances with, not its behaviour at a tolerance (that is work-precision's).
pub fn fixed_steps(method: &str) -> &'static str {
    if pendula::integrator::find(method).is_ok_and(|m| m.adaptive()) { ", fixed steps" } else { "" }
}

/// Error against step on log-log axes, with guides of slope 1, 2 and 4 (thin, dashed, grey,
/// each named "slope p" at its end, outside the legend).
pub fn figure(system: &str, t_end: f64, results: &[MethodConvergence], reference: &str) -> Figure {
    let tu = pendula::model::find(system).map_or("s", |i| i.time_unit());
    let mut fig = Figure::new(
        format!(
            "{system}: global error at t = {}, against the {reference}",
            with_unit(pendula_viz::number(t_end), tu)
        ),
        format!("step size {}", axis_label("h", tu)),
        "max |y(t) − y_ref(t)|",
    )
    .scales(Scale::Log, Scale::Log);
    for r in results.iter().filter(|r| !r.hs.is_empty()) {
        let label = format!("{}{} ({})", r.method.name, fixed_steps(r.method.name), r.estimate.label());
        fig = fig.with_style(
            label,
            method_style(r.method.name),
            Kind::LineMarkers,
            r.hs.iter().copied().zip(r.errors.iter().copied()).collect(),
        );
    }
    let all_h = results.iter().flat_map(|r| r.hs.iter().copied());
    let (h0, h1) = all_h.fold((f64::NEG_INFINITY, f64::INFINITY), |(a, b), h| (a.max(h), b.min(h)));
    if h0.is_finite() && h1 < h0 {
        // Near the median error at each method's first step, so that the guides sit among the
        // data, and a factor 30 below it, so that no guide hides a method lying on it.
        let mut firsts: Vec<f64> =
            results.iter().filter_map(|r| r.errors.first().copied()).filter(|e| *e > 0.0).collect();
        firsts.sort_by(f64::total_cmp);
        let anchor = firsts.get(firsts.len() / 2).copied().unwrap_or(1.0) / 30.0;
        // Dense points: a dashed line is interpolated in data coordinates, which bends on log axes.
        // Guides end where the data does: below the smallest error they would only stretch the axis.
        let floor = results
            .iter()
            .flat_map(|r| r.errors.iter().copied())
            .filter(|e| *e > 0.0)
            .fold(f64::INFINITY, f64::min);
        for p in [1, 2, 4] {
            let c = anchor / h0.powi(p);
            let line = (0..=24)
                .map(|k| h0 * (h1 / h0).powf(k as f64 / 24.0))
                .map(|h| (h, c * h.powi(p)))
                .filter(|(_, e)| *e >= floor)
                .collect();
            // A guide, not data: thin, dashed, grey, named on the line and not in the legend.
            fig = fig.with(format!("slope {p}"), GUIDE, Kind::Guide, line);
        }
    }
    fig
}
