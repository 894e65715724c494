//! `pendula plot`: draws a pendula CSV or .npy file — a trajectory's time series, its
//! phase portrait and its energy error, any table's columns against one of them, or a
//! sweep's or fractal's grid as a heat map — into a PNG or SVG. `simulate --plot` draws the
//! run it just made with the same functions.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use pendula::system::{self, SystemInfo};
use pendula_viz::{Bar, Bars, Figure, Heatmap, Kind, Legend, Scale, method_color, method_style, palette};

use crate::args::LargeArg;
use crate::output::AtomicFile;

#[derive(Debug, Clone, Args)]
pub struct PlotArgs {
    /// The file: a CSV with a header (a trajectory from `simulate`, or any of pendula's
    /// tables), or a .npy (a `simulate` trajectory, a `sweep` or a `fractal` grid).
    pub file: PathBuf,
    /// Column on the x axis of the time series [default: t, else the first column].
    #[arg(long, value_name = "NAME")]
    pub x: Option<String>,
    /// Columns to draw against it, comma-separated [default: a trajectory's positions (its
    /// angles), else every other column]; for a grid of several columns, the one to colour.
    #[arg(long, value_name = "NAME,NAME", value_delimiter = ',')]
    pub y: Vec<String>,
    /// A phase portrait: the first angle (wrapped to [-pi, pi)), or the first position,
    /// against its velocity.
    #[arg(long)]
    pub phase: bool,
    /// The energy error E - E0 against time.
    #[arg(long)]
    pub energy: bool,
    /// The system a .npy trajectory is of, for its column names and units (a .npy has no
    /// header) [default: the one whose state fits the column count, when only one does].
    #[arg(long, value_name = "NAME")]
    pub system: Option<String>,
    /// Output FILE.png or FILE.svg [default: the input's name with -plot.png].
    #[arg(long, value_name = "FILE.png")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub large: LargeArg,
}

/// Rows of named columns, with what is known of them: units, which are angles, which
/// position has which velocity, where time and energy are.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Title of the figures.
    pub title: String,
    names: Vec<String>,
    /// Units ("" when unknown or dimensionless).
    units: Vec<String>,
    angle: Vec<bool>,
    /// For a position's column, its velocity's column.
    velocity: Vec<Option<usize>>,
    energy: Option<usize>,
    /// Unit of energy ("" when dimensionless).
    energy_unit: String,
    /// The values, row by row.
    rows: Vec<f64>,
}

impl Trajectory {
    /// Columns named `names` (a CSV header); when they are `t`, a system's state and
    /// `energy` — `simulate`'s layout — they take that system's units and structure
    /// (`system`, when given, else the first catalogue entry whose state names fit).
    pub fn new(
        title: String,
        names: Vec<String>,
        rows: Vec<f64>,
        system: Option<&'static SystemInfo>,
    ) -> Self {
        let n = names.len();
        let fits = |info: &SystemInfo| {
            n == info.state.len() + 2
                && names[0] == "t"
                && names[n - 1] == "energy"
                && info.state.iter().zip(&names[1..n - 1]).all(|(q, name)| q.name == name)
        };
        let info = system.filter(|i| fits(i)).or_else(|| {
            pendula::model::CATALOGUE
                .iter()
                .map(pendula::model::Entry::info)
                .flat_map(members)
                .find(|i| fits(i))
        });
        let mut t = Trajectory {
            title,
            units: vec![String::new(); n],
            angle: vec![false; n],
            velocity: vec![None; n],
            energy: None,
            energy_unit: String::new(),
            names,
            rows,
        };
        if let Some(info) = info {
            // Dimensionless systems (the driven pendulum, whose velocity is in units of a
            // frequency) print no units for time and energy.
            let dimensionless = info.state.iter().any(|q| q.unit == "1");
            let half = info.state.len() / 2;
            t.units[0] = if dimensionless { String::new() } else { "s".into() };
            for (k, q) in info.state.iter().enumerate() {
                t.units[k + 1] = if q.unit == "1" { String::new() } else { q.unit.into() };
                t.angle[k + 1] = q.is_angle();
                if k < half {
                    t.velocity[k + 1] = Some(k + 1 + half);
                }
            }
            t.energy = Some(n - 1);
            t.energy_unit = if dimensionless { String::new() } else { "J".into() };
        } else {
            t.energy = t.names.iter().position(|c| c == "energy");
        }
        t
    }

    /// The rows `simulate` keeps for a run of `info`: t, the state, the energy.
    pub fn of_run(info: &'static SystemInfo, rows: Vec<f64>, title: String) -> Self {
        let mut names = vec!["t".to_owned()];
        names.extend(info.state.iter().map(|q| q.name.to_owned()));
        names.push("energy".into());
        Trajectory::new(title, names, rows, Some(info))
    }

    fn width(&self) -> usize {
        self.names.len()
    }

    fn column(&self, k: usize) -> impl Iterator<Item = f64> + '_ {
        self.rows.chunks_exact(self.width()).map(move |r| r[k])
    }

    /// The index of column `name`, or an error listing the columns.
    fn index(&self, name: &str) -> Result<usize> {
        self.names
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| anyhow!("unknown column `{name}`: the columns are {}", self.names.join(", ")))
    }

    fn label(&self, k: usize) -> String {
        with_unit(&self.names[k], &self.units[k])
    }

    /// The time series of `ys` against `x` (defaults: `t`, or the first column; the
    /// positions of a trajectory, or all other columns).
    pub fn series(&self, x: Option<&str>, ys: &[String]) -> Result<Figure> {
        let x = match x {
            Some(name) => self.index(name)?,
            None => self.names.iter().position(|c| c == "t").unwrap_or(0),
        };
        let ys: Vec<usize> = if ys.is_empty() {
            let positions: Vec<usize> = (0..self.width()).filter(|&k| self.velocity[k].is_some()).collect();
            if positions.is_empty() {
                (0..self.width()).filter(|&k| k != x && Some(k) != self.energy).collect()
            } else {
                positions
            }
        } else {
            ys.iter().map(|n| self.index(n)).collect::<Result<_>>()?
        };
        if ys.is_empty() {
            bail!("nothing to draw against {}: the only column is {}", self.names[x], self.names[x]);
        }
        let units: Vec<&str> = ys.iter().map(|&k| self.units[k].as_str()).collect();
        let names: Vec<&str> = ys.iter().map(|&k| self.names[k].as_str()).collect();
        let y_label = if units.iter().all(|u| *u == units[0]) {
            with_unit(&names.join(", "), units[0])
        } else {
            ys.iter().map(|&k| self.label(k)).collect::<Vec<_>>().join(", ")
        };
        let mut figure = Figure::new(self.title.clone(), self.label(x), y_label);
        for (i, &k) in ys.iter().enumerate() {
            let points = self.column(x).zip(self.column(k)).collect();
            figure = figure.with(self.names[k].clone(), palette(i), Kind::Line, points);
        }
        Ok(figure)
    }

    /// The phase portrait of the first angle (wrapped to [−π, π)) against its velocity, or
    /// of the first position when there is no angle.
    pub fn phase(&self) -> Result<Figure> {
        let positions: Vec<usize> = (0..self.width()).filter(|&k| self.velocity[k].is_some()).collect();
        let Some(&q) = positions.iter().find(|&&k| self.angle[k]).or(positions.first()) else {
            bail!(
                "--phase needs a trajectory (t, a system's state, energy: `simulate`'s columns); the columns are {}",
                self.names.join(", ")
            );
        };
        let v = self.velocity[q].expect("a position has a velocity");
        let wrap = self.angle[q];
        let points: Vec<(f64, f64)> = self
            .column(q)
            .zip(self.column(v))
            .map(|(a, b)| (if wrap { system::wrap_angle(a) } else { a }, b))
            .collect();
        // A wrapped angle jumps at ±π: dots, not a line across the figure.
        let jumps = wrap && self.column(q).any(|a| a.abs() > std::f64::consts::PI);
        let title = format!("{}: phase portrait", self.title);
        let x_label = if wrap {
            format!("{} wrapped to [-pi, pi) ({})", self.names[q], self.units[q])
        } else {
            self.label(q)
        };
        let kind = if jumps { Kind::Dots } else { Kind::Line };
        Ok(Figure::new(title, x_label, self.label(v)).with("", palette(1), kind, points))
    }

    /// The energy error E − E₀ against time.
    pub fn energy_error(&self) -> Result<Figure> {
        let Some(e) = self.energy else {
            bail!("--energy needs an `energy` column; the columns are {}", self.names.join(", "));
        };
        let t = self.names.iter().position(|c| c == "t").unwrap_or(0);
        let e0 = self.column(e).next().unwrap_or(f64::NAN);
        let points = self.column(t).zip(self.column(e)).map(|(t, e)| (t, e - e0)).collect();
        let title = format!("{}: energy error", self.title);
        Ok(Figure::new(title, self.label(t), with_unit("E - E0", &self.energy_unit))
            .with("", palette(0), Kind::Line, points)
            .legend(Legend::UpperLeft))
    }

    /// What `simulate --plot` draws: the time series, the phase portrait, the energy error.
    pub fn default_panels(&self) -> Result<Vec<Figure>> {
        Ok(vec![self.series(None, &[])?, self.phase()?, self.energy_error()?])
    }
}

/// `name (unit)`, or the name alone without a unit.
fn with_unit(name: &str, unit: &str) -> String {
    if unit.is_empty() { name.to_owned() } else { format!("{name} ({unit})") }
}

/// A catalogue entry and, for a family (the chain), each of its members.
fn members(info: &'static SystemInfo) -> Vec<&'static SystemInfo> {
    match info.variant {
        None => vec![info],
        Some(pick) => (1..=64).filter_map(|n| pick(&[("links".to_owned(), f64::from(n))]).ok()).collect(),
    }
}

/// Draws the panels one above the other, as PNG or SVG bytes by `path`'s extension.
pub fn draw(panels: &[Figure], path: &Path) -> Result<Vec<u8>> {
    let panels: Vec<Figure> = panels
        .iter()
        .map(|f| {
            let mut f = f.clone();
            if panels.len() > 1 {
                f.size = (960, 480);
            }
            f
        })
        .collect();
    let svg = path.extension().and_then(|e| e.to_str()) == Some("svg");
    if svg {
        let (w, mut h) = (panels.iter().map(|f| f.size.0).max().unwrap_or(0), 0);
        let mut body = String::new();
        for f in &panels {
            let inner = f.svg()?;
            // Each panel is a nested <svg>, shifted down by the ones above it.
            let inner = inner.trim_start_matches(|c| c != '<');
            let inner = inner.strip_prefix("<?xml").map_or(inner, |r| &r[r.find('>').map_or(0, |i| i + 1)..]);
            body.push_str(&format!("<g transform=\"translate(0,{h})\">{inner}</g>\n"));
            h += f.size.1;
        }
        return Ok(format!(
            "<svg width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" xmlns=\"http://www.w3.org/2000/svg\">\n{body}</svg>\n"
        )
        .into_bytes());
    }
    if panels.len() == 1 {
        return Ok(panels[0].png()?);
    }
    // Decode each panel's PNG and stack the pixels.
    let (w, mut h) = (panels[0].size.0, 0u32);
    let mut rgb = Vec::new();
    for f in &panels {
        let bytes = f.png()?;
        let mut reader =
            png::Decoder::new(std::io::Cursor::new(bytes)).read_info().context("decoding a panel")?;
        let mut buf = vec![0; reader.output_buffer_size().context("a panel's size")?];
        let frame = reader.next_frame(&mut buf).context("decoding a panel")?;
        if frame.width != w
            || frame.color_type != png::ColorType::Rgb
            || frame.bit_depth != png::BitDepth::Eight
        {
            bail!("the panels of a plot must be 8-bit RGB images of one width");
        }
        rgb.extend_from_slice(&buf[..frame.buffer_size()]);
        h += frame.height;
    }
    let mut out = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut out, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&rgb)?;
        writer.finish()?;
    }
    Ok(out)
}

/// A grid from `sweep` or `fractal`: axes (from the JSON description beside the file, when
/// there is one) and the values of each cell.
pub struct Grid {
    /// (name, lo, hi, n) per axis, fastest first.
    axes: Vec<(String, f64, f64, usize)>,
    /// Column names; one unnamed column for a fractal.
    columns: Vec<String>,
    /// The axes' labels, with units where the description gives them.
    axis_labels: Vec<String>,
    /// The columns' labels, with units where the description gives them.
    labels: Vec<String>,
    /// Cells, the first axis fastest, each with `columns.len()` values.
    values: Vec<f64>,
    /// A fractal's flip times (coloured by their logarithm, as `fractal` draws them).
    flip_times: bool,
}

/// The JSON description of a .npy: FILE.npy.json (what `sweep` and `fractal` write beside
/// their arrays), else FILE.json beside it (`--summary` of `sweep` or `fractal` under the
/// same name; for a fractal's FILE-converged.npy, the fractal's FILE.npy.json or FILE.json),
/// if it has the grid's axes.
fn description(path: &Path) -> Option<serde_json::Value> {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    let mut candidates = vec![PathBuf::from(format!("{}.json", path.display())), path.with_extension("json")];
    if let Some(fractal) = stem.strip_suffix("-converged") {
        candidates.push(path.with_file_name(format!("{fractal}.npy.json")));
        candidates.push(path.with_file_name(format!("{fractal}.json")));
    }
    candidates.iter().find_map(|p| {
        // Larger than a description: not one of ours.
        let text = crate::shards::read_capped(p, crate::limits::MAX_DESCRIPTION_BYTES).ok()?;
        let doc: serde_json::Value = serde_json::from_slice(&text).ok()?;
        doc.get("axes").and_then(|a| a.as_array()).is_some().then_some(doc)
    })
}

fn axes_of(doc: &serde_json::Value) -> Vec<(String, f64, f64, usize)> {
    doc["axes"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|a| {
            Some((
                a["name"].as_str()?.to_owned(),
                a["lo"].as_f64()?,
                a["hi"].as_f64()?,
                usize::try_from(a["n"].as_u64()?).ok()?,
            ))
        })
        .collect()
}

/// Reads a .npy of float64 or uint8 (the fractal's flags) as float64 with its shape, once
/// its header's claim is checked against the file and the limits.
fn read_npy(path: &Path, allow_large: bool) -> Result<(Vec<usize>, Vec<f64>)> {
    use ndarray_npy::ReadNpyExt;
    let claim = crate::limits::npy_claim(path)?;
    // The array as read, and the float64 copy drawn from.
    let values = claim.len() as f64;
    crate::limits::check(
        "plot",
        allow_large,
        &[crate::limits::Estimate::new(
            crate::limits::Cost::Memory,
            values * (claim.item as f64 + 8.0),
            format!("{} values of {:?}", crate::limits::round(values), claim.shape),
        )],
    )?;
    let open = || std::fs::File::open(path).with_context(|| format!("cannot read {}", path.display()));
    if let Ok(a) = ndarray::ArrayD::<f64>::read_npy(open()?) {
        return Ok((a.shape().to_vec(), a.iter().copied().collect()));
    }
    let a = ndarray::ArrayD::<u8>::read_npy(open()?).map_err(|e| {
        anyhow!("cannot read {} as a .npy of float64 or uint8 (pendula's arrays): {e}", path.display())
    })?;
    Ok((a.shape().to_vec(), a.iter().map(|&v| f64::from(v)).collect()))
}

/// Whether the first column increases from a non-negative start, as time does.
fn looks_like_time(shape: &[usize], values: &[f64]) -> bool {
    let (rows, cols) = (shape[0], shape[1]);
    let t: Vec<f64> = (0..rows).map(|r| values[r * cols]).collect();
    rows >= 2 && cols >= 3 && t[0] >= 0.0 && t.windows(2).all(|w| w[1] > w[0])
}

/// The trajectory's column names for a .npy of `cols` columns.
fn npy_columns(cols: usize, system_name: Option<&str>) -> Result<(Vec<String>, Option<&'static SystemInfo>)> {
    let named = |info: &'static SystemInfo| {
        let mut names = vec!["t".to_owned()];
        names.extend(info.state.iter().map(|q| q.name.to_owned()));
        names.push("energy".into());
        (names, Some(info))
    };
    if let Some(name) = system_name {
        let info = pendula::model::find(name)?;
        let fit = members(info).into_iter().find(|m| m.state.len() + 2 == cols);
        return match fit {
            Some(m) => Ok(named(m)),
            None => bail!(
                "invalid --system {name}: its trajectories have {} columns (t, state, energy), the file has {cols}",
                info.state.len() + 2
            ),
        };
    }
    // Every system with a state of this size; one layout of names and units is enough
    // (the double pendulum and the two-link chain share theirs).
    let fits: Vec<&'static SystemInfo> = pendula::model::CATALOGUE
        .iter()
        .map(pendula::model::Entry::info)
        .flat_map(members)
        .filter(|m| m.state.len() + 2 == cols)
        .collect();
    let same = |a: &SystemInfo, b: &SystemInfo| {
        a.state.iter().zip(b.state).all(|(p, q)| p.name == q.name && p.unit == q.unit)
    };
    match fits.first() {
        Some(first) if fits.iter().all(|f| same(first, f)) => Ok(named(first)),
        _ => Ok((Vec::new(), None)),
    }
}

fn heatmap(grid: &Grid, column: usize, title: String) -> Result<Heatmap> {
    let c = grid.columns.len();
    let values: Vec<f64> = grid.values.chunks_exact(c).map(|cell| cell[column]).collect();
    let (x, y) = (&grid.axes[0], &grid.axes[1]);
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let (lo, hi) = finite.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    // Positive values over two decades or more (flip times) are coloured by their logarithm.
    let log = grid.flip_times || (lo > 0.0 && hi / lo >= 100.0);
    Ok(Heatmap {
        title,
        x_label: grid.axis_labels[0].clone(),
        y_label: grid.axis_labels[1].clone(),
        bar_label: grid.labels[column].clone(),
        x: (x.1, x.2),
        y: (y.1, y.2),
        nx: x.3,
        ny: y.3,
        values,
        log,
        nan_color: pendula_viz::BLACK,
        categories: Vec::new(),
    })
}

/// What a file holds, read.
pub enum Contents {
    Table(Trajectory),
    Grid(Grid),
    Categories(Categories),
}

/// A table whose first column names things (a method, in `compare`'s, `stability`'s,
/// `convergence`'s and `work-precision`'s tables): its numeric columns are drawn per name —
/// one bar per name when each has one row, one line per name when names repeat — and its
/// other text columns are notes.
pub struct Categories {
    title: String,
    /// The first column's name (`method`).
    key: String,
    /// The first column, row by row.
    labels: Vec<String>,
    /// Numeric columns: name and values (NaN where empty).
    numbers: Vec<(String, Vec<f64>)>,
    /// Text columns after the first: name and values.
    texts: Vec<(String, Vec<String>)>,
}

/// The value column a bar chart of these columns draws by default: the headline of
/// pendula's tables when present, else the first numeric column.
const HEADLINES: [&str; 3] = ["max_rel_energy_error", "largest_stable_dt", "error"];

impl Categories {
    fn column(&self, name: &str) -> Result<usize> {
        self.numbers.iter().position(|(n, _)| n == name).ok_or_else(|| {
            let text = self.texts.iter().any(|(n, _)| n == name) || name == self.key;
            anyhow!(
                "{} column `{name}`: the numeric columns are {}",
                if text { "not a numeric" } else { "unknown" },
                self.numbers.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ")
            )
        })
    }

    fn unique(&self) -> bool {
        self.labels.iter().enumerate().all(|(i, l)| !self.labels[..i].contains(l))
    }

    /// A log scale for these values when all are positive and span two decades or more.
    fn scale(values: impl Iterator<Item = f64>) -> Scale {
        let (lo, hi) = values
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        if lo > 0.0 && hi / lo >= 100.0 { Scale::Log } else { Scale::Linear }
    }

    /// The style of a name: a method's own, else the i-th.
    fn style(name: &str, i: usize) -> pendula_viz::Style {
        if pendula::integrator::find(name).is_ok() {
            method_style(name)
        } else {
            pendula_viz::series_style(i)
        }
    }

    /// One bar per name of column `--y` (default: [`HEADLINES`]), each row's notes beside it
    /// (the text columns, where a value is missing or a note says why); a row whose note
    /// says it was refused is drawn as refused.
    fn bars(&self, ys: &[String]) -> Result<Figure> {
        let k = match ys {
            [] => HEADLINES.iter().find_map(|h| self.column(h).ok()).unwrap_or(0),
            [name] => self.column(name)?,
            _ => bail!(
                "{} has one row per {}: it is drawn as bars of one column; give one --y NAME ({})",
                self.title,
                self.key,
                self.numbers.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ")
            ),
        };
        let (name, values) = &self.numbers[k];
        let scale = Self::scale(values.iter().copied());
        let mut bars = Bars::new(format!("{}: {name} per {}", self.title, self.key), name.clone(), scale);
        for (r, label) in self.labels.iter().enumerate() {
            let v = Some(values[r]).filter(|v| v.is_finite() && (scale == Scale::Linear || *v > 0.0));
            let notes: Vec<&str> =
                self.texts.iter().map(|(_, t)| t[r].as_str()).filter(|t| !t.is_empty()).collect();
            let refused = notes.iter().any(|n| n.starts_with("refused"));
            let note = match (v, notes.is_empty()) {
                (Some(v), true) => pendula_viz::number(v),
                (Some(v), false) => format!("{}: {}", pendula_viz::number(v), notes.join("; ")),
                (None, false) => notes.join("; "),
                (None, true) => "no value".to_owned(),
            };
            let bar = Bar::new(label.clone(), v, method_color(label), Some(shorten(&note, 90)));
            bars.bars.push(Bar { refused, ..bar });
        }
        if bars.bars.iter().all(|b| b.value.is_none()) {
            bail!("nothing to draw: column `{name}` of {} has no value", self.title);
        }
        Ok(Figure::from(bars))
    }

    /// One line per name: `--y` (default `error` when there is one, else every other numeric
    /// column) against `--x` (default the first numeric column).
    fn lines(&self, x: Option<&str>, ys: &[String]) -> Result<Figure> {
        let given = x.map(|name| self.column(name)).transpose()?;
        let ys: Vec<usize> = if ys.is_empty() {
            match self.column("error") {
                Ok(e) if given != Some(e) => vec![e],
                // Every numeric column but x (the first, unless given).
                _ => (0..self.numbers.len())
                    .filter(|&k| Some(k) != given)
                    .skip(usize::from(given.is_none()))
                    .collect(),
            }
        } else {
            ys.iter().map(|n| self.column(n)).collect::<Result<_>>()?
        };
        let x = given.unwrap_or_else(|| (0..self.numbers.len()).find(|k| !ys.contains(k)).unwrap_or(0));
        if ys.is_empty() {
            bail!("nothing to draw against {}: it is the only numeric column", self.numbers[x].0);
        }
        let (xs, x_name) = (&self.numbers[x].1, &self.numbers[x].0);
        let y_names: Vec<&str> = ys.iter().map(|&k| self.numbers[k].0.as_str()).collect();
        let mut fig = Figure::new(self.title.clone(), x_name.clone(), y_names.join(", ")).scales(
            Self::scale(xs.iter().copied()),
            Self::scale(ys.iter().flat_map(|&k| self.numbers[k].1.iter().copied())),
        );
        let mut names: Vec<&str> = Vec::new();
        for l in &self.labels {
            if !names.contains(&l.as_str()) {
                names.push(l);
            }
        }
        for (i, name) in names.iter().enumerate() {
            for &k in &ys {
                let points: Vec<(f64, f64)> = (0..self.labels.len())
                    .filter(|&r| self.labels[r] == *name)
                    .map(|r| (xs[r], self.numbers[k].1[r]))
                    .collect();
                let label =
                    if ys.len() == 1 { (*name).to_owned() } else { format!("{name}: {}", self.numbers[k].0) };
                fig = fig.with_style(label, Self::style(name, i), Kind::LineMarkers, points);
            }
        }
        Ok(fig)
    }
}

/// `text`, or its first `keep` characters and an ellipsis (a bar's note must fit its row).
fn shorten(text: &str, keep: usize) -> String {
    match text.char_indices().nth(keep) {
        None => text.to_owned(),
        Some((i, _)) => format!("{}…", &text[..i]),
    }
}

/// A CSV table whose first column holds names, read into its numeric and text columns.
fn categories(
    title: String,
    names: &[String],
    records: &[csv::StringRecord],
    number: &dyn Fn(&str) -> bool,
) -> Result<Contents> {
    let field = |r: &csv::StringRecord, c: usize| r.get(c).unwrap_or("").trim().to_owned();
    let (mut numbers, mut texts) = (Vec::new(), Vec::new());
    for (c, name) in names.iter().enumerate().skip(1) {
        let column: Vec<String> = records.iter().map(|r| field(r, c)).collect();
        if column.iter().all(|f| number(f)) {
            numbers.push((name.clone(), column.iter().map(|f| f.parse().unwrap_or(f64::NAN)).collect()));
        } else {
            texts.push((name.clone(), column));
        }
    }
    if numbers.is_empty() {
        bail!(
            "{title}: no numeric column to draw (the columns are {}, all text)",
            names.iter().map(|n| crate::parse::clip(n)).collect::<Vec<_>>().join(", ")
        );
    }
    let labels = records.iter().map(|r| field(r, 0)).collect();
    Ok(Contents::Categories(Categories { title, key: names[0].clone(), labels, numbers, texts }))
}

/// Reads `args.file` (the fuzz harness, `tests/fuzz/`, calls it on generated files).
pub fn read(args: &PlotArgs) -> Result<Contents> {
    let path = &args.file;
    let title =
        path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    let system = args.system.as_deref().map(pendula::model::find).transpose()?;
    match path.extension().and_then(|e| e.to_str()) {
        Some("csv") => {
            let mut reader =
                csv::Reader::from_path(path).with_context(|| format!("cannot read {}", path.display()))?;
            let names: Vec<String> = reader
                .headers()
                .with_context(|| format!("cannot read the header of {}", path.display()))?
                .iter()
                .map(|s| s.trim().to_owned())
                .collect();
            let records: Vec<csv::StringRecord> = reader
                .records()
                .enumerate()
                .map(|(r, record)| {
                    record.with_context(|| format!("cannot read {} row {}", path.display(), r + 1))
                })
                .collect::<Result<_>>()?;
            let number = |f: &str| f.trim().is_empty() || f.trim().parse::<f64>().is_ok();
            // A first column of names (pendula's tables put the method first): drawn per name.
            if !records.is_empty() && records.iter().any(|r| !r.get(0).is_some_and(number)) {
                return categories(title, &names, &records, &number);
            }
            let mut rows = Vec::new();
            for (r, record) in records.iter().enumerate() {
                for (c, field) in record.iter().enumerate() {
                    let v = match field.trim() {
                        "" => f64::NAN,
                        f => f.parse().map_err(|_| {
                            anyhow!(
                                "{} row {} column {}: `{}` is not a number (plot draws numeric columns)",
                                path.display(),
                                r + 1,
                                crate::parse::clip(names.get(c).map_or("?", String::as_str)),
                                crate::parse::clip(f)
                            )
                        })?,
                    };
                    rows.push(v);
                }
            }
            if rows.is_empty() {
                bail!("{} has no rows to draw", path.display());
            }
            Ok(Contents::Table(Trajectory::new(title, names, rows, system)))
        }
        Some("npy") => {
            let (shape, values) = read_npy(path, args.large.allow_large)?;
            if values.is_empty() {
                bail!("{} has no values to draw", path.display());
            }
            let doc = description(path);
            let axes = doc.as_ref().map(axes_of).unwrap_or_default();
            let named = doc
                .as_ref()
                .and_then(|d| d["columns"].as_array())
                .map(|c| c.iter().filter_map(|v| v.as_str().map(str::to_owned)).collect::<Vec<_>>());
            // A fractal's summary has its t-max; its flags file ends in -converged.
            let fractal = doc.as_ref().is_some_and(|d| d.get("t_max").is_some());
            let flags = title.contains("-converged");
            // The description's system (a summary of a fractal names none: the double
            // pendulum), for the units and symbols of what it does not spell out.
            let system = doc.as_ref().and_then(|d| d["system"].as_str()).unwrap_or("double");
            let info = pendula::model::find(system).ok();
            let axis_label = |i: usize, name: &str| {
                let unit = doc.as_ref().and_then(|d| d["axis_units"][i].as_str()).map(str::to_owned);
                match unit.or_else(|| Some(info?.quantity(name).ok()?.unit.to_owned())) {
                    Some(u) => pendula_viz::system_axis_label(system, name, &u),
                    None => pendula_viz::pretty(name),
                }
            };
            let column_label = |k: usize, name: &str| {
                let doc = doc.as_ref();
                let unit = doc.and_then(|d| d["units"][k].as_str()).map(str::to_owned).or_else(|| {
                    info.map(|i| crate::commands::sweep::quantity_unit(i, name).to_owned())
                        .filter(|u| !u.is_empty())
                });
                match (doc.and_then(|d| d["labels"][k].as_str()), unit) {
                    (Some(label), Some(u)) if pendula_viz::unit(&u).is_empty() => {
                        format!("{label} (dimensionless)")
                    }
                    (Some(label), Some(u)) => format!("{label} ({})", pendula_viz::unit(&u)),
                    (Some(label), None) => label.to_owned(),
                    (None, Some(u)) => pendula_viz::axis_label(name, &u),
                    (None, None) => name.to_owned(),
                }
            };
            let grid_of = |axes: Vec<(String, f64, f64, usize)>, columns: usize| {
                let one = columns == 1;
                let (columns, labels) = match &named {
                    _ if columns == 1 && flags => {
                        (vec!["converged".into()], vec!["converged (1) or not (0)".into()])
                    }
                    Some(n) if n.len() == columns => {
                        (n.clone(), n.iter().enumerate().map(|(k, c)| column_label(k, c)).collect())
                    }
                    _ if columns == 1 && fractal => {
                        (vec!["flip_time".into()], vec!["time to first flip (s)".into()])
                    }
                    _ if columns == 1 => (vec!["value".into()], vec!["value".into()]),
                    _ => {
                        let names: Vec<String> = (0..columns).map(|k| format!("c{k}")).collect();
                        (names.clone(), names)
                    }
                };
                Grid {
                    axis_labels: axes.iter().enumerate().map(|(i, a)| axis_label(i, &a.0)).collect(),
                    axes,
                    columns,
                    labels,
                    values: values.clone(),
                    flip_times: fractal && !flags && one,
                }
            };
            let index_axes = |dims: &[usize]| -> Vec<(String, f64, f64, usize)> {
                ["column index", "row index"]
                    .iter()
                    .zip(dims)
                    .map(|(n, &d)| ((*n).to_owned(), 0.0, d as f64, d))
                    .collect()
            };
            let fits = |axes: &[(String, f64, f64, usize)], dims: &[usize]| {
                axes.len() == dims.len() && axes.iter().zip(dims).all(|(a, &d)| a.3 == d)
            };
            match shape.as_slice() {
                [n] => {
                    let names = vec!["index".to_owned(), "value".to_owned()];
                    let rows = values.iter().enumerate().flat_map(|(i, v)| [i as f64, *v]).collect();
                    let _ = n;
                    Ok(Contents::Table(Trajectory::new(title, names, rows, None)))
                }
                // A fractal (N₂, N₁) with its axes, or a one-axis sweep (N₁, columns).
                [n2, n1] if fits(&axes, &[*n1, *n2]) => Ok(Contents::Grid(grid_of(axes, 1))),
                [n1, c] if fits(&axes, &[*n1]) => {
                    let g = grid_of(axes, *c);
                    let mut names = vec![g.axes[0].0.clone()];
                    names.extend(g.columns.iter().cloned());
                    // The axis's and columns' units, from the description.
                    let units: Vec<String> = std::iter::once(&g.axis_labels[0])
                        .chain(&g.labels)
                        .map(|l| l.rsplit_once(" (").map_or("", |(_, u)| u.trim_end_matches(')')).to_owned())
                        .collect();
                    let (a, step) = (g.axes[0].1, (g.axes[0].2 - g.axes[0].1) / *n1 as f64);
                    let rows = values
                        .chunks_exact(*c)
                        .enumerate()
                        .flat_map(|(i, row)| {
                            std::iter::once(a + (i as f64 + 0.5) * step).chain(row.iter().copied())
                        })
                        .collect();
                    let mut t = Trajectory::new(title, names, rows, None);
                    t.units = units;
                    Ok(Contents::Table(t))
                }
                [_, c] if looks_like_time(&shape, &values) => {
                    let (names, info) = npy_columns(*c, args.system.as_deref())?;
                    if info.is_some() {
                        return Ok(Contents::Table(Trajectory::new(title, names, values, info)));
                    }
                    // Several systems fit (or none): positions y1…, then velocities.
                    let names = std::iter::once("t".to_owned())
                        .chain((1..c - 1).map(|k| format!("y{k}")))
                        .chain(std::iter::once("energy".to_owned()))
                        .collect();
                    if !crate::parse::quiet() {
                        eprintln!(
                            "note: {} has {c} columns, taken as t, y1 … y{}, energy; give --system NAME for names and units",
                            path.display(),
                            c - 2
                        );
                    }
                    let mut t = Trajectory::new(title, names, values, None);
                    t.energy = Some(c - 1);
                    let half = (c - 2) / 2;
                    for k in 0..half {
                        t.velocity[k + 1] = Some(k + 1 + half);
                    }
                    Ok(Contents::Table(t))
                }
                [n2, n1] => Ok(Contents::Grid(grid_of(index_axes(&[*n1, *n2]), 1))),
                [n2, n1, c] => {
                    let axes = if fits(&axes, &[*n1, *n2]) { axes } else { index_axes(&[*n1, *n2]) };
                    Ok(Contents::Grid(grid_of(axes, *c)))
                }
                other => bail!(
                    "cannot draw {}: an array of shape {other:?} (pendula writes 1, 2 or 3 dimensions)",
                    path.display()
                ),
            }
        }
        _ => bail!("invalid file `{}`: plot reads pendula's .csv and .npy files", path.display()),
    }
}

pub fn run(args: &PlotArgs) -> Result<()> {
    let out = args.out.clone().unwrap_or_else(|| {
        let stem = args.file.file_stem().map_or_else(|| "plot".into(), |s| s.to_string_lossy().into_owned());
        args.file.with_file_name(format!("{stem}-plot.png"))
    });
    crate::parse::check_image_path(&out, "--out")?;
    if !args.file.exists() {
        bail!("cannot read {}: no such file", args.file.display());
    }
    // The file is read whole: its size is checked first, and a FIFO or device has none to
    // check (/dev/zero would be read until memory runs out).
    let meta =
        std::fs::metadata(&args.file).with_context(|| format!("cannot read {}", args.file.display()))?;
    if !meta.is_file() {
        bail!(
            "cannot read {}: it is not a regular file (plot reads a file whole, and checks its size first)",
            args.file.display()
        );
    }
    let size = meta.len() as f64;
    crate::limits::check(
        "plot",
        args.large.allow_large,
        &[crate::limits::Estimate::new(crate::limits::Cost::Input, size, args.file.display().to_string())],
    )?;
    // The picture may not replace what it is drawn from.
    crate::output::claim_input(&args.file, "input file")?;
    let file = AtomicFile::create(&out, "--out")?;
    let bytes = match picture(args, &out, read(args)?)? {
        Picture::Panels(panels) => draw(&panels, &out)?,
        Picture::Map(map) if out.extension().and_then(|e| e.to_str()) == Some("svg") => {
            map.svg()?.into_bytes()
        }
        Picture::Map(map) => map.png()?,
    };
    file.write_all(&bytes)?;
    file.commit()?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// What `plot` draws: a table's panels, or a grid's heat map.
pub enum Picture {
    Panels(Vec<Figure>),
    Map(Heatmap),
}

/// The picture of `contents` that the flags ask for, checked and laid out, not yet drawn
/// into `out`.
pub fn picture(args: &PlotArgs, _out: &Path, contents: Contents) -> Result<Picture> {
    Ok(match contents {
        Contents::Table(t) => {
            let mut panels = Vec::new();
            if args.x.is_some() || !args.y.is_empty() || !(args.phase || args.energy) {
                panels.push(t.series(args.x.as_deref(), &args.y)?);
            }
            if args.phase {
                panels.push(t.phase()?);
            }
            if args.energy {
                panels.push(t.energy_error()?);
            }
            Picture::Panels(panels)
        }
        Contents::Categories(c) => {
            if args.phase || args.energy {
                bail!(
                    "{} is a table per {} ({}): --phase and --energy apply to trajectories",
                    args.file.display(),
                    c.key,
                    c.labels.len()
                );
            }
            if c.unique() {
                if args.x.is_some() {
                    bail!(
                        "{} has one row per {}: it is drawn as bars of one column (--y NAME); --x applies to tables whose {} repeats",
                        args.file.display(),
                        c.key,
                        c.key
                    );
                }
                Picture::Panels(vec![c.bars(&args.y)?])
            } else {
                Picture::Panels(vec![c.lines(args.x.as_deref(), &args.y)?])
            }
        }
        Contents::Grid(g) => {
            if args.phase || args.energy || args.x.is_some() {
                bail!(
                    "{} is a grid ({} x {} cells): it is drawn as a heat map; --phase, --energy and --x apply to trajectories and tables",
                    args.file.display(),
                    g.axes[0].3,
                    g.axes[1].3
                );
            }
            let column = match args.y.as_slice() {
                [] => 0,
                [name] => g.columns.iter().position(|c| c == name).ok_or_else(|| {
                    anyhow!("unknown column `{name}`: the columns are {}", g.columns.join(", "))
                })?,
                _ => bail!("a heat map shows one column: give one --y NAME ({})", g.columns.join(", ")),
            };
            let title = args.file.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            Picture::Map(heatmap(&g, column, title)?)
        }
    })
}
