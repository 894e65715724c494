//! Battery cases: limits (see main.rs).

use crate::harness::Case;

/// The cases of this class.
pub fn cases() -> Vec<Case> {
    Vec::new()
}

#[test]
fn limits() {
    crate::harness::run(cases());
}
