//! The ensemble engine for every catalogued system and every explicit Runge–Kutta method,
//! and for separable systems with the explicit partitioned methods ([`LaneMethod`]): a
//! system's own equations ([`Equations`], written once) over [`Lanes`] of [`LANES`] members,
//! the integrators' own steps ([`crate::integrator::explicit_rk`]'s stages,
//! [`crate::integrator::partitioned::kick_drift`], written once), and one run loop: flips located on the cubic Hermite interpolant, members retired when they flip (if
//! asked), the first non-finite state an error naming the member and the time.
//!
//! A member's bits do not depend on its lane, its lane group, its chunk or the thread count:
//! lanes never interact. They are the bits of the same member run alone in one lane
//! (`Lanes<1, …>`, [`solve_one`]): the same operations in the same order.
//!
//! # How it is built
//!
//! `engine`: the ensemble engine: one run loop (`kernel`: flips, retirement, failures, the fallback
//! to the exact trigonometry) around a `LaneStep`, what a method does in one step of a lane group —
//! `RkStep` (every system, every explicit Runge–Kutta method: `Equations` over `Lanes`, the
//! integrators' own stages `fixed_stages`, `fixed_update`), `KickDrift` (symplectic Euler,
//! Störmer–Verlet and the Yoshida compositions on separable systems: the integrators' own
//! `kick_drift`, in the velocities) and `TaoLanes` (Tao's map on the non-separable Hamiltonian
//! systems: the integrators' own `tao_step` over the equations' own gradient `Canonical`, state
//! (q, p) and the copy (x, y), converted from and to (q, q') by the model's own maps);
//! `solve_one` is one member alone, bit for bit a lane's result.
//!
//! The ensemble engine, `crates/pendula/src/ensemble/engine.rs`, advances 16 members of any
//! catalogued system at once with any explicit Runge–Kutta method of at most four stages, and of
//! any separable system (the pendulum and the oscillator, undamped, driven or not) with the
//! explicit partitioned methods — symplectic Euler, Störmer–Verlet, the Yoshida compositions — as
//! kick–drift in the velocities (`kick_drift` in `crates/pendula/src/integrator/partitioned.rs`,
//! generic over the number type: for H = ½ q′ᵀ M q′ + V(t, q) with M constant the same map as the
//! (q, p) stepper, the accelerations from the equations' own right-hand side and kept in the lane
//! state from one step to the next, one evaluation per Verlet step; the engine checks each member
//! for a separable Hamiltonian before any step, and names the first that is not). The methods are
//! data, `LaneMethod`. The system's own `Equations` over `Lanes<8>` (each lane group's two halves
//! evaluated one after the other, one AVX-512 vector per value: a whole group at once spilled), the
//! integrators' own stages (`fixed_stages`, `fixed_update` in
//! `crates/pendula/src/integrator/explicit_rk.rs`, the tableau copied into fixed-size arrays so
//! that its loops unroll), and one run loop: a cheap probe per step (0·x is NaN exactly when x is
//! not finite; an angle beyond its lane's watch of π) sends only the rare step in which something
//! happens — a flip, a retirement, a non-finite state — to the lane-by-lane bookkeeping. The kernel
//! is compiled per state dimension and number of stages (`Equations::rhs_sized` hands the dimension
//! to the equations, for the chain's temporaries), as `kernel_fused` (fused multiply-adds; AVX-512,
//! AVX2+FMA, NEON) and `kernel_plain` (AVX, the portable fallback), chosen at run time by
//! `multiversion`; debug builds (the tests) compile only AVX2+FMA and the fallback, the same
//! arithmetic in a fraction of the build time. rayon spreads chunks of members over the cores;
//! members are made on demand and results stored into the caller's rows, so memory is the output
//! plus a few chunks. A lane that flips keeps the state at both ends of the step, and its flip time
//! is located after the loop on the cubic Hermite interpolant with the event locator's bisection
//! (so `fractal` and `simulate --event flip` agree); its branch-free sine and cosine are in
//! `crates/pendula/src/num/trig.rs` (fast for |x| ≤ 2²⁰; the equations' `trig_reach` is tracked as
//! data flow, and a lane group that may have gone beyond runs again with a copy of its kernel that
//! reduces such angles exactly, by Payne–Hanek, in `crates/pendula/src/num/trig/exact.rs`).
//! `engine::solve_one` is one member in the same arithmetic, bit for bit a lane.
//! `crates/pendula/src/ensemble/mod.rs` is the double pendulum's typed front (`Member`, `run`).
//! `engine::solve_one_resumable` is the fast path of a single fixed-step run with an explicit
//! tableau (`DynModel::solve_fastest`; RK4 on the free double pendulum, W1, takes
//! `ensemble::rk4_trajectory` in `crates/pendula/src/ensemble/trajectory.rs` instead, whose
//! energies come from the step's trigonometry): one lane, pausing and continuing bit for bit. `engine::stroboscopic` samples every member once per drive period
//! (orbit diagrams; `crates/pendula/src/ensemble/driven.rs` is the driven pendulum's typed
//! front): the run's time counted in periods, each lane's equations scaled to its own period,
//! the run loop called period by period with the angles wrapped between.

use rayon::prelude::*;

use super::{CHUNK, has_fma};

/// Members per lane group, the ensemble's one [`super::LANES`]: in the engine, two halves of
/// one AVX-512 vector per value, whose independent chains of operations hide each other's
/// latency (8 alone measured slower on the hand-written kernels this engine replaced: 1.14 s
/// against 0.87 s on one core).
pub use super::LANES;
use crate::checkpoint::{Leg, Pause, Reader, RunState, Snapshot, Words};
use crate::integrator::explicit_rk::{
    Plan, Row, StageRhs, Tableau, explicit_stages, explicit_update, fixed_stages, fixed_update, plan,
};
use crate::integrator::partitioned::{Accelerations, Partition, kick_drift};
use crate::integrator::tao::{TaoScheme, tao_step};
use crate::integrator::{Method, Stepper};
use crate::num::{Lanes, Num, trig};
use crate::observe::Observer;
use crate::system::{Canonical, Equations, Model, SystemInfo};
use crate::{Error, Report, RunSpec, Simulation};

/// The largest state the engine runs (the 8-link chain's 16 variables).
pub const MAX_DIM: usize = 16;

/// The most stages of an explicit method the engine runs (RK4's 4).
pub const MAX_STAGES: usize = 4;

type V = [f64; LANES];

/// A method as the engine runs it on lanes: data, chosen by [`crate::model::lane_method`]
/// before any step.
#[derive(Debug, Clone, Copy)]
pub enum LaneMethod {
    /// An explicit Runge–Kutta tableau (at most [`MAX_STAGES`] stages), on every system.
    Rk(&'static Tableau),
    /// A partitioned scheme (symplectic Euler, Störmer–Verlet, a Yoshida composition) on a
    /// separable system, kick–drift in the velocities
    /// ([`crate::integrator::partitioned::kick_drift`]): `method` is its descriptor (what it
    /// requires of each member), `scheme` its steps.
    KickDrift {
        /// The method's descriptor.
        method: &'static Method,
        /// Its scheme.
        scheme: Partition,
    },
    /// Tao's extended-phase-space map ([`crate::integrator::tao::tao_step`]) on a
    /// non-separable Hamiltonian system (the double pendulum, free or driven; the chain
    /// while its state and the copy fit the lane record, up to [`TAO_MAX_DIM`] variables):
    /// the lanes hold (q, p) and the copy (x, y), converted from and to (q, q') per member
    /// with the model's own maps, so that each member's result is that of the scalar run's
    /// arithmetic in the engine's numbers. `method` is its descriptor (what it requires of
    /// each member: a Hamiltonian form, so no damping), `scheme` its weights and binding
    /// constant.
    Tao {
        /// The method's descriptor.
        method: &'static Method,
        /// Its composition weights and binding constant ω.
        scheme: TaoScheme,
    },
}

impl LaneMethod {
    /// The lane form of `method`, by its scheme alone (whether a system meets what it needs
    /// is [`crate::model::lane_method`]'s question): an explicit tableau, a partitioned
    /// scheme as kick–drift, Tao's map; `None` for the implicit and adaptive methods.
    pub fn of(method: &'static Method) -> Option<LaneMethod> {
        use crate::integrator::Scheme;
        match method.scheme {
            Scheme::ExplicitRk(tableau) => Some(LaneMethod::Rk(tableau)),
            Scheme::Partitioned(scheme) => Some(LaneMethod::KickDrift { method, scheme }),
            Scheme::Tao(scheme) => Some(LaneMethod::Tao { method, scheme }),
            _ => None,
        }
    }

    /// Right-hand side evaluations of a run of `steps` steps (for Störmer–Verlet and the
    /// compositions, one per Verlet step and one at the start: the last of a step is the
    /// first of the next).
    pub fn evaluations(&self, steps: u64) -> u64 {
        let start = u64::from(steps > 0);
        match self {
            LaneMethod::Rk(t) => t.b.len() as u64 * steps,
            LaneMethod::KickDrift { scheme: Partition::SymplecticEuler, .. } => steps,
            LaneMethod::KickDrift { scheme: Partition::StormerVerlet, .. } => steps + start,
            LaneMethod::KickDrift { scheme: Partition::Composition(w), .. } => w.len() as u64 * steps + start,
            // Four gradients per second-order map (A, B, B, A), as the scalar stepper counts.
            LaneMethod::Tao { scheme, .. } => 4 * scheme.weights.len() as u64 * steps,
        }
    }
}

/// What an ensemble run of explicit steps does.
#[derive(Debug, Clone, Copy)]
pub struct LaneSpec<'a> {
    /// The method.
    pub method: LaneMethod,
    /// Step size, s (in the system's units when dimensionless).
    pub h: f64,
    /// Number of steps, from t = 0.
    pub steps: u64,
    /// Retire a member when it first flips (an angle passes ±π).
    pub stop_at_flip: bool,
    /// Record flip times (implied by `stop_at_flip`).
    pub track_flips: bool,
    /// When set (by another thread: a Ctrl-C), the run stops before its next lane group
    /// with [`Error::Interrupted`]; what it wrote is then incomplete.
    pub cancel: Option<&'a std::sync::atomic::AtomicBool>,
}

/// The members of an ensemble run, as every ensemble entry point takes them: `count`
/// members of the system entry `info` (for the chain, the member with its number of links),
/// member i's values — every parameter, then every state variable, in the order of `info`'s
/// quantities — written by `values(i, slots)`. Members are made when their lane group runs,
/// so a run over a million members holds no million-row table of them.
#[derive(Clone, Copy)]
pub struct Members<'a> {
    /// The system entry the members belong to.
    pub info: &'static SystemInfo,
    /// How many members.
    pub count: usize,
    /// Writes member i's values into the slots handed to it (as many as `info` has quantities).
    pub values: &'a (dyn Fn(usize, &mut [f64]) + Sync),
}

/// What the engine's lanes hand a result store: the member's index, its outcome, its row.
pub type StoreLane<'a, T> = dyn Fn(usize, &LaneOutcome, &mut [T]) + Sync + 'a;

/// Where an ensemble run's results go: one row of `len` values per member in `out` (so
/// `out` holds count × `len`), each written by `store` from the member's result (`S`: for the
/// lanes [`StoreLane`], for the scalar path [`crate::sweep::StoreValues`]).
pub struct Rows<'a, T, S: ?Sized> {
    /// count × `len` values.
    pub out: &'a mut [T],
    /// Values per member.
    pub len: usize,
    /// Writes member i's row from its result.
    pub store: &'a S,
}

/// A member's results.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaneOutcome {
    /// The state at the end (or where the member retired), the first `dim` entries used.
    pub state: [f64; MAX_DIM],
    /// Time of the first flip, s, or NaN: where the cubic Hermite interpolant of the angle
    /// that crossed (its values and rates at both ends of the step) passes ±π.
    pub flip_time: f64,
}

/// Whether the engine runs `method` on `info`'s states: a tableau of at most [`MAX_STAGES`]
/// stages on at most [`MAX_DIM`] variables; kick–drift on states of [`KICK_DRIFT_DIM`]
/// variables (the kernels compiled for it: every separable system catalogued has one degree of
/// freedom); Tao's map on states of 4 to [`TAO_MAX_DIM`] variables (the non-separable systems
/// catalogued have two degrees of freedom or more; the copy doubles the lane record).
pub fn supports(info: &SystemInfo, method: &LaneMethod) -> bool {
    match method {
        LaneMethod::Rk(tableau) => (1..=MAX_STAGES).contains(&tableau.b.len()) && info.state.len() <= MAX_DIM,
        LaneMethod::KickDrift { .. } => info.state.len() == KICK_DRIFT_DIM,
        LaneMethod::Tao { .. } => (4..=TAO_MAX_DIM).contains(&info.state.len()),
    }
}

/// The largest state Tao's map runs on lanes: with its copy, the lane record's
/// [`MAX_DIM`] values (the chain up to 4 links).
pub const TAO_MAX_DIM: usize = MAX_DIM / 2;

/// The padded dimension of the Tao kernel of a system whose [`Model::DIM`] is `model_dim`
/// (its copy starts there): 4 for the double pendulum, the largest, [`TAO_MAX_DIM`], for a
/// family's members (the chain's: one kernel for every link count that fits).
const fn tao_padded(model_dim: usize) -> usize {
    if model_dim <= 4 { 4 } else { TAO_MAX_DIM }
}

/// The state dimension the kick–drift kernels are compiled for.
pub const KICK_DRIFT_DIM: usize = 2;

/// Whether member `values` (parameters then state, as [`run`] takes them) meets what
/// `method` requires of it ([`crate::simulate::check`]: for kick–drift, a separable
/// Hamiltonian, so no damping; for Tao's map a Hamiltonian form), before any step.
fn check_member<M: Model>(
    info: &'static SystemInfo,
    method: &LaneMethod,
    values: &[f64],
) -> Result<(), Error> {
    let (LaneMethod::KickDrift { method, .. } | LaneMethod::Tao { method, .. }) = method else {
        return Ok(());
    };
    crate::simulate::check(method, &member_model::<M>(info, values)?)
}

/// The model of member `values` (parameters then state).
fn member_model<M: Model>(info: &'static SystemInfo, values: &[f64]) -> Result<M, Error> {
    let settings: Vec<(String, f64)> =
        info.quantities().map(|q| q.name.to_owned()).zip(values.iter().copied()).collect();
    Ok(M::from_values(&info.values(&settings)?))
}

/// Runs the `members` of the system `M` in parallel on rayon's pool, chunk by chunk and lane
/// group by lane group; each member's result is stored into its row of `rows`.
///
/// # Errors
/// For kick–drift, [`Error::UnmetRequirement`] for the first member (in index order) that
/// is not separable (damped), naming it, before it takes a step; else
/// [`Error::NonFiniteMember`] for the first member whose state became non-finite;
/// [`Error::Interrupted`] when `spec.cancel` was set.
///
/// # Panics
/// If the engine does not run the method on the system ([`supports`]): a caller's error.
pub fn run<M: Model, T: Send>(
    members: &Members<'_>,
    spec: &LaneSpec,
    rows: Rows<'_, T, StoreLane<'_, T>>,
) -> Result<(), Error> {
    let Members { info, count, values: member } = *members;
    let Rows { out, len: row_len, store } = rows;
    assert!(supports(info, &spec.method), "the engine does not run this method on {}", info.name);
    assert_eq!(out.len(), count * row_len, "one row per member");
    if let LaneMethod::Tao { scheme, .. } = &spec.method {
        crate::integrator::tao::check_binding_step(scheme, spec.h)?;
    }
    let width = info.parameters.len() + info.state.len();
    let failures: Vec<(usize, Error)> = out
        .par_chunks_mut(CHUNK * row_len)
        .enumerate()
        .filter_map(|(c, rows)| {
            let start = c * CHUNK;
            // Before the chunk's members are made and checked: once cancelled, every chunk
            // left ends at once (their checks, a model per member with Tao's map, summed to
            // a second over a million members).
            if spec.cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
                return Some((start, Error::Interrupted));
            }
            let n = rows.len() / row_len;
            let mut values = vec![0.0; n * width];
            for (i, v) in values.chunks_mut(width).enumerate() {
                member(start + i, v);
            }
            for (i, v) in values.chunks(width).enumerate() {
                if let Err(e) = check_member::<M>(info, &spec.method, v) {
                    return Some((start + i, name_member(e, start + i)));
                }
            }
            let mut first: Option<(usize, Error)> = None;
            for (g, (group, rows)) in
                values.chunks(LANES * width).zip(rows.chunks_mut(LANES * row_len)).enumerate()
            {
                if spec.cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
                    return Some((start + g * LANES, Error::Interrupted));
                }
                let members: Vec<&[f64]> = group.chunks(width).collect();
                let (outcomes, failed) = run_group::<M>(info, &members, spec, None);
                for (i, (o, row)) in outcomes.iter().zip(rows.chunks_mut(row_len)).enumerate() {
                    store(start + g * LANES + i, o, row);
                }
                if let Some((i, t)) = failed {
                    let member = start + g * LANES + i;
                    first.get_or_insert((member, Error::NonFiniteMember { member, t }));
                }
            }
            first
        })
        .collect();
    match failures.into_iter().min_by_key(|(m, _)| *m) {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

/// A stroboscopic ensemble run ([`stroboscopic`]): every member sampled once per period of
/// its drive by RK4 (kernels of their own, in each lane's time unit, compiled for RK4 alone),
/// the Poincaré section of the extended phase space at phase 0.
#[derive(Clone, Copy)]
pub struct Strobe<'a> {
    /// Steps per drive period (at least 1): each member steps its own period / this.
    pub steps_per_period: u32,
    /// Samples per member, one per period after its transient.
    pub samples: usize,
    /// Member i's drive period, s (in the system's units when dimensionless), and the whole
    /// periods run before its first sample.
    pub periods: &'a (dyn Fn(usize) -> (f64, u64) + Sync),
    /// As [`LaneSpec::cancel`].
    pub cancel: Option<&'a std::sync::atomic::AtomicBool>,
}

/// A lane group's part of a [`Strobe`] run: its members' periods and transients, and their
/// rows of samples.
pub(crate) struct StrobeGroup<'a> {
    periods: &'a [(f64, u64)],
    samples: usize,
    rows: &'a mut [f64],
}

/// Samples the `members` of the system `M` once per drive
/// period: the engine's steps on each member's own step (its period / `steps_per_period`:
/// the run's time is counted in periods, each lane's equations scaled to it), the samples
/// taken between the periods, angles wrapped into [−π, π). Member i's samples go to
/// `out[i · samples · dim ..]`, one state per sample. Lane groups are the work items, in
/// parallel on rayon's pool; results do not depend on the pool's size.
///
/// # Errors
/// [`Error::UnmetRequirement`] for a system with no drive of more than two degrees of
/// freedom (a family: the chain); [`Error::NonFiniteMember`] for the first member (in index
/// order) whose state became non-finite, with the time; [`Error::Interrupted`] when
/// `strobe.cancel` was set.
///
/// # Panics
/// If `out` does not hold count × samples × dim values, or the tableau is not one the engine
/// runs on `info`'s states.
pub fn stroboscopic<M: Model>(
    members: &Members<'_>,
    strobe: &Strobe<'_>,
    out: &mut [f64],
) -> Result<(), Error> {
    let Members { info, count, values: member } = *members;
    // Stroboscopic kernels are compiled for the driven systems' states alone (the build
    // time): no family (the chain) has a drive.
    if M::DIM > 4 {
        return Err(Error::UnmetRequirement {
            method: "stroboscopic",
            needs: "a driven system",
            reason: format!("{} has no drive", info.name),
            suggestion: "a driven system: the driven pendulum, oscillator or double pendulum".into(),
        });
    }
    let dim = info.state.len();
    let per_member = strobe.samples * dim;
    assert_eq!(out.len(), count * per_member, "count × samples × dim values");
    assert!(strobe.steps_per_period >= 1, "at least one step per period");
    let crate::integrator::Scheme::ExplicitRk(rk4) = crate::integrator::explicit_rk::RK4.scheme else {
        unreachable!("RK4 is explicit")
    };
    let spec = LaneSpec {
        method: LaneMethod::Rk(rk4),
        h: 1.0 / f64::from(strobe.steps_per_period),
        steps: u64::from(strobe.steps_per_period),
        stop_at_flip: false,
        track_flips: false,
        cancel: None,
    };
    assert!(supports(info, &spec.method), "the engine does not run this method on {}", info.name);
    let width = info.parameters.len() + info.state.len();
    if per_member == 0 {
        return Ok(());
    }
    let failures: Vec<(usize, Error)> = out
        .par_chunks_mut(LANES * per_member)
        .enumerate()
        .filter_map(|(g, rows)| {
            let start = g * LANES;
            if strobe.cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
                return Some((start, Error::Interrupted));
            }
            let n = rows.len() / per_member;
            let mut values = vec![0.0; n * width];
            for (i, v) in values.chunks_mut(width).enumerate() {
                member(start + i, v);
            }
            let periods: Vec<(f64, u64)> = (start..start + n).map(strobe.periods).collect();
            let members: Vec<&[f64]> = values.chunks(width).collect();
            let group = StrobeGroup { periods: &periods, samples: strobe.samples, rows };
            let (_, failed) = run_group::<M>(info, &members, &spec, Some(group));
            failed.map(|(i, t)| (start + i, Error::NonFiniteMember { member: start + i, t }))
        })
        .collect();
    if failures.iter().any(|(_, e)| matches!(e, Error::Interrupted)) {
        return Err(Error::Interrupted);
    }
    match failures.into_iter().min_by_key(|(m, _)| *m) {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

/// `e`, a member's unmet requirement, saying which member.
fn name_member(e: Error, member: usize) -> Error {
    match e {
        Error::UnmetRequirement { method, needs, reason, suggestion } => Error::UnmetRequirement {
            method,
            needs,
            reason: format!("member {member}: {reason}"),
            suggestion,
        },
        other => other,
    }
}

/// A lane group's run: `members` (at most [`LANES`]; the group is padded with copies of the
/// last, whose results are dropped) from their values. The outcomes, and the first lane whose
/// state became non-finite with the time.
pub(crate) fn run_group<M: Model>(
    info: &'static SystemInfo,
    members: &[&[f64]],
    spec: &LaneSpec,
    strobe: Option<StrobeGroup<'_>>,
) -> (Vec<LaneOutcome>, Option<(usize, f64)>) {
    let np = info.parameters.len();
    let dim = info.state.len();
    let pick = |i: usize| members[i.min(members.len() - 1)];
    let index = |name: &str| {
        info.parameters
            .iter()
            .position(|q| q.name == name)
            .unwrap_or_else(|| panic!("{} has no {name}", info.name))
    };
    // Tao's map runs on (q, p), its copy (x, y) after the padded state, each member's
    // (q, q') converted by its own model (and back after the run).
    let tao_models: Vec<M> = match spec.method {
        LaneMethod::Tao { .. } => (0..LANES)
            .map(|i| member_model::<M>(info, pick(i)).expect("a member checked before the run"))
            .collect(),
        _ => Vec::new(),
    };
    let mut start = [[0.0; LANES]; MAX_DIM];
    #[allow(clippy::needless_range_loop)] // lane i of every variable
    for i in 0..LANES {
        let y = &pick(i)[np..np + dim];
        if let Some(model) = tao_models.get(i) {
            let mut z = [0.0; MAX_DIM];
            model.to_momenta(y, &mut z[..dim]);
            for (k, &v) in z[..dim].iter().enumerate() {
                start[k][i] = v;
                start[tao_padded(M::DIM) + k][i] = v;
            }
        } else {
            for (k, &v) in y.iter().enumerate() {
                start[k][i] = v;
            }
        }
    }
    let mut record = Record::new(start);
    // The angles among the positions (the flips' variables); positions come first and their
    // rates are the velocities, dim/2 further on (every catalogued state is (q, q')).
    let angles: Vec<usize> = (0..dim / 2).filter(|&k| info.state[k].is_angle()).collect();
    let track = spec.track_flips || spec.stop_at_flip;
    let setting = |name: &str| pick(0)[index(name)];
    // Kernels are compiled per state dimension (the system's, `M::DIM`; for the chain its
    // members', padded) and per number of stages, so that their loops unroll.
    macro_rules! call {
        (true, $d:tt, $wide:tt, $eq:ident, $step:ident, $run:ident, $record:ident) => {
            kernel_fused::<_, $d, $wide>(&$eq, &$step, &$run, &mut $record)
        };
        (false, $d:tt, $wide:tt, $eq:ident, $step:ident, $run:ident, $record:ident) => {
            kernel_plain::<_, $d, $wide>(&$eq, &$step, &$run, &mut $record)
        };
    }
    let run =
        Run { dim, angles: &angles, h: spec.h, steps: spec.steps, stop_at_flip: spec.stop_at_flip, track };
    // A stroboscopic run: each lane's time unit is its member's drive period.
    let time_scale: Option<[f64; LANES]> =
        strobe.as_ref().map(|s| std::array::from_fn(|i| s.periods[i.min(members.len() - 1)].0));
    macro_rules! equations {
        ($fma:tt, $wide:tt) => {
            [0, 1].map(|half| {
                M::over::<Lanes<HALF, $fma, $wide>>(&setting, &|name| {
                    let k = index(name);
                    Lanes(std::array::from_fn(|i| pick(half * HALF + i)[k]))
                })
            })
        };
    }
    macro_rules! with {
        ($fma:tt, $wide:tt, $d:tt, $s:tt, $scaled:tt) => {{
            let LaneMethod::Rk(tableau) = spec.method else { unreachable!("a tableau") };
            let eq = equations!($fma, $wide);
            let step = RkStep::<_, $d, $s, $fma, $wide, $scaled>::new(tableau, spec.h, time_scale);
            call!($fma, $d, $wide, eq, step, run, record)
        }};
    }
    macro_rules! go {
        ($fma:tt, $wide:tt) => {{
            match spec.method {
                // A stroboscopic run's steps in each lane's own time unit: RK4's kernels of
                // their own (`Strobe`).
                LaneMethod::Rk(_) if time_scale.is_some() => rk!($fma, $wide, 4, true),
                LaneMethod::Rk(tableau) => rk!($fma, $wide, tableau.b.len(), false),
                LaneMethod::Tao { scheme, .. } => {
                    // Compiled only for the dimensions it runs on (`supports`).
                    if const { M::DIM == 4 } {
                        tao!($fma, $wide, 4, 8, scheme)
                    } else if const { M::DIM > 4 } {
                        // A family's members padded to the largest (one kernel, not one per
                        // padded size: the build time).
                        tao!($fma, $wide, TAO_MAX_DIM, MAX_DIM, scheme)
                    } else {
                        unreachable!("Tao's lanes on {} variables", M::DIM)
                    }
                }
                LaneMethod::KickDrift { scheme, .. } => {
                    // Compiled only for the dimension it runs on (`supports`).
                    if const { M::DIM == KICK_DRIFT_DIM } {
                        let eq = equations!($fma, $wide);
                        let step = KickDrift::<_, KICK_DRIFT_DIM, $fma, $wide> {
                            eqs: std::marker::PhantomData,
                            scheme,
                            primed: false,
                        };
                        call!($fma, 4, $wide, eq, step, run, record)
                    } else {
                        unreachable!("kick-drift lanes on {} variables", M::DIM)
                    }
                }
            }
        }};
    }
    // Tao's map on states padded to D variables, the copy after them (W = 2 D).
    macro_rules! tao {
        ($fma:tt, $wide:tt, $d:tt, $w:tt, $scheme:expr) => {{
            let eq = equations!($fma, $wide);
            let step =
                TaoLanes::<_, $d, $fma, $wide> { eqs: std::marker::PhantomData, scheme: $scheme, n: dim / 2 };
            call!($fma, $w, $wide, eq, step, run, record)
        }};
    }
    // Kernels for every number of stages up to MAX_STAGES, each unrolled.
    macro_rules! by_stages {
        ($fma:tt, $wide:tt, $d:tt, $stages:expr, false) => {
            match $stages {
                1 => with!($fma, $wide, $d, 1, false),
                2 => with!($fma, $wide, $d, 2, false),
                3 => with!($fma, $wide, $d, 3, false),
                _ => with!($fma, $wide, $d, 4, false),
            }
        };
        ($fma:tt, $wide:tt, $d:tt, $stages:expr, true) => {{
            debug_assert_eq!($stages, 4, "a stroboscopic run is RK4's");
            with!($fma, $wide, $d, 4, true)
        }};
    }
    macro_rules! rk {
        ($fma:tt, $wide:tt, $stages:expr, $scaled:tt) => {{
            const { assert!(MAX_STAGES == 4, "a kernel for each number of stages") };
            let stages = $stages;
            // Only the dimensions this system has are compiled (`if const`).
            if const { M::DIM == 2 } {
                by_stages!($fma, $wide, 2, stages, $scaled)
            } else if const { M::DIM == 4 } {
                by_stages!($fma, $wide, 4, stages, $scaled)
            } else {
                family!($fma, $wide, stages, $scaled)
            }
        }};
    }
    // A family (the chain): its members' dimensions, padded to 4, 8 or 16 variables (the
    // padding stays zero: the chain's equations read and write its first 2n). No family is
    // driven, so none has stroboscopic kernels (`stroboscopic` refuses it first).
    macro_rules! family {
        ($fma:tt, $wide:tt, $stages:expr, false) => {
            match dim {
                ..=4 => by_stages!($fma, $wide, 4, $stages, false),
                ..=8 => by_stages!($fma, $wide, 8, $stages, false),
                _ => by_stages!($fma, $wide, 16, $stages, false),
            }
        };
        ($fma:tt, $wide:tt, $stages:expr, true) => {
            unreachable!("stroboscopic lanes on {}", info.name)
        };
    }
    // The fast trigonometry alone; if some lane's arguments went beyond its range (the
    // record is then as it was), again with the exact reduction for those arguments.
    let fma = has_fma();
    macro_rules! advance {
        () => {{
            let done = if fma { go!(true, false) } else { super::plain!(go!(false, false)) };
            if !done {
                if fma {
                    go!(true, true);
                } else {
                    super::plain!(go!(false, true));
                }
            }
        }};
    }
    if let Some(StrobeGroup { periods, samples, rows }) = strobe {
        // Period by period (each from the drive's phase 0: the equations are periodic in
        // time), the angles wrapped into [−π, π) after each (the state's meaning is the same
        // and the sine's arguments stay small), sampled after each member's transient.
        let last = periods.iter().map(|p| p.1).max().unwrap_or(0) + samples as u64;
        for period in 0..last {
            advance!();
            if let Some(i) = (0..members.len()).find(|&i| !record.failed_at[i].is_nan()) {
                return (Vec::new(), Some((i, (period as f64 + record.failed_at[i]) * periods[i].0)));
            }
            for &a in &angles {
                for v in &mut record.state[a] {
                    *v = crate::system::wrap_angle(*v);
                }
            }
            for (i, &(_, transient)) in periods.iter().enumerate() {
                if let Some(s) = period.checked_sub(transient).map(|s| s as usize).filter(|&s| s < samples) {
                    for k in 0..dim {
                        rows[(i * samples + s) * dim + k] = record.state[k][i];
                    }
                }
            }
        }
        return (Vec::new(), None);
    }
    advance!();
    // Tao's lanes back to (q, q'): the final states, and the flipped lanes' ends of the
    // flip's step (their rates are the velocities).
    for (i, model) in tao_models.iter().enumerate().take(members.len()) {
        let convert = |v: &mut [V; MAX_DIM]| {
            let (mut z, mut y) = ([0.0; MAX_DIM], [0.0; MAX_DIM]);
            for k in 0..dim {
                z[k] = v[k][i];
            }
            model.to_velocities(&z[..dim], &mut y[..dim]);
            for k in 0..dim {
                v[k][i] = y[k];
            }
        };
        convert(&mut record.state);
        if record.flip_step[i] >= 0.0 {
            let [before, after] = &mut record.ends;
            convert(before);
            convert(after);
        }
    }
    let outcomes = (0..members.len())
        .map(|i| LaneOutcome {
            state: std::array::from_fn(|k| record.state[k][i]),
            flip_time: flip_time(
                record.flip_step[i],
                [&record.ends[0], &record.ends[1]],
                &angles,
                dim,
                i,
                spec.h,
            ),
        })
        .collect();
    let failed =
        (0..members.len()).find(|&i| !record.failed_at[i].is_nan()).map(|i| (i, record.failed_at[i]));
    (outcomes, failed)
}

/// A lane group's state and per-lane records, arrays over the lanes.
pub(crate) struct Record {
    pub(crate) state: [V; MAX_DIM],
    /// The step in which the lane first flipped (−1: none), as a float.
    pub(crate) flip_step: [f64; LANES],
    /// The watched variables at the start and the end of that step.
    pub(crate) ends: [[V; MAX_DIM]; 2],
    /// Time at which the lane's state became non-finite (NaN: never).
    pub(crate) failed_at: [f64; LANES],
}

impl Record {
    /// A group starting from `state` (its first values per variable; the rest zero), with
    /// nothing recorded.
    pub(crate) fn new(state: [V; MAX_DIM]) -> Record {
        Record {
            state,
            flip_step: [-1.0; LANES],
            ends: [[[0.0; LANES]; MAX_DIM]; 2],
            failed_at: [f64::NAN; LANES],
        }
    }
}

/// One step of a lane group, for [`kernel`]: what a method does. The run loop around it —
/// flips, retirement, non-finite states, the fallback to the exact trigonometry — is the
/// same for every method.
pub(crate) trait LaneStep<const W: usize, const FMA: bool, const WIDE: bool>: Copy {
    /// The equations the step evaluates, handed to it by the kernel (a reference the
    /// compiler knows to be read-only across the whole run, so that what is computed from
    /// the parameters alone stays out of the loop: held in the step, it measured 18% slower).
    type Equations;

    /// Writes into `next`, every value of it (it holds the previous step's on entry), the
    /// state after one step of size `h` from time `t` and state `y` (W values per lane: the
    /// member's variables, then any the method keeps of its own); the reach of the sine and
    /// cosine arguments it took folded into `reach` (one value per half group, not `WIDE`;
    /// see [`Equations::trig_reach`]).
    fn step(
        &mut self,
        eqs: &Self::Equations,
        t: f64,
        h: f64,
        y: &[Lanes<LANES, FMA, WIDE>; W],
        next: &mut [Lanes<LANES, FMA, WIDE>; W],
        reach: &mut [Lanes<HALF, FMA, WIDE>; 2],
    );
}

/// An explicit Runge–Kutta step of S stages on states of D variables: the integrators' own
/// stages ([`fixed_stages`], [`fixed_update`]) over the system's equations, half a group at
/// a time. The tableau is copied into fixed-size arrays, so that its loops unroll and its
/// zero coefficients are known once per group.
struct RkStep<E, const D: usize, const S: usize, const FMA: bool, const WIDE: bool, const SCALED: bool> {
    eqs: std::marker::PhantomData<fn(&E)>,
    a: [[f64; S]; S],
    plan: [Row; S],
    c: [f64; S],
    b: [f64; S],
    scale: f64,
    /// Each lane's time unit ([`LaneRhs::time_scale`]), read only when `SCALED` (a kernel
    /// of its own: a run-time choice in the stages measured W3 1.5 times slower).
    time_scale: Option<[Lanes<HALF, FMA, WIDE>; 2]>,
    /// The stages' slopes (kept between steps only as storage: every step writes them
    /// before reading).
    k: [[Lanes<LANES, FMA, WIDE>; D]; S],
}

// By hand: derived, they would ask the equations to be `Copy`, which a reference to them is.
impl<E, const D: usize, const S: usize, const FMA: bool, const WIDE: bool, const SCALED: bool> Clone
    for RkStep<E, D, S, FMA, WIDE, SCALED>
{
    fn clone(&self) -> Self {
        *self
    }
}

impl<E, const D: usize, const S: usize, const FMA: bool, const WIDE: bool, const SCALED: bool> Copy
    for RkStep<E, D, S, FMA, WIDE, SCALED>
{
}

impl<E, const D: usize, const S: usize, const FMA: bool, const WIDE: bool, const SCALED: bool>
    RkStep<E, D, S, FMA, WIDE, SCALED>
{
    fn new(tab: &Tableau, h: f64, time_scale: Option<[f64; LANES]>) -> Self {
        let (mut a, mut c, mut b) = ([[0.0; S]; S], [0.0; S], [0.0; S]);
        for i in 0..S {
            a[i][..i].copy_from_slice(&tab.a[i][..i]);
            c[i] = tab.c[i];
            b[i] = tab.b[i];
        }
        let mut plan = [Row::Sum; S];
        for (i, p) in plan.iter_mut().enumerate() {
            *p = Row::of(&a[i][..i]);
        }
        RkStep {
            eqs: std::marker::PhantomData,
            a,
            plan,
            c,
            b,
            scale: h / tab.denominator,
            time_scale: time_scale
                .map(|s| [0, 1].map(|half| Lanes(std::array::from_fn(|i| s[half * HALF + i])))),
            k: [[Lanes::splat(0.0); D]; S],
        }
    }
}

impl<E, const D: usize, const S: usize, const FMA: bool, const WIDE: bool, const SCALED: bool>
    LaneStep<D, FMA, WIDE> for RkStep<E, D, S, FMA, WIDE, SCALED>
where
    E: Equations<Lanes<HALF, FMA, WIDE>>,
{
    type Equations = [E; 2];

    #[inline(always)]
    fn step(
        &mut self,
        eqs: &[E; 2],
        t: f64,
        h: f64,
        y: &[Lanes<LANES, FMA, WIDE>; D],
        next: &mut [Lanes<LANES, FMA, WIDE>; D],
        reach: &mut [Lanes<HALF, FMA, WIDE>; 2],
    ) {
        let mut f = LaneRhs::<_, D, FMA, WIDE, SCALED> { eqs, reach: *reach, time_scale: self.time_scale };
        fixed_stages::<_, _, D, _>(&self.a, &self.plan, &self.c, 0, &mut self.k, &mut f, t, h, y);
        *reach = f.reach;
        fixed_update::<_, D>(&self.b, &self.k, self.scale, y, next);
    }
}

/// A kick–drift step ([`kick_drift`]) on states of D variables (positions, then velocities),
/// the accelerations kept after them in the lane state (W ≥ D + D/2 values per lane), from one
/// step to the next.
struct KickDrift<E, const D: usize, const FMA: bool, const WIDE: bool> {
    eqs: std::marker::PhantomData<fn(&E)>,
    scheme: Partition,
    /// Whether the kept accelerations are those at the step's start (false until the first
    /// step of a kernel's run has computed them).
    primed: bool,
}

// By hand, as `RkStep`'s.
impl<E, const D: usize, const FMA: bool, const WIDE: bool> Clone for KickDrift<E, D, FMA, WIDE> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<E, const D: usize, const FMA: bool, const WIDE: bool> Copy for KickDrift<E, D, FMA, WIDE> {}

impl<E, const D: usize, const W: usize, const FMA: bool, const WIDE: bool> LaneStep<W, FMA, WIDE>
    for KickDrift<E, D, FMA, WIDE>
where
    E: Equations<Lanes<HALF, FMA, WIDE>>,
{
    type Equations = [E; 2];

    #[inline(always)]
    fn step(
        &mut self,
        eqs: &[E; 2],
        t: f64,
        h: f64,
        y: &[Lanes<LANES, FMA, WIDE>; W],
        next: &mut [Lanes<LANES, FMA, WIDE>; W],
        reach: &mut [Lanes<HALF, FMA, WIDE>; 2],
    ) {
        const { assert!(W >= D + D / 2, "room for the accelerations") };
        let n = D / 2;
        *next = *y;
        let mut accel = LaneAccelerations::<_, D, FMA, WIDE> {
            f: LaneRhs::<_, D, FMA, WIDE, false> { eqs, reach: *reach, time_scale: None },
            full: [Lanes::splat(0.0); D],
            rates: [Lanes::splat(0.0); D],
        };
        let (state, kept) = next.split_at_mut(D);
        let (q, v) = state.split_at_mut(n);
        kick_drift(self.scheme, t, h, q, v, &mut kept[..n], self.primed, &mut accel);
        self.primed = true;
        *reach = accel.f.reach;
    }
}

/// Tao's map ([`tao_step`]) on a lane group of states padded to D variables: (q, p) in the
/// first 2n values, the copy (x, y) D values further on (W ≥ 2 D); the equations' own
/// gradient ([`Canonical`]), half a group at a time as the Runge–Kutta stages are.
struct TaoLanes<E, const D: usize, const FMA: bool, const WIDE: bool> {
    eqs: std::marker::PhantomData<fn(&E)>,
    scheme: TaoScheme,
    /// Degrees of freedom of the members.
    n: usize,
}

// By hand, as `RkStep`'s.
impl<E, const D: usize, const FMA: bool, const WIDE: bool> Clone for TaoLanes<E, D, FMA, WIDE> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<E, const D: usize, const FMA: bool, const WIDE: bool> Copy for TaoLanes<E, D, FMA, WIDE> {}

impl<E, const D: usize, const W: usize, const FMA: bool, const WIDE: bool> LaneStep<W, FMA, WIDE>
    for TaoLanes<E, D, FMA, WIDE>
where
    E: Equations<Lanes<HALF, FMA, WIDE>> + Canonical<Lanes<HALF, FMA, WIDE>>,
{
    type Equations = [E; 2];

    #[inline(always)]
    fn step(
        &mut self,
        eqs: &[E; 2],
        t: f64,
        h: f64,
        y: &[Lanes<LANES, FMA, WIDE>; W],
        next: &mut [Lanes<LANES, FMA, WIDE>; W],
        reach: &mut [Lanes<HALF, FMA, WIDE>; 2],
    ) {
        const { assert!(W >= 2 * D, "room for the copy") };
        *next = *y;
        // The halves written out, as the stages' (each half's equations stay values).
        self.half::<0, W>(&eqs[0], t, h, next, &mut reach[0]);
        self.half::<1, W>(&eqs[1], t, h, next, &mut reach[1]);
    }
}

impl<E, const D: usize, const FMA: bool, const WIDE: bool> TaoLanes<E, D, FMA, WIDE>
where
    E: Equations<Lanes<HALF, FMA, WIDE>> + Canonical<Lanes<HALF, FMA, WIDE>>,
{
    #[inline(always)]
    fn half<const H: usize, const W: usize>(
        &self,
        eq: &E,
        t: f64,
        h: f64,
        state: &mut [Lanes<LANES, FMA, WIDE>; W],
        reach: &mut Lanes<HALF, FMA, WIDE>,
    ) {
        type L<const FMA: bool, const WIDE: bool> = Lanes<HALF, FMA, WIDE>;
        let n = self.n;
        let zero = L::<FMA, WIDE>::splat(0.0);
        let mut z = [zero; W];
        for (v, w) in z.iter_mut().zip(state.iter()) {
            v.0.copy_from_slice(&w.0[H * HALF..][..HALF]);
        }
        let (mut dq, mut dp) = ([zero; D], [zero; D]);
        let mut gradient = LaneGradient::<_, D, FMA, WIDE> { eq, n, reach: *reach };
        let (own, copy) = z.split_at_mut(D);
        let (q, p) = own[..2 * n].split_at_mut(n);
        let (x, y) = copy[..2 * n].split_at_mut(n);
        tao_step(&self.scheme, t, h, [q, p, x, y], &mut dq[..n], &mut dp[..n], &mut gradient);
        *reach = gradient.reach;
        for (v, w) in state.iter_mut().zip(&z) {
            v.0[H * HALF..][..HALF].copy_from_slice(&w.0);
        }
    }
}

/// Half a lane group's Hamiltonian gradient for [`tao_step`], from the equations' own
/// ([`Canonical`]), tracking (when not `WIDE`) how far the sine and cosine arguments reach (not
/// a closure: its method is kept in line, with the kernel's instruction set).
struct LaneGradient<'a, E, const D: usize, const FMA: bool, const WIDE: bool> {
    eq: &'a E,
    n: usize,
    reach: Lanes<HALF, FMA, WIDE>,
}

impl<E, const D: usize, const FMA: bool, const WIDE: bool>
    crate::integrator::tao::Gradient<Lanes<HALF, FMA, WIDE>> for LaneGradient<'_, E, D, FMA, WIDE>
where
    E: Equations<Lanes<HALF, FMA, WIDE>> + Canonical<Lanes<HALF, FMA, WIDE>>,
{
    #[inline(always)]
    fn gradient(
        &mut self,
        t: f64,
        q: &[Lanes<HALF, FMA, WIDE>],
        p: &[Lanes<HALF, FMA, WIDE>],
        dq: &mut [Lanes<HALF, FMA, WIDE>],
        dp: &mut [Lanes<HALF, FMA, WIDE>],
    ) {
        let t = Lanes::splat(t);
        if !WIDE {
            // The gradient's arguments laid out as a state (positions, then momenta in the
            // velocities' place) for the equations' bound on their trigonometry.
            let n = self.n;
            let mut s = [Lanes::splat(0.0); D];
            s[..n].copy_from_slice(q);
            s[n..2 * n].copy_from_slice(p);
            self.reach = self.eq.trig_reach(t, &s[..2 * n]).max(self.reach);
        }
        self.eq.gradient(t, q, p, dq, dp);
    }
}

/// A lane group's accelerations for [`kick_drift`], from the equations' right-hand side (not
/// a closure: its method is kept in line, with the kernel's instruction set).
struct LaneAccelerations<'a, E, const D: usize, const FMA: bool, const WIDE: bool> {
    f: LaneRhs<'a, E, D, FMA, WIDE, false>,
    /// The equations' state: the positions, and velocities left at zero (the accelerations
    /// of a separable system do not depend on them).
    full: [Lanes<LANES, FMA, WIDE>; D],
    rates: [Lanes<LANES, FMA, WIDE>; D],
}

impl<E: Equations<Lanes<HALF, FMA, WIDE>>, const D: usize, const FMA: bool, const WIDE: bool>
    Accelerations<Lanes<LANES, FMA, WIDE>> for LaneAccelerations<'_, E, D, FMA, WIDE>
{
    #[inline(always)]
    fn accelerations(&mut self, t: f64, q: &[Lanes<LANES, FMA, WIDE>], a: &mut [Lanes<LANES, FMA, WIDE>]) {
        let n = D / 2;
        self.full[..n].copy_from_slice(q);
        self.f.eval(t, &self.full, &mut self.rates);
        a.copy_from_slice(&self.rates[n..]);
    }
}

/// A run's parameters, for the kernel.
pub(crate) struct Run<'a> {
    /// The variables watched for flips and failures: the first `dim` of the state (the
    /// member's own; a method may keep more after them, as Tao's copy).
    pub(crate) dim: usize,
    /// The angles among the watched variables (their rates `dim / 2` further on).
    pub(crate) angles: &'a [usize],
    pub(crate) h: f64,
    pub(crate) steps: u64,
    pub(crate) stop_at_flip: bool,
    /// Whether flips are located (a run-time flag, not a compiled variant: with nothing to
    /// watch the probe never calls for the lane-by-lane step).
    pub(crate) track: bool,
}

/// Lane i's flip time, s (NaN: no flip, `step` < 0): the first time, within the step of the
/// flip (step number `step`, of size `h`), at which the cubic Hermite interpolant of an angle
/// that crossed passes ±π, from the state at both ends of that step (`before`, `after`: the
/// positions `angles`, and their rates `dim / 2` further on). Shared with Tao's lanes.
pub(crate) fn flip_time(
    step: f64,
    [before, after]: [&[[f64; LANES]]; 2],
    angles: &[usize],
    dim: usize,
    i: usize,
    h: f64,
) -> f64 {
    use std::f64::consts::PI;
    if step < 0.0 {
        return f64::NAN;
    }
    let mut first = f64::INFINITY;
    for &k in angles {
        let (a, b) = (before[k][i], after[k][i]);
        if a.abs() <= PI && b.abs() > PI {
            let (da, db) = (before[k + dim / 2][i], after[k + dim / 2][i]);
            first = first.min(crate::events::hermite_crossing(
                h,
                (step + 1.0) * h,
                [a, da],
                [b, db],
                PI.copysign(b),
            ));
        }
    }
    step * h + first * h
}

/// Members per evaluation of the equations: half a lane group, one AVX-512 vector per value.
/// The group's two halves are evaluated one after the other (two independent chains of
/// about 60 operations each), which keeps every intermediate in registers; a whole group at
/// once, two vectors per value, measured slower from spills.
const HALF: usize = LANES / 2;

/// The right-hand side of a lane group's stages, evaluated half a group at a time, tracking
/// (when not `WIDE`) how far the sine and cosine arguments reach.
struct LaneRhs<'a, E, const D: usize, const FMA: bool, const WIDE: bool, const SCALED: bool> {
    eqs: &'a [E; 2],
    reach: [Lanes<HALF, FMA, WIDE>; 2],
    /// Each lane's time unit, s per unit of the run's time (see [`Strobe`]: a stroboscopic
    /// run steps every member in fractions of its own drive period), or `None`: seconds.
    time_scale: Option<[Lanes<HALF, FMA, WIDE>; 2]>,
}

impl<
    E: Equations<Lanes<HALF, FMA, WIDE>>,
    const D: usize,
    const FMA: bool,
    const WIDE: bool,
    const SCALED: bool,
> StageRhs<Lanes<LANES, FMA, WIDE>> for LaneRhs<'_, E, D, FMA, WIDE, SCALED>
{
    #[inline(always)]
    fn eval(&mut self, t: f64, y: &[Lanes<LANES, FMA, WIDE>], dydt: &mut [Lanes<LANES, FMA, WIDE>]) {
        let t = Lanes::splat(t);
        // The halves written out, not a loop: each half's equations (and the products of
        // parameters they form) are then values the compiler keeps across the steps.
        self.half::<0>(t, y, dydt);
        self.half::<1>(t, y, dydt);
    }
}

impl<
    E: Equations<Lanes<HALF, FMA, WIDE>>,
    const D: usize,
    const FMA: bool,
    const WIDE: bool,
    const SCALED: bool,
> LaneRhs<'_, E, D, FMA, WIDE, SCALED>
{
    #[inline(always)]
    fn half<const H: usize>(
        &mut self,
        t: Lanes<HALF, FMA, WIDE>,
        y: &[Lanes<LANES, FMA, WIDE>],
        dydt: &mut [Lanes<LANES, FMA, WIDE>],
    ) {
        let mut yh = [Lanes([0.0; HALF]); D];
        for (v, w) in yh.iter_mut().zip(y) {
            v.0.copy_from_slice(&w.0[H * HALF..][..HALF]);
        }
        let eq = &self.eqs[H];
        // In a lane's own time unit s: y' = s f(s t, y) (a branch on a value fixed for the
        // run, always taken the same way).
        let scale = if SCALED { self.time_scale.map(|s| s[H]) } else { None };
        let t = scale.map_or(t, |s| s * t);
        if !WIDE {
            self.reach[H] = eq.trig_reach(t, &yh).max(self.reach[H]);
        }
        let mut dh = [Lanes([0.0; HALF]); D];
        eq.rhs_sized(t, &yh, &mut dh);
        if let Some(s) = scale {
            for v in &mut dh {
                *v = s * *v;
            }
        }
        for (v, w) in dydt.iter_mut().zip(&dh) {
            v.0[H * HALF..][..HALF].copy_from_slice(&w.0);
        }
    }
}

/// [`kernel`] with fused multiply-adds, compiled for the instruction sets that have them and
/// chosen at run time (debug builds, the tests: AVX2 with FMA and the portable fallback only,
/// the same arithmetic — `mul_add` is correctly rounded everywhere — in a fraction of the
/// build time).
#[cfg_attr(
    not(debug_assertions),
    multiversion::multiversion(targets(
        "x86_64+avx512f+avx512dq+avx2+fma",
        "x86_64+avx2+fma",
        "aarch64+neon"
    ))
)]
#[cfg_attr(debug_assertions, multiversion::multiversion(targets("x86_64+avx2+fma", "aarch64+neon")))]
pub(crate) fn kernel_fused<St, const W: usize, const WIDE: bool>(
    eqs: &St::Equations,
    step: &St,
    run: &Run<'_>,
    record: &mut Record,
) -> bool
where
    St: LaneStep<W, true, WIDE>,
{
    kernel::<St, W, true, WIDE>(eqs, step, run, record)
}

/// [`kernel`] without fused multiply-adds, for CPUs without them (AVX, or the portable
/// fallback).
#[cfg_attr(not(debug_assertions), multiversion::multiversion(targets("x86_64+avx")))]
#[cfg_attr(debug_assertions, allow(dead_code))] // debug builds fuse (`has_fma`)
pub(crate) fn kernel_plain<St, const W: usize, const WIDE: bool>(
    eqs: &St::Equations,
    step: &St,
    run: &Run<'_>,
    record: &mut Record,
) -> bool
where
    St: LaneStep<W, false, WIDE>,
{
    kernel::<St, W, false, WIDE>(eqs, step, run, record)
}

/// The run loop of a lane group: `run.steps` steps of `method` from `record`'s state.
/// Branch-free per lane: retired lanes keep computing but their state is not updated; a
/// flip's step is recorded, and its time interpolated once at the end. Not `WIDE`, the fast
/// trigonometry alone: false, with `record` untouched, after the first step in which some
/// lane's sine and cosine arguments ([`Equations::trig_reach`], tracked as data flow) went
/// beyond its range; `WIDE`, every argument (true).
#[allow(clippy::needless_range_loop)] // lane-indexed loops: the form that vectorises over lanes
#[inline(always)]
fn kernel<St, const W: usize, const FMA: bool, const WIDE: bool>(
    eqs: &St::Equations,
    method: &St,
    run: &Run<'_>,
    record: &mut Record,
) -> bool
where
    St: LaneStep<W, FMA, WIDE>,
{
    use std::f64::consts::PI;
    type L<const FMA: bool, const WIDE: bool> = Lanes<LANES, FMA, WIDE>;
    let (dim, h) = (run.dim, run.h);
    // A copy of the method's data local to the kernel: the compiler keeps what it needs in
    // registers (a step reached through a reference measured 8% slower on W3).
    let mut method = *method;
    let zero = L::<FMA, WIDE>::splat(0.0);
    let mut y: [L<FMA, WIDE>; W] = [zero; W];
    for (v, s) in y.iter_mut().zip(&record.state) {
        *v = Lanes(*s);
    }
    let mut active = [true; LANES];
    // Whether some lane has retired (then states are updated lane by lane).
    let mut retired = false;
    // Per lane, how far an angle may go before the step needs a closer look: π while the lane
    // may still flip, beyond every angle once it has (or has retired).
    let mut watch = [if run.track { PI } else { f64::INFINITY }; LANES];
    let mut flip_step = [-1.0; LANES];
    let [mut before, mut after] = [[[0.0; LANES]; MAX_DIM]; 2];
    let mut failed_step = [-1.0; LANES];
    let mut reach = [Lanes([0.0; HALF]); 2];
    // Every step writes all of it (no copy of y first).
    let mut next = y;
    for step in 0..run.steps {
        // Times from the step index, as the scalar loop computes them.
        let t = step as f64 * h;
        method.step(eqs, t, h, &y, &mut next, &mut reach);
        // One probe per lane for the common step, in which nothing happens: the sum of the
        // state's components is finite (so is every component; a sum that overflows only
        // sends the step to the closer look), and no watched angle went beyond π. Every loop
        // runs over the lanes innermost: one vector operation per variable.
        let mut probe = next[0].0;
        for v in &next[1..dim] {
            for i in 0..LANES {
                probe[i] += v.0[i];
            }
        }
        let mut notable = [false; LANES];
        for i in 0..LANES {
            // 0 · x is NaN exactly when x is not finite.
            notable[i] = (0.0 * probe[i]).is_nan();
        }
        for &a in run.angles {
            for i in 0..LANES {
                notable[i] |= next[a].0[i].abs() > watch[i];
            }
        }
        let mut any = false;
        for i in 0..LANES {
            any |= notable[i];
        }
        if !any {
            if retired {
                // Every variable, the method's own too: a retired lane keeps all it had.
                for c in 0..W {
                    for i in 0..LANES {
                        y[c].0[i] = if active[i] { next[c].0[i] } else { y[c].0[i] };
                    }
                }
            } else {
                y = next;
            }
        } else {
            // Lane by lane: a non-finite state, a flip, a retirement.
            let step_f = step as f64;
            let mut finite = [true; LANES];
            for v in &next[..dim] {
                for i in 0..LANES {
                    finite[i] &= v.0[i].is_finite();
                }
            }
            for i in 0..LANES {
                failed_step[i] = if active[i] & !finite[i] { step_f } else { failed_step[i] };
            }
            if run.track {
                let mut crosses = [false; LANES];
                for &a in run.angles {
                    for i in 0..LANES {
                        let (o, n) = (y[a].0[i].abs(), next[a].0[i].abs());
                        crosses[i] |= (o <= PI) & (n > PI);
                    }
                }
                let mut flips = [false; LANES];
                let mut keep = [false; LANES];
                for i in 0..LANES {
                    flips[i] = active[i] & finite[i] & crosses[i] & (flip_step[i] < 0.0);
                    flip_step[i] = if flips[i] { step_f } else { flip_step[i] };
                    keep[i] = active[i] & finite[i];
                    active[i] = keep[i] & !(run.stop_at_flip & flips[i]);
                    retired |= !active[i];
                    watch[i] = if active[i] & (flip_step[i] < 0.0) { PI } else { f64::INFINITY };
                }
                for c in 0..dim {
                    for i in 0..LANES {
                        before[c][i] = if flips[i] { y[c].0[i] } else { before[c][i] };
                        after[c][i] = if flips[i] { next[c].0[i] } else { after[c][i] };
                    }
                }
                for c in 0..W {
                    for i in 0..LANES {
                        y[c].0[i] = if keep[i] { next[c].0[i] } else { y[c].0[i] };
                    }
                }
            } else {
                // Nothing retires: a non-finite lane makes the whole run an error, so its
                // state need not be kept; only the step it failed at (once) is.
                y = next;
                for i in 0..LANES {
                    active[i] &= finite[i];
                }
            }
        }
        if !WIDE {
            // Loops, not iterator adaptors: their closures, left out of line, do not get the
            // kernel's instruction set.
            let mut beyond = false;
            for r in &reach {
                for i in 0..HALF {
                    beyond |= r.0[i] > trig::FAST_RANGE;
                }
            }
            if beyond {
                return false;
            }
        }
        if retired {
            let mut any = false;
            for i in 0..LANES {
                any |= active[i];
            }
            if !any {
                break;
            }
        }
    }
    for (at, step) in record.failed_at.iter_mut().zip(failed_step) {
        if step >= 0.0 {
            *at = (step + 1.0) * h;
        }
    }
    record.flip_step = flip_step;
    record.ends = [before, after];
    for (s, v) in record.state.iter_mut().zip(&y) {
        *s = v.0;
    }
    true
}

/// One member in the engine arithmetic: an explicit tableau stepping the model's own
/// equations over one lane (`Lanes<1, FMA, true>`: the polynomial sine and cosine, the exact
/// reduction where an argument needs it, fused multiply-adds when `FMA`) — the bits a lane of
/// [`run`] gives the member. A [`Stepper`] of the scalar run loop (the system it is handed is
/// not used: the stepper holds the model's equations in its own number type).
struct OneLane<E, const FMA: bool> {
    tableau: &'static Tableau,
    plan: Plan,
    eq: E,
    k: Vec<Lanes<1, FMA, true>>,
    stage: Vec<Lanes<1, FMA, true>>,
    y: Vec<Lanes<1, FMA, true>>,
}

impl<S: ?Sized, E: Equations<Lanes<1, FMA, true>>, const FMA: bool> Stepper<S> for OneLane<E, FMA> {
    fn step(&mut self, _: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        // Compiled for the CPU's instruction set, as the lanes' kernels are (without, each
        // fused multiply-add would be a call into libm).
        if FMA {
            one_lane_fused(self, t, h, y);
        } else {
            one_lane_plain(self, t, h, y);
        }
        Ok(())
    }
}

/// [`one_lane_step`] for the instruction sets with fused multiply-adds (see [`kernel_fused`]).
#[cfg_attr(
    not(debug_assertions),
    multiversion::multiversion(targets(
        "x86_64+avx512f+avx512dq+avx2+fma",
        "x86_64+avx2+fma",
        "aarch64+neon"
    ))
)]
#[cfg_attr(debug_assertions, multiversion::multiversion(targets("x86_64+avx2+fma", "aarch64+neon")))]
fn one_lane_fused<E: Equations<Lanes<1, FMA, true>>, const FMA: bool>(
    stepper: &mut OneLane<E, FMA>,
    t: f64,
    h: f64,
    y: &mut [f64],
) {
    one_lane_step(stepper, t, h, y);
}

/// [`one_lane_step`] without fused multiply-adds (see [`kernel_plain`]).
#[cfg_attr(not(debug_assertions), multiversion::multiversion(targets("x86_64+avx")))]
fn one_lane_plain<E: Equations<Lanes<1, FMA, true>>, const FMA: bool>(
    stepper: &mut OneLane<E, FMA>,
    t: f64,
    h: f64,
    y: &mut [f64],
) {
    one_lane_step(stepper, t, h, y);
}

/// One explicit Runge–Kutta step on one lane: the integrators' own stages over the model's
/// equations.
#[inline(always)]
fn one_lane_step<E: Equations<Lanes<1, FMA, true>>, const FMA: bool>(
    stepper: &mut OneLane<E, FMA>,
    t: f64,
    h: f64,
    y: &mut [f64],
) {
    let tab = stepper.tableau;
    for (lane, v) in stepper.y.iter_mut().zip(y.iter()) {
        *lane = Lanes([*v]);
    }
    let mut f = OneLaneRhs { eq: &stepper.eq };
    explicit_stages(
        tab.a,
        &stepper.plan,
        tab.c,
        0,
        &mut stepper.k,
        &mut stepper.stage,
        &mut f,
        t,
        h,
        &stepper.y,
    );
    explicit_update(tab.b, &stepper.k, h / tab.denominator, &mut stepper.y);
    for (v, lane) in y.iter_mut().zip(&stepper.y) {
        *v = lane.0[0];
    }
}

/// One lane's right-hand side for [`explicit_stages`] (not a closure: its method is kept in
/// line, with the step's instruction set).
struct OneLaneRhs<'a, E> {
    eq: &'a E,
}

impl<E: Equations<Lanes<1, FMA, true>>, const FMA: bool> StageRhs<Lanes<1, FMA, true>> for OneLaneRhs<'_, E> {
    #[inline(always)]
    fn eval(&mut self, t: f64, y: &[Lanes<1, FMA, true>], dydt: &mut [Lanes<1, FMA, true>]) {
        self.eq.rhs(Lanes([t]), y, dydt);
    }
}

/// Kick–drift on one lane: what a lane of [`run`] gives a member with
/// [`LaneMethod::KickDrift`] (the accelerations kept from step to step, as the lanes keep
/// them in their state).
struct OneLaneKickDrift<E, const FMA: bool> {
    scheme: Partition,
    eq: E,
    /// Positions then velocities, the equations' state (velocities zero while the
    /// accelerations are evaluated).
    y: Vec<Lanes<1, FMA, true>>,
    full: Vec<Lanes<1, FMA, true>>,
    rates: Vec<Lanes<1, FMA, true>>,
    a: Vec<Lanes<1, FMA, true>>,
    primed: bool,
}

impl<S: ?Sized, E: Equations<Lanes<1, FMA, true>>, const FMA: bool> Stepper<S> for OneLaneKickDrift<E, FMA> {
    fn step(&mut self, _: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        let n = y.len() / 2;
        for (lane, v) in self.y.iter_mut().zip(y.iter()) {
            *lane = Lanes([*v]);
        }
        let Self { eq, full, rates, .. } = self;
        let mut accel = |s: f64, q: &[Lanes<1, FMA, true>], a: &mut [Lanes<1, FMA, true>]| {
            full[..n].copy_from_slice(q);
            eq.rhs(Lanes([s]), full, rates);
            a.copy_from_slice(&rates[n..]);
        };
        let (q, v) = self.y.split_at_mut(n);
        kick_drift(self.scheme, t, h, q, v, &mut self.a, self.primed, &mut accel);
        self.primed = true;
        for (v, lane) in y.iter_mut().zip(&self.y) {
            *v = lane.0[0];
        }
        Ok(())
    }
}

/// Tao's map on one lane, on (q, p): what a lane of [`run`] gives a member with
/// [`LaneMethod::Tao`] (the copy kept from step to step, as the lanes keep it in their
/// state; it starts equal to the state).
struct OneLaneTao<E, const FMA: bool> {
    scheme: TaoScheme,
    eq: E,
    /// (q, p), then the copy (x, y).
    z: Vec<Lanes<1, FMA, true>>,
    dq: Vec<Lanes<1, FMA, true>>,
    dp: Vec<Lanes<1, FMA, true>>,
    primed: bool,
}

impl<S: ?Sized, E: Equations<Lanes<1, FMA, true>> + Canonical<Lanes<1, FMA, true>>, const FMA: bool>
    Stepper<S> for OneLaneTao<E, FMA>
{
    fn step(&mut self, _: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        let (dim, n) = (y.len(), y.len() / 2);
        for (k, v) in y.iter().enumerate() {
            self.z[k] = Lanes([*v]);
            if !self.primed {
                self.z[dim + k] = Lanes([*v]);
            }
        }
        self.primed = true;
        let Self { eq, z, dq, dp, scheme, .. } = self;
        let mut gradient =
            |t: f64, a: &[Lanes<1, FMA, true>], b: &[Lanes<1, FMA, true>], dq: &mut [_], dp: &mut [_]| {
                eq.gradient(Lanes([t]), a, b, dq, dp);
            };
        let (own, copy) = z.split_at_mut(dim);
        let (q, p) = own.split_at_mut(n);
        let (x, w) = copy.split_at_mut(n);
        tao_step(scheme, t, h, [q, p, x, w], dq, dp, &mut gradient);
        for (v, lane) in y.iter_mut().zip(&self.z) {
            *v = lane.0[0];
        }
        Ok(())
    }
}

/// Whether the one-lane Runge–Kutta stepper used fused multiply-adds: its whole state
/// (stages are not kept across steps), so that a run paused on a CPU with them is refused on
/// one without (it would round differently), and one paused without continues without.
impl<E, const FMA: bool> Snapshot for OneLane<E, FMA> {
    fn save(&self, out: &mut Words) {
        out.bool(FMA);
    }
    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        if from.bool()? != FMA {
            return Err(Error::BadCheckpoint {
                part: ONE_LANE,
                reason: "it was computed with a different use of fused multiply-adds".into(),
            });
        }
        Ok(())
    }
}

/// The checkpoint part of the one-lane stepper.
const ONE_LANE: &str = "the engine's one-lane stepper";

/// Runs `model` from `y0` with `method` in the engine arithmetic (see the one-lane steppers:
/// polynomial sine and cosine, fused multiply-adds where the CPU has them), fixed steps as
/// `spec` says, showing every state to `observer` (without an energy: observers that need one
/// compute it): the single-member form of [`run`], bit for bit what a lane of a sweep gives
/// the same member.
///
/// # Errors
/// What `method` requires and the model lacks ([`crate::simulate::check`]); an invalid
/// `spec`; [`Error::NonFinite`] at the first non-finite state.
pub fn solve_one<M: Model>(
    model: &M,
    method: LaneMethod,
    y0: &[f64],
    spec: &RunSpec,
    observer: &mut dyn Observer,
) -> Result<Report, Error> {
    match solve_one_resumable(model, method, y0, spec, observer, None, &Pause::NEVER)? {
        Leg::Done(report) => Ok(report),
        Leg::Paused(state) => unreachable!("a run that never pauses paused at step {}", state.steps),
    }
}

/// [`solve_one`] that pauses when `pause` says so (after a step, never the last) and
/// continues `from` a state it paused at, bit for bit, as
/// [`crate::simulate::resume::solve_resumable`] does: the fast path of a single fixed-step
/// run ([`crate::model::DynModel::solve_fastest`]). Explicit Runge–Kutta tableaus only may
/// pause (their stepper keeps nothing between steps but whether it fuses multiply-adds);
/// kick–drift and Tao's map run without pausing.
///
/// # Errors
/// As [`solve_one`]; [`Error::BadCheckpoint`] when `from` does not fit.
///
/// # Panics
/// When asked to pause or resume with another method than a tableau.
pub fn solve_one_resumable<M: Model>(
    model: &M,
    method: LaneMethod,
    y0: &[f64],
    spec: &RunSpec,
    observer: &mut dyn Observer,
    from: Option<&RunState>,
    pause: &Pause<'_>,
) -> Result<Leg<Report>, Error> {
    fn go<M: Model, const FMA: bool>(
        model: &M,
        method: LaneMethod,
        y0: &[f64],
        spec: &RunSpec,
        observer: &mut dyn Observer,
        from: Option<&RunState>,
        pause: &Pause<'_>,
    ) -> Result<Leg<Report>, Error> {
        let n = y0.len();
        let zero = Lanes([0.0]);
        let eq = model.convert(&|x| Lanes::<1, FMA, true>([x]));
        let mut y = y0.to_vec();
        let simulation = Simulation { system: &(), spec: *spec };
        let leg = match method {
            LaneMethod::Rk(tableau) => {
                let mut stepper = OneLane::<_, FMA> {
                    tableau,
                    plan: plan(tableau.a),
                    eq,
                    k: vec![zero; tableau.b.len() * n],
                    stage: vec![zero; n],
                    y: vec![zero; n],
                };
                let done = match from {
                    None => 0,
                    Some(state) => {
                        state.check(n)?;
                        stepper.restore_all(&state.stepper, ONE_LANE)?;
                        y.copy_from_slice(&state.y);
                        state.steps
                    }
                };
                match simulation.run_from(&mut stepper, &mut y, observer, done, pause)? {
                    Leg::Done(outcome) => Leg::Done(outcome),
                    Leg::Paused(mut state) => {
                        state.stepper = stepper.snapshot();
                        state.evaluations = [method.evaluations(state.steps), 0, 0];
                        return Ok(Leg::Paused(state));
                    }
                }
            }
            LaneMethod::KickDrift { method, scheme } => {
                assert!(from.is_none() && pause.never(), "kick-drift on one lane does not pause");
                crate::simulate::check(method, model)?;
                Leg::Done(simulation.run(
                    &mut OneLaneKickDrift::<_, FMA> {
                        scheme,
                        eq,
                        y: vec![zero; n],
                        full: vec![zero; n],
                        rates: vec![zero; n],
                        a: vec![zero; n / 2],
                        primed: false,
                    },
                    &mut y,
                    observer,
                )?)
            }
            LaneMethod::Tao { method, scheme } => {
                assert!(from.is_none() && pause.never(), "Tao's map on one lane does not pause");
                // On (q, p), converted by the model's own maps as the lanes convert; the
                // observer shown (q, q').
                crate::simulate::check(method, model)?;
                crate::integrator::tao::check_binding_step(&scheme, spec.h)?;
                let mut z = vec![0.0; n];
                model.to_momenta(y0, &mut z);
                let mut shown = crate::simulate::ToVelocities { model, y: vec![0.0; n], inner: observer };
                let outcome = simulation.run(
                    &mut OneLaneTao::<_, FMA> {
                        scheme,
                        eq,
                        z: vec![zero; 2 * n],
                        dq: vec![zero; n / 2],
                        dp: vec![zero; n / 2],
                        primed: false,
                    },
                    &mut z,
                    &mut shown,
                )?;
                model.to_velocities(&z, &mut y);
                Leg::Done(outcome)
            }
        };
        let Leg::Done(outcome) = leg else { unreachable!("paused legs returned above") };
        Ok(Leg::Done(Report {
            outcome,
            rhs_evals: method.evaluations(outcome.steps()),
            state: y,
            steps_rejected: 0,
            jacobian_evals: 0,
        }))
    }
    // A run continued from a checkpoint keeps the arithmetic it was saved with.
    let fma = match from {
        None => has_fma(),
        Some(state) => {
            let fma = Reader::new(&state.stepper.0, ONE_LANE).bool()?;
            if fma && !has_fma() {
                return Err(Error::BadCheckpoint {
                    part: ONE_LANE,
                    reason: "it was computed with fused multiply-adds, which this CPU lacks".into(),
                });
            }
            fma
        }
    };
    if fma {
        go::<M, true>(model, method, y0, spec, observer, from, pause)
    } else {
        super::plain!(go::<M, false>(model, method, y0, spec, observer, from, pause))
    }
}
