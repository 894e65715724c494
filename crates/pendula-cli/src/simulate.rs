//! `pendula simulate`: one system, one method, a trajectory and a summary.

use std::io::Write;
use std::ops::ControlFlow;
use std::time::Instant;

use anyhow::Result;
use pendula::error::Short;
use pendula::events::{EventLocator, EventSpec};
use pendula::observe::{EnergyTracker, Observer, Sample};
use serde_json::{Map, Value, json};

use crate::cli::SimulateArgs;
use crate::config::{self, Output, SimulateConfig};
use crate::output::{AtomicFile, Sink};

/// Tracks energy at every step and writes the kept steps.
struct Writer<F> {
    energy: EnergyTracker<F>,
    every: u64,
    sink: Sink,
    rows: u64,
    failure: Option<anyhow::Error>,
}

impl<F: FnMut(f64, &[f64]) -> f64> Observer for Writer<F> {
    fn observe(&mut self, s: &Sample<'_>) -> ControlFlow<()> {
        let e = match s.energy {
            Some(e) => {
                self.energy.record(e);
                e
            }
            None => self.energy.track(s.t, s.y),
        };
        if self.every > 0 && (s.step.is_multiple_of(self.every) || s.last) {
            let row = std::iter::once(s.t).chain(s.y.iter().copied()).chain(std::iter::once(e));
            if let Err(err) = self.sink.row(row) {
                self.failure = Some(err);
                return ControlFlow::Break(());
            }
            self.rows += 1;
        }
        ControlFlow::Continue(())
    }
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    let config = config::simulate(args)?;
    let SimulateConfig { values, method, spec, tolerances, first_step, every, out, summary } = &config;
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

    let mut columns = vec!["t"];
    columns.extend(info.state.iter().map(|q| q.name));
    columns.push("energy");
    let model = values.build();
    let mut writer = Writer {
        energy: EnergyTracker::new(|t, y: &[f64]| model.energy(t, y)),
        every: every.unwrap_or(0),
        sink: Sink::new(out.as_ref(), out_file.as_ref(), &columns)?,
        rows: 0,
        failure: None,
    };
    let specs = args
        .events
        .iter()
        .map(|e| EventSpec::parse(e, &*model, args.stop_on_event))
        .collect::<Result<Vec<_>, _>>()?;
    let watch_events = !specs.is_empty();
    let mut events = EventLocator::new(&*model, specs);
    let mut both = (&mut writer, &mut events);
    // Without events the writer alone watches: one call per step less on the fast paths.
    let observers: &mut dyn Observer = if watch_events { &mut both } else { both.0 };
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
    if let Some(err) = writer.failure.take() {
        return Err(err);
    }
    let report = report?;
    let energy = writer.energy.stats();
    let rows = writer.rows;
    writer.sink.finish(out_file.as_ref())?;
    if let Some(f) = out_file {
        f.commit()?;
    }

    let t_end = report.outcome.t();
    let mut final_state = Map::new();
    final_state.insert("t".into(), json!(t_end));
    for (q, v) in info.state.iter().zip(&report.state) {
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
        writeln!(err, "events: {} (first: {} at t = {} s)", events.found.len(), first.name, Short(first.t))?;
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
