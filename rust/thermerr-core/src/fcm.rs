//! Fuzzy c-means (Bezdek), iterated step for step as scikit-fuzzy's `skfuzzy.cluster.cmeans`.
//!
//! Rows of the sample matrix are the objects. One iteration, exactly in scikit-fuzzy's order:
//!
//! 1. normalise each object's memberships to sum 1, clip them below at ε (machine epsilon) and
//!    raise them to `m`: w_ik = max(u_ik / Σ_j u_jk, ε)^m;
//! 2. centres v_i = Σ_k w_ik x_k / Σ_k w_ik;
//! 3. distances d_ik = max(‖x_k − v_i‖, ε);
//! 4. objective J = Σ_k Σ_i w_ik d_ik² (the memberships of step 1, the centres of step 2);
//! 5. new memberships u_ik = d_ik^(−2/(m−1)) / Σ_j d_jk^(−2/(m−1)), computed as scikit-fuzzy's
//!    `normalize_power_columns` does (ratios to the largest distance, clipped at ε, divided by the
//!    smallest, then powered), which never divides by zero;
//! 6. stop when ‖U_new − U_old‖_F < tol (Frobenius norm over all memberships) or after
//!    `max_iter` iterations. The iteration count includes the last iteration.
//!
//! The fitted model reports the centres of step 2 and the memberships of step 5 of the last
//! iteration, and the objective of its step 4, as scikit-fuzzy does.
//!
//! **A point on a centre.** Distances are clipped at ε, so an object at distance 0 from centre i
//! gets the ratio ε against the others and membership 1 − O(ε²) there, which rounds to exactly
//! 1.0; its other memberships are O(ε²)·(scale)⁻², not exactly 0. This is methods.md's "membership 1
//! there" up to rounding, and it is scikit-fuzzy's behaviour, so the two agree. They differ from
//! a literal "1 and 0" rule only below 1e−30. The clip is absolute: data whose distances are all
//! below ε (about 2.2e−16) cannot be clustered; scale such data first.
//!
//! **Speed.** One pass over the data per iteration: the sweep that computes the distances to the
//! current centres of a block of objects also accumulates those objects' weighted sums for the
//! next centres while their rows are still in cache. Objects are split into a fixed number of
//! groups (set by the problem size, not by the thread count) that run in parallel, each with its
//! own accumulator, reduced in a fixed order: results are bitwise the same on any number of threads.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::linear::check_features;
use crate::portable;
use crate::samples::{check_finite, Matrix, Samples};

const EPS: f64 = f64::EPSILON;
/// Objects whose distances are computed together, so each chunk of the centres is reused.
const BLOCK: usize = 8;
/// Features per cache chunk (2 KiB of one row; a block of rows and the centres stay in L1).
const CHUNK: usize = 256;
/// Upper bound on the object groups that run in parallel (each holds a c × d accumulator).
const MAX_GROUPS: usize = 8;
/// Below this many multiply-adds per iteration, threads cost more than they save.
const PAR_MIN_WORK: usize = 1 << 17;

/// Hyper-parameters of fuzzy c-means; a consuming builder with defaults, checked by [`check`].
///
/// [`check`]: FcmParams::check
#[derive(Clone, Debug, PartialEq)]
pub struct FcmParams(FcmValidParams);

/// Checked hyper-parameters; [`FcmValidParams::fit`] runs the algorithm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FcmValidParams {
    pub n_clusters: usize,
    pub m: f64,
    pub tol: f64,
    pub max_iter: usize,
    pub seed: Option<u64>,
    /// Initial partition, `n_objects × n_clusters`, rows summing to 1.
    pub init: Option<Matrix>,
}

impl FcmParams {
    /// `n_clusters` clusters, m = 2, tol = 1e-5, at most 1000 iterations, random start.
    pub fn new(n_clusters: usize) -> Self {
        FcmParams(FcmValidParams {
            n_clusters,
            m: 2.0,
            tol: 1e-5,
            max_iter: 1000,
            seed: None,
            init: None,
        })
    }

    /// Weighting exponent (fuzziness), m > 1.
    pub fn m(mut self, m: f64) -> Self {
        self.0.m = m;
        self
    }

    /// Stop when the Frobenius norm of the membership change falls below `tol`.
    pub fn tol(mut self, tol: f64) -> Self {
        self.0.tol = tol;
        self
    }

    pub fn max_iter(mut self, max_iter: usize) -> Self {
        self.0.max_iter = max_iter;
        self
    }

    /// Seed of the random initial partition (ChaCha8); ignored when `init` is given.
    pub fn seed(mut self, seed: Option<u64>) -> Self {
        self.0.seed = seed;
        self
    }

    /// Initial partition, `n_objects × n_clusters`, non-negative, rows summing to 1.
    pub fn init(mut self, init: Option<Matrix>) -> Self {
        self.0.init = init;
        self
    }

    /// Validates everything that does not depend on the data.
    pub fn check(self) -> Result<FcmValidParams> {
        let p = self.0;
        if p.n_clusters < 2 {
            return Err(Error::param(
                "n_clusters",
                format!("must be at least 2, got {}", p.n_clusters),
            ));
        }
        if !(p.m > 1.0 && p.m.is_finite()) {
            return Err(Error::param(
                "m",
                format!("must be finite and > 1, got {}", p.m),
            ));
        }
        if !(p.tol > 0.0 && p.tol.is_finite()) {
            return Err(Error::param(
                "tol",
                format!("must be finite and > 0, got {}", p.tol),
            ));
        }
        if p.max_iter == 0 {
            return Err(Error::param("max_iter", "must be at least 1"));
        }
        if let Some(u) = &p.init {
            check_partition(u, p.n_clusters)?;
        }
        Ok(p)
    }
}

fn check_partition(u: &Matrix, c: usize) -> Result<()> {
    if u.ncols() != c {
        return Err(Error::param(
            "init",
            format!(
                "must have n_clusters = {c} columns, got shape {} x {}",
                u.nrows(),
                u.ncols()
            ),
        ));
    }
    for (k, row) in u.data.chunks_exact(c).enumerate() {
        if let Some(v) = row.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(Error::param(
                "init",
                format!("row {k} holds {v}; memberships must be finite and non-negative"),
            ));
        }
        let s: f64 = row.iter().sum();
        if (s - 1.0).abs() > 1e-6 {
            return Err(Error::param(
                "init",
                format!("row {k} sums to {s}; each object's memberships must sum to 1"),
            ));
        }
    }
    Ok(())
}

/// A fitted fuzzy c-means partition.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FcmModel {
    /// Weighting exponent used (needed to compute memberships of new objects).
    pub m: f64,
    /// Cluster centres, `n_clusters × n_features`.
    pub centers: Matrix,
    /// Memberships of the fitted objects, `n_objects × n_clusters`; rows sum to 1.
    pub membership: Matrix,
    /// Iterations run, the last one included.
    pub n_iter: usize,
    /// J_m of the last iteration.
    pub objective: f64,
    /// J_m of every iteration.
    pub history: Vec<f64>,
    /// Whether the membership change fell below `tol` before `max_iter`.
    pub converged: bool,
}

impl FcmValidParams {
    /// Runs fuzzy c-means on the rows of `x`.
    pub fn fit(&self, x: Samples<'_>) -> Result<FcmModel> {
        x.require_finite("X")?;
        let (n, c) = (x.nrows(), self.n_clusters);
        if c > n {
            return Err(Error::param(
                "n_clusters",
                format!("{c} clusters need at least {c} objects, got {n}"),
            ));
        }
        let u0 = match &self.init {
            Some(u) => {
                check_partition(u, c)?;
                if u.nrows() != n {
                    return Err(Error::param(
                        "init",
                        format!("must have one row per object ({n}), got {}", u.nrows()),
                    ));
                }
                u.data.clone()
            }
            None => random_partition(n, c, self.seed),
        };
        let d = x.ncols();
        if n.saturating_mul(4) <= d && n <= GRAM_MAX_OBJECTS {
            gram_run(x, c, self.m, u0, self.tol, self.max_iter)
        } else {
            Fcm::new(x, c, self.m).run(u0, self.tol, self.max_iter)
        }
    }
}

/// Objects at most this many (and at most a quarter of the features) take the Gram path: its
/// O(n²d) set-up costs about n/20 direct iterations, repaid within a typical fit.
const GRAM_MAX_OBJECTS: usize = 256;

/// The same iteration for few objects with many features (sensor series: 20 objects of hundreds
/// of samples). Every centre is a weighted mean of the objects, so with the Gram matrix
/// G = X̃X̃ᵀ of the mean-centred objects, ‖x_k − v_i‖² = G_kk − 2(GW)_ki/s_i + (WᵀGW)_ii/s_i²:
/// one O(n²d) product up front, then O(n²c) per iteration instead of O(ndc). The centres
/// themselves are formed once, at the end.
fn gram_run(
    x: Samples<'_>,
    c: usize,
    m: f64,
    u0: Vec<f64>,
    tol: f64,
    max_iter: usize,
) -> Result<FcmModel> {
    let (n, d) = (x.nrows(), x.ncols());
    let mut mean = vec![0.0; d];
    for r in x.rows() {
        for (a, v) in mean.iter_mut().zip(r) {
            *a += v;
        }
    }
    mean.iter_mut().for_each(|v| *v /= n as f64);
    // the mean-centred objects, row-major, and their Gram matrix in a fixed order of operations
    // (the same bits on every CPU: sensor grouping decides the identified network)
    let xc: Vec<f64> = x
        .rows()
        .flat_map(|r| r.iter().zip(&mean).map(|(v, m)| v - m))
        .collect();
    let objects: Vec<&[f64]> = xc.chunks_exact(d).collect();
    let gflat = crate::linalg::gram(&objects, d)?;
    let g = |k: usize, l: usize| gflat[k * n + l];
    let mut u_prev: Vec<f64> = u0.iter().map(|v| v.max(EPS)).collect();
    let mut u_new = vec![0.0; n * c];
    let mut w = vec![0.0; n * c];
    let mut gw = vec![0.0; n * c];
    let mut dist = vec![0.0; n * c];
    let mut history = Vec::new();
    let mut converged = false;
    let mut n_iter = 0;
    while n_iter < max_iter {
        n_iter += 1;
        crate::interrupt::check()?;
        for (wr, ur) in w.chunks_exact_mut(c).zip(u_prev.chunks_exact(c)) {
            weights(ur, wr, m);
        }
        let mut s = vec![0.0; c];
        for wr in w.chunks_exact(c) {
            for (a, v) in s.iter_mut().zip(wr) {
                *a += v;
            }
        }
        for k in 0..n {
            for i in 0..c {
                let mut acc = 0.0;
                for l in 0..n {
                    acc += g(k, l) * w[l * c + i];
                }
                gw[k * c + i] = acc;
            }
        }
        let mut vv = vec![0.0; c];
        for k in 0..n {
            for i in 0..c {
                vv[i] += w[k * c + i] * gw[k * c + i];
            }
        }
        let mut objective = 0.0;
        for k in 0..n {
            for i in 0..c {
                let d2 = g(k, k) - 2.0 * gw[k * c + i] / s[i] + vv[i] / (s[i] * s[i]);
                let dk = d2.max(0.0).sqrt().max(EPS);
                dist[k * c + i] = dk;
                objective += w[k * c + i] * dk * dk;
            }
        }
        history.push(objective);
        for (ur, dr) in u_new.chunks_exact_mut(c).zip(dist.chunks_exact(c)) {
            memberships(dr, ur, m);
        }
        let delta = u_new
            .iter()
            .zip(&u_prev)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        std::mem::swap(&mut u_prev, &mut u_new);
        if delta < tol {
            converged = true;
            break;
        }
    }
    // centres of the last iteration: from the weights that produced its distances
    let mut s = vec![0.0; c];
    let mut centers = vec![0.0; c * d];
    for (k, r) in x.rows().enumerate() {
        for i in 0..c {
            let wk = w[k * c + i];
            s[i] += wk;
            for (a, v) in centers[i * d..(i + 1) * d].iter_mut().zip(r) {
                *a += wk * v;
            }
        }
    }
    for i in 0..c {
        centers[i * d..(i + 1) * d]
            .iter_mut()
            .for_each(|v| *v /= s[i]);
    }
    fitted(m, centers, c, d, u_prev, n_iter, history, converged)
}

/// The fitted model, refusing a partition that diverged to non-finite values.
#[allow(clippy::too_many_arguments)]
fn fitted(
    m: f64,
    centers: Vec<f64>,
    c: usize,
    d: usize,
    u: Vec<f64>,
    n_iter: usize,
    history: Vec<f64>,
    converged: bool,
) -> Result<FcmModel> {
    if let Err(e) = check_finite(&u, c, "membership") {
        return Err(Error::Numerical(format!("fuzzy c-means diverged ({e})")));
    }
    Ok(FcmModel {
        m,
        centers: Matrix {
            shape: [c, d],
            data: centers,
        },
        membership: Matrix {
            shape: [u.len() / c.max(1), c],
            data: u,
        },
        n_iter,
        objective: history.last().copied().unwrap_or(f64::NAN),
        history,
        converged,
    })
}

/// Uniform random memberships, each row normalised to sum 1 (drawn object by object).
fn random_partition(n: usize, c: usize, seed: Option<u64>) -> Vec<f64> {
    let seed = seed.unwrap_or_else(|| rand::rng().random());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut u: Vec<f64> = (0..n * c).map(|_| rng.random::<f64>()).collect();
    for row in u.chunks_exact_mut(c) {
        let s: f64 = row.iter().sum();
        row.iter_mut().for_each(|v| *v /= s);
    }
    u
}

/// Per-group state of the sweep, allocated once per fit.
struct Group {
    start: usize,
    end: usize,
    acc: Vec<f64>,
    den: Vec<f64>,
    dist: Vec<f64>,
    objective: f64,
    delta2: f64,
}

struct Fcm<'a> {
    x: Samples<'a>,
    c: usize,
    m: f64,
    groups: Vec<Group>,
    parallel: bool,
}

impl<'a> Fcm<'a> {
    fn new(x: Samples<'a>, c: usize, m: f64) -> Self {
        let (n, d) = (x.nrows(), x.ncols());
        let per = n.div_ceil(MAX_GROUPS).max(BLOCK);
        let groups = (0..n.div_ceil(per))
            .map(|g| Group {
                start: g * per,
                end: ((g + 1) * per).min(n),
                acc: vec![0.0; c * d],
                den: vec![0.0; c],
                dist: vec![0.0; BLOCK * c],
                objective: 0.0,
                delta2: 0.0,
            })
            .collect();
        let parallel = n.saturating_mul(d).saturating_mul(c) >= PAR_MIN_WORK;
        Fcm {
            x,
            c,
            m,
            groups,
            parallel,
        }
    }

    fn run(mut self, u0: Vec<f64>, tol: f64, max_iter: usize) -> Result<FcmModel> {
        let (n, d, c, m) = (self.x.nrows(), self.x.ncols(), self.c, self.m);
        // scikit-fuzzy clips the initial partition before its first comparison
        let mut u_prev: Vec<f64> = u0.iter().map(|v| v.max(EPS)).collect();
        let mut u_new = vec![0.0; n * c];
        let mut w_prev = vec![0.0; n * c];
        let mut w_new = vec![0.0; n * c];
        for (w, u) in w_prev.chunks_exact_mut(c).zip(u_prev.chunks_exact(c)) {
            weights(u, w, m);
        }
        let mut centers = vec![0.0; c * d];
        self.for_groups(&mut [], &mut [], &w_prev, &[], |x, g, _, _, w, _| {
            init_accumulate(x, g, w, c)
        });
        self.reduce(&mut centers)?;

        let mut history = Vec::new();
        let mut converged = false;
        let mut n_iter = 0;
        while n_iter < max_iter {
            n_iter += 1;
            crate::interrupt::check()?;
            let last = n_iter == max_iter;
            let ctr = &centers;
            self.for_groups(
                &mut u_new,
                &mut w_new,
                &w_prev,
                &u_prev,
                |x, g, u, wn, wp, up| sweep(x, g, ctr, u, wn, wp, up, c, m, !last),
            );
            history.push(self.groups.iter().map(|g| g.objective).sum::<f64>());
            let delta = self.groups.iter().map(|g| g.delta2).sum::<f64>().sqrt();
            std::mem::swap(&mut u_prev, &mut u_new);
            std::mem::swap(&mut w_prev, &mut w_new);
            if delta < tol {
                converged = true;
                break;
            }
            if !last {
                self.reduce(&mut centers)?;
            }
        }
        fitted(m, centers, c, d, u_prev, n_iter, history, converged)
    }

    /// Runs `f` on every group, in parallel when the problem is large enough, handing it the
    /// group's rows of the four `n × c` buffers (empty slices stay empty).
    fn for_groups<F>(&mut self, u_new: &mut [f64], w_new: &mut [f64], w: &[f64], u: &[f64], f: F)
    where
        F: Fn(Samples<'_>, &mut Group, &mut [f64], &mut [f64], &[f64], &[f64]) + Sync,
    {
        let (x, c, d) = (self.x, self.c, self.x.ncols());
        let parts = |g: &Group, len: usize| {
            if len == 0 {
                0..0
            } else {
                g.start * c..g.end * c
            }
        };
        let mut work: Vec<(&mut Group, &mut [f64], &mut [f64])> = Vec::new();
        let (mut un, mut wn) = (u_new, w_new);
        for g in self.groups.iter_mut() {
            let (la, lb) = (parts(g, un.len()).len(), parts(g, wn.len()).len());
            let (a, rest) = std::mem::take(&mut un).split_at_mut(la);
            un = rest;
            let (b, rest) = std::mem::take(&mut wn).split_at_mut(lb);
            wn = rest;
            work.push((g, a, b));
        }
        let run = |(g, a, b): &mut (&mut Group, &mut [f64], &mut [f64])| {
            let rows = &x.as_slice()[g.start * d..g.end * d];
            let xs = Samples::new(rows, g.end - g.start, d).unwrap_or(x);
            let wr = &w[parts(g, w.len())];
            let ur = &u[parts(g, u.len())];
            f(xs, g, a, b, wr, ur);
        };
        if self.parallel {
            work.par_iter_mut().for_each(run);
        } else {
            work.iter_mut().for_each(run);
        }
    }

    /// Centres = (Σ over groups of the accumulators) / (Σ of the weights), in group order.
    fn reduce(&self, centers: &mut [f64]) -> Result<()> {
        let c = self.c;
        let d = self.x.ncols();
        let mut den = vec![0.0; c];
        for g in &self.groups {
            den.iter_mut().zip(&g.den).for_each(|(a, b)| *a += b);
        }
        if let Some(i) = den.iter().position(|s| !(*s > 0.0 && s.is_finite())) {
            return Err(Error::Numerical(format!(
                "the weights of cluster {i} sum to {} (m = {} is too large for this data)",
                den[i], self.m
            )));
        }
        let groups = &self.groups;
        let body = |(k, out): (usize, &mut [f64])| {
            let off = k * CHUNK;
            out.iter_mut().for_each(|v| *v = 0.0);
            for g in groups {
                let src = &g.acc[off..off + out.len()];
                out.iter_mut().zip(src).for_each(|(a, b)| *a += b);
            }
            for (j, v) in out.iter_mut().enumerate() {
                *v /= den[(off + j) / d.max(1)];
            }
        };
        if self.parallel {
            centers.par_chunks_mut(CHUNK).enumerate().for_each(body);
        } else {
            centers.chunks_mut(CHUNK).enumerate().for_each(body);
        }
        Ok(())
    }
}

/// w = max(u / Σu, ε)^m, scikit-fuzzy's weights of the centre update.
#[inline(always)]
fn weights(u: &[f64], w: &mut [f64], m: f64) {
    let s: f64 = u.iter().sum();
    for (wi, ui) in w.iter_mut().zip(u) {
        let v = (ui / s).max(EPS);
        *wi = if m == 2.0 {
            v * v
        } else {
            portable::powf(v, m)
        };
    }
}

/// Memberships from distances, as scikit-fuzzy's `normalize_power_columns(d, -2/(m-1))`.
#[inline(always)]
fn memberships(dist: &[f64], u: &mut [f64], m: f64) {
    let e = -2.0 / (m - 1.0);
    let mx = dist.iter().fold(0.0f64, |a, &b| a.max(b));
    for (ui, di) in u.iter_mut().zip(dist) {
        *ui = (di / mx).max(EPS);
    }
    let mn = u.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    for ui in u.iter_mut() {
        let r = *ui / mn;
        *ui = if e == -2.0 {
            1.0 / (r * r)
        } else {
            portable::powf(r, e)
        };
    }
    let s: f64 = u.iter().sum();
    u.iter_mut().for_each(|v| *v /= s);
}

fn init_accumulate(x: Samples<'_>, g: &mut Group, w: &[f64], c: usize) {
    g.acc.iter_mut().for_each(|v| *v = 0.0);
    g.den.iter_mut().for_each(|v| *v = 0.0);
    let rows = x.nrows();
    let mut b0 = 0;
    while b0 < rows {
        let b1 = (b0 + BLOCK).min(rows);
        accumulate(x, b0, b1, &w[b0 * c..b1 * c], g, c);
        b0 = b1;
    }
}

/// acc_i += Σ_{b in block} w_bi x_b, chunk by chunk so the accumulator chunk stays in L1.
#[inline(always)]
fn accumulate(x: Samples<'_>, b0: usize, b1: usize, w: &[f64], g: &mut Group, c: usize) {
    let d = x.ncols();
    for wb in w.chunks_exact(c) {
        for (den, wi) in g.den.iter_mut().zip(wb) {
            *den += wi;
        }
    }
    let mut j0 = 0;
    while j0 < d {
        let j1 = (j0 + CHUNK).min(d);
        for i in 0..c {
            let acc = &mut g.acc[i * d + j0..i * d + j1];
            for (b, wb) in (b0..b1).zip(w.chunks_exact(c)) {
                axpy(acc, wb[i], &x.row(b)[j0..j1]);
            }
        }
        j0 = j1;
    }
}

#[inline(always)]
fn axpy(acc: &mut [f64], a: f64, x: &[f64]) {
    for (s, v) in acc.iter_mut().zip(x) {
        *s += a * v;
    }
}

/// Σ (a − b)² with 16 independent partial sums (vectorises, and rounds the same with or
/// without SIMD because the lanes are explicit).
#[inline(always)]
fn sqdist(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 16];
    let ac = a.chunks_exact(16);
    let bc = b.chunks_exact(16);
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for k in 0..16 {
            let t = x[k] - y[k];
            acc[k] += t * t;
        }
    }
    let mut rest = 0.0;
    for (x, y) in ar.iter().zip(br) {
        let t = x - y;
        rest += t * t;
    }
    let mut h = [0.0f64; 8];
    for k in 0..8 {
        h[k] = acc[k] + acc[k + 8];
    }
    ((h[0] + h[4]) + (h[1] + h[5])) + ((h[2] + h[6]) + (h[3] + h[7])) + rest
}

/// The distance kernel, chosen once per sweep by the CPU's features.
trait Kernel {
    fn sqdist(a: &[f64], b: &[f64]) -> f64;
}

struct Scalar;

impl Kernel for Scalar {
    #[inline(always)]
    fn sqdist(a: &[f64], b: &[f64]) -> f64 {
        sqdist(a, b)
    }
}

/// Only used by [`sweep_avx2`], which runs after the CPU was checked for AVX2.
#[cfg(target_arch = "x86_64")]
struct Avx2;

#[cfg(target_arch = "x86_64")]
impl Kernel for Avx2 {
    #[inline(always)]
    fn sqdist(a: &[f64], b: &[f64]) -> f64 {
        // SAFETY: `Avx2` is only used inside `sweep_avx2`, called after AVX2 was detected.
        unsafe { sqdist_avx2(a, b) }
    }
}

/// [`sqdist`] with AVX2 intrinsics: the same 16 lanes and the same final sum order, so the
/// result is bitwise that of the scalar code (LLVM vectorised the scalar version poorly).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn sqdist_avx2(a: &[f64], b: &[f64]) -> f64 {
    use std::arch::x86_64::*;
    let n = a.len().min(b.len());
    let full = n - n % 16;
    let mut acc = [_mm256_setzero_pd(); 4];
    let (pa, pb) = (a.as_ptr(), b.as_ptr());
    let mut j = 0;
    while j < full {
        for (q, s) in acc.iter_mut().enumerate() {
            // SAFETY: j + 4q + 4 <= full <= len of both slices
            let t = unsafe {
                _mm256_sub_pd(
                    _mm256_loadu_pd(pa.add(j + 4 * q)),
                    _mm256_loadu_pd(pb.add(j + 4 * q)),
                )
            };
            *s = _mm256_add_pd(*s, _mm256_mul_pd(t, t));
        }
        j += 16;
    }
    let mut rest = 0.0;
    for k in full..n {
        let t = a[k] - b[k];
        rest += t * t;
    }
    let lo = _mm256_add_pd(acc[0], acc[2]);
    let hi = _mm256_add_pd(acc[1], acc[3]);
    let q = _mm256_add_pd(lo, hi);
    let mut v = [0.0f64; 4];
    // SAFETY: v holds 4 doubles
    unsafe { _mm256_storeu_pd(v.as_mut_ptr(), q) };
    ((v[0] + v[1]) + (v[2] + v[3])) + rest
}

/// One iteration over a group: distances to `centers`, new memberships, objective and change,
/// and (unless `accumulate_next`) the weighted sums of the next centres.
#[allow(clippy::too_many_arguments)]
fn sweep(
    x: Samples<'_>,
    g: &mut Group,
    centers: &[f64],
    u_new: &mut [f64],
    w_new: &mut [f64],
    w_prev: &[f64],
    u_prev: &[f64],
    c: usize,
    m: f64,
    accumulate_next: bool,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            unsafe {
                return sweep_avx2(
                    x,
                    g,
                    centers,
                    u_new,
                    w_new,
                    w_prev,
                    u_prev,
                    c,
                    m,
                    accumulate_next,
                );
            }
        }
    }
    sweep_generic::<Scalar>(
        x,
        g,
        centers,
        u_new,
        w_new,
        w_prev,
        u_prev,
        c,
        m,
        accumulate_next,
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn sweep_avx2(
    x: Samples<'_>,
    g: &mut Group,
    centers: &[f64],
    u_new: &mut [f64],
    w_new: &mut [f64],
    w_prev: &[f64],
    u_prev: &[f64],
    c: usize,
    m: f64,
    accumulate_next: bool,
) {
    sweep_generic::<Avx2>(
        x,
        g,
        centers,
        u_new,
        w_new,
        w_prev,
        u_prev,
        c,
        m,
        accumulate_next,
    )
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn sweep_generic<K: Kernel>(
    x: Samples<'_>,
    g: &mut Group,
    centers: &[f64],
    u_new: &mut [f64],
    w_new: &mut [f64],
    w_prev: &[f64],
    u_prev: &[f64],
    c: usize,
    m: f64,
    accumulate_next: bool,
) {
    let (rows, d) = (x.nrows(), x.ncols());
    g.objective = 0.0;
    g.delta2 = 0.0;
    g.acc.iter_mut().for_each(|v| *v = 0.0);
    g.den.iter_mut().for_each(|v| *v = 0.0);
    let mut b0 = 0;
    while b0 < rows {
        let b1 = (b0 + BLOCK).min(rows);
        let nb = b1 - b0;
        let dist = &mut g.dist[..nb * c];
        dist.iter_mut().for_each(|v| *v = 0.0);
        let mut j0 = 0;
        while j0 < d {
            let j1 = (j0 + CHUNK).min(d);
            for (b, db) in (b0..b1).zip(dist.chunks_exact_mut(c)) {
                let xb = &x.row(b)[j0..j1];
                for (i, di) in db.iter_mut().enumerate() {
                    *di += K::sqdist(xb, &centers[i * d + j0..i * d + j1]);
                }
            }
            j0 = j1;
        }
        for (k, db) in (b0..b1).zip(dist.chunks_exact_mut(c)) {
            let r = k * c..(k + 1) * c;
            let mut obj = 0.0;
            for (di, wi) in db.iter_mut().zip(&w_prev[r.clone()]) {
                *di = di.sqrt().max(EPS);
                obj += wi * (*di * *di);
            }
            g.objective += obj;
            let u = &mut u_new[r.clone()];
            memberships(db, u, m);
            g.delta2 += u
                .iter()
                .zip(&u_prev[r.clone()])
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>();
            weights(u, &mut w_new[r], m);
        }
        if accumulate_next {
            accumulate(x, b0, b1, &w_new[b0 * c..b1 * c], g, c);
        }
        b0 = b1;
    }
}

impl FcmModel {
    pub fn n_clusters(&self) -> usize {
        self.centers.nrows()
    }

    pub fn n_features(&self) -> usize {
        self.centers.ncols()
    }

    /// Checks a partition read from a file.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Format(format!("fcm model: {m}")));
        if self.centers.nrows() == 0 || self.centers.ncols() == 0 {
            return bad("no cluster centres".into());
        }
        if !(self.m > 1.0 && self.m.is_finite()) {
            return bad(format!("fuzziness m must be > 1, got {}", self.m));
        }
        if self.membership.ncols() != self.centers.nrows() && self.membership.nrows() > 0 {
            return bad(format!(
                "memberships over {} clusters for {} centres",
                self.membership.ncols(),
                self.centers.nrows()
            ));
        }
        crate::samples::require_finite_model("fcm", "centers", &self.centers.data)?;
        crate::samples::require_finite_model("fcm", "membership", &self.membership.data)
    }

    /// Hard labels of the fitted objects: the cluster of largest membership (first on ties).
    pub fn labels(&self) -> Vec<usize> {
        hard_labels(&self.membership)
    }

    /// Memberships of new objects to the fitted centres (`n × n_clusters`), as scikit-fuzzy's
    /// `cmeans_predict` returns them (there, iterating with fixed centres reaches this after one
    /// step).
    pub fn predict_membership(&self, x: Samples<'_>) -> Result<Matrix> {
        check_features(x.ncols(), self.n_features())?;
        x.require_finite("X")?;
        let (c, d, m) = (self.n_clusters(), self.n_features(), self.m);
        let mut u = vec![0.0; x.nrows() * c];
        let centers = &self.centers.data;
        let body = |(k, uk): (usize, &mut [f64])| {
            let mut dist = [0.0f64; 64];
            let mut big = Vec::new();
            let dk: &mut [f64] = if c <= 64 {
                &mut dist[..c]
            } else {
                big.resize(c, 0.0);
                &mut big
            };
            for (i, di) in dk.iter_mut().enumerate() {
                *di = sqdist(x.row(k), &centers[i * d..(i + 1) * d])
                    .sqrt()
                    .max(EPS);
            }
            memberships(dk, uk, m);
        };
        if x.nrows() * d * c >= PAR_MIN_WORK {
            u.par_chunks_mut(c).enumerate().for_each(body);
        } else {
            u.chunks_mut(c).enumerate().for_each(body);
        }
        Ok(Matrix {
            shape: [x.nrows(), c],
            data: u,
        })
    }

    /// Hard labels of new objects.
    pub fn predict(&self, x: Samples<'_>) -> Result<Vec<usize>> {
        Ok(hard_labels(&self.predict_membership(x)?))
    }
}

/// Index of the largest entry of every row (the first one on ties).
pub fn hard_labels(u: &Matrix) -> Vec<usize> {
    u.data
        .chunks_exact(u.ncols().max(1))
        .map(|row| {
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

    fn blobs(n_per: usize, d: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut x = Vec::new();
        for k in 0..3 * n_per {
            let centre = (k / n_per) as f64 * 10.0;
            for j in 0..d {
                x.push(centre + (j % 2) as f64 + rng.random::<f64>() - 0.5);
            }
        }
        x
    }

    #[test]
    fn autotraits() {
        fn is_send_sync<T: Send + Sync>() {}
        is_send_sync::<FcmParams>();
        is_send_sync::<FcmValidParams>();
        is_send_sync::<FcmModel>();
    }

    #[test]
    fn separates_blobs_and_partition_is_valid() {
        let x = blobs(30, 3, 1);
        let s = Samples::new(&x, 90, 3).unwrap();
        let f = FcmParams::new(3)
            .seed(Some(7))
            .check()
            .unwrap()
            .fit(s)
            .unwrap();
        assert!(f.converged);
        for row in f.membership.data.chunks(3) {
            assert_relative_eq!(row.iter().sum::<f64>(), 1.0, epsilon = 1e-12);
        }
        let l = f.labels();
        for b in 0..3 {
            let first = l[b * 30];
            assert!(l[b * 30..(b + 1) * 30].iter().all(|v| *v == first));
        }
        let mut firsts = vec![l[0], l[30], l[60]];
        firsts.sort();
        assert_eq!(firsts, vec![0, 1, 2]);
        // the objective never increases (Bezdek's alternating optimisation)
        for w in f.history.windows(2) {
            assert!(w[1] <= w[0] * (1.0 + 1e-12), "{:?}", f.history);
        }
        assert_eq!(f.predict(s).unwrap(), l);
    }

    #[test]
    fn seed_is_deterministic_and_parallel_matches_sequential() {
        // 200 x 800 x 3 is above PAR_MIN_WORK, so this runs the parallel path
        let x = blobs(67, 800, 3);
        let n = x.len() / 800;
        let s = Samples::new(&x, n, 800).unwrap();
        let p = FcmParams::new(3).seed(Some(11)).check().unwrap();
        let a = p.fit(s).unwrap();
        let b = p.fit(s).unwrap();
        assert_eq!(a, b);
        let mut f = Fcm::new(s, 3, 2.0);
        f.parallel = false;
        let c = f.run(random_partition(n, 3, Some(11)), 1e-5, 1000).unwrap();
        assert_eq!(a, c);
    }

    #[test]
    fn point_on_a_centre_gets_membership_one() {
        // three identical points per cluster: the centres land exactly on them
        let x = [0.0, 0.0, 0.0, 5.0, 5.0, 5.0];
        let s = Samples::new(&x, 6, 1).unwrap();
        let f = FcmParams::new(2)
            .seed(Some(0))
            .check()
            .unwrap()
            .fit(s)
            .unwrap();
        assert!(f.membership.data.iter().all(|v| v.is_finite()));
        let l = f.labels();
        for (k, row) in f.membership.data.chunks(2).enumerate() {
            assert_eq!(row[l[k]], 1.0);
        }
        let u = f
            .predict_membership(Samples::new(&[f.centers.data[0]], 1, 1).unwrap())
            .unwrap();
        assert_eq!(u.data[0], 1.0);
    }

    #[test]
    fn bad_params_are_refused() {
        let x = blobs(2, 2, 0);
        let s = Samples::new(&x, 6, 2).unwrap();
        assert!(FcmParams::new(1).check().is_err());
        assert!(FcmParams::new(2).m(1.0).check().is_err());
        assert!(FcmParams::new(2).m(f64::NAN).check().is_err());
        assert!(FcmParams::new(2).tol(0.0).check().is_err());
        assert!(FcmParams::new(2).max_iter(0).check().is_err());
        assert!(FcmParams::new(7).check().unwrap().fit(s).is_err());
        let bad = Matrix {
            shape: [6, 2],
            data: vec![0.5, 0.6, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5],
        };
        assert!(FcmParams::new(2).init(Some(bad)).check().is_err());
        let neg = Matrix {
            shape: [1, 2],
            data: vec![1.5, -0.5],
        };
        assert!(FcmParams::new(2).init(Some(neg)).check().is_err());
        let short = Matrix {
            shape: [1, 2],
            data: vec![0.5, 0.5],
        };
        let p = FcmParams::new(2).init(Some(short)).check().unwrap();
        assert!(p.fit(s).is_err());
        let nan = [0.0, f64::NAN];
        let e = FcmParams::new(2)
            .check()
            .unwrap()
            .fit(Samples::new(&nan, 2, 1).unwrap())
            .unwrap_err();
        assert!(matches!(e, Error::NonFinite { .. }));
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_kernel_rounds_like_the_scalar_one() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for len in [0, 1, 15, 16, 17, 100, 512, 1000] {
            let a: Vec<f64> = (0..len).map(|_| rng.random::<f64>() * 1e3).collect();
            let b: Vec<f64> = (0..len).map(|_| rng.random::<f64>()).collect();
            let fast = unsafe { sqdist_avx2(&a, &b) };
            assert_eq!(fast.to_bits(), sqdist(&a, &b).to_bits(), "len {len}");
        }
    }

    #[test]
    fn json_round_trip() {
        let x = blobs(5, 2, 4);
        let s = Samples::new(&x, 15, 2).unwrap();
        let f = FcmParams::new(3)
            .seed(Some(1))
            .check()
            .unwrap()
            .fit(s)
            .unwrap();
        let back: FcmModel = serde_json::from_str(&serde_json::to_string(&f).unwrap()).unwrap();
        assert_eq!(f, back);
    }
}
