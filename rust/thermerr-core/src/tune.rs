//! Hyper-parameter search of an ε-SVR (seed 004): chicken swarm optimisation (or PSO) over
//! (C, γ), minimising the cross-validated mean squared error over explicit (train, test) splits:
//! time-ordered ones ([`time_series_split`], scikit-learn's `TimeSeriesSplit`) for runs, or the
//! shuffled k-fold ones of the seed ([`kfold_splits`]). The objective is evaluated
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

/// One cross-validation split: the samples an SVR is trained on and those it is scored on.
/// Rows are taken in the order the indices are given (as scikit-learn's `X[train]`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Split {
    pub train: Vec<usize>,
    pub test: Vec<usize>,
}

/// Test-index sets of k folds: sizes ⌈n/k⌉ for the first n mod k folds and ⌊n/k⌋ for the rest
/// (as scikit-learn's `KFold`), over the samples in order, or shuffled by `seed`.
///
/// Not for time series: a fold's complement trains on samples after its test block. See
/// [`time_series_split`].
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

/// The [`kfold`] folds as (train, test) splits: each test set in increasing index order, its
/// training set the complement in increasing order (the rows the k-fold search has always used).
pub fn kfold_splits(n: usize, k: usize, seed: Option<u64>) -> Result<Vec<Split>> {
    Ok(complement_splits(&kfold(n, k, seed)?, n))
}

/// Test-index folds as (train, test) splits, each training set the complement of its test set;
/// both in increasing index order. Indices `>= n` are dropped here: validate with
/// [`check_folds`] first when the folds come from outside.
pub fn complement_splits(folds: &[Vec<usize>], n: usize) -> Vec<Split> {
    folds
        .iter()
        .map(|test| {
            let mut is_test = vec![false; n];
            test.iter()
                .filter(|&&i| i < n)
                .for_each(|&i| is_test[i] = true);
            let (test, train): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| is_test[i]);
            Split { train, test }
        })
        .collect()
}

/// Time-ordered splits, index for index those of scikit-learn's
/// `TimeSeriesSplit(n_splits, gap=gap, test_size=test_size, max_train_size=max_train_size)`:
/// `n_splits` consecutive test blocks of `test_size` samples (default ⌊n/(n_splits+1)⌋) ending
/// at the last sample; each training set the samples before its test block less the `gap`
/// samples just before it, the last `max_train_size` of them if given. `max_train_size` 0 means
/// no limit, as in scikit-learn. Every training index is below every test index of its split.
pub fn time_series_split(
    n: usize,
    n_splits: usize,
    gap: usize,
    test_size: Option<usize>,
    max_train_size: Option<usize>,
) -> Result<Vec<Split>> {
    if n_splits < 2 {
        return Err(Error::param(
            "cv",
            format!("need at least 2 time-ordered splits, got {n_splits}"),
        ));
    }
    let n_folds = n_splits + 1;
    let test_size = test_size.unwrap_or(n / n_folds);
    if test_size == 0 && n_folds <= n {
        return Err(Error::param("cv", "test_size must be at least 1"));
    }
    if n_folds > n {
        return Err(Error::param(
            "cv",
            format!("{n_splits} time-ordered splits need at least {n_folds} samples, got {n}"),
        ));
    }
    if n <= gap.saturating_add(test_size.saturating_mul(n_splits)) {
        return Err(Error::param(
            "cv",
            format!(
                "too many splits ({n_splits}) for {n} samples with test_size {test_size} and gap {gap}"
            ),
        ));
    }
    let first = n - n_splits * test_size;
    Ok((0..n_splits)
        .map(|s| {
            let test_start = first + s * test_size;
            let train_end = test_start - gap;
            let train_start = match max_train_size {
                Some(m) if m > 0 && m < train_end => train_end - m,
                _ => 0,
            };
            Split {
                train: (train_start..train_end).collect(),
                test: (test_start..test_start + test_size).collect(),
            }
        })
        .collect())
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

/// Checks explicit splits over `n` samples: at least one; in each, a non-empty training set and
/// a non-empty test set, every index below `n`, no index in both. The error names the fold.
pub fn check_splits(splits: &[Split], n: usize) -> Result<()> {
    if splits.is_empty() {
        return Err(Error::param("cv", "need at least one (train, test) split"));
    }
    let mut in_train = vec![false; n];
    for (f, s) in splits.iter().enumerate() {
        for (name, set) in [("training", &s.train), ("test", &s.test)] {
            if set.is_empty() {
                return Err(Error::param(
                    "cv",
                    format!("fold {f}: the {name} set is empty"),
                ));
            }
            if let Some(&i) = set.iter().find(|&&i| i >= n) {
                return Err(Error::param(
                    "cv",
                    format!("fold {f}: {name} index {i} is out of range for {n} samples"),
                ));
            }
        }
        s.train.iter().for_each(|&i| in_train[i] = true);
        let both = s.test.iter().find(|&&i| in_train[i]).copied();
        s.train.iter().for_each(|&i| in_train[i] = false);
        if let Some(i) = both {
            return Err(Error::param(
                "cv",
                format!("fold {f}: index {i} is in both the training and the test set"),
            ));
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

fn split(x: Samples<'_>, y: &[f64], splits: &[Split]) -> Vec<Fold> {
    let gather = |idx: &[usize]| -> (Vec<f64>, Vec<f64>) {
        let mut xs = Vec::with_capacity(idx.len() * x.ncols());
        idx.iter().for_each(|&i| xs.extend_from_slice(x.row(i)));
        (xs, idx.iter().map(|&i| y[i]).collect())
    };
    splits
        .iter()
        .map(|s| {
            let (x_train, y_train) = gather(&s.train);
            let (x_test, y_test) = gather(&s.test);
            Fold {
                x_train,
                y_train,
                x_test,
                y_test,
            }
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

/// Mean over splits of the held-out MSE of an SVR with parameters `p` trained on each split's
/// training set (as scikit-learn's `cross_val_score(..., cv=splits,
/// scoring="neg_mean_squared_error")`, sign flipped).
pub fn cv_mse(x: Samples<'_>, y: &[f64], splits: &[Split], p: &SvrParams) -> Result<f64> {
    x.require_finite("X")?;
    check_target(y, x.nrows())?;
    check_splits(splits, x.nrows())?;
    let parts = split(x, y, splits);
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

/// Searches (C, γ) minimising the mean held-out MSE over `splits` (time-ordered ones from
/// [`time_series_split`], shuffled k-fold ones from [`kfold_splits`], or any checked by
/// [`check_splits`]), then refits on all the data.
/// `progress(generation, best_so_far)` is called after the initial population (generation 0) and
/// after every generation (1..=iters).
pub fn tune_svr(
    x: Samples<'_>,
    y: &[f64],
    splits: &[Split],
    params: &TuneParams,
    mut progress: impl FnMut(usize, f64),
) -> Result<TuneResult> {
    x.require_finite("X")?;
    check_target(y, x.nrows())?;
    check_splits(splits, x.nrows())?;
    let bounds = params.bounds()?;
    let parts = split(x, y, splits);
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

    fn pairs(s: &[Split]) -> Vec<(Vec<usize>, Vec<usize>)> {
        s.iter()
            .map(|s| (s.train.clone(), s.test.clone()))
            .collect()
    }

    #[test]
    fn time_series_split_equals_scikit_learn() {
        // TimeSeriesSplit(3).split(range(10)), scikit-learn 1.9.1
        assert_eq!(
            pairs(&time_series_split(10, 3, 0, None, None).unwrap()),
            vec![
                ((0..4).collect(), vec![4, 5]),
                ((0..6).collect(), vec![6, 7]),
                ((0..8).collect(), vec![8, 9]),
            ]
        );
        // TimeSeriesSplit(3, gap=2, test_size=2, max_train_size=3).split(range(10))
        assert_eq!(
            pairs(&time_series_split(10, 3, 2, Some(2), Some(3)).unwrap()),
            vec![
                (vec![0, 1], vec![4, 5]),
                (vec![1, 2, 3], vec![6, 7]),
                (vec![3, 4, 5], vec![8, 9]),
            ]
        );
        // max_train_size=0 is no limit in scikit-learn
        assert_eq!(
            time_series_split(7, 2, 0, None, Some(0)).unwrap(),
            time_series_split(7, 2, 0, None, None).unwrap()
        );
        for (n, k, gap, ts) in [
            (5, 5, 0, None),
            (10, 1, 0, None),
            (10, 3, 4, None),
            (10, 3, 0, Some(0)),
            (10, 3, 1, Some(3)),
        ] {
            let e = time_series_split(n, k, gap, ts, None).unwrap_err();
            assert!(matches!(e, Error::InvalidParam { name: "cv", .. }), "{e}");
        }
    }

    #[test]
    fn time_splits_train_only_before_the_test_block() {
        for n in 6..40 {
            for k in 2..5 {
                for gap in 0..3 {
                    let Ok(s) = time_series_split(n, k, gap, None, Some(n / 3)) else {
                        continue;
                    };
                    check_splits(&s, n).unwrap();
                    for sp in &s {
                        assert!(
                            sp.train.iter().max().unwrap() + gap < *sp.test.iter().min().unwrap()
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn kfold_splits_are_the_complements_in_order() {
        let s = kfold_splits(17, 5, Some(3)).unwrap();
        let f = kfold(17, 5, Some(3)).unwrap();
        for (sp, test) in s.iter().zip(&f) {
            let mut t = test.clone();
            t.sort();
            assert_eq!(sp.test, t);
            assert_eq!(
                sp.train,
                (0..17).filter(|i| !t.contains(i)).collect::<Vec<_>>()
            );
        }
        check_splits(&s, 17).unwrap();
    }

    #[test]
    fn bad_splits_name_the_fold() {
        let ok = Split {
            train: vec![0, 1],
            test: vec![2],
        };
        let cases = [
            (
                Split {
                    train: vec![0, 1],
                    test: vec![],
                },
                "fold 1: the test set is empty",
            ),
            (
                Split {
                    train: vec![],
                    test: vec![3],
                },
                "fold 1: the training set is empty",
            ),
            (
                Split {
                    train: vec![0, 1],
                    test: vec![1, 2],
                },
                "fold 1: index 1 is in both",
            ),
            (
                Split {
                    train: vec![0, 9],
                    test: vec![2],
                },
                "fold 1: training index 9 is out of range",
            ),
        ];
        for (bad, msg) in cases {
            let e = check_splits(&[ok.clone(), bad], 5).unwrap_err();
            assert!(matches!(e, Error::InvalidParam { name: "cv", .. }));
            assert!(e.to_string().contains(msg), "{e}");
        }
        assert!(check_splits(&[], 5).is_err());
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
        let folds = kfold_splits(n, 5, Some(1)).unwrap();
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
