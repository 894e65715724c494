//! Physical systems: the [`System`] trait and its capabilities, and each system (its
//! catalogue entry [`SystemInfo`] and its equations). The list of them is
//! `crate::model::CATALOGUE`, in the layer above.
//!
//! A system is a first-order ODE y' = f(t, y) ([`System`]). What else it offers is a
//! separate small trait: [`Energy`] (its mechanical energy T + V) and [`Hamiltonian`]
//! (its canonical form on (q, p), needed by symplectic methods). [`Model`] ties a catalogued
//! system to its parameters and to its Hamiltonian form, and [`DynSystem`] is its
//! object-safe face for the command line. This layer imports nothing from the integrators,
//! the run loop, the observers or the ensemble engine: they are built on it.
//!
//! # The core types
//!
//! `Equations<T>`: a system's right-hand side over any `Num`, written once; `System::rhs` is its
//! `f64` case, the Jacobian its dual case, the ensemble engine its lanes case.
//!
//! `Model`, `DynSystem`: a catalogued system: built from `Values` (and, over any `Num`, by `over`
//! and `convert`), with its Hamiltonian form and the (q, q') ↔ (q, p) maps; its energy scale
//! (`energy_scale`, what relative energy errors divide by), the power of its non-conservative
//! forces (`power`), its time scale (`time_scale`); `DynSystem` is its physics' object-safe face.
//!
//! # The systems
//!
//! Systems, one file each: `crates/pendula/src/system/oscillator.rs`,
//! `crates/pendula/src/system/pendulum.rs`, `crates/pendula/src/system/double.rs` (free, or with
//! joint friction and a drive torque as generalized forces), `crates/pendula/src/system/chain.rs`
//! (the N-link chain: mass matrix solved by its L D Lᵀ factorisation on the stack, in one matrix
//! with the pairs' sines, one generic code path for f64, num-dual so the Jacobians are exact, and
//! the engine's lanes, whose kernels size its temporaries by their compiled dimension through
//! `Equations::rhs_sized`) and `crates/pendula/src/system/driven.rs` (Baker and Gollub's driven
//! pendulum, and the `PRESETS` registry of named parameter sets with their sources), each with its
//! catalogue entry (`INFO`), its Hamiltonian form, and its exact solution where one exists.
//! `Model::autonomous` and `DynModel::conserves_energy` say whether an energy surface exists
//! (Poincaré sections need one). Special functions (elliptic K, F, Jacobi sn/cn/dn/am) are in
//! `crates/pendula/src/special.rs`.

pub mod chain;
pub mod double;
pub mod driven;
pub mod oscillator;
pub mod pendulum;

use crate::Error;
use crate::num::Num;

/// A first-order ODE system y' = f(t, y).
pub trait System {
    /// Length of the state vector y.
    fn dim(&self) -> usize;
    /// Writes f(t, y) into `dydt`; both slices have length [`System::dim`].
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]);

    /// Writes the Jacobian ∂f/∂y at (t, y) into `jac`, row-major (`jac[i n + j]` = ∂fᵢ/∂yⱼ,
    /// n = [`System::dim`]), and returns true; returns false when the system has none
    /// (the default), and implicit methods then use fixed-point iteration.
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        let _ = (t, y, jac);
        false
    }
}

/// A system's equations of motion over a number type `T` ([`Num`]: `f64`, dual numbers for
/// Jacobians, [`crate::num::Lanes`] for the ensemble engine), written once: the scalar
/// [`System::rhs`] of a catalogued system is its `Equations<f64>::rhs`.
pub trait Equations<T: Num>: Send + Sync {
    /// Writes f(t, y) into `dydt`; both slices have the system's dimension.
    fn rhs(&self, t: T, y: &[T], dydt: &mut [T]);

    /// [`Equations::rhs`] where the state's length `D` is known when compiling (the ensemble
    /// engine compiles a kernel per dimension); for a system whose temporaries grow with its
    /// size (the chain) to size them by `D`. The same arithmetic as `rhs`.
    #[inline(always)]
    fn rhs_sized<const D: usize>(&self, t: T, y: &[T; D], dydt: &mut [T; D])
    where
        Self: Sized,
    {
        self.rhs(t, y, dydt);
    }

    /// A bound on |x| over the arguments x of every sine and cosine [`Equations::rhs`] takes
    /// at (t, y): the lanes' branch-free trigonometry serves |x| ≤ 2²⁰ rad
    /// ([`crate::num::trig::FAST_RANGE`]), and a lane group whose bound goes beyond runs
    /// again with the exact reduction. By default 2 maxᵢ |yᵢ| (angles and their differences);
    /// systems with a drive add its phase.
    fn trig_reach(&self, t: T, y: &[T]) -> T {
        let _ = t;
        reach(y)
    }
}

/// A system's Hamiltonian gradient over a number type `T`, written once: what Tao's map
/// ([`crate::integrator::tao::tao_step`]) evaluates on its two copies, for the scalar stepper,
/// the ensemble engine's lanes and the one-lane reference alike. It is the gradient of the
/// system's Hamiltonian form ([`Model::hamiltonian_form`], which says whether the form exists:
/// a damped system has none, and then nothing calls this), at (t, q, p).
pub trait Canonical<T: Num> {
    /// Writes ∂H/∂q into `dq` and ∂H/∂p into `dp` (each of length n = dim/2) at (t, q, p).
    fn gradient(&self, t: T, q: &[T], p: &[T], dq: &mut [T], dp: &mut [T]);
}

/// 2 maxᵢ |yᵢ|: a bound on every angle of `y` and every difference of two (see
/// [`Equations::trig_reach`]).
#[inline(always)]
pub fn reach<T: Num>(y: &[T]) -> T {
    let mut r = T::splat(0.0);
    for &v in y {
        r = v.abs().max(r);
    }
    r + r
}

/// A system whose mechanical energy T + V can be evaluated, J.
pub trait Energy: System {
    /// Mechanical energy at (t, y), J. Conserved when the system is undamped and undriven.
    fn energy(&self, t: f64, y: &[f64]) -> f64;
}

/// A system in canonical form: y = (q₁…qₙ, p₁…pₙ) and y' = (∂H/∂p, −∂H/∂q).
///
/// Symplectic methods need the two halves of the gradient separately: a "kick" uses
/// ∂H/∂q and a "drift" uses ∂H/∂p. When [`Hamiltonian::separable`] is true
/// (H = T(p) + V(t, q)), ∂H/∂q must not depend on p nor ∂H/∂p on q, and methods use their
/// explicit form.
pub trait Hamiltonian: System {
    /// Writes ∂H/∂q at (t, q, p) into `out` (length n = dim/2).
    fn dh_dq(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]);
    /// Writes ∂H/∂p at (t, q, p) into `out` (length n = dim/2).
    fn dh_dp(&self, t: f64, q: &[f64], p: &[f64], out: &mut [f64]);
    /// True when H = T(p) + V(t, q).
    fn separable(&self) -> bool {
        false
    }
}

/// Hamilton's equations y' = (∂H/∂p, −∂H/∂q), for implementing [`System::rhs`] of a
/// [`Hamiltonian`] form.
pub fn hamilton_rhs<H: Hamiltonian + ?Sized>(h: &H, t: f64, y: &[f64], dydt: &mut [f64]) {
    let n = y.len() / 2;
    let (q, p) = y.split_at(n);
    let (dq, dp) = dydt.split_at_mut(n);
    h.dh_dp(t, q, p, dq);
    h.dh_dq(t, q, p, dp);
    for v in dp.iter_mut() {
        *v = -*v;
    }
}

/// What values a parameter or state variable may take.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Domain {
    /// Finite and > 0 (masses, lengths, g).
    Positive,
    /// Finite and ≥ 0 (damping, frequencies).
    NonNegative,
    /// Any finite value.
    Real,
    /// 0 or 1.
    Flag,
    /// A whole number of links, 1 to [`chain::MAX_LINKS`].
    Links,
}

impl Domain {
    /// The domain in words, for error messages.
    pub fn describe(self) -> &'static str {
        match self {
            Domain::Positive => "must be finite and > 0",
            Domain::NonNegative => "must be finite and >= 0",
            Domain::Real => "must be finite",
            Domain::Flag => "must be 0 or 1",
            Domain::Links => "must be a whole number from 1 to 8",
        }
    }

    /// Whether `v` lies in the domain.
    pub fn contains(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Domain::Positive => v > 0.0,
                Domain::NonNegative => v >= 0.0,
                Domain::Real => true,
                Domain::Flag => v == 0.0 || v == 1.0,
                Domain::Links => v.fract() == 0.0 && (1.0..=chain::MAX_LINKS as f64).contains(&v),
            }
    }
}

/// A named quantity of a system: a parameter or a state variable.
#[derive(Debug, Clone, Copy)]
pub struct Quantity {
    /// Name used on the command line and in scenario files.
    pub name: &'static str,
    /// SI unit (`rad` for angles, which also accept a `deg` suffix on input).
    pub unit: &'static str,
    /// Value used when none is given.
    pub default: f64,
    /// Allowed values.
    pub domain: Domain,
    /// One line of description.
    pub description: &'static str,
}

impl Quantity {
    /// Whether this quantity is an angle (input may carry a `deg` suffix).
    pub fn is_angle(&self) -> bool {
        self.unit == "rad"
    }
}

/// Picks a family's member from (name, value) settings (see [`SystemInfo::variant`]).
pub type Variant = fn(&[(String, f64)]) -> Result<&'static SystemInfo, Error>;

/// A catalogue entry: a system's name, its quantities and its units.
pub struct SystemInfo {
    /// Name used on the command line.
    pub name: &'static str,
    /// One line of description.
    pub description: &'static str,
    /// Physical parameters, in a fixed order.
    pub parameters: &'static [Quantity],
    /// State variables (positions, then velocities), in the order of the state vector.
    pub state: &'static [Quantity],
    /// For a family of systems whose quantities depend on a setting (the chain's `links`):
    /// the member the settings choose, whose entry [`SystemInfo::values`] then uses. This
    /// entry lists the quantities of the largest member, so that names can be checked early.
    pub variant: Option<Variant>,
    /// Whether the system is written in dimensionless units (time in units of 1/ω₀, energy
    /// in units of m g l): its outputs then carry no s, 1/s or J.
    pub dimensionless: bool,
    /// The energy scale that relative energy errors are taken against, in words (see
    /// [`Model::energy_scale`]).
    pub energy_scale: &'static str,
    /// The horizon of the accuracy studies (convergence, work-precision), in periods
    /// [`Model::time_scale`]: a real stretch of motion, yet short of the time over which
    /// chaos amplifies every error by orders of magnitude (which would hide the methods'
    /// orders behind the Lyapunov growth).
    pub study_periods: f64,
}

impl std::fmt::Debug for SystemInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SystemInfo").field("name", &self.name).finish_non_exhaustive()
    }
}

impl SystemInfo {
    /// The unit of time: `s`, or `""` for a dimensionless system.
    pub fn time_unit(&self) -> &'static str {
        if self.dimensionless { "" } else { "s" }
    }

    /// The unit of rates (Lyapunov exponents, growth rates): `1/s`, or `""`.
    pub fn rate_unit(&self) -> &'static str {
        if self.dimensionless { "" } else { "1/s" }
    }

    /// The unit of energy: `J`, or `""` for a dimensionless system.
    pub fn energy_unit(&self) -> &'static str {
        if self.dimensionless { "" } else { "J" }
    }

    /// Every quantity: parameters then state variables.
    pub fn quantities(&self) -> impl Iterator<Item = &'static Quantity> + use<> {
        let (p, s): (&'static [Quantity], &'static [Quantity]) = (self.parameters, self.state);
        p.iter().chain(s.iter())
    }

    /// Looks up a parameter or state variable by name.
    pub fn quantity(&self, name: &str) -> Result<&'static Quantity, Error> {
        self.quantities()
            .find(|q| q.name == name)
            .ok_or_else(|| Error::unknown_name(self.name, name, self.quantities().map(|q| q.name)))
    }

    /// The catalogue's defaults with `settings` (name, value) applied in order, validated.
    pub fn values(&'static self, settings: &[(String, f64)]) -> Result<Values, Error> {
        if let Some(variant) = self.variant {
            let member = variant(settings)?;
            if !std::ptr::eq(member, self) {
                return member.values(settings);
            }
        }
        let mut values: Vec<f64> = self.quantities().map(|q| q.default).collect();
        for (name, value) in settings {
            let index = self.quantities().position(|q| q.name == name);
            let q = self.quantity(name)?;
            if !q.domain.contains(*value) {
                return Err(Error::InvalidValue {
                    name: name.clone(),
                    value: *value,
                    allowed: q.domain.describe(),
                });
            }
            values[index.expect("quantity() found it")] = *value;
        }
        Ok(Values { info: self, values })
    }
}

/// Validated values of every parameter and initial-state variable of one system.
#[derive(Debug, Clone)]
pub struct Values {
    info: &'static SystemInfo,
    values: Vec<f64>,
}

impl Values {
    /// The system these values belong to.
    pub fn info(&self) -> &'static SystemInfo {
        self.info
    }

    /// The value of a parameter or state variable.
    ///
    /// # Panics
    /// If `name` is not one of the system's quantities: a programming error in a system file.
    pub fn get(&self, name: &str) -> f64 {
        let i = self.info.quantities().position(|q| q.name == name);
        self.values[i.unwrap_or_else(|| panic!("{} has no quantity {name}", self.info.name))]
    }

    /// (name, value) of every parameter.
    pub fn parameters(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        self.info.parameters.iter().zip(&self.values).map(|(q, v)| (q.name, *v))
    }

    /// The initial state vector, in the order of [`SystemInfo::state`].
    pub fn initial_state(&self) -> &[f64] {
        &self.values[self.info.parameters.len()..]
    }
}

/// A catalogued system: built from [`Values`], with its Hamiltonian form when it has one.
///
/// The user-facing state is (positions, velocities); the Hamiltonian form's state is
/// (positions, momenta), and the two conversions map between them.
pub trait Model: System + Energy + Sized + Send + Sync + 'static {
    /// The canonical (q, p) form.
    type Form: Hamiltonian + Energy;
    /// Catalogue entry of this system.
    const INFO: &'static SystemInfo;
    /// The dimension of the state (for a family, the largest member's: the chain's 16): the
    /// ensemble engine's kernels are compiled for it, their loops unrolled.
    const DIM: usize;
    /// The same system over another number type ([`Equations`]); `Over<f64>` is `Self`.
    type Over<T: Num>: Equations<T> + Canonical<T>;
    /// The system over `T`, each parameter `name` being `value(name)` (lanes: one member's
    /// value per lane), structural settings (the chain's `links`, the small-angle flag) read
    /// from `setting(name)` (the same for every lane).
    fn over<T: Num>(setting: &dyn Fn(&str) -> f64, value: &dyn Fn(&str) -> T) -> Self::Over<T>;
    /// This system over `T`, each parameter converted by `f` (one lane, dual numbers).
    fn convert<T: Num>(&self, f: &dyn Fn(f64) -> T) -> Self::Over<T>;
    /// Builds the system from validated values.
    fn from_values(values: &Values) -> Self;
    /// The Hamiltonian form, or why there is none (for example, damping).
    fn hamiltonian_form(&self) -> Result<Self::Form, String>;
    /// (q, q') → (q, p).
    fn to_momenta(&self, y: &[f64], z: &mut [f64]);
    /// (q, p) → (q, q').
    fn to_velocities(&self, z: &[f64], y: &mut [f64]);
    /// The exact state at time t from `y0` at t = 0, written into `y`, when a closed form
    /// exists for these parameters; false otherwise.
    fn exact(&self, _t: f64, _y0: &[f64], _y: &mut [f64]) -> bool {
        false
    }
    /// Whether the equations do not depend on time (no drive): with a Hamiltonian form,
    /// the energy is then conserved.
    fn autonomous(&self) -> bool {
        true
    }
    /// The catalogue entry of this instance: [`Model::INFO`], except in a family, whose
    /// members each have their own (see [`SystemInfo::variant`]).
    fn info(&self) -> &'static SystemInfo {
        Self::INFO
    }
    /// The energy scale that relative energy errors of a run from `y0` are taken against, J
    /// (in the system's units when dimensionless): a size of the motion's energy that is
    /// never near zero for ordinary states — for the pendulums, the potential energy gained
    /// from hanging at rest to every rod horizontal, or the initial energy above the
    /// potential's minimum when that is larger ([`SystemInfo::energy_scale`] says it in
    /// words). Dividing by |E(0)| instead misleads: E(0) depends on where V = 0 is put and
    /// may vanish for ordinary states.
    fn energy_scale(&self, y0: &[f64]) -> f64;
    /// The power of the non-conservative forces (damping, drive) at (t, y), J/s: dE/dt =
    /// power along every solution, so that E(t) − E(0) − ∫₀ᵗ power dt is conserved. Zero (the
    /// default) for a free system.
    fn power(&self, _t: f64, _y: &[f64]) -> f64 {
        0.0
    }
    /// The period of small oscillations about the stable equilibrium, s (in the system's
    /// units when dimensionless): the time scale that steps and horizons of studies are
    /// measured in.
    fn time_scale(&self) -> f64;
}

/// The object-safe face of a [`Model`]'s physics, used where the system is chosen at run
/// time; `crate::model::DynModel` adds the runs.
pub trait DynSystem: Send + Sync {
    /// Catalogue entry.
    fn info(&self) -> &'static SystemInfo;
    /// Mechanical energy at (t, y), J.
    fn energy(&self, t: f64, y: &[f64]) -> f64;
    /// The scale of relative energy errors of a run from `y0` (see [`Model::energy_scale`]).
    fn energy_scale(&self, y0: &[f64]) -> f64;
    /// The power of the non-conservative forces at (t, y), J/s (see [`Model::power`]).
    fn power(&self, t: f64, y: &[f64]) -> f64;
    /// The period of small oscillations, s (see [`Model::time_scale`]).
    fn time_scale(&self) -> f64;
    /// The right-hand side f(t, y) of the (position, velocity) form.
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]);
    /// The Jacobian ∂f/∂y of the (position, velocity) form, row-major; false when the
    /// system has none (see [`System::jacobian`]).
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool;
    /// The exact state at t from `y0` at t = 0, if a closed form exists (see [`Model::exact`]).
    fn exact(&self, t: f64, y0: &[f64]) -> Option<Vec<f64>>;
    /// (q, q') → (q, p) (see [`Model::to_momenta`]).
    fn to_momenta(&self, y: &[f64], z: &mut [f64]);
    /// (q, p) → (q, q') (see [`Model::to_velocities`]).
    fn to_velocities(&self, z: &[f64], y: &mut [f64]);
    /// Ok when the system is Hamiltonian and autonomous, so that its energy is conserved;
    /// otherwise why not.
    fn conserves_energy(&self) -> Result<(), String>;
}

impl<M: Model> DynSystem for M {
    fn info(&self) -> &'static SystemInfo {
        Model::info(self)
    }
    fn energy(&self, t: f64, y: &[f64]) -> f64 {
        Energy::energy(self, t, y)
    }
    fn energy_scale(&self, y0: &[f64]) -> f64 {
        Model::energy_scale(self, y0)
    }
    fn power(&self, t: f64, y: &[f64]) -> f64 {
        Model::power(self, t, y)
    }
    fn time_scale(&self) -> f64 {
        Model::time_scale(self)
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        System::rhs(self, t, y, dydt);
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        System::jacobian(self, t, y, jac)
    }
    fn exact(&self, t: f64, y0: &[f64]) -> Option<Vec<f64>> {
        let mut y = vec![0.0; y0.len()];
        Model::exact(self, t, y0, &mut y).then_some(y)
    }
    fn to_momenta(&self, y: &[f64], z: &mut [f64]) {
        Model::to_momenta(self, y, z);
    }
    fn to_velocities(&self, z: &[f64], y: &mut [f64]) {
        Model::to_velocities(self, z, y);
    }
    fn conserves_energy(&self) -> Result<(), String> {
        self.hamiltonian_form()?;
        if !self.autonomous() {
            return Err(format!("the `{}` system is driven (time-dependent)", Model::info(self).name));
        }
        Ok(())
    }
}

/// A [`DynSystem`]'s (position, velocity) ODE as a [`System`], for analyses written over
/// plain systems (Lyapunov exponents).
pub struct AsSystem<'a>(pub &'a dyn DynSystem);

impl System for AsSystem<'_> {
    fn dim(&self) -> usize {
        self.0.info().state.len()
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        self.0.rhs(t, y, dydt);
    }
    fn jacobian(&self, t: f64, y: &[f64], jac: &mut [f64]) -> bool {
        self.0.jacobian(t, y, jac)
    }
}

/// The largest state [`dual_jacobian`] differentiates (the 8-link chain's 16).
const MAX_DUAL_DIM: usize = 16;

/// The Jacobian of `f`, a map of R^dim into itself (dim ≤ 16), at `y` by forward-mode
/// automatic differentiation (num-dual): one dual-number evaluation per column, written
/// row-major into `jac`; nothing is allocated.
pub(crate) fn dual_jacobian(
    dim: usize,
    f: impl Fn(&[num_dual::Dual64], &mut [num_dual::Dual64]),
    y: &[f64],
    jac: &mut [f64],
) {
    use num_dual::Dual64;
    let mut seeded = [Dual64::from(0.0); MAX_DUAL_DIM];
    let mut out = [Dual64::from(0.0); MAX_DUAL_DIM];
    for column in 0..dim {
        for j in 0..dim {
            seeded[j] = Dual64::new(y[j], if j == column { 1.0 } else { 0.0 });
        }
        f(&seeded[..dim], &mut out[..dim]);
        for row in 0..dim {
            jac[row * dim + column] = out[row].eps;
        }
    }
}

/// An angle wrapped into [−π, π), rad: θ − 2π ⌊θ/2π + ½⌋.
#[inline]
pub fn wrap_angle(theta: f64) -> f64 {
    use std::f64::consts::TAU;
    theta - TAU * (theta / TAU + 0.5).floor()
}
