//! Poincaré sections of two-degree-of-freedom Hamiltonian systems (the double pendulum,
//! the two-link chain): initial conditions on a fixed-energy surface, and the crossings of
//! a section qₛ = v (mod 2π) in the direction q̇ₛ > 0, located on the integrator's dense
//! output (or its Hermite interpolant).

use rayon::prelude::*;

use crate::control::Tolerances;
use crate::events::{Direction, EventKind, EventLocator, EventSpec};
use crate::integrator::{Method, Scheme};
use crate::model::DynModel;
use crate::{End, Error, RunSpec};

/// How the orbits are integrated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stepping {
    /// An embedded pair with adaptive steps and these tolerances.
    Adaptive(Tolerances),
    /// Fixed steps of this size, s (a symplectic method, for instance).
    Fixed(f64),
}

/// What to compute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoincareSpec {
    /// The energy of every orbit, J.
    pub energy: f64,
    /// Number of orbits.
    pub count: usize,
    /// Index (0 or 1) of the position that defines the section.
    pub section: usize,
    /// The section's value, rad.
    pub value: f64,
    /// Length of each orbit, s.
    pub t_end: f64,
}

/// One orbit: its start and its crossings.
#[derive(Debug, Clone, PartialEq)]
pub struct Orbit {
    /// Initial state (positions, velocities).
    pub initial: Vec<f64>,
    /// Crossing times, s.
    pub t: Vec<f64>,
    /// The state at each crossing in canonical form (q₁, q₂, p₁, p₂).
    pub crossings: Vec<[f64; 4]>,
}

/// The R2 low-discrepancy sequence in the unit square (M. Roberts, 2018): point k.
fn r2(k: usize) -> (f64, f64) {
    // The plastic number φ₂, the real root of x³ = x + 1.
    const PHI2: f64 = 1.324_717_957_244_746;
    let (a1, a2) = (1.0 / PHI2, 1.0 / (PHI2 * PHI2));
    ((0.5 + a1 * k as f64).fract(), (0.5 + a2 * k as f64).fract())
}

/// The kinetic energy ½ pᵀ A(q) p as (A₁₁, A₁₂, A₂₂) and the potential V(q), from energy
/// evaluations (exact for a kinetic energy quadratic in the momenta).
fn quadratic(model: &dyn DynModel, q: [f64; 2]) -> ([f64; 3], f64) {
    let mut y = [0.0; 4];
    let mut h = |p: [f64; 2]| {
        model.to_velocities(&[q[0], q[1], p[0], p[1]], &mut y);
        model.energy(0.0, &y)
    };
    let v = h([0.0, 0.0]);
    let (t1, t2, t12) = (h([1.0, 0.0]) - v, h([0.0, 1.0]) - v, h([1.0, 1.0]) - v);
    ([2.0 * t1, t12 - t1 - t2, 2.0 * t2], v)
}

/// Checks that `model` has what a Poincaré section on an energy surface needs: two degrees of
/// freedom and a conserved energy, so that the section of the surface is two-dimensional.
///
/// # Errors
/// [`Error::UnmetRequirement`] naming every need the system misses (a damped, driven pendulum
/// misses both).
pub fn check_system(model: &dyn DynModel) -> Result<(), Error> {
    let info = model.info();
    let mut reasons = Vec::new();
    if info.state.len() != 4 {
        let dof = info.state.len() / 2;
        reasons.push(format!(
            "`{}` has {dof} degree{} of freedom, not 2",
            info.name,
            if dof == 1 { "" } else { "s" }
        ));
    }
    if let Err(reason) = model.conserves_energy() {
        reasons.push(format!("{reason}: it has no conserved energy surface"));
    }
    if reasons.is_empty() {
        return Ok(());
    }
    Err(Error::UnmetRequirement {
        method: "poincare",
        needs: "a conservative system with two degrees of freedom",
        reason: reasons.join("; "),
        suggestion: "the double pendulum, or the chain with links=2".into(),
    })
}

/// How far above the energy at rest a section's energy may lie, in energy scales: beyond
/// about 1/ε ≈ 4.5e15 scales the potential energy is lost in the round-off of the kinetic, and
/// the motion is free rotation whatever the system; 10¹² keeps three digits of the potential.
pub const MAX_ENERGY_SCALES: f64 = 1e12;

/// The highest energy [`energy_surface_states`] accepts, in the system's energy unit: the
/// energy at rest plus [`MAX_ENERGY_SCALES`] energy scales.
pub fn max_energy(model: &dyn DynModel) -> f64 {
    let rest = vec![0.0; model.info().state.len()];
    model.energy(0.0, &rest) + MAX_ENERGY_SCALES * model.energy_scale(&rest)
}

/// `count` initial states (positions, velocities) with energy `energy`, on the section
/// (q_s = value) and crossing it upwards (q̇_s > 0): the other position q_o and its momentum
/// p_o follow the R2 sequence over q_o ∈ [−π, π) and over the p_o allowed at that q_o: with
/// T = ½ pᵀ A p, the least kinetic energy for a given p_o is ½ p_o² (a_oo − a_so²/a_ss), so
/// |p_o| ≤ √(2 (E − V) / (a_oo − a_so²/a_ss)). Then p_s solves H = E on the root with
/// q̇_s = ∂H/∂p_s > 0. Positions where E ≤ V are skipped.
///
/// # Errors
/// [`Error::UnmetRequirement`] unless the system has two degrees of freedom and conserves
/// energy; [`Error::InvalidValue`] when no point of the section has V < E, or E is above
/// [`max_energy`] or not finite.
pub fn energy_surface_states(model: &dyn DynModel, spec: &PoincareSpec) -> Result<Vec<Vec<f64>>, Error> {
    check_system(model)?;
    if !spec.energy.is_finite() || spec.energy > max_energy(model) {
        return Err(Error::InvalidValue {
            name: "energy".into(),
            value: spec.energy,
            allowed: "must be finite and at most 1e12 energy scales above the energy at rest",
        });
    }
    let (s, o) = (spec.section, 1 - spec.section);
    let mut states = Vec::with_capacity(spec.count);
    let mut k = 0;
    // Give up when far more points were rejected than accepted: the energy is (almost) too low.
    while states.len() < spec.count {
        if k > 1000 * spec.count.max(1) {
            return Err(Error::InvalidValue {
                name: "energy".into(),
                value: spec.energy,
                allowed: "must exceed the potential energy somewhere on the section",
            });
        }
        let (u, w) = r2(k);
        k += 1;
        let mut q = [0.0; 2];
        q[s] = spec.value;
        q[o] = -std::f64::consts::PI + 2.0 * std::f64::consts::PI * u;
        let (a, v) = quadratic(model, q);
        let spare = spec.energy - v;
        if spare <= 0.0 {
            continue;
        }
        // Entries by role: a_ss, a_so, a_oo.
        let (a_ss, a_so, a_oo) = if s == 0 { (a[0], a[1], a[2]) } else { (a[2], a[1], a[0]) };
        // min over p_s of ½ pᵀ A p = ½ p_o² (a_oo − a_so²/a_ss).
        let schur = a_oo - a_so * a_so / a_ss;
        let p_o = (2.0 * w - 1.0) * (2.0 * spare / schur).sqrt();
        // ½ a_ss p_s² + a_so p_o p_s + ½ a_oo p_o² = spare, root with ∂H/∂p_s = a_ss p_s + a_so p_o > 0.
        let (qa, qb, qc) = (0.5 * a_ss, a_so * p_o, 0.5 * a_oo * p_o * p_o - spare);
        let disc = qb * qb - 4.0 * qa * qc;
        if disc <= 0.0 {
            continue;
        }
        let p_s = (-qb + disc.sqrt()) / (2.0 * qa);
        let mut z = [0.0; 4];
        z[..2].copy_from_slice(&q);
        z[2 + s] = p_s;
        z[2 + o] = p_o;
        let mut y = vec![0.0; 4];
        model.to_velocities(&z, &mut y);
        states.push(y);
    }
    Ok(states)
}

/// Integrates each state of [`energy_surface_states`] for `spec.t_end` and locates its
/// crossings of the section, in parallel on rayon's pool (results in orbit order, the same
/// for any thread count).
///
/// # Errors
/// Those of [`energy_surface_states`]; a method that cannot run with `stepping`; the runs'
/// errors.
pub fn poincare(
    model: &dyn DynModel,
    method: &Method,
    stepping: Stepping,
    spec: &PoincareSpec,
) -> Result<Vec<Orbit>, Error> {
    let states = energy_surface_states(model, spec)?;
    let event = EventSpec {
        name: "section".into(),
        kind: EventKind::Section { index: spec.section, value: spec.value, periodic: true },
        direction: Direction::Rising,
        terminal: false,
    };
    states
        .par_iter()
        .map(|y0| {
            let mut locator = EventLocator::new(model, vec![event.clone()]);
            match (stepping, method.scheme) {
                (Stepping::Adaptive(tol), Scheme::Embedded(_)) => {
                    model.solve_adaptive(method, y0, spec.t_end, None, &tol, &mut locator)?;
                }
                (Stepping::Fixed(h), _) => {
                    let run = RunSpec { t0: 0.0, h, end: End::Time(spec.t_end) };
                    model.solve(method, y0, &run, &mut locator)?;
                }
                (Stepping::Adaptive(_), _) => {
                    return Err(Error::UnmetRequirement {
                        method: method.name,
                        needs: "a step size",
                        reason: "it takes fixed steps".into(),
                        suggestion: "dop853 (adaptive) or a step size".into(),
                    });
                }
            }
            let mut orbit = Orbit { initial: y0.clone(), t: Vec::new(), crossings: Vec::new() };
            for e in locator.found {
                let mut z = [0.0; 4];
                model.to_momenta(&e.state, &mut z);
                orbit.t.push(e.t);
                orbit.crossings.push(z);
            }
            Ok(orbit)
        })
        .collect()
}

/// The largest |H − `energy`| over every crossing of `orbits` (J): how well the runs kept
/// the energy surface they started on.
pub fn max_energy_error(model: &dyn DynModel, orbits: &[Orbit], energy: f64) -> f64 {
    let mut y = [0.0; 4];
    orbits
        .iter()
        .flat_map(|o| o.t.iter().zip(&o.crossings))
        .map(|(t, z)| {
            model.to_velocities(z, &mut y);
            (model.energy(*t, &y) - energy).abs()
        })
        .fold(0.0, f64::max)
}
