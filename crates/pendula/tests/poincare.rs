//! Poincaré sections: starts on the energy surface, crossings on the section with the right
//! direction and energy, two independent integrators agreeing on them, periodic angle
//! sections, determinism across thread counts, and refusals.

use pendula::analysis::poincare::{PoincareSpec, Stepping, energy_surface_states, poincare};
use pendula::control::Tolerances;
use pendula::events::{EventLocator, EventSpec};
use pendula::integrator::embedded::DOP853;
use pendula::integrator::gauss_legendre::GAUSS_LEGENDRE_4;
use pendula::{End, RunSpec};

use crate::support::values;

fn spec(count: usize) -> PoincareSpec {
    PoincareSpec { energy: -15.0, count, section: 0, value: 0.0, t_end: 60.0 }
}

fn tight() -> Stepping {
    Stepping::Adaptive(Tolerances { rtol: 1e-11, atol: 1e-11, h_min: 0.0, h_max: f64::INFINITY })
}

#[test]
fn starts_lie_on_the_energy_surface_and_cross_upwards() {
    for (system, settings, section) in
        [("double", vec![("m2", 0.7), ("l1", 1.3)], 0), ("chain", vec![("links", 2.0), ("m1", 2.0)], 1)]
    {
        let model = values(system, &settings).build();
        let spec = PoincareSpec { section, value: 0.3, ..spec(50) };
        let states = energy_surface_states(&*model, &spec).unwrap();
        assert_eq!(states.len(), 50);
        for y in &states {
            assert!(
                (model.energy(0.0, y) - spec.energy).abs() < 1e-12 * 30.0,
                "{system}: E = {}",
                model.energy(0.0, y)
            );
            assert_eq!(y[section], 0.3);
            assert!(y[2 + section] > 0.0, "{system}: the section angle must increase");
        }
    }
}

#[test]
fn crossings_are_on_the_section_with_the_energy() {
    let model = values("double", &[]).build();
    let orbits = poincare(&*model, &DOP853, tight(), &spec(6)).unwrap();
    let mut n = 0;
    for o in &orbits {
        for z in &o.crossings {
            let mut y = [0.0; 4];
            model.to_velocities(z, &mut y);
            assert!(y[0].sin().abs() < 1e-9 && y[0].cos() > 0.0, "θ₁ = {}", y[0]);
            assert!(y[2] > 0.0, "θ̇₁ = {} must be > 0", y[2]);
            assert!((model.energy(0.0, &y) + 15.0).abs() < 1e-7, "E = {}", model.energy(0.0, &y));
            n += 1;
        }
    }
    assert!(n > 6 * 20, "{n} crossings");
}

#[test]
fn dop853_and_gauss_legendre_agree_on_the_crossings() {
    let model = values("double", &[]).build();
    let short = PoincareSpec { t_end: 10.0, ..spec(3) };
    let a = poincare(&*model, &DOP853, tight(), &short).unwrap();
    let b = poincare(&*model, &GAUSS_LEGENDRE_4, Stepping::Fixed(1e-3), &short).unwrap();
    for (oa, ob) in a.iter().zip(&b) {
        assert_eq!(oa.initial, ob.initial);
        assert_eq!(oa.t.len(), ob.t.len());
        for (za, zb) in oa.crossings.iter().zip(&ob.crossings) {
            let d = za.iter().zip(zb).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
            assert!(d < 1e-6, "crossings differ by {d:e}");
        }
    }
}

#[test]
fn same_orbits_on_one_and_two_threads() {
    let model = values("double", &[]).build();
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| poincare(&*model, &DOP853, tight(), &spec(5)).unwrap())
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn angle_sections_repeat_every_two_pi() {
    // A rotating pendulum passes θ = 0 (mod 2π) once per revolution, always upwards.
    let v = values("pendulum", &[("theta", 0.0), ("omega", 8.0)]);
    let model = v.build();
    let event = EventSpec::parse("section:theta=0+", &*model, false).unwrap();
    let mut locator = EventLocator::new(&*model, vec![event]);
    let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Time(20.0) };
    model.solve(&GAUSS_LEGENDRE_4, v.initial_state(), &spec, &mut locator).unwrap();
    let t: Vec<f64> = locator.found.iter().map(|e| e.t).collect();
    assert!(t.len() > 10, "{} crossings", t.len());
    let period = t[1] - t[0];
    for w in t.windows(2) {
        assert!((w[1] - w[0] - period).abs() < 1e-9, "revolution {} vs {period}", w[1] - w[0]);
    }
    for e in &locator.found {
        assert!(e.state[0].sin().abs() < 1e-9 && e.state[0].cos() > 0.0);
    }
}

#[test]
fn refuses_what_has_no_energy_surface() {
    let damped = values("double", &[("damping", 0.1)]).build();
    let err = energy_surface_states(&*damped, &spec(3)).unwrap_err();
    assert!(err.to_string().contains("damping"), "{err}");
    let driven = values("double", &[("drive_amplitude", 1.0)]).build();
    assert!(energy_surface_states(&*driven, &spec(3)).unwrap_err().to_string().contains("driven"));
    let pendulum = values("pendulum", &[]).build();
    assert!(energy_surface_states(&*pendulum, &spec(3)).is_err());
    let double = values("double", &[]).build();
    let low = PoincareSpec { energy: -40.0, ..spec(3) };
    assert!(energy_surface_states(&*double, &low).unwrap_err().to_string().contains("energy"));
}
