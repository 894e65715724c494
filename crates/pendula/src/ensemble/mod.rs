//! Ensembles. [`engine`] runs every catalogued system with every explicit Runge–Kutta
//! method on lanes, from the systems' own equations ([`crate::num::Lanes`]). This module is
//! the double pendulum's typed front to it ([`Member`], [`BatchSpec`]: the fractal's and the
//! benchmarks' form), and Tao's map on lanes for the free double pendulum (its Hamiltonian
//! gradient is the pendulum's own, [`DoublePendulum::hamiltonian_gradient`], one pendulum
//! per lane).
//!
//! Many double pendulums advanced together, in lanes of
//! [`LANES`] structure-of-arrays values that the compiler turns into SIMD (8 f64 per AVX-512
//! vector, 4 per AVX2), with branch-free sine and cosine ([`trig`]), CPU dispatch at run
//! time (`multiversion`, with a portable fallback), and rayon across cores.
//!
//! Determinism: lanes never interact and every lane runs the same operations in the same
//! order, so a member's result does not depend on which lane, chunk or thread computes it:
//! results are bitwise identical for any thread count, any chunking (shards), and any of
//! the dispatched instruction sets (no fused multiply-add is introduced: Rust does not
//! contract a·b + c).
//!
//! A member that flips (with [`BatchSpec::stop_at_flip`]) retires: its lane keeps computing
//! (branch-free) but its state stays at the step where the flip was seen. A non-finite state
//! is an error naming the member and the time.

pub mod driven;
pub mod engine;
mod trajectory;

pub use crate::num::trig;

pub use trajectory::{rk4_trajectory, rk4_trajectory_resumable};

use rayon::prelude::*;

use crate::Error;
use crate::num::Num;
use crate::system::double::DoublePendulum;

/// One lane in the engine arithmetic.
type Lanes1<const FMA: bool, const WIDE: bool> = crate::num::Lanes<1, FMA, WIDE>;

/// Values per lane group: two AVX-512 vectors, four AVX2 vectors (16 measured fastest on
/// W3: 0.87 s on one core, against 1.14 s with 8 lanes and 0.92 s with 32).
pub const LANES: usize = 16;

/// Members per parallel work item (a multiple of [`LANES`]): large enough to amortise the
/// scheduling, small enough to balance the load of early-retiring members.
const CHUNK: usize = 256;

/// One double pendulum of an ensemble: its parameters and its initial state
/// (θ₁, θ₂, ω₁, ω₂).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Member {
    /// Masses, lengths, g.
    pub pendulum: DoublePendulum,
    /// Initial (θ₁, θ₂, ω₁, ω₂), rad and rad/s.
    pub state: [f64; 4],
}

/// The integration method of an ensemble run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BatchMethod {
    /// The classical Runge–Kutta method.
    Rk4,
    /// Tao's explicit symplectic map (tao-2, tao-4) on the Hamiltonian form (θ, p), with its
    /// composition weights and binding constant ω (see [`crate::integrator::tao`]).
    Tao(crate::integrator::tao::TaoScheme),
}

impl BatchMethod {
    /// The kernel form of `method`, if the double pendulum's kernels run it (RK4, tao-2,
    /// tao-4).
    pub fn of(method: &crate::integrator::Method) -> Option<BatchMethod> {
        use crate::integrator::Scheme;
        match method.scheme {
            Scheme::Tao(scheme) => Some(BatchMethod::Tao(scheme)),
            Scheme::ExplicitRk(t) => match crate::integrator::explicit_rk::RK4.scheme {
                Scheme::ExplicitRk(rk4) if std::ptr::eq(t, rk4) => Some(BatchMethod::Rk4),
                _ => None,
            },
            _ => None,
        }
    }
}

/// What to run: method, step and length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatchSpec {
    /// The method.
    pub method: BatchMethod,
    /// Step size, s.
    pub h: f64,
    /// Number of steps.
    pub steps: u64,
    /// Retire a member when it first flips (an angle passes ±π).
    pub stop_at_flip: bool,
    /// Record flip times (implied by `stop_at_flip`); without, `flip_time` is NaN and the
    /// kernel skips the bookkeeping.
    pub track_flips: bool,
}

/// A member's results.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemberResult {
    /// State at the end (or where the member retired).
    pub state: [f64; 4],
    /// Time of the first flip, s, or NaN if it did not flip: where the cubic Hermite
    /// interpolant of the crossing angle over the step (its values and rates at both ends)
    /// passes ±π, as [`crate::events`] locates a `flip` on a fixed-step run.
    pub flip_time: f64,
}

/// Stores member i's final state and flip time into its row.
pub type StoreValues<'a, T> = dyn Fn(usize, &[f64], f64, &mut [T]) + Sync + 'a;

/// Stores member i's result into its row.
type StoreIndexed<'a, T> = dyn Fn(usize, &Member, &MemberResult, &mut [T]) + Sync + 'a;

/// [`run_into`] with members given by their values, in the order of the double pendulum's
/// catalogue entry (m1, m2, l1, l2, g, damping, drive_amplitude, drive_frequency, θ₁, θ₂, ω₁,
/// ω₂), written by `member(i, values)`; each result stored with `store(i, state, flip_time,
/// row)`.
///
/// # Errors
/// As [`run_into`].
pub fn run_values<T: Send>(
    count: usize,
    member: &(dyn Fn(usize, &mut [f64]) + Sync),
    spec: &BatchSpec,
    out: &mut [T],
    row_len: usize,
    store: &StoreValues<'_, T>,
) -> Result<(), Error> {
    use crate::system::Model;
    let info = DoublePendulum::INFO;
    let np = info.parameters.len();
    let of = |i: usize| {
        let mut v = [0.0; 12];
        member(i, &mut v);
        let value = |name: &str| {
            let k = info.parameters.iter().position(|q| q.name == name);
            v[k.unwrap_or_else(|| panic!("the double pendulum has no {name}"))]
        };
        Member { pendulum: DoublePendulum::over(&value, &value), state: std::array::from_fn(|k| v[np + k]) }
    };
    run_indexed(count, &of, spec, out, row_len, &|i, _, r: &MemberResult, row: &mut [T]| {
        store(i, &r.state, r.flip_time, row);
    })
}

/// Runs every member, in parallel on rayon's current pool, writing `out[i]` for `members[i]`.
///
/// # Errors
/// With Tao's map, [`Error::UnmetRequirement`] for the first member (in index order) that is
/// damped or driven; else [`Error::NonFiniteMember`] for the first whose state became
/// non-finite.
pub fn run(members: &[Member], spec: &BatchSpec, out: &mut [MemberResult]) -> Result<(), Error> {
    assert_eq!(members.len(), out.len(), "one result per member");
    run_into(members.len(), &|i| members[i], spec, out, 1, &|_, r, row| row[0] = *r)
}

/// Runs `count` members made on demand by `member(i)`, in parallel on rayon's current pool,
/// and stores each result with `store(member, result, row)` into its row of `out` (rows of
/// `row_len` values): memory beyond `out` is a few chunks per thread, whatever the count.
///
/// # Errors
/// With Tao's map, [`Error::UnmetRequirement`] for the first member (in index order) that is
/// damped or driven; else [`Error::NonFiniteMember`] for the first whose state became
/// non-finite.
pub fn run_into<T: Send>(
    count: usize,
    member: &(dyn Fn(usize) -> Member + Sync),
    spec: &BatchSpec,
    out: &mut [T],
    row_len: usize,
    store: &(dyn Fn(&Member, &MemberResult, &mut [T]) + Sync),
) -> Result<(), Error> {
    run_indexed(count, member, spec, out, row_len, &|_, m, r, row| store(m, r, row))
}

/// [`run_into`], the store told each member's index.
fn run_indexed<T: Send>(
    count: usize,
    member: &(dyn Fn(usize) -> Member + Sync),
    spec: &BatchSpec,
    out: &mut [T],
    row_len: usize,
    store: &StoreIndexed<'_, T>,
) -> Result<(), Error> {
    assert_eq!(out.len(), count * row_len, "one row per member");
    let scheme = match spec.method {
        BatchMethod::Rk4 => return run_rk4_on_engine(count, member, spec, out, row_len, store),
        BatchMethod::Tao(scheme) => scheme,
    };
    if let Some(member) = (0..count).find(|&i| member(i).pendulum.is_forced()) {
        return Err(Error::UnmetRequirement {
            method: "tao on lanes",
            needs: "a free double pendulum",
            reason: format!("member {member} is damped or driven"),
            suggestion: "rk4 on lanes, or one run per member (pendula::solve)",
        });
    }
    let failures: Vec<(usize, f64)> = out
        .par_chunks_mut(CHUNK * row_len)
        .enumerate()
        .filter_map(|(c, rows)| {
            let start = c * CHUNK;
            let members: Vec<Member> = (start..start + rows.len() / row_len).map(member).collect();
            let mut results = vec![MemberResult { state: [0.0; 4], flip_time: f64::NAN }; members.len()];
            let failed = run_chunk(&members, scheme, spec, &mut results);
            for (j, ((m, r), row)) in members.iter().zip(&results).zip(rows.chunks_mut(row_len)).enumerate() {
                store(start + j, m, r, row);
            }
            failed.map(|(i, t)| (start + i, t))
        })
        .collect();
    match failures.into_iter().min_by_key(|&(m, _)| m) {
        Some((member, t)) => Err(Error::NonFiniteMember { member, t }),
        None => Ok(()),
    }
}

/// RK4 on the general engine ([`engine::run`]), forces included.
fn run_rk4_on_engine<T: Send>(
    count: usize,
    member: &(dyn Fn(usize) -> Member + Sync),
    spec: &BatchSpec,
    out: &mut [T],
    row_len: usize,
    store: &StoreIndexed<'_, T>,
) -> Result<(), Error> {
    use crate::system::Model;
    let crate::integrator::Scheme::ExplicitRk(tableau) = crate::integrator::explicit_rk::RK4.scheme else {
        unreachable!("RK4 is an explicit Runge-Kutta method")
    };
    let lanes = engine::LaneSpec {
        tableau,
        h: spec.h,
        steps: spec.steps,
        stop_at_flip: spec.stop_at_flip,
        track_flips: spec.track_flips,
    };
    let values = |i: usize, v: &mut [f64]| {
        let Member { pendulum: d, state } = member(i);
        let p = [d.m1, d.m2, d.l1, d.l2, d.g, d.damping, d.drive_amplitude, d.drive_frequency];
        v[..8].copy_from_slice(&p);
        v[8..].copy_from_slice(&state);
    };
    let store = |i: usize, o: &engine::LaneOutcome, row: &mut [T]| {
        let r = MemberResult { state: std::array::from_fn(|k| o.state[k]), flip_time: o.flip_time };
        store(i, &member(i), &r, row);
    };
    engine::run::<DoublePendulum, T>(DoublePendulum::INFO, count, &values, &lanes, out, row_len, &store)
}

/// Runs a chunk of members serially with Tao's map, in lane groups; the last group is padded
/// with copies of its last member, whose results are dropped. The first member (in index
/// order) whose state became non-finite, and when.
fn run_chunk(
    members: &[Member],
    scheme: crate::integrator::tao::TaoScheme,
    spec: &BatchSpec,
    out: &mut [MemberResult],
) -> Option<(usize, f64)> {
    let mut first_failure = None;
    for (g, (group, results)) in members.chunks(LANES).zip(out.chunks_mut(LANES)).enumerate() {
        let pick = |i: usize| group[i.min(group.len() - 1)];
        let mut lanes = Lanes {
            state: std::array::from_fn(|k| std::array::from_fn(|i| pick(i).state[k])),
            flip_step: [-1.0; LANES],
            flip_ends: [[[0.0; LANES]; 4]; 2],
            failed_at: [f64::NAN; LANES],
        };
        let pendulums: [DoublePendulum; LANES] = std::array::from_fn(|i| pick(i).pendulum);
        tao_lanes(&mut lanes, &pendulums, scheme, spec.h, spec.steps, spec.stop_at_flip);
        for (i, r) in results.iter_mut().enumerate() {
            *r = MemberResult {
                state: std::array::from_fn(|k| lanes.state[k][i]),
                flip_time: engine::flip_time(
                    lanes.flip_step[i],
                    [&lanes.flip_ends[0], &lanes.flip_ends[1]],
                    &[0, 1],
                    4,
                    i,
                    spec.h,
                ),
            };
            if !lanes.failed_at[i].is_nan() && first_failure.is_none() {
                first_failure = Some((g * LANES + i, lanes.failed_at[i]));
            }
        }
    }
    first_failure
}

/// A lane group: state (θ₁, θ₂, ω₁, ω₂) and per-lane records, each an array over the lanes.
struct Lanes {
    state: [[f64; LANES]; 4],
    /// The step in which the lane first flipped (−1: none), as a float.
    flip_step: [f64; LANES],
    /// (θ₁, θ₂, θ₁', θ₂') at the start and the end of that step: what the cubic Hermite
    /// interpolant of the angles needs: the Tao kernel stores (q, p), which `tao_lanes` turns into
    /// (q, ∂H/∂p) for the flipped lanes.
    flip_ends: [[V; 4]; 2],
    /// Time at which the lane's state became non-finite (NaN: never).
    failed_at: [f64; LANES],
}

type V = [f64; LANES];

/// Half the trigonometry's fast range: while |θ₁| and |θ₂| are within it, so are θ₁, θ₂ and
/// θ₁ − θ₂, and the fast path serves every sine and cosine the kernels take.
const HALF_FAST: f64 = 0.5 * trig::FAST_RANGE;

/// max(x, r) by a comparison, not `f64::max`: one vector instruction, and a NaN x (which either
/// path turns into NaN) leaves r as it was.
#[inline(always)]
fn max_of(x: f64, r: f64) -> f64 {
    if x > r { x } else { r }
}

/// Whether some lane's `reach` is beyond [`HALF_FAST`]: then a fast kernel run is wrong.
#[inline(always)]
fn beyond_half_fast(reach: &V) -> bool {
    reach.iter().fold(false, |beyond, &r| beyond | (r > HALF_FAST))
}

/// Whether this CPU has fused multiply-add instructions (then the trigonometric polynomials
/// use them: faster, and as accurate, but rounded differently from the plain kernel), so
/// that results computed in parts — a checkpoint continued later — are bit-identical only
/// on CPUs that answer the same.
pub fn has_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(target_arch = "aarch64")]
    {
        true
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        false
    }
}

/// The gradient (∂H/∂q₁, ∂H/∂q₂, ∂H/∂p₁, ∂H/∂p₂) of the free double pendulum's Hamiltonian at
/// (q, p) for every lane: [`DoublePendulum::hamiltonian_gradient`] over one lane at a time
/// (`Lanes<1, …>`, the engine arithmetic; the loop over lanes vectorises), from the raw
/// parameters m₁, m₂, l₁, l₂, g per lane. Not `WIDE`, `reach` = max(reach, |q₁|, |q₂|) per
/// lane, data flow only (a test and branch per stage instead cost the W3 sweep 12–17%).
#[inline(always)]
fn gradient<const FMA: bool, const WIDE: bool>(
    raw: &[V; 5],
    [q1, q2]: [&V; 2],
    [p1, p2]: [&V; 2],
    out: &mut [V; 4],
    reach: &mut V,
) {
    type One<const FMA: bool, const WIDE: bool> = Lanes1<FMA, WIDE>;
    for i in 0..LANES {
        if !WIDE {
            reach[i] = max_of(q2[i].abs(), max_of(q1[i].abs(), reach[i]));
        }
        let one = |x: f64| One::<FMA, WIDE>::splat(x);
        // Free: the forcing terms are constant zeros, folded away.
        let pendulum = DoublePendulum {
            m1: one(raw[0][i]),
            m2: one(raw[1][i]),
            l1: one(raw[2][i]),
            l2: one(raw[3][i]),
            g: one(raw[4][i]),
            damping: one(0.0),
            drive_amplitude: one(0.0),
            drive_frequency: one(0.0),
        };
        let g = pendulum.hamiltonian_gradient(one(0.0), [one(q1[i]), one(q2[i])], [one(p1[i]), one(p2[i])]);
        for k in 0..4 {
            out[k][i] = g[k].0[0];
        }
    }
}

/// Tao steps for a lane group: (θ, ω) → (q, p) with the libm cosine, the extended-space map
/// with the branch-free trigonometry, and back.
fn tao_lanes(
    lanes: &mut Lanes,
    pendulums: &[DoublePendulum; LANES],
    scheme: crate::integrator::tao::TaoScheme,
    h: f64,
    steps: u64,
    stop_at_flip: bool,
) {
    let mut z = [[0.0; LANES]; 4];
    for (i, d) in pendulums.iter().enumerate() {
        let y: [f64; 4] = std::array::from_fn(|k| lanes.state[k][i]);
        let p = d.momenta(&y);
        z[0][i] = y[0];
        z[1][i] = y[1];
        z[2][i] = p[0];
        z[3][i] = p[1];
    }
    let raw: [V; 5] = std::array::from_fn(|k| {
        std::array::from_fn(|i| {
            let d = pendulums[i];
            [d.m1, d.m2, d.l1, d.l2, d.g][k]
        })
    });
    // The fast kernel, and if it gave up (`lanes` and `z` left as they were), the wide one.
    let run = (h, steps);
    let done = if has_fma() {
        tao_kernel::<true, false>(lanes, &raw, &mut z, scheme, run, stop_at_flip)
    } else {
        tao_kernel::<false, false>(lanes, &raw, &mut z, scheme, run, stop_at_flip)
    };
    if !done {
        if has_fma() {
            tao_kernel::<true, true>(lanes, &raw, &mut z, scheme, run, stop_at_flip);
        } else {
            tao_kernel::<false, true>(lanes, &raw, &mut z, scheme, run, stop_at_flip);
        }
    }
    // The flipped lanes' rates θ' = ∂H/∂p at both ends of the flip's step, for the Hermite
    // interpolant (scalar, once per flipped member: the loop above stays branch-free).
    for (i, d) in pendulums.iter().enumerate().filter(|(i, _)| lanes.flip_step[*i] >= 0.0) {
        for end in &mut lanes.flip_ends {
            let mut w = [0.0; 2];
            crate::system::Hamiltonian::dh_dp(
                &d.form(),
                0.0,
                &[end[0][i], end[1][i]],
                &[end[2][i], end[3][i]],
                &mut w,
            );
            end[2][i] = w[0];
            end[3][i] = w[1];
        }
    }
    for (i, d) in pendulums.iter().enumerate() {
        let mut w = [0.0; 2];
        crate::system::Hamiltonian::dh_dp(&d.form(), 0.0, &[z[0][i], z[1][i]], &[z[2][i], z[3][i]], &mut w);
        lanes.state[0][i] = z[0][i];
        lanes.state[1][i] = z[1][i];
        lanes.state[2][i] = w[0];
        lanes.state[3][i] = w[1];
    }
}

/// The Tao map for a lane group on (q, p) in `z`, with the copies (x, y) kept here, `steps`
/// steps of size `h`. Not `WIDE`, the fast trigonometry alone: false, with `lanes` and `z`
/// untouched, after the first step in which an angle was beyond [`HALF_FAST`]; `WIDE`, every
/// angle (true).
// Compiled for several instruction sets, chosen at run time; debug builds (the tests)
// for AVX2 with FMA and the portable fallback only: the same arithmetic, a fraction of
// the build time.
#[cfg_attr(
    not(debug_assertions),
    multiversion::multiversion(targets(
        "x86_64+avx512f+avx512dq+avx2+fma",
        "x86_64+avx2+fma",
        "x86_64+avx+fma",
        "x86_64+avx",
        "x86_64+sse4.1",
        "aarch64+neon",
    ))
)]
#[cfg_attr(debug_assertions, multiversion::multiversion(targets("x86_64+avx2+fma", "aarch64+neon")))]
fn tao_kernel<const FMA: bool, const WIDE: bool>(
    lanes: &mut Lanes,
    raw: &[V; 5],
    z: &mut [V; 4],
    scheme: crate::integrator::tao::TaoScheme,
    (h, steps): (f64, u64),
    stop_at_flip: bool,
) -> bool {
    use std::f64::consts::PI;
    let [mut q1, mut q2, mut p1, mut p2] = *z;
    let (mut x1, mut x2, mut y1, mut y2) = (q1, q2, p1, p2);
    let mut grad = [[0.0; LANES]; 4];
    let mut active = [true; LANES];
    let mut flip_step = [-1.0; LANES];
    let [mut before, mut after] = [[[0.0; LANES]; 4]; 2];
    let mut failed_step = [-1.0; LANES];
    let mut reach = [0.0; LANES];
    for step in 0..steps {
        let old = [q1, q2, p1, p2];
        let (old_x, old_y) = ([x1, x2], [y1, y2]);
        for &w in scheme.weights {
            let half = 0.5 * w * h;
            // φ_A(δ/2) φ_B(δ/2) φ_C(δ) φ_B(δ/2) φ_A(δ/2), δ = w h.
            for phase in 0..5 {
                match phase {
                    0 | 4 => {
                        gradient::<FMA, WIDE>(raw, [&q1, &q2], [&y1, &y2], &mut grad, &mut reach);
                        for i in 0..LANES {
                            p1[i] -= half * grad[0][i];
                            p2[i] -= half * grad[1][i];
                            x1[i] += half * grad[2][i];
                            x2[i] += half * grad[3][i];
                        }
                    }
                    1 | 3 => {
                        gradient::<FMA, WIDE>(raw, [&x1, &x2], [&p1, &p2], &mut grad, &mut reach);
                        for i in 0..LANES {
                            q1[i] += half * grad[2][i];
                            q2[i] += half * grad[3][i];
                            y1[i] -= half * grad[0][i];
                            y2[i] -= half * grad[1][i];
                        }
                    }
                    _ => {
                        let (sin, cos) = (2.0 * scheme.binding * w * h).sin_cos();
                        for (q, p, x, y) in
                            [(&mut q1, &mut p1, &mut x1, &mut y1), (&mut q2, &mut p2, &mut x2, &mut y2)]
                        {
                            for i in 0..LANES {
                                let (sq, sp) = (q[i] + x[i], p[i] + y[i]);
                                let (dq, dp) = (q[i] - x[i], p[i] - y[i]);
                                let (rq, rp) = (cos * dq + sin * dp, -sin * dq + cos * dp);
                                q[i] = 0.5 * (sq + rq);
                                x[i] = 0.5 * (sq - rq);
                                p[i] = 0.5 * (sp + rp);
                                y[i] = 0.5 * (sp - rp);
                            }
                        }
                    }
                }
            }
        }
        if !WIDE && beyond_half_fast(&reach) {
            return false;
        }
        let step_f = step as f64;
        for i in 0..LANES {
            let finite = q1[i].is_finite() & q2[i].is_finite() & p1[i].is_finite() & p2[i].is_finite();
            let (o1, n1, o2, n2) = (old[0][i].abs(), q1[i].abs(), old[1][i].abs(), q2[i].abs());
            let (cross1, cross2) = ((o1 <= PI) & (n1 > PI), (o2 <= PI) & (n2 > PI));
            let flips = active[i] & finite & (cross1 | cross2) & (flip_step[i] < 0.0);
            flip_step[i] = if flips { step_f } else { flip_step[i] };
            let new = [q1[i], q2[i], p1[i], p2[i]];
            for k in 0..4 {
                before[k][i] = if flips { old[k][i] } else { before[k][i] };
                after[k][i] = if flips { new[k] } else { after[k][i] };
            }
            failed_step[i] = if active[i] & !finite { step_f } else { failed_step[i] };
            let keep = active[i] & finite;
            // A lane that stopped keeps its state (and copy) from before this step.
            q1[i] = if keep { q1[i] } else { old[0][i] };
            q2[i] = if keep { q2[i] } else { old[1][i] };
            p1[i] = if keep { p1[i] } else { old[2][i] };
            p2[i] = if keep { p2[i] } else { old[3][i] };
            x1[i] = if keep { x1[i] } else { old_x[0][i] };
            x2[i] = if keep { x2[i] } else { old_x[1][i] };
            y1[i] = if keep { y1[i] } else { old_y[0][i] };
            y2[i] = if keep { y2[i] } else { old_y[1][i] };
            // Unlike RK4, a flipped lane stopped here keeps the state after the flip.
            if keep & flips & stop_at_flip {
                active[i] = false;
            } else {
                active[i] = keep;
            }
        }
        if !active.iter().any(|&a| a) {
            break;
        }
    }
    for (at, step) in lanes.failed_at.iter_mut().zip(failed_step) {
        if step >= 0.0 {
            *at = (step + 1.0) * h;
        }
    }
    lanes.flip_step = flip_step;
    lanes.flip_ends = [before, after];
    *z = [q1, q2, p1, p2];
    true
}
