//! `pendula._core`: the pendula library (not the CLI) for Python. The pure-Python package
//! `pendula` (`python/pendula/`) is the face users see; this module holds what needs the
//! library: the catalogue, a built system's equations, single runs and ensembles.
//!
//! Every computation runs with the GIL released (`Python::detach`), so Python threads run
//! pendula concurrently. Library errors reach Python as the package's own exception classes
//! (`pendula.errors`), chosen here by the error's kind: bad input is a `ValueError` subclass
//! that names the value and what is allowed, a failed run an `IntegrationError` with the time.
//!
//! # How it is built
//!
//! The Python package: `crates/pendula-py/src/lib.rs` is `_core` — the catalogue as data, a built
//! system (`CoreSystem`: its equations over numpy columns), `solve` (one run on the library's
//! fastest path, `DynModel::solve_fastest`, as `pendula simulate` runs it, with the library's
//! `EventLocator` for event specs and, on request, what the continuous solution needs: dy/dt at
//! every state and the method's own dense coefficients where it has them) and `ensemble` (the
//! library's `ensemble_path`, lanes on all cores); `crates/pendula-py/src/study.rs` wraps the
//! library's analyses (`pendula::analysis`: Lyapunov exponents, Poincaré sections, the flip
//! fractal, bifurcation and convergence studies, work–precision; the registry's studies, the
//! divergence among them, through `crates/pendula-py/src/studies.rs`) and
//! `crates/pendula-py/src/animate.rs` pendula-viz's GIF animation. Each long computation runs on a
//! worker thread with the GIL released while the calling thread checks Python's signals (and
//! updates a progress bar) every 20 ms (by default the bar shows itself only where a terminal or a
//! notebook watches and the run, judged by its progress after 0.5 s, will take 3 s or more:
//! `dense.show_bar`); a Ctrl-C sets the flag that the run's observer and the engine
//! (`LaneSpec::cancel`, between lane groups, also under `flip_times_cancellable`) poll, so that one call over all the members or pixels keeps every thread busy to
//! the end and still stops within a work item's time. Library errors become the classes of
//! `crates/pendula-py/python/pendula/errors.py` by their kind. The pure-Python layer
//! (`crates/pendula-py/python/pendula/`) holds what Python users see: `__init__.py` (`System`,
//! pickled by name and values, versioned; `Solution`, scipy's shape, `y` a view of `states`;
//! `EnsembleResult`; `catalogue()`, `solve` with `method="auto"`, `ensemble`), `dense.py` (`sol`:
//! Hairer's dense polynomials or the cubic Hermite interpolant, scipy-style callable events located
//! on it, the progress bar), `animation.py` (`Solution.animate()`), `study.py` (the studies' result
//! objects with `plot()`), `sweep.py` (`sweep`, `merge`, the CLI's file format), `distributed.py`
//! (sweeps and fractals cut into parts computed on Dask workers: sweep shards then merged, or pixel
//! ranges of the fractal, `_core.fractal(pixels=…)`, assembled by `_core.fractal(times=…)`; byte
//! for byte the local result; `sweep_array`, a lazy `dask.array` whose blocks are runs of cells,
//! `_core.sweep(cells=…)`, computed by `map_blocks`). Its tests are pytest files in
//! `crates/pendula-py/tests/`, among them one that executes `examples/paper-study.ipynb` with
//! nbclient; `scripts/test-python` builds the package into target/py-venv with maturin and runs
//! them, after the Rust suites in `scripts/test`.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pendula::checkpoint::{Leg, Pause};
use pendula::control::Tolerances;
use pendula::ensemble::engine::{self, LaneOutcome, LaneSpec, Members};
use pendula::events::{EndAtEvent, EventLocator, EventSpec};
use pendula::integrator::{self, Method};
use pendula::model::{CATALOGUE, DynModel, EnsemblePath, ensemble_path};
use pendula::observe::{Flow, Observer, Sample};
use pendula::system::{Quantity, Values};
use pendula::{End, Error, RunSpec, Stepping};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

mod animate;
mod dense;
mod io;
mod serve;
mod studies;
mod study;
mod sweep;

/// The package's exception `class` (in `pendula.errors`) raised with `message`.
pub(crate) fn raise(py: Python<'_>, class: &str, message: String) -> PyErr {
    match py.import("pendula.errors").and_then(|m| m.getattr(class)) {
        Ok(cls) => PyErr::from_value(
            cls.call1((message,)).unwrap_or_else(|e| e.into_value(py).into_bound(py).into_any()),
        ),
        Err(e) => e,
    }
}

/// The Python exception for a library error: its class by kind, its message the library's.
fn to_py(py: Python<'_>, e: &Error) -> PyErr {
    // An error of one part of a computation is of its source's kind.
    let kind = match e {
        Error::In { inner, .. } => inner,
        e => e,
    };
    let class = match kind {
        Error::UnknownSystem { .. }
        | Error::UnknownMethod { .. }
        | Error::UnknownPreset { .. }
        | Error::UnknownName { .. }
        | Error::UnknownStudy { .. }
        | Error::UnknownInput { .. } => "UnknownNameError",
        Error::UnmetRequirement { .. } => "UnsuitableMethodError",
        Error::NonFinite { .. } | Error::NonFiniteMember { .. } | Error::NonFiniteIn { .. } => {
            "NonFiniteStateError"
        }
        Error::StepSizeTooSmall { .. } => "StepSizeTooSmallError",
        Error::NewtonDidNotConverge { .. } => "NewtonError",
        Error::InvalidValue { .. }
        | Error::InvalidInput { .. }
        | Error::OutOfRange { .. }
        | Error::TooLarge { .. } => "InvalidValueError",
        _ => "PendulaError",
    };
    raise(py, class, e.to_string())
}

/// The library's error from a run of `solve`, in the words of `pendula.solve`'s arguments:
/// the step `h` is `dt`, the times `t0` and `t_end` are `t_span`, and a step size too small is
/// cured by `rtol` and `atol` (Python sets no smallest step).
fn solve_error(py: Python<'_>, e: &Error) -> PyErr {
    match e {
        Error::InvalidValue { name, value, allowed } => {
            let name = match name.as_str() {
                "h" => "dt",
                "t0" | "t_end" => "t_span",
                other => other,
            };
            raise(
                py,
                "InvalidValueError",
                format!("invalid value {} for `{name}`: {allowed}", pendula::error::Short(*value)),
            )
        }
        Error::StepSizeTooSmall { t, h } => raise(
            py,
            "StepSizeTooSmallError",
            format!(
                "the step size fell to {} s at t = {} s, below what the time can resolve (loosen rtol and atol)",
                pendula::error::Short(*h),
                pendula::error::Short(*t)
            ),
        ),
        other => to_py(py, other),
    }
}

/// The time a failed run failed at, if the error says.
fn failure_time(e: &Error) -> Option<f64> {
    match e {
        Error::NonFinite { t }
        | Error::NonFiniteMember { t, .. }
        | Error::NonFiniteIn { t, .. }
        | Error::StepSizeTooSmall { t, .. }
        | Error::NewtonDidNotConverge { t, .. } => Some(*t),
        _ => None,
    }
}

fn quantity<'py>(py: Python<'py>, q: &Quantity) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", q.name)?;
    d.set_item("unit", q.unit)?;
    d.set_item("default", q.default)?;
    d.set_item("domain", q.domain.describe())?;
    d.set_item("description", q.description)?;
    d.set_item("angle", q.is_angle())?;
    Ok(d)
}

/// The method `method="auto"` picks for `system`, and why ([`pendula::model::auto_method`]).
#[pyfunction]
fn auto_method(system: &CoreSystem) -> (&'static str, &'static str) {
    let (method, why) = pendula::model::auto_method(&*system.model);
    (method.name, why)
}

/// The catalogue as plain data: `{"systems": [...], "methods": [...]}`. A system's
/// `separable` and `conservative` are those of its defaults.
#[pyfunction]
fn catalogue(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let systems = PyList::empty(py);
    for entry in CATALOGUE {
        let info = entry.info();
        let d = PyDict::new(py);
        d.set_item("name", info.name)?;
        d.set_item("description", info.description)?;
        d.set_item("dimensionless", info.dimensionless)?;
        d.set_item("energy_scale", info.energy_scale)?;
        let params = PyList::empty(py);
        for q in info.parameters {
            params.append(quantity(py, q)?)?;
        }
        d.set_item("parameters", params)?;
        let state = PyList::empty(py);
        for q in info.state {
            state.append(quantity(py, q)?)?;
        }
        d.set_item("state", state)?;
        let model = info.values(&[]).map_err(|e| to_py(py, &e))?.build();
        d.set_item("separable", model.separable())?;
        d.set_item("conservative", model.conserves_energy().is_ok())?;
        systems.append(d)?;
    }
    let methods = PyList::empty(py);
    for m in integrator::METHODS {
        let d = PyDict::new(py);
        d.set_item("name", m.name)?;
        d.set_item("title", m.title)?;
        d.set_item("order", m.order)?;
        d.set_item("symplectic", m.symplectic)?;
        d.set_item("symmetric", m.symmetric)?;
        d.set_item("adaptive", m.adaptive())?;
        d.set_item("requirement", m.requirement.describe())?;
        d.set_item("description", m.description)?;
        d.set_item("reference", m.reference)?;
        methods.append(d)?;
    }
    let out = PyDict::new(py);
    out.set_item("systems", systems)?;
    out.set_item("methods", methods)?;
    Ok(out)
}

/// A catalogued system built from validated values: its equations and runs.
#[pyclass(module = "pendula._core", frozen)]
struct CoreSystem {
    values: Values,
    model: Box<dyn DynModel>,
}

#[pymethods]
impl CoreSystem {
    /// The system `name` with `params` (parameter and initial-state values by name; the rest
    /// at their defaults).
    #[new]
    fn new(py: Python<'_>, name: &str, params: Vec<(String, f64)>) -> PyResult<Self> {
        let info = pendula::model::find(name).map_err(|e| to_py(py, &e))?;
        let values = info.values(&params).map_err(|e| to_py(py, &e))?;
        let model = values.build();
        Ok(CoreSystem { values, model })
    }

    /// The catalogue name.
    #[getter]
    fn name(&self) -> &'static str {
        self.values.info().name
    }

    /// Every parameter and initial-state value, by name, in the catalogue's order.
    fn values(&self) -> Vec<(&'static str, f64)> {
        let info = self.values.info();
        info.quantities().map(|q| (q.name, self.values.get(q.name))).collect()
    }

    /// The state's names.
    #[getter]
    fn names(&self) -> Vec<&'static str> {
        self.values.info().state.iter().map(|q| q.name).collect()
    }

    /// The initial state from the values.
    fn initial_state(&self) -> Vec<f64> {
        self.values.initial_state().to_vec()
    }

    /// Whether the system has a separable Hamiltonian form.
    #[getter]
    fn separable(&self) -> bool {
        self.model.separable()
    }

    /// Whether the system has a Hamiltonian form (no damping).
    #[getter]
    fn hamiltonian(&self) -> bool {
        integrator::find("verlet").is_ok_and(|m| self.model.check(m).is_ok())
    }

    /// Whether the energy is conserved (a Hamiltonian form, no drive); else why not.
    fn conservative(&self) -> (bool, Option<String>) {
        match self.model.conserves_energy() {
            Ok(()) => (true, None),
            Err(why) => (false, Some(why)),
        }
    }

    /// Whether the system is dimensionless (no units).
    #[getter]
    fn dimensionless(&self) -> bool {
        self.values.info().dimensionless
    }

    /// The energy scale relative energy errors from `y0` are taken against, and its
    /// description.
    fn energy_scale(&self, y0: Vec<f64>) -> PyResult<(f64, &'static str)> {
        self.check_dim(&y0)?;
        Ok((self.model.energy_scale(&y0), self.values.info().energy_scale))
    }

    /// dy/dt at (t, y) for each column of `y` (shape (n_state, k)).
    fn rhs<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        y: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.map_columns(py, y, |m, a, b| m.rhs(t, a, b))
    }

    /// The energy at time t of each column of `y` (shape (n_state, k)).
    fn energy<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        y: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let y = y.as_array();
        self.check_rows(y.nrows())?;
        let mut col = vec![0.0; y.nrows()];
        let e: Vec<f64> = y
            .columns()
            .into_iter()
            .map(|column| {
                col.iter_mut().zip(column).for_each(|(c, v)| *c = *v);
                self.model.energy(t, &col)
            })
            .collect();
        Ok(e.into_pyarray(py))
    }

    /// (q, q') → (q, p) for each column of `y`.
    fn to_momenta<'py>(
        &self,
        py: Python<'py>,
        y: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.conservative_form(py)?;
        self.map_columns(py, y, |m, a, b| m.to_momenta(a, b))
    }

    /// (q, p) → (q, q') for each column of `z`.
    #[pyo3(name = "from_momenta")]
    fn velocities_of<'py>(
        &self,
        py: Python<'py>,
        z: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.conservative_form(py)?;
        self.map_columns(py, z, |m, a, b| m.to_velocities(a, b))
    }

    /// The pickled form: the name and every value (version 1).
    fn __getnewargs__(&self) -> (&'static str, Vec<(String, f64)>) {
        let values = self.values().into_iter().map(|(n, v)| (n.to_owned(), v)).collect();
        (self.name(), values)
    }
}

impl CoreSystem {
    fn check_rows(&self, rows: usize) -> PyResult<()> {
        let n = self.values.info().state.len();
        if rows != n {
            return Err(raise_shape(n, rows));
        }
        Ok(())
    }

    fn check_dim(&self, y: &[f64]) -> PyResult<()> {
        self.check_rows(y.len())
    }

    fn conservative_form(&self, py: Python<'_>) -> PyResult<()> {
        // The momenta are those of the Hamiltonian form; a damped system has none.
        let method = integrator::find("verlet").map_err(|e| to_py(py, &e))?;
        self.model.check(method).map_err(|e| {
            raise(
                py,
                "UnsuitableMethodError",
                format!("no momenta: {}", e.to_string().split("; ").nth(1).unwrap_or("no Hamiltonian form")),
            )
        })
    }

    fn map_columns<'py>(
        &self,
        py: Python<'py>,
        y: PyReadonlyArray2<'py, f64>,
        f: impl Fn(&dyn DynModel, &[f64], &mut [f64]),
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let y = y.as_array();
        self.check_rows(y.nrows())?;
        let mut out = numpy::ndarray::Array2::<f64>::zeros(y.raw_dim());
        let (mut col, mut d) = (vec![0.0; y.nrows()], vec![0.0; y.nrows()]);
        for (j, column) in y.columns().into_iter().enumerate() {
            col.iter_mut().zip(column).for_each(|(c, v)| *c = *v);
            f(&*self.model, &col, &mut d);
            out.column_mut(j).iter_mut().zip(&d).for_each(|(o, v)| *o = *v);
        }
        Ok(out.into_pyarray(py))
    }
}

fn raise_shape(expected: usize, got: usize) -> PyErr {
    Python::attach(|py| {
        raise(
            py,
            "InvalidValueError",
            format!("a state has {expected} variables; got an array with {got} rows"),
        )
    })
}

/// What a run keeps of every accepted step: t, then the state; with `dense`, what the
/// continuous solution between the steps needs. The run goes on in the calling thread with
/// the GIL released; about every 20 ms of wall time this observer takes the GIL back for a
/// moment to run Python's signal handlers (a Ctrl-C) and the progress callback, and ends the
/// run at once if either raised (`pending`). No watcher thread: a short run costs nothing
/// extra, and a Ctrl-C is seen within 20 ms and a step.
struct Rows<'a> {
    rows: Vec<f64>,
    model: &'a dyn DynModel,
    dense: Option<DenseRecord>,
    progress: Option<Py<PyAny>>,
    /// Samples since the clock was last read, and when Python last had its turn.
    samples: u32,
    checked: std::time::Instant,
    pending: Option<PyErr>,
}

impl Rows<'_> {
    /// Python's turn, if 20 ms have passed (the clock is read every 32 samples).
    fn python(&mut self, t: f64) -> Flow {
        self.samples += 1;
        if self.samples < 32 {
            return Flow::Continue(());
        }
        self.samples = 0;
        if self.checked.elapsed() < std::time::Duration::from_millis(20) {
            return Flow::Continue(());
        }
        self.checked = std::time::Instant::now();
        let progress = &self.progress;
        let turn = Python::attach(|py| {
            py.check_signals()?;
            match progress {
                Some(p) => p.call1(py, (t,)).map(|_| ()),
                None => Ok(()),
            }
        });
        match turn {
            Ok(()) => Flow::Continue(()),
            Err(e) => {
                self.pending = Some(e);
                Flow::Break(pendula::observe::Stop::Enough)
            }
        }
    }
}

/// The continuous solution of a run, step by step: dy/dt at every state (the cubic Hermite
/// interpolant's data, which every method has), and the method's own dense output (its
/// steps' t₀, h and coefficients) when it gives one at every step.
struct DenseRecord {
    /// dy/dt at each state, row after row.
    f: Vec<f64>,
    /// (t₀, h) of each step's dense output, s.
    steps: Vec<f64>,
    /// Each step's coefficients, `terms` rows of the state's length.
    coefficients: Vec<f64>,
    terms: usize,
    /// Whether every step so far had the method's dense output.
    complete: bool,
    buf: Vec<f64>,
}

impl Observer for Rows<'_> {
    fn observe(&mut self, sample: &Sample<'_>) -> Flow {
        self.rows.push(sample.t);
        self.rows.extend_from_slice(sample.y);
        if let Some(d) = &mut self.dense {
            self.model.rhs(sample.t, sample.y, &mut d.buf);
            d.f.extend_from_slice(&d.buf);
            if sample.step > 0 {
                match &sample.dense {
                    Some(step) if d.complete => {
                        let c = step.coefficients();
                        d.terms = c.len() / sample.y.len();
                        d.steps.extend_from_slice(&[step.t0, step.h]);
                        d.coefficients.extend_from_slice(c);
                    }
                    _ => d.complete = false,
                }
            }
        }
        self.python(sample.t)
    }

    fn wants_dense(&self) -> bool {
        self.dense.is_some()
    }
}

/// Runs `f` with the GIL released. Unless `short`, on a worker thread, while this (the
/// calling) thread checks Python's signal handlers every 20 ms (they run only in the main
/// thread, with the GIL): a Ctrl-C sets the flag `f` is given, which the run polls, and the
/// KeyboardInterrupt is raised once the run has returned. A `short` run (well under the 0.2 s
/// a Ctrl-C may wait) runs here, without the thread's cost. `progress`, if given, is called
/// (with 0: the work is not counted) at each check, so that Python can show the time elapsed.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    short: bool,
    progress: Option<&Bound<'_, PyAny>>,
    f: impl FnOnce(&AtomicBool) -> T + Send,
) -> PyResult<T> {
    let done = AtomicU64::new(0);
    interruptible_counted(py, short, progress, &done, |flag| f(flag))
}

/// [`interruptible`] for a run that counts what it has finished in `done` (members, cells,
/// pixels): `progress`, if given, is called with the count at each check, and an exception it
/// raises stops the run as a Ctrl-C does.
pub(crate) fn interruptible_counted<T: Send>(
    py: Python<'_>,
    short: bool,
    progress: Option<&Bound<'_, PyAny>>,
    done: &AtomicU64,
    f: impl FnOnce(&AtomicBool) -> T + Send,
) -> PyResult<T> {
    let flag = AtomicBool::new(false);
    if short {
        return Ok(py.detach(|| f(&flag)));
    }
    let (out, pending) = std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::channel();
        let flag = &flag;
        scope.spawn(move || {
            // The receiver outlives the worker (the loop below waits for this message).
            let _ = tx.send(f(flag));
        });
        let mut pending: Option<PyErr> = None;
        let mut rx = rx;
        loop {
            // The receiver moves into the wait and back (it may be sent, not shared).
            let (received, back) =
                py.detach(move || (rx.recv_timeout(std::time::Duration::from_millis(20)), rx));
            rx = back;
            match received {
                Ok(out) => return (out, pending),
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    let tick = || match progress {
                        Some(p) => p.call1((done.load(Ordering::Relaxed),)).map(|_| ()),
                        None => Ok(()),
                    };
                    if pending.is_none()
                        && let Err(e) = py.check_signals().and_then(|()| tick())
                    {
                        flag.store(true, Ordering::Relaxed);
                        pending = Some(e);
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    panic!("the run's thread ended without a result")
                }
            }
        }
    });
    match pending {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

/// One run: `method` (a catalogue name) on `system` from `y0` over [t0, t_end], fixed steps
/// `dt` or, for an embedded pair, adaptive steps with `rtol`, `atol` (default 1e-6 each, as
/// the CLI) from a first step `dt`. `events` are the CLI's `--event` specs (`flip`,
/// `zero:NAME`, `section:NAME=VALUE[+|-]`), located by the library; with `stop_on_event`
/// the first ends the run, at the event. With `dense`, the continuous solution is kept.
/// `progress`, if given, is called with the time reached, s, about every 20 ms.
///
/// Returns a dict: `t` (k,), `states` (k, n_state), `nfev`, `steps`, `rejected`, `method`,
/// `events` ([(name, t, state)]), `stopped` (the terminal event's name or None), with
/// `dense`: `f` (k, n_state: dy/dt at each state) and, when the method gave its own dense
/// output at every step, `dense_steps` (k − 1, 2: t₀ and h) and `dense_coefficients`
/// (k − 1, terms, n_state); and `error` (None, or (exception, t)) — a failed run keeps the
/// steps it took.
#[pyfunction]
#[pyo3(signature = (system, method, t0, t_end, y0, dt=None, rtol=None, atol=None, dense=false, events=Vec::new(), stop_on_event=false, progress=None))]
#[allow(clippy::too_many_arguments)] // the run's description, as Python passes it
fn solve<'py>(
    py: Python<'py>,
    system: &CoreSystem,
    method: &str,
    t0: f64,
    t_end: f64,
    y0: Vec<f64>,
    dt: Option<f64>,
    rtol: Option<f64>,
    atol: Option<f64>,
    dense: bool,
    events: Vec<String>,
    stop_on_event: bool,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let method: &'static Method = integrator::find(method).map_err(|e| to_py(py, &e))?;
    system.check_dim(&y0)?;
    for (i, e) in events.iter().enumerate() {
        if events[..i].contains(e) {
            return Err(raise(
                py,
                "InvalidValueError",
                format!("invalid event {e:?}: it is given twice; give each event once"),
            ));
        }
    }
    let specs = events
        .iter()
        .map(|e| EventSpec::parse(e, &*system.model, stop_on_event))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| to_py(py, &e))?;
    // The messages name Python's arguments (t_span, dt), never the library's (t0, h).
    if !(t0.is_finite() && t_end.is_finite()) {
        return Err(raise(
            py,
            "InvalidValueError",
            format!("invalid t_span ({t0}, {t_end}): finite times (s)"),
        ));
    }
    if t_end == t0 {
        return Err(raise(
            py,
            "InvalidValueError",
            format!(
                "invalid t_span ({t0}, {t_end}): the end must differ from the start (before it: the run goes backward in time)"
            ),
        ));
    }
    if let Some(v) = dt
        && !(v.is_finite() && v > 0.0)
    {
        // scipy's convention: the step is a size, the direction is t_span's.
        return Err(raise(
            py,
            "InvalidValueError",
            format!(
                "invalid value {v} for `dt`: a finite step size > 0 (s); the direction comes from t_span, as in scipy's solve_ivp: t_span=(10, 0) runs backward"
            ),
        ));
    }
    for (name, v) in [("rtol", rtol), ("atol", atol)] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err(raise(
                py,
                "InvalidValueError",
                format!("invalid value {v} for `{name}`: a finite number > 0"),
            ));
        }
    }
    if let Some(v) = y0.iter().find(|v| !v.is_finite()) {
        return Err(raise(py, "InvalidValueError", format!("invalid value {v} in `y0`: finite numbers")));
    }
    system.model.check(method).map_err(|e| to_py(py, &e))?;
    // An embedded pair controls its step (dt, if given, the first to try).
    let adaptive = method.adaptive();
    if !adaptive && (rtol.is_some() || atol.is_some()) {
        return Err(raise(
            py,
            "InvalidValueError",
            format!(
                "rtol and atol apply to adaptive methods (dopri5, dop853); `{}` takes fixed steps dt",
                method.name
            ),
        ));
    }
    let tol = Tolerances {
        rtol: rtol.unwrap_or(pendula::simulate::defaults::RTOL),
        atol: atol.unwrap_or(pendula::simulate::defaults::ATOL),
        h_min: 0.0,
        h_max: f64::INFINITY,
    };
    if adaptive {
        tol.validate().map_err(|e| solve_error(py, &e))?;
    }
    // Backward when t_end < t0: negative steps of size dt.
    let direction = if t_end < t0 { -1.0 } else { 1.0 };
    let spec =
        RunSpec { t0, h: direction * dt.unwrap_or(pendula::simulate::defaults::DT), end: End::Time(t_end) };
    if !adaptive {
        // Checked here, to be named as the arguments are (the library speaks of h and of
        // its binding constant, which Python does not set).
        spec.schedule().map_err(|e| solve_error(py, &e))?;
        if let Some(refusal) = integrator::tao::step_refusal(method, spec.h) {
            return Err(to_py(py, &refusal));
        }
    }
    let model = &*system.model;
    let n = y0.len();
    let watch_events = !specs.is_empty();
    let progress = progress.map(Bound::unbind);
    let (rows, found, stopped, result) = py.detach(|| {
        let record = dense.then(|| DenseRecord {
            f: Vec::new(),
            steps: Vec::new(),
            coefficients: Vec::new(),
            terms: 0,
            complete: true,
            buf: vec![0.0; n],
        });
        let rows = Rows {
            rows: Vec::new(),
            model,
            dense: record,
            progress,
            samples: 0,
            checked: std::time::Instant::now(),
            pending: None,
        };
        let mut chain = EndAtEvent { events: EventLocator::new(model, specs), inner: rows };
        // Without events the locator is left out: one call per step less.
        let observer: &mut dyn Observer = if watch_events { &mut chain } else { &mut chain.inner };
        let result = if adaptive {
            // From any start, either way in time.
            model.solve_adaptive_from(method, &y0, t0, t_end, dt, &tol, observer).map(Leg::Done)
        } else {
            model.solve_fastest(method, &y0, &Stepping::Fixed(spec), observer, None, &Pause::NEVER)
        };
        let stopped = chain.events.stopped_at().map(|e| e.name.clone());
        let Rows { rows, dense, pending, .. } = chain.inner;
        ((rows, dense, pending), chain.events.found, stopped, result)
    });
    let (rows, record, pending) = rows;
    // A Ctrl-C (KeyboardInterrupt) or an exception of the progress callback ended the run.
    if let Some(e) = pending {
        return Err(e);
    }
    let k = rows.len() / (n + 1);
    let t: Vec<f64> = rows.chunks(n + 1).map(|r| r[0]).collect();
    let states: Vec<f64> = rows.chunks(n + 1).flat_map(|r| r[1..].iter().copied()).collect();
    let out = PyDict::new(py);
    out.set_item("t", t.into_pyarray(py))?;
    out.set_item(
        "states",
        numpy::ndarray::Array2::from_shape_vec((k, n), states).expect("k rows").into_pyarray(py),
    )?;
    out.set_item("method", method.name)?;
    out.set_item("adaptive", adaptive)?;
    let found: Vec<(String, f64, Vec<f64>)> = found.into_iter().map(|e| (e.name, e.t, e.state)).collect();
    out.set_item("events", found)?;
    out.set_item("stopped", stopped)?;
    if let Some(d) = record {
        out.set_item(
            "f",
            numpy::ndarray::Array2::from_shape_vec((k, n), d.f).expect("k rows").into_pyarray(py),
        )?;
        let s = d.steps.len() / 2;
        if d.complete && s > 0 && s + 1 == k {
            out.set_item(
                "dense_steps",
                numpy::ndarray::Array2::from_shape_vec((s, 2), d.steps).expect("s rows").into_pyarray(py),
            )?;
            out.set_item(
                "dense_coefficients",
                numpy::ndarray::Array3::from_shape_vec((s, d.terms, n), d.coefficients)
                    .expect("s steps")
                    .into_pyarray(py),
            )?;
            out.set_item("dense_order", method.dense_order())?;
        }
    }
    match result {
        Ok(Leg::Done(report)) => {
            out.set_item("nfev", report.rhs_evals)?;
            out.set_item("steps", report.outcome.steps())?;
            out.set_item("rejected", report.steps_rejected)?;
            out.set_item("error", py.None())?;
        }
        Ok(Leg::Paused(_)) => unreachable!("never paused"),
        Err(e) => {
            let class = solve_error(py, &e);
            out.set_item("nfev", py.None())?;
            out.set_item("steps", k.saturating_sub(1))?;
            out.set_item("rejected", py.None())?;
            out.set_item("error", (class.into_value(py), failure_time(&e)))?;
        }
    }
    Ok(out)
}

/// An ensemble: `m` members of `system`, member i's parameters `params[i]` (columns named by
/// `param_names`, the rest the system's values) and initial state `y0s[i]`, `steps` steps of
/// `dt` with `method`. On the SIMD lanes when the library says so (`ensemble_path`), else one
/// scalar run per member; all cores (`threads`). Returns (rows (m, n_state + 1, or + 2 with
/// `energy_error`): the final state, the first flip time or NaN, and E_end − E_0 (J) from the
/// member's own model; the engine's name).
#[pyfunction]
#[pyo3(signature = (system, y0s, param_names, params, method, dt, steps, until_flip, threads=None, energy_error=false, progress=None))]
#[allow(clippy::too_many_arguments)] // the ensemble's description, as Python passes it
fn ensemble<'py>(
    py: Python<'py>,
    system: &CoreSystem,
    y0s: PyReadonlyArray2<'py, f64>,
    param_names: Vec<String>,
    params: PyReadonlyArray2<'py, f64>,
    method: &str,
    dt: f64,
    steps: u64,
    until_flip: bool,
    threads: Option<usize>,
    energy_error: bool,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, &'static str)> {
    let method: &'static Method = integrator::find(method).map_err(|e| to_py(py, &e))?;
    let info = system.values.info();
    let (np, dim) = (info.parameters.len(), info.state.len());
    let y0s = y0s.as_array().to_owned();
    let params = params.as_array().to_owned();
    let m = y0s.nrows();
    if y0s.ncols() != dim {
        return Err(raise(
            py,
            "InvalidValueError",
            format!("y0s has {} columns; the `{}` state has {dim}", y0s.ncols(), info.name),
        ));
    }
    if params.nrows() != m || params.ncols() != param_names.len() {
        return Err(raise(
            py,
            "InvalidValueError",
            format!(
                "params has shape ({}, {}); expected ({m}, {})",
                params.nrows(),
                params.ncols(),
                param_names.len()
            ),
        ));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(raise(
            py,
            "InvalidValueError",
            format!("invalid value {dt} for `dt`: a finite number > 0"),
        ));
    }
    let mut slots = Vec::new();
    for name in &param_names {
        let q = info.quantity(name).map_err(|e| to_py(py, &e))?;
        if info.state.iter().any(|s| s.name == q.name) {
            return Err(raise(
                py,
                "InvalidValueError",
                format!("`{name}` is a state variable: give it in y0s"),
            ));
        }
        slots.push(info.parameters.iter().position(|p| p.name == q.name).expect("a parameter"));
    }
    // Every member validated before any step: its values within their domains.
    let base: Vec<f64> = info.quantities().map(|q| system.values.get(q.name)).collect();
    let member = |i: usize, v: &mut [f64]| {
        v.copy_from_slice(&base);
        for (k, &s) in slots.iter().enumerate() {
            v[s] = params[[i, k]];
        }
        v[np..].iter_mut().zip(y0s.row(i)).for_each(|(a, b)| *a = *b);
    };
    let settings_of = |v: &[f64]| -> Vec<(String, f64)> {
        info.quantities().map(|q| q.name.to_owned()).zip(v.iter().copied()).collect()
    };
    let mut v = vec![0.0; base.len()];
    for i in 0..m {
        member(i, &mut v);
        info.values(&settings_of(&v))
            .map_err(|e| raise(py, "InvalidValueError", format!("member {i}: {e}")))?;
    }
    let path = ensemble_path(method, &system.values);
    let cols = dim + 1 + usize::from(energy_error);
    let threads = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 {
        return Err(raise(py, "InvalidValueError", "invalid value 0 for `threads`: at least 1".to_owned()));
    }
    let mut data = vec![0.0; m * cols];
    let model = &*system.model;
    // One run over all the members, the interrupt flag looked at by each work item (slices
    // would each wait for their slowest member); a member's result does not depend on the
    // thread count.
    let done = AtomicU64::new(0);
    let result = interruptible_counted(py, false, progress.as_ref(), &done, |flag| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("threads");
        pool.install(|| -> Result<(), Error> {
            // The final state, the flip time and, if asked, the energy error from the
            // member's own model (built only then).
            let write = |i: usize, state: &[f64], flip: f64, row: &mut [f64]| {
                row[..dim].copy_from_slice(&state[..dim]);
                row[dim] = flip;
                if energy_error {
                    let mut v = vec![0.0; base.len()];
                    member(i, &mut v);
                    let model = info.values(&settings_of(&v)).expect("validated above").build();
                    row[dim + 1] = model.energy(0.0, &state[..dim]) - model.energy(0.0, &v[np..]);
                }
                done.fetch_add(1, Ordering::Relaxed);
            };
            let members = Members { info, count: m, values: &member };
            match path {
                EnsemblePath::Engine(lanes) => {
                    let spec = LaneSpec {
                        method: lanes,
                        h: dt,
                        steps,
                        stop_at_flip: until_flip,
                        track_flips: true,
                        cancel: Some(flag),
                    };
                    let store =
                        |i: usize, o: &LaneOutcome, row: &mut [f64]| write(i, &o.state, o.flip_time, row);
                    model.ensemble(&members, &spec, engine::Rows { out: &mut data, len: cols, store: &store })
                }
                EnsemblePath::Scalar => {
                    // One scalar run per member, as a sweep's scalar cells run.
                    let spec = pendula::sweep::ScalarSpec {
                        method,
                        h: dt,
                        steps,
                        stop_at_flip: until_flip,
                        cancel: Some(flag),
                    };
                    let store =
                        |i: usize, state: &[f64], flip: f64, row: &mut [f64]| write(i, state, flip, row);
                    pendula::sweep::run_scalar(
                        &members,
                        &spec,
                        engine::Rows { out: &mut data, len: cols, store: &store },
                    )
                    .map_err(|e| e.into_error())
                }
            }
        })
    })?;
    // An interrupted run raised KeyboardInterrupt above; what is left is the run's own.
    result.map_err(|e| to_py(py, &e))?;
    Ok((
        numpy::ndarray::Array2::from_shape_vec((m, cols), data).expect("m rows").into_pyarray(py),
        match path {
            EnsemblePath::Engine(_) => "simd lanes (ensemble engine)",
            EnsemblePath::Scalar => "scalar",
        },
    ))
}

/// The extension module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(catalogue, m)?)?;
    m.add_function(wrap_pyfunction!(auto_method, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    study::register(m)?;
    studies::register(m)?;
    sweep::register(m)?;
    io::register(m)?;
    dense::register(m)?;
    serve::register(m)?;
    m.add_function(wrap_pyfunction!(animate::animation_gif, m)?)?;
    m.add_class::<CoreSystem>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The library's defaults of a run, which `pendula.solve` takes when given none.
    let defaults = PyDict::new(m.py());
    {
        use pendula::simulate::defaults as d;
        defaults.set_item("system", d::SYSTEM)?;
        defaults.set_item("method", d::METHOD)?;
        defaults.set_item("dt", d::DT)?;
        defaults.set_item("t_end", d::T_END)?;
        defaults.set_item("rtol", d::RTOL)?;
        defaults.set_item("atol", d::ATOL)?;
    }
    m.add("SIMULATE_DEFAULTS", defaults)?;
    Ok(())
}
