//! Ensembles. [`engine`] runs every catalogued system on lanes — every explicit Runge–Kutta
//! method, kick–drift on separable systems, Tao's map on the non-separable ones — from the
//! systems' own equations ([`crate::num::Lanes`]) and the integrators' own steps. This module
//! is the double pendulum's typed front to it ([`Member`], [`run`]: the benchmarks' and the
//! tests' form), and [`rk4_trajectory`], one free double pendulum with RK4 in the engine's
//! arithmetic and its energy from the step's trigonometry (the fast path of `simulate`, W1).
//!
//! Many members advance together, in lanes of [`LANES`] structure-of-arrays values that the
//! compiler turns into SIMD (8 f64 per AVX-512 vector, 4 per AVX2), with branch-free sine and
//! cosine ([`trig`]), CPU dispatch at run time (`multiversion`, with a portable fallback),
//! and rayon across cores.
//!
//! Determinism: lanes never interact and every lane runs the same operations in the same
//! order, so a member's result does not depend on which lane, chunk or thread computes it:
//! results are bitwise identical for any thread count, any chunking (shards), and any of
//! the dispatched instruction sets (no fused multiply-add is introduced: Rust does not
//! contract a·b + c).
//!
//! A member that flips (with [`LaneSpec::stop_at_flip`]) retires: its lane keeps computing
//! (branch-free) but its state stays at the step where the flip was seen. A non-finite state
//! is an error naming the member and the time.

/// `item`, a kernel function, compiled for every instruction set the single-trajectory kernel
/// runs on and chosen at run time (`multiversion`); debug builds (the tests) for AVX2 with FMA
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

use crate::Error;
use crate::system::double::DoublePendulum;
use engine::{LaneOutcome, LaneSpec};

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
    /// Masses, lengths, g, and any damping or drive.
    pub pendulum: DoublePendulum,
    /// Initial (θ₁, θ₂, ω₁, ω₂), rad and rad/s.
    pub state: [f64; 4],
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

/// Runs every member on the engine ([`engine::run`]), in parallel on rayon's current pool,
/// writing `out[i]` for `members[i]`.
///
/// # Errors
/// As [`engine::run`]: a member the method cannot run (damped, with Tao's map), named; the
/// first member whose state became non-finite; [`Error::Interrupted`].
///
/// # Panics
/// If the engine does not run `spec.method` on the double pendulum ([`engine::supports`]).
pub fn run(members: &[Member], spec: &LaneSpec<'_>, out: &mut [MemberResult]) -> Result<(), Error> {
    use crate::system::Model;
    assert_eq!(members.len(), out.len(), "one result per member");
    let values = |i: usize, v: &mut [f64]| {
        let Member { pendulum: d, state } = members[i];
        let p = [d.m1, d.m2, d.l1, d.l2, d.g, d.damping, d.drive_amplitude, d.drive_frequency];
        v[..8].copy_from_slice(&p);
        v[8..].copy_from_slice(&state);
    };
    let store = |_: usize, o: &LaneOutcome, row: &mut [MemberResult]| {
        row[0] = MemberResult { state: std::array::from_fn(|k| o.state[k]), flip_time: o.flip_time };
    };
    let members = engine::Members { info: DoublePendulum::INFO, count: members.len(), values: &values };
    engine::run::<DoublePendulum, _>(&members, spec, engine::Rows { out, len: 1, store: &store })
}

/// Whether the engine's arithmetic fuses multiply-adds (then the trigonometric polynomials
/// use them: faster, and as accurate, but rounded differently from the plain kernels): where
/// the CPU has fused multiply-add instructions, and always in debug builds (the tests), which
/// compile the fused kernels alone — on a CPU without the instructions they run
/// `f64::mul_add` in software, correctly rounded, so with the same bits. Results computed in
/// parts (a checkpoint continued later) are bit-identical only where this answers the same.
pub fn has_fma() -> bool {
    if cfg!(debug_assertions) {
        return true;
    }
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

/// `$e`, a run of the plain (unfused) kernels, in release builds; unreachable in debug builds,
/// which fuse multiply-adds everywhere ([`has_fma`]) and so do not compile the plain kernels
/// (a third of the library's build time in the tests).
#[cfg(not(debug_assertions))]
macro_rules! plain {
    ($e:expr) => {
        $e
    };
}
#[cfg(debug_assertions)]
macro_rules! plain {
    ($e:expr) => {
        unreachable!("debug builds fuse multiply-adds (ensemble::has_fma)")
    };
}
pub(crate) use plain;
