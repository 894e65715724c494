//! The symplectic condition Φ'(z)ᵀ Ω Φ'(z) = Ω for one step of the symplectic methods on the
//! double pendulum's (non-separable) Hamiltonian form — for Tao's methods, of their map on
//! the extended phase space (q, p, x, y), where they are symplectic — and time
//! reversibility of the symmetric ones.

use pendula::integrator::embedded::EmbeddedRk;
use pendula::integrator::explicit_rk::{EULER, ExplicitRk};
use pendula::integrator::gauss_legendre::Collocation;
use pendula::integrator::partitioned::PartitionedStepper;
use pendula::integrator::tao::TaoStepper;
use pendula::integrator::{METHODS, Method, Requirement, Scheme, Stepper};
use pendula::system::Hamiltonian;
use pendula::system::double::{DoublePendulum, DoublePendulumForm};

const H: f64 = 0.01;

fn form() -> DoublePendulumForm {
    DoublePendulum { m1: 1.0, m2: 1.5, l1: 1.0, l2: 0.8, g: 9.81, ..Default::default() }.form()
}

/// States (θ₁, θ₂, p₁, p₂) to test at.
const STATES: [[f64; 4]; 3] = [[2.0, -0.2, 0.3, -0.4], [0.4, 1.9, -2.5, 1.1], [-1.2, 2.8, 4.0, 2.0]];

fn step<const N: usize>(stepper: &mut dyn FnMut(&mut [f64; N]), z: [f64; N]) -> [f64; N] {
    let mut z = z;
    stepper(&mut z);
    z
}

/// Jacobian of the one-step map by 8th-order central differences: truncation below 1e-15
/// at ε = 5e-3, round-off (and the implicit solver's tolerance) about 1e-13.
fn jacobian<const N: usize>(stepper: &mut dyn FnMut(&mut [f64; N]), z: [f64; N]) -> [[f64; N]; N] {
    const W: [f64; 4] = [4.0 / 5.0, -1.0 / 5.0, 4.0 / 105.0, -1.0 / 280.0];
    let eps = 5e-3;
    let mut jac = [[0.0; N]; N];
    for j in 0..N {
        for (k, w) in W.iter().enumerate() {
            let d = (k + 1) as f64 * eps;
            let (mut plus, mut minus) = (z, z);
            plus[j] += d;
            minus[j] -= d;
            let (fp, fm) = (step(stepper, plus), step(stepper, minus));
            for i in 0..N {
                jac[i][j] += w * (fp[i] - fm[i]) / eps;
            }
        }
    }
    jac
}

/// max |JᵀΩJ − Ω| for the state (q, p) or (q, p, x, y) in blocks of two degrees of freedom:
/// Ω pairs qᵢ with pᵢ (and xᵢ with yᵢ).
fn symplectic_defect<const N: usize>(jac: &[[f64; N]; N]) -> f64 {
    let omega = |i: usize, j: usize| {
        let (bi, bj) = (i / 4, j / 4);
        match (bi == bj, i % 4, j % 4) {
            (true, 0, 2) | (true, 1, 3) => 1.0,
            (true, 2, 0) | (true, 3, 1) => -1.0,
            _ => 0.0,
        }
    };
    let mut worst = 0.0_f64;
    for a in 0..N {
        for b in 0..N {
            let mut s = 0.0;
            for i in 0..N {
                for j in 0..N {
                    s += jac[i][a] * omega(i, j) * jac[j][b];
                }
            }
            worst = worst.max((s - omega(a, b)).abs());
        }
    }
    worst
}

/// A stepper for any registered method, on a Hamiltonian form with 2 degrees of freedom.
fn stepper(method: &Method) -> Box<dyn Stepper<dyn Hamiltonian>> {
    match method.scheme {
        Scheme::ExplicitRk(t) => Box::new(ExplicitRk::new(t, 4)),
        Scheme::Partitioned(p) => Box::new(PartitionedStepper::new(p, 2)),
        Scheme::Collocation(t) => Box::new(Collocation::new(t, 4)),
        Scheme::Embedded(t) => Box::new(EmbeddedRk::new(t, 4)),
        Scheme::Tao(t) => Box::new(TaoStepper::new(t, 2)),
    }
}

/// Every symplectic method that applies to the double pendulum (all but the compositions,
/// which need a separable H).
#[test]
fn ref_symplectic_methods_preserve_the_symplectic_form() {
    let sys = form();
    let mut checked = 0;
    for method in METHODS.iter().filter(|m| m.symplectic && m.requirement != Requirement::Separable) {
        for z in STATES {
            let defect = if let Scheme::Tao(scheme) = method.scheme {
                // The extended map from a state whose copy is displaced from (q, p), as
                // after a few steps.
                let mut tao = TaoStepper::new(scheme, 2);
                let mut advance = |s: &mut [f64; 8]| tao.step_extended(&sys, 0.0, H, s);
                let [q1, q2, p1, p2] = z;
                symplectic_defect(&jacobian(&mut advance, [q1, q2, p1, p2, q1 + 0.01, q2, p1, p2 - 0.02]))
            } else {
                let mut stepper = stepper(method);
                let mut advance = |z: &mut [f64; 4]| stepper.step(&sys, 0.0, H, z).unwrap();
                symplectic_defect(&jacobian(&mut advance, z))
            };
            eprintln!("{} at {z:?}: defect {defect:.2e}", method.name);
            assert!(defect < 1e-12, "{} at {z:?}: {defect:e}", method.name);
        }
        checked += 1;
    }
    assert!(checked >= 7, "{checked}");
}

/// The same test fails for a non-symplectic method: it can tell the difference.
#[test]
fn ref_explicit_euler_is_not_symplectic() {
    let sys = form();
    let Scheme::ExplicitRk(tableau) = EULER.scheme else { unreachable!() };
    let mut stepper = ExplicitRk::new(tableau, 4);
    let mut advance = |z: &mut [f64; 4]| stepper.step(&sys, 0.0, H, z).unwrap();
    let defect = symplectic_defect(&jacobian(&mut advance, STATES[0]));
    assert!(defect > 1e-6, "{defect:e}");
}

/// Symmetric methods retrace their steps: Φ₋ₕ ∘ Φₕ = id up to round-off — on the double
/// pendulum, or for methods that need a separable H on a separable two-degree-of-freedom
/// system (two uncoupled pendulums).
#[test]
fn symmetric_methods_are_time_reversible() {
    let double = form();
    let two = TwoPendulums;
    for method in METHODS.iter().filter(|m| m.symmetric) {
        let sys: &dyn Hamiltonian = if method.requirement == Requirement::Separable { &two } else { &double };
        let mut stepper = stepper(method);
        for z0 in STATES {
            let mut z = z0;
            for k in 0..100 {
                stepper.step(sys, k as f64 * H, H, &mut z).unwrap();
            }
            for k in (1..=100).rev() {
                stepper.step(sys, k as f64 * H, -H, &mut z).unwrap();
            }
            let back = z.iter().zip(&z0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(back < 1e-12, "{}: {back:e}", method.name);
        }
    }
}

/// Two uncoupled unit pendulums: H = (p₁² + p₂²)/2 − g (cos q₁ + cos q₂), separable.
struct TwoPendulums;

impl pendula::system::System for TwoPendulums {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
        pendula::system::hamilton_rhs(self, t, y, dydt);
    }
}

impl Hamiltonian for TwoPendulums {
    fn dh_dq(&self, _t: f64, q: &[f64], _p: &[f64], out: &mut [f64]) {
        out[0] = 9.81 * q[0].sin();
        out[1] = 9.81 * q[1].sin();
    }
    fn dh_dp(&self, _t: f64, _q: &[f64], p: &[f64], out: &mut [f64]) {
        out.copy_from_slice(p);
    }
    fn separable(&self) -> bool {
        true
    }
}
