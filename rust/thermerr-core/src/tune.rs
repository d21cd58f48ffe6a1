//! Hyper-parameter search of an ε-SVR (seed 004): chicken swarm optimisation (or PSO) over
//! (C, γ), minimising the k-fold cross-validated mean squared error. The objective is evaluated
//! natively: each generation's population × folds SVR fits run in parallel (rayon).

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::samples::{check_target, Samples};
use crate::svr::{Gamma, KernelKind, SvrModel, SvrParams};
use crate::swarm::{cso_minimize_batch, pso_minimize_batch, Bounds, CsoParams, PsoParams};

/// Which swarm searches.
#[derive(Clone, Debug, PartialEq)]
pub enum Search {
    Cso(CsoParams),
    Pso(PsoParams),
}

/// How (C, γ) are searched: between the bounds as they are (seed 004), or on log10 of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    Linear,
    Log,
}

/// The search problem.
#[derive(Clone, Debug, PartialEq)]
pub struct TuneParams {
    /// Fixed SVR parameters (epsilon, tol, ...); C and γ are searched. The kernel is RBF.
    pub svr: SvrParams,
    pub c_bounds: (f64, f64),
    pub gamma_bounds: (f64, f64),
    pub scale: Scale,
    pub search: Search,
}

/// The outcome of [`tune_svr`].
#[derive(Clone, Debug)]
pub struct TuneResult {
    pub c: f64,
    pub gamma: f64,
    /// Cross-validated MSE at (c, gamma).
    pub cv_mse: f64,
    /// Best CV MSE after each generation.
    pub history: Vec<f64>,
    pub n_evals: usize,
    /// The SVR refitted on all the data with (c, gamma).
    pub model: SvrModel,
}

/// Test-index sets of k folds: sizes ⌈n/k⌉ for the first n mod k folds and ⌊n/k⌋ for the rest
/// (as scikit-learn's `KFold`), over the samples in order, or shuffled by `seed`.
pub fn kfold(n: usize, k: usize, seed: Option<u64>) -> Result<Vec<Vec<usize>>> {
    if k < 2 || k > n {
        return Err(Error::param(
            "cv",
            format!("need 2 <= folds <= samples ({n}), got {k}"),
        ));
    }
    let mut idx: Vec<usize> = (0..n).collect();
    if let Some(s) = seed {
        idx.shuffle(&mut ChaCha8Rng::seed_from_u64(s));
    }
    let mut out = Vec::with_capacity(k);
    let mut start = 0;
    for f in 0..k {
        let len = n / k + usize::from(f < n % k);
        out.push(idx[start..start + len].to_vec());
        start += len;
    }
    Ok(out)
}

/// Checks that `folds` are disjoint, non-empty test sets of valid sample indices.
pub fn check_folds(folds: &[Vec<usize>], n: usize) -> Result<()> {
    if folds.len() < 2 {
        return Err(Error::param("cv", "need at least 2 folds"));
    }
    let mut seen = vec![false; n];
    for (f, test) in folds.iter().enumerate() {
        if test.is_empty() || test.len() >= n {
            return Err(Error::param(
                "cv",
                format!("fold {f} must hold between 1 and {} samples", n - 1),
            ));
        }
        for &i in test {
            if i >= n || seen[i] {
                return Err(Error::param(
                    "cv",
                    format!("fold {f}: index {i} is out of range or in two folds"),
                ));
            }
            seen[i] = true;
        }
    }
    Ok(())
}

/// Training and test sets of one fold.
struct Fold {
    x_train: Vec<f64>,
    y_train: Vec<f64>,
    x_test: Vec<f64>,
    y_test: Vec<f64>,
}

fn split(x: Samples<'_>, y: &[f64], folds: &[Vec<usize>]) -> Vec<Fold> {
    let n = x.nrows();
    folds
        .iter()
        .map(|test| {
            let mut is_test = vec![false; n];
            test.iter().for_each(|&i| is_test[i] = true);
            let mut f = Fold {
                x_train: Vec::new(),
                y_train: Vec::new(),
                x_test: Vec::new(),
                y_test: Vec::new(),
            };
            for i in 0..n {
                if is_test[i] {
                    f.x_test.extend_from_slice(x.row(i));
                    f.y_test.push(y[i]);
                } else {
                    f.x_train.extend_from_slice(x.row(i));
                    f.y_train.push(y[i]);
                }
            }
            f
        })
        .collect()
}

fn fold_mse(f: &Fold, d: usize, p: &SvrParams) -> f64 {
    let fit = p
        .clone()
        .check()
        .and_then(|p| p.fit(Samples::new(&f.x_train, f.y_train.len(), d)?, &f.y_train))
        .and_then(|m| {
            let xt = Samples::new(&f.x_test, f.y_test.len(), d)?;
            m.predict(xt)
        });
    match fit {
        Ok(pred) => {
            pred.iter()
                .zip(&f.y_test)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                / f.y_test.len() as f64
        }
        Err(_) => f64::INFINITY,
    }
}

/// Mean over folds of the held-out MSE of an SVR with parameters `p` (as scikit-learn's
/// `cross_val_score(..., scoring="neg_mean_squared_error")`, sign flipped).
pub fn cv_mse(x: Samples<'_>, y: &[f64], folds: &[Vec<usize>], p: &SvrParams) -> Result<f64> {
    x.require_finite("X")?;
    check_target(y, x.nrows())?;
    check_folds(folds, x.nrows())?;
    let parts = split(x, y, folds);
    let d = x.ncols();
    Ok(parts.par_iter().map(|f| fold_mse(f, d, p)).sum::<f64>() / parts.len() as f64)
}

impl TuneParams {
    /// The fixed SVR parameters with this C and γ (RBF kernel).
    pub fn svr_at(&self, c: f64, gamma: f64) -> SvrParams {
        self.svr
            .clone()
            .c(c)
            .gamma(Gamma::Value(gamma))
            .kernel(KernelKind::Rbf)
    }

    fn decode(&self, v: &[f64]) -> (f64, f64) {
        match self.scale {
            Scale::Linear => (v[0], v[1]),
            Scale::Log => (10f64.powf(v[0]), 10f64.powf(v[1])),
        }
    }

    fn bounds(&self) -> Result<Bounds> {
        for (name, (lo, hi)) in [("C", self.c_bounds), ("gamma", self.gamma_bounds)] {
            if !(lo > 0.0 && hi > lo && hi.is_finite()) {
                return Err(Error::param(
                    if name == "C" { "C" } else { "gamma" },
                    format!("bounds must satisfy 0 < low < high < inf, got ({lo}, {hi})"),
                ));
            }
        }
        let t = |(lo, hi): (f64, f64)| match self.scale {
            Scale::Linear => (lo, hi),
            Scale::Log => (lo.log10(), hi.log10()),
        };
        Ok(Bounds::from_pairs(&[
            t(self.c_bounds),
            t(self.gamma_bounds),
        ]))
    }
}

/// Searches (C, γ) minimising the k-fold CV MSE over `folds`, then refits on all the data.
/// `progress(generation, best_so_far)` is called after the initial population (generation 0) and
/// after every generation (1..=iters).
pub fn tune_svr(
    x: Samples<'_>,
    y: &[f64],
    folds: &[Vec<usize>],
    params: &TuneParams,
    mut progress: impl FnMut(usize, f64),
) -> Result<TuneResult> {
    x.require_finite("X")?;
    check_target(y, x.nrows())?;
    check_folds(folds, x.nrows())?;
    let bounds = params.bounds()?;
    let parts = split(x, y, folds);
    let d = x.ncols();
    let mut generation = 0usize;
    let mut best = f64::INFINITY;
    let eval = |pop: &[Vec<f64>]| -> Result<Vec<f64>> {
        let nf = parts.len();
        let per: Vec<f64> = (0..pop.len() * nf)
            .into_par_iter()
            .map(|t| {
                let (c, g) = params.decode(&pop[t / nf]);
                fold_mse(&parts[t % nf], d, &params.svr_at(c, g))
            })
            .collect();
        // a fold whose fit failed scores infinity, an interrupted one too: stop here instead
        crate::interrupt::check()?;
        let out: Vec<f64> = per
            .chunks(nf)
            .map(|c| c.iter().sum::<f64>() / nf as f64)
            .collect();
        best = out.iter().copied().fold(best, f64::min);
        progress(generation, best);
        generation += 1;
        Ok(out)
    };
    let res = match &params.search {
        Search::Cso(p) => cso_minimize_batch(eval, &bounds, p)?,
        Search::Pso(p) => pso_minimize_batch(eval, &bounds, p)?,
    };
    if !res.f.is_finite() {
        return Err(Error::Numerical(
            "no (C, gamma) in the bounds gave a finite cross-validated error".into(),
        ));
    }
    let (c, gamma) = params.decode(&res.x);
    let model = params.svr_at(c, gamma).check()?.fit(x, y)?;
    Ok(TuneResult {
        c,
        gamma,
        cv_mse: res.f,
        history: res.history,
        n_evals: res.n_evals,
        model,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kfold_sizes_follow_scikit_learn() {
        let f = kfold(17, 5, None).unwrap();
        let sizes: Vec<usize> = f.iter().map(|v| v.len()).collect();
        assert_eq!(sizes, vec![4, 4, 3, 3, 3]);
        assert_eq!(f[0], vec![0, 1, 2, 3]);
        let s = kfold(17, 5, Some(3)).unwrap();
        let mut all: Vec<usize> = s.concat();
        all.sort();
        assert_eq!(all, (0..17).collect::<Vec<_>>());
        assert_eq!(s, kfold(17, 5, Some(3)).unwrap());
        assert!(kfold(3, 5, None).is_err());
    }

    #[test]
    fn tuning_finds_a_better_cv_error_than_the_corners_and_is_deterministic() {
        let n = 45;
        let x: Vec<f64> = (0..n)
            .flat_map(|i| {
                let t = i as f64 / n as f64;
                [t * 3.0, (t * 5.0).sin(), (t * 2.0).cos(), t * t]
            })
            .collect();
        let y: Vec<f64> = x
            .chunks(4)
            .map(|r| 3.0 * r[0] + r[1] * r[1] - r[2])
            .collect();
        let s = Samples::new(&x, n, 4).unwrap();
        let folds = kfold(n, 5, Some(1)).unwrap();
        let tp = TuneParams {
            svr: SvrParams::default(),
            c_bounds: (0.01, 100.0),
            gamma_bounds: (1e-3, 10.0),
            scale: Scale::Log,
            search: Search::Cso(CsoParams {
                pop: 10,
                iters: 15,
                seed: 7,
                ..Default::default()
            }),
        };
        let mut calls = 0;
        let r = tune_svr(s, &y, &folds, &tp, |_, _| calls += 1).unwrap();
        assert_eq!(calls, 16); // the initial population, then 15 generations
        for (c, g) in [(0.01, 1e-3), (100.0, 10.0), (0.01, 10.0), (100.0, 1e-3)] {
            let corner = cv_mse(s, &y, &folds, &tp.svr_at(c, g)).unwrap();
            assert!(r.cv_mse < corner, "{} vs corner {corner}", r.cv_mse);
        }
        let again = tune_svr(s, &y, &folds, &tp, |_, _| {}).unwrap();
        assert_eq!(
            (r.c, r.gamma, r.cv_mse),
            (again.c, again.gamma, again.cv_mse)
        );
        // the reported CV error is the objective at the reported point
        let direct = cv_mse(s, &y, &folds, &tp.svr_at(r.c, r.gamma)).unwrap();
        assert!((direct - r.cv_mse).abs() <= 1e-12 * direct.max(1.0));
    }
}
