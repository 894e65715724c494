//! The `argv` target: command lines through clap, then through each command's validation
//! up to its first output (see the module above).

use std::rc::Rc;

use clap::{CommandFactory, FromArgMatches};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::{Index, select};
use proptest::strategy::{BoxedStrategy, Union};

use super::files::Env;
use super::{claims, ordinary};
use pendula_cli::cli::{COMMANDS, Cli, Command};

/// Texts a number may be given as: the edges of f64 and of the counts' ranges, and what
/// Rust's parser reads silently as something else.
pub(super) const NUMBERS: &[&str] = &[
    "",
    " ",
    "0",
    "-0",
    "+0",
    "-0.0",
    "0.0",
    "1",
    "-1",
    "2",
    "3",
    "4",
    "5",
    "7",
    "10",
    "20",
    "100",
    "175",
    "180",
    "1000",
    "0.5",
    "0.25",
    "-0.5",
    "0.1",
    "0.01",
    "0.001",
    "1e-3",
    "1e-6",
    "1e-9",
    "1e-12",
    "1e-15",
    "1e-16",
    "1e-300",
    "2.2250738585072014e-308",
    "2.225e-308",
    "1e-310",
    "1e-320",
    "4.9e-324",
    "5e-324",
    "1e-400",
    "0e-400",
    "0.000e5",
    "1e6",
    "1e9",
    "1e10",
    "1e13",
    "1e15",
    "1e300",
    "-1e300",
    "1e308",
    "1.7976931348623157e308",
    "1.8e308",
    "1e400",
    "-1e400",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "+inf",
    "infinity",
    "-Infinity",
    "INF",
    "0x10",
    "1_000",
    "1,5",
    "1.5.5",
    "--",
    "-",
    "+",
    ".",
    "e",
    "1e",
    "1e+",
    "e5",
    " 7 ",
    "7\n",
    "\t3",
    "٣",
    "１",
    "½",
    "∞",
    "1/2",
    "3.14159265358979323846264338327950288",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999",
    "-9223372036854775808",
    "4294967296",
    "65536",
    "1000000",
    "1000001",
    "1000000000",
    "1000000001",
    "10000000000000",
    "10000000000001",
    "30",
    "31",
    "50",
    "51",
    "240",
    "241",
    "1024",
    "1025",
    "2deg",
    "120deg",
    "-90deg",
    "180deg",
    "1e400deg",
    "nandeg",
    "infdeg",
    "deg",
    "pi",
    "-pi",
    "+pi",
    "2pi",
    "2*pi",
    "0.5pi",
    "*pi",
    "1e308pi",
    "pideg",
    "degpi",
    "-",
    "\u{0}",
    "\u{202e}1",
    "😀",
];

/// Counts: each range's edges, and beyond.
pub(super) const COUNTS: &[&str] = &[
    "0",
    "1",
    "2",
    "3",
    "4",
    "5",
    "8",
    "16",
    "30",
    "31",
    "64",
    "100",
    "150",
    "1000",
    "4096",
    "65535",
    "65536",
    "1000000",
    "1000001",
    "1000000000",
    "1000000001",
    "4294967296",
    "10000000000000",
    "10000000000001",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999",
    "-1",
    "-0",
    "+3",
    " 3",
    "1e3",
    "0x10",
    "3.0",
    "",
    "nan",
];

/// Paths relative to the working directory (none of them is written: the commands stop
/// before their first output); [`Env`] adds real files.
const PATHS: &[&str] = &[
    "out.csv",
    "out.npy",
    "t.csv",
    "x.npy",
    "p.png",
    "p.svg",
    "a.gif",
    "a.mp4",
    "s.json",
    "s.toml",
    "out",
    "dir/",
    "",
    "-",
    ".",
    "..",
    "/",
    "/dev/null",
    "/dev/zero",
    "/proc/self/status",
    "no/such/dir/x.csv",
    "a b.csv",
    "ü.png",
    "x.CSV",
    ".npy",
    "x.npy.json",
    "../x.png",
    "./",
    "-.csv",
    "--out",
];

/// What a flag's value is, by its name: so that generated values get past the first check.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Number,
    Count,
    Name,
    Setting,
    Axis,
    Event,
    List,
    Path,
    Size,
    Shard,
}

fn kind(long: &str) -> Kind {
    match long {
        "set" | "section" => Kind::Setting,
        "grid" | "param" => Kind::Axis,
        "event" => Kind::Event,
        "methods" | "record" | "y" | "t-eval" => Kind::List,
        "scenario" | "out" | "summary" | "plot" | "out-dir" | "gallery" => Kind::Path,
        "method" | "preset" | "system" | "variable" | "x" | "until" => Kind::Name,
        "steps" | "every" | "levels" | "tol-levels" | "fps" | "count" | "samples" | "steps-per-period"
        | "threads" | "emit-slurm" | "cpus" | "port" | "max-sessions" => Kind::Count,
        "size" => Kind::Size,
        "shard" => Kind::Shard,
        "partition" | "host" => Kind::Name,
        _ => Kind::Number,
    }
}

/// A subcommand as clap defines it: its long flags, and whether each takes a value.
#[derive(Debug, Clone)]
struct Sub {
    name: String,
    flags: Vec<(String, bool)>,
    positionals: usize,
}

fn subcommands() -> Vec<Sub> {
    Cli::command()
        .get_subcommands()
        .map(|s| Sub {
            name: s.get_name().to_owned(),
            flags: s
                .get_arguments()
                .filter_map(|a| Some((a.get_long()?.to_owned(), a.get_action().takes_values())))
                .collect(),
            positionals: s.get_positionals().count(),
        })
        .collect()
}

/// Every name a command line may hold: systems, methods, presets, quantities, and the
/// words of `list`, `completions`, `--record` and `plot`.
fn names() -> Vec<String> {
    use pendula::model::CATALOGUE;
    use pendula::system::driven::PRESETS;
    let mut names: Vec<String> = CATALOGUE.iter().map(|s| s.name.to_owned()).collect();
    names.extend(pendula::integrator::METHODS.iter().map(|m| m.name.to_owned()));
    names.extend(PRESETS.iter().map(|p| p.name.to_owned()));
    for s in CATALOGUE {
        names.extend(s.quantities().map(|q| q.name.to_owned()));
    }
    for word in [
        "systems",
        "methods",
        "presets",
        "bash",
        "zsh",
        "fish",
        "elvish",
        "powershell",
        "final",
        "flip-time",
        "energy-error",
        "flip",
        "t",
        "energy",
        "index",
        "value",
        "c0",
        "links",
    ] {
        names.push(word.to_owned());
    }
    names.sort();
    names.dedup();
    names
}

/// The generators of each kind of value, shared (`BoxedStrategy` is a reference-counted
/// pointer) by every flag's.
#[derive(Clone)]
pub(super) struct Values {
    number: BoxedStrategy<String>,
    count: BoxedStrategy<String>,
    name: BoxedStrategy<String>,
    path: BoxedStrategy<String>,
    wild: BoxedStrategy<String>,
    setting: BoxedStrategy<String>,
    axis: BoxedStrategy<String>,
    event: BoxedStrategy<String>,
    list: BoxedStrategy<String>,
    size: BoxedStrategy<String>,
    shard: BoxedStrategy<String>,
}

/// Any text: short printable or control characters, or, rarely, a long run of one
/// character (up to Linux's 128 KiB for one argument).
pub(super) fn wild() -> BoxedStrategy<String> {
    prop_oneof![
        6 => "\\PC{0,12}",
        3 => vec(any::<char>(), 0..8).prop_map(|c| c.into_iter().collect::<String>()),
        1 => (select(&["x", "9", "é", "[", "=", ":", ",", "-", "1e", "😀"][..]), 0usize..4).prop_map(|(c, k)| {
            c.repeat([100, 4_000, 40_000, 130_000][k])
        }),
    ]
    .boxed()
}

impl Values {
    pub(super) fn new(paths: Vec<String>) -> Self {
        let number = prop_oneof![
            6 => select(NUMBERS).prop_map(str::to_owned),
            2 => any::<f64>().prop_map(|x| format!("{x}")),
            1 => any::<f64>().prop_map(|x| format!("{x:e}")),
            3 => (-5.0..5.0f64).prop_map(|x| format!("{x}")),
            2 => (0u64..100).prop_map(|n| n.to_string()),
            1 => any::<i64>().prop_map(|n| n.to_string()),
            1 => ((-400.0..400.0f64), select(&["deg", "pi", "*pi", " deg", "e5", "%", "s"][..]))
                .prop_map(|(x, s)| format!("{x}{s}")),
        ]
        .boxed();
        let count = prop_oneof![
            4 => select(COUNTS).prop_map(str::to_owned),
            4 => (0u64..70).prop_map(|n| n.to_string()),
            1 => any::<u64>().prop_map(|n| n.to_string()),
        ]
        .boxed();
        let named = names();
        let name = prop_oneof![
            8 => select(named.clone()),
            // Misspelt: a character dropped, doubled, swapped or changed, or in capitals.
            3 => (select(named), any::<Index>(), 0u8..5).prop_map(|(n, at, how)| misspell(&n, at, how)),
            1 => wild(),
        ]
        .boxed();
        let path = prop_oneof![
            4 => select(PATHS).prop_map(str::to_owned),
            4 => select(paths),
            1 => wild(),
            1 => (1usize..5).prop_map(|k| "p".repeat([255, 256, 4096, 5000][k - 1]) + ".csv"),
        ]
        .boxed();
        let setting = prop_oneof![
            8 => (name.clone(), select(&["=", "=", "=", "==", " = ", ":", ""][..]), number.clone())
                .prop_map(|(n, s, v)| format!("{n}{s}{v}")),
            1 => wild(),
        ]
        .boxed();
        let axis = prop_oneof![
            8 => (name.clone(), number.clone(), number.clone(), count.clone(), 0u8..8)
                .prop_map(|(n, lo, hi, c, form)| match form {
                    0 => format!("{n}={lo}:{hi}"),
                    1 => format!("{n}={lo}:{hi}:{c}:{c}"),
                    2 => format!("={lo}:{hi}:{c}"),
                    3 => format!("{n}{lo}:{hi}:{c}"),
                    _ => format!("{n}={lo}:{hi}:{c}"),
                }),
            1 => wild(),
        ]
        .boxed();
        let event = prop_oneof![
            3 => select(&["flip", "flip+", "flip-", "zero", "zero:", "section:", "section:=1", "section:theta1="][..])
                .prop_map(str::to_owned),
            6 => (select(&["zero:", "section:"][..]), name.clone(), number.clone(), select(&["", "", "+", "-", "++", "+-"][..]))
                .prop_map(|(k, n, v, d)| if k == "zero:" { format!("{k}{n}{d}") } else { format!("{k}{n}={v}{d}") }),
            1 => wild(),
        ]
        .boxed();
        let list = (
            vec(prop_oneof![3 => name.clone(), 1 => number.clone()], 0..5),
            select(&[",", ",", ", ", ",,"][..]),
        )
            .prop_map(|(items, sep)| items.join(sep))
            .boxed();
        let size = prop_oneof![
            6 => (count.clone(), select(&["x", "x", "X", "*", "", " x "][..]), count.clone())
                .prop_map(|(w, x, h)| format!("{w}{x}{h}")),
            1 => wild(),
        ]
        .boxed();
        let shard = prop_oneof![
            6 => (count.clone(), select(&["/", "/", "/", ":", "-"][..]), count.clone())
                .prop_map(|(k, s, n)| format!("{k}{s}{n}")),
            1 => wild(),
        ]
        .boxed();
        Values { number, count, name, path, wild: wild(), setting, axis, event, list, size, shard }
    }

    fn of(&self, kind: Kind) -> BoxedStrategy<String> {
        match kind {
            Kind::Number => self.number.clone(),
            Kind::Count => self.count.clone(),
            Kind::Name => self.name.clone(),
            Kind::Setting => self.setting.clone(),
            Kind::Axis => self.axis.clone(),
            Kind::Event => self.event.clone(),
            Kind::List => self.list.clone(),
            Kind::Path => self.path.clone(),
            Kind::Size => self.size.clone(),
            Kind::Shard => self.shard.clone(),
        }
    }

    /// A value for a flag of `kind`: mostly of its kind, sometimes of any.
    fn value(&self, kind: Kind) -> BoxedStrategy<String> {
        prop_oneof![
            8 => self.of(kind),
            1 => self.number.clone(),
            1 => self.wild.clone(),
        ]
        .boxed()
    }

    /// A subcommand's positional argument.
    fn positional(&self, sub: &str) -> BoxedStrategy<String> {
        match sub {
            "plot" | "merge" => self.value(Kind::Path),
            _ => self.value(Kind::Name),
        }
    }
}

/// `name` misspelt: `how` picks the mistake, `at` where.
fn misspell(name: &str, at: Index, how: u8) -> String {
    let mut c: Vec<char> = name.chars().collect();
    if c.is_empty() {
        return name.to_owned();
    }
    let i = at.index(c.len());
    match how {
        0 => {
            c.remove(i);
        }
        1 => c.insert(i, c[i]),
        2 if i + 1 < c.len() => c.swap(i, i + 1),
        3 => c[i] = 'x',
        _ => return name.to_uppercase(),
    }
    c.into_iter().collect()
}

/// One occurrence of a flag: `--flag value`, `--flag=value`, or `--flag` alone.
fn occurrence(values: &Values, long: &str, takes_value: bool) -> BoxedStrategy<Vec<String>> {
    let long = long.to_owned();
    if !takes_value {
        return Just(vec![format!("--{long}")]).boxed();
    }
    (values.value(kind(&long)), 0u8..3)
        .prop_map(move |(v, form)| match form {
            0 => vec![format!("--{long}={v}")],
            _ => vec![format!("--{long}"), v],
        })
        .boxed()
}

/// A subcommand's generators: any one of its flags, and its positionals.
#[derive(Clone)]
struct SubStrategy {
    name: String,
    flags: BoxedStrategy<Vec<String>>,
    positional: BoxedStrategy<String>,
    positionals: usize,
}

/// A change to a command line.
#[derive(Debug, Clone)]
enum Mutation {
    /// The value at this position (after a flag) replaced.
    Replace(usize, String),
    /// A flag and its value added at this place.
    Add(Index, Vec<String>),
    Remove(Index),
    Duplicate(Index),
    Insert(Index, String),
    Swap(Index, Index),
}

impl Mutation {
    fn apply(&self, argv: &mut Vec<String>) {
        let n = argv.len();
        match self {
            Mutation::Replace(at, v) if *at < n => argv[*at] = v.clone(),
            Mutation::Replace(..) => {}
            Mutation::Add(at, tokens) => {
                // After the subcommand, so that it stays first.
                let i = 1 + at.index(n);
                argv.splice(i.min(n)..i.min(n), tokens.iter().cloned());
            }
            Mutation::Remove(at) if n > 1 => {
                argv.remove(1 + at.index(n - 1));
            }
            Mutation::Duplicate(at) if n > 1 => {
                let i = 1 + at.index(n - 1);
                argv.insert(i, argv[i].clone());
            }
            Mutation::Insert(at, token) => argv.insert(at.index(n + 1), token.clone()),
            Mutation::Swap(a, b) if n > 1 => argv.swap(a.index(n), b.index(n)),
            _ => {}
        }
    }
}

/// Valid requests that cost milliseconds, mutated to reach every command's later checks: each
/// command's examples in the CLI's one list of commands (`cli::COMMANDS`), and each library
/// study on its defaults (the harness stops every request before it runs).
fn baselines() -> Vec<String> {
    COMMANDS
        .iter()
        .flat_map(|c| c.examples.iter().map(|e| (*e).to_owned()))
        .chain(pendula::study::STUDIES.iter().map(|s| s.name.to_owned()))
        .collect()
}

/// The mutations of `base` (its flags' values replaced by typed ones, its subcommand's
/// flags added, tokens moved).
fn mutations(values: &Values, sub: &Sub, base: &[String]) -> BoxedStrategy<Mutation> {
    // Where each value of a flag is, and its kind.
    let slots: Vec<(usize, Kind)> = base
        .windows(2)
        .enumerate()
        .filter_map(|(i, w)| {
            let long = w[0].strip_prefix("--")?;
            sub.flags.iter().any(|(f, v)| f == long && *v).then_some((i + 1, kind(long)))
        })
        .collect();
    let mut arms: Vec<(u32, BoxedStrategy<Mutation>)> = vec![
        (1, any::<Index>().prop_map(Mutation::Remove).boxed()),
        (1, any::<Index>().prop_map(Mutation::Duplicate).boxed()),
        (1, (any::<Index>(), values.wild.clone()).prop_map(|(at, t)| Mutation::Insert(at, t)).boxed()),
        (1, (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::Swap(a, b)).boxed()),
    ];
    if !sub.flags.is_empty() {
        let add = Union::new(sub.flags.iter().map(|(f, v)| occurrence(values, f, *v)));
        arms.push((4, (any::<Index>(), add).prop_map(|(at, t)| Mutation::Add(at, t)).boxed()));
    }
    if !slots.is_empty() {
        let values = values.clone();
        let replace = (0..slots.len())
            .prop_flat_map(move |k| {
                let (at, kind) = slots[k];
                values.value(kind).prop_map(move |v| Mutation::Replace(at, v))
            })
            .boxed();
        arms.push((8, replace));
    }
    Union::new_weighted(arms).boxed()
}

/// Command lines: random tokens, a subcommand with flags and values, or a baseline mutated.
fn command_lines(values: &Values) -> BoxedStrategy<Vec<String>> {
    let subs = subcommands();
    let mut tokens: Vec<String> = subs.iter().map(|s| s.name.clone()).collect();
    for s in &subs {
        tokens.extend(s.flags.iter().map(|(f, _)| format!("--{f}")));
    }
    tokens.extend(
        ["--help", "-h", "--version", "-V", "--", "-", "--=", "---", "--no-such-flag"].map(str::to_owned),
    );
    tokens.sort();
    tokens.dedup();
    let random =
        vec(prop_oneof![4 => select(tokens), 2 => values.number.clone(), 1 => values.wild.clone()], 0..8)
            .boxed();

    // Per subcommand: any of its flags, and its positionals.
    let per_sub: Rc<Vec<SubStrategy>> = Rc::new(
        subs.iter()
            .map(|s| SubStrategy {
                name: s.name.clone(),
                flags: if s.flags.is_empty() {
                    Just(Vec::new()).boxed()
                } else {
                    Union::new(s.flags.iter().map(|(f, v)| occurrence(values, f, *v))).boxed()
                },
                positional: values.positional(&s.name),
                // One more than clap takes, sometimes.
                positionals: s.positionals.min(2) + usize::from(s.positionals > 0),
            })
            .collect(),
    );
    let structured = (0..per_sub.len())
        .prop_flat_map(move |i| {
            let SubStrategy { name, flags, positional, positionals } = per_sub[i].clone();
            (vec(flags, 0..7), vec(positional, 0..=positionals), any::<Index>()).prop_map(
                move |(flags, positionals, at)| {
                    let mut argv = vec![name.clone()];
                    argv.extend(flags.into_iter().flatten());
                    // The positionals somewhere among the flags.
                    let i = 1 + at.index(argv.len());
                    argv.splice(i..i, positionals);
                    argv
                },
            )
        })
        .boxed();

    let bases: Vec<(Vec<String>, BoxedStrategy<Mutation>)> = baselines()
        .iter()
        .map(|b| {
            let argv: Vec<String> = b.split_whitespace().map(str::to_owned).collect();
            let sub = subs.iter().find(|s| s.name == argv[0]).expect("a baseline's subcommand");
            let m = mutations(values, sub, &argv);
            (argv, m)
        })
        .collect();
    let bases = Rc::new(bases);
    let mutated = (0..bases.len())
        .prop_flat_map(move |i| {
            let (argv, m) = bases[i].clone();
            vec(m, 0..4).prop_map(move |ms| {
                let mut argv = argv.clone();
                for m in &ms {
                    m.apply(&mut argv);
                }
                argv
            })
        })
        .boxed();

    prop_oneof![1 => random, 3 => structured, 4 => mutated].boxed()
}

/// Runs `cases` command lines.
pub(super) fn run(cases: u32) -> Result<(), String> {
    let env = Env::new();
    let values = Values::new(env.paths());
    // Built once and reused, as `Cli::try_parse_from` would build it for every call.
    let cli = std::cell::RefCell::new(Cli::command());
    let outcomes = std::cell::RefCell::new(Outcomes::default());
    let result = super::fuzz("argv", cases, command_lines(&values), |argv| {
        check(&env, &mut cli.borrow_mut(), argv, &mut outcomes.borrow_mut())
    });
    let o = outcomes.into_inner();
    super::report(&format!(
        "fuzz argv: {} refused by clap, {} by the commands' validation before their first output, {} reached it",
        o.clap, o.refused, o.accepted
    ));
    result
}

/// How the command lines fared: that the generator gets past clap, and past validation.
#[derive(Debug, Default)]
struct Outcomes {
    clap: u64,
    refused: u64,
    accepted: u64,
}

/// One command line: parsed, then validated up to the first output; every refusal ordinary.
fn check(env: &Env, cli: &mut clap::Command, argv: &[String], outcomes: &mut Outcomes) -> Result<(), String> {
    let args = std::iter::once("pendula".to_owned()).chain(argv.iter().map(|a| env.rooted(a)));
    let parsed = cli.try_get_matches_from_mut(args).and_then(|m| Cli::from_arg_matches(&m));
    let command = match parsed {
        Ok(cli) => cli.command,
        // clap's refusals: usage errors exit 2; --help and --version print and exit 0.
        Err(e) => {
            outcomes.clap += 1;
            super::refused();
            return match e.exit_code() {
                0 | 2 if !e.to_string().trim().is_empty() => Ok(()),
                code => Err(format!("clap refused with exit {code}: {e}")),
            };
        }
    };
    match &command {
        // Their output is all they do, and clap has checked their words.
        Command::List { .. } | Command::Completions { .. } | Command::Man { .. } => {
            outcomes.accepted += 1;
            return Ok(());
        }
        Command::Report(r) if r.gallery_list => {
            outcomes.accepted += 1;
            return Ok(());
        }
        // A server has no output to stop at, and never ends: its validation is a function.
        Command::Serve(args) => {
            return match pendula_cli::commands::serve::options(args) {
                Ok(_) => {
                    outcomes.accepted += 1;
                    Ok(())
                }
                Err(e) => {
                    outcomes.refused += 1;
                    ordinary(&e)
                }
            };
        }
        // `simulate --every 0` has no output to stop at: its validation is a function.
        Command::Simulate(args) => {
            return match pendula_cli::config::simulate(args) {
                Ok(_) => {
                    outcomes.accepted += 1;
                    after_first_output(&command)
                }
                Err(e) => {
                    outcomes.refused += 1;
                    ordinary(&e)
                }
            };
        }
        _ => {}
    }
    pendula_cli::output::validate_only(true);
    let result = {
        let _claims = claims();
        pendula_cli::dispatch(&command)
    };
    pendula_cli::output::validate_only(false);
    match result {
        Ok(()) => Err("the command ran to its end without an output: its outputs bypass output.rs".into()),
        Err(e) if e.chain().any(|c| c.is::<pendula_cli::output::Validated>()) => {
            outcomes.accepted += 1;
            after_first_output(&command)
        }
        Err(e) => {
            outcomes.refused += 1;
            ordinary(&e)
        }
    }
}

/// What the commands check after their first output is open: `simulate`'s events, `plot`'s
/// file, `merge`'s shard descriptions.
fn after_first_output(command: &Command) -> Result<(), String> {
    match command {
        Command::Simulate(args) => {
            let config =
                pendula_cli::config::simulate(args).map_err(|e| format!("accepted, then refused: {e:#}"))?;
            let model = config.values.build();
            for e in &args.events {
                if let Err(err) = pendula::events::EventSpec::parse(e, &*model, args.stop_on_event) {
                    ordinary(&err.into())?;
                }
            }
            Ok(())
        }
        Command::Plot(args) => super::files::plot_checks(args, false),
        Command::Merge(args) => {
            for path in &args.shards {
                if let Err(err) = pendula_cli::commands::merge::describe(path) {
                    ordinary(&err)?;
                }
            }
            Ok(())
        }
        _ => Ok(()),
    }
}
