//! The catalogue: every system pendula knows, chosen by name at run time, and [`DynModel`],
//! the object-safe face through which the command line builds and runs one.
//!
//! This is the top of the library's layers: a system (`crate::system`) knows its equations
//! and nothing of the methods that integrate it; the run loop (`crate::simulate`) and the
//! ensemble engine (`crate::ensemble`) are generic over [`Model`]; here the two meet, for
//! each catalogued system once.
//!
//! # The catalogue
//!
//! `CATALOGUE`, `DynModel`: every system, one `Entry` each (its `SystemInfo`: name, parameters and
//! state with units, defaults and domains; whether it is dimensionless; its energy scale in words;
//! the horizon of accuracy studies in periods; an entry may be a family, `SystemInfo::variant`: the
//! chain's `links` picks the member entry), how to build it, and its systems-test-kit check;
//! `DynModel` is a built system's object-safe face with its runs (`check`, `solve`,
//! `solve_adaptive`, `solve_resumable`, `solve_fastest`, `ensemble`, `solve_lane`); `ensemble_path`
//! and `lane_method` decide the engine before any step.

use std::ops::Deref;

use crate::Error;
use crate::checkpoint::{Leg, Pause, RunState};
use crate::control::Tolerances;
use crate::ensemble::engine::{self, LaneMethod, LaneSpec, Members, Rows, StoreLane};
use crate::integrator::{Method, Scheme};
use crate::observe::Observer;
use crate::simulate::{Report, RunSpec, Stepping};
use crate::system::{DynSystem, Model, SystemInfo, Values, chain, double, driven, oscillator, pendulum};

/// Every system pendula knows, in the order `pendula list systems` shows them. A new system
/// is enrolled by one line here (its entry, [`Entry::of`]); the tests that loop over the
/// catalogue then check it.
pub static CATALOGUE: &[Entry] = &[
    Entry::of::<oscillator::Oscillator>(),
    Entry::of::<pendulum::Pendulum>(),
    Entry::of::<double::DoublePendulum>(),
    Entry::of::<chain::Chain>(),
    Entry::of::<driven::DrivenPendulum>(),
];

/// A catalogued system: its description ([`SystemInfo`], which the entry derefs to) and how
/// to build it from validated values.
pub struct Entry {
    info: &'static SystemInfo,
    build: fn(&Values) -> Box<dyn DynModel>,
    check: fn(&Values) -> Vec<String>,
}

impl Entry {
    /// The entry of the system `M`.
    pub const fn of<M: Model>() -> Entry {
        Entry { info: M::INFO, build: build::<M>, check: crate::kit::check_values::<M> }
    }

    /// The system's description.
    pub fn info(&self) -> &'static SystemInfo {
        self.info
    }

    /// The systems test kit's failures for this system with `values` (see [`crate::kit`]):
    /// empty when it passes.
    pub fn check(&self, values: &Values) -> Vec<String> {
        (self.check)(values)
    }
}

impl Deref for Entry {
    type Target = SystemInfo;
    fn deref(&self) -> &SystemInfo {
        self.info
    }
}

impl std::fmt::Debug for Entry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Entry").field("name", &self.info.name).finish_non_exhaustive()
    }
}

fn build<M: Model>(values: &Values) -> Box<dyn DynModel> {
    Box::new(M::from_values(values))
}

/// Looks a system up by name.
///
/// # Errors
/// [`Error::UnknownSystem`], with the valid names and the closest ones.
pub fn find(name: &str) -> Result<&'static SystemInfo, Error> {
    CATALOGUE.iter().find(|s| s.name == name).map(Entry::info).ok_or_else(|| Error::UnknownSystem {
        name: name.to_owned(),
        valid: CATALOGUE.iter().map(|s| s.name).collect::<Vec<_>>().join(", "),
        suggestions: crate::error::suggestions(name, CATALOGUE.iter().map(|s| s.name)),
    })
}

impl Values {
    /// Builds the system.
    pub fn build(&self) -> Box<dyn DynModel> {
        let name = self.info().name;
        let entry = CATALOGUE.iter().find(|e| e.name == name);
        (entry.unwrap_or_else(|| panic!("{name} is not in the catalogue")).build)(self)
    }

    /// Checks that the initial state's energy and the system's energy scale are finite: each
    /// value may lie in its domain while together they overflow (`omega1 = 1e300` squares to
    /// infinity), and a study that measures energy errors against an infinite scale, or a run
    /// started at an infinite energy, measures nothing.
    ///
    /// # Errors
    /// [`Error::InvalidValue`] naming the initial energy (or the energy scale) and its value.
    pub fn check_energy(&self) -> Result<(), Error> {
        let model = self.build();
        let state = self.initial_state();
        let energy = model.energy(0.0, state);
        let scale = model.energy_scale(state);
        let (name, value) =
            if !energy.is_finite() { ("initial energy", energy) } else { ("energy scale", scale) };
        if value.is_finite() {
            return Ok(());
        }
        Err(Error::InvalidValue {
            name: name.into(),
            value,
            allowed: "must be finite: a velocity, angle or parameter so large that the energy overflows (make it smaller)",
        })
    }
}

/// How the ensemble engine runs `method` on `model`'s system, or `None` when it does not
/// ([`crate::ensemble::engine::supports`]): explicit Runge–Kutta methods of at most four
/// stages on every catalogued system, damped and driven variants included; the explicit
/// partitioned methods (symplectic Euler, Störmer–Verlet, the Yoshida compositions) on
/// separable systems, kick–drift; Tao's maps on the non-separable Hamiltonian systems (the
/// double pendulum undamped, the chain while its state fits). Answered before any step is
/// taken, from the system's structure: the callers choose the engine by this, never by names.
/// (A member of an ensemble that lacks what the method needs — a damped one, when damping is
/// swept — is refused by the engine, naming it, as a scalar run refuses it.)
pub fn lane_method(method: &'static Method, model: &dyn DynModel) -> Option<LaneMethod> {
    let lanes = LaneMethod::of(method)?;
    let fits = match lanes {
        LaneMethod::Rk(_) => true,
        LaneMethod::KickDrift { .. } => model.separable(),
        LaneMethod::Tao { .. } => model.check(method).is_ok() && !model.separable(),
    };
    if !fits {
        return None;
    }
    engine::supports(model.info(), &lanes).then_some(lanes)
}

/// Which engine an ensemble runs on, decided by the library before any step (callers never
/// compare names).
#[derive(Debug, Clone, Copy)]
pub enum EnsemblePath {
    /// The engine ([`DynModel::ensemble`]) with this method: every system with an
    /// explicit tableau, forces included; separable systems with kick–drift.
    Engine(LaneMethod),
    /// No lanes for this method: one scalar run per member.
    Scalar,
}

/// The engine for an ensemble of `method` runs of the system of `base` (its members differ
/// from it in some quantities; one that lacks what the method needs — damped, with
/// kick–drift or Tao's map — is refused by the engine, naming it, as a scalar run refuses
/// it).
pub fn ensemble_path(method: &'static Method, base: &Values) -> EnsemblePath {
    match lane_method(method, &*base.build()) {
        Some(lanes) => EnsemblePath::Engine(lanes),
        None => EnsemblePath::Scalar,
    }
}

/// The methods of `methods` (in their order) that apply to `model` and are stable at every
/// step up to `max_h` (Tao's maps only where ω h ≤ 1, [`Method::max_step`]); `None` for
/// `max_h` keeps every step limit. What a study runs when no method is named.
pub fn applicable(
    model: &dyn DynModel,
    methods: &[&'static Method],
    max_h: Option<f64>,
) -> Vec<&'static Method> {
    let within = |m: &Method| match (m.max_step(), max_h) {
        (Some(limit), Some(h)) => h <= limit,
        _ => true,
    };
    methods.iter().copied().filter(|m| model.check(m).is_ok() && within(m)).collect()
}

/// The method `auto` picks for `model`, and why: a symplectic explicit method where the
/// system has a Hamiltonian form — yoshida-4 when it is separable, tao-4 otherwise (a
/// bounded energy error on long runs) — else the adaptive dop853 (damped or driven).
pub fn auto_method(model: &dyn DynModel) -> (&'static Method, &'static str) {
    use crate::integrator::{composition::YOSHIDA_4, embedded::DOP853, partitioned::VERLET, tao::TAO_4};
    if model.separable() {
        (&YOSHIDA_4, "separable Hamiltonian: explicit symplectic, order 4")
    } else if model.check(&VERLET).is_ok() {
        (&TAO_4, "non-separable Hamiltonian: explicit symplectic (Tao), order 4")
    } else {
        (&DOP853, "not Hamiltonian (damped): adaptive, order 8")
    }
}

/// The methods named, in order: each a known method ([`crate::integrator::find`]) that
/// applies to `model`, each named once.
///
/// # Errors
/// The first unknown name ([`Error::UnknownMethod`], with a did-you-mean), the first method
/// the system cannot run ([`Error::UnmetRequirement`]), or [`Error::InvalidInput`] for
/// `methods` when none is named or one is named twice.
pub fn named_methods<'a>(
    model: &dyn DynModel,
    names: impl IntoIterator<Item = &'a str>,
) -> Result<Vec<&'static Method>, Error> {
    let names: Vec<&str> = names.into_iter().map(str::trim).collect();
    let invalid = |allowed: String| Error::InvalidInput {
        name: "methods".into(),
        value: crate::error::clip(&names.join(","), 80),
        allowed,
    };
    if names.is_empty() {
        return Err(invalid("name at least one method".into()));
    }
    let mut methods: Vec<&'static Method> = Vec::with_capacity(names.len());
    for name in &names {
        let method = crate::integrator::find(name)?;
        model.check(method)?;
        if methods.iter().any(|m| m.name == method.name) {
            return Err(invalid(format!("{} is listed twice; list each method once", method.name)));
        }
        methods.push(method);
    }
    Ok(methods)
}

/// A catalogued system chosen at run time: its physics ([`DynSystem`]) and its runs.
pub trait DynModel: DynSystem {
    /// Whether `method` applies to this system: [`crate::simulate::check`], before any step.
    ///
    /// # Errors
    /// As [`crate::simulate::check`].
    fn check(&self, method: &Method) -> Result<(), Error>;
    /// Runs `members` of this system (of its entry, for the chain with its links) on the
    /// ensemble engine into `rows`: see [`crate::ensemble::engine::run`].
    ///
    /// # Errors
    /// As [`crate::ensemble::engine::run`].
    fn ensemble(
        &self,
        members: &Members<'_>,
        spec: &LaneSpec,
        rows: Rows<'_, f64, StoreLane<'_, f64>>,
    ) -> Result<(), Error>;
    /// Samples `members` of this system once per drive period on the ensemble engine: see
    /// [`crate::ensemble::engine::stroboscopic`].
    ///
    /// # Errors
    /// As [`crate::ensemble::engine::stroboscopic`].
    fn stroboscopic(
        &self,
        members: &Members<'_>,
        strobe: &engine::Strobe<'_>,
        out: &mut [f64],
    ) -> Result<(), Error>;
    /// Runs this system alone in the engine arithmetic (see
    /// [`crate::ensemble::engine::solve_one`]): bit for bit what a lane of
    /// [`DynModel::ensemble`] gives it.
    ///
    /// # Errors
    /// As [`crate::ensemble::engine::solve_one`].
    fn solve_lane(
        &self,
        method: LaneMethod,
        y0: &[f64],
        spec: &RunSpec,
        observer: &mut dyn Observer,
    ) -> Result<Report, Error>;
    /// Whether this system has a separable Hamiltonian form (the explicit partitioned
    /// methods' requirement; none when damped).
    fn separable(&self) -> bool;
    /// Runs `method` from `y0` as `spec` says, showing every step to `observer`
    /// (see [`crate::simulate::solve`]).
    ///
    /// # Errors
    /// As [`crate::simulate::solve`].
    fn solve(
        &self,
        method: &Method,
        y0: &[f64],
        spec: &RunSpec,
        observer: &mut dyn Observer,
    ) -> Result<Report, Error>;
    /// Runs an embedded pair with adaptive steps to `t_end` (see
    /// [`crate::simulate::solve_adaptive`]).
    ///
    /// # Errors
    /// As [`crate::simulate::solve_adaptive`].
    fn solve_adaptive(
        &self,
        method: &Method,
        y0: &[f64],
        t_end: f64,
        h0: Option<f64>,
        tol: &Tolerances,
        observer: &mut dyn Observer,
    ) -> Result<Report, Error>;
    /// [`DynModel::solve_adaptive`] from `t0`, forward or backward in time (see
    /// [`crate::simulate::adaptive::solve_adaptive_from`]).
    ///
    /// # Errors
    /// As [`crate::simulate::adaptive::solve_adaptive_from`].
    #[allow(clippy::too_many_arguments)] // solve_adaptive's arguments and the start time
    fn solve_adaptive_from(
        &self,
        method: &Method,
        y0: &[f64],
        t0: f64,
        t_end: f64,
        h0: Option<f64>,
        tol: &Tolerances,
        observer: &mut dyn Observer,
    ) -> Result<Report, Error>;
    /// Runs `method` from `y0` as `stepping` says, able to pause and to continue from a
    /// paused state (see [`crate::simulate::resume::solve_resumable`]).
    ///
    /// # Errors
    /// As [`crate::simulate::resume::solve_resumable`].
    fn solve_resumable(
        &self,
        method: &Method,
        y0: &[f64],
        stepping: &Stepping<'_>,
        observer: &mut dyn Observer,
        from: Option<&RunState>,
        pause: &Pause<'_>,
    ) -> Result<Leg<Report>, Error>;
    /// [`DynModel::solve_resumable`], on the fastest path the library has for this system and
    /// method: RK4 on the free double pendulum runs the single-trajectory kernel
    /// ([`crate::ensemble::rk4_trajectory_resumable`]); other fixed steps of an explicit
    /// Runge–Kutta tableau the ensemble engine runs on the system take its one lane
    /// ([`crate::ensemble::engine::solve_one_resumable`]: bit for bit a lane of a sweep); both
    /// in the engine's arithmetic, which differs from the reference by rounding. Everything
    /// else runs [`DynModel::solve_resumable`]. The choice depends only on the model, the method and
    /// the stepping, so a run continued from a checkpoint takes the path it was saved on.
    ///
    /// # Errors
    /// As the path taken.
    fn solve_fastest(
        &self,
        method: &Method,
        y0: &[f64],
        stepping: &Stepping<'_>,
        observer: &mut dyn Observer,
        from: Option<&RunState>,
        pause: &Pause<'_>,
    ) -> Result<Leg<Report>, Error>;
}

impl<M: Model> DynModel for M {
    fn check(&self, method: &Method) -> Result<(), Error> {
        crate::simulate::check(method, self)
    }
    fn ensemble(
        &self,
        members: &Members<'_>,
        spec: &LaneSpec,
        rows: Rows<'_, f64, StoreLane<'_, f64>>,
    ) -> Result<(), Error> {
        engine::run::<M, f64>(members, spec, rows)
    }
    fn stroboscopic(
        &self,
        members: &Members<'_>,
        strobe: &engine::Strobe<'_>,
        out: &mut [f64],
    ) -> Result<(), Error> {
        engine::stroboscopic::<M>(members, strobe, out)
    }
    fn solve_lane(
        &self,
        method: LaneMethod,
        y0: &[f64],
        spec: &RunSpec,
        observer: &mut dyn Observer,
    ) -> Result<Report, Error> {
        engine::solve_one(self, method, y0, spec, observer)
    }
    fn separable(&self) -> bool {
        use crate::system::Hamiltonian;
        self.hamiltonian_form().is_ok_and(|form| form.separable())
    }
    fn solve(
        &self,
        method: &Method,
        y0: &[f64],
        spec: &RunSpec,
        observer: &mut dyn Observer,
    ) -> Result<Report, Error> {
        crate::simulate::solve(self, method, y0, spec, observer)
    }
    fn solve_adaptive(
        &self,
        method: &Method,
        y0: &[f64],
        t_end: f64,
        h0: Option<f64>,
        tol: &Tolerances,
        observer: &mut dyn Observer,
    ) -> Result<Report, Error> {
        crate::simulate::solve_adaptive(self, method, y0, t_end, h0, tol, observer)
    }
    fn solve_adaptive_from(
        &self,
        method: &Method,
        y0: &[f64],
        t0: f64,
        t_end: f64,
        h0: Option<f64>,
        tol: &Tolerances,
        observer: &mut dyn Observer,
    ) -> Result<Report, Error> {
        crate::simulate::adaptive::solve_adaptive_from(self, method, y0, t0, t_end, h0, tol, observer)
    }
    fn solve_resumable(
        &self,
        method: &Method,
        y0: &[f64],
        stepping: &Stepping<'_>,
        observer: &mut dyn Observer,
        from: Option<&RunState>,
        pause: &Pause<'_>,
    ) -> Result<Leg<Report>, Error> {
        crate::simulate::resume::solve_resumable(self, method, y0, stepping, observer, from, pause)
    }
    fn solve_fastest(
        &self,
        method: &Method,
        y0: &[f64],
        stepping: &Stepping<'_>,
        observer: &mut dyn Observer,
        from: Option<&RunState>,
        pause: &Pause<'_>,
    ) -> Result<Leg<Report>, Error> {
        // RK4 on the free double pendulum: the single-trajectory kernel, whose energies come
        // from the step's own trigonometry (W1; the engine's one lane measured 3.4 times the C
        // limit kernel there, this kernel 0.5).
        let double = (self as &dyn std::any::Any).downcast_ref::<double::DoublePendulum>();
        if let (Stepping::Fixed(spec), Some(d), Scheme::ExplicitRk(tableau)) =
            (stepping, double, method.scheme)
            && !d.is_forced()
            && matches!(crate::integrator::explicit_rk::RK4.scheme, Scheme::ExplicitRk(rk4) if std::ptr::eq(tableau, rk4))
        {
            return crate::ensemble::rk4_trajectory_resumable(d, y0, spec, observer, from, pause);
        }
        // Fixed steps of any other explicit tableau the engine runs on this system: its one
        // lane, bit for bit a lane of a sweep.
        if let (Stepping::Fixed(spec), Scheme::ExplicitRk(tableau)) = (stepping, method.scheme)
            && engine::supports(Model::info(self), &LaneMethod::Rk(tableau))
        {
            let lanes = LaneMethod::Rk(tableau);
            return engine::solve_one_resumable(self, lanes, y0, spec, observer, from, pause);
        }
        self.solve_resumable(method, y0, stepping, observer, from, pause)
    }
}
