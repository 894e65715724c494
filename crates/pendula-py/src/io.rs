//! The format crate ([`pendula_io`]) for the pure-Python package: the value syntax
//! (`120deg`, `pi`, `NAME=LO:HI:N`) read by the one parser every front end uses, `.npy`
//! arrays written by the one writer, and shards read and checked for a merge by the one
//! reader. Its refusals are `InvalidValueError`s, or the library's
//! own class for an unknown name.

use numpy::{IntoPyArray, PyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::{raise, to_py};

/// Adds the format functions to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(parse_value, m)?)?;
    m.add_function(wrap_pyfunction!(parse_axis, m)?)?;
    m.add_function(wrap_pyfunction!(save_npy, m)?)?;
    m.add_function(wrap_pyfunction!(npy_written, m)?)?;
    m.add_function(wrap_pyfunction!(load_shard, m)?)?;
    m.add_function(wrap_pyfunction!(check_shards, m)?)?;
    m.add("SHARD_FORMAT", pendula_io::shard::SHARD_FORMAT)
}

/// The Python exception for the format crate's error.
pub(crate) fn io_error(py: Python<'_>, e: pendula_io::Error) -> PyErr {
    match e {
        pendula_io::Error::Library(e) => to_py(py, &e),
        other => raise(py, "InvalidValueError", other.to_string()),
    }
}

/// The value `text` given for `name` (a quantity of `system` when a system is named: an angle
/// takes `deg` and `pi` suffixes, a mass or a length is checked against its default), in SI
/// units and radians.
#[pyfunction]
#[pyo3(signature = (system, name, text))]
fn parse_value(py: Python<'_>, system: Option<&str>, name: &str, text: &str) -> PyResult<f64> {
    let quantity = match system {
        Some(system) => {
            let family = pendula::model::find(system).map_err(|e| to_py(py, &e))?;
            Some(family.quantity(name).map_err(|e| to_py(py, &e))?)
        }
        None => None,
    };
    pendula_io::value::parse_value(name, text, quantity).map_err(|e| io_error(py, e))
}

/// The axis `NAME=LO:HI:N` of a grid over `system` with the settings `set` (which choose a
/// family's member): (name, lo, hi, n). The bounds are left to the sweep's validation.
#[pyfunction]
fn parse_axis(
    py: Python<'_>,
    system: &str,
    set: Vec<(String, f64)>,
    text: &str,
) -> PyResult<(String, f64, f64, usize)> {
    let family = pendula::model::find(system).map_err(|e| to_py(py, &e))?;
    let info = family.values(&set).map_err(|e| to_py(py, &e))?.info();
    let example = pendula_io::value::axis_example(info);
    let a = pendula_io::value::parse_axis_text(info, "grid", &example, text).map_err(|e| io_error(py, e))?;
    Ok((a.name, a.lo, a.hi, a.n))
}

/// The values of a C-contiguous float64 array and its shape.
fn contiguous<'a>(
    py: Python<'_>,
    data: &'a PyReadonlyArrayDyn<'_, f64>,
) -> PyResult<(Vec<usize>, &'a [f64])> {
    let values = data.as_slice().map_err(|_| {
        raise(py, "InvalidValueError", "a .npy array is written from a C-contiguous array".into())
    })?;
    Ok((data.shape().to_vec(), values))
}

/// Writes `data` (C-contiguous float64) as a `.npy` file at `path`; (bytes, CRC-32) of the
/// file.
#[pyfunction]
fn save_npy(
    py: Python<'_>,
    path: std::path::PathBuf,
    data: PyReadonlyArrayDyn<'_, f64>,
) -> PyResult<(u64, u32)> {
    let (shape, values) = contiguous(py, &data)?;
    let file = std::fs::File::create(&path)?;
    let mut w = std::io::BufWriter::new(file);
    let written = pendula_io::npy::write(&mut w, &shape, values)?;
    w.into_inner().map_err(|e| e.into_error())?;
    Ok((written.bytes, written.crc32))
}

/// (bytes, CRC-32) of the `.npy` file [`save_npy`] writes for `data`, without writing it.
#[pyfunction]
fn npy_written(py: Python<'_>, data: PyReadonlyArrayDyn<'_, f64>) -> PyResult<(u64, u32)> {
    let (shape, values) = contiguous(py, &data)?;
    let written = pendula_io::npy::write(std::io::sink(), &shape, values)?;
    Ok((written.bytes, written.crc32))
}

/// The shard saved at `path` (`.npy`, its description beside it): (its description as JSON
/// text, its rows (count, columns)), after the description was checked against itself and
/// the file against the description (length, CRC-32, header).
#[pyfunction]
fn load_shard<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
) -> PyResult<(String, Bound<'py, PyArray2<f64>>)> {
    use pendula_io::shard;
    let io = |e| io_error(py, e);
    let d = shard::read_description(&path).map_err(io)?;
    let s = shard::describe_value(&d, &path).map_err(io)?;
    shard::verify_data(&s, s.n).map_err(io)?;
    let columns = *s.shape.last().expect("a checked shape");
    shard::check_header(&s, columns).map_err(io)?;
    let rows = shard::read_rows(&s, columns).map_err(io)?;
    let rows = numpy::ndarray::Array2::from_shape_vec((s.count, columns), rows).expect("whole rows");
    Ok((d.to_string(), rows.into_pyarray(py)))
}

/// Checks the shards handed to a merge, given as (name, description as JSON text): each
/// description against itself, all of one run, all N of them once.
#[pyfunction]
fn check_shards(py: Python<'_>, parts: Vec<(String, String)>) -> PyResult<()> {
    use pendula_io::shard;
    let io = |e| io_error(py, e);
    let parts = parts
        .iter()
        .map(|(name, text)| {
            let d: serde_json::Value = serde_json::from_str(text).map_err(|e| {
                raise(py, "InvalidValueError", format!("invalid shard description of {name}: {e}"))
            })?;
            shard::describe_value(&d, std::path::Path::new(name)).map_err(io)
        })
        .collect::<PyResult<Vec<_>>>()?;
    shard::same_run(&parts).map_err(io)?;
    shard::complete(&parts).map_err(io)
}
