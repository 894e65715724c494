//! The flip fractal: its two resolutions against independent ensemble runs of every pixel
//! (the energy shortcut included), its convergence flag against the rule, and bitwise
//! determinism across thread counts.

use pendula::analysis::fractal::{FractalSpec, GridAxis, cannot_flip, converged, flip_fractal};
use pendula::ensemble::engine::{LaneMethod, LaneSpec};
use pendula::ensemble::{self, Member, MemberResult};
use pendula::system::double::DoublePendulum;

fn spec() -> FractalSpec {
    let axis = |n| GridAxis { lo: -std::f64::consts::PI, hi: std::f64::consts::PI, n };
    FractalSpec {
        pendulum: DoublePendulum::default(),
        theta1: axis(40),
        theta2: axis(30),
        t_max: 15.0,
        h: 0.01,
        method: LaneMethod::of(&pendula::integrator::explicit_rk::RK4).unwrap(),
        tolerance: 0.01,
    }
}

/// Flip times of every pixel (none skipped) straight from the ensemble engine.
fn independent(spec: &FractalSpec, h: f64) -> Vec<f64> {
    let (n1, n2) = (spec.theta1.n, spec.theta2.n);
    let members: Vec<Member> = (0..n1 * n2)
        .map(|i| Member {
            pendulum: spec.pendulum,
            state: [spec.theta1.centre(i % n1), spec.theta2.centre(i / n1), 0.0, 0.0],
        })
        .collect();
    let batch = LaneSpec {
        method: spec.method,
        h,
        steps: (spec.t_max / h).ceil() as u64,
        stop_at_flip: true,
        track_flips: true,
        cancel: None,
    };
    let mut out = vec![MemberResult { state: [0.0; 4], flip_time: f64::NAN }; members.len()];
    ensemble::run(&members, &batch, &mut out).unwrap();
    out.iter().map(|r| if r.flip_time <= spec.t_max { r.flip_time } else { f64::NAN }).collect()
}

fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
}

#[test]
fn both_resolutions_and_the_flags_match_independent_runs() {
    let spec = spec();
    let f = flip_fractal(&spec).unwrap();
    let (coarse, fine) = (independent(&spec, spec.h), independent(&spec, spec.h / 2.0));
    assert!(same(&f.flip_time, &coarse), "step h differs from a full ensemble run");
    assert!(same(&f.flip_time_half_step, &fine), "step h/2 differs from a full ensemble run");
    let mut flagged = 0;
    for i in 0..coarse.len() {
        let moved = coarse[i].is_nan() != fine[i].is_nan()
            || (coarse[i].is_finite() && (coarse[i] - fine[i]).abs() > spec.tolerance);
        assert_eq!(f.converged[i], !moved, "pixel {i}: {} vs {}", coarse[i], fine[i]);
        flagged += usize::from(moved);
    }
    // The check must be able to fail: some pixels do move at these steps, most do not.
    assert!(flagged > 0 && flagged < coarse.len() / 4, "{flagged} of {} flagged", coarse.len());
    assert!(f.forbidden > 0);
}

#[test]
fn energy_bound_is_heyls_for_equal_pendulums() {
    // For m₁ = m₂, l₁ = l₂ no flip is possible from rest when 2 cos θ₁ + cos θ₂ > 1.
    let p = DoublePendulum::default();
    for i in 0..100 {
        for j in 0..100 {
            let (a, b) = (-3.1 + 0.062 * i as f64, -3.1 + 0.062 * j as f64);
            let heyl = 2.0 * a.cos() + b.cos() > 1.0;
            if (2.0 * a.cos() + b.cos() - 1.0).abs() > 1e-12 {
                assert_eq!(cannot_flip(&p, a, b), heyl, "({a}, {b})");
            }
        }
    }
    assert!(
        converged(f64::NAN, f64::NAN, 0.0) && !converged(1.0, f64::NAN, 1.0) && converged(1.0, 1.005, 0.01)
    );
}

#[test]
fn bitwise_identical_on_one_and_two_threads() {
    let spec = spec();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| flip_fractal(&spec).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert!(same(&a.flip_time, &b.flip_time) && same(&a.flip_time_half_step, &b.flip_time_half_step));
    assert_eq!(a.converged, b.converged);
}

/// Computed in ranges of pixels (as a checkpointed `fractal` computes its chunks, of uneven
/// sizes that split lane groups), the flip times and the assembled fractal are bitwise those
/// of the fractal computed at once.
#[test]
fn ranges_of_pixels_give_the_same_bits() {
    use pendula::analysis::fractal::{assemble, flip_times};
    let spec = spec();
    let whole = flip_fractal(&spec).unwrap();
    let pixels = spec.theta1.n * spec.theta2.n;
    let (mut at_h, mut at_half) = (Vec::new(), Vec::new());
    let mut start = 0;
    for len in [1, 37, 250, 5].into_iter().cycle() {
        let end = (start + len).min(pixels);
        let (a, b) = flip_times(&spec, start..end, &|_| ()).unwrap();
        at_h.extend(a);
        at_half.extend(b);
        start = end;
        if start == pixels {
            break;
        }
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&at_h), bits(&whole.flip_time));
    assert_eq!(bits(&at_half), bits(&whole.flip_time_half_step));
    let parts = assemble(&spec, at_h, at_half);
    assert_eq!(parts.converged, whole.converged);
    assert_eq!(parts.forbidden, whole.forbidden);
}
