//! Dense least squares and solves on faer, with rank checks instead of silent garbage.

use faer::linalg::solvers::{Solve, SolveLstsq};
use faer::{Mat, MatRef};

use crate::error::{Error, Result};

/// Minimises ‖A x − b‖₂. Full column rank: column-pivoted QR. Rank deficient (or wide): the
/// minimum-norm solution from the SVD with numpy's default cut-off `eps · max(m, n) · σ_max`,
/// which is what `numpy.linalg.lstsq` / `scipy.linalg.lstsq` return.
pub fn lstsq(a: MatRef<'_, f64>, b: &[f64]) -> Result<Vec<f64>> {
    let (m, n) = (a.nrows(), a.ncols());
    if b.len() != m {
        return Err(Error::Shape(format!(
            "least squares: {m} equations but {} right-hand sides",
            b.len()
        )));
    }
    if m == 0 || n == 0 {
        return Err(Error::Shape("least squares on an empty system".into()));
    }
    let rhs = Mat::from_fn(m, 1, |i, _| b[i]);
    let tol = f64::EPSILON * m.max(n) as f64;
    if m >= n {
        // blocked Householder QR without pivoting (much faster than column pivoting on tall
        // systems); a diagonal of R that is tiny against the column norms means rank deficiency,
        // and the SVD below takes over
        let qr = a.qr();
        let r = qr.thin_R();
        let col_norm = |j: usize| (0..m).map(|i| a[(i, j)] * a[(i, j)]).sum::<f64>().sqrt();
        let scale = (0..n).map(col_norm).fold(0.0_f64, f64::max);
        let full_rank = scale > 0.0 && (0..n).all(|i| r[(i, i)].abs() > tol * scale * 1e3);
        if full_rank {
            let x = qr.solve_lstsq(&rhs);
            return finite_vec(x.as_ref(), "least squares");
        }
    }
    let svd = a
        .thin_svd()
        .map_err(|e| Error::Numerical(format!("SVD did not converge: {e:?}")))?;
    let s = svd.S().column_vector();
    let smax = (0..s.nrows()).map(|i| s[i]).fold(0.0_f64, f64::max);
    if smax == 0.0 {
        return Err(Error::Numerical(
            "least squares on an all-zero matrix".into(),
        ));
    }
    let (u, v) = (svd.U(), svd.V());
    let mut x = vec![0.0; n];
    for k in 0..s.nrows() {
        if s[k] <= tol * smax {
            continue;
        }
        let coef: f64 = (0..m).map(|i| u[(i, k)] * b[i]).sum::<f64>() / s[k];
        for (j, xj) in x.iter_mut().enumerate() {
            *xj += coef * v[(j, k)];
        }
    }
    Ok(x)
}

/// Solves the square system A x = b by LU with partial pivoting; errors if A is singular to
/// working precision.
pub fn solve(a: MatRef<'_, f64>, b: &[f64]) -> Result<Vec<f64>> {
    let n = a.nrows();
    if a.ncols() != n || b.len() != n {
        return Err(Error::Shape(format!(
            "solve: matrix {} x {} with {} right-hand sides",
            a.nrows(),
            a.ncols(),
            b.len()
        )));
    }
    let lu = a.partial_piv_lu();
    let u = lu.U();
    let umax = (0..n).map(|i| u[(i, i)].abs()).fold(0.0_f64, f64::max);
    if (0..n).any(|i| u[(i, i)].abs() <= f64::EPSILON * n as f64 * umax) || umax == 0.0 {
        return Err(Error::Numerical(
            "the system is singular to working precision (duplicate samples or a spread so large \
             that the basis functions coincide?)"
                .into(),
        ));
    }
    let rhs = Mat::from_fn(n, 1, |i, _| b[i]);
    finite_vec(lu.solve(&rhs).as_ref(), "linear solve")
}

fn finite_vec(x: MatRef<'_, f64>, what: &str) -> Result<Vec<f64>> {
    let v: Vec<f64> = (0..x.nrows()).map(|i| x[(i, 0)]).collect();
    if v.iter().all(|t| t.is_finite()) {
        Ok(v)
    } else {
        Err(Error::Numerical(format!(
            "{what} produced non-finite values"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn overdetermined_full_rank() {
        // y = 1 + 2a − 3b exactly
        let a = Mat::from_fn(5, 3, |i, j| match j {
            0 => 1.0,
            1 => i as f64,
            _ => (i * i) as f64,
        });
        let b: Vec<f64> = (0..5)
            .map(|i| 1.0 + 2.0 * i as f64 - 3.0 * (i * i) as f64)
            .collect();
        let x = lstsq(a.as_ref(), &b).unwrap();
        assert_relative_eq!(x[0], 1.0, epsilon = 1e-10);
        assert_relative_eq!(x[1], 2.0, epsilon = 1e-10);
        assert_relative_eq!(x[2], -3.0, epsilon = 1e-10);
    }

    #[test]
    fn rank_deficient_gives_min_norm() {
        // two identical columns: the minimum-norm solution splits the weight evenly
        let a = Mat::from_fn(4, 2, |i, _| (i + 1) as f64);
        let b: Vec<f64> = (0..4).map(|i| 2.0 * (i + 1) as f64).collect();
        let x = lstsq(a.as_ref(), &b).unwrap();
        assert_relative_eq!(x[0], 1.0, epsilon = 1e-10);
        assert_relative_eq!(x[1], 1.0, epsilon = 1e-10);
    }

    #[test]
    fn singular_solve_is_an_error() {
        let a = Mat::from_fn(2, 2, |_, _| 1.0);
        assert!(solve(a.as_ref(), &[1.0, 2.0]).is_err());
    }
}
