//! `pendula report`: the paper's numerical study and pendula's chaos tools in one
//! self-contained HTML page — a table of contents, numbered sections, and figures whose
//! captions name the exact command that made them.
//!
//! The report runs those commands themselves (through the same dispatcher as the command
//! line, with `--out-dir` and `--summary` pointing into its folder), embeds their figures and
//! builds its sentences and tables from their JSON summaries, so that what the text says is
//! what the numbers beside it show. `--gallery DIR` runs the README gallery's commands
//! ([`GALLERY`]) and copies each picture there.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use base64::Engine as _;
use clap::Args;
use serde_json::Value;

use crate::study::{OutDir, QUIET, short};

#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Directory for report.html and every figure and table in it [default: pendula-out/report].
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    /// Instead of the report, regenerate the README gallery into DIR: every picture from the
    /// exact command its caption names (docs/gallery in the repository).
    #[arg(long, value_name = "DIR", conflicts_with = "out_dir")]
    pub gallery: Option<PathBuf>,
    /// Print the gallery's manifest (picture, command) and stop.
    #[arg(long, conflicts_with_all = ["out_dir", "gallery"])]
    pub gallery_list: bool,
}

/// One figure of the report: a command, the file it writes, and what the caption says.
pub struct Shown {
    /// The command after `pendula`, as a reader would type it.
    pub command: &'static str,
    /// The PNG (or GIF) it writes into its --out-dir.
    pub file: &'static str,
}

/// A picture of the README gallery: its file name in docs/gallery and the command whose
/// output it is (the caption names the same command; a test checks the README against this).
pub struct GalleryEntry {
    /// File name in the gallery folder.
    pub name: &'static str,
    /// The command after `pendula`.
    pub command: &'static str,
    /// The file the command writes into its --out-dir.
    pub file: &'static str,
}

/// The README gallery, one line per picture.
#[rustfmt::skip]
pub static GALLERY: &[GalleryEntry] = &[
    GalleryEntry { name: "pendulum_energy.png", command: "compare pendulum --methods euler,rk4,symplectic-euler,verlet --dt 0.05 --t-end 500", file: "energy.png" },
    GalleryEntry { name: "double_energy.png", command: "compare double --methods euler,rk4,symplectic-euler,verlet,gauss-legendre-4 --evals-per-second 700 --t-end 100000", file: "energy.png" },
    GalleryEntry { name: "oscillator_convergence.png", command: "convergence oscillator", file: "convergence.png" },
    GalleryEntry { name: "double_convergence.png", command: "convergence double", file: "convergence.png" },
    GalleryEntry { name: "work_precision.png", command: "work-precision pendulum", file: "work_precision_evals.png" },
    GalleryEntry { name: "stability.png", command: "stability double", file: "stability.png" },
    GalleryEntry { name: "period.png", command: "period", file: "period.png" },
    GalleryEntry { name: "regimes.png", command: "oscillator-regimes", file: "regimes.png" },
    GalleryEntry { name: "resonance_amplitude.png", command: "oscillator-regimes", file: "resonance_amplitude.png" },
    GalleryEntry { name: "divergence.png", command: "divergence", file: "divergence.png" },
    GalleryEntry { name: "lyapunov.png", command: "lyapunov --spectrum --t-end 500", file: "lyapunov.png" },
    GalleryEntry { name: "poincare.png", command: "poincare", file: "poincare.png" },
    GalleryEntry { name: "bifurcation.png", command: "bifurcation", file: "bifurcation.png" },
    GalleryEntry { name: "fractal.png", command: "fractal", file: "fractal.png" },
    GalleryEntry { name: "fractal_converged.png", command: "fractal", file: "fractal-converged.png" },
    GalleryEntry { name: "chaos.gif", command: "animate double --compare 1e-3 --t-end 12 --fps 20 --size 400x400", file: "animation.gif" },
];

/// Parses and runs one command line (`pendula ARGS...`) as the binary would. The dispatcher
/// above the commands passes it in: the report is one of the commands it runs.
pub type RunLine = fn(&[String]) -> Result<()>;

/// Runs `command` (after `pendula`) with its outputs in `dir`; returns its summary, if it
/// writes one.
fn run_in(run_line: RunLine, command: &str, dir: &Path) -> Result<Option<Value>> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut args: Vec<String> =
        std::iter::once("pendula".to_owned()).chain(command.split_whitespace().map(str::to_owned)).collect();
    let animate = args[1] == "animate";
    let summary = dir.join("summary.json");
    if animate {
        args.extend(["--out".into(), dir.join("animation.gif").display().to_string()]);
    } else {
        args.extend(["--out-dir".into(), dir.display().to_string()]);
        args.extend(["--summary".into(), summary.display().to_string()]);
    }
    run_line(&args).with_context(|| format!("report: `pendula {command}`"))?;
    if animate {
        return Ok(None);
    }
    let text =
        std::fs::read_to_string(&summary).with_context(|| format!("cannot read {}", summary.display()))?;
    Ok(Some(serde_json::from_str(&text)?))
}

/// A folder name for a command's outputs.
fn slug(command: &str) -> String {
    let s: String =
        command.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect();
    s.chars().take(60).collect()
}

/// The page being built.
struct Page {
    dir: PathBuf,
    html: String,
    toc: Vec<(String, String)>,
    figures: usize,
    /// Summaries of the commands already run, by command.
    runs: Vec<(String, Option<Value>)>,
    /// The caption of the next table: it holds the data of the figure just shown.
    next_caption: Option<String>,
    /// How a command is run.
    run_line: RunLine,
}

/// The table that belongs to a figure: the numbers it is drawn from or that it shows.
enum Data {
    /// This table, under the figure.
    Table { header: Vec<String>, rows: Vec<Vec<String>> },
    /// The next table the page writes (the caller's own) is the figure's.
    Next,
    /// None (an animation, whose numbers are those of the figures beside it).
    None,
}

impl Data {
    /// A table of (quantity with its unit, value) rows.
    fn pairs(rows: Vec<(&str, String)>) -> Self {
        Data::Table {
            header: vec!["quantity".into(), "value".into()],
            rows: rows.into_iter().map(|(k, v)| vec![k.to_owned(), v]).collect(),
        }
    }

    /// A table with this header.
    fn table(header: &[&str], rows: Vec<Vec<String>>) -> Self {
        Data::Table { header: header.iter().map(|h| (*h).to_owned()).collect(), rows }
    }
}

/// A number as a table cell: a whole number as an integer (5, not 5.0000), others to a few
/// digits without trailing zeros (0.05, 1.5387, 2.475e-5).
fn number(v: f64) -> String {
    if v.is_finite() && v.fract() == 0.0 && v.abs() < 1e15 {
        return format!("{v:.0}");
    }
    let s = short(v);
    if s.contains('.') && !s.contains('e') {
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        s
    }
}

/// A summary's value as a table cell: integers as integers (30, not 30.0000), other numbers
/// to a few digits, strings as they are, lists joined, none as "-".
fn cell(v: &Value) -> String {
    match v {
        Value::Number(n) => match (n.as_u64(), n.as_i64()) {
            (Some(u), _) => u.to_string(),
            (_, Some(i)) => i.to_string(),
            _ => n.as_f64().map_or_else(|| n.to_string(), number),
        },
        Value::String(s) => s.clone(),
        Value::Bool(b) => if *b { "yes" } else { "no" }.to_owned(),
        Value::Array(a) => a.iter().map(cell).collect::<Vec<_>>().join(", "),
        Value::Null | Value::Object(_) => "-".to_owned(),
    }
}

impl Page {
    /// Runs a command once (later calls reuse its outputs).
    fn run(&mut self, command: &str) -> Result<Option<Value>> {
        if let Some((_, s)) = self.runs.iter().find(|(c, _)| c == command) {
            return Ok(s.clone());
        }
        let s = run_in(self.run_line, command, &self.dir.join(slug(command)))?;
        self.runs.push((command.to_owned(), s.clone()));
        Ok(s)
    }

    fn section(&mut self, title: &str, text: &str) {
        let n = self.toc.len() + 1;
        let id = format!("s{n}");
        let _ = write!(self.html, "<h2 id=\"{id}\">{n}. {}</h2>\n<p>{text}</p>\n", escape(title));
        self.toc.push((id, format!("{n}. {title}")));
    }

    fn paragraph(&mut self, text: &str) {
        let _ = writeln!(self.html, "<p>{text}</p>");
    }

    /// Embeds the figure `shown` with a caption that ends by naming its command, and its own
    /// table (`data`, from the run's summary and files).
    fn figure(&mut self, shown: &Shown, caption: &str, data: Data) -> Result<()> {
        self.run(shown.command)?;
        let path = self.dir.join(slug(shown.command)).join(shown.file);
        let bytes = std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
        let mime = if shown.file.ends_with(".gif") { "image/gif" } else { "image/png" };
        self.figures += 1;
        let encoded = base64::engine::general_purpose::STANDARD.encode(&bytes);
        let full = format!(
            "Figure {}. {caption} Made by <code>pendula {}</code>.",
            self.figures,
            escape(shown.command)
        );
        let _ = writeln!(
            self.html,
            "<figure><img src=\"data:{mime};base64,{encoded}\" alt=\"{}\"><figcaption>{full}</figcaption></figure>",
            escape(caption)
        );
        match data {
            Data::Table { header, rows } => {
                self.next_caption = Some(format!("Data of Figure {}", self.figures));
                let header: Vec<&str> = header.iter().map(String::as_str).collect();
                self.table(&header, &rows, "figure-data");
            }
            Data::Next => self.next_caption = Some(format!("Data of Figure {}", self.figures)),
            Data::None => self.next_caption = None,
        }
        Ok(())
    }

    /// The summary of a command run earlier, and the folder of its files.
    fn summary(&mut self, command: &str) -> Result<(Value, PathBuf)> {
        let s = self.run(command)?.with_context(|| format!("`pendula {command}` writes a summary"))?;
        Ok((s, self.dir.join(slug(command))))
    }

    fn table(&mut self, header: &[&str], rows: &[Vec<String>], class: &str) {
        let _ = write!(self.html, "<table class=\"{class}\">");
        if let Some(caption) = self.next_caption.take() {
            let _ = write!(self.html, "<caption>{}</caption>", escape(&caption));
        }
        self.html.push_str("<tr>");
        for h in header {
            let _ = write!(self.html, "<th>{}</th>", escape(h));
        }
        self.html.push_str("</tr>\n");
        for row in rows {
            self.html.push_str("<tr>");
            for c in row {
                let _ = write!(self.html, "<td>{}</td>", escape(c));
            }
            self.html.push_str("</tr>\n");
        }
        self.html.push_str("</table>\n");
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// Restores the commands' own output when the report ends, however it ends.
struct Quiet;

impl Quiet {
    fn on() -> Self {
        QUIET.store(true, std::sync::atomic::Ordering::Relaxed);
        Quiet
    }
}

impl Drop for Quiet {
    fn drop(&mut self) {
        QUIET.store(false, std::sync::atomic::Ordering::Relaxed);
    }
}

/// The files it writes in its study directory (listed with the command in `cli::COMMANDS`).
pub const FILES: &[&str] = &["report.html"];

pub fn run(args: &ReportArgs, run_line: RunLine) -> Result<()> {
    if args.gallery_list {
        for entry in GALLERY {
            println!("{}\tpendula {}", entry.name, entry.command);
        }
        return Ok(());
    }
    if let Some(dir) = &args.gallery {
        return gallery(dir, run_line);
    }
    let start = Instant::now();
    let mut out = OutDir::new(args.out_dir.as_deref(), "report", FILES)?;
    let dir = out.path().to_path_buf();
    let _quiet = Quiet::on();
    let mut page = Page {
        dir: dir.join("runs"),
        html: String::new(),
        toc: Vec::new(),
        figures: 0,
        runs: Vec::new(),
        next_caption: None,
        run_line,
    };
    build(&mut page)?;
    drop(_quiet);

    let wall = start.elapsed().as_secs_f64();
    let mut toc = String::from("<nav><h2>Contents</h2><ol>");
    for (id, title) in &page.toc {
        let _ = write!(
            toc,
            "<li><a href=\"#{id}\">{}</a></li>",
            escape(title.split_once(". ").map_or(title, |t| t.1))
        );
    }
    toc.push_str("</ol></nav>\n");
    let html = format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>pendula: the numerical study of \
         \"From Simple to Double Pendulum\"</title>\n<style>body{{font-family:sans-serif;max-width:1000px;margin:2em auto;\
         line-height:1.45;color:#222}}img{{max-width:100%}}figure{{margin:1em 0}}figcaption{{color:#555;font-size:90%}}\
         table{{border-collapse:collapse;margin:1em 0}}td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\
         caption{{caption-side:top;text-align:left;color:#555;font-size:90%}}code{{background:#f4f4f4}}</style></head><body>\n<h1>pendula: the numerical study of \"From Simple to Double \
         Pendulum\"</h1>\n<p>Every figure below was computed by pendula {} in {wall:.0} s, by the command its caption \
         names (run with <code>--out-dir</code> and <code>--summary</code> pointing into this folder; the figures, \
         CSV tables and JSON summaries are in <code>runs/</code>). Equations and methods follow the paper as corrected by \
         its errata; each method has one colour and line style throughout. Relative energy errors are taken against each \
         system's energy scale (for the double pendulum (m₁+m₂) g l₁ + m₂ g l₂, or the energy above the minimum if larger), \
         never against |E(0)|, which vanishes for ordinary states.</p>\n{toc}{}</body></html>\n",
        env!("CARGO_PKG_VERSION"),
        page.html
    );
    out.write("report.html", html.as_bytes())?;
    println!("report: {} ({} figures, {wall:.0} s)", out.path().join("report.html").display(), page.figures);
    out.finish()?;
    Ok(())
}

/// The energy study of one compare run: its table and the sentences drawn from it.
fn energy_section(page: &mut Page, command: &'static str, lead: &str, caption: &str) -> Result<()> {
    let s = page.run(command)?.context("compare writes a summary")?;
    let methods = s["methods"].as_object().context("methods")?;
    let (mut bounded, mut growing, mut failed) = (Vec::new(), Vec::new(), Vec::new());
    let mut rows = Vec::new();
    for (name, m) in methods {
        // A failed run has no growth: its status (`failed`, `refused`) is shown instead.
        let growth = m["growth"].as_str().or(m["status"].as_str()).unwrap_or("-");
        match growth {
            "bounded" => bounded.push(name.clone()),
            "growing" => growing.push(name.clone()),
            _ => failed.push(name.clone()),
        }
        rows.push(vec![
            name.clone(),
            short(f(&m["dt"])),
            m["cost_evals"].as_u64().map_or_else(|| "-".to_owned(), |c| c.to_string()),
            short(f(&m["max_rel_energy_error"])),
            short(f(&m["drift_rate"])),
            growth.to_owned(),
            m["failure"].as_str().unwrap_or("").to_owned(),
        ]);
    }
    let mut text = format!(
        "{lead} Relative errors are against the energy scale {} J ({}). Judged from each run (growing when the largest error so \
         far grew by {}× or more over each of the last two doublings of time, T/4 → T/2 → T): bounded — {}; growing — {}.",
        short(f(&s["energy_scale"])),
        escape(s["energy_scale_definition"].as_str().unwrap_or("")),
        pendula::analysis::GROWTH_FACTOR,
        if bounded.is_empty() { "none".to_owned() } else { bounded.join(", ") },
        if growing.is_empty() { "none".to_owned() } else { growing.join(", ") },
    );
    if !failed.is_empty() {
        let _ = write!(text, " Not run to the end: {} (see the table).", failed.join(", "));
    }
    for c in s["crossovers"].as_array().into_iter().flatten() {
        let _ = match c["t"].as_f64() {
            Some(t) => write!(
                text,
                " RK4's drifting error passes {}'s bounded error ({}) at t ≈ {} s.",
                c["bounded"].as_str().unwrap_or(""),
                short(f(&c["bound"])),
                super::compare::round_time(t)
            ),
            None => match c["t_extrapolated"].as_f64() {
                Some(t) => write!(
                    text,
                    " RK4's drifting error stays below {}'s bounded error ({}) over the whole run; at its fitted drift it \
                     would pass it at t ≈ {} s (extrapolated).",
                    c["bounded"].as_str().unwrap_or(""),
                    short(f(&c["bound"])),
                    super::compare::round_sig(t)
                ),
                None => write!(
                    text,
                    " RK4's drifting error stays below {}'s bounded error ({}) over the whole run.",
                    c["bounded"].as_str().unwrap_or(""),
                    short(f(&c["bound"]))
                ),
            },
        };
    }
    page.paragraph(&text);
    // Runs stopped for their error are drawn again below the chart, over their own span.
    let stopped: Vec<&str> = methods
        .iter()
        .filter(|(_, m)| m["failure"].as_str().is_some_and(|f| f.starts_with("stopped at t = ")))
        .map(|(name, _)| name.as_str())
        .collect();
    let caption = if stopped.is_empty() {
        caption.to_owned()
    } else {
        format!(
            "{caption} Below: {} over its own run, to where its error reached the energy scale.",
            stopped.join(", ")
        )
    };
    page.figure(&Shown { command, file: "energy.png" }, &caption, Data::Next)?;
    page.table(
        &["method", "dt (s)", "cost (evals)", "max rel. error", "drift (1/s)", "error", "note"],
        &rows,
        "energy",
    );
    Ok(())
}

/// The orders table of one convergence run.
fn convergence_table(page: &mut Page, command: &'static str) -> Result<()> {
    let s = page.run(command)?.context("convergence writes a summary")?;
    let rows: Vec<Vec<String>> = s["tables"]["orders"]
        .as_array()
        .context("orders")?
        .iter()
        .map(|row| {
            vec![
                row["method"].as_str().unwrap_or("").to_owned(),
                row["declared_order"].to_string(),
                row["fitted_order"].as_f64().map_or("-".into(), |o| format!("{o:.3}")),
                row["note"].as_str().unwrap_or("").to_owned(),
            ]
        })
        .collect();
    page.table(&["method", "declared order", "fitted order", "note"], &rows, "orders");
    Ok(())
}

fn build(page: &mut Page) -> Result<()> {
    page.section(
        "The harmonic oscillator: damping regimes and resonance (paper §2, Figure 1)",
        "Free decay from x = 1 m at rest in the three damping regimes, and the forced steady state against the drive \
         frequency. Lines are the closed forms, markers RK4 at h = 0.01 s. The phase lag runs from 0 to π and is π/2 at \
         resonance, not \"slightly delayed\" as §2.2 says (ERRATA).",
    );
    let regimes = "oscillator-regimes";
    let (r, dir) = page.summary(regimes)?;
    page.figure(
        &Shown { command: regimes, file: "regimes.png" },
        "Underdamped, critically damped and overdamped decay: exact lines, RK4 markers.",
        transients_data(&dir.join("transients.csv"))?,
    )?;
    let peaks: Vec<Vec<String>> = r["tables"]["peaks"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|p| {
            vec![
                cell(&p["zeta"]),
                cell(&p["drive_ratio"]),
                cell(&p["amplitude_exact"]),
                cell(&p["amplitude_simulated"]),
            ]
        })
        .collect();
    page.figure(
        &Shown { command: regimes, file: "resonance_amplitude.png" },
        &format!(
            "Steady-state amplitude against drive frequency; simulated amplitudes agree with the exact ones to {} (relative).",
            short(f(&r["max_rel_amplitude_error"]))
        ),
        Data::table(
            &[
                "damping ratio ζ",
                "peak at Ω/ω₀ (dimensionless)",
                "peak amplitude X k/F, exact (dimensionless)",
                "simulated (dimensionless)",
            ],
            peaks,
        ),
    )?;
    page.figure(
        &Shown { command: regimes, file: "resonance_phase.png" },
        &format!(
            "Phase lag of the steady state against drive frequency; simulated lags agree with the exact ones to {} rad.",
            short(f(&r["max_phase_error"]))
        ),
        phase_data(&dir.join("resonance.csv"))?,
    )?;

    page.section(
        "Energy conservation: the simple pendulum (paper §7.3, §8.3, Figure 6)",
        "The simple pendulum from 60° at a coarse step h = 0.05 s over 500 s. Its Hamiltonian is separable, so symplectic \
         Euler and Verlet are the explicit schemes of §8. RK4 does not preserve energy, contrary to §7.3 (ERRATA).",
    );
    energy_section(
        page,
        "compare pendulum --methods euler,rk4,symplectic-euler,verlet --dt 0.05 --t-end 500",
        "All four methods at the same step.",
        "Simple pendulum: envelope of the relative energy error, every method at h = 0.05 s.",
    )?;

    page.section(
        "Energy conservation at equal cost: the double pendulum (paper §6, §8.3, Figure 7)",
        "The double pendulum from (120°, −10°). Its Hamiltonian is not separable, so the paper's explicit symplectic Euler \
         and Verlet would be neither symplectic nor (Verlet) symmetric (ERRATA); pendula runs their generalizations on \
         (θ, p), implicit, with the stages solved to round-off, and the Gauss–Legendre collocation methods. A fair \
         comparison gives every method the same work: 700 right-hand-side evaluations per simulated second (RK4 at \
         h = 1/175 s; a Jacobian counts one evaluation per state variable), each method's step chosen to spend it. The \
         implicit methods' iterations make their steps larger than RK4's at the same cost, and RK4's error is smaller \
         than the low-order symplectic methods' at first: only over a long run does its secular drift overtake their \
         bounded errors. A crossover beyond the run is extrapolated from RK4's fitted drift rate, and says so.",
    );
    energy_section(
        page,
        "compare double --methods euler,rk4,symplectic-euler,verlet,gauss-legendre-4 --evals-per-second 700 --t-end 100000",
        "Five methods at equal cost over 100 000 s.",
        "Double pendulum at equal cost (700 evaluations per second): envelope of the relative energy error over 100 000 s.",
    )?;

    page.section(
        "Accuracy: global error against step size (paper §7.1–7.3, §8.3), every method",
        "The error at the end of a few small-oscillation periods against the exact solution (oscillator) or dop853 at \
         tolerance 10⁻¹⁴ (double pendulum, 2 s: longer and chaos amplifies every error by orders of magnitude). Each \
         method runs its own ladder of halved steps; the order is fitted on the straight stretch of the log-log curve \
         that ends at the smallest step between saturation (errors of 1% of the state) and the round-off floor, found \
         without looking at the declared order — where there is none the legend and the table say why: \
         \"step too large\" (the errors reach the round-off floor while the slope still changes) or \"saturated at \
         round-off\". dopri5 and dop853 run here at fixed steps, without their error control: their curves measure the \
         order of the formula they advance with. The paper's printed RK4 (k₄ \
         from yₙ + k₃, k₄ left out of the update) is not even consistent (ERRATA); pendula's is the classical method.",
    );
    for command in ["convergence oscillator", "convergence double"] {
        let system = command.split_whitespace().nth(1).unwrap_or("");
        page.figure(
            &Shown { command, file: "convergence.png" },
            &format!("{system}: global error against step for every applicable method; the legend gives the fitted orders, or why there is none."),
            Data::Next,
        )?;
        convergence_table(page, command)?;
    }

    let wp = "work-precision pendulum";
    let (_, dir) = page.summary(wp)?;
    let costs = work_precision_rows(&dir.join("work_precision.csv"))?;
    // The cheapest method to reach the target error, and what RK4 spends for it.
    let reach = |m: &str| costs.iter().find(|c| c.0 == m).and_then(|c| c.1);
    let cheapest = costs.iter().filter_map(|c| c.1.map(|n| (c.0.as_str(), n))).min_by_key(|c| c.1);
    let mut text = String::from(
        "The same errors against what they cost, for fixed-step methods over their ladders and for the adaptive pairs \
         dopri5 and dop853 over tolerances 10⁻³ … 10⁻¹²: the higher-order and adaptive methods reach a given accuracy \
         for far fewer evaluations.",
    );
    if let Some((m, n)) = cheapest {
        let _ = write!(
            text,
            " To bring the error at 10 s to 10⁻⁶ or below the cheapest is {m}, with {n} evaluations"
        );
        let _ = match (reach("rk4"), reach("euler")) {
            (Some(r), Some(e)) => write!(text, "; RK4 needs {r}, Euler {e}."),
            (Some(r), None) => write!(text, "; RK4 needs {r}, and Euler does not get there on its ladder."),
            _ => write!(text, "."),
        };
    }
    page.section("Cost: work-precision (error against right-hand-side evaluations)", &text);
    page.figure(
        &Shown { command: wp, file: "work_precision_evals.png" },
        "Simple pendulum from 60°: error at 10 s against right-hand-side evaluations, every method.",
        Data::table(
            &["method", "evaluations to error ≤ 10⁻⁶", "smallest error (rad, rad/s)", "evaluations there"],
            costs
                .iter()
                .map(|(m, n, e, at)| {
                    vec![
                        m.clone(),
                        n.map_or_else(|| "not reached".to_owned(), |n| n.to_string()),
                        number(*e),
                        at.to_string(),
                    ]
                })
                .collect(),
        ),
    )?;

    let mut text = String::from(
        "The largest step at which the relative energy error (against the energy scale) stays below 10% over 20 s, found by \
         bisection. Tao's maps are refused above binding · h = 1; that is a limit of the method's definition, drawn as \
         such (an empty, hatched bar marked refused), not a stability result.",
    );
    for command in ["stability", "stability double"] {
        let (s, _) = page.summary(command)?;
        let steps = stability_rows(&s);
        let measured = steps.iter().filter(|r| !r.3 && r.1.is_some());
        let smallest =
            measured.clone().min_by(|a, b| a.1.partial_cmp(&b.1).unwrap_or(std::cmp::Ordering::Equal));
        let largest = measured.max_by(|a, b| a.1.partial_cmp(&b.1).unwrap_or(std::cmp::Ordering::Equal));
        if let (Some(a), Some(b)) = (smallest, largest) {
            let _ = write!(
                text,
                " On the {}, the stable steps run from {} s ({}) to {} s ({}).",
                match s["system"].as_str().unwrap_or("") {
                    "pendulum" => "simple pendulum",
                    "double" => "double pendulum",
                    other => other,
                },
                number(a.1.unwrap_or(f64::NAN)),
                a.0,
                number(b.1.unwrap_or(f64::NAN)),
                b.0
            );
        }
    }
    page.section("Stability: the largest usable step (paper §7.3 \"Stability\")", &text);
    for command in ["stability", "stability double"] {
        let (s, _) = page.summary(command)?;
        let system = s["system"].as_str().unwrap_or("").to_owned();
        let rows = stability_rows(&s)
            .into_iter()
            .map(|(m, h, note, _)| vec![m, h.map_or_else(|| "-".to_owned(), number), note])
            .collect();
        page.figure(
            &Shown { command, file: "stability.png" },
            &format!("{system}: largest stable step of every applicable method."),
            Data::table(&["method", "largest stable step h (s)", "note"], rows),
        )?;
    }

    let p = page.run("period")?.context("summary")?;
    page.section(
        "Beyond small angles: the period of the simple pendulum (paper §3, §5)",
        &format!(
            "The pendulum is a harmonic oscillator only at small angles (ERRATA): its exact period 4√(l/g) K(sin(θ₀/2)) \
             grows without bound as θ₀ → π. Simulated periods (RK4, h = 1 ms, zero crossings on the Hermite interpolant) \
             match the exact one to {} at worst (relative).",
            short(f(&p["max_rel_error_simulated"]))
        ),
    );
    // Every 15° and the largest amplitude (all of them are in runs/period/period.csv).
    let all: Vec<&Value> = p["tables"]["period"].as_array().into_iter().flatten().collect();
    let period_rows: Vec<&Value> = all
        .iter()
        .enumerate()
        .filter(|(k, r)| f(&r["amplitude_deg"]) % 15.0 == 0.0 || *k + 1 == all.len())
        .map(|(_, r)| *r)
        .collect();
    page.figure(
        &Shown { command: "period", file: "period.png" },
        "Period against amplitude: exact, simulated and small-angle (the table: every 15° and the largest amplitude).",
        Data::table(
            &["amplitude θ₀ (°)", "exact period T (s)", "simulated (s)", "small-angle (s)"],
            period_rows
                .iter()
                .map(|r| vec![cell(&r["amplitude_deg"]), cell(&r["exact"]), cell(&r["simulated"]), cell(&r["small_angle"])])
                .collect(),
        ),
    )?;
    let rel = |r: &Value, k: &str| number((f(&r[k]) / f(&r["exact"]) - 1.0).abs());
    page.figure(
        &Shown { command: "period", file: "period_error.png" },
        "Relative error of the simulated and of the small-angle period.",
        Data::table(
            &["amplitude θ₀ (°)", "|T_sim / T − 1| (dimensionless)", "|T_small / T − 1| (dimensionless)"],
            period_rows
                .iter()
                .map(|r| vec![cell(&r["amplitude_deg"]), rel(r, "simulated"), rel(r, "small_angle")])
                .collect(),
        ),
    )?;

    let d = page.run("divergence")?.context("summary")?;
    page.section(
        "Sensitivity to initial conditions (paper §1)",
        &format!(
            "Two double pendulums started {} rad apart in θ₁ separate exponentially, at a fitted rate of {} 1/s, until the \
             distance saturates.",
            short(f(&d["delta"])),
            short(f(&d["growth_rate"]))
        ),
    );
    let window =
        d["fit_start"].is_number().then(|| format!("{} … {}", cell(&d["fit_start"]), cell(&d["fit_end"])));
    page.figure(
        &Shown { command: "divergence", file: "divergence.png" },
        "Distance between two nearby double pendulums, log scale, with the fitted exponential.",
        Data::pairs(vec![
            ("initial separation δ in θ₁ (rad)", cell(&d["delta"])),
            ("fitted growth rate (1/s)", cell(&d["growth_rate"])),
            ("fit window t (s)", window.unwrap_or_else(|| "-".into())),
            ("distance where the fit stops (rad, rad/s combined)", cell(&d["saturation"])),
            ("method", cell(&d["method"])),
            ("step h (s)", cell(&d["dt"])),
            ("duration (s)", cell(&d["t_end"])),
        ]),
    )?;
    let divergence_figure = page.figures;
    page.figure(
        &Shown { command: "animate double --compare 1e-3 --t-end 12 --fps 20 --size 400x400", file: "animation.gif" },
        "Two double pendulums 10⁻³ rad apart part ways after a few seconds; the gauges show each one's relative energy error.",
        Data::None,
    )?;

    let l = page.run("lyapunov --spectrum --t-end 500")?.context("summary")?;
    // The exponents' table: one row each, with its value and uncertainty.
    let exponents: Vec<&Value> = l["tables"]["exponents"].as_array().into_iter().flatten().collect();
    let spectrum: Vec<String> = exponents.iter().map(|e| short(f(&e["value"]))).collect();
    page.section(
        "Lyapunov exponents",
        &format!(
            "The variational equations v' = J v integrated beside the orbit, re-orthonormalised by QR (Benettin et al. \
             1980): the double pendulum from the default state has the spectrum {} 1/s, in ± pairs as a Hamiltonian \
             system's must be.",
            spectrum.join(", ")
        ),
    );
    let mut rows: Vec<Vec<String>> = exponents
        .iter()
        .map(|e| {
            vec![
                format!("{} (1/s)", pendula_viz::pretty(e["exponent"].as_str().unwrap_or("?"))),
                format!("{} ± {}", short(f(&e["value"])), short(f(&e["uncertainty"]))),
            ]
        })
        .collect();
    rows.extend([
        vec!["method".to_owned(), cell(&l["method"])],
        vec!["step h (s)".to_owned(), cell(&l["dt"])],
        vec!["duration (s)".to_owned(), cell(&l["t_end"])],
        vec!["transient left out (s)".to_owned(), cell(&l["transient"])],
    ]);
    page.figure(
        &Shown { command: "lyapunov --spectrum --t-end 500", file: "lyapunov.png" },
        "Running estimates of the four Lyapunov exponents.",
        Data::table(&["quantity", "value"], rows),
    )?;
    growth_rates(page, divergence_figure)?;

    let q = page.run("poincare")?.context("summary")?;
    page.section(
        "Poincaré section",
        &format!(
            "{} orbits on the energy surface E = {} J, their {} upward crossings of θ₁ = 0 located by events on dop853's \
             dense output (largest energy error {}): invariant curves of regular orbits beside a chaotic sea.",
            cell(&q["count"]),
            cell(&q["energy"]),
            cell(&q["crossings"]),
            short(f(&q["max_energy_error"]))
        ),
    );
    page.figure(
        &Shown { command: "poincare", file: "poincare.png" },
        "Poincaré section of the double pendulum (θ₂, p₂) at θ₁ = 0.",
        Data::pairs(vec![
            ("orbits", cell(&q["count"])),
            ("energy E (J)", cell(&q["energy"])),
            ("crossings of θ₁ = 0, rising", cell(&q["crossings"])),
            ("duration of each orbit (s)", cell(&q["t_end"])),
            ("largest relative energy error", cell(&q["max_energy_error"])),
            ("method", cell(&q["method"])),
        ]),
    )?;

    let fr = page.run("fractal")?.context("summary")?;
    page.section(
        "The flip fractal",
        &format!(
            "The time until either rod first flips over, from rest, over (θ₁, θ₂) on the ensemble engine (SIMD lanes, all \
             cores), run again at half the step: {} of the pixels moved by more than the tolerance.",
            fr["unconverged_share"].as_f64().map_or("-".into(), |v| format!("{:.1} %", 100.0 * v))
        ),
    );
    let grid = |a: &Value| format!("{} … {} rad, {} pixels", cell(&a["lo"]), cell(&a["hi"]), cell(&a["n"]));
    page.figure(
        &Shown { command: "fractal", file: "fractal.png" },
        "Time to the first flip (log colour scale); black: no flip within the horizon.",
        Data::pairs(vec![
            ("θ₁ range", grid(&fr["axes"][0])),
            ("θ₂ range", grid(&fr["axes"][1])),
            ("pixels", cell(&fr["pixels"])),
            ("pixels that flip", cell(&fr["flipped"])),
            ("pixels that cannot flip (energy)", cell(&fr["forbidden_by_energy"])),
            ("horizon t_max (s)", cell(&fr["t_max"])),
            ("method", cell(&fr["method"])),
            ("step h (s)", cell(&fr["dt"])),
            ("threads", cell(&fr["threads"])),
        ]),
    )?;
    page.figure(
        &Shown { command: "fractal", file: "fractal-converged.png" },
        "Convergence flags of the flip fractal: pixels whose flip time moved when the step was halved.",
        Data::pairs(vec![
            ("steps compared h, h/2 (s)", format!("{}, {}", cell(&fr["dt"]), cell(&fr["dt_check"]))),
            ("tolerance on the flip time (s)", cell(&fr["tolerance"])),
            ("pixels not converged", cell(&fr["unconverged"])),
            (
                "share not converged",
                fr["unconverged_share"].as_f64().map_or("-".into(), |v| format!("{:.1} %", 100.0 * v)),
            ),
        ]),
    )?;

    let (b, _) = page.summary("bifurcation")?;
    page.section(
        "Bifurcation of the driven pendulum",
        &format!(
            "Baker and Gollub's damped, driven pendulum (q = 2, ω_D = 2/3): the angular velocity once per drive period \
             against the drive amplitude g, {} values from {} to {}, {} samples each after a transient of {} (time \
             in units of 1/ω₀) — period doubling, chaos, windows.",
            cell(&b["n"]),
            cell(&b["lo"]),
            cell(&b["hi"]),
            cell(&b["samples"]),
            cell(&b["transient"]),
        ),
    );
    page.figure(
        &Shown { command: "bifurcation", file: "bifurcation.png" },
        "Stroboscopic orbit diagram of the driven pendulum.",
        Data::pairs(vec![
            ("drive amplitude g (dimensionless)", format!("{} … {}", cell(&b["lo"]), cell(&b["hi"]))),
            ("values of g", cell(&b["n"])),
            ("samples per value", cell(&b["samples"])),
            ("transient (1/ω₀)", cell(&b["transient"])),
            ("RK4 steps per drive period", cell(&b["steps_per_period"])),
            ("kernel", cell(&b["tables"]["run"][0]["kernel"])),
            ("threads", cell(&b["threads"])),
        ]),
    )?;
    Ok(())
}

/// The data of the free-decay figure: per damping ratio, the largest deviation of RK4 from
/// the exact decay, read from the run's transients.csv (zeta, t, exact, simulated).
fn transients_data(path: &Path) -> Result<Data> {
    let mut worst: Vec<(f64, f64, f64)> = Vec::new();
    for row in read_csv(path)? {
        let (zeta, exact, simulated) = (row[0], row[2], row[3]);
        let dev = (simulated - exact).abs();
        match worst.iter_mut().find(|w| w.0 == zeta) {
            Some(w) => {
                w.1 = w.1.max(dev);
                w.2 = w.2.max(exact.abs());
            }
            None => worst.push((zeta, dev, exact.abs())),
        }
    }
    let regime = |z: f64| {
        if z < 1.0 {
            "underdamped"
        } else if z == 1.0 {
            "critically damped"
        } else {
            "overdamped"
        }
    };
    Ok(Data::table(
        &["damping ratio ζ", "regime", "largest |x_RK4 − x_exact| (m)"],
        worst.iter().map(|(z, d, _)| vec![format!("{z}"), regime(*z).to_owned(), number(*d)]).collect(),
    ))
}

/// The data of the phase figure: per damping ratio, the exact lag at resonance (Ω = ω₀,
/// where it is π/2) and the largest deviation of the simulated lags, from resonance.csv
/// (zeta, drive_ratio, amplitude_exact, amplitude_simulated, phase_exact, phase_simulated).
fn phase_data(path: &Path) -> Result<Data> {
    let mut per: Vec<(f64, f64, f64, f64)> = Vec::new();
    for row in read_csv(path)? {
        let (zeta, ratio, exact, simulated) = (row[0], row[1], row[4], row[5]);
        let dev = (simulated - exact).abs();
        match per.iter_mut().find(|p| p.0 == zeta) {
            Some(p) => {
                p.1 = p.1.max(dev);
                if (ratio - 1.0).abs() < (p.3 - 1.0).abs() {
                    (p.2, p.3) = (exact, ratio);
                }
            }
            None => per.push((zeta, dev, exact, ratio)),
        }
    }
    Ok(Data::table(
        &[
            "damping ratio ζ",
            "exact lag at Ω/ω₀ nearest 1 (rad)",
            "at Ω/ω₀",
            "largest |φ_sim − φ_exact| (rad)",
        ],
        per.iter().map(|(z, d, lag, r)| vec![format!("{z}"), number(*lag), number(*r), number(*d)]).collect(),
    ))
}

/// The numeric rows of a CSV file written by a study command.
fn read_csv(path: &Path) -> Result<Vec<Vec<f64>>> {
    let mut reader =
        csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
    reader
        .records()
        .map(|r| {
            let r = r.with_context(|| format!("cannot read {}", path.display()))?;
            Ok(r.iter().map(|v| v.trim().parse().unwrap_or(f64::NAN)).collect())
        })
        .collect()
}

/// The error the work-precision section quotes the cost of.
const WP_TARGET: f64 = 1e-6;

/// A method's row of the work-precision table: its name, the fewest evaluations to
/// [`WP_TARGET`] (if reached), its smallest error and the evaluations there.
type CostRow = (String, Option<u64>, f64, u64);

/// Per method of a work-precision table (`work_precision.csv`: method, dt, tol, error,
/// rhs_evals, wall_s): the fewest evaluations of a run whose error is at most [`WP_TARGET`]
/// (none when no run gets there), the smallest error, and its evaluations.
fn work_precision_rows(path: &Path) -> Result<Vec<CostRow>> {
    let mut reader =
        csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
    // (method, its (error, evaluations)), in the order the methods ran.
    let mut methods: Vec<(String, Vec<(f64, u64)>)> = Vec::new();
    for record in reader.records() {
        let r = record.with_context(|| format!("cannot read {}", path.display()))?;
        let (m, error, evals) = (&r[0], r[3].parse::<f64>(), r[4].parse::<u64>());
        let (Ok(error), Ok(evals)) = (error, evals) else { continue };
        if methods.last().is_none_or(|(name, _)| name != m) {
            methods.push((m.to_owned(), Vec::new()));
        }
        if error.is_finite()
            && let Some((_, points)) = methods.last_mut()
        {
            points.push((error, evals));
        }
    }
    let mut rows = Vec::new();
    for (m, points) in methods {
        let Some(best) = points.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0)) else { continue };
        let reach = points.iter().filter(|p| p.0 <= WP_TARGET).map(|p| p.1).min();
        rows.push((m, reach, best.0, best.1));
    }
    Ok(rows)
}

/// Per method of a stability summary: its largest stable step, its note, and whether that
/// step is a refusal (a limit of the method's definition) rather than a stability limit.
fn stability_rows(s: &Value) -> Vec<(String, Option<f64>, String, bool)> {
    s["tables"]["stability"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|row| {
            let (m, h) = (row["method"].as_str().unwrap_or("").to_owned(), row["largest_stable_dt"].as_f64());
            let limit = pendula::integrator::find(&m).ok().and_then(pendula::analysis::accepted_step_limit);
            let refused = matches!((h, limit), (Some(h), Some(l)) if h >= l / 1.01);
            (m, h, row["note"].as_str().unwrap_or("").to_owned(), refused)
        })
        .collect()
}

/// The commands whose growth rates [`growth_rates`] reconciles: the report's long Benettin
/// run, `lyapunov` on its defaults, `divergence` on its defaults (the report's divergence
/// figure), and `divergence` with the lab's butterfly settings and fit window (RK4 at 0.01 s;
/// the largest separation of 8 pendulums 10⁻⁹ rad apart, 7·10⁻⁹ at the start, fitted from
/// 100 δ to 0.1: `fitGrowth` in crates/pendula-web/assets/app.js).
pub const GROWTH_COMMANDS: [&str; 4] = [
    "lyapunov --spectrum --t-end 500",
    "lyapunov",
    "divergence",
    "divergence --dt 0.01 --delta 7e-9 --fit-from 1e-7 --saturation 0.1",
];

/// Finite-time rates of a Benettin run over consecutive windows of `window` s: from the
/// running average λ(t) (rows of t, λ₁, … of lyapunov.csv), the growth between window ends,
/// (λ(b) b − λ(a) a) / (b − a).
pub fn finite_time_rates(t: &[f64], lambda: &[f64], window: f64) -> Vec<f64> {
    let mut rates = Vec::new();
    let (mut a, mut sum_a) = (0.0, 0.0);
    for (&b, &l) in t.iter().zip(lambda) {
        if b - a >= window - 1e-9 {
            rates.push((l * b - sum_a) / (b - a));
            (a, sum_a) = (b, l * b);
        }
    }
    rates
}

/// One paragraph and one table that reconcile the growth rates the report's commands (and
/// the lab) give for the default double pendulum, with the numbers from their summaries.
fn growth_rates(page: &mut Page, divergence_figure: usize) -> Result<()> {
    let [long, short_run, diverge, lab] = GROWTH_COMMANDS;
    // Settings to three significant digits (500 s, 0.5 s, 10⁻⁹ rad), rates to three decimals.
    let num = pendula_viz::number;
    let l = page.run(long)?.context("summary")?;
    let s = page.run(short_run)?.context("summary")?;
    let d = page.run(diverge)?.context("summary")?;
    let b = page.run(lab)?.context("summary")?;
    let window = |v: &Value| (f(&v["fit_start"]), f(&v["fit_end"]));
    let (d0, d1) = window(&d);
    let (b0, b1) = window(&b);
    // The long run's own finite-time rates over windows as long as the divergence fit's.
    let csv = page.dir.join(slug(long)).join("lyapunov.csv");
    let text = std::fs::read_to_string(&csv).with_context(|| format!("cannot read {}", csv.display()))?;
    let (ts, lambdas): (Vec<f64>, Vec<f64>) = text
        .lines()
        .skip(1)
        .filter_map(|line| {
            let mut cells = line.split(',').map(|c| c.parse::<f64>());
            Some((cells.next()?.ok()?, cells.next()?.ok()?))
        })
        .unzip();
    let rates = finite_time_rates(&ts, &lambdas, d1 - d0);
    let n = rates.len().max(1) as f64;
    let mean = rates.iter().sum::<f64>() / n;
    let sd = (rates.iter().map(|r| (r - mean) * (r - mean)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
    let (lo, hi) = rates.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, z), r| (a.min(*r), z.max(*r)));
    let rate = |v: &Value, k: &str| format!("{:.3}", f(&v[k]));
    let pm = |v: &Value| format!("{:.3} ± {:.3}", f(&v["lambda_max"]), f(&v["uncertainty"]));
    let rows = vec![
        vec![
            format!("Benettin λ₁, {} s (section above)", num(f(&l["t_end"]))),
            format!("pendula {long}"),
            format!("{}, h = {} s", l["method"].as_str().unwrap_or(""), num(f(&l["dt"]))),
            format!(
                "renormalised every {} s, averaged over {} s after a {} s transient; ± standard error of 10 batch means",
                num(f(&l["renormalise"])),
                num(f(&l["t_end"])),
                num(f(&l["transient"]))
            ),
            pm(&l),
        ],
        vec![
            format!("Benettin λ₁, {} s (lyapunov's default)", num(f(&s["t_end"]))),
            format!("pendula {short_run}"),
            format!("{}, h = {} s", s["method"].as_str().unwrap_or(""), num(f(&s["dt"]))),
            format!("the same, over the first {} s of the same orbit", num(f(&s["t_end"]))),
            pm(&s),
        ],
        vec![
            format!("divergence fit (Figure {divergence_figure})"),
            format!("pendula {diverge}"),
            format!("{}, h = {} s", d["method"].as_str().unwrap_or(""), num(f(&d["dt"]))),
            format!(
                "slope of ln distance of two orbits {} rad apart, t = {} … {} s, until the distance passes {}",
                num(f(&d["delta"])),
                num(d0),
                num(d1),
                num(f(&d["saturation"]))
            ),
            rate(&d, "growth_rate"),
        ],
        vec![
            "the lab's butterfly mode (its rule)".to_owned(),
            format!("pendula {lab}"),
            format!("{}, h = {} s", b["method"].as_str().unwrap_or(""), num(f(&b["dt"]))),
            format!(
                "the same slope from {} to {} (100 δ to 0.1), t = {} … {} s",
                num(f(&b["fit_from"])),
                num(f(&b["saturation"])),
                num(b0),
                num(b1)
            ),
            rate(&b, "growth_rate"),
        ],
        vec![
            format!("finite-time rates over {} s windows", num(d1 - d0)),
            format!("pendula {long} (lyapunov.csv)"),
            format!("{}, h = {} s", l["method"].as_str().unwrap_or(""), num(f(&l["dt"]))),
            format!(
                "{} consecutive windows of the Benettin run as long as the divergence fit's: mean ± standard deviation (range {:.3} … {:.3})",
                rates.len(),
                lo,
                hi
            ),
            format!("{mean:.3} ± {sd:.3}"),
        ],
    ];
    let lambda = f(&l["lambda_max"]);
    let z = |v: f64| (v - lambda) / sd;
    let combined = f(&l["uncertainty"]).hypot(f(&s["uncertainty"]));
    let paragraph = format!(
        "<b>Four growth rates, one exponent.</b> The largest Lyapunov exponent λ₁ is a limit over infinite time; each \
         number below is a finite-time estimate of it, and they differ for that reason. Benettin's method follows the \
         tangent dynamics (λ₁ from one vector), renormalised every {} s, and averages its logarithmic growth: over {} s it gives {} 1/s, over \
         the default {} s {} 1/s — the same orbit, the shorter average being its first {} s; they differ by {:.3} 1/s, \
         {} their combined uncertainty {:.3}. The divergence fit (Figure {divergence_figure}, {} 1/s) is the slope of \
         ln distance of two real orbits over one window, t = {} … {} s, from the start until the distance passes {}: \
         one finite-time rate, including the first seconds in which the separation turns along the most unstable \
         direction, with no average over the orbit. The lab's butterfly mode fits another window by its own rule (RK4 \
         at {} s, the largest separation of 8 pendulums 10⁻⁹ rad apart, from 100 δ to 0.1; reproduced here: {} 1/s). \
         Over windows as long as the divergence fit's, the Benettin run's own finite-time rates scatter with standard \
         deviation {sd:.3} 1/s (from {lo:.3} to {hi:.3}): the divergence fit lies {:+.1} and the lab's rate {:+.1} of \
         those standard deviations from the long-run λ₁, {}. Quote λ₁ = {} 1/s, the long-run renormalised average \
         with its uncertainty; a windowed fit tells how fast two nearby states part over that stretch of the orbit, \
         not the exponent.",
        num(f(&l["renormalise"])),
        num(f(&l["t_end"])),
        pm(&l),
        num(f(&s["t_end"])),
        pm(&s),
        num(f(&s["t_end"])),
        (f(&l["lambda_max"]) - f(&s["lambda_max"])).abs(),
        if (f(&l["lambda_max"]) - f(&s["lambda_max"])).abs() <= combined { "within" } else { "more than" },
        combined,
        rate(&d, "growth_rate"),
        num(d0),
        num(d1),
        num(f(&d["saturation"])),
        num(f(&b["dt"])),
        rate(&b, "growth_rate"),
        z(f(&d["growth_rate"])),
        z(f(&b["growth_rate"])),
        if z(f(&d["growth_rate"])).abs() <= 2.0 && z(f(&b["growth_rate"])).abs() <= 2.0 {
            "within that scatter"
        } else {
            "not both within two of them"
        },
        pm(&l),
    );
    page.paragraph(&paragraph);
    page.table(&["estimate", "command", "method", "what is measured", "λ (1/s)"], &rows, "growth-rates");
    Ok(())
}

/// Regenerates the README gallery into `dir`.
fn gallery(dir: &Path, run_line: RunLine) -> Result<()> {
    let created = crate::output::CreatedDirs::create(dir, "--gallery")?;
    crate::output::probe(dir, "--gallery")?;
    let work = tempfile::tempdir()?;
    let _quiet = Quiet::on();
    let mut done: Vec<&str> = Vec::new();
    for entry in GALLERY {
        let sub = work.path().join(slug(entry.command));
        if !done.contains(&entry.command) {
            run_in(run_line, entry.command, &sub)?;
            done.push(entry.command);
        }
        let from = sub.join(entry.file);
        if !from.exists() {
            bail!("gallery: `pendula {}` wrote no {}", entry.command, entry.file);
        }
        let bytes = std::fs::read(&from)?;
        let file = crate::output::AtomicFile::create(&dir.join(entry.name), "--gallery")?;
        file.write_all(&bytes)?;
        file.commit()?;
    }
    created.keep();
    drop(_quiet);
    println!("gallery: {} pictures in {}", GALLERY.len(), dir.display());
    Ok(())
}
