//! `Solution.sol` and callable events on the library's own interpolants: the continuous
//! solution ([`pendula::events::Continuous`]: each step's dense output, or the cubic Hermite
//! interpolant) and the event locator's bisection ([`pendula::events::bisect`]), so that a
//! Python event is located as the library locates its own.

use numpy::{
    IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::raise;

/// Adds the continuous solution's functions to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(dense_at, m)?)?;
    m.add_function(wrap_pyfunction!(bisect, m)?)
}

/// The state at each time of `tq` (within the run: the caller checks), (n_state, m): from the
/// recorded times `ts` (N,), states and derivatives (N, n), and, for a method with dense
/// output, each step's (t₀, h) (N − 1, 2) and coefficients (N − 1, terms, n).
#[pyfunction]
#[pyo3(signature = (ts, states, f, steps, coefficients, tq))]
fn dense_at<'py>(
    py: Python<'py>,
    ts: PyReadonlyArray1<'py, f64>,
    states: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray2<'py, f64>,
    steps: Option<PyReadonlyArray2<'py, f64>>,
    coefficients: Option<PyReadonlyArray3<'py, f64>>,
    tq: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let slice = |r| contiguous(py, r);
    let (ts_s, states_s, f_s) = (slice(ts.as_slice())?, slice(states.as_slice())?, slice(f.as_slice())?);
    let n = states.shape()[1];
    let dense = match (&steps, &coefficients) {
        (Some(s), Some(c)) => Some((slice(s.as_slice())?, slice(c.as_slice())?)),
        _ => None,
    };
    let times = slice(tq.as_slice())?;
    let continuous = pendula::events::Continuous { ts: ts_s, states: states_s, f: f_s, dense };
    let mut out = numpy::ndarray::Array2::<f64>::zeros((n, times.len()));
    let mut y = vec![0.0; n];
    for (k, &t) in times.iter().enumerate() {
        continuous.at(t, &mut y);
        out.column_mut(k).iter_mut().zip(&y).for_each(|(o, v)| *o = *v);
    }
    Ok(out.into_pyarray(py))
}

/// An array's values, which must be C-contiguous (Python passes them so).
fn contiguous<'a>(py: Python<'_>, r: Result<&'a [f64], numpy::AsSliceError>) -> PyResult<&'a [f64]> {
    r.map_err(|_| {
        raise(py, "InvalidValueError", "a continuous solution's arrays must be C-contiguous".into())
    })
}

/// The fraction s ∈ [0, 1] of a step of size `h`, ending at time `t`, where `g(s)` changes
/// sign (`sign`: its sign at s = 0), by the library locator's bisection.
#[pyfunction]
fn bisect(h: f64, t: f64, sign: f64, g: Bound<'_, PyAny>) -> PyResult<f64> {
    let mut failed = None;
    let s = pendula::events::bisect(h, t, sign, |s| match g.call1((s,)).and_then(|v| v.extract::<f64>()) {
        Ok(v) => v,
        Err(e) => {
            failed.get_or_insert(e);
            f64::NAN
        }
    });
    failed.map_or(Ok(s), Err)
}
