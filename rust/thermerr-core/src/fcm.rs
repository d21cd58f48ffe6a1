//! Fuzzy c-means (Bezdek), the sensor-clustering step of seed 003.
//!
//! The iteration is the one scikit-fuzzy's `cmeans` runs, so that the two agree number for number
//! from the same initial partition: memberships are normalised per object and floored at machine
//! epsilon before the centre update, distances are floored at epsilon (so an object that coincides
//! with a centre gets membership 1 there, to within ~eps², and nothing divides by zero), and the
//! loop stops when the Frobenius norm of the change in the partition falls below `tol`.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::linear::check_features;
use crate::samples::{Matrix, Samples};

/// Hyper-parameters of fuzzy c-means (unchecked).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FcmParams {
    pub n_clusters: usize,
    /// Weighting exponent m > 1.
    pub m: f64,
    /// Stop when ‖U⁽ᵇ⁺¹⁾ − U⁽ᵇ⁾‖_F < tol.
    pub tol: f64,
    pub max_iter: usize,
    /// Seed of the random initial partition (ignored when `init` is given).
    pub seed: Option<u64>,
    /// Initial partition, n_objects × n_clusters.
    pub init: Option<Matrix>,
}

impl FcmParams {
    pub fn new(n_clusters: usize) -> Self {
        FcmParams {
            n_clusters,
            m: 2.0,
            tol: 1e-5,
            max_iter: 1000,
            seed: None,
            init: None,
        }
    }

    fn check(&self, n: usize) -> Result<()> {
        if self.n_clusters < 2 {
            return Err(Error::param(
                "n_clusters",
                format!("must be >= 2, got {}", self.n_clusters),
            ));
        }
        if self.n_clusters > n {
            return Err(Error::param(
                "n_clusters",
                format!("{} clusters for only {n} objects", self.n_clusters),
            ));
        }
        if !(self.m > 1.0 && self.m.is_finite()) {
            return Err(Error::param("m", format!("must be > 1, got {}", self.m)));
        }
        if !(self.tol > 0.0 && self.tol.is_finite()) {
            return Err(Error::param(
                "tol",
                format!("must be > 0, got {}", self.tol),
            ));
        }
        if self.max_iter == 0 {
            return Err(Error::param("max_iter", "must be >= 1"));
        }
        if let Some(u) = &self.init {
            if u.shape != [n, self.n_clusters] {
                return Err(Error::param(
                    "init",
                    format!(
                        "must be n_objects x n_clusters = {n} x {}, got {} x {}",
                        self.n_clusters, u.shape[0], u.shape[1]
                    ),
                ));
            }
            for k in 0..n {
                let row = u.row(k);
                if row.iter().any(|v| !v.is_finite() || *v < 0.0) || row.iter().sum::<f64>() <= 0.0
                {
                    return Err(Error::param(
                        "init",
                        format!("row {k} must be non-negative with a positive sum"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Clusters the rows of `x` (each row one object).
    pub fn fit(&self, x: Samples<'_>) -> Result<FuzzyCMeans> {
        x.require_finite("X")?;
        let (n, d, c) = (x.nrows(), x.ncols(), self.n_clusters);
        self.check(n)?;
        let eps = f64::EPSILON;
        let mut u = match &self.init {
            Some(u0) => u0.data.clone(),
            None => {
                let mut rng = ChaCha8Rng::seed_from_u64(self.seed.unwrap_or(0));
                let mut u: Vec<f64> = (0..n * c).map(|_| rng.random::<f64>()).collect();
                for row in u.chunks_exact_mut(c) {
                    let s: f64 = row.iter().sum();
                    row.iter_mut().for_each(|v| *v /= s);
                }
                u
            }
        };
        let initial = Matrix {
            shape: [n, c],
            data: u.clone(),
        };
        u.iter_mut().for_each(|v| *v = v.max(eps));
        let mut um = vec![0.0; n * c];
        let mut centers = vec![0.0; c * d];
        let mut dist = vec![0.0; n * c];
        let mut u_new = vec![0.0; n * c];
        let mut history = Vec::new();
        let mut n_iter = 0;
        let mut converged = false;
        while n_iter < self.max_iter {
            // memberships of the previous step, normalised and floored, raised to m
            for (row_u, row_um) in u.chunks_exact(c).zip(um.chunks_exact_mut(c)) {
                let s: f64 = row_u.iter().sum();
                for (a, b) in row_u.iter().zip(row_um.iter_mut()) {
                    *b = (a / s).max(eps).powf(self.m);
                }
            }
            update_centers(x, &um, c, &mut centers);
            distances(x, &centers, c, &mut dist);
            dist.iter_mut().for_each(|v| *v = v.max(eps));
            let jm: f64 = um.iter().zip(&dist).map(|(w, dd)| w * dd * dd).sum();
            history.push(jm);
            memberships(&dist, c, self.m, &mut u_new);
            n_iter += 1;
            let change: f64 = u_new
                .iter()
                .zip(&u)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            std::mem::swap(&mut u, &mut u_new);
            if change < self.tol {
                converged = true;
                break;
            }
        }
        Ok(FuzzyCMeans {
            m: self.m,
            centers: Matrix {
                shape: [c, d],
                data: centers,
            },
            membership: Matrix {
                shape: [n, c],
                data: u,
            },
            initial,
            n_iter,
            converged,
            objective: history.last().copied().unwrap_or(f64::NAN),
            objective_history: history,
        })
    }
}

/// v_i = Σ_k w_ki x_k / Σ_k w_ki, in parallel over blocks of features (rows of X stay contiguous).
fn update_centers(x: Samples<'_>, w: &[f64], c: usize, centers: &mut [f64]) {
    let d = x.ncols();
    let mut wsum = vec![0.0; c];
    for row in w.chunks_exact(c) {
        for (s, v) in wsum.iter_mut().zip(row) {
            *s += v;
        }
    }
    const BLOCK: usize = 256;
    let n_blocks = d.div_ceil(BLOCK);
    let blocks: Vec<Vec<f64>> = (0..n_blocks)
        .into_par_iter()
        .map(|b| {
            let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(d));
            let mut acc = vec![0.0; c * (hi - lo)];
            for (k, row) in x.rows().enumerate() {
                let xs = &row[lo..hi];
                for i in 0..c {
                    let wk = w[k * c + i];
                    let a = &mut acc[i * (hi - lo)..(i + 1) * (hi - lo)];
                    for (dst, src) in a.iter_mut().zip(xs) {
                        *dst += wk * src;
                    }
                }
            }
            acc
        })
        .collect();
    for (b, acc) in blocks.iter().enumerate() {
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(d));
        for i in 0..c {
            for (j, v) in acc[i * (hi - lo)..(i + 1) * (hi - lo)].iter().enumerate() {
                centers[i * d + lo + j] = v / wsum[i];
            }
        }
    }
}

/// Euclidean distance of every object to every centre (n × c), in parallel over objects.
fn distances(x: Samples<'_>, centers: &[f64], c: usize, out: &mut [f64]) {
    let d = x.ncols();
    out.par_chunks_mut(c).enumerate().for_each(|(k, row)| {
        let xk = x.row(k);
        for (i, o) in row.iter_mut().enumerate() {
            *o = crate::samples::sq_dist(xk, &centers[i * d..(i + 1) * d]).sqrt();
        }
    });
}

/// u_ki = d_ki^(−2/(m−1)) / Σ_j d_kj^(−2/(m−1)), computed on distances scaled by their row
/// minimum so that the powers stay in range (distances are already floored at eps).
fn memberships(dist: &[f64], c: usize, m: f64, out: &mut [f64]) {
    let p = -2.0 / (m - 1.0);
    for (drow, urow) in dist.chunks_exact(c).zip(out.chunks_exact_mut(c)) {
        let dmin = drow.iter().copied().fold(f64::INFINITY, f64::min);
        let mut s = 0.0;
        for (dv, uv) in drow.iter().zip(urow.iter_mut()) {
            *uv = (dv / dmin).powf(p);
            s += *uv;
        }
        urow.iter_mut().for_each(|v| *v /= s);
    }
}

/// A fitted fuzzy c-means partition.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FuzzyCMeans {
    pub m: f64,
    /// Cluster centres, n_clusters × n_features.
    pub centers: Matrix,
    /// Final memberships, n_objects × n_clusters (rows sum to 1).
    pub membership: Matrix,
    /// The initial partition the iteration started from.
    pub initial: Matrix,
    pub n_iter: usize,
    pub converged: bool,
    /// J_m of the last iteration: the memberships that built the centres, against the distances
    /// to those centres (what scikit-fuzzy reports as the last entry of `jm`).
    pub objective: f64,
    pub objective_history: Vec<f64>,
}

impl FuzzyCMeans {
    pub fn n_clusters(&self) -> usize {
        self.centers.nrows()
    }

    /// Hard labels: the cluster of largest membership of each object.
    pub fn labels(&self) -> Vec<usize> {
        hard_labels(&self.membership)
    }

    /// Memberships of new objects to the fitted centres (one membership update).
    pub fn predict_membership(&self, x: Samples<'_>) -> Result<Matrix> {
        check_features(x.ncols(), self.centers.ncols())?;
        x.require_finite("X")?;
        let c = self.n_clusters();
        let mut dist = vec![0.0; x.nrows() * c];
        distances(x, &self.centers.data, c, &mut dist);
        dist.iter_mut().for_each(|v| *v = v.max(f64::EPSILON));
        let mut u = vec![0.0; x.nrows() * c];
        memberships(&dist, c, self.m, &mut u);
        Ok(Matrix {
            shape: [x.nrows(), c],
            data: u,
        })
    }
}

/// Index of the largest value of each row (ties: the first).
pub fn hard_labels(u: &Matrix) -> Vec<usize> {
    (0..u.nrows())
        .map(|k| {
            let row = u.row(k);
            let mut best = 0;
            for (i, v) in row.iter().enumerate() {
                if *v > row[best] {
                    best = i;
                }
            }
            best
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn blobs() -> Vec<f64> {
        let mut x = Vec::new();
        for (cx, cy) in [(0.0, 0.0), (5.0, 5.0), (0.0, 6.0)] {
            for k in 0..10 {
                let a = k as f64 * 0.7;
                x.extend([cx + 0.3 * a.sin(), cy + 0.3 * a.cos()]);
            }
        }
        x
    }

    #[test]
    fn separates_blobs_and_is_deterministic() {
        let x = blobs();
        let s = Samples::new(&x, 30, 2).unwrap();
        let mut p = FcmParams::new(3);
        p.seed = Some(7);
        let a = p.fit(s).unwrap();
        let b = p.fit(s).unwrap();
        assert_eq!(a, b);
        let l = a.labels();
        for g in 0..3 {
            assert!(l[g * 10..(g + 1) * 10].iter().all(|v| *v == l[g * 10]));
        }
        for k in 0..30 {
            assert_relative_eq!(
                a.membership.row(k).iter().sum::<f64>(),
                1.0,
                epsilon = 1e-12
            );
        }
        assert!(a.converged);
    }

    #[test]
    fn coinciding_point_has_membership_one() {
        // two identical points at one spot, one elsewhere: with c = 2 the centre lands on them
        let x = [0.0, 0.0, 0.0, 0.0, 10.0, 10.0];
        let mut p = FcmParams::new(2);
        p.init = Some(Matrix {
            shape: [3, 2],
            data: vec![1.0, 0.0, 1.0, 0.0, 0.0, 1.0],
        });
        let f = p.fit(Samples::new(&x, 3, 2).unwrap()).unwrap();
        assert!(f.membership.data.iter().all(|v| v.is_finite()));
        assert_relative_eq!(f.membership.row(0)[0], 1.0, epsilon = 1e-12);
        assert_relative_eq!(f.membership.row(2)[1], 1.0, epsilon = 1e-12);
    }

    #[test]
    fn refuses_bad_params() {
        let x = blobs();
        let s = Samples::new(&x, 30, 2).unwrap();
        assert!(FcmParams::new(1).fit(s).is_err());
        assert!(FcmParams::new(31).fit(s).is_err());
        let mut p = FcmParams::new(3);
        p.m = 1.0;
        assert!(p.fit(s).is_err());
        let mut p = FcmParams::new(3);
        p.init = Some(Matrix::zeros(30, 3));
        assert!(p.fit(s).is_err());
    }
}
