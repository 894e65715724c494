//! Battery cases: writes (see main.rs). Outputs are never destroyed or confused: a FIFO or a
//! device node is written in place and left a node; two outputs of one run that are one
//! file, a summary onto one of the run's own files, `merge` onto its input, a directory where
//! a file belongs and `-` where stdout is not taken are refused before the run, and leave
//! everything as it was; a full device reports the path and replaces nothing; and `merge`
//! checks every shard against its description.
//!
//! The device nodes are the cases' own, made with mknod in their directory (null: 1,3; full:
//! 1,7), never the system's /dev; making them needs root, as CI has (such cases are skipped,
//! saying so, without it).

use std::path::Path;
use std::process::Command;

use super::harness::Case;
use crate::util::{PRECIOUS, binary, run};

fn precious(dir: &Path, name: &str) {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, PRECIOUS).unwrap();
}

/// A character device `name` (major, minor) in `dir`.
fn mknod(dir: &Path, name: &str, major: u32, minor: u32) {
    run(Command::new("mknod").arg(dir.join(name)).args(["c", &major.to_string(), &minor.to_string()]));
}

/// A private /dev/null.
fn null(dir: &Path, name: &str) {
    mknod(dir, name, 1, 3);
}

/// A private /dev/full: every write fails with ENOSPC.
fn full(dir: &Path, name: &str) {
    mknod(dir, name, 1, 7);
}

fn mkfifo(dir: &Path, name: &str) {
    run(Command::new("mkfifo").arg(dir.join(name)));
}

/// `pendula ARGS` in `dir`, for a case's setup; it must succeed.
fn pendula(dir: &Path, args: &str) {
    run(binary().args(args.split_whitespace()).current_dir(dir));
}

/// A small sweep of 6 cells, whole (`whole.npy`) and in three shards of 2 cells each
/// (`p1.npy` … `p3.npy`, with their descriptions).
const SWEEP: &str = "sweep --grid theta1=0:1:6 --t-end 0.1";

fn shards(dir: &Path) {
    pendula(dir, &format!("{SWEEP} --out whole.npy"));
    for k in 1..=3 {
        pendula(dir, &format!("{SWEEP} --shard {k}/3 --out p{k}.npy"));
    }
}

/// Edits a shard's description.
fn edit(dir: &Path, json: &str, change: impl Fn(&mut serde_json::Value)) {
    let path = dir.join(json);
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    change(&mut doc);
    std::fs::write(path, serde_json::to_vec_pretty(&doc).unwrap()).unwrap();
}

/// The JSON summary that a case wrote into a FIFO.
fn json(bytes: &[u8]) -> serde_json::Value {
    serde_json::from_slice(bytes)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(bytes)))
}

const FAST: &str = "simulate pendulum --t-end 1";
const STABILITY: &str = "stability oscillator --methods euler --t-end 10";
const COMPARE: &str = "compare pendulum --methods rk4 --t-end 1";
const FRACTAL: &str = "fractal --grid theta1=-3:3:8 --grid theta2=-3:3:8 --t-max 1";

/// The cases of this class.
pub fn cases() -> Vec<Case> {
    let mut cases = special_files();
    cases.extend(same_file_twice());
    cases.extend(directories());
    cases.extend(stdout());
    cases.extend(out_dirs());
    cases.extend(merge());
    cases.extend(checkpoints());
    cases
}

/// FIFOs and device nodes are written in place and stay nodes; a full one fails with the path.
fn special_files() -> Vec<Case> {
    vec![
        Case::new("trajectory onto a null device", &format!("{FAST} --out null"))
            .needs_root()
            .setup(|d| null(d, "null"))
            .exit(0)
            .says("wrote null"),
        Case::new("summary onto a null device", &format!("{FAST} --every 0 --summary null"))
            .needs_root()
            .setup(|d| null(d, "null"))
            .exit(0),
        Case::new("one null device for several outputs", &format!("{FAST} --out null --summary null"))
            .needs_root()
            .setup(|d| null(d, "null"))
            .exit(0),
        Case::new("summary onto a full device", &format!("{FAST} --every 0 --summary full"))
            .needs_root()
            .setup(|d| full(d, "full"))
            .exit(1)
            .says("cannot write --summary full: No space left on device"),
        Case::new("trajectory onto a full device", &format!("{FAST} --out full"))
            .needs_root()
            .setup(|d| full(d, "full"))
            .exit(1)
            .says("cannot write --out full: No space left on device"),
        Case::new(
            "a full summary device keeps the trajectory's earlier file",
            &format!("{FAST} --out x.csv --summary full"),
        )
        .needs_root()
        .setup(|d| {
            full(d, "full");
            precious(d, "x.csv");
        })
        .exit(1)
        .says("--summary full"),
        Case::new("study summary onto a full device", &format!("{STABILITY} --out-dir s --summary full"))
            .needs_root()
            .setup(|d| {
                full(d, "full");
                precious(d, "s/stability.csv");
            })
            .exit(1)
            .says("cannot write --summary full: No space left on device"),
        Case::new("fractal summary onto a full device", &format!("{FRACTAL} --summary full"))
            .needs_root()
            .setup(|d| full(d, "full"))
            .exit(1)
            .says("--summary full"),
        Case::new("sweep onto a full device", &format!("{SWEEP} --out full.npy"))
            .needs_root()
            .setup(|d| full(d, "full.npy"))
            .exit(1)
            .says("cannot write --out full.npy: No space left on device"),
        Case::new("animation onto a null device", "animate pendulum --t-end 0.2 --out null.gif")
            .needs_root()
            .setup(|d| null(d, "null.gif"))
            .exit(0),
        Case::new("plot onto a full device", "plot x.csv --out full.png")
            .needs_root()
            .setup(|d| {
                pendula(d, &format!("{FAST} --out x.csv"));
                full(d, "full.png");
            })
            .exit(1)
            .says("cannot write --out full.png"),
        Case::new("a socket takes no file", &format!("{FAST} --summary sock"))
            .setup(|d| {
                // Bound and dropped: the socket's node stays.
                std::os::unix::net::UnixListener::bind(d.join("sock")).unwrap();
            })
            .says("it is a socket"),
        Case::new("summary into a FIFO", &format!("{FAST} --every 0 --summary ff"))
            .setup(|d| mkfifo(d, "ff"))
            .reads_fifo("ff", |b| assert_eq!(json(b)["system"], "pendulum"))
            .exit(0),
        Case::new("CSV trajectory into a FIFO", &format!("{FAST} --out ff"))
            .setup(|d| mkfifo(d, "ff"))
            .reads_fifo("ff", |b| {
                let text = String::from_utf8_lossy(b);
                assert!(text.starts_with("t,theta,omega,energy\n"), "{}", &text[..40.min(text.len())]);
                assert_eq!(text.lines().count(), 1002);
            })
            .exit(0),
        Case::new(".npy trajectory into a FIFO (spooled)", &format!("{FAST} --out ff.npy"))
            .setup(|d| mkfifo(d, "ff.npy"))
            .reads_fifo("ff.npy", |b| {
                use ndarray_npy::ReadNpyExt;
                let a = ndarray::Array2::<f64>::read_npy(b).unwrap();
                assert_eq!(a.dim(), (1001, 4));
                assert_eq!(a[[1000, 0]], 1.0);
            })
            .exit(0),
        Case::new("study summary into a FIFO", &format!("{STABILITY} --out-dir s --summary ff"))
            .setup(|d| mkfifo(d, "ff"))
            .reads_fifo("ff", |b| {
                let rows = json(b)["tables"]["stability"].clone();
                let euler =
                    rows.as_array().unwrap().iter().find(|r| r["method"] == "euler").cloned().unwrap();
                assert!(euler["largest_stable_dt"].is_number());
            })
            .creates("s/")
            .exit(0),
        Case::new("sweep into a FIFO", &format!("{SWEEP} --out ff.npy"))
            .setup(|d| mkfifo(d, "ff.npy"))
            .reads_fifo("ff.npy", |b| assert!(b.starts_with(b"\x93NUMPY"), "{} bytes", b.len()))
            // The array's description (axes, columns, units) beside it, a regular file.
            .creates("ff.npy.json")
            .exit(0),
        Case::new("two outputs onto one FIFO", &format!("{FAST} --out ff --summary ff"))
            .setup(|d| mkfifo(d, "ff"))
            .reads_fifo("ff", |b| assert!(b.is_empty(), "{} bytes written", b.len()))
            .says("same file"),
    ]
}

/// Two outputs of one run that are one file, refused before the run.
fn same_file_twice() -> Vec<Case> {
    vec![
        Case::new("--out and --summary the same file", &format!("{FAST} --out x.csv --summary x.csv"))
            .setup(|d| precious(d, "x.csv"))
            .says("--summary x.csv and --out x.csv are the same file"),
        Case::new("summary onto the default trajectory", &format!("{FAST} --summary trajectory.csv"))
            .says("are the same file"),
        Case::new("summary onto the plot", &format!("{FAST} --plot p.png --summary p.png")).says("same file"),
        Case::new("the same file by another name", &format!("{FAST} --out x.csv --summary ./sub/../x.csv"))
            .setup(|d| std::fs::create_dir(d.join("sub")).unwrap())
            .says("same file"),
        Case::new("the same file through a symlink", &format!("{FAST} --out x.csv --summary link.json"))
            .setup(|d| {
                precious(d, "x.csv");
                std::os::unix::fs::symlink("x.csv", d.join("link.json")).unwrap();
            })
            .says("same file"),
        Case::new(
            "the same new file through a dangling symlink",
            &format!("{FAST} --out x.csv --summary link.json"),
        )
        .setup(|d| std::os::unix::fs::symlink("x.csv", d.join("link.json")).unwrap())
        .says("same file"),
        Case::new("the same file through a hard link", &format!("{FAST} --out a.csv --summary b.json"))
            .setup(|d| {
                precious(d, "a.csv");
                std::fs::hard_link(d.join("a.csv"), d.join("b.json")).unwrap();
            })
            .says("same file"),
        Case::new(
            "a summary onto compare's own figure",
            &format!("{COMPARE} --summary pendula-out/compare/energy.png"),
        )
        .setup(|d| precious(d, "pendula-out/compare/energy.png"))
        .says("is one of the files that compare writes"),
        Case::new(
            "a summary onto a phase portrait",
            &format!("{COMPARE} --out-dir c --summary c/phase_rk4.svg"),
        )
        .says("is one of the files that compare writes in --out-dir c"),
        Case::new(
            "a summary onto the study's table",
            &format!("{STABILITY} --out-dir s --summary s/stability.csv"),
        )
        .setup(|d| precious(d, "s/stability.csv"))
        .says("one of the files that stability writes"),
        Case::new(
            "a summary onto the study's manifest",
            &format!("{STABILITY} --out-dir s --summary s/.pendula-stability.files"),
        )
        .says("one of the files that stability writes"),
        Case::new("a summary onto the fractal's picture", &format!("{FRACTAL} --out f.npy --summary f.png"))
            .says("--summary f.png and --out f.png are the same file"),
        Case::new(
            "a summary onto the fractal's flags",
            &format!("{FRACTAL} --summary pendula-out/fractal/fractal-converged.npy"),
        )
        .says("one of the files that fractal writes"),
        Case::new(
            "a summary onto the shard's description",
            &format!("{SWEEP} --shard 1/2 --out s.npy --summary s.npy.json"),
        )
        .says("same file"),
        Case::new("a summary onto the sweep", &format!("{SWEEP} --out s.npy --summary s.npy"))
            .setup(|d| precious(d, "s.npy"))
            .says("same file"),
        Case::new("a plot onto the file it draws", "plot x.png --out x.png")
            .setup(|d| precious(d, "x.png"))
            .says("--out x.png is the input file x.png"),
        Case::new("summary and trajectory on stdout", &format!("{FAST} --out - --summary -"))
            .says("would both write to stdout"),
    ]
}

/// A directory where a file belongs, refused before the run.
fn directories() -> Vec<Case> {
    let dir = |d: &Path, name: &str| std::fs::create_dir_all(d.join(name)).unwrap();
    vec![
        Case::new("trajectory onto a directory", &format!("{FAST} --out d.csv"))
            .setup(move |d| dir(d, "d.csv"))
            .says("it is a directory"),
        Case::new("summary onto a directory", &format!("{FAST} --summary d"))
            .setup(move |d| dir(d, "d"))
            .says("cannot write --summary d: it is a directory"),
        Case::new("summary path ending in a slash", &format!("{FAST} --summary new/"))
            .says("names a directory"),
        Case::new("study summary onto a directory", &format!("{COMPARE} --summary d"))
            .setup(move |d| dir(d, "d"))
            .says("--summary d: it is a directory"),
        Case::new("a directory in the place of a study's figure", &format!("{COMPARE} --out-dir c"))
            .setup(move |d| {
                dir(d, "c/energy.png");
                precious(d, "c/summary.csv");
            })
            .says("is a directory where compare writes a file"),
        Case::new("a directory in the place of a phase portrait", &format!("{COMPARE} --out-dir c"))
            .setup(move |d| dir(d, "c/phase_rk4.png"))
            .says("c/phase_rk4.png is a directory"),
        Case::new("a directory in the place of the fractal's picture", &format!("{FRACTAL} --out-dir f"))
            .setup(move |d| dir(d, "f/fractal.png"))
            .says("is a directory where fractal writes a file"),
        Case::new("a file as the study directory", &format!("{STABILITY} --out-dir s"))
            .setup(|d| precious(d, "s"))
            .says("it is a file, not a directory"),
        Case::new("merge onto a directory", "merge p1.npy p2.npy p3.npy --out d.npy")
            .setup(move |d| {
                shards(d);
                dir(d, "d.npy");
            })
            .says("--out d.npy: it is a directory"),
        Case::new("sweep into a missing directory", &format!("{SWEEP} --out no/s.npy"))
            .says("the directory no does not exist"),
    ]
}

/// `-` is stdout where a command takes it, and refused elsewhere: never a file named `-`.
fn stdout() -> Vec<Case> {
    vec![
        Case::new("trajectory on stdout", &format!("{FAST} --out -")).exit(0),
        Case::new("study summary on stdout", &format!("{STABILITY} --out-dir s --summary -"))
            .creates("s/")
            .exit(0),
        Case::new("merge to stdout", "merge p1.npy p2.npy p3.npy --out -")
            .setup(shards)
            .says("merge writes a .npy file, not stdout"),
        Case::new("sweep to stdout", &format!("{SWEEP} --out -"))
            .says("sweep writes a .npy file, not stdout"),
        Case::new("fractal to stdout", &format!("{FRACTAL} --out -")).says("not to stdout"),
        Case::new("animation to stdout", "animate pendulum --t-end 0.2 --out -").says("not stdout"),
        Case::new("plot to stdout", "plot x.csv --out -")
            .setup(|d| pendula(d, &format!("{FAST} --out x.csv")))
            .says("not stdout"),
        Case::new("a study directory on stdout", &format!("{STABILITY} --out-dir -"))
            .says("cannot go to stdout"),
        Case::new("man pages into a directory `-`", "man --out-dir -").says("cannot go to stdout"),
    ]
}

/// A study command refused or failed leaves no directory it created, and every earlier file.
fn out_dirs() -> Vec<Case> {
    vec![
        Case::new("refused summary, no study directory left", &format!("{COMPARE} --summary no/s.json"))
            .says("--summary no/s.json"),
        Case::new(
            "refused summary, nested study directory removed",
            &format!("{STABILITY} --out-dir a/b/c --summary no/s.json"),
        )
        .says("the directory no does not exist"),
        Case::new(
            "refused summary, existing study directory kept",
            &format!("{STABILITY} --out-dir s --summary no/s.json"),
        )
        .setup(|d| precious(d, "s/stability.png"))
        .says("--summary no/s.json"),
        Case::new("no crossing, no Poincaré directory left", "poincare --t-end 0.01")
            .says("no orbit crossed"),
        Case::new("refused lyapunov summary, no directory left", "lyapunov --t-end 20 --summary d")
            .setup(|d| std::fs::create_dir(d.join("d")).unwrap())
            .says("it is a directory"),
        Case::new(
            "animation too small, no default directory left",
            "animate pendulum --t-end 0.2 --size 64x64",
        )
        .says("--size"),
        Case::new("study re-run writes its files", &format!("{STABILITY} --out-dir s --summary s.json"))
            .setup(|d| precious(d, "s/notes.txt"))
            .creates("s/")
            .creates("s.json")
            .exit(0)
            .after(|d| assert_eq!(std::fs::read(d.join("s/notes.txt")).unwrap(), PRECIOUS)),
    ]
}

/// `merge` trusts no shard: each description is checked against the grid and its data.
fn merge() -> Vec<Case> {
    const ALL: &str = "merge p1.npy p2.npy p3.npy --out m.npy";
    vec![
        Case::new("merged shards equal the whole sweep", ALL).setup(shards).creates("m.npy").exit(0).after(
            |d| {
                assert_eq!(
                    std::fs::read(d.join("m.npy")).unwrap(),
                    std::fs::read(d.join("whole.npy")).unwrap()
                )
            },
        ),
        Case::new("merge onto one of its shards", "merge p1.npy p2.npy p3.npy --out p1.npy")
            .setup(shards)
            .says("--out p1.npy is the input shard p1.npy"),
        Case::new("merge onto a shard's description", "merge p1.npy p2.npy p3.npy --out p2.npy.json")
            .setup(shards)
            .says("invalid --out p2.npy.json"),
        Case::new(
            "merge onto a shard's description through a symlink",
            "merge p1.npy p2.npy p3.npy --out m.npy",
        )
        .setup(|d| {
            shards(d);
            std::os::unix::fs::symlink("p2.npy.json", d.join("m.npy")).unwrap();
        })
        .says("--out m.npy is the shard description p2.npy.json"),
        Case::new("merge onto a shard by another name", "merge p1.npy p2.npy p3.npy --out ./p3.npy")
            .setup(shards)
            .says("is the input shard p3.npy"),
        Case::new("a description lying about its offset", ALL)
            .setup(|d| {
                shards(d);
                edit(d, "p2.npy.json", |j| j["offset"] = 0.into());
            })
            .says("p2.npy.json: the description says cells 0 to 2"),
        Case::new("a description lying about its extent", ALL)
            .setup(|d| {
                shards(d);
                edit(d, "p3.npy.json", |j| j["count"] = 1.into());
            })
            .says("does not match the grid"),
        Case::new("two shards' data swapped", ALL)
            .setup(|d| {
                shards(d);
                std::fs::rename(d.join("p1.npy"), d.join("tmp.npy")).unwrap();
                std::fs::rename(d.join("p2.npy"), d.join("p1.npy")).unwrap();
                std::fs::rename(d.join("tmp.npy"), d.join("p2.npy")).unwrap();
            })
            .says("p1.npy: its CRC-32 is"),
        Case::new("a corrupted shard", ALL)
            .setup(|d| {
                shards(d);
                let path = d.join("p3.npy");
                let mut bytes = std::fs::read(&path).unwrap();
                let last = bytes.len() - 1;
                bytes[last] ^= 1;
                std::fs::write(path, bytes).unwrap();
            })
            .says("p3.npy: its CRC-32 is"),
        Case::new("a truncated shard", ALL)
            .setup(|d| {
                shards(d);
                let path = d.join("p2.npy");
                let bytes = std::fs::read(&path).unwrap();
                std::fs::write(path, &bytes[..bytes.len() - 8]).unwrap();
            })
            .says("the file is truncated"),
        Case::new("a missing shard", "merge p1.npy p3.npy --out m.npy")
            .setup(shards)
            .says("shard 2/3 is missing: give all 3 shards"),
        Case::new("two missing shards", "merge p3.npy --out m.npy")
            .setup(shards)
            .says("shards 1/3, 2/3 are missing"),
        Case::new("a shard given twice", "merge p1.npy p2.npy p2.npy p3.npy --out m.npy")
            .setup(shards)
            .says("p2.npy and p2.npy are both shard 2/3"),
        Case::new("a shard and its copy", "merge p1.npy p2.npy c2.npy p3.npy --out m.npy")
            .setup(|d| {
                shards(d);
                std::fs::copy(d.join("p2.npy"), d.join("c2.npy")).unwrap();
                std::fs::copy(d.join("p2.npy.json"), d.join("c2.npy.json")).unwrap();
            })
            .says("p2.npy and c2.npy are both shard 2/3"),
        Case::new("a shard of another sweep", "merge o1.npy p2.npy p3.npy --out m.npy")
            .setup(|d| {
                shards(d);
                pendula(d, "sweep --grid theta1=0:1:6 --t-end 0.2 --shard 1/3 --out o1.npy");
            })
            .says("p2.npy is a shard of another sweep than o1.npy"),
        Case::new("a description of the first format", ALL)
            .setup(|d| {
                shards(d);
                edit(d, "p1.npy.json", |j| j["pendula_sweep"] = 1.into());
            })
            .says("format 1, which has no checksum"),
        Case::new("a description of a newer format", ALL)
            .setup(|d| {
                shards(d);
                edit(d, "p1.npy.json", |j| j["pendula_sweep"] = 99.into());
            })
            .says("format 99, written by a newer pendula"),
        Case::new("a description without a checksum", ALL)
            .setup(|d| {
                shards(d);
                edit(d, "p3.npy.json", |j| {
                    j.as_object_mut().unwrap().remove("data");
                });
            })
            .says("p3.npy.json has no `data`"),
        Case::new("a shard without its description", ALL)
            .setup(|d| {
                shards(d);
                std::fs::remove_file(d.join("p2.npy.json")).unwrap();
            })
            .says("cannot read p2.npy.json"),
        Case::new("a truncated description", ALL)
            .setup(|d| {
                shards(d);
                let path = d.join("p1.npy.json");
                let text = std::fs::read(&path).unwrap();
                std::fs::write(path, &text[..text.len() / 2]).unwrap();
            })
            .says("invalid shard description p1.npy.json"),
        // Found by the fuzz harness (tests/fuzz): k x cells overflowed, a panic.
        Case::new("a description of a grid too large to count its slices", ALL)
            .setup(|d| {
                shards(d);
                edit(d, "p3.npy.json", |j| {
                    j["shape"] = serde_json::json!([1u64 << 62, 4]);
                    j["shard"] = 5.into();
                    j["shards"] = 5.into();
                });
            })
            .says("p3.npy.json: the description says cells 4 to 6")
            .says("does not match the grid"),
        Case::new("a description larger than a description", ALL)
            .setup(|d| {
                shards(d);
                let path = d.join("p2.npy.json");
                let mut text = std::fs::read(&path).unwrap();
                text.extend(std::iter::repeat_n(b' ', 2 << 20));
                std::fs::write(path, text).unwrap();
            })
            .says("cannot read p2.npy.json")
            .says("larger than 1 MiB"),
        Case::new("a merge that fails keeps the earlier output", "merge p1.npy p2.npy --out m.npy")
            .setup(|d| {
                shards(d);
                precious(d, "m.npy");
            })
            .says("missing"),
    ]
}

/// `--checkpoint FILE`, its `FILE.chunks` and the trajectory's `OUT.partial` are outputs
/// like the others, and regular files that pendula reads back: onto another output, a
/// directory, `-`, a FIFO or a device, or an existing checkpoint, they are refused before the
/// run; `resume` refuses what is not a checkpoint of this version, naming the file.
fn checkpoints() -> Vec<Case> {
    let checkpoint = |d: &Path, name: &str, text: &str| std::fs::write(d.join(name), text).unwrap();
    vec![
        Case::new("checkpoint onto the trajectory", &format!("{FAST} --out x.csv --checkpoint x.csv"))
            .setup(|d| precious(d, "x.csv"))
            .says("invalid --checkpoint x.csv: it is also the --out file"),
        Case::new(
            "checkpoint onto the summary",
            &format!("{FAST} --out t.csv --summary s.json --checkpoint s.json"),
        )
        .setup(|d| precious(d, "s.json"))
        .says("it is also the --summary file"),
        Case::new(
            "checkpoint onto the summary by another name",
            &format!("{FAST} --out t.csv --summary s.json --checkpoint sub/../s.json"),
        )
        .setup(|d| {
            std::fs::create_dir(d.join("sub")).unwrap();
            precious(d, "s.json");
        })
        .says("are the same file"),
        Case::new(
            "summary onto the partial trajectory",
            &format!("{FAST} --out t.csv --checkpoint c.ckpt --summary t.csv.partial"),
        )
        .says("same file"),
        Case::new("checkpoint onto a directory", &format!("{FAST} --out t.csv --checkpoint d"))
            .setup(|d| std::fs::create_dir(d.join("d")).unwrap())
            .says("invalid --checkpoint d: it is a directory"),
        Case::new("checkpoint on stdout", &format!("{FAST} --out t.csv --checkpoint -"))
            .says("invalid --checkpoint -"),
        Case::new("an existing checkpoint", &format!("{FAST} --out t.csv --checkpoint c.ckpt"))
            .setup(|d| precious(d, "c.ckpt"))
            .says("it exists (from a run interrupted earlier?)")
            .says("pendula resume"),
        Case::new("checkpoint onto a FIFO", &format!("{FAST} --out t.csv --checkpoint ff"))
            .setup(|d| mkfifo(d, "ff"))
            .reads_fifo("ff", |b| assert!(b.is_empty(), "{} bytes written", b.len()))
            .says("cannot write --checkpoint ff: it is a FIFO"),
        Case::new("checkpoint onto a null device", &format!("{FAST} --out t.csv --checkpoint null"))
            .needs_root()
            .setup(|d| null(d, "null"))
            .says("--checkpoint null: it is a character device"),
        Case::new("checkpointed trajectory into a FIFO", &format!("{FAST} --out ff --checkpoint c.ckpt"))
            .setup(|d| mkfifo(d, "ff"))
            .reads_fifo("ff", |b| assert!(b.is_empty(), "{} bytes written", b.len()))
            .says("cannot write --out ff: it is a FIFO"),
        Case::new(
            "sweep's checkpoint onto its shard description",
            &format!("{SWEEP} --shard 1/2 --out s.npy --checkpoint s.npy.json"),
        )
        .says("it is also the --out (shard description) file"),
        Case::new(
            "summary onto the sweep's finished chunks",
            &format!("{SWEEP} --out s.npy --checkpoint c --summary c.chunks"),
        )
        .setup(|d| precious(d, "c.chunks"))
        .says("same file"),
        Case::new(
            "fractal's checkpoint onto its picture",
            &format!("{FRACTAL} --out f.npy --checkpoint f.png"),
        )
        .says("it is also the --out file"),
        Case::new("resume of a missing checkpoint", "resume gone.ckpt")
            .says("cannot read the checkpoint")
            .says("gone.ckpt"),
        Case::new("resume of a corrupt checkpoint", "resume c.ckpt")
            .setup(move |d| checkpoint(d, "c.ckpt", "pendula-checkpoint 1 crc32=00000000\n{}\n"))
            .says("c.ckpt is not a checkpoint pendula can resume")
            .says("do not match its checksum"),
        Case::new("resume of another version's checkpoint", "resume c.ckpt")
            .setup(move |d| checkpoint(d, "c.ckpt", "pendula-checkpoint 99 crc32=00000000\n{}\n"))
            .says("c.ckpt is not a checkpoint pendula can resume")
            .says("format version 99"),
        Case::new("resume of a file that is no checkpoint", "resume x.csv")
            .setup(|d| precious(d, "x.csv"))
            .says("x.csv is not a checkpoint pendula can resume"),
        Case::new("resume of a directory", "resume d")
            .setup(|d| std::fs::create_dir(d.join("d")).unwrap())
            .says("cannot read the checkpoint")
            .says("it is a directory"),
        Case::new("resume of a FIFO", "resume ff")
            .setup(|d| mkfifo(d, "ff"))
            .reads_fifo("ff", |b| assert!(b.is_empty(), "{} bytes written", b.len()))
            .says("it is a FIFO, not a checkpoint file"),
    ]
}

#[test]
fn writes() {
    super::harness::run(cases());
}
