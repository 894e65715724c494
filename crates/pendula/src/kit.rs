//! The systems test kit: what every catalogued system must satisfy, checked on any state of
//! any [`Model`] ([`check`]). Every entry of `crate::model::CATALOGUE` carries it, so the
//! tests run it on every system and variant, and a new system is checked by being
//! catalogued (after diffsol's `test_ode_solver` kit).
//!
//! The checks, each against an independent computation (central differences, a closed-form
//! identity, the other form of the equations), never against the code under test:
//!
//! - the Jacobian (where the system has one) against central differences of the rhs;
//! - (q, q') → (q, p) → (q, q') returns the state;
//! - the Hamiltonian form, where there is one, gives the model's velocities and, from
//!   p' = −∂H/∂q, the model's accelerations (through the momenta's time derivative along the
//!   flow, by central differences), and H equals the energy;
//! - the energy's time derivative along the flow (central differences) is the power of the
//!   forces ([`Model::power`]: zero for a conservative system);
//! - every default lies in its domain;
//! - the equations written once give the same values in every number type: one lane of a
//!   16-lane group is bit for bit the one-lane result (the same operations); the dual
//!   numbers' value parts and the engine arithmetic agree with the `f64` rhs to rounding
//!   (num-dual divides through a reciprocal; the engine's sine and cosine are polynomials).

use num_dual::Dual64;

use crate::num::Lanes;
use crate::system::{Energy, Equations, Model, System, Values};

/// The failures of the kit's checks for `model` at time `t` and state `y`, in words (empty:
/// every check passed).
pub fn check<M: Model>(model: &M, t: f64, y: &[f64]) -> Vec<String> {
    let mut failures = Vec::new();
    let mut fail = |what: String| failures.push(what);
    let name = model.info().name;
    let n = y.len();
    let mut f = vec![0.0; n];
    model.rhs(t, y, &mut f);
    let scale = y.iter().chain(&f).fold(1.0f64, |s, v| s.max(v.abs()));

    // The Jacobian against central differences.
    let mut jac = vec![0.0; n * n];
    if model.jacobian(t, y, &mut jac) {
        for j in 0..n {
            let eps = 1e-6 * y[j].abs().max(1.0);
            let (mut up, mut down) = (y.to_vec(), y.to_vec());
            up[j] += eps;
            down[j] -= eps;
            let (mut fu, mut fd) = (vec![0.0; n], vec![0.0; n]);
            model.rhs(t, &up, &mut fu);
            model.rhs(t, &down, &mut fd);
            for i in 0..n {
                let numeric = (fu[i] - fd[i]) / (2.0 * eps);
                if (numeric - jac[i * n + j]).abs() > 1e-5 * scale.max(numeric.abs()) {
                    fail(format!(
                        "{name}: Jacobian J[{i}][{j}] = {} but central differences give {numeric}",
                        jac[i * n + j]
                    ));
                }
            }
        }
    }

    // (q, q') ↔ (q, p).
    let mut z = vec![0.0; n];
    let mut back = vec![0.0; n];
    model.to_momenta(y, &mut z);
    model.to_velocities(&z, &mut back);
    for i in 0..n {
        if (back[i] - y[i]).abs() > 1e-12 * scale {
            fail(format!("{name}: (q, q') -> (q, p) -> (q, q') moved variable {i}: {} to {}", y[i], back[i]));
        }
    }

    // The states a step ε before and after y along the flow (y ∓ ε f), to first order: the
    // central differences below of p(y(t)) and of E(t, y(t)).
    let eps = 1e-6;
    let (mut ya, mut yb) = (y.to_vec(), y.to_vec());
    for i in 0..n {
        ya[i] += eps * f[i];
        yb[i] -= eps * f[i];
    }

    // The Hamiltonian form against the model's equations and energy.
    if let Ok(form) = model.hamiltonian_form() {
        let half = n / 2;
        let mut g = vec![0.0; n];
        form.rhs(t, &z, &mut g);
        for i in 0..half {
            if (g[i] - f[i]).abs() > 1e-10 * scale {
                fail(format!("{name}: the Hamiltonian form's q'{i} = {} but the model's is {}", g[i], f[i]));
            }
        }
        // p' along the model's flow, by central differences of p(y(t)).
        let (mut za, mut zb) = (vec![0.0; n], vec![0.0; n]);
        model.to_momenta(&ya, &mut za);
        model.to_momenta(&yb, &mut zb);
        let pscale = z.iter().chain(&g).fold(1.0f64, |s, v| s.max(v.abs()));
        for i in half..n {
            let numeric = (za[i] - zb[i]) / (2.0 * eps);
            if (numeric - g[i]).abs() > 1e-5 * pscale {
                fail(format!(
                    "{name}: the Hamiltonian form's p'{} = {} but the model's flow gives {numeric}",
                    i - half,
                    g[i]
                ));
            }
        }
        let (h, e) = (form.energy(t, &z), model.energy(t, y));
        if (h - e).abs() > 1e-10 * model.energy_scale(y) {
            fail(format!("{name}: H = {h} but the energy is {e}"));
        }
    }

    // dE/dt along the flow is the power of the forces.
    let de = (model.energy(t + eps, &ya) - model.energy(t - eps, &yb)) / (2.0 * eps);
    let power = model.power(t, y);
    let escale = model.energy_scale(y) / model.time_scale();
    if (de - power).abs() > 1e-5 * escale.max(power.abs()) {
        fail(format!("{name}: dE/dt = {de} along the flow but the forces' power is {power}"));
    }

    // Defaults in their domains.
    for q in model.info().quantities() {
        if !q.domain.contains(q.default) {
            fail(format!(
                "{name}: the default {} = {} is outside its domain ({})",
                q.name,
                q.default,
                q.domain.describe()
            ));
        }
    }

    // One set of equations, every number type.
    let dual = model.convert(&Dual64::from);
    let yd: Vec<Dual64> = y.iter().map(|&v| Dual64::from(v)).collect();
    let mut fd = vec![Dual64::from(0.0); n];
    Equations::rhs(&dual, Dual64::from(t), &yd, &mut fd);
    for i in 0..n {
        // To rounding: num-dual divides through a reciprocal.
        if (fd[i].re - f[i]).abs() > 1e-14 * scale {
            fail(format!(
                "{name}: the dual rhs's value part {i} is {} but the f64 rhs gives {}",
                fd[i].re, f[i]
            ));
        }
    }
    let one = model.convert(&|x| Lanes::<1, false, true>([x]));
    let wide = model.convert(&|x| Lanes::<16, false, true>([x; 16]));
    let y1: Vec<Lanes<1, false, true>> = y.iter().map(|&v| Lanes([v])).collect();
    let y16: Vec<Lanes<16, false, true>> = y.iter().map(|&v| Lanes([v; 16])).collect();
    let (mut f1, mut f16) = (vec![Lanes([0.0]); n], vec![Lanes([0.0; 16]); n]);
    Equations::rhs(&one, Lanes([t]), &y1, &mut f1);
    Equations::rhs(&wide, Lanes([t; 16]), &y16, &mut f16);
    for i in 0..n {
        if f16[i].0.iter().any(|v| v.to_bits() != f1[i].0[0].to_bits()) {
            fail(format!(
                "{name}: a lane group's rhs {i} is {:?} but one lane gives {}",
                f16[i].0, f1[i].0[0]
            ));
        }
        if (f1[i].0[0] - f[i]).abs() > 1e-13 * scale {
            fail(format!(
                "{name}: the engine arithmetic's rhs {i} is {} but the reference's {}",
                f1[i].0[0], f[i]
            ));
        }
    }
    failures
}

/// [`check`] on a system built from `values`, at t = 0.3 and its initial state.
pub fn check_values<M: Model>(values: &Values) -> Vec<String> {
    check(&M::from_values(values), 0.3, values.initial_state())
}
