//! Checkpoints continue a run bit for bit: every method, fixed and adaptive, paused after
//! many different steps (every step, every 7th, every 50th …), its state turned into words
//! and back, its observers rebuilt and restored as a new process would, shows the same
//! samples and ends in the same bits, with the same evaluation counts, as the run that never
//! paused. Controls show that the comparison sees a lost stepper state.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};

use pendula::analysis::EnergyBalance;
use pendula::checkpoint::{Leg, Pause, RunState, Snapshot, Words};
use pendula::control::Tolerances;
use pendula::events::{EventLocator, EventSpec};
use pendula::integrator::{self, METHODS, Method};
use pendula::model::DynModel;
use pendula::observe::{Flow, Grid, Observer, Resample, Sample};
use pendula::system::{Model, Values, double::DoublePendulum};
use pendula::{End, Error, Report, RunSpec, Stepping};

use crate::support::values;

/// The bits of every sample an observer saw: step, t, state, and the energy if given.
#[derive(Debug, Default, Clone, PartialEq)]
struct Tape(Vec<u64>);

impl Observer for Tape {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        self.0.push(s.step);
        self.0.push(s.t.to_bits());
        self.0.extend(s.y.iter().map(|v| v.to_bits()));
        if let Some(e) = s.energy {
            self.0.push(e.to_bits());
        }
        ControlFlow::Continue(())
    }
}

/// Sets the pause flag at every `every`-th step, so that the run pauses right after it.
struct PauseEvery<'a> {
    flag: &'a AtomicBool,
    every: u64,
}

impl Observer for PauseEvery<'_> {
    fn observe(&mut self, s: &Sample<'_>) -> Flow {
        if s.step > 0 && s.step.is_multiple_of(self.every) {
            self.flag.store(true, Ordering::Relaxed);
        }
        ControlFlow::Continue(())
    }
}

/// What a run produced: the samples, the grid's samples, the observers' final states, and
/// the report's bits.
#[derive(Debug, PartialEq)]
struct Result_ {
    samples: Tape,
    grid: Tape,
    observers: Words,
    report: Vec<u64>,
    legs: usize,
}

fn report_bits(r: &Report) -> Vec<u64> {
    let mut v =
        vec![r.outcome.steps(), r.outcome.t().to_bits(), r.rhs_evals, r.steps_rejected, r.jacobian_evals];
    v.push(u64::from(matches!(r.outcome, pendula::Outcome::Stopped { .. })));
    v.extend(r.state.iter().map(|x| x.to_bits()));
    v
}

/// One run of `method` on `values`, paused every `every` steps (`None`: never), each leg
/// continued from its [`RunState`] after a round trip through words, with the event locator,
/// the energy balance and the resampler rebuilt and restored from their words. `fast` takes
/// the double pendulum's RK4 fast path.
fn run(
    v: &Values,
    method: &Method,
    stepping: &Stepping<'_>,
    events: &[&str],
    every: Option<u64>,
    fast: bool,
) -> Result<Result_, Error> {
    let model: Box<dyn DynModel> = v.build();
    let specs: Vec<EventSpec> =
        events.iter().map(|e| EventSpec::parse(e, &*model, false)).collect::<Result<_, _>>()?;
    let flag = AtomicBool::new(false);
    let dim = v.initial_state().len();
    let (mut samples, mut grid_tape) = (Tape::default(), Tape::default());
    let mut saved: Option<(RunState, Words, Words, Words)> = None;
    let mut legs = 0;
    loop {
        legs += 1;
        // A new process: fresh observers, restored from the words of the last pause.
        let mut locator = EventLocator::new(&*model, specs.clone());
        let mut energy = EnergyBalance::new(&*model, v.initial_state());
        let mut grid = Resample::new(Grid::Spacing(0.037), dim, std::mem::take(&mut grid_tape));
        if let Some((_, e, b, g)) = &saved {
            locator.restore_all(e, "events")?;
            energy.restore_all(b, "energy")?;
            grid.restore_all(g, "grid")?;
        }
        let mut pauser = PauseEvery { flag: &flag, every: every.unwrap_or(u64::MAX) };
        let tape = std::mem::take(&mut samples);
        let mut observers = (&mut pauser, (&mut locator, (&mut energy, (tape, &mut grid))));
        let from = saved.as_ref().map(|(s, ..)| s);
        let pause = Pause { at: f64::INFINITY, flag: Some(&flag) };
        flag.store(false, Ordering::Relaxed);
        let leg = if fast {
            model.solve_fastest(method, v.initial_state(), stepping, &mut observers, from, &pause)?
        } else {
            model.solve_resumable(method, v.initial_state(), stepping, &mut observers, from, &pause)?
        };
        samples = std::mem::take(&mut observers.1.1.1.0);
        let words = |o: &dyn Snapshot| o.snapshot();
        match leg {
            Leg::Paused(state) => {
                assert!(every.is_some(), "a run without pauses paused");
                // Through words and back, as the checkpoint file stores it.
                let state = RunState::from_words(&state.to_words())?;
                saved = Some((state, words(&locator), words(&energy), words(&grid)));
                grid_tape = std::mem::take(&mut grid.inner);
            }
            Leg::Done(report) => {
                let mut observers = words(&locator);
                observers.words(&words(&energy));
                observers.words(&words(&grid));
                return Ok(Result_ {
                    samples,
                    grid: grid.inner,
                    observers,
                    report: report_bits(&report),
                    legs,
                });
            }
        }
    }
}

/// The run paused every 1, 7 and 50 steps equals the run that never paused.
fn check(v: &Values, method: &Method, stepping: &Stepping<'_>, events: &[&str], fast: bool) {
    let whole = match run(v, method, stepping, events, None, fast) {
        Ok(r) => r,
        // A method this system does not support (yoshida on the double pendulum).
        Err(Error::UnmetRequirement { .. }) => return,
        Err(e) => panic!("{} on {}: {e}", method.name, v.info().name),
    };
    assert_eq!(whole.legs, 1);
    for every in [1, 7, 50] {
        let parts = run(v, method, stepping, events, Some(every), fast).unwrap();
        let name = format!("{} on {}, paused every {every} steps", method.name, v.info().name);
        // Every step of the run is a leg at `every` = 1: steps + 1 legs (the last is not paused after).
        let steps = whole.report[0];
        assert_eq!(parts.legs as u64, (steps - 1) / every + 1, "{name}: {} legs", parts.legs);
        assert_eq!(parts.report, whole.report, "{name}: the report differs");
        assert_eq!(parts.samples, whole.samples, "{name}: the samples differ");
        assert_eq!(parts.grid, whole.grid, "{name}: the resampled rows differ");
        assert_eq!(parts.observers, whole.observers, "{name}: the observers' states differ");
    }
}

fn fixed(h: f64, t_end: f64) -> Stepping<'static> {
    Stepping::Fixed(RunSpec { t0: 0.0, h, end: End::Time(t_end) })
}

/// Every fixed-step method on the chaotic double pendulum (non-separable: the implicit
/// partitioned methods, Gauss–Legendre's Newton iteration, Tao's copy) and on the driven
/// pendulum (time-dependent: the partitioned methods' cached force), with events located,
/// to an end time that shortens the last step.
#[test]
fn every_fixed_step_method_continues_bit_for_bit() {
    let double = values("double", &[]);
    let driven = values("driven-pendulum", &[("drive_amplitude", 1.2), ("theta", 2.5)]);
    for method in METHODS {
        check(&double, method, &fixed(0.004, 0.4013), &["flip", "zero:theta2"], false);
        check(&driven, method, &fixed(0.004, 0.4013), &["zero:theta"], false);
    }
}

/// The fast paths of fixed-step explicit methods — the single-trajectory kernel (RK4 on the
/// free double pendulum), the ensemble engine's one lane (the damped and the driven double
/// pendulum, the chain, the pendulum) — and a damped run whose energy balance integrates the
/// work.
#[test]
fn the_fast_path_and_the_energy_balance_continue_bit_for_bit() {
    let double = values("double", &[("theta1", 2.9), ("theta2", 2.0)]);
    check(&double, &integrator::explicit_rk::RK4, &fixed(0.005, 1.0013), &["flip", "zero:theta1"], true);
    let damped = values("double", &[("damping", 0.3), ("theta1", 2.0)]);
    check(&damped, &integrator::explicit_rk::RK4, &fixed(0.004, 0.4), &["zero:theta2"], true);
    let driven = values("double", &[("drive_amplitude", 2.0), ("drive_frequency", 1.5)]);
    check(&driven, &integrator::explicit_rk::EULER, &fixed(0.004, 0.4), &["zero:theta1"], true);
    check(&values("chain", &[("links", 3.0)]), &integrator::explicit_rk::RK4, &fixed(0.004, 0.4), &[], true);
    check(
        &values("pendulum", &[]),
        &integrator::explicit_rk::RK4,
        &fixed(0.01, 1.003),
        &["zero:theta"],
        true,
    );
    check(&damped, &integrator::explicit_rk::RK4, &fixed(0.004, 0.4), &["zero:theta2"], false);
    check(&damped, &integrator::gauss_legendre::GAUSS_LEGENDRE_4, &fixed(0.004, 0.4), &[], false);
}

/// dopri5 and dop853 with adaptive steps: the controller's step and error history, the
/// first-same-as-last derivative, the dense output the events and the grid are interpolated
/// on, and the rejected steps' count.
#[test]
fn adaptive_runs_continue_bit_for_bit() {
    let tol = Tolerances { rtol: 1e-7, atol: 1e-7, h_min: 0.0, h_max: f64::INFINITY };
    let double = values("double", &[("theta1", 2.9), ("theta2", 2.0)]);
    let damped = values("double", &[("damping", 0.3), ("drive_amplitude", 2.0), ("drive_frequency", 1.5)]);
    for method in [&integrator::embedded::DOPRI5, &integrator::embedded::DOP853] {
        let adaptive = Stepping::Adaptive { t_end: 4.0, h0: None, tol: &tol };
        check(&double, method, &adaptive, &["flip", "zero:theta2", "section:theta1=0+"], false);
        check(&damped, method, &adaptive, &["zero:theta1"], false);
        let first = Stepping::Adaptive { t_end: 2.0, h0: Some(1e-3), tol: &tol };
        check(&double, method, &first, &[], false);
    }
}

/// A terminal event ends the continued run where it ends the whole one.
#[test]
fn a_terminal_event_ends_the_continued_run_at_the_same_step() {
    let v = values("double", &[("theta1", 2.9), ("theta2", 2.0)]);
    let model = v.build();
    let stepping = fixed(0.005, 20.0);
    let rk4 = &integrator::explicit_rk::RK4;
    let flip = vec![EventSpec::parse("flip", &*model, true).unwrap()];
    let solve = |locator: &mut EventLocator<'_>, from: Option<&RunState>, pause: &Pause<'_>| {
        model.solve_resumable(rk4, v.initial_state(), &stepping, locator, from, pause).unwrap()
    };
    let mut whole = EventLocator::new(&*model, flip.clone());
    let Leg::Done(report) = solve(&mut whole, None, &Pause::NEVER) else { unreachable!() };
    assert!(matches!(report.outcome, pendula::Outcome::Stopped { .. }), "{:?}", report.outcome);
    let mut first = EventLocator::new(&*model, flip.clone());
    let Leg::Paused(state) = solve(&mut first, None, &Pause { at: 0.5, flag: None }) else {
        panic!("no pause at 0.5 s")
    };
    let mut second = EventLocator::new(&*model, flip);
    second.restore_all(&first.snapshot(), "events").unwrap();
    let Leg::Done(continued) = solve(&mut second, Some(&state), &Pause::NEVER) else {
        panic!("paused again")
    };
    assert_eq!(report_bits(&continued), report_bits(&report));
    assert_eq!(second.found, whole.found);
    assert_eq!(second.stopped_at(), whole.stopped_at());
}

/// Controls: continuing with the stepper's state lost — a Gauss–Legendre stepper's kept
/// stages and Jacobian, Tao's copy, an embedded pair's first-same-as-last stage, each
/// replaced by those of the first step, or dopri5's controller history reset — gives other
/// bits or other counts, so the comparisons above would see a state that is not saved.
#[test]
fn control_a_lost_stepper_state_is_seen() {
    use pendula::observe::Ignore;
    let v = values("double", &[]);
    let model = v.build();
    let tol = Tolerances { rtol: 1e-7, atol: 1e-7, h_min: 0.0, h_max: f64::INFINITY };
    let cases: [(&Method, Stepping<'_>); 4] = [
        (&integrator::gauss_legendre::GAUSS_LEGENDRE_4, fixed(0.01, 2.0)),
        (&integrator::tao::TAO_4, fixed(0.004, 1.0)),
        (&integrator::embedded::DOP853, fixed(0.01, 1.0)),
        (&integrator::embedded::DOPRI5, Stepping::Adaptive { t_end: 2.0, h0: None, tol: &tol }),
    ];
    for (method, stepping) in cases {
        let solve = |from: Option<&RunState>, pause: &Pause<'_>| {
            model.solve_resumable(method, v.initial_state(), &stepping, &mut Ignore, from, pause).unwrap()
        };
        let Leg::Done(whole) = solve(None, &Pause::NEVER) else { unreachable!() };
        let Leg::Paused(mut state) = solve(None, &Pause { at: 0.5, flag: None }) else {
            panic!("{}: no pause", method.name)
        };
        let Leg::Done(kept) = solve(Some(&state), &Pause::NEVER) else { unreachable!() };
        assert_eq!(report_bits(&kept), report_bits(&whole), "{}", method.name);
        let saved = state.clone();
        match stepping {
            // The controller's previous error back to its initial 1e-4.
            Stepping::Adaptive { .. } => {
                let n = state.control.0.len();
                state.control.0[n - 1] = 1e-4_f64.to_bits();
            }
            // The stepper's state after the first step: its shape fits, its memory is another's.
            Stepping::Fixed(_) => {
                let Leg::Paused(at_start) = solve(None, &Pause { at: 0.0, flag: None }) else {
                    unreachable!()
                };
                state.stepper = at_start.stepper;
            }
        }
        assert_ne!(saved, state, "{}: the control changed nothing", method.name);
        let Leg::Done(lost) = solve(Some(&state), &Pause::NEVER) else { unreachable!() };
        assert_ne!(
            report_bits(&lost),
            report_bits(&whole),
            "{}: losing the stepper's state changed nothing",
            method.name
        );
    }
}

/// Words that do not fit are refused, naming the part: another method's stepper state, a
/// truncated list, a state of another dimension, a step past the end, a word missing.
#[test]
fn states_that_do_not_fit_are_refused() {
    use pendula::observe::Ignore;
    let v = values("double", &[]);
    let model = v.build();
    let stepping = fixed(0.004, 1.0);
    let solve = |method: &Method, from: Option<&RunState>, pause: &Pause<'_>| {
        model.solve_resumable(method, v.initial_state(), &stepping, &mut Ignore, from, pause)
    };
    let gl4 = &integrator::gauss_legendre::GAUSS_LEGENDRE_4;
    let Leg::Paused(gl) = solve(gl4, None, &Pause { at: 0.5, flag: None }).unwrap() else {
        panic!("no pause")
    };
    let bad = |r: Result<Leg<Report>, Error>| match r {
        Err(e @ Error::BadCheckpoint { .. }) => e.to_string(),
        other => panic!("expected BadCheckpoint, got {other:?}"),
    };
    let message = bad(solve(&integrator::tao::TAO_4, Some(&gl), &Pause::NEVER));
    assert!(message.starts_with("the saved state of the stepper does not fit"), "{message}");
    let mut short = gl.clone();
    short.stepper.0.truncate(10);
    assert!(bad(solve(gl4, Some(&short), &Pause::NEVER)).contains("ends"));
    let mut other = gl.clone();
    other.y.push(0.0);
    assert!(bad(solve(gl4, Some(&other), &Pause::NEVER)).contains("5 variables"));
    let mut late = gl;
    late.steps = 10_000;
    assert!(bad(solve(gl4, Some(&late), &Pause::NEVER)).contains("step 10000"));
    let mut words = late.to_words();
    words.0.pop();
    assert!(matches!(RunState::from_words(&words), Err(Error::BadCheckpoint { .. })));
}

/// `Simulation::run_from`, the building block for a stepper of one's own: paused at a
/// simulated time with the stepper kept (its state is the caller's), it continues to the
/// bits of the run that never paused.
#[test]
fn simulation_run_from_continues_a_paused_run() {
    use pendula::integrator::tao::TaoStepper;
    let v = values("double", &[]);
    let model = DoublePendulum::from_values(&v);
    let form = model.hamiltonian_form().unwrap();
    let pendula::integrator::Scheme::Tao(scheme) = integrator::tao::TAO_4.scheme else { unreachable!() };
    let spec = RunSpec { t0: 0.0, h: 0.004, end: End::Time(1.0) };
    let start = || {
        let mut z = [0.0; 4];
        Model::to_momenta(&model, v.initial_state(), &mut z);
        z
    };
    let run = pendula::Simulation { system: &form, spec };
    let (mut whole, mut tape) = (start(), Tape::default());
    let outcome = run.run(&mut TaoStepper::new(scheme, 2), &mut whole, &mut tape).unwrap();
    let (mut z, mut parts) = (start(), Tape::default());
    let mut stepper = TaoStepper::new(scheme, 2);
    let Leg::Paused(at) =
        run.run_from(&mut stepper, &mut z, &mut parts, 0, &Pause { at: 0.5, flag: None }).unwrap()
    else {
        panic!("no pause")
    };
    assert_eq!(at.t, 0.5);
    assert_eq!(at.y, z.to_vec());
    // A fresh stepper restored from the kept one's words, as after a restart.
    let mut restored = TaoStepper::new(scheme, 2);
    restored.restore_all(&stepper.snapshot(), "tao").unwrap();
    let Leg::Done(end) = run.run_from(&mut restored, &mut z, &mut parts, at.steps, &Pause::NEVER).unwrap()
    else {
        unreachable!()
    };
    assert_eq!(end, outcome);
    assert_eq!(z, whole);
    assert_eq!(parts, tape);
}

/// A pause asked for before the run starts (an interrupt during set-up) pauses after the
/// first step, not at the initial state, which a continued run would show again: the
/// continued run's samples are the whole run's, each once. A saved state at step 0 is refused.
#[test]
fn a_pause_before_the_start_comes_after_the_first_step() {
    let v = values("double", &[]);
    let model = v.build();
    let stepping = fixed(0.01, 0.5);
    let rk4 = &integrator::explicit_rk::RK4;
    let flag = AtomicBool::new(true);
    let (mut whole, mut parts) = (Tape::default(), Tape::default());
    let Leg::Done(report) =
        model.solve_resumable(rk4, v.initial_state(), &stepping, &mut whole, None, &Pause::NEVER).unwrap()
    else {
        unreachable!()
    };
    let pause = Pause { at: f64::INFINITY, flag: Some(&flag) };
    let Leg::Paused(state) =
        model.solve_resumable(rk4, v.initial_state(), &stepping, &mut parts, None, &pause).unwrap()
    else {
        panic!("no pause")
    };
    assert_eq!(state.steps, 1);
    let Leg::Done(end) = model
        .solve_resumable(rk4, v.initial_state(), &stepping, &mut parts, Some(&state), &Pause::NEVER)
        .unwrap()
    else {
        unreachable!()
    };
    assert_eq!(parts, whole);
    assert_eq!(report_bits(&end), report_bits(&report));
    let at_start = RunState { steps: 0, ..state };
    let err =
        model.solve_resumable(rk4, v.initial_state(), &stepping, &mut parts, Some(&at_start), &Pause::NEVER);
    assert!(matches!(err, Err(Error::BadCheckpoint { .. })), "{err:?}");
}
