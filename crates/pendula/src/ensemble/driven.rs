//! Stroboscopic sampling of many damped, driven pendulums ([`DrivenPendulum`]) on the
//! ensemble engine: lanes of [`LANES`] pendulums advanced by RK4 in structure-of-arrays
//! form with the engine's branch-free sine, `multiversion` dispatch and rayon over chunks.
//!
//! Each member takes `steps_per_period` steps per drive period T = 2π/ω_D (its own step
//! h = T/M), so the drive phase after k steps is 2πk/M for every member: the drive values
//! cos(2π j/(2M)) at the steps and half-steps are one table shared by all lanes. Once per
//! period the angle is wrapped into [−π, π) and, after the member's transient, (θ, ω) is
//! recorded — the Poincaré section of the extended phase space at phase 0.
//!
//! Determinism: as for the double pendulums (see [`super`]), a member's samples do not
//! depend on its lane, chunk or thread.

use rayon::prelude::*;

use super::{LANES, has_fma, trig};
use crate::Error;
use crate::system::driven::DrivenPendulum;

/// One member: a driven pendulum, its start (θ, ω), and how many whole periods to discard.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrivenMember {
    /// The pendulum.
    pub pendulum: DrivenPendulum,
    /// Initial (θ, ω).
    pub state: [f64; 2],
    /// Drive periods run before the first sample.
    pub transient_periods: u64,
}

/// Whether the stroboscopic kernel runs members of `info`'s system (the driven pendulum):
/// callers choose it by this, not by name.
pub fn runs(info: &crate::system::SystemInfo) -> bool {
    std::ptr::eq(info, <DrivenPendulum as crate::system::Model>::INFO)
}

/// How to sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StroboSpec {
    /// RK4 steps per drive period (M ≥ 4).
    pub steps_per_period: u32,
    /// Samples per member, one per period after its transient.
    pub samples: usize,
}

/// Members per parallel work item.
const CHUNK: usize = 64;

/// Samples every member: `out[(member · samples + s) · 2 ..]` receives (θ, ω) of sample s.
///
/// # Errors
/// The first member (in index order) whose state became non-finite, with the time.
///
/// # Panics
/// If `out` does not hold members × samples × 2 values or `steps_per_period < 4`.
pub fn stroboscopic(members: &[DrivenMember], spec: &StroboSpec, out: &mut [f64]) -> Result<(), Error> {
    let per_member = spec.samples * 2;
    assert_eq!(out.len(), members.len() * per_member, "members × samples × 2 values");
    assert!(spec.steps_per_period >= 4, "at least 4 steps per period");
    let m = spec.steps_per_period as usize;
    let two_pi = 2.0 * std::f64::consts::PI;
    // cos(2π j/(2M)) for j = 0 … 2M: the drive at every step and half-step of a period.
    let drive: Vec<f64> = (0..=2 * m).map(|j| (two_pi * j as f64 / (2 * m) as f64).cos()).collect();
    let failures: Vec<(usize, f64)> = out
        .par_chunks_mut(CHUNK * per_member)
        .enumerate()
        .filter_map(|(c, rows)| {
            let start = c * CHUNK;
            let chunk = &members[start..start + rows.len() / per_member.max(1)];
            let mut first: Option<(usize, f64)> = None;
            for (g, (group, rows)) in chunk.chunks(LANES).zip(rows.chunks_mut(LANES * per_member)).enumerate()
            {
                if let Err((i, t)) = run_group(group, spec, &drive, rows) {
                    first.get_or_insert((start + g * LANES + i, t));
                }
            }
            first
        })
        .collect();
    match failures.into_iter().min_by_key(|&(member, _)| member) {
        Some((member, t)) => Err(Error::NonFiniteMember { member, t }),
        None => Ok(()),
    }
}

/// Structure-of-arrays state of a lane group.
struct Lanes {
    theta: [f64; LANES],
    omega: [f64; LANES],
    h: [f64; LANES],
    /// The quality factor q (the damping rate is 1/q).
    q: [f64; LANES],
    amplitude: [f64; LANES],
}

/// A lane group's periods; on failure, the lane that became non-finite first (in index
/// order) and when.
fn run_group(
    group: &[DrivenMember],
    spec: &StroboSpec,
    drive: &[f64],
    rows: &mut [f64],
) -> Result<(), (usize, f64)> {
    let pick = |i: usize| group[i.min(group.len() - 1)];
    let m = spec.steps_per_period as f64;
    let mut lanes = Lanes {
        theta: std::array::from_fn(|i| pick(i).state[0]),
        omega: std::array::from_fn(|i| pick(i).state[1]),
        h: std::array::from_fn(|i| 2.0 * std::f64::consts::PI / pick(i).pendulum.drive_frequency / m),
        q: std::array::from_fn(|i| pick(i).pendulum.q),
        amplitude: std::array::from_fn(|i| pick(i).pendulum.drive_amplitude),
    };
    let per_member = spec.samples * 2;
    let last_period = group.iter().map(|g| g.transient_periods).max().unwrap_or(0) + spec.samples as u64;
    for period in 0..last_period {
        let before = (lanes.theta, lanes.omega);
        let fast = if has_fma() {
            period_kernel::<true, false>(&mut lanes, drive)
        } else {
            period_kernel::<false, false>(&mut lanes, drive)
        };
        if !fast {
            // An angle was beyond the sine's fast range (rare: the first period, before any
            // wrap, or an enormous ω): the period again, reducing such angles exactly.
            (lanes.theta, lanes.omega) = before;
            if has_fma() {
                period_kernel::<true, true>(&mut lanes, drive);
            } else {
                period_kernel::<false, true>(&mut lanes, drive);
            }
        }
        for (i, member) in group.iter().enumerate() {
            let (theta, omega) = (lanes.theta[i], lanes.omega[i]);
            if !(theta.is_finite() && omega.is_finite()) {
                return Err((i, (period + 1) as f64 * lanes.h[i] * m));
            }
            // Wrap into [−π, π): the equations are 2π-periodic in θ, and the sine's argument
            // stays small however long the run.
            let wrapped = crate::system::wrap_angle(theta);
            lanes.theta[i] = wrapped;
            if period >= member.transient_periods {
                let s = (period - member.transient_periods) as usize;
                if s < spec.samples {
                    let at = i * per_member + 2 * s;
                    rows[at] = wrapped;
                    rows[at + 1] = omega;
                }
            }
        }
    }
    Ok(())
}

dispatched! {
/// One drive period of RK4 steps for every lane. Not `WIDE`: the fast sine alone, tracking per
/// lane the largest |ω| at the steps' starts (data flow only: a branch in the loop would slow
/// it), and whether that proves every sine's argument was in the fast range
/// ([`stayed_fast`]) — if not, the results may be wrong. `WIDE`: angles beyond the fast range
/// reduced exactly, per lane (true); the others get the same bits.
fn period_kernel<const FMA: bool, const WIDE: bool>(lanes: &mut Lanes, drive: &[f64]) -> bool {
    let steps = (drive.len() - 1) / 2;
    let Lanes { theta, omega, h, q, amplitude } = lanes;
    // The system's own equation (`DrivenPendulum::acceleration`), one lane at a time in the
    // engine arithmetic, with the drive's cosine from the shared table.
    let accel = |th: f64, w: f64, q: f64, amplitude: f64, c: f64| {
        let one = |x: f64| -> crate::num::Lanes<1, FMA, WIDE> { crate::num::Lanes([x]) };
        let pendulum =
            DrivenPendulum { q: one(q), drive_amplitude: one(amplitude), drive_frequency: one(0.0) };
        pendulum.acceleration(one(th), one(w), one(c)).0[0]
    };
    // max(x, r) by a comparison, not f64::max: one instruction, and a NaN x (which either path
    // turns into NaN) leaves r as it was.
    let max = |x: f64, r: f64| if x > r { x } else { r };
    let start = *theta;
    let mut fastest = [0.0; LANES];
    for k in 0..steps {
        let (c0, c_half, c1) = (drive[2 * k], drive[2 * k + 1], drive[2 * k + 2]);
        for i in 0..LANES {
            let (th, w, h, b, a) = (theta[i], omega[i], h[i], q[i], amplitude[i]);
            let hh = 0.5 * h;
            let k1 = accel(th, w, b, a, c0);
            let (th2, w2) = (th + hh * w, w + hh * k1);
            let k2 = accel(th2, w2, b, a, c_half);
            let (th3, w3) = (th + hh * w2, w + hh * k2);
            let k3 = accel(th3, w3, b, a, c_half);
            let (th4, w4) = (th + h * w3, w + h * k3);
            let k4 = accel(th4, w4, b, a, c1);
            if !WIDE {
                fastest[i] = max(w.abs(), fastest[i]);
            }
            let h6 = h / 6.0;
            theta[i] = th + h6 * (w + 2.0 * w2 + 2.0 * w3 + w4);
            omega[i] = w + h6 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
    }
    WIDE || (0..LANES).all(|i| stayed_fast(start[i], fastest[i], h[i], 1.0 / q[i], amplitude[i], steps))
}
}

/// Whether every sine argument of a lane's period was within the fast range, given |θ₀| at the
/// period's start, the largest |ω| at its steps' starts (V), and the lane's step h, damping b
/// and amplitude A. While the arguments are in range the sine is at most 1, so every slope
/// k = −bω − sin θ + A cos(…) has |k| ≤ |b||ω| + B, B = 1 + |A|, and the stage velocities of a
/// step from ω (ω₂ = ω + hk₁/2, ω₃ = ω + hk₂/2, ω₄ = ω + hk₃) differ from ω by at most
/// X/2, X/2 (1 + h|b|/2) and X (1 + h|b|/2 (1 + h|b|/2)) ≤ X (1 + h|b| + (h|b|)²), with
/// X = h(|b|V + B): all within S = V + X (1 + h|b| + (h|b|)²). Every argument (θ + hω/2,
/// θ + hω₂/2, θ + hω₃) and every step of θ then moves at most hS, so by induction over the
/// steps all arguments lie within |θ₀| + M h S, M steps; rounding adds at most ulp(2²⁰) per
/// step, well inside the margin of 10⁻⁹ rad per step allowed here. NaN passes (either path
/// gives NaN).
fn stayed_fast(theta0: f64, fastest: f64, h: f64, b: f64, a: f64, steps: usize) -> bool {
    let hb = h * b.abs();
    let x = h * (b.abs() * fastest + 1.0 + a.abs());
    let s = fastest + x * (1.0 + hb + hb * hb);
    let bound = theta0.abs() + steps as f64 * (h * s + 1e-9);
    bound <= trig::FAST_RANGE || bound.is_nan()
}
