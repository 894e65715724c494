//! Adaptive steps with an embedded pair and the PI controller.

use pendula::control::Tolerances;
use pendula::integrator::embedded::{DOP853, DOPRI5, EmbeddedRk};
use pendula::integrator::explicit_rk::RK4;
use pendula::integrator::{Method, Scheme};
use pendula::observe::{Ignore, Recorder};
use pendula::system::Model;
use pendula::{Error, Outcome};

use crate::support::values;

fn tol(t: f64) -> Tolerances {
    Tolerances { rtol: t, atol: t, h_min: 0.0, h_max: f64::INFINITY }
}

/// On the oscillator (exact solution) the global error follows the tolerance: a log-log fit
/// of error against tolerance has a slope near 1 (an order-5 method controlled on an
/// order-4 estimate gives slightly less: 5/5 … 4/5 is the expected range).
#[test]
fn ref_error_is_proportional_to_the_tolerance() {
    let v = values("oscillator", &[("x", 1.0), ("v", 0.5)]);
    let model = v.build();
    let exact = model.exact(10.0, v.initial_state()).unwrap();
    let tols = [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];
    let errors: Vec<f64> = tols
        .iter()
        .map(|&t| {
            let r =
                model.solve_adaptive(&DOPRI5, v.initial_state(), 10.0, None, &tol(t), &mut Ignore).unwrap();
            r.state.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
        })
        .collect();
    let slope = pendula::analysis::fit_order(&tols, &errors).unwrap().order;
    eprintln!("errors {errors:?}, slope {slope}");
    assert!((0.75..=1.1).contains(&slope), "{slope}");
}

/// The run lands on t_end exactly, observers see every accepted step, and the work is
/// pinned: a change of controller that doubles the cost shows here.
#[test]
fn regress_work_counts_on_the_double_pendulum() {
    let v = values("double", &[]);
    let model = v.build();
    let mut rec = Recorder::default();
    let r = model.solve_adaptive(&DOPRI5, v.initial_state(), 10.0, None, &tol(1e-8), &mut rec).unwrap();
    let Outcome::ReachedEnd { steps, t } = r.outcome else { panic!("{:?}", r.outcome) };
    assert_eq!(t, 10.0);
    assert_eq!(rec.rows.len() / 5, steps as usize + 1);
    assert_eq!(rec.rows[rec.rows.len() - 5], 10.0);
    // 6 evaluations per attempted step (FSAL) plus the first stage and 2 for the initial step.
    assert_eq!(r.rhs_evals, 6 * (steps + r.steps_rejected) + 3);
    insta::assert_snapshot!(format!("accepted {steps}, rejected {}, rhs evals {}", r.steps_rejected, r.rhs_evals), @"accepted 643, rejected 30, rhs evals 4041");
}

#[test]
fn step_below_the_minimum_is_an_error_naming_t_and_h() {
    let v = values("double", &[]);
    let strict = Tolerances { rtol: 1e-12, atol: 1e-12, h_min: 1e-2, h_max: f64::INFINITY };
    let err = v
        .build()
        .solve_adaptive(&DOPRI5, v.initial_state(), 10.0, Some(1e-2), &strict, &mut Ignore)
        .unwrap_err();
    let Error::StepSizeTooSmall { t, h } = err else { panic!("{err:?}") };
    assert!(h < 1e-2 && (0.0..10.0).contains(&t), "t {t} h {h}");
    assert!(err.to_string().contains("below the minimum"));
}

#[test]
fn tolerances_need_an_embedded_method() {
    let v = values("pendulum", &[]);
    let err =
        v.build().solve_adaptive(&RK4, v.initial_state(), 1.0, None, &tol(1e-6), &mut Ignore).unwrap_err();
    assert!(matches!(err, Error::UnmetRequirement { .. }), "{err:?}");
    let bad = Tolerances { rtol: 0.0, ..tol(1e-6) };
    assert!(matches!(
        v.build().solve_adaptive(&DOPRI5, v.initial_state(), 1.0, None, &bad, &mut Ignore),
        Err(Error::InvalidValue { .. })
    ));
}

/// Dense output of one step from the exact state of the oscillator: the error at θ = 0.3
/// and 0.7 shrinks as h^(p+1) for an interpolant of order p: 5 for dopri5 (p = 4), 8 for
/// dop853 (p = 7); both interpolants pass through the step's ends exactly.
#[test]
fn ref_dense_output_has_the_declared_order() {
    let v = values("oscillator", &[("x", 1.0), ("v", 0.5)]);
    let model = v.build();
    let system = pendula::system::oscillator::Oscillator::from_values(&v);
    let y0 = v.initial_state().to_vec();
    let dense_order = |method: &Method, hs: &[f64]| {
        let Scheme::Embedded(tableau) = method.scheme else { unreachable!() };
        let errors: Vec<f64> = hs
            .iter()
            .map(|&h| {
                let mut stepper = EmbeddedRk::new(tableau, 2);
                let mut y = y0.clone();
                stepper.attempt(&system, 0.0, h, &y);
                stepper.accept(&system, 0.0, h, h, &mut y, true);
                let dense = stepper.dense_output().expect("dense output was asked for");
                let mut at = [0.0; 2];
                dense.at(h, &mut at);
                assert_eq!(at.as_slice(), y.as_slice(), "{} at the step's end", method.name);
                dense.at(0.0, &mut at);
                assert_eq!(at.as_slice(), y0.as_slice(), "{} at the step's start", method.name);
                [0.3, 0.7]
                    .iter()
                    .map(|theta| {
                        dense.at(theta * h, &mut at);
                        let exact = model.exact(theta * h, &y0).unwrap();
                        at.iter().zip(&exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        let order = pendula::analysis::fit_order(hs, &errors).unwrap().order;
        eprintln!("{}: dense errors {errors:?} -> slope {order:.3}", method.name);
        order
    };
    let p5 = dense_order(&DOPRI5, &[0.4, 0.2, 0.1, 0.05]);
    assert!((p5 - 5.0).abs() < 0.15, "dopri5: {p5}");
    let p8 = dense_order(&DOP853, &[1.6, 0.8, 0.4, 0.2]);
    assert!((p8 - 8.0).abs() < 0.15, "dop853: {p8}");
}

/// The bench's W2 problem: the double pendulum from (120°, −10°) to t = 10 s at rtol = atol
/// = 1e-10. Hairer's DOP853 needs about 6,500 evaluations for it (the integrators issue):
/// pendula's dop853 must need no more, and (same method, same controller) at about the same
/// accuracy: within 1e-6 (the peers: 3e-7 … 1e-6) of mpmath's 30-digit Taylor solution (tests/reference).
#[test]
fn ref_dop853_on_the_w2_problem() {
    let v = values("double", &[("theta1", 120f64.to_radians()), ("theta2", -10f64.to_radians())]);
    let model = v.build();
    let r = model.solve_adaptive(&DOP853, v.initial_state(), 10.0, None, &tol(1e-10), &mut Ignore).unwrap();
    let reference = W2_REFERENCE;
    let error = r.state.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    eprintln!(
        "dop853 W2: {} accepted, {} rejected, {} evaluations, error {error:.2e}",
        r.outcome.steps(),
        r.steps_rejected,
        r.rhs_evals
    );
    assert!(r.rhs_evals <= 6500, "{}", r.rhs_evals);
    assert!(error < 1e-6, "{error}");
    // 12 evaluations per accepted step and 11 per rejected one (the new point is evaluated
    // only on acceptance), plus 2 for the initial step size and 1 for the first stage.
    assert_eq!(r.rhs_evals, 12 * r.outcome.steps() + 11 * r.steps_rejected + 3);
}

/// The oracle the integrators issue names: the `ode_solvers` crate's ports of Hairer's
/// Dop853 and Dopri5 on the W2 problem with the bench's settings (safety 0.9; β = 0 and
/// step factors 0.333 … 6 for DOP853, β = 0.04 and 0.2 … 10 for DOPRI5): pendula's pairs
/// need no more evaluations and land as close to the reference.
#[test]
fn ref_embedded_pairs_need_no_more_evaluations_than_ode_solvers() {
    use ode_solvers::dop_shared::{OutputType, Stats};
    use ode_solvers::{Dop853 as Oracle853, Dopri5 as Oracle5, System as OracleSystem, Vector4};
    struct W2;
    impl OracleSystem<f64, Vector4<f64>> for W2 {
        fn system(&self, _t: f64, y: &Vector4<f64>, dy: &mut Vector4<f64>) {
            // The bench's SPEC equations, written here independently of pendula's.
            let (m1, m2, l1, l2, g) = (1.0, 1.0, 1.0, 1.0, 9.81);
            let (s1, s2, sd, cd) = (y[0].sin(), y[1].sin(), (y[0] - y[1]).sin(), (y[0] - y[1]).cos());
            let (m11, m12, m21, m22) = ((m1 + m2) * l1, m2 * l2 * cd, l1 * cd, l2);
            let r1 = -m2 * l2 * y[3] * y[3] * sd - (m1 + m2) * g * s1;
            let r2 = l1 * y[2] * y[2] * sd - g * s2;
            let det = m11 * m22 - m12 * m21;
            *dy = Vector4::new(y[2], y[3], (r1 * m22 - m12 * r2) / det, (m11 * r2 - m21 * r1) / det);
        }
    }
    let y0 = Vector4::new(120f64.to_radians(), -10f64.to_radians(), 0.0, 0.0);
    let error_of = |y: &[f64]| y.iter().zip(&W2_REFERENCE).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    type Oracle<'a> = Box<dyn Fn() -> (Stats, Vec<f64>) + 'a>;
    let oracles: [(&Method, Oracle<'_>); 2] = [
        (
            &DOP853,
            Box::new(|| {
                let (rtol, n_max, n_stiff) = (1e-10, 100_000_000, 1000);
                let mut o = Oracle853::from_param(
                    W2,
                    0.0,
                    10.0,
                    10.0,
                    y0,
                    rtol,
                    rtol,
                    0.9,
                    0.0,
                    0.333,
                    6.0,
                    10.0,
                    0.0,
                    n_max,
                    n_stiff,
                    OutputType::Sparse,
                );
                let stats = o.integrate().unwrap();
                (stats, o.y_out().last().unwrap().iter().copied().collect())
            }),
        ),
        (
            &DOPRI5,
            Box::new(|| {
                let (rtol, n_max, n_stiff) = (1e-10, 100_000_000, 1000);
                let mut o = Oracle5::from_param(
                    W2,
                    0.0,
                    10.0,
                    10.0,
                    y0,
                    rtol,
                    rtol,
                    0.9,
                    0.04,
                    0.2,
                    10.0,
                    10.0,
                    0.0,
                    n_max,
                    n_stiff,
                    OutputType::Sparse,
                );
                let stats = o.integrate().unwrap();
                (stats, o.y_out().last().unwrap().iter().copied().collect())
            }),
        ),
    ];
    let v = values("double", &[("theta1", 120f64.to_radians()), ("theta2", -10f64.to_radians())]);
    let model = v.build();
    for (method, oracle) in oracles {
        let (stats, theirs) = oracle();
        let their_error = error_of(&theirs);
        let r =
            model.solve_adaptive(method, v.initial_state(), 10.0, None, &tol(1e-10), &mut Ignore).unwrap();
        let error = error_of(&r.state);
        eprintln!(
            "{}: ode_solvers {} evaluations ({} accepted, {} rejected), error {their_error:.2e}; \
             pendula {} ({} accepted, {} rejected), error {error:.2e}",
            method.name,
            stats.num_eval,
            stats.accepted_steps,
            stats.rejected_steps,
            r.rhs_evals,
            r.outcome.steps(),
            r.steps_rejected
        );
        assert!(
            r.rhs_evals <= stats.num_eval as u64,
            "{}: {} > {}",
            method.name,
            r.rhs_evals,
            stats.num_eval
        );
        assert!(error <= 2.0 * their_error, "{}: {error} vs {their_error}", method.name);
    }
}

/// The W2 state at t = 10 s from mpmath's 30-digit Taylor integrator
/// (`reference/mpmath_reference.py`, DOUBLE_W2; the bench's long-double RK4 reference agrees
/// to 1.4e-11).
const W2_REFERENCE: [f64; 4] =
    [-0.80261199632904428466, -2.4815018039174808687, -1.9522456761794939867, -2.3287508057048290787];

/// A state at rest with atol = 0: every component's error is exactly 0 against a scale of
/// 0. That meets the tolerance; before, 0/0 made every step a rejection and DOPRI5 never
/// finished. Both pairs reach the end in a handful of growing steps.
#[test]
fn a_state_at_rest_with_zero_atol_reaches_the_end() {
    let v = values("oscillator", &[("x", 0.0), ("v", 0.0)]);
    let model = v.build();
    let tol = Tolerances { rtol: 1e-6, atol: 0.0, h_min: 0.0, h_max: f64::INFINITY };
    for method in [&DOPRI5, &DOP853] {
        let r = model.solve_adaptive(method, v.initial_state(), 10.0, None, &tol, &mut Ignore).unwrap();
        assert_eq!(r.outcome, Outcome::ReachedEnd { steps: r.outcome.steps(), t: 10.0 }, "{}", method.name);
        assert!(r.outcome.steps() < 20 && r.steps_rejected == 0, "{}: {r:?}", method.name);
        assert_eq!(r.state, [0.0, 0.0]);
    }
}

/// The smallest step is bounded below by what the end time resolves (16 ε t_end), also at
/// t = 0, where a floor relative to t alone is 0: an error that only a vanishing step meets
/// (a spring of 1e300 N/m) fails at once with the step it asked for, instead of creeping on
/// at steps of 1e-150 s.
#[test]
fn a_vanishing_step_at_the_start_is_an_error_not_a_stall() {
    let v = values("oscillator", &[("k", 1e300)]);
    let model = v.build();
    let err =
        model.solve_adaptive(&DOPRI5, v.initial_state(), 1.0, None, &tol(1e-6), &mut Ignore).unwrap_err();
    let Error::StepSizeTooSmall { t, h } = err else { panic!("{err:?}") };
    assert_eq!(t, 0.0);
    assert!(h < 16.0 * f64::EPSILON, "h {h}");
}

/// A relative tolerance below round-off (about 4.5 ε) cannot be met by any step: refused,
/// and so is one above 1; 1e-15 itself is allowed.
#[test]
fn relative_tolerance_is_bounded_by_round_off() {
    for (rtol, ok) in [(1e-16, false), (1e-15, true), (1.0, true), (2.0, false)] {
        let t = Tolerances { rtol, ..tol(1e-6) };
        assert_eq!(t.validate().is_ok(), ok, "rtol {rtol}");
    }
    let err = Tolerances { rtol: 1e-300, ..tol(1e-6) }.validate().unwrap_err();
    assert!(err.to_string().contains("round-off"), "{err}");
}

/// Adaptive runs from any start and backward in time: the driven, damped oscillator from
/// t₀ = 2 s back to −1 s with dop853 is its exact solution (the drive at the true times),
/// and a run from 0 to a negative end goes backward too; every time decreases, the last is
/// the end exactly.
#[test]
fn adaptive_runs_go_backward_from_any_start() {
    let v =
        values("oscillator", &[("c", 0.2), ("drive_amplitude", 1.0), ("drive_frequency", 1.3), ("k", 4.0)]);
    let model = v.build();
    let y0 = v.initial_state();
    for (t0, t_end) in [(2.0, -1.0), (0.0, -3.0), (-1.0, 2.0)] {
        let start = model.exact(t0, y0).unwrap();
        let mut rec = Recorder::default();
        let r = model.solve_adaptive_from(&DOP853, &start, t0, t_end, None, &tol(1e-12), &mut rec).unwrap();
        assert_eq!(r.outcome.t(), t_end);
        let times: Vec<f64> = rec.rows.chunks(3).map(|row| row[0]).collect();
        assert_eq!((times[0], *times.last().unwrap()), (t0, t_end));
        let d = (t_end - t0).signum();
        assert!(times.windows(2).all(|w| d * (w[1] - w[0]) > 0.0), "{t0} → {t_end}");
        let diff = crate::support::max_diff(&r.state, &model.exact(t_end, y0).unwrap());
        assert!(diff < 1e-9, "{t0} → {t_end}: {diff:e}");
    }
    // An end equal to the start is refused, naming the end.
    match model.solve_adaptive_from(&DOP853, y0, 1.0, 1.0, None, &tol(1e-8), &mut Ignore) {
        Err(Error::InvalidValue { name, .. }) => assert_eq!(name, "t_end"),
        other => panic!("{other:?}"),
    }
}
