//! Fuzzy c-means.

use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::fcm::{hard_labels, FcmModel, FcmParams};

use crate::{matrix_to_py, samples, vec_to_py, PyErrWrap};

/// A fitted fuzzy c-means partition (the Python `FcmModel` estimator holds one).
#[pyclass(frozen, module = "thermerr_rs._core", name = "FcmModel")]
pub struct PyFcmModel {
    pub(crate) inner: FcmModel,
}

fn labels_to_py(py: Python<'_>, l: Vec<usize>) -> Bound<'_, PyArray1<i64>> {
    PyArray1::from_vec(py, l.into_iter().map(|v| v as i64).collect())
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
        let init = init
            .as_ref()
            .map(|u| samples(u).map(|s| s.to_matrix()))
            .transpose()?;
        let params = FcmParams::new(n_clusters)
            .m(m)
            .tol(tol)
            .max_iter(max_iter)
            .seed(seed)
            .init(init)
            .check()
            .map_err(PyErrWrap)?;
        let inner = crate::detach(py, || params.fit(xs))?;
        Ok(PyFcmModel { inner })
    }

    /// Memberships of new objects (rows of `x`) to the fitted centres.
    fn predict_membership<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let xs = samples(&x)?;
        let u = crate::detach_short(py, || self.inner.predict_membership(xs))?;
        matrix_to_py(py, u)
    }

    /// Hard labels of new objects (largest membership).
    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let xs = samples(&x)?;
        let l = crate::detach_short(py, || self.inner.predict(xs))?;
        Ok(labels_to_py(py, l))
    }

    #[getter]
    fn centers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix_to_py(py, self.inner.centers.clone())
    }

    #[getter]
    fn membership<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix_to_py(py, self.inner.membership.clone())
    }

    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        labels_to_py(py, hard_labels(&self.inner.membership))
    }

    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_to_py(py, self.inner.history.clone())
    }

    #[getter]
    fn m(&self) -> f64 {
        self.inner.m
    }

    #[getter]
    fn n_iter(&self) -> usize {
        self.inner.n_iter
    }

    #[getter]
    fn objective(&self) -> f64 {
        self.inner.objective
    }

    #[getter]
    fn converged(&self) -> bool {
        self.inner.converged
    }

    #[getter]
    fn n_clusters(&self) -> usize {
        self.inner.n_clusters()
    }

    #[getter]
    fn n_features(&self) -> usize {
        self.inner.n_features()
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyFcmModel>()
}
