//! Model files through their one owner, `thermerr_core::artifact`: reading validates the whole
//! file and hands back the family's fitted pyclass; writing validates what it writes. Python
//! keeps only the mapping from a file's `kind` to its estimator class.

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::artifact::{read_envelope, write_envelope, Artifact, Header, Model};
use thermerr_core::fcm::FcmModel;
use thermerr_core::Error;

use crate::fcm::PyFcmModel;
use crate::grey::{PyBpModel, PyGreyModel};
use crate::hybrid::PyHybridModel;
use crate::linear::PyMlrModel;
use crate::rbf::PyRbfModel;
use crate::svr::PySvrModel;
use crate::{samples, slice1, vec_to_py, PyErrWrap};

fn format_err(msg: impl Into<String>) -> PyErr {
    PyErrWrap(Error::Format(msg.into())).into()
}

/// The fitted core model a pyclass holds, as the file's `kind` names it.
fn core_model(kind: &str, inner: &Bound<'_, PyAny>) -> PyResult<Model> {
    let m = if let Ok(m) = inner.cast::<PyMlrModel>() {
        Model::Mlr(m.get().inner.clone())
    } else if let Ok(m) = inner.cast::<PyRbfModel>() {
        Model::Rbf(m.get().inner.clone())
    } else if let Ok(m) = inner.cast::<PySvrModel>() {
        Model::Svr(m.get().inner.clone())
    } else if let Ok(m) = inner.cast::<PyBpModel>() {
        Model::Bp(m.get().inner.clone())
    } else if let Ok(m) = inner.cast::<PyGreyModel>() {
        let g = m.get().inner.clone();
        match kind {
            "gm1n" => Model::Gm1n(g),
            _ => Model::GreyBp(g),
        }
    } else if let Ok(m) = inner.cast::<PyHybridModel>() {
        Model::Hybrid(m.get().inner.clone())
    } else {
        return Err(format_err(format!(
            "cannot write a {} as a {kind} model",
            inner.get_type().name()?
        )));
    };
    if m.kind() != kind {
        return Err(format_err(format!(
            "the fitted model is a {}, not a {kind}",
            m.kind()
        )));
    }
    Ok(m)
}

fn to_py(py: Python<'_>, m: Model) -> PyResult<Py<PyAny>> {
    Ok(match m {
        Model::Mlr(inner) => Py::new(py, PyMlrModel { inner })?.into_any(),
        Model::Rbf(inner) => Py::new(py, PyRbfModel { inner })?.into_any(),
        Model::Svr(inner) => Py::new(py, PySvrModel { inner })?.into_any(),
        Model::Bp(inner) => Py::new(py, PyBpModel { inner })?.into_any(),
        Model::GreyBp(inner) | Model::Gm1n(inner) => Py::new(py, PyGreyModel { inner })?.into_any(),
        Model::Hybrid(inner) => Py::new(py, PyHybridModel { inner })?.into_any(),
    })
}

fn header_json(h: &Header) -> PyResult<String> {
    serde_json::to_string(h).map_err(|e| format_err(e.to_string()))
}

/// Reads and validates the text of a model file: (kind, n_features, header as JSON, the fitted
/// model as its pyclass).
#[pyfunction]
fn read_model(py: Python<'_>, text: &str) -> PyResult<(String, usize, String, Py<PyAny>)> {
    let (kind, n, header, model) = read_envelope(text).map_err(PyErrWrap)?;
    if kind == "fcm" {
        let f: FcmModel =
            serde_json::from_value(model).map_err(|e| format_err(format!("fcm model: {e}")))?;
        f.validate().map_err(PyErrWrap)?;
        if f.n_features() != n {
            return Err(format_err(format!(
                "n_features is {n} but the fcm model takes {}",
                f.n_features()
            )));
        }
        header.validate(n).map_err(PyErrWrap)?;
        let obj = Py::new(py, PyFcmModel { inner: f })?.into_any();
        return Ok((kind, n, header_json(&header)?, obj));
    }
    let a = Artifact::from_json(text).map_err(PyErrWrap)?;
    let h = header_json(&a.header)?;
    Ok((kind, n, h, to_py(py, a.model)?))
}

/// Writes a model file of `kind` from its header (as JSON) and fitted pyclass; what it writes
/// is validated first, so that it can be read back.
#[pyfunction]
fn write_model(kind: &str, header: &str, inner: &Bound<'_, PyAny>) -> PyResult<String> {
    let header: Header =
        serde_json::from_str(header).map_err(|e| format_err(format!("header: {e}")))?;
    if let Ok(f) = inner.cast::<PyFcmModel>() {
        let f = &f.get().inner;
        f.validate().map_err(PyErrWrap)?;
        header.validate(f.n_features()).map_err(PyErrWrap)?;
        let v = serde_json::to_value(f).map_err(|e| format_err(e.to_string()))?;
        return Ok(write_envelope("fcm", f.n_features(), &header, v).map_err(PyErrWrap)?);
    }
    let a = Artifact {
        header,
        model: core_model(kind, inner)?,
    };
    Ok(a.to_json().map_err(PyErrWrap)?)
}

/// Min–max scaling (and 1-AGO) of a model's inputs: the core's one implementation, as recorded
/// in the file's `preprocessing`.
#[pyclass(frozen, module = "thermerr_rs._core", name = "Preprocessing")]
pub struct PyPreprocessing {
    inner: thermerr_core::artifact::Preprocessing,
}

#[pymethods]
impl PyPreprocessing {
    /// The training ranges of `x` (and of `y`, for `minmax_ago`).
    #[staticmethod]
    #[pyo3(signature = (kind, x, y = None))]
    fn fit(
        kind: &str,
        x: PyReadonlyArray2<'_, f64>,
        y: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<Self> {
        let xs = samples(&x)?;
        xs.require_finite("X").map_err(PyErrWrap)?;
        let ys = match &y {
            Some(a) => slice1(a)?,
            None => &[],
        };
        let inner =
            thermerr_core::artifact::Preprocessing::fit(kind, xs.as_slice(), xs.ncols(), ys)
                .map_err(PyErrWrap)?;
        Ok(PyPreprocessing { inner })
    }

    /// Reads the file's `preprocessing` entry (as JSON) for a model of `n_features` inputs.
    #[staticmethod]
    fn from_json(text: &str, n_features: usize) -> PyResult<Self> {
        let inner: thermerr_core::artifact::Preprocessing =
            serde_json::from_str(text).map_err(|e| format_err(format!("preprocessing: {e}")))?;
        inner.validate(n_features).map_err(PyErrWrap)?;
        Ok(PyPreprocessing { inner })
    }

    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.inner).map_err(|e| format_err(e.to_string()))
    }

    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }

    /// A run's inputs, row after row from its start.
    fn transform<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let xs = samples(&x)?;
        let out = self
            .inner
            .transform(xs.as_slice(), xs.ncols())
            .map_err(PyErrWrap)?;
        crate::matrix_to_py(
            py,
            thermerr_core::Matrix {
                shape: [xs.nrows(), xs.ncols()],
                data: out,
            },
        )
    }

    /// The target the model is fitted to.
    fn transform_target<'py>(
        &self,
        py: Python<'py>,
        y: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(vec_to_py(py, self.inner.transform_target(slice1(&y)?)))
    }

    /// The model's outputs over a run back to errors.
    fn inverse<'py>(
        &self,
        py: Python<'py>,
        y1: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(vec_to_py(py, self.inner.inverse(slice1(&y1)?)))
    }
}

/// A long repeat of the training run: (feature, first row, seconds).
type Repeat = (usize, usize, f64);

/// Sensor-fault limits learnt from training readings `x` (rows at `times` seconds), as the
/// JSON of a model file's `guard` (no fallbacks: Python fits those), and whether the model file
/// `text` can use fallback models (one without state from sample to sample).
#[pyfunction]
#[pyo3(signature = (text, x, times, hold_s))]
fn guard_from_training(
    text: &str,
    x: PyReadonlyArray2<'_, f64>,
    times: Option<PyReadonlyArray1<'_, f64>>,
    hold_s: f64,
) -> PyResult<(String, bool, Vec<Repeat>)> {
    let p = thermerr_core::artifact::Predictor::from_json(text).map_err(PyErrWrap)?;
    let fallbacks = thermerr_core::guard::takes_fallbacks(&p);
    let xs = samples(&x)?;
    let t = match &times {
        Some(a) => Some(slice1(a)?),
        None => None,
    };
    let (g, repeats) = thermerr_core::guard::Guard::from_training_with_repeats(
        xs.as_slice(),
        xs.ncols(),
        t,
        hold_s,
    )
    .map_err(PyErrWrap)?;
    let g = serde_json::to_string(&g).map_err(|e| format_err(e.to_string()))?;
    let repeats = repeats
        .into_iter()
        .map(|r| (r.feature, r.from_row, r.seconds))
        .collect();
    Ok((g, fallbacks, repeats))
}

/// A run's raw readings (NaN where missing) through a guarded model file, row by row as
/// `thermerr-edge` runs it: the predictions (NaN while a sensor has not given a good reading)
/// and each row's status.
#[pyfunction]
#[pyo3(signature = (text, x, times))]
fn predict_guarded<'py>(
    py: Python<'py>,
    text: &str,
    x: PyReadonlyArray2<'py, f64>,
    times: Option<PyReadonlyArray1<'py, f64>>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Vec<String>)> {
    let xs = samples(&x)?;
    let t = match &times {
        Some(a) => Some(slice1(a)?),
        None => None,
    };
    let p = thermerr_core::artifact::Predictor::from_json(text).map_err(PyErrWrap)?;
    let mut g = thermerr_core::guard::GuardedPredictor::new(p)
        .map_err(PyErrWrap)?
        .ok_or_else(|| format_err("the model file has no guard (fit it with one)"))?;
    let d = xs.ncols();
    if d != g.predictor().n_inputs() {
        return Err(PyErrWrap(Error::Shape(format!(
            "the model takes {} features, got {d} columns",
            g.predictor().n_inputs()
        )))
        .into());
    }
    if let Some(t) = t {
        if t.len() != xs.nrows() {
            return Err(PyErrWrap(Error::Shape(format!(
                "{} times for {} rows",
                t.len(),
                xs.nrows()
            )))
            .into());
        }
    }
    let (y, status) = crate::detach_short(py, || {
        let mut y = Vec::with_capacity(xs.nrows());
        let mut status = Vec::with_capacity(xs.nrows());
        for (i, row) in xs.as_slice().chunks_exact(d).enumerate() {
            y.push(g.step(t.map(|t| t[i]), row)?.unwrap_or(f64::NAN));
            let mut st = String::new();
            g.write_status(&mut st)
                .map_err(|e| Error::Format(e.to_string()))?;
            status.push(st);
        }
        Ok((y, status))
    })?;
    Ok((vec_to_py(py, y), status))
}

/// Per-sample latency (ns: p50, p99, mean) of `n` predictions of the model file `text` cycling
/// through the rows of `x` (raw readings), by the core's `Predictor::latency`: the code and the
/// loop `thermerr-edge --bench-latency` runs.
#[pyfunction]
fn sample_latency(
    py: Python<'_>,
    text: &str,
    x: PyReadonlyArray2<'_, f64>,
    n: usize,
) -> PyResult<(f64, f64, f64)> {
    let xs = samples(&x)?;
    let mut p = thermerr_core::artifact::Predictor::from_json(text).map_err(PyErrWrap)?;
    let d = xs.ncols();
    let rows: Vec<&[f64]> = xs.as_slice().chunks_exact(d.max(1)).collect();
    let lat = crate::detach_short(py, || p.latency(&rows, n))?;
    Ok((lat.p50_ns, lat.p99_ns, lat.mean_ns))
}

/// A run's model inputs with temperature history (`thermerr_core::artifact::History`): each
/// reading, then its rise over each time constant.
#[pyfunction]
#[pyo3(signature = (x, times, tau_s, step_s))]
fn history_transform<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    times: Option<PyReadonlyArray1<'py, f64>>,
    tau_s: Vec<f64>,
    step_s: f64,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let xs = samples(&x)?;
    let t = match &times {
        Some(a) => Some(slice1(a)?),
        None => None,
    };
    let h = thermerr_core::artifact::History { tau_s, step_s };
    let out = h
        .transform(xs.as_slice(), xs.ncols(), t)
        .map_err(PyErrWrap)?;
    crate::matrix_to_py(
        py,
        thermerr_core::Matrix {
            shape: [xs.nrows(), xs.ncols() * h.width()],
            data: out,
        },
    )
}

/// The median step of a time axis (s), as the core uses it everywhere
/// (`thermerr_core::timeaxis::median_step`); `None` with fewer than two samples.
#[pyfunction]
fn median_step(times: PyReadonlyArray1<'_, f64>) -> PyResult<Option<f64>> {
    Ok(thermerr_core::timeaxis::median_step(slice1(&times)?))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(history_transform, m)?)?;
    m.add_function(wrap_pyfunction!(median_step, m)?)?;
    m.add_function(wrap_pyfunction!(guard_from_training, m)?)?;
    m.add_function(wrap_pyfunction!(predict_guarded, m)?)?;
    m.add_function(wrap_pyfunction!(sample_latency, m)?)?;
    m.add_class::<PyPreprocessing>()?;
    m.add_function(wrap_pyfunction!(read_model, m)?)?;
    m.add_function(wrap_pyfunction!(write_model, m)?)?;
    Ok(())
}
