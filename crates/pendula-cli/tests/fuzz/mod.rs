//! The fuzz harness (issue 12): proptest, with a fixed seed and a fixed budget, feeds
//! generated and hostile input to every reader of user input, in process (through the
//! library target, `pendula_cli`, whose test hooks it sets), and checks that
//! none panics and that every refusal is an ordinary error: a message of at most
//! [`pendula_cli::MAX_MESSAGE`] bytes, which the binary prints with exit 2 (or 1 for a numerical
//! failure). An abort (an allocation of a size read from input, a stack overflow) ends the
//! test process, and fails the test as loudly.
//!
//! The targets, each a share of the budget:
//!
//! - `argv` ([`argv`]): command lines (random tokens; every subcommand with its flags and
//!   hostile values; cheap valid requests with a few mutations) through the clap parser and
//!   then [`pendula_cli::dispatch`], stopped at the command's first output
//!   ([`pendula_cli::output::validate_only`]): everything a command checks before it writes has
//!   been checked, and nothing runs. What commands check after their first output is
//!   called directly: `simulate`'s events, `plot`'s reading of its file, `merge`'s reading
//!   of the shard descriptions.
//! - `scenario` ([`files::scenario`]): `simulate --scenario` files (random bytes, valid
//!   scenarios mutated, deep nesting, huge lines) through [`pendula_cli::config::parse_scenario`]
//!   and, when read, the rest of `simulate`'s validation.
//! - `npy` ([`files::npy`]): .npy files (headers built to lie: shapes beyond the data,
//!   repeated keys, deep nesting, huge lengths) through [`pendula_cli::limits::npy_claim_from`]
//!   and then ndarray-npy's reader, as `plot` and `merge` call it after the claim.
//! - `shards` ([`files::shards`]): the shards of a real sweep and their descriptions,
//!   mutated, through `merge` ([`pendula_cli::commands::merge::run`], which writes its output in
//!   a temporary directory).
//! - `plot` ([`files::plot`]): CSV, .npy and JSON descriptions, mutated, through `plot`'s
//!   reader and its panels; every 64th case also drawn and written
//!   ([`pendula_cli::commands::plot::run`]).
//!
//! Inputs are counted and the count printed (on the real stderr, past the test harness's
//! capture). `PENDULA_FUZZ_CASES` sets the budget: 100 000 in all by default (CI, well under
//! a minute on 2 cores), 10⁷ for the documented long local run (docs/GUIDE.md, "Fuzzing").
//! `PENDULA_FUZZ_TARGETS=argv,npy` runs only those targets.

mod argv;
mod files;

use std::io::Write as _;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Mutex, MutexGuard, PoisonError};
use std::time::Instant;

use proptest::strategy::Strategy;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestError, TestRng, TestRunner};

use crate::util::panic_text;

/// Inputs in all when `PENDULA_FUZZ_CASES` is not set.
const DEFAULT_CASES: u64 = 100_000;

/// The seed of every run (each target's is this with its name mixed in): a failure in CI is
/// the same failure on a laptop.
const SEED: [u8; 32] = *b"pendula fuzz, issue 12, seed 001";

/// Stack of the harness's threads: the binary's main thread's (8 MiB on Linux), so that
/// whatever recursion the binary survives, the harness survives too, and no deeper.
const STACK: usize = 8 << 20;

/// A fuzz target: its name, its share of the budget (per mille) and how it runs `cases`
/// inputs.
struct Target {
    name: &'static str,
    per_mille: u64,
    run: fn(u32) -> Result<(), String>,
}

const TARGETS: &[Target] = &[
    Target { name: "argv", per_mille: 550, run: argv::run },
    Target { name: "scenario", per_mille: 150, run: files::scenario },
    Target { name: "npy", per_mille: 200, run: files::npy },
    // The file targets write and read real files (a few milliseconds each): fewer of them.
    Target { name: "shards", per_mille: 50, run: files::shards },
    Target { name: "plot", per_mille: 50, run: files::plot },
];

/// The budget: `PENDULA_FUZZ_CASES`, or [`DEFAULT_CASES`].
fn budget() -> u64 {
    match std::env::var("PENDULA_FUZZ_CASES") {
        Ok(text) => text.trim().parse().unwrap_or_else(|_| panic!("PENDULA_FUZZ_CASES={text}: not a count")),
        Err(_) => DEFAULT_CASES,
    }
}

/// Prints past the test harness's capture: the counts belong in CI's log.
fn report(line: &str) {
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// Runs `cases` inputs drawn from `strategy` (seeded with [`SEED`] and `name`) through
/// `check`, each under `catch_unwind`: a panic, or a `check` that says why the outcome is
/// wrong, fails the run with the input (shrunk by proptest) and the reason.
fn fuzz<S>(
    name: &str,
    cases: u32,
    strategy: S,
    check: impl Fn(&S::Value) -> Result<(), String>,
) -> Result<(), String>
where
    S: Strategy,
    S::Value: std::fmt::Debug,
{
    let config = Config {
        cases,
        failure_persistence: None,
        max_shrink_iters: 4096,
        max_shrink_time: 120_000,
        verbose: 0,
        ..Config::default()
    };
    let mut seed = SEED;
    for (i, b) in name.bytes().enumerate() {
        seed[i % 32] ^= b;
    }
    let mut runner = TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &seed));
    // The slowest input, for the report: a reader that takes seconds on a small input is a
    // way to hang the command (not asserted: timings vary with the machine).
    let slowest = std::cell::RefCell::new((std::time::Duration::ZERO, String::new()));
    // Inputs run, and those refused: the generators must get past the first checks.
    let (ran, refused) = (std::cell::Cell::new(0u64), std::cell::Cell::new(0u64));
    let outcome = runner.run(&strategy, |input| {
        let began = Instant::now();
        let before = REFUSALS.get();
        let outcome = catch_unwind(AssertUnwindSafe(|| check(&input)));
        let took = began.elapsed();
        ran.set(ran.get() + 1);
        if REFUSALS.get() > before {
            refused.set(refused.get() + 1);
        }
        if took > slowest.borrow().0 {
            *slowest.borrow_mut() = (took, clip_debug(&input).chars().take(300).collect());
        }
        match outcome {
            Ok(Ok(())) => Ok(()),
            Ok(Err(why)) => Err(TestCaseError::fail(why)),
            Err(panic) => Err(TestCaseError::fail(format!("panicked: {}", panic_text(&*panic)))),
        }
    });
    let (took, input) = slowest.into_inner();
    report(&format!(
        "fuzz {name}: {} inputs run, {} refused with an ordinary error, {} accepted; slowest {:.0} ms: {input}",
        ran.get(),
        refused.get(),
        ran.get() - refused.get(),
        took.as_secs_f64() * 1e3
    ));
    match outcome {
        Ok(()) => Ok(()),
        Err(TestError::Fail(why, input)) => {
            Err(format!("fuzz {name}: {why}\n  input (shrunk): {}", clip_debug(&input)))
        }
        Err(TestError::Abort(why)) => Err(format!("fuzz {name}: proptest gave up: {why}")),
    }
}

/// An input for a failure's message: its first 2000 characters.
fn clip_debug(input: &impl std::fmt::Debug) -> String {
    let text = format!("{input:?}");
    match text.char_indices().nth(2000) {
        None => text,
        Some((cut, _)) => format!("{}… ({} bytes in all)", &text[..cut], text.len()),
    }
}

/// Counts a refusal (an ordinary error, or clap's).
fn refused() {
    REFUSALS.set(REFUSALS.get() + 1);
}

thread_local! {
    /// Refusals on this thread, for the counts.
    static REFUSALS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// Checks that `err` is an ordinary refusal: a message that says something, with no panic
/// in it, short enough to read.
fn ordinary(err: &anyhow::Error) -> Result<(), String> {
    refused();
    let text = pendula_cli::message(err);
    if text.trim().is_empty() {
        return Err(format!("an error with an empty message: {err:?}"));
    }
    if text.len() > pendula_cli::MAX_MESSAGE {
        let head: String = text.chars().take(300).collect();
        return Err(format!(
            "a message of {} bytes (at most {}): {head}…",
            text.len(),
            pendula_cli::MAX_MESSAGE
        ));
    }
    if text.contains("panicked") {
        return Err(format!("a message about a panic: {text}"));
    }
    Ok(())
}

/// Serializes what touches the process-wide list of claimed outputs (`output::scope`):
/// `dispatch` and `merge` on different targets' threads would otherwise share it.
static CLAIMS: Mutex<()> = Mutex::new(());

fn claims() -> MutexGuard<'static, ()> {
    CLAIMS.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Sets this thread up for fuzzing: warnings silenced (millions of them would fill the
/// captured output), commands run to the end unless a target stops them.
fn quiet_thread() {
    pendula_cli::parse::QUIET_WARNINGS.set(true);
    pendula_cli::output::validate_only(false);
}

#[test]
fn every_reader_of_input_refuses_hostile_input_without_panicking() {
    let total = budget();
    let only: Option<Vec<String>> = std::env::var("PENDULA_FUZZ_TARGETS")
        .ok()
        .map(|t| t.split(',').map(|s| s.trim().to_owned()).collect());
    let targets: Vec<&Target> =
        TARGETS.iter().filter(|t| only.as_ref().is_none_or(|o| o.iter().any(|n| n == t.name))).collect();
    assert!(!targets.is_empty(), "PENDULA_FUZZ_TARGETS names no target");
    let shares: u64 = targets.iter().map(|t| t.per_mille).sum();
    // Each target's cases, the rounding given to the first so that they add up to the budget.
    let mut counts: Vec<u64> = targets.iter().map(|t| total * t.per_mille / shares).collect();
    counts[0] += total - counts.iter().sum::<u64>();
    let start = Instant::now();
    report(&format!(
        "fuzz: {total} inputs over {} targets, seed {:?}",
        targets.len(),
        String::from_utf8_lossy(&SEED)
    ));
    // Two threads (CI's cores), each taking the next target; the largest first.
    let mut order: Vec<usize> = (0..targets.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(counts[i]));
    let next = std::sync::atomic::AtomicUsize::new(0);
    // Per target run: its index and its result.
    let results: Mutex<Vec<(usize, Result<(), String>)>> = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            std::thread::Builder::new()
                .stack_size(STACK)
                .spawn_scoped(scope, || {
                    quiet_thread();
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&i) = order.get(k) else { break };
                        let began = Instant::now();
                        let cases = u32::try_from(counts[i]).expect("at most 2^32 cases a target");
                        let result = (targets[i].run)(cases);
                        let seconds = began.elapsed().as_secs_f64();
                        report(&format!(
                            "fuzz {}: {} inputs in {seconds:.1} s: {}",
                            targets[i].name,
                            counts[i],
                            if result.is_ok() {
                                "no panic, every refusal an ordinary error"
                            } else {
                                "FAILED"
                            }
                        ));
                        results.lock().unwrap_or_else(PoisonError::into_inner).push((i, result));
                    }
                })
                .expect("a fuzz thread");
        }
    });
    let results = results.into_inner().unwrap_or_else(PoisonError::into_inner);
    let failures: Vec<&String> = results.iter().filter_map(|(_, r)| r.as_ref().err()).collect();
    let ran: u64 = results.iter().map(|(i, _)| counts[*i]).sum();
    report(&format!(
        "fuzz: {ran} inputs in all in {:.1} s; {}",
        start.elapsed().as_secs_f64(),
        if failures.is_empty() {
            "no panic".to_owned()
        } else {
            format!("{} targets FAILED", failures.len())
        }
    ));
    assert!(failures.is_empty(), "{}", failures.iter().map(|f| f.as_str()).collect::<Vec<_>>().join("\n\n"));
    assert_eq!(ran, total, "every target ran its share");
}
