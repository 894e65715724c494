//! Integrator kernels against the `ode_solvers` crate on the bench's workloads
//! (`../shared/bench/SPEC.md`), in one process so that the ratios are fair:
//!
//! - W2: the double pendulum from (120°, −10°) to t = 10 s, adaptive 8th order at
//!   rtol = atol = 1e-10 (`dop853` vs `ode_solvers::Dop853`, the same steps);
//! - W1 (shortened): RK4 at h = 1 ms for 10⁴ steps (`rk4` vs `ode_solvers::Rk4`);
//! - W3 (shortened): a 64 × 64 grid of initial angles from rest, RK4 at h = 10 ms for 100
//!   steps, on one thread (the ensemble engine vs `ode_solvers::Rk4` cell by cell);
//! - the general engine's lanes against scalar runs per member: the chain of three links and
//!   the damped, driven double pendulum, 1024 members, RK4 for 200 steps, one thread.
//!
//! Run: `cargo bench -p pendula --bench integrators`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use ode_solvers::dop_shared::OutputType;
use ode_solvers::{Dop853, Rk4, System as OdeSystem, Vector4};
use pendula::control::Tolerances;
use pendula::ensemble::engine::{LaneMethod, LaneOutcome, LaneSpec, Members, Rows};
use pendula::ensemble::{self, Member, MemberResult};
use pendula::integrator::embedded::DOP853;
use pendula::integrator::explicit_rk::RK4;
use pendula::model::find;
use pendula::observe::Ignore;
use pendula::{End, RunSpec};

/// The SPEC's equations for `ode_solvers`.
struct W;

impl OdeSystem<f64, Vector4<f64>> for W {
    fn system(&self, _t: f64, y: &Vector4<f64>, dy: &mut Vector4<f64>) {
        let (m1, m2, l1, l2, g) = (1.0, 1.0, 1.0, 1.0, 9.81);
        let (s1, s2, sd, cd) = (y[0].sin(), y[1].sin(), (y[0] - y[1]).sin(), (y[0] - y[1]).cos());
        let (m11, m12, m21, m22) = ((m1 + m2) * l1, m2 * l2 * cd, l1 * cd, l2);
        let r1 = -m2 * l2 * y[3] * y[3] * sd - (m1 + m2) * g * s1;
        let r2 = l1 * y[2] * y[2] * sd - g * s2;
        let det = m11 * m22 - m12 * m21;
        *dy = Vector4::new(y[2], y[3], (r1 * m22 - m12 * r2) / det, (m11 * r2 - m21 * r1) / det);
    }
}

fn benches(c: &mut Criterion) {
    let values = find("double").unwrap().values(&[]).unwrap();
    let model = values.build();
    let y0 = values.initial_state().to_vec();
    let v0 = Vector4::new(y0[0], y0[1], y0[2], y0[3]);

    let mut w2 = c.benchmark_group("W2 dop853 rtol=atol=1e-10 t=10");
    let tol = Tolerances { rtol: 1e-10, atol: 1e-10, h_min: 0.0, h_max: f64::INFINITY };
    w2.bench_function("pendula", |b| {
        b.iter(|| model.solve_adaptive(&DOP853, black_box(&y0), 10.0, None, &tol, &mut Ignore).unwrap())
    });
    w2.bench_function("ode_solvers", |b| {
        b.iter(|| {
            let mut s = Dop853::from_param(
                W,
                0.0,
                10.0,
                10.0,
                black_box(v0),
                1e-10,
                1e-10,
                0.9,
                0.0,
                0.333,
                6.0,
                10.0,
                0.0,
                100_000_000,
                1000,
                OutputType::Sparse,
            );
            s.integrate().unwrap();
            *s.y_out().last().unwrap()
        })
    });
    w2.finish();

    let mut w1 = c.benchmark_group("W1 rk4 h=1e-3 10^4 steps");
    let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Steps(10_000) };
    w1.bench_function("pendula", |b| {
        b.iter(|| model.solve(&RK4, black_box(&y0), &spec, &mut Ignore).unwrap())
    });
    w1.bench_function("ode_solvers", |b| {
        b.iter(|| {
            let mut s = Rk4::new(W, 0.0, black_box(v0), 10.0, 1e-3);
            s.integrate().unwrap();
            *s.y_out().last().unwrap()
        })
    });
    w1.finish();

    let mut w3 = c.benchmark_group("W3 64x64 rk4 h=1e-2 100 steps, 1 thread");
    w3.sample_size(10);
    let cell = |i: usize| -std::f64::consts::PI + (i as f64 + 0.5) * (2.0 * std::f64::consts::PI / 64.0);
    let pendulum = pendula::system::double::DoublePendulum {
        m1: 1.0,
        m2: 1.0,
        l1: 1.0,
        l2: 1.0,
        g: 9.81,
        ..Default::default()
    };
    let members: Vec<Member> =
        (0..64 * 64).map(|c| Member { pendulum, state: [cell(c % 64), cell(c / 64), 0.0, 0.0] }).collect();
    let spec = LaneSpec {
        method: LaneMethod::of(&RK4).unwrap(),
        h: 1e-2,
        steps: 100,
        stop_at_flip: false,
        track_flips: true,
        cancel: None,
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let mut out = vec![MemberResult { state: [0.0; 4], flip_time: 0.0 }; members.len()];
    w3.bench_function("pendula ensemble", |b| {
        b.iter(|| pool.install(|| ensemble::run(black_box(&members), &spec, &mut out).unwrap()))
    });
    w3.bench_function("ode_solvers per cell", |b| {
        b.iter(|| {
            members
                .iter()
                .map(|m| {
                    let y = Vector4::new(m.state[0], m.state[1], 0.0, 0.0);
                    let mut s = Rk4::new(W, 0.0, black_box(y), 1.0, 1e-2);
                    s.integrate().unwrap();
                    s.y_out().last().unwrap()[0]
                })
                .sum::<f64>()
        })
    });
    w3.finish();

    // Lanes against per-member scalar runs of the same method, one thread: rk4 on the chain
    // of three links and the driven double pendulum (issue 13 asks for at least 5 times), and
    // kick-drift (yoshida-4) on the driven pendulum.
    for (name, system, method, settings) in [
        ("chain N=3", "chain", &RK4, vec![("links".to_owned(), 3.0)]),
        (
            "driven double",
            "double",
            &RK4,
            vec![
                ("drive_amplitude".to_owned(), 2.0),
                ("drive_frequency".to_owned(), 3.0),
                ("damping".to_owned(), 0.1),
            ],
        ),
        (
            "driven pendulum",
            "pendulum",
            &pendula::integrator::composition::YOSHIDA_4,
            vec![("drive_amplitude".to_owned(), 2.0), ("drive_frequency".to_owned(), 3.0)],
        ),
    ] {
        let entry = find(system).unwrap();
        let values = entry.values(&settings).unwrap();
        let info = values.info();
        let raw: Vec<f64> =
            values.parameters().map(|(_, v)| v).chain(values.initial_state().iter().copied()).collect();
        let np = info.parameters.len();
        let dim = info.state.len();
        let count = 1024;
        let member = |i: usize, v: &mut [f64]| {
            v.copy_from_slice(&raw);
            v[np] += 1e-3 * i as f64;
        };
        let model = values.build();
        let lanes = pendula::ensemble::engine::LaneSpec {
            method: pendula::model::lane_method(method, &*model).unwrap(),
            h: 1e-3,
            steps: 200,
            stop_at_flip: false,
            track_flips: false,
            cancel: None,
        };
        let mut out = vec![0.0; count * dim];
        let mut group =
            c.benchmark_group(format!("{name}: 1024 members, {}, 200 steps, 1 thread", method.name));
        group.sample_size(10);
        group.bench_function("lanes", |b| {
            b.iter(|| {
                pool.install(|| {
                    let store =
                        |_: usize, o: &LaneOutcome, row: &mut [f64]| row.copy_from_slice(&o.state[..dim]);
                    let members = Members { info, count, values: &member };
                    model.ensemble(&members, &lanes, Rows { out: &mut out, len: dim, store: &store }).unwrap()
                })
            })
        });
        let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Steps(200) };
        group.bench_function("scalar per member", |b| {
            b.iter(|| {
                (0..count)
                    .map(|i| {
                        let mut v = raw.clone();
                        member(i, &mut v);
                        model.solve(method, black_box(&v[np..]), &spec, &mut Ignore).unwrap().state[0]
                    })
                    .sum::<f64>()
            })
        });
        group.finish();
    }
}

criterion_group!(integrators, benches);
criterion_main!(integrators);
