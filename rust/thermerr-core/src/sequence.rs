//! What the models that read past errors (grey, filter) share: the checks of one streaming step
//! and the run of a streaming state over a whole series.

use crate::error::{Error, Result};

/// Checks one step: `m` finite temperatures and, if given, a finite measured previous error.
pub fn check_step(temps: &[f64], m: usize, measured_prev: Option<f64>) -> Result<()> {
    if temps.len() != m {
        return Err(Error::Shape(format!(
            "the model takes {m} temperatures, got {}",
            temps.len()
        )));
    }
    if let Some(j) = temps.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "temperatures".into(),
            row: 0,
            col: j,
        });
    }
    if measured_prev.is_some_and(|v| !v.is_finite()) {
        return Err(Error::NonFinite {
            what: "measured error".into(),
            row: 0,
            col: 0,
        });
    }
    Ok(())
}

/// Runs `push(row, measured_prev)` over the rows of `temps` (`m` per row): closed loop, or one
/// step ahead when `measured` is given (its value k−1 enters at step k).
pub fn run_series(
    kind: &str,
    temps: &[f64],
    m: usize,
    measured: Option<&[f64]>,
    mut push: impl FnMut(&[f64], Option<f64>) -> Result<f64>,
) -> Result<Vec<f64>> {
    if m == 0 || temps.len() % m != 0 {
        return Err(Error::Shape(format!(
            "the model takes {m} temperatures per sample"
        )));
    }
    let n = temps.len() / m;
    if let Some(y) = measured {
        if y.len() != n {
            return Err(Error::Shape(format!(
                "{n} samples but {} measured errors",
                y.len()
            )));
        }
    }
    (0..n)
        .map(|k| {
            let prev = measured.filter(|_| k > 0).map(|y| y[k - 1]);
            push(&temps[k * m..(k + 1) * m], prev).and_then(|y| {
                if y.is_finite() {
                    Ok(y)
                } else {
                    Err(crate::samples::non_finite_prediction(kind, Some(k), y))
                }
            })
        })
        .collect()
}
