//! One double pendulum with RK4 through the ensemble engine's arithmetic: the fast path of
//! `pendula simulate double --method rk4`, resumable like [`crate::simulate::resume::solve_resumable`].

use super::{has_fma, trig};
use crate::checkpoint::{Leg, Pause, Reader, RunState, Words};
use crate::num::Lanes;
use crate::observe::Pausing;
use std::ops::ControlFlow;

use crate::observe::{Observer, Sample};
use crate::simulate::Schedule;
use crate::system::double::DoublePendulum;
use crate::{Error, Outcome, Report, RunSpec};

/// One double pendulum with RK4 through the engine's arithmetic (branch-free sine and cosine,
/// fused multiply-adds where the CPU has them), showing every state, with its energy
/// ([`crate::observe::Sample::energy`]), to `observer`: the
/// fast path of `pendula simulate double --method rk4`. It follows [`crate::Simulation::run`]
/// (schedule, first sample, the shortened last step, [`crate::Error::NonFinite`] with the
/// time, an observer's stop) and differs from the general path only by rounding (≈1e-11 at
/// t = 10 s on the chaotic default orbit).
///
/// # Errors
/// A damped or driven pendulum ([`crate::Error::UnmetRequirement`]: the kernel implements
/// the free equations); an invalid `spec`; [`crate::Error::NonFinite`] at the first
/// non-finite state.
pub fn rk4_trajectory(
    pendulum: &DoublePendulum,
    y0: &[f64],
    spec: &RunSpec,
    observer: &mut dyn Observer,
) -> Result<Report, Error> {
    match rk4_trajectory_resumable(pendulum, y0, spec, observer, None, &Pause::NEVER)? {
        Leg::Done(report) => Ok(report),
        Leg::Paused(state) => unreachable!("a run that never pauses paused at step {}", state.steps),
    }
}

/// [`rk4_trajectory`] that pauses when `pause` says so (after a step, never the last) and
/// continues `from` a state it paused at, bit for bit. The state is the step index and the
/// four variables (the trigonometry is recomputed from them, as after every step), and
/// whether fused multiply-adds were used: a state saved with them is refused on a CPU
/// without (it would round differently); one saved without continues without them.
///
/// # Errors
/// As [`rk4_trajectory`]; [`Error::BadCheckpoint`] when `from` does not fit.
pub fn rk4_trajectory_resumable(
    pendulum: &DoublePendulum,
    y0: &[f64],
    spec: &RunSpec,
    observer: &mut dyn Observer,
    from: Option<&RunState>,
    pause: &Pause<'_>,
) -> Result<Leg<Report>, Error> {
    if pendulum.is_forced() {
        return Err(Error::UnmetRequirement {
            method: "ensemble::rk4_trajectory",
            needs: "an undamped, undriven double pendulum",
            reason: format!(
                "this one has damping = {} and drive_amplitude = {}",
                pendulum.damping, pendulum.drive_amplitude
            ),
            suggestion: "pendula::solve with RK4".into(),
        });
    }
    let schedule = spec.schedule()?;
    let mut y: [f64; 4] = y0.try_into().expect("four state variables");
    if y.iter().any(|v| !v.is_finite()) {
        return Err(Error::NonFinite { t: spec.t0 });
    }
    let (done, fma) = match from {
        None => (0, has_fma()),
        Some(state) => {
            state.check(4)?;
            let mut r = Reader::new(&state.stepper.0, "the rk4 fast path");
            let fma = r.bool()?;
            r.finish()?;
            if fma && !has_fma() {
                return Err(Error::BadCheckpoint {
                    part: "the rk4 fast path",
                    reason: "it was computed with fused multiply-adds, which this CPU lacks".into(),
                });
            }
            if state.steps >= schedule.steps {
                return Err(Error::BadCheckpoint {
                    part: "the run",
                    reason: format!(
                        "it is at step {}, and the run has {} steps",
                        state.steps, schedule.steps
                    ),
                });
            }
            y.copy_from_slice(&state.y);
            (state.steps, fma)
        }
    };
    let p = pendulum;
    // The kernel's loop is the same whether it may pause or not: the check is the
    // observer's (see `Simulation::run_from`).
    let mut pausing = Pausing::new(observer, pause);
    let (steps, outcome) = match (fma, pause.never()) {
        (true, true) => trajectory_kernel::<true, _>(p, &mut y, spec, &schedule, done, pausing.inner())?,
        (false, true) => {
            super::plain!(trajectory_kernel::<false, _>(p, &mut y, spec, &schedule, done, pausing.inner())?)
        }
        (true, false) => trajectory_kernel::<true, _>(p, &mut y, spec, &schedule, done, &mut pausing)?,
        (false, false) => {
            super::plain!(trajectory_kernel::<false, _>(p, &mut y, spec, &schedule, done, &mut pausing)?)
        }
    };
    Ok(match (!pausing.paused).then_some(outcome) {
        Some(outcome) => Leg::Done(Report {
            outcome,
            rhs_evals: 4 * steps,
            state: y.to_vec(),
            steps_rejected: 0,
            jacobian_evals: 0,
        }),
        None => {
            let mut stepper = Words::new();
            stepper.bool(fma);
            Leg::Paused(RunState {
                steps,
                t: spec.t0 + steps as f64 * spec.h,
                y: y.to_vec(),
                rejected: 0,
                evaluations: [4 * steps, 0, 0],
                stepper,
                control: Words::new(),
            })
        }
    })
}

/// The trigonometry of a state: (sin, cos) of θ₁ − θ₂, θ₁ and θ₂ — what both the
/// accelerations and the energy need, computed once per step (one test of the angles picks
/// the fast path for all three, or the path for every angle).
#[inline(always)]
fn trig_of<const FMA: bool>(y: &[f64; 4]) -> [(f64, f64); 3] {
    if fast_pair(y[0], y[1]) { trig_of_with::<FMA, false>(y) } else { trig_of_with::<FMA, true>(y) }
}

/// Whether the fast trigonometry serves a, b and a − b ([`trig::is_fast`]).
#[inline(always)]
fn fast_pair(a: f64, b: f64) -> bool {
    trig::is_fast(a) & trig::is_fast(b) & trig::is_fast(a - b)
}

/// [`trig_of`] with `trig`'s fast path alone (`WIDE` false) or for every angle.
#[inline(always)]
fn trig_of_with<const FMA: bool, const WIDE: bool>(y: &[f64; 4]) -> [(f64, f64); 3] {
    let sc = trig::sin_cos_with::<FMA, WIDE>;
    [sc(y[0] - y[1]), sc(y[0]), sc(y[1])]
}

/// The energy T + V of one double pendulum ([`DoublePendulum::energy_from`], in the
/// reference arithmetic) from its trigonometry.
#[inline(always)]
fn energy_from(p: &DoublePendulum, y: &[f64; 4], tr: &[(f64, f64); 3]) -> f64 {
    p.energy_from(y, [tr[0].1, tr[1].1, tr[2].1])
}

/// One pendulum in the engine arithmetic: one lane.
type One<const FMA: bool, const WIDE: bool> = Lanes<1, FMA, WIDE>;

/// θ' = ω and the accelerations of one double pendulum ([`DoublePendulum::accelerations`] in
/// the engine arithmetic, one lane: the bits a lane of the ensemble engine gets) from `trig`
/// = (sin(θ₁ − θ₂), cos(θ₁ − θ₂), sin θ₁, sin θ₂). The free pendulum's: no time needed.
#[inline(always)]
fn accelerations_from<const FMA: bool>(p: &DoublePendulum, y: &[f64; 4], trig: [f64; 4]) -> [f64; 4] {
    let one = |x: f64| -> One<FMA, false> { Lanes([x]) };
    let [a1, a2] = p.map(one).accelerations_from(one(0.0), &y.map(one), trig.map(one));
    [y[2], y[3], a1.0[0], a2.0[0]]
}

/// The accelerations of one double pendulum at y (as [`trig_of`], one test of the angles).
#[inline(always)]
fn accelerations_one<const FMA: bool>(p: &DoublePendulum, y: &[f64; 4]) -> [f64; 4] {
    if fast_pair(y[0], y[1]) {
        accelerations_one_with::<FMA, false>(p, y)
    } else {
        accelerations_one_with::<FMA, true>(p, y)
    }
}

/// [`accelerations_one`] with `trig`'s fast path alone (`WIDE` false) or for every angle.
#[inline(always)]
fn accelerations_one_with<const FMA: bool, const WIDE: bool>(p: &DoublePendulum, y: &[f64; 4]) -> [f64; 4] {
    let one = |x: f64| -> One<FMA, WIDE> { Lanes([x]) };
    let [a1, a2] = p.map(one).accelerations(one(0.0), &y.map(one));
    [y[2], y[3], a1.0[0], a2.0[0]]
}

dispatched! {
/// Steps from `done` (showing the initial state first when it is 0): the steps taken and how
/// the run ended.
fn trajectory_kernel<const FMA: bool, O: Observer + ?Sized>(
    p: &DoublePendulum,
    y: &mut [f64; 4],
    spec: &RunSpec,
    schedule: &Schedule,
    done: u64,
    observer: &mut O,
) -> Result<(u64, Outcome), Error> {
    let (t0, h) = (spec.t0, spec.h);
    let mut tr = trig_of::<FMA>(y);
    if done == 0
        && let ControlFlow::Break(stop) =
            observer.observe(&Sample { energy: Some(energy_from(p, y, &tr)), ..Sample::new(0, t0, y, false) })
    {
        stop.into_result()?;
        return Ok((0, Outcome::Stopped { steps: 0, t: t0 }));
    }
    let m = trig::madd::<FMA>;
    for k in done + 1..=schedule.steps {
        let last = k == schedule.steps;
        let step = if last { schedule.last_h } else { h };
        let (hh, h6) = (0.5 * step, step / 6.0);
        let k1 = accelerations_from::<FMA>(p, y, [tr[0].0, tr[0].1, tr[1].0, tr[2].0]);
        let k2 = accelerations_one::<FMA>(p, &std::array::from_fn(|c| m(hh, k1[c], y[c])));
        let k3 = accelerations_one::<FMA>(p, &std::array::from_fn(|c| m(hh, k2[c], y[c])));
        let k4 = accelerations_one::<FMA>(p, &std::array::from_fn(|c| m(step, k3[c], y[c])));
        for c in 0..4 {
            y[c] = m(h6, m(2.0, k2[c] + k3[c], k1[c]) + k4[c], y[c]);
        }
        let t = if last { schedule.t_end } else { t0 + k as f64 * h };
        if y.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite { t });
        }
        tr = trig_of::<FMA>(y);
        if let ControlFlow::Break(stop) =
            observer.observe(&Sample { energy: Some(energy_from(p, y, &tr)), ..Sample::new(k, t, y, last) })
        {
            stop.into_result()?;
            return Ok((k, Outcome::Stopped { steps: k, t }));
        }
    }
    Ok((schedule.steps, Outcome::ReachedEnd { steps: schedule.steps, t: schedule.t_end }))
}
}
