//! The ensemble engine runs every catalogued system, damped and driven variants included,
//! with every explicit method it takes (the explicit Runge–Kutta methods everywhere; the
//! explicit partitioned methods, kick–drift, on separable systems): a lane group's members get
//! exactly the bits each gets alone in one lane (`solve_lane`, through the scalar run loop),
//! and agree with the reference arithmetic (`solve`: glibc's sine and cosine, no fused
//! operations; for the partitioned methods the (q, p) steppers) to rounding.

use pendula::ensemble::engine::{LaneMethod, LaneOutcome, LaneSpec, Members, Rows};
use pendula::integrator::explicit_rk::Tableau;
use pendula::integrator::{self, Method, Requirement, Scheme};
use pendula::model::{CATALOGUE, DynModel, lane_method};
use pendula::observe::Ignore;
use pendula::system::Values;
use pendula::{End, RunSpec};

use crate::support::{max_diff, samples, values};

/// A test method the catalogue does not hold: an explicit tableau of `stages` stages.
const fn test_method(name: &'static str, order: u32, tableau: &'static Tableau) -> Method {
    Method {
        name,
        title: name,
        order,
        requirement: Requirement::Any,
        symplectic: false,
        symmetric: false,
        description: "a test tableau",
        reference: "Hairer, Norsett, Wanner, Solving ODEs I, §II.1",
        scheme: Scheme::ExplicitRk(tableau),
    }
}

/// Heun's method, 2 stages, order 2.
static HEUN: Method = test_method(
    "heun (test)",
    2,
    &Tableau { c: &[0.0, 1.0], a: &[&[], &[1.0]], b: &[1.0, 1.0], denominator: 2.0 },
);

/// Kutta's third-order method, 3 stages.
static KUTTA3: Method = test_method(
    "kutta-3 (test)",
    3,
    &Tableau { c: &[0.0, 0.5, 1.0], a: &[&[], &[0.5], &[-1.0, 2.0]], b: &[1.0, 4.0, 1.0], denominator: 6.0 },
);

/// Every catalogued system with its defaults, and the variants with forces or structure.
fn variants() -> Vec<Values> {
    let mut all: Vec<Values> = CATALOGUE.iter().map(|e| e.values(&[]).unwrap()).collect();
    all.push(values("double", &[("damping", 0.3)]));
    all.push(values("double", &[("drive_amplitude", 2.0), ("drive_frequency", 3.0)]));
    all.push(values("pendulum", &[("damping", 0.2), ("drive_amplitude", 1.0), ("drive_frequency", 2.0)]));
    all.push(values("pendulum", &[("linear", 1.0)]));
    all.push(values("oscillator", &[("c", 0.4), ("drive_amplitude", 1.0), ("drive_frequency", 1.3)]));
    all.push(values("chain", &[("links", 5.0), ("m3", 2.0), ("l2", 0.5)]));
    all.push(values("chain", &[("links", 1.0)]));
    all
}

/// Runs the members `all` (each one's values: parameters, then state) of `model`'s system on
/// the lanes: their final states, one row of the state's size each.
fn run_members(model: &dyn DynModel, all: &[Vec<f64>], spec: &LaneSpec) -> Result<Vec<f64>, pendula::Error> {
    let info = model.info();
    let dim = info.state.len();
    let mut out = vec![0.0; all.len() * dim];
    let values = |i: usize, v: &mut [f64]| v.copy_from_slice(&all[i]);
    let store = |_: usize, o: &LaneOutcome, row: &mut [f64]| row.copy_from_slice(&o.state[..dim]);
    let members = Members { info, count: all.len(), values: &values };
    model.ensemble(&members, spec, Rows { out: &mut out, len: dim, store: &store })?;
    Ok(out)
}

/// Checks that each member's row of `out` (`all` run on the lanes by `spec`) is, bit for bit,
/// what the member gets alone in one lane (`solve_lane`, through the scalar run loop, with as
/// many evaluations), and within `tol` (relative to the state's largest value) of `method` in
/// the reference arithmetic (`solve`: glibc's sine and cosine, no fused operations; for the
/// partitioned methods and Tao's map, the (q, p) steppers).
fn assert_each_lane_is_one_lane(
    info: &'static pendula::system::SystemInfo,
    all: &[Vec<f64>],
    out: &[f64],
    spec: &LaneSpec,
    method: &Method,
    tol: f64,
) {
    let (dim, np) = (info.state.len(), info.parameters.len());
    for (i, m) in all.iter().enumerate() {
        let settings: Vec<(String, f64)> =
            info.quantities().map(|q| q.name.to_owned()).zip(m.iter().copied()).collect();
        let one = info.values(&settings).unwrap().build();
        let run = RunSpec { t0: 0.0, h: spec.h, end: End::Steps(spec.steps) };
        let alone = one.solve_lane(spec.method, &m[np..], &run, &mut Ignore).unwrap();
        let lane = &out[i * dim..(i + 1) * dim];
        assert!(
            lane.iter().zip(&alone.state).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{} {} member {i}: lane {lane:?}, alone {:?}",
            info.name,
            method.name,
            alone.state
        );
        let reference = one.solve(method, &m[np..], &run, &mut Ignore).unwrap();
        let scale = reference.state.iter().fold(1.0f64, |s, v| s.max(v.abs()));
        let diff = max_diff(lane, &reference.state);
        assert!(
            diff <= tol * scale,
            "{} {} member {i}: {diff} from the reference arithmetic",
            info.name,
            method.name
        );
        assert_eq!(alone.rhs_evals, reference.rhs_evals, "{} {}", info.name, method.name);
    }
}

/// `count` members around `base`: every state variable and every real parameter moved a
/// little, differently per member (so that lanes differ in every input); with `keep_zeros`,
/// quantities that are zero in `base` (a damping, a drive left off) stay zero.
fn members(base: &Values, count: usize, keep_zeros: bool) -> Vec<Vec<f64>> {
    let info = base.info();
    let raw: Vec<f64> =
        base.parameters().map(|(_, v)| v).chain(base.initial_state().iter().copied()).collect();
    let mut jitter = samples(count * raw.len(), 0.9, 1.1);
    (0..count)
        .map(|_| {
            raw.iter()
                .zip(info.quantities())
                .map(|(&v, q)| {
                    let f = jitter.next().unwrap();
                    // Structural settings (links, the small-angle flag) are the group's.
                    if q.name == "links" || q.name == "linear" || (keep_zeros && v == 0.0) {
                        v
                    } else if v == 0.0 {
                        f - 0.9
                    } else {
                        v * f
                    }
                })
                .collect()
        })
        .collect()
}

#[test]
fn a_sweep_of_every_system_is_each_member_alone_bit_for_bit() {
    let mut checked = Vec::new();
    for base in variants() {
        let info = base.info();
        // 37 members: two full lane groups and a padded one.
        let all = members(&base, 37, false);
        // The catalogue's explicit methods (1 and 4 stages) and the test tableaus of 2 and 3:
        // a kernel for every number of stages the engine admits.
        let explicit =
            integrator::METHODS.iter().copied().filter(|m| matches!(m.scheme, Scheme::ExplicitRk(_)));
        for method in explicit.chain([&HEUN, &KUTTA3]) {
            let model = base.build();
            let lanes = lane_method(method, &*model).expect("the engine runs every explicit method");
            let (h, steps) = if info.dimensionless { (0.05, 400) } else { (2e-3, 400) };
            let spec =
                LaneSpec { method: lanes, h, steps, stop_at_flip: false, track_flips: false, cancel: None };
            let out = run_members(&*model, &all, &spec).unwrap();
            assert_each_lane_is_one_lane(info, &all, &out, &spec, method, 1e-9);
            checked.push(format!("{} {}", info.name, method.name));
        }
    }
    // Every catalogued system, with every explicit method and both test tableaus.
    for entry in CATALOGUE {
        assert!(checked.iter().any(|c| c.starts_with(&format!("{} ", entry.name))), "{} not run", entry.name);
        for test in [&HEUN, &KUTTA3] {
            assert!(
                checked.contains(&format!("{} {}", entry.name, test.name)),
                "{} {} not run",
                entry.name,
                test.name
            );
        }
    }
}

/// A member whose state becomes non-finite is an error naming the member and the time.
#[test]
fn a_member_that_blows_up_is_named() {
    let base = values("oscillator", &[]);
    let info = base.info();
    let mut all = members(&base, 20, false);
    // Member 13: a stiff spring that explicit Euler at this step amplifies without bound.
    let k = info.quantities().position(|q| q.name == "k").unwrap();
    all[13][k] = 1e6;
    let spec = LaneSpec {
        method: lane_method(&integrator::explicit_rk::EULER, &*base.build()).unwrap(),
        h: 0.01,
        steps: 2000,
        stop_at_flip: false,
        track_flips: false,
        cancel: None,
    };
    let err = run_members(&*base.build(), &all, &spec).unwrap_err();
    match err {
        pendula::Error::NonFiniteMember { member, t } => {
            assert_eq!(member, 13);
            assert!(t > 0.0 && t <= 20.0, "{t}");
        }
        other => panic!("{other:?}"),
    }
}

/// The explicit partitioned methods (symplectic Euler, Störmer–Verlet, the Yoshida
/// compositions) run on lanes, kick–drift in the velocities, for every separable variant —
/// free and driven, the small-angle pendulum — with the bits of each member alone, and agree
/// with the (q, p) steppers to rounding; on systems that are not separable (the double
/// pendulum, the chain, any damped system) the engine does not take them (the scalar
/// steppers run them, implicitly where they must).
#[test]
fn kick_drift_lanes_run_every_separable_system_bit_for_bit() {
    let separable = [
        values("pendulum", &[]),
        values("pendulum", &[("drive_amplitude", 1.0), ("drive_frequency", 2.0)]),
        values("pendulum", &[("linear", 1.0)]),
        values("oscillator", &[]),
        values("oscillator", &[("drive_amplitude", 1.0), ("drive_frequency", 1.3)]),
    ];
    let partitioned: Vec<&'static integrator::Method> =
        integrator::METHODS.iter().copied().filter(|m| matches!(m.scheme, Scheme::Partitioned(_))).collect();
    let mut checked = Vec::new();
    for base in &separable {
        let info = base.info();
        let all = members(base, 37, true);
        let model = base.build();
        for &method in &partitioned {
            let lanes = lane_method(method, &*model).expect("kick-drift on a separable system");
            assert!(matches!(lanes, LaneMethod::KickDrift { .. }), "{lanes:?}");
            let (h, steps) = (2e-3, 400);
            let spec =
                LaneSpec { method: lanes, h, steps, stop_at_flip: false, track_flips: false, cancel: None };
            let out = run_members(&*model, &all, &spec).unwrap();
            assert_each_lane_is_one_lane(info, &all, &out, &spec, method, 1e-10);
            checked.push(method.name);
        }
    }
    for method in &partitioned {
        assert_eq!(checked.iter().filter(|&&c| c == method.name).count(), separable.len(), "{}", method.name);
    }
    // Not separable: no kick-drift lanes.
    for base in [
        values("double", &[]),
        values("chain", &[("links", 3.0)]),
        values("pendulum", &[("damping", 0.2)]),
        values("oscillator", &[("c", 0.4)]),
    ] {
        let model = base.build();
        for &method in &partitioned {
            assert!(lane_method(method, &*model).is_none(), "{} {}", base.info().name, method.name);
        }
    }
}

/// A kick-drift ensemble whose members include a damped one is refused before any step,
/// naming the member and why (a scalar run of it is refused the same way).
#[test]
fn a_damped_member_of_a_kick_drift_ensemble_is_named() {
    let base = values("pendulum", &[]);
    let info = base.info();
    let mut all = members(&base, 20, true);
    let damping = info.quantities().position(|q| q.name == "damping").unwrap();
    all[17][damping] = 0.3;
    all[19][damping] = 0.1;
    let spec = LaneSpec {
        method: lane_method(&integrator::partitioned::VERLET, &*base.build()).unwrap(),
        h: 0.01,
        steps: 100,
        stop_at_flip: false,
        track_flips: false,
        cancel: None,
    };
    let err = run_members(&*base.build(), &all, &spec).unwrap_err();
    match &err {
        pendula::Error::UnmetRequirement { method, reason, .. } => {
            assert_eq!(*method, "verlet");
            assert!(reason.starts_with("member 17: ") && reason.contains("damping = 0.3"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
}

/// One flip rule: a sweep's `flip_time` column is the same whether the lanes ran the grid or
/// one scalar run per cell did (both locate the crossing on the cubic Hermite interpolant of
/// the angle over the step). The two paths differ only in rounding (polynomial against
/// glibc's trigonometry), so their flip times agree far below the step's interpolation error:
/// the linear rule the scalar path had before differed from the lanes' by 1.5e-7 s in the
/// first cell already (this test failed on it).
#[test]
fn a_sweeps_flip_times_are_the_same_on_lanes_and_on_the_scalar_path() {
    use pendula::sweep::{Axis, Record, ScalarSpec, SweepSpec, run_scalar};
    for (system, set) in [("double", vec![]), ("chain", vec![("links".to_owned(), 3.0)])] {
        let axes = vec![
            Axis { name: "theta1".into(), lo: 1.5, hi: 3.0, n: 12 },
            Axis { name: "theta2".into(), lo: -3.0, hi: 3.0, n: 12 },
        ];
        let sweep = SweepSpec {
            system: pendula::model::find(system).unwrap(),
            set: set.clone(),
            axes: axes.clone(),
            method: &integrator::explicit_rk::RK4,
            h: 0.01,
            steps: 300,
            until_flip: true,
            records: vec![Record::FlipTime],
            shard: (1, 1),
        }
        .validate()
        .unwrap();
        assert!(sweep.kernel().starts_with("simd lanes"), "{system}: {}", sweep.kernel());
        let cells = sweep.cells();
        let mut lanes = vec![0.0; cells];
        sweep.compute(0, &mut lanes, None, &|| {}).unwrap();
        // The same cells, one scalar run each.
        let first = sweep.values(0).unwrap();
        let info = first.info();
        let names: Vec<&str> = info.quantities().map(|q| q.name).collect();
        let fill = |i: usize, v: &mut [f64]| {
            let cell = sweep.values(i).unwrap();
            for (slot, name) in v.iter_mut().zip(&names) {
                *slot = cell.get(name);
            }
        };
        let spec = ScalarSpec {
            method: &integrator::explicit_rk::RK4,
            h: 0.01,
            steps: 300,
            stop_at_flip: true,
            cancel: None,
        };
        let mut scalar = vec![0.0; cells];
        let store = |_: usize, _: &[f64], flip: f64, row: &mut [f64]| row[0] = flip;
        let members = Members { info, count: cells, values: &fill };
        run_scalar(&members, &spec, Rows { out: &mut scalar, len: 1, store: &store }).unwrap();
        let mut flips = 0;
        for (i, (a, b)) in lanes.iter().zip(&scalar).enumerate() {
            assert_eq!(a.is_nan(), b.is_nan(), "{system} cell {i}: lanes {a}, scalar {b}");
            if a.is_finite() {
                flips += 1;
                assert!((a - b).abs() < 1e-9, "{system} cell {i}: lanes {a} s, scalar {b} s");
            }
        }
        assert!(flips > cells / 4, "{system}: only {flips} of {cells} cells flipped");
    }
}

/// Tao's maps run on lanes for every non-separable Hamiltonian system whose state and copy
/// fit the lane record — the double pendulum, free and driven, and the chain up to 4 links —
/// each member bit for bit its run alone in one lane, and within rounding of the scalar
/// stepper (glibc's trigonometry, no fused operations) with as many gradient evaluations.
/// Damped members have no Hamiltonian and are refused (see `forced.rs`); the 5-link chain's
/// state with its copy exceeds the record and runs one member at a time.
#[test]
fn tao_lanes_run_every_non_separable_system_bit_for_bit() {
    let systems = [
        values("double", &[]),
        values("double", &[("drive_amplitude", 2.0), ("drive_frequency", 3.0)]),
        values("chain", &[("links", 2.0)]),
        values("chain", &[("links", 3.0)]),
        values("chain", &[("links", 4.0), ("m3", 2.0), ("l2", 0.5)]),
    ];
    let tao: Vec<&'static integrator::Method> =
        integrator::METHODS.iter().copied().filter(|m| matches!(m.scheme, Scheme::Tao(_))).collect();
    assert_eq!(tao.len(), 2);
    let mut checked = 0;
    for base in &systems {
        let info = base.info();
        let all = members(base, 37, true);
        let model = base.build();
        for &method in &tao {
            let lanes = lane_method(method, &*model).expect("Tao's lanes on a non-separable system");
            assert!(matches!(lanes, LaneMethod::Tao { .. }), "{lanes:?}");
            let (h, steps) = (2e-3, 400);
            let spec =
                LaneSpec { method: lanes, h, steps, stop_at_flip: false, track_flips: false, cancel: None };
            let out = run_members(&*model, &all, &spec).unwrap();
            assert_each_lane_is_one_lane(info, &all, &out, &spec, method, 1e-9);
            checked += 1;
        }
    }
    assert_eq!(checked, systems.len() * tao.len());
    // Separable systems take kick-drift; the 5-link chain's state and copy exceed the record.
    for base in [values("pendulum", &[]), values("oscillator", &[]), values("chain", &[("links", 5.0)])] {
        let model = base.build();
        for &method in &tao {
            assert!(lane_method(method, &*model).is_none(), "{} {}", base.info().name, method.name);
        }
    }
}
