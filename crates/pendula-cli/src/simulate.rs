//! `pendula simulate`: one system, one method, a trajectory and a summary.

use std::io::Write;
use std::ops::ControlFlow;
use std::time::Instant;

use anyhow::Result;
use pendula::events::{EndAtEvent, EventLocator, EventSpec};
use pendula::observe::{EnergyTracker, Every, Ignore, Observer, Resample, Sample};
use serde_json::{Map, Value, json};

use crate::cli::SimulateArgs;
use crate::config::{self, Output, SimulateConfig};
use crate::output::{AtomicFile, Sink};

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

pub fn run(args: &SimulateArgs) -> Result<()> {
    let config = config::simulate(args)?;
    let SimulateConfig { values, method, spec, tolerances, first_step, every, out, summary, grid, plot } =
        &config;
    let info = values.info();
    // Open the outputs first: a path that cannot be written fails before the work.
    let out_file = match out {
        Some(Output::Csv(p) | Output::Npy(p)) => Some(AtomicFile::create(p, "--out")?),
        _ => None,
    };
    // `--summary -` prints the summary on stdout.
    let to_stdout = summary.as_deref() == Some(std::path::Path::new("-"));
    let summary_file =
        summary.as_deref().filter(|_| !to_stdout).map(|p| AtomicFile::create(p, "--summary")).transpose()?;
    let plot_file = plot.as_deref().map(|p| AtomicFile::create(p, "--plot")).transpose()?;

    let mut columns = vec!["t"];
    columns.extend(info.state.iter().map(|q| q.name));
    columns.push("energy");
    let model = values.build();
    let mut energy = EnergyTracker::new(|t, y: &[f64]| model.energy(t, y));
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
    let mut watch = EndAtEvent { events: EventLocator::new(&*model, specs), inner: (&mut energy, rows) };
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
    if let Some(err) = writer.failure.take() {
        return Err(err);
    }
    let report = report?;
    let energy = energy.stats();
    let rows = writer.rows;
    writer.sink.finish(out_file.as_ref())?;
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
        file.handle()?.write_all(&bytes)?;
    }
    if let Some(f) = out_file {
        f.commit()?;
    }
    if let Some(f) = plot_file {
        f.commit()?;
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
    if summary.is_some() {
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
                "max_abs_error": energy.max_abs_error,
                "max_rel_error": energy.max_rel_error(),
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
        match summary_file {
            Some(f) => {
                // Serialised whole, then written at once: a File takes one syscall per token.
                let mut handle = std::io::BufWriter::new(f.handle()?);
                serde_json::to_writer_pretty(&mut handle, &doc)?;
                writeln!(handle)?;
                handle.into_inner().map_err(|e| e.into_error())?;
                f.commit()?;
            }
            None => {
                let mut out = std::io::stdout().lock();
                serde_json::to_writer_pretty(&mut out, &doc)?;
                writeln!(out)?;
            }
        }
    }

    // The human summary is composed first and written at once (stderr is unbuffered).
    let mut err = Vec::new();
    writeln!(
        err,
        "{} with {}: {steps} steps {} to t = {t_end} s, {} rhs evaluations, {wall_s:.3} s",
        info.name,
        method.name,
        match tolerances {
            Some(t) =>
                format!("(adaptive, rtol {:e} atol {:e}, {} rejected)", t.rtol, t.atol, report.steps_rejected),
            None => format!("of {} s", spec.h),
        },
        report.rhs_evals
    )?;
    writeln!(
        err,
        "energy: {:.12e} J -> {:.12e} J, max |dE| = {:.3e} J (relative {:.3e})",
        energy.initial,
        energy.last,
        energy.max_abs_error,
        energy.max_rel_error()
    )?;
    match out {
        Some(Output::Csv(p) | Output::Npy(p)) => writeln!(err, "wrote {} ({rows} rows)", p.display())?,
        Some(Output::Stdout) => {}
        None => writeln!(err, "no trajectory written (--every 0)")?,
    }
    if let Some(first) = events.found.first() {
        writeln!(err, "events: {} (first: {} at t = {} s)", events.found.len(), first.name, first.t)?;
    }
    if let Some(e) = events.stopped_at() {
        writeln!(err, "stopped at the event {} (t = {} s)", e.name, e.t)?;
    }
    if let Some(p) = plot {
        writeln!(err, "wrote {}", p.display())?;
    }
    if let Some(p) = summary.as_deref().filter(|_| !to_stdout) {
        writeln!(err, "wrote {}", p.display())?;
    }
    std::io::stderr().write_all(&err)?;
    Ok(())
}

/// The double pendulum of these values (of the `double` system).
fn double(values: &pendula::system::Values) -> pendula::system::double::DoublePendulum {
    <pendula::system::double::DoublePendulum as pendula::system::Model>::from_values(values)
}
