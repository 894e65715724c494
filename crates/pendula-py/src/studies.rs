//! The library's study registry ([`pendula::study::STUDIES`]) for Python: `studies()`
//! describes every study and its parameters (from which `pendula` makes one function per
//! study), `run_study` runs one with the GIL released and returns its report as dicts and
//! numpy arrays. A new study in the library needs nothing here.

use numpy::IntoPyArray;
use pendula::study::{self, Budget, Cells, Input, Inputs, Kind, Style, Unit};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{interruptible, to_py};

/// Every study: `name`, `about`, and `params`, each a dict with `name`, `help`, `kind`
/// ([`pendula::study::Param::kind_name`]), `default` (the value, or the default system's
/// name), `default_text` (as documentation shows it) and `unit` (`time` for the system's
/// time unit).
#[pyfunction]
fn studies(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for s in study::STUDIES {
        let params = PyList::empty(py);
        for p in s.params {
            let d = PyDict::new(py);
            d.set_item("name", p.name)?;
            d.set_item("help", p.help)?;
            d.set_item("default_text", p.default_text())?;
            d.set_item("kind", p.kind_name())?;
            match p.kind {
                Kind::System { default, .. } | Kind::Method { default } => d.set_item("default", default)?,
                Kind::Methods | Kind::Variable { .. } | Kind::Preset | Kind::Threads => {
                    d.set_item("default", py.None())?
                }
                Kind::Section { default } => d.set_item("default", default)?,
                // The default axis is one system's: the study chooses it.
                Kind::Axis { .. } => d.set_item("default", py.None())?,
                Kind::Flag => d.set_item("default", false)?,
                Kind::Real { .. } | Kind::Optional { .. } | Kind::Reals { .. } => {
                    match p.kind {
                        Kind::Real { default, .. } => d.set_item("default", default)?,
                        _ => d.set_item("default", py.None())?,
                    }
                    let unit = p.real_unit().unwrap_or(Unit::None);
                    d.set_item(
                        "unit",
                        match unit {
                            Unit::None => "",
                            Unit::Time => "time",
                            Unit::Fixed(u) => u,
                        },
                    )?;
                }
                Kind::Count { default, .. } => d.set_item("default", default)?,
            }
            params.append(d)?;
        }
        let d = PyDict::new(py);
        d.set_item("name", s.name)?;
        d.set_item("about", s.about)?;
        d.set_item("params", params)?;
        d.set_item("files", s.files.to_vec())?;
        list.append(d)?;
    }
    Ok(list)
}

/// Runs the study `name` with `values` ((parameter, value) pairs: a str for a system or a
/// method, a number otherwise) and `set` ((system quantity, value) pairs). Returns `study`,
/// `inputs`, `summary` (sentences), `numbers` and `units` (by key), `tables` (name →
/// column → array), `columns_units` (name → column → unit), `shown` (the names of the tables
/// short enough to print whole) and `plots`.
#[pyfunction]
#[pyo3(signature = (name, values, set, progress=None))]
fn run_study<'py>(
    py: Python<'py>,
    name: &str,
    values: Vec<(String, Bound<'py, PyAny>)>,
    set: Vec<(String, f64)>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let study = study::find(name).map_err(|e| to_py(py, &e))?;
    let mut inputs = Inputs { values: Vec::new(), set };
    for (key, v) in values {
        let input = if let Ok(text) = v.extract::<String>() {
            Input::Name(text)
        } else if v.is_instance_of::<pyo3::types::PyBool>() {
            // A switch's state (True is 1 to Python's float(): the study refuses a bool
            // where a number belongs).
            Input::Flag(v.is_truthy()?)
        } else if let Ok(x) = v.extract::<f64>() {
            Input::Number(x)
        } else if let Ok(list) = v.extract::<Vec<f64>>() {
            // A sequence or an array of numbers (the steps of a convergence study).
            Input::Numbers(list)
        } else {
            return Err(crate::raise(
                py,
                "InvalidValueError",
                format!("invalid value {} for `{key}`: a number or a name", v.repr()?),
            ));
        };
        inputs.values.push((key, input));
    }
    let report = interruptible(py, false, progress.as_ref(), |_| (study.run)(&inputs, &Budget::UNLIMITED))?
        .map_err(|e| to_py(py, &e))?;
    let out = PyDict::new(py);
    out.set_item("study", report.study)?;
    let given = PyDict::new(py);
    for (k, v) in &report.inputs {
        match v {
            Input::Number(x) => given.set_item(k, x)?,
            Input::Name(s) => given.set_item(k, s)?,
            Input::Flag(b) => given.set_item(k, b)?,
            Input::Numbers(v) => given.set_item(k, v.clone())?,
        }
    }
    out.set_item("inputs", given)?;
    out.set_item("summary", report.summary.clone())?;
    let (numbers, units) = (PyDict::new(py), PyDict::new(py));
    for n in &report.numbers {
        numbers.set_item(n.key, n.value)?;
        units.set_item(n.key, n.unit)?;
    }
    out.set_item("numbers", numbers)?;
    let texts = PyDict::new(py);
    for (k, v) in &report.texts {
        texts.set_item(*k, v)?;
    }
    out.set_item("texts", texts)?;
    out.set_item("units", units)?;
    let (tables, columns_units, decimals) = (PyDict::new(py), PyDict::new(py), PyDict::new(py));
    let shown: Vec<&str> = report.tables.iter().filter(|t| t.shown).map(|t| t.name).collect();
    out.set_item("shown", shown)?;
    for t in report.tables {
        let (columns, units) = (PyDict::new(py), PyDict::new(py));
        for c in t.columns {
            units.set_item(c.name, c.unit)?;
            if let Some(d) = c.decimals {
                decimals.set_item((t.name, c.name), d)?;
            }
            match c.values {
                // An index or a count as integers.
                // A missing one (NaN) makes the column floats.
                Cells::Numbers(v) if c.whole && v.iter().all(|x| x.is_finite()) => {
                    columns
                        .set_item(c.name, v.iter().map(|x| *x as i64).collect::<Vec<_>>().into_pyarray(py))?;
                }
                Cells::Numbers(v) => columns.set_item(c.name, v.into_pyarray(py))?,
                Cells::Text(t) => columns.set_item(c.name, t)?,
            }
        }
        tables.set_item(t.name, columns)?;
        columns_units.set_item(t.name, units)?;
    }
    out.set_item("tables", tables)?;
    out.set_item("columns_units", columns_units)?;
    // (table, column) → the decimals a printed table shows.
    out.set_item("decimals", decimals)?;
    let plots = PyList::empty(py);
    for p in report.plots {
        let d = PyDict::new(py);
        d.set_item("name", p.name)?;
        d.set_item("title", p.title)?;
        for (key, axis) in [("x", p.x), ("y", p.y)] {
            let a = PyDict::new(py);
            a.set_item("label", axis.label)?;
            a.set_item("unit", axis.unit)?;
            a.set_item("log", axis.log)?;
            d.set_item(key, a)?;
        }
        let series = PyList::empty(py);
        for line in p.series {
            let l = PyDict::new(py);
            l.set_item("label", line.label)?;
            l.set_item(
                "style",
                match line.style {
                    Style::Solid => "solid",
                    Style::Dashed => "dashed",
                    Style::Points => "points",
                    Style::LineMarkers => "line-markers",
                    Style::Dots => "dots",
                    Style::Guide => "guide",
                },
            )?;
            let (x, y): (Vec<f64>, Vec<f64>) = line.points.iter().map(|[x, y]| (*x, *y)).unzip();
            l.set_item("x", x.into_pyarray(py))?;
            l.set_item("y", y.into_pyarray(py))?;
            series.append(l)?;
        }
        d.set_item("series", series)?;
        let bars = PyList::empty(py);
        for b in p.bars {
            let e = PyDict::new(py);
            e.set_item("label", b.label)?;
            e.set_item("value", b.value)?;
            e.set_item("note", b.note)?;
            e.set_item("refused", b.refused)?;
            bars.append(e)?;
        }
        d.set_item("bars", bars)?;
        d.set_item("limits", p.limits)?;
        d.set_item("legend", p.legend)?;
        plots.append(d)?;
    }
    out.set_item("plots", plots)?;
    Ok(out)
}

/// Adds the functions to `_core`.
/// Every study's defaults ([`pendula::study::defaults::ALL`]) by study name: `system`,
/// `method`, `dt`, `t_end` (None where the study chooses per method) and its own, by
/// keyword; Python's signatures take theirs from here.
#[pyfunction]
fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    use pendula::study::defaults::{ALL, Value};
    let out = PyDict::new(py);
    for d in ALL {
        let one = PyDict::new(py);
        one.set_item("system", d.system)?;
        one.set_item("method", d.method)?;
        one.set_item("dt", d.dt)?;
        one.set_item("t_end", d.t_end)?;
        for v in d.values {
            match v.value {
                Value::Number(x) => one.set_item(v.name, x)?,
                Value::Count(n) => one.set_item(v.name, n)?,
                Value::Text(t) => one.set_item(v.name, t)?,
                Value::PerSystem(of, otherwise) => {
                    let per = PyDict::new(py);
                    for (system, x) in of {
                        per.set_item(*system, *x)?;
                    }
                    one.set_item(v.name, (per, otherwise))?;
                }
            }
        }
        out.set_item(d.study, one)?;
    }
    Ok(out)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(defaults, m)?)?;
    m.add_function(wrap_pyfunction!(studies, m)?)?;
    m.add_function(wrap_pyfunction!(run_study, m)?)
}
