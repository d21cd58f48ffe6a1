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

/// Whether every value is finite: the exponent bits tested over blocks without an early exit
/// per value (which keeps a scan over a whole simulation from vectorising).
pub fn all_finite(xs: &[f64]) -> bool {
    const EXP: u64 = 0x7ff0_0000_0000_0000;
    xs.chunks(64).all(|c| {
        !c.iter()
            .fold(false, |bad, v| bad | (v.to_bits() & EXP == EXP))
    })
}

/// Σ aᵢ·bᵢ over the shorter of the two, in eight interleaved partial sums (which the compiler
/// turns into vector instructions; a single running sum cannot be reordered).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}

/// Minimises Σᵢ ((Σⱼ xⱼ·colsⱼ[i] − yᵢ)/σ)² + Σⱼ ((xⱼ − cⱼ)/sⱼ)² over the first `rows` rows: a
/// least-squares fit with a Gaussian prior (cⱼ, sⱼ) on every coefficient. The prior makes the
/// normal equations positive definite, so they are solved by Cholesky, then refined once with
/// the residual of the full system (which brings the error back to about what a QR of the
/// stacked system gives, the squared condition number notwithstanding). The columns are read
/// in place: a few passes over them instead of building and factoring the tall matrix, for the
/// narrow fits a calibration repeats at every evaluation.
pub fn lstsq_with_prior(
    cols: &[&[f64]],
    y: &[f64],
    rows: usize,
    sigma: f64,
    prior: &[(f64, f64)],
) -> Result<Vec<f64>> {
    let nb = cols.len();
    if prior.len() != nb || y.len() < rows || cols.iter().any(|c| c.len() < rows) {
        return Err(Error::Shape(
            "least squares with a prior: columns, prior and rows disagree".into(),
        ));
    }
    if nb == 0 {
        return Ok(Vec::new());
    }
    let w = 1.0 / (sigma * sigma);
    let dot = |a: &[f64], b: &[f64]| dot(&a[..rows], &b[..rows]);
    let mut gram = Mat::<f64>::zeros(nb, nb);
    for i in 0..nb {
        for j in 0..=i {
            let g = w * dot(cols[i], cols[j]);
            gram[(i, j)] = g;
            gram[(j, i)] = g;
        }
        gram[(i, i)] += 1.0 / (prior[i].1 * prior[i].1);
    }
    let chol = gram.llt(faer::Side::Lower).map_err(|_| {
        Error::Numerical(
            "least squares with a prior: the normal equations are not positive definite".into(),
        )
    })?;
    // right-hand side of the normal equations for a residual (r_data, x)
    let rhs = |r: &[f64], x: &[f64]| {
        Mat::from_fn(nb, 1, |j, _| {
            w * dot(cols[j], r) + (prior[j].0 - x[j]) / (prior[j].1 * prior[j].1)
        })
    };
    let mut x = vec![0.0; nb];
    let mut r: Vec<f64> = y[..rows].to_vec();
    for refine in [false, true] {
        if refine {
            // the data residual of the first solution, for the refinement
            for (c, xj) in cols.iter().zip(&x) {
                for (ri, ci) in r.iter_mut().zip(&c[..rows]) {
                    *ri -= xj * ci;
                }
            }
        }
        let d = chol.solve(&rhs(&r, &x));
        for (j, xj) in x.iter_mut().enumerate() {
            *xj += d[(j, 0)];
        }
    }
    if x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err(Error::Numerical(
            "least squares with a prior produced non-finite values".into(),
        ))
    }
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
    fn all_finite_finds_any_non_finite_value_anywhere() {
        let mut xs: Vec<f64> = (0..200).map(|k| k as f64 * 1e300 - 1e302).collect();
        xs.push(f64::MAX);
        xs.push(f64::MIN_POSITIVE / 2.0); // subnormal: finite
        assert!(all_finite(&xs));
        assert!(all_finite(&[]));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for at in [0, 63, 64, 150, xs.len() - 1] {
                let mut ys = xs.clone();
                ys[at] = bad;
                assert!(!all_finite(&ys), "{bad} at {at}");
                assert_eq!(all_finite(&ys), ys.iter().all(|v| v.is_finite()));
            }
        }
    }

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
    fn a_prior_fit_matches_the_stacked_qr() {
        // nearly collinear columns (a node's rise and a slower one), as in a drift map
        let n = 500;
        let c0: Vec<f64> = (0..n).map(|i| 1.0 - (-(i as f64) / 80.0).exp()).collect();
        let c1: Vec<f64> = (0..n).map(|i| 1.0 - (-(i as f64) / 95.0).exp()).collect();
        let c2: Vec<f64> = (0..n).map(|i| ((i as f64) / 37.0).sin()).collect();
        let y: Vec<f64> = (0..n)
            .map(|i| {
                3.0 * c0[i] - 2.0 * c1[i] + 0.5 * c2[i] + 1e-3 * ((i * 7919 % 101) as f64 - 50.0)
            })
            .collect();
        let (sigma, prior) = (0.05, [(1.0, 2.0), (0.0, 10.0), (0.0, 50.0)]);
        let cols = [c0.as_slice(), c1.as_slice(), c2.as_slice()];
        let x = lstsq_with_prior(&cols, &y, n, sigma, &prior).unwrap();
        // the same problem as one stacked system, by QR
        let a = Mat::from_fn(n + 3, 3, |i, j| {
            if i < n {
                cols[j][i] / sigma
            } else if i - n == j {
                1.0 / prior[j].1
            } else {
                0.0
            }
        });
        let b: Vec<f64> = (0..n + 3)
            .map(|i| {
                if i < n {
                    y[i] / sigma
                } else {
                    prior[i - n].0 / prior[i - n].1
                }
            })
            .collect();
        let q = lstsq(a.as_ref(), &b).unwrap();
        for j in 0..3 {
            // both backward stable to about eps·cond: agree far below the fit's own precision
            assert_relative_eq!(x[j], q[j], max_relative = 1e-10);
        }
    }

    #[test]
    fn singular_solve_is_an_error() {
        let a = Mat::from_fn(2, 2, |_, _| 1.0);
        assert!(solve(a.as_ref(), &[1.0, 2.0]).is_err());
    }
}
