//! What the study commands (compare, convergence, stability, period, oscillator-regimes,
//! report) share: their common arguments, the output directory, tables and progress.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use pendula::integrator::{self, METHODS, Method, Requirement};
use pendula::system::{self, DynModel, Values};
use pendula_viz::Figure;

use crate::config::{f64_arg, parse_settings};
use crate::output::AtomicFile;

/// Arguments every study command takes.
#[derive(Debug, Clone, Args)]
pub struct Common {
    /// Set a parameter or initial-state variable of the system, NAME=VALUE (`pendula list
    /// systems` names them; each command's help gives an example for its system).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Directory for CSV, PNG and SVG outputs [default: pendula-out/<command>].
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    /// Write the headline numbers as JSON here.
    #[arg(long, value_name = "FILE.json")]
    pub summary: Option<PathBuf>,
}

/// A geometric range of step sizes and an end time, as convergence and work-precision take
/// them.
#[derive(Debug, Clone, Args)]
pub struct StepRange {
    /// Smallest step size, s [default: dt-max / 2^(levels - 1)].
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub dt_min: Option<String>,
    /// Largest step size, s [default: 0.05 for convergence, 0.1 for work-precision].
    #[arg(long, value_name = "H", allow_hyphen_values = true)]
    pub dt_max: Option<String>,
    /// Number of step sizes, geometrically spaced [default: 5 for convergence, 7 for
    /// work-precision].
    #[arg(long, value_name = "N")]
    pub levels: Option<usize>,
    /// End time at which the error is measured, s [default: 10].
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub t_end: Option<String>,
}

impl StepRange {
    /// The steps, largest first, and the end time, validated.
    pub fn resolve(&self, default_max: f64, default_levels: usize) -> Result<(Vec<f64>, f64)> {
        let levels = self.levels.unwrap_or(default_levels);
        if levels < 2 {
            bail!("invalid --levels {levels}: need at least 2 step sizes");
        }
        let dt_max = f64_arg("--dt-max", self.dt_max.as_deref(), default_max, "a step size in seconds")?;
        let fallback = dt_max / 2f64.powi(levels as i32 - 1);
        let dt_min = f64_arg("--dt-min", self.dt_min.as_deref(), fallback, "a step size in seconds")?;
        let t_end = f64_arg("--t-end", self.t_end.as_deref(), 10.0, "an end time in seconds")?;
        if !(dt_min.is_finite() && dt_min > 0.0 && dt_max.is_finite() && dt_max > dt_min) {
            bail!(
                "invalid step range --dt-min {dt_min} --dt-max {dt_max}: need 0 < dt-min < dt-max, both finite"
            );
        }
        let spec = pendula::RunSpec { t0: 0.0, h: dt_min, end: pendula::End::Time(t_end) };
        crate::config::schedule(&spec, "--dt-min", "--t-end")?;
        let hs =
            (0..levels).map(|i| dt_max * (dt_min / dt_max).powf(i as f64 / (levels - 1) as f64)).collect();
        Ok((hs, t_end))
    }
}

/// Validated system values from a name and `--set` items.
pub fn values(system: &str, set: &[String]) -> Result<Values> {
    let info = system::find(system)?;
    Ok(info.values(&parse_settings(info, set)?)?)
}

/// Validated values from an optional system name, an optional `--preset` (which picks the
/// system when none is named) and `--set` items over it; `default` names the system when
/// neither does.
pub fn preset_values(
    system: Option<&str>,
    preset: Option<&str>,
    set: &[String],
    default: &str,
) -> Result<Values> {
    let (info, settings) = preset_settings(system, preset, set, default)?;
    Ok(info.values(&settings)?)
}

/// The system and the (name, value) settings of [`preset_values`], not yet validated as a
/// whole (for commands that add their own settings per run).
pub fn preset_settings(
    system: Option<&str>,
    preset: Option<&str>,
    set: &[String],
    default: &str,
) -> Result<(&'static system::SystemInfo, Vec<(String, f64)>)> {
    let preset = preset.map(system::driven::find_preset).transpose()?;
    let name = system.or(preset.map(|p| p.system)).unwrap_or(default);
    let info = system::find(name)?;
    let mut settings = match preset {
        Some(p) => crate::config::preset_settings(info, p)?,
        None => Vec::new(),
    };
    settings.extend(parse_settings(info, set)?);
    Ok((info, settings))
}

/// Methods from a comma-separated list, or every method that applies to `model` at steps up
/// to `max_h` when `None` (Tao's maps apply only where ω h ≤ 1; `None` for `max_h` keeps
/// them).
pub fn methods(
    list: Option<&str>,
    model: &dyn DynModel,
    values: &Values,
    max_h: Option<f64>,
) -> Result<Vec<&'static Method>> {
    let stable = |m: &Method| match (m.scheme, max_h) {
        (pendula::integrator::Scheme::Tao(t), Some(h)) => {
            pendula::integrator::tao::check_binding_step(&t, h).is_ok()
        }
        _ => true,
    };
    match list {
        Some(text) => text.split(',').map(|name| Ok(integrator::find(name.trim())?)).collect(),
        None => Ok(METHODS.iter().copied().filter(|m| applies(m, model, values) && stable(m)).collect()),
    }
}

/// Whether `method` can run on the model (its requirement is met).
fn applies(method: &Method, model: &dyn DynModel, values: &Values) -> bool {
    method.requirement == Requirement::Any || {
        let spec = pendula::RunSpec { t0: 0.0, h: 1e-3, end: pendula::End::Steps(1) };
        !matches!(
            model.solve(method, values.initial_state(), &spec, &mut pendula::observe::Ignore),
            Err(pendula::Error::UnmetRequirement { .. })
        )
    }
}

/// The output directory: created if needed; files appear whole (temporary name, then rename).
pub struct OutDir {
    path: PathBuf,
    written: Vec<PathBuf>,
}

impl OutDir {
    /// `--out-dir`, or `pendula-out/<command>`.
    pub fn new(dir: Option<&Path>, command: &str) -> Result<Self> {
        let path = dir.map_or_else(|| Path::new("pendula-out").join(command), Path::to_path_buf);
        if path.exists() && !path.is_dir() {
            bail!("cannot write --out-dir {}: it is a file, not a directory", path.display());
        }
        std::fs::create_dir_all(&path)
            .with_context(|| format!("cannot create --out-dir {}", path.display()))?;
        // Fail now, not after the work, if the directory cannot be written.
        AtomicFile::create(&path.join(".pendula-probe"), "--out-dir")?;
        Ok(OutDir { path, written: Vec::new() })
    }

    /// Where the files go.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `bytes` to `name` in the directory.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf> {
        let path = self.path.join(name);
        let file = AtomicFile::create(&path, "--out-dir")?;
        std::io::Write::write_all(&mut file.handle()?, bytes)?;
        file.commit()?;
        self.written.push(path.clone());
        Ok(path)
    }

    /// Writes `name.png` and `name.svg`.
    pub fn figure(&mut self, name: &str, figure: &Figure) -> Result<()> {
        self.write(&format!("{name}.png"), &figure.png()?)?;
        self.write(&format!("{name}.svg"), figure.svg()?.as_bytes())?;
        Ok(())
    }

    /// Writes a CSV file from a header and rows of fields.
    pub fn csv(&mut self, name: &str, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(header)?;
        for row in rows {
            w.write_record(row)?;
        }
        self.write(name, &w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))?)?;
        Ok(())
    }

    /// Tells stderr what was written.
    pub fn report(&self) {
        eprintln!("wrote {} files to {}", self.written.len(), self.path.display());
    }
}

/// Writes the `--summary` JSON, if asked for.
pub fn summary(path: Option<&Path>, doc: &serde_json::Value) -> Result<()> {
    if let Some(path) = path {
        let file = AtomicFile::create(path, "--summary")?;
        // Serialised through a buffer: a File takes one syscall per token.
        let mut handle = std::io::BufWriter::new(file.handle()?);
        serde_json::to_writer_pretty(&mut handle, doc)?;
        std::io::Write::write_all(&mut handle, b"\n")?;
        handle.into_inner().map_err(|e| e.into_error())?;
        file.commit()?;
    }
    Ok(())
}

/// A progress bar on stderr for `n` units of work; invisible when stderr is not a terminal.
pub fn progress(n: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(n);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {elapsed}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_owned());
    bar
}

/// A plain-text table with aligned columns.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut widths: Vec<usize> = header.iter().map(|h| h.len()).collect();
    for row in rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(cell.len());
        }
    }
    let mut out = String::new();
    let line = |out: &mut String, cells: &mut dyn Iterator<Item = &str>| {
        let parts: Vec<String> = cells.zip(&widths).map(|(c, w)| format!("{c:>w$}")).collect();
        let _ = writeln!(out, "{}", parts.join("  ").trim_end());
    };
    line(&mut out, &mut header.iter().copied());
    for row in rows {
        line(&mut out, &mut row.iter().map(String::as_str));
    }
    out
}

/// A number for tables and CSV: shortest round-trip form.
pub fn num(v: f64) -> String {
    if v.is_finite() { ryu::Buffer::new().format(v).to_owned() } else { String::new() }
}

/// A number for humans: 4 significant digits.
pub fn short(v: f64) -> String {
    if !v.is_finite() {
        "-".into()
    } else if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}
