//! The exact solutions the conformance suite trusts, checked independently: the oscillator
//! against its ODE by finite differences, the pendulum against mpmath's Taylor integrator.

use pendula::system::oscillator::{Oscillator, Regime};
use pendula::system::pendulum::Pendulum;

fn oscillator(c: f64, f: f64, w: f64) -> Oscillator {
    Oscillator { m: 2.0, k: 8.0, c, drive_amplitude: f, drive_frequency: w }
}

/// The exact solution satisfies m x'' + c x' + k x = F cos(Ω t), v = x', and the initial
/// conditions, in every regime (ω₀ = 2, critical c = 8).
#[test]
fn ref_oscillator_solves_its_ode() {
    let cases = [
        (0.0, 0.0, 0.0, Regime::Undamped),
        (1.0, 0.0, 0.0, Regime::Underdamped),
        (8.0, 0.0, 0.0, Regime::CriticallyDamped),
        (20.0, 0.0, 0.0, Regime::Overdamped),
        (1.0, 3.0, 1.5, Regime::Underdamped),
        (20.0, 3.0, 2.5, Regime::Overdamped),
        (0.0, 3.0, 2.0, Regime::Undamped), // undamped resonance
        (0.0, 3.0, 0.7, Regime::Undamped),
    ];
    let (x0, v0) = (0.7, -1.1);
    for (c, f, w, regime) in cases {
        let o = oscillator(c, f, w);
        assert_eq!(o.regime(), regime);
        let (x, v) = o.exact(0.0, x0, v0);
        assert!((x - x0).abs() < 1e-15 && (v - v0).abs() < 1e-15, "c={c} f={f} w={w}");
        let e = 1e-4;
        for t in [0.3, 1.7, 4.2] {
            let (xm, _) = o.exact(t - e, x0, v0);
            let (x, v) = o.exact(t, x0, v0);
            let (xp, _) = o.exact(t + e, x0, v0);
            let dx = (xp - xm) / (2.0 * e);
            let ddx = (xp - 2.0 * x + xm) / (e * e);
            assert!((dx - v).abs() < 1e-7, "v = x' at c={c} t={t}");
            let residual = o.m * ddx + o.c * v + o.k * x - f * (w * t).cos();
            assert!(residual.abs() < 1e-5, "residual {residual} at c={c} f={f} w={w} t={t}");
        }
    }
}

/// Amplitude F/√((k − mΩ²)² + (cΩ)²) and lag π/2 at resonance, by hand.
#[test]
fn ref_oscillator_steady_state() {
    let o = oscillator(1.0, 3.0, 2.0);
    let s = o.steady_state();
    assert!((s.amplitude - 1.5).abs() < 1e-15); // F / (c Ω) = 3 / 2
    assert!((s.phase_lag - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    let far = oscillator(1.0, 3.0, 100.0).steady_state();
    assert!(far.phase_lag > 3.1 && far.phase_lag < std::f64::consts::PI);
}

const PENDULUM: Pendulum = Pendulum {
    m: 1.0,
    l: 1.0,
    g: 9.81,
    damping: 0.0,
    drive_amplitude: 0.0,
    drive_frequency: 0.0,
    linear: false,
};

/// Jacobi-function solution against mpmath.odefun (Taylor series, 30 digits): libration
/// from rest, near the top, with negative initial velocity, and rotation.
#[test]
fn ref_pendulum_exact_solution() {
    for (th0, w0, t, want) in [
        (60.0, 0.0, 1.3, [-0.83949406409888873323, 1.8146654343314863416]),
        (170.0, 0.0, 2.5, [-2.9646401419693288368, 0.09110448365875616632]),
        (30.0, -2.0, 0.7, [-0.83962745813802492483, -0.33112552074010137716]),
        (10.0, 7.0, 1.1, [5.229244143880671479, 6.2748120417297432517]),
    ] {
        let (th, w) = PENDULUM.exact(t, f64::to_radians(th0), w0).unwrap();
        assert!((th - want[0]).abs() < 1e-12, "theta0={th0}: {th} vs {}", want[0]);
        assert!((w - want[1]).abs() < 1e-12, "theta0={th0}: {w} vs {}", want[1]);
    }
}

/// 4 √(l/g) K(sin 85°) from mpmath, and the small-angle limit.
#[test]
fn ref_pendulum_period() {
    let p = PENDULUM.period(170f64.to_radians());
    assert!((p / 4.893524274105486164 - 1.0).abs() < 1e-14);
    let small = PENDULUM.period(1e-6);
    assert!((small / PENDULUM.small_angle_period() - 1.0).abs() < 1e-12);
}
