//! RBF networks and k-means.

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::kmeans::kmeans as core_kmeans;
use thermerr_core::rbf::{RbfModel, RbfParams};
use thermerr_core::Matrix;

use crate::params::{parse, Given};
use crate::{matrix_to_py, samples, slice1, vec_to_py};

/// A fitted RBF network (the Python `RBFNetwork` holds one).
#[pyclass(frozen, module = "thermerr_rs._core", name = "RbfModel")]
pub struct PyRbfModel {
    pub(crate) inner: RbfModel,
}

#[pymethods]
impl PyRbfModel {
    #[staticmethod]
    #[pyo3(signature = (x, y, *, design = None, spread = None, goal = None, max_neurons = None, n_centers = None, seed = None, rule = None, max_candidates = None))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        design: Option<&str>,
        spread: Option<f64>,
        goal: Option<f64>,
        max_neurons: Option<usize>,
        n_centers: Option<usize>,
        seed: Option<u64>,
        rule: Option<&str>,
        max_candidates: Option<usize>,
    ) -> PyResult<Self> {
        let params = RbfParams::new()
            .given(parse(design)?, RbfParams::design)
            .given(spread, RbfParams::spread)
            .given(goal, RbfParams::goal)
            .max_neurons(max_neurons)
            .n_centers(n_centers)
            .seed(seed)
            .given(parse(rule)?, RbfParams::rule)
            .given(max_candidates, RbfParams::max_candidates);
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let inner = crate::detach(py, || params.check()?.fit(xs, ys))?;
        Ok(PyRbfModel { inner })
    }

    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        crate::predict_rows(py, &x, |xs| self.inner.predict(xs))
    }

    #[getter]
    fn centers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix_to_py(py, self.inner.centers.clone())
    }

    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_to_py(py, self.inner.weights.clone())
    }

    #[getter]
    fn bias(&self) -> f64 {
        self.inner.bias
    }

    #[getter]
    fn selected(&self) -> Vec<usize> {
        self.inner.selected.clone()
    }

    #[getter]
    fn sse_history<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_to_py(py, self.inner.sse_history.clone())
    }

    #[getter]
    fn n_features(&self) -> usize {
        self.inner.n_features()
    }
}

/// Lloyd's k-means from given initial centres: (centres, labels, n_iter, inertia).
#[pyfunction]
#[pyo3(signature = (x, init, max_iter = 300))]
#[allow(clippy::type_complexity)]
fn kmeans<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    init: PyReadonlyArray2<'py, f64>,
    max_iter: usize,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Vec<usize>, usize, f64)> {
    let xs = samples(&x)?;
    let is = samples(&init)?;
    let init = Matrix {
        shape: [is.nrows(), is.ncols()],
        data: is.as_slice().to_vec(),
    };
    let km = crate::detach(py, || core_kmeans(xs, &init, max_iter))?;
    Ok((
        matrix_to_py(py, km.centers)?,
        km.labels,
        km.n_iter,
        km.inertia,
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRbfModel>()?;
    m.add_function(wrap_pyfunction!(kmeans, m)?)?;
    Ok(())
}
