//! ε-SVR solved by SMO.

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::svr::{Gamma, Kernel, KernelKind, SvrModel, SvrParams};
use thermerr_core::Error;

use crate::{matrix_to_py, samples, slice1, vec_to_py, PyErrWrap};

/// `gamma` as scikit-learn takes it: "scale", "auto" or a positive number.
#[derive(FromPyObject)]
pub(crate) enum GammaArg {
    Name(String),
    Value(f64),
}

pub(crate) fn parse_gamma(g: GammaArg) -> PyResult<Gamma> {
    match g {
        GammaArg::Value(v) => Ok(Gamma::Value(v)),
        GammaArg::Name(s) => match s.as_str() {
            "scale" => Ok(Gamma::Scale),
            "auto" => Ok(Gamma::Auto),
            other => Err(PyErrWrap(Error::InvalidParam {
                name: "gamma",
                reason: format!("must be \"scale\", \"auto\" or a positive number, got {other:?}"),
            })
            .into()),
        },
    }
}

pub(crate) fn parse_kernel(k: &str) -> PyResult<KernelKind> {
    match k {
        "rbf" => Ok(KernelKind::Rbf),
        "linear" => Ok(KernelKind::Linear),
        other => Err(PyErrWrap(Error::InvalidParam {
            name: "kernel",
            reason: format!("must be \"rbf\" or \"linear\", got {other:?}"),
        })
        .into()),
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
    #[pyo3(signature = (x, y, *, c = 1.0, epsilon = 0.1, kernel = "rbf", gamma = GammaArg::Name("scale".into()), tol = 1e-3, shrinking = true, cache_size = 200.0, max_iter = None))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        c: f64,
        epsilon: f64,
        kernel: &str,
        gamma: GammaArg,
        tol: f64,
        shrinking: bool,
        cache_size: f64,
        max_iter: Option<usize>,
    ) -> PyResult<Self> {
        let params = SvrParams {
            c,
            epsilon,
            kernel: parse_kernel(kernel)?,
            gamma: parse_gamma(gamma)?,
            tol,
            shrinking,
            cache_size,
            max_iter,
        };
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let inner = py.detach(|| params.fit(xs, ys)).map_err(PyErrWrap)?;
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
