//! `thermerr_rs._core`: thin pyo3 wrappers over `thermerr-core`. Inputs are extracted first,
//! then every kernel runs inside one `py.detach` so long work releases the GIL.

mod artifact;
mod error;
mod fcm;
mod grey;
mod hybrid;
mod linear;
mod params;
mod rbf;
mod run;
mod svr;
mod swarm;
mod thermal;

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use thermerr_core::Samples;

pub use error::{PyErrWrap, PyRes};

/// Runs a core call with the GIL released and turns its error into the matching exception: the
/// one way every binding calls into the core (polars' `enter_polars`).
///
/// The call runs on a scoped worker thread while this (the caller's) thread polls Python's
/// signal handlers every 50 ms. On Ctrl-C the handler's `KeyboardInterrupt` is kept, the core's
/// interrupt flag is raised, every long loop of the core returns at its next check, and the
/// `KeyboardInterrupt` is raised here — within a second, and with nothing half-done left
/// behind (the core returns before writing anything). Only the main thread sees signals, as in
/// Python itself.
pub(crate) fn detach<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> thermerr_core::Result<T> + Send,
) -> PyResult<T> {
    detach_ticking(py, f, |_| {})
}

/// [`detach`], calling `tick` with the GIL held at every poll (every 50 ms) while the call runs,
/// and once more when it has ended: the place to draw a progress bar from the call's
/// [`thermerr_core::progress::Progress`].
pub(crate) fn detach_ticking<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> thermerr_core::Result<T> + Send,
    mut tick: impl FnMut(Python<'_>) + Send,
) -> PyResult<T> {
    let (joined, signal) = py.detach(|| {
        std::thread::scope(|scope| {
            let caller = std::thread::current();
            let worker = scope.spawn(move || {
                let r = f();
                caller.unpark();
                r
            });
            let mut signal: Option<PyErr> = None;
            while !worker.is_finished() {
                std::thread::park_timeout(std::time::Duration::from_millis(50));
                if signal.is_none() && !worker.is_finished() {
                    if let Err(e) = Python::attach(|py| {
                        tick(py);
                        py.check_signals()
                    }) {
                        thermerr_core::interrupt::request();
                        signal = Some(e);
                    }
                }
            }
            // the last counts too: a call that ends between two polls (or before the first, on
            // a small run) still shows where it ended
            if signal.is_none() {
                Python::attach(&mut tick);
            }
            (worker.join(), signal)
        })
    });
    // an interrupt raised here or by a callback (a progress bar's KeyboardInterrupt, also in
    // that last tick, after the work) is spent once the call has stopped: the next call starts
    // clean
    if signal.is_some()
        || thermerr_core::interrupt::requested()
        || matches!(joined, Ok(Err(thermerr_core::Error::Interrupted)))
    {
        thermerr_core::interrupt::clear();
    }
    let result = match joined {
        Ok(r) => r,
        Err(panic) => std::panic::resume_unwind(panic),
    };
    if let Some(e) = signal {
        return Err(e);
    }
    result.map_err(|e| PyErrWrap(e).into())
}

/// [`detach`] without the watch for Ctrl-C, for calls too short to need one (a model's predict
/// over a batch): no thread is started.
pub(crate) fn detach_short<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> thermerr_core::Result<T> + Send,
) -> PyResult<T> {
    py.detach(f).map_err(|e| PyErrWrap(e).into())
}

/// Predicts the rows of `x` with a model's batch `predict`, the GIL released.
pub(crate) fn predict_rows<'py>(
    py: Python<'py>,
    x: &PyReadonlyArray2<'py, f64>,
    predict: impl FnOnce(Samples<'_>) -> thermerr_core::Result<Vec<f64>> + Send,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let xs = samples(x)?;
    Ok(vec_to_py(py, detach_short(py, || predict(xs))?))
}

/// Borrows a C-contiguous float64 2-D array as row-major samples.
pub(crate) fn samples<'a>(x: &'a PyReadonlyArray2<'_, f64>) -> PyResult<Samples<'a>> {
    let (n, d) = (x.shape()[0], x.shape()[1]);
    let data = x.as_slice().map_err(|_| {
        pyo3::exceptions::PyValueError::new_err("X must be a C-contiguous float64 array")
    })?;
    Ok(Samples::new(data, n, d).map_err(PyErrWrap)?)
}

pub(crate) fn slice1<'a>(y: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    y.as_slice().map_err(|_| {
        pyo3::exceptions::PyValueError::new_err("y must be a contiguous float64 array")
    })
}

/// Moves an owned matrix into a 2-D NumPy array (no copy of the buffer).
pub(crate) fn matrix_to_py(
    py: Python<'_>,
    m: thermerr_core::Matrix,
) -> PyResult<Bound<'_, numpy::PyArray2<f64>>> {
    use numpy::PyArrayMethods;
    let [r, c] = m.shape;
    PyArray1::from_vec(py, m.data).reshape([r, c])
}

/// Runs a model that reads past errors over the rows of `x`: closed loop, or one step ahead from
/// the measured errors `y`; the GIL is released while it runs.
pub(crate) fn predict_series<'py>(
    py: Python<'py>,
    x: &PyReadonlyArray2<'py, f64>,
    y: Option<&PyReadonlyArray1<'py, f64>>,
    n_features: usize,
    f: impl Fn(&[f64], Option<&[f64]>) -> thermerr_core::Result<Vec<f64>> + Sync,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let xs = samples(x)?;
    thermerr_core::linear::check_features(xs.ncols(), n_features).map_err(PyErrWrap)?;
    xs.require_finite("X").map_err(PyErrWrap)?;
    let ys = match y {
        Some(a) => Some(slice1(a)?),
        None => None,
    };
    let out = detach_short(py, || f(xs.as_slice(), ys))?;
    Ok(vec_to_py(py, out))
}

pub(crate) fn vec_to_py(py: Python<'_>, v: Vec<f64>) -> Bound<'_, PyArray1<f64>> {
    PyArray1::from_vec(py, v)
}

/// Asks every running kernel to stop at its next check, from any thread: how a caller that
/// runs kernels on threads of its own (the fleet's dask threads, which never see a signal)
/// passes Ctrl-C on. Each interrupted call clears the request when it returns, so the caller
/// repeats it until its threads are done, then calls [`clear_interrupt`].
#[pyfunction]
fn request_interrupt() {
    thermerr_core::interrupt::request();
}

/// Withdraws a request of [`request_interrupt`], so that the next call starts clean.
#[pyfunction]
fn clear_interrupt() {
    thermerr_core::interrupt::clear();
}

/// Looks numpy's C API up now. rust-numpy does it on the first array, running Python code (numpy's
/// version check) that a Ctrl-C interrupts, and then panics ("Failed to access NumPy array API
/// capsule"): on a 1-s run, Ctrl-C while `init` read it crossed into Python as a PanicException.
/// At import a failure is an ImportError naming the cause.
fn load_numpy_api(py: Python<'_>) -> PyResult<()> {
    let prev = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {})); // the error below says it
    let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let _ = numpy::PyArray1::<f64>::zeros(py, 0, false);
    }));
    std::panic::set_hook(prev);
    out.map_err(|e| {
        let why = e
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        pyo3::exceptions::PyImportError::new_err(format!(
            "numpy's C API could not be loaded: {why}"
        ))
    })
}

#[pymodule(gil_used = false)]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    load_numpy_api(m.py())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(request_interrupt, m)?)?;
    m.add_function(wrap_pyfunction!(clear_interrupt, m)?)?;
    m.add("FORMAT_VERSION", thermerr_core::artifact::FORMAT_VERSION)?;
    m.add(
        "NETWORK_RULES",
        thermerr_core::thermal::diagnose::NetworkRule::ALL.map(|r| r.as_str()),
    )?;
    artifact::register(m)?;
    run::register(m)?;
    linear::register(m)?;
    fcm::register(m)?;
    rbf::register(m)?;
    thermal::register(m)?;
    svr::register(m)?;
    swarm::register(m)?;
    grey::register(m)?;
    hybrid::register(m)?;
    params::register(m)?;
    Ok(())
}
