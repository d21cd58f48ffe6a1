//! Figures of merit shared by every model and report (methods.md, "Figures of merit").

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The seeds' figures of merit for one residual series `r = measured − predicted`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scores {
    /// Number of samples scored.
    pub n: usize,
    /// Root mean square of the residual.
    pub rms: f64,
    /// Largest absolute residual.
    pub max_abs: f64,
    /// Residual band: max(r) − min(r).
    pub band: f64,
    /// Smallest and largest residual.
    pub min_residual: f64,
    pub max_residual: f64,
    /// Mean over the kept samples of 1 − |r|/|e|; `None` when every sample was left out.
    pub mean_accuracy: Option<f64>,
    /// Indices left out of the mean accuracy because |e| ≤ `zero_tol`.
    pub accuracy_excluded: Vec<usize>,
    /// The threshold used for "near zero" measured error.
    pub zero_tol: f64,
    /// 1 − RMS(r) / RMS(e): the share of the error a compensation would remove.
    /// `None` when the measured error is identically zero.
    pub compensation_rate: Option<f64>,
    /// RMS of the measured error (the "before compensation" figure).
    pub rms_measured: f64,
}

/// Default "near zero" threshold for the mean accuracy, as a share of max |e|.
pub const DEFAULT_ZERO_FRACTION: f64 = 0.05;

/// Root mean square of a series (0 for an empty one).
pub fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// RMS of a stream of values, summed in order; NaN for none (nothing to score).
pub fn rms_of(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x * x;
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        (s / n as f64).sqrt()
    }
}

/// The least and the greatest of a stream of values ((+∞, −∞) for none; a NaN is passed
/// over, as `f64::min` and `f64::max` pass it over).
pub fn min_max(v: impl IntoIterator<Item = f64>) -> (f64, f64) {
    v.into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
}

/// Scores `predicted` against `measured`. `zero_tol` is the |e| at or below which a sample is left
/// out of the mean accuracy; `None` takes 5 % of max |e|.
pub fn scores(measured: &[f64], predicted: &[f64], zero_tol: Option<f64>) -> Result<Scores> {
    if measured.len() != predicted.len() {
        return Err(Error::Shape(format!(
            "measured has {} values but predicted has {}",
            measured.len(),
            predicted.len()
        )));
    }
    if measured.is_empty() {
        return Err(Error::Shape("cannot score an empty series".into()));
    }
    for (what, v) in [("measured", measured), ("predicted", predicted)] {
        if let Some(k) = v.iter().position(|t| !t.is_finite()) {
            return Err(Error::NonFinite {
                what: what.into(),
                row: k,
                col: 0,
            });
        }
    }
    if let Some(t) = zero_tol {
        if !(t >= 0.0 && t.is_finite()) {
            return Err(Error::param(
                "zero_tol",
                format!("must be finite and >= 0, got {t}"),
            ));
        }
    }
    let n = measured.len();
    let emax = measured.iter().fold(0.0_f64, |a, e| a.max(e.abs()));
    let zero_tol = zero_tol.unwrap_or(DEFAULT_ZERO_FRACTION * emax);
    let mut sum_sq = 0.0;
    let mut sum_sq_e = 0.0;
    let (mut rmin, mut rmax, mut amax) = (f64::INFINITY, f64::NEG_INFINITY, 0.0_f64);
    let mut acc_sum = 0.0;
    let mut excluded = Vec::new();
    for (k, (&e, &p)) in measured.iter().zip(predicted).enumerate() {
        let r = e - p;
        sum_sq += r * r;
        sum_sq_e += e * e;
        rmin = rmin.min(r);
        rmax = rmax.max(r);
        amax = amax.max(r.abs());
        if e.abs() <= zero_tol {
            excluded.push(k);
        } else {
            acc_sum += 1.0 - r.abs() / e.abs();
        }
    }
    let kept = n - excluded.len();
    let rms = (sum_sq / n as f64).sqrt();
    let rms_measured = (sum_sq_e / n as f64).sqrt();
    Ok(Scores {
        n,
        rms,
        max_abs: amax,
        band: rmax - rmin,
        min_residual: rmin,
        max_residual: rmax,
        mean_accuracy: (kept > 0).then(|| acc_sum / kept as f64),
        accuracy_excluded: excluded,
        zero_tol,
        compensation_rate: (rms_measured > 0.0).then(|| 1.0 - rms / rms_measured),
        rms_measured,
    })
}

/// Pearson's correlation of two series over their common length; 0 when either is constant or
/// shorter than two.
pub fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()) as f64;
    if n < 2.0 {
        return 0.0;
    }
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma).powi(2);
        sbb += (y - mb).powi(2);
    }
    if saa <= 0.0 || sbb <= 0.0 {
        0.0
    } else {
        sab / (saa * sbb).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn hand_computed() {
        let e = [10.0, 20.0, 0.1, -10.0];
        let p = [9.0, 22.0, 0.0, -10.5];
        let s = scores(&e, &p, None).unwrap();
        // residuals 1, −2, 0.1, 0.5
        assert_relative_eq!(s.rms, ((1.0 + 4.0 + 0.01 + 0.25) / 4.0_f64).sqrt());
        assert_relative_eq!(s.max_abs, 2.0);
        assert_relative_eq!(s.band, 3.0);
        // 0.1 <= 5 % of 20 is left out of the accuracy
        assert_eq!(s.accuracy_excluded, vec![2]);
        let acc = ((1.0 - 0.1) + (1.0 - 0.1) + (1.0 - 0.05)) / 3.0;
        assert_relative_eq!(s.mean_accuracy.unwrap(), acc);
        let rms_e = ((100.0 + 400.0 + 0.01 + 100.0) / 4.0_f64).sqrt();
        assert_relative_eq!(s.compensation_rate.unwrap(), 1.0 - s.rms / rms_e);
    }

    #[test]
    fn refuses_bad_input() {
        assert!(scores(&[], &[], None).is_err());
        assert!(scores(&[1.0], &[1.0, 2.0], None).is_err());
        assert!(scores(&[1.0, f64::NAN], &[1.0, 2.0], None).is_err());
    }
}
