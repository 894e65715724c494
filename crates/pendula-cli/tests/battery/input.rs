//! Battery cases: ambiguous or out-of-range input (see main.rs).

use crate::harness::Case;

/// The cases of this class.
pub fn cases() -> Vec<Case> {
    vec![
        Case::new("zero step", "simulate --dt 0").says("--dt"),
        Case::new("unknown system", "simulate pendulm").says("pendulum"),
    ]
}

#[test]
fn input() {
    crate::harness::run(cases());
}
