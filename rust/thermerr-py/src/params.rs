//! What the families' `fit` entry points share. Their keywords default to `None`, which keeps the
//! core's default, so defaults live in one place; names parse through the core's `FromStr`.

use std::str::FromStr;

use pyo3::prelude::*;
use pyo3::types::PyAny;
use thermerr_core::grey::{Gm1nParams, GreyBpParams};
use thermerr_core::hybrid::HybridParams;
use thermerr_core::linear::MlrParams;
use thermerr_core::nn::{BpParams, Trainer};
use thermerr_core::rbf::RbfParams;
use thermerr_core::svr::SvrParams;
use thermerr_core::Error;

use crate::PyErrWrap;

/// Applies a builder setter when the keyword was given.
pub(crate) trait Given: Sized {
    fn given<T>(self, v: Option<T>, set: impl FnOnce(Self, T) -> Self) -> Self {
        match v {
            Some(v) => set(self, v),
            None => self,
        }
    }
}

impl<P> Given for P {}

/// A parameter enum from its name, refused as the core refuses it (`ParameterError`).
pub(crate) fn parse<T: FromStr<Err = Error>>(name: Option<&str>) -> PyResult<Option<T>> {
    Ok(name.map(str::parse).transpose().map_err(PyErrWrap)?)
}

/// The network keywords of the BP, GM + BP and hybrid models onto the family's network.
#[allow(clippy::too_many_arguments)]
pub(crate) fn net(
    p: BpParams,
    hidden: Option<Vec<usize>>,
    trainer: Option<Trainer>,
    lr: Option<f64>,
    momentum: Option<f64>,
    max_epochs: Option<usize>,
    goal: Option<f64>,
    patience: Option<usize>,
    init: Option<f64>,
    seed: Option<u64>,
) -> BpParams {
    p.given(hidden, BpParams::hidden_sizes)
        .given(trainer, BpParams::trainer)
        .given(lr, BpParams::lr)
        .given(momentum, BpParams::momentum)
        .given(max_epochs, BpParams::max_epochs)
        .given(goal, |p, g| p.goal(Some(g)))
        .given(patience, BpParams::patience)
        .given(init, BpParams::init)
        .given(seed, BpParams::seed)
}

/// The core's default hyper-parameters of a model kind (the estimators' `kind`), as checked
/// parameters serialise them.
#[pyfunction]
fn default_params<'py>(py: Python<'py>, kind: &str) -> PyResult<Bound<'py, PyAny>> {
    fn json<T: serde::Serialize>(p: thermerr_core::Result<T>) -> PyResult<String> {
        let p = p.map_err(PyErrWrap)?;
        serde_json::to_string(&p).map_err(|e| PyErrWrap(Error::Format(e.to_string())).into())
    }
    let text = match kind {
        "mlr" => json(MlrParams::new().check())?,
        "rbf" => json(RbfParams::new().check())?,
        "svr" => json(SvrParams::new().check())?,
        "bp" => json(BpParams::new().check())?,
        "greybp" => json(GreyBpParams::new().check())?,
        "gm1n" => json(Gm1nParams::new().check())?,
        "hybrid" => json(HybridParams::new().check())?,
        other => {
            return Err(PyErrWrap(Error::InvalidParam {
                name: "kind",
                reason: format!(
                    "must be \"mlr\", \"rbf\", \"svr\", \"bp\", \"greybp\", \"gm1n\" or \"hybrid\", got {other:?}"
                ),
            })
            .into())
        }
    };
    py.import("json")?.call_method1("loads", (text,))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(default_params, m)?)
}
