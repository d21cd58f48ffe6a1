//! Seed 002: rolling GM(1,N) + BP network, GM alone, BP alone; the small network trainers.

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use thermerr_core::grey::{Gm1nParams, GmWork, GreyBpModel, GreyBpParams};
use thermerr_core::nn::{BpModel, BpParams};
use thermerr_core::Error;

use crate::params::{net, parse, Given};
use crate::{samples, slice1, vec_to_py, PyErrWrap};

/// A fitted rolling GM(1,N) (+ BP) model.
#[pyclass(frozen, module = "thermerr_rs._core", name = "GreyModel")]
pub struct PyGreyModel {
    pub(crate) inner: GreyBpModel,
}

#[pymethods]
impl PyGreyModel {
    #[staticmethod]
    #[pyo3(signature = (x, y, *, windows = None, hidden = None, trainer = None, lr = None, momentum = None, max_epochs = None, goal = None, patience = None, init = None, seed = None, large_n = None))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        windows: Option<Vec<usize>>,
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
        let params = GreyBpParams::new()
            .given(windows, GreyBpParams::windows)
            .net(|p| {
                let hidden = hidden.map(|h| vec![h]);
                net(
                    p, hidden, trainer, lr, momentum, max_epochs, goal, patience, init, seed,
                )
                // 0: never (Python's large_n=None)
                .given(large_n, |p, l| p.large_n((l > 0).then_some(l)))
            });
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let inner = crate::detach(py, || params.check()?.fit(xs, ys))?;
        Ok(PyGreyModel { inner })
    }

    /// The GM(1,N) of one window alone (seed 002's "GM").
    #[staticmethod]
    #[pyo3(signature = (x, y, *, window = None))]
    fn fit_gm1n(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        window: Option<usize>,
    ) -> PyResult<Self> {
        let params = Gm1nParams::new().given(window, Gm1nParams::window);
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let inner = crate::detach(py, || params.check()?.fit(xs, ys))?;
        Ok(PyGreyModel { inner })
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
        vec_to_py(py, self.inner.history.clone())
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
}

#[pymethods]
impl PyBpModel {
    #[staticmethod]
    #[pyo3(signature = (x, y, *, hidden = None, trainer = None, lr = None, momentum = None, max_epochs = None, goal = None, patience = None, init = None, seed = None, large_n = None))]
    #[allow(clippy::too_many_arguments)]
    fn fit(
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray1<'_, f64>,
        hidden: Option<Vec<usize>>,
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
        let params = net(
            BpParams::new(),
            hidden,
            parse(trainer)?,
            lr,
            momentum,
            max_epochs,
            goal,
            patience,
            init,
            seed,
        )
        // 0: never (Python's large_n=None)
        .given(large_n, |p, l| p.large_n((l > 0).then_some(l)));
        let (xs, ys) = (samples(&x)?, slice1(&y)?);
        let inner = crate::detach(py, || params.check()?.fit(xs, ys))?;
        Ok(PyBpModel { inner })
    }

    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        crate::predict_rows(py, &x, |xs| self.inner.predict(xs))
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
    m.add_class::<PyGreyModel>()?;
    m.add_class::<PyBpModel>()?;
    m.add_function(wrap_pyfunction!(gm1n_window, m)?)?;
    Ok(())
}
