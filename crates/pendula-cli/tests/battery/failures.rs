//! Battery cases: failures (see main.rs). A numerical failure is exit 1 from every command
//! and names its time; a method that fails inside a study is reported as failed, never with
//! numbers that read as a result; parameters that make a study's numbers meaningless are
//! refused with the reason (exit 2).

use super::harness::Case;

/// The files a study writes into `dir`, with the directory and its manifest.
fn study_files(case: Case, dir: &str, command: &str, files: &[&str]) -> Case {
    let mut case = case.creates(dir).creates(&format!("{dir}/.pendula-{command}.files"));
    for f in files {
        case = case.creates(&format!("{dir}/{f}"));
    }
    case
}

/// The cases of this class.
pub fn cases() -> Vec<Case> {
    vec![
        // A failed method is a failure, not a row of zeros.
        study_files(
            Case::new(
                "compare lists a blown-up method as failed",
                "compare double --methods euler,verlet --dt 3 --t-end 30 --out-dir o --summary s.json",
            )
            .exit(0)
            .says("wrote 7 files")
            .creates("s.json")
            .after(|d| {
                let csv = std::fs::read_to_string(d.join("o/summary.csv")).unwrap();
                let verlet = csv.lines().find(|l| l.starts_with("verlet,")).unwrap();
                // No steps, evaluations or cost, no errors: failed, with the reason and time.
                assert!(verlet.starts_with("verlet,3.0,,,,"), "{verlet}");
                assert!(verlet.contains(",,,,failed,the state became non-finite at t = 3 s"), "{verlet}");
                let s: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(d.join("s.json")).unwrap()).unwrap();
                assert_eq!(s["methods"]["verlet"]["status"], "failed");
                assert!(s["methods"]["verlet"]["steps"].is_null());
                assert_eq!(s["methods"]["euler"]["status"], "completed");
            }),
            "o",
            "compare",
            &[
                "summary.csv",
                "energy.png",
                "energy.svg",
                "trajectory.png",
                "trajectory.svg",
                "phase_euler.png",
                "phase_euler.svg",
            ],
        ),
        Case::new(
            "compare where every method fails",
            "compare double --methods gauss-legendre-4,verlet --dt 3 --t-end 30 --out-dir o",
        )
        .exit(1)
        .says("every method failed")
        .says("did not converge")
        .creates("o"),
        Case::new(
            "convergence where every run fails",
            "convergence pendulum --set damping=1e5 --methods rk4 --out-dir o",
        )
        .exit(1)
        .says("every run failed")
        .says("non-finite")
        .creates("o"),
        Case::new(
            "work-precision where every run fails",
            "work-precision pendulum --set damping=1e5 --methods rk4 --out-dir o",
        )
        .exit(1)
        .says("every run failed")
        .creates("o"),
        Case::new(
            "convergence whose reference run fails",
            "convergence driven-pendulum --set drive_frequency=1e15 --methods rk4 --out-dir o",
        )
        .exit(1)
        .says("the reference run (dop853")
        .says("t = 0 s")
        .creates("o"),
        // Every numerical failure is exit 1.
        Case::new(
            "fractal's non-finite state",
            "fractal --set g=1e300 --grid theta1=-pi:pi:4 --grid theta2=-pi:pi:4",
        )
        .exit(1)
        .says("fractal pixel")
        .says("non-finite")
        .creates("pendula-out")
        .creates("pendula-out/fractal"),
        Case::new("sweep's non-finite state", "sweep --set g=1e300 --grid theta1=-pi:pi:4")
            .exit(1)
            .says("cell 0 of the sweep")
            .says("non-finite"),
        Case::new(
            "bifurcation's non-finite state",
            "bifurcation --param drive_amplitude=1e308:1.7e308:2 --transient 100 --samples 2 --out-dir o",
        )
        .exit(1)
        .says("drive_amplitude = ")
        .says("non-finite")
        .brief(300)
        .creates("o"),
        Case::new(
            "lyapunov's non-finite state",
            "lyapunov --method euler --dt 0.5 --renormalise 0.5 --t-end 100 --transient 0",
        )
        .exit(1)
        .says("non-finite at t = 6 s"),
        Case::new("poincare's non-finite state", "poincare --method rk4 --dt 1 --count 2 --t-end 100")
            .exit(1)
            .says("non-finite"),
        Case::new("animate's non-finite state", "animate --method euler --dt 0.5 --out a.gif")
            .exit(1)
            .says("non-finite"),
        Case::new(
            "simulate's non-finite state",
            "simulate oscillator --method euler --set k=1e300 --dt 1 --out x.csv",
        )
        .exit(1)
        .says("t = 3 s"),
        Case::new("an adaptive step below its minimum", "simulate --method dopri5 --h-min 0.5 --every 0")
            .exit(1)
            .says("below the minimum"),
        // Meaningless numbers are refused, with the reason.
        Case::new("oscillator-regimes with a tiny mass", "oscillator-regimes --set m=1e-6")
            .says("w0 = sqrt(k/m) = 1000 rad/s")
            .says("meaningless"),
        Case::new("divergence from a huge angle", "divergence --set theta1=1e12deg").says("lost in rounding"),
    ]
}

#[test]
fn failures() {
    super::harness::run(cases());
}
