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

/// Minimises ‖Σⱼ xⱼ·colsⱼ − b‖₂ as [`lstsq`] does (QR where the columns have full rank, else the
/// SVD's minimum-norm solution with numpy's cut-off), on nalgebra's unblocked Householder QR and
/// SVD, whose order of operations is fixed by the code (no CPU-dispatched kernels): the same bits
/// on every machine. For the thermal network's fits, whose verdicts on a real run move with the
/// last bits; the estimators keep faer's faster blocked [`lstsq`].
pub fn lstsq_columns(cols: &[&[f64]], b: &[f64]) -> Result<Vec<f64>> {
    let mut x = lstsq_columns_many(cols, &[b])?;
    Ok(x.pop().expect("one solution per right-hand side"))
}

/// [`lstsq_columns`] for several right-hand sides on the same columns: one factorisation, then
/// each `b` solved as [`lstsq_columns`] would solve it alone (the same bits). On a 1-Hz log of
/// days the factorisation of a long matrix is the cost, and the screening asks the same basis
/// about every temperature.
pub fn lstsq_columns_many(cols: &[&[f64]], bs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
    let n = cols.len();
    let m = cols.first().map_or(0, |c| c.len());
    if cols.iter().any(|c| c.len() != m) || bs.iter().any(|b| b.len() != m) {
        return Err(Error::Shape(format!(
            "least squares: columns of {m} rows but a column or right-hand side of another length"
        )));
    }
    if m == 0 || n == 0 || bs.is_empty() {
        return Err(Error::Shape("least squares on an empty system".into()));
    }
    if !bs.iter().all(|b| all_finite(b)) || !cols.iter().all(|c| all_finite(c)) {
        return Err(Error::Numerical(
            "least squares on a system with non-finite values".into(),
        ));
    }
    let matrix = || nalgebra::DMatrix::from_fn(m, n, |i, j| cols[j][i]);
    let tol = f64::EPSILON * m.max(n) as f64;
    if m >= n {
        let scale = cols
            .iter()
            .map(|c| dot(c, c).sqrt())
            .fold(0.0_f64, f64::max);
        let qr = matrix().qr();
        let r = qr.r();
        let full_rank = scale > 0.0 && (0..n).all(|i| r[(i, i)].abs() > tol * scale * 1e3);
        if full_rank {
            return bs
                .iter()
                .map(|b| {
                    let mut qtb = nalgebra::DVector::from_column_slice(b);
                    qr.q_tr_mul(&mut qtb);
                    let top = qtb.rows(0, n).into_owned();
                    let x = r
                        .solve_upper_triangular(&top)
                        .ok_or_else(|| Error::Numerical("least squares: R is singular".into()))?;
                    finite(x.iter().copied().collect(), "least squares")
                })
                .collect();
        }
    }
    // a bounded number of sweeps: nalgebra's `svd` would loop until convergence
    let svd = matrix()
        .try_svd(true, true, f64::EPSILON, 10_000)
        .ok_or_else(|| Error::Numerical("SVD did not converge".into()))?;
    let smax = svd.singular_values.max();
    if smax == 0.0 {
        return Err(Error::Numerical(
            "least squares on an all-zero matrix".into(),
        ));
    }
    bs.iter()
        .map(|b| {
            let x = svd
                .solve(&nalgebra::DVector::from_column_slice(b), tol * smax)
                .map_err(|e| Error::Numerical(format!("least squares: {e}")))?;
            finite(x.iter().copied().collect(), "least squares")
        })
        .collect()
}

fn finite(v: Vec<f64>, what: &str) -> Result<Vec<f64>> {
    if v.iter().all(|t| t.is_finite()) {
        Ok(v)
    } else {
        Err(Error::Numerical(format!(
            "{what} produced non-finite values"
        )))
    }
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
/// turns into vector instructions; a single running sum cannot be reordered). The order of the
/// operations is fixed by this code alone, not by the CPU: the same bits on every machine.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; LANES];
    let body = n / LANES * LANES;
    lanes_add(&mut acc, &a[..body], &b[..body]);
    lanes_finish(&acc, &a[body..], &b[body..])
}

const LANES: usize = 8;

/// accᵢ += Σ over the rows k ≡ i (mod 8) of aₖ·bₖ, row by row (`a.len()` a multiple of 8)
#[inline(always)]
fn lanes_add(acc: &mut [f64; LANES], a: &[f64], b: &[f64]) {
    for (x, y) in a.chunks_exact(LANES).zip(b.chunks_exact(LANES)) {
        for k in 0..LANES {
            acc[k] += x[k] * y[k];
        }
    }
}

/// The partial sums combined, plus the rows past the last full group of eight.
#[inline(always)]
fn lanes_finish(acc: &[f64; LANES], ta: &[f64], tb: &[f64]) -> f64 {
    let tail: f64 = ta.iter().zip(tb).map(|(x, y)| x * y).sum();
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}

/// The Gram matrix CᵀC of `cols` over their first `rows` entries, n × n row-major, each entry
/// exactly [`dot`] of its two columns (the same bits): the products are accumulated over blocks
/// of rows that stay in cache, in the same order as one `dot` after the other would. Where the
/// CPU has AVX2 the same operations run four lanes at a time (no fused multiply-add: the
/// result does not depend on the CPU). It replaces a BLAS product whose kernels, and so whose
/// rounding, differ between CPUs (faer-rs #134): a calibration's verdicts on a real run move
/// with the last bits.
pub fn gram(cols: &[&[f64]], rows: usize) -> Result<Vec<f64>> {
    if cols.iter().any(|c| c.len() < rows) {
        return Err(Error::Shape(format!(
            "Gram matrix: a column is shorter than {rows} rows"
        )));
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked on the line above
        return Ok(unsafe { gram_avx2(cols, rows) });
    }
    Ok(gram_lanes(cols, rows))
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn gram_avx2(cols: &[&[f64]], rows: usize) -> Vec<f64> {
    gram_lanes(cols, rows)
}

#[inline(always)]
fn gram_lanes(cols: &[&[f64]], rows: usize) -> Vec<f64> {
    // rows per block: n columns of it stay in the first-level cache
    const BLOCK: usize = 64;
    let n = cols.len();
    let body = rows / LANES * LANES;
    // the accumulators of the lower triangle's pairs (i, j ≤ i), row after row of it
    let mut acc = vec![[0.0; LANES]; n * (n + 1) / 2];
    let mut lo = 0;
    while lo < body {
        let hi = (lo + BLOCK).min(body);
        let mut p = 0;
        for i in 0..n {
            let a = &cols[i][lo..hi];
            let row = &mut acc[p..p + i + 1];
            // four pairs at a time: column i's values loaded once for four others
            let mut quads = row.chunks_exact_mut(4);
            let mut j = 0;
            for q in &mut quads {
                let b = [0, 1, 2, 3].map(|d| &cols[j + d][lo..hi]);
                lanes_add4(q, a, b);
                j += 4;
            }
            for (s, c) in quads.into_remainder().iter_mut().zip(&cols[j..=i]) {
                lanes_add(s, a, &c[lo..hi]);
            }
            p += i + 1;
        }
        lo = hi;
    }
    let mut g = vec![0.0; n * n];
    let mut p = 0;
    for i in 0..n {
        for j in 0..=i {
            let v = lanes_finish(&acc[p], &cols[i][body..rows], &cols[j][body..rows]);
            g[i * n + j] = v;
            g[j * n + i] = v;
            p += 1;
        }
    }
    g
}

/// [`lanes_add`] for four pairs (a, b₀..b₃) at once, each accumulator in the same order.
#[inline(always)]
fn lanes_add4(acc: &mut [[f64; LANES]], a: &[f64], b: [&[f64]; 4]) {
    let mut s = [acc[0], acc[1], acc[2], acc[3]];
    for (g, x) in a.chunks_exact(LANES).enumerate() {
        let o = g * LANES;
        for (sd, bd) in s.iter_mut().zip(&b) {
            let y = &bd[o..o + LANES];
            for k in 0..LANES {
                sd[k] += x[k] * y[k];
            }
        }
    }
    acc[..4].copy_from_slice(&s);
}

/// The Cholesky factor L (A = L·Lᵀ) of a symmetric positive definite n × n matrix, computed
/// and applied in a fixed order of operations (the same bits on every CPU; the systems here
/// are a few dozen unknowns).
pub struct Cholesky {
    n: usize,
    /// row-major, lower triangle
    l: Vec<f64>,
}

impl Cholesky {
    /// Factors `a` (row-major; only its lower triangle is read). `None` if A is not positive
    /// definite to working precision (or not n × n).
    pub fn new(a: &[f64], n: usize) -> Option<Cholesky> {
        if a.len() != n * n {
            return None;
        }
        let mut l = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                let mut s = a[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k];
                }
                if i == j {
                    // also false for NaN
                    if !(s > 0.0 && s.is_finite()) {
                        return None;
                    }
                    l[i * n + i] = s.sqrt();
                } else {
                    l[i * n + j] = s / l[j * n + j];
                }
            }
        }
        Some(Cholesky { n, l })
    }

    /// x with A x = b (`b` of length n).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let (n, l) = (self.n, &self.l);
        let mut x = b.to_vec();
        for i in 0..n {
            let mut s = x[i];
            for k in 0..i {
                s -= l[i * n + k] * x[k];
            }
            x[i] = s / l[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = x[i];
            for k in i + 1..n {
                s -= l[k * n + i] * x[k];
            }
            x[i] = s / l[i * n + i];
        }
        x
    }
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
    // w·CᵀC plus the prior's precision on the diagonal (each entry `dot`'s bits, as before)
    let mut gram = gram(cols, rows)?;
    for g in gram.iter_mut() {
        *g *= w;
    }
    for (i, p) in prior.iter().enumerate() {
        gram[i * nb + i] += 1.0 / (p.1 * p.1);
    }
    let chol = Cholesky::new(&gram, nb).ok_or_else(|| {
        Error::Numerical(
            "least squares with a prior: the normal equations are not positive definite".into(),
        )
    })?;
    // right-hand side of the normal equations for a residual (r_data, x)
    let rhs = |r: &[f64], x: &[f64]| -> Vec<f64> {
        (0..nb)
            .map(|j| w * dot(cols[j], r) + (prior[j].0 - x[j]) / (prior[j].1 * prior[j].1))
            .collect()
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
        for (xj, dj) in x.iter_mut().zip(d) {
            *xj += dj;
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
    finite((0..x.nrows()).map(|i| x[(i, 0)]).collect(), what)
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

    /// Columns of awkward lengths (not multiples of the lanes or the block) and sizes.
    fn columns(n: usize, rows: usize) -> Vec<Vec<f64>> {
        (0..n)
            .map(|j| {
                (0..rows)
                    .map(|i| {
                        ((i * 7919 + j * 104_729) % 1009) as f64 / 97.0 - 5.0 + 1e-9 * i as f64
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn gram_is_every_pair_s_dot_to_the_bit() {
        for (n, rows) in [(1, 1), (3, 7), (5, 64), (7, 65), (23, 1945), (30, 11_671)] {
            let cols = columns(n, rows + 3);
            let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
            let g = gram(&refs, rows).unwrap();
            for i in 0..n {
                for j in 0..n {
                    let want = dot(&cols[i][..rows], &cols[j][..rows]);
                    assert_eq!(
                        g[i * n + j].to_bits(),
                        want.to_bits(),
                        "{n}x{rows} ({i}, {j})"
                    );
                }
            }
            // the lanes without AVX2 give the same bits as the dispatched kernel
            assert_eq!(gram_lanes(&refs, rows), g);
        }
        assert!(gram(&[&[1.0, 2.0][..]], 3).is_err());
    }

    #[test]
    fn cholesky_solves_and_refuses_what_is_not_positive_definite() {
        // A = MᵀM + I for a random-ish M: SPD; check A·x = b
        let n = 12;
        let cols = columns(n, 40);
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let mut a = gram(&refs, 40).unwrap();
        for i in 0..n {
            a[i * n + i] += 1.0;
        }
        let b: Vec<f64> = (0..n).map(|i| i as f64 - 4.5).collect();
        let x = Cholesky::new(&a, n).unwrap().solve(&b);
        for i in 0..n {
            let ax: f64 = (0..n).map(|j| a[i * n + j] * x[j]).sum();
            assert_relative_eq!(ax, b[i], epsilon = 1e-9, max_relative = 1e-9);
        }
        assert!(Cholesky::new(&[1.0, 2.0, 2.0, 1.0], 2).is_none()); // indefinite
        assert!(Cholesky::new(&[f64::NAN], 1).is_none());
        assert!(Cholesky::new(&[1.0, 0.0, 0.0], 2).is_none()); // not n x n
    }

    #[test]
    fn lstsq_columns_agrees_with_faer_s_lstsq() {
        // full rank, tall: the same solution to rounding (1e-9 relative: both are backward
        // stable QR solutions of a system with a condition number of about 1e2)
        let cols = columns(6, 500);
        let b: Vec<f64> = (0..500).map(|i| (i as f64 / 30.0).sin() * 3.0).collect();
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let a = Mat::from_fn(500, 6, |i, j| cols[j][i]);
        let want = lstsq(a.as_ref(), &b).unwrap();
        let got = lstsq_columns(&refs, &b).unwrap();
        for (g, w) in got.iter().zip(&want) {
            assert_relative_eq!(g, w, epsilon = 1e-9, max_relative = 1e-9);
        }
        // two identical columns: the minimum-norm solution, as numpy's lstsq gives
        let c: Vec<f64> = (0..4).map(|i| (i + 1) as f64).collect();
        let b: Vec<f64> = c.iter().map(|v| 2.0 * v).collect();
        let x = lstsq_columns(&[&c[..], &c[..]], &b).unwrap();
        assert_relative_eq!(x[0], 1.0, epsilon = 1e-10);
        assert_relative_eq!(x[1], 1.0, epsilon = 1e-10);
        assert!(lstsq_columns(&[&c[..3]], &b).is_err());
        let nan = [1.0, f64::NAN, 2.0, 3.0];
        assert!(lstsq_columns(&[&nan[..]], &b).is_err());
        assert!(lstsq_columns(&[&c[..]], &nan).is_err());
        assert!(lstsq_columns(&[&[0.0; 4][..]], &[0.0; 4]).is_err());
    }

    #[test]
    fn several_right_hand_sides_solve_as_each_alone() {
        // one factorisation for all: each solution the same bits as its own call, on the QR
        // path (full rank) and on the SVD path (two identical columns)
        let cols = columns(5, 300);
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let bs: Vec<Vec<f64>> = (1..4)
            .map(|k| {
                (0..300)
                    .map(|i| (i as f64 / (10.0 * k as f64)).cos())
                    .collect()
            })
            .collect();
        let brefs: Vec<&[f64]> = bs.iter().map(Vec::as_slice).collect();
        let many = lstsq_columns_many(&refs, &brefs).unwrap();
        for (x, b) in many.iter().zip(&bs) {
            assert_eq!(x, &lstsq_columns(&refs, b).unwrap());
        }
        let twice = [refs[0], refs[0], refs[1]];
        let many = lstsq_columns_many(&twice, &brefs).unwrap();
        for (x, b) in many.iter().zip(&bs) {
            assert_eq!(x, &lstsq_columns(&twice, b).unwrap());
        }
        // a right-hand side of another length, or none at all, is refused
        assert!(lstsq_columns_many(&refs, &[&bs[0][..299]]).is_err());
        assert!(lstsq_columns_many(&refs, &[]).is_err());
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
