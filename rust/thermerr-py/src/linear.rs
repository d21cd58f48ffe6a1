//! Multiple linear regression.

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::linear::{MlrModel, MlrParams};

use crate::params::Given;
use crate::{samples, slice1, vec_to_py};

/// A fitted linear model (the Python `MLR` estimator holds one).
#[pyclass(frozen, module = "thermerr_rs._core", name = "MlrModel")]
pub struct PyMlrModel {
    pub(crate) inner: MlrModel,
}

#[pymethods]
impl PyMlrModel {
    #[staticmethod]
    #[pyo3(signature = (x, y, *, fit_intercept = None, alpha = None))]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        fit_intercept: Option<bool>,
        alpha: Option<f64>,
    ) -> PyResult<Self> {
        let params = MlrParams::new()
            .given(fit_intercept, MlrParams::fit_intercept)
            .given(alpha, MlrParams::alpha);
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let inner = crate::detach(py, || params.check()?.fit(xs, ys))?;
        Ok(PyMlrModel { inner })
    }

    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        crate::predict_rows(py, &x, |xs| self.inner.predict(xs))
    }

    #[getter]
    fn coef<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_to_py(py, self.inner.coef.clone())
    }

    #[getter]
    fn intercept(&self) -> f64 {
        self.inner.intercept
    }

    #[getter]
    fn n_features(&self) -> usize {
        self.inner.n_features()
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMlrModel>()
}
