//! Battery cases: writes (see main.rs).

use crate::harness::Case;

/// The cases of this class.
pub fn cases() -> Vec<Case> {
    Vec::new()
}

#[test]
fn writes() {
    crate::harness::run(cases());
}
