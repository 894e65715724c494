//! Battery cases: limits (see main.rs). Requests whose work, output or memory would take
//! hours or abort the process are refused at once (exit 2), naming the estimate, the limit
//! and `--allow-large`; hard ranges name the range; sizes read from files are checked
//! against the file before anything is allocated.

use std::path::Path;

use super::harness::Case;

/// A shard description (FILE.npy.json, as `sweep --shard` writes) with these fields.
fn description(dir: &Path, name: &str, shape: &str, count: &str, shards: &str) {
    // Format 2: the data's length and CRC-32, here those of the file the case wrote first,
    // so that merge's refusal is the claim's, not the checksum's.
    let data = std::fs::read(dir.join(name)).unwrap_or_default();
    let text = format!(
        "{{\"pendula_sweep\": 2, \"fingerprint\": \"0123456789abcdef\", \"shape\": {shape}, \"shard\": 1, \"shards\": {shards}, \"offset\": 0, \"count\": {count}, \"data\": {{\"bytes\": {}, \"crc32\": \"{:08x}\"}}}}",
        data.len(),
        crc32fast::hash(&data)
    );
    std::fs::write(dir.join(format!("{name}.json")), text).unwrap();
}

/// A .npy file of float64 whose header claims `shape` (a Python tuple) over `values` values.
fn npy(dir: &Path, name: &str, shape: &str, values: usize) {
    let mut dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    bytes.extend_from_slice(dict.as_bytes());
    bytes.extend(std::iter::repeat_n(0u8, 8 * values));
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// The cases of this class.
pub fn cases() -> Vec<Case> {
    vec![
        // Work: pendulum-steps on the ensemble engine (10^13) and the scalar integrators (10^11).
        Case::new("sweep of 10^14 cells", "sweep --grid theta1=0:1:10000000 --grid theta2=0:1:10000000")
            .says("pendulum-steps")
            .says("1e14 cells")
            .says("--allow-large"),
        Case::new("sweep of 10^18 cells", "sweep --grid theta1=0:1:1000000000 --grid theta2=0:1:1000000000")
            .says("more than any machine can hold"),
        Case::new("sweep of 10^13 steps", "sweep --grid theta1=0:1:1000 --steps 10000000000000")
            .says("1e16 pendulum-steps")
            .says("1e13"),
        // Gauss-Legendre (implicit) has no lanes (rk4 and, on separable systems, verlet now
        // run on the engine's, issue 13).
        Case::new(
            "sweep on the scalar path",
            "sweep pendulum --method gauss-legendre-4 --grid theta=0:1:100000 --t-end 100000",
        )
        .says("pendulum-steps")
        .says("scalar integrators"),
        Case::new("sweep of a pendulum on lanes", "sweep pendulum --grid theta=0:1:1000000 --t-end 1000000")
            .says("pendulum-steps")
            .says("ensemble engine"),
        Case::new("sweep array of 32 GB", "sweep --grid theta1=0:1:100000 --grid theta2=0:1:10000 --steps 1")
            .says("GiB")
            .says("--allow-large"),
        Case::new(
            "fractal of 10^10 pixels",
            "fractal --grid theta1=-pi:pi:100000 --grid theta2=-pi:pi:100000",
        )
        .says("100000 x 100000 pixels")
        .says("--allow-large"),
        Case::new("fractal to t = 10^12", "fractal --t-max 1e12").says("pendulum-steps").says("1e13"),
        Case::new(
            "fractal beyond the machine's memory even when allowed",
            "fractal --allow-large --grid theta1=-pi:pi:1000000 --grid theta2=-pi:pi:1000000",
        )
        .says("this machine's"),
        Case::new("bifurcation of 10^8 values", "bifurcation --param drive_amplitude=1:1.5:100000000")
            .says("--allow-large"),
        Case::new("bifurcation of 10^12 samples", "bifurcation --samples 1000000000000").says("<= 10^6"),
        Case::new("bifurcation with a transient of 10^12", "bifurcation --transient 1e12")
            .says("pendulum-steps")
            .says("drive periods"),
        Case::new("poincare of 10^12 orbits", "poincare --count 1000000000000").says("<= 10000"),
        Case::new("poincare to t = 10^12", "poincare --t-end 1e12").says("pendulum-steps").says("orbits"),
        // A vast energy within the domain (up to 10^12 energy scales, 2.9e13 J here): its cost.
        Case::new("poincare at a vast energy", "poincare --energy 1e10").says("crossings").says("over the limit"),
        Case::new("lyapunov to t = 10^15", "lyapunov --t-end 1e15").says("10^13").says("--t-end 1e15"),
        Case::new("lyapunov to t = 10^9", "lyapunov --t-end 1e9").says("pendulum-steps").says("tangent"),
        Case::new("simulate u64::MAX steps", "simulate --steps 18446744073709551615").says("<= 10^13"),
        Case::new("simulate 10^12 steps", "simulate --t-end 1e9 --every 0").says("1e12 pendulum-steps"),
        Case::new("simulate at dt = 1e-12", "simulate --dt 1e-12 --every 0").says("pendulum-steps"),
        Case::new("simulate streaming 1.4 TiB", "simulate --t-end 1e7 --every 1")
            .says("TiB")
            .says("--every N"),
        Case::new("simulate adaptive to t = 10^12", "simulate --method dop853 --t-end 1e12 --every 0")
            .says("adaptive steps"),
        Case::new("simulate --plot of 10^9 rows", "simulate --t-end 1e6 --every 0 --plot p.png")
            .says("--plot"),
        Case::new("simulate at rtol 1e-300", "simulate --method dopri5 --rtol 1e-300").says("1e-15"),
        Case::new(
            "simulate at rest with atol 0 ends",
            "simulate oscillator --method dopri5 --atol 0 --set x=0 --every 0",
        )
        .exit(0)
        .says("oscillator with dopri5"),
        Case::new("convergence at 10^8 levels", "convergence --levels 100000000").says("<= 30"),
        Case::new("convergence to t = 10^9", "convergence --t-end 1e9 --dt-min 1e-3 --dt-max 1e-2")
            .says("pendulum-steps"),
        Case::new("work-precision at 1000 tolerances", "work-precision --tol-levels 1000").says("<= 30"),
        Case::new("work-precision at tolerance 1e-300", "work-precision --tol-min 1e-300").says("round-off"),
        Case::new("compare to t = 10^12", "compare --t-end 1e12")
            .says("pendulum-steps")
            .says("evaluations/s"),
        Case::new("compare at 10^12 steps", "compare pendulum --dt 1e-6 --t-end 1e6").says("pendulum-steps"),
        Case::new("stability to t = 10^9", "stability --t-end 1e9").says("pendulum-steps"),
        Case::new("period at dt = 1e-9", "period --dt 1e-9").says("amplitudes"),
        Case::new("oscillator-regimes of a slow oscillator", "oscillator-regimes --set m=1e12")
            .says("pendulum-steps"),
        Case::new("animate for 10^6 s", "animate --t-end 1e6").says("frames").says("GiB"),
        Case::new("animate at dt = 1e-12", "animate --dt 1e-12").says("pendulum-steps"),
        Case::new("divergence to t = 10^9", "divergence --t-end 1e9").says("pendulum-steps"),
        // Threads: at most the cores without --allow-large, 1024 with it.
        Case::new("sweep on 100000 threads", "sweep --grid theta1=0:1:4 --threads 100000").says("cores"),
        Case::new("fractal on u64::MAX threads", "fractal --threads 18446744073709551615").says("cores"),
        Case::new(
            "bifurcation on 10^6 threads even when allowed",
            "bifurcation --allow-large --threads 1000000",
        )
        .says("at most 1024"),
        // Sizes claimed by files.
        Case::new("merge of shards claiming 10^15 cells", "merge a.npy --out m.npy")
            .setup(|d| {
                npy(d, "a.npy", "(1, 4)", 4);
                description(d, "a.npy", "[1000000000000000, 4]", "1000000000000000", "1");
            })
            .says("merge")
            .says("--allow-large"),
        Case::new("merge of a shard whose header lies", "merge a.npy --out m.npy")
            .setup(|d| {
                npy(d, "a.npy", "(1000000000000000, 1)", 4);
                description(d, "a.npy", "[4, 1]", "4", "1");
            })
            .says("header claims"),
        Case::new("merge of 10^15 shards", "merge a.npy --out m.npy")
            .setup(|d| {
                npy(d, "a.npy", "(4, 1)", 4);
                description(d, "a.npy", "[4, 1]", "4", "1000000000000000");
            })
            .says("is not a shard of a grid of 4 cells"),
        Case::new("merge of 10^15 shards of a grid that large", "merge a.npy --out m.npy")
            .setup(|d| {
                npy(d, "a.npy", "(1, 1)", 1);
                let data = std::fs::read(d.join("a.npy")).unwrap();
                let text = format!(
                    "{{\"pendula_sweep\": 2, \"fingerprint\": \"0123456789abcdef\", \"shape\": [1000000000000000, 1], \"shard\": 1, \"shards\": 1000000000000000, \"offset\": 0, \"count\": 1, \"data\": {{\"bytes\": {}, \"crc32\": \"{:08x}\"}}}}",
                    data.len(),
                    crc32fast::hash(&data)
                );
                std::fs::write(d.join("a.npy.json"), text).unwrap();
            })
            .says("shards 2/1000000000000000, 3/1000000000000000, 4/1000000000000000, 5/1000000000000000, 6/1000000000000000 and 999999999999994 more are missing"),
        Case::new("plot of a .npy whose header lies", "plot big.npy")
            .setup(|d| npy(d, "big.npy", "(1000000000000, 1000)", 16))
            .says("not a valid .npy"),
        // Scenario files: 1 MiB at most, nesting 16 deep at most, messages short.
        Case::new("scenario of a 10 MB garbage line", "simulate --scenario s.toml")
            .setup(|d| std::fs::write(d.join("s.toml"), "x".repeat(10 << 20)).unwrap())
            .says("larger than 1 MiB")
            .brief(400),
        Case::new("scenario with a 5 MB string", "simulate --scenario s.toml")
            .setup(|d| {
                std::fs::write(d.join("s.toml"), format!("system = \"{}\"\n", "a".repeat(5 << 20))).unwrap()
            })
            .says("larger than 1 MiB")
            .brief(400),
        Case::new("scenario of a 900 kB line", "simulate --scenario s.toml")
            .setup(|d| {
                std::fs::write(
                    d.join("s.toml"),
                    format!("dt = 0.1\n{}\n", "#=".repeat(450_000).replace('#', "x")),
                )
                .unwrap()
            })
            .says("line 2")
            .brief(600),
        Case::new("scenario with a 900 kB string for a number", "simulate --scenario s.toml")
            .setup(|d| {
                std::fs::write(d.join("s.toml"), format!("dt = \"{}\"\n", "a".repeat(900_000))).unwrap()
            })
            .says("line 1")
            .brief(600),
        Case::new("scenario of arrays nested 100000 deep", "simulate --scenario s.toml")
            .setup(|d| std::fs::write(d.join("s.toml"), format!("x = {}\n", "[".repeat(100_000))).unwrap())
            .says("nested more than 16 deep")
            .says("line 1"),
        Case::new("scenario of inline tables nested 100000 deep", "simulate --scenario s.toml")
            .setup(|d| {
                std::fs::write(d.join("s.toml"), format!("dt = 0.1\nx = {}\n", "{ a = ".repeat(100_000)))
                    .unwrap()
            })
            .says("nested more than 16 deep")
            .says("line 2"),
        Case::new("scenario of endless zeros", "simulate --scenario /dev/zero").says("larger than 1 MiB"),
        Case::new("scenario that is not UTF-8", "simulate --scenario s.toml")
            .setup(|d| std::fs::write(d.join("s.toml"), b"dt = 0.1\nsystem = \"\xff\xfe\"\n").unwrap())
            .says("line 2")
            .says("not UTF-8"),
        Case::new(
            "scenario brackets in a comment are no nesting",
            "simulate --scenario s.toml --steps 1 --every 0",
        )
        .setup(|d| {
            let text = format!("system = \"pendulum\" # {}\n[set]\ntheta = \"60deg\"\n", "[".repeat(40));
            std::fs::write(d.join("s.toml"), text).unwrap();
        })
        .exit(0)
        .says("pendulum with rk4"),
    ]
}

#[test]
fn limits() {
    super::harness::run(cases());
}
