//! The ensemble engine: its RK4 lanes against the scalar RK4, flip times against located
//! events, bitwise determinism across thread counts and chunkings, and non-finite members
//! reported by index (its sine and cosine: trig.rs).

use pendula::ensemble::engine::{LaneMethod, LaneSpec};
use pendula::ensemble::{self, Member, MemberResult};
use pendula::events::{EventLocator, EventSpec};
use pendula::integrator::explicit_rk::RK4;
use pendula::system::double::DoublePendulum;
use pendula::{End, RunSpec};

use crate::support::{samples, values};

fn members() -> Vec<Member> {
    let mut out = Vec::new();
    for (i, (a, b)) in samples(21, -3.0, 3.0).zip(samples(21, -2.0, 2.5).skip(3)).enumerate() {
        let pendulum = DoublePendulum {
            m1: 1.0,
            m2: 0.5 + 0.1 * i as f64,
            l1: 1.0,
            l2: 0.7,
            g: 9.81,
            ..Default::default()
        };
        out.push(Member { pendulum, state: [a, b, 0.1 * i as f64 - 1.0, 0.3] });
    }
    out
}

/// RK4 as the lanes run it.
fn rk4() -> LaneMethod {
    LaneMethod::of(&RK4).unwrap()
}

fn run(members: &[Member], steps: u64, stop_at_flip: bool) -> Vec<MemberResult> {
    let spec = LaneSpec { method: rk4(), h: 0.01, steps, stop_at_flip, track_flips: true, cancel: None };
    let mut out = vec![MemberResult { state: [0.0; 4], flip_time: 0.0 }; members.len()];
    ensemble::run(members, &spec, &mut out).unwrap();
    out
}

/// Over 1 s the lanes agree with the scalar RK4 (glibc sine and cosine) to 1e-11: the
/// difference is rounding in sin/cos, amplified over 100 steps of a chaotic system.
#[test]
fn rk4_lanes_match_the_scalar_rk4() {
    let ms = members();
    let lanes = run(&ms, 100, false);
    let mut worst = 0.0_f64;
    for (m, r) in ms.iter().zip(&lanes) {
        let spec = RunSpec { t0: 0.0, h: 0.01, end: End::Steps(100) };
        let scalar =
            pendula::solve(&m.pendulum, &RK4, &m.state, &spec, &mut pendula::observe::Ignore).unwrap().state;
        worst = scalar.iter().zip(&r.state).map(|(a, b)| (a - b).abs()).fold(worst, f64::max);
    }
    eprintln!("max difference {worst:.2e}");
    assert!(worst < 1e-11, "{worst}");
}

/// The flip time matches the scalar flip event (RK4, both located on the cubic Hermite
/// interpolant of the step) to within what the lanes' sine rounding (≤ 2 ulp from glibc's)
/// grows to on these chaotic orbits over 10 s; the CLI test `fractal_flip_times_agree_with_
/// simulate_flip_events` checks early flips to 1e-9 s. Members that never flip have NaN; a
/// retired member stops at the step after its flip.
#[test]
fn flip_times_match_located_flip_events() {
    let v = values("double", &[]);
    let model = v.build();
    let ms = members();
    let results = run(&ms, 1000, true);
    let mut flipped = 0;
    for (m, r) in ms.iter().zip(&results) {
        let dp = values(
            "double",
            &[
                ("m1", m.pendulum.m1),
                ("m2", m.pendulum.m2),
                ("l1", m.pendulum.l1),
                ("l2", m.pendulum.l2),
                ("theta1", m.state[0]),
                ("theta2", m.state[1]),
                ("omega1", m.state[2]),
                ("omega2", m.state[3]),
            ],
        );
        let one = dp.build();
        let spec = EventSpec::parse("flip", &*model, true).unwrap();
        let mut events = EventLocator::new(&*one, vec![spec]);
        let run = RunSpec { t0: 0.0, h: 0.01, end: End::Steps(1000) };
        one.solve(&RK4, dp.initial_state(), &run, &mut events).unwrap();
        match events.found.first() {
            Some(e) => {
                flipped += 1;
                assert!((e.t - r.flip_time).abs() < 2e-3, "event {} vs lanes {}", e.t, r.flip_time);
                assert!(r.state[0].abs() > std::f64::consts::PI || r.state[1].abs() > std::f64::consts::PI);
            }
            None => assert!(r.flip_time.is_nan(), "{}", r.flip_time),
        }
    }
    assert!(flipped >= 3, "{flipped}");
}

/// Bitwise the same with 1 and 2 threads, and when the members are run in other groupings
/// (every member alone, and a shifted slice): no lane depends on another.
#[test]
fn results_are_bitwise_identical_whatever_the_threads_and_chunks() {
    let ms: Vec<Member> = members().into_iter().cycle().take(700).collect();
    let with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| run(&ms, 300, true))
    };
    let (one, two) = (with(1), with(2));
    let bits = |r: &[MemberResult]| -> Vec<u64> {
        r.iter().flat_map(|m| m.state.iter().chain([&m.flip_time]).map(|v| v.to_bits())).collect()
    };
    assert_eq!(bits(&one), bits(&two));
    let alone: Vec<MemberResult> =
        ms[..9].iter().flat_map(|m| run(std::slice::from_ref(m), 300, true)).collect();
    assert_eq!(bits(&alone), bits(&one[..9]));
    let shifted = run(&ms[3..], 300, true);
    assert_eq!(bits(&shifted), bits(&one[3..]));
}

#[test]
fn a_non_finite_member_is_named() {
    let mut ms = members();
    ms[13].state[2] = f64::INFINITY;
    for track_flips in [true, false] {
        let spec =
            LaneSpec { method: rk4(), h: 0.01, steps: 10, stop_at_flip: false, track_flips, cancel: None };
        let mut out = vec![MemberResult { state: [0.0; 4], flip_time: 0.0 }; ms.len()];
        let err = ensemble::run(&ms, &spec, &mut out).unwrap_err();
        let pendula::Error::NonFiniteMember { member, t } = err else {
            panic!("expected a non-finite member, got {err}")
        };
        assert_eq!(member, 13);
        assert_eq!(t, 0.01);
        assert!(err.to_string().contains("member 13"), "{err}");
    }
}

/// tao-4 lanes (branch-free trigonometry) agree with the scalar tao-4 (libm) over 100 steps of
/// 2 ms to 1e-10, and are bitwise the same whatever the thread count.
#[test]
fn tao_lanes_match_the_scalar_tao() {
    use pendula::integrator::Scheme;
    use pendula::integrator::tao::TAO_4;
    let Scheme::Tao(scheme) = TAO_4.scheme else { unreachable!() };
    let ms = members();
    let spec = LaneSpec {
        method: LaneMethod::Tao { method: &TAO_4, scheme },
        h: 0.002,
        steps: 100,
        stop_at_flip: false,
        track_flips: true,
        cancel: None,
    };
    let with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut out = vec![MemberResult { state: [0.0; 4], flip_time: 0.0 }; ms.len()];
        pool.install(|| ensemble::run(&ms, &spec, &mut out).unwrap());
        out
    };
    let (one, two) = (with(1), with(2));
    let mut worst = 0.0_f64;
    for ((m, a), b) in ms.iter().zip(&one).zip(&two) {
        assert_eq!(a.state.map(f64::to_bits), b.state.map(f64::to_bits));
        let run = RunSpec { t0: 0.0, h: 0.002, end: End::Steps(100) };
        let scalar =
            pendula::solve(&m.pendulum, &TAO_4, &m.state, &run, &mut pendula::observe::Ignore).unwrap().state;
        worst = scalar.iter().zip(&a.state).map(|(x, y)| (x - y).abs()).fold(worst, f64::max);
    }
    eprintln!("tao-4 lanes vs scalar: {worst:.2e}");
    assert!(worst < 1e-10, "{worst}");
}

/// Angles beyond the trigonometry's fast range take its exact reduction: members started at
/// θ = 1e7, −2.5e6 and 1e17 rad, and one at 524 287.9 rad that passes half the fast range
/// (2¹⁹, where a lane group leaves the fast kernel) a third of the way through. On the RK4
/// lanes (flips tracked or not) and the tao-4 lanes, and on one lane alone, they agree
/// with the scalar integrators (glibc) to 1e-11, as members at ordinary angles do (measured:
/// 7e-15), and the other members of their lane groups get the same bits as in a run without
/// them.
#[test]
fn huge_angles_take_the_exact_reduction() {
    use pendula::integrator::Scheme;
    use pendula::integrator::tao::TAO_4;
    let Scheme::Tao(tao) = TAO_4.scheme else { unreachable!() };
    let plain = members();
    let mut huge = plain.clone();
    let changed = [(3, 0, 1e7), (5, 1, -2.5e6), (9, 0, 1e17), (17, 1, 524_287.9)];
    for &(i, k, angle) in &changed {
        huge[i].state[k] = angle;
    }
    let batch = |method, h, track_flips| LaneSpec {
        method,
        h,
        steps: 100,
        stop_at_flip: false,
        track_flips,
        cancel: None,
    };
    for (spec, scalar_method) in [
        (batch(rk4(), 0.01, true), &RK4),
        (batch(rk4(), 0.01, false), &RK4),
        (batch(LaneMethod::Tao { method: &TAO_4, scheme: tao }, 0.002, true), &TAO_4),
    ] {
        let run = |ms: &[Member]| {
            let mut out = vec![MemberResult { state: [0.0; 4], flip_time: 0.0 }; ms.len()];
            ensemble::run(ms, &spec, &mut out).unwrap();
            out
        };
        let (before, after) = (run(&plain), run(&huge));
        for (i, (a, b)) in before.iter().zip(&after).enumerate() {
            if changed.iter().all(|c| c.0 != i) {
                assert_eq!(a.state.map(f64::to_bits), b.state.map(f64::to_bits), "member {i}");
                assert_eq!(a.flip_time.to_bits(), b.flip_time.to_bits(), "member {i}");
            }
        }
        let steps = RunSpec { t0: 0.0, h: spec.h, end: End::Steps(100) };
        for &(i, _, angle) in &changed {
            let m = &huge[i];
            let scalar =
                pendula::solve(&m.pendulum, scalar_method, &m.state, &steps, &mut pendula::observe::Ignore)
                    .unwrap();
            let mut paths = vec![("lanes", after[i].state)];
            // One member alone on the engine's one lane (the fast path of a single run).
            let one = pendula::ensemble::engine::solve_one(
                &m.pendulum,
                spec.method,
                &m.state,
                &steps,
                &mut pendula::observe::Ignore,
            );
            paths.push(("one lane", one.unwrap().state.try_into().unwrap()));
            for (path, state) in paths {
                let d = state.iter().zip(&scalar.state).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                let name = if matches!(spec.method, LaneMethod::Rk(_)) { "rk4" } else { "tao-4" };
                eprintln!("{name} {path}, member {i} at {angle:e}: {d:.2e}");
                assert!(d < 1e-11, "{name} {path}, member {i} at {angle:e}: {d:e} from the scalar path");
            }
        }
    }
}
