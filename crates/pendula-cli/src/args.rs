//! The argument groups several commands share, declared once (ripgrep's low-level arguments,
//! converted in one step into validated values): the system to run (a positional name), its
//! settings (`--set`) and preset (`--preset`), the method and its step (`--method`, `--dt`),
//! the end time (`--t-end`), the worker threads (`--threads`), the JSON summary (`--summary`)
//! and the limits' override (`--allow-large`). A command whose flag means something more
//! says so in its help (`cli.rs`'s `mut_arg`, or a note in its [`Defaults`]).
//!
//! Each command states its defaults once, in a [`Defaults`]. Its help text and its conversion
//! both read them: [`Defaults::document`] writes `[default: …]` into the help of the shared
//! arguments the command has (`cli.rs` applies it to every argument of the command), and the
//! groups' `resolve` methods fall back to the same values. What the help says is what runs
//! (`tests/cli.rs` checks the help of every command against its `Defaults`).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use pendula::error::Short;
use pendula::integrator::{self, Method};

use crate::parse::{f64_arg, positive_arg};

/// A command's defaults: the library's for its study ([`pendula::study::defaults`], read
/// through `Deref`: `DEFAULTS.system`, `DEFAULTS.dt`, …), and a sentence the command adds
/// to an argument's help, by argument id (`dt`, `t_end`, …). Fields the command does not
/// take are not shown (`document` touches only the arguments the command has).
#[derive(Debug, Clone, Copy)]
pub struct Defaults {
    /// The library's defaults of the study.
    pub of: &'static pendula::study::defaults::Defaults,
    /// A sentence the command adds to an argument's help, by argument id (`dt`, `t_end`, …).
    pub notes: &'static [(&'static str, &'static str)],
}

impl std::ops::Deref for Defaults {
    type Target = pendula::study::defaults::Defaults;

    fn deref(&self) -> &Self::Target {
        self.of
    }
}

impl Defaults {
    /// The command of the study whose defaults are `of`, with its help's `notes`.
    pub const fn of(
        of: &'static pendula::study::defaults::Defaults,
        notes: &'static [(&'static str, &'static str)],
    ) -> Self {
        Defaults { of, notes }
    }

    /// The number given to the study's own flag `id` (`--` and the id with `-` for `_`), or
    /// its default ([`pendula::study::defaults`]); `what` says what the flag takes.
    pub fn number(&self, id: &str, given: &Option<String>, what: &str) -> Result<f64> {
        f64_arg(&flag(id), given.as_deref(), self.of.number(id), what)
    }

    /// [`Defaults::number`] of a flag that must be > 0.
    pub fn positive(&self, id: &str, given: &Option<String>, what: &str) -> Result<f64> {
        positive_arg(&flag(id), given.as_deref(), self.of.number(id), what)
    }

    /// [`Defaults::number`] of a flag that must be >= 0 (a time discarded, a tolerance).
    pub fn non_negative(&self, id: &str, given: &Option<String>, what: &str) -> Result<f64> {
        let v = self.number(id, given, what)?;
        if v < 0.0 {
            anyhow::bail!("invalid {} {}: must be finite and >= 0", flag(id), Short(v));
        }
        Ok(v)
    }

    /// `arg` with its help stating this command's default, when it is one of the shared
    /// arguments; other arguments unchanged.
    pub fn document(&self, arg: clap::Arg) -> clap::Arg {
        let id = arg.get_id().as_str().to_owned();
        // The study's own default: written after the flag's own help.
        let long = arg.get_long().map(|l| l.replace('-', "_"));
        if let Some(d) = self.of.values.iter().find(|d| d.name == id || Some(d.name) == long.as_deref()) {
            let own =
                arg.get_help().map(|h| h.to_string().trim_end_matches('.').to_owned()).unwrap_or_default();
            let why = if d.why.is_empty() { String::new() } else { format!(", {}", d.why) };
            return arg.help(format!("{own} [default: {}{why}]", d.value));
        }
        let (what, default) = match id.as_str() {
            "system" => {
                ("System to run (see `pendula list systems`)".to_owned(), Some(self.system.to_owned()))
            }
            "method" => {
                ("Integration method (see `pendula list methods`)".to_owned(), self.method.map(str::to_owned))
            }
            "dt" => ("Step size, s".to_owned(), self.dt.map(|v| Short(v).to_string())),
            "t_end" => ("End time, s".to_owned(), self.t_end.map(|v| Short(v).to_string())),
            // The other shared groups' help, with the command's note after it.
            "set" | "preset" | "threads" | "summary" => {
                let own = arg.get_help().map(|h| h.to_string().trim_end_matches('.').to_owned());
                (own.unwrap_or_default(), None)
            }
            _ => return arg,
        };
        let note = self.notes.iter().find(|(n, _)| *n == id);
        if default.is_none() && note.is_none() {
            // Not the group's argument but the command's own of the same name (compare's
            // `--dt`, one step for every method): its own help stays.
            return arg;
        }
        // One sentence is shown without its period, as clap shows a doc comment's.
        let default = default.map_or(String::new(), |d| format!(" [default: {d}]"));
        let note = note.map_or(String::new(), |(_, text)| format!(". {text}"));
        arg.help(format!("{what}{default}{note}"))
    }
}

/// The flag of argument id `id`: `--steps-per-period` for `steps_per_period`.
fn flag(id: &str) -> String {
    format!("--{}", id.replace('_', "-"))
}

/// Several methods, by name: the accuracy and comparison studies'.
#[derive(Debug, Clone, Default, Args)]
pub struct MethodsArg {
    /// Comma-separated methods [default: every method that applies].
    #[arg(long, value_name = "LIST")]
    pub methods: Option<String>,
}

impl MethodsArg {
    /// The methods named ([`pendula::model::named_methods`]: each must apply, named once),
    /// or every method that applies to `model` ([`pendula::model::applicable`]).
    pub fn resolve(&self, model: &dyn pendula::model::DynModel) -> Result<Vec<&'static Method>> {
        match self.methods.as_deref() {
            Some(text) => pendula::model::named_methods(model, text.split(',')).map_err(|e| match e {
                pendula::Error::InvalidInput { allowed, .. } => {
                    anyhow::anyhow!("invalid --methods `{}`: {allowed}", crate::parse::clip(text))
                }
                other => other.into(),
            }),
            None => Ok(pendula::model::applicable(model, integrator::METHODS, None)),
        }
    }
}

/// The system, by name (positional).
#[derive(Debug, Clone, Default, Args, serde::Serialize, serde::Deserialize)]
pub struct SystemArg {
    /// System to run (see `pendula list systems`).
    pub system: Option<String>,
}

impl SystemArg {
    /// The name given, or the command's default.
    pub fn name<'a>(&'a self, defaults: &'a Defaults) -> &'a str {
        self.system.as_deref().unwrap_or(defaults.system)
    }
}

/// The method and its step size.
#[derive(Debug, Clone, Default, Args, serde::Serialize, serde::Deserialize)]
pub struct MethodArgs {
    /// Integration method (see `pendula list methods`).
    #[arg(long, value_name = "NAME")]
    pub method: Option<String>,
    /// Step size, s.
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub dt: Option<String>,
}

impl MethodArgs {
    /// The method named, or the command's default.
    pub fn method(&self, defaults: &Defaults) -> Result<&'static Method> {
        Ok(integrator::find(self.method.as_deref().unwrap_or(defaults.method.expect("a default method")))?)
    }

    /// The step given (any finite number: the run's schedule judges it, naming `--dt`), or
    /// the command's default.
    pub fn dt(&self, defaults: &Defaults) -> Result<f64> {
        f64_arg("--dt", self.dt.as_deref(), defaults.dt.expect("a default step"), "a step size in seconds")
    }

    /// The step given, which must be > 0, or the command's default.
    pub fn positive_dt(&self, defaults: &Defaults) -> Result<f64> {
        positive_arg(
            "--dt",
            self.dt.as_deref(),
            defaults.dt.expect("a default step"),
            "a step size in seconds",
        )
    }
}

/// The end time.
#[derive(Debug, Clone, Default, Args, serde::Serialize, serde::Deserialize)]
pub struct EndArg {
    /// End time, s.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_end: Option<String>,
}

impl EndArg {
    /// The end time given (any finite number: the run's schedule judges it), or the
    /// command's default.
    pub fn t_end(&self, defaults: &Defaults) -> Result<f64> {
        f64_arg(
            "--t-end",
            self.t_end.as_deref(),
            defaults.t_end.expect("a default end"),
            "an end time in seconds",
        )
    }

    /// The end time given, which must be > 0, or the command's default.
    pub fn positive_t_end(&self, defaults: &Defaults) -> Result<f64> {
        positive_arg(
            "--t-end",
            self.t_end.as_deref(),
            defaults.t_end.expect("a default end"),
            "a time in seconds",
        )
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// Every command that takes a shared argument states its default in the help, from its
    /// `Defaults`: a command whose variant in `cli.rs` lacks `mut_args(… .document(a))`
    /// shows the group's bare doc comment instead, and fails here.
    #[test]
    fn every_shared_argument_is_documented_by_its_commands_defaults() {
        let bare = [
            "System to run (see `pendula list systems`)",
            "Integration method (see `pendula list methods`)",
            "Step size, s",
            "End time, s",
        ];
        let cli = crate::cli::Cli::command();
        let mut documented = 0;
        for command in cli.get_subcommands() {
            for arg in command.get_arguments() {
                let help = arg.get_help().map(ToString::to_string).unwrap_or_default();
                let name = command.get_name();
                assert!(!bare.contains(&help.as_str()), "`pendula {name}`: {} undocumented", arg.get_id());
                if bare.iter().any(|b| help.starts_with(b)) {
                    documented += 1;
                }
            }
        }
        // The commands not on the study registry (whose flags studies.rs documents) take 16
        // shared arguments: the system, the method, the step and the end time.
        assert!(documented >= 16, "only {documented} shared arguments documented");
    }

    /// No default is written twice: every `[default: …]` that states a number in any
    /// command's help is the library's ([`pendula::study::defaults`], or a registry study's
    /// parameter), written into the help from it; a number typed into a doc comment fails.
    #[test]
    fn every_number_a_help_gives_as_default_is_the_librarys() {
        let cli = crate::cli::Cli::command();
        let mut checked = 0;
        for command in cli.get_subcommands() {
            let name = command.get_name();
            let lib = pendula::study::defaults::ALL.iter().find(|d| d.study == name);
            let study = pendula::study::find(name).ok();
            for arg in command.get_arguments() {
                let help = arg.get_help().map(ToString::to_string).unwrap_or_default();
                let Some(at) = help.find("[default: ") else { continue };
                let stated = &help[at + 10..];
                let numeric = stated.starts_with(|c: char| c.is_ascii_digit() || c == '-');
                if !numeric {
                    continue;
                }
                let id = arg.get_id().as_str();
                let expected = match (lib, study) {
                    (Some(d), _) => match (id, d.values.iter().find(|v| v.name == id)) {
                        (_, Some(v)) => v.value.to_string(),
                        ("dt", None) => pendula::error::Short(d.dt.expect("a step")).to_string(),
                        ("t_end", None) => pendula::error::Short(d.t_end.expect("an end")).to_string(),
                        _ => panic!(
                            "`pendula {name} --{}`: a default typed into its help: {help}",
                            arg.get_long().unwrap_or(id)
                        ),
                    },
                    (None, Some(s)) => {
                        let p =
                            s.params.iter().find(|p| p.name.replace('-', "_") == id).expect("a parameter");
                        p.default_text()
                    }
                    (None, None) => panic!("`pendula {name}`: a default typed into its help: {help}"),
                };
                assert!(
                    stated.starts_with(&expected),
                    "`pendula {name}` {id}: {help} (the library says {expected})"
                );
                checked += 1;
            }
        }
        // The shared step and end times of eight commands, and some thirty of their own.
        assert!(checked >= 40, "only {checked} numeric defaults checked");
        // And the other way: every default the library declares for a command is in its help.
        for d in pendula::study::defaults::ALL {
            let command = cli.find_subcommand(d.study).expect("a command per study");
            for v in d.values {
                let arg = command
                    .get_arguments()
                    .find(|a| a.get_long().map(|l| l.replace('-', "_")).as_deref() == Some(v.name))
                    .unwrap_or_else(|| panic!("`pendula {}` has no --{}", d.study, v.name));
                let help = arg.get_help().map(ToString::to_string).unwrap_or_default();
                assert!(help.contains(&format!("[default: {}", v.value)), "`pendula {}`: {help}", d.study);
            }
        }
    }

    /// What the help states is what the conversion uses.
    #[test]
    fn the_help_states_the_default_the_conversion_takes() {
        use super::{EndArg, MethodArgs, SystemArg};
        let d = crate::commands::animate::DEFAULTS;
        let help = d.document(clap::Arg::new("t_end")).get_help().unwrap().to_string();
        let t_end = EndArg::default().t_end(&d).unwrap();
        assert!(help.contains(&format!("[default: {t_end}]")), "{help}");
        let m = MethodArgs::default();
        assert_eq!(m.method(&d).unwrap().name, d.method.unwrap());
        let dt_help = d.document(clap::Arg::new("dt")).get_help().unwrap().to_string();
        assert!(dt_help.contains(&format!("[default: {}]", m.dt(&d).unwrap())), "{dt_help}");
        assert_eq!(SystemArg::default().name(&d), "double");
    }
}

/// The settings over the system's defaults.
#[derive(Debug, Clone, Default, Args, serde::Serialize, serde::Deserialize)]
pub struct SetArgs {
    /// Set a parameter or initial-state variable, NAME=VALUE (`pendula list systems` names
    /// them); angles take a `deg` or `pi` suffix (bare numbers are radians).
    #[arg(id = "set", long = "set", value_name = "NAME=VALUE")]
    #[serde(rename = "set")]
    pub items: Vec<String>,
}

/// A named parameter set (`pendula list presets`), which picks the system.
#[derive(Debug, Clone, Default, Args, serde::Serialize, serde::Deserialize)]
pub struct PresetArg {
    /// Start from a named preset (see `pendula list presets`); it picks the system, and
    /// --set applies over it.
    #[arg(id = "preset", long = "preset", value_name = "NAME")]
    #[serde(rename = "preset")]
    pub name: Option<String>,
}

/// The worker threads of a parallel command.
#[derive(Debug, Clone, Default, Args, serde::Serialize, serde::Deserialize)]
pub struct ThreadsArg {
    /// Worker threads, at most the cores (1024 with --allow-large) [default: all cores]; the
    /// result does not depend on it.
    #[arg(id = "threads", long = "threads", value_name = "N")]
    #[serde(rename = "threads")]
    pub count: Option<String>,
}

impl ThreadsArg {
    /// The threads given (1 to the cores; to 1024 with `allow_large`), or every core.
    pub fn resolve(&self, allow_large: bool) -> Result<usize> {
        crate::limits::threads(self.count.as_deref(), allow_large)
    }
}

/// Where the JSON summary goes.
#[derive(Debug, Clone, Default, Args, serde::Serialize, serde::Deserialize)]
pub struct SummaryArg {
    /// Write a JSON summary here (`-`: on stdout, and what is printed for people on stderr).
    #[arg(id = "summary", long = "summary", value_name = "FILE.json")]
    #[serde(rename = "summary")]
    pub path: Option<PathBuf>,
}

/// Whether to run beyond the limits (`crate::limits`).
#[derive(Debug, Clone, Copy, Default, Args, serde::Serialize, serde::Deserialize)]
pub struct LargeArg {
    #[arg(long, help = crate::limits::ALLOW_LARGE_HELP)]
    pub allow_large: bool,
}
