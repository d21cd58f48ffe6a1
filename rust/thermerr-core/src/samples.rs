//! Row-major views of sample matrices (rows are samples, columns are features) and the owned,
//! serialisable matrix that fitted models store.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A borrowed row-major `n × d` matrix.
#[derive(Clone, Copy, Debug)]
pub struct Samples<'a> {
    data: &'a [f64],
    n: usize,
    d: usize,
}

impl<'a> Samples<'a> {
    /// Wraps `data` as `n` rows of `d` columns; errors when the length does not match.
    pub fn new(data: &'a [f64], n: usize, d: usize) -> Result<Self> {
        if n.checked_mul(d) != Some(data.len()) {
            return Err(Error::Shape(format!(
                "a {n} x {d} matrix needs {} values, got {}",
                n.saturating_mul(d),
                data.len()
            )));
        }
        Ok(Samples { data, n, d })
    }

    pub fn nrows(&self) -> usize {
        self.n
    }

    pub fn ncols(&self) -> usize {
        self.d
    }

    pub fn as_slice(&self) -> &'a [f64] {
        self.data
    }

    #[inline]
    pub fn row(&self, i: usize) -> &'a [f64] {
        &self.data[i * self.d..(i + 1) * self.d]
    }

    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.d + j]
    }

    pub fn rows(&self) -> impl Iterator<Item = &'a [f64]> + '_ {
        self.data.chunks_exact(self.d.max(1)).take(self.n)
    }

    /// Errors unless there is at least one row and one column and every value is finite.
    pub fn require_finite(&self, what: &str) -> Result<()> {
        if self.n == 0 || self.d == 0 {
            return Err(Error::Shape(format!(
                "{what} is empty ({} x {})",
                self.n, self.d
            )));
        }
        check_finite(self.data, self.d, what)
    }

    /// A faer view of the same memory.
    #[cfg(feature = "fit")]
    pub fn as_faer(&self) -> faer::MatRef<'a, f64> {
        faer::MatRef::from_row_major_slice(self.data, self.n, self.d)
    }

    pub fn to_matrix(&self) -> Matrix {
        Matrix {
            shape: [self.n, self.d],
            data: self.data.to_vec(),
        }
    }
}

/// Errors naming the first non-finite value of a row-major buffer with `d` columns.
pub fn check_finite(data: &[f64], d: usize, what: &str) -> Result<()> {
    match data.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(k) => Err(Error::NonFinite {
            what: what.to_string(),
            row: k / d.max(1),
            col: k % d.max(1),
        }),
    }
}

/// Errors unless `y` is non-empty, finite and of length `n`.
pub fn check_target(y: &[f64], n: usize) -> Result<()> {
    if y.len() != n {
        return Err(Error::Shape(format!(
            "X has {n} rows but y has {} values",
            y.len()
        )));
    }
    check_finite(y, 1, "y")
}

/// Refuses a model file whose `field` holds a non-finite number (serde_json reads `1e999` as
/// infinity).
pub fn require_finite_model(kind: &str, field: &str, v: &[f64]) -> crate::Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(crate::Error::Format(format!(
            "{kind} model: {field}[{i}] is not a finite number"
        ))),
        None => Ok(()),
    }
}

/// Refuses predictions that are not finite numbers: a model whose numbers overflow on this
/// input (a model file with coefficients near the f64 limit, inputs far outside the training
/// range) is an error naming the first such sample (0-based), never an `inf` handed on.
pub fn require_finite_predictions(kind: &str, y: Vec<f64>) -> crate::Result<Vec<f64>> {
    match y.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(non_finite_prediction(kind, Some(i), y[i])),
        None => Ok(y),
    }
}

/// The error of [`require_finite_predictions`] (for one sample of a batch when `sample` is
/// given, for the sample at hand when streaming).
pub fn non_finite_prediction(kind: &str, sample: Option<usize>, y: f64) -> crate::Error {
    let which = sample.map_or(String::new(), |i| format!(" for sample {i}"));
    crate::Error::Numerical(format!(
        "{kind} model: the prediction{which} is not a finite number ({y}): \
         the model's numbers overflow on this input"
    ))
}

/// An owned row-major matrix, serialised as `{"shape": [r, c], "data": [...]}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawMatrix")]
pub struct Matrix {
    pub shape: [usize; 2],
    pub data: Vec<f64>,
}

#[derive(Deserialize)]
struct RawMatrix {
    shape: [usize; 2],
    data: Vec<f64>,
}

impl TryFrom<RawMatrix> for Matrix {
    type Error = String;
    fn try_from(raw: RawMatrix) -> std::result::Result<Self, String> {
        if raw.shape[0].checked_mul(raw.shape[1]) != Some(raw.data.len()) {
            return Err(format!(
                "matrix of shape {:?} holds {} values",
                raw.shape,
                raw.data.len()
            ));
        }
        Ok(Matrix {
            shape: raw.shape,
            data: raw.data,
        })
    }
}

impl Matrix {
    pub fn zeros(r: usize, c: usize) -> Self {
        Matrix {
            shape: [r, c],
            data: vec![0.0; r * c],
        }
    }

    pub fn nrows(&self) -> usize {
        self.shape[0]
    }

    pub fn ncols(&self) -> usize {
        self.shape[1]
    }

    pub fn view(&self) -> Samples<'_> {
        Samples {
            data: &self.data,
            n: self.shape[0],
            d: self.shape[1],
        }
    }

    #[inline]
    pub fn row(&self, i: usize) -> &[f64] {
        let d = self.shape[1];
        &self.data[i * d..(i + 1) * d]
    }

    #[cfg(feature = "fit")]
    pub fn from_faer(m: faer::MatRef<'_, f64>) -> Self {
        let (r, c) = (m.nrows(), m.ncols());
        let mut data = Vec::with_capacity(r * c);
        for i in 0..r {
            for j in 0..c {
                data.push(m[(i, j)]);
            }
        }
        Matrix {
            shape: [r, c],
            data,
        }
    }
}

#[inline]
/// Squared Euclidean distance of two equally long slices.
pub fn sq_dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_mismatch_is_an_error() {
        assert!(Samples::new(&[1.0, 2.0, 3.0], 2, 2).is_err());
    }

    #[test]
    fn non_finite_is_located() {
        let x = [1.0, 2.0, 3.0, f64::NAN];
        let s = Samples::new(&x, 2, 2).unwrap();
        let e = s.require_finite("X").unwrap_err().to_string();
        assert!(e.contains("row 1, column 1"), "{e}");
    }

    #[test]
    fn matrix_json_checks_its_shape() {
        let bad = r#"{"shape":[2,2],"data":[1,2,3]}"#;
        assert!(serde_json::from_str::<Matrix>(bad).is_err());
        let good = r#"{"shape":[1,2],"data":[1,2]}"#;
        assert_eq!(
            serde_json::from_str::<Matrix>(good).unwrap().row(0),
            &[1.0, 2.0]
        );
    }
}
