//! Multiple linear regression: ordinary least squares with an intercept, optionally with an L2
//! penalty on the slopes (ridge, `alpha`).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
#[cfg(feature = "fit")]
use crate::linalg::lstsq;
#[cfg(feature = "fit")]
use crate::samples::check_target;
use crate::samples::Samples;

/// Hyper-parameters of [`MlrModel`]; a consuming builder with defaults, checked by
/// [`MlrParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub struct MlrParams(MlrValidParams);

/// Checked hyper-parameters; [`MlrValidParams::fit`] fits the model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MlrValidParams {
    pub fit_intercept: bool,
    /// L2 penalty α on the slopes (0: ordinary least squares); the intercept is not penalised,
    /// as in scikit-learn's `Ridge`.
    #[serde(default)]
    pub alpha: f64,
}

impl Default for MlrParams {
    /// With an intercept.
    fn default() -> Self {
        MlrParams(MlrValidParams {
            fit_intercept: true,
            alpha: 0.0,
        })
    }
}

impl MlrParams {
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether to fit an intercept (otherwise the plane goes through the origin).
    pub fn fit_intercept(mut self, v: bool) -> Self {
        self.0.fit_intercept = v;
        self
    }

    /// The L2 penalty on the slopes (ridge regression); 0 is ordinary least squares.
    pub fn alpha(mut self, v: f64) -> Self {
        self.0.alpha = v;
        self
    }

    /// `alpha` must be finite and ≥ 0.
    pub fn check(self) -> Result<MlrValidParams> {
        if !(self.0.alpha.is_finite() && self.0.alpha >= 0.0) {
            return Err(Error::param(
                "alpha",
                format!("must be a finite number >= 0, got {}", self.0.alpha),
            ));
        }
        Ok(self.0)
    }
}

/// A fitted linear model y = b + Σ_j w_j x_j.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MlrModel {
    pub coef: Vec<f64>,
    pub intercept: f64,
}

#[cfg(feature = "fit")]
impl MlrValidParams {
    /// Fits by least squares on centred data, as scikit-learn's `LinearRegression` does (centring
    /// keeps the intercept out of the conditioning of the design matrix). With `alpha` > 0 the
    /// slopes minimise ‖Aw − b‖² + α‖w‖² (scikit-learn's `Ridge`), solved as the least squares
    /// of A stacked on √α·I (b on zeros), which never forms AᵀA.
    pub fn fit(&self, x: Samples<'_>, y: &[f64]) -> Result<MlrModel> {
        x.require_finite("X")?;
        check_target(y, x.nrows())?;
        let (n, d) = (x.nrows(), x.ncols());
        let (xm, ym) = if self.fit_intercept {
            let mut xm = vec![0.0; d];
            for row in x.rows() {
                for (m, v) in xm.iter_mut().zip(row) {
                    *m += v;
                }
            }
            xm.iter_mut().for_each(|m| *m /= n as f64);
            (xm, y.iter().sum::<f64>() / n as f64)
        } else {
            (vec![0.0; d], 0.0)
        };
        let rows = if self.alpha > 0.0 { n + d } else { n };
        let root = self.alpha.sqrt();
        let a = faer::Mat::from_fn(rows, d, |i, j| {
            if i < n {
                x.get(i, j) - xm[j]
            } else if i - n == j {
                root
            } else {
                0.0
            }
        });
        let mut b: Vec<f64> = y.iter().map(|v| v - ym).collect();
        b.resize(rows, 0.0);
        let coef = lstsq(a.as_ref(), &b)?;
        let intercept = ym - coef.iter().zip(&xm).map(|(c, m)| c * m).sum::<f64>();
        Ok(MlrModel { coef, intercept })
    }
}

impl MlrModel {
    pub fn n_features(&self) -> usize {
        self.coef.len()
    }

    /// Checks a model read from a file.
    pub fn validate(&self) -> Result<()> {
        if self.coef.is_empty() {
            return Err(crate::Error::Format("mlr model: no coefficients".into()));
        }
        crate::samples::require_finite_model("mlr", "coef", &self.coef)?;
        crate::samples::require_finite_model("mlr", "intercept", &[self.intercept])
    }

    /// Predicts one sample.
    #[inline]
    pub fn predict_one(&self, x: &[f64]) -> f64 {
        self.intercept + self.coef.iter().zip(x).map(|(c, v)| c * v).sum::<f64>()
    }

    pub fn predict(&self, x: Samples<'_>) -> Result<Vec<f64>> {
        check_features(x.ncols(), self.n_features())?;
        x.require_finite("X")?;
        crate::samples::require_finite_predictions(
            "mlr",
            x.rows().map(|r| self.predict_one(r)).collect(),
        )
    }
}

/// Errors when a sample matrix has another number of columns than the model was fitted on.
pub fn check_features(got: usize, want: usize) -> Result<()> {
    if got != want {
        return Err(Error::Shape(format!(
            "X has {got} features, but the model was fitted with {want}"
        )));
    }
    Ok(())
}

#[cfg(all(test, feature = "fit"))]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn recovers_exact_plane() {
        let x: Vec<f64> = (0..20)
            .flat_map(|i| [i as f64, ((i * 7) % 5) as f64])
            .collect();
        let y: Vec<f64> = x.chunks(2).map(|r| 3.0 + 0.5 * r[0] - 2.0 * r[1]).collect();
        let m = MlrParams::new()
            .check()
            .unwrap()
            .fit(Samples::new(&x, 20, 2).unwrap(), &y)
            .unwrap();
        assert_relative_eq!(m.intercept, 3.0, epsilon = 1e-10);
        assert_relative_eq!(m.coef[0], 0.5, epsilon = 1e-12);
        assert_relative_eq!(m.coef[1], -2.0, epsilon = 1e-12);
        assert!(m.predict(Samples::new(&[1.0], 1, 1).unwrap()).is_err());
    }

    #[test]
    fn autotraits() {
        fn is_send_sync<T: Send + Sync>() {}
        is_send_sync::<MlrParams>();
        is_send_sync::<MlrValidParams>();
        is_send_sync::<MlrModel>();
    }
}
