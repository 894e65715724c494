//! Ensembles. [`engine`] runs every catalogued system with every explicit Runge–Kutta
//! method on lanes (and separable systems with the explicit partitioned methods), from the systems' own equations ([`crate::num::Lanes`]). This module is
//! the double pendulum's typed front to it ([`Member`], [`BatchSpec`]: the fractal's and the
//! benchmarks' form), and Tao's map on lanes for the free double pendulum: a step of the
//! engine's ([`engine`]'s `LaneStep`, on the engine's one run loop with its flips,
//! retirement and failures), whose gradient is the pendulum's own,
//! [`DoublePendulum::hamiltonian_gradient`], over a whole lane group.
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

/// `item`, a kernel function, compiled for every instruction set the scalar-per-lane kernels
/// run on and chosen at run time (`multiversion`); debug builds (the tests) for AVX2 with FMA
/// and the portable fallback only: the same arithmetic, a fraction of the build time. (The
/// engine's kernels split their targets by whether they fuse multiply-adds instead.)
macro_rules! dispatched {
    ($item:item) => {
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
        $item
    };
}

pub mod driven;
pub mod engine;
mod trajectory;

pub use crate::num::trig;

pub use trajectory::{rk4_trajectory, rk4_trajectory_resumable};

use rayon::prelude::*;

use crate::Error;
use crate::num::Num;
use crate::system::double::DoublePendulum;

/// Values per lane group: two AVX-512 vectors, four AVX2 vectors (16 measured fastest on
/// W3: 0.87 s on one core, against 1.14 s with 8 lanes and 0.92 s with 32).
pub const LANES: usize = 16;

/// Members per parallel work item (a multiple of [`LANES`]): large enough to amortise the
/// scheduling, small enough to balance the load of early-retiring members.
pub(crate) const CHUNK: usize = 256;

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
    run_values_cancellable(count, member, spec, out, row_len, store, None)
}

/// [`run_values`], stopped early when `cancel` is set: each parallel work item looks at it
/// before it starts, so a run stops within one work item's time, and the rows not computed
/// are left as they were.
///
/// # Errors
/// As [`run_into`], and [`Error::Interrupted`] when `cancel` was set.
pub fn run_values_cancellable<T: Send>(
    count: usize,
    member: &(dyn Fn(usize, &mut [f64]) + Sync),
    spec: &BatchSpec,
    out: &mut [T],
    row_len: usize,
    store: &StoreValues<'_, T>,
    cancel: Option<&std::sync::atomic::AtomicBool>,
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
    let store = |i: usize, _: &Member, r: &MemberResult, row: &mut [T]| {
        store(i, &r.state, r.flip_time, row);
    };
    run_indexed(count, &of, spec, out, row_len, &store, cancel)
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
    run_into_cancellable(count, member, spec, out, row_len, store, None)
}

/// [`run_into`], stopped early when `cancel` is set (as [`run_values_cancellable`]).
///
/// # Errors
/// As [`run_into`], and [`Error::Interrupted`] when `cancel` was set.
pub fn run_into_cancellable<T: Send>(
    count: usize,
    member: &(dyn Fn(usize) -> Member + Sync),
    spec: &BatchSpec,
    out: &mut [T],
    row_len: usize,
    store: &(dyn Fn(&Member, &MemberResult, &mut [T]) + Sync),
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<(), Error> {
    run_indexed(count, member, spec, out, row_len, &|_, m, r, row| store(m, r, row), cancel)
}

/// [`run_into`], the store told each member's index.
fn run_indexed<T: Send>(
    count: usize,
    member: &(dyn Fn(usize) -> Member + Sync),
    spec: &BatchSpec,
    out: &mut [T],
    row_len: usize,
    store: &StoreIndexed<'_, T>,
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<(), Error> {
    assert_eq!(out.len(), count * row_len, "one row per member");
    let scheme = match spec.method {
        BatchMethod::Rk4 => return run_rk4_on_engine(count, member, spec, out, row_len, store, cancel),
        BatchMethod::Tao(scheme) => scheme,
    };
    if let Some(member) = (0..count).find(|&i| member(i).pendulum.is_forced()) {
        return Err(Error::UnmetRequirement {
            method: "tao on lanes",
            needs: "a free double pendulum",
            reason: format!("member {member} is damped or driven"),
            suggestion: "rk4 on lanes, or one run per member (pendula::solve)".into(),
        });
    }
    let failures: Vec<(usize, Error)> = out
        .par_chunks_mut(CHUNK * row_len)
        .enumerate()
        .filter_map(|(c, rows)| {
            let start = c * CHUNK;
            if cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
                return Some((start, Error::Interrupted));
            }
            let members: Vec<Member> = (start..start + rows.len() / row_len).map(member).collect();
            let mut results = vec![MemberResult { state: [0.0; 4], flip_time: f64::NAN }; members.len()];
            let failed = run_chunk(&members, scheme, spec, &mut results);
            for (j, ((m, r), row)) in members.iter().zip(&results).zip(rows.chunks_mut(row_len)).enumerate() {
                store(start + j, m, r, row);
            }
            failed.map(|(i, t)| (start + i, Error::NonFiniteMember { member: start + i, t }))
        })
        .collect();
    // An interruption wins over a member's failure: the run did not finish.
    if failures.iter().any(|(_, e)| matches!(e, Error::Interrupted)) {
        return Err(Error::Interrupted);
    }
    match failures.into_iter().min_by_key(|(m, _)| *m) {
        Some((_, e)) => Err(e),
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
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<(), Error> {
    use crate::system::Model;
    let crate::integrator::Scheme::ExplicitRk(tableau) = crate::integrator::explicit_rk::RK4.scheme else {
        unreachable!("RK4 is an explicit Runge-Kutta method")
    };
    let lanes = engine::LaneSpec {
        method: engine::LaneMethod::Rk(tableau),
        h: spec.h,
        steps: spec.steps,
        stop_at_flip: spec.stop_at_flip,
        track_flips: spec.track_flips,
        cancel,
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
        let pendulums: [DoublePendulum; LANES] = std::array::from_fn(|i| pick(i).pendulum);
        let states: [[f64; 4]; LANES] = std::array::from_fn(|i| pick(i).state);
        let (finals, flip_times, failed_at) = tao_group(&pendulums, &states, scheme, spec);
        for (i, r) in results.iter_mut().enumerate() {
            *r = MemberResult { state: finals[i], flip_time: flip_times[i] };
            if !failed_at[i].is_nan() && first_failure.is_none() {
                first_failure = Some((g * LANES + i, failed_at[i]));
            }
        }
    }
    first_failure
}

/// A lane group of free double pendulums under Tao's map on the engine's run loop
/// ([`engine::kernel_fused`]): (θ, ω) → (q, p) with the libm cosine, the steps with the
/// branch-free trigonometry ([`TaoStep`]), and back. The final states, flip times and the
/// times at which states became non-finite (NaN: never).
fn tao_group(
    pendulums: &[DoublePendulum; LANES],
    states: &[[f64; 4]; LANES],
    scheme: crate::integrator::tao::TaoScheme,
    spec: &BatchSpec,
) -> ([[f64; 4]; LANES], [f64; LANES], [f64; LANES]) {
    use engine::{Record, Run, kernel_fused, kernel_plain};
    // The engine's state: (q₁, q₂, p₁, p₂), then the copy (x₁, x₂, y₁, y₂), which starts
    // equal to it.
    let mut start = [[0.0; LANES]; engine::MAX_DIM];
    for (i, (d, y)) in pendulums.iter().zip(states).enumerate() {
        let p = d.momenta(y);
        for (k, v) in [y[0], y[1], p[0], p[1]].into_iter().enumerate() {
            start[k][i] = v;
            start[k + 4][i] = v;
        }
    }
    let mut record = Record::new(start);
    let track = spec.track_flips || spec.stop_at_flip;
    let run =
        Run { dim: 4, angles: &[0, 1], h: spec.h, steps: spec.steps, stop_at_flip: spec.stop_at_flip, track };
    // The fast trigonometry alone; if some lane's angles went beyond its range (the record
    // is then as it was), again with the exact reduction.
    let done = if has_fma() {
        kernel_fused::<_, 8, false>(&group(pendulums), &TaoStep::<true, false> { scheme }, &run, &mut record)
    } else {
        kernel_plain::<_, 8, false>(&group(pendulums), &TaoStep::<false, false> { scheme }, &run, &mut record)
    };
    if !done {
        if has_fma() {
            kernel_fused::<_, 8, true>(
                &group(pendulums),
                &TaoStep::<true, true> { scheme },
                &run,
                &mut record,
            );
        } else {
            kernel_plain::<_, 8, true>(
                &group(pendulums),
                &TaoStep::<false, true> { scheme },
                &run,
                &mut record,
            );
        }
    }
    // Back to (θ, ω), and the flipped lanes' rates θ' = ∂H/∂p at both ends of the flip's
    // step for the Hermite interpolant (scalar, once per member).
    let rates = |d: &DoublePendulum, v: &[[f64; LANES]], i: usize| {
        let mut w = [0.0; 2];
        crate::system::Hamiltonian::dh_dp(&d.form(), 0.0, &[v[0][i], v[1][i]], &[v[2][i], v[3][i]], &mut w);
        w
    };
    let mut ends = record.ends;
    let mut finals = [[0.0; 4]; LANES];
    for (i, d) in pendulums.iter().enumerate() {
        if record.flip_step[i] >= 0.0 {
            for end in &mut ends {
                let w = rates(d, &end[..], i);
                end[2][i] = w[0];
                end[3][i] = w[1];
            }
        }
        let w = rates(d, &record.state[..], i);
        finals[i] = [record.state[0][i], record.state[1][i], w[0], w[1]];
    }
    let flip_times = std::array::from_fn(|i| {
        engine::flip_time(record.flip_step[i], [&ends[0], &ends[1]], &[0, 1], 4, i, spec.h)
    });
    (finals, flip_times, record.failed_at)
}

/// A lane group in the engine arithmetic.
type Group<const FMA: bool, const WIDE: bool> = crate::num::Lanes<LANES, FMA, WIDE>;

/// Tao's extended-phase-space map for a lane group of free double pendulums: the engine's
/// state is (q, p) and the copy (x, y); the gradient is the pendulums' own
/// ([`DoublePendulum::hamiltonian_gradient`]), over the whole group at once (its two
/// halves' independent chains interleaved: measured faster here than half a group at a
/// time, 1.10 s against 1.56 s for 128² members × 1000 tao-4 steps on one core, and than
/// the Tao kernel this replaced, 1.28 s, bit for bit the same results).
#[derive(Clone, Copy)]
struct TaoStep<const FMA: bool, const WIDE: bool> {
    scheme: crate::integrator::tao::TaoScheme,
}

/// A lane group of free double pendulums, one per lane.
fn group<const FMA: bool, const WIDE: bool>(
    pendulums: &[DoublePendulum; LANES],
) -> DoublePendulum<Group<FMA, WIDE>> {
    let lanes = |f: fn(&DoublePendulum) -> f64| crate::num::Lanes(std::array::from_fn(|i| f(&pendulums[i])));
    DoublePendulum {
        m1: lanes(|d| d.m1),
        m2: lanes(|d| d.m2),
        l1: lanes(|d| d.l1),
        l2: lanes(|d| d.l2),
        g: lanes(|d| d.g),
        // Free (checked before): the forcing terms are zeros, skipped.
        damping: lanes(|_| 0.0),
        drive_amplitude: lanes(|_| 0.0),
        drive_frequency: lanes(|_| 0.0),
    }
}

impl<const FMA: bool, const WIDE: bool> engine::LaneStep<8, FMA, WIDE> for TaoStep<FMA, WIDE> {
    type Equations = DoublePendulum<Group<FMA, WIDE>>;

    #[inline(always)]
    fn step(
        &mut self,
        d: &DoublePendulum<Group<FMA, WIDE>>,
        _t: f64,
        h: f64,
        y: &[Group<FMA, WIDE>; 8],
        next: &mut [Group<FMA, WIDE>; 8],
        reach: &mut [crate::num::Lanes<{ LANES / 2 }, FMA, WIDE>; 2],
    ) {
        type G<const FMA: bool, const WIDE: bool> = Group<FMA, WIDE>;
        let [mut q1, mut q2, mut p1, mut p2, mut x1, mut x2, mut y1, mut y2] = *y;
        let zero = G::<FMA, WIDE>::splat(0.0);
        // The reach of the gradient's arguments, max |q| over the angles it is given (their
        // difference reaches at most twice that: doubled below).
        let mut r = zero;
        for &w in self.scheme.weights {
            let step = G::<FMA, WIDE>::splat(0.5 * w * h);
            // φ_A(δ/2) φ_B(δ/2) φ_C(δ) φ_B(δ/2) φ_A(δ/2), δ = w h.
            for phase in 0..5 {
                match phase {
                    0 | 4 => {
                        if !WIDE {
                            r = q2.abs().max(q1.abs().max(r));
                        }
                        let g = d.hamiltonian_gradient(zero, [q1, q2], [y1, y2]);
                        p1 = p1 - step * g[0];
                        p2 = p2 - step * g[1];
                        x1 = x1 + step * g[2];
                        x2 = x2 + step * g[3];
                    }
                    1 | 3 => {
                        if !WIDE {
                            r = x2.abs().max(x1.abs().max(r));
                        }
                        let g = d.hamiltonian_gradient(zero, [x1, x2], [p1, p2]);
                        q1 = q1 + step * g[2];
                        q2 = q2 + step * g[3];
                        y1 = y1 - step * g[0];
                        y2 = y2 - step * g[1];
                    }
                    _ => {
                        let (sin, cos) = (2.0 * self.scheme.binding * w * h).sin_cos();
                        let (sin, cos) = (G::<FMA, WIDE>::splat(sin), G::<FMA, WIDE>::splat(cos));
                        let one_half = G::<FMA, WIDE>::splat(0.5);
                        for (q, p, x, y) in
                            [(&mut q1, &mut p1, &mut x1, &mut y1), (&mut q2, &mut p2, &mut x2, &mut y2)]
                        {
                            let (sq, sp) = (*q + *x, *p + *y);
                            let (dq, dp) = (*q - *x, *p - *y);
                            let (rq, rp) = (cos * dq + sin * dp, -sin * dq + cos * dp);
                            *q = one_half * (sq + rq);
                            *x = one_half * (sq - rq);
                            *p = one_half * (sp + rp);
                            *y = one_half * (sp - rp);
                        }
                    }
                }
            }
        }
        #[allow(clippy::needless_range_loop)] // lane-indexed: the form that vectorises
        if !WIDE {
            // Loops, not iterator adaptors: kept in line, with the kernel's instruction set.
            let n = LANES / 2;
            for half in 0..2 {
                for i in 0..n {
                    let doubled = r.0[half * n + i] + r.0[half * n + i];
                    let bound = reach[half].0[i];
                    reach[half].0[i] = if doubled > bound { doubled } else { bound };
                }
            }
        }
        *next = [q1, q2, p1, p2, x1, x2, y1, y2];
    }
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
