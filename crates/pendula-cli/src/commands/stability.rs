//! `pendula stability`: the largest stable step of each method (paper §7.3 "Stability").

use anyhow::Result;
use clap::Args;
use pendula::analysis::{StabilityCriterion, largest_stable_step};
use pendula_viz::{Bar, Bars, Figure, Scale, axis_label, method_color, with_unit};
use serde_json::json;

use crate::args::{Defaults, EndArg, SystemArg};
use crate::limits::{self, Cost, Estimate};
use crate::study::{self, Common, OutDir, num, short};

#[derive(Debug, Clone, Args)]
pub struct StabilityArgs {
    #[command(flatten)]
    pub system: SystemArg,
    #[command(flatten)]
    pub methods: crate::args::MethodsArg,
    #[command(flatten)]
    pub end: EndArg,
    /// Largest allowed relative energy error for a run to count as stable.
    #[arg(long, value_name = "X", allow_hyphen_values = true)]
    pub max_energy_error: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// What stability runs without arguments.
pub const DEFAULTS: Defaults = crate::args::Defaults::of(
    &pendula::study::defaults::STABILITY,
    &[("t_end", "The length of each test run.")],
);

pub fn run(args: &StabilityArgs) -> Result<()> {
    let system = args.system.name(&DEFAULTS);
    let values = study::values(system, &args.common.set.items)?;
    let t_end = args.end.t_end(&DEFAULTS)?;
    let bound = DEFAULTS.positive("max_energy_error", &args.max_energy_error, "a relative error > 0")?;
    let spec = pendula::RunSpec { t0: 0.0, h: 1.0, end: pendula::End::Time(t_end) };
    crate::parse::schedule(&spec, "--t-end", "--t-end")?;
    let model = values.build();
    let methods = args.methods.resolve(&*model)?;
    // What it costs, at most: per method, the bisection's runs (both ends of the range, then
    // halvings of log h to 1%), each as long as a run at the smallest step.
    let runs = 2.0 + ((H_RANGE.1 / H_RANGE.0).ln() / 1.01f64.ln()).log2().ceil();
    let per_run = limits::steps(t_end, H_RANGE.0);
    limits::check(
        "stability",
        args.common.large.allow_large,
        &[Estimate::new(
            Cost::Steps,
            methods.len() as f64 * runs * per_run,
            format!(
                "{} methods x {runs} runs of up to {} steps (h down to {} s over {} s)",
                methods.len(),
                limits::round(per_run),
                H_RANGE.0,
                pendula::error::Short(t_end)
            ),
        )],
    )?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "stability")?;
    let summary = args.common.summary.open()?;
    let criterion = StabilityCriterion { t_end, max_rel_energy_error: bound };
    let results = stable_steps(&values, &methods, &criterion)?;
    let notes: Vec<String> = methods.iter().zip(&results).map(|(m, (_, h))| note(m, *h)).collect();
    let rows: Vec<Vec<String>> = results
        .iter()
        .zip(&notes)
        .map(|((m, h), n)| vec![(*m).to_owned(), h.map_or(String::new(), num), n.clone()])
        .collect();
    out.csv("stability.csv", &["method", "largest_stable_dt", "note"], &rows)?;
    let (h_min, h_max) = H_RANGE;
    sayln!(
        summary,
        "{system}: largest step whose relative energy error (against the energy scale {}) stays <= {bound} over {t_end} s (searched {h_min} .. {h_max} s)",
        short(model.energy_scale(values.initial_state()))
    );
    let shown: Vec<Vec<String>> = results
        .iter()
        .zip(&notes)
        .map(|((m, h), n)| {
            vec![
                (*m).to_owned(),
                h.map_or(format!("< {h_min}"), |h| if h >= h_max { format!(">= {h_max}") } else { short(h) }),
                n.clone(),
            ]
        })
        .collect();
    say!(summary, "{}", study::table(&["method", "largest stable dt (s)", "note"], &shown));
    out.figure("stability", &figure(system, &criterion, &results))?;
    let map: serde_json::Map<String, serde_json::Value> =
        results.iter().map(|(m, h)| ((*m).to_owned(), json!(h))).collect();
    let note_map: serde_json::Map<String, serde_json::Value> =
        results.iter().zip(&notes).map(|((m, _), n)| ((*m).to_owned(), json!(n))).collect();
    // The summary and the files appear together or not at all.
    out.finish_with(summary,
        &json!({ "system": system, "criterion": { "t_end": t_end, "max_rel_energy_error": bound }, "largest_stable_dt": map, "notes": note_map }),
    )?;
    Ok(())
}

/// What the number means, when it is not plainly the stability limit.
pub fn note(method: &pendula::integrator::Method, h: Option<f64>) -> String {
    match (pendula::analysis::accepted_step_limit(method), h) {
        (Some(limit), Some(h)) if h >= limit / 1.01 => format!(
            "refused above h = {} s (binding * h <= 1): stable at every step it accepts",
            short(limit)
        ),
        (_, None) => format!("unstable at every step tried, down to {} s", H_RANGE.0),
        _ => String::new(),
    }
}

/// Search range of the step, s.
pub const H_RANGE: (f64, f64) = (1e-5, 2.0);

/// The largest stable step of each method.
pub fn stable_steps(
    values: &pendula::system::Values,
    methods: &[&'static pendula::integrator::Method],
    criterion: &StabilityCriterion,
) -> Result<Vec<(&'static str, Option<f64>)>> {
    let model = values.build();
    let bar = study::progress(methods.len() as u64, "stability");
    let mut results = Vec::new();
    for method in methods {
        let h =
            largest_stable_step(&*model, method, values.initial_state(), H_RANGE.0, H_RANGE.1, criterion)?;
        results.push((method.name, h));
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(results)
}

/// Largest stable step per method: a bar per method on a log axis over the search range,
/// every method listed, one that is stable at no step tried marked so in words.
pub fn figure(
    system: &str,
    criterion: &StabilityCriterion,
    results: &[(&'static str, Option<f64>)],
) -> Figure {
    let (h_min, h_max) = H_RANGE;
    let tu = pendula::model::find(system).map_or("s", |i| i.time_unit());
    let rows: Vec<Row<'_>> = results
        .iter()
        .map(|(m, h)| {
            let limit = pendula::integrator::find(m).ok().and_then(pendula::analysis::accepted_step_limit);
            let refused = matches!(h, Some(h) if limit.is_some_and(|l| *h >= l / 1.01));
            let note = match h {
                // A refusal is not a stability result: say which it is (the bar is drawn
                // empty and hatched).
                Some(_) if refused => Some(format!(
                    "refused above {} (binding · h ≤ 1); stable below",
                    with_unit(num(limit.unwrap_or_default()), tu)
                )),
                None => Some(format!("unstable at every step tried (down to {})", with_unit(num(h_min), tu))),
                Some(h) if *h >= h_max => Some(format!("≥ {} (the search limit)", with_unit(num(h_max), tu))),
                Some(_) => None,
            };
            Row { method: m, h: *h, note, refused }
        })
        .collect();
    bars_figure(system, criterion, &rows)
}

/// One bar of the stability chart.
pub struct Row<'a> {
    /// The method.
    pub method: &'a str,
    /// Its largest stable step (or refusal limit), if any.
    pub h: Option<f64>,
    /// Printed beside the bar (or in place of a missing one) instead of the value.
    pub note: Option<String>,
    /// The step is where the method refuses to go, not a stability limit: drawn as refused.
    pub refused: bool,
}

/// The bar chart of [`figure`] from its rows: a note, when given, is printed beside the bar
/// (or in place of a missing one) instead of the value; a refused method's bar is empty and
/// hatched.
pub fn bars_figure(system: &str, criterion: &StabilityCriterion, rows: &[Row<'_>]) -> Figure {
    let (bound, t_end) = (criterion.max_rel_energy_error, criterion.t_end);
    let info = pendula::model::find(system).ok();
    let tu = info.map_or("s", |i| i.time_unit());
    let mut bars = Bars::new(
        format!(
            "{system}: largest stable step (relative energy error ≤ {} over {})",
            pendula_viz::number(bound),
            with_unit(t_end, tu)
        ),
        format!("largest stable step {}", axis_label("h", tu)),
        Scale::Log,
    );
    bars.limits = Some(H_RANGE);
    for r in rows {
        let note = r.note.clone().or_else(|| r.h.map(|h| with_unit(pendula_viz::number(h), tu)));
        let bar = Bar::new(r.method, r.h, method_color(r.method), note);
        bars.bars.push(Bar { refused: r.refused, ..bar });
    }
    Figure::from(bars)
}
