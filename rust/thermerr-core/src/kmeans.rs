//! Lloyd's k-means, the centre-picking stage of the two-stage RBF design.
//!
//! From the same initial centres it runs the iteration scikit-learn's `KMeans(algorithm="lloyd",
//! tol=0)` runs: assign every sample to its nearest centre and move each centre to the mean of
//! its samples, until the assignment no longer changes (or `max_iter`); if it stopped on the
//! iteration cap, the labels are recomputed for the final centres. A centre that loses all its
//! samples stays where it is (scikit-learn relocates it to a far sample instead).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::samples::{sq_dist, Matrix, Samples};

/// A k-means result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KMeans {
    pub centers: Matrix,
    pub labels: Vec<usize>,
    pub n_iter: usize,
    /// Σ of squared distances of samples to their centre.
    pub inertia: f64,
}

/// k-means++ seeding (one candidate per step), from a seed.
pub fn kmeans_plus_plus(x: Samples<'_>, k: usize, seed: u64) -> Result<Matrix> {
    let chosen = kmeans_plus_plus_indices(x, k, seed)?;
    let mut data = Vec::with_capacity(k * x.ncols());
    for &i in &chosen {
        data.extend_from_slice(x.row(i));
    }
    Ok(Matrix {
        shape: [k, x.ncols()],
        data,
    })
}

/// The sample indices [`kmeans_plus_plus`] picks, in the order it picks them (D² sampling:
/// a sample is drawn with probability proportional to its squared distance to the nearest one
/// already picked; once every sample coincides with a picked one, the first unpicked index).
pub fn kmeans_plus_plus_indices(x: Samples<'_>, k: usize, seed: u64) -> Result<Vec<usize>> {
    let n = x.nrows();
    if k == 0 || k > n {
        return Err(Error::param(
            "n_centers",
            format!("must be within 1..={n}, got {k}"),
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut chosen = vec![rng.random_range(0..n)];
    let mut d2: Vec<f64> = x.rows().map(|r| sq_dist(r, x.row(chosen[0]))).collect();
    while chosen.len() < k {
        let total: f64 = d2.iter().sum();
        let next = if total > 0.0 {
            let mut t = rng.random::<f64>() * total;
            let mut pick = n - 1;
            for (i, v) in d2.iter().enumerate() {
                if t < *v {
                    pick = i;
                    break;
                }
                t -= v;
            }
            pick
        } else {
            (0..n).find(|i| !chosen.contains(i)).unwrap_or(0)
        };
        chosen.push(next);
        for (i, r) in x.rows().enumerate() {
            d2[i] = d2[i].min(sq_dist(r, x.row(next)));
        }
    }
    Ok(chosen)
}

fn assign(x: Samples<'_>, c: &Matrix, labels: &mut [usize]) -> f64 {
    use rayon::prelude::*;
    let best: Vec<(f64, usize)> = (0..x.nrows())
        .into_par_iter()
        .map(|i| {
            let r = x.row(i);
            let mut best = (f64::INFINITY, 0);
            for j in 0..c.nrows() {
                let d = sq_dist(r, c.row(j));
                if d < best.0 {
                    best = (d, j);
                }
            }
            best
        })
        .collect();
    for (l, b) in labels.iter_mut().zip(&best) {
        *l = b.1;
    }
    best.iter().map(|b| b.0).sum()
}

/// Runs Lloyd's iteration from `init` (k × d).
pub fn kmeans(x: Samples<'_>, init: &Matrix, max_iter: usize) -> Result<KMeans> {
    x.require_finite("X")?;
    let (n, d, k) = (x.nrows(), x.ncols(), init.nrows());
    if init.ncols() != d || k == 0 || k > n {
        return Err(Error::param(
            "init",
            format!(
                "initial centres must be k x {d} with 1 <= k <= {n}, got {} x {}",
                k,
                init.ncols()
            ),
        ));
    }
    let mut centers = init.clone();
    let mut labels = vec![usize::MAX; n];
    let mut old = vec![usize::MAX; n];
    let mut n_iter = 0;
    let mut strict = false;
    for it in 0..max_iter.max(1) {
        crate::interrupt::check()?;
        n_iter = it + 1;
        assign(x, &centers, &mut labels);
        let mut sums = vec![0.0; k * d];
        let mut counts = vec![0usize; k];
        for (i, r) in x.rows().enumerate() {
            counts[labels[i]] += 1;
            for (s, v) in sums[labels[i] * d..(labels[i] + 1) * d].iter_mut().zip(r) {
                *s += v;
            }
        }
        for j in 0..k {
            if counts[j] > 0 {
                for t in 0..d {
                    centers.data[j * d + t] = sums[j * d + t] / counts[j] as f64;
                }
            }
        }
        if labels == old {
            strict = true;
            break;
        }
        old.copy_from_slice(&labels);
    }
    let inertia = if strict {
        x.rows()
            .zip(&labels)
            .map(|(r, &l)| sq_dist(r, centers.row(l)))
            .sum()
    } else {
        assign(x, &centers, &mut labels)
    };
    Ok(KMeans {
        centers,
        labels,
        n_iter,
        inertia,
    })
}
