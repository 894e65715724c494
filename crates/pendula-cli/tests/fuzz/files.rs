//! The file targets: scenario files, .npy files, sweep shards and their descriptions, and
//! `plot`'s inputs; and [`Env`], the real files the targets start from.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use clap::Parser;
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::{Index, select};
use proptest::strategy::BoxedStrategy;
use serde_json::{Value, json};

use super::argv::{COUNTS, NUMBERS, wild};
use super::{claims, ordinary};
use pendula_cli::cli::{Cli, Command};
use pendula_cli::commands::plot::PlotArgs;

/// A valid scenario, as the guide (docs/GUIDE.md) shows one.
const SCENARIO: &str = "system = \"pendulum\"\nmethod = \"rk4\"\ndt = 0.01\nsteps = 10\nevery = 2\nout = \"t.csv\"\n\n[set]\ntheta = \"30deg\"\nl = 2\n";

/// The files every target may start from, made by the real commands in a temporary
/// directory: a scenario, a trajectory as CSV and .npy, a sweep's grid and its summary, a
/// fractal's grid, flags and summary, and the two shards of a sweep with their
/// descriptions.
pub(super) struct Env {
    dir: tempfile::TempDir,
}

/// The names of [`Env`]'s files (and its directory `dir`).
const FILES: &[&str] = &[
    "s.toml",
    "bad.toml",
    "dir",
    "t.csv",
    "t.npy",
    "flags.npy",
    "g.npy",
    "g.json",
    "frac.npy",
    "frac.json",
    "frac-converged.npy",
    "s1.npy",
    "s1.npy.json",
    "s2.npy",
    "s2.npy.json",
];

impl Env {
    pub(super) fn new() -> Env {
        let dir = tempfile::Builder::new().prefix("pendula-fuzz").tempdir().expect("a temporary directory");
        let env = Env { dir };
        let write = |name: &str, bytes: &[u8]| std::fs::write(env.path(name), bytes).expect("a setup file");
        write("s.toml", SCENARIO.as_bytes());
        write("bad.toml", b"dt = [[[[\n");
        std::fs::create_dir(env.path("dir")).expect("a setup directory");
        // A double pendulum's trajectory, as `simulate` writes it.
        let rows: Vec<[f64; 6]> = (0..6)
            .map(|i| {
                let t = i as f64 * 0.1;
                [t, 1.0 - t, 0.5 * t, -t, 0.2, -1.5 + 1e-9 * t]
            })
            .collect();
        let mut csv = String::from("t,theta1,theta2,omega1,omega2,energy\n");
        for r in &rows {
            csv.push_str(&r.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(","));
            csv.push('\n');
        }
        write("t.csv", csv.as_bytes());
        let flat: Vec<f64> = rows.iter().flatten().copied().collect();
        write("t.npy", &npy_bytes(&ndarray::Array2::from_shape_vec((6, 6), flat).expect("a 6 x 6 array")));
        write(
            "flags.npy",
            &npy_bytes(&ndarray::Array2::<u8>::from_shape_fn((3, 4), |(i, j)| ((i + j) % 2) as u8)),
        );
        let p = |name: &str| env.path(name).display().to_string();
        run_real(&[
            "sweep",
            "--grid",
            "theta1=0:1:4",
            "--steps",
            "10",
            "--shard",
            "1/2",
            "--out",
            &p("s1.npy"),
        ]);
        run_real(&[
            "sweep",
            "--grid",
            "theta1=0:1:4",
            "--steps",
            "10",
            "--shard",
            "2/2",
            "--out",
            &p("s2.npy"),
        ]);
        run_real(&[
            "sweep",
            "--grid",
            "theta1=0:1:3",
            "--grid",
            "theta2=0:1:2",
            "--steps",
            "5",
            "--out",
            &p("g.npy"),
            "--summary",
            &p("g.json"),
        ]);
        run_real(&[
            "fractal",
            "--grid",
            "theta1=0:1:3",
            "--grid",
            "theta2=0:1:2",
            "--t-max",
            "0.05",
            "--out",
            &p("frac.npy"),
            "--summary",
            &p("frac.json"),
            "--threads",
            "1",
        ]);
        env
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    fn read(&self, name: &str) -> Vec<u8> {
        std::fs::read(self.path(name)).expect("a setup file")
    }

    /// Every file's absolute path.
    pub(super) fn paths(&self) -> Vec<String> {
        FILES.iter().map(|n| self.path(n).display().to_string()).collect()
    }

    /// `token`, or the absolute path of the file of that name (a baseline's `t.csv`).
    pub(super) fn rooted(&self, token: &str) -> String {
        if FILES.contains(&token) { self.path(token).display().to_string() } else { token.to_owned() }
    }
}

/// Runs a command for real (the harness's setup), with its outputs.
fn run_real(args: &[&str]) {
    let cli = Cli::try_parse_from(std::iter::once("pendula").chain(args.iter().copied()))
        .unwrap_or_else(|e| panic!("the setup `{}` does not parse: {e}", args.join(" ")));
    pendula_cli::output::validate_only(false);
    let _claims = claims();
    pendula_cli::dispatch(&cli.command)
        .unwrap_or_else(|e| panic!("the setup `{}` failed: {e:#}", args.join(" ")));
}

/// An array as .npy bytes.
fn npy_bytes<A: ndarray_npy::WritableElement, D: ndarray::Dimension>(a: &ndarray::Array<A, D>) -> Vec<u8> {
    use ndarray_npy::WriteNpyExt;
    let mut bytes = Vec::new();
    a.write_npy(&mut bytes).expect("an array in memory");
    bytes
}

/// A change to a file's bytes.
#[derive(Debug, Clone)]
enum Edit {
    /// A bit flipped.
    Flip(Index, u8),
    /// A byte replaced.
    Set(Index, u8),
    Insert(Index, u8),
    Delete(Index),
    /// Cut at this place.
    Truncate(Index),
    /// A stretch copied elsewhere.
    Splice(Index, Index, Index),
    /// A run of digits replaced by a number (a header's count made huge, negative, a float).
    Number(Index, String),
}

fn edit() -> BoxedStrategy<Edit> {
    prop_oneof![
        3 => (any::<Index>(), 0u8..8).prop_map(|(at, bit)| Edit::Flip(at, bit)),
        2 => (any::<Index>(), any::<u8>()).prop_map(|(at, b)| Edit::Set(at, b)),
        1 => (any::<Index>(), any::<u8>()).prop_map(|(at, b)| Edit::Insert(at, b)),
        1 => any::<Index>().prop_map(Edit::Delete),
        1 => any::<Index>().prop_map(Edit::Truncate),
        1 => (any::<Index>(), any::<Index>(), any::<Index>()).prop_map(|(a, b, c)| Edit::Splice(a, b, c)),
        4 => (any::<Index>(), prop_oneof![select(COUNTS), select(NUMBERS)]).prop_map(|(at, n)| Edit::Number(at, n.to_owned())),
    ]
    .boxed()
}

impl Edit {
    fn apply(&self, b: &mut Vec<u8>) {
        let n = b.len();
        match self {
            Edit::Flip(at, bit) if n > 0 => b[at.index(n)] ^= 1 << bit,
            Edit::Set(at, v) if n > 0 => b[at.index(n)] = *v,
            Edit::Insert(at, v) => b.insert(at.index(n + 1), *v),
            Edit::Delete(at) if n > 0 => {
                b.remove(at.index(n));
            }
            Edit::Truncate(at) => b.truncate(at.index(n + 1)),
            Edit::Splice(from, len, to) if n > 0 => {
                let start = from.index(n);
                let piece = b[start..(start + len.index(64) + 1).min(n)].to_vec();
                let to = to.index(n + 1);
                b.splice(to..to, piece);
            }
            Edit::Number(at, number) if n > 0 => {
                // The digits at or after `at` (the first run of them), else at `at`.
                let from = at.index(n);
                let start = (from..n).find(|&i| b[i].is_ascii_digit()).unwrap_or(from);
                let end = (start..n).find(|&i| !b[i].is_ascii_digit()).unwrap_or(n).max(start);
                b.splice(start..end, number.bytes());
            }
            _ => {}
        }
    }
}

fn edited(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        e.apply(&mut bytes);
    }
    bytes
}

// ---------------------------------------------------------------------------------------
// Scenario files.

/// Keys a scenario may hold, and some it may not.
const KEYS: &[&str] = &[
    "system",
    "method",
    "dt",
    "t_end",
    "t-end",
    "steps",
    "rtol",
    "atol",
    "h_min",
    "h-min",
    "h_max",
    "h-max",
    "every",
    "out",
    "summary",
    "set",
    "binding",
    "x",
    "set.theta1",
    "\"dt\"",
    "'steps'",
    "",
];

/// TOML values: numbers at and past every edge, strings, other types.
const TOML_VALUES: &[&str] = &[
    "1",
    "0",
    "-0",
    "-1",
    "2",
    "10",
    "0.01",
    "1e-3",
    "1.5",
    "-0.0",
    "1e400",
    "-1e400",
    "1e-320",
    "5e-324",
    "inf",
    "-inf",
    "nan",
    "+nan",
    "0x1F",
    "0o7",
    "0b1",
    "1_000",
    "9223372036854775807",
    "-9223372036854775808",
    "9223372036854775808",
    "18446744073709551615",
    "99999999999999999999",
    "10000000000000",
    "10000000000001",
    "1e13",
    "\"double\"",
    "\"pendulum\"",
    "\"oscillator\"",
    "\"chain\"",
    "\"driven-pendulum\"",
    "\"rk4\"",
    "\"dopri5\"",
    "\"tao-2\"",
    "\"gauss-legendre-4\"",
    "\"120deg\"",
    "\"pi\"",
    "\"-0.5pi\"",
    "\"1e400\"",
    "\"nan\"",
    "\"\"",
    "\"t.csv\"",
    "\"t.npy\"",
    "\"-\"",
    "\"/dev/null\"",
    "'lit'",
    "\"\\u0000\"",
    "\"\\uD800\"",
    "true",
    "false",
    "1979-05-27T07:32:00Z",
    "07:32:00",
    "[]",
    "[1, 2]",
    "[[1], [\"a\"]]",
    "{}",
    "{ a = 1 }",
    "{ theta1 = 1 }",
    "\"unterminated",
    "'''multi\nline'''",
    "\"\"\"multi\nline\"\"\"",
];

fn toml_value() -> BoxedStrategy<String> {
    prop_oneof![
        6 => select(TOML_VALUES).prop_map(str::to_owned),
        2 => select(NUMBERS).prop_map(|n| format!("\"{}\"", n.escape_default())),
        1 => any::<f64>().prop_map(|x| format!("{x:?}")),
        1 => any::<i64>().prop_map(|n| n.to_string()),
    ]
    .boxed()
}

fn quantity_name() -> BoxedStrategy<String> {
    let mut names: Vec<String> =
        pendula::model::CATALOGUE.iter().flat_map(|s| s.quantities().map(|q| q.name.to_owned())).collect();
    names.sort();
    names.dedup();
    names.extend(["links", "nope", "theta 1", "\"theta1\"", "θ"].map(str::to_owned));
    select(names).boxed()
}

/// A scenario's text: keys and values, `[set]` tables, headers, comments and junk lines.
fn toml_text() -> BoxedStrategy<String> {
    let line = prop_oneof![
        6 => (select(KEYS), select(&[" = ", "=", " ", " == ", ": "][..]), toml_value())
            .prop_map(|(k, eq, v)| format!("{k}{eq}{v}")),
        3 => vec((quantity_name(), toml_value()), 0..5).prop_map(|items| {
            let mut t = String::from("[set]");
            for (n, v) in items {
                t.push_str(&format!("\n{n} = {v}"));
            }
            t
        }),
        1 => select(&["[set]", "[set.theta1]", "[[set]]", "[system]", "[set", "set]", "[]", "# comment", "\u{feff}", "\t", "\r"][..])
            .prop_map(str::to_owned),
        1 => wild(),
    ];
    (vec(line, 0..9), select(&["\n", "\n", "\r\n", "\r"][..]))
        .prop_map(|(lines, eol)| lines.join(eol))
        .boxed()
}

/// Nesting beyond the parser's recursion (arrays, inline tables, dotted keys, headers),
/// and just at the limit.
fn deep() -> BoxedStrategy<Vec<u8>> {
    (select(&[15usize, 16, 17, 100, 10_000, 400_000][..]), 0u8..7)
        .prop_map(|(d, form)| {
            match form {
                0 => format!("a = {}{}", "[".repeat(d), "]".repeat(d)),
                1 => format!("a = {}1{}", "{b = ".repeat(d), "}".repeat(d)),
                2 => format!("[set]\ntheta1 = {}", "[".repeat(d)),
                3 => format!("set.{}b = 1", "a.".repeat(d.min(500_000))),
                4 => format!("[{}b]", "a.".repeat(d.min(500_000))),
                5 => format!("a = {}", "[{x = ".repeat(d)),
                _ => format!("[set]\ntheta1 = {}1{}", "[".repeat(d), "]".repeat(d)),
            }
            .into_bytes()
        })
        .boxed()
}

/// Lines up to and past the size cap (1 MiB).
fn huge() -> BoxedStrategy<Vec<u8>> {
    (select(&[1_000usize, 100_000, (1 << 20) - 20, (1 << 20) + 1, 3 << 20][..]), 0u8..4)
        .prop_map(|(n, form)| {
            match form {
                0 => format!("a = \"{}\"", "x".repeat(n)),
                1 => format!("# {}", "x".repeat(n)),
                2 => format!("[set]\ntheta1 = \"{}\"", "9".repeat(n)),
                _ => "x".repeat(n),
            }
            .into_bytes()
        })
        .boxed()
}

/// A scenario of known keys, each with a plausible value or a hostile one: most get past
/// the parser to `simulate`'s validation.
fn scenario_struct() -> BoxedStrategy<Vec<u8>> {
    let plausible: &[(&str, &[&str])] = &[
        ("system", &["\"double\"", "\"pendulum\"", "\"oscillator\"", "\"chain\"", "\"driven-pendulum\""]),
        (
            "method",
            &["\"rk4\"", "\"verlet\"", "\"dopri5\"", "\"dop853\"", "\"tao-2\"", "\"gauss-legendre-4\""],
        ),
        ("dt", &["0.01", "0.001", "1", "1e-9"]),
        ("t_end", &["1", "0.5", "10", "1e6"]),
        ("steps", &["10", "1", "1000"]),
        ("every", &["1", "0", "5"]),
        ("rtol", &["1e-6", "1e-10"]),
        ("atol", &["1e-6", "0"]),
        ("h_max", &["0.1", "1"]),
        ("out", &["\"t.csv\"", "\"t.npy\"", "\"-\""]),
        ("summary", &["\"s.json\"", "\"-\""]),
    ];
    let line = |(key, values): &(&'static str, &'static [&'static str])| {
        let key = *key;
        proptest::option::weighted(
            0.4,
            prop_oneof![4 => select(*values).prop_map(str::to_owned), 1 => toml_value()],
        )
        .prop_map(move |v| v.map(|v| format!("{key} = {v}\n")).unwrap_or_default())
        .boxed()
    };
    let lines: Vec<BoxedStrategy<String>> = plausible.iter().map(line).collect();
    let set = vec(
        (
            quantity_name(),
            prop_oneof![3 => select(NUMBERS).prop_map(|n| format!("\"{}\"", n.escape_default())), 2 => toml_value()],
        ),
        0..4,
    );
    (lines, set)
        .prop_map(|(lines, set)| {
            let mut text: String = lines.concat();
            if !set.is_empty() {
                text.push_str("[set]\n");
                for (n, v) in set {
                    text.push_str(&format!("{n} = {v}\n"));
                }
            }
            text.into_bytes()
        })
        .boxed()
}

fn scenario_files() -> BoxedStrategy<Vec<u8>> {
    prop_oneof![
        8 => scenario_struct(),
        4 => vec(any::<u8>(), 0..200),
        12 => toml_text().prop_map(String::into_bytes),
        8 => (toml_text(), vec(edit(), 1..4)).prop_map(|(t, e)| edited(t.into_bytes(), &e)),
        4 => vec(edit(), 1..5).prop_map(|e| edited(SCENARIO.as_bytes().to_vec(), &e)),
        1 => deep(),
        1 => huge(),
    ]
    .boxed()
}

/// Runs `cases` scenario files through `simulate`'s reader and, when read, its validation.
pub(super) fn scenario(cases: u32) -> Result<(), String> {
    let Command::Simulate(args) = Cli::try_parse_from(["pendula", "simulate"]).expect("a command").command
    else {
        unreachable!("simulate parses as simulate")
    };
    super::fuzz("scenario", cases, scenario_files(), |bytes| {
        match pendula_cli::config::parse_scenario(bytes.clone(), "s.toml") {
            Err(e) => ordinary(&e),
            Ok(scenario) => match pendula_cli::config::simulate_with(&args, scenario) {
                Ok(_) => Ok(()),
                Err(e) => ordinary(&e),
            },
        }
    })
}

// ---------------------------------------------------------------------------------------
// .npy files.

/// A .npy file as generated: its header's parts, each possibly a lie.
#[derive(Debug, Clone)]
struct NpyFile {
    version: u8,
    descr: &'static str,
    fortran: &'static str,
    shape: Vec<String>,
    /// Another entry of the header's dict (a repeated key, a deep nest), or none.
    extra: String,
    /// The keys' order.
    order: u8,
    /// Bytes of data beyond (or short of) what the shape claims.
    slack: i64,
    /// A header length that is not the header's.
    length: Option<u32>,
}

const DESCRS: &[&str] = &[
    "'<f8'",
    "'<f8'",
    "'<f8'",
    "'|u1'",
    "'|u1'",
    "'<i8'",
    "'>f8'",
    "'<f4'",
    "'|b1'",
    "'<c16'",
    "'<U10'",
    "'<f0'",
    "'<f99999999999999999999'",
    "'<f'",
    "[('a', '<f8')]",
    "'O'",
    "'|V8'",
    "1",
    "'<f8",
    "\"<f8\"",
    "'f8'",
];

const DIMS: &[&str] = &[
    "0",
    "1",
    "2",
    "3",
    "4",
    "5",
    "6",
    "10",
    "64",
    "1000",
    "1000000",
    "4294967296",
    "9223372036854775807",
    "18446744073709551615",
    "18446744073709551616",
    "-1",
    "1e3",
    "2**64",
    "99999999999999999999999",
    "",
    "None",
];

fn npy_file() -> BoxedStrategy<NpyFile> {
    let extra = prop_oneof![
        8 => Just(String::new()),
        1 => select(&[
            "'shape': (1,)", "'shape': (1000000000000000,)", "'shape': (2, 3)", "'descr': '<f4'", "'descr': '|u1'",
            "'fortran_order': True", "'x': 1", "'x': \"'shape': (9,)\"",
        ][..]).prop_map(str::to_owned),
        1 => (select(&[100usize, 10_000, 200_000][..]), 0u8..3).prop_map(|(d, k)| match k {
            0 => format!("'x': {}{}", "(".repeat(d), ")".repeat(d)),
            1 => format!("'x': {}", "[".repeat(d)),
            _ => format!("'x': {}1{}", "{1: ".repeat(d), "}".repeat(d)),
        }),
    ];
    (
        select(&[1u8, 1, 2, 3, 0, 4][..]),
        select(DESCRS),
        select(&["False", "False", "True", "0", "'no'"][..]),
        vec(prop_oneof![4 => (1u64..8).prop_map(|d| d.to_string()), 1 => select(DIMS).prop_map(str::to_owned)], 0..4),
        extra,
        0u8..6,
        prop_oneof![6 => Just(0i64), 1 => -16i64..16],
        prop_oneof![8 => Just(None), 1 => any::<u32>().prop_map(Some), 1 => (0u32..200).prop_map(Some)],
    )
        .prop_map(|(version, descr, fortran, shape, extra, order, slack, length)| NpyFile {
            version,
            descr,
            fortran,
            shape,
            extra,
            order,
            slack,
            length,
        })
        .boxed()
}

impl NpyFile {
    fn bytes(&self) -> Vec<u8> {
        let shape = match self.shape.len() {
            1 => format!("({},)", self.shape[0]),
            _ => format!("({})", self.shape.join(", ")),
        };
        let mut entries = [
            format!("'descr': {}", self.descr),
            format!("'fortran_order': {}", self.fortran),
            format!("'shape': {shape}"),
        ];
        entries.rotate_left(usize::from(self.order % 3));
        if self.order >= 3 {
            entries.swap(0, 1);
        }
        let mut dict = format!("{{{}", entries.join(", "));
        if !self.extra.is_empty() {
            dict.push_str(", ");
            dict.push_str(&self.extra);
        }
        dict.push_str(", }");
        let prefix = if self.version == 1 { 10 } else { 12 };
        // Padded with spaces to 64 bytes, ending in a newline, as numpy writes it.
        let pad = (64 - (prefix + dict.len() + 1) % 64) % 64;
        let header = format!("{dict}{}\n", " ".repeat(pad));
        let mut out = b"\x93NUMPY".to_vec();
        out.extend([self.version, 0]);
        let length = self.length.unwrap_or(header.len() as u32);
        if self.version == 1 {
            out.extend((length as u16).to_le_bytes());
        } else {
            out.extend(length.to_le_bytes());
        }
        out.extend(header.bytes());
        // As much data as the shape claims, when that is little, give or take the slack.
        let item = self.descr.trim_start_matches(|c: char| !c.is_ascii_digit());
        let item: u64 =
            item.chars().take_while(char::is_ascii_digit).collect::<String>().parse().unwrap_or(8);
        let values = self.shape.iter().try_fold(1u64, |n, d| n.checked_mul(d.parse().ok()?));
        let data = values.and_then(|v| v.checked_mul(item)).filter(|&d| d <= 1 << 16).unwrap_or(64);
        let data = (data as i64 + self.slack).max(0) as usize;
        out.extend((0..data).map(|i| (i * 37 % 251) as u8));
        out
    }
}

/// Runs `cases` .npy files through the claim and, when it holds, through ndarray-npy's
/// reader as `plot` and `merge` call it.
pub(super) fn npy(cases: u32) -> Result<(), String> {
    let strategy = prop_oneof![
        6 => npy_file().prop_map(|f| f.bytes()),
        3 => (npy_file(), vec(edit(), 1..4)).prop_map(|(f, e)| edited(f.bytes(), &e)),
        1 => vec(any::<u8>(), 0..128),
        1 => vec(any::<u8>(), 0..64).prop_map(|tail| [b"\x93NUMPY\x01\x00".as_slice(), &tail].concat()),
    ];
    super::fuzz("npy", cases, strategy, |bytes| check_npy(bytes))
}

fn check_npy(bytes: &[u8]) -> Result<(), String> {
    use ndarray_npy::ReadNpyExt;
    let claim = match pendula_cli::limits::npy_claim_from(Cursor::new(bytes), bytes.len() as u64, "x.npy") {
        Ok(claim) => claim,
        Err(e) => return ordinary(&e),
    };
    // The claim holds: its values are the data after the header...
    let header = ndarray_npy::npy::header::Header::from_reader(&mut Cursor::new(bytes));
    // ...and the reader, which allocates what its own parse of the header says, agrees with it.
    if let Ok(h) = &header
        && h.shape != claim.shape
    {
        return Err(format!(
            "the claim says shape {:?}, ndarray-npy's reader {:?}: the reader would allocate by a shape not checked",
            claim.shape, h.shape
        ));
    }
    // As `plot` reads it (float64, else uint8), which allocates float64s for every value
    // before it checks the type: at most 8 times the claimed data (under 64 KiB here).
    if ndarray::ArrayD::<f64>::read_npy(Cursor::new(bytes)).is_err()
        && let Err(e) = ndarray::ArrayD::<u8>::read_npy(Cursor::new(bytes))
    {
        return ordinary(&anyhow::anyhow!(
            "cannot read x.npy as a .npy of float64 or uint8: {}",
            pendula_cli::parse::clip(&e.to_string())
        ));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Shards.

/// JSON values a field of a description may be given.
fn json_value() -> BoxedStrategy<Value> {
    let numbers: &[u64] = &[0, 1, 2, 3, 4, 5, 8, 16, 192, 1 << 31, 1 << 32, 1 << 62, 1 << 63, u64::MAX];
    prop_oneof![
        4 => select(numbers).prop_map(Value::from),
        1 => any::<i64>().prop_map(Value::from),
        1 => select(&[-1.0, 0.5, 1.5, 1e300, -0.0, 4.0][..]).prop_map(|x| json!(x)),
        1 => select(&["2", "", "17af4b93", "ffffffff", "xyz", "0x1f", "00000000"][..]).prop_map(|s| json!(s)),
        1 => Just(Value::Null),
        1 => any::<bool>().prop_map(Value::from),
        3 => vec(select(numbers), 0..4).prop_map(|v| json!(v)),
        1 => Just(json!({"bytes": 192, "crc32": "00000000"})),
    ]
    .boxed()
}

const FIELDS: &[&str] = &[
    "pendula_sweep",
    "shape",
    "shard",
    "shards",
    "offset",
    "count",
    "fingerprint",
    "data",
    "data.bytes",
    "data.crc32",
    "columns",
    "axes",
    "system",
];

/// A change to a shard: its .npy file's bytes, its description's fields or bytes.
#[derive(Debug, Clone)]
enum ShardEdit {
    Npy(Edit),
    Field(&'static str, Value),
    Remove(&'static str),
    Json(Edit),
    /// The description's length and CRC-32 made the data's, so that the data's edits get
    /// past the checksum to the .npy reader.
    Checksum,
}

fn shard_edit() -> BoxedStrategy<ShardEdit> {
    prop_oneof![
        3 => edit().prop_map(ShardEdit::Npy),
        4 => (select(FIELDS), json_value()).prop_map(|(k, v)| ShardEdit::Field(k, v)),
        1 => select(FIELDS).prop_map(ShardEdit::Remove),
        1 => edit().prop_map(ShardEdit::Json),
        3 => Just(ShardEdit::Checksum),
    ]
    .boxed()
}

/// A shard's files: its data and its description's bytes.
#[derive(Clone)]
struct Shard {
    npy: Vec<u8>,
    json: Vec<u8>,
}

impl Shard {
    fn edited(&self, edits: &[ShardEdit]) -> Shard {
        let mut npy = self.npy.clone();
        let mut doc: Option<Value> = serde_json::from_slice(&self.json).ok();
        let mut json_edits = Vec::new();
        for e in edits {
            match e {
                ShardEdit::Npy(e) => e.apply(&mut npy),
                ShardEdit::Json(e) => json_edits.push(e.clone()),
                // A description that is no longer JSON takes only byte edits.
                ShardEdit::Field(..) | ShardEdit::Remove(..) if doc.is_none() => {}
                ShardEdit::Field(key, v) => set(doc.as_mut().expect("a document"), key, Some(v.clone())),
                ShardEdit::Remove(key) => set(doc.as_mut().expect("a document"), key, None),
                ShardEdit::Checksum => {
                    if let Some(d) = doc.as_mut() {
                        let w = pendula_cli::shards::checksum(npy.as_slice()).expect("bytes in memory");
                        d["data"] = json!({"bytes": w.bytes, "crc32": format!("{:08x}", w.crc32)});
                    }
                }
            }
        }
        let json = match doc {
            Some(d) => serde_json::to_vec_pretty(&d).expect("a JSON value"),
            None => self.json.clone(),
        };
        Shard { npy, json: edited(json, &json_edits) }
    }
}

/// Sets (or with `None` removes) the field `key` (`data.bytes`: within `data`) of `doc`.
fn set(doc: &mut Value, key: &str, value: Option<Value>) {
    let (object, key) = match key.split_once('.') {
        Some((outer, inner)) => (&mut doc[outer], inner),
        None => (doc, key),
    };
    if let Some(map) = object.as_object_mut() {
        match value {
            Some(v) => {
                map.insert(key.to_owned(), v);
            }
            None => {
                map.remove(key);
            }
        }
    }
}

/// Runs `cases` merges of the two shards of a sweep, edited, given in various orders.
pub(super) fn shards(cases: u32) -> Result<(), String> {
    let env = Env::new();
    let originals = [
        Shard { npy: env.read("s1.npy"), json: env.read("s1.npy.json") },
        Shard { npy: env.read("s2.npy"), json: env.read("s2.npy.json") },
    ];
    let dir = env.path("merge");
    std::fs::create_dir(&dir).expect("a directory for the merges");
    let strategy = (vec(shard_edit(), 0..4), vec(shard_edit(), 0..4), 0u8..7, any::<bool>());
    super::fuzz("shards", cases, strategy, |(a, b, order, allow_large)| {
        let files = [originals[0].edited(a), originals[1].edited(b)];
        for (name, shard) in ["a", "b"].iter().zip(&files) {
            std::fs::write(dir.join(format!("{name}.npy")), &shard.npy).map_err(|e| e.to_string())?;
            std::fs::write(dir.join(format!("{name}.npy.json")), &shard.json).map_err(|e| e.to_string())?;
        }
        let names: &[&str] = match order {
            0 => &["a", "b"],
            1 => &["b", "a"],
            2 => &["a"],
            3 => &["a", "a"],
            4 => &["a", "b", "a"],
            5 => &["b", "a", "b", "a"],
            _ => &["a", "b", "m"],
        };
        let args = pendula_cli::commands::merge::MergeArgs {
            shards: names.iter().map(|n| dir.join(format!("{n}.npy"))).collect(),
            out: dir.join("m.npy"),
            large: pendula_cli::args::LargeArg { allow_large: *allow_large },
        };
        pendula_cli::output::validate_only(false);
        let _claims = claims();
        let _outputs = pendula_cli::output::scope();
        match pendula_cli::commands::merge::run(&args) {
            Ok(()) => Ok(()),
            Err(e) => ordinary(&e),
        }
    })
}

// ---------------------------------------------------------------------------------------
// Plot's inputs.

/// An input of `plot`: one of [`Env`]'s files (and its description, if any), edited.
#[derive(Debug, Clone)]
struct PlotCase {
    base: usize,
    data: Vec<Edit>,
    /// Edits of the description's fields (`axes.0.lo`: the first axis's `lo`).
    fields: Vec<(&'static str, Value)>,
    rows: Vec<Vec<String>>,
    x: Option<String>,
    y: Vec<String>,
    phase: bool,
    energy: bool,
    system: Option<String>,
    svg: bool,
    /// Drawn and written, not only read and laid out (rendering takes milliseconds).
    draw: bool,
}

/// `plot`'s inputs: (file, its description's name and the name it must have beside it).
const PLOT_BASES: &[(&str, Option<(&str, &str)>)] = &[
    ("t.csv", None),
    ("t.npy", None),
    ("flags.npy", None),
    ("g.npy", Some(("g.json", "x.json"))),
    ("frac.npy", Some(("frac.json", "x.json"))),
    ("frac-converged.npy", Some(("frac.json", "x.json"))),
    ("s1.npy", Some(("s1.npy.json", "x.npy.json"))),
];

const PLOT_FIELDS: &[&str] = &[
    "axes",
    "axes.0",
    "axes.0.lo",
    "axes.0.hi",
    "axes.0.n",
    "axes.0.name",
    "axes.1.lo",
    "axes.1.hi",
    "axes.1.n",
    "columns",
    "t_max",
];

fn plot_case() -> BoxedStrategy<PlotCase> {
    let column = prop_oneof![
        4 => select(&["t", "theta1", "theta2", "omega1", "omega2", "energy", "value", "c0", "y1", "index", "theta"][..])
            .prop_map(str::to_owned),
        1 => wild(),
    ]
    .boxed();
    let cell = prop_oneof![
        6 => select(NUMBERS).prop_map(str::to_owned),
        2 => any::<f64>().prop_map(|x| x.to_string()),
        1 => wild(),
    ];
    // Mostly one change at a time, so that many inputs get past the reader to the layout.
    let fields = prop_oneof![3 => Just(Vec::new()), 2 => vec((select(PLOT_FIELDS), json_value()), 1..3)];
    let data = prop_oneof![1 => Just(Vec::new()), 1 => vec(edit(), 1..3)];
    let rows = prop_oneof![3 => Just(Vec::new()), 1 => vec(vec(cell, 0..8), 1..3)];
    let y = prop_oneof![3 => Just(Vec::new()), 1 => vec(column.clone(), 1..3)];
    (
        (0..PLOT_BASES.len(), data, fields, rows),
        (
            proptest::option::weighted(0.1, column),
            y,
            proptest::bool::weighted(0.2),
            proptest::bool::weighted(0.2),
            proptest::option::weighted(
                0.2,
                select(&["double", "pendulum", "chain", "oscillator", "nope"][..]).prop_map(str::to_owned),
            ),
            proptest::bool::weighted(0.2),
            proptest::bool::weighted(1.0 / 64.0),
        ),
    )
        .prop_map(|((base, data, fields, rows), (x, y, phase, energy, system, svg, draw))| PlotCase {
            base,
            data,
            fields,
            rows,
            x,
            y,
            phase,
            energy,
            system,
            svg,
            draw,
        })
        .boxed()
}

/// Sets `path` (`axes.0.lo`) in `doc` to `v`, where the containers exist.
fn set_path(doc: &mut Value, path: &str, v: Value) {
    let mut at = doc;
    let parts: Vec<&str> = path.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        let next = match at {
            Value::Object(map) if last => {
                map.insert((*part).to_owned(), v);
                return;
            }
            Value::Array(list) if last => {
                if let Some(slot) = part.parse::<usize>().ok().and_then(|k| list.get_mut(k)) {
                    *slot = v;
                }
                return;
            }
            Value::Object(map) => map.get_mut(*part),
            Value::Array(list) => part.parse::<usize>().ok().and_then(|k| list.get_mut(k)),
            _ => None,
        };
        match next {
            Some(n) => at = n,
            None => return,
        }
    }
}

/// One of `plot`'s inputs as read: its bytes, its description and the name that description
/// has beside the file, and its name.
struct PlotBase {
    bytes: Vec<u8>,
    description: Option<(Value, &'static str)>,
    name: &'static str,
}

/// Runs `cases` of `plot`'s inputs through its reader and its layout, and every 64th
/// through `plot` itself.
pub(super) fn plot(cases: u32) -> Result<(), String> {
    let env = Env::new();
    let bases: Vec<PlotBase> = PLOT_BASES
        .iter()
        .map(|(name, desc)| PlotBase {
            bytes: env.read(name),
            description: desc
                .map(|(from, to)| (serde_json::from_slice(&env.read(from)).expect("a description"), to)),
            name,
        })
        .collect();
    let dir = env.path("plot");
    std::fs::create_dir(&dir).expect("a directory for the plots");
    super::fuzz("plot", cases, plot_case(), |case| {
        let PlotBase { bytes, description, name } = &bases[case.base];
        let mut bytes = edited(bytes.clone(), &case.data);
        // A CSV's extra rows: cells of numbers at every edge, and ragged rows.
        for row in &case.rows {
            bytes.extend(format!("\n{}", row.join(",")).bytes());
        }
        // The file keeps its kind's name (`-converged` marks a fractal's flags).
        let file = dir.join(if name.ends_with("-converged.npy") {
            "x-converged.npy".to_owned()
        } else {
            format!("x.{}", if name.ends_with(".csv") { "csv" } else { "npy" })
        });
        for stale in ["x.json", "x.npy.json"] {
            let _ = std::fs::remove_file(dir.join(stale));
        }
        std::fs::write(&file, &bytes).map_err(|e| e.to_string())?;
        if let Some((doc, beside)) = description {
            let mut doc = doc.clone();
            for (path, v) in &case.fields {
                set_path(&mut doc, path, v.clone());
            }
            std::fs::write(dir.join(beside), serde_json::to_vec(&doc).expect("JSON"))
                .map_err(|e| e.to_string())?;
        }
        let args = PlotArgs {
            file,
            x: case.x.clone(),
            y: case.y.clone(),
            phase: case.phase,
            energy: case.energy,
            system: case.system.clone(),
            out: Some(dir.join(if case.svg { "p.svg" } else { "p.png" })),
            large: pendula_cli::args::LargeArg { allow_large: false },
        };
        plot_checks(&args, case.draw)
    })
}

/// `plot`'s checks of `args.file`: read and laid out, or with `draw` the whole command.
pub(super) fn plot_checks(args: &PlotArgs, draw: bool) -> Result<(), String> {
    if draw {
        pendula_cli::output::validate_only(false);
        let _claims = claims();
        let _outputs = pendula_cli::output::scope();
        return match pendula_cli::commands::plot::run(args) {
            Ok(()) => Ok(()),
            Err(e) => ordinary(&e),
        };
    }
    let out = args.out.clone().unwrap_or_else(|| Path::new("p.png").to_owned());
    match pendula_cli::commands::plot::read(args)
        .and_then(|c| pendula_cli::commands::plot::picture(args, &out, c))
    {
        Ok(_) => Ok(()),
        Err(e) => ordinary(&e),
    }
}
