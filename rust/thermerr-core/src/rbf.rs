//! Radial basis function networks (seeds 001 and 003): a Gaussian hidden layer with MATLAB's
//! `radbas` convention, φ(r) = exp(−(b·r)²) with b = √(ln 2)/spread (so φ = 0.5 at r = spread),
//! and a linear output with a bias, y = Σ wᵢ φ(‖x − cᵢ‖) + b₀.
//!
//! Designs: `Exact` (MATLAB `newrbe`: a neuron on every training sample, bordered interpolation
//! system with Σw = 0), `Ols` (MATLAB `newrb`:
//! forward orthogonal least squares, Chen–Cowan–Grant 1991, adding the training vector that lowers
//! the sum-squared error most — or, with `Rule::MaxError`, the one with the largest residual —
//! until the goal or the neuron cap; on more than `max_candidates` samples the candidates are a
//! seeded k-means++ pool of `max_candidates` training vectors) and `KMeans` (k-means centres,
//! least-squares weights).

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::{parse_name, Error, Result};
#[cfg(feature = "fit")]
use crate::kmeans::{kmeans, kmeans_plus_plus, kmeans_plus_plus_indices};
#[cfg(feature = "fit")]
use crate::linalg::{lstsq, solve};
use crate::linear::check_features;
#[cfg(feature = "fit")]
use crate::samples::check_target;
use crate::samples::{sq_dist, Matrix, Samples};
#[cfg(feature = "fit")]
use rayon::prelude::*;

/// Default candidate pool of the OLS design: every training vector up to this many samples, a
/// seeded k-means++ pool of this many above.
pub const MAX_CANDIDATES: usize = 500;

fn default_max_candidates() -> usize {
    MAX_CANDIDATES
}

/// √(−ln 0.5): MATLAB's radbas width constant (0.8326).
pub const RADBAS: f64 = 0.832_554_611_157_697_7;

/// How the hidden layer is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Design {
    Exact,
    Ols,
    KMeans,
}

impl Design {
    const NAMES: [(&'static str, Design); 3] = [
        ("exact", Design::Exact),
        ("ols", Design::Ols),
        ("kmeans", Design::KMeans),
    ];
}

impl FromStr for Design {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_name("design", s, &Self::NAMES)
    }
}

/// How the incremental design picks its next neuron.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Rule {
    /// The training vector whose neuron lowers the sum-squared error most (newrb).
    Ols,
    /// The training vector with the largest current |residual| (seed 003's text).
    MaxError,
}

impl Rule {
    const NAMES: [(&'static str, Rule); 2] = [("ols", Rule::Ols), ("max_error", Rule::MaxError)];
}

impl FromStr for Rule {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_name("rule", s, &Self::NAMES)
    }
}

/// Hyper-parameters of an RBF network; a consuming builder with defaults, checked by
/// [`RbfParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub struct RbfParams(RbfValidParams);

/// Checked hyper-parameters; [`RbfValidParams::fit`] trains the network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RbfValidParams {
    pub design: Design,
    pub spread: f64,
    /// Sum-squared-error goal of the OLS design.
    pub goal: f64,
    pub max_neurons: Option<usize>,
    pub n_centers: Option<usize>,
    pub seed: Option<u64>,
    pub rule: Rule,
    /// Candidate pool of the OLS design: with more samples than this, the candidates are this
    /// many training vectors picked by k-means++ (seeded by `seed`); otherwise every sample.
    #[serde(default = "default_max_candidates")]
    pub max_candidates: usize,
}

impl Default for RbfParams {
    /// Exact design, spread 1, SSE goal 0, no neuron cap, min(n, 10) k-means centres, k-means++
    /// seed 0, the OLS selection rule, [`MAX_CANDIDATES`] OLS candidates.
    fn default() -> Self {
        RbfParams(RbfValidParams {
            design: Design::Exact,
            spread: 1.0,
            goal: 0.0,
            max_neurons: None,
            n_centers: None,
            seed: None,
            rule: Rule::Ols,
            max_candidates: MAX_CANDIDATES,
        })
    }
}

impl RbfParams {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn design(mut self, design: Design) -> Self {
        self.0.design = design;
        self
    }

    /// Width of every neuron in input units (φ = 0.5 at this distance), > 0.
    pub fn spread(mut self, spread: f64) -> Self {
        self.0.spread = spread;
        self
    }

    /// Sum-squared-error goal of the OLS design, >= 0.
    pub fn goal(mut self, goal: f64) -> Self {
        self.0.goal = goal;
        self
    }

    /// Neuron cap of the OLS design (`None`: the number of samples).
    pub fn max_neurons(mut self, max_neurons: Option<usize>) -> Self {
        self.0.max_neurons = max_neurons;
        self
    }

    /// Centres of the k-means design (`None`: min(n, 10)).
    pub fn n_centers(mut self, n_centers: Option<usize>) -> Self {
        self.0.n_centers = n_centers;
        self
    }

    /// Seed of the k-means++ start, and of the OLS candidate pool (`None`: 0).
    pub fn seed(mut self, seed: Option<u64>) -> Self {
        self.0.seed = seed;
        self
    }

    pub fn rule(mut self, rule: Rule) -> Self {
        self.0.rule = rule;
        self
    }

    /// Candidate pool of the OLS design, >= 1: on at most this many samples every training
    /// vector is a candidate (the exhaustive newrb search, O(n²) memory and O(n²) per neuron);
    /// on more, a k-means++ pool of this many training vectors seeded by `seed` (O(n·m) memory
    /// and per neuron, at most m neurons).
    pub fn max_candidates(mut self, max_candidates: usize) -> Self {
        self.0.max_candidates = max_candidates;
        self
    }

    /// Validates everything that does not depend on the data.
    pub fn check(self) -> Result<RbfValidParams> {
        let p = self.0;
        if !(p.spread.is_finite() && p.spread > 0.0) {
            return Err(Error::param(
                "spread",
                format!("must be > 0, got {}", p.spread),
            ));
        }
        if !(p.goal.is_finite() && p.goal >= 0.0) {
            return Err(Error::param(
                "goal",
                format!("must be >= 0, got {}", p.goal),
            ));
        }
        if p.max_neurons == Some(0) {
            return Err(Error::param("max_neurons", "must be >= 1"));
        }
        if p.n_centers == Some(0) {
            return Err(Error::param("n_centers", "must be >= 1"));
        }
        if p.max_candidates == 0 {
            return Err(Error::param("max_candidates", "must be >= 1"));
        }
        Ok(p)
    }
}

/// A fitted RBF network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RbfModel {
    pub centers: Matrix,
    pub spread: f64,
    pub weights: Vec<f64>,
    pub bias: f64,
    /// Training-sample index of each centre (exact and OLS designs).
    pub selected: Vec<usize>,
    /// Sum-squared training error after each neuron (OLS design; bias only first).
    #[serde(default)]
    pub sse_history: Vec<f64>,
}

#[cfg(feature = "fit")]
fn design_matrix(x: Samples<'_>, centers: &Matrix, b: f64) -> faer::Mat<f64> {
    let k = centers.nrows();
    let rows: Vec<Vec<f64>> = (0..x.nrows())
        .into_par_iter()
        .map(|i| {
            (0..k)
                .map(|j| (-(b * b) * sq_dist(x.row(i), centers.row(j))).exp())
                .collect()
        })
        .collect();
    faer::Mat::from_fn(
        x.nrows(),
        k + 1,
        |i, j| if j == k { 1.0 } else { rows[i][j] },
    )
}

#[cfg(feature = "fit")]
fn rows_of(x: Samples<'_>, idx: &[usize]) -> Matrix {
    let mut data = Vec::with_capacity(idx.len() * x.ncols());
    for &i in idx {
        data.extend_from_slice(x.row(i));
    }
    Matrix {
        shape: [idx.len(), x.ncols()],
        data,
    }
}

#[cfg(feature = "fit")]
impl RbfValidParams {
    /// Trains on the rows of `x` to the targets `y`.
    pub fn fit(&self, x: Samples<'_>, y: &[f64]) -> Result<RbfModel> {
        x.require_finite("X")?;
        check_target(y, x.nrows())?;
        let n = x.nrows();
        if let Some(c) = self.n_centers.filter(|&c| c > n) {
            return Err(Error::param(
                "n_centers",
                format!("must be within 1..={n}, got {c}"),
            ));
        }
        let b = RADBAS / self.spread;
        match self.design {
            Design::Exact => {
                let idx: Vec<usize> = (0..n).collect();
                let centers = rows_of(x, &idx);
                // interpolation with a constant term: [Φ 1; 1ᵀ 0][w; b] = [y; 0] (Σw = 0 fixes
                // the one degree of freedom the bias adds), solved by LU; if that system is
                // singular to working precision, the minimum-norm least-squares solution
                let a = design_matrix(x, &centers, b);
                let sq = faer::Mat::from_fn(n + 1, n + 1, |i, j| {
                    if i < n {
                        a[(i, j)]
                    } else if j < n {
                        1.0
                    } else {
                        0.0
                    }
                });
                let mut rhs = y.to_vec();
                rhs.push(0.0);
                let sol = match solve(sq.as_ref(), &rhs) {
                    Ok(s) => s,
                    Err(_) => lstsq(a.as_ref(), y)?,
                };
                Ok(self.finish(centers, sol, idx, Vec::new()))
            }
            Design::KMeans => {
                let k = self.n_centers.unwrap_or(n.min(10));
                let init = kmeans_plus_plus(x, k, self.seed.unwrap_or(0))?;
                let km = kmeans(x, &init, 300)?;
                let a = design_matrix(x, &km.centers, b);
                let sol = lstsq(a.as_ref(), y)?;
                Ok(self.finish(km.centers, sol, Vec::new(), Vec::new()))
            }
            Design::Ols => self.fit_ols(x, y, b),
        }
    }

    fn finish(
        &self,
        centers: Matrix,
        sol: Vec<f64>,
        selected: Vec<usize>,
        sse: Vec<f64>,
    ) -> RbfModel {
        let k = centers.nrows();
        RbfModel {
            centers,
            spread: self.spread,
            weights: sol[..k].to_vec(),
            bias: sol[k],
            selected,
            sse_history: sse,
        }
    }

    /// The OLS candidates, ascending: every sample when there are at most `max_candidates`,
    /// else the `max_candidates` samples k-means++ picks (seeded by `seed`, duplicates dropped).
    fn candidate_pool(&self, x: Samples<'_>) -> Result<Vec<usize>> {
        let n = x.nrows();
        if n <= self.max_candidates {
            return Ok((0..n).collect());
        }
        let mut pool = kmeans_plus_plus_indices(x, self.max_candidates, self.seed.unwrap_or(0))?;
        pool.sort_unstable();
        pool.dedup();
        Ok(pool)
    }

    /// Forward selection with modified Gram–Schmidt: every remaining candidate column is kept
    /// orthogonal to the bias and to the neurons chosen so far, so the error reduction of each
    /// candidate is (wᵀy)²/(wᵀw); one step costs O(n·m) for m candidates (m = n: O(n²)). The
    /// candidates are updated in parallel, each with its own sums in a fixed order, so the result
    /// does not depend on the thread count. With every sample a candidate the sums run left to
    /// right (the arithmetic of the original exhaustive search, bit for bit); with a pool they
    /// run in eight interleaved lanes (vectorised).
    fn fit_ols(&self, x: Samples<'_>, y: &[f64], b: f64) -> Result<RbfModel> {
        struct Cand {
            idx: usize,
            col: Vec<f64>,
            scale: f64,
            ww: f64,
            wy: f64,
            used: bool,
        }
        let n = x.nrows();
        let pool = self.candidate_pool(x)?;
        let lanes = pool.len() < n;
        let dot = |a: &[f64], b: &[f64]| {
            if lanes {
                crate::linalg::dot(a, b)
            } else {
                dot_seq(a, b)
            }
        };
        let cap = self.max_neurons.unwrap_or(n).min(pool.len());
        let mean = y.iter().sum::<f64>() / n as f64;
        let mut resid: Vec<f64> = y.iter().map(|v| v - mean).collect();
        let min_len = (1 << 15) / n.max(1) + 1;
        let mut cand: Vec<Cand> = pool
            .par_iter()
            .with_min_len(min_len)
            .map(|&j| {
                let mut col: Vec<f64> = (0..n)
                    .map(|i| (-(b * b) * sq_dist(x.row(i), x.row(j))).exp())
                    .collect();
                let m = col.iter().sum::<f64>() / n as f64;
                col.iter_mut().for_each(|v| *v -= m);
                let scale = dot(&col, &col);
                Cand {
                    idx: j,
                    scale,
                    ww: scale,
                    wy: dot(&col, &resid),
                    col,
                    used: false,
                }
            })
            .collect();
        let mut sse = dot(&resid, &resid);
        let mut history = vec![sse];
        let mut selected = Vec::new();
        while selected.len() < cap && sse > self.goal {
            crate::interrupt::check()?;
            let mut best: Option<(f64, usize)> = None;
            for (k, c) in cand.iter().enumerate() {
                if c.used || c.ww <= 1e-12 * c.scale.max(f64::MIN_POSITIVE) {
                    continue;
                }
                let key = match self.rule {
                    Rule::Ols => c.wy * c.wy / c.ww,
                    Rule::MaxError => resid[c.idx].abs(),
                };
                if best.is_none_or(|(v, _)| key > v) {
                    best = Some((key, k));
                }
            }
            let Some((_, s)) = best else { break };
            let chosen = &mut cand[s];
            chosen.used = true;
            selected.push(chosen.idx);
            let (ww, wy) = (chosen.ww, chosen.wy);
            let w = std::mem::take(&mut chosen.col);
            for (r, wi) in resid.iter_mut().zip(&w) {
                *r -= wy / ww * wi;
            }
            sse = dot(&resid, &resid);
            history.push(sse);
            if selected.len() == cap || sse <= self.goal {
                break;
            }
            cand.par_iter_mut()
                .with_min_len(min_len)
                .filter(|c| !c.used)
                .for_each(|c| {
                    let p = dot(&c.col, &w) / ww;
                    for (ci, wi) in c.col.iter_mut().zip(&w) {
                        *ci -= p * wi;
                    }
                    c.ww = dot(&c.col, &c.col);
                    c.wy = dot(&c.col, &resid);
                });
        }
        drop(cand);
        let centers = rows_of(x, &selected);
        let a = design_matrix(x, &centers, b);
        let sol = lstsq(a.as_ref(), y)?;
        Ok(self.finish(centers, sol, selected, history))
    }
}

/// Σ aᵢbᵢ left to right.
#[cfg(feature = "fit")]
#[inline]
fn dot_seq(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

impl RbfModel {
    pub fn n_features(&self) -> usize {
        self.centers.ncols()
    }

    /// Checks a model read from a file: one weight per centre, a positive spread, finite numbers.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(crate::Error::Format(format!("rbf model: {m}")));
        if self.centers.ncols() == 0 {
            return bad("centres with no features".into());
        }
        if self.weights.len() != self.centers.nrows() {
            return bad(format!(
                "{} weights for {} centres",
                self.weights.len(),
                self.centers.nrows()
            ));
        }
        if !(self.spread > 0.0 && self.spread.is_finite()) {
            return bad(format!("spread must be > 0, got {}", self.spread));
        }
        crate::samples::require_finite_model("rbf", "centers", &self.centers.data)?;
        crate::samples::require_finite_model("rbf", "weights", &self.weights)?;
        crate::samples::require_finite_model("rbf", "bias", &[self.bias])
    }

    /// One sample, no allocation.
    #[inline]
    pub fn predict_one(&self, x: &[f64]) -> f64 {
        let b = RADBAS / self.spread;
        let b2 = b * b;
        let mut acc = self.bias;
        for (j, w) in self.weights.iter().enumerate() {
            acc += w * (-b2 * sq_dist(x, self.centers.row(j))).exp();
        }
        acc
    }

    pub fn predict(&self, x: Samples<'_>) -> Result<Vec<f64>> {
        check_features(x.ncols(), self.n_features())?;
        x.require_finite("X")?;
        crate::samples::require_finite_predictions("rbf", self.predict_unchecked(x))
    }

    fn predict_unchecked(&self, x: Samples<'_>) -> Vec<f64> {
        #[cfg(not(feature = "fit"))]
        return x.rows().map(|r| self.predict_one(r)).collect();
        #[cfg(feature = "fit")]
        if x.nrows() * self.weights.len() * x.ncols() < 1 << 16 {
            return x.rows().map(|r| self.predict_one(r)).collect();
        }
        #[cfg(feature = "fit")]
        (0..x.nrows())
            .into_par_iter()
            .map(|i| self.predict_one(x.row(i)))
            .collect()
    }
}

#[cfg(all(test, feature = "fit"))]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn data() -> (Vec<f64>, Vec<f64>) {
        let x: Vec<f64> = (0..30)
            .flat_map(|i| [i as f64 / 10.0, ((i * 7) % 11) as f64 / 10.0])
            .collect();
        let y = x
            .chunks(2)
            .map(|r| (r[0]).sin() + 0.5 * r[1] * r[1])
            .collect();
        (x, y)
    }

    #[test]
    fn exact_interpolates() {
        let (x, y) = data();
        let s = Samples::new(&x, 30, 2).unwrap();
        let net = RbfParams::new()
            .spread(0.5)
            .check()
            .unwrap()
            .fit(s, &y)
            .unwrap();
        for (p, t) in net.predict(s).unwrap().iter().zip(&y) {
            assert_relative_eq!(p, t, epsilon = 1e-8);
        }
    }

    #[test]
    fn ols_sse_decreases_and_stops_at_goal() {
        let (x, y) = data();
        let s = Samples::new(&x, 30, 2).unwrap();
        let p = RbfParams::new()
            .design(Design::Ols)
            .spread(0.8)
            .goal(0.01)
            .check()
            .unwrap();
        let net = p.fit(s, &y).unwrap();
        assert!(net.sse_history.windows(2).all(|w| w[1] <= w[0] + 1e-12));
        assert!(*net.sse_history.last().unwrap() <= 0.01);
        assert!(net.sse_history[net.sse_history.len() - 2] > 0.01);
        let pred = net.predict(s).unwrap();
        let sse: f64 = pred.iter().zip(&y).map(|(a, b)| (a - b) * (a - b)).sum();
        assert_relative_eq!(sse, *net.sse_history.last().unwrap(), epsilon = 1e-8);
    }

    #[test]
    fn ols_pool_above_max_candidates() {
        // 300 samples, a pool of 40: the pool path (k-means++ candidates, lane sums)
        let x: Vec<f64> = (0..300)
            .flat_map(|i| [(i as f64 * 0.37).sin(), (i as f64 * 0.11).cos()])
            .collect();
        let y: Vec<f64> = x
            .chunks(2)
            .map(|r| (2.0 * r[0]).sin() + r[1] * r[1])
            .collect();
        let s = Samples::new(&x, 300, 2).unwrap();
        let p = RbfParams::new()
            .design(Design::Ols)
            .spread(0.7)
            .max_candidates(40)
            .check()
            .unwrap();
        let net = p.fit(s, &y).unwrap();
        let pool = p.candidate_pool(s).unwrap();
        assert_eq!(pool.len(), 40);
        assert!(pool.windows(2).all(|w| w[0] < w[1]));
        assert!(net.selected.iter().all(|i| pool.contains(i)));
        assert!(net.selected.len() <= 40);
        assert!(net.sse_history.windows(2).all(|w| w[1] <= w[0] + 1e-9));
        let pred = net.predict(s).unwrap();
        let sse: f64 = pred.iter().zip(&y).map(|(a, b)| (a - b) * (a - b)).sum();
        assert_relative_eq!(
            sse,
            *net.sse_history.last().unwrap(),
            max_relative = 1e-6,
            epsilon = 1e-9
        );
        assert_eq!(net, p.fit(s, &y).unwrap());
        // a pool of every sample is the exhaustive search
        let all = p.clone();
        let all = RbfValidParams {
            max_candidates: 300,
            max_neurons: Some(10),
            ..all
        };
        assert_eq!(all.candidate_pool(s).unwrap(), (0..300).collect::<Vec<_>>());
        assert_eq!(all.fit(s, &y).unwrap().selected.len(), 10);
    }

    #[test]
    fn the_lane_dot_is_a_dot_product() {
        let a: Vec<f64> = (0..37).map(|i| (i as f64).sin()).collect();
        let b: Vec<f64> = (0..37).map(|i| (i as f64 * 0.3).cos()).collect();
        for k in [0, 1, 7, 8, 9, 16, 37] {
            assert_relative_eq!(
                crate::linalg::dot(&a[..k], &b[..k]),
                dot_seq(&a[..k], &b[..k]),
                epsilon = 1e-12
            );
        }
    }

    #[test]
    fn refuses_bad_params() {
        let (x, y) = data();
        let s = Samples::new(&x, 30, 2).unwrap();
        assert!(RbfParams::new().spread(0.0).check().is_err());
        assert!(RbfParams::new().n_centers(Some(0)).check().is_err());
        assert!(RbfParams::new().max_candidates(0).check().is_err());
        assert!(RbfParams::new()
            .design(Design::KMeans)
            .n_centers(Some(31))
            .check()
            .unwrap()
            .fit(s, &y)
            .is_err());
    }

    #[test]
    fn names_parse_as_serde_reads_them() {
        crate::error::assert_names_agree(&Design::NAMES);
        crate::error::assert_names_agree(&Rule::NAMES);
        let e = "magic".parse::<Design>().unwrap_err().to_string();
        assert!(
            e.contains(r#"must be "exact", "ols" or "kmeans", got "magic""#),
            "{e}"
        );
    }

    #[test]
    fn autotraits() {
        fn is_send_sync<T: Send + Sync>() {}
        is_send_sync::<RbfParams>();
        is_send_sync::<RbfValidParams>();
        is_send_sync::<RbfModel>();
    }
}
