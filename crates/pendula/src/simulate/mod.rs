//! The run loop: a [`Simulation`] drives a stepper over a system and shows every state to
//! an observer; [`solve`] does the same for a catalogued [`Model`] and a [`Method`] chosen
//! at run time, and [`crate::simulate::resume::solve_resumable`] also pauses and continues it bit for bit
//! ([`crate::checkpoint`]). The adaptive loop is in [`crate::simulate::adaptive`].
//!
//! # The core types
//!
//! `Simulation`: the fixed-step loop: system + stepper + `RunSpec` → `Outcome`, showing every state
//! to an observer.
//!
//! `solve`, `check`: `solve` runs a catalogued model with a method chosen at run time and a
//! `Stepping` (fixed: a `RunSpec`; adaptive: tolerances), the one entry for a single run
//! (`solve_adaptive` is its shorthand, `solve_resumable` its resumable form); methods that need (q,
//! p) run on the Hamiltonian form and show states as (q, q'); `check(method, model)` answers
//! whether the method applies before any step (`DynModel::check`; the CLI's method lists use it).

pub mod adaptive;
pub mod resume;

use std::cell::Cell;

use crate::Error;
use crate::checkpoint::{Leg, Pause, RunState, Snapshot};
use crate::control::Tolerances;
use crate::integrator::embedded::EmbeddedRk;
use crate::integrator::explicit_rk::ExplicitRk;
use crate::integrator::gauss_legendre::Collocation;
use crate::integrator::partitioned::PartitionedStepper;
use crate::integrator::tao::TaoStepper;
use crate::integrator::{Method, Requirement, Scheme, Stepper};
use crate::observe::Pausing;
use std::ops::ControlFlow;

use crate::observe::{Observer, Sample};
pub use crate::simulate::adaptive::solve_adaptive;
use crate::system::{Hamiltonian, Model, System};

/// More steps than this is surely a mistake (10¹³ steps take days).
pub const MAX_STEPS: f64 = 1e13;

/// Where a run ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum End {
    /// At this time, s; the last step is shortened to land on it exactly.
    Time(f64),
    /// After this many steps of size h.
    Steps(u64),
}

/// A fixed-step run: start time, step size and end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSpec {
    /// Start time t₀, s.
    pub t0: f64,
    /// Step size h, s: > 0, or < 0 for a run backward in time to an `End::Time` before t₀
    /// (every method steps with a negative h as with a positive one; t = t₀ + k h).
    pub h: f64,
    /// Where the run ends.
    pub end: End,
}

/// The steps a [`RunSpec`] takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Schedule {
    /// Number of steps.
    pub steps: u64,
    /// Size of the last step, s (h unless shortened to land on the end time).
    pub last_h: f64,
    /// Final time, s.
    pub t_end: f64,
}

impl RunSpec {
    /// Checks the values and works out the steps.
    pub fn schedule(&self) -> Result<Schedule, Error> {
        let invalid =
            |name: &str, value: f64, allowed| Error::InvalidValue { name: name.to_owned(), value, allowed };
        let h = self.h;
        // A negative step runs backward, to an end time before the start; toward a later
        // end, or for a step count, it is the step that is wrong.
        let backward = h < 0.0 && matches!(self.end, End::Time(t_end) if t_end < self.t0);
        if !(h.is_finite() && (h > 0.0 || backward)) {
            return Err(invalid("h", h, "the step size must be finite and > 0"));
        }
        if !self.t0.is_finite() {
            return Err(invalid("t0", self.t0, "the start time must be finite"));
        }
        match self.end {
            End::Steps(n) => {
                if n == 0 {
                    return Err(invalid("steps", 0.0, "the number of steps must be >= 1"));
                }
                if n as f64 > MAX_STEPS {
                    return Err(invalid("steps", n as f64, "the number of steps must be at most 10^13"));
                }
                Ok(Schedule { steps: n, last_h: h, t_end: self.t0 + n as f64 * h })
            }
            End::Time(t_end) => {
                let span = t_end - self.t0;
                let ahead = if backward { span < 0.0 } else { span > 0.0 };
                if !(t_end.is_finite() && ahead) {
                    let allowed = if backward {
                        "with a negative step the run goes backward: the end time must be finite and before the start"
                    } else {
                        "the end time must be finite and > 0"
                    };
                    return Err(invalid("t_end", t_end, allowed));
                }
                let ratio = span / h;
                if ratio > MAX_STEPS {
                    return Err(invalid("h", h, "the step size gives more than 10^13 steps"));
                }
                // A whole number of steps up to rounding (10/1e-3 = 9999.999…): keep every
                // step at h, as a fixed-step user expects, and land on t_end exactly.
                let whole = ratio.round();
                if whole >= 1.0 && (ratio - whole).abs() <= 1e-9 * whole {
                    return Ok(Schedule { steps: whole as u64, last_h: h, t_end });
                }
                let steps = ratio.ceil().max(1.0);
                let last_h = t_end - (self.t0 + (steps - 1.0) * h);
                Ok(Schedule { steps: steps as u64, last_h, t_end })
            }
        }
    }
}

/// How a run ended (failures are [`Error`]s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// It reached its end.
    ReachedEnd {
        /// Steps taken.
        steps: u64,
        /// Final time, s.
        t: f64,
    },
    /// An observer stopped it.
    Stopped {
        /// Steps taken.
        steps: u64,
        /// Time of the last state, s.
        t: f64,
    },
}

impl Outcome {
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        match *self {
            Outcome::ReachedEnd { steps, .. } | Outcome::Stopped { steps, .. } => steps,
        }
    }
    /// Time of the last state, s.
    pub fn t(&self) -> f64 {
        match *self {
            Outcome::ReachedEnd { t, .. } | Outcome::Stopped { t, .. } => t,
        }
    }
}

/// A fixed-step run of a system.
#[derive(Debug, Clone, Copy)]
pub struct Simulation<'a, S: ?Sized> {
    /// What moves.
    pub system: &'a S,
    /// Start, step size and end.
    pub spec: RunSpec,
}

impl<S: ?Sized> Simulation<'_, S> {
    /// Advances `y` (the initial state on entry, the final state on return) with `stepper`,
    /// showing the initial state and every step to `observer`.
    ///
    /// # Errors
    /// An invalid [`RunSpec`]; [`Error::NonFinite`] at the first non-finite state; the
    /// stepper's own errors.
    pub fn run<St, O>(&self, stepper: &mut St, y: &mut [f64], observer: &mut O) -> Result<Outcome, Error>
    where
        St: Stepper<S> + ?Sized,
        O: Observer + ?Sized,
    {
        self.steps(stepper, y, observer, 0)
    }

    /// Continues a run of which `done` steps are taken: `y` holds the state after them (in
    /// the stepper's coordinates), the stepper what they left it, and the observer has seen
    /// them; with `done` = 0 it is [`Simulation::run`], whose observer first sees the
    /// initial state. After each step but the last it asks `pause` whether to stop there,
    /// and if so returns [`Leg::Paused`] with the step index, time and state (the caller
    /// adds the stepper's state and the counters). Times come from the step index as in a
    /// run that never paused, so a run continued from any step is the same bits.
    ///
    /// # Errors
    /// As [`Simulation::run`]; [`Error::BadCheckpoint`] when `done` is past the last step.
    pub fn run_from<St, O>(
        &self,
        stepper: &mut St,
        y: &mut [f64],
        observer: &mut O,
        done: u64,
        pause: &Pause<'_>,
    ) -> Result<Leg<Outcome>, Error>
    where
        St: Stepper<S> + ?Sized,
        O: Observer + ?Sized,
    {
        // A run that never pauses takes the loop as it is; one that may pause has its
        // observer wrapped, so that the loop itself is the same either way (a check inside
        // it changed how the compiler vectorised the steps, at a cost of 10% measured).
        if pause.never() {
            return self.steps(stepper, y, observer, done).map(Leg::Done);
        }
        let mut pausing = Pausing::new(observer, pause);
        let outcome = self.steps(stepper, y, &mut pausing, done)?;
        Ok(match pausing.paused {
            false => Leg::Done(outcome),
            true => Leg::Paused(RunState::at(outcome.steps(), outcome.t(), y)),
        })
    }

    /// The loop of [`Simulation::run`] and [`Simulation::run_from`].
    pub(crate) fn steps<St, O>(
        &self,
        stepper: &mut St,
        y: &mut [f64],
        observer: &mut O,
        done: u64,
    ) -> Result<Outcome, Error>
    where
        St: Stepper<S> + ?Sized,
        O: Observer + ?Sized,
    {
        let Schedule { steps, last_h, t_end } = self.spec.schedule()?;
        let (t0, h) = (self.spec.t0, self.spec.h);
        if done >= steps && done > 0 {
            return Err(Error::BadCheckpoint {
                part: "the run",
                reason: format!("it is at step {done}, and the run has {steps} steps"),
            });
        }
        if y.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite { t: if done == 0 { t0 } else { t0 + done as f64 * h } });
        }
        if done == 0 {
            let first = Sample::new(0, t0, y, false);
            if let ControlFlow::Break(stop) = observer.observe(&first) {
                stop.into_result()?;
                return Ok(Outcome::Stopped { steps: 0, t: t0 });
            }
        }
        for k in done + 1..=steps {
            let last = k == steps;
            // t from the step index, not by accumulation, so that it does not drift.
            let t = t0 + (k - 1) as f64 * h;
            stepper.step(self.system, t, if last { last_h } else { h }, y)?;
            let t_next = if last { t_end } else { t0 + k as f64 * h };
            if y.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFinite { t: t_next });
            }
            if let ControlFlow::Break(stop) = observer.observe(&Sample::new(k, t_next, y, last)) {
                stop.into_result()?;
                return Ok(Outcome::Stopped { steps: k, t: t_next });
            }
        }
        Ok(Outcome::ReachedEnd { steps, t: t_end })
    }
}

/// What a single run does when the user names nothing: the CLI's `pendula simulate`,
/// Python's `pendula.solve` and the lab's first run read these, so that the same request ends
/// in the same state in every front end (a test runs all three).
pub mod defaults {
    /// The system run when none is named.
    pub const SYSTEM: &str = "double";
    /// The method: the classical fourth-order Runge–Kutta method, the paper's workhorse.
    pub const METHOD: &str = "rk4";
    /// The step size, s: a hundredth of the double pendulum's small-oscillation period
    /// (about 1.5 s) is far inside RK4's stable range and keeps its energy error near 1e-9
    /// of the energy scale over 10 s.
    pub const DT: f64 = 1e-3;
    /// The end time, s (the run starts at 0).
    pub const T_END: f64 = 10.0;
    /// The relative tolerance of adaptive methods (dopri5, dop853).
    pub const RTOL: f64 = 1e-6;
    /// The absolute tolerance of adaptive methods.
    pub const ATOL: f64 = 1e-6;
}

/// What [`solve`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// How the run ended.
    pub outcome: Outcome,
    /// Right-hand-side evaluations: calls of f, or pairs of ∂H/∂q and ∂H/∂p evaluations.
    pub rhs_evals: u64,
    /// Final state, in the model's (position, velocity) coordinates.
    pub state: Vec<f64>,
    /// Steps rejected by the step-size controller (0 for fixed steps).
    pub steps_rejected: u64,
    /// Jacobian evaluations (implicit methods' Newton iterations), each costing a few
    /// evaluations of f.
    pub jacobian_evals: u64,
}

/// Runs `method` on `model` from `y0` (positions, velocities), stepping as `stepping` says
/// (fixed steps: `&RunSpec`; adaptive steps with tolerances: `&Stepping::Adaptive { .. }`), showing every state to `observer` in the same coordinates: the
/// library's one entry for a single run ([`solve_adaptive`] and
/// [`crate::solve_resumable`] are its shorthand and its resumable form).
///
/// Methods that need a Hamiltonian form run on (q, p): the state is converted before the
/// run, and back for every observed state and at the end. Whether the method applies is
/// answered by [`check`] before any step is taken.
///
/// # Errors
/// [`Error::UnmetRequirement`] when the model lacks what the method needs (see [`check`]) or
/// the stepping does not fit the method (adaptive steps need an error estimate), and
/// everything [`Simulation::run`] reports.
pub fn solve<'a, M: Model, S: Into<Stepping<'a>> + Copy>(
    model: &M,
    method: &Method,
    y0: &[f64],
    stepping: &S,
    observer: &mut dyn Observer,
) -> Result<Report, Error> {
    match crate::simulate::resume::solve_resumable(
        model,
        method,
        y0,
        &(*stepping).into(),
        observer,
        None,
        &Pause::NEVER,
    )? {
        Leg::Done(report) => Ok(report),
        Leg::Paused(state) => unreachable!("a run that never pauses paused at step {}", state.steps),
    }
}

/// Whether `method` applies to `model`, answered before any step is taken: the structure its
/// [`Requirement`] names — a Hamiltonian form (the model's [`Model::hamiltonian_form`]), and
/// for explicit splittings a separable one. Runs ([`solve`]) and ensembles check with it;
/// callers ask it to choose, never compare names.
///
/// # Errors
/// [`Error::UnmetRequirement`]: what the method needs, why the model lacks it, and methods
/// that apply.
pub fn check<M: Model>(method: &Method, model: &M) -> Result<(), Error> {
    let unmet = |reason| Error::UnmetRequirement {
        method: method.name,
        needs: method.requirement.describe(),
        reason,
        suggestion: alternatives(method, model),
    };
    meets(method.requirement, model).map_err(unmet)
}

/// Whether `model` has the structure `requirement` names; else why not, in words.
fn meets<M: Model>(requirement: Requirement, model: &M) -> Result<(), String> {
    match requirement {
        Requirement::Any => Ok(()),
        Requirement::Hamiltonian | Requirement::HamiltonianExplicit => model.hamiltonian_form().map(|_| ()),
        Requirement::Separable => {
            if model.hamiltonian_form()?.separable() {
                Ok(())
            } else {
                Err(format!(
                    "the `{}` system's Hamiltonian is not separable (its kinetic energy depends on the positions)",
                    M::INFO.name
                ))
            }
        }
    }
}

/// The methods to try instead of `method` on `model`: only those that apply to it, as it is
/// set (a damped pendulum has no Hamiltonian, so no method is symplectic there); for a
/// symplectic method on a system with a Hamiltonian, the symplectic ones that apply. First-order
/// methods are offered only when nothing better applies.
fn alternatives<M: Model>(method: &Method, model: &M) -> String {
    let all: Vec<&Method> = crate::integrator::METHODS
        .iter()
        .copied()
        .filter(|m| m.name != method.name && meets(m.requirement, model).is_ok())
        .collect();
    let better: Vec<&Method> = all.iter().copied().filter(|m| m.order >= 2).collect();
    let mut applies = if better.is_empty() { all } else { better };
    // The workhorses first: fourth order (rk4, gauss-legendre-4, tao-4), then by distance
    // from it, in the registry's order otherwise.
    applies.sort_by_key(|m| m.order.abs_diff(4));
    let names = |ms: &[&Method]| ms.iter().map(|m| m.name).collect::<Vec<_>>().join(", ");
    let symplectic: Vec<&Method> = applies.iter().copied().filter(|m| m.symplectic).collect();
    if method.symplectic && model.hamiltonian_form().is_ok() && !symplectic.is_empty() {
        format!("{} (they apply here and stay symplectic)", names(&symplectic))
    } else if applies.is_empty() {
        "no method applies to this system".to_owned()
    } else {
        format!("{} (the methods that apply to this system as set)", names(&applies))
    }
}

impl From<RunSpec> for Stepping<'_> {
    fn from(spec: RunSpec) -> Self {
        Stepping::Fixed(spec)
    }
}

/// How a run steps: fixed steps as a [`RunSpec`] says, or adaptive steps of an embedded pair
/// from t = 0 to `t_end` (see [`solve_adaptive`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stepping<'a> {
    /// Fixed steps.
    Fixed(RunSpec),
    /// Adaptive steps.
    Adaptive {
        /// End time, s.
        t_end: f64,
        /// The first step to try, s; `None` picks one from the problem.
        h0: Option<f64>,
        /// Tolerances and step bounds.
        tol: &'a Tolerances,
    },
}

/// What to do with the stepper a method's family builds: run it on the model's own
/// (position, velocity) ODE, or on its Hamiltonian form ([`dispatch`], the one match on the
/// family, hands it over).
pub(crate) trait Drive<M: Model> {
    /// What the run gives back.
    type Output;
    /// Runs `stepper` on the model's own ODE.
    fn direct(
        self,
        model: &M,
        stepper: &mut (impl for<'a> Stepper<Counted<'a, M>> + Snapshot),
    ) -> Result<Self::Output, Error>;
    /// Runs `stepper` on the Hamiltonian form `form`, showing states as (q, q').
    fn on_form(
        self,
        model: &M,
        form: &M::Form,
        stepper: &mut (impl for<'a> Stepper<Counted<'a, M::Form>> + Snapshot),
    ) -> Result<Self::Output, Error>;
}

/// Builds `method`'s stepper for `model` (fixed step `h`) and hands it to `drive`.
///
/// # Errors
/// [`Error::UnmetRequirement`] when the model lacks what the method needs, Tao's maps above
/// their stable step, and the drive's errors.
pub(crate) fn dispatch<M: Model, D: Drive<M>>(
    model: &M,
    method: &Method,
    h: f64,
    drive: D,
) -> Result<D::Output, Error> {
    check(method, model)?;
    let dim = model.dim();
    // Checked: the forms the methods below need exist.
    let form = || model.hamiltonian_form().expect("checked: the model has a Hamiltonian form");
    match method.scheme {
        Scheme::ExplicitRk(tableau) => drive.direct(model, &mut ExplicitRk::new(tableau, dim)),
        Scheme::Embedded(tableau) => drive.direct(model, &mut EmbeddedRk::new(tableau, dim)),
        Scheme::Collocation(tableau) => match model.hamiltonian_form() {
            // On (q, p), where the method is symplectic.
            Ok(form) => drive.on_form(model, &form, &mut Collocation::new(tableau, dim)),
            // Damped or otherwise not Hamiltonian: still an order-2s method on the ODE.
            Err(_) => drive.direct(model, &mut Collocation::new(tableau, dim)),
        },
        Scheme::Tao(scheme) => {
            crate::integrator::tao::check_binding_step(&scheme, h)?;
            drive.on_form(model, &form(), &mut TaoStepper::new(scheme, dim / 2))
        }
        Scheme::Partitioned(partition) => {
            drive.on_form(model, &form(), &mut PartitionedStepper::new(partition, dim / 2))
        }
    }
}

/// Shows (q, p) states to an observer as (q, q').
pub(crate) struct ToVelocities<'a, M> {
    pub(crate) model: &'a M,
    pub(crate) y: Vec<f64>,
    pub(crate) inner: &'a mut dyn Observer,
}

impl<M: Model> Observer for ToVelocities<'_, M> {
    fn observe(&mut self, sample: &Sample<'_>) -> crate::observe::Flow {
        self.model.to_velocities(sample.y, &mut self.y);
        self.inner.observe(&Sample { y: &self.y, dense: None, energy: None, ..*sample })
    }
}

/// Counts a system's evaluations.
pub(crate) struct Counted<'a, S: ?Sized> {
    inner: &'a S,
    rhs: Cell<u64>,
    halves: Cell<u64>,
    pub(crate) jacobians: Cell<u64>,
}

impl<'a, S: ?Sized> Counted<'a, S> {
    pub(crate) fn new(inner: &'a S) -> Self {
        Counted { inner, rhs: Cell::new(0), halves: Cell::new(0), jacobians: Cell::new(0) }
    }

    pub(crate) fn evaluations(&self) -> u64 {
        self.rhs.get() + self.halves.get().div_ceil(2)
    }

    /// The counters (f, half-evaluations, Jacobians), for a [`RunState`].
    pub(crate) fn counts(&self) -> [u64; 3] {
        [self.rhs.get(), self.halves.get(), self.jacobians.get()]
    }

    /// Sets the counters to those of a [`RunState`].
    pub(crate) fn set_counts(&self, [rhs, halves, jacobians]: [u64; 3]) {
        self.rhs.set(rhs);
        self.halves.set(halves);
        self.jacobians.set(jacobians);
    }
}

impl<S: System + ?Sized> System for Counted<'_, S> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.rhs.set(self.rhs.get() + 1);
        self.inner.rhs(t, y, dydt);
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        let available = self.inner.jacobian(t, y, jac);
        self.jacobians.set(self.jacobians.get() + u64::from(available));
        available
    }
}

impl<S: Hamiltonian + ?Sized> Hamiltonian for Counted<'_, S> {
    fn dh_dq(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        self.halves.set(self.halves.get() + 1);
        self.inner.dh_dq(t, q, p, out);
    }
    fn dh_dp(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]) {
        self.halves.set(self.halves.get() + 1);
        self.inner.dh_dp(t, q, p, out);
    }
    fn separable(&self) -> bool {
        self.inner.separable()
    }
}
