//! Battery cases: ambiguous or out-of-range input (see main.rs). A name given twice, a
//! float beyond f64 (read as inf, a subnormal or 0), a huge integer, a mass of 1e300, an
//! amplitude a command cannot mean: refused (exit 2) with the text as typed, the flag the
//! user gave, and what is allowed.

use super::harness::Case;

/// The cases of this class.
pub fn cases() -> Vec<Case> {
    vec![
        Case::new("zero step", "simulate --dt 0").says("--dt"),
        Case::new("unknown system", "simulate pendulm").says("pendulum"),
        // A name set twice, or set and swept.
        Case::new("a name set twice", "simulate --set theta1=1 --set theta1=2")
            .says("`theta1` is set twice")
            .says("--set theta1=1")
            .says("--set theta1=2"),
        Case::new("a name set twice in a study", "compare --set m2=2 --set m2=3").says("set twice"),
        Case::new("a name set twice in animate", "animate --set theta1=1 --set theta1=2").says("set twice"),
        Case::new("set and swept in sweep", "sweep --set theta1=1 --grid theta1=0:1:4")
            .says("both set and swept")
            .says("--set theta1=1")
            .says("--grid theta1=0:1:4"),
        Case::new(
            "set and swept in bifurcation",
            "bifurcation --set drive_amplitude=1.2 --param drive_amplitude=1:1.5:10",
        )
        .says("both set and swept")
        .says("--param drive_amplitude=1:1.5:10"),
        Case::new("a fractal axis twice", "fractal --grid theta1=0:1:4 --grid theta1=0:1:8")
            .says("given twice"),
        Case::new("a method twice", "compare --methods rk4,verlet,rk4").says("rk4 is listed twice"),
        Case::new("a method twice in convergence", "convergence --methods verlet,verlet")
            .says("listed twice"),
        Case::new("an event twice", "simulate --event flip --event flip").says("--event flip").says("twice"),
        // The checkpoint's interval: a positive time, and only with a checkpoint.
        Case::new("a checkpoint interval without a checkpoint", "simulate --checkpoint-every 1")
            .says("--checkpoint <FILE>"),
        Case::new("a zero checkpoint interval", "simulate --out t.csv --checkpoint c --checkpoint-every 0")
            .says("invalid --checkpoint-every 0: must be finite and > 0"),
        Case::new("a NaN checkpoint interval", "simulate --out t.csv --checkpoint c --checkpoint-every nan")
            .says("invalid value `nan` for --checkpoint-every"),
        Case::new(
            "a checkpoint interval beyond f64",
            "simulate --out t.csv --checkpoint c --checkpoint-every 1e400",
        )
        .says("invalid value `1e400` for --checkpoint-every"),
        Case::new(
            "a negative checkpoint interval",
            "simulate --out t.csv --checkpoint c --checkpoint-every -2",
        )
        .says("invalid --checkpoint-every -2"),
        Case::new("a checkpointed trajectory on stdout", "simulate --out - --checkpoint c")
            .says("--checkpoint needs the trajectory in a file"),
        Case::new(
            "a scenario value overridden by a flag is allowed",
            "simulate --scenario s.toml --set theta1=1 --steps 1 --every 0",
        )
        .setup(|d| std::fs::write(d.join("s.toml"), "[set]\ntheta1 = \"30deg\"\n").unwrap())
        .exit(0)
        .says("double with rk4"),
        // Floats beyond f64, as typed.
        Case::new("a subnormal step", "simulate --dt=1e-320")
            .says("`1e-320`")
            .says("smallest normal")
            .brief(300),
        Case::new("a step that underflows to 0", "simulate --dt 1e-400").says("`1e-400`"),
        Case::new("a step that overflows", "simulate --dt 1e400").says("`1e400`").says("largest float"),
        Case::new("an end that overflows", "simulate --t-end 1e400").says("`1e400`").says("--t-end"),
        Case::new("an angle that overflows", "simulate --set theta1=1e400").says("`1e400`").says("`theta1`"),
        Case::new("a binding that overflows", "simulate --method tao-2 --binding 1e400").says("--binding"),
        Case::new("an infinite atol", "simulate --method dopri5 --atol inf").says("`inf`").says("finite"),
        Case::new("a NaN step", "animate --dt nan").says("NaN"),
        Case::new("a subnormal smallest step", "convergence --dt-min 1e-320")
            .says("`1e-320`")
            .says("--dt-min"),
        Case::new("an evaluation rate that underflows", "compare --evals-per-second 1e-320")
            .says("--evals-per-second"),
        Case::new("a separation that overflows", "divergence --delta 1e400").says("`1e400`").says("--delta"),
        Case::new("an energy that overflows", "poincare --energy 1e400").says("`1e400`"),
        Case::new("a tolerance below round-off", "poincare --tol 1e-300").says("--tol").says("round-off"),
        Case::new("a zero energy bound", "stability --max-energy-error 0")
            .says("--max-energy-error")
            .says("> 0"),
        // Huge integers, with the range.
        Case::new("a huge step count", "simulate --steps 99999999999999999999").says("<= 10^13"),
        Case::new("a float for a count", "simulate --every 1e3").says("`1e3`").says("--every"),
        Case::new("a huge cell count", "sweep --grid theta1=0:1:99999999999999999999").says("cells"),
        Case::new("no cells", "bifurcation --param drive_amplitude=1:1.5:0").says(">= 1"),
        Case::new("too few tolerances", "work-precision --tol-levels 1").says(">= 2"),
        Case::new("levels blamed on --levels", "convergence --levels 1000").says("--levels").says("<= 30"),
        Case::new("a huge orbit count", "poincare --count 99999999999999999999999").says("orbits"),
        // Physical values out of range.
        Case::new("a mass of 1e300", "simulate --set m1=1e300").says("`m1`").says("10^12").brief(400),
        Case::new("a length of 1e-13", "simulate pendulum --set l=1e-13").says("length"),
        Case::new("a scenario mass of 1e300", "simulate --scenario s.toml")
            .setup(|d| std::fs::write(d.join("s.toml"), "[set]\nm2 = 1e300\n").unwrap())
            .says("`m2`"),
        Case::new("an amplitude past the libration", "period --max-amplitude 200").says("below 180"),
        Case::new("an amplitude below the first", "period --max-amplitude 3").says("from 5"),
        Case::new("period's own angle", "period --set theta=1").says("from rest"),
        Case::new("oscillator-regimes' own damping", "oscillator-regimes --set c=1").says("set k and m only"),
        Case::new("poincare's own start", "poincare --set theta1=1").says("set parameters only"),
        Case::new("fractal's own start", "fractal --set theta1=1").says("set parameters only"),
        Case::new("a step longer than the interval", "lyapunov --dt 100").says("invalid --dt 100"),
        Case::new("a separation lost in rounding", "divergence --set theta1=1e10")
            .says("lost in rounding")
            .says("--delta"),
        // The report's folder must be one.
        Case::new("a report into a file", "report --out-dir f")
            .setup(|d| std::fs::write(d.join("f"), "precious").unwrap())
            .says("--out-dir f"),
        Case::new("a gallery into a file", "report --gallery f")
            .setup(|d| std::fs::write(d.join("f"), "precious").unwrap())
            .says("--gallery f"),
        // Echoes stay short.
        Case::new("a plot of a CSV with a 100 kB field", "plot t.csv")
            .setup(|d| std::fs::write(d.join("t.csv"), format!("t,x\n0,{}\n", "z".repeat(100_000))).unwrap())
            .says("is not a number")
            .says("bytes in all")
            .brief(400),
        Case::new("a 100 kB --set", "simulate")
            .arg(format!("--set=theta1={}", "9".repeat(100_000)))
            .says("`theta1`")
            .brief(400),
        // Paths are quoted whole, but a message is at most 4 KiB: its middle is elided.
        Case::new("a 100 kB --out", "simulate --steps 1")
            .arg(format!("--out={}.csv", "p".repeat(100_000)))
            .says("cannot write --out ppp")
            .says("bytes elided")
            .says("File name too long")
            .brief(4200),
        // Found by the fuzz harness (tests/fuzz): .npy headers that the claim and the reader
        // read differently, or that the reader's parser takes days over.
        Case::new("a .npy header giving its shape twice", "plot x.npy")
            .setup(|d| {
                let header =
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (1,), 'shape': (1000000000000000,), }";
                std::fs::write(d.join("x.npy"), npy(header, &[0; 8])).unwrap();
            })
            .says("x.npy")
            .says("claims [1000000000000000] values of 8 bytes"),
        Case::new("a .npy header nested 40 deep", "plot x.npy")
            .setup(|d| {
                let header = format!(
                    "{{'descr': '<f8', 'fortran_order': False, 'shape': (1,), 'x': {}1{}}}",
                    "{1: ".repeat(40),
                    "}".repeat(40)
                );
                std::fs::write(d.join("x.npy"), npy(&header, &[0; 8])).unwrap();
            })
            .says("its header nests 9 deep, more than 8"),
        Case::new("a .npy of no values along an axis too long to count", "plot x.npy")
            .setup(|d| {
                let header = "{'descr': '<f8', 'fortran_order': False, 'shape': (0, 9223372036854775808), }";
                std::fs::write(d.join("x.npy"), npy(header, &[])).unwrap();
            })
            .says("beyond counting"),
        Case::new("a .npy of values of no bytes", "plot x.npy")
            .setup(|d| {
                let header = "{'descr': '|V0', 'fortran_order': False, 'shape': (100000000000,), }";
                std::fs::write(d.join("x.npy"), npy(header, &[])).unwrap();
            })
            .says("take no bytes"),
        // The commands that only print: a misspelt choice gets the valid ones.
        Case::new("list of a misspelt kind", "list methodz")
            .says("possible values: systems, methods, presets")
            .says("'methods'"),
        Case::new("completions for an unknown shell", "completions tcsh").says("possible values: bash"),
        Case::new("man pages into a file", "man --out-dir man")
            .setup(|d| std::fs::write(d.join("man"), "x").unwrap())
            .says("cannot write --out-dir man: it is a file, not a directory"),
        Case::new("a plot of an endless file", "plot z.csv")
            .setup(|d| std::os::unix::fs::symlink("/dev/zero", d.join("z.csv")).unwrap())
            .says("z.csv: it is not a regular file"),
        // Issue 29's held-out battery. A direction written twice is a spec error naming the
        // spec and what is allowed, not "invalid value NaN".
        Case::new("a section with two directions", "simulate --steps 1 --event section:theta1=0++")
            .says("`section:theta1=0++`")
            .says("VALUE a number, then at most one + or -")
            .says("did you mean `section:theta1=0+`"),
        Case::new("a section value that is no number", "simulate --steps 1 --event section:theta1=zero")
            .says("`section:theta1=zero`")
            .says("`zero` is not a number"),
        // The energy's domain before the work estimate (which would call it too much work).
        Case::new("a Poincaré energy of 1e308", "poincare --energy 1e308")
            .says("invalid --energy 1e308: at most")
            .says("energy scales above the energy at rest"),
        // Each value in its domain, the energy together infinite: refused by every study.
        Case::new("a non-finite initial energy in stability", "stability double --set omega1=1e300")
            .says("initial energy")
            .says("must be finite"),
        Case::new("a non-finite initial energy in stability's pendulum", "stability --set omega=1e300")
            .says("initial energy"),
        Case::new("a non-finite initial energy in compare", "compare --set omega2=1e300")
            .says("initial energy"),
        Case::new("a non-finite initial energy in convergence", "convergence double --set omega1=-1e300")
            .says("initial energy"),
        Case::new("a non-finite initial energy in divergence", "divergence --set omega1=1e300")
            .says("initial energy"),
        Case::new("a non-finite initial energy in lyapunov", "lyapunov --set omega1=1e300")
            .says("initial energy"),
        Case::new(
            "a non-finite initial energy in work-precision",
            "work-precision double --set omega1=1e300",
        )
        .says("initial energy"),
        Case::new("a non-finite initial energy in animate", "animate --set omega1=1e300")
            .says("initial energy"),
        Case::new(
            "a non-finite initial energy in bifurcation",
            "bifurcation --set omega=1e300 --param drive_amplitude=1:1.5:4",
        )
        .says("initial energy"),
    ]
}

/// A .npy file (format 1) of `header` (a Python dict, padded here) and `data`.
fn npy(header: &str, data: &[u8]) -> Vec<u8> {
    let pad = (64 - (10 + header.len() + 1) % 64) % 64;
    let header = format!("{header}{}\n", " ".repeat(pad));
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.bytes());
    bytes.extend(data);
    bytes
}

#[test]
fn input() {
    super::harness::run(cases());
}
