//! `pendula compare`: several methods on one problem — energy error, trajectories, phase
//! portraits and cost (paper §7.3, §8.3, Figures 6 and 7).

use std::time::Instant;

use anyhow::Result;
use clap::Args;
use pendula::analysis::{EnergySeries, drift_rate, envelope};
use pendula::observe::{Every, Recorder};
use pendula::{End, RunSpec};
use pendula_viz::{Figure, Kind, Scale, axis_label, method_style, pretty, with_unit};
use serde_json::json;

use crate::config::f64_arg;
use crate::study::{self, Common, OutDir, num, short};

#[derive(Debug, Clone, Args)]
pub struct CompareArgs {
    /// System [default: double].
    pub system: Option<String>,
    /// Comma-separated methods [default: every method that applies].
    #[arg(long, value_name = "LIST")]
    pub methods: Option<String>,
    /// Step size, s [default: 0.01].
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub dt: Option<String>,
    /// End time, s [default: 100].
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_end: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// One method's run.
pub struct Run {
    pub method: &'static str,
    pub steps: u64,
    pub rhs_evals: u64,
    pub wall_s: f64,
    pub max_rel_energy_error: f64,
    pub drift_rate: f64,
    /// Where it failed, if it did.
    pub failure: Option<String>,
    pub energy: Vec<(f64, f64)>,
    pub trajectory: Vec<f64>,
}

/// Samples kept per series: enough for a smooth curve, few enough for a light SVG.
const SAMPLES: u64 = 2000;

pub fn run(args: &CompareArgs) -> Result<()> {
    let system = args.system.as_deref().unwrap_or("double");
    let values = study::values(system, &args.common.set)?;
    let h = f64_arg("--dt", args.dt.as_deref(), 0.01, "a step size in seconds")?;
    let t_end = f64_arg("--t-end", args.t_end.as_deref(), 100.0, "an end time in seconds")?;
    let spec = RunSpec { t0: 0.0, h, end: End::Time(t_end) };
    spec.schedule()?;
    let model = values.build();
    let methods = study::methods(args.methods.as_deref(), &*model, &values, Some(h))?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "compare")?;

    let bar = study::progress(methods.len() as u64, "compare");
    let mut runs = Vec::new();
    for method in &methods {
        runs.push(compare_one(&values, method, &spec)?);
        bar.inc(1);
    }
    bar.finish_and_clear();

    let header = ["method", "dt", "steps", "rhs_evals", "wall_s", "max_rel_energy_error", "drift_rate"];
    let rows: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            vec![
                r.method.to_owned(),
                num(h),
                r.steps.to_string(),
                r.rhs_evals.to_string(),
                num(r.wall_s),
                num(r.max_rel_energy_error),
                num(r.drift_rate),
            ]
        })
        .collect();
    out.csv("summary.csv", &header, &rows)?;
    let shown: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            vec![
                r.method.to_owned(),
                r.steps.to_string(),
                r.rhs_evals.to_string(),
                format!("{:.3}", r.wall_s),
                short(r.max_rel_energy_error),
                short(r.drift_rate),
                r.failure.clone().unwrap_or_default(),
            ]
        })
        .collect();
    print!(
        "{}",
        study::table(&["method", "steps", "rhs evals", "wall s", "max |dE/E0|", "drift 1/s", "note"], &shown)
    );

    for (name, figure) in figures(&values, &runs, h, t_end) {
        out.figure(&name, &figure)?;
    }
    let doc = json!({
        "system": system,
        "dt": h,
        "t_end": t_end,
        "methods": runs.iter().map(|r| (r.method.to_owned(), json!({
            "steps": r.steps, "rhs_evals": r.rhs_evals, "wall_s": r.wall_s,
            "max_rel_energy_error": r.max_rel_energy_error, "drift_rate": r.drift_rate,
            "failure": r.failure,
        }))).collect::<serde_json::Map<_, _>>(),
    });
    study::summary(args.common.summary.as_deref(), &doc)?;
    out.report();
    Ok(())
}

/// Runs one method, keeping ~2000 samples of its energy error and trajectory. A run that
/// fails numerically (Euler blowing up) is kept up to its failure and reported, not fatal.
pub fn compare_one(
    values: &pendula::system::Values,
    method: &'static pendula::integrator::Method,
    spec: &RunSpec,
) -> Result<Run> {
    let model = values.build();
    let steps = spec.schedule()?.steps;
    let every = (steps / SAMPLES).max(1);
    let mut energy = EnergySeries::new(&*model, values.initial_state(), every);
    let mut traj = Every { n: every, inner: Recorder::default() };
    let start = Instant::now();
    let result = model.solve(method, values.initial_state(), spec, &mut (&mut energy, &mut traj));
    let wall_s = start.elapsed().as_secs_f64();
    let (steps, rhs_evals, failure) = match result {
        Ok(report) => (report.outcome.steps(), report.rhs_evals, None),
        Err(e @ (pendula::Error::NonFinite { .. } | pendula::Error::NewtonDidNotConverge { .. })) => {
            (0, 0, Some(e.to_string()))
        }
        Err(e) => return Err(e.into()),
    };
    Ok(Run {
        method: method.name,
        steps,
        rhs_evals,
        wall_s,
        max_rel_energy_error: energy.max_abs,
        drift_rate: drift_rate(&energy.t, &energy.error),
        failure,
        energy: energy.t.iter().copied().zip(energy.error.iter().map(|e| e.abs())).collect(),
        trajectory: traj.inner.rows,
    })
}

/// Energy error envelope, early trajectories, and one phase portrait per method.
pub fn figures(values: &pendula::system::Values, runs: &[Run], h: f64, t_end: f64) -> Vec<(String, Figure)> {
    let info = values.info();
    let dim = info.state.len();
    let n = dim / 2;
    let system = info.name;
    let (q, v) = (&info.state[0], &info.state[n]);
    let angle = q.is_angle();
    let tu = info.time_unit();
    let step = with_unit(h, tu);
    // |error| crosses zero every oscillation; on a log axis its envelope reads better.
    let mut energy = Figure::new(
        format!(
            "{system}: relative energy error (envelope over windows of {}), h = {step}",
            with_unit(pendula_viz::number(t_end / 300.0), tu)
        ),
        axis_label("t", tu),
        "max |E(t) − E(0)| / energy scale",
    )
    .scales(Scale::Linear, Scale::Log);
    let t_show = t_end.min(20.0);
    let mut trajectory = Figure::new(
        format!("{system}: {} against time, h = {step}", pretty(q.name)),
        axis_label("t", tu),
        axis_label(q.name, q.unit),
    );
    let mut figures = Vec::new();
    for r in runs {
        let style = method_style(r.method);
        let (t, e): (Vec<f64>, Vec<f64>) = r.energy.iter().copied().unzip();
        energy = energy.with_style(r.method, style, Kind::Line, envelope(&t, &e, 300));
        let rows = r.trajectory.chunks(dim + 1);
        trajectory = trajectory.with_style(
            r.method,
            style,
            Kind::Line,
            rows.clone().take_while(|row| row[0] <= t_show).map(|row| (row[0], row[1])).collect(),
        );
        let wrap = |x: f64| if angle { pendula::system::wrap_angle(x) } else { x };
        let q_label = axis_label(q.name, q.unit);
        let phase = Figure::new(
            format!("{system}: phase portrait with {}, h = {step}, t ≤ {}", r.method, with_unit(t_end, tu)),
            if angle { format!("{q_label}, wrapped to [−π, π)") } else { q_label },
            axis_label(v.name, v.unit),
        )
        .with(
            r.method,
            style.color,
            Kind::Dots,
            rows.map(|row| (wrap(row[1]), row[1 + n])).collect(),
        );
        figures.push((format!("phase_{}", r.method), phase));
    }
    figures.insert(0, ("trajectory".to_owned(), trajectory));
    figures.insert(0, ("energy".to_owned(), energy));
    figures
}
