//! The studies' own tests (`pendula::study`): each study's checks against closed forms and
//! its refusals of bad inputs, one module per study file. Here rather than in the library's
//! source: unit tests there compiled the whole library a second time for the tests (140 s of
//! CI's build).

mod accuracy {
    use pendula::study::accuracy::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    fn column<'a>(r: &'a Report, table: &str, name: &str) -> &'a pendula::study::Cells {
        &r.table(table).unwrap().column(name).unwrap().values
    }

    fn texts(c: &pendula::study::Cells) -> &[String] {
        match c {
            pendula::study::Cells::Text(t) => t,
            _ => panic!("a text column"),
        }
    }

    #[test]
    fn orders_on_the_oscillator_match_the_declared_ones_against_its_exact_solution() {
        let inputs = Inputs::default().name("methods", "euler,rk4,verlet");
        let r = (CONVERGENCE.run)(&inputs, &Budget::UNLIMITED).unwrap();
        assert_eq!(r.texts, vec![("reference", "exact solution".to_owned())]);
        let orders = r.table("orders").unwrap();
        let fitted = orders.column("fitted_order").unwrap().as_numbers();
        let declared = orders.column("declared_order").unwrap().as_numbers();
        assert_eq!(declared, &[1.0, 4.0, 2.0]);
        for (f, d) in fitted.iter().zip(declared) {
            assert!((f - d).abs() < 0.1, "fitted {f}, declared {d}");
        }
        // Every error is the max-norm distance to x(t) = cos t (m, k, x(0) = 1 at rest, no
        // damping: the oscillator's defaults), recomputed here for Euler's largest step (its
        // few steps keep rounding far below the error).
        let methods = texts(column(&r, "convergence", "method"));
        let dts = r.table("convergence").unwrap().column("dt").unwrap().as_numbers();
        let errors = r.table("convergence").unwrap().column("error").unwrap().as_numbers();
        let i = methods.iter().position(|m| m == "euler").unwrap();
        let (h, t) = (dts[i], r.inputs.iter().find(|(n, _)| *n == "t_end").map(|(_, v)| v.clone()).unwrap());
        let Input::Number(t) = t else { panic!("t_end") };
        let schedule = pendula::study::schedule(h, t).unwrap();
        // Explicit Euler on x'' = -x: with z = x - i v each step multiplies z by 1 + i h; the
        // run lands on t with a last step of its own.
        let n = schedule.steps as i32 - 1;
        let (rho, phi) = ((1.0 + h * h).sqrt().powi(n), f64::from(n) * h.atan());
        let (re, im) = (rho * phi.cos(), rho * phi.sin());
        let k = schedule.last_h;
        let (x, v) = (re - k * im, -(im + k * re));
        let exact = ((x - t.cos()).abs()).max((v + t.sin()).abs());
        assert!((errors[i] - exact).abs() <= 1e-8 * exact, "{} against {exact}", errors[i]);
    }

    #[test]
    fn work_precision_halves_steps_at_double_cost_and_runs_tolerances_for_the_pairs() {
        let inputs = Inputs::default()
            .name("methods", "rk4,dopri5")
            .numbers("dts", &[0.1, 0.05, 0.025])
            .number("t_end", 2.0);
        let r = (WORK_PRECISION.run)(&inputs, &Budget::UNLIMITED).unwrap();
        let t = r.table("work_precision").unwrap();
        let methods = texts(&t.column("method").unwrap().values);
        let evals = t.column("rhs_evals").unwrap().as_numbers();
        let errors = t.column("error").unwrap().as_numbers();
        let tols = t.column("tol").unwrap().as_numbers();
        let rk4: Vec<usize> = (0..methods.len()).filter(|i| methods[*i] == "rk4").collect();
        assert_eq!(rk4.len(), 3);
        for w in rk4.windows(2) {
            // Halving the step doubles the work (4 evaluations a step) and cuts the error
            // about 16-fold (order 4).
            assert_eq!(evals[w[1]], 2.0 * evals[w[0]]);
            assert!(errors[w[1]] < errors[w[0]] / 10.0, "{errors:?}");
        }
        let pair: Vec<f64> =
            (0..methods.len()).filter(|i| methods[*i] == "dopri5").map(|i| tols[i]).collect();
        assert_eq!(pair.len(), 10);
        assert_eq!((pair[0], pair[9]), (1e-3, 1e-12));
    }

    #[test]
    fn bad_steps_and_tolerances_are_named() {
        let err = |study: &'static Study, inputs: Inputs| {
            (study.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string()
        };
        let e = err(&CONVERGENCE, Inputs::default().number("levels", 1.0));
        assert!(e.contains("`levels`") && e.contains(">= 2"), "{e}");
        let e = err(&CONVERGENCE, Inputs::default().number("dt_min", 0.1).number("dt_max", 0.01));
        assert!(e.contains("`dt_min`") && e.contains("smaller than `dt_max` 0.01"), "{e}");
        let e = err(&CONVERGENCE, Inputs::default().numbers("dts", &[0.1]).number("levels", 3.0));
        assert!(e.contains("not both"), "{e}");
        let e = err(&CONVERGENCE, Inputs::default().numbers("dts", &[0.1, -0.1]));
        assert_eq!(e, "invalid value -0.1 for `dts`: must be finite and > 0");
        let e = err(&WORK_PRECISION, Inputs::default().numbers("tols", &[1e-20]));
        assert!(e.contains("`tols`") && e.contains("round-off"), "{e}");
        let e = err(&WORK_PRECISION, Inputs::default().number("tol_min", 1e-2));
        assert!(e.contains("`tol_min`") && e.contains("smaller than `tol_max`"), "{e}");
        // Every step above Tao's limit: the refusal names the largest dt allowed.
        let inputs = Inputs::default()
            .name("system", "double")
            .name("methods", "tao-4")
            .numbers("dts", &[0.01])
            .number("t_end", 2.0);
        assert_eq!(
            err(&CONVERGENCE, inputs),
            "invalid value 0.01 for `dt`: tao-4 is unstable above w dt = 1 (its binding constant w = 200 1/s): a dt of at most 0.005 s"
        );
    }
}

mod bifurcation {
    use pendula::study::bifurcation::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    /// Below the first period doubling (Baker and Gollub: g = 0.9 is periodic with one cycle
    /// per drive period), every sample of a value is the same point once the transient has
    /// died out; in the chaotic band (g = 1.5) they scatter.
    #[test]
    fn a_periodic_orbit_is_one_point_and_a_chaotic_one_scatters() {
        let run = |lo: f64, hi: f64| {
            let inputs = Inputs::default()
                .name("param", &format!("drive_amplitude={lo}:{hi}:1"))
                .number("samples", 20.0)
                .number("transient", 300.0);
            let report = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap();
            let omega = report.table("bifurcation").unwrap().column("omega").unwrap().as_numbers().to_vec();
            omega.iter().fold(f64::NEG_INFINITY, |a, b| a.max(*b))
                - omega.iter().fold(f64::INFINITY, |a, b| a.min(*b))
        };
        assert!(run(0.89, 0.91) < 1e-6);
        assert!(run(1.49, 1.51) > 0.1);
    }

    #[test]
    fn bad_inputs_name_the_value() {
        let run = |inputs: Inputs| (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string();
        assert!(
            run(Inputs::default().name("param", "theta=0:1:4"))
                .contains("not a parameter of driven-pendulum")
        );
        assert!(run(Inputs::default().name("param", "q=2:1:4")).contains("need finite LO < HI"));
        assert!(run(Inputs::default().name("system", "double")).contains("give `param`"));
        assert!(run(Inputs::default().name("system", "chain")).contains("needs a driven system"));
        assert!(run(Inputs::default().number("samples", 0.0)).contains("whole number of samples"));
        assert!(run(Inputs::default().name("variable", "omgea")).contains("did you mean `omega`"));
        let e = run(Inputs::default().name("param", "drive_frequency=-1:1:4"));
        assert!(e.contains("drive_frequency"), "{e}");
        assert!(run(Inputs::default().number("threads", 0.0)).contains("threads"));
    }
}

mod compare {
    use pendula::study::compare::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    #[test]
    fn at_equal_cost_the_symplectic_methods_spend_what_rk4_spends_and_stay_bounded() {
        // The simple pendulum from 150°, 40 evaluations per second over 3000 s: verlet and
        // symplectic Euler spend RK4's evaluations to 5 %, their energy errors stay bounded,
        // RK4's grows.
        let inputs = Inputs::default()
            .name("system", "pendulum")
            .name("methods", "rk4,verlet,symplectic-euler")
            .number("evals_per_second", 40.0)
            .number("t_end", 3000.0)
            .set("theta", 150f64.to_radians());
        let r = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap();
        let t = r.table("compare").unwrap();
        let cost = t.column("cost_evals").unwrap().as_numbers();
        for i in [1, 2] {
            assert!((cost[i] / cost[0] - 1.0).abs() < 0.05, "{cost:?}");
        }
        let pendula::study::Cells::Text(growth) = &t.column("growth").unwrap().values else { panic!("text") };
        assert_eq!(growth, &["growing", "bounded", "bounded"]);
        // The pendulum's energy scale from 150°: E(0) − V_min = m g l (1 − cos 150°), above
        // m g l = 9.81 J.
        let scale = 9.81 * (1.0 - 150f64.to_radians().cos());
        assert!((r.number("energy_scale").unwrap() - scale).abs() < 1e-12 * scale);
    }

    #[test]
    fn a_step_and_a_cost_together_are_refused() {
        let inputs = Inputs::default().number("dt", 0.01).number("evals_per_second", 100.0);
        let e = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string();
        assert!(e.contains("`dt`") && e.contains("not both"), "{e}");
    }
}

mod defaults {
    use pendula::study::defaults::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    #[test]
    fn each_study_names_each_default_once_and_a_known_system_and_method() {
        for d in ALL {
            pendula::model::find(d.system).unwrap();
            if let Some(m) = d.method {
                pendula::integrator::find(m).unwrap();
            }
            for (i, v) in d.values.iter().enumerate() {
                assert!(!d.values[..i].iter().any(|w| w.name == v.name), "{}: {} twice", d.study, v.name);
            }
        }
        assert_eq!(Value::Number(1e-9).to_string(), "1e-9");
    }
}

mod divergence {
    use pendula::study::divergence::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    /// The damped oscillator is linear: the separation of two solutions is itself a solution,
    /// whose envelope decays as e^(−c t / 2m), a fitted rate of −c/2m = −0.1 /s (closed form).
    #[test]
    fn a_linear_separation_decays_at_the_damping_rate() {
        let inputs = Inputs::default()
            .name("system", "oscillator")
            .set("c", 0.2)
            .number("delta", 1e-3)
            .number("t_end", 60.0)
            .number("saturation", 1.0);
        let report = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap();
        let rate = report.number("growth_rate").unwrap();
        assert!((rate + 0.1).abs() < 0.005, "{rate}");
    }

    #[test]
    fn bad_inputs_name_the_value() {
        let run = |inputs: Inputs| (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string();
        assert!(run(Inputs::default().number("delta", 0.0)).contains("`delta`: a finite separation, not 0"));
        assert!(run(Inputs::default().number("saturation", 1e-12)).contains("`saturation`"));
        assert!(run(Inputs::default().name("variable", "phi")).contains("phi"));
        assert!(run(Inputs::default().number("fit_from", 0.1)).contains("smaller than saturation"));
        assert!(run(Inputs::default().set("theta1", 1e12)).contains("lost in rounding"));
    }
}

mod energy_budget {
    use pendula::study::energy_budget::*;
    #[allow(unused_imports)]
    use pendula::study::*;
    use pendula::study::{Budget, Inputs};

    /// The damped simple pendulum loses exactly the energy its damping dissipates: for the
    /// small-angle (linear) form from θ₀ at rest, the exact energy is known in closed form,
    /// so E(T) − E(0) is checked against it, and W(T) must equal it (the balance is the
    /// integrator's error, far below the change at this step).
    #[test]
    fn work_balances_the_energy_lost_to_damping() {
        let (b, theta0, t_end) = (0.2, 0.1, 10.0);
        let inputs = Inputs::default()
            .name("system", "pendulum")
            .set("damping", b)
            .set("linear", 1.0)
            .set("theta", theta0)
            .number("t_end", t_end);
        let report = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap();
        // θ'' + b θ' + ω0² θ = 0 with ω0² = g/l: underdamped closed form.
        let (g, l, m) = (9.81f64, 1.0f64, 1.0f64);
        let w0 = (g / l).sqrt();
        let wd = (w0 * w0 - b * b / 4.0).sqrt();
        let a = (-b * t_end / 2.0).exp();
        let theta = theta0 * a * ((wd * t_end).cos() + b / (2.0 * wd) * (wd * t_end).sin());
        let omega = -theta0 * a * (w0 * w0 / wd) * (wd * t_end).sin();
        // The linear pendulum's energy: ½ m l² ω² + ½ m g l θ².
        let energy = |th: f64, om: f64| 0.5 * m * l * l * om * om + 0.5 * m * g * l * th * th;
        let exact_change = energy(theta, omega) - energy(theta0, 0.0);
        let change = report.number("final_energy").unwrap() - report.number("initial_energy").unwrap();
        assert!((change - exact_change).abs() < 1e-6 * exact_change.abs(), "{change} vs {exact_change}");
        let work = report.number("work").unwrap();
        assert!((work - exact_change).abs() < 1e-6 * exact_change.abs(), "W {work} vs {exact_change}");
        assert!(report.number("max_balance").unwrap() < 1e-8, "{:?}", report.number("max_balance"));
        let table = report.table("energy-budget").unwrap();
        assert_eq!(table.column("t").unwrap().as_numbers().last(), Some(&t_end));
        assert!(report.summary[1].starts_with("The balance"), "{:?}", report.summary);
    }

    #[test]
    fn a_free_system_does_no_work() {
        let inputs = Inputs::default().name("system", "oscillator").number("t_end", 5.0);
        let report = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap();
        assert_eq!(report.number("work"), Some(0.0));
        assert!(report.summary[1].starts_with("No damping or drive"), "{:?}", report.summary);
        // The preset belongs to the default system only.
        assert!(report.summary[0].starts_with("oscillator, rk4"), "{:?}", report.summary);
    }

    #[test]
    fn the_default_run_shows_each_term_and_refuses_runs_over_budget() {
        let report = (STUDY.run)(&Inputs::default(), &Budget::UNLIMITED).unwrap();
        assert!(
            report.summary[0].starts_with("double (damping = 0.1 N m s), rk4 at dt = 0.001 s to t = 20 s"),
            "{:?}",
            report.summary
        );
        assert!(report.number("work").unwrap() < -1.0, "damping dissipates: {:?}", report.number("work"));
        let e = (STUDY.run)(
            &Inputs::default(),
            &Budget { max_steps: Some(1000.0), max_values: None, max_lane_steps: None },
        )
        .unwrap_err();
        assert!(matches!(e, pendula::Error::TooLarge { .. }), "{e}");
        let e = (STUDY.run)(&Inputs::default().name("method", "verlet"), &Budget::UNLIMITED).unwrap_err();
        assert!(e.to_string().contains("verlet needs"), "{e}");
    }
}

mod lyapunov {
    use pendula::study::lyapunov::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    /// The damped driven pendulum contracts phase space at the rate 1/q: its two exponents
    /// sum to −1/q (−0.5 for q = 2), whatever the orbit (closed form: the trace of the
    /// Jacobian); its largest is positive on Baker & Gollub's chaotic orbit.
    #[test]
    fn a_dissipative_spectrum_sums_to_the_phase_space_contraction() {
        let inputs = Inputs::default()
            .name("preset", "baker-gollub-chaotic-1.5")
            .number("dt", 0.01)
            .number("t_end", 300.0)
            .number("transient", 50.0)
            .flag("spectrum", true);
        let report = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap();
        assert!((report.number("sum").unwrap() + 0.5).abs() < 1e-6, "{:?}", report.number("sum"));
        assert!(report.number("lambda_max").unwrap() > 0.05);
        assert_eq!(report.table("exponents").unwrap().rows(), 2);
        assert_eq!(report.table("lyapunov").unwrap().columns.len(), 3);
    }

    #[test]
    fn bad_inputs_name_the_value() {
        let run = |inputs: Inputs| (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string();
        assert!(run(Inputs::default().number("dt", 100.0)).contains("`dt`: must be at most `renormalise`"));
        assert!(run(Inputs::default().number("t_end", 1.0)).contains("at least 20 re-orthonormalisations"));
        let e = run(Inputs::default().name("system", "pendulum").name("preset", "baker-gollub-chaotic"));
        assert!(e.contains("it is for the system driven-pendulum, not pendulum"), "{e}");
        assert!(run(Inputs::default().name("preset", "nope")).contains("unknown preset `nope`"));
        assert!(run(Inputs::default().number("spectrum", 1.0)).contains("on or off"));
        let over = Budget { max_steps: Some(1e9), max_values: Some(1e5), max_lane_steps: None };
        let e = (STUDY.run)(&Inputs::default().number("renormalise", 1e-3), &over).unwrap_err();
        assert!(e.to_string().contains("rows of the running estimate"), "{e}");
    }
}

mod registry {
    use pendula::study::*;

    #[test]
    fn unknown_studies_and_inputs_are_named_with_suggestions() {
        let e = find("energy-budgte").unwrap_err().to_string();
        assert!(
            e.contains("unknown study `energy-budgte`") && e.contains("did you mean `energy-budget`"),
            "{e}"
        );
        let inputs = Inputs::default().number("t_edn", 3.0);
        let e = Args::new(&energy_budget::STUDY, &inputs).unwrap_err().to_string();
        assert!(e.contains("`t_edn`") && e.contains("did you mean `t_end`"), "{e}");
    }

    #[test]
    fn values_are_checked_against_their_declared_domain() {
        let args_of = |inputs: &Inputs| Args::new(&energy_budget::STUDY, inputs).map(|a| a.real("dt"));
        assert_eq!(args_of(&Inputs::default()).unwrap().unwrap(), 1e-3);
        let e = args_of(&Inputs::default().number("dt", -1.0)).unwrap().unwrap_err().to_string();
        assert_eq!(e, "invalid value -1 for `dt`: must be finite and > 0");
        let e = args_of(&Inputs::default().name("dt", "fast")).unwrap().unwrap_err().to_string();
        assert!(e.contains("`fast`") && e.contains("a number"), "{e}");
    }

    #[test]
    fn sentences_quote_four_significant_digits() {
        let cases = [
            (0.149035943, "0.1490"),
            (-25.00145685, "-25.00"),
            (1.468845978e-8, "1.469e-8"),
            (29.579, "29.58"),
            (2.5e6, "2.500e6"),
            (0.0, "0"),
            (1234.5678, "1235"),
        ];
        for (x, text) in cases {
            assert_eq!(sig(x), text);
        }
    }

    #[test]
    fn budgets_refuse_runs_over_their_limit() {
        let b = Budget { max_steps: Some(1e6), max_values: Some(10.0), max_lane_steps: None };
        assert!(b.afford(1e6, "a run").is_ok());
        let e = b.afford(2e6, "a sweep").unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "a sweep would take {} steps, over the limit of {}",
                pendula::error::Short(2e6),
                pendula::error::Short(1e6)
            )
        );
        assert!(b.afford(f64::NAN, "x").is_err());
        let e = b.afford_values(11.0, "a table").unwrap_err().to_string();
        assert_eq!(e, "a table would hold 11 table values, over the limit of 10");
        assert!(Budget::UNLIMITED.afford(1e30, "x").is_ok());
    }

    #[test]
    fn every_study_runs_on_its_defaults_and_its_report_is_consistent() {
        for study in STUDIES {
            let report = (study.run)(&Inputs::default(), &Budget::UNLIMITED).unwrap();
            assert_eq!(report.study, study.name);
            assert_eq!(report.inputs.len(), study.params.len(), "{}", study.name);
            for t in &report.tables {
                assert!(t.columns.iter().all(|c| c.len() == t.rows()), "{}", t.name);
                assert!(t.rows() > 0, "{}", t.name);
            }
            assert!(!report.summary.is_empty());
            let mut stems: Vec<&str> =
                report.tables.iter().map(|t| t.name).chain(report.plots.iter().map(|p| p.name)).collect();
            stems.sort_unstable();
            stems.dedup();
            let mut declared = study.files.to_vec();
            declared.sort_unstable();
            assert_eq!(stems, declared, "{}: the files it declares", study.name);
        }
    }
}

mod period {
    use pendula::study::period::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    /// At 170° the exact period is mpmath's 4 √(l/g) K(sin 85°) = 4.893524274105486 s
    /// (l = 1 m, g = 9.81 m/s²), and the simulated one agrees to 1e-6.
    #[test]
    fn periods_match_the_exact_period_from_an_independent_reference() {
        let report = (STUDY.run)(&Inputs::default(), &Budget::UNLIMITED).unwrap();
        let t = report.table("period").unwrap();
        let row = t.column("amplitude_deg").unwrap().as_numbers().iter().position(|a| *a == 170.0).unwrap();
        let exact = t.column("exact").unwrap().as_numbers()[row];
        let simulated = t.column("simulated").unwrap().as_numbers()[row];
        assert!((exact - 4.893_524_274_105_486).abs() < 1e-12, "{exact}");
        assert!((simulated / exact - 1.0).abs() < 1e-6, "{simulated}");
        assert!(report.number("max_rel_error_simulated").unwrap() < 1e-6);
        assert!(report.summary[0].contains("at every amplitude"), "{:?}", report.summary);
    }

    #[test]
    fn bad_amplitudes_systems_and_start_states_are_refused_naming_the_value() {
        let run = |inputs: Inputs| (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string();
        let e = run(Inputs::default().number("max_amplitude", 180.0));
        assert!(e.contains("`max_amplitude`") && e.contains("below 180"), "{e}");
        let e = run(Inputs::default().number("max_amplitude", 3.0));
        assert!(e.contains("from 5"), "{e}");
        let e = run(Inputs::default().set("theta", 1.0));
        assert!(e.contains("`theta`") && e.contains("from rest"), "{e}");
        let e = run(Inputs::default().name("system", "double"));
        assert!(e.contains("`double`") && e.contains("pendulum only"), "{e}");
        let e = (STUDY.run)(
            &Inputs::default().number("dt", 1e-9),
            &Budget { max_steps: Some(1e9), max_values: None, max_lane_steps: None },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("35 amplitudes"), "{e}");
    }
}

mod poincare {
    use pendula::study::poincare::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    /// Every crossing lies on the section θ₁ = 0 (mod 2π) and on the energy surface H = E
    /// (the double pendulum's energy, written independently of the code under test from
    /// its canonical form: H = (m₂ l₂² p₁² + (m₁ + m₂) l₁² p₂² − 2 m₂ l₁ l₂ p₁ p₂ cos Δ) /
    /// (2 m₂ l₁² l₂² (m₁ + m₂ sin² Δ)) − (m₁ + m₂) g l₁ cos θ₁ − m₂ g l₂ cos θ₂, unit masses
    /// and lengths).
    #[test]
    fn crossings_lie_on_the_section_and_the_energy_surface() {
        let inputs = Inputs::default().number("count", 3.0).number("t_end", 30.0);
        let report = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap();
        let table = report.table("poincare").unwrap();
        let col = |n: &str| table.column(n).unwrap().as_numbers().to_vec();
        let (t1, t2, p1, p2) = (col("theta1"), col("theta2"), col("p1"), col("p2"));
        assert!(t1.len() > 10, "{} crossings", t1.len());
        let g = 9.81;
        for i in 0..t1.len() {
            assert!(pendula::system::wrap_angle(t1[i]).abs() < 1e-9);
            let d = t1[i] - t2[i];
            let kinetic = (p1[i].powi(2) + 2.0 * p2[i].powi(2) - 2.0 * p1[i] * p2[i] * d.cos())
                / (2.0 * (1.0 + d.sin().powi(2)));
            let h = kinetic - 2.0 * g * t1[i].cos() - g * t2[i].cos();
            assert!((h + 15.0).abs() < 1e-6, "H = {h}");
        }
        assert_eq!(report.number("crossings").unwrap(), t1.len() as f64);
        let per_orbit: f64 =
            report.table("orbits").unwrap().column("crossings").unwrap().as_numbers().iter().sum();
        assert_eq!(per_orbit, t1.len() as f64);
    }

    #[test]
    fn bad_inputs_name_the_value() {
        let run = |inputs: Inputs| (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string();
        let e = run(Inputs::default().name("section", "theta3=0"));
        assert!(e.contains("`theta3` is not an angle of double (did you mean `theta1` or `theta2`?)"), "{e}");
        assert!(run(Inputs::default().name("section", "omega1=0")).contains("valid: theta1, theta2"));
        assert!(
            run(Inputs::default().number("count", 0.0)).contains("whole number of orbits, >= 1 and <= 10000")
        );
        assert!(run(Inputs::default().name("method", "rk4")).contains("takes fixed steps: give `dt`"));
        assert!(run(Inputs::default().set("theta1", 1.0)).contains("set parameters only"));
        assert!(
            run(Inputs::default().number("energy", 1e308)).contains("energy scales above the energy at rest")
        );
        assert!(run(Inputs::default().number("t_end", 0.01)).contains("no orbit crossed the section"));
        assert!(run(Inputs::default().number("dt", 400.0)).contains("at most `t_end`"));
        assert!(run(Inputs::default().name("system", "pendulum")).contains("two degrees of freedom"));
    }
}

mod regimes {
    use pendula::study::regimes::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    /// The resonance peak is where d/dΩ of 1/√((1 − r²)² + (2ζr)²) vanishes: r = √(1 − 2ζ²),
    /// with X k/F = 1/(2ζ√(1 − ζ²)) (closed forms, independent of the code).
    #[test]
    fn peaks_are_the_closed_form_and_the_simulation_agrees() {
        let report = (STUDY.run)(&Inputs::default(), &Budget::UNLIMITED).unwrap();
        let peaks = report.table("peaks").unwrap();
        for i in 0..peaks.rows() {
            let zeta = peaks.column("zeta").unwrap().as_numbers()[i];
            let ratio = peaks.column("drive_ratio").unwrap().as_numbers()[i];
            assert!((ratio - (1.0 - 2.0 * zeta * zeta).sqrt()).abs() < 1e-12, "{zeta}");
            let amplitude = 1.0 / (2.0 * zeta * (1.0 - zeta * zeta).sqrt());
            let exact = peaks.column("amplitude_exact").unwrap().as_numbers()[i];
            let simulated = peaks.column("amplitude_simulated").unwrap().as_numbers()[i];
            assert!((exact / amplitude - 1.0).abs() < 1e-12 && (simulated / amplitude - 1.0).abs() < 1e-6);
        }
        assert!(report.number("max_rel_amplitude_error").unwrap() < 1e-6);
        assert!(report.number("max_decay_error").unwrap() < 1e-6);
    }

    #[test]
    fn its_own_settings_and_unresolved_oscillators_are_refused() {
        let run = |inputs: Inputs| (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string();
        let e = run(Inputs::default().set("c", 1.0));
        assert!(e.contains("`c`") && e.contains("set k and m only"), "{e}");
        let e = run(Inputs::default().set("m", 1e-6));
        assert!(e.contains("w0 = sqrt(k/m) = 1000 rad/s") && e.contains("meaningless"), "{e}");
    }
}

mod round_trip {
    use pendula::study::round_trip::*;
    #[allow(unused_imports)]
    use pendula::study::*;
    use pendula::study::{Budget, Inputs};

    fn trip(method: &str) -> Report {
        (STUDY.run)(&Inputs::default().name("method", method), &Budget::UNLIMITED).unwrap()
    }

    /// On the pendulum's regular motion a symmetric method returns to round-off; RK4, not
    /// symmetric, keeps its truncation error there and back (at dt = 0.01 s its error over 20 s
    /// is about 1e-7, six orders above round-off).
    #[test]
    fn symmetric_methods_retrace_their_steps_and_rk4_does_not() {
        let verlet = trip("verlet").number("return_error").unwrap();
        let gauss = trip("gauss-legendre-4").number("return_error").unwrap();
        let rk4 = trip("rk4").number("return_error").unwrap();
        assert!(verlet < 1e-11 && gauss < 1e-11, "symmetric: {verlet:e}, {gauss:e}");
        assert!(rk4 > 1e4 * verlet.max(gauss), "rk4 {rk4:e} against symmetric {verlet:e}, {gauss:e}");
        assert!(trip("verlet").summary[1].starts_with("verlet is symmetric"));
        assert!(trip("rk4").summary[1].starts_with("rk4 is not symmetric"));
    }

    #[test]
    fn the_table_pairs_the_two_runs_at_the_same_times() {
        let r = trip("verlet");
        let table = r.table("round-trip").unwrap();
        let t = table.column("t").unwrap().as_numbers();
        assert!(t.len() >= 1000, "{} rows", t.len());
        assert_eq!(t[0], 0.0);
        assert!((t[t.len() - 1] - 20.0).abs() < 1e-9);
        // At t = t_end the two runs share the turning state.
        assert_eq!(table.column("distance").unwrap().as_numbers().last(), Some(&0.0));
        assert_eq!(r.plots[0].y.unit, "rad and rad/s combined");
    }
}

mod stability {
    use pendula::study::stability::*;
    #[allow(unused_imports)]
    use pendula::study::*;

    /// Forward Euler on the harmonic oscillator x'' = −ω² x grows the energy by the factor
    /// (1 + ω²h²) every step (closed form), so its largest step keeping the relative energy
    /// error within ε over T is the root of (1 + ω²h²)^(T/h) = 1 + ε; the bisection finds it to
    /// 1%. Verlet is stable to ω h = 2, far above.
    #[test]
    fn euler_s_limit_on_the_oscillator_is_the_closed_form() {
        let (t_end, eps) = (20.0, 0.1);
        let inputs = Inputs::default()
            .name("system", "oscillator")
            .name("methods", "euler,verlet")
            .number("t_end", t_end)
            .number("max_energy_error", eps);
        let report = (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap();
        let steps =
            report.table("stability").unwrap().column("largest_stable_dt").unwrap().as_numbers().to_vec();
        // ω = 1 rad/s for the catalogue's k = 1 N/m, m = 1 kg: solve (T/h) ln(1 + h²) = ln(1 + ε).
        let f = |h: f64| (t_end / h) * (1.0 + h * h).ln() - (1.0 + eps).ln();
        let (mut lo, mut hi) = (1e-6, 1.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid) < 0.0 { lo = mid } else { hi = mid }
        }
        assert!(steps[0] <= lo * 1.0001 && steps[0] > lo / 1.02, "euler {} vs {lo}", steps[0]);
        assert!(steps[1] > 1.0, "verlet {}", steps[1]);
        assert!(report.summary[1].contains("(euler)"), "{:?}", report.summary);
        // Verlet is stable at the top of the search range: its limit is only bounded below.
        assert!(report.summary[1].ends_with("to at least 2.000 s (verlet)"), "{:?}", report.summary);
    }

    #[test]
    fn bad_inputs_name_the_value() {
        let run = |inputs: Inputs| (STUDY.run)(&inputs, &Budget::UNLIMITED).unwrap_err().to_string();
        let e = run(Inputs::default().number("max_energy_error", 0.0));
        assert!(e.contains("`max_energy_error`"), "{e}");
        let e = run(Inputs::default().name("methods", "euler,rk5"));
        assert!(e.contains("unknown method `rk5`"), "{e}");
        let e = run(Inputs::default().number("t_end", -1.0));
        assert!(e.contains("`t_end`"), "{e}");
    }
}
