//! The adaptive loop of the embedded pairs: attempt a step, let the PI controller judge its
//! error estimate, accept or reject it, and land on the end time exactly. It can pause after
//! an accepted step and continue from the [`RunState`] it hands back
//! ([`crate::simulate::resume::solve_resumable`]).

use crate::Error;
use crate::checkpoint::{Leg, Pause, Reader, RunState, Snapshot, Words};
use crate::control::{PiController, Tolerances, Verdict};
use crate::integrator::embedded::EmbeddedRk;
use crate::integrator::{Method, Scheme};
use std::ops::ControlFlow;

use crate::observe::{Observer, Sample};
use crate::simulate::{Counted, Outcome, Report};
use crate::system::{Model, System};

/// Runs an embedded pair with adaptive steps from t = 0 to `t_end` (landing on it exactly;
/// a negative `t_end` runs backward in time, see [`solve_adaptive_from`]), showing the
/// initial state and every accepted step to `observer`. `h0` is the size of the first step
/// to try; `None` picks one from the problem (Hairer, Nørsett, Wanner §II.4).
///
/// # Errors
/// [`Error::UnmetRequirement`] for a method without an error estimate, invalid tolerances,
/// [`Error::StepSizeTooSmall`], [`Error::NonFinite`].
pub fn solve_adaptive<M: Model>(
    model: &M,
    method: &Method,
    y0: &[f64],
    t_end: f64,
    h0: Option<f64>,
    tol: &Tolerances,
    observer: &mut dyn Observer,
) -> Result<Report, Error> {
    solve_adaptive_from(model, method, y0, 0.0, t_end, h0, tol, observer)
}

/// [`solve_adaptive`] from `t0` instead of 0, forward or backward in time: with `t_end`
/// before `t0` the steps are negative (the system is evaluated at the true times, so a
/// drive is followed backward), as scipy's `solve_ivp` integrates a span `(t0, t_end)`
/// with `t_end < t0`. `h0` is the first step's size (> 0; its sign is the run's direction).
///
/// # Errors
/// As [`solve_adaptive`]; [`Error::InvalidValue`] for a start time that is not finite or an
/// end time equal to it.
#[allow(clippy::too_many_arguments)] // solve_adaptive's arguments and the start time
pub fn solve_adaptive_from<M: Model>(
    model: &M,
    method: &Method,
    y0: &[f64],
    t0: f64,
    t_end: f64,
    h0: Option<f64>,
    tol: &Tolerances,
    observer: &mut dyn Observer,
) -> Result<Report, Error> {
    assert_eq!(y0.len(), model.dim(), "initial state of the wrong length");
    match run(model, method, y0, t0, t_end, h0, tol, observer, None, &Pause::NEVER)? {
        Leg::Done(report) => Ok(report),
        Leg::Paused(state) => unreachable!("a run that never pauses paused at step {}", state.steps),
    }
}

/// Where the loop stands between two steps.
struct Position {
    t: f64,
    /// The size of the next step to try, s (> 0; the run's direction gives its sign).
    h: f64,
    accepted: u64,
    rejected: u64,
    /// Whether the last attempt was rejected (the next accepted step then may not grow).
    just_rejected: bool,
}

/// The adaptive loop of [`solve_adaptive`] (from `t0`, backward when `t_end` < `t0`), started
/// afresh or `from` a paused state, pausing after an accepted step (not the last) when
/// `pause` says so.
#[allow(clippy::too_many_arguments)] // solve_adaptive's arguments, and where to start and pause
pub(crate) fn run<M: Model>(
    model: &M,
    method: &Method,
    y0: &[f64],
    t0: f64,
    t_end: f64,
    h0: Option<f64>,
    tol: &Tolerances,
    observer: &mut dyn Observer,
    from: Option<&RunState>,
    pause: &Pause<'_>,
) -> Result<Leg<Report>, Error> {
    let Scheme::Embedded(tableau) = method.scheme else {
        return Err(Error::UnmetRequirement {
            method: method.name,
            needs: "fixed steps (a step size h)",
            reason: "tolerances apply to methods with an error estimate".into(),
            suggestion: "dopri5 or dop853 for adaptive steps".into(),
        });
    };
    tol.validate()?;
    if !t0.is_finite() {
        return Err(Error::InvalidValue {
            name: "t0".into(),
            value: t0,
            allowed: "the start time must be finite",
        });
    }
    if !(t_end.is_finite() && t_end != t0) {
        return Err(Error::InvalidValue {
            name: "t_end".into(),
            value: t_end,
            allowed: "the end time must be finite and differ from the start (before it: a run backward in time)",
        });
    }
    // The direction of time: +1 forward, −1 backward. Step sizes are kept positive; the
    // loop compares times in the run's direction (d·t, exact), so a forward run is the same
    // bits as before backward runs existed.
    let d = if t_end < t0 { -1.0 } else { 1.0 };
    let system = Counted::new(model);
    let mut stepper = EmbeddedRk::new(tableau, y0.len());
    let mut control = PiController::new(tableau.control);
    let dense = observer.wants_dense();
    let report = |outcome, y: Vec<f64>, rejected, system: &Counted<'_, M>| Report {
        outcome,
        rhs_evals: system.evaluations(),
        state: y,
        steps_rejected: rejected,
        jacobian_evals: system.jacobians.get(),
    };
    let (mut y, mut at) = match from {
        None => {
            let y = y0.to_vec();
            if y.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFinite { t: t0 });
            }
            if let ControlFlow::Break(stop) = observer.observe(&Sample::new(0, t0, &y, false)) {
                stop.into_result()?;
                return Ok(Leg::Done(report(Outcome::Stopped { steps: 0, t: t0 }, y, 0, &system)));
            }
            let h = h0
                .map(f64::abs)
                .unwrap_or_else(|| initial_step(&system, t0, d, &y, method.order, tol))
                .min(tol.h_max)
                .min(d * (t_end - t0));
            (y, Position { t: t0, h, accepted: 0, rejected: 0, just_rejected: false })
        }
        Some(state) => {
            state.check(y0.len())?;
            stepper.restore_all(&state.stepper, "the dopri5/dop853 stepper")?;
            let mut r = Reader::new(&state.control.0, "the step-size controller");
            let (h, just_rejected) = (r.f64()?, r.bool()?);
            control.restore(&mut r)?;
            r.finish()?;
            if !(d * state.t < d * t_end && h.is_finite() && h > 0.0) {
                return Err(Error::BadCheckpoint {
                    part: "the run",
                    reason: format!(
                        "it is at t = {} s with a next step of {h} s, to end at {t_end} s",
                        state.t
                    ),
                });
            }
            system.set_counts(state.evaluations);
            let at =
                Position { t: state.t, h, accepted: state.steps, rejected: state.rejected, just_rejected };
            (state.y.clone(), at)
        }
    };
    loop {
        let Position { t, mut h, .. } = at;
        // Land on t_end exactly; stretch a last step that would leave a sliver.
        let last = d * t + 1.01 * h >= d * t_end;
        if last {
            h = d * (t_end - t);
        }
        // Never below what the end time can resolve: a smaller step would need more than
        // 1/(16 ε) ≈ 3·10¹⁴ steps to get there, and at t = 0 a floor of 16 ε |t| alone is 0,
        // which let a rejected step shrink to 0 and the run stall for ever.
        let floor = tol.h_min.max(16.0 * f64::EPSILON * t.abs().max(t_end.abs()));
        if h < floor && !last {
            return Err(Error::StepSizeTooSmall { t, h });
        }
        stepper.attempt(&system, t, d * h, &y);
        let err = stepper.error_norm(&y, tol.rtol, tol.atol);
        match control.judge(h, err) {
            Verdict::Accept(next) => {
                let t_new = if last { t_end } else { t + d * h };
                stepper.accept(&system, t, d * h, t_new, &mut y, dense);
                at.accepted += 1;
                at.t = t_new;
                if y.iter().any(|v| !v.is_finite()) {
                    return Err(Error::NonFinite { t: t_new });
                }
                let sample =
                    Sample { dense: stepper.dense_output(), ..Sample::new(at.accepted, t_new, &y, last) };
                if let ControlFlow::Break(stop) = observer.observe(&sample) {
                    stop.into_result()?;
                    let outcome = Outcome::Stopped { steps: at.accepted, t: t_new };
                    return Ok(Leg::Done(report(outcome, y, at.rejected, &system)));
                }
                if last {
                    break;
                }
                // After a rejection, do not grow the step at once (as DOPRI5 does).
                at.h = if at.just_rejected { next.min(h) } else { next }.min(tol.h_max);
                at.just_rejected = false;
                if pause.due(t_new) {
                    let mut control_words = Words::new();
                    control_words.f64(at.h);
                    control_words.bool(at.just_rejected);
                    control.save(&mut control_words);
                    return Ok(Leg::Paused(RunState {
                        steps: at.accepted,
                        t: t_new,
                        y,
                        rejected: at.rejected,
                        evaluations: system.counts(),
                        stepper: stepper.snapshot(),
                        control: control_words,
                    }));
                }
            }
            Verdict::Reject(next) => {
                at.rejected += 1;
                at.just_rejected = true;
                if next < floor {
                    return Err(Error::StepSizeTooSmall { t, h: next });
                }
                at.h = next;
            }
        }
    }
    let outcome = Outcome::ReachedEnd { steps: at.accepted, t: t_end };
    Ok(Leg::Done(Report { jacobian_evals: 0, ..report(outcome, y, at.rejected, &system) }))
}

/// A first step from the sizes of y₀, f(0, y₀) and an estimate of f', as Hairer's DOPRI5 and
/// DOP853 codes choose it (`HINIT`; Hairer, Nørsett, Wanner §II.4, "Starting step size"):
/// h₀ = 0.01 ‖y₀‖/‖f₀‖, one Euler step to estimate ‖f'‖, then h₁ = (0.01 / max(‖f₀‖,
/// ‖f'‖))^(1/p) with p the method's order, and the smaller of 100 h₀ and h₁. Norms are
/// weighted sums of squares (not means), as in the codes.
///
/// The run starts at `t0` in direction `d` (±1); the step returned is a size (> 0).
fn initial_step<S: System + ?Sized>(
    system: &S,
    t0: f64,
    d: f64,
    y0: &[f64],
    order: u32,
    tol: &Tolerances,
) -> f64 {
    let n = y0.len();
    let scale: Vec<f64> = y0.iter().map(|v| tol.atol + tol.rtol * v.abs()).collect();
    let norm2 = |v: &[f64]| v.iter().zip(&scale).map(|(a, s)| (a / s) * (a / s)).sum::<f64>();
    let mut f0 = vec![0.0; n];
    system.rhs(t0, y0, &mut f0);
    let (dny, dnf) = (norm2(y0), norm2(&f0));
    let h0 = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { 0.01 * (dny / dnf).sqrt() }.min(tol.h_max);
    let y1: Vec<f64> = y0.iter().zip(&f0).map(|(y, f)| y + d * h0 * f).collect();
    let mut f1 = vec![0.0; n];
    system.rhs(t0 + d * h0, &y1, &mut f1);
    let diff: Vec<f64> = f1.iter().zip(&f0).map(|(a, b)| a - b).collect();
    let der2 = norm2(&diff).sqrt() / h0;
    let der12 = der2.max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { (0.01 / der12).powf(1.0 / order as f64) };
    (100.0 * h0).min(h1)
}
