//! ε-support vector regression (seed 004), solved by SMO exactly as LIBSVM (and so scikit-learn's
//! `SVR`) does: the 2l-variable dual of Chang & Lin, second-order working-set selection (Fan, Chen
//! & Lin 2005), shrinking with gradient reconstruction, an LRU cache of single-precision kernel
//! columns, and the same stopping rule (max violation < `tol`).
//!
//! The dual: minimise ½ (α − α*)ᵀ K (α − α*) + ε Σ (αᵢ + αᵢ*) − Σ yᵢ (αᵢ − αᵢ*) subject to
//! Σ (αᵢ − αᵢ*) = 0 and 0 ≤ αᵢ, αᵢ* ≤ C. The prediction is f(x) = Σ_s β_s k(x, x_s) + b with
//! β = α − α* over the support vectors (β ≠ 0) and b = −ρ.
//!
//! Kernel values in the solver follow LIBSVM's arithmetic to the bit: ‖xᵢ‖² + ‖xⱼ‖² − 2 xᵢ·xⱼ
//! with sequential sums, `exp` in double, then rounded to `f32` for the cache (LIBSVM's `Qfloat`).

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::{parse_name, Error, Result};
use crate::linear::check_features;
#[cfg(feature = "fit")]
use crate::samples::check_target;
use crate::samples::{Matrix, Samples};

/// The kernel of a fitted SVR.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Kernel {
    /// k(x, x') = exp(−γ‖x − x'‖²)
    Rbf { gamma: f64 },
    /// k(x, x') = x·x'
    Linear,
}

impl Kernel {
    /// One kernel value as LIBSVM's `k_function` computes it at prediction time.
    #[inline]
    pub fn eval(&self, x: &[f64], sv: &[f64]) -> f64 {
        match *self {
            Kernel::Rbf { gamma } => (-gamma * sq_diff(x, sv)).exp(),
            Kernel::Linear => dot(x, sv),
        }
    }
}

/// Σ (aᵢ − bᵢ)², summed in order: `k_function`'s squared distance.
#[inline]
fn sq_diff(a: &[f64], b: &[f64]) -> f64 {
    let mut sum = 0.0;
    for (x, y) in a.iter().zip(b) {
        let d = x - y;
        sum += d * d;
    }
    sum
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = 0.0;
    for (x, y) in a.iter().zip(b) {
        s += x * y;
    }
    s
}

/// A fitted ε-SVR: f(x) = Σ_s dual_coef_s · k(x, sv_s) + intercept.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SvrModel {
    pub kernel: Kernel,
    /// Support vectors, one per row, in training order.
    pub support_vectors: Matrix,
    /// αᵢ − αᵢ* of each support vector.
    pub dual_coef: Vec<f64>,
    pub intercept: f64,
    /// Training indices of the support vectors.
    #[serde(default)]
    pub support: Vec<usize>,
    /// SMO iterations the solver took.
    #[serde(default)]
    pub n_iter: usize,
}

impl SvrModel {
    pub fn n_features(&self) -> usize {
        self.support_vectors.ncols()
    }

    /// Checks a model read from a file: one dual coefficient (and training index, if any) per
    /// support vector, a positive γ, finite numbers.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(crate::Error::Format(format!("svr model: {m}")));
        let n_sv = self.support_vectors.nrows();
        if self.support_vectors.ncols() == 0 {
            return bad("support vectors with no features".into());
        }
        if self.dual_coef.len() != n_sv {
            return bad(format!(
                "{} dual coefficients for {n_sv} support vectors",
                self.dual_coef.len()
            ));
        }
        if !self.support.is_empty() && self.support.len() != n_sv {
            return bad(format!(
                "{} support indices for {n_sv} support vectors",
                self.support.len()
            ));
        }
        if let Kernel::Rbf { gamma } = self.kernel {
            if !(gamma > 0.0 && gamma.is_finite()) {
                return bad(format!("gamma must be > 0, got {gamma}"));
            }
        }
        crate::samples::require_finite_model("svr", "support_vectors", &self.support_vectors.data)?;
        crate::samples::require_finite_model("svr", "dual_coef", &self.dual_coef)?;
        crate::samples::require_finite_model("svr", "intercept", &[self.intercept])
    }

    /// One sample, no allocation; the sum runs over the support vectors in order, as LIBSVM's.
    #[inline]
    pub fn predict_one(&self, x: &[f64]) -> f64 {
        let mut sum = 0.0;
        for (s, c) in self.dual_coef.iter().enumerate() {
            sum += c * self.kernel.eval(x, self.support_vectors.row(s));
        }
        sum + self.intercept
    }

    pub fn predict(&self, x: Samples<'_>) -> Result<Vec<f64>> {
        check_features(x.ncols(), self.n_features())?;
        x.require_finite("X")?;
        crate::samples::require_finite_predictions("svr", self.predict_unchecked(x))
    }

    fn predict_unchecked(&self, x: Samples<'_>) -> Vec<f64> {
        #[cfg(feature = "fit")]
        if x.nrows() * self.dual_coef.len() * x.ncols() >= 1 << 16 {
            use rayon::prelude::*;
            return (0..x.nrows())
                .into_par_iter()
                .map(|i| self.predict_one(x.row(i)))
                .collect();
        }
        x.rows().map(|r| self.predict_one(r)).collect()
    }
}

/// γ of the RBF kernel, with scikit-learn's names.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Gamma {
    /// 1 / (n_features · Var(X)), the variance over all entries of X (1 if that is 0).
    Scale,
    /// 1 / n_features.
    Auto,
    Value(f64),
}

impl FromStr for Gamma {
    type Err = Error;
    /// The names only ("scale", "auto"); a number is [`Gamma::Value`].
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "scale" => Ok(Gamma::Scale),
            "auto" => Ok(Gamma::Auto),
            other => Err(Error::param(
                "gamma",
                format!("must be \"scale\", \"auto\" or a positive number, got {other:?}"),
            )),
        }
    }
}

/// Which kernel to fit with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum KernelKind {
    Rbf,
    Linear,
}

impl KernelKind {
    const NAMES: [(&'static str, KernelKind); 2] =
        [("rbf", KernelKind::Rbf), ("linear", KernelKind::Linear)];
}

impl FromStr for KernelKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_name("kernel", s, &Self::NAMES)
    }
}

/// Hyper-parameters of an ε-SVR; a consuming builder with scikit-learn's meaning and defaults,
/// checked by [`SvrParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub struct SvrParams(SvrValidParams);

/// Checked hyper-parameters; [`SvrValidParams::fit`] solves the dual.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SvrValidParams {
    pub c: f64,
    pub epsilon: f64,
    pub kernel: KernelKind,
    pub gamma: Gamma,
    /// Stopping tolerance on the maximal violating pair (LIBSVM's `-e`).
    pub tol: f64,
    pub shrinking: bool,
    /// Kernel cache in MiB.
    pub cache_size: f64,
    /// Iteration cap; `None` = no limit (scikit-learn's −1).
    pub max_iter: Option<usize>,
}

impl Default for SvrParams {
    /// scikit-learn's: C = 1, ε = 0.1, RBF kernel with γ = "scale", tol = 1e-3, shrinking, a
    /// 200 MiB cache, no iteration cap.
    fn default() -> Self {
        SvrParams(SvrValidParams {
            c: 1.0,
            epsilon: 0.1,
            kernel: KernelKind::Rbf,
            gamma: Gamma::Scale,
            tol: 1e-3,
            shrinking: true,
            cache_size: 200.0,
            max_iter: None,
        })
    }
}

impl SvrParams {
    pub fn new() -> Self {
        Self::default()
    }

    /// Box constraint of the dual variables, > 0.
    pub fn c(mut self, c: f64) -> Self {
        self.0.c = c;
        self
    }

    /// Half-width of the ε-insensitive tube, >= 0.
    pub fn epsilon(mut self, epsilon: f64) -> Self {
        self.0.epsilon = epsilon;
        self
    }

    pub fn kernel(mut self, kernel: KernelKind) -> Self {
        self.0.kernel = kernel;
        self
    }

    pub fn gamma(mut self, gamma: Gamma) -> Self {
        self.0.gamma = gamma;
        self
    }

    pub fn tol(mut self, tol: f64) -> Self {
        self.0.tol = tol;
        self
    }

    pub fn shrinking(mut self, shrinking: bool) -> Self {
        self.0.shrinking = shrinking;
        self
    }

    /// Kernel cache in MiB, > 0.
    pub fn cache_size(mut self, cache_size: f64) -> Self {
        self.0.cache_size = cache_size;
        self
    }

    pub fn max_iter(mut self, max_iter: Option<usize>) -> Self {
        self.0.max_iter = max_iter;
        self
    }

    /// Validates every parameter (none depends on the data).
    pub fn check(self) -> Result<SvrValidParams> {
        let p = self.0;
        if !(p.c > 0.0 && p.c.is_finite()) {
            return Err(Error::param("C", format!("must be > 0, got {}", p.c)));
        }
        if !(p.epsilon >= 0.0 && p.epsilon.is_finite()) {
            return Err(Error::param(
                "epsilon",
                format!("must be >= 0, got {}", p.epsilon),
            ));
        }
        if !(p.tol > 0.0 && p.tol.is_finite()) {
            return Err(Error::param("tol", format!("must be > 0, got {}", p.tol)));
        }
        if !(p.cache_size > 0.0 && p.cache_size.is_finite()) {
            return Err(Error::param(
                "cache_size",
                format!("must be > 0 MiB, got {}", p.cache_size),
            ));
        }
        if let Gamma::Value(g) = p.gamma {
            if !(g > 0.0 && g.is_finite()) {
                return Err(Error::param("gamma", format!("must be > 0, got {g}")));
            }
        }
        Ok(p)
    }
}

/// Resolves `gamma="scale"` on the training matrix as scikit-learn does.
#[cfg(feature = "fit")]
pub fn scale_gamma(x: Samples<'_>) -> f64 {
    let data = x.as_slice();
    let n = data.len() as f64;
    let mean = data.iter().sum::<f64>() / n;
    let var = data.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    if var != 0.0 {
        1.0 / (x.ncols() as f64 * var)
    } else {
        1.0
    }
}

#[cfg(feature = "fit")]
impl SvrValidParams {
    /// The kernel these parameters give on `x` (γ resolved).
    pub fn kernel_for(&self, x: Samples<'_>) -> Kernel {
        match self.kernel {
            KernelKind::Linear => Kernel::Linear,
            KernelKind::Rbf => Kernel::Rbf {
                gamma: match self.gamma {
                    Gamma::Scale => scale_gamma(x),
                    Gamma::Auto => 1.0 / x.ncols() as f64,
                    Gamma::Value(g) => g,
                },
            },
        }
    }

    /// Solves the dual on the rows of `x` with targets `y`.
    pub fn fit(&self, x: Samples<'_>, y: &[f64]) -> Result<SvrModel> {
        x.require_finite("X")?;
        check_target(y, x.nrows())?;
        check_rows(x.nrows())?;
        let kernel = self.kernel_for(x);
        let q = SvrQ::new(Source::Rows(x), kernel, self.cache_size);
        let rows: Vec<usize> = (0..x.nrows()).collect();
        self.solve_q(q, x, &rows, y, None)
    }

    /// [`fit`](Self::fit) on the rows `rows` of the data `shared` was formed from (`x`, all of
    /// it), reading the squared distances from `shared` instead of forming them: the same model,
    /// bit for bit, as `fit` on those rows gathered (`tests::shared_distances_give_the_same_model`).
    /// RBF kernel with γ given as a value only.
    ///
    /// `warm`: start SMO from another solution on the same rows, `(β, C)` with β = α − α* per
    /// row, fitted with that C (a neighbouring point of a search): α and α* are scaled by the
    /// ratio of the Cs, which keeps them feasible. The solver then stops by the same rule, at a
    /// solution as optimal (within `tol`) as a cold start's, but not the same bits.
    pub(crate) fn fit_shared(
        &self,
        x: Samples<'_>,
        rows: &[usize],
        y: &[f64],
        shared: &SharedDistances,
        warm: Option<(&[f64], f64)>,
    ) -> Result<SvrModel> {
        let gamma = match (self.kernel, self.gamma) {
            (KernelKind::Rbf, Gamma::Value(g)) => g,
            _ => {
                return Err(Error::param(
                    "kernel",
                    "shared distances need an RBF kernel with gamma given as a number",
                ))
            }
        };
        check_target(y, rows.len())?;
        check_rows(rows.len())?;
        let kernel = Kernel::Rbf { gamma };
        let q = SvrQ::new(Source::Shared { d: shared, rows }, kernel, self.cache_size);
        let init = match warm {
            Some((beta, c0)) if beta.len() == rows.len() && c0 > 0.0 => {
                let (l, r) = (rows.len(), self.c / c0);
                let mut a = vec![0.0; 2 * l];
                for (k, &b) in beta.iter().enumerate() {
                    // at the old bound exactly: at the new one exactly
                    let v = if b.abs() >= c0 {
                        self.c
                    } else {
                        (b.abs() * r).min(self.c)
                    };
                    a[if b > 0.0 { k } else { k + l }] = v;
                }
                Some(a)
            }
            _ => None,
        };
        self.solve_q(q, x, rows, y, init)
    }

    fn solve_q(
        &self,
        mut q: SvrQ<'_>,
        x: Samples<'_>,
        rows: &[usize],
        y: &[f64],
        init: Option<Vec<f64>>,
    ) -> Result<SvrModel> {
        let kernel = q.kernel;
        let l = rows.len();
        let mut p = Vec::with_capacity(2 * l);
        p.extend(y.iter().map(|v| self.epsilon - v));
        p.extend(y.iter().map(|v| self.epsilon + v));
        let sol = solve(
            &mut q,
            p,
            self.c,
            self.tol,
            self.shrinking,
            self.max_iter,
            init,
        )?;
        let mut support = Vec::new();
        let mut dual_coef = Vec::new();
        for i in 0..l {
            let b = sol.alpha[i] - sol.alpha[i + l];
            if b.abs() > 0.0 {
                support.push(i);
                dual_coef.push(b);
            }
        }
        let mut sv = Vec::with_capacity(support.len() * x.ncols());
        for &i in &support {
            sv.extend_from_slice(x.row(rows[i]));
        }
        Ok(SvrModel {
            kernel,
            support_vectors: Matrix {
                shape: [support.len(), x.ncols()],
                data: sv,
            },
            dual_coef,
            intercept: -sol.rho,
            support,
            n_iter: sol.n_iter,
        })
    }
}

/// The squared distances between all rows of a data set, in both of LIBSVM's forms, formed
/// once so that many RBF fits and predictions on subsets of the rows (a search's folds and
/// points) read them instead of forming each from the features again: `train[i·n + j]` =
/// ‖xᵢ‖² + ‖xⱼ‖² − 2 xᵢ·xⱼ (the solver's), `predict[i·n + j]` = Σ (xᵢ − xⱼ)² (`k_function`'s),
/// sequential sums as LIBSVM's. 16 n² bytes.
#[cfg(feature = "fit")]
pub(crate) struct SharedDistances {
    n: usize,
    train: Vec<f64>,
    predict: Vec<f64>,
}

#[cfg(feature = "fit")]
impl SharedDistances {
    /// Both forms for the rows of `x` (rows in parallel).
    pub(crate) fn new(x: Samples<'_>) -> Self {
        use rayon::prelude::*;
        let n = x.nrows();
        let xsq: Vec<f64> = x.rows().map(|r| dot(r, r)).collect();
        let mut train = vec![0.0; n * n];
        let mut predict = vec![0.0; n * n];
        train
            .par_chunks_mut(n.max(1))
            .zip(predict.par_chunks_mut(n.max(1)))
            .enumerate()
            .for_each(|(i, (t, p))| {
                let xi = x.row(i);
                for j in 0..n {
                    let xj = x.row(j);
                    t[j] = xsq[i] + xsq[j] - 2.0 * dot(xi, xj);
                    p[j] = sq_diff(xi, xj);
                }
            });
        Self { n, train, predict }
    }

    /// Bytes the two forms take for `n` rows.
    pub(crate) fn bytes(n: usize) -> usize {
        16usize.saturating_mul(n).saturating_mul(n)
    }
}

#[cfg(feature = "fit")]
impl SvrModel {
    /// The predictions at the rows `at` of the data `shared` was formed from, for a model fitted
    /// by [`SvrValidParams::fit_shared`] on its rows `rows`: the same numbers, bit for bit, as
    /// [`predict`](Self::predict) on those rows gathered.
    pub(crate) fn predict_shared(
        &self,
        at: &[usize],
        rows: &[usize],
        shared: &SharedDistances,
    ) -> Vec<f64> {
        use rayon::prelude::*;
        let gamma = match self.kernel {
            Kernel::Rbf { gamma } => gamma,
            Kernel::Linear => unreachable!("fit_shared fits RBF models only"),
        };
        let one = |&t: &usize| {
            let d = &shared.predict[t * shared.n..(t + 1) * shared.n];
            let mut sum = 0.0;
            for (c, &s) in self.dual_coef.iter().zip(&self.support) {
                sum += c * (-gamma * d[rows[s]]).exp();
            }
            sum + self.intercept
        };
        if at.len() * self.dual_coef.len() >= 1 << 16 {
            at.par_iter().map(one).collect()
        } else {
            at.iter().map(one).collect()
        }
    }
}

/// Kernel values formed per task when a column is filled.
#[cfg(feature = "fit")]
const FILL_CHUNK: usize = 256;

/// Where the solver's kernel values come from: formed from the rows of the training data, or read
/// from distances formed once for a superset of them.
#[cfg(feature = "fit")]
enum Source<'a> {
    Rows(Samples<'a>),
    Shared {
        d: &'a SharedDistances,
        rows: &'a [usize],
    },
}

/// The SVR's Q matrix over 2l variables (LIBSVM's `SVR_Q`): Q_ts = s_t s_u K(t mod l, u mod l),
/// with the permutation that shrinking applies, over an LRU cache of kernel rows.
#[cfg(feature = "fit")]
struct SvrQ<'a> {
    src: Source<'a>,
    l: usize,
    kernel: Kernel,
    xsq: Vec<f64>,
    /// the training rows transposed (feature-major), for the RBF's column fills
    xt: Vec<f64>,
    cache: Cache,
    /// s_t = ±1 of each (permuted) variable, as f32 so that s_t s_u K is formed exactly as
    /// LIBSVM's `Qfloat` products are.
    sign: Vec<f32>,
    /// The kernel row of each (permuted) variable, as u32: half the bytes of the gathers' index
    /// stream (fewer than 2³¹ rows: `check_rows`).
    index: Vec<u32>,
    qd: Vec<f64>,
}

#[cfg(feature = "fit")]
impl<'a> SvrQ<'a> {
    fn new(src: Source<'a>, kernel: Kernel, cache_mib: f64) -> Self {
        let (l, xsq) = match &src {
            Source::Rows(x) => (x.nrows(), x.rows().map(|r| dot(r, r)).collect()),
            Source::Shared { rows, .. } => (rows.len(), Vec::new()),
        };
        let xt = match (&src, kernel) {
            (Source::Rows(x), Kernel::Rbf { .. }) => {
                let (n, d) = (x.nrows(), x.ncols());
                let mut t = vec![0.0; n * d];
                for (j, r) in x.rows().enumerate() {
                    for (k, &v) in r.iter().enumerate() {
                        t[k * n + j] = v;
                    }
                }
                t
            }
            _ => Vec::new(),
        };
        let mut q = SvrQ {
            src,
            l,
            kernel,
            xsq,
            xt,
            cache: Cache::new(l, cache_mib),
            sign: (0..2 * l).map(|t| if t < l { 1.0 } else { -1.0 }).collect(),
            index: (0..2 * l).map(|t| (t % l) as u32).collect(),
            qd: Vec::new(),
        };
        let qd: Vec<f64> = (0..l).map(|i| q.k(i, i)).collect();
        q.qd = qd.iter().chain(&qd).copied().collect();
        q
    }

    /// LIBSVM's training-time kernel (`kernel_rbf` uses the precomputed squared norms).
    #[inline]
    fn k(&self, i: usize, j: usize) -> f64 {
        match (&self.src, self.kernel) {
            (Source::Rows(x), Kernel::Rbf { gamma }) => {
                let d = dot(x.row(i), x.row(j));
                (-gamma * (self.xsq[i] + self.xsq[j] - 2.0 * d)).exp()
            }
            (Source::Rows(x), Kernel::Linear) => dot(x.row(i), x.row(j)),
            (Source::Shared { d, rows }, Kernel::Rbf { gamma }) => {
                (-gamma * d.train[rows[i] * d.n + rows[j]]).exp()
            }
            (Source::Shared { .. }, Kernel::Linear) => unreachable!("fit_shared is RBF only"),
        }
    }

    /// K(i, j) as f32 for j = start.. into `out`: the same values as [`k`](Self::k), with the
    /// RBF's dot products of a chunk formed in one pass before its `exp`s, so that the
    /// independent sequential sums overlap in the processor instead of waiting on each `exp`.
    fn fill(&self, i: usize, start: usize, out: &mut [f32]) {
        match (&self.src, self.kernel) {
            (Source::Rows(x), Kernel::Rbf { gamma }) => {
                // the chunk's dot products feature by feature over the transposed rows: each is
                // still the sequential sum over the features (LIBSVM's bits), and the sums of
                // neighbouring rows advance together in vector registers
                let (n, l) = (out.len(), self.l);
                let xi = x.row(i);
                let mut acc = [0.0f64; FILL_CHUNK];
                // eight rows at a time, their eight sums kept in registers over the features
                let mut j = 0;
                while j + 8 <= n {
                    let mut s = [0.0f64; 8];
                    for (k, &a) in xi.iter().enumerate() {
                        let c = &self.xt[k * l + start + j..k * l + start + j + 8];
                        for o in 0..8 {
                            s[o] += a * c[o];
                        }
                    }
                    acc[j..j + 8].copy_from_slice(&s);
                    j += 8;
                }
                for (jj, s) in acc.iter_mut().enumerate().take(n).skip(j) {
                    for (k, &a) in xi.iter().enumerate() {
                        *s += a * self.xt[k * l + start + jj];
                    }
                }
                let acc = &acc[..n];
                let sq = &self.xsq[start..start + n];
                for ((o, s), &q) in out.iter_mut().zip(acc.iter()).zip(sq) {
                    *o = (-gamma * (self.xsq[i] + q - 2.0 * s)).exp() as f32;
                }
            }
            (Source::Shared { d, rows }, Kernel::Rbf { gamma }) => {
                let base = &d.train[rows[i] * d.n..(rows[i] + 1) * d.n];
                let end = start + out.len();
                for (o, &r) in out.iter_mut().zip(&rows[start..end]) {
                    *o = (-gamma * base[r]).exp() as f32;
                }
            }
            _ => {
                for (o, j) in out.iter_mut().zip(start..) {
                    *o = self.k(i, j) as f32;
                }
            }
        }
    }

    fn swap_index(&mut self, i: usize, j: usize) {
        self.sign.swap(i, j);
        self.index.swap(i, j);
        self.qd.swap(i, j);
    }

    /// Makes sure the kernel row of variable `i` is cached (most recently used); returns the
    /// data index of that row. Q_iu = s_i s_u K[row][index_u] for every variable u.
    ///
    /// LIBSVM copies each requested column into a buffer with the signs applied; reading the
    /// cached row through `index` and `sign` instead gives the same f32 values without the copy.
    fn col(&mut self, i: usize) -> usize {
        let real = self.index[i] as usize;
        if !self.cache.has(real) {
            // on this thread: a rayon split per column cost more in wake-ups than it saved
            let mut row = self.cache.take_slot(self.l);
            for (c, out) in row.chunks_mut(FILL_CHUNK).enumerate() {
                self.fill(real, c * FILL_CHUNK, out);
            }
            self.cache.put(real, row);
        } else {
            self.cache.touch(real);
        }
        real
    }

    /// Q_iu for the first `len` variables u into `out` (LIBSVM's `get_Q`).
    fn column(&mut self, i: usize, len: usize, out: &mut [f32]) {
        let real = self.col(i);
        let (d, si) = (self.cache.row(real), self.sign[i]);
        // every cached row holds all l kernel values, and `index` is (0..2l) mod l from `new`,
        // only ever swapped since: each entry is inside the row (gather_signed's contract)
        assert_eq!(d.len(), self.l);
        debug_assert!(self.index.iter().all(|&u| (u as usize) < self.l));
        gather_signed(
            d,
            si,
            &self.sign[..len],
            &self.index[..len],
            &mut out[..len],
        );
    }

    fn data(&self, real: usize) -> &[f32] {
        self.cache.row(real)
    }
}

/// The solver indexes kernel rows with u32 and gathers with i32 offsets: fewer than 2³¹ rows
/// (a kernel row of that many would not fit in memory anyway).
#[cfg(feature = "fit")]
fn check_rows(n: usize) -> Result<()> {
    if n >= i32::MAX as usize {
        return Err(Error::Shape(format!(
            "{n} rows: an SVR fits fewer than 2^31"
        )));
    }
    Ok(())
}

/// out_t = s_i s_t d[index_t]: a cached kernel row read in the variables' (permuted) order.
/// Every `index` must be inside `d` (a panic on the portable path, undefined behaviour on the
/// AVX2 one): [`SvrQ::column`], its only caller, keeps that invariant. (Checking it here cost
/// a pass over the indices per column, which took back all that the gather saves.)
#[cfg(feature = "fit")]
fn gather_signed(d: &[f32], si: f32, sign: &[f32], index: &[u32], out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above) and the caller keeps every index
        // inside `d`
        unsafe { gather_signed_avx2(d, si, sign, index, out) };
        return;
    }
    for ((o, s), &u) in out.iter_mut().zip(sign).zip(index) {
        *o = si * s * d[u as usize];
    }
}

/// [`gather_signed`] with AVX2's gather, four variables at a time: the same products
/// (s_i·s_t)·d in f32. The caller guarantees every `index` is inside `d`.
#[cfg(all(feature = "fit", target_arch = "x86_64"))]
#[target_feature(enable = "avx2")]
unsafe fn gather_signed_avx2(d: &[f32], si: f32, sign: &[f32], index: &[u32], out: &mut [f32]) {
    use std::arch::x86_64::*;
    let n = out.len().min(sign.len()).min(index.len());
    let full = n - n % 8;
    let vsi = _mm256_set1_ps(si);
    let mut t = 0;
    while t < full {
        // SAFETY: t + 8 <= n for `index`, `sign` and `out`; the indices are inside `d`, which
        // is far shorter than i32::MAX
        unsafe {
            let idx = _mm256_loadu_si256(index.as_ptr().add(t) as *const __m256i);
            let dv = _mm256_i32gather_ps::<4>(d.as_ptr(), idx);
            let sv = _mm256_loadu_ps(sign.as_ptr().add(t));
            _mm256_storeu_ps(
                out.as_mut_ptr().add(t),
                _mm256_mul_ps(_mm256_mul_ps(vsi, sv), dv),
            );
        }
        t += 8;
    }
    for k in full..n {
        out[k] = si * sign[k] * d[index[k] as usize];
    }
}

/// LRU cache of full kernel rows (f32), bounded in bytes like LIBSVM's (at least two rows).
#[cfg(feature = "fit")]
struct Cache {
    rows: Vec<Option<Vec<f32>>>,
    prev: Vec<usize>,
    next: Vec<usize>,
    /// Sentinel index of the circular LRU list (= number of rows).
    head: usize,
    free_rows: usize,
}

#[cfg(feature = "fit")]
impl Cache {
    fn new(l: usize, mib: f64) -> Self {
        let bytes = (mib * 1048576.0) as usize;
        let capacity = (bytes / (4 * l.max(1))).max(2);
        let n = l + 1;
        Cache {
            rows: vec![None; l],
            prev: vec![l; n],
            next: vec![l; n],
            head: l,
            free_rows: capacity,
        }
    }

    fn has(&self, i: usize) -> bool {
        self.rows[i].is_some()
    }

    fn unlink(&mut self, i: usize) {
        let (p, n) = (self.prev[i], self.next[i]);
        self.next[p] = n;
        self.prev[n] = p;
    }

    fn push_back(&mut self, i: usize) {
        let h = self.head;
        let last = self.prev[h];
        self.next[last] = i;
        self.prev[i] = last;
        self.next[i] = h;
        self.prev[h] = i;
    }

    /// A buffer for row `i`, evicting the least recently used row if the budget is spent.
    fn take_slot(&mut self, l: usize) -> Vec<f32> {
        if self.free_rows == 0 {
            // the budget is spent, so the LRU list is not empty: reuse its oldest row's buffer
            let old = self.next[self.head];
            self.unlink(old);
            if let Some(v) = self.rows[old].take() {
                return v;
            }
        }
        self.free_rows = self.free_rows.saturating_sub(1);
        vec![0.0; l]
    }

    fn put(&mut self, i: usize, row: Vec<f32>) {
        self.rows[i] = Some(row);
        self.push_back(i);
    }

    /// Marks row `i` (which must be cached) most recently used.
    fn touch(&mut self, i: usize) {
        self.unlink(i);
        self.push_back(i);
    }

    fn row(&self, i: usize) -> &[f32] {
        self.rows[i].as_deref().unwrap_or(&[])
    }
}

#[cfg(feature = "fit")]
struct Solution {
    alpha: Vec<f64>,
    rho: f64,
    n_iter: usize,
}

#[cfg(feature = "fit")]
#[derive(Clone, Copy, PartialEq, Eq)]
enum Status {
    Lower,
    Upper,
    Free,
}

#[cfg(feature = "fit")]
const TAU: f64 = 1e-12;

// The selection passes run on one thread: since they run in vector lanes, splitting them
// across threads (as they were from 16 384 variables) cost more in wake-ups than it saved at
// every size measured (10 000 rows: 0.88 s split, 0.67 s not; 20 000: 3.7 s and 2.8 s;
// 40 000: 22.0 s and 21.1 s).

/// argmax over I_up of −y_t G_t in a slice starting at variable `off` (last index on ties).
/// `up[t]`: t ∈ I_up, i.e. y_t = +1 and α_t < C, or y_t = −1 and α_t > 0.
#[cfg(feature = "fit")]
fn scan_i(g: &[f64], y: &[f64], up: &[bool], off: usize) -> (f64, usize) {
    let (mut gmax, mut idx) = (f64::NEG_INFINITY, usize::MAX);
    for (t, ((&g, &y), &up)) in g.iter().zip(y).zip(up).enumerate() {
        // −y·G with y = ±1 is exactly LIBSVM's −G or G
        let v = -y * g;
        if up && v >= gmax {
            gmax = v;
            idx = off + t;
        }
    }
    (gmax, idx)
}

/// The gradient update of one SMO step, G_t += Q_it Δα_i + Q_jt Δα_j: the two kernel columns,
/// the two steps, and each variable's label and I_up membership, over the same variables as
/// the slice of G it is applied to.
#[cfg(feature = "fit")]
#[derive(Clone, Copy)]
struct Update<'s> {
    qi: &'s [f32],
    qj: &'s [f32],
    dai: f64,
    daj: f64,
    y: &'s [f64],
    up: &'s [bool],
}

#[cfg(feature = "fit")]
impl<'s> Update<'s> {
    /// The same update for the variables from `k` on.
    fn from(&self, k: usize) -> Update<'s> {
        Update {
            qi: &self.qi[k..],
            qj: &self.qj[k..],
            y: &self.y[k..],
            up: &self.up[k..],
            ..*self
        }
    }
}

/// The gradient update `u` over a slice of G starting at variable `off`, and [`scan_i`] of the
/// updated slice in the same pass (lanes, as [`Pass2::run`]).
#[cfg(feature = "fit")]
fn update_scan(u: &Update<'_>, g: &mut [f64], off: usize) -> (f64, usize) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above
        return unsafe { update_scan_avx2(u, g, off) };
    }
    update_scan_lanes(u, g, off)
}

/// [`update_scan_lanes`] in AVX2 intrinsics: the same operations in the same order on four
/// variables at a time, then the scalar loop's lanes for the rest.
#[cfg(all(feature = "fit", target_arch = "x86_64"))]
#[target_feature(enable = "avx2")]
unsafe fn update_scan_avx2(u: &Update<'_>, g: &mut [f64], off: usize) -> (f64, usize) {
    use std::arch::x86_64::*;
    let n = g.len();
    let Update {
        qi,
        qj,
        dai,
        daj,
        y,
        up,
    } = *u;
    assert!(qi.len() >= n && qj.len() >= n && y.len() >= n && up.len() >= n);
    let full = n - n % LANES;
    let (vdi, vdj, vnan, sign) = (
        _mm256_set1_pd(dai),
        _mm256_set1_pd(daj),
        _mm256_set1_pd(f64::NAN),
        _mm256_set1_pd(-0.0),
    );
    let mut mx = _mm256_set1_pd(f64::NEG_INFINITY);
    let mut ix = _mm256_set1_pd(-1.0);
    let mut at = _mm256_setr_pd(
        off as f64,
        (off + 1) as f64,
        (off + 2) as f64,
        (off + 3) as f64,
    );
    let step = _mm256_set1_pd(LANES as f64);
    let mut t = 0;
    while t < full {
        // SAFETY: t + 4 <= full <= n <= the length of every slice (asserted above)
        let (g4, qi4, qj4, y4, um) = unsafe {
            let bytes = std::ptr::read_unaligned(up.as_ptr().add(t) as *const u32);
            (
                _mm256_loadu_pd(g.as_ptr().add(t)),
                _mm256_cvtps_pd(_mm_loadu_ps(qi.as_ptr().add(t))),
                _mm256_cvtps_pd(_mm_loadu_ps(qj.as_ptr().add(t))),
                _mm256_loadu_pd(y.as_ptr().add(t)),
                _mm256_castsi256_pd(_mm256_cmpgt_epi64(
                    _mm256_cvtepu8_epi64(_mm_cvtsi32_si128(bytes as i32)),
                    _mm256_setzero_si256(),
                )),
            )
        };
        let gt = _mm256_add_pd(
            g4,
            _mm256_add_pd(_mm256_mul_pd(qi4, vdi), _mm256_mul_pd(qj4, vdj)),
        );
        // SAFETY: as above
        unsafe { _mm256_storeu_pd(g.as_mut_ptr().add(t), gt) };
        let v = _mm256_blendv_pd(vnan, _mm256_mul_pd(_mm256_xor_pd(y4, sign), gt), um);
        let take = _mm256_cmp_pd::<_CMP_GE_OQ>(v, mx);
        mx = _mm256_blendv_pd(mx, v, take);
        ix = _mm256_blendv_pd(ix, at, take);
        at = _mm256_add_pd(at, step);
        t += LANES;
    }
    let (mut m4, mut i4) = ([0.0f64; LANES], [0.0f64; LANES]);
    // SAFETY: each array holds four doubles
    unsafe {
        _mm256_storeu_pd(m4.as_mut_ptr(), mx);
        _mm256_storeu_pd(i4.as_mut_ptr(), ix);
    }
    let mut lanes = ScanLanes {
        mx: m4,
        ix: i4.map(|v| if v < 0.0 { usize::MAX } else { v as usize }),
    };
    lanes.update(&u.from(full), &mut g[full..], off + full);
    lanes.join()
}

/// Per-lane state of the first selection pass: each lane's largest −y_t G_t over I_up with
/// the last index reaching it.
#[cfg(feature = "fit")]
struct ScanLanes {
    mx: [f64; LANES],
    ix: [usize; LANES],
}

#[cfg(feature = "fit")]
impl ScanLanes {
    /// Applies `u` to a slice of G starting at variable `off` and scans it into lane
    /// (t mod LANES).
    #[inline(always)]
    fn update(&mut self, u: &Update<'_>, g: &mut [f64], off: usize) {
        let n = g.len();
        let (qi, qj, y, up) = (&u.qi[..n], &u.qj[..n], &u.y[..n], &u.up[..n]);
        let (dai, daj) = (u.dai, u.daj);
        for t in 0..n {
            let k = (off + t) % LANES;
            let gt = g[t] + (qi[t] as f64 * dai + qj[t] as f64 * daj);
            g[t] = gt;
            // −y·G with y = ±1 is exactly LIBSVM's −G or G
            let v = if up[t] { -y[t] * gt } else { f64::NAN };
            if v >= self.mx[k] {
                self.mx[k] = v;
                self.ix[k] = off + t;
            }
        }
    }

    /// The largest value and, among the lanes reaching it, the largest index: LIBSVM's
    /// sequential `>=` result.
    fn join(&self) -> (f64, usize) {
        let best = self.mx.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let idx = (0..LANES)
            .filter(|&k| self.ix[k] != usize::MAX && self.mx[k] == best)
            .map(|k| self.ix[k])
            .max()
            .unwrap_or(usize::MAX);
        (best, idx)
    }
}

/// The portable [`update_scan`]: one pass through [`ScanLanes`].
#[cfg(feature = "fit")]
fn update_scan_lanes(u: &Update<'_>, g: &mut [f64], off: usize) -> (f64, usize) {
    let mut lanes = ScanLanes {
        mx: [f64::NEG_INFINITY; LANES],
        ix: [usize::MAX; LANES],
    };
    lanes.update(u, g, off);
    lanes.join()
}

/// The second half of the working-set selection over a range of variables.
#[cfg(feature = "fit")]
struct Pass2<'s> {
    g: &'s [f64],
    y: &'s [f64],
    /// j ∈ I_low: y_j = +1 and α_j > 0, or y_j = −1 and α_j < C
    low: &'s [bool],
    qd: &'s [f64],
    /// Q_ij for every active j (contiguous, as LIBSVM's column buffer).
    qi: &'s [f32],
    yi: f64,
    qdi: f64,
    gmax: f64,
}

#[cfg(feature = "fit")]
#[derive(Clone, Copy)]
struct Pass2Out {
    obj_min: f64,
    idx: usize,
    gmax2: f64,
}

#[cfg(feature = "fit")]
impl Pass2Out {
    fn none() -> Self {
        Pass2Out {
            obj_min: f64::INFINITY,
            idx: usize::MAX,
            gmax2: f64::NEG_INFINITY,
        }
    }
}

/// Lanes of the branch-free selection loops: independent running minima (maxima) that the
/// compiler keeps in vector registers, joined at the end with LIBSVM's tie rule.
#[cfg(feature = "fit")]
const LANES: usize = 4;

#[cfg(feature = "fit")]
impl Pass2<'_> {
    fn run(&self, lo: usize, hi: usize) -> Pass2Out {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above
            return unsafe { self.run_avx2(lo, hi) };
        }
        self.run_lanes(lo, hi)
    }

    /// [`run_lanes`](Self::run_lanes) in AVX2 intrinsics: the same operations in the same
    /// order on four variables at a time, so the same values and the same selection (the
    /// scalar loop vectorised poorly: two lanes, indices kept in general registers).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn run_avx2(&self, lo: usize, hi: usize) -> Pass2Out {
        use std::arch::x86_64::*;
        let (g, y, low) = (&self.g[lo..hi], &self.y[lo..hi], &self.low[lo..hi]);
        let (qd, qi) = (&self.qd[lo..hi], &self.qi[lo..hi]);
        let n = g.len();
        assert!(y.len() == n && low.len() == n && qd.len() == n && qi.len() == n);
        let full = n - n % LANES;
        let c = -2.0 * self.yi;
        let (vgmax, vqdi, vc) = (
            _mm256_set1_pd(self.gmax),
            _mm256_set1_pd(self.qdi),
            _mm256_set1_pd(c),
        );
        let (vtau, vnan, vninf, vzero) = (
            _mm256_set1_pd(TAU),
            _mm256_set1_pd(f64::NAN),
            _mm256_set1_pd(f64::NEG_INFINITY),
            _mm256_setzero_pd(),
        );
        let sign = _mm256_set1_pd(-0.0);
        let mut mn = _mm256_set1_pd(f64::INFINITY);
        let mut ix = _mm256_set1_pd(-1.0);
        let mut mx = vninf;
        let mut at = _mm256_setr_pd(lo as f64, (lo + 1) as f64, (lo + 2) as f64, (lo + 3) as f64);
        let step = _mm256_set1_pd(LANES as f64);
        let mut j = 0;
        while j < full {
            // SAFETY: j + 4 <= full <= n, the length of every slice (asserted above)
            let (g4, y4, qd4, qi4, lm) = unsafe {
                let bytes = std::ptr::read_unaligned(low.as_ptr().add(j) as *const u32);
                (
                    _mm256_loadu_pd(g.as_ptr().add(j)),
                    _mm256_loadu_pd(y.as_ptr().add(j)),
                    _mm256_loadu_pd(qd.as_ptr().add(j)),
                    _mm256_cvtps_pd(_mm_loadu_ps(qi.as_ptr().add(j))),
                    _mm256_castsi256_pd(_mm256_cmpgt_epi64(
                        _mm256_cvtepu8_epi64(_mm_cvtsi32_si128(bytes as i32)),
                        _mm256_setzero_si256(),
                    )),
                )
            };
            let v = _mm256_mul_pd(y4, g4);
            let gd = _mm256_add_pd(vgmax, v);
            let quad = _mm256_add_pd(
                _mm256_add_pd(vqdi, qd4),
                _mm256_mul_pd(_mm256_mul_pd(vc, y4), qi4),
            );
            let q = _mm256_blendv_pd(vtau, quad, _mm256_cmp_pd::<_CMP_GT_OQ>(quad, vzero));
            let o = _mm256_div_pd(_mm256_xor_pd(_mm256_mul_pd(gd, gd), sign), q);
            let valid = _mm256_and_pd(lm, _mm256_cmp_pd::<_CMP_GT_OQ>(gd, vzero));
            let obj = _mm256_blendv_pd(vnan, o, valid);
            let take = _mm256_cmp_pd::<_CMP_LE_OQ>(obj, mn);
            mn = _mm256_blendv_pd(mn, obj, take);
            ix = _mm256_blendv_pd(ix, at, take);
            let vv = _mm256_blendv_pd(vninf, v, lm);
            mx = _mm256_blendv_pd(mx, vv, _mm256_cmp_pd::<_CMP_GE_OQ>(vv, mx));
            at = _mm256_add_pd(at, step);
            j += LANES;
        }
        let (mut m4, mut i4, mut x4) = ([0.0f64; LANES], [0.0f64; LANES], [0.0f64; LANES]);
        // SAFETY: each array holds four doubles
        unsafe {
            _mm256_storeu_pd(m4.as_mut_ptr(), mn);
            _mm256_storeu_pd(i4.as_mut_ptr(), ix);
            _mm256_storeu_pd(x4.as_mut_ptr(), mx);
        }
        let mut lanes = Pass2Lanes {
            mn: m4,
            ix: i4.map(|v| if v < 0.0 { usize::MAX } else { v as usize }),
            mx: x4,
        };
        self.tail(full, n, lo, &mut lanes);
        lanes.join()
    }

    /// The loop without branches: a variable outside I_low (or with G_i + y_j G_j <= 0) gives
    /// NaN, which no comparison takes. Each lane keeps its minimum of the objective with the
    /// last index reaching it, and its maximum of y_j G_j; the join takes the smallest minimum
    /// and, among the lanes that reach it, the largest index: the same (last) index LIBSVM's
    /// sequential `<=` ends on. Every value is formed by the same operations as LIBSVM's.
    #[inline(always)]
    fn run_lanes(&self, lo: usize, hi: usize) -> Pass2Out {
        let n = hi - lo;
        let mut lanes = Pass2Lanes {
            mn: [f64::INFINITY; LANES],
            ix: [usize::MAX; LANES],
            mx: [f64::NEG_INFINITY; LANES],
        };
        self.tail(0, n, lo, &mut lanes);
        lanes.join()
    }

    /// Variables `from..n` of the range starting at `lo`, into lane (t mod LANES).
    #[inline(always)]
    fn tail(&self, from: usize, n: usize, lo: usize, lanes: &mut Pass2Lanes) {
        let (gmax, yi, qdi) = (self.gmax, self.yi, self.qdi);
        let (g, y, low) = (
            &self.g[lo..lo + n],
            &self.y[lo..lo + n],
            &self.low[lo..lo + n],
        );
        let (qd, qi) = (&self.qd[lo..lo + n], &self.qi[lo..lo + n]);
        for j in from..n {
            let k = j % LANES;
            let ok = low[j];
            // y_j·G_j is LIBSVM's G_j (y = +1) or −G_j (y = −1), exactly
            let v = y[j] * g[j];
            let grad_diff = gmax + v;
            // −2·y_i·y_j ∈ {±2}: the same rounding as LIBSVM's QD_i + QD_j ∓ 2·y_i·Q_ij
            let quad = qdi + qd[j] + (-2.0 * yi * y[j]) * qi[j] as f64;
            let q = if quad > 0.0 { quad } else { TAU };
            let o = -(grad_diff * grad_diff) / q;
            let obj = if ok && grad_diff > 0.0 { o } else { f64::NAN };
            let vv = if ok { v } else { f64::NEG_INFINITY };
            if obj <= lanes.mn[k] {
                lanes.mn[k] = obj;
                lanes.ix[k] = lo + j;
            }
            if vv >= lanes.mx[k] {
                lanes.mx[k] = vv;
            }
        }
    }
}

/// Per-lane state of the second selection pass: each lane's smallest objective with the last
/// index reaching it (NaN, a non-candidate, is never taken) and its largest y_j·G_j over I_low.
#[cfg(feature = "fit")]
struct Pass2Lanes {
    mn: [f64; LANES],
    ix: [usize; LANES],
    mx: [f64; LANES],
}

#[cfg(feature = "fit")]
impl Pass2Lanes {
    /// The smallest minimum and, among the lanes reaching it, the largest index: the same
    /// (last) index LIBSVM's sequential `<=` ends on.
    fn join(&self) -> Pass2Out {
        let obj_min = self.mn.iter().copied().fold(f64::INFINITY, f64::min);
        let mut out = Pass2Out::none();
        out.gmax2 = self.mx.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if obj_min < f64::INFINITY {
            out.obj_min = obj_min;
            out.idx = (0..LANES)
                .filter(|&k| self.ix[k] != usize::MAX && self.mn[k] == obj_min)
                .map(|k| self.ix[k])
                .max()
                .expect("a lane reaches the minimum");
        }
        out
    }
}

/// LIBSVM's `Solver::Solve` for the SVR problem (all variables share the bound C, α starts at 0).
#[cfg(feature = "fit")]
struct Solver<'q, 'a> {
    q: &'q mut SvrQ<'a>,
    l: usize,
    active_size: usize,
    y: Vec<f32>,
    /// y as f64, and membership of I_up / I_low, kept in step with `status`
    yf: Vec<f64>,
    up: Vec<bool>,
    low: Vec<bool>,
    g: Vec<f64>,
    status: Vec<Status>,
    alpha: Vec<f64>,
    p: Vec<f64>,
    active_set: Vec<usize>,
    g_bar: Vec<f64>,
    c: f64,
    eps: f64,
    unshrink: bool,
    /// Column buffers of the working pair; `qi_of` says which (variable, length) `qi` holds.
    qi: Vec<f32>,
    qj: Vec<f32>,
    qi_of: Option<(usize, usize)>,
}

#[cfg(feature = "fit")]
fn solve(
    q: &mut SvrQ<'_>,
    p: Vec<f64>,
    c: f64,
    eps: f64,
    shrinking: bool,
    max_iter: Option<usize>,
    init: Option<Vec<f64>>,
) -> Result<Solution> {
    let l = p.len();
    let mut s = Solver {
        l,
        active_size: l,
        y: q.sign.clone(),
        yf: q.sign.iter().map(|&s| s as f64).collect(),
        // α = 0 everywhere: I_up holds the y = +1 variables, I_low the y = −1 ones
        up: q.sign.iter().map(|&s| s > 0.0).collect(),
        low: q.sign.iter().map(|&s| s < 0.0).collect(),
        g: p.clone(),
        status: vec![Status::Lower; l],
        alpha: vec![0.0; l],
        p,
        active_set: (0..l).collect(),
        g_bar: vec![0.0; l],
        c,
        eps,
        unshrink: false,
        qi: vec![0.0; l],
        qj: vec![0.0; l],
        qi_of: None,
        q,
    };
    if let Some(a) = init {
        s.start_from(a);
    }
    let mut iter = 0usize;
    let mut counter = l.min(1000) + 1;
    // the first half of the next selection, computed during the last gradient update
    let mut first: Option<(f64, usize)> = None;
    loop {
        if max_iter.is_some_and(|m| iter >= m) {
            break;
        }
        // one relaxed load per iteration, next to O(l) work: every fit of a search stops at once
        crate::interrupt::check()?;
        counter -= 1;
        if counter == 0 {
            counter = l.min(1000);
            if shrinking {
                s.do_shrinking();
                first = None;
            }
        }
        let (i, j) = match s.select_working_set(first.take()) {
            Some(ij) => ij,
            None => {
                s.reconstruct_gradient();
                s.active_size = l;
                match s.select_working_set(None) {
                    Some(ij) => {
                        counter = 1;
                        ij
                    }
                    None => break,
                }
            }
        };
        iter += 1;
        first = Some(s.take_step(i, j));
    }
    let rho = s.calculate_rho();
    let mut alpha = vec![0.0; l];
    for k in 0..l {
        alpha[s.active_set[k]] = s.alpha[k];
    }
    Ok(Solution {
        alpha,
        rho,
        n_iter: iter,
    })
}

#[cfg(feature = "fit")]
impl Solver<'_, '_> {
    fn is_upper(&self, i: usize) -> bool {
        self.status[i] == Status::Upper
    }
    fn is_lower(&self, i: usize) -> bool {
        self.status[i] == Status::Lower
    }
    fn is_free(&self, i: usize) -> bool {
        self.status[i] == Status::Free
    }
    fn update_status(&mut self, i: usize) {
        let st = if self.alpha[i] >= self.c {
            Status::Upper
        } else if self.alpha[i] <= 0.0 {
            Status::Lower
        } else {
            Status::Free
        };
        self.status[i] = st;
        let pos = self.y[i] > 0.0;
        self.up[i] = if pos {
            st != Status::Upper
        } else {
            st != Status::Lower
        };
        self.low[i] = if pos {
            st != Status::Lower
        } else {
            st != Status::Upper
        };
    }

    fn swap_index(&mut self, i: usize, j: usize) {
        self.q.swap_index(i, j);
        self.y.swap(i, j);
        self.yf.swap(i, j);
        self.up.swap(i, j);
        self.low.swap(i, j);
        self.g.swap(i, j);
        self.status.swap(i, j);
        self.alpha.swap(i, j);
        self.p.swap(i, j);
        self.active_set.swap(i, j);
        self.g_bar.swap(i, j);
    }

    /// Starts from α = `a` (2l values in [0, C], in the unpermuted order) instead of 0, as
    /// LIBSVM's solver does for a given α: statuses from α, G = p + Qα and Ḡ = C Σ_upper Q_u.
    /// Variables t and t + l share kernel row t mod l, so both sums go through one row per
    /// data row: (Qα)_t = s_t Σ_k (α_k − α_{k+l}) K(t mod l, k).
    fn start_from(&mut self, a: Vec<f64>) {
        let n = self.l / 2;
        self.alpha = a;
        for i in 0..self.l {
            self.update_status(i);
        }
        let (mut kb, mut ku) = (vec![0.0f64; n], vec![0.0f64; n]);
        for k in 0..n {
            let beta = self.alpha[k] - self.alpha[k + n];
            let upper =
                self.c * ((self.is_upper(k) as u8 as f64) - (self.is_upper(k + n) as u8 as f64));
            if beta == 0.0 && upper == 0.0 {
                continue;
            }
            let r = self.q.col(k);
            for ((b, u), &v) in kb.iter_mut().zip(ku.iter_mut()).zip(self.q.data(r)) {
                *b += beta * v as f64;
                *u += upper * v as f64;
            }
        }
        for t in 0..self.l {
            let (s, row) = (self.yf[t], t % n);
            self.g[t] = self.p[t] + s * kb[row];
            self.g_bar[t] = s * ku[row];
        }
    }

    fn reconstruct_gradient(&mut self) {
        let (a, l) = (self.active_size, self.l);
        if a == l {
            return;
        }
        for j in a..l {
            self.g[j] = self.g_bar[j] + self.p[j];
        }
        let nr_free = (0..a).filter(|&j| self.is_free(j)).count();
        if nr_free * l > 2 * a * (l - a) {
            for i in a..l {
                let ri = self.q.col(i);
                let (di, si) = (self.q.data(ri), self.q.sign[i]);
                let mut gi = self.g[i];
                for (((st, al), s), &u) in self.status[..a]
                    .iter()
                    .zip(&self.alpha)
                    .zip(&self.q.sign)
                    .zip(&self.q.index)
                {
                    if *st == Status::Free {
                        gi += al * (si * s * di[u as usize]) as f64;
                    }
                }
                self.g[i] = gi;
            }
        } else {
            for i in 0..a {
                if self.is_free(i) {
                    let ri = self.q.col(i);
                    let (di, si) = (self.q.data(ri), self.q.sign[i]);
                    let ai = self.alpha[i];
                    for ((g, s), &u) in self.g[a..l]
                        .iter_mut()
                        .zip(&self.q.sign[a..l])
                        .zip(&self.q.index[a..l])
                    {
                        *g += ai * (si * s * di[u as usize]) as f64;
                    }
                }
            }
        }
    }

    /// The first half of the working-set selection: i = argmax over I_up of −y_t G_t (the last
    /// index on ties, as LIBSVM's `>=`). `None` in the index when I_up is empty.
    fn select_i(&self) -> (f64, usize) {
        let a = self.active_size;
        scan_i(&self.g[..a], &self.yf[..a], &self.up[..a], 0)
    }

    /// Second-order working-set selection (Fan, Chen & Lin 2005) given the first index
    /// `(gmax, i)`; `None` when optimal within `eps`.
    fn select_working_set(&mut self, first: Option<(f64, usize)>) -> Option<(usize, usize)> {
        let a = self.active_size;
        let (gmax, i) = first.unwrap_or_else(|| self.select_i());
        let (mut gmin_idx, mut gmax2) = (usize::MAX, f64::NEG_INFINITY);
        if i != usize::MAX {
            self.q.column(i, a, &mut self.qi);
            self.qi_of = Some((i, a));
            let ctx = Pass2 {
                g: &self.g[..a],
                y: &self.yf[..a],
                low: &self.low[..a],
                qd: &self.q.qd[..a],
                qi: &self.qi[..a],
                yi: self.y[i] as f64,
                qdi: self.q.qd[i],
                gmax,
            };
            let r = ctx.run(0, a);
            gmin_idx = r.idx;
            gmax2 = r.gmax2;
        }
        if gmax + gmax2 < self.eps || gmin_idx == usize::MAX {
            return None;
        }
        Some((i, gmin_idx))
    }

    /// One SMO step on the pair (i, j); returns the first half of the next working-set
    /// selection, scanned while the gradient is updated.
    fn take_step(&mut self, i: usize, j: usize) -> (f64, usize) {
        let a = self.active_size;
        let (si, sj) = (self.q.sign[i], self.q.sign[j]);
        let (ci, cj) = (self.c, self.c);
        let (old_ai, old_aj) = (self.alpha[i], self.alpha[j]);
        if self.qi_of != Some((i, a)) {
            self.q.column(i, a, &mut self.qi);
        }
        self.qi_of = None;
        self.q.column(j, a, &mut self.qj);
        let qd = &self.q.qd;
        let qij = self.qi[j] as f64;
        let (mut ai, mut aj) = (old_ai, old_aj);
        if self.y[i] != self.y[j] {
            let mut quad = qd[i] + qd[j] + 2.0 * qij;
            if quad <= 0.0 {
                quad = TAU;
            }
            let delta = (-self.g[i] - self.g[j]) / quad;
            let diff = ai - aj;
            ai += delta;
            aj += delta;
            if diff > 0.0 {
                if aj < 0.0 {
                    aj = 0.0;
                    ai = diff;
                }
            } else if ai < 0.0 {
                ai = 0.0;
                aj = -diff;
            }
            if diff > ci - cj {
                if ai > ci {
                    ai = ci;
                    aj = ci - diff;
                }
            } else if aj > cj {
                aj = cj;
                ai = cj + diff;
            }
        } else {
            let mut quad = qd[i] + qd[j] - 2.0 * qij;
            if quad <= 0.0 {
                quad = TAU;
            }
            let delta = (self.g[i] - self.g[j]) / quad;
            let sum = ai + aj;
            ai -= delta;
            aj += delta;
            if sum > ci {
                if ai > ci {
                    ai = ci;
                    aj = sum - ci;
                }
            } else if aj < 0.0 {
                aj = 0.0;
                ai = sum;
            }
            if sum > cj {
                if aj > cj {
                    aj = cj;
                    ai = sum - cj;
                }
            } else if ai < 0.0 {
                ai = 0.0;
                aj = sum;
            }
        }
        self.alpha[i] = ai;
        self.alpha[j] = aj;
        let dai = ai - old_ai;
        let daj = aj - old_aj;
        let ui = self.is_upper(i);
        let uj = self.is_upper(j);
        self.update_status(i);
        self.update_status(j);
        let next = {
            let u = Update {
                qi: &self.qi[..a],
                qj: &self.qj[..a],
                dai,
                daj,
                y: &self.yf[..a],
                up: &self.up[..a],
            };
            update_scan(&u, &mut self.g[..a], 0)
        };
        if ui != self.is_upper(i) {
            let ri = self.q.col(i);
            let di = self.q.data(ri);
            let c = if ui { -ci } else { ci };
            for ((g, s), &u) in self.g_bar.iter_mut().zip(&self.q.sign).zip(&self.q.index) {
                *g += c * (si * s * di[u as usize]) as f64;
            }
        }
        if uj != self.is_upper(j) {
            let rj = self.q.col(j);
            let dj = self.q.data(rj);
            let c = if uj { -cj } else { cj };
            for ((g, s), &u) in self.g_bar.iter_mut().zip(&self.q.sign).zip(&self.q.index) {
                *g += c * (sj * s * dj[u as usize]) as f64;
            }
        }
        next
    }

    fn be_shrunk(&self, i: usize, gmax1: f64, gmax2: f64) -> bool {
        if self.is_upper(i) {
            if self.y[i] == 1.0 {
                -self.g[i] > gmax1
            } else {
                -self.g[i] > gmax2
            }
        } else if self.is_lower(i) {
            if self.y[i] == 1.0 {
                self.g[i] > gmax2
            } else {
                self.g[i] > gmax1
            }
        } else {
            false
        }
    }

    fn do_shrinking(&mut self) {
        let mut gmax1 = f64::NEG_INFINITY;
        let mut gmax2 = f64::NEG_INFINITY;
        for i in 0..self.active_size {
            let g = self.g[i];
            if self.y[i] == 1.0 {
                if !self.is_upper(i) && -g >= gmax1 {
                    gmax1 = -g;
                }
                if !self.is_lower(i) && g >= gmax2 {
                    gmax2 = g;
                }
            } else {
                if !self.is_upper(i) && -g >= gmax2 {
                    gmax2 = -g;
                }
                if !self.is_lower(i) && g >= gmax1 {
                    gmax1 = g;
                }
            }
        }
        if !self.unshrink && gmax1 + gmax2 <= self.eps * 10.0 {
            self.unshrink = true;
            self.reconstruct_gradient();
            self.active_size = self.l;
        }
        let mut i = 0;
        while i < self.active_size {
            if self.be_shrunk(i, gmax1, gmax2) {
                self.active_size -= 1;
                while self.active_size > i {
                    if !self.be_shrunk(self.active_size, gmax1, gmax2) {
                        self.swap_index(i, self.active_size);
                        break;
                    }
                    self.active_size -= 1;
                }
            }
            i += 1;
        }
    }

    fn calculate_rho(&self) -> f64 {
        let mut nr_free = 0usize;
        let (mut ub, mut lb, mut sum_free) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
        for i in 0..self.active_size {
            let yg = self.y[i] as f64 * self.g[i];
            if self.is_upper(i) {
                if self.y[i] == -1.0 {
                    ub = ub.min(yg);
                } else {
                    lb = lb.max(yg);
                }
            } else if self.is_lower(i) {
                if self.y[i] == 1.0 {
                    ub = ub.min(yg);
                } else {
                    lb = lb.max(yg);
                }
            } else {
                nr_free += 1;
                sum_free += yg;
            }
        }
        if nr_free > 0 {
            sum_free / nr_free as f64
        } else {
            (ub + lb) / 2.0
        }
    }
}

#[cfg(all(test, feature = "fit"))]
mod tests {
    use super::*;

    fn data(n: usize) -> (Vec<f64>, Vec<f64>) {
        let x: Vec<f64> = (0..n)
            .flat_map(|i| {
                let t = i as f64 / n as f64;
                [t * 4.0, (t * 7.0).sin(), (t * 3.0).cos()]
            })
            .collect();
        let y = x
            .chunks(3)
            .map(|r| r[0].sin() + 0.5 * r[1] - r[2])
            .collect();
        (x, y)
    }

    #[test]
    fn kkt_holds_at_the_solution() {
        let (x, y) = data(80);
        let s = Samples::new(&x, 80, 3).unwrap();
        let params = SvrParams::new()
            .c(3.0)
            .epsilon(0.05)
            .tol(1e-6)
            .check()
            .unwrap();
        let m = params.fit(s, &y).unwrap();
        // Σβ = 0 and |β| ≤ C
        let sum: f64 = m.dual_coef.iter().sum();
        assert!(sum.abs() < 1e-9, "{sum}");
        assert!(m.dual_coef.iter().all(|b| b.abs() <= 3.0 + 1e-12));
        // free SVs sit on the ε-tube (within the f32 kernel cache and tol), bounded ones outside
        let pred = m.predict(s).unwrap();
        for (k, &i) in m.support.iter().enumerate() {
            let r = y[i] - pred[i];
            if m.dual_coef[k].abs() < 3.0 - 1e-9 {
                assert!((r.abs() - 0.05).abs() < 1e-4, "free SV {i}: r={r}");
            } else {
                assert!(r.abs() >= 0.05 - 1e-4, "bounded SV {i}: r={r}");
            }
        }
        // non-SVs inside the tube
        for i in 0..80 {
            if !m.support.contains(&i) {
                assert!((y[i] - pred[i]).abs() <= 0.05 + 1e-4);
            }
        }
    }

    /// A fit and its predictions through distances formed once for a superset of the rows are
    /// the ones from the rows gathered, bit for bit (rows in any order, a small cache too).
    #[test]
    fn shared_distances_give_the_same_model() {
        let (x, y) = data(150);
        let all = Samples::new(&x, 150, 3).unwrap();
        let shared = SharedDistances::new(all);
        let rows: Vec<usize> = (0..150).filter(|i| i % 3 != 1).rev().collect();
        let test: Vec<usize> = (0..150).filter(|i| i % 3 == 1).collect();
        let gather =
            |idx: &[usize]| -> Vec<f64> { idx.iter().flat_map(|&i| all.row(i).to_vec()).collect() };
        let (xr, xt) = (gather(&rows), gather(&test));
        let yr: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
        for (c, gamma, cache) in [(10.0, 0.7, 200.0), (0.5, 3.0, 1e-3)] {
            let p = SvrParams::new()
                .c(c)
                .epsilon(0.02)
                .gamma(Gamma::Value(gamma))
                .cache_size(cache)
                .check()
                .unwrap();
            let a = p
                .fit(Samples::new(&xr, rows.len(), 3).unwrap(), &yr)
                .unwrap();
            let b = p.fit_shared(all, &rows, &yr, &shared, None).unwrap();
            assert_eq!(a, b);
            let pa = a
                .predict(Samples::new(&xt, test.len(), 3).unwrap())
                .unwrap();
            let pb = b.predict_shared(&test, &rows, &shared);
            assert_eq!(pa, pb);
        }
        // the linear kernel, or a γ by name, cannot be read from distances
        let lin = SvrParams::new().kernel(KernelKind::Linear).check().unwrap();
        assert!(lin.fit_shared(all, &rows, &yr, &shared, None).is_err());
    }

    /// A warm start from a neighbouring (C, γ) reaches a solution that meets the same stopping
    /// rule in fewer iterations; its predictions agree with the cold start's to O(tol).
    #[test]
    fn a_warm_start_ends_at_an_equally_good_solution_sooner() {
        let (x, y) = data(200);
        let all = Samples::new(&x, 200, 3).unwrap();
        let shared = SharedDistances::new(all);
        let rows: Vec<usize> = (0..200).collect();
        let at = |c: f64, g: f64| {
            SvrParams::new()
                .c(c)
                .epsilon(0.01)
                .gamma(Gamma::Value(g))
                .check()
                .unwrap()
        };
        let old = at(20.0, 1.1)
            .fit_shared(all, &rows, &y, &shared, None)
            .unwrap();
        let mut beta = vec![0.0; 200];
        for (&k, &b) in old.support.iter().zip(&old.dual_coef) {
            beta[k] = b;
        }
        let new = at(30.0, 1.0);
        let cold = new.fit_shared(all, &rows, &y, &shared, None).unwrap();
        let warm = new
            .fit_shared(all, &rows, &y, &shared, Some((&beta, 20.0)))
            .unwrap();
        assert!(
            warm.n_iter < cold.n_iter,
            "{} vs {}",
            warm.n_iter,
            cold.n_iter
        );
        let (pc, pw) = (cold.predict(all).unwrap(), warm.predict(all).unwrap());
        let worst = pc
            .iter()
            .zip(&pw)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        // two solutions meeting the rule (max violation < tol = 1e-3) differ by O(tol)
        assert!(worst < 1e-2, "largest difference {worst}");
        // the equality constraint survives the scaling: Σ β = 0
        let sum: f64 = warm.dual_coef.iter().sum();
        assert!(sum.abs() < 1e-9 * 30.0 * 200.0, "{sum}");
    }

    #[test]
    fn shrinking_and_tiny_cache_give_the_same_model() {
        let (x, y) = data(120);
        let s = Samples::new(&x, 120, 3).unwrap();
        let base = SvrParams::new().c(10.0).epsilon(0.01).tol(1e-5);
        let a = base.clone().check().unwrap().fit(s, &y).unwrap();
        let b = base
            .clone()
            .shrinking(false)
            .cache_size(1e-4)
            .check()
            .unwrap()
            .fit(s, &y)
            .unwrap();
        let pa = a.predict(s).unwrap();
        let pb = b.predict(s).unwrap();
        for (u, v) in pa.iter().zip(&pb) {
            assert!((u - v).abs() < 1e-3, "{u} vs {v}");
        }
        // the cache size alone never changes a single bit
        let c = base.cache_size(1e-4).check().unwrap().fit(s, &y).unwrap();
        assert_eq!(a, c);
    }

    #[test]
    fn bad_params_are_errors() {
        let (x, y) = data(10);
        let s = Samples::new(&x, 10, 3).unwrap();
        for p in [
            SvrParams::new().c(0.0),
            SvrParams::new().epsilon(-1.0),
            SvrParams::new().gamma(Gamma::Value(f64::NAN)),
        ] {
            assert!(p.check().is_err());
        }
        let p = SvrParams::new().check().unwrap();
        assert!(p.fit(s, &y[..9]).is_err());
    }

    #[test]
    fn names_parse_as_serde_reads_them() {
        crate::error::assert_names_agree(&KernelKind::NAMES);
        for (n, g) in [("scale", Gamma::Scale), ("auto", Gamma::Auto)] {
            assert_eq!(n.parse::<Gamma>().unwrap(), g);
            assert_eq!(serde_json::to_string(&g).unwrap(), format!("{n:?}"));
        }
        let e = "wide".parse::<Gamma>().unwrap_err().to_string();
        assert!(
            e.contains("gamma") && e.contains(r#""scale", "auto""#),
            "{e}"
        );
    }

    #[test]
    fn autotraits() {
        fn is_send_sync<T: Send + Sync>() {}
        is_send_sync::<SvrParams>();
        is_send_sync::<SvrValidParams>();
        is_send_sync::<SvrModel>();
    }

    #[test]
    fn model_json_round_trip() {
        let (x, y) = data(30);
        let s = Samples::new(&x, 30, 3).unwrap();
        let m = SvrParams::new().check().unwrap().fit(s, &y).unwrap();
        let back: SvrModel = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
        assert_eq!(m, back);
    }
}

#[cfg(all(test, feature = "fit"))]
mod lane_tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// G, y, the I_low (or I_up) mask, QD and Q_i of one random selection case.
    type Case = (Vec<f64>, Vec<f64>, Vec<bool>, Vec<f64>, Vec<f32>);

    /// Random selection inputs with ties, ±0, empty sets and every length mod LANES.
    fn case(rng: &mut rand_chacha::ChaCha8Rng, n: usize) -> Case {
        let pick = |rng: &mut rand_chacha::ChaCha8Rng| -> f64 {
            match rng.random_range(0..6) {
                0 => 0.0,
                1 => -0.0,
                2 => 0.5,
                _ => rng.random_range(-2.0..2.0),
            }
        };
        let g = (0..n).map(|_| pick(rng)).collect();
        let y = (0..n)
            .map(|_| if rng.random_bool(0.5) { 1.0 } else { -1.0 })
            .collect();
        let mask = (0..n).map(|_| rng.random_bool(0.7)).collect();
        let qd = (0..n).map(|_| rng.random_range(0.5..1.5)).collect();
        let qi = (0..n).map(|_| rng.random_range(-1.0f32..1.0)).collect();
        (g, y, mask, qd, qi)
    }

    /// LIBSVM's sequential loops, as they were before the lanes.
    fn sequential_pass2(p: &Pass2<'_>) -> (f64, usize, f64) {
        let (mut obj_min, mut idx, mut gmax2) = (f64::INFINITY, usize::MAX, f64::NEG_INFINITY);
        for j in 0..p.g.len() {
            if !p.low[j] {
                continue;
            }
            let v = p.y[j] * p.g[j];
            let gd = p.gmax + v;
            if v >= gmax2 {
                gmax2 = v;
            }
            if gd > 0.0 {
                let quad = p.qdi + p.qd[j] + (-2.0 * p.yi * p.y[j]) * p.qi[j] as f64;
                let o = if quad > 0.0 {
                    -(gd * gd) / quad
                } else {
                    -(gd * gd) / TAU
                };
                if o <= obj_min {
                    idx = j;
                    obj_min = o;
                }
            }
        }
        (obj_min, idx, gmax2)
    }

    #[test]
    fn the_gather_reads_the_row_as_the_scalar_loop() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for n in 0..40 {
            let d: Vec<f32> = (0..n.max(1))
                .map(|_| rng.random_range(-1.0f32..1.0))
                .collect();
            let index: Vec<u32> = (0..2 * n)
                .map(|_| rng.random_range(0..d.len() as u32))
                .collect();
            let sign: Vec<f32> = (0..2 * n)
                .map(|_| if rng.random_bool(0.5) { 1.0 } else { -1.0 })
                .collect();
            let mut out = vec![0.0f32; 2 * n];
            gather_signed(&d, -0.5, &sign, &index, &mut out);
            for t in 0..2 * n {
                assert_eq!(
                    out[t].to_bits(),
                    (-0.5 * sign[t] * d[index[t] as usize]).to_bits()
                );
            }
        }
    }

    #[test]
    fn lanes_select_what_the_sequential_loops_select() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for n in 0..70 {
            for _ in 0..20 {
                let (g, y, low, qd, qi) = case(&mut rng, n);
                let p = Pass2 {
                    g: &g,
                    y: &y,
                    low: &low,
                    qd: &qd,
                    qi: &qi,
                    yi: 1.0,
                    qdi: 1.0,
                    gmax: 0.3,
                };
                let want = sequential_pass2(&p);
                for got in [p.run_lanes(0, n), p.run(0, n)] {
                    assert_eq!(
                        (got.obj_min.to_bits(), got.idx),
                        (want.0.to_bits(), want.1),
                        "n = {n}"
                    );
                    assert_eq!(got.gmax2, want.2, "n = {n}");
                }
                // the first pass, with the update
                let (dai, daj) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                let qj: Vec<f32> = qi.iter().rev().copied().collect();
                let mut g_seq = g.clone();
                for t in 0..n {
                    g_seq[t] += qi[t] as f64 * dai + qj[t] as f64 * daj;
                }
                let want = scan_i(&g_seq, &y, &low, 3);
                let (mut g1, mut g2) = (g.clone(), g.clone());
                let u = Update {
                    qi: &qi,
                    qj: &qj,
                    dai,
                    daj,
                    y: &y,
                    up: &low,
                };
                let a = update_scan_lanes(&u, &mut g1, 3);
                let b = update_scan(&u, &mut g2, 3);
                for (got, gg) in [(a, &g1), (b, &g2)] {
                    assert_eq!(
                        (got.0.to_bits(), got.1),
                        (want.0.to_bits(), want.1),
                        "n = {n}"
                    );
                    assert!(gg
                        .iter()
                        .zip(&g_seq)
                        .all(|(a, b)| a.to_bits() == b.to_bits()));
                }
            }
        }
    }
}
