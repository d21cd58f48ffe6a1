//! Hyper-parameter search of an ε-SVR (seed 004): chicken swarm optimisation (or PSO) over
//! (C, γ), minimising the cross-validated mean squared error over explicit (train, test) splits:
//! time-ordered ones ([`time_series_split`], scikit-learn's `TimeSeriesSplit`) for runs, or the
//! shuffled k-fold ones of the seed ([`kfold_splits`]). The objective is evaluated
//! natively: a generation's points in parallel (rayon), each fitting its folds in turn (those
//! that tell most per unit of work first); a point stops as soon as its folds so far prove it
//! cannot beat its member's memory, and every (point, fold) is fitted once per search. Both are exact: the
//! search takes the same path to the same result as with every fold of every point fitted
//! ([`SearchCost`] counts what was fitted).

use std::collections::HashMap;

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::samples::{check_target, Samples};
use crate::svr::{Gamma, KernelKind, SharedDistances, SvrModel, SvrParams};
use crate::swarm::{cso_minimize_pruned, pso_minimize_pruned, Bounds, CsoParams, PsoParams};

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
    /// Start each fold's SMO from the solution of the nearest point already fitted on that fold
    /// (within [`WARM_RADIUS`] decades of C and γ): fewer iterations, each solution as optimal
    /// within `tol` as a cold start's but not the same bits, so the search's path may differ in
    /// the last digits. `Some(false)`: the plain search's path, bit for bit. `None`: warm starts
    /// in a thinned search's first stage (which only ranks points; the result is scored cold on
    /// every row), not in a search on every row ([`TuneParams::warm`]).
    pub warm_start: Option<bool>,
    /// Search on every `thin`-th row (1: every row, the plain search). With `thin` k > 1 the swarm
    /// runs on rows 0, k, 2k, … of the data, each split keeping its rows among them, and every
    /// fit there takes C·k (the ε-insensitive loss summed over a k-th of the rows, weighted as
    /// the whole sum); then the [`REFINE`] best points it fitted on every fold are scored on
    /// every row, and a compass search on every row ([`POLISH_ROUNDS`] rounds) starts from the
    /// best of them. [`auto_thin`] chooses k from the splits.
    pub thin: usize,
}

/// Training rows of the largest split that [`auto_thin`] aims at: each fit of a thinned search
/// trains on about this many rows.
pub const THIN_ROWS: usize = 1000;

/// Points a thinned search scores on every row: its best, by the thinned objective, of those it
/// fitted on every fold.
pub const REFINE: usize = 16;

/// Rounds of the compass search on every row that ends a thinned search (four points a round at
/// most).
pub const POLISH_ROUNDS: usize = 8;

/// How far (Euclidean, in decades of C and γ) a fitted point may be from a new one to start its
/// solver from.
pub const WARM_RADIUS: f64 = 0.5;

/// Fitted solutions kept per fold for warm starts (the most recent ones).
const WARM_KEEP: usize = 64;

/// A point's task in a generation: its MSE per fold (NaN where not fitted), the solutions it
/// found (per fold) and how many folds it fitted.
type PointDone = (Vec<f64>, Vec<(usize, Solved)>, usize);

/// A fold's fitted solution: (log10 C, log10 γ), C, and β = α − α* per training row.
struct Solved {
    at: [f64; 2],
    c: f64,
    beta: Vec<f64>,
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
    /// The SVR fits the search did and would have done with every fold of every point.
    pub cost: SearchCost,
    /// The SVR refitted on all the data with (c, gamma).
    pub model: SvrModel,
    /// The thinning the search ran with (1: every row).
    pub thin: usize,
}

/// How many fold fits a search did (`fits`) against the `n_evals × folds` of a search that fits
/// every fold of every point (`full`): the difference is points met before (fitted once per
/// fold) and points stopped early because their first folds already exceeded their member's
/// memory.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SearchCost {
    pub fits: usize,
    pub full: usize,
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

/// The thinning of a search over `splits` (see [`TuneParams::thin`]): the smallest k that brings
/// the largest training set to at most [`THIN_ROWS`] rows, or less where a split would keep fewer
/// than two training rows or no test row; 1 (no thinning) up to [`THIN_ROWS`] training rows.
pub fn auto_thin(splits: &[Split]) -> usize {
    let most = splits.iter().map(|s| s.train.len()).max().unwrap_or(0);
    let mut k = most.div_ceil(THIN_ROWS).max(1);
    while k > 1
        && !splits
            .iter()
            .all(|s| on_stride(&s.train, k).count() >= 2 && on_stride(&s.test, k).count() >= 1)
    {
        k -= 1;
    }
    k
}

/// The indices of `idx` on the stride k (rows 0, k, 2k, …), renumbered along it, in their order.
fn on_stride(idx: &[usize], k: usize) -> impl Iterator<Item = usize> + '_ {
    idx.iter()
        .filter(move |&&i| i % k == 0)
        .map(move |&i| i / k)
}

/// The data and splits of a search on every k-th row: rows 0, k, 2k, … of `x`, `y`, and each
/// split's indices on the stride, renumbered, in their order. A split left without a training or
/// test row is a [`Error::InvalidParam`] naming it.
fn thinned(
    x: Samples<'_>,
    y: &[f64],
    splits: &[Split],
    k: usize,
) -> Result<(Vec<f64>, Vec<f64>, Vec<Split>)> {
    let rows: Vec<usize> = (0..x.nrows()).step_by(k).collect();
    let mut xs = Vec::with_capacity(rows.len() * x.ncols());
    rows.iter().for_each(|&i| xs.extend_from_slice(x.row(i)));
    let ys = rows.iter().map(|&i| y[i]).collect();
    let out: Vec<Split> = splits
        .iter()
        .map(|s| Split {
            train: on_stride(&s.train, k).collect(),
            test: on_stride(&s.test, k).collect(),
        })
        .collect();
    for (j, s) in out.iter().enumerate() {
        if s.train.is_empty() || s.test.is_empty() {
            return Err(Error::param(
                "thin",
                format!(
                    "one row in {k} leaves fold {j} without a {} row; use a smaller thin",
                    if s.train.is_empty() {
                        "training"
                    } else {
                        "test"
                    }
                ),
            ));
        }
    }
    Ok((xs, ys, out))
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
    mse_of(fit, &f.y_test)
}

/// The held-out MSE of predictions, +∞ for a failed fit or a NaN (NaN marks "not fitted" in
/// [`FoldedObjective`]).
fn mse_of(pred: Result<Vec<f64>>, y: &[f64]) -> f64 {
    let mse = match pred {
        Ok(pred) => {
            pred.iter()
                .zip(y)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                / y.len() as f64
        }
        Err(_) => f64::INFINITY,
    };
    if mse.is_nan() {
        f64::INFINITY
    } else {
        mse
    }
}

/// A point stops once its partial mean exceeds the bar by more than this relative margin:
/// the held-out MSEs are non-negative, so the full mean is at least the partial one, and the
/// margin covers the rounding of summing the folds in another order (a few ulps).
const STOP_MARGIN: f64 = 1e-9;

/// The largest data set (in bytes of its two distance matrices, 16 n²) whose distances a search
/// forms once and shares between its fits; above it every fit forms its kernel from the features.
pub const SHARED_MAX_BYTES: usize = 1 << 30;

/// The cross-validated MSE of a search's points, fold by fold, each (point, fold) fitted once.
struct FoldedObjective<'a> {
    parts: &'a [Fold],
    splits: &'a [Split],
    x: Samples<'a>,
    shared: Option<SharedDistances>,
    params: &'a TuneParams,
    /// every fit takes C times this (the thinning of a thinned search's first stage)
    c_scale: f64,
    /// per point (C, γ bits): each fold's MSE, NaN while not fitted
    seen: HashMap<[u64; 2], Vec<f64>>,
    /// the point with the smallest mean over all folds so far
    best: Option<([u64; 2], f64)>,
    /// per fold, recent solutions to start from (with `warm_start`)
    solved: Vec<Vec<Solved>>,
    cost: SearchCost,
}

impl<'a> FoldedObjective<'a> {
    fn new(
        x: Samples<'a>,
        parts: &'a [Fold],
        splits: &'a [Split],
        params: &'a TuneParams,
        c_scale: f64,
        max_shared_bytes: usize,
    ) -> Self {
        let shared = (SharedDistances::bytes(x.nrows()) <= max_shared_bytes)
            .then(|| SharedDistances::new(x));
        Self {
            parts,
            splits,
            x,
            shared,
            params,
            c_scale,
            seen: HashMap::new(),
            best: None,
            solved: (0..parts.len()).map(|_| Vec::new()).collect(),
            cost: SearchCost::default(),
        }
    }

    /// Held-out MSE of fold `j` at (c, γ): from the shared distances if formed (the same bits),
    /// started from the nearest solution on the fold with `warm_start`; with the new solution to
    /// keep for later starts.
    fn fold(&self, j: usize, c: f64, gamma: f64, warm_start: bool) -> (f64, Option<Solved>) {
        let (f, svr) = (&self.parts[j], self.params.svr_at(c * self.c_scale, gamma));
        let Some(sh) = &self.shared else {
            return (fold_mse(f, self.x.ncols(), &svr), None);
        };
        let s = &self.splits[j];
        let at = [c.log10(), gamma.log10()];
        let warm = warm_start.then(|| {
            self.solved[j]
                .iter()
                .map(|w| ((w.at[0] - at[0]).hypot(w.at[1] - at[1]), w))
                .filter(|(d, _)| *d <= WARM_RADIUS)
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, w)| (w.beta.as_slice(), w.c))
        });
        let model = svr
            .check()
            .and_then(|p| p.fit_shared(self.x, &s.train, &f.y_train, sh, warm.flatten()));
        let solved = model.as_ref().ok().filter(|_| warm_start).map(|m| {
            let mut beta = vec![0.0; s.train.len()];
            for (&k, &b) in m.support.iter().zip(&m.dual_coef) {
                beta[k] = b;
            }
            Solved {
                at,
                c: c * self.c_scale,
                beta,
            }
        });
        let pred = model.map(|m| m.predict_shared(&s.test, &s.train, sh));
        (mse_of(pred, &f.y_test), solved)
    }

    /// The mean over the folds at (c, γ) with every solver started cold: the objective as
    /// [`cv_mse`] computes it (the same bits), for the point a warm-started search returns.
    fn cold_mean(&self, c: f64, gamma: f64) -> f64 {
        let per: Vec<f64> = (0..self.parts.len())
            .into_par_iter()
            .map(|j| self.fold(j, c, gamma, false).0)
            .collect();
        fold_mean(&per)
    }

    /// The points fitted on every fold, by their mean, best first: `(C, γ, mean)`.
    fn complete(&self) -> Vec<(f64, f64, f64)> {
        let mut out: Vec<(f64, f64, f64)> = self
            .seen
            .iter()
            .filter(|(_, per)| per.iter().all(|m| !m.is_nan()))
            .map(|(k, per)| (f64::from_bits(k[0]), f64::from_bits(k[1]), fold_mean(per)))
            .collect();
        // ties by the point itself: the same order whatever the hash map's
        out.sort_by(|a, b| {
            a.2.total_cmp(&b.2)
                .then(a.0.total_cmp(&b.0))
                .then(a.1.total_cmp(&b.1))
        });
        out
    }

    /// The order to fit folds in: the most of the best point's error per unit of work first
    /// (work ~ training size squared), so that a point that cannot win is stopped soonest; by
    /// training size until a point has all its folds.
    fn order(&self) -> Vec<usize> {
        let work = |j: usize| (self.parts[j].y_train.len() as f64).powi(2);
        let mut order: Vec<usize> = (0..self.parts.len()).collect();
        match self.best.map(|(k, _)| &self.seen[&k]) {
            Some(per) => order.sort_by(|&a, &b| (per[b] / work(b)).total_cmp(&(per[a] / work(a)))),
            None => order.sort_by(|&a, &b| work(a).total_cmp(&work(b))),
        }
        order
    }

    /// The mean MSE over the folds of each point, or, for a point whose value is at least its
    /// `bar` (the swarm's contract, see [`cso_minimize_pruned`]), a partial mean at least `bar`.
    fn eval(&mut self, pop: &[Vec<f64>], bar: &[f64]) -> Result<Vec<f64>> {
        let nf = self.parts.len();
        let keys: Vec<[u64; 2]> = pop
            .iter()
            .map(|v| {
                let (c, g) = self.params.decode(v);
                [c.to_bits(), g.to_bits()]
            })
            .collect();
        self.cost.full += pop.len() * nf;
        // one task per distinct point, run until its folds exceed the largest bar among the
        // members standing on it (so every member's own decision below is known)
        let mut tasks: Vec<([u64; 2], f64)> = Vec::new();
        for (i, k) in keys.iter().enumerate() {
            match tasks.iter_mut().find(|(t, _)| t == k) {
                Some(t) => t.1 = t.1.max(bar[i]),
                None => tasks.push((*k, bar[i])),
            }
        }
        let order = self.order();
        let stops = |sum: f64, b: f64| sum / nf as f64 > b * (1.0 + STOP_MARGIN);
        let this = &*self;
        // points in parallel, each one's folds in turn: both cores busy to the end
        let done: Vec<PointDone> = tasks
            .par_iter()
            .map(|(k, b)| {
                let (c, g) = (f64::from_bits(k[0]), f64::from_bits(k[1]));
                let mut per = this
                    .seen
                    .get(k)
                    .cloned()
                    .unwrap_or_else(|| vec![f64::NAN; nf]);
                let (mut sum, mut solved, mut fits) = (0.0, Vec::new(), 0);
                for &j in &order {
                    if per[j].is_nan() {
                        let (m, w) = this.fold(j, c, g, this.params.warm());
                        per[j] = m;
                        fits += 1;
                        solved.extend(w.map(|w| (j, w)));
                    }
                    sum += per[j];
                    if stops(sum, *b) {
                        break;
                    }
                }
                (per, solved, fits)
            })
            .collect();
        // an interrupted fit scores infinity: stop here instead
        crate::interrupt::check()?;
        // merged in task order after the whole batch: the same starts on any thread count
        for ((k, _), (per, solved, fits)) in tasks.iter().zip(done) {
            self.seen.insert(*k, per);
            self.cost.fits += fits;
            for (j, w) in solved {
                let kept = &mut self.solved[j];
                if kept.len() == WARM_KEEP {
                    kept.remove(0);
                }
                kept.push(w);
            }
        }
        let mut open = vec![true; pop.len()];
        let out: Vec<f64> = (0..pop.len())
            .map(|i| {
                let per = &self.seen[&keys[i]];
                let mut sum = 0.0;
                for &j in &order {
                    sum += per[j];
                    if stops(sum, bar[i]) {
                        open[i] = false;
                        return sum / nf as f64;
                    }
                }
                // summed in fold order, as a search that fits every fold
                fold_mean(per)
            })
            .collect();
        for i in (0..pop.len()).filter(|&i| open[i]) {
            if self.best.is_none_or(|(_, b)| out[i] < b) {
                self.best = Some((keys[i], out[i]));
            }
        }
        Ok(out)
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
    let per: Vec<f64> = parts.par_iter().map(|f| fold_mse(f, d, p)).collect();
    Ok(fold_mean(&per))
}

/// The mean of the folds' MSEs, summed in fold order: the one objective value [`cv_mse`] and the
/// search compute, bit for bit.
fn fold_mean(per: &[f64]) -> f64 {
    per.iter().sum::<f64>() / per.len() as f64
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

    /// A point (C, γ) as the swarm's position (log10 of both on the log scale).
    fn encode(&self, c: f64, gamma: f64) -> Vec<f64> {
        match self.scale {
            Scale::Linear => vec![c, gamma],
            Scale::Log => vec![c.log10(), gamma.log10()],
        }
    }

    /// Whether the search starts fold solvers warm: as asked, else only in a thinned search.
    pub fn warm(&self) -> bool {
        self.warm_start.unwrap_or(self.thin > 1)
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
    progress: impl FnMut(usize, f64),
) -> Result<TuneResult> {
    search_with(x, y, splits, params, progress, SHARED_MAX_BYTES)
}

/// [`tune_svr`] with the distances shared only up to `max_shared_bytes`.
fn search_with(
    x: Samples<'_>,
    y: &[f64],
    splits: &[Split],
    params: &TuneParams,
    mut progress: impl FnMut(usize, f64),
    max_shared_bytes: usize,
) -> Result<TuneResult> {
    x.require_finite("X")?;
    check_target(y, x.nrows())?;
    check_splits(splits, x.nrows())?;
    let bounds = params.bounds()?;
    let k = params.thin;
    if k == 0 {
        return Err(Error::param("thin", "must be at least 1 (1: every row)"));
    }
    let parts = split(x, y, splits);
    let (c, gamma, cv_mse, history, n_evals, cost) = if k == 1 {
        let mut objective = FoldedObjective::new(x, &parts, splits, params, 1.0, max_shared_bytes);
        let res = run_swarm(&mut objective, &bounds, params, &mut progress)?;
        let (c, gamma) = params.decode(&res.x);
        // a warm-started solution differs from a cold one in the last digits: report the
        // objective at the point as anyone recomputing it gets it
        let cv_mse = if params.warm() && res.f.is_finite() {
            objective.cold_mean(c, gamma)
        } else {
            res.f
        };
        (c, gamma, cv_mse, res.history, res.n_evals, objective.cost)
    } else {
        // first stage: the swarm on every k-th row, C scaled by k
        let (tx, ty, tsplits) = thinned(x, y, splits, k)?;
        let ts = Samples::new(&tx, ty.len(), x.ncols())?;
        let tparts = split(ts, &ty, &tsplits);
        let mut coarse =
            FoldedObjective::new(ts, &tparts, &tsplits, params, k as f64, max_shared_bytes);
        let res = run_swarm(&mut coarse, &bounds, params, &mut progress)?;
        let pts: Vec<Vec<f64>> = coarse
            .complete()
            .into_iter()
            .filter(|p| p.2.is_finite())
            .take(REFINE)
            .map(|p| params.encode(p.0, p.1))
            .collect();
        let stage1 = coarse.cost;
        drop(coarse);
        // second stage, on every row and cold: those points a few at a time, each batch against
        // the best so far (a point whose first folds already exceed it stops: it cannot win),
        // then a compass search from the best
        let cold = TuneParams {
            warm_start: Some(false),
            ..params.clone()
        };
        let mut fine = FoldedObjective::new(x, &parts, splits, &cold, 1.0, max_shared_bytes);
        let mut best = (Vec::new(), f64::INFINITY);
        for batch in pts.chunks(2 * rayon::current_num_threads().max(1)) {
            let out = fine.eval(batch, &vec![best.1; batch.len()])?;
            for (p, v) in batch.iter().zip(out) {
                if v < best.1 {
                    best = (p.clone(), v);
                }
            }
        }
        let mut scored = pts.len();
        if best.1.is_finite() {
            let (polished, n) = polish(&mut fine, &bounds, best)?;
            best = polished;
            scored += n;
        }
        let (c, gamma) = if best.1.is_finite() {
            cold.decode(&best.0)
        } else {
            (f64::NAN, f64::NAN)
        };
        let cv_mse = best.1;
        let cost = SearchCost {
            fits: stage1.fits + fine.cost.fits,
            full: stage1.full + fine.cost.full,
        };
        (c, gamma, cv_mse, res.history, res.n_evals + scored, cost)
    };
    crate::interrupt::check()?;
    if !cv_mse.is_finite() {
        return Err(Error::Numerical(
            "no (C, gamma) in the bounds gave a finite cross-validated error".into(),
        ));
    }
    let model = params.svr_at(c, gamma).check()?.fit(x, y)?;
    Ok(TuneResult {
        c,
        gamma,
        cv_mse,
        history,
        n_evals,
        cost,
        model,
        thin: k,
    })
}

/// A compass search on every row from the best point (position, CV MSE) of a thinned search:
/// each round scores the four neighbours one step along each coordinate of the search box (a
/// sixteenth of its width at first) against the best so far (a neighbour whose first folds
/// already exceed it stops), moves to the best if it is better, else halves the step;
/// [`POLISH_ROUNDS`] rounds at most. Returns the best point and how many points it scored.
fn polish(
    fine: &mut FoldedObjective<'_>,
    bounds: &Bounds,
    start: (Vec<f64>, f64),
) -> Result<((Vec<f64>, f64), usize)> {
    let (lo, hi) = (&bounds.lower, &bounds.upper);
    let (mut best, mut step, mut scored) = (start, 1.0 / 16.0, 0);
    for _ in 0..POLISH_ROUNDS {
        let mut trial: Vec<Vec<f64>> = Vec::new();
        for d in 0..best.0.len() {
            for sign in [-1.0, 1.0] {
                let mut p = best.0.clone();
                p[d] = (p[d] + sign * step * (hi[d] - lo[d])).clamp(lo[d], hi[d]);
                // a neighbour clipped back onto the point (at the box's edge) is not scored
                if p != best.0 && !trial.contains(&p) {
                    trial.push(p);
                }
            }
        }
        if trial.is_empty() {
            break;
        }
        let out = fine.eval(&trial, &vec![best.1; trial.len()])?;
        scored += trial.len();
        match (0..trial.len()).min_by(|&a, &b| out[a].total_cmp(&out[b])) {
            Some(i) if out[i] < best.1 => best = (trial[i].clone(), out[i]),
            _ => step /= 2.0,
        }
    }
    Ok((best, scored))
}

/// The swarm of `params` over `bounds` on `objective`; `progress(generation, best_so_far)` after
/// the initial population (generation 0) and after every generation.
fn run_swarm(
    objective: &mut FoldedObjective<'_>,
    bounds: &Bounds,
    params: &TuneParams,
    progress: &mut impl FnMut(usize, f64),
) -> Result<crate::swarm::SwarmResult> {
    let mut generation = 0usize;
    let mut best = f64::INFINITY;
    let eval = |pop: &[Vec<f64>], bar: &[f64]| -> Result<Vec<f64>> {
        let out = objective.eval(pop, bar)?;
        best = out.iter().copied().fold(best, f64::min);
        progress(generation, best);
        generation += 1;
        Ok(out)
    };
    match &params.search {
        Search::Cso(p) => cso_minimize_pruned(eval, bounds, p),
        Search::Pso(p) => pso_minimize_pruned(eval, bounds, p),
    }
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

    /// Three smooth inputs over a run and a nonlinear target with a little deterministic noise.
    fn curve(n: usize) -> (Vec<f64>, Vec<f64>) {
        let x: Vec<f64> = (0..n)
            .flat_map(|i| {
                let t = i as f64 / n as f64;
                [t * 3.0, (t * 7.0).sin(), (t * 2.0).cos()]
            })
            .collect();
        let y = x
            .chunks(3)
            .enumerate()
            .map(|(i, r)| 3.0 * r[0] + r[1] * r[1] - r[2] + 0.05 * ((i * 37 % 11) as f64 - 5.0))
            .collect();
        (x, y)
    }

    /// A CSO search (pop 10 × 15) of C ∈ [0.01, 100], γ ∈ [1e-3, 10] on log scales.
    fn cso_in_box(seed: u64, warm_start: Option<bool>, thin: usize) -> TuneParams {
        TuneParams {
            svr: SvrParams::default(),
            c_bounds: (0.01, 100.0),
            gamma_bounds: (1e-3, 10.0),
            scale: Scale::Log,
            search: Search::Cso(CsoParams {
                pop: 10,
                iters: 15,
                seed,
                ..Default::default()
            }),
            warm_start,
            thin,
        }
    }

    /// The search's CV error is below that of each corner of [`cso_in_box`]'s box.
    fn beats_the_corners(
        r: &TuneResult,
        s: Samples<'_>,
        y: &[f64],
        splits: &[Split],
        tp: &TuneParams,
    ) {
        for (c, g) in [(0.01, 1e-3), (100.0, 10.0), (0.01, 10.0), (100.0, 1e-3)] {
            let corner = cv_mse(s, y, splits, &tp.svr_at(c, g)).unwrap();
            assert!(r.cv_mse < corner, "{} vs corner {corner}", r.cv_mse);
        }
    }

    #[test]
    fn tuning_finds_a_better_cv_error_than_the_corners_and_is_deterministic() {
        let n = 45;
        let (x, y) = curve(n);
        let s = Samples::new(&x, n, 3).unwrap();
        let folds = kfold_splits(n, 5, Some(1)).unwrap();
        let tp = cso_in_box(7, Some(true), 1);
        let mut calls = 0;
        let r = tune_svr(s, &y, &folds, &tp, |_, _| calls += 1).unwrap();
        assert_eq!(calls, 16); // the initial population, then 15 generations
        beats_the_corners(&r, s, &y, &folds, &tp);
        let again = tune_svr(s, &y, &folds, &tp, |_, _| {}).unwrap();
        assert_eq!(
            (r.c, r.gamma, r.cv_mse),
            (again.c, again.gamma, again.cv_mse)
        );
        // the reported CV error is the objective at the reported point, warm starts or not:
        // recomputed cold, summed in fold order as cv_mse sums
        let direct = cv_mse(s, &y, &folds, &tp.svr_at(r.c, r.gamma)).unwrap();
        assert_eq!(direct.to_bits(), r.cv_mse.to_bits());
    }

    /// The pruned, memoised search takes the same path as one that fits every fold of every
    /// point, bit for bit, with both swarms and both kinds of splits, and fits fewer folds.
    #[test]
    fn stopping_early_and_memoising_change_nothing_but_the_work() {
        let n = 60;
        let (x, y) = curve(n);
        let s = Samples::new(&x, n, 3).unwrap();
        let searches = [
            Search::Cso(CsoParams {
                pop: 10,
                iters: 15,
                seed: 3,
                ..Default::default()
            }),
            Search::Pso(PsoParams {
                pop: 10,
                iters: 15,
                seed: 3,
                ..Default::default()
            }),
        ];
        let time = time_series_split(n, 4, 0, None, None).unwrap();
        let shuffled = kfold_splits(n, 4, Some(2)).unwrap();
        for search in searches {
            for splits in [&time, &shuffled] {
                let tp = TuneParams {
                    svr: SvrParams::default(),
                    c_bounds: (0.01, 10.0),
                    gamma_bounds: (1e-3, 1.0),
                    scale: Scale::Log,
                    search: search.clone(),
                    warm_start: Some(false),
                    thin: 1,
                };
                let r = tune_svr(s, &y, splits, &tp, |_, _| {}).unwrap();
                // each fit forming its kernel from the rows (a data set above the sharing
                // limit): the same search
                let own = search_with(s, &y, splits, &tp, |_, _| {}, 0).unwrap();
                assert_eq!(
                    (r.c.to_bits(), r.gamma.to_bits(), r.cv_mse.to_bits(), r.cost),
                    (
                        own.c.to_bits(),
                        own.gamma.to_bits(),
                        own.cv_mse.to_bits(),
                        own.cost
                    )
                );
                // the plain search: every fold of every point
                let parts = split(s, &y, splits);
                let full = |pop: &[Vec<f64>]| -> Result<Vec<f64>> {
                    Ok(pop
                        .iter()
                        .map(|v| {
                            let (c, g) = tp.decode(v);
                            parts
                                .iter()
                                .map(|f| fold_mse(f, 3, &tp.svr_at(c, g)))
                                .sum::<f64>()
                                / parts.len() as f64
                        })
                        .collect())
                };
                let b = tp.bounds().unwrap();
                let plain = match &tp.search {
                    Search::Cso(p) => crate::swarm::cso_minimize_batch(full, &b, p),
                    Search::Pso(p) => crate::swarm::pso_minimize_batch(full, &b, p),
                }
                .unwrap();
                let (c, g) = tp.decode(&plain.x);
                assert_eq!(
                    (r.c.to_bits(), r.gamma.to_bits(), r.cv_mse.to_bits()),
                    (c.to_bits(), g.to_bits(), plain.f.to_bits()),
                    "{search:?}"
                );
                assert_eq!(r.history, plain.history);
                assert_eq!(r.cost.full, plain.n_evals * splits.len());
                assert!(r.cost.fits < r.cost.full, "{:?}", r.cost);
            }
        }
    }

    #[test]
    fn thinning_keeps_every_kth_row_and_names_an_emptied_fold() {
        let n = 20;
        let (x, y) = curve(n);
        let s = Samples::new(&x, n, 3).unwrap();
        // test blocks 5..10, 10..15, 15..20, each trained on the rows before it
        let splits = time_series_split(n, 3, 0, None, None).unwrap();
        let (tx, ty, ts) = thinned(s, &y, &splits, 3).unwrap();
        let rows = [0, 3, 6, 9, 12, 15, 18];
        assert_eq!(ty, rows.map(|i| y[i]));
        assert_eq!(&tx[2 * 3..3 * 3], s.row(6));
        // train 0..5 -> rows 0, 3 -> 0, 1; test 5..10 -> rows 6, 9 -> 2, 3
        assert_eq!(
            ts[0],
            Split {
                train: vec![0, 1],
                test: vec![2, 3]
            }
        );
        assert_eq!(ts[2].train, vec![0, 1, 2, 3, 4]);
        // every 7th row: 0, 7, 14, none in the last test block 15..20
        let e = thinned(s, &y, &splits, 7).unwrap_err().to_string();
        assert!(e.contains("fold 2 without a test row"), "{e}");
    }

    #[test]
    fn auto_thin_aims_at_thin_rows_and_keeps_every_split_whole() {
        let at = |train: usize, test: Vec<usize>| Split {
            train: (0..train).collect(),
            test,
        };
        assert_eq!(auto_thin(&[at(THIN_ROWS, vec![THIN_ROWS])]), 1);
        assert_eq!(auto_thin(&[at(THIN_ROWS + 1, vec![THIN_ROWS + 2])]), 2);
        let six = time_series_split(6000, 5, 0, None, None).unwrap();
        assert_eq!(auto_thin(&six), 5); // largest training set 5 000 rows
                                        // a one-row test block off every stride k <= 3 except 1
        assert_eq!(auto_thin(&[at(3 * THIN_ROWS, vec![3 * THIN_ROWS + 1])]), 1);
    }

    /// A thinned search reports the objective on every row at its point (what cv_mse gives,
    /// bit for bit), the same on every run, and a point better than the box's corners. (How
    /// close it comes to the plain search is measured on the shop run: docs/methods.md.)
    #[test]
    fn a_thinned_search_reports_the_full_objective_at_its_point() {
        let n = 400;
        let (x, y) = curve(n);
        let s = Samples::new(&x, n, 3).unwrap();
        let splits = time_series_split(n, 4, 0, None, None).unwrap();
        let tp = |thin: usize| cso_in_box(5, None, thin);
        let r = tune_svr(s, &y, &splits, &tp(4), |_, _| {}).unwrap();
        assert_eq!(r.thin, 4);
        let direct = cv_mse(s, &y, &splits, &tp(4).svr_at(r.c, r.gamma)).unwrap();
        assert_eq!(direct.to_bits(), r.cv_mse.to_bits());
        let again = tune_svr(s, &y, &splits, &tp(4), |_, _| {}).unwrap();
        assert_eq!(
            (r.c.to_bits(), r.gamma.to_bits(), r.cv_mse.to_bits()),
            (
                again.c.to_bits(),
                again.gamma.to_bits(),
                again.cv_mse.to_bits()
            )
        );
        beats_the_corners(&r, s, &y, &splits, &tp(1));
    }
}
