//! Jacobians and the implicit methods' Newton iteration: every system's Jacobian (analytic,
//! or by num-dual for the double pendulum) matches finite differences of its right-hand
//! side; Gauss–Legendre solves its stages by simplified Newton where a Jacobian exists, gets
//! the same step as fixed-point iteration, succeeds at steps where fixed-point iteration
//! diverges, falls back to it without a Jacobian, and fails with a clear error when neither
//! converges.

use pendula::Error;
use pendula::integrator::Stepper;
use pendula::integrator::gauss_legendre::{
    Collocation, GAUSS_LEGENDRE_2, GAUSS_LEGENDRE_4, GAUSS_LEGENDRE_6, ImplicitTableau, Solver,
};
use pendula::integrator::{Method, Scheme};
use pendula::system::double::DoublePendulum;
use pendula::system::oscillator::Oscillator;
use pendula::system::pendulum::Pendulum;
use pendula::system::{Model, System};
use proptest::prelude::*;

use crate::support::values;

/// ∂f/∂y by central differences with step 1e-6 (error ~1e-10 here).
fn finite_difference_jacobian(system: &dyn System, t: f64, y: &[f64]) -> Vec<f64> {
    let n = y.len();
    let mut jac = vec![0.0; n * n];
    let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
    for col in 0..n {
        let e = 1e-6 * (1.0 + y[col].abs());
        let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
        yp[col] += e;
        ym[col] -= e;
        system.rhs(t, &yp, &mut plus);
        system.rhs(t, &ym, &mut minus);
        for row in 0..n {
            jac[row * n + col] = (plus[row] - minus[row]) / (2.0 * e);
        }
    }
    jac
}

fn check_jacobian(name: &str, system: &dyn System, t: f64, y: &[f64]) {
    let n = y.len();
    let mut jac = vec![0.0; n * n];
    assert!(system.jacobian(t, y, &mut jac), "{name} has a Jacobian");
    let fd = finite_difference_jacobian(system, t, y);
    for (k, (a, b)) in jac.iter().zip(&fd).enumerate() {
        assert!((a - b).abs() <= 1e-6 * (1.0 + b.abs()), "{name} at {y:?}: entry {k}: {a} vs {b}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn double_pendulum_jacobians_match_finite_differences(
        (m1, m2, l1, l2, g) in (0.2..5.0, 0.2..5.0, 0.2..3.0, 0.2..3.0, 1.0..20.0),
        y in (-4.0..4.0, -4.0..4.0, -5.0..5.0, -5.0..5.0),
    ) {
        let model = DoublePendulum { m1, m2, l1, l2, g, ..Default::default() };
        let y = [y.0, y.1, y.2, y.3];
        check_jacobian("double", &model, 0.0, &y);
        check_jacobian("double (Hamiltonian form)", &model.form(), 0.0, &y);
    }
}

#[test]
fn oscillator_and_pendulum_jacobians_match_finite_differences() {
    let osc = values("oscillator", &[("c", 0.3), ("k", 2.0), ("m", 0.7)]);
    let o = Oscillator::from_values(&osc);
    check_jacobian("oscillator", &o, 0.3, &[0.4, -1.2]);
    check_jacobian(
        "oscillator (Hamiltonian form)",
        &Oscillator::from_values(&values("oscillator", &[])).hamiltonian_form().unwrap(),
        0.3,
        &[0.4, -1.2],
    );
    for linear in [0.0, 1.0] {
        let p = Pendulum::from_values(&values("pendulum", &[("l", 0.8), ("linear", linear)]));
        check_jacobian("pendulum", &p, 0.0, &[2.5, 1.0]);
        check_jacobian("pendulum (Hamiltonian form)", &p.hamiltonian_form().unwrap(), 0.0, &[2.5, 1.0]);
        let damped = Pendulum::from_values(&values("pendulum", &[("damping", 0.4), ("linear", linear)]));
        check_jacobian("damped pendulum", &damped, 0.0, &[2.5, 1.0]);
    }
}

fn tableau(method: &Method) -> &'static ImplicitTableau {
    let Scheme::Collocation(t) = method.scheme else { unreachable!() };
    t
}

/// On the double pendulum's (θ, p) form at h = 0.01, Newton converges in a few iterations
/// and gives the fixed-point step to round-off.
#[test]
fn newton_and_fixed_point_agree() {
    let form = DoublePendulum::from_values(&values("double", &[])).form();
    let z0 = [2.0, -0.2, 0.3, -0.5];
    for method in [&GAUSS_LEGENDRE_2, &GAUSS_LEGENDRE_4, &GAUSS_LEGENDRE_6] {
        let (mut newton, mut fixed) = (z0, z0);
        let mut a = Collocation::new(tableau(method), 4);
        let mut b = Collocation::fixed_point_only(tableau(method), 4);
        a.step(&form, 0.0, 0.01, &mut newton).unwrap();
        b.step(&form, 0.0, 0.01, &mut fixed).unwrap();
        let Some(Solver::SimplifiedNewton(k)) = a.last_solver else { panic!("{:?}", a.last_solver) };
        let Some(Solver::FixedPoint(m)) = b.last_solver else { panic!("{:?}", b.last_solver) };
        let diff = newton.iter().zip(&fixed).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        eprintln!("{}: Newton {k} iterations, fixed point {m}, difference {diff:.1e}", method.name);
        assert!(k <= 8, "{}: {k} Newton iterations", method.name);
        assert!(diff < 1e-14, "{}: {diff}", method.name);
    }
}

/// A stiff oscillator (ω = 100 rad/s) at h = 0.1 s, hω = 10: the fixed-point iteration
/// diverges (it needs h ω ρ(A) < 1); Newton converges, and the step is right: Gauss methods
/// conserve quadratic invariants exactly, so the energy holds to round-off, and the step
/// back with −h returns to the start.
#[test]
fn newton_converges_where_fixed_point_iteration_diverges() {
    let osc = Oscillator::from_values(&values("oscillator", &[("k", 1e4), ("m", 1.0)]));
    let form = osc.hamiltonian_form().unwrap();
    let z = [0.3, 20.0];
    let energy = |z: &[f64]| pendula::system::Energy::energy(&form, 0.0, z);
    for method in [&GAUSS_LEGENDRE_2, &GAUSS_LEGENDRE_4, &GAUSS_LEGENDRE_6] {
        let h = 0.1;
        let mut fixed = z;
        let err =
            Collocation::fixed_point_only(tableau(method), 2).step(&form, 0.0, h, &mut fixed).unwrap_err();
        assert!(matches!(err, Error::NewtonDidNotConverge { .. }), "{err:?}");
        let mut newton = z;
        let mut stepper = Collocation::new(tableau(method), 2);
        stepper.step(&form, 0.0, h, &mut newton).unwrap();
        let forward = stepper.last_solver;
        assert!(matches!(forward, Some(Solver::SimplifiedNewton(k)) if k <= 4), "{forward:?}");
        let de = (energy(&newton) / energy(&z) - 1.0).abs();
        let mut back = newton;
        stepper.step(&form, h, -h, &mut back).unwrap();
        let gap = back.iter().zip(&z).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        eprintln!("{}: {forward:?}, relative energy change {de:.1e}, back within {gap:.1e}", method.name);
        assert!(de < 1e-13, "{}: {de}", method.name);
        assert!(gap < 1e-12, "{}: {gap}", method.name);
    }
}

/// From a fast state of the double pendulum at h = 0.3 s, simplified Newton (Jacobian
/// frozen at the step's start) stops contracting; full Newton converges, to the right
/// solution: the step back with −h returns to the start to 1e-11.
#[test]
fn full_newton_takes_over_on_the_rotating_double_pendulum() {
    let model = DoublePendulum::from_values(&values("double", &[]));
    let form = model.form();
    let mut z = [0.0; 4];
    model.to_momenta(&[3.0, 2.5, 1.0, -2.0], &mut z);
    let mut stepper = Collocation::new(tableau(&GAUSS_LEGENDRE_4), 4);
    let mut y = z;
    stepper.step(&form, 0.0, 0.3, &mut y).unwrap();
    let forward = stepper.last_solver;
    assert!(matches!(forward, Some(Solver::Newton(_))), "{forward:?}");
    stepper.step(&form, 0.3, -0.3, &mut y).unwrap();
    let gap = y.iter().zip(&z).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    eprintln!("{forward:?} then {:?}: back within {gap:.1e}", stepper.last_solver);
    assert!(gap < 1e-11, "{gap}");
}

/// A system without a Jacobian is solved by fixed-point iteration; a step far too large for
/// either solver is an error naming the time.
#[test]
fn fixed_point_fallback_and_failure() {
    struct NoJacobian(Oscillator);
    impl System for NoJacobian {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, t: f64, y: &[f64], dydt: &mut [f64]) {
            self.0.rhs(t, y, dydt);
        }
    }
    let system = NoJacobian(Oscillator::from_values(&values("oscillator", &[])));
    let mut stepper = Collocation::new(tableau(&GAUSS_LEGENDRE_4), 2);
    let mut y = [1.0, 0.0];
    stepper.step(&system, 0.0, 0.1, &mut y).unwrap();
    assert!(matches!(stepper.last_solver, Some(Solver::FixedPoint(_))), "{:?}", stepper.last_solver);

    let form = DoublePendulum::from_values(&values("double", &[])).form();
    let mut z = [3.0, 2.5, 20.0, -20.0];
    let err = Collocation::new(tableau(&GAUSS_LEGENDRE_4), 4).step(&form, 7.0, 50.0, &mut z).unwrap_err();
    let Error::NewtonDidNotConverge { t, .. } = err else { panic!("{err:?}") };
    assert_eq!(t, 7.0);
    assert!(err.to_string().contains("t = 7 s"), "{err}");
}
