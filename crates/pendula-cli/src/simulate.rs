//! `pendula simulate`: one system, one method, a trajectory and a summary — run in one go,
//! or in legs between checkpoints (`--checkpoint`, continued by `pendula resume`), which
//! give the same bytes.

use std::io::Write;
use std::time::Instant;

use anyhow::Result;
use pendula::analysis::EnergyBalance;
use pendula::checkpoint::{Leg, Pause};
use pendula::error::Short;
use pendula::events::{EndAtEvent, EventLocator, EventSpec};
use pendula::observe::{Every, Observer, Resample};
use pendula::{Report, Stepping};
use serde_json::{Map, Value, json};

use crate::config::SimulateArgs;
use crate::config::{self, Output, SimulateConfig};
use crate::output::{AtomicFile, PartialFile};
use crate::run_state::{Resumed, Saved};
use crate::sink::Sink;
use crate::study::Summary;
use crate::watch::{Progress, Rows, Watch, Writer};

pub fn run(args: &SimulateArgs) -> Result<()> {
    execute(args, None)
}

/// Where the trajectory is written: a temporary file renamed into place at the end, or, for
/// a run that writes checkpoints, the visible `OUT.partial` a checkpoint can refer to.
enum Trajectory {
    Atomic(AtomicFile),
    Partial(PartialFile),
}

/// The trajectory's output, claimed and not yet written.
enum Opened<'a> {
    Atomic(AtomicFile),
    Partial(PartialFile),
    /// A checkpoint's partial file, and how much of it the checkpoint recorded.
    Resumed(&'a Output, PartialFile, crate::sink::Position),
    None,
}

/// Runs `simulate` from the start, or `resumed` from a checkpoint (`pendula resume`).
pub(crate) fn execute(args: &SimulateArgs, resumed: Option<Resumed>) -> Result<()> {
    let config = config::simulate(args)?;
    let SimulateConfig {
        values,
        method,
        spec,
        tolerances,
        first_step,
        every,
        out,
        summary,
        grid,
        plot,
        checkpoint,
    } = &config;
    let fingerprint = crate::run_state::fingerprint(&config, args);
    if let Some(r) = &resumed {
        r.checkpoint.check_fingerprint(&fingerprint)?;
    }
    // From here an interrupt asks for a checkpoint (taken after the first step at the
    // earliest) rather than ending the process.
    let _registered = checkpoint.as_ref().map(|_| crate::output::Checkpointing::start());
    // The checkpoint is claimed with the outputs: a regular file, none of them.
    if let Some(c) = checkpoint {
        crate::output::claim_regular(&c.path, "--checkpoint", "a checkpoint")?;
    }
    let info = values.info();
    let mut columns = vec!["t"];
    columns.extend(info.state.iter().map(|q| q.name));
    columns.push("energy");
    // Claim every output first, writing nothing: a path that cannot be written, or two
    // outputs that are one file, fail before any byte goes anywhere (a FIFO included).
    let opened = match (out, checkpoint, &resumed) {
        (Some(Output::Csv(p) | Output::Npy(p)), None, _) => Opened::Atomic(AtomicFile::create(p, "--out")?),
        (Some(o @ (Output::Csv(p) | Output::Npy(p))), Some(_), Some(r)) => {
            let (position, partial) = r.out.as_ref().ok_or_else(|| r.mismatch("a trajectory file"))?;
            Opened::Resumed(o, PartialFile::claim_recorded(p, partial, "--out")?, *position)
        }
        (Some(Output::Csv(p) | Output::Npy(p)), Some(_), None) => {
            Opened::Partial(PartialFile::claim(p, "--out")?)
        }
        (Some(Output::Stdout), _, _) => {
            crate::output::claim_stdout("--out")?;
            Opened::None
        }
        (None, _, _) => Opened::None,
    };
    // `--summary -` prints the summary on stdout (config refuses it with `--out -`).
    let summary_out = Summary::open(summary.as_deref())?;
    let plot_file = plot.as_deref().map(|p| AtomicFile::create(p, "--plot")).transpose()?;
    // Every output claimed: a checkpoint left by an earlier run is not overwritten.
    if let (Some(c), None) = (checkpoint, &resumed)
        && c.path.exists()
    {
        anyhow::bail!(
            "invalid --checkpoint {}: it exists (from a run interrupted earlier?): continue that run with `pendula resume {}`, or remove the file to start again",
            crate::checkpoint::absolute(&c.path).display(),
            crate::checkpoint::absolute(&c.path).display()
        );
    }
    let (trajectory, sink, kept) = match opened {
        Opened::Atomic(file) => {
            let sink = Sink::new(out.as_ref(), Some(file.handle()?), &columns)?;
            (Some(Trajectory::Atomic(file)), sink, None)
        }
        Opened::Resumed(o, partial, position) => {
            let (sink, kept) = Sink::resume(o, &partial, columns.len(), &position, plot.is_some())?;
            (Some(Trajectory::Partial(partial)), sink, kept)
        }
        Opened::Partial(mut partial) => {
            let file = partial.create()?;
            let sink = Sink::new(out.as_ref(), Some(file), &columns)?;
            (Some(Trajectory::Partial(partial)), sink, None)
        }
        Opened::None => (None, Sink::new(out.as_ref(), None, &columns)?, None),
    };

    let model = values.build();
    // The energy error relative to the system's scale, or for damped and driven runs the
    // energy balance E − E(0) − W.
    let energy = EnergyBalance::new(&*model, values.initial_state());
    let progress = Progress::new(spec.t0, spec.schedule()?.t_end);
    let writer =
        Writer { model: &*model, sink, rows: 0, kept: kept.or_else(|| plot.is_some().then(Vec::new)) };
    let specs = args
        .events
        .iter()
        .map(|e| EventSpec::parse(e, &*model, args.stop_on_event))
        .collect::<Result<Vec<_>, _>>()?;
    let watch_events = !specs.is_empty();
    // Rows: on the --output-dt / --t-eval grid, or every N-th step and the last (a plot
    // without a trajectory file draws every step).
    let rows = match (grid, every.or(plot.is_some().then_some(1))) {
        (Some(g), _) => Rows::Grid(Resample::new(g.clone(), info.state.len(), writer)),
        (None, Some(n)) => Rows::Every(Every { n, inner: writer }),
        (None, None) => Rows::None(writer),
    };
    // The energy is tracked at every step; a terminal event ends the run, and the rows, at
    // the event's time and state.
    let mut watch = Watch { events: EventLocator::new(&*model, specs), energy, rows, progress };
    let mut saved = match &resumed {
        Some(r) => Some(r.restore(&mut watch)?),
        None => None,
    };
    let stepping = match tolerances {
        Some(tol) => Stepping::Adaptive { t_end: spec.schedule()?.t_end, h0: *first_step, tol },
        None => Stepping::Fixed(*spec),
    };
    let mut trajectory = trajectory;
    let mut next = saved.as_ref().map_or_else(
        || checkpoint.as_ref().and_then(|c| c.every).unwrap_or(f64::INFINITY),
        |s| s.next_checkpoint,
    );
    let earlier_wall = resumed.as_ref().map_or(0.0, |r| r.wall_s);
    let start = Instant::now();
    // Legs between checkpoints; one leg without --checkpoint.
    let report = loop {
        let pause = match checkpoint {
            Some(_) => Pause { at: next, flag: Some(crate::output::pause_flag()) },
            None => Pause::NEVER,
        };
        let from = saved.as_ref().map(|s| &s.run);
        let y0 = values.initial_state();
        let Watch { events, energy, rows, progress } = &mut watch;
        let mut ignore = pendula::observe::Ignore;
        let rows: &mut dyn Observer = match rows {
            Rows::Grid(r) => r,
            Rows::Every(e) => e,
            Rows::None(_) => &mut ignore,
        };
        let mut chain = EndAtEvent {
            events: std::mem::replace(events, EventLocator::new(&*model, Vec::new())),
            inner: (energy, (rows, progress)),
        };
        // Without events the locator is left out: one call per step less on the fast paths.
        let observers: &mut dyn Observer = if watch_events { &mut chain } else { &mut chain.inner };
        // The library picks the fastest path (the double pendulum's RK4 kernel, or the
        // general run loop).
        let leg = model.solve_fastest(method, y0, &stepping, observers, from, &pause);
        *events = chain.events;
        let state = match leg {
            Ok(Leg::Done(report)) => break report,
            Ok(Leg::Paused(state)) => state,
            Err(err) => {
                // A run that failed numerically leaves nothing: continuing from its checkpoint
                // would fail the same way. (A checkpoint that does not fit is left as it is.)
                let numerical = matches!(
                    err,
                    pendula::Error::NonFinite { .. }
                        | pendula::Error::NewtonDidNotConverge { .. }
                        | pendula::Error::StepSizeTooSmall { .. }
                );
                if let (true, Some(c)) = (numerical, checkpoint) {
                    if let Some(Trajectory::Partial(p)) = trajectory.take() {
                        p.remove();
                    }
                    let _ = std::fs::remove_file(&c.path);
                }
                return Err(err.into());
            }
        };
        let c = checkpoint.as_ref().expect("only a checkpointing run pauses");
        // The next checkpoint at the next multiple of the interval after this one.
        next = c.every.map_or(f64::INFINITY, |every| every * ((state.t / every).floor() + 1.0));
        let partial = match &mut trajectory {
            Some(Trajectory::Partial(p)) => Some(p),
            _ => None,
        };
        let at = Saved { run: state, next_checkpoint: next };
        let wall_s = earlier_wall + start.elapsed().as_secs_f64();
        crate::run_state::write(&c.path, args, &fingerprint, &at, &mut watch, partial, wall_s)?;
        if let Some(signal) = crate::output::interrupted_by() {
            watch.progress.finish();
            return Err(crate::output::Interrupted {
                signal,
                message: format!(
                    "checkpoint written to {} at t = {} s (step {}); continue with `pendula resume {}`",
                    crate::checkpoint::absolute(&c.path).display(),
                    Short(at.run.t),
                    at.run.steps,
                    crate::checkpoint::absolute(&c.path).display()
                ),
            }
            .into());
        }
        saved = Some(at);
    };
    let wall_s = earlier_wall + start.elapsed().as_secs_f64();
    let Watch { events, energy, rows, progress } = watch;
    progress.finish();
    let writer = rows.into_writer();
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
    let report: &Report = &report;

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
    // The trajectory, its picture and the summary appear together or not at all; a
    // checkpointing run's checkpoint goes in the same step (the run is complete).
    finish_files(summary_out, &doc, trajectory, plot_file, checkpoint.as_ref().map(|c| c.path.as_path()))?;

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

/// Puts the finished files in place, as one step for an interrupt: the trajectory (renamed
/// from its temporary or partial name), the plot and the summary `doc`; a checkpointing
/// run's checkpoint is removed (the run is complete).
fn finish_files(
    summary: Summary,
    doc: &Value,
    trajectory: Option<Trajectory>,
    plot: Option<AtomicFile>,
    checkpoint: Option<&std::path::Path>,
) -> Result<()> {
    let (mut files, mut partial) = (Vec::new(), None);
    match trajectory {
        Some(Trajectory::Atomic(f)) => files.push(f),
        Some(Trajectory::Partial(p)) => partial = Some(p),
        None => {}
    }
    files.extend(plot);
    summary.write_then(doc, files, |guard| {
        if let Some(p) = partial {
            p.finish(guard)?;
        }
        if let Some(c) = checkpoint {
            crate::checkpoint::remove(c)?;
        }
        Ok(())
    })
}
