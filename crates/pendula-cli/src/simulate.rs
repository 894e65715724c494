//! `pendula simulate`: one system, one method, a trajectory and a summary.

use std::io::Write;
use std::ops::ControlFlow;
use std::time::Instant;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use pendula::analysis::EnergyBalance;
use pendula::error::Short;
use pendula::events::{EndAtEvent, EventLocator, EventSpec};
use pendula::observe::{Every, Ignore, Observer, Resample, Sample};
use serde_json::{Map, Value, json};

use crate::cli::SimulateArgs;
use crate::config::{self, Output, SimulateConfig};
use crate::output::{AtomicFile, Sink};
use crate::study::Summary;

/// Writes the states it is shown as rows (t, state, energy), and keeps them for `--plot`.
struct Writer<'a> {
    model: &'a dyn pendula::system::DynModel,
    sink: Sink,
    rows: u64,
    /// The rows, flat, when the run is to be drawn.
    kept: Option<Vec<f64>>,
    failure: Option<anyhow::Error>,
}

impl Observer for Writer<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> ControlFlow<()> {
        let e = s.energy.unwrap_or_else(|| self.model.energy(s.t, s.y));
        let row = || std::iter::once(s.t).chain(s.y.iter().copied()).chain(std::iter::once(e));
        if let Err(err) = self.sink.row(row()) {
            self.failure = Some(err);
            return ControlFlow::Break(());
        }
        if let Some(kept) = &mut self.kept {
            kept.extend(row());
        }
        self.rows += 1;
        ControlFlow::Continue(())
    }
}

/// A progress bar over simulated time (stderr, drawn only on a terminal) for runs longer
/// than half a second, looked at every 4096 steps: a per-step check of one bit pattern.
struct Progress {
    bar: Option<ProgressBar>,
    start: Instant,
    t0: f64,
    span: f64,
}

/// Ticks of the bar from t0 to t_end.
const PROGRESS_TICKS: u64 = 1000;

impl Progress {
    fn new(t0: f64, t_end: f64) -> Self {
        Progress { bar: None, start: Instant::now(), t0, span: t_end - t0 }
    }

    fn at(&mut self, step: u64, t: f64) {
        if !step.is_multiple_of(4096) {
            return;
        }
        let bar = match &self.bar {
            Some(bar) => bar,
            // A short run finishes before a bar would be read: none is drawn.
            None if self.start.elapsed().as_secs_f64() < 0.5 => return,
            None => {
                let bar = ProgressBar::new(PROGRESS_TICKS);
                bar.set_style(
                    ProgressStyle::with_template("simulate [{bar:30}] {percent:>3}% {elapsed} (eta {eta})")
                        .expect("valid template")
                        .progress_chars("=> "),
                );
                self.bar.insert(bar)
            }
        };
        let done = ((t - self.t0) / self.span).clamp(0.0, 1.0);
        bar.set_position((done * PROGRESS_TICKS as f64) as u64);
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Observer for Progress {
    fn observe(&mut self, s: &Sample<'_>) -> ControlFlow<()> {
        self.at(s.step, s.t);
        ControlFlow::Continue(())
    }
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    let config = config::simulate(args)?;
    let SimulateConfig { values, method, spec, tolerances, first_step, every, out, summary, grid, plot } =
        &config;
    let info = values.info();
    // Open the outputs first: a path that cannot be written fails before the work.
    let out_file = match out {
        Some(Output::Csv(p) | Output::Npy(p)) => Some(AtomicFile::create(p, "--out")?),
        Some(Output::Stdout) => {
            crate::output::claim_stdout("--out")?;
            None
        }
        None => None,
    };
    // `--summary -` prints the summary on stdout (config refuses it with `--out -`).
    let summary_out = Summary::open(summary.as_deref())?;
    let plot_file = plot.as_deref().map(|p| AtomicFile::create(p, "--plot")).transpose()?;

    let mut columns = vec!["t"];
    columns.extend(info.state.iter().map(|q| q.name));
    columns.push("energy");
    let model = values.build();
    // The energy error relative to the system's scale, or for damped and driven runs the
    // energy balance E − E(0) − W.
    let mut energy = EnergyBalance::new(&*model, values.initial_state());
    let mut progress = Progress::new(spec.t0, spec.schedule()?.t_end);
    let mut writer = Writer {
        model: &*model,
        sink: Sink::new(out.as_ref(), out_file.as_ref(), &columns)?,
        rows: 0,
        kept: plot.is_some().then(Vec::new),
        failure: None,
    };
    let specs = args
        .events
        .iter()
        .map(|e| EventSpec::parse(e, &*model, args.stop_on_event))
        .collect::<Result<Vec<_>, _>>()?;
    let watch_events = !specs.is_empty();
    // Rows: on the --output-dt / --t-eval grid, or every N-th step and the last (a plot
    // without a trajectory file draws every step).
    let (mut on_grid, mut thinned, mut none);
    let rows: &mut dyn Observer = match (grid, every.or(plot.is_some().then_some(1))) {
        (Some(g), _) => {
            on_grid = Resample::new(g.clone(), info.state.len(), &mut writer);
            &mut on_grid
        }
        (None, Some(n)) => {
            thinned = Every { n, inner: &mut writer };
            &mut thinned
        }
        (None, None) => {
            none = Ignore;
            &mut none
        }
    };
    // The energy is tracked at every step; a terminal event ends the run, and the rows, at
    // the event's time and state.
    let mut watch =
        EndAtEvent { events: EventLocator::new(&*model, specs), inner: (&mut energy, (rows, &mut progress)) };
    // Without events the locator is left out: one call per step less on the fast paths.
    let observers: &mut dyn Observer = if watch_events { &mut watch } else { &mut watch.inner };
    let start = Instant::now();
    let report = match tolerances {
        Some(tol) => {
            let t_end = spec.schedule()?.t_end;
            model.solve_adaptive(method, values.initial_state(), t_end, *first_step, tol, observers)
        }
        // The double pendulum with RK4 takes the ensemble engine's single-trajectory kernel.
        // It implements the free equations: damped or driven runs take the general path.
        None if info.name == "double" && method.name == "rk4" && !double(values).is_forced() => {
            pendula::ensemble::rk4_trajectory(&double(values), values.initial_state(), spec, observers)
        }
        None => model.solve(method, values.initial_state(), spec, observers),
    };
    let wall_s = start.elapsed().as_secs_f64();
    let EndAtEvent { events, .. } = watch;
    progress.finish();
    if let Some(err) = writer.failure.take() {
        return Err(err);
    }
    let report = report?;
    let energy_unit = info.energy_unit();
    let rows = writer.rows;
    writer.sink.finish()?;
    // A run stopped by an event ends at the event, not at the end of the step past it.
    let (t_end, final_y) = match events.stopped_at() {
        Some(e) => (e.t, e.state.as_slice()),
        None => (report.outcome.t(), report.state.as_slice()),
    };
    if let (Some(file), Some(kept)) = (&plot_file, &writer.kept) {
        let title = format!("{} with {}", info.name, method.name);
        let trajectory = crate::commands::plot::Trajectory::of_run(info, kept.clone(), title);
        let bytes = crate::commands::plot::draw(
            &trajectory.default_panels()?,
            plot.as_deref().expect("a plot path"),
        )?;
        file.write_all(&bytes)?;
    }

    let mut final_state = Map::new();
    final_state.insert("t".into(), json!(t_end));
    for (q, v) in info.state.iter().zip(final_y) {
        final_state.insert(q.name.into(), json!(v));
    }
    let mut initial = Map::new();
    for (q, v) in info.state.iter().zip(values.initial_state()) {
        initial.insert(q.name.into(), json!(v));
    }
    let parameters: Map<String, Value> = values.parameters().map(|(n, v)| (n.to_owned(), json!(v))).collect();
    let steps = report.outcome.steps();
    let doc = json!({
        "system": info.name,
        "method": method.name,
        "parameters": parameters,
        "initial": initial,
        "dt": if tolerances.is_some() { serde_json::Value::Null } else { json!(spec.h) },
        "steps": steps,
        "steps_accepted": steps,
        "steps_rejected": report.steps_rejected,
        "binding": match method.scheme {
            pendula::integrator::Scheme::Tao(t) => json!(t.binding),
            _ => serde_json::Value::Null,
        },
        "rtol": tolerances.map(|t| t.rtol),
        "atol": tolerances.map(|t| t.atol),
        "rhs_evals": report.rhs_evals,
        "t_end": t_end,
        "final": final_state,
        "energy": {
            "initial": energy.initial,
            "final": energy.last,
            "tracked": energy.quantity(),
            "work": energy.forced.then_some(energy.work),
            "scale": energy.scale,
            "scale_definition": info.energy_scale,
            "max_abs_error": energy.max_abs,
            "max_rel_error": energy.max_rel(),
        },
        "wall_s": wall_s,
        "events": events.found.iter().map(|e| {
            let mut state = Map::new();
            for (q, v) in info.state.iter().zip(&e.state) {
                state.insert(q.name.into(), json!(v));
            }
            json!({ "name": e.name, "t": e.t, "state": state })
        }).collect::<Vec<_>>(),
    });
    let summary_path = summary_out.path().map(std::path::Path::to_path_buf);
    // The trajectory, its picture and the summary appear together or not at all.
    summary_out.write_with(&doc, out_file.into_iter().chain(plot_file).collect())?;

    // The human summary is composed first and written at once (stderr is unbuffered).
    let mut err = Vec::new();
    writeln!(
        err,
        "{} with {}: {steps} steps {} to t = {} s, {} rhs evaluations, {wall_s:.3} s",
        info.name,
        method.name,
        match tolerances {
            Some(t) =>
                format!("(adaptive, rtol {:e} atol {:e}, {} rejected)", t.rtol, t.atol, report.steps_rejected),
            None => format!("of {} s", Short(spec.h)),
        },
        Short(t_end),
        report.rhs_evals
    )?;
    writeln!(
        err,
        "energy: {:.12e}{u} -> {:.12e}{u}; {}: max {:.3e}{u}, {:.3e} of the energy scale {:.4}{u}",
        energy.initial,
        energy.last,
        energy.quantity(),
        energy.max_abs,
        energy.max_rel(),
        energy.scale,
        u = if energy_unit.is_empty() { String::new() } else { format!(" {energy_unit}") },
    )?;
    match out {
        Some(Output::Csv(p) | Output::Npy(p)) => writeln!(err, "wrote {} ({rows} rows)", p.display())?,
        Some(Output::Stdout) => {}
        None => writeln!(err, "no trajectory written (--every 0)")?,
    }
    if let Some(first) = events.found.first() {
        writeln!(err, "events: {} (first: {} at t = {} s)", events.found.len(), first.name, Short(first.t))?;
    }
    if let Some(e) = events.stopped_at() {
        writeln!(err, "stopped at the event {} (t = {} s)", e.name, Short(e.t))?;
    }
    if let Some(p) = plot {
        writeln!(err, "wrote {}", p.display())?;
    }
    if let Some(p) = summary_path {
        writeln!(err, "wrote {}", p.display())?;
    }
    std::io::stderr().write_all(&err)?;
    Ok(())
}

/// The double pendulum of these values (of the `double` system).
fn double(values: &pendula::system::Values) -> pendula::system::double::DoublePendulum {
    <pendula::system::double::DoublePendulum as pendula::system::Model>::from_values(values)
}
