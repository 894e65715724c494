//! Every method × every reference problem: the measured order of convergence equals the
//! declared order. Methods enrol by being in `METHODS`; problems are listed here.

use pendula::Error;
use pendula::integrator::{METHODS, Method, Requirement, Scheme};
use pendula::system::oscillator::Oscillator;
use pendula::system::pendulum::Pendulum;
use pendula::system::{Model, Values};

use pendula::analysis::fit_order;

use crate::support::{final_state, max_diff, values};

/// A problem with an independently known solution at `t_end`.
struct Problem {
    name: &'static str,
    values: Values,
    t_end: f64,
    reference: Vec<f64>,
    /// Step sizes for methods of order ≤ 2 and of higher order: in the asymptotic range,
    /// with errors well above round-off. `None`: no such range exists for this problem.
    low_order_h: [f64; 4],
    high_order_h: Option<[f64; 4]>,
    /// Only methods of orders in this range are measured on this problem (the reason is
    /// beside it).
    orders: std::ops::RangeInclusive<u32>,
    /// Methods whose asymptotic range on this problem lies below round-off (their leading
    /// error term is smaller than the next one down to ~1e-14): the order is fitted over
    /// every error above round-off and only checked not to fall short of the declared one.
    pre_asymptotic: &'static [&'static str],
}

fn problems() -> Vec<Problem> {
    let osc = values("oscillator", &[("x", 1.0), ("v", 0.5)]);
    let o = Oscillator::from_values(&osc);
    let (x, v) = o.exact(10.0, 1.0, 0.5);
    let drive = [("x", 1.0), ("v", 0.5), ("drive_amplitude", 0.5), ("drive_frequency", 1.7)];
    let driven = values("oscillator", &drive);
    let (xd, vd) = Oscillator::from_values(&driven).exact(10.0, 1.0, 0.5);
    let damped = values("oscillator", &[drive.as_slice(), &[("c", 0.3)]].concat());
    let (xc, vc) = Oscillator::from_values(&damped).exact(10.0, 1.0, 0.5);
    let pend = values("pendulum", &[("theta", 1.0), ("omega", 0.0)]);
    let (th, w) = Pendulum::from_values(&pend).exact(5.0, 1.0, 0.0).unwrap();
    let deg = std::f64::consts::PI / 180.0;
    vec![
        Problem {
            name: "oscillator (closed form)",
            values: osc,
            t_end: 10.0,
            reference: vec![x, v],
            low_order_h: [0.02, 0.01, 0.005, 0.0025],
            high_order_h: Some([0.1, 0.05, 0.025, 0.0125]),
            orders: 1..=8,
            pre_asymptotic: &[],
        },
        Problem {
            name: "driven oscillator (closed form)",
            values: driven,
            t_end: 10.0,
            reference: vec![xd, vd],
            low_order_h: [0.02, 0.01, 0.005, 0.0025],
            high_order_h: Some([0.1, 0.05, 0.025, 0.0125]),
            orders: 1..=8,
            pre_asymptotic: &[],
        },
        Problem {
            // Not Hamiltonian: the symplectic methods must refuse it.
            name: "damped driven oscillator (closed form)",
            values: damped,
            t_end: 10.0,
            reference: vec![xc, vc],
            low_order_h: [0.02, 0.01, 0.005, 0.0025],
            high_order_h: Some([0.1, 0.05, 0.025, 0.0125]),
            orders: 1..=8,
            pre_asymptotic: &[],
        },
        Problem {
            name: "pendulum at 1 rad (Jacobi elliptic solution)",
            values: pend,
            t_end: 5.0,
            reference: vec![th, w],
            low_order_h: [0.004, 0.002, 0.001, 0.0005],
            high_order_h: Some([0.02, 0.01, 0.005, 0.0025]),
            orders: 1..=8,
            // dop853's local orders from h = 0.32 by factors of √2: 8.0, 9.3, 9.6, 10.1, 7.7,
            // 7.9, then round-off (its h⁸ and h⁹ terms cancel near h = 0.1).
            pre_asymptotic: &["dop853"],
        },
        Problem {
            name: "double pendulum A (mpmath Taylor, 30 digits)",
            values: values("double", &[("theta1", 120.0 * deg), ("theta2", -10.0 * deg)]),
            t_end: 2.0,
            reference: vec![
                1.1528016719796439749,
                -0.46715839071399934831,
                -0.056676482593218044406,
                5.8056603694950057652,
            ],
            low_order_h: [0.0004, 0.0002, 0.0001, 0.00005],
            // Near the top and chaotic, RK4's h⁴ and h⁵ error terms compete (error components
            // change sign) until round-off takes over: local orders 5.6, 4.8, 3.6, 3.6, 3.8
            // between h = 0.02 and 3e-4. Order-4 methods are measured on problem B.
            high_order_h: None,
            orders: 1..=2,
            pre_asymptotic: &[],
        },
        Problem {
            name: "double pendulum B (mpmath Taylor, 30 digits)",
            values: values(
                "double",
                &[
                    ("m2", 2.0),
                    ("l2", 0.5),
                    ("theta1", 60.0 * deg),
                    ("theta2", 90.0 * deg),
                    ("omega1", 0.5),
                    ("omega2", -1.0),
                ],
            ),
            t_end: 2.0,
            reference: vec![
                0.11783193862318899444,
                0.23250278895559659906,
                3.8461324332452524999,
                0.52132294269446865527,
            ],
            low_order_h: [0.0004, 0.0002, 0.0001, 0.00005],
            high_order_h: Some([0.01, 0.005, 0.0025, 0.00125]),
            // Above order 4 the next error terms compete here: dopri5's local orders are 4.0,
            // 4.7, 4.9 from h = 0.01 to 1.25e-3 before round-off. Higher orders use C.
            orders: 1..=4,
            pre_asymptotic: &[],
        },
        Problem {
            name: "double pendulum C (mpmath Taylor, 30 digits)",
            values: values("double", &[("theta1", 30.0 * deg), ("theta2", -20.0 * deg), ("omega1", 0.3)]),
            t_end: 2.0,
            reference: vec![
                -0.42497637758405030691,
                0.47454179309306458975,
                0.12613604682010879975,
                0.88917271530262891489,
            ],
            low_order_h: [0.0004, 0.0002, 0.0001, 0.00005],
            high_order_h: Some([0.01, 0.005, 0.0025, 0.00125]),
            // For orders 5 and up; on C, RK4 is pre-asymptotic down to h ~ 1e-3 (local orders
            // 2.6, 3.6, 3.8 from h = 0.02), and B measures order 4.
            orders: 5..=8,
            // dop853's local orders from h = 0.16 by factors of √2: 7.7, 12.6, 6.5, 9.2, 9.3,
            // 9.3, 9.6, then round-off.
            pre_asymptotic: &["dop853"],
        },
    ]
}

/// The fitted order, or `None` when the problem has no step range for this order or the
/// method does not apply to it (only an unmet requirement may say so).
fn measured_order(problem: &Problem, method: &Method) -> Option<f64> {
    let pre_asymptotic = problem.pre_asymptotic.contains(&method.name);
    // Step ranges are set for order 4; higher orders reach round-off sooner, so they take
    // larger steps: ×2 per two orders.
    if !problem.orders.contains(&method.order) {
        return None;
    }
    let hs: Vec<f64> = if let Scheme::Tao(tao) = method.scheme {
        // Tao's maps need ω h ≤ 1, and their higher orders hold only where ω h is small (the
        // binding term's error dominates above): tao-4 gives local orders near 1.5 at
        // ω h = 1 … 10 and 4.0 below ω h = 0.25, whatever the problem.
        [0.25, 0.125, 0.0625, 0.03125].map(|x| x / tao.binding).to_vec()
    } else if method.order <= 2 {
        problem.low_order_h.to_vec()
    } else {
        let hs = problem.high_order_h?.map(|h| h * 2f64.powi((method.order as i32 - 4) / 2));
        if method.order >= 8 {
            // Order 8 spans 10 decades over 4 halvings and its asymptotic window is narrow
            // (dop853 on the pendulum: local orders 8.0, 9.3, 9.6, 10.1 from h = 0.32 to 0.08,
            // its h⁸ and h⁹ terms cancelling, then 7.7, 7.9 before round-off at h = 0.03):
            // steps from 4× the largest down to the smallest in factors of √2.
            (0..=10).map(|i| 4.0 * hs[0] * 0.5f64.powf(i as f64 / 2.0)).collect()
        } else {
            hs.to_vec()
        }
    };
    let mut errors = Vec::new();
    for &h in &hs {
        match final_state(&problem.values, method, h, problem.t_end) {
            Ok(state) => errors.push(max_diff(&state, &problem.reference)),
            Err(Error::UnmetRequirement { .. }) if method.requirement != Requirement::Any => return None,
            Err(e) => panic!("{} on {}: {e}", method.name, problem.name),
        }
    }
    // High orders reach the round-off floor within the step range: leave out errors below
    // 2e-14 (~100 ε). Order 8 also has a narrow window between pre-asymptotic large steps and
    // that floor: fit its three finest steps above it.
    let (fit_h, fit_e): (Vec<f64>, Vec<f64>) = if method.order >= 6 {
        let kept: Vec<(f64, f64)> =
            hs.iter().copied().zip(errors.iter().copied()).filter(|(_, e)| *e > 2e-14).collect();
        let from = if method.order >= 8 && !pre_asymptotic { kept.len().saturating_sub(3) } else { 0 };
        kept[from..].iter().copied().unzip()
    } else {
        (hs.to_vec(), errors.clone())
    };
    assert!(
        fit_h.len() >= 3,
        "{} on {}: fewer than 3 errors above round-off: {errors:?}",
        method.name,
        problem.name
    );
    let order = fit_order(&fit_h, &fit_e).expect("positive errors").order;
    eprintln!(
        "{:<17} on {:<48} errors {} -> order {order:.3}",
        method.name,
        problem.name,
        errors.iter().map(|e| format!("{e:.3e}")).collect::<Vec<_>>().join(" ")
    );
    Some(order)
}

#[test]
fn ref_measured_order_equals_declared_order() {
    let mut failures = Vec::new();
    let mut measured = 0;
    for problem in problems() {
        for method in METHODS {
            let Some(order) = measured_order(&problem, method) else {
                continue;
            };
            measured += 1;
            // ±0.1 as the foundation issue asks up to order 4, ±0.15 above (the integrators issue).
            let tolerance = if method.order <= 4 { 0.1 } else { 0.15 };
            let deviation = order - method.order as f64;
            let fails = if problem.pre_asymptotic.contains(&method.name) {
                deviation < -tolerance
            } else {
                deviation.abs() > tolerance
            };
            if fails {
                failures.push(format!(
                    "{} on {}: {order:.3}, declared {}",
                    method.name, problem.name, method.order
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    // Every pair but the ones explained as skipped: orders above a problem's max_order,
    // methods needing a Hamiltonian on the damped oscillator, and methods needing a separable
    // H on the double pendulum.
    let mut expected = 0;
    for p in problems() {
        for m in METHODS {
            let damped = p.name.starts_with("damped");
            let double = p.name.starts_with("double");
            let skip = !p.orders.contains(&m.order)
                || (damped && m.requirement != Requirement::Any)
                || (double && m.requirement == Requirement::Separable);
            expected += usize::from(!skip);
        }
    }
    assert_eq!(measured, expected);
}

/// Embedded pairs: Σ b = 1 and the quadrature conditions Σ bᵢ cᵢ^(k−1) = 1/k up to the
/// declared order, every error estimate's weights sum to 0, row sums of A equal c, the
/// new-point row is b, and the dense output's weights add nothing to a constant (Σ d = 0).
#[test]
fn embedded_tableaus_are_consistent() {
    use pendula::integrator::Scheme;
    use pendula::integrator::embedded::ErrorEstimate;
    let mut checked = 0;
    for method in METHODS {
        if let Scheme::Embedded(t) = method.scheme {
            let name = method.name;
            for k in 1..=method.order {
                let q: f64 = t.b.iter().zip(t.c).map(|(b, c)| b * c.powi(k as i32 - 1)).sum();
                assert!((q - 1.0 / k as f64).abs() < 1e-14, "{name}: B({k}) = {q}");
            }
            let estimates: Vec<&[f64]> = match t.error {
                ErrorEstimate::Single { e } => vec![e],
                ErrorEstimate::Dop853 { e5, e3 } => vec![e5, e3],
            };
            for e in estimates {
                assert!(e.iter().sum::<f64>().abs() < 1e-14, "{name}: Σe = {}", e.iter().sum::<f64>());
            }
            assert_eq!(t.a.len(), t.c.len(), "{name}");
            for (i, (row, c)) in t.a.iter().zip(t.c).enumerate() {
                assert!(row.len() <= i, "{name}: row {i} is not strictly lower triangular");
                assert!((row.iter().sum::<f64>() - c).abs() < 1e-14, "{name}: row {i}");
            }
            let new_point = t.a[t.new_point];
            assert!(new_point.len() <= t.b.len() && t.b.len() <= t.stages, "{name}");
            assert!(t.b.iter().enumerate().all(|(i, b)| new_point.get(i).unwrap_or(&0.0) == b), "{name}");
            for d in t.dense {
                assert!(d.iter().sum::<f64>().abs() < 1e-11, "{name}: Σd = {}", d.iter().sum::<f64>());
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 2);
}

/// Collocation tableaus: Σ b = 1, row sums of A equal c, and the quadrature conditions
/// Σ bᵢ cᵢ^(k−1) = 1/k up to k = 2s (Gauss quadrature is exact to degree 2s − 1).
#[test]
fn collocation_tableaus_are_consistent() {
    use pendula::integrator::Scheme;
    let mut checked = 0;
    for method in METHODS {
        if let Scheme::Collocation(t) = method.scheme {
            let s = t.b.len();
            assert_eq!(2 * s as u32, method.order, "{}", method.name);
            for (row, c) in t.a.iter().zip(t.c) {
                assert!((row.iter().sum::<f64>() - c).abs() < 1e-15, "{}", method.name);
            }
            for k in 1..=2 * s {
                let q: f64 = t.b.iter().zip(t.c).map(|(b, c)| b * c.powi(k as i32 - 1)).sum();
                assert!((q - 1.0 / k as f64).abs() < 1e-15, "{}: B({k}) = {q}", method.name);
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 3);
}

/// Σ b = 1 and the row sums of A equal c, for every Runge–Kutta tableau.
#[test]
fn tableaus_are_consistent() {
    use pendula::integrator::Scheme;
    for method in METHODS {
        if let Scheme::ExplicitRk(t) = method.scheme {
            let sum: f64 = t.b.iter().sum::<f64>() / t.denominator;
            assert!((sum - 1.0).abs() < 1e-15, "{}: Σb = {sum}", method.name);
            for (row, c) in t.a.iter().zip(t.c) {
                assert!((row.iter().sum::<f64>() - c).abs() < 1e-15, "{}", method.name);
            }
            assert_eq!(t.a.len(), t.b.len());
            assert_eq!(method.requirement, Requirement::Any);
        }
    }
}

/// Compositions (Yoshida over Verlet, Tao's triple jump): the weights sum to 1 and are
/// symmetric (wᵢ = wₛ₊₁₋ᵢ), which makes the composition symmetric; for order p > 2 built
/// from a second-order symmetric map, Σ wᵢ³ = 0 (the h³ error term cancels).
#[test]
fn composition_weights_are_consistent() {
    use pendula::integrator::partitioned::Partition;
    let mut checked = 0;
    for method in METHODS {
        let weights: &[f64] = match method.scheme {
            Scheme::Partitioned(Partition::Composition(w)) => w,
            Scheme::Tao(t) => t.weights,
            _ => continue,
        };
        let name = method.name;
        assert!((weights.iter().sum::<f64>() - 1.0).abs() < 1e-14, "{name}: Σw");
        assert!(weights.iter().zip(weights.iter().rev()).all(|(a, b)| a == b), "{name}: not symmetric");
        if method.order > 2 {
            let cubes: f64 = weights.iter().map(|w| w * w * w).sum();
            assert!(cubes.abs() < 1e-13, "{name}: Σw³ = {cubes}");
        }
        checked += 1;
    }
    assert_eq!(checked, 5);
}
