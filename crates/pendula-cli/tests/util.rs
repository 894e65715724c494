//! Helpers shared by the test modules: running the `pendula` binary, and reading what it left.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The `pendula` binary of this build, with no argument yet.
pub fn binary() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pendula"))
}

/// The `pendula` binary as assert_cmd's command, to run in `dir`.
pub fn pendula_in(dir: &Path) -> assert_cmd::Command {
    let mut cmd = assert_cmd::Command::cargo_bin("pendula").unwrap();
    cmd.current_dir(dir);
    cmd
}

/// `pendula ARGS` run in `dir`, its exit status and outputs to be asserted.
pub fn pendula(dir: &Path, args: &[&str]) -> assert_cmd::assert::Assert {
    pendula_in(dir).args(args).assert()
}

/// Runs `command` and asserts that it succeeded (a setup step: `mknod`, `mount`, a run whose
/// output a case needs).
pub fn run(command: &mut Command) {
    let out = command.output().unwrap();
    assert!(out.status.success(), "{command:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// Whether the tests run as root (mounting a tmpfs and mknod need it).
pub fn is_root() -> bool {
    static ROOT: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ROOT.get_or_init(|| {
        Command::new("id").arg("-u").output().is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
    })
}

/// The names in `dir` (not below it), sorted.
pub fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Every entry below `dir` by its path relative to `dir`: a file by its bytes, a directory as
/// `<dir>`, a symbolic link by its target, anything else as `<special>`. Two snapshots are
/// equal when nothing was written, removed, created or replaced.
pub fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for entry in entries.flatten() {
            let path = entry.path();
            let rel = path.strip_prefix(root).unwrap().to_owned();
            let Ok(meta) = std::fs::symlink_metadata(&path) else { continue };
            if meta.is_dir() {
                out.insert(rel, b"<dir>".to_vec());
                walk(root, &path, out);
            } else if meta.is_file() {
                out.insert(rel, std::fs::read(&path).unwrap_or_default());
            } else if meta.file_type().is_symlink() {
                out.insert(rel, format!("<link {:?}>", std::fs::read_link(&path).ok()).into_bytes());
            } else {
                out.insert(rel, b"<special>".to_vec());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// The contents of an earlier result that a failed or interrupted run must leave as it was.
pub const PRECIOUS: &[u8] = b"an earlier result, not to be touched\n";

/// Writes [`PRECIOUS`] to `dir/name` (making its directories), and returns its path.
pub fn precious(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, PRECIOUS).unwrap();
    path
}

/// A JSON file's value.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The texts of an SVG file's `<text>` elements, in order.
pub fn svg_texts(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    svg.split("<text")
        .skip(1)
        .map(|t| t.split_once('>').unwrap().1.split("</text>").next().unwrap().trim().to_owned())
        .collect()
}

/// A panic's message (a failed check's, a failed input's).
pub fn panic_text(e: &(dyn std::any::Any + Send)) -> String {
    e.downcast_ref::<String>()
        .cloned()
        .or_else(|| e.downcast_ref::<&str>().map(|s| (*s).to_owned()))
        .unwrap_or_else(|| "(no message)".to_owned())
}
