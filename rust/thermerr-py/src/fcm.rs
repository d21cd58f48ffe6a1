//! Fuzzy c-means.

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::fcm::{FcmParams, FuzzyCMeans};
use thermerr_core::Matrix;

use crate::{samples, vec_to_py, PyErrWrap};

pub(crate) fn matrix_to_py<'py>(
    py: Python<'py>,
    m: &Matrix,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, m.data.clone()).reshape(m.shape)
}

fn matrix_from_py(a: &PyReadonlyArray2<'_, f64>) -> PyResult<Matrix> {
    let s = samples(a)?;
    Ok(Matrix {
        shape: [s.nrows(), s.ncols()],
        data: s.as_slice().to_vec(),
    })
}

/// A fitted fuzzy c-means partition (the Python `FuzzyCMeans` holds one).
#[pyclass(frozen, module = "thermerr_rs._core", name = "FcmModel")]
pub struct PyFcmModel {
    inner: FuzzyCMeans,
}

#[pymethods]
impl PyFcmModel {
    #[staticmethod]
    #[pyo3(signature = (x, *, n_clusters, m = 2.0, tol = 1e-5, max_iter = 1000, seed = None, init = None))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        n_clusters: usize,
        m: f64,
        tol: f64,
        max_iter: usize,
        seed: Option<u64>,
        init: Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<Self> {
        let xs = samples(&x)?;
        let init = init.as_ref().map(matrix_from_py).transpose()?;
        let params = FcmParams {
            n_clusters,
            m,
            tol,
            max_iter,
            seed,
            init,
        };
        let inner = py.detach(|| params.fit(xs)).map_err(PyErrWrap)?;
        Ok(PyFcmModel { inner })
    }

    fn predict_membership<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let xs = samples(&x)?;
        let u = py
            .detach(|| self.inner.predict_membership(xs))
            .map_err(PyErrWrap)?;
        matrix_to_py(py, &u)
    }

    #[getter]
    fn centers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix_to_py(py, &self.inner.centers)
    }

    #[getter]
    fn membership<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix_to_py(py, &self.inner.membership)
    }

    #[getter]
    fn initial<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix_to_py(py, &self.inner.initial)
    }

    #[getter]
    fn labels(&self) -> Vec<usize> {
        self.inner.labels()
    }

    #[getter]
    fn n_iter(&self) -> usize {
        self.inner.n_iter
    }

    #[getter]
    fn converged(&self) -> bool {
        self.inner.converged
    }

    #[getter]
    fn objective(&self) -> f64 {
        self.inner.objective
    }

    #[getter]
    fn objective_history<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_to_py(py, self.inner.objective_history.clone())
    }

    #[getter]
    fn n_features(&self) -> usize {
        self.inner.centers.ncols()
    }

    fn to_json(&self) -> PyResult<String> {
        crate::to_json(&self.inner)
    }

    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        Ok(PyFcmModel {
            inner: crate::from_json(text)?,
        })
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyFcmModel>()
}
