//! Swarm minimisers (CSO, PSO) over a Python callable or a built-in test function, and the
//! native SVR tuning of seed 004.

use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyAny;
use thermerr_core::svr::SvrParams;
use thermerr_core::swarm::{
    cso_minimize_batch, pso_minimize_batch, Bounds, CsoParams, PsoParams, SwarmResult,
};
use thermerr_core::tune::{self, Scale, Search, TuneParams};
use thermerr_core::Error;

use crate::svr::PySvrModel;
use crate::{samples, slice1, PyErrWrap};

/// The built-in test objectives, evaluated natively (no Python in the loop).
fn builtin(name: &str) -> Option<fn(&[f64]) -> f64> {
    fn sphere(x: &[f64]) -> f64 {
        x.iter().map(|v| v * v).sum()
    }
    fn rosenbrock(x: &[f64]) -> f64 {
        x.windows(2)
            .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
            .sum()
    }
    fn rastrigin(x: &[f64]) -> f64 {
        10.0 * x.len() as f64
            + x.iter()
                .map(|v| v * v - 10.0 * (2.0 * std::f64::consts::PI * v).cos())
                .sum::<f64>()
    }
    match name {
        "sphere" => Some(sphere),
        "rosenbrock" => Some(rosenbrock),
        "rastrigin" => Some(rastrigin),
        _ => None,
    }
}

/// Either swarm's parameters, from one flat keyword list.
#[derive(Clone)]
enum Method {
    Cso(CsoParams),
    Pso(PsoParams),
}

#[allow(clippy::too_many_arguments)]
fn method(
    name: &str,
    pop: usize,
    iters: usize,
    g: usize,
    roosters: f64,
    hens: f64,
    fl: (f64, f64),
    w: f64,
    c1: f64,
    c2: f64,
    vmax_frac: f64,
    seed: u64,
) -> PyResult<Method> {
    match name {
        "cso" => Ok(Method::Cso(CsoParams {
            pop,
            iters,
            g,
            roosters,
            hens,
            fl,
            seed,
        })),
        "pso" => Ok(Method::Pso(PsoParams {
            pop,
            iters,
            w,
            c1,
            c2,
            vmax_frac,
            seed,
        })),
        other => Err(PyErrWrap(Error::InvalidParam {
            name: "method",
            reason: format!("must be \"cso\" or \"pso\", got {other:?}"),
        })
        .into()),
    }
}

type Out = (Vec<f64>, f64, Vec<f64>, usize);

fn out(r: SwarmResult) -> Out {
    (r.x, r.f, r.history, r.n_evals)
}

/// Minimises `f` over the box `bounds` with CSO or PSO: (x, f, history, n_evals).
///
/// `f` is the name of a built-in objective ("sphere", "rosenbrock", "rastrigin"; evaluated
/// natively without the GIL) or a Python callable taking one point (a 1-D array) and returning
/// a float — or, with `vectorized=True`, the whole population (pop × dim) returning pop floats.
#[pyfunction]
#[pyo3(signature = (f, bounds, *, method = "cso", pop = 20, iters = 100, g = 10, roosters = 0.2, hens = 0.6, fl = (0.4, 1.0), w = 0.7298, c1 = 1.49618, c2 = 1.49618, vmax_frac = 0.2, seed = 0, vectorized = false))]
#[allow(clippy::too_many_arguments)]
fn swarm_minimize(
    py: Python<'_>,
    f: Bound<'_, PyAny>,
    bounds: Vec<(f64, f64)>,
    method: &str,
    pop: usize,
    iters: usize,
    g: usize,
    roosters: f64,
    hens: f64,
    fl: (f64, f64),
    w: f64,
    c1: f64,
    c2: f64,
    vmax_frac: f64,
    seed: u64,
    vectorized: bool,
) -> PyResult<Out> {
    let m = self::method(
        method, pop, iters, g, roosters, hens, fl, w, c1, c2, vmax_frac, seed,
    )?;
    let b = Bounds::from_pairs(&bounds);
    if let Ok(name) = f.extract::<String>() {
        let obj = builtin(&name).ok_or_else(|| {
            PyErrWrap(Error::InvalidParam {
                name: "f",
                reason: format!(
                    "unknown built-in objective {name:?} (known: sphere, rosenbrock, rastrigin)"
                ),
            })
        })?;
        // the built-ins are cheap: evaluated serially (handing 20 of them to rayon per
        // generation costs more than it saves), without the GIL
        let batch = |p: &[Vec<f64>]| Ok(p.iter().map(|x| obj(x)).collect());
        let r = crate::detach(py, || match &m {
            Method::Cso(p) => cso_minimize_batch(batch, &b, p),
            Method::Pso(p) => pso_minimize_batch(batch, &b, p),
        })?;
        return Ok(out(r));
    }
    if !f.is_callable() {
        return Err(pyo3::exceptions::PyTypeError::new_err(
            "f must be a callable or the name of a built-in objective",
        ));
    }
    // a Python exception inside the objective stops the search and is re-raised as it is
    let mut raised: Option<PyErr> = None;
    let eval = |popu: &[Vec<f64>]| -> thermerr_core::Result<Vec<f64>> {
        let r: PyResult<Vec<f64>> = (|| {
            if vectorized {
                let arr = PyArray2::from_vec2(py, popu)?;
                let v = f.call1((arr,))?;
                let vals: Vec<f64> = v.extract()?;
                if vals.len() != popu.len() {
                    return Err(pyo3::exceptions::PyValueError::new_err(format!(
                        "the vectorized objective returned {} values for {} points",
                        vals.len(),
                        popu.len()
                    )));
                }
                Ok(vals)
            } else {
                popu.iter()
                    .map(|x| {
                        let arr = numpy::PyArray1::from_slice(py, x);
                        f.call1((arr,))?.extract::<f64>()
                    })
                    .collect()
            }
        })();
        r.map_err(|e| {
            raised = Some(e);
            Error::Numerical("the objective raised an exception".into())
        })
    };
    let r = match &m {
        Method::Cso(p) => cso_minimize_batch(eval, &b, p),
        Method::Pso(p) => pso_minimize_batch(eval, &b, p),
    };
    match (r, raised) {
        (_, Some(e)) => Err(e),
        (Ok(r), None) => Ok(out(r)),
        (Err(e), None) => Err(PyErrWrap(e).into()),
    }
}

/// Test-index sets of `k` folds over `n` samples (in order, or shuffled by `seed`).
#[pyfunction]
#[pyo3(signature = (n, k, seed = None))]
fn kfold(n: usize, k: usize, seed: Option<u64>) -> PyResult<Vec<Vec<usize>>> {
    Ok(tune::kfold(n, k, seed).map_err(PyErrWrap)?)
}

type Pairs = Vec<(Vec<usize>, Vec<usize>)>;

fn to_pairs(s: Vec<tune::Split>) -> Pairs {
    s.into_iter().map(|s| (s.train, s.test)).collect()
}

fn from_pairs(p: Pairs) -> Vec<tune::Split> {
    p.into_iter()
        .map(|(train, test)| tune::Split { train, test })
        .collect()
}

/// The `kfold` folds as (train, test) pairs, training sets the complements (both sorted).
#[pyfunction]
#[pyo3(signature = (n, k, seed = None))]
fn kfold_splits(n: usize, k: usize, seed: Option<u64>) -> PyResult<Pairs> {
    Ok(to_pairs(tune::kfold_splits(n, k, seed).map_err(PyErrWrap)?))
}

/// scikit-learn's `TimeSeriesSplit(n_splits, gap=, test_size=, max_train_size=)` over `n`
/// samples, as (train, test) pairs.
#[pyfunction]
#[pyo3(signature = (n, n_splits, *, gap = 0, test_size = None, max_train_size = None))]
fn time_series_split(
    n: usize,
    n_splits: usize,
    gap: usize,
    test_size: Option<usize>,
    max_train_size: Option<usize>,
) -> PyResult<Pairs> {
    Ok(to_pairs(
        tune::time_series_split(n, n_splits, gap, test_size, max_train_size).map_err(PyErrWrap)?,
    ))
}

/// Checks (train, test) pairs over `n` samples (raises ParameterError naming the fold).
#[pyfunction]
fn check_splits(splits: Pairs, n: usize) -> PyResult<()> {
    Ok(tune::check_splits(&from_pairs(splits), n).map_err(PyErrWrap)?)
}

/// The thinning `tune_svr(thin="auto")` takes for these splits (the core's rule).
#[pyfunction]
fn auto_thin(splits: Pairs) -> usize {
    tune::auto_thin(&from_pairs(splits))
}

/// Mean held-out MSE of an SVR (C, gamma) over the given (train, test) splits.
#[pyfunction]
#[pyo3(signature = (x, y, splits, *, c, gamma, epsilon = 0.1, tol = 1e-3))]
#[allow(clippy::too_many_arguments)]
fn svr_cv_mse(
    py: Python<'_>,
    x: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray1<'_, f64>,
    splits: Pairs,
    c: f64,
    gamma: f64,
    epsilon: f64,
    tol: f64,
) -> PyResult<f64> {
    let (xs, ys) = (samples(&x)?, slice1(&y)?);
    let p = SvrParams::new()
        .c(c)
        .epsilon(epsilon)
        .tol(tol)
        .gamma(thermerr_core::svr::Gamma::Value(gamma));
    let splits = from_pairs(splits);
    crate::detach(py, || tune::cv_mse(xs, ys, &splits, &p))
}

/// Native CSO/PSO search of (C, gamma) by the CV MSE over (train, test) splits; returns
/// (C, gamma, cv_mse, history, n_evals, n_fits, thin, model): n_fits the fold fits done (each point
/// met before, or stopped early, costs fewer than its folds); `thin` None: the core's
/// `auto_thin` of the splits. `progress(generation, best)` is called after
/// each generation (with the GIL), if given.
#[pyfunction]
#[pyo3(signature = (x, y, splits, *, method = "cso", c_bounds = (0.01, 1000.0), gamma_bounds = (1e-4, 10.0), scale = "log", epsilon = 0.1, tol = 1e-3, pop = 20, iters = 100, g = 10, roosters = 0.2, hens = 0.6, fl = (0.4, 1.0), w = 0.7298, c1 = 1.49618, c2 = 1.49618, vmax_frac = 0.2, seed = 0, warm_start = None, thin = None, progress = None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn tune_svr(
    py: Python<'_>,
    x: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray1<'_, f64>,
    splits: Pairs,
    method: &str,
    c_bounds: (f64, f64),
    gamma_bounds: (f64, f64),
    scale: &str,
    epsilon: f64,
    tol: f64,
    pop: usize,
    iters: usize,
    g: usize,
    roosters: f64,
    hens: f64,
    fl: (f64, f64),
    w: f64,
    c1: f64,
    c2: f64,
    vmax_frac: f64,
    seed: u64,
    warm_start: Option<bool>,
    thin: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(f64, f64, f64, Vec<f64>, usize, usize, usize, PySvrModel)> {
    let search = match self::method(
        method, pop, iters, g, roosters, hens, fl, w, c1, c2, vmax_frac, seed,
    )? {
        Method::Cso(p) => Search::Cso(p),
        Method::Pso(p) => Search::Pso(p),
    };
    let scale = match scale {
        "log" => Scale::Log,
        "linear" => Scale::Linear,
        other => {
            return Err(PyErrWrap(Error::InvalidParam {
                name: "scale",
                reason: format!("must be \"log\" or \"linear\", got {other:?}"),
            })
            .into())
        }
    };
    let (xs, ys) = (samples(&x)?, slice1(&y)?);
    let splits = from_pairs(splits);
    let tp = TuneParams {
        svr: SvrParams::new().epsilon(epsilon).tol(tol),
        c_bounds,
        gamma_bounds,
        scale,
        search,
        warm_start,
        thin: thin.unwrap_or_else(|| tune::auto_thin(&splits)),
    };
    let r = crate::detach(py, || {
        tune::tune_svr(xs, ys, &splits, &tp, |gen, best| {
            if let Some(cb) = &progress {
                Python::attach(|py| {
                    // a failing progress callback must not stop the search, but an
                    // interrupt raised in it (or while it ran) stops it like Ctrl-C
                    if let Err(e) = cb.call1(py, (gen, best)) {
                        if e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py) {
                            thermerr_core::interrupt::request();
                        }
                    }
                });
            }
        })
    })?;
    Ok((
        r.c,
        r.gamma,
        r.cv_mse,
        r.history,
        r.n_evals,
        r.cost.fits,
        r.thin,
        PySvrModel { inner: r.model },
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(swarm_minimize, m)?)?;
    m.add_function(wrap_pyfunction!(kfold, m)?)?;
    m.add_function(wrap_pyfunction!(kfold_splits, m)?)?;
    m.add_function(wrap_pyfunction!(time_series_split, m)?)?;
    m.add_function(wrap_pyfunction!(check_splits, m)?)?;
    m.add_function(wrap_pyfunction!(auto_thin, m)?)?;
    m.add_function(wrap_pyfunction!(svr_cv_mse, m)?)?;
    m.add_function(wrap_pyfunction!(tune_svr, m)?)?;
    Ok(())
}
