//! Seed 000: the hybrid LR/MA/AR filter + network and its comparison variants.

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::hybrid::{HybridModel, HybridParams};

use crate::params::{net, parse, Given};
use crate::{samples, slice1, vec_to_py};

/// A fitted filter model (the Python `HybridFilterNet` holds one).
#[pyclass(frozen, module = "thermerr_rs._core", name = "HybridModel")]
pub struct PyHybridModel {
    pub(crate) inner: HybridModel,
}

#[pymethods]
impl PyHybridModel {
    #[staticmethod]
    #[pyo3(signature = (x, y, *, starts = Vec::new(), variant = None, ma_lags = None, ar_lags = None, c_y = None, limit = None, hidden = None, trainer = None, lr = None, momentum = None, max_epochs = None, goal = None, patience = None, init = None, seed = None, large_n = None))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        starts: Vec<usize>,
        variant: Option<&str>,
        ma_lags: Option<usize>,
        ar_lags: Option<usize>,
        c_y: Option<f64>,
        limit: Option<f64>,
        hidden: Option<usize>,
        trainer: Option<&str>,
        lr: Option<f64>,
        momentum: Option<f64>,
        max_epochs: Option<usize>,
        goal: Option<f64>,
        patience: Option<usize>,
        init: Option<f64>,
        seed: Option<u64>,
        large_n: Option<usize>,
    ) -> PyResult<Self> {
        let trainer = parse(trainer)?;
        let params = HybridParams::new()
            .given(parse(variant)?, HybridParams::variant)
            .given(ma_lags, HybridParams::ma_lags)
            .given(ar_lags, HybridParams::ar_lags)
            .given(c_y, HybridParams::c_y)
            .given(limit, HybridParams::limit)
            .net(|p| {
                let hidden = hidden.map(|h| vec![h]);
                net(
                    p, hidden, trainer, lr, momentum, max_epochs, goal, patience, init, seed,
                )
                // 0: never (Python's large_n=None)
                .given(large_n, |p, l| p.large_n((l > 0).then_some(l)))
            });
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let inner = crate::detach(py, || params.check()?.fit(xs, ys, &starts))?;
        Ok(PyHybridModel { inner })
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
        vec_to_py(py, self.inner.history.clone())
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
