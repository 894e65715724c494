//! `pendula.sweep`'s computation: the library's sweep ([`pendula::sweep`]), the
//! one `pendula sweep` runs, so the two give the same array bit for bit (and the same shard
//! fingerprints, so their shards merge together). The arguments arrive parsed by
//! `python/pendula/sweep.py` (numbers, names); here the library checks them
//! ([`Record::parse_list`], [`SweepSpec::validate`]) and its refusals are phrased with
//! Python's argument names. The run releases the GIL and stops at a Ctrl-C.

use std::time::Instant;

use numpy::IntoPyArray;
use pendula::error::{did_you_mean, suggestions};
use pendula::sweep::{Axis, CellError, Record, RecordError, SweepSpec};
use pendula::{End, Error, RunSpec, integrator};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use std::sync::atomic::{AtomicU64, Ordering};

use crate::{interruptible_counted, raise, to_py};

/// Adds the sweep's function to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(sweep, m)?)
}

/// The library error `e` with the Python argument names: the library's step `h` is `dt`.
fn renamed(py: Python<'_>, e: Error) -> PyErr {
    match e {
        Error::InvalidValue { name, value, allowed } if name == "h" => {
            to_py(py, &Error::InvalidValue { name: "dt".into(), value, allowed })
        }
        other => to_py(py, &other),
    }
}

/// A failed cell's error, its message saying which cell ("cell 17 of the sweep: …"), as
/// the CLI says it; the class is the library error's.
fn cell_error(py: Python<'_>, e: CellError) -> PyErr {
    let err = to_py(py, &e.error);
    if let Some(c) = e.cell {
        // The message is the exception's only argument: replaced, the class kept.
        let _ = err.value(py).setattr("args", (format!("cell {c} of the sweep: {}", e.error),));
    }
    err
}

/// A sweep of `system` over `axes` ((name, lo, hi, n), the first fastest) with `set` the
/// same for every cell, `steps` steps of `dt` (or to `t_end`, s) with `method`; `until`
/// `"flip"` stops each cell at its first flip; `records` the recorded quantities' names;
/// shard (K, N) of the cells, or the cells [start, end) given as `cells` (a block of
/// `pendula.distributed.sweep_array`). Returns the rows (count, columns) and the run's
/// description (`description`: the shard description's JSON, without `data`).
#[pyfunction]
#[pyo3(signature = (system, set, axes, method, dt, steps, t_end, until, records, shard, threads=None, progress=None, cells=None))]
#[allow(clippy::too_many_arguments)] // the sweep's description, as Python passes it
fn sweep<'py>(
    py: Python<'py>,
    system: &str,
    set: Vec<(String, f64)>,
    axes: Vec<(String, f64, f64, usize)>,
    method: &str,
    dt: f64,
    steps: Option<u64>,
    t_end: Option<f64>,
    until: Option<String>,
    records: Vec<String>,
    shard: (usize, usize),
    threads: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
    cells: Option<(usize, usize)>,
) -> PyResult<Bound<'py, PyDict>> {
    let family = pendula::model::find(system).map_err(|e| to_py(py, &e))?;
    let info = family.values(&set).map_err(|e| to_py(py, &e))?.info();
    let method = integrator::find(method).map_err(|e| to_py(py, &e))?;
    let invalid = |message: String| raise(py, "InvalidValueError", message);
    let end = match (steps, t_end) {
        (Some(n), None) => End::Steps(n),
        (None, Some(t)) => End::Time(t),
        _ => return Err(invalid("give steps or t_end (s), not both".into())),
    };
    let schedule = RunSpec { t0: 0.0, h: dt, end }.schedule().map_err(|e| renamed(py, e))?;
    if schedule.last_h != dt {
        return Err(invalid(format!(
            "invalid value {} for `t_end`: it must be a whole number of steps of dt {dt}",
            schedule.t_end
        )));
    }
    let until_flip = match until.as_deref() {
        None => false,
        Some("flip") if pendula::sweep::has_angle(info) => true,
        Some("flip") => {
            return Err(invalid(format!("invalid until 'flip': the `{}` system has no angle", info.name)));
        }
        Some(other) => {
            return Err(invalid(format!(
                "invalid value {other:?} for `until`{}: None or 'flip'",
                did_you_mean(&suggestions(other, ["flip"]))
            )));
        }
    };
    let parsed = Record::parse_list(records.iter().map(String::as_str), info).map_err(|e| match e {
        RecordError::Unknown { name, suggestions } => invalid(format!(
            "invalid record {name:?}{}: expected {}",
            did_you_mean(&suggestions),
            pendula::sweep::record_names()
        )),
        RecordError::NoAngle => {
            invalid(format!("invalid record 'flip-time': the `{}` system has no angle", info.name))
        }
        RecordError::Twice(name) => invalid(format!("invalid record: {name:?} is given twice")),
    })?;
    let axes = axes.into_iter().map(|(name, lo, hi, n)| Axis { name, lo, hi, n }).collect();
    let spec = SweepSpec {
        system: family,
        set,
        axes,
        method,
        h: dt,
        steps: schedule.steps,
        until_flip,
        records: parsed,
        shard,
    };
    let sweep = spec.validate().map_err(|e| renamed(py, e))?;
    let threads = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(invalid("invalid value 0 for `threads`: at least 1".into()));
    }
    let (start, end) = match cells {
        None => sweep.range(),
        Some((a, b)) if a < b && b <= sweep.cells() => (a, b),
        Some((a, b)) => {
            return Err(invalid(format!(
                "invalid cells ({a}, {b}): a range start < end <= {} of the sweep's cells",
                sweep.cells()
            )));
        }
    };
    let cols = sweep.columns().len();
    let mut data: Vec<f64> = Vec::new();
    data.try_reserve_exact((end - start) * cols).map_err(|_| {
        pyo3::exceptions::PyMemoryError::new_err(format!(
            "cannot allocate {} bytes for the sweep's array",
            (end - start) * cols * 8
        ))
    })?;
    data.resize((end - start) * cols, 0.0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| raise(py, "PendulaError", format!("cannot start {threads} threads: {e}")))?;
    let begin = Instant::now();
    let done = AtomicU64::new(0);
    let result = interruptible_counted(py, false, progress.as_ref(), &done, |flag| {
        pool.install(|| {
            sweep.compute(start, &mut data, Some(flag), &|| {
                done.fetch_add(1, Ordering::Relaxed);
            })
        })
    })?;
    // An interrupted run raised KeyboardInterrupt above; what is left is the run's own.
    result.map_err(|e| cell_error(py, e))?;
    let wall_s = begin.elapsed().as_secs_f64();

    let s = sweep.spec();
    let out = PyDict::new(py);
    let rows = numpy::ndarray::Array2::from_shape_vec((end - start, cols), data).expect("whole rows");
    out.set_item("data", rows.into_pyarray(py))?;
    out.set_item("pendula", env!("CARGO_PKG_VERSION"))?;
    out.set_item("system", sweep.info().name)?;
    out.set_item("method", s.method.name)?;
    out.set_item("dt", s.h)?;
    out.set_item("steps", s.steps)?;
    let axes: Vec<(&str, f64, f64, usize)> =
        s.axes.iter().map(|a| (a.name.as_str(), a.lo, a.hi, a.n)).collect();
    out.set_item("axes", axes)?;
    out.set_item("columns", sweep.columns().to_vec())?;
    out.set_item("shape", sweep.shape())?;
    out.set_item("shard", s.shard.0)?;
    out.set_item("shards", s.shard.1)?;
    out.set_item("offset", start)?;
    out.set_item("count", end - start)?;
    out.set_item("fingerprint", sweep.fingerprint())?;
    out.set_item("kernel", sweep.kernel())?;
    out.set_item("fma", pendula::ensemble::has_fma())?;
    out.set_item("threads", threads)?;
    out.set_item("wall_s", wall_s)?;
    let run = pendula_io::shard::RunFacts {
        cells: (start, end),
        data: None,
        fma: pendula::ensemble::has_fma(),
        threads,
        wall_s,
    };
    out.set_item("description", pendula_io::shard::sweep_description(&sweep, &run).to_string())?;
    Ok(out)
}
