//! The study not on the registry, `pendula.fractal` (it streams pixels over the ensemble
//! engine and stops between slices on Ctrl-C): the library's analysis with the library's
//! defaults, its result as a plain dict of numbers and arrays for `pendula.study` to wrap.
//!
//! The arguments arrive with the defaults filled in by Python (from the library's
//! `study::defaults`); what the library does not yet check itself is checked here, naming
//! the Python argument (the ports onto `pendula::study` move those checks below). Every
//! study runs with the GIL released. It stops early on Ctrl-C (between slices of pixels).

use std::sync::atomic::Ordering;

use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pendula::Error;
use pendula::analysis::fractal::{FractalSpec, GridAxis, assemble, flip_times_cancellable};
use pendula::integrator::{self, Method};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{CoreSystem, interruptible_counted, raise, to_py};

/// An `InvalidValueError` for `name` = `value`, with what is allowed.
fn invalid(py: Python<'_>, name: &str, value: impl std::fmt::Display, allowed: &str) -> PyErr {
    raise(py, "InvalidValueError", format!("invalid value {value} for `{name}`: {allowed}"))
}

/// A worker pool of `threads` (default: every core).
fn pool(py: Python<'_>, threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    let threads = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(invalid(py, "threads", 0, "at least 1"));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| raise(py, "PendulaError", format!("cannot start {threads} threads: {e}")))
}

/// The flip fractal as `pendula fractal`: the double pendulum `system` (its parameters; it
/// starts at rest at each pixel) over the grid `theta1` × `theta2` ((lo, hi, n), cell
/// centres), flip times at `dt` and `dt`/2 to `t_max`, pixels converged within
/// `tolerance` (s). Computed in slices of pixels, Ctrl-C honoured between them. Returns
/// `flip_time`, `flip_time_half_step` (n₂, n₁; NaN: no flip), `converged` (bool),
/// `forbidden`, the axes' cell centres `theta1_centres`, `theta2_centres` (rad).
#[pyfunction]
#[pyo3(signature = (system, theta1, theta2, t_max, method, dt, tolerance, threads=None, progress=None, pixels=None, times=None))]
#[allow(clippy::too_many_arguments)] // the study's description, as Python passes it
pub(crate) fn fractal<'py>(
    py: Python<'py>,
    system: &CoreSystem,
    theta1: (f64, f64, usize),
    theta2: (f64, f64, usize),
    t_max: f64,
    method: &str,
    dt: f64,
    tolerance: f64,
    threads: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
    pixels: Option<(usize, usize)>,
    times: Option<(Vec<f64>, Vec<f64>)>,
) -> PyResult<Bound<'py, PyDict>> {
    let method: &'static Method = integrator::find(method).map_err(|e| to_py(py, &e))?;
    let (theta1, theta2) = (GridAxis::from(theta1), GridAxis::from(theta2));
    let spec = FractalSpec::new(&system.values, theta1, theta2, t_max, dt, method, tolerance).map_err(
        |e| match e {
            // A method the ensemble engine does not run is unsuitable, as Python classes it.
            Error::InvalidInput { ref name, .. } if name == "method" => {
                raise(py, "UnsuitableMethodError", e.to_string())
            }
            e => to_py(py, &e),
        },
    )?;
    let pool = pool(py, threads)?;
    let all = theta1.n * theta2.n;
    // A part of the map (`pixels`, for `pendula.distributed`): its flip times alone, row-major
    // pixel indices [start, end). Or the whole map's flip times already computed (`times`,
    // the parts put together): assembled without computing.
    let (first, pixels) = match pixels {
        Some((start, end)) if start < end && end <= all => (start, end),
        Some((start, end)) => {
            return Err(invalid(
                py,
                "pixels",
                format!("({start}, {end})"),
                &format!("0 <= start < end <= {all}"),
            ));
        }
        None => (0, all),
    };
    // At dt and at dt/2, per pixel; None when interrupted.
    type FlipTimes = (Vec<f64>, Vec<f64>);
    let done = std::sync::atomic::AtomicU64::new(0);
    if let Some((at_h, at_half)) = times {
        if at_h.len() != all || at_half.len() != all {
            return Err(invalid(
                py,
                "times",
                format!("{} and {} values", at_h.len(), at_half.len()),
                &format!("{all} flip times at dt and {all} at dt/2"),
            ));
        }
        return assembled(py, method, &spec, at_h, at_half);
    }
    // One call over all the pixels, the flag looked at by each work item: every thread stays
    // busy to the end (slices would each wait for their slowest pixel). The library counts
    // each pixel twice (at dt and dt/2); progress is in pixels.
    let ticks = std::sync::atomic::AtomicU64::new(0);
    let tick = |n: u64| {
        let t = ticks.fetch_add(n, Ordering::Relaxed) + n;
        done.store(t / 2, Ordering::Relaxed);
    };
    let times = interruptible_counted(py, false, progress.as_ref(), &done, |flag| {
        pool.install(|| -> Result<Option<FlipTimes>, Error> {
            match flip_times_cancellable(&spec, first..pixels, &tick, Some(flag)) {
                Ok(t) => Ok(Some(t)),
                Err(Error::Interrupted) => Ok(None),
                Err(e) => Err(e),
            }
        })
    })?;
    let (at_h, at_half) = match times {
        Ok(Some(t)) => t,
        // Interrupted: the KeyboardInterrupt was raised above.
        Ok(None) => return Err(raise(py, "PendulaError", "the fractal was interrupted".to_owned())),
        Err(Error::NonFiniteMember { member, t }) => {
            let (i, j) = (member % theta1.n, member / theta1.n);
            return Err(raise(
                py,
                "NonFiniteStateError",
                format!(
                    "{} (fractal pixel ({i}, {j}) at theta1 = {}, theta2 = {})",
                    Error::NonFinite { t },
                    theta1.centre(i),
                    theta2.centre(j)
                ),
            ));
        }
        Err(e) => return Err(to_py(py, &e)),
    };
    if first > 0 || pixels < all {
        let out = PyDict::new(py);
        out.set_item("flip_time", at_h.into_pyarray(py))?;
        out.set_item("flip_time_half_step", at_half.into_pyarray(py))?;
        return Ok(out);
    }
    assembled(py, method, &spec, at_h, at_half)
}

/// The fractal's result from its flip times at dt and dt/2 (every pixel, row-major).
fn assembled<'py>(
    py: Python<'py>,
    method: &Method,
    spec: &FractalSpec,
    at_h: Vec<f64>,
    at_half: Vec<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let (theta1, theta2) = (spec.theta1, spec.theta2);
    let fractal = assemble(spec, at_h, at_half);
    let shape = (theta2.n, theta1.n);
    let out = PyDict::new(py);
    out.set_item("method", method.name)?;
    let grid = |v: Vec<f64>| Array2::from_shape_vec(shape, v).expect("the grid").into_pyarray(py);
    out.set_item("flip_time", grid(fractal.flip_time))?;
    out.set_item("flip_time_half_step", grid(fractal.flip_time_half_step))?;
    out.set_item(
        "converged",
        Array2::from_shape_vec(shape, fractal.converged).expect("the grid").into_pyarray(py),
    )?;
    out.set_item("forbidden", fractal.forbidden)?;
    let centres = |a: GridAxis| (0..a.n).map(|i| a.centre(i)).collect::<Vec<_>>().into_pyarray(py);
    out.set_item("theta1_centres", centres(theta1))?;
    out.set_item("theta2_centres", centres(theta2))?;
    Ok(out)
}

/// Adds the studies to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fractal, m)?)?;
    Ok(())
}
