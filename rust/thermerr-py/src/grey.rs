//! Seed 002: rolling GM(1,N) + BP network, GM alone, BP alone; the small network trainers.

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::grey::{GmWork, GreyBpModel, GreyBpParams};
use thermerr_core::nn::{Act, BpModel, MlpParams, Trainer};
use thermerr_core::Error;

use crate::{samples, slice1, vec_to_py, PyErrWrap};

fn act(name: &str, what: &'static str) -> PyResult<Act> {
    match name {
        "sigmoid" => Ok(Act::Sigmoid),
        "tanh" => Ok(Act::Tanh),
        "linear" => Ok(Act::Linear),
        other => Err(PyErrWrap(Error::InvalidParam {
            name: what,
            reason: format!("must be \"sigmoid\", \"tanh\" or \"linear\", got {other:?}"),
        })
        .into()),
    }
}

/// Network and trainer parameters from the flat keywords the Python estimators pass.
#[allow(clippy::too_many_arguments)]
pub(crate) fn mlp_params(
    hidden: Vec<usize>,
    hidden_act: &str,
    output_act: &str,
    output_scale: f64,
    init: f64,
    trainer: &str,
    lr: f64,
    momentum: f64,
    max_epochs: usize,
    goal: f64,
    patience: usize,
    seed: u64,
) -> PyResult<MlpParams> {
    let trainer = match trainer {
        "seed" | "gd" => Trainer::Gd {
            lr,
            momentum,
            max_epochs,
            goal,
        },
        "adam" => Trainer::Adam {
            lr,
            max_epochs,
            goal,
            patience,
        },
        other => {
            return Err(PyErrWrap(Error::InvalidParam {
                name: "trainer",
                reason: format!("must be \"seed\" or \"adam\", got {other:?}"),
            })
            .into())
        }
    };
    Ok(MlpParams {
        hidden_sizes: hidden,
        hidden: act(hidden_act, "hidden_activation")?,
        output: act(output_act, "output_activation")?,
        output_scale,
        init,
        trainer,
        seed,
    })
}

/// A fitted rolling GM(1,N) (+ BP) model.
#[pyclass(frozen, module = "thermerr_rs._core", name = "GreyModel")]
pub struct PyGreyModel {
    pub(crate) inner: GreyBpModel,
    pub(crate) history: Vec<f64>,
}

#[pymethods]
impl PyGreyModel {
    /// `net=False` fits the first window's GM alone.
    #[staticmethod]
    #[pyo3(signature = (x, y, *, windows, net = true, hidden = 7, trainer = "seed", lr = 0.01, momentum = 0.9, max_epochs = 8000, goal = 0.01, patience = 500, init = 1.0, seed = 0))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        windows: Vec<usize>,
        net: bool,
        hidden: usize,
        trainer: &str,
        lr: f64,
        momentum: f64,
        max_epochs: usize,
        goal: f64,
        patience: usize,
        init: f64,
        seed: u64,
    ) -> PyResult<Self> {
        let np = if net {
            Some(mlp_params(
                vec![hidden],
                "sigmoid",
                "linear",
                1.0,
                init,
                trainer,
                lr,
                momentum,
                max_epochs,
                goal,
                patience,
                seed,
            )?)
        } else {
            None
        };
        let params = GreyBpParams { windows, net: np };
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let (inner, history) = py.detach(|| params.fit(xs, ys)).map_err(PyErrWrap)?;
        Ok(PyGreyModel { inner, history })
    }

    /// Closed loop, or one step ahead from the measured errors `y` (y[k−1] enters at step k).
    #[pyo3(signature = (x, y = None))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
        y: Option<PyReadonlyArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        crate::predict_series(py, &x, y.as_ref(), self.inner.n_features(), |t, m| {
            self.inner.predict(t, m)
        })
    }

    #[getter]
    fn windows(&self) -> Vec<usize> {
        self.inner.windows.clone()
    }

    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_to_py(py, self.history.clone())
    }

    #[getter]
    fn n_features(&self) -> usize {
        self.inner.n_features()
    }
}

/// GM(1,N) on one window: ([a, b2..bN], the restored prediction of the next sample).
#[pyfunction]
fn gm1n_window<'py>(
    py: Python<'py>,
    e: PyReadonlyArray1<'py, f64>,
    t: PyReadonlyArray2<'py, f64>,
    t_next: PyReadonlyArray1<'py, f64>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, f64)> {
    let (es, ts, tn) = (slice1(&e)?, samples(&t)?, slice1(&t_next)?);
    if ts.nrows() != es.len() || tn.len() != ts.ncols() {
        return Err(PyErrWrap(Error::Shape(format!(
            "{} errors, {} x {} temperatures and {} next temperatures do not match",
            es.len(),
            ts.nrows(),
            ts.ncols(),
            tn.len()
        )))
        .into());
    }
    let mut w = GmWork::new(es.len(), ts.ncols());
    let v = w.predict_next(es, ts.as_slice(), tn).ok_or_else(|| {
        PyErrWrap(Error::Numerical(
            "the GM(1,N) least-squares system is singular".into(),
        ))
    })?;
    Ok((vec_to_py(py, w.theta.clone()), v))
}

/// A fitted BP network regressor (min–max scaled inputs and output).
#[pyclass(frozen, module = "thermerr_rs._core", name = "BpModel")]
pub struct PyBpModel {
    pub(crate) inner: BpModel,
    pub(crate) history: Vec<f64>,
}

#[pymethods]
impl PyBpModel {
    #[staticmethod]
    #[pyo3(signature = (x, y, *, hidden = vec![7], trainer = "seed", lr = 0.01, momentum = 0.9, max_epochs = 8000, goal = 0.01, patience = 500, init = 1.0, seed = 0))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        hidden: Vec<usize>,
        trainer: &str,
        lr: f64,
        momentum: f64,
        max_epochs: usize,
        goal: f64,
        patience: usize,
        init: f64,
        seed: u64,
    ) -> PyResult<Self> {
        let p = mlp_params(
            hidden, "sigmoid", "linear", 1.0, init, trainer, lr, momentum, max_epochs, goal,
            patience, seed,
        )?;
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let (inner, history) = py.detach(|| p.fit_bp(xs, ys)).map_err(PyErrWrap)?;
        Ok(PyBpModel { inner, history })
    }

    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let xs = samples(&x)?;
        let y = py.detach(|| self.inner.predict(xs)).map_err(PyErrWrap)?;
        Ok(vec_to_py(py, y))
    }

    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_to_py(py, self.history.clone())
    }

    #[getter]
    fn n_features(&self) -> usize {
        self.inner.n_features()
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyGreyModel>()?;
    m.add_class::<PyBpModel>()?;
    m.add_function(wrap_pyfunction!(gm1n_window, m)?)?;
    Ok(())
}
