//! The double pendulum's formulations agree: its accelerations satisfy the Euler–Lagrange
//! equations of the Lagrangian (47) (by finite differences), the Hamiltonian gradient
//! matches finite differences of H, Hamilton's equations are the Lagrangian equations
//! mapped through p = M(θ) ω, and both forms integrate to the same motion.

use pendula::integrator::Scheme;
use pendula::integrator::explicit_rk::{ExplicitRk, RK4};
use pendula::observe::Ignore;
use pendula::system::double::DoublePendulum;
use pendula::system::{Energy, Hamiltonian, Model, System};
use pendula::{End, RunSpec, Simulation};
use proptest::prelude::*;

fn pendulum() -> impl Strategy<Value = DoublePendulum> {
    (0.2..5.0, 0.2..5.0, 0.2..3.0, 0.2..3.0, 1.0..20.0).prop_map(|(m1, m2, l1, l2, g)| DoublePendulum {
        m1,
        m2,
        l1,
        l2,
        g,
        ..Default::default()
    })
}

fn state() -> impl Strategy<Value = [f64; 4]> {
    (-4.0..4.0, -4.0..4.0, -5.0..5.0, -5.0..5.0).prop_map(|(a, b, c, d)| [a, b, c, d])
}

/// ∂f/∂x_i at x by central differences.
fn partial(f: &dyn Fn(&[f64; 4]) -> f64, x: &[f64; 4], i: usize, e: f64) -> f64 {
    let (mut p, mut m) = (*x, *x);
    p[i] += e;
    m[i] -= e;
    (f(&p) - f(&m)) / (2.0 * e)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// d/dt ∂L/∂ωᵢ − ∂L/∂θᵢ = 0 with θ'' from `rhs`, every derivative of L by finite
    /// differences: d/dt ∂L/∂ωᵢ = Σⱼ ∂²L/∂ωᵢ∂θⱼ ωⱼ + Σⱼ ∂²L/∂ωᵢ∂ωⱼ θ''ⱼ.
    #[test]
    fn ref_accelerations_satisfy_euler_lagrange(sys in pendulum(), y in state()) {
        let lag = |y: &[f64; 4]| sys.lagrangian(y);
        let mut f = [0.0; 4];
        sys.rhs(0.0, &y, &mut f);
        let e = 1e-4;
        for i in 0..2 {
            let dl_dw = |x: &[f64; 4]| partial(&lag, x, 2 + i, e);
            let mut ddt = 0.0;
            for j in 0..2 {
                ddt += partial(&dl_dw, &y, j, e) * y[2 + j] + partial(&dl_dw, &y, 2 + j, e) * f[2 + j];
            }
            let residual = ddt - partial(&lag, &y, i, e);
            let scale = sys.energy(0.0, &y).abs() + (sys.m1 + sys.m2) * sys.g * (sys.l1 + sys.l2);
            prop_assert!(residual.abs() < 1e-5 * scale, "residual {residual} (scale {scale})");
        }
    }

    /// ∂H/∂q and ∂H/∂p ((87), (88), (108), (109)) against finite differences of H (94).
    #[test]
    fn ref_hamiltonian_gradient_matches_h(sys in pendulum(), z in state()) {
        let form = sys.form();
        let h = |z: &[f64; 4]| form.energy(0.0, z);
        let (mut dq, mut dp) = ([0.0; 2], [0.0; 2]);
        form.dh_dq(0.0, &z[..2], &z[2..], &mut dq);
        form.dh_dp(0.0, &z[..2], &z[2..], &mut dp);
        let scale = 1.0 + dq.iter().chain(&dp).map(|v| v.abs()).fold(0.0, f64::max);
        for i in 0..2 {
            prop_assert!((partial(&h, &z, i, 1e-6) - dq[i]).abs() < 1e-7 * scale);
            prop_assert!((partial(&h, &z, 2 + i, 1e-6) - dp[i]).abs() < 1e-7 * scale);
        }
    }

    /// Hamilton's ṗ equals d/dt (M(θ) ω) along the Lagrangian flow, and θ̇ = ∂H/∂p = ω.
    #[test]
    fn ref_hamilton_equations_are_the_lagrangian_ones(sys in pendulum(), y in state()) {
        let form = sys.form();
        let mut z = [0.0; 4];
        sys.to_momenta(&y, &mut z);
        let (mut fy, mut fz) = ([0.0; 4], [0.0; 4]);
        sys.rhs(0.0, &y, &mut fy);
        form.rhs(0.0, &z, &mut fz);
        let e = 1e-5;
        let along = |s: f64| {
            let mut x = [0.0; 4];
            for k in 0..4 { x[k] = y[k] + s * fy[k]; }
            sys.momenta(&x)
        };
        let (pp, pm) = (along(e), along(-e));
        let scale = 1.0 + fz.iter().map(|v| v.abs()).fold(0.0, f64::max);
        for i in 0..2 {
            prop_assert!((fz[i] - y[2 + i]).abs() < 1e-12 * scale);
            prop_assert!(((pp[i] - pm[i]) / (2.0 * e) - fz[2 + i]).abs() < 1e-6 * scale);
        }
    }
}

/// RK4 on (θ, ω) and on (θ, p) over 10 s, from a regular (non-chaotic) state at a step small
/// enough that the two discretizations differ by less than 1e-12.
#[test]
fn ref_lagrangian_and_hamiltonian_forms_agree_over_10_s() {
    let sys = DoublePendulum { m1: 1.0, m2: 1.0, l1: 1.0, l2: 1.0, g: 9.81, ..Default::default() };
    let form = sys.form();
    let Scheme::ExplicitRk(tableau) = RK4.scheme else { unreachable!() };
    let spec = RunSpec { t0: 0.0, h: 2e-4, end: End::Time(10.0) };
    let mut y = [0.5, -0.3, 0.0, 0.0];
    let mut z = [0.0; 4];
    sys.to_momenta(&y, &mut z);
    Simulation { system: &sys, spec }.run(&mut ExplicitRk::new(tableau, 4), &mut y, &mut Ignore).unwrap();
    Simulation { system: &form, spec }.run(&mut ExplicitRk::new(tableau, 4), &mut z, &mut Ignore).unwrap();
    let mut back = [0.0; 4];
    sys.to_velocities(&z, &mut back);
    let diff = y.iter().zip(&back).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    eprintln!("Lagrangian vs Hamiltonian after 10 s: {diff:.2e}");
    assert!(diff < 2e-12, "{diff:e}");
}

/// `auto` picks an explicit symplectic method where the system has a Hamiltonian form
/// (yoshida-4 separable, tao-4 not), and dop853 for a damped system.
#[test]
fn auto_picks_a_symplectic_method_where_there_is_a_hamiltonian() {
    use pendula::model::auto_method;
    let pick =
        |system, set: &[(&str, f64)]| auto_method(&*crate::support::values(system, set).build()).0.name;
    assert_eq!(pick("pendulum", &[]), "yoshida-4");
    assert_eq!(pick("double", &[]), "tao-4");
    assert_eq!(pick("pendulum", &[("damping", 0.1)]), "dop853");
}

/// Without methods named, a study runs those that apply: Tao's maps only at steps up to
/// their limit 1/ω (5 ms at ω = 200 1/s), the others at any step.
#[test]
fn applicable_methods_keep_taos_maps_only_within_their_step_limit() {
    use pendula::integrator::METHODS;
    use pendula::model::applicable;
    let model = crate::support::values("double", &[]).build();
    let names = |max_h| applicable(&*model, METHODS, max_h).iter().map(|m| m.name).collect::<Vec<_>>();
    assert!(names(None).contains(&"tao-4") && names(Some(0.005)).contains(&"tao-4"));
    let coarse = names(Some(0.01));
    assert!(
        !coarse.contains(&"tao-4") && !coarse.contains(&"tao-2") && coarse.contains(&"rk4"),
        "{coarse:?}"
    );
}
