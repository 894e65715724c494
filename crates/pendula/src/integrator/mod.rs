//! Integration methods: descriptors ([`Method`]), the registry [`METHODS`], and the
//! [`Stepper`] trait their steppers implement.
//!
//! A method is data: a `static` [`Method`] in its family's file (Butcher tableau, scheme)
//! plus one line in [`METHODS`]. Steppers are built from descriptors, own their scratch
//! buffers (allocated once), and allocate nothing per step.
//!
//! # The families
//!
//! Method families, one file each: `crates/pendula/src/integrator/explicit_rk.rs` (Butcher
//! tableaus: `euler`, `rk4`), `crates/pendula/src/integrator/partitioned.rs` (`symplectic-euler`,
//! `verlet`), `crates/pendula/src/integrator/composition.rs` (Yoshida's compositions of Verlet, as
//! weight tables; separable systems only) and `crates/pendula/src/integrator/gauss_legendre.rs`
//! (Gauss collocation, full implicit tableaus; on the Hamiltonian form when there is one; stages by
//! simplified then full Newton with `System::jacobian` — analytic for the oscillator and the
//! pendulum, num-dual forward-mode differentiation of a generic copy of the equations for the
//! double pendulum — and fixed-point iteration as the fallback; the stepper keeps the last step's
//! stages, whose extrapolated collocation polynomial starts the next iteration, and its Jacobian
//! and LU factors while simplified Newton contracts fast, so that a step costs about 12 evaluations
//! on the chaotic double pendulum at h = 0.02 s) and `crates/pendula/src/integrator/tao.rs` (Tao's
//! extended-phase-space maps `tao-2`, `tao-4`: the stepper keeps the copy (x, y) between steps; the
//! binding constant is part of the method's data, changed by `Method::with_binding`) and
//! `crates/pendula/src/integrator/embedded.rs` (embedded pairs `dopri5` and `dop853`, each a
//! tableau with its error estimator, its dense-output coefficients and its controller parameters).
//! Step-size control is separate from the methods: `crates/pendula/src/control.rs` holds the
//! tolerances and the PI controller, and `solve_adaptive` in
//! `crates/pendula/src/simulate/adaptive.rs` runs the adaptive loop (attempt, judge, accept or
//! reject, land on t_end; `solve_adaptive_from` from any start, and backward in time when t_end is
//! before it, step sizes kept positive and times compared in the run's direction). A fixed-step
//! `RunSpec` with a negative h runs backward to an end time before t₀; Python's `solve(t_span=(10,
//! 0))` uses both, as scipy's `solve_ivp` integrates backward. The partitioned methods run on a
//! system's Hamiltonian form: explicit when H is separable (oscillator, pendulum), implicit with
//! fixed-point iteration to round-off when it is not (the double pendulum). `dispatch` (behind
//! `solve`) is the one place that matches on the family (`Scheme`): a new family adds one arm
//! there; a new method in a family adds none.

pub mod composition;
pub mod embedded;
pub mod explicit_rk;
pub mod gauss_legendre;
pub mod partitioned;
pub mod tao;

use crate::Error;

/// Advances a state by one step.
pub trait Stepper<S: ?Sized> {
    /// Advances `y` from t to t + h in place.
    fn step(&mut self, system: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error>;
}

/// What a method needs of a system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Requirement {
    /// Any ODE y' = f(t, y).
    Any,
    /// A Hamiltonian form on (q, p); explicit when H is separable, implicit otherwise.
    Hamiltonian,
    /// A separable Hamiltonian H = T(p) + V(t, q).
    Separable,
    /// A Hamiltonian form, separable or not, used explicitly (Tao's extended phase space).
    HamiltonianExplicit,
}

impl Requirement {
    /// The requirement in words, for `pendula list methods` and error messages.
    pub fn describe(self) -> &'static str {
        match self {
            Requirement::Any => "any ODE",
            Requirement::Hamiltonian => {
                "a Hamiltonian system (explicit if H = T(p) + V(q), implicit otherwise)"
            }
            Requirement::Separable => "a separable Hamiltonian H = T(p) + V(q)",
            Requirement::HamiltonianExplicit => "a Hamiltonian system (separable or not; explicit)",
        }
    }
}

/// How a method steps: the data its stepper is built from.
#[derive(Debug, Clone, Copy)]
pub enum Scheme {
    /// An explicit Runge–Kutta method with this tableau.
    ExplicitRk(&'static explicit_rk::Tableau),
    /// A partitioned method on (q, p).
    Partitioned(partitioned::Partition),
    /// A fully implicit Runge–Kutta (collocation) method, run on the Hamiltonian form when
    /// the system has one.
    Collocation(&'static gauss_legendre::ImplicitTableau),
    /// An embedded Runge–Kutta pair: adaptive with tolerances, or fixed-step.
    Embedded(&'static embedded::EmbeddedTableau),
    /// Tao's extended-phase-space map and its compositions, on a Hamiltonian form.
    Tao(tao::TaoScheme),
}

/// A method descriptor.
#[derive(Debug, Clone, Copy)]
pub struct Method {
    /// Name used on the command line.
    pub name: &'static str,
    /// Name in the literature.
    pub title: &'static str,
    /// Order of the global error.
    pub order: u32,
    /// What it needs of the system.
    pub requirement: Requirement,
    /// Whether it preserves the symplectic form (on a Hamiltonian system).
    pub symplectic: bool,
    /// Whether it is symmetric (time-reversible).
    pub symmetric: bool,
    /// One line of description.
    pub description: &'static str,
    /// Where it is defined.
    pub reference: &'static str,
    /// The data its stepper is built from.
    pub scheme: Scheme,
}

impl Method {
    /// The order of the method's own dense output (the embedded pairs: dopri5 4, dop853 7);
    /// `None` for a method without one, whose continuous solution is the cubic Hermite
    /// interpolant of order 3 ([`crate::events::hermite`]).
    pub fn dense_order(&self) -> Option<u32> {
        match &self.scheme {
            Scheme::Embedded(t) => Some(t.dense_order),
            _ => None,
        }
    }

    /// Whether the method controls its step (the embedded pairs): a given step is only the
    /// first to try.
    pub fn adaptive(&self) -> bool {
        matches!(self.scheme, Scheme::Embedded(_))
    }

    /// The largest step this method is run at, s: for Tao's maps
    /// [`tao::MAX_BINDING_STEP`] / ω (above it they are unstable, and refused); `None` for
    /// the others, whose stable step depends on the system.
    pub fn max_step(&self) -> Option<f64> {
        match &self.scheme {
            Scheme::Tao(t) => Some(tao::MAX_BINDING_STEP / t.binding),
            _ => None,
        }
    }
}

/// Every method pendula knows, in the order `pendula list methods` shows them.
#[rustfmt::skip] // one method per line
pub static METHODS: &[&Method] = &[
    &explicit_rk::EULER,
    &explicit_rk::RK4,
    &partitioned::SYMPLECTIC_EULER,
    &partitioned::VERLET,
    &composition::YOSHIDA_4,
    &composition::YOSHIDA_6,
    &composition::YOSHIDA_8,
    &gauss_legendre::GAUSS_LEGENDRE_2,
    &gauss_legendre::GAUSS_LEGENDRE_4,
    &gauss_legendre::GAUSS_LEGENDRE_6,
    &tao::TAO_2,
    &tao::TAO_4,
    &embedded::DOPRI5,
    &embedded::DOP853,
];

/// Looks a method up by name.
pub fn find(name: &str) -> Result<&'static Method, Error> {
    METHODS.iter().copied().find(|m| m.name == name).ok_or_else(|| Error::UnknownMethod {
        name: name.to_owned(),
        valid: METHODS.iter().map(|m| m.name).collect::<Vec<_>>().join(", "),
        suggestions: crate::error::suggestions(name, METHODS.iter().map(|m| m.name)),
    })
}
