//! The hardening battery: impossible, ambiguous and hostile requests to every command, each
//! with its expected exit code, a fragment of its message, and the file-system state it must
//! leave (see `harness.rs`: by default exactly what the case's setup left, byte for byte).
//! One module per class of request.
//!
//! - `limits`: resource bombs refused before any work, with the estimate and the limit;
//! - `writes`: outputs never destroyed or confused (special files, the same path twice,
//!   directories, full disks);
//! - `input`: ambiguous or out-of-range input refused with a message naming it;
//! - `failures`: numerical failures reported as failures (exit 1), never as results;
//! - `fuzz`: generated requests (proptest, a fixed seed), each of which must end cleanly.

mod failures;
mod fuzz;
mod harness;
mod input;
mod limits;
mod writes;

/// Every case of every class.
fn all() -> Vec<harness::Case> {
    [limits::cases(), writes::cases(), input::cases(), failures::cases()].into_iter().flatten().collect()
}

/// Issue 12 asks for at least 100 cases across every command; each class has its own share.
#[test]
fn the_battery_has_at_least_100_cases_in_every_class() {
    let classes = [
        ("limits", limits::cases()),
        ("writes", writes::cases()),
        ("input", input::cases()),
        ("failures", failures::cases()),
    ];
    for (name, cases) in &classes {
        eprintln!("battery {name}: {} cases", cases.len());
        assert!(cases.len() >= 10, "the {name} class has only {} cases", cases.len());
    }
    let total = all().len();
    eprintln!("battery: {total} cases in all");
    assert!(total >= 100, "the battery has {total} cases, fewer than 100");
}
