//! `pendula compare`: several methods on one problem — energy error, trajectories, phase
//! portraits and cost (paper §7.3, §8.3, Figures 6 and 7). The runs and their analysis
//! (equal-cost steps, growth, crossovers) are the library's [`pendula::analysis::compare`];
//! here are the flags, the table and the figures.

use anyhow::Result;
use clap::Args;
pub use pendula::analysis::compare::{
    Crossover, DEFAULT_EVALS_PER_SECOND, EARLY, GIVE_UP, Run, SAMPLES, Steps, WINDOWS, compare_one,
    crossovers, default_t_end, equal_cost_step, round_sig, round_time,
};
use pendula::analysis::{Growth, envelope};
use pendula::study::compare::growth_word;
use pendula::system::Values;
use pendula_viz::{Figure, Kind, Scale, axis_label, method_style, pretty, with_unit};
use serde_json::json;

use crate::args::{Defaults, SystemArg};
use crate::study::{self, Common, OutDir, num, short};

#[derive(Debug, Clone, Args)]
pub struct CompareArgs {
    #[command(flatten)]
    pub system: SystemArg,
    #[command(flatten)]
    pub methods: crate::args::MethodsArg,
    /// The cost given to every method: right-hand-side evaluations per simulated second
    /// (a Jacobian counts as one evaluation per state variable); each method's step is
    /// chosen to spend it.
    #[arg(long, value_name = "N", conflicts_with = "dt", allow_hyphen_values = true)]
    pub evals_per_second: Option<String>,
    /// One step size for every method instead of equal cost, s.
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub dt: Option<String>,
    /// End time, s.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_end: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// What compare runs on without a system named (its methods and steps are its own).
pub const DEFAULTS: Defaults = crate::args::Defaults::of(&pendula::study::defaults::COMPARE, &[]);

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &[
    "summary.csv",
    "energy.png",
    "energy.svg",
    "trajectory.png",
    "trajectory.svg",
    "phase_*.png",
    "phase_*.svg",
];

pub fn run(args: &CompareArgs) -> Result<()> {
    let system = args.system.name(&DEFAULTS);
    // The flags as the library's study reads them (pendula::study::compare): it checks the
    // inputs and the work before anything is written.
    let study = &pendula::study::compare::STUDY;
    let mut inputs = pendula::study::Inputs::default().name("system", system);
    if let Some(text) = &args.methods.methods {
        inputs = inputs.name("methods", text);
    }
    for (name, flag, text) in [
        ("evals_per_second", "--evals-per-second", &args.evals_per_second),
        ("dt", "--dt", &args.dt),
        ("t_end", "--t-end", &args.t_end),
    ] {
        if let Some(text) = text {
            inputs = inputs.number(name, crate::parse::parse_value(flag, text, None)?);
        }
    }
    if !args.common.set.items.is_empty() {
        inputs.set = crate::parse::parse_settings(pendula::model::find(system)?, &args.common.set.items)?;
    }
    let read = pendula::study::Args::new(study, &inputs).and_then(|a| {
        pendula::study::compare::Spec::read(&a, &crate::studies::budget(args.common.large.allow_large))
    });
    let spec = read.map_err(|e| crate::studies::error(study, e))?;
    let mut out = OutDir::new(args.common.out_dir.as_deref(), "compare", FILES)?;
    let summary = args.common.summary.open()?;

    let bar = study::progress(spec.methods.len() as u64, "compare");
    let comparison = spec.run(|| bar.inc(1)).map_err(|e| crate::studies::error(study, e))?;
    bar.finish_and_clear();
    let (values, steps, t_end) = (&comparison.spec.values, comparison.spec.steps, comparison.spec.t_end);
    let runs = &comparison.runs;

    let header = [
        "method",
        "dt",
        "steps",
        "rhs_evals",
        "cost_evals",
        "wall_s",
        "max_rel_energy_error",
        "max_abs_energy_error",
        "drift_rate",
        "growth",
        "failure",
    ];
    let rows: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            // A failed run's counts are left empty and its growth says `failed`.
            let count = |n: u64| if r.failed.is_some() { String::new() } else { n.to_string() };
            vec![
                r.method.to_owned(),
                num(r.h),
                count(r.steps),
                count(r.rhs_evals),
                count(r.cost),
                num(r.wall_s),
                num(r.max_rel_energy_error),
                num(r.max_abs_energy_error),
                num(r.drift_rate),
                growth_word(r).to_owned(),
                r.failure.clone().unwrap_or_default(),
            ]
        })
        .collect();
    out.csv("summary.csv", &header, &rows)?;
    let model_scale = comparison.energy_scale;
    let info = values.info();
    sayln!(summary, "{}", comparison.opening());
    let shown: Vec<Vec<String>> = runs
        .iter()
        .map(|r| {
            vec![
                r.method.to_owned(),
                short(r.h),
                if r.failed.is_some() { "-".to_owned() } else { r.cost.to_string() },
                format!("{:.3}", r.wall_s),
                short(r.max_rel_energy_error),
                short(r.drift_rate),
                r.failed.unwrap_or_else(|| r.growth.map_or("-", Growth::word)).to_owned(),
                r.failure.clone().unwrap_or_default(),
            ]
        })
        .collect();
    say!(
        summary,
        "{}",
        study::table(
            &["method", "dt", "cost (evals)", "wall s", "max rel. error", "drift 1/s", "error", "note"],
            &shown
        )
    );
    let crossings = &comparison.crossovers;
    for c in crossings {
        sayln!(summary, "{}", c.sentence(info.time_unit()));
    }

    for (name, figure) in figures(values, runs, steps, t_end) {
        out.figure(&name, &figure)?;
    }
    let doc = json!({
        "system": system,
        "steps": match steps {
            Steps::Equal(h) => json!({ "mode": "equal step", "dt": h }),
            Steps::EqualCost(n) => json!({ "mode": "equal cost", "evals_per_second": n }),
        },
        "t_end": t_end,
        "energy_scale": model_scale,
        "energy_scale_definition": info.energy_scale,
        "methods": runs.iter().map(|r| (r.method.to_owned(), json!({
            "status": r.failed.unwrap_or("completed"),
            "dt": r.h,
            "steps": r.failed.is_none().then_some(r.steps),
            "rhs_evals": r.failed.is_none().then_some(r.rhs_evals),
            "cost_evals": r.failed.is_none().then_some(r.cost),
            "wall_s": r.wall_s,
            "max_rel_energy_error": r.max_rel_energy_error, "max_abs_energy_error": r.max_abs_energy_error,
            "drift_rate": r.drift_rate, "growth": r.growth.map(Growth::word), "failure": r.failure,
        }))).collect::<serde_json::Map<_, _>>(),
        "crossovers": crossings.iter().map(|c| json!({
            "growing": c.growing, "bounded": c.bounded, "bound": c.bound, "t": c.t,
            "t_extrapolated": c.extrapolated(), "drift_rate": c.drift_rate,
        })).collect::<Vec<_>>(),
    });
    // The summary and the files appear together or not at all.
    out.finish_with(summary, &doc)?;
    Ok(())
}

/// The energy figure's panel for the runs stopped early for their error (Euler within
/// seconds at a coarse step): each over its own span, which on the whole run's time axis is
/// a streak at t ≈ 0. `None` when no run stopped.
pub fn stopped_panel(system: &str, runs: &[Run], steps: Steps, tu: &str, y_label: &str) -> Option<Figure> {
    let stopped: Vec<&Run> = runs.iter().filter(|r| r.stopped_energy.len() > 1).collect();
    let span = stopped.iter().filter_map(|r| r.stopped_energy.last()).map(|p| p.0).fold(0.0, f64::max);
    if stopped.is_empty() || span <= 0.0 {
        return None;
    }
    let names: Vec<&str> = stopped.iter().map(|r| r.method).collect();
    let mut panel = Figure::new(
        format!(
            "{system}: {} over its own run, to t = {}, where its error reached the energy scale",
            names.join(", "),
            with_unit(pendula_viz::number(span), tu)
        ),
        axis_label("t", tu),
        y_label,
    )
    .scales(Scale::Linear, Scale::Log);
    for r in stopped {
        let label = match steps {
            Steps::Equal(_) => format!(
                "{} (stopped at t = {})",
                r.method,
                with_unit(pendula_viz::number(r.stopped_energy.last()?.0), tu)
            ),
            Steps::EqualCost(_) => format!(
                "{} (h = {}, stopped at t = {})",
                r.method,
                with_unit(pendula_viz::number(r.h), tu),
                with_unit(pendula_viz::number(r.stopped_energy.last()?.0), tu)
            ),
        };
        let (t, e): (Vec<f64>, Vec<f64>) = r.stopped_energy.iter().copied().unzip();
        // An envelope over its own span when it has many samples; every sample when few.
        let points = if t.len() > 2 * WINDOWS {
            // The envelope's points sit at its windows' centres: from the first sample to the
            // one that stopped the run, as the curve itself.
            let mut env = envelope(&t, &e, WINDOWS);
            env.insert(0, r.stopped_energy[0]);
            env.push(*r.stopped_energy.last()?);
            env
        } else {
            r.stopped_energy.clone()
        };
        panel = panel.with_style(label, method_style(r.method), Kind::Line, points);
    }
    Some(panel.with(
        "error = energy scale: the run is stopped",
        pendula_viz::GUIDE,
        Kind::Dashed,
        vec![(0.0, GIVE_UP), (span, GIVE_UP)],
    ))
}

/// Energy error envelope, early trajectories, and one phase portrait per method.
pub fn figures(values: &Values, runs: &[Run], steps: Steps, t_end: f64) -> Vec<(String, Figure)> {
    let info = values.info();
    let dim = info.state.len();
    let n = dim / 2;
    let system = info.name;
    let (q, v) = (&info.state[0], &info.state[n]);
    let angle = q.is_angle();
    let tu = info.time_unit();
    let scale = values.build().energy_scale(values.initial_state());
    let how = match steps {
        Steps::Equal(h) => format!("h = {}", with_unit(h, tu)),
        Steps::EqualCost(n) => format!(
            "equal cost, {} evaluations/{}",
            pendula_viz::number(n),
            if tu.is_empty() { "unit time" } else { tu }
        ),
    };
    // |error| crosses zero every oscillation; on a log axis its envelope reads better.
    let mut energy = Figure::new(
        format!("{system}: relative energy error (envelope), {how}"),
        axis_label("t", tu),
        format!(
            "max |E(t) − E(0)| / energy scale ({})",
            with_unit(pendula_viz::number(scale), info.energy_unit())
        ),
    )
    .scales(Scale::Linear, Scale::Log);
    let t_show = t_end.min(EARLY);
    let mut trajectory = Figure::new(
        format!("{system}: {} against time, {how}", pretty(q.name)),
        axis_label("t", tu),
        axis_label(q.name, q.unit),
    );
    let mut figures = Vec::new();
    for r in runs.iter().filter(|r| !r.energy.is_empty()) {
        let style = method_style(r.method);
        let label = match steps {
            Steps::Equal(_) => r.method.to_owned(),
            Steps::EqualCost(_) => format!("{} (h = {})", r.method, with_unit(pendula_viz::number(r.h), tu)),
        };
        let (t, e): (Vec<f64>, Vec<f64>) = r.energy.iter().copied().unzip();
        energy = energy.with_style(label.clone(), style, Kind::Line, envelope(&t, &e, WINDOWS));
        let rows = r.trajectory.chunks(dim + 1);
        trajectory = trajectory.with_style(
            label,
            style,
            Kind::Line,
            r.early.chunks(dim + 1).take_while(|row| row[0] <= t_show).map(|row| (row[0], row[1])).collect(),
        );
        let wrap = |x: f64| if angle { pendula::system::wrap_angle(x) } else { x };
        let q_label = axis_label(q.name, q.unit);
        let phase = Figure::new(
            format!(
                "{system}: phase portrait with {}, h = {}, t ≤ {}",
                r.method,
                with_unit(pendula_viz::number(r.h), tu),
                with_unit(pendula_viz::number(t_end), tu)
            ),
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
    if let Some(panel) = stopped_panel(system, runs, steps, tu, &energy.y_label) {
        energy = energy.with_panel(panel);
    }
    // Every method may have failed before its first step (all refused): no curves to draw.
    if !energy.series.is_empty() {
        figures.insert(0, ("trajectory".to_owned(), trajectory));
        figures.insert(0, ("energy".to_owned(), energy));
    }
    figures
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Euler at h = 0.05 s on the pendulum is stopped within seconds of a 500 s run: the
    /// energy figure's panel draws it over its own span, from its first sample to the step
    /// that stopped it, with a legend entry; a method that ran to the end is not in it.
    #[test]
    fn the_energy_figure_shows_a_stopped_run_over_its_own_span() {
        let values = crate::study::values("pendulum", &[]).unwrap();
        let steps = Steps::Equal(0.05);
        let runs: Vec<Run> = ["euler", "verlet"]
            .iter()
            .map(|m| compare_one(&values, pendula::integrator::find(m).unwrap(), steps, 500.0).unwrap())
            .collect();
        let (euler, verlet) = (&runs[0], &runs[1]);
        let stop = euler.stopped_energy.last().unwrap().0;
        assert!(stop > 1.0 && stop < 10.0, "stopped at {stop}");
        assert!(euler.failure.as_deref().unwrap().contains("stopped at t = "), "{:?}", euler.failure);
        assert!(verlet.stopped_energy.is_empty() && verlet.failure.is_none());
        // Every step of its short run (64 steps, about 13 of them in the thinned series).
        assert!(euler.stopped_energy.len() as f64 >= stop / 0.05, "{}", euler.stopped_energy.len());

        let figures = figures(&values, &runs, steps, 500.0);
        let energy = &figures.iter().find(|(n, _)| n == "energy").unwrap().1;
        // On the main chart Euler's curve covers under 1% of the 500 s axis: the streak.
        let main = energy.series.iter().find(|s| s.label == "euler").unwrap();
        assert!(main.points.iter().all(|p| p.0 <= stop + 0.05 && p.0 < 0.01 * 500.0));
        let panel = energy.panel.as_ref().expect("a panel for the stopped run");
        assert_eq!(panel.x_label, energy.x_label);
        assert_eq!(panel.y_label, energy.y_label);
        let curve = panel.series.iter().find(|s| s.label.starts_with("euler (stopped at t = ")).unwrap();
        let (x0, x1) =
            curve.points.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
        assert_eq!(x0, euler.stopped_energy[0].0);
        assert_eq!(x1, stop);
        assert!(x0 <= 0.05, "{x0}");
        // Its error grows over the panel to the energy scale, where the run was stopped.
        assert!(curve.points[0].1 < 0.1 && curve.points.last().unwrap().1 > GIVE_UP);
        assert!(panel.series.iter().all(|s| !s.label.starts_with("verlet")));
        // Nothing stopped, no panel.
        let figures = figures_of_verlet(&values, &runs[1..], steps);
        assert!(figures.panel.is_none());
    }

    fn figures_of_verlet(values: &Values, runs: &[Run], steps: Steps) -> Figure {
        figures(values, runs, steps, 500.0).into_iter().find(|(n, _)| n == "energy").unwrap().1
    }
}
