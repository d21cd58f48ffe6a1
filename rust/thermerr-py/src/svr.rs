//! ε-SVR solved by SMO.

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::svr::{Gamma, Kernel, SvrModel, SvrParams};

use crate::params::{parse, Given};
use crate::{matrix_to_py, samples, slice1, vec_to_py, PyErrWrap};

/// `gamma` as scikit-learn takes it: "scale", "auto" or a positive number.
#[derive(FromPyObject)]
pub(crate) enum GammaArg {
    Name(String),
    Value(f64),
}

impl GammaArg {
    fn gamma(self) -> PyResult<Gamma> {
        match self {
            GammaArg::Value(v) => Ok(Gamma::Value(v)),
            GammaArg::Name(s) => Ok(s.parse().map_err(PyErrWrap)?),
        }
    }
}

/// A fitted ε-SVR (the Python `SVR` holds one).
#[pyclass(frozen, module = "thermerr_rs._core", name = "SvrModel")]
pub struct PySvrModel {
    pub(crate) inner: SvrModel,
}

#[pymethods]
impl PySvrModel {
    #[staticmethod]
    #[pyo3(signature = (x, y, *, c = None, epsilon = None, kernel = None, gamma = None, tol = None, shrinking = None, cache_size = None, max_iter = None))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        c: Option<f64>,
        epsilon: Option<f64>,
        kernel: Option<&str>,
        gamma: Option<GammaArg>,
        tol: Option<f64>,
        shrinking: Option<bool>,
        cache_size: Option<f64>,
        max_iter: Option<usize>,
    ) -> PyResult<Self> {
        let params = SvrParams::new()
            .given(c, SvrParams::c)
            .given(epsilon, SvrParams::epsilon)
            .given(parse(kernel)?, SvrParams::kernel)
            .given(gamma.map(GammaArg::gamma).transpose()?, SvrParams::gamma)
            .given(tol, SvrParams::tol)
            .given(shrinking, SvrParams::shrinking)
            .given(cache_size, SvrParams::cache_size)
            .max_iter(max_iter);
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let inner = py
            .detach(|| params.check()?.fit(xs, ys))
            .map_err(PyErrWrap)?;
        Ok(PySvrModel { inner })
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
    fn support_vectors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix_to_py(py, self.inner.support_vectors.clone())
    }

    #[getter]
    fn dual_coef<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_to_py(py, self.inner.dual_coef.clone())
    }

    #[getter]
    fn support(&self) -> Vec<usize> {
        self.inner.support.clone()
    }

    #[getter]
    fn intercept(&self) -> f64 {
        self.inner.intercept
    }

    #[getter]
    fn n_iter(&self) -> usize {
        self.inner.n_iter
    }

    /// γ of the RBF kernel as resolved at fit time (None for the linear kernel).
    #[getter]
    fn gamma(&self) -> Option<f64> {
        match self.inner.kernel {
            Kernel::Rbf { gamma } => Some(gamma),
            Kernel::Linear => None,
        }
    }

    #[getter]
    fn n_features(&self) -> usize {
        self.inner.n_features()
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySvrModel>()?;
    Ok(())
}
