//! # pendula
//!
//! Harmonic oscillators, simple and double pendulums, and the integrators that move them,
//! verified against exact solutions and independent references. The physics follows
//! "From Simple to Double Pendulum" (Di Giorno, 2025), as corrected by its errata.
//!
//! ## Brief overview
//!
//! A [`System`](system::System) is an ODE y' = f(t, y); small capability traits say what
//! else it offers: [`Energy`](system::Energy) and a [`Hamiltonian`](system::Hamiltonian)
//! form on (q, p). A [`Method`](integrator::Method) is a descriptor (name, order,
//! requirement, tableau) from the registry [`METHODS`](integrator::METHODS); its
//! [`Stepper`](integrator::Stepper) advances a state by one step without allocating. A
//! [`Simulation`] drives a stepper over a system and shows every state to an
//! [`Observer`](observe::Observer), which records, thins, tracks energy or stops the run.
//! The [`CATALOGUE`](model::CATALOGUE) lists the systems with their parameters, units and
//! defaults; [`solve`] runs any catalogued system with any method chosen at run time.
//!
//! ```
//! use pendula::integrator::{Stepper, explicit_rk::{ExplicitRk, RK4}, Scheme};
//! use pendula::observe::EnergyTracker;
//! use pendula::system::{Energy, Model, double::DoublePendulum};
//! use pendula::{End, RunSpec, Simulation};
//!
//! let pendulum = DoublePendulum { m1: 1.0, m2: 1.0, l1: 1.0, l2: 1.0, g: 9.81, ..Default::default() };
//! let Scheme::ExplicitRk(tableau) = RK4.scheme else { unreachable!() };
//! let mut y = [120f64.to_radians(), -10f64.to_radians(), 0.0, 0.0];
//! let mut energy = EnergyTracker::new(|t, y: &[f64]| pendulum.energy(t, y));
//! let run = Simulation { system: &pendulum, spec: RunSpec { t0: 0.0, h: 1e-3, end: End::Time(10.0) } };
//! let outcome = run.run(&mut ExplicitRk::new(tableau, 4), &mut y, &mut energy)?;
//! assert_eq!(outcome.steps(), 10_000);
//! // Relative to the energy scale (m₁ + m₂) g l₁ + m₂ g l₂ = 29.43 J, not to |E(0)|.
//! let scale = pendulum.energy_scale(&[120f64.to_radians(), -10f64.to_radians(), 0.0, 0.0]);
//! assert!(energy.stats().max_rel_error(scale) < 1e-7);
//! # Ok::<(), pendula::Error>(())
//! ```
//!
//! ## Units and names
//!
//! SI units throughout: seconds, metres, kilograms, radians (angles from the downward
//! vertical, y up), g = 9.81 m/s² by default. Abbreviations: t time, h step size, y state,
//! q positions, p momenta, rhs right-hand side f(t, y), H Hamiltonian.

pub mod analysis;
pub mod checkpoint;
pub mod control;
pub mod ensemble;
pub mod error;
pub mod events;
pub mod integrator;
pub mod kit;
pub mod model;
pub mod num;
pub mod observe;
pub mod simulate;
pub mod special;
pub mod study;
pub mod sweep;
pub mod system;

pub use error::Error;
pub use simulate::resume::solve_resumable;
pub use simulate::{End, Outcome, Report, RunSpec, Simulation, Stepping, check, solve, solve_adaptive};
