//! The library's study registry ([`pendula::study::STUDIES`]) as subcommands: one per
//! study, its flags and their `[default: …]` derived from the study's parameters, so that a
//! new study needs no CLI code. Flags are spelled `--t-end` for the parameter `t_end`; the
//! system is the positional argument; `--set`, `--out-dir`, `--summary` and `--allow-large`
//! are every study command's. The report is presented as every study's is: its summary
//! printed, its tables written as CSV and its plots as PNG and SVG in the output directory,
//! and a JSON summary of what ran and the numbers found.

use anyhow::Result;
use clap::{Arg, ArgMatches, Args, FromArgMatches};
use pendula::study::{Budget, Cells, Input, Inputs, Kind, Param, Report, STUDIES, Study, Unit};
use serde_json::{Map, Value, json};

use crate::study::{Common, OutDir, num};

/// Studies the CLI presents with a command of its own over the same library spec: `compare`
/// writes the files it wrote before the registry (`summary.csv`, its energy, trajectory and
/// phase figures), which `pendula report` reads.
pub const OWN_COMMANDS: &[&str] = &["compare"];

/// The registry's studies that are subcommands here.
pub fn registered() -> impl Iterator<Item = &'static Study> {
    STUDIES.iter().copied().filter(|s| !OWN_COMMANDS.contains(&s.name))
}

/// A study command as parsed: which study, and its arguments.
#[derive(Debug, Clone)]
pub struct StudyCommand {
    study: &'static Study,
    matches: ArgMatches,
}

/// The flag of a parameter: `--t-end` for `t_end`.
pub fn flag(param: &Param) -> String {
    match param.kind {
        // The positional argument: named as a word.
        Kind::System { .. } => param.name.to_owned(),
        _ => format!("--{}", param.name.replace('_', "-")),
    }
}

/// The help of a parameter: its phrase, its unit, and its default (from the study, so that
/// it is written once).
pub fn help(study: &Study, param: &Param) -> String {
    let unit = match param.real_unit() {
        Some(Unit::Time) => ", s (none for a dimensionless system)".to_owned(),
        Some(Unit::Fixed(u)) => format!(", {u}"),
        _ => String::new(),
    };
    respell(study, &format!("{}{unit} [default: {}]", param.help, param.default_text()))
}

/// `text` with each parameter it names in backticks (`` `renormalise` ``) spelled as its
/// flag (`--renormalise`).
fn respell(study: &Study, text: &str) -> String {
    let names = study.params.iter().map(|p| (p.name, flag(p))).chain([("set", "--set".to_owned())]);
    names.fold(text.to_owned(), |t, (n, f)| t.replace(&format!("`{n}`"), &f))
}

/// The subcommand of `study`.
pub fn command(study: &'static Study) -> clap::Command {
    let mut cmd = clap::Command::new(study.name);
    for p in study.params {
        let arg = match p.kind {
            // The one system it runs: nothing to choose.
            Kind::System { fixed: true, .. } => continue,
            Kind::System { .. } => Arg::new(p.name).value_name("SYSTEM"),
            Kind::Method { .. } => Arg::new(p.name).long(p.name).value_name("NAME"),
            Kind::Methods => Arg::new(p.name).long(p.name).value_name("LIST"),
            Kind::Variable { .. } | Kind::Preset => Arg::new(p.name).long(p.name).value_name("NAME"),
            Kind::Flag => Arg::new(p.name).long(p.name).action(clap::ArgAction::SetTrue),
            Kind::Section { .. } => Arg::new(p.name).long(p.name).value_name("NAME=VALUE"),
            Kind::Axis { .. } => Arg::new(p.name).long(p.name).value_name("NAME=LO:HI:N"),
            Kind::Reals { .. } => Arg::new(p.name).long(p.name).value_name("LIST").allow_hyphen_values(true),
            Kind::Real { .. } | Kind::Optional { .. } | Kind::Count { .. } | Kind::Threads => {
                Arg::new(p.name)
                    .long(p.name.replace('_', "-"))
                    .value_name(p.name.to_uppercase())
                    .allow_hyphen_values(true)
            }
        };
        cmd = cmd.arg(arg.help(help(study, p)));
    }
    // After the shared arguments, whose own doc would otherwise be the command's about.
    let cmd = Common::augment_args(cmd).about(study.about);
    match set_help(study) {
        Some(help) => cmd.mut_arg("set", |a| a.help(help)),
        None => cmd,
    }
}

/// `--set` help with an example on the study's default system: its first parameter at twice
/// its default (`--set l=2` for the pendulum), which is always in its domain.
fn set_help(study: &Study) -> Option<String> {
    // `fixed`: only the system's parameters may be set (its start is the study's).
    let (default, fixed, own_start) = study.params.iter().find_map(|p| match p.kind {
        Kind::System { default, fixed, own_start, .. } => {
            Some((default, fixed || own_start.is_some(), own_start))
        }
        _ => None,
    })?;
    let info = pendula::model::find(default).ok()?;
    let q = info.parameters.iter().find(|q| q.default > 0.0)?;
    let what = if fixed { "a parameter" } else { "a parameter or initial-state variable" };
    let example = |q: &pendula::system::Quantity| {
        format!(
            "`--set {}={}`{}",
            q.name,
            pendula::error::Short(2.0 * q.default),
            if matches!(q.unit, "" | "1") { String::new() } else { format!(" ({})", q.unit) }
        )
    };
    // A study that takes a preset: its settings come first, and `--set` applies over them.
    let over_preset = study.params.iter().any(|p| matches!(p.kind, Kind::Preset)).then(|| {
        // Only where the presets are another system's.
        let preset = pendula::system::driven::PRESETS.first().filter(|p| p.system != default)?;
        let info = pendula::model::find(preset.system).ok()?;
        let q = info.parameters.iter().find(|q| q.default > 0.0)?;
        Some(format!(", or over a --preset's settings ({} with a {} preset)", example(q), preset.system))
    });
    Some(format!(
        "Set {what} of the {default} system, e.g. {}{}; `pendula list systems` names them{}{}",
        example(q),
        over_preset.flatten().unwrap_or_default(),
        if fixed { "" } else { "; angles take a `deg` or `pi` suffix (bare numbers are radians)" },
        own_start.map(|why| format!(" ({})", respell(study, why))).unwrap_or_default()
    ))
}

impl FromArgMatches for StudyCommand {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let Some((name, sub)) = matches.subcommand() else {
            return Err(clap::Error::new(clap::error::ErrorKind::MissingSubcommand));
        };
        let study = registered()
            .find(|s| s.name == name)
            .ok_or_else(|| clap::Error::new(clap::error::ErrorKind::InvalidSubcommand))?;
        Ok(StudyCommand { study, matches: sub.clone() })
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl clap::Subcommand for StudyCommand {
    fn augment_subcommands(cmd: clap::Command) -> clap::Command {
        registered().fold(cmd, |cmd, s| cmd.subcommand(command(s)))
    }

    fn augment_subcommands_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_subcommands(cmd)
    }

    fn has_subcommand(name: &str) -> bool {
        registered().any(|s| s.name == name)
    }
}

impl StudyCommand {
    /// The study's name.
    pub fn name(&self) -> &'static str {
        self.study.name
    }

    /// Reads the arguments into the study's inputs, runs it, and writes its report.
    pub fn run(&self) -> Result<()> {
        let common = Common::from_arg_matches(&self.matches)?;
        let inputs = self.inputs(&common)?;
        let budget = budget(common.large.allow_large);
        // Checked before the output directory is touched: bad input leaves no trace.
        let files: Vec<String> =
            self.study.files.iter().flat_map(|f| ["csv", "png", "svg"].map(|e| format!("{f}.{e}"))).collect();
        let files: Vec<&str> = files.iter().map(String::as_str).collect();
        let mut out = OutDir::new(common.out_dir.as_deref(), self.study.name, &files)?;
        let summary = common.summary.open()?;
        let report = (self.study.run)(&inputs, &budget).map_err(|e| error(self.study, e))?;
        for line in &report.summary {
            sayln!(summary, "{line}");
        }
        for table in report.tables.iter().filter(|t| t.shown) {
            let header: Vec<String> =
                table
                    .columns
                    .iter()
                    .map(|c| {
                        if c.unit.is_empty() { c.name.to_owned() } else { format!("{} ({})", c.name, c.unit) }
                    })
                    .collect();
            let header: Vec<&str> = header.iter().map(String::as_str).collect();
            say!(summary, "\n{}", crate::study::table(&header, &rows(table, true).collect::<Vec<_>>()));
        }
        for table in &report.tables {
            let header: Vec<&str> = table.columns.iter().map(|c| c.name).collect();
            out.csv_rows(&format!("{}.csv", table.name), &header, rows(table, false))?;
        }
        for plot in &report.plots {
            out.figure(plot.name, &pendula_viz::Figure::from(plot))?;
        }
        out.finish_with(summary, &document(&report))
    }

    /// The study's inputs: each given flag read with the value syntax (`120deg`, `pi`, `1e-3`),
    /// `--set` items against the system's quantities.
    fn inputs(&self, common: &Common) -> Result<Inputs> {
        let mut inputs = Inputs::default();
        // Values read in the units of the system's quantities they name (`90deg`), once the
        // system is known.
        let (mut system, mut preset, mut in_units) = (None, None, Vec::new());
        for p in self.study.params {
            if let Kind::Flag = p.kind {
                if self.matches.get_flag(p.name) {
                    inputs.values.push((p.name.to_owned(), Input::Flag(true)));
                }
                continue;
            }
            let Ok(Some(text)) = self.matches.try_get_one::<String>(p.name) else { continue };
            let value = match p.kind {
                Kind::System { .. }
                | Kind::Method { .. }
                | Kind::Methods
                | Kind::Variable { .. }
                | Kind::Preset => Input::Name(text.clone()),
                Kind::Section { .. } | Kind::Axis { .. } => {
                    in_units.push((p, text.as_str()));
                    continue;
                }
                // Within the CLI's thread limit (four a core without --allow-large).
                Kind::Threads => {
                    Input::Number(crate::limits::threads(Some(text), common.large.allow_large)? as f64)
                }
                Kind::Real { .. } | Kind::Optional { .. } | Kind::Count { .. } | Kind::Flag => {
                    Input::Number(crate::parse::parse_value(&flag(p), text, None)?)
                }
                // Comma-separated, each in the value syntax.
                Kind::Reals { .. } => Input::Numbers(
                    text.split(',')
                        .map(|item| crate::parse::parse_value(&flag(p), item.trim(), None))
                        .collect::<Result<_>>()?,
                ),
            };
            match p.kind {
                Kind::System { .. } => system = Some(text.as_str()),
                // A preset picks the system when none is named (the study checks that
                // they agree).
                Kind::Preset => {
                    preset = Some(pendula::system::driven::find_preset(text)?.system);
                }
                _ => {}
            }
            inputs.values.push((p.name.to_owned(), value));
        }
        let system = system.or(preset);
        let default = self.study.params.iter().find_map(|p| match p.kind {
            Kind::System { default, .. } => Some(default),
            _ => None,
        });
        for (p, text) in in_units {
            let info = pendula::model::find(system.or(default).unwrap_or_default())?;
            let value = match p.kind {
                // A section's value in the value syntax of its angle, as a number.
                Kind::Section { .. } => match text.split_once('=') {
                    Some((angle, value)) => {
                        match info.state.iter().find(|q| q.name == angle.trim() && q.is_angle()) {
                            Some(q) => {
                                format!(
                                    "{}={:?}",
                                    q.name,
                                    crate::parse::parse_value(&flag(p), value, Some(q))?
                                )
                            }
                            None => text.to_owned(),
                        }
                    }
                    None => text.to_owned(),
                },
                // An axis's bounds in its quantity's value syntax; a name the system does not
                // have, and the other checks, are the study's.
                _ => {
                    let example = "drive_amplitude=1.0:1.5:800";
                    match pendula_io::value::parse_axis_text(info, &flag(p), example, text) {
                        Ok(a) if info.parameters.iter().any(|q| q.name == a.name) => {
                            format!("{}={:?}:{:?}:{}", a.name, a.lo, a.hi, a.n)
                        }
                        Err(e)
                            if info.quantity(text.split('=').next().unwrap_or_default().trim()).is_ok() =>
                        {
                            return Err(e.into());
                        }
                        _ => text.to_owned(),
                    }
                }
            };
            inputs.values.push((p.name.to_owned(), Input::Name(value)));
        }
        if !common.set.items.is_empty() {
            let name = system.or(default).ok_or_else(|| {
                anyhow::anyhow!("invalid --set: {} runs no system whose values it could set", self.study.name)
            })?;
            let info = pendula::model::find(name)?;
            inputs.set = crate::parse::parse_settings(info, &common.set.items)?;
        }
        Ok(inputs)
    }
}

/// The CLI's limits as a study's budget: none with `--allow-large`.
pub fn budget(allow_large: bool) -> Budget {
    let limited = !allow_large;
    Budget {
        max_steps: limited.then_some(crate::limits::MAX_SCALAR_STEPS),
        // The tables are written as CSV: each value a cell.
        max_values: limited.then_some(crate::limits::MAX_OUTPUT_BYTES / crate::limits::CSV_BYTES_PER_VALUE),
        max_lane_steps: limited.then_some(crate::limits::MAX_LANE_STEPS),
    }
}

/// A library error of `study` with its parameter names spelled as flags.
pub fn error(study: &Study, e: pendula::Error) -> anyhow::Error {
    let mut names: Vec<(&str, String)> = study.params.iter().map(|p| (p.name, flag(p))).collect();
    names.push(("set", "--set".to_owned()));
    let names: Vec<(&str, &str)> = names.iter().map(|(n, f)| (*n, f.as_str())).collect();
    match e {
        // Worded as every command's refusal over the limits (the budget's limit is the same).
        pendula::Error::TooLarge { what, cost, amount, .. } => {
            let estimate = match cost {
                pendula::study::Cost::Steps => {
                    crate::limits::Estimate::new(crate::limits::Cost::Steps, amount, what)
                }
                pendula::study::Cost::LaneSteps => {
                    crate::limits::Estimate::new(crate::limits::Cost::LaneSteps, amount, what)
                }
                // Each value a CSV cell.
                pendula::study::Cost::Values => crate::limits::Estimate::new(
                    crate::limits::Cost::Output,
                    amount * crate::limits::CSV_BYTES_PER_VALUE,
                    what,
                ),
            };
            crate::limits::check(study.name, false, &[estimate])
                .err()
                .unwrap_or_else(|| anyhow::anyhow!("{}: refusing a request over the limits", study.name))
        }
        e => respelled(e, &names),
    }
}

/// A library error with the parameters it names (`name`, and `` `name` `` in its words)
/// spelled as their flags in `names` ((parameter, flag) pairs).
pub fn respelled(e: pendula::Error, names: &[(&str, &str)]) -> anyhow::Error {
    let flag_of = |name: &str| names.iter().find(|(n, _)| *n == name).map(|(_, f)| *f);
    let words = |text: &str| names.iter().fold(text.to_owned(), |t, (n, f)| t.replace(&format!("`{n}`"), f));
    match e {
        pendula::Error::InvalidInput { name, value, allowed } => {
            let shown = flag_of(&name).unwrap_or(&name);
            let allowed = words(&allowed);
            if value.parse::<f64>().is_ok() {
                anyhow::anyhow!("invalid {shown} {value}: {allowed}")
            } else {
                anyhow::anyhow!("invalid {shown} `{value}`: {allowed}")
            }
        }
        pendula::Error::InvalidValue { name, value, allowed } if flag_of(&name).is_some() => {
            let shown = flag_of(&name).unwrap_or_default();
            anyhow::anyhow!("invalid {shown} {}: {}", pendula::error::Short(value), words(allowed))
        }
        pendula::Error::OutOfRange { name, value, why } if flag_of(&name).is_some() => {
            let shown = flag_of(&name).unwrap_or_default();
            anyhow::anyhow!("invalid {shown} {}: {why}", pendula::error::Short(value))
        }
        e => crate::parse::flag_error(e, names),
    }
}

/// A table's rows, each value as CSV and the printed tables write numbers, made one at a time.
/// A printed table (`printed`) shows a column's [`pendula::study::Column::decimals`].
fn rows(table: &pendula::study::Table, printed: bool) -> impl Iterator<Item = Vec<String>> + '_ {
    let cell = move |c: &pendula::study::Column, i: usize| match &c.values {
        Cells::Numbers(v) if printed && v[i].is_finite() && c.decimals.is_some() => {
            format!("{:.*}", c.decimals.unwrap_or_default(), v[i])
        }
        // A missing whole number (NaN) is an empty cell.
        Cells::Numbers(v) if c.whole && v[i].is_finite() => format!("{}", v[i] as i64),
        Cells::Numbers(v) => num(v[i]),
        Cells::Text(t) => t[i].clone(),
    };
    (0..table.rows()).map(move |i| table.columns.iter().map(|c| cell(c, i)).collect())
}

/// A number in JSON: a whole one (a count, a round end time) as an integer, so that readers
/// take `30` orbits as the count it is; others with every digit.
fn number(x: f64) -> Value {
    if x.fract() == 0.0 && x.abs() < 9e15 { json!(x as i64) } else { json!(x) }
}

/// The JSON summary: every input as the run used it, every number, and the rows of the
/// tables short enough to show (`tables.NAME`, a list of {column: value}).
fn document(report: &Report) -> Value {
    let mut doc = Map::new();
    doc.insert("study".into(), json!(report.study));
    for (name, input) in &report.inputs {
        let v = match input {
            Input::Number(x) => number(*x),
            Input::Name(s) => json!(s),
            Input::Flag(b) => json!(b),
            Input::Numbers(v) => Value::Array(v.iter().map(|x| number(*x)).collect()),
        };
        doc.insert((*name).into(), v);
    }
    for (key, text) in &report.texts {
        doc.insert((*key).into(), json!(text));
    }
    for n in &report.numbers {
        doc.insert(n.key.into(), number(n.value));
    }
    let mut tables = Map::new();
    for t in report.tables.iter().filter(|t| t.shown) {
        let rows: Vec<Value> = (0..t.rows())
            .map(|i| {
                let cell = |c: &pendula::study::Column| match &c.values {
                    Cells::Numbers(v) => number(v[i]),
                    Cells::Text(t) => json!(t[i]),
                };
                Value::Object(t.columns.iter().map(|c| (c.name.to_owned(), cell(c))).collect())
            })
            .collect();
        tables.insert(t.name.into(), Value::Array(rows));
    }
    if !tables.is_empty() {
        doc.insert("tables".into(), Value::Object(tables));
    }
    Value::Object(doc)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_flag_shows_the_default_its_study_declares() {
        for study in STUDIES {
            let cmd = command(study);
            for p in study.params.iter().filter(|p| !matches!(p.kind, Kind::System { fixed: true, .. })) {
                let arg =
                    cmd.get_arguments().find(|a| a.get_id() == p.name).expect("an argument per parameter");
                let shown = arg.get_help().expect("help").to_string();
                // The default as declared, its parameter names spelled as flags.
                let default = respell(study, &p.default_text());
                assert!(shown.ends_with(&format!("[default: {default}]")), "{}: {shown}", p.name);
            }
        }
    }
}
