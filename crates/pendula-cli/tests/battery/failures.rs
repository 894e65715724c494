//! Battery cases: failures (see main.rs).

use crate::harness::Case;

/// The cases of this class.
pub fn cases() -> Vec<Case> {
    Vec::new()
}

#[test]
fn failures() {
    crate::harness::run(cases());
}
