//! `pendula simulate`: one system, one method, a trajectory and a summary.

use std::io::Write;
use std::ops::ControlFlow;
use std::time::Instant;

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use pendula::analysis::EnergyBalance;
use pendula::error::Short;
use pendula::events::{EventLocator, EventSpec};
use pendula::observe::{Observer, Sample};
use serde_json::{Map, Value, json};

use crate::cli::SimulateArgs;
use crate::config::{self, Output, SimulateConfig};
use crate::output::{AtomicFile, Sink};
use crate::study::Summary;

/// Tracks the energy error (or balance) at every step, writes the kept steps and moves the
/// progress bar.
struct Writer<'a> {
    energy: EnergyBalance<'a>,
    every: u64,
    sink: Sink,
    rows: u64,
    failure: Option<anyhow::Error>,
    progress: Progress,
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

impl Observer for Writer<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> ControlFlow<()> {
        self.progress.at(s.step, s.t);
        self.energy.track(s.t, s.y, s.energy);
        let (e, work) = (self.energy.last, self.energy.work);
        if self.every > 0 && (s.step.is_multiple_of(self.every) || s.last) {
            // Forced runs add the work W(t) of damping and drive, so E − E(0) − W is the balance.
            let forced = self.energy.forced.then_some(work);
            let row = std::iter::once(s.t).chain(s.y.iter().copied()).chain([e]).chain(forced);
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
    // `--summary -` prints the summary on stdout (config refuses it with `--out -`).
    let summary_out = Summary::open(summary.as_deref())?;

    let mut columns = vec!["t"];
    columns.extend(info.state.iter().map(|q| q.name));
    columns.push("energy");
    let model = values.build();
    let balance = EnergyBalance::new(&*model, values.initial_state());
    if balance.forced {
        columns.push("work");
    }
    let mut writer = Writer {
        energy: balance,
        every: every.unwrap_or(0),
        sink: Sink::new(out.as_ref(), out_file.as_ref(), &columns)?,
        rows: 0,
        failure: None,
        progress: Progress::new(spec.t0, spec.schedule()?.t_end),
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
    writer.progress.finish();
    if let Some(err) = writer.failure.take() {
        return Err(err);
    }
    let report = report?;
    let energy = &writer.energy;
    let energy_unit = info.energy_unit();
    let rows = writer.rows;
    writer.sink.finish()?;
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
    summary_out.write(&doc)?;

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
