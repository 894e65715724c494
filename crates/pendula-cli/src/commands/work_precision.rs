//! `pendula work-precision`: error against cost — right-hand-side evaluations and wall
//! time — for each method over a range of step sizes, or of tolerances for the adaptive
//! pairs (as DiffEqDevTools' WorkPrecisionSet).

use anyhow::{Result, bail};
use clap::Args;
use pendula::analysis::{self, WorkPoint};
use pendula_viz::{Figure, Kind, Scale, method_style, with_unit};
use serde_json::json;

use crate::args::Defaults;
use crate::parse::parse_count;
use crate::study::{self, Common, OutDir, num, short};
use pendula::integrator::Method;
use pendula::integrator::Scheme;

#[derive(Debug, Clone, Args)]
pub struct WorkPrecisionArgs {
    #[command(flatten)]
    pub accuracy: crate::study::Accuracy,
    /// Loosest tolerance (rtol = atol) for the adaptive methods (dopri5, dop853).
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    pub tol_max: Option<String>,
    /// Tightest tolerance for the adaptive methods, at least 1e-15 (round-off).
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    pub tol_min: Option<String>,
    /// Number of tolerances, geometrically spaced, 2 to 30.
    #[arg(long, value_name = "N")]
    pub tol_levels: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// The tolerances, loosest first, validated.
fn tolerances(args: &WorkPrecisionArgs) -> Result<Vec<f64>> {
    let levels = match &args.tol_levels {
        Some(text) => parse_count("--tol-levels", text, 2, crate::limits::MAX_LEVELS, "tolerances")? as usize,
        None => DEFAULTS.of.count("tol_levels") as usize,
    };
    let hi = DEFAULTS.number("tol_max", &args.tol_max, "a tolerance in (0, 1)")?;
    let lo = DEFAULTS.number("tol_min", &args.tol_min, "a tolerance in (0, 1)")?;
    if !(lo > 0.0 && lo < hi && hi < 1.0) {
        bail!(
            "invalid tolerance range --tol-min {} --tol-max {}: need 0 < tol-min < tol-max < 1",
            short(lo),
            short(hi)
        );
    }
    // Below round-off no step meets the tolerance (the library's bound on rtol).
    if lo < pendula::control::MIN_RTOL {
        bail!(
            "invalid --tol-min {}: must be at least {:e}; a smaller tolerance is below round-off",
            short(lo),
            pendula::control::MIN_RTOL
        );
    }
    Ok(analysis::tolerance_ladder(hi, lo, levels))
}

/// What work-precision runs on without a system named (its methods and steps are its own).
pub const DEFAULTS: Defaults = crate::args::Defaults::of(&pendula::study::defaults::WORK_PRECISION, &[]);

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &[
    "work_precision.csv",
    "work_precision_evals.png",
    "work_precision_evals.svg",
    "work_precision_time.png",
    "work_precision_time.svg",
];

pub fn run(args: &WorkPrecisionArgs) -> Result<()> {
    let system = args.accuracy.system.name(&DEFAULTS);
    let values = study::values(system, &args.common.set.items)?;
    let (ladder, t_end) =
        args.accuracy.steps.resolve_or_default(crate::study::default_t_end(&values), &DEFAULTS)?;
    let tols = tolerances(args)?;
    let model = values.build();
    let methods = args.accuracy.methods.resolve(&*model)?;
    // Fixed-step methods run their steps; the adaptive ones are estimated per tolerance.
    let period = crate::limits::motion_period(&*model, values.initial_state());
    let runs: f64 = methods
        .iter()
        .map(|m| match m.scheme {
            Scheme::Embedded(_) => {
                tols.len() as f64 * crate::limits::adaptive_steps(t_end, period, f64::INFINITY)
            }
            _ => crate::study::steps_for(&values, m, &ladder, t_end)
                .iter()
                .map(|h| crate::limits::steps(t_end, *h))
                .sum(),
        })
        .sum();
    if analysis::nothing_to_run(&methods, |m| crate::study::steps_for(&values, m, &ladder, t_end), true) {
        bail!(
            "work-precision: no step of the methods' default ladders fits --t-end {} within their cost caps (at most 2e6 steps a run); give a shorter --t-end, or the steps (--dt-min, --dt-max, --levels)",
            short(t_end)
        );
    }
    study::check_study(
        "work-precision",
        args.common.large.allow_large,
        &values,
        t_end,
        runs,
        format!("the runs of {} methods to t = {} s", methods.len(), short(t_end)),
    )?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "work-precision", FILES)?;
    let summary = args.common.summary.open()?;
    let reference = analysis::reference_state(&*model, values.initial_state(), t_end)
        .map_err(|e| study::reference_failed(e, t_end))?;
    let bar = study::progress(methods.len() as u64, "work-precision");
    let ladder = |m: &Method| crate::study::steps_for(&values, m, &ladder, t_end);
    let problem =
        analysis::Problem { model: &*model, y0: values.initial_state(), t_end, reference: &reference };
    let results = analysis::work_precision_study(&problem, &methods, ladder, &tols, || bar.inc(1))?;
    bar.finish_and_clear();
    let produced = results.iter().any(|r| !r.points.is_empty());
    let first = analysis::all_dropped(produced, results.iter().map(|r| &r.dropped[..]));
    study::all_failed("work-precision", produced, first.map(|d| d.error.clone()))?;
    // Per method: why some runs are missing (the library's reason), if any are.
    let notes: Vec<Option<String>> =
        results.iter().map(|r| r.dropped.last().map(super::convergence::dropped)).collect();
    let results: Vec<(&'static str, Vec<WorkPoint>)> =
        results.into_iter().map(|r| (r.method.name, r.points)).collect();

    let mut rows = Vec::new();
    for (m, points) in &results {
        for p in points {
            rows.push(vec![
                (*m).to_owned(),
                num(p.h),
                p.tol.map_or(String::new(), num),
                num(p.error),
                p.rhs_evals.to_string(),
                num(p.wall_s),
            ]);
        }
    }
    // For adaptive runs `dt` is the mean accepted step and `tol` the tolerance.
    out.csv("work_precision.csv", &["method", "dt", "tol", "error", "rhs_evals", "wall_s"], &rows)?;
    // For each method: the fewest evaluations that reach an error of 1e-6, if any run did.
    let target = 1e-6;
    let shown: Vec<Vec<String>> = results
        .iter()
        .zip(&notes)
        .map(|((m, points), note)| {
            let best = points.iter().filter(|p| p.error <= target).min_by_key(|p| p.rhs_evals);
            let why = match (best, note) {
                (_, Some(n)) => n.clone(),
                (None, None) => "no run reached 1e-6".to_owned(),
                (Some(_), None) => String::new(),
            };
            vec![
                (*m).to_owned(),
                best.map_or("-".into(), |p| p.rhs_evals.to_string()),
                best.map_or("-".into(), |p| match p.tol {
                    Some(tol) => format!("tol {}", short(tol)),
                    None => format!("dt {}", short(p.h)),
                }),
                short(points.iter().map(|p| p.error).fold(f64::INFINITY, f64::min)),
                why,
            ]
        })
        .collect();
    let unit = values.info().time_unit();
    sayln!(summary, "{system}: error at t = {} {unit} against the {}", short(t_end), reference.source);
    say!(
        summary,
        "{}",
        study::table(&["method", "rhs evals for error <= 1e-6", "at", "smallest error", "note"], &shown)
    );
    for (name, x_label, cost) in [
        (
            "work_precision_evals",
            "right-hand-side evaluations",
            (|p: &WorkPoint| p.rhs_evals as f64) as fn(&WorkPoint) -> f64,
        ),
        ("work_precision_time", "wall time (s)", |p: &WorkPoint| p.wall_s),
    ] {
        let mut fig = Figure::new(
            format!(
                "{system}: work-precision at t = {}, against the {}",
                with_unit(pendula_viz::number(t_end), values.info().time_unit()),
                reference.source
            ),
            x_label,
            "max |y(t) − y_ref(t)|",
        )
        .scales(Scale::Log, Scale::Log);
        for (m, points) in &results {
            fig = fig.with_style(
                *m,
                method_style(m),
                Kind::LineMarkers,
                points.iter().map(|p| (cost(p), p.error)).collect(),
            );
        }
        out.figure(name, &fig)?;
    }
    let doc = json!({
        "system": system, "t_end": t_end, "reference": reference.source,
        "methods": results.iter().map(|(m, points)| ((*m).to_owned(), json!(points.iter().map(|p| json!({
            "dt": p.h, "tol": p.tol, "error": p.error, "rhs_evals": p.rhs_evals, "wall_s": p.wall_s
        })).collect::<Vec<_>>()))).collect::<serde_json::Map<_, _>>(),
    });
    // The summary and the files appear together or not at all.
    out.finish_with(summary, &doc)?;
    Ok(())
}
