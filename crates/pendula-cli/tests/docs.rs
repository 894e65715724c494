//! The examples of README.md and docs/GUIDE.md run as printed: every ```sh block, and the
//! guide's scenario file (```toml) through `pendula simulate --scenario`.
//!
//! Each shell block runs in a fresh directory under `bash -e`, with the binary under test as
//! `pendula` (first on the PATH) and as `target/release/pendula`; so `cargo build --release`
//! (which would build that binary) does nothing there, and any other cargo command fails the
//! block. A block right under `<!-- example not run: REASON -->` is not run, and says why; nor
//! is the README's first block, the set-up commands (`bash scripts/test` is this test suite
//! itself, and the report it starts is run end to end by `tests/study.rs`).

use std::path::{Path, PathBuf};
use std::process::Command;

use tempfile::TempDir;

/// A fenced block of a document.
struct Block {
    /// The document and the line of the block's opening fence, for messages.
    place: String,
    lang: String,
    code: String,
    /// The reason given by an `<!-- example not run: … -->` line right above the fence.
    not_run: Option<String>,
}

const NOT_RUN: &str = "<!-- example not run:";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The fenced blocks of `doc` (relative to the repository), their indentation removed.
fn blocks(doc: &str) -> Vec<Block> {
    let text = std::fs::read_to_string(root().join(doc)).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let indent = line.len() - line.trim_start().len();
        let Some(lang) = line.trim_start().strip_prefix("```") else {
            i += 1;
            continue;
        };
        let end = (i + 1..lines.len())
            .find(|&j| lines[j].trim_start() == "```")
            .unwrap_or_else(|| panic!("{doc}:{}: a block that does not end", i + 1));
        let code: Vec<&str> = lines[i + 1..end].iter().map(|l| l.get(indent..).unwrap_or("")).collect();
        let above = if i > 0 { lines[i - 1].trim() } else { "" };
        let not_run = above.strip_prefix(NOT_RUN).map(|r| r.trim_end_matches("-->").trim().to_owned());
        found.push(Block {
            place: format!("{doc}:{}", i + 1),
            lang: lang.trim().to_owned(),
            code: code.join("\n") + "\n",
            not_run,
        });
        i = end + 1;
    }
    found
}

/// A directory holding `pendula`, the binary under test, for the PATH.
fn bin_dir() -> TempDir {
    let bin = TempDir::new().unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_pendula"), bin.path().join("pendula")).unwrap();
    bin
}

/// Runs a shell example in a fresh directory; its output when it fails.
fn run_shell(code: &str, bin: &Path) -> Result<(), String> {
    let dir = TempDir::new().unwrap();
    std::fs::create_dir_all(dir.path().join("target/release")).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_pendula"), dir.path().join("target/release/pendula"))
        .unwrap();
    let prelude = "cargo() { [ \"$*\" = 'build --release' ] && return 0; \
                   echo \"the examples' test runs no cargo $*\" >&2; return 1; }\n";
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let out = Command::new("timeout")
        .args(["600", "bash", "-e", "-c"])
        .arg(format!("{prelude}{code}"))
        .current_dir(dir.path())
        .env("PATH", path)
        .output()
        .unwrap();
    if out.status.success() {
        Ok(())
    } else {
        let tail = |b: &[u8]| {
            let s = String::from_utf8_lossy(b).into_owned();
            s[s.len().saturating_sub(2000)..].to_owned()
        };
        Err(format!("{}\nstdout: {}\nstderr: {}", out.status, tail(&out.stdout), tail(&out.stderr)))
    }
}

#[test]
fn shell_examples_run_as_printed() {
    let bin = bin_dir();
    let (mut ran, mut skipped, mut failures) = (0, Vec::new(), Vec::new());
    for doc in ["README.md", "docs/GUIDE.md"] {
        for (k, block) in blocks(doc).into_iter().enumerate() {
            if block.lang != "sh" {
                continue;
            }
            if doc == "README.md" && k == 0 {
                assert!(
                    block.code.contains("bash scripts/test"),
                    "the README's first block is the set-up: {}",
                    block.code
                );
                continue;
            }
            if let Some(reason) = block.not_run {
                assert!(
                    reason.split_whitespace().count() >= 4,
                    "{}: say why the example is not run",
                    block.place
                );
                skipped.push(block.place);
                continue;
            }
            if let Err(e) = run_shell(&block.code, bin.path()) {
                failures.push(format!("{}:\n{}\n{e}", block.place, block.code));
            }
            ran += 1;
        }
    }
    assert!(failures.is_empty(), "examples that failed:\n{}", failures.join("\n\n"));
    assert!(ran >= 4, "only {ran} shell examples ran (not run: {skipped:?})");
}

/// The guide's scenario files run: `pendula simulate --scenario FILE` writes the trajectory
/// the file names, one row per `every` steps (and the first and last).
#[test]
fn the_guides_scenario_files_run() {
    let scenarios: Vec<Block> = blocks("docs/GUIDE.md").into_iter().filter(|b| b.lang == "toml").collect();
    assert!(!scenarios.is_empty(), "no scenario file in the guide");
    for block in scenarios {
        let dir = TempDir::new().unwrap();
        std::fs::write(dir.path().join("scenario.toml"), &block.code).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_pendula"))
            .args(["simulate", "--scenario", "scenario.toml"])
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(out.status.success(), "{}: {}", block.place, String::from_utf8_lossy(&out.stderr));
        let value = |key: &str| {
            block.code.lines().find_map(|l| {
                let (k, v) = l.split_once('=')?;
                (k.trim() == key).then(|| v.split('#').next().unwrap().trim().trim_matches('"').to_owned())
            })
        };
        let file = value("out").expect("the scenario names its output");
        let rows = std::fs::read_to_string(dir.path().join(&file)).unwrap().lines().count() - 1;
        let steps = (value("t_end").unwrap().parse::<f64>().unwrap()
            / value("dt").unwrap().parse::<f64>().unwrap())
        .round();
        let every: f64 = value("every").unwrap().parse().unwrap();
        assert_eq!(rows as f64, (steps / every).ceil() + 1.0, "{}: rows of {file}", block.place);
    }
}

/// An `example not run` line stands right above a block (so it cannot outlive the example it
/// excuses), and the parser finds the blocks the tests above rely on.
#[test]
fn not_run_notes_stand_above_blocks() {
    for doc in ["README.md", "docs/GUIDE.md"] {
        let text = std::fs::read_to_string(root().join(doc)).unwrap();
        let notes = text.matches(NOT_RUN).count();
        let blocks = blocks(doc);
        assert_eq!(
            notes,
            blocks.iter().filter(|b| b.not_run.is_some()).count(),
            "{doc}: a note above no block"
        );
        assert!(blocks.iter().any(|b| b.lang == "sh" && b.not_run.is_none()), "{doc}: no shell example runs");
    }
}
