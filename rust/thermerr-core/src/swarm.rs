//! Box-bounded, derivative-free swarm minimisers: chicken swarm optimisation (CSO, Meng et al.
//! 2014) and the standard global-best particle swarm (PSO).
//!
//! Each method has two entry points:
//!
//! * `*_minimize_batch(f, bounds, params)`: `f` receives the whole population of one generation
//!   (`&[Vec<f64>]`, one row per individual) and returns one objective value per row. The caller
//!   decides how to evaluate them (serially, with rayon, or with one call back into Python per
//!   generation). An `Err` from `f` aborts the search and is returned as is.
//! * `*_minimize(f, bounds, params)`: `f` is a plain `Fn(&[f64]) -> f64 + Sync`, evaluated on the
//!   population in parallel with rayon.
//!
//! All randomness comes from one [`ChaCha8Rng`] seeded with `params.seed` and drawn in a fixed
//! order on the calling thread; objective values are only ever read after a whole generation has
//! been evaluated. The two entry points therefore give bit-identical results for the same seed,
//! whatever the number of threads.
//!
//! **Non-finite objective values** (NaN, ±∞) count as +∞: such a point never becomes a personal
//! or global best. If every evaluated point is non-finite the result has `f = +∞` and `x` is the
//! first individual of the initial population.
//!
//! Every new position is clipped to the bounds, coordinate by coordinate.
//!
//! # CSO variant implemented
//!
//! Meng, Liu, Gao & Zhang (2014), "A new bio-inspired algorithm: chicken swarm optimization", as in
//! the authors' reference MATLAB code, with the choices below:
//!
//! * **Greedy personal memory** (as in the reference code): each chicken i keeps its personal best
//!   position `p_i` and value `f_i`. Every move starts from the personal best positions (the
//!   current positions are only trial points), all moves of a generation read the memory of the
//!   previous generation, the whole population is then evaluated, and `p_i` is replaced only if
//!   the trial point is strictly better. All `f` in the rules below are personal-best values.
//! * **Hierarchy**: at generations 1, G+1, 2G+1, … the swarm is ranked by personal-best value
//!   (stable, ties by index); the best `RN = round(roosters·pop)` are roosters, the worst
//!   `CN = round((1 − roosters − hens)·pop)` are chicks, the remaining `HN = pop − RN − CN` are
//!   hens. Each hen is assigned a uniformly random rooster (its group), each chick a uniformly
//!   random mother among *all* hens (the reference code first draws a subset of mother hens with
//!   an extra `mPercent` parameter; here every hen may be a mother). Roles, groups and mothers
//!   stay fixed until the next regrouping.
//! * **Rooster** i: `x = p_i ⊙ (1 + σ² · N(0, 1))` per coordinate (the paper's `Randn(0, σ²)` has
//!   standard deviation σ², as in the reference code), with `σ² = 1` if `f_i ≤ f_k`, else
//!   `exp((f_k − f_i)/(|f_i| + ε))`, k a uniformly random other rooster (σ² = 1 when RN = 1).
//! * **Hen** i: `x = p_i + S1·u1 ⊙ (p_r1 − p_i) + S2·u2 ⊙ (p_r2 − p_i)`, u1, u2 uniform on [0, 1)
//!   per coordinate, `S1 = exp((f_i − f_r1)/(|f_i| + ε))` (Meng's sign), `S2 = exp(f_r2 − f_i)`,
//!   r1 the hen's rooster and r2 uniformly random among the roosters and hens other than i and r1
//!   (paper and methods.md; the reference code draws r2 only among chickens ranked above i). When
//!   no such r2 exists (one rooster, one hen) the S2 term is left out.
//! * **Chick** i: `x = p_i + FL·(p_m − p_i)`, m its mother, FL uniform on `params.fl` (one draw per
//!   chick and generation). The default (0.4, 1.0) is the range the paper recommends; the
//!   reference code uses [0.5, 0.9], and seed 004 of methods.md writes [0, 2].
//! * ε = `f64::MIN_POSITIVE` (MATLAB's `realmin`). The exponents of σ², S1 and S2 are capped at
//!   [`EXP_CAP`] so that the factors stay finite (see there); where f_i = +∞ the ratios
//!   `(a − b)/|f_i|` take their limit ±1 and ∞ − ∞ is taken as 0.
//!
//! # PSO
//!
//! Global-best PSO with inertia (Shi & Eberhart; defaults are Clerc's constriction values
//! w = 0.7298, c1 = c2 = 1.49618): `v ← w·v + c1·r1 ⊙ (p_i − x) + c2·r2 ⊙ (g − x)`, r1, r2 uniform
//! per coordinate, each velocity coordinate clamped to ±`vmax_frac`·(upper − lower), `x ← x + v`
//! clipped to the bounds (the velocity is kept). Initial velocities are uniform in ±vmax.
//! Synchronous: the global best g is updated once per generation, after the whole swarm has been
//! evaluated.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};

/// Upper cap on the exponents of CSO's σ², S1 and S2.
///
/// `S2 = exp(f_r2 − f_i)` is not normalised: a hen whose random r2 is much worse than itself
/// (f_r2 − f_i > 709) would overflow to +∞, and ∞·0 would then give NaN coordinates. (S1 and
/// σ² can overflow as well when objective values have mixed signs.) With the cap the factor is
/// at most e^50 ≈ 5·10²¹: a jump that large leaves the box in every coordinate where the
/// difference is not negligible and is clipped to the bound, which is what the uncapped rule
/// would give too.
pub const EXP_CAP: f64 = 50.0;

/// Box constraints `lower[j] ≤ x[j] ≤ upper[j]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Bounds {
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
}

impl Bounds {
    pub fn new(lower: Vec<f64>, upper: Vec<f64>) -> Self {
        Bounds { lower, upper }
    }

    /// From `(lower, upper)` pairs, one per coordinate.
    pub fn from_pairs(pairs: &[(f64, f64)]) -> Self {
        Bounds {
            lower: pairs.iter().map(|p| p.0).collect(),
            upper: pairs.iter().map(|p| p.1).collect(),
        }
    }

    /// The same interval `[lower, upper]` in each of `dim` coordinates.
    pub fn uniform(dim: usize, lower: f64, upper: f64) -> Self {
        Bounds {
            lower: vec![lower; dim],
            upper: vec![upper; dim],
        }
    }

    pub fn dim(&self) -> usize {
        self.lower.len()
    }

    fn check(&self) -> Result<()> {
        if self.lower.len() != self.upper.len() {
            return Err(Error::param(
                "bounds",
                format!(
                    "lower has {} entries, upper {}",
                    self.lower.len(),
                    self.upper.len()
                ),
            ));
        }
        if self.lower.is_empty() {
            return Err(Error::param("bounds", "no coordinates"));
        }
        for (j, (&l, &u)) in self.lower.iter().zip(&self.upper).enumerate() {
            if !(l.is_finite() && u.is_finite() && l < u && (u - l).is_finite()) {
                return Err(Error::param(
                    "bounds",
                    format!("coordinate {j}: need finite lower < upper with a finite range, got [{l}, {u}]"),
                ));
            }
        }
        Ok(())
    }

    /// A uniform random point of the box.
    fn sample(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        self.lower
            .iter()
            .zip(&self.upper)
            .map(|(&l, &u)| (l + (u - l) * rng.random::<f64>()).min(u))
            .collect()
    }
}

/// Parameters of [`cso_minimize`] / [`cso_minimize_batch`].
#[derive(Clone, Debug, PartialEq)]
pub struct CsoParams {
    /// Number of chickens (≥ 2).
    pub pop: usize,
    /// Number of generations (≥ 1).
    pub iters: usize,
    /// Regroup (re-rank and reassign roles) every `g` generations (≥ 1).
    pub g: usize,
    /// Fraction of roosters; `round(roosters·pop)` must be ≥ 1.
    pub roosters: f64,
    /// Fraction of hens; chicks are the remaining `1 − roosters − hens`. At least one hen is
    /// required.
    pub hens: f64,
    /// Range of the chicks' follow factor FL (uniform), `lo ≤ hi`.
    pub fl: (f64, f64),
    pub seed: u64,
}

impl Default for CsoParams {
    fn default() -> Self {
        CsoParams {
            pop: 20,
            iters: 100,
            g: 10,
            roosters: 0.2,
            hens: 0.6,
            fl: (0.4, 1.0),
            seed: 0,
        }
    }
}

impl CsoParams {
    /// Numbers of roosters, hens and chicks, after validating every parameter.
    fn roles(&self) -> Result<(usize, usize, usize)> {
        if self.pop < 2 {
            return Err(Error::param("pop", format!("need >= 2, got {}", self.pop)));
        }
        if self.iters < 1 {
            return Err(Error::param("iters", "need >= 1, got 0"));
        }
        if self.g < 1 {
            return Err(Error::param("g", "need >= 1, got 0"));
        }
        let (r, h) = (self.roosters, self.hens);
        if !(r.is_finite() && h.is_finite() && r >= 0.0 && h >= 0.0 && r + h <= 1.0 + 1e-12) {
            return Err(Error::param(
                "roosters",
                format!("need roosters >= 0, hens >= 0 and roosters + hens <= 1, got {r} and {h}"),
            ));
        }
        let (lo, hi) = self.fl;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(Error::param(
                "fl",
                format!("need finite lo <= hi, got ({lo}, {hi})"),
            ));
        }
        let n = self.pop as f64;
        let rn = (r * n).round() as usize;
        let cn = ((1.0 - r - h).max(0.0) * n).round() as usize;
        if rn < 1 {
            return Err(Error::param(
                "roosters",
                format!("round({r}·{}) = 0 roosters; need at least one", self.pop),
            ));
        }
        let hn = self.pop.saturating_sub(rn + cn);
        if hn < 1 {
            return Err(Error::param(
                "hens",
                format!(
                    "{} chickens minus {rn} roosters and {cn} chicks leaves no hen; need at least one",
                    self.pop
                ),
            ));
        }
        Ok((rn, hn, cn))
    }
}

/// Parameters of [`pso_minimize`] / [`pso_minimize_batch`].
#[derive(Clone, Debug, PartialEq)]
pub struct PsoParams {
    /// Number of particles (≥ 1).
    pub pop: usize,
    /// Number of generations (≥ 1).
    pub iters: usize,
    /// Inertia weight (finite, ≥ 0).
    pub w: f64,
    /// Cognitive (personal-best) coefficient (finite, ≥ 0).
    pub c1: f64,
    /// Social (global-best) coefficient (finite, ≥ 0).
    pub c2: f64,
    /// Velocity clamp as a fraction of each coordinate's range (finite, > 0).
    pub vmax_frac: f64,
    pub seed: u64,
}

impl Default for PsoParams {
    fn default() -> Self {
        PsoParams {
            pop: 20,
            iters: 100,
            w: 0.7298,
            c1: 1.49618,
            c2: 1.49618,
            vmax_frac: 0.2,
            seed: 0,
        }
    }
}

impl PsoParams {
    fn check(&self) -> Result<()> {
        if self.pop < 1 {
            return Err(Error::param("pop", "need >= 1, got 0"));
        }
        if self.iters < 1 {
            return Err(Error::param("iters", "need >= 1, got 0"));
        }
        for (name, v) in [("w", self.w), ("c1", self.c1), ("c2", self.c2)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::param(name, format!("need finite >= 0, got {v}")));
            }
        }
        if !(self.vmax_frac.is_finite() && self.vmax_frac > 0.0) {
            return Err(Error::param(
                "vmax_frac",
                format!("need finite > 0, got {}", self.vmax_frac),
            ));
        }
        Ok(())
    }
}

/// Outcome of a swarm search.
#[derive(Clone, Debug, PartialEq)]
pub struct SwarmResult {
    /// Best point found (inside the bounds).
    pub x: Vec<f64>,
    /// Objective value at `x` (+∞ if no evaluated point had a finite value).
    pub f: f64,
    /// Best value after each generation (`iters` entries, non-increasing).
    pub history: Vec<f64>,
    /// Number of objective evaluations, `pop·(iters + 1)`.
    pub n_evals: usize,
}

/// Evaluates one generation through the caller's batch function, checks the length and maps
/// non-finite values to +∞.
fn eval<F>(f: &mut F, pop: &[Vec<f64>], n_evals: &mut usize) -> Result<Vec<f64>>
where
    F: FnMut(&[Vec<f64>]) -> Result<Vec<f64>>,
{
    let mut v = f(pop)?;
    if v.len() != pop.len() {
        return Err(Error::Shape(format!(
            "swarm objective returned {} values for a population of {}",
            v.len(),
            pop.len()
        )));
    }
    for y in &mut v {
        if !y.is_finite() {
            *y = f64::INFINITY;
        }
    }
    *n_evals += pop.len();
    Ok(v)
}

/// Clips to `[lo, hi]`; a NaN coordinate (only possible from ∞·0 in degenerate arithmetic) falls
/// back to `fallback`, which is inside the box.
fn clip(v: f64, lo: f64, hi: f64, fallback: f64) -> f64 {
    if v.is_nan() {
        fallback
    } else {
        v.clamp(lo, hi)
    }
}

/// Index of the first minimum.
fn argmin(v: &[f64]) -> usize {
    let mut best = 0;
    for (i, &y) in v.iter().enumerate() {
        if y < v[best] {
            best = i;
        }
    }
    best
}

/// Standard normal draw (Box–Muller, the cosine branch only, so one draw uses exactly two
/// uniforms).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// `(a − b)/(|fi| + ε)` for values in (−∞, +∞], where `fi` is `a` or `b`: ∞ − ∞ is 0 and, when
/// `fi` = +∞ and the other is finite, the ratio takes its limit ±1.
fn rel_diff(a: f64, b: f64, fi: f64) -> f64 {
    if a == b {
        0.0
    } else if fi.is_infinite() {
        if a > b {
            1.0
        } else {
            -1.0
        }
    } else {
        (a - b) / (fi.abs() + f64::MIN_POSITIVE)
    }
}

/// `exp(min(e, EXP_CAP))`, with NaN (cannot occur from [`rel_diff`], guarded anyway) as e = 0.
fn capped_exp(e: f64) -> f64 {
    if e.is_nan() {
        1.0
    } else {
        e.min(EXP_CAP).exp()
    }
}

/// Chicken swarm optimisation, evaluating each generation with one call of `f` (see the module
/// documentation for the exact variant).
pub fn cso_minimize_batch<F>(mut f: F, bounds: &Bounds, params: &CsoParams) -> Result<SwarmResult>
where
    F: FnMut(&[Vec<f64>]) -> Result<Vec<f64>>,
{
    bounds.check()?;
    let (rn, hn, cn) = params.roles()?;
    let n = params.pop;
    let d = bounds.dim();
    let (lo, hi) = (&bounds.lower, &bounds.upper);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut n_evals = 0;

    let mut x: Vec<Vec<f64>> = (0..n).map(|_| bounds.sample(&mut rng)).collect();
    let mut pf = eval(&mut f, &x, &mut n_evals)?;
    let mut px = x.clone();
    let b = argmin(&pf);
    let mut best_x = px[b].clone();
    let mut best_f = pf[b];
    let mut history = Vec::with_capacity(params.iters);

    // order[rank] = chicken; mate[h] = rank of hen h's rooster; mother[c] = rank of chick c's hen
    let mut order: Vec<usize> = (0..n).collect();
    let mut mate = vec![0usize; hn];
    let mut mother = vec![0usize; cn];

    for t in 0..params.iters {
        if t % params.g == 0 {
            order = (0..n).collect();
            order.sort_by(|&a, &b| pf[a].total_cmp(&pf[b]));
            for m in mate.iter_mut() {
                *m = rng.random_range(0..rn);
            }
            for m in mother.iter_mut() {
                *m = rn + rng.random_range(0..hn);
            }
        }

        // roosters
        for r in 0..rn {
            let i = order[r];
            let k = if rn > 1 {
                let mut q = rng.random_range(0..rn - 1);
                if q >= r {
                    q += 1;
                }
                order[q]
            } else {
                i
            };
            let sigma2 = if pf[i] <= pf[k] {
                1.0
            } else {
                capped_exp(rel_diff(pf[k], pf[i], pf[i]))
            };
            for j in 0..d {
                let z = normal(&mut rng);
                x[i][j] = clip(px[i][j] * (1.0 + sigma2 * z), lo[j], hi[j], px[i][j]);
            }
        }

        // hens
        let n_r2 = rn + hn - 2; // candidates for r2: roosters and hens other than i and r1
        for h in 0..hn {
            let rank = rn + h;
            let i = order[rank];
            let r1 = order[mate[h]];
            let r2 = if n_r2 > 0 {
                // skip the two excluded ranks, mate[h] < rn <= rank
                let mut q = rng.random_range(0..n_r2);
                if q >= mate[h] {
                    q += 1;
                }
                if q >= rank {
                    q += 1;
                }
                Some(order[q])
            } else {
                None
            };
            let s1 = capped_exp(rel_diff(pf[i], pf[r1], pf[i]));
            for j in 0..d {
                let u = rng.random::<f64>();
                x[i][j] = px[i][j] + s1 * u * (px[r1][j] - px[i][j]);
            }
            if let Some(r2) = r2 {
                // exp(f_r2 − f_i), ∞ − ∞ taken as 0; exponent capped at EXP_CAP (overflow)
                let e = if pf[r2] == pf[i] { 0.0 } else { pf[r2] - pf[i] };
                let s2 = capped_exp(e);
                for j in 0..d {
                    let u = rng.random::<f64>();
                    x[i][j] += s2 * u * (px[r2][j] - px[i][j]);
                }
            }
            for j in 0..d {
                x[i][j] = clip(x[i][j], lo[j], hi[j], px[i][j]);
            }
        }

        // chicks
        let (fl_lo, fl_hi) = params.fl;
        for c in 0..cn {
            let i = order[rn + hn + c];
            let m = order[mother[c]];
            let fl = fl_lo + (fl_hi - fl_lo) * rng.random::<f64>();
            for j in 0..d {
                x[i][j] = clip(
                    px[i][j] + fl * (px[m][j] - px[i][j]),
                    lo[j],
                    hi[j],
                    px[i][j],
                );
            }
        }

        let fit = eval(&mut f, &x, &mut n_evals)?;
        for i in 0..n {
            if fit[i] < pf[i] {
                pf[i] = fit[i];
                px[i].copy_from_slice(&x[i]);
            }
            if pf[i] < best_f {
                best_f = pf[i];
                best_x.copy_from_slice(&px[i]);
            }
        }
        history.push(best_f);
    }
    Ok(SwarmResult {
        x: best_x,
        f: best_f,
        history,
        n_evals,
    })
}

/// Chicken swarm optimisation with `f` evaluated on each generation in parallel (rayon). Gives
/// the same result, bit for bit, as [`cso_minimize_batch`] with a serial evaluation of `f`.
pub fn cso_minimize<F>(f: F, bounds: &Bounds, params: &CsoParams) -> Result<SwarmResult>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    cso_minimize_batch(
        |pop: &[Vec<f64>]| Ok(pop.par_iter().map(|x| f(x)).collect()),
        bounds,
        params,
    )
}

/// Global-best particle swarm, evaluating each generation with one call of `f`.
pub fn pso_minimize_batch<F>(mut f: F, bounds: &Bounds, params: &PsoParams) -> Result<SwarmResult>
where
    F: FnMut(&[Vec<f64>]) -> Result<Vec<f64>>,
{
    bounds.check()?;
    params.check()?;
    let n = params.pop;
    let d = bounds.dim();
    let (lo, hi) = (&bounds.lower, &bounds.upper);
    let vmax: Vec<f64> = lo
        .iter()
        .zip(hi)
        .map(|(l, h)| params.vmax_frac * (h - l))
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut n_evals = 0;

    let mut x: Vec<Vec<f64>> = (0..n).map(|_| bounds.sample(&mut rng)).collect();
    let mut v: Vec<Vec<f64>> = (0..n)
        .map(|_| {
            vmax.iter()
                .map(|vm| vm * (2.0 * rng.random::<f64>() - 1.0))
                .collect()
        })
        .collect();
    let mut pf = eval(&mut f, &x, &mut n_evals)?;
    let mut px = x.clone();
    let b = argmin(&pf);
    let mut best_x = px[b].clone();
    let mut best_f = pf[b];
    let mut history = Vec::with_capacity(params.iters);

    for _ in 0..params.iters {
        for i in 0..n {
            for j in 0..d {
                let r1 = rng.random::<f64>();
                let r2 = rng.random::<f64>();
                let vj = params.w * v[i][j]
                    + params.c1 * r1 * (px[i][j] - x[i][j])
                    + params.c2 * r2 * (best_x[j] - x[i][j]);
                // all terms are finite (positions inside the box), so vj is not NaN
                v[i][j] = vj.clamp(-vmax[j], vmax[j]);
                x[i][j] = clip(x[i][j] + v[i][j], lo[j], hi[j], x[i][j]);
            }
        }
        let fit = eval(&mut f, &x, &mut n_evals)?;
        for i in 0..n {
            if fit[i] < pf[i] {
                pf[i] = fit[i];
                px[i].copy_from_slice(&x[i]);
            }
        }
        // synchronous: the global best moves only after the whole swarm has been evaluated
        for i in 0..n {
            if pf[i] < best_f {
                best_f = pf[i];
                best_x.copy_from_slice(&px[i]);
            }
        }
        history.push(best_f);
    }
    Ok(SwarmResult {
        x: best_x,
        f: best_f,
        history,
        n_evals,
    })
}

/// Global-best particle swarm with `f` evaluated on each generation in parallel (rayon). Gives
/// the same result, bit for bit, as [`pso_minimize_batch`] with a serial evaluation of `f`.
pub fn pso_minimize<F>(f: F, bounds: &Bounds, params: &PsoParams) -> Result<SwarmResult>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    pso_minimize_batch(
        |pop: &[Vec<f64>]| Ok(pop.par_iter().map(|x| f(x)).collect()),
        bounds,
        params,
    )
}
