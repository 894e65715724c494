//! Damping and drive on the double pendulum: the energy balance dE/dt = Q · ω (the power of
//! the generalized forces, a closed form), the Hamiltonian form of the driven pendulum, and
//! the ensemble paths that must refuse what they do not implement.

use pendula::ensemble::engine::{LaneMethod, LaneSpec};
use pendula::ensemble::{self, Member, MemberResult};
use pendula::integrator::explicit_rk::RK4;
use pendula::observe::Recorder;
use pendula::system::double::DoublePendulum;
use pendula::system::{Energy, Hamiltonian, Model, System};
use pendula::{End, RunSpec};

fn forced() -> DoublePendulum {
    DoublePendulum {
        m1: 1.3,
        m2: 0.7,
        l1: 0.9,
        l2: 1.2,
        g: 9.81,
        damping: 0.15,
        drive_amplitude: 2.5,
        drive_frequency: 1.7,
    }
}

#[test]
fn ref_energy_change_equals_work_of_friction_and_drive() {
    let p = forced();
    let h = 1e-4;
    let mut rec = Recorder::default();
    let spec = RunSpec { t0: 0.0, h, end: End::Time(5.0) };
    pendula::solve(&p, &RK4, &[2.0, -0.5, 0.3, -1.0], &spec, &mut rec).unwrap();
    let rows: Vec<&[f64]> = rec.rows.chunks(5).collect();
    let power = |r: &[f64]| {
        let q = p.generalized_forces(r[0], r[3], r[4]);
        q[0] * r[3] + q[1] * r[4]
    };
    // Trapezoidal rule on the RK4 samples: error O(h²) ≈ 1e-8 relative.
    let work: f64 = rows.windows(2).map(|w| 0.5 * (w[1][0] - w[0][0]) * (power(w[0]) + power(w[1]))).sum();
    let (first, last) = (rows[0], rows[rows.len() - 1]);
    let change = p.energy(last[0], &last[1..]) - p.energy(first[0], &first[1..]);
    assert!(change.abs() > 1.0, "the forcing must do visible work, got {change} J");
    assert!((change - work).abs() < 1e-6 * work.abs().max(1.0), "ΔE = {change} J, ∫Q·ω dt = {work} J");
}

#[test]
fn damping_alone_only_removes_energy() {
    let p = DoublePendulum { damping: 0.3, drive_amplitude: 0.0, ..forced() };
    let mut rec = Recorder::default();
    let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Time(20.0) };
    pendula::solve(&p, &RK4, &[2.0, -0.5, 0.0, 0.0], &spec, &mut rec).unwrap();
    let e: Vec<f64> = rec.rows.chunks(5).map(|r| p.energy(r[0], &r[1..])).collect();
    // dE/dt = −b (ω₁² + (ω₂ − ω₁)²) ≤ 0: no step may gain more than round-off.
    assert!(e.windows(2).all(|w| w[1] <= w[0] + 1e-12), "energy rose somewhere");
    assert!(e[e.len() - 1] < e[0] - 1.0, "damping must remove energy: {} → {}", e[0], e[e.len() - 1]);
}

#[test]
fn driven_hamiltonian_form_gives_the_lagrangian_equations() {
    let p = DoublePendulum { damping: 0.0, ..forced() };
    let form = p.hamiltonian_form().unwrap();
    for (t, y) in [(0.3, [0.4, -1.2, 0.7, 2.1]), (2.9, [2.5, 1.0, -3.0, 0.2])] {
        let mut z = [0.0; 4];
        p.to_momenta(&y, &mut z);
        let (mut dy, mut dz) = ([0.0; 4], [0.0; 4]);
        p.rhs(t, &y, &mut dy);
        form.rhs(t, &z, &mut dz);
        // ṗ = d/dt (M θ̇) = M θ̈ + Ṁ θ̇, checked through a small time step of both forms.
        let eps = 1e-6;
        let y2: Vec<f64> = y.iter().zip(&dy).map(|(a, b)| a + eps * b).collect();
        let mut z2 = [0.0; 4];
        p.to_momenta(&y2, &mut z2);
        for k in 2..4 {
            let fd = (z2[k] - z[k]) / eps;
            assert!((fd - dz[k]).abs() < 1e-4 * (1.0 + dz[k].abs()), "p{} rate {fd} vs {}", k - 1, dz[k]);
        }
        let mut w = [0.0; 2];
        form.dh_dp(t, &z[..2], &z[2..], &mut w);
        assert!((w[0] - y[2]).abs() < 1e-12 && (w[1] - y[3]).abs() < 1e-12);
    }
    let damped = DoublePendulum { damping: 0.1, ..forced() };
    assert!(damped.hamiltonian_form().unwrap_err().contains("damping = 0.1"));
}

/// RK4 on lanes runs damped and driven pendulums (the double pendulum's one set of
/// equations has the forces, issue 13); Tao's lanes run the driven one (its Hamiltonian
/// depends on time) and refuse the damped one, naming it; the single-trajectory fast path
/// refuses both.
#[test]
fn ensemble_paths_run_or_refuse_forced_pendulums() {
    let free = Member { pendulum: DoublePendulum::default(), state: [1.0, 0.5, 0.0, 0.0] };
    let mut members = vec![free; 40];
    members[21].pendulum.damping = 0.2;
    members[30].pendulum.drive_amplitude = 2.0;
    members[30].pendulum.drive_frequency = 3.0;
    let spec = LaneSpec {
        method: LaneMethod::of(&RK4).unwrap(),
        h: 0.01,
        steps: 10,
        stop_at_flip: false,
        track_flips: false,
        cancel: None,
    };
    let mut out = vec![MemberResult { state: [0.0; 4], flip_time: f64::NAN }; members.len()];
    ensemble::run(&members, &spec, &mut out).unwrap();
    let run = RunSpec { t0: 0.0, h: 0.01, end: End::Steps(10) };
    let spec_steps = run;
    for i in [0, 21, 30] {
        let m = members[i];
        let reference =
            pendula::solve(&m.pendulum, &RK4, &m.state, &run, &mut Recorder::default()).unwrap().state;
        let diff = out[i].state.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(diff < 1e-12, "member {i}: {:?} against {reference:?}", out[i].state);
    }
    assert_ne!(out[21].state, out[0].state, "the damping acts");
    assert_ne!(out[30].state, out[0].state, "the drive acts");
    // Tao's lanes integrate the Hamiltonian, driven or not: the damped member has none and
    // is refused, named, before any step; without it the driven member runs, as the scalar
    // tao-2 runs it.
    let scheme = pendula::integrator::tao::TaoScheme { weights: &[1.0], binding: 100.0 };
    let tao =
        LaneSpec { method: LaneMethod::Tao { method: &pendula::integrator::tao::TAO_2, scheme }, ..spec };
    let refused = ensemble::run(&members, &tao, &mut out).unwrap_err();
    assert!(
        matches!(&refused, pendula::Error::UnmetRequirement { reason, .. }
            if reason.starts_with("member 21: ") && reason.contains("damping = 0.2")),
        "{refused}"
    );
    members[21].pendulum.damping = 0.0;
    ensemble::run(&members, &tao, &mut out).unwrap();
    let tao2 = pendula::integrator::tao::TAO_2.with_binding(100.0).unwrap();
    let m = members[30];
    let reference =
        pendula::solve(&m.pendulum, &tao2, &m.state, &run, &mut Recorder::default()).unwrap().state;
    let diff = out[30].state.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(diff < 1e-12, "driven member on tao lanes: {:?} against {reference:?}", out[30].state);
    assert_ne!(out[30].state, out[0].state, "the drive acts on Tao's lanes");

    // The fast path of a single run (the engine's one lane) runs forced pendulums too: the
    // same bits as their lanes in the RK4 ensemble above.
    let rk4 = LaneMethod::of(&RK4).unwrap();
    for i in [21, 30] {
        let m = members[i];
        let spec = LaneSpec {
            method: rk4,
            h: 0.01,
            steps: 10,
            stop_at_flip: false,
            track_flips: false,
            cancel: None,
        };
        let mut lanes = [MemberResult { state: [0.0; 4], flip_time: f64::NAN }];
        ensemble::run(&[m], &spec, &mut lanes).unwrap();
        let one = pendula::ensemble::engine::solve_one(
            &m.pendulum,
            rk4,
            &m.state,
            &spec_steps,
            &mut Recorder::default(),
        )
        .unwrap()
        .state;
        assert_eq!(one, lanes[0].state, "member {i}");
    }
}

#[test]
fn damped_jacobian_matches_central_differences() {
    let p = forced();
    let (t, y) = (0.7, [0.4, -1.2, 0.7, 2.1]);
    let mut jac = [0.0; 16];
    assert!(p.jacobian(t, &y, &mut jac));
    for j in 0..4 {
        let eps = 1e-6;
        let (mut up, mut down) = (y, y);
        up[j] += eps;
        down[j] -= eps;
        let (mut fu, mut fd) = ([0.0; 4], [0.0; 4]);
        p.rhs(t, &up, &mut fu);
        p.rhs(t, &down, &mut fd);
        for i in 0..4 {
            let numeric = (fu[i] - fd[i]) / (2.0 * eps);
            assert!((numeric - jac[i * 4 + j]).abs() < 1e-6, "J[{i}][{j}] = {} vs {numeric}", jac[i * 4 + j]);
        }
    }
}
