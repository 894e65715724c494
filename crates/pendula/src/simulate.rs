//! The run loop: a [`Simulation`] drives a stepper over a system and shows every state to
//! an observer; [`solve`] does the same for a catalogued [`Model`] and a [`Method`] chosen
//! at run time.

use std::cell::Cell;

use crate::Error;
use crate::control::{PiController, Tolerances, Verdict};
use crate::integrator::embedded::EmbeddedRk;
use crate::integrator::explicit_rk::ExplicitRk;
use crate::integrator::gauss_legendre::Collocation;
use crate::integrator::partitioned::PartitionedStepper;
use crate::integrator::tao::TaoStepper;
use crate::integrator::{Method, Requirement, Scheme, Stepper};
use crate::observe::{Observer, Sample};
use crate::system::{Hamiltonian, Model, System};

/// More steps than this is surely a mistake (10¹³ steps take days).
const MAX_STEPS: f64 = 1e13;

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
    /// Step size h, s.
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
        if !(h.is_finite() && h > 0.0) {
            return Err(invalid("dt", h, "the step size must be finite and > 0"));
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
                if !(t_end.is_finite() && span > 0.0) {
                    return Err(invalid("t-end", t_end, "the end time must be finite and > 0"));
                }
                let ratio = span / h;
                if ratio > MAX_STEPS {
                    return Err(invalid("dt", h, "the step size gives more than 10^13 steps"));
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
        let Schedule { steps, last_h, t_end } = self.spec.schedule()?;
        let (t0, h) = (self.spec.t0, self.spec.h);
        if y.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite { t: t0 });
        }
        let first = Sample::new(0, t0, y, false);
        if observer.observe(&first).is_break() {
            return Ok(Outcome::Stopped { steps: 0, t: t0 });
        }
        for k in 1..=steps {
            let last = k == steps;
            // t from the step index, not by accumulation, so that it does not drift.
            let t = t0 + (k - 1) as f64 * h;
            stepper.step(self.system, t, if last { last_h } else { h }, y)?;
            let t_next = if last { t_end } else { t0 + k as f64 * h };
            if y.iter().any(|v| !v.is_finite()) {
                return Err(Error::NonFinite { t: t_next });
            }
            if observer.observe(&Sample::new(k, t_next, y, last)).is_break() {
                return Ok(Outcome::Stopped { steps: k, t: t_next });
            }
        }
        Ok(Outcome::ReachedEnd { steps, t: t_end })
    }
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

/// Runs `method` on `model` from `y0` (positions, velocities), showing every state to
/// `observer` in the same coordinates.
///
/// Methods that need a Hamiltonian form run on (q, p): the state is converted before the
/// run, and back for every observed state and at the end.
///
/// # Errors
/// [`Error::UnmetRequirement`] when the model lacks what the method needs, and everything
/// [`Simulation::run`] reports.
pub fn solve<M: Model>(
    model: &M,
    method: &Method,
    y0: &[f64],
    spec: &RunSpec,
    observer: &mut dyn Observer,
) -> Result<Report, Error> {
    let dim = model.dim();
    assert_eq!(y0.len(), dim, "initial state of the wrong length");
    match method.scheme {
        Scheme::ExplicitRk(tableau) => {
            run_direct(model, &mut ExplicitRk::new(tableau, dim), y0, spec, observer)
        }
        Scheme::Embedded(tableau) => {
            run_direct(model, &mut EmbeddedRk::new(tableau, dim), y0, spec, observer)
        }
        Scheme::Collocation(tableau) => match model.hamiltonian_form() {
            // On (q, p), where the method is symplectic.
            Ok(form) => run_on_form(model, &form, &mut Collocation::new(tableau, dim), y0, spec, observer),
            // Damped or otherwise not Hamiltonian: still an order-2s method on the ODE.
            Err(_) => run_direct(model, &mut Collocation::new(tableau, dim), y0, spec, observer),
        },
        Scheme::Tao(scheme) => {
            let form = model.hamiltonian_form().map_err(|reason| Error::UnmetRequirement {
                method: method.name,
                needs: method.requirement.describe(),
                reason,
                suggestion: method.requirement.suggestion(),
            })?;
            crate::integrator::tao::check_binding_step(&scheme, spec.h)?;
            run_on_form(model, &form, &mut TaoStepper::new(scheme, dim / 2), y0, spec, observer)
        }
        Scheme::Partitioned(partition) => {
            let unmet = |reason| Error::UnmetRequirement {
                method: method.name,
                needs: method.requirement.describe(),
                reason,
                suggestion: method.requirement.suggestion(),
            };
            let form = model.hamiltonian_form().map_err(unmet)?;
            if method.requirement == Requirement::Separable && !form.separable() {
                return Err(unmet(format!(
                    "the `{}` system's Hamiltonian is not separable (its kinetic energy depends on the positions)",
                    M::INFO.name
                )));
            }
            run_on_form(model, &form, &mut PartitionedStepper::new(partition, dim / 2), y0, spec, observer)
        }
    }
}

/// Runs a stepper on the model's own (position, velocity) ODE.
fn run_direct<M: Model>(
    model: &M,
    stepper: &mut impl for<'a> Stepper<Counted<'a, M>>,
    y0: &[f64],
    spec: &RunSpec,
    observer: &mut dyn Observer,
) -> Result<Report, Error> {
    let system = Counted::new(model);
    let mut y = y0.to_vec();
    let outcome = Simulation { system: &system, spec: *spec }.run(stepper, &mut y, observer)?;
    Ok(Report {
        outcome,
        rhs_evals: system.evaluations(),
        state: y,
        steps_rejected: 0,
        jacobian_evals: system.jacobians.get(),
    })
}

/// Runs an embedded pair with adaptive steps from t = 0 to `t_end` (landing on it exactly),
/// showing the initial state and every accepted step to `observer`. `h0` is the first step
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
    let Scheme::Embedded(tableau) = method.scheme else {
        return Err(Error::UnmetRequirement {
            method: method.name,
            needs: "fixed steps (--dt)",
            reason: "tolerances apply to methods with an error estimate".into(),
            suggestion: "dopri5 or dop853 for adaptive steps",
        });
    };
    tol.validate()?;
    if !(t_end.is_finite() && t_end > 0.0) {
        return Err(Error::InvalidValue {
            name: "t-end".into(),
            value: t_end,
            allowed: "the end time must be finite and > 0",
        });
    }
    let system = Counted::new(model);
    let mut y = y0.to_vec();
    if y.iter().any(|v| !v.is_finite()) {
        return Err(Error::NonFinite { t: 0.0 });
    }
    let mut stepper = EmbeddedRk::new(tableau, y.len());
    let mut control = PiController::new(tableau.control);
    let dense = observer.wants_dense();
    let (mut accepted, mut rejected) = (0u64, 0u64);
    if observer.observe(&Sample::new(0, 0.0, &y, false)).is_break() {
        return Ok(Report {
            outcome: Outcome::Stopped { steps: 0, t: 0.0 },
            rhs_evals: 0,
            state: y,
            steps_rejected: 0,
            jacobian_evals: system.jacobians.get(),
        });
    }
    let mut t = 0.0;
    let mut h = h0.unwrap_or_else(|| initial_step(&system, &y, method.order, tol)).min(tol.h_max).min(t_end);
    let mut just_rejected = false;
    loop {
        // Land on t_end exactly; stretch a last step that would leave a sliver.
        let last = t + 1.01 * h >= t_end;
        if last {
            h = t_end - t;
        }
        // Never below what the end time can resolve: a smaller step would need more than
        // 1/(16 ε) ≈ 3·10¹⁴ steps to get there, and at t = 0 a floor of 16 ε |t| alone is 0,
        // which let a rejected step shrink to 0 and the run stall for ever.
        let floor = tol.h_min.max(16.0 * f64::EPSILON * t.abs().max(t_end));
        if h < floor && !last {
            return Err(Error::StepSizeTooSmall { t, h });
        }
        stepper.attempt(&system, t, h, &y);
        let err = stepper.error_norm(&y, tol.rtol, tol.atol);
        match control.judge(h, err) {
            Verdict::Accept(next) => {
                let t_new = if last { t_end } else { t + h };
                stepper.accept(&system, t, h, t_new, &mut y, dense);
                accepted += 1;
                t = t_new;
                if y.iter().any(|v| !v.is_finite()) {
                    return Err(Error::NonFinite { t });
                }
                let sample = Sample { dense: stepper.dense_output(), ..Sample::new(accepted, t, &y, last) };
                if observer.observe(&sample).is_break() {
                    let outcome = Outcome::Stopped { steps: accepted, t };
                    return Ok(Report {
                        outcome,
                        rhs_evals: system.evaluations(),
                        state: y,
                        steps_rejected: rejected,
                        jacobian_evals: system.jacobians.get(),
                    });
                }
                if last {
                    break;
                }
                // After a rejection, do not grow the step at once (as DOPRI5 does).
                h = if just_rejected { next.min(h) } else { next }.min(tol.h_max);
                just_rejected = false;
            }
            Verdict::Reject(next) => {
                rejected += 1;
                just_rejected = true;
                if next < floor {
                    return Err(Error::StepSizeTooSmall { t, h: next });
                }
                h = next;
            }
        }
    }
    let outcome = Outcome::ReachedEnd { steps: accepted, t: t_end };
    Ok(Report {
        outcome,
        rhs_evals: system.evaluations(),
        state: y,
        steps_rejected: rejected,
        jacobian_evals: 0,
    })
}

/// A first step from the sizes of y₀, f(0, y₀) and an estimate of f', as Hairer's DOPRI5 and
/// DOP853 codes choose it (`HINIT`; Hairer, Nørsett, Wanner §II.4, "Starting step size"):
/// h₀ = 0.01 ‖y₀‖/‖f₀‖, one Euler step to estimate ‖f'‖, then h₁ = (0.01 / max(‖f₀‖,
/// ‖f'‖))^(1/p) with p the method's order, and the smaller of 100 h₀ and h₁. Norms are
/// weighted sums of squares (not means), as in the codes.
fn initial_step<S: System + ?Sized>(system: &S, y0: &[f64], order: u32, tol: &Tolerances) -> f64 {
    let n = y0.len();
    let scale: Vec<f64> = y0.iter().map(|v| tol.atol + tol.rtol * v.abs()).collect();
    let norm2 = |v: &[f64]| v.iter().zip(&scale).map(|(a, s)| (a / s) * (a / s)).sum::<f64>();
    let mut f0 = vec![0.0; n];
    system.rhs(0.0, y0, &mut f0);
    let (dny, dnf) = (norm2(y0), norm2(&f0));
    let h0 = if dnf <= 1e-10 || dny <= 1e-10 { 1e-6 } else { 0.01 * (dny / dnf).sqrt() }.min(tol.h_max);
    let y1: Vec<f64> = y0.iter().zip(&f0).map(|(y, f)| y + h0 * f).collect();
    let mut f1 = vec![0.0; n];
    system.rhs(h0, &y1, &mut f1);
    let diff: Vec<f64> = f1.iter().zip(&f0).map(|(a, b)| a - b).collect();
    let der2 = norm2(&diff).sqrt() / h0;
    let der12 = der2.max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { (0.01 / der12).powf(1.0 / order as f64) };
    (100.0 * h0).min(h1)
}

/// Runs a stepper on the Hamiltonian form, converting to (q, p) before and back after, and
/// for every state the observer sees.
fn run_on_form<M: Model>(
    model: &M,
    form: &M::Form,
    stepper: &mut impl for<'a> Stepper<Counted<'a, M::Form>>,
    y0: &[f64],
    spec: &RunSpec,
    observer: &mut dyn Observer,
) -> Result<Report, Error> {
    let dim = y0.len();
    let system = Counted::new(form);
    let mut z = vec![0.0; dim];
    model.to_momenta(y0, &mut z);
    let mut shown = ToVelocities { model, y: vec![0.0; dim], inner: observer };
    let outcome = Simulation { system: &system, spec: *spec }.run(stepper, &mut z, &mut shown)?;
    let mut y = vec![0.0; dim];
    model.to_velocities(&z, &mut y);
    Ok(Report {
        outcome,
        rhs_evals: system.evaluations(),
        state: y,
        steps_rejected: 0,
        jacobian_evals: system.jacobians.get(),
    })
}

/// Shows (q, p) states to an observer as (q, q').
struct ToVelocities<'a, M> {
    model: &'a M,
    y: Vec<f64>,
    inner: &'a mut dyn Observer,
}

impl<M: Model> Observer for ToVelocities<'_, M> {
    fn observe(&mut self, sample: &Sample<'_>) -> std::ops::ControlFlow<()> {
        self.model.to_velocities(sample.y, &mut self.y);
        self.inner.observe(&Sample { y: &self.y, dense: None, energy: None, ..*sample })
    }
}

/// Counts a system's evaluations.
struct Counted<'a, S: ?Sized> {
    inner: &'a S,
    rhs: Cell<u64>,
    halves: Cell<u64>,
    jacobians: Cell<u64>,
}

impl<'a, S: ?Sized> Counted<'a, S> {
    fn new(inner: &'a S) -> Self {
        Counted { inner, rhs: Cell::new(0), halves: Cell::new(0), jacobians: Cell::new(0) }
    }

    fn evaluations(&self) -> u64 {
        self.rhs.get() + self.halves.get().div_ceil(2)
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
