//! `pendula convergence`: global error against step size on log-log axes, and the fitted
//! order of each method (paper §7.3, §8.3).

use anyhow::Result;
use clap::Args;
use pendula::analysis::{self, fit_order};
use pendula_viz::{Figure, GUIDE, Kind, Scale, axis_label, method_style, with_unit};
use serde_json::json;

use crate::study::{self, Common, OutDir, StepRange, num};

#[derive(Debug, Clone, Args)]
pub struct ConvergenceArgs {
    /// System [default: oscillator].
    pub system: Option<String>,
    /// Comma-separated methods [default: every method that applies].
    #[arg(long, value_name = "LIST")]
    pub methods: Option<String>,
    #[command(flatten)]
    pub steps: StepRange,
    #[command(flatten)]
    pub common: Common,
}

/// The result for one method.
pub struct MethodConvergence {
    pub method: &'static str,
    pub hs: Vec<f64>,
    pub errors: Vec<f64>,
    /// Fitted order over the errors above the round-off floor.
    pub order: Option<f64>,
}

/// Errors below this (relative to the state's size) are round-off, not truncation, and
/// are left out of the fit.
const ROUNDOFF_FLOOR: f64 = 1e-12;

pub fn run(args: &ConvergenceArgs) -> Result<()> {
    let system = args.system.as_deref().unwrap_or("oscillator");
    let values = study::values(system, &args.common.set)?;
    let (hs, t_end) = args.steps.resolve(0.05, 5)?;
    let model = values.build();
    let methods = study::methods(args.methods.as_deref(), &*model, &values, Some(hs[0]))?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "convergence")?;

    let (results, reference) = study_orders(&values, &methods, &hs, t_end)?;

    let mut rows = Vec::new();
    for r in &results {
        for (h, e) in r.hs.iter().zip(&r.errors) {
            rows.push(vec![r.method.to_owned(), num(*h), num(*e)]);
        }
    }
    out.csv("convergence.csv", &["method", "dt", "error"], &rows)?;
    println!("{system}: error at t = {t_end} s against the {}", reference.source);
    let shown: Vec<Vec<String>> = results
        .iter()
        .map(|r| {
            let declared =
                pendula::integrator::find(r.method).map(|m| m.order.to_string()).unwrap_or_default();
            vec![r.method.to_owned(), declared, r.order.map_or("-".into(), |o| format!("{o:.3}"))]
        })
        .collect();
    print!("{}", study::table(&["method", "declared order", "fitted order"], &shown));
    out.figure("convergence", &figure(system, t_end, &results, reference.source))?;
    let orders: serde_json::Map<String, serde_json::Value> =
        results.iter().map(|r| (r.method.to_owned(), json!(r.order))).collect();
    study::summary(
        args.common.summary.as_deref(),
        &json!({ "system": system, "t_end": t_end, "reference": reference.source, "dt": hs, "orders": orders }),
    )?;
    out.report();
    Ok(())
}

/// Errors and fitted orders of `methods` at steps `hs`, against the exact solution or a
/// dop853 reference at tolerance 1e-14.
pub fn study_orders(
    values: &pendula::system::Values,
    methods: &[&'static pendula::integrator::Method],
    hs: &[f64],
    t_end: f64,
) -> Result<(Vec<MethodConvergence>, analysis::Reference)> {
    let model = values.build();
    let reference = analysis::reference_state(&*model, values.initial_state(), t_end)?;
    let scale = reference.state.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
    let bar = study::progress(methods.len() as u64, "convergence");
    let mut results = Vec::new();
    for method in methods {
        let errors = analysis::convergence_errors(
            &*model,
            method,
            values.initial_state(),
            t_end,
            hs,
            &reference.state,
        )?;
        let (fit_h, fit_e): (Vec<f64>, Vec<f64>) = hs
            .iter()
            .zip(&errors)
            .filter(|(_, e)| **e > ROUNDOFF_FLOOR * scale)
            .map(|(h, e)| (*h, *e))
            .unzip();
        let order = fit_order(&fit_h, &fit_e).map(|f| f.order);
        results.push(MethodConvergence { method: method.name, hs: hs.to_vec(), errors, order });
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok((results, reference))
}

/// Error against step on log-log axes, with dashed guides of slope 1, 2 and 4.
pub fn figure(system: &str, t_end: f64, results: &[MethodConvergence], reference: &str) -> Figure {
    let tu = pendula::system::find(system).map_or("s", |i| i.time_unit());
    let mut fig = Figure::new(
        format!("{system}: global error at t = {}, against the {reference}", with_unit(t_end, tu)),
        format!("step size {}", axis_label("h", tu)),
        "max |y(t) − y_ref(t)|",
    )
    .scales(Scale::Log, Scale::Log);
    for r in results {
        let label = match r.order {
            Some(o) => format!("{} (order {o:.2})", r.method),
            None => r.method.to_owned(),
        };
        fig = fig.with_style(
            label,
            method_style(r.method),
            Kind::LineMarkers,
            r.hs.iter().copied().zip(r.errors.iter().copied()).collect(),
        );
    }
    if let Some(first) = results.first() {
        let (h0, h1) = (first.hs[0], first.hs[first.hs.len() - 1]);
        // Near the median error at the first step, so that the guides sit among the data.
        let mut firsts: Vec<f64> = results.iter().map(|r| r.errors[0]).filter(|e| *e > 0.0).collect();
        firsts.sort_by(f64::total_cmp);
        // A factor 30 below it, so that no guide hides a method lying on it.
        let anchor = firsts.get(firsts.len() / 2).copied().unwrap_or(1.0) / 30.0;
        // Dense points: a dashed line is interpolated in data coordinates, which bends on log axes.
        for p in [1, 2, 4] {
            let c = anchor / h0.powi(p);
            let line =
                (0..=24).map(|k| h0 * (h1 / h0).powf(k as f64 / 24.0)).map(|h| (h, c * h.powi(p))).collect();
            let label = if p == 1 { "guides: slopes 1, 2, 4" } else { "" };
            fig = fig.with(label, GUIDE, Kind::Dashed, line);
        }
    }
    fig
}
