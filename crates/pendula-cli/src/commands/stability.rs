//! `pendula stability`: the largest stable step of each method (paper §7.3 "Stability").

use anyhow::Result;
use clap::Args;
use pendula::analysis::{StabilityCriterion, largest_stable_step};
use pendula_viz::{Figure, Kind, Legend, Scale, method_color};
use serde_json::json;

use crate::config::f64_arg;
use crate::study::{self, Common, OutDir, Summary, num, short};

#[derive(Debug, Clone, Args)]
pub struct StabilityArgs {
    /// System [default: pendulum].
    pub system: Option<String>,
    /// Comma-separated methods [default: every method that applies].
    #[arg(long, value_name = "LIST")]
    pub methods: Option<String>,
    /// Length of each test run, s [default: 20].
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_end: Option<String>,
    /// Largest allowed relative energy error for a run to count as stable [default: 0.1].
    #[arg(long, value_name = "X", allow_hyphen_values = true)]
    pub max_energy_error: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

pub fn run(args: &StabilityArgs) -> Result<()> {
    let system = args.system.as_deref().unwrap_or("pendulum");
    let values = study::values(system, &args.common.set)?;
    let t_end = f64_arg("--t-end", args.t_end.as_deref(), 20.0, "a time in seconds")?;
    let bound = f64_arg("--max-energy-error", args.max_energy_error.as_deref(), 0.1, "a relative error > 0")?;
    if !(bound.is_finite() && bound > 0.0) {
        anyhow::bail!("invalid --max-energy-error {bound}: must be finite and > 0");
    }
    let spec = pendula::RunSpec { t0: 0.0, h: 1.0, end: pendula::End::Time(t_end) };
    crate::config::schedule(&spec, "--t-end", "--t-end")?;
    let model = values.build();
    let methods = study::methods(args.methods.as_deref(), &*model, &values, None)?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "stability")?;
    let summary = Summary::open(args.common.summary.as_deref())?;
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
    summary.write(
        &json!({ "system": system, "criterion": { "t_end": t_end, "max_rel_energy_error": bound }, "largest_stable_dt": map, "notes": note_map }),
    )?;
    out.finish()?;
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

/// Largest stable step per method, on a log axis.
pub fn figure(
    system: &str,
    criterion: &StabilityCriterion,
    results: &[(&'static str, Option<f64>)],
) -> Figure {
    let (bound, t_end) = (criterion.max_rel_energy_error, criterion.t_end);
    let mut fig = Figure::new(
        format!("{system}: largest stable step (|dE/E0| <= {bound} over {t_end} s)"),
        "method (position in the table)",
        "largest stable step h (s)",
    )
    .scales(Scale::Linear, Scale::Log)
    .legend(Legend::LowerRight);
    for (i, (m, h)) in results.iter().enumerate() {
        if let Some(h) = h {
            fig = fig.with(*m, method_color(m), Kind::Markers, vec![(i as f64 + 1.0, *h)]);
        }
    }
    fig
}
