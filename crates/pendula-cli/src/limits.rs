//! What a request costs, estimated before any work, and the limits beyond which a command
//! refuses it (exit 2) unless `--allow-large` is given. Every limit is stated here once; the
//! guide's table (docs/GUIDE.md, "Limits and `--allow-large`") and `--help` say the same.
//!
//! The unit of work is the pendulum-step: one step of one state (a sweep's cell, a fractal's
//! pixel, a Lyapunov run's state or tangent vector), whatever the method. Two limits, because
//! the two engines differ a hundredfold in speed: the ensemble engine's SIMD lanes do some
//! 10⁹ pendulum-steps a second on a laptop's cores, the scalar integrators some 10⁷ (RK4 on
//! the double pendulum; implicit methods several times fewer). Both limits are about an
//! hour of a laptop's time. Bytes are counted as written: .npy at 8 bytes a value, CSV at
//! 25 (ryu's shortest round-trip form is at most 24 characters, and a separator).

use anyhow::{Result, bail};

// Value formatting, shared with the parsing layer below, where it lives.
pub use crate::parse::sci;

/// Pendulum-steps on the ensemble engine (fractal, sweep of the free double pendulum with
/// rk4 or Tao's maps, bifurcation of the driven pendulum).
pub const MAX_LANE_STEPS: f64 = 1e13;
/// Pendulum-steps on the scalar integrators (every other run).
pub const MAX_SCALAR_STEPS: f64 = 1e11;
/// Bytes of output files one command writes.
pub const MAX_OUTPUT_BYTES: f64 = (1u64 << 30) as f64;
/// Bytes of results one command holds in memory at once.
pub const MAX_MEMORY_BYTES: f64 = (2u64 << 30) as f64;
/// Bytes of an input file (`plot`, `merge`).
pub const MAX_INPUT_BYTES: f64 = (1u64 << 30) as f64;
pub use pendula_io::shard::MAX_DESCRIPTION_BYTES;
/// Orbits of a Poincaré section: more are not told apart on the figure.
pub const MAX_ORBITS: u64 = 10_000;
/// Stroboscopic samples per parameter value of a bifurcation diagram.
pub const MAX_SAMPLES: u64 = 1_000_000;
/// RK4 steps per drive period of a bifurcation diagram.
pub const MAX_STEPS_PER_PERIOD: u64 = 1_000_000;
/// Threads, even with `--allow-large`.
pub const MAX_THREADS: usize = 1024;
/// Steps of a fixed-step run (the library's own bound: 10¹³ steps take days).
pub const MAX_STEPS: u64 = 10_000_000_000_000;
pub use pendula::study::{ADAPTIVE_STEPS_PER_PERIOD, adaptive_steps, motion_period};
/// Bytes of a CSV value (at most 24 characters and a separator).
pub const CSV_BYTES_PER_VALUE: f64 = 25.0;

/// The flag that lifts the limits, as help texts and messages name it.
pub const ALLOW_LARGE_HELP: &str = "Run even when the estimate exceeds the limits (10^13 \
pendulum-steps on the ensemble engine, 10^11 on the scalar integrators, 1 GiB of output, \
2 GiB of memory, four threads per core).";

/// What an estimate counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cost {
    /// Pendulum-steps on the ensemble engine's SIMD lanes.
    LaneSteps,
    /// Pendulum-steps on the scalar integrators.
    Steps,
    /// Bytes written to files.
    Output,
    /// Bytes held in memory at once.
    Memory,
    /// Bytes read from an input file.
    Input,
}

impl Cost {
    /// The limit, and why it is there.
    pub fn limit(self) -> (f64, &'static str) {
        match self {
            Cost::LaneSteps => (MAX_LANE_STEPS, "about an hour of a laptop's cores on the ensemble engine"),
            Cost::Steps => (MAX_SCALAR_STEPS, "about an hour of a laptop's cores on the scalar integrators"),
            Cost::Output => (MAX_OUTPUT_BYTES, "of output files"),
            Cost::Memory => (MAX_MEMORY_BYTES, "of memory"),
            Cost::Input => (MAX_INPUT_BYTES, "of input read"),
        }
    }

    fn amount(self, x: f64) -> String {
        match self {
            Cost::LaneSteps | Cost::Steps => format!("{} pendulum-steps", round(x)),
            Cost::Output | Cost::Memory | Cost::Input => bytes(x),
        }
    }
}

/// An estimate of one cost of a request, and how it was reckoned.
#[derive(Debug, Clone)]
pub struct Estimate {
    pub cost: Cost,
    pub amount: f64,
    /// The factors, for the message: `512 x 512 pixels x 30000 steps`.
    pub how: String,
}

impl Estimate {
    pub fn new(cost: Cost, amount: f64, how: impl Into<String>) -> Self {
        Estimate { cost, amount, how: how.into() }
    }
}

/// Refuses the request when an estimate exceeds its limit and `allow_large` is not set;
/// even with it, memory beyond the machine's (an allocation that would abort the process).
pub fn check(command: &str, allow_large: bool, estimates: &[Estimate]) -> Result<()> {
    for e in estimates {
        let (limit, why) = e.cost.limit();
        // A NaN estimate (from a NaN input that slipped through) is refused too.
        if (e.amount.is_nan() || e.amount > limit) && !allow_large {
            bail!(
                "{command}: refusing a request of about {} ({}), over the limit of {} ({why}); give --allow-large to run it anyway",
                e.cost.amount(e.amount),
                e.how,
                e.cost.amount(limit),
            );
        }
        if e.cost == Cost::Memory
            && let Some(total) = physical_memory()
            && (e.amount.is_nan() || e.amount > total)
        {
            bail!(
                "{command}: the request needs about {} of memory ({}), more than this machine's {}, even with --allow-large",
                bytes(e.amount),
                e.how,
                bytes(total)
            );
        }
    }
    Ok(())
}

/// The machine's memory, bytes (Linux: /proc/meminfo), if known.
fn physical_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kb: f64 =
        text.lines().find(|l| l.starts_with("MemTotal:"))?.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

/// The machine's cores (1 when unknown).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Threads allowed per core without `--allow-large`: a few, so that a 2-core machine can show
/// that results do not depend on the thread count (1, 2, 3 ... 8), and no more, since threads
/// beyond the cores only take turns.
pub const THREADS_PER_CORE: usize = 4;

/// `--threads`: a whole number from 1 to [`THREADS_PER_CORE`] times the machine's cores (to
/// [`MAX_THREADS`] with `--allow-large`), or every core when not given. More threads than
/// cores is allowed with a warning: the results are the same bit for bit, only not faster.
pub fn threads(text: Option<&str>, allow_large: bool) -> Result<usize> {
    let cores = cores();
    let Some(text) = text else { return Ok(cores) };
    let n = crate::parse::parse_count("--threads", text, 1, u64::MAX, "threads")?;
    let most = THREADS_PER_CORE * cores;
    if n > most as u64 && !allow_large {
        bail!(
            "invalid --threads {}: this machine has {cores} cores, and more threads than cores only take turns; give 1 to {most}, or --allow-large to insist (up to {MAX_THREADS})",
            round(n as f64)
        );
    }
    if n > MAX_THREADS as u64 {
        bail!(
            "invalid --threads {}: at most {MAX_THREADS}, even with --allow-large (this machine has {cores} cores)",
            round(n as f64)
        );
    }
    if n > cores as u64 && !crate::parse::quiet() {
        eprintln!(
            "warning: --threads {n} is more than this machine's {cores} cores: the threads take turns (the results are the same, bit for bit, only not faster)"
        );
    }
    Ok(n as usize)
}

pub use pendula::error::approx as round;

pub use pendula_io::value::bytes;

/// Steps of a run of `span` seconds at step `h`, at least 1 (as [`pendula::RunSpec::schedule`]
/// counts them, without its checks: for estimates of validated values).
pub fn steps(span: f64, h: f64) -> f64 {
    (span / h).ceil().max(1.0)
}

pub use pendula_io::npy::Claim as NpyClaim;

/// Reads and checks the header of the .npy at `path`: see [`pendula_io::npy::claim`].
pub fn npy_claim(path: &std::path::Path) -> Result<NpyClaim> {
    Ok(pendula_io::npy::claim(path)?)
}

/// [`npy_claim`] of the .npy `file`, `length` bytes long, named `name` in messages (the fuzz
/// harness, `tests/fuzz/`, reads generated files from memory): see
/// [`pendula_io::npy::claim_from`].
pub fn npy_claim_from(file: impl std::io::Read, length: u64, name: &str) -> Result<NpyClaim> {
    Ok(pendula_io::npy::claim_from(file, length, name)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_read_well() {
        assert_eq!(bytes(512.0), "512 B");
        assert_eq!(bytes(1536.0), "1.5 KiB");
        assert_eq!(bytes(MAX_OUTPUT_BYTES), "1 GiB");
        assert_eq!(bytes(8e15), "7276 TiB");
        assert_eq!(bytes(3.2e10), "29.8 GiB");
        assert_eq!(round(12345.0), "12345");
        assert_eq!(round(1e14), "1e14");
        assert_eq!(round(7.86432e19), "7.864e19");
        assert_eq!(sci(1e-12), "1e-12");
    }

    #[test]
    fn an_estimate_over_its_limit_is_refused_unless_allowed() {
        let big = [Estimate::new(Cost::Steps, 1e12, "10 x 1e11")];
        let err = check("simulate", false, &big).unwrap_err().to_string();
        for needle in ["1e12 pendulum-steps", "10 x 1e11", "1e11", "--allow-large"] {
            assert!(err.contains(needle), "`{needle}` not in {err}");
        }
        assert!(check("simulate", true, &big).is_ok());
        assert!(check("simulate", false, &[Estimate::new(Cost::Steps, 1e11, "")]).is_ok());
        // NaN is no estimate to run on.
        assert!(check("simulate", false, &[Estimate::new(Cost::Output, f64::NAN, "")]).is_err());
    }

    #[test]
    fn memory_beyond_the_machine_is_refused_even_when_allowed() {
        let huge = [Estimate::new(Cost::Memory, 1e30, "a lot")];
        if physical_memory().is_some() {
            let err = check("fractal", true, &huge).unwrap_err().to_string();
            assert!(err.contains("this machine's"), "{err}");
        }
    }
}
