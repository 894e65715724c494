//! ARCHITECTURE.md stays true: every path it names in backticks exists.

use std::path::Path;

#[test]
fn architecture_paths_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let mut checked = 0;
    for (i, piece) in text.split('`').enumerate() {
        // Odd pieces are inside backticks; paths are the ones with a slash and no spaces.
        if i % 2 == 1 && piece.contains('/') && !piece.contains(' ') && !piece.contains("::") {
            assert!(root.join(piece).exists(), "ARCHITECTURE.md names `{piece}`, which does not exist");
            checked += 1;
        }
    }
    assert!(checked >= 10, "only {checked} paths found");
}
