//! Adaptive steps with an embedded pair and the PI controller.

use pendula::control::Tolerances;
use pendula::integrator::embedded::DOPRI5;
use pendula::integrator::explicit_rk::RK4;
use pendula::observe::{Ignore, Recorder};
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
    insta::assert_snapshot!(format!("accepted {steps}, rejected {}, rhs evals {}", r.steps_rejected, r.rhs_evals), @"accepted 642, rejected 29, rhs evals 4029");
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
