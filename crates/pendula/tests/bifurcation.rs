//! Stroboscopic sampling of the damped, driven pendulum: the ensemble kernel against the
//! scalar RK4 path, Baker and Gollub's period-1 and period-2 attractors, and determinism.

use pendula::analysis::strobe::stroboscopic as scalar;
use pendula::ensemble::driven::{DrivenMember, StroboSpec, stroboscopic};
use pendula::integrator::explicit_rk::RK4;
use pendula::model::DynModel;
use pendula::system::driven::DrivenPendulum;
use pendula::system::{Model, wrap_angle};

use crate::support::values;

fn member(g: f64, frequency: f64, transient: u64) -> DrivenMember {
    DrivenMember {
        pendulum: DrivenPendulum { q: 2.0, drive_amplitude: g, drive_frequency: frequency },
        state: [0.2, 0.0],
        transient_periods: transient,
    }
}

#[test]
fn lanes_match_the_scalar_rk4() {
    // Periodic regimes over 50 periods; chaotic ones over 3 (where round-off still is
    // below the tolerance after amplification by exp(λ t)).
    let cases =
        [(0.9, 2.0 / 3.0, 50), (1.07, 2.0 / 3.0, 50), (1.5, 2.0 / 3.0, 3), (1.2, 0.8, 3), (0.5, 1.3, 50)];
    let members: Vec<DrivenMember> = cases.iter().map(|&(g, f, _)| member(g, f, 0)).collect();
    let samples = 50;
    let spec = StroboSpec { steps_per_period: 120, samples };
    let mut out = vec![0.0; members.len() * samples * 2];
    stroboscopic(&members, &spec, &mut out).unwrap();
    for (k, (&(g, f, check), m)) in cases.iter().zip(&members).enumerate() {
        let v = values("driven-pendulum", &[("drive_amplitude", g), ("drive_frequency", f)]);
        let model = DrivenPendulum::from_values(&v);
        let rows =
            scalar(&model as &dyn DynModel, &RK4, &m.state, 2.0 * std::f64::consts::PI / f, 120, 0, samples)
                .unwrap();
        for s in 0..check {
            let (lane, row) = (&out[(k * samples + s) * 2..][..2], &rows[s * 2..][..2]);
            let d = (lane[0] - wrap_angle(row[0])).abs().max((lane[1] - row[1]).abs());
            assert!(d < 1e-10, "g = {g}, sample {s}: lanes {lane:?} vs scalar {row:?}");
        }
    }
}

#[test]
fn baker_gollub_period_one_and_period_two() {
    let members = [member(0.9, 2.0 / 3.0, 300), member(1.07, 2.0 / 3.0, 300)];
    let samples = 8;
    let mut out = vec![0.0; 2 * samples * 2];
    stroboscopic(&members, &StroboSpec { steps_per_period: 200, samples }, &mut out).unwrap();
    let omega = |k: usize, s: usize| out[(k * samples + s) * 2 + 1];
    for s in 0..samples - 1 {
        assert!((omega(0, s + 1) - omega(0, s)).abs() < 1e-6, "g = 0.9 is period 1");
    }
    for s in 0..samples - 2 {
        assert!((omega(1, s + 2) - omega(1, s)).abs() < 1e-6, "g = 1.07 repeats every 2 periods");
        assert!((omega(1, s + 1) - omega(1, s)).abs() > 1e-2, "g = 1.07 is not period 1");
    }
}

#[test]
fn same_samples_on_one_and_two_threads() {
    let members: Vec<DrivenMember> =
        (0..100).map(|i| member(1.0 + 0.005 * i as f64, 2.0 / 3.0, 20)).collect();
    let spec = StroboSpec { steps_per_period: 100, samples: 10 };
    let run = |threads| {
        let mut out = vec![0.0; 100 * 10 * 2];
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| stroboscopic(&members, &spec, &mut out).unwrap());
        out
    };
    let (a, b) = (run(1), run(2));
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
}

/// Members started beyond the sine's fast range run their first period (before the wrap into
/// [−π, π)) with the exact reduction, and their lane-group mates get the same bits as without
/// them. In the period-1 regime their samples agree with the scalar RK4 (glibc), which keeps
/// the angle unwrapped and so rounds it to ulp(θ₀) at every step: within 20 ulp(θ₀) (measured
/// 10) for θ₀ = 2e6 and −1e7 rad. At θ₀ = 1e17 both paths hold θ at 1e17 for the first period
/// (an ulp there is 16 rad), so its first sample agrees to rounding; later the scalar path
/// stays there while the lanes wrap.
#[test]
fn huge_initial_angles_take_the_exact_reduction() {
    let plain: Vec<DrivenMember> = (0..6).map(|i| member(0.9 + 0.01 * i as f64, 2.0 / 3.0, 0)).collect();
    let mut huge = plain.clone();
    let cases = [(1, 2e6), (2, -1e7), (4, 1e17)];
    for &(k, angle) in &cases {
        huge[k].state[0] = angle;
    }
    let samples = 30;
    let spec = StroboSpec { steps_per_period: 120, samples };
    let run = |members: &[DrivenMember]| {
        let mut out = vec![0.0; members.len() * samples * 2];
        stroboscopic(members, &spec, &mut out).unwrap();
        out
    };
    let (before, after) = (run(&plain), run(&huge));
    for k in [0, 3, 5] {
        let rows = k * samples * 2..(k + 1) * samples * 2;
        assert!(before[rows.clone()].iter().zip(&after[rows]).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
    for (k, angle) in cases {
        let m = &huge[k];
        let period = 2.0 * std::f64::consts::PI / m.pendulum.drive_frequency;
        let rows = scalar(&m.pendulum as &dyn DynModel, &RK4, &m.state, period, 120, 0, samples).unwrap();
        let (compared, tolerance) = if angle.abs() < 1e8 {
            (samples, 20.0 * (angle.abs().next_up() - angle.abs()))
        } else {
            (1, 1e-12)
        };
        let mut worst = 0.0_f64;
        for s in 0..compared {
            let (lane, row) = (&after[(k * samples + s) * 2..][..2], &rows[s * 2..][..2]);
            worst = worst.max((lane[0] - wrap_angle(row[0])).abs()).max((lane[1] - row[1]).abs());
        }
        eprintln!("θ₀ = {angle:e}: {worst:.2e} over {compared} samples");
        assert!(worst < tolerance, "θ₀ = {angle:e}: {worst:e} from the scalar path");
    }
}

/// A member whose angle starts small but whose speed carries it far beyond the sine's fast
/// range within its first period (ω₀ = 2e12 rad/s: θ passes 4e12 rad) is caught by the
/// kernel's bound on its arguments and its group runs again with the exact reduction: its
/// lane-group mates keep their bits, and its first sample's ω is within rounding of the scalar
/// RK4's (glibc): 64 ulp allowed, 25 measured — the engine steps each member in fractions of
/// its period, its equations scaled by the period, which rounds differently from the scalar
/// path's steps in seconds. (At these speeds the sine's error moves ω by less than its own
/// rounding: with the fast path forced, 10 to 23 ulp were measured; the exact reduction's
/// accuracy is `trig.rs`'s to test.)
#[test]
fn huge_velocities_take_the_exact_reduction() {
    let plain: Vec<DrivenMember> = (0..3).map(|i| member(0.9 + 0.01 * i as f64, 2.0 / 3.0, 0)).collect();
    let mut huge = plain.clone();
    huge[1].state[1] = 2e12;
    let samples = 3;
    let spec = StroboSpec { steps_per_period: 120, samples };
    let run = |members: &[DrivenMember]| {
        let mut out = vec![0.0; members.len() * samples * 2];
        stroboscopic(members, &spec, &mut out).unwrap();
        out
    };
    let (before, after) = (run(&plain), run(&huge));
    for k in [0, 2] {
        let rows = k * samples * 2..(k + 1) * samples * 2;
        assert!(before[rows.clone()].iter().zip(&after[rows]).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
    let m = &huge[1];
    let period = 2.0 * std::f64::consts::PI / m.pendulum.drive_frequency;
    let rows = scalar(&m.pendulum as &dyn DynModel, &RK4, &m.state, period, 120, 0, samples).unwrap();
    let (lane, row) = (after[samples * 2 + 1], rows[1]);
    let ulp = row.abs().next_up() - row.abs();
    eprintln!("ω after one period: lanes {lane:e}, scalar {row:e}: {} ulp", (lane - row).abs() / ulp);
    assert!((lane - row).abs() <= 64.0 * ulp, "lanes {lane:e}, scalar {row:e}");
}

/// Orbit diagrams of every driven system run on the engine's lanes, each value stepping its
/// own period: the driven simple pendulum, the driven oscillator and the driven double
/// pendulum agree with one scalar RK4 run per value (glibc) to 1e-10 over 5 periods.
#[test]
fn orbit_diagrams_of_every_driven_system_match_the_scalar_rk4() {
    use pendula::analysis::strobe::{OrbitDiagramSpec, orbit_diagram};
    for (system, base) in [
        ("pendulum", vec![("damping", 0.5), ("drive_amplitude", 1.2)]),
        ("oscillator", vec![("c", 0.3), ("drive_amplitude", 1.0)]),
        ("double", vec![("damping", 0.2), ("drive_amplitude", 3.0)]),
    ] {
        let all: Vec<pendula::system::Values> = (0..20)
            .map(|i| {
                let mut settings = base.clone();
                settings.push(("drive_frequency", 0.8 + 0.05 * i as f64));
                values(system, &settings)
            })
            .collect();
        let spec = OrbitDiagramSpec { transient: 3.0, samples: 5, steps_per_period: 100 };
        let lanes = orbit_diagram(&all, &spec).unwrap();
        let info = all[0].info();
        let dim = info.state.len();
        for (k, v) in all.iter().enumerate() {
            let period = 2.0 * std::f64::consts::PI / v.get("drive_frequency");
            let transient = (3.0 / period).ceil() as u64;
            let rows = scalar(&*v.build(), &RK4, v.initial_state(), period, 100, transient, 5).unwrap();
            for s in 0..5 {
                for (j, q) in info.state.iter().enumerate() {
                    let r = rows[s * dim + j];
                    let r = if q.is_angle() { wrap_angle(r) } else { r };
                    let lane = lanes[(k * 5 + s) * dim + j];
                    assert!(
                        (lane - r).abs() < 1e-10,
                        "{system} value {k} sample {s} {}: {lane} vs {r}",
                        q.name
                    );
                }
            }
        }
    }
}
