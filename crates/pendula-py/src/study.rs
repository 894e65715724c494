//! The studies not yet on the registry (`pendula.fractal`, `convergence`, `work_precision`): the library's analyses with the library's
//! defaults, their results as plain dicts of numbers and arrays for `pendula.study` to wrap.
//!
//! The arguments arrive with the defaults filled in by Python (from the library's
//! `study::defaults`); what the library does not yet check itself is checked here, naming
//! the Python argument (the ports onto `pendula::study` move those checks below). Every
//! study runs with the GIL released. Only the fractal stops early on Ctrl-C (between slices
//! of pixels); the others have no cancellation hook in the library, so a Ctrl-C is raised
//! once they return.

use std::sync::atomic::Ordering;

use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pendula::Error;
use pendula::analysis::fractal::{FractalSpec, GridAxis, assemble, flip_times_cancellable};
use pendula::analysis::{self, OrderEstimate};
use pendula::ensemble::BatchMethod;
use pendula::error::Short;
use pendula::integrator::{self, METHODS, Method, Scheme};
use pendula::model::DynModel;
use pendula::system::{Model, double::DoublePendulum};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{CoreSystem, interruptible, interruptible_counted, raise, to_py};

/// An `InvalidValueError` for `name` = `value`, with what is allowed.
fn invalid(py: Python<'_>, name: &str, value: impl std::fmt::Display, allowed: &str) -> PyErr {
    raise(py, "InvalidValueError", format!("invalid value {value} for `{name}`: {allowed}"))
}

/// `value` unless it is not finite and > 0.
fn positive(py: Python<'_>, name: &str, value: f64) -> PyResult<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(invalid(py, name, Short(value), "a finite number > 0"))
    }
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
    let info = system.values.info();
    if !std::ptr::eq(info, <DoublePendulum as Model>::INFO) {
        return Err(raise(
            py,
            "InvalidValueError",
            format!("invalid system `{}`: the flip fractal is the double pendulum's (`double`)", info.name),
        ));
    }
    let pendulum = DoublePendulum::from_values(&system.values);
    if pendulum.is_forced() {
        return Err(raise(
            py,
            "InvalidValueError",
            "invalid system: the fractal's ensemble kernels integrate the free double pendulum (damping and drive_amplitude must be 0)".to_owned(),
        ));
    }
    let axis = |name: &str, (lo, hi, n): (f64, f64, usize)| -> PyResult<GridAxis> {
        if !(lo.is_finite() && hi.is_finite() && lo < hi && n >= 1) {
            return Err(raise(
                py,
                "InvalidValueError",
                format!(
                    "invalid {name} = ({lo}, {hi}, {n}): (lo, hi, n) with finite lo < hi (rad) and n >= 1"
                ),
            ));
        }
        Ok(GridAxis { lo, hi, n })
    };
    let (theta1, theta2) = (axis("theta1", theta1)?, axis("theta2", theta2)?);
    let t_max = positive(py, "t_max", t_max)?;
    let h = positive(py, "dt", dt)?;
    if h > t_max {
        return Err(invalid(py, "dt", Short(h), &format!("at most t_max = {} s", Short(t_max))));
    }
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(invalid(py, "tolerance", Short(tolerance), "a finite time >= 0 (s)"));
    }
    let method: &'static Method = integrator::find(method).map_err(|e| to_py(py, &e))?;
    let Some(batch) = BatchMethod::of(method) else {
        return Err(raise(
            py,
            "UnsuitableMethodError",
            format!(
                "invalid method `{}`: the fractal runs on the ensemble engine: rk4, tao-2 or tao-4",
                method.name
            ),
        ));
    };
    if let Scheme::Tao(scheme) = method.scheme {
        integrator::tao::check_binding_step(&scheme, h).map_err(|e| to_py(py, &e))?;
    }
    let pool = pool(py, threads)?;
    let spec = FractalSpec { pendulum, theta1, theta2, t_max, h, method: batch, tolerance };
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

/// The methods named ([`pendula::model::named_methods`]: each must apply, named once), or
/// every method that applies ([`pendula::model::applicable`]).
fn methods_of(
    py: Python<'_>,
    model: &dyn DynModel,
    names: Option<Vec<String>>,
) -> PyResult<Vec<&'static Method>> {
    match names {
        None => Ok(pendula::model::applicable(model, METHODS, None)),
        Some(names) => {
            pendula::model::named_methods(model, names.iter().map(String::as_str)).map_err(|e| to_py(py, &e))
        }
    }
}

/// Why a step of a study's ladder was dropped, in the words of Python's arguments: the step
/// is `dt`, and Tao's step limit names the largest dt (the library's message speaks of h and
/// of the binding constant, which the studies do not set).
fn dropped(d: &analysis::Dropped) -> String {
    let e = &d.error;
    if d.adaptive {
        return e.to_string();
    }
    if let Error::InvalidValue { .. } = e
        && let Some(why) = crate::tao_step_refusal(d.method, d.x)
    {
        return why;
    }
    match e {
        Error::InvalidValue { name, value, allowed } if name == "h" => {
            format!("invalid value {} for `dt`: {allowed}", Short(*value))
        }
        other => other.to_string(),
    }
}

/// A method's note on its dropped run: where (`dt` or `tol`) and why ([`dropped`]).
fn failure_note(d: &analysis::Dropped) -> String {
    format!("at {} = {}: {}", if d.adaptive { "tol" } else { "dt" }, Short(d.x), dropped(d))
}

/// The error of a study whose every run was dropped ([`analysis::all_dropped`]), in the
/// words of [`dropped`]; `Ok` when some run gave a point.
fn all_dropped<'a>(
    py: Python<'_>,
    produced: bool,
    dropped: impl IntoIterator<Item = &'a [analysis::Dropped]>,
) -> PyResult<()> {
    match analysis::all_dropped(produced, dropped) {
        Some(first) => Err(refused(py, &first.error, self::dropped(first))),
        None => Ok(()),
    }
}

/// The error of a study whose every step was dropped, with the message of [`dropped`].
fn refused(py: Python<'_>, e: &Error, why: String) -> PyErr {
    match e {
        Error::InvalidValue { .. } => raise(py, "InvalidValueError", why),
        other => to_py(py, other),
    }
}

/// The end time (default: the system's study horizon) and the given steps, checked.
fn horizon_and_steps(
    py: Python<'_>,
    system: &CoreSystem,
    t_end: Option<f64>,
    dts: Option<Vec<f64>>,
) -> PyResult<(f64, Option<Vec<f64>>)> {
    let t_end = positive(py, "t_end", t_end.unwrap_or_else(|| analysis::study_horizon(&system.values)))?;
    if let Some(hs) = &dts {
        if hs.is_empty() {
            return Err(raise(
                py,
                "InvalidValueError",
                "invalid dts []: give at least one step (s)".to_owned(),
            ));
        }
        for h in hs {
            positive(py, "dts", *h)?;
        }
    }
    Ok((t_end, dts))
}

/// What both accuracy studies share: the end time (default: the study horizon) and the
/// steps checked, the methods, a refusal when no method has a run to do, the reference
/// state, and `study` run on them with the GIL released.
#[allow(clippy::too_many_arguments)] // the studies' shared description
fn accuracy_study<'py, T: Send>(
    py: Python<'py>,
    system: &CoreSystem,
    methods: Option<Vec<String>>,
    dts: Option<Vec<f64>>,
    t_end: Option<f64>,
    tolerances: bool,
    progress: Option<&Bound<'py, PyAny>>,
    study: impl Fn(
        &analysis::Problem<'_>,
        &[&'static Method],
        &dyn Fn(&Method) -> Vec<f64>,
    ) -> Result<Vec<T>, Error>
    + Sync,
) -> PyResult<(f64, analysis::Reference, Vec<T>)> {
    let (t_end, dts) = horizon_and_steps(py, system, t_end, dts)?;
    let model = &*system.model;
    let methods = methods_of(py, model, methods)?;
    let ladder =
        |m: &Method| dts.clone().unwrap_or_else(|| analysis::method_ladder(m, model.time_scale(), t_end));
    if analysis::nothing_to_run(&methods, ladder, tolerances) {
        return Err(raise(
            py,
            "InvalidValueError",
            format!(
                "invalid t_end {}: no step of the methods' default ladders fits within their cost caps (at most 2e6 steps a run); give a shorter t_end, or dts",
                Short(t_end)
            ),
        ));
    }
    let y0 = system.values.initial_state();
    let run = || -> Result<_, Error> {
        let reference = analysis::reference_state(model, y0, t_end)?;
        let results =
            study(&analysis::Problem { model, y0, t_end, reference: &reference }, &methods, &ladder)?;
        Ok((reference, results))
    };
    let (reference, results) = interruptible(py, false, progress, |_| run())?.map_err(|e| to_py(py, &e))?;
    Ok((t_end, reference, results))
}

/// An accuracy study's result: `t_end`, the `reference`'s source and the `methods`.
fn accuracy_result<'py>(
    py: Python<'py>,
    t_end: f64,
    reference: &analysis::Reference,
    methods: Bound<'py, PyList>,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("t_end", t_end)?;
    out.set_item("reference", reference.source)?;
    out.set_item("methods", methods)?;
    Ok(out)
}

/// A convergence study as `pendula convergence`: each method's steps (`dts`, or its default
/// ladder) to `t_end` (default: the study horizon), the max-norm error against the exact
/// solution or a dop853 reference, and the order fitted in the asymptotic range.
#[pyfunction]
#[pyo3(signature = (system, methods=None, dts=None, t_end=None, progress=None))]
#[allow(clippy::too_many_arguments)] // the study's description, as Python passes it
pub(crate) fn convergence<'py>(
    py: Python<'py>,
    system: &CoreSystem,
    methods: Option<Vec<String>>,
    dts: Option<Vec<f64>>,
    t_end: Option<f64>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (t_end, reference, results) =
        accuracy_study(py, system, methods, dts, t_end, false, progress.as_ref(), |p, m, ladder| {
            analysis::convergence_study(p, m, ladder, || ())
        })?;
    let produced = results.iter().any(|r| !r.hs.is_empty());
    all_dropped(py, produced, results.iter().map(|r| &r.dropped[..]))?;
    let list = PyList::empty(py);
    for r in results {
        let d = PyDict::new(py);
        d.set_item("method", r.method.name)?;
        d.set_item("order", r.estimate.order())?;
        match r.estimate {
            OrderEstimate::Fitted { points, h_min, h_max, .. } => {
                d.set_item("fit", (points, h_min, h_max))?;
            }
            _ => d.set_item("fit", py.None())?,
        }
        d.set_item("reason", r.estimate.reason())?;
        d.set_item("failure", r.dropped.last().map(failure_note))?;
        // The table's note and the legend's label, as the library words them.
        d.set_item("note", r.note(pendula::study::sig, failure_note))?;
        d.set_item("label", r.estimate.label())?;
        d.set_item("dt", r.hs.into_pyarray(py))?;
        d.set_item("error", r.errors.into_pyarray(py))?;
        list.append(d)?;
    }
    accuracy_result(py, t_end, &reference, list)
}

/// A work-precision study as `pendula work-precision`: fixed-step methods at their steps
/// (`dts`, or each one's default ladder), embedded pairs at the tolerances `tols`
/// (rtol = atol), to `t_end` (default: the study horizon). Per method, points (dt, tol,
/// error, rhs_evals, wall_s) and why some are missing.
#[pyfunction]
#[pyo3(signature = (system, tols, methods=None, dts=None, t_end=None, progress=None))]
#[allow(clippy::too_many_arguments)] // the study's description, as Python passes it
pub(crate) fn work_precision<'py>(
    py: Python<'py>,
    system: &CoreSystem,
    tols: Vec<f64>,
    methods: Option<Vec<String>>,
    dts: Option<Vec<f64>>,
    t_end: Option<f64>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    if tols.is_empty() {
        return Err(raise(
            py,
            "InvalidValueError",
            "invalid tols []: give at least one tolerance".to_owned(),
        ));
    }
    for tol in &tols {
        if !(*tol >= pendula::control::MIN_RTOL && *tol < 1.0) {
            return Err(invalid(
                py,
                "tols",
                Short(*tol),
                &format!(
                    "tolerances in [{:e}, 1) (a smaller one is below round-off)",
                    pendula::control::MIN_RTOL
                ),
            ));
        }
    }
    let (t_end, reference, results) =
        accuracy_study(py, system, methods, dts, t_end, true, progress.as_ref(), |p, m, ladder| {
            analysis::work_precision_study(p, m, ladder, &tols, || ())
        })?;
    let produced = results.iter().any(|r| !r.points.is_empty());
    all_dropped(py, produced, results.iter().map(|r| &r.dropped[..]))?;
    let list = PyList::empty(py);
    for r in results {
        let (d, points) = (PyDict::new(py), &r.points);
        d.set_item("method", r.method.name)?;
        d.set_item("dt", points.iter().map(|p| p.h).collect::<Vec<_>>().into_pyarray(py))?;
        d.set_item(
            "tol",
            points.iter().map(|p| p.tol.unwrap_or(f64::NAN)).collect::<Vec<_>>().into_pyarray(py),
        )?;
        d.set_item("error", points.iter().map(|p| p.error).collect::<Vec<_>>().into_pyarray(py))?;
        d.set_item("rhs_evals", points.iter().map(|p| p.rhs_evals).collect::<Vec<_>>().into_pyarray(py))?;
        d.set_item("wall_s", points.iter().map(|p| p.wall_s).collect::<Vec<_>>().into_pyarray(py))?;
        d.set_item("failure", r.dropped.last().map(failure_note))?;
        list.append(d)?;
    }
    accuracy_result(py, t_end, &reference, list)
}

/// The tolerances of a work-precision study: `levels` from `loosest` to `tightest`,
/// geometric, the ends exact.
#[pyfunction]
pub(crate) fn tolerance_ladder(loosest: f64, tightest: f64, levels: usize) -> Vec<f64> {
    analysis::convergence::tolerance_ladder(loosest, tightest, levels)
}

/// Adds the studies to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fractal, m)?)?;
    m.add_function(wrap_pyfunction!(convergence, m)?)?;
    m.add_function(wrap_pyfunction!(work_precision, m)?)?;
    m.add_function(wrap_pyfunction!(tolerance_ladder, m)?)?;
    Ok(())
}
