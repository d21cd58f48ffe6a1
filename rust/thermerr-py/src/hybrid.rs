//! Seed 000: the hybrid LR/MA/AR filter + network and its comparison variants.

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::hybrid::{HybridModel, HybridParams, Variant};
use thermerr_core::Error;

use crate::grey::mlp_params;
use crate::{samples, slice1, vec_to_py, PyErrWrap};

/// A fitted filter model (the Python `HybridFilterNet` holds one).
#[pyclass(frozen, module = "thermerr_rs._core", name = "HybridModel")]
pub struct PyHybridModel {
    pub(crate) inner: HybridModel,
    pub(crate) history: Vec<f64>,
}

#[pymethods]
impl PyHybridModel {
    #[staticmethod]
    #[pyo3(signature = (x, y, *, starts = Vec::new(), variant = "hybrid", ma_lags = 1, ar_lags = 2, c_y = 0.02, limit = 50.0, hidden = 30, trainer = "adam", lr = 0.01, momentum = 0.9, max_epochs = 10000, goal = 0.0, patience = 500, init = 0.5, seed = 0))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        starts: Vec<usize>,
        variant: &str,
        ma_lags: usize,
        ar_lags: usize,
        c_y: f64,
        limit: f64,
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
        let variant = match variant {
            "hybrid" => Variant::Hybrid,
            "arma" => Variant::Arma,
            "lrnn" => Variant::LrNn,
            "fnn" => Variant::Fnn,
            other => {
                return Err(PyErrWrap(Error::InvalidParam {
                    name: "variant",
                    reason: format!(
                        "must be \"hybrid\", \"arma\", \"lrnn\" or \"fnn\", got {other:?}"
                    ),
                })
                .into())
            }
        };
        let net = mlp_params(
            vec![hidden],
            "tanh",
            "tanh",
            1.0,
            init,
            trainer,
            lr,
            momentum,
            max_epochs,
            goal,
            patience,
            seed,
        )?;
        let p = HybridParams {
            variant,
            ma_lags,
            ar_lags,
            c_y,
            limit,
            net,
        };
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let (inner, history) = py.detach(|| p.fit(xs, ys, &starts)).map_err(PyErrWrap)?;
        Ok(PyHybridModel { inner, history })
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

    /// (LR, MA, AR) coefficient vectors.
    #[getter]
    fn filters(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        (
            self.inner.lr.clone(),
            self.inner.ma.clone(),
            self.inner.ar.clone(),
        )
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
    m.add_class::<PyHybridModel>()?;
    Ok(())
}
