//! Calibration: fit the network's parameters to a measured run.
//!
//! Free parameters (capacities, conductances, source powers in log space with bounds a factor
//! `bound_factor` around the nominal values; source exponents linear within ±`exponent_span`;
//! the sensed nodes' initial offsets; and the nonlinear parameters of an extension) are searched
//! by bounded Levenberg–Marquardt. The drift coefficients, which are linear given the simulated
//! temperatures, are solved exactly inside every evaluation (variable projection). The objective
//! stacks the sensed temperatures and the error axis, each divided by its noise level, plus weak
//! priors that keep unidentifiable parameters near the user's estimate.

use std::collections::BTreeMap;

use super::machine::{FittedStart, Machine, NodeSpec};
use super::sim::{
    drift_terms, finish, lag, median_step, simulate_nodes, simulate_nodes_on, Init, RunView,
    Simulation, Steps, Thinned,
};
use crate::error::{Error, Result};
use crate::linalg::{dot, gram, lstsq_columns, lstsq_with_prior, Cholesky};
use crate::metrics::rms_of;
use crate::optim::{least_squares, LmOptions};
use crate::portable;

/// One free parameter and where it lives in the machine.
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    Capacity(usize),
    AmbientG(usize),
    Link(usize),
    SourceW(usize),
    SourceExponent(usize),
    /// Initial offset of node i (K), not stored in the machine.
    InitOffset(usize),
    /// `lag_s` of drift entry d.
    Lag(usize),
    /// `sensor_drift_k_per_h` of node i.
    SensorDrift(usize),
    /// `exponent` of input term k of drift entry d.
    InputExponent(usize, usize),
}

/// How a parameter is searched: log space (positive quantities) or linear, and its bounds.
#[derive(Clone, Debug)]
pub struct FreeParam {
    pub param: Param,
    pub log: bool,
    pub lo: f64,
    pub hi: f64,
    pub start: f64,
    /// prior centre and width in the search space (None: no prior)
    pub prior: Option<(f64, f64)>,
}

/// The free parameter of a drift of node `i`'s sensor reading: linear, −3..3 K/h, from 0 (the
/// diagnosis's `sensor_drift` candidates and the drift identification calibrates beside its
/// network).
pub fn sensor_drift_param(i: usize) -> FreeParam {
    FreeParam {
        param: Param::SensorDrift(i),
        log: false,
        lo: -3.0,
        hi: 3.0,
        start: 0.0,
        prior: None,
    }
}

/// Options of [`calibrate`].
#[derive(Clone, Debug)]
pub struct CalibrationOptions {
    pub axis: String,
    /// Positive parameters are bounded to [nominal / f, nominal · f].
    pub bound_factor: f64,
    /// Source exponents are bounded to nominal ± this.
    pub exponent_span: f64,
    pub fit_initial: bool,
    /// Width of the log-space prior on thermal parameters (ln 2: a factor of two is one σ).
    pub prior_log_sigma: f64,
    /// Noise levels; `None` estimates them from the data (second differences, MAD).
    pub sigma_t: Option<f64>,
    pub sigma_e: Option<f64>,
    /// Only rows `< fit_rows` are fitted (the rest is held out); `None`: all rows.
    pub fit_rows: Option<usize>,
    pub max_iter: usize,
    /// Also search the machine's thermal parameters (false: only extension parameters and the
    /// linear drift terms, the thermal network kept as given).
    pub thermal: bool,
    /// Fit the error axis with the temperatures (false: the search sees the temperatures alone,
    /// and the axis's drift map is solved once on the network it ends with).
    pub fit_error: bool,
    /// Also stop when a step lowers the fit's BIC by less than this (0: only the fixed
    /// tolerances). BIC = n·ln(SSR/n) + …, so a step's ΔBIC ≈ n·ΔSSR/SSR: on a run whose model
    /// misfits by far more than the noise (SSR/n ≫ 1), the fixed absolute tolerance
    /// ([`CALIBRATION_ATOL`]) asks for cost decreases that move the BIC by a millionth.
    pub min_bic_step: f64,
    /// A ridge penalty λ on the drift map's node coefficients (`um_per_k`), relative to the
    /// mean square of their terms over the fitted rows, toward the file's values ([`fit_drift`];
    /// `None`: only the weak prior of [`prior_of`], least squares in effect). The diagnosis
    /// sets it from [`drift_penalty`].
    pub drift_ridge: Option<f64>,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            axis: String::new(),
            bound_factor: 3.0,
            exponent_span: 0.6,
            fit_initial: true,
            prior_log_sigma: std::f64::consts::LN_2,
            sigma_t: None,
            sigma_e: None,
            fit_rows: None,
            max_iter: 100,
            thermal: true,
            fit_error: true,
            min_bic_step: 0.0,
            drift_ridge: None,
        }
    }
}

impl CalibrationOptions {
    /// Refuses options that would make the search meaningless (a bound factor of 1 or less
    /// freezes every parameter at its nominal value).
    pub fn check(&self) -> Result<()> {
        if !(self.bound_factor.is_finite() && self.bound_factor > 1.0) {
            return Err(Error::param(
                "bound_factor",
                format!(
                    "must be > 1 (parameters range over nominal / f .. nominal · f), got {}",
                    self.bound_factor
                ),
            ));
        }
        if !(self.exponent_span.is_finite() && self.exponent_span >= 0.0) {
            return Err(Error::param(
                "exponent_span",
                format!("must be >= 0, got {}", self.exponent_span),
            ));
        }
        if !(self.prior_log_sigma.is_finite() && self.prior_log_sigma > 0.0) {
            return Err(Error::param(
                "prior_log_sigma",
                format!("must be > 0, got {}", self.prior_log_sigma),
            ));
        }
        if !(self.min_bic_step.is_finite() && self.min_bic_step >= 0.0) {
            return Err(Error::param(
                "min_bic_step",
                format!("must be >= 0, got {}", self.min_bic_step),
            ));
        }
        if self.max_iter == 0 {
            return Err(Error::param("max_iter", "must be at least 1"));
        }
        if let Some(l) = self.drift_ridge {
            if !(l.is_finite() && l >= 0.0) {
                return Err(Error::param(
                    "drift_ridge",
                    format!("must be >= 0, got {l}"),
                ));
            }
        }
        for (name, v) in [("sigma_t", self.sigma_t), ("sigma_e", self.sigma_e)] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return Err(Error::param(name, format!("must be > 0, got {v}")));
                }
            }
        }
        Ok(())
    }
}

/// A calibrated machine and how well it fits.
#[derive(Clone, Debug)]
pub struct Calibration {
    pub machine: Machine,
    pub init: Vec<f64>,
    pub sigma_t: f64,
    pub sigma_e: f64,
    /// Σ of squared normalised data residuals over the fitted rows (priors excluded).
    pub ssr: f64,
    /// Number of data residuals and of fitted parameters (nonlinear + linear drift terms).
    pub n_data: usize,
    pub n_params: usize,
    pub n_iter: usize,
    pub converged: bool,
}

impl Calibration {
    /// Bayesian information criterion of the fit (Gaussian residuals, noise known up to scale).
    pub fn bic(&self) -> f64 {
        let n = self.n_data.max(1) as f64;
        n * portable::ln((self.ssr / n).max(1e-300)) + self.n_params as f64 * portable::ln(n)
    }
}

/// The least σ_e of a probe as a share of its span over the fitted rows ([`Reading::sigma`]).
/// A floor keeps a smoothed probe (second differences all but zero) from outweighing every
/// temperature; as a share of the span it is the same whatever the probe's unit. An absolute
/// 0.02 µm stood here before: a run logged in mm then weighed its probe a thousand times less
/// than the same run in µm and gave another network (real 46-h run, E_ch3 held out 12.5 µm in
/// µm, 5 µm in mm). A share of 10⁻³ bound on the real run's two probes that move 86 µm (0.087
/// against their noise of 0.02-0.05 µm) and changed two diagnoses; 10⁻⁴ binds on none of its
/// probes nor on the synthetic runs' (noise 0.15 µm).
pub const SIGMA_E_FLOOR_SHARE: f64 = 1e-4;

/// Robust noise level of a series: MAD of second differences / (0.6745 · √6).
pub fn noise_level(y: &[f64]) -> f64 {
    if y.len() < 3 {
        return 0.0;
    }
    let mut d: Vec<f64> = y
        .windows(3)
        .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs())
        .collect();
    d.sort_by(|a, b| a.total_cmp(b));
    d[d.len() / 2] / (0.6745 * 6f64.sqrt())
}

/// The default free parameters of a machine (all thermal parameters, initial offsets of the
/// sensed nodes).
pub fn default_params(m: &Machine, opts: &CalibrationOptions) -> Vec<FreeParam> {
    let f = opts.bound_factor;
    let pos = |param: Param, v: f64| FreeParam {
        param,
        log: true,
        lo: portable::ln(v / f),
        hi: portable::ln(v * f),
        start: portable::ln(v),
        prior: Some((portable::ln(v), opts.prior_log_sigma)),
    };
    let mut out = Vec::new();
    if opts.thermal {
        for (i, n) in m.nodes.iter().enumerate() {
            if n.boundary.is_some() {
                continue;
            }
            out.push(pos(Param::Capacity(i), n.capacity_j_per_k));
            if n.ambient_w_per_k > 0.0 {
                out.push(pos(Param::AmbientG(i), n.ambient_w_per_k));
            }
        }
        for (k, l) in m.links.iter().enumerate() {
            if l.w_per_k > 0.0 {
                out.push(pos(Param::Link(k), l.w_per_k));
            }
        }
        for (k, s) in m.sources.iter().enumerate() {
            if s.w > 0.0 {
                out.push(pos(Param::SourceW(k), s.w));
                out.push(FreeParam {
                    param: Param::SourceExponent(k),
                    log: false,
                    lo: s.exponent - opts.exponent_span,
                    hi: s.exponent + opts.exponent_span,
                    start: s.exponent,
                    prior: Some((s.exponent, opts.exponent_span)),
                });
            }
        }
    }
    if opts.fit_initial {
        for (i, n) in m.nodes.iter().enumerate() {
            if n.sensor.is_some() && n.boundary.is_none() {
                out.push(FreeParam {
                    param: Param::InitOffset(i),
                    log: false,
                    lo: -1.0,
                    hi: 1.0,
                    start: 0.0,
                    prior: None,
                });
            }
        }
    }
    out
}

/// Writes parameter values (in search space) into a copy of the machine; returns it and the
/// initial offsets.
pub fn apply(m: &Machine, free: &[FreeParam], x: &[f64]) -> (Machine, Vec<f64>) {
    let mut out = m.refit_copy();
    let mut init = vec![0.0; m.nodes.len()];
    for (fp, &v) in free.iter().zip(x) {
        let v = if fp.log { portable::exp(v) } else { v };
        match fp.param {
            Param::Capacity(i) => out.nodes[i].capacity_j_per_k = v,
            Param::AmbientG(i) => out.nodes[i].ambient_w_per_k = v,
            Param::Link(k) => out.links[k].w_per_k = v,
            Param::SourceW(k) => out.sources[k].w = v,
            Param::SourceExponent(k) => out.sources[k].exponent = v,
            Param::InitOffset(i) => init[i] = v,
            Param::Lag(d) => out.drift[d].lag_s = Some(v),
            Param::SensorDrift(i) => out.nodes[i].sensor_drift_k_per_h = v,
            Param::InputExponent(d, k) => out.drift[d].inputs[k].exponent = v,
        }
    }
    (out, init)
}

/// The linear drift terms of `axis` fitted to `error` over its fitted rows among the first
/// `rows`, with weak priors, and with `ridge` a penalty on the node terms ([`ridge_prior`]).
/// Returns the coefficients (lagged terms first, then instant ones) and the fitted series
/// (every row).
#[allow(clippy::too_many_arguments)]
fn fit_drift(
    m: &Machine,
    d: usize,
    run: &RunView<'_>,
    temps: &[f64],
    error: &Reading<'_>,
    rows: usize,
    sigma_e: f64,
    ridge: Option<f64>,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let measured: &[f64] = &error.values;
    let (basis, mut prior) = drift_basis(m, d, run, temps)?;
    if basis.is_empty() {
        return Ok((Vec::new(), vec![0.0; measured.len()]));
    }
    // the node terms come first (`drift_terms`)
    let nodes = m.drift[d].um_per_k.len();
    let coef = if error.failing.is_empty() {
        let cols: Vec<&[f64]> = basis.iter().map(Vec::as_slice).collect();
        ridge_prior(&mut prior, &cols[..nodes], rows, sigma_e, ridge);
        lstsq_with_prior(&cols, measured, rows, sigma_e, &prior)?
    } else {
        // a failing probe: the fitted rows only
        let kept: Vec<Vec<f64>> = basis.iter().map(|b| error.kept(b, 0..rows)).collect();
        let cols: Vec<&[f64]> = kept.iter().map(Vec::as_slice).collect();
        let y = error.kept(measured, 0..rows);
        ridge_prior(&mut prior, &cols[..nodes], y.len(), sigma_e, ridge);
        lstsq_with_prior(&cols, &y, y.len(), sigma_e, &prior)?
    };
    let fitted = combine(&coef, &basis, measured.len());
    Ok((coef, fitted))
}

/// Narrows the priors of the node terms `nodes` (the first of `prior`) to a ridge penalty
/// λ·s·‖c − c₀‖², s the mean of their squared norms over `rows`: a prior width of σ/√(λ·s) in
/// [`lstsq_with_prior`]'s units, never wider than the prior's own.
fn ridge_prior(
    prior: &mut [(f64, f64)],
    nodes: &[&[f64]],
    rows: usize,
    sigma: f64,
    ridge: Option<f64>,
) {
    let Some(lambda) = ridge else { return };
    if nodes.is_empty() {
        return;
    }
    let s = nodes
        .iter()
        .map(|c| dot(&c[..rows], &c[..rows]))
        .sum::<f64>()
        / nodes.len() as f64;
    let width = sigma / (lambda * s).sqrt();
    if width.is_finite() && width > 0.0 {
        for p in prior.iter_mut().take(nodes.len()) {
            p.1 = p.1.min(width);
        }
    }
}

/// Σ coefₖ·basisₖ over `len` rows.
fn combine(coef: &[f64], basis: &[Vec<f64>], len: usize) -> Vec<f64> {
    let mut fitted = vec![0.0; len];
    for (c, s) in coef.iter().zip(basis) {
        for (f, v) in fitted.iter_mut().zip(s) {
            *f += c * v;
        }
    }
    fitted
}

/// The linear drift terms' series and their priors (centre, width).
type DriftBasis = (Vec<Vec<f64>>, Vec<(f64, f64)>);

/// The series of the linear drift terms of axis `d` on node temperatures `temps` (lagged terms
/// first, through the axis' lag, then instant ones) and each one's weak prior ([`prior_of`]).
fn drift_basis(m: &Machine, d: usize, run: &RunView<'_>, temps: &[f64]) -> Result<DriftBasis> {
    let spec = &m.drift[d];
    let terms = drift_terms(m, spec, run, temps)?;
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut prior: Vec<(f64, f64)> = Vec::new();
    for ((c, s), label) in terms.lagged.into_iter().zip(&terms.labels_lagged) {
        basis.push(match spec.lag_s {
            Some(tau) => lag(run.time, &s, tau),
            None => s,
        });
        prior.push(prior_of(label, c));
    }
    for ((c, s), label) in terms.instant.into_iter().zip(&terms.labels_instant) {
        basis.push(s);
        prior.push(prior_of(label, c));
    }
    Ok((basis, prior))
}

/// Ridge penalties a drift map for a new run chooses from ([`ridge_drift`]): λ relative to the
/// mean diagonal of the terms' Gram matrix, 10⁻⁶ (least squares, all but) to 1 by half decades.
pub const RIDGE_GRID: [f64; 13] = [
    1e-6, 3.16e-6, 1e-5, 3.16e-5, 1e-4, 3.16e-4, 1e-3, 3.16e-3, 1e-2, 3.16e-2, 1e-1, 3.16e-1, 1.0,
];
/// Blocked folds (contiguous, in time order) that choose the penalty.
pub const RIDGE_FOLDS: usize = 5;

/// Minimises ‖Σⱼ cⱼ·colsⱼ − y‖² + λ·s·‖c‖², s the mean of the columns' squared norms.
fn ridge(cols: &[&[f64]], y: &[f64], lambda: f64) -> Result<Vec<f64>> {
    let s = cols.iter().map(|c| dot(c, c)).sum::<f64>() / cols.len() as f64;
    let width = 1.0 / (lambda * s.max(f64::MIN_POSITIVE)).sqrt();
    lstsq_with_prior(cols, y, y.len(), 1.0, &vec![(0.0, width); cols.len()])
}

/// The drift map of axis `d` that a run simulated from its first readings calls for: its linear
/// terms on node temperatures `temps`, fitted to `error` over its fitted rows among the first
/// `rows` by ridge regression, the penalty the one of [`RIDGE_GRID`] that predicts best across
/// [`RIDGE_FOLDS`] blocked folds of those rows (each block predicted from the others). Node rises
/// that move together let least squares trade large coefficients of opposite signs; those carry
/// any difference between the simulated and the real temperatures (a start, another run's duty)
/// into the axis many times over. Returns the coefficients (in [`fit_drift`]'s order), λ and
/// the folds' share ([`ridge_by_folds`]; a map with no term: 1, it predicts zero drift).
pub fn ridge_drift(
    m: &Machine,
    d: usize,
    run: &RunView<'_>,
    temps: &[f64],
    error: &Reading<'_>,
    rows: usize,
) -> Result<(Vec<f64>, f64, Option<f64>)> {
    let (x, y) = kept_terms(m, d, run, temps, error, rows)?;
    if x.is_empty() {
        return Ok((Vec::new(), 0.0, Some(1.0)));
    }
    ridge_by_folds(&x, &y)
}

/// The drift terms of axis `d` ([`drift_basis`]) and the error, over the error's fitted rows
/// among the first `rows`.
fn kept_terms(
    m: &Machine,
    d: usize,
    run: &RunView<'_>,
    temps: &[f64],
    error: &Reading<'_>,
    rows: usize,
) -> Result<(Vec<Vec<f64>>, Vec<f64>)> {
    let (basis, _) = drift_basis(m, d, run, temps)?;
    let x = basis.iter().map(|b| error.kept(b, 0..rows)).collect();
    Ok((x, error.kept(&error.values, 0..rows)))
}

/// A drift map's node terms cancel when one term alone swings more than this many times the
/// axis's whole drift (RMS over the training rows).
pub const CANCELLING_TERMS: f64 = 3.0;

/// The largest node term of axis `d`'s drift map on node temperatures `temps` (row-major, one
/// row per sample) over the first `rows`, when it swings more than [`CANCELLING_TERMS`] times
/// the sum of all of them: (node, coefficient, the term's RMS, the drift's RMS). Node rises that
/// move together let least squares trade large coefficients of opposite signs; a fraction of a
/// kelvin in one node (its start, another run's duty) then moves the axis by many µm.
pub fn cancelling_term(
    m: &Machine,
    d: usize,
    temps: &[f64],
    rows: usize,
) -> Option<(String, f64, f64, f64)> {
    let nn = m.nodes.len();
    let rows = rows.min(temps.len() / nn.max(1));
    if rows == 0 {
        return None;
    }
    let terms: Vec<(&String, f64, usize)> = m.drift[d]
        .um_per_k
        .iter()
        .filter_map(|(name, &c)| Some((name, c, m.node_index(name)?)))
        .collect();
    let rise = |k: usize, r: usize| temps[r * nn + k] - temps[k];
    let total = rms_of((0..rows).map(|r| terms.iter().map(|&(_, c, k)| c * rise(k, r)).sum()));
    let (name, c, big) = terms
        .iter()
        .map(|&(name, c, k)| (name, c, rms_of((0..rows).map(|r| c * rise(k, r)))))
        .max_by(|a, b| a.2.total_cmp(&b.2))?;
    (big > CANCELLING_TERMS * total.max(1e-12)).then(|| (name.clone(), c, big, total))
}

/// The ridge penalty of [`CalibrationOptions::drift_ridge`] for axis `d` of `m`: the one of
/// [`RIDGE_GRID`] with which the node terms (on temperatures `temps`, shrunk toward the file's
/// coefficients) fitted to the first `1 − held_share` of the fitted rows among the first `rows`
/// best predict the rest, forward in time as a held-out tail or a new run is predicted. Other
/// drift terms are left out of the choice. Blocked folds that predict a middle block from both
/// sides ([`ridge_by_folds`]) keep least squares here: a map whose node terms cancel (±48 µm/K
/// on a 23-h real run, where the file had ±3) fits every block of the run it was fitted to,
/// and goes astray only beyond it (held out 40 µm, where the file gave 2.5).
pub fn drift_penalty(
    m: &Machine,
    d: usize,
    run: &RunView<'_>,
    temps: &[f64],
    error: &Reading<'_>,
    rows: usize,
    held_share: f64,
) -> Result<f64> {
    let (mut x, mut y) = kept_terms(m, d, run, temps, error, rows)?;
    let nominal: Vec<f64> = m.drift[d].um_per_k.values().copied().collect();
    x.truncate(nominal.len()); // the node terms come first
    for (c, col) in nominal.iter().zip(&x) {
        for (v, b) in y.iter_mut().zip(col) {
            *v -= c * b;
        }
    }
    forward_penalty(&x, &y, held_share)
}

/// The one of [`RIDGE_GRID`] with which a ridge regression of `y` on the columns `x`, fitted to
/// the first `1 − held_share` of the rows, best predicts the rest (the smallest on a tie); too
/// few rows on either side: the smallest.
pub fn forward_penalty(x: &[Vec<f64>], y: &[f64], held_share: f64) -> Result<f64> {
    let n = y.len();
    let cut = ((n as f64) * (1.0 - held_share)).round() as usize;
    if x.is_empty() || cut < 2 * x.len() + 10 || n < cut + 10 {
        return Ok(RIDGE_GRID[0]);
    }
    let fit: Vec<&[f64]> = x.iter().map(|c| &c[..cut]).collect();
    let mut best = (f64::INFINITY, RIDGE_GRID[0]);
    for &lambda in &RIDGE_GRID {
        crate::interrupt::check()?;
        let c = ridge(&fit, &y[..cut], lambda)?;
        let sse: f64 = (cut..n)
            .map(|k| (y[k] - c.iter().zip(x).map(|(c, b)| c * b[k]).sum::<f64>()).powi(2))
            .sum();
        if sse < best.0 {
            best = (sse, lambda);
        }
    }
    Ok(best.1)
}

/// Ridge regression of `y` on the columns `x`, the penalty the one of [`RIDGE_GRID`] whose fits
/// predict best across [`RIDGE_FOLDS`] contiguous blocks of the rows (each block from the
/// others; the smallest on a tie); too few rows for the folds: the smallest. Returns the
/// coefficients on every row, the penalty and how well the folds predicted: their squared error
/// over `y`'s sum of squares (0: exact; 1: no better than zero), `None` without the folds.
pub fn ridge_by_folds(x: &[Vec<f64>], y: &[f64]) -> Result<(Vec<f64>, f64, Option<f64>)> {
    let cols: Vec<&[f64]> = x.iter().map(Vec::as_slice).collect();
    let best = folds_best(&cols, y)?;
    let lambda = best.map_or(RIDGE_GRID[0], |b| b.1);
    let ss = y.iter().map(|v| v * v).sum::<f64>();
    let share = best.map(|(sse, _)| sse / ss.max(f64::MIN_POSITIVE));
    Ok((ridge(&cols, y, lambda)?, lambda, share))
}

/// The ridge penalty of [`RIDGE_GRID`] that predicts `y` best across [`RIDGE_FOLDS`] contiguous
/// blocks (the smallest on a tie) and its blocked-fold squared error; `None` with too few rows
/// for the folds.
fn folds_best(cols: &[&[f64]], y: &[f64]) -> Result<Option<(f64, f64)>> {
    let (n, p) = (y.len(), cols.len());
    let mut best = (f64::INFINITY, RIDGE_GRID[0]);
    if n < RIDGE_FOLDS * (2 * p + 10) {
        return Ok(None);
    }
    let edge = |k: usize| k * n / RIDGE_FOLDS;
    // each block's Gram matrix and Xᵀy, once: a fold's are the sums over the other blocks
    let blocks = (0..RIDGE_FOLDS)
        .map(|f| {
            let r = edge(f)..edge(f + 1);
            let bc: Vec<&[f64]> = cols.iter().map(|c| &c[r.clone()]).collect();
            let xty: Vec<f64> = bc.iter().map(|c| dot(c, &y[r.clone()])).collect();
            Ok((gram(&bc, r.len())?, xty))
        })
        .collect::<Result<Vec<_>>>()?;
    for &lambda in &RIDGE_GRID {
        crate::interrupt::check()?;
        let mut sse = 0.0;
        for f in 0..RIDGE_FOLDS {
            let (mut g, mut rhs) = (vec![0.0; p * p], vec![0.0; p]);
            for (_, (gb, bb)) in blocks.iter().enumerate().filter(|(b, _)| *b != f) {
                g.iter_mut().zip(gb).for_each(|(a, v)| *a += v);
                rhs.iter_mut().zip(bb).for_each(|(a, v)| *a += v);
            }
            let s = (0..p).map(|j| g[j * p + j]).sum::<f64>() / p as f64;
            for j in 0..p {
                g[j * p + j] += lambda * s;
            }
            let Some(chol) = Cholesky::new(&g, p) else {
                sse = f64::INFINITY; // not positive definite at this penalty: not chosen
                break;
            };
            let c = chol.solve(&rhs);
            sse += (edge(f)..edge(f + 1))
                .map(|k| (y[k] - c.iter().zip(cols).map(|(c, b)| c * b[k]).sum::<f64>()).powi(2))
                .sum::<f64>();
        }
        if sse < best.0 {
            best = (sse, lambda);
        }
    }
    Ok(Some(best))
}

/// Weak prior (centre, width) of a linear drift coefficient: nominal node coefficients are kept
/// within about their own size; extension terms start at zero with a wide prior.
fn prior_of(label: &str, nominal: f64) -> (f64, f64) {
    if label.starts_with("um_per_k.") {
        (nominal, nominal.abs() + 1.0)
    } else if label.starts_with("quadratic") {
        (0.0, 1.0)
    } else if label.starts_with("inputs.") {
        (0.0, 50.0)
    } else {
        (0.0, 10.0)
    }
}

/// Stores fitted drift coefficients back into the machine.
pub fn store_drift(m: &mut Machine, d: usize, coef: &[f64]) {
    let spec = &mut m.drift[d];
    let mut it = coef.iter().copied();
    for v in spec.um_per_k.values_mut() {
        *v = it.next().unwrap_or(*v);
    }
    for v in spec.quadratic_um_per_k2.values_mut() {
        *v = it.next().unwrap_or(*v);
    }
    if let Some(v) = spec.ambient_um_per_k.as_mut() {
        *v = it.next().unwrap_or(*v);
    }
    for c in spec.columns.iter_mut() {
        c.um_per_k = it.next().unwrap_or(c.um_per_k);
    }
    for t in spec.inputs.iter_mut() {
        t.um = it.next().unwrap_or(t.um);
    }
}

/// A measured column of a run, and the rows where the run shows it failing
/// ([`crate::guard::failing_rows`]: from a jump away to a jump back, or to the end), which are neither
/// fitted nor scored. No failing rows is the usual case, and then nothing changes.
pub struct Reading<'a> {
    /// The column; a probe (`E_*`) whose first reading is further from zero than it moves over
    /// the whole run is taken from that reading ([`crate::guard::probe_offset`]).
    pub values: std::borrow::Cow<'a, [f64]>,
    /// Half-open row ranges, in order.
    pub failing: Vec<std::ops::Range<usize>>,
}

impl<'a> Reading<'a> {
    /// Column `name` of `run`, with its failing rows ([`RunView::failing`]).
    pub fn of(run: &RunView<'a>, name: &str) -> Result<Self> {
        let col = run.col(name)?;
        let failing = run.failing(name)?.to_vec();
        let offset = match name.starts_with("E_") {
            true => crate::guard::probe_offset(col, &failing),
            false => None,
        };
        Ok(Reading {
            values: match offset {
                Some(v) => std::borrow::Cow::Owned(col.iter().map(|x| x - v).collect()),
                None => std::borrow::Cow::Borrowed(col),
            },
            failing,
        })
    }

    /// Whether row `k` is fitted and scored.
    pub fn reads(&self, k: usize) -> bool {
        !self.failing.iter().any(|r| r.contains(&k))
    }

    /// How many of the first `rows` rows are fitted.
    pub fn fitted_rows(&self, rows: usize) -> usize {
        rows - self
            .failing
            .iter()
            .map(|r| r.end.min(rows).saturating_sub(r.start))
            .sum::<usize>()
    }

    /// RMS of `predicted − values` over the rows among `rows` that are scored (a failing
    /// probe's rows left out); NaN when none is.
    pub fn rmse(&self, predicted: &[f64], rows: std::ops::Range<usize>) -> f64 {
        crate::metrics::rms_of(
            rows.filter(|&k| self.reads(k))
                .map(|k| predicted[k] - self.values[k]),
        )
    }

    /// The values of `v` (a series of the run's rows) on the fitted rows among `rows`.
    pub fn kept(&self, v: &[f64], rows: std::ops::Range<usize>) -> Vec<f64> {
        rows.filter(|&k| self.reads(k)).map(|k| v[k]).collect()
    }

    /// The noise level ([`noise_level`]) of the fitted rows among the first `rows`.
    pub fn noise(&self, rows: usize) -> f64 {
        if self.failing.is_empty() {
            return noise_level(&self.values[..rows]);
        }
        noise_level(&self.kept(&self.values, 0..rows))
    }

    /// The probe's σ_e on the first `rows`: its noise level, at least its resolution's
    /// rounding noise (the smallest step between two readings / √12: a probe logged to 0.1 µm
    /// on a slow drift has second differences of zero, and its readings are ±0.05 µm all the
    /// same) and [`SIGMA_E_FLOOR_SHARE`] of its span over the fitted rows among them. Each
    /// scales with the probe's unit, so the same run in mm or nm weighs its probe alike and
    /// gives the same network, its drift in that unit. A probe that reads one value throughout:
    /// 1 (in its unit), any value weighing it alike.
    pub fn sigma(&self, rows: usize) -> f64 {
        let kept = self.kept(&self.values, 0..rows);
        let (lo, hi) = crate::metrics::min_max(kept.iter().copied());
        let step = kept
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .filter(|d| *d > 0.0)
            .fold(f64::INFINITY, f64::min);
        let rounding = if step.is_finite() {
            step / 12f64.sqrt()
        } else {
            0.0
        };
        let s = noise_level(&kept)
            .max(rounding)
            .max(SIGMA_E_FLOOR_SHARE * (hi - lo));
        if s > 0.0 && s.is_finite() {
            s
        } else {
            1.0
        }
    }
}

/// A sensed node's reading in a run.
pub struct Sensed<'a> {
    /// The node's index in the machine.
    pub node: usize,
    pub reading: Reading<'a>,
}

/// The sensed simulated nodes of `m` (a sensor and no boundary) and their readings in `run`,
/// in the machine's order.
pub fn sensed<'a>(m: &Machine, run: &RunView<'a>) -> Result<Vec<Sensed<'a>>> {
    let mut out = Vec::new();
    for (i, n) in m.nodes.iter().enumerate() {
        if let (Some(c), None) = (&n.sensor, &n.boundary) {
            out.push(Sensed {
                node: i,
                reading: Reading::of(run, c)?,
            });
        }
    }
    Ok(out)
}

/// The measured series a calibration compares with.
pub struct Targets<'a> {
    pub axis_index: usize,
    /// The axis's measured error.
    pub error: Reading<'a>,
    /// per sensed simulated node
    pub sensors: Vec<Sensed<'a>>,
}

pub fn targets<'a>(m: &Machine, run: &RunView<'a>, axis: &str) -> Result<Targets<'a>> {
    let axis_index = m.drift.iter().position(|d| d.axis == axis).ok_or_else(|| {
        Error::param(
            "axis",
            format!("the machine has no drift entry for `{axis}`"),
        )
    })?;
    let mut tg = Targets {
        axis_index,
        error: Reading::of(run, axis)?,
        sensors: sensed(m, run)?,
    };
    // where a temperature that drives the network fails, the model runs on its last right
    // reading (sim::driving) but what it predicts there is not fitted or scored
    let unknown = driver_failing(m, run)?;
    if !unknown.is_empty() {
        tg.error.failing = union(&tg.error.failing, &unknown);
        for sn in tg.sensors.iter_mut() {
            sn.reading.failing = union(&sn.reading.failing, &unknown);
        }
    }
    Ok(tg)
}

/// The failing rows ([`crate::guard::failing_rows`]) of the columns that drive the network:
/// the room and the boundary nodes.
pub fn driver_failing(m: &Machine, run: &RunView<'_>) -> Result<Vec<std::ops::Range<usize>>> {
    let mut cols: Vec<&str> = m
        .nodes
        .iter()
        .filter_map(|n| n.boundary.as_deref())
        .collect();
    if let super::machine::Ambient::Column(c) = &m.ambient {
        cols.push(c);
    }
    let mut out = Vec::new();
    for c in cols {
        out = union(&out, &run.failing(c)?);
    }
    Ok(out)
}

/// The union of two sets of row ranges, as ordered, disjoint ranges.
fn union(
    a: &[std::ops::Range<usize>],
    b: &[std::ops::Range<usize>],
) -> Vec<std::ops::Range<usize>> {
    let mut all: Vec<std::ops::Range<usize>> = a.iter().chain(b).cloned().collect();
    all.sort_by_key(|r| r.start);
    let mut out: Vec<std::ops::Range<usize>> = Vec::new();
    for r in all {
        match out.last_mut() {
            Some(last) if r.start <= last.end => last.end = last.end.max(r.end),
            _ => out.push(r),
        }
    }
    out
}

/// Simulates `m` and returns (simulation with fitted drift, normalised data residuals over
/// `rows`). `refit_drift`: `None` keeps `m`'s drift map; `Some(ridge)` re-solves its
/// coefficients on `rows` ([`fit_drift`], with `ridge` its penalty on the node terms).
#[allow(clippy::too_many_arguments)]
pub fn evaluate(
    m: &Machine,
    init: &[f64],
    run: &RunView<'_>,
    tg: &Targets<'_>,
    rows: usize,
    sigma_t: f64,
    sigma_e: f64,
    refit_drift: Option<Option<f64>>,
) -> Result<(Machine, Simulation, Vec<f64>)> {
    let temps = simulate_nodes(m, run, &Init::Offsets(init.to_vec()))?;
    let mut fitted = m.refit_copy();
    if let Some(ridge) = refit_drift {
        let (coef, _) = fit_drift(
            m,
            tg.axis_index,
            run,
            &temps,
            &tg.error,
            rows,
            sigma_e,
            ridge,
        )?;
        store_drift(&mut fitted, tg.axis_index, &coef);
    }
    let sim = finish(&fitted, run, temps)?;
    let e = &sim.drift[tg.axis_index].1;
    let r = normalised(&fitted, run, tg, &sim.temps, e, rows, sigma_t, sigma_e);
    Ok((fitted, sim, r))
}

/// The normalised data residuals of `m` over `rows` (sensors, then, with `fit_error`, the
/// axis' error), the drift coefficients re-solved on `rows`: the third part of what [`evaluate`] returns, without
/// building the simulation's readings and every axis' drift (the search's inner loop).
#[allow(clippy::too_many_arguments)]
fn residuals(
    m: &Machine,
    init: &[f64],
    run: &RunView<'_>,
    tg: &Targets<'_>,
    rows: usize,
    sigma_t: f64,
    sigma_e: f64,
    fit_error: bool,
    steps: &Steps,
    ridge: Option<f64>,
) -> Result<Vec<f64>> {
    let temps = simulate_nodes_on(m, run, &Init::Offsets(init.to_vec()), steps)?;
    let e = match fit_error {
        true => {
            fit_drift(
                m,
                tg.axis_index,
                run,
                &temps,
                &tg.error,
                rows,
                sigma_e,
                ridge,
            )?
            .1
        }
        false => Vec::new(),
    };
    Ok(normalised(m, run, tg, &temps, &e, rows, sigma_t, sigma_e))
}

/// The residuals of node temperatures `temps` and the axis' drift `e` against the targets over
/// `rows`: each sensed node's reading, then the error, each over its noise level.
#[allow(clippy::too_many_arguments)]
fn normalised(
    m: &Machine,
    run: &RunView<'_>,
    tg: &Targets<'_>,
    temps: &[f64],
    e: &[f64],
    rows: usize,
    sigma_t: f64,
    sigma_e: f64,
) -> Vec<f64> {
    let mut r = Vec::with_capacity(rows * (tg.sensors.len() + 1));
    let nn = m.nodes.len();
    for sn in &tg.sensors {
        let (i, meas) = (sn.node, &*sn.reading.values);
        let node = &m.nodes[i];
        let (off, drift) = (node.sensor_offset_k, node.sensor_drift_k_per_h);
        let rows_of = temps.chunks_exact(nn).zip(meas).take(rows);
        if !sn.reading.failing.is_empty() {
            // a failing sensor: its fitted rows only
            r.extend(
                rows_of
                    .zip(run.time)
                    .enumerate()
                    .filter(|(k, _)| sn.reading.reads(*k))
                    .map(|(_, ((t, mk), tk))| {
                        (t[i] + off + drift * (tk - run.time[0]) / 3600.0 - mk) / sigma_t
                    }),
            );
        } else if drift == 0.0 {
            // the drift term is ±0 then: the same numbers without it (the inner loop's cost);
            // the node's column gathered first, so that the arithmetic runs on contiguous data
            let start = r.len();
            r.extend(rows_of.map(|(t, _)| t[i]));
            for (v, mk) in r[start..].iter_mut().zip(meas) {
                *v = (*v + off - mk) / sigma_t;
            }
        } else {
            r.extend(rows_of.zip(run.time).map(|((t, mk), tk)| {
                (t[i] + off + drift * (tk - run.time[0]) / 3600.0 - mk) / sigma_t
            }));
        }
    }
    let pairs = e.iter().zip(tg.error.values.iter()).take(rows);
    if tg.error.failing.is_empty() {
        r.extend(pairs.map(|(ek, mk)| (ek - mk) / sigma_e));
    } else {
        r.extend(
            pairs
                .enumerate()
                .filter(|(k, _)| tg.error.reads(*k))
                .map(|(_, (ek, mk))| (ek - mk) / sigma_e),
        );
    }
    r
}

/// Runs sampled faster than this are calibrated on every k-th sample, k = ⌊`FIT_STEP_S` / median
/// step⌋: a lumped network's time constants are minutes to hours, so a minute resolves them, and
/// each calibration costs k times less. Simulations and held-out figures keep every sample.
pub const FIT_STEP_S: f64 = 60.0;
/// A calibration stops when a step lowers the cost ½·Σr² of the noise-normalised residuals by
/// less than this: a thousandth of the smallest BIC difference the diagnosis acts on (10).
pub const CALIBRATION_ATOL: f64 = 0.01;
/// Thinning never leaves fewer fitted rows than this.
pub const MIN_THINNED_ROWS: usize = 200;

/// The thinning factor `calibrate` applies to a run with time axis `time`, `rows` of it fitted.
pub fn fit_thinning(time: &[f64], rows: usize) -> usize {
    let k = median_step(time).map_or(1, |h| (FIT_STEP_S / h).floor().clamp(1.0, 1e6) as usize);
    k.min(rows / MIN_THINNED_ROWS).max(1)
}

/// Calibrates `m` on `run` with the given free parameters (`None`: [`default_params`]), on every
/// [`fit_thinning`]-th row of a run sampled faster than [`FIT_STEP_S`].
pub fn calibrate(
    m: &Machine,
    run: &RunView<'_>,
    opts: &CalibrationOptions,
    free: Option<Vec<FreeParam>>,
) -> Result<Calibration> {
    opts.check()?;
    let rows = opts.fit_rows.unwrap_or(run.len()).min(run.len());
    // the held-out rows are neither fitted nor needed to simulate the fitted ones
    let run = &run.head(rows);
    let k = fit_thinning(run.time, rows);
    if k <= 1 {
        return calibrate_all_rows(m, run, opts, free);
    }
    let thin = Thinned::of(run, k);
    let opts = CalibrationOptions {
        fit_rows: Some(rows.div_ceil(k)),
        ..opts.clone()
    };
    calibrate_all_rows(m, &thin.view(), &opts, free)
}

fn calibrate_all_rows(
    m: &Machine,
    run: &RunView<'_>,
    opts: &CalibrationOptions,
    free: Option<Vec<FreeParam>>,
) -> Result<Calibration> {
    let tg = targets(m, run, &opts.axis)?;
    let rows = opts.fit_rows.unwrap_or(run.len()).min(run.len());
    if rows < 10 {
        return Err(Error::Shape(format!(
            "{}: {rows} rows are too few to calibrate on",
            run.source
        )));
    }
    let sigma_t = opts.sigma_t.unwrap_or_else(|| {
        let s: Vec<f64> = tg.sensors.iter().map(|sn| sn.reading.noise(rows)).collect();
        let mean = if s.is_empty() {
            0.03
        } else {
            s.iter().sum::<f64>() / s.len() as f64
        };
        mean.max(0.005)
    });
    let sigma_e = opts.sigma_e.unwrap_or_else(|| tg.error.sigma(rows));
    let free = free.unwrap_or_else(|| default_params(m, opts));
    let n_linear = {
        let d = &m.drift[tg.axis_index];
        d.um_per_k.len()
            + d.quadratic_um_per_k2.len()
            + usize::from(d.ambient_um_per_k.is_some())
            + d.columns.len()
            + d.inputs.len()
    };
    let steps = Steps::of(run.time);
    let residual = |x: &[f64]| -> Result<Vec<f64>> {
        let (mm, init) = apply(m, &free, x);
        let mut r = residuals(
            &mm,
            &init,
            run,
            &tg,
            rows,
            sigma_t,
            sigma_e,
            opts.fit_error,
            &steps,
            opts.drift_ridge,
        )?;
        for (fp, v) in free.iter().zip(x) {
            if let Some((c, w)) = fp.prior {
                r.push((v - c) / w);
            }
        }
        Ok(r)
    };
    let (x, n_iter, converged) = if free.is_empty() {
        (Vec::new(), 0, true)
    } else {
        let x0: Vec<f64> = free.iter().map(|f| f.start.clamp(f.lo, f.hi)).collect();
        let lo: Vec<f64> = free.iter().map(|f| f.lo).collect();
        let hi: Vec<f64> = free.iter().map(|f| f.hi).collect();
        // a step's ΔBIC ≈ n·ΔSSR/SSR: n times the relative decrease of the cost
        let n_data = tg
            .sensors
            .iter()
            .map(|sn| sn.reading.fitted_rows(rows))
            .sum::<usize>()
            + tg.error.fitted_rows(rows) * usize::from(opts.fit_error);
        let lm = LmOptions {
            max_iter: opts.max_iter,
            ftol: (opts.min_bic_step / n_data as f64).max(1e-9),
            atol: CALIBRATION_ATOL,
            ..LmOptions::default()
        };
        let res = least_squares(residual, &x0, &lo, &hi, &lm)?;
        (res.x, res.n_iter, res.converged)
    };
    let (mm, init) = apply(m, &free, &x);
    let (mut fitted, _, r) = evaluate(
        &mm,
        &init,
        run,
        &tg,
        rows,
        sigma_t,
        sigma_e,
        Some(opts.drift_ridge),
    )?;
    fitted.start = Some(FittedStart {
        run: run.source.to_string(),
        initial_k: named_offsets(&fitted, &init),
    });
    let ssr: f64 = r.iter().map(|v| v * v).sum();
    if !ssr.is_finite() {
        return Err(Error::Numerical(format!(
            "{}: the calibrated model's residual is not finite (values too large for the network?)",
            run.source
        )));
    }
    Ok(Calibration {
        machine: fitted,
        init,
        sigma_t,
        sigma_e,
        ssr,
        n_data: r.len(),
        n_params: free
            .iter()
            .filter(|f| !matches!(f.param, Param::InitOffset(_)))
            .count()
            + n_linear,
        n_iter,
        converged,
    })
}

/// Initial offsets (K, added to each node's formats.md start) by node name, every node's, in
/// the machine's order: how a report records the start it simulated from.
pub fn named_offsets(m: &Machine, off: &[f64]) -> BTreeMap<String, f64> {
    m.nodes
        .iter()
        .zip(off.iter().chain(std::iter::repeat(&0.0)))
        .map(|(n, &v)| (n.name.clone(), v))
        .collect()
}

/// The offsets of [`named_offsets`] back as the simulation's vector; a name the machine lacks,
/// or an offset that is not finite, is refused naming it (nodes not named start at 0).
pub fn offsets_by_name(m: &Machine, named: &BTreeMap<String, f64>) -> Result<Vec<f64>> {
    let mut off = vec![0.0; m.nodes.len()];
    for (name, &v) in named {
        let i = m.node_index(name).ok_or_else(|| {
            Error::param(
                "initial_k",
                format!(
                    "the machine has no node `{name}` (nodes: {})",
                    m.nodes
                        .iter()
                        .map(|n| n.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })?;
        if !v.is_finite() {
            return Err(Error::param(
                "initial_k",
                format!("`{name}`: {v} is not a finite offset"),
            ));
        }
        off[i] = v;
    }
    Ok(off)
}

/// Initial offsets of the sensed nodes that best explain the first `window` readings of a run
/// (linear least squares: the network is linear in its initial state). Unsensed nodes keep the
/// formats.md start (the ambient's first reading).
pub fn fit_initial_offsets(m: &Machine, run: &RunView<'_>, window: usize) -> Result<Vec<f64>> {
    let nn = m.nodes.len();
    let sensed = sensed(m, run)?;
    let w = window.min(run.len()).max(1);
    if sensed.is_empty() {
        return Ok(vec![0.0; nn]);
    }
    let base = simulate_nodes(m, run, &Init::Offsets(vec![0.0; nn]))?;
    let (cols, rhs) = start_system(m, &sensed, run.time, w, &base, sensed.len(), |j| {
        let mut off = vec![0.0; nn];
        off[sensed[j].node] = 1.0;
        simulate_nodes(m, run, &Init::Offsets(off))
    })?;
    let cols: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    let sol = lstsq_columns(&cols, &rhs)?;
    let mut off = vec![0.0; nn];
    for (sj, v) in sensed.iter().zip(sol) {
        off[sj.node] = v.clamp(-2.0, 2.0);
    }
    Ok(off)
}

/// The least-squares system of a fitted start (the network is linear in its start): over the
/// first `w` rows that each of the `sensed` nodes reads, one column per unknown start `j`
/// (`response(j)`: the node temperatures, row-major, with that start 1 K higher, less `base`,
/// the temperatures from the start as it is) and the right-hand side (each reading less what
/// its sensor would read on `base`, [`NodeSpec::sensor_reads`]).
pub fn start_system(
    m: &Machine,
    sensed: &[Sensed<'_>],
    time: &[f64],
    w: usize,
    base: &[f64],
    unknowns: usize,
    mut response: impl FnMut(usize) -> Result<Vec<f64>>,
) -> Result<(Vec<Vec<f64>>, Vec<f64>)> {
    let nn = m.nodes.len();
    let mut cols = Vec::with_capacity(unknowns);
    for j in 0..unknowns {
        let resp = response(j)?;
        let mut col = Vec::with_capacity(w * sensed.len());
        for sn in sensed {
            let i = sn.node;
            for k in (0..w).filter(|&k| sn.reading.reads(k)) {
                col.push(resp[k * nn + i] - base[k * nn + i]);
            }
        }
        cols.push(col);
    }
    let mut rhs = Vec::with_capacity(w * sensed.len());
    for sn in sensed {
        let (i, meas) = (sn.node, &*sn.reading.values);
        let node: &NodeSpec = &m.nodes[i];
        for k in (0..w).filter(|&k| sn.reading.reads(k)) {
            rhs.push(meas[k] - node.sensor_reads(base[k * nn + i], time[k] - time[0]));
        }
    }
    Ok((cols, rhs))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two columns that move together (the second the first plus a small wiggle) and a third of
    /// its own; `y` is the first column plus the third, plus a hundred times the wiggle fading
    /// over the first rows: a difference least squares takes up (as it takes up a start offset
    /// on a slow node, or another run's duty) and the later rows do not have.
    fn collinear(n: usize) -> (Vec<Vec<f64>>, Vec<f64>) {
        let wiggle = |k: usize, a: f64| (k as f64 * a).sin();
        let a: Vec<f64> = (0..n)
            .map(|k| 10.0 * (1.0 - (-(k as f64) / 300.0).exp()))
            .collect();
        let b: Vec<f64> = a
            .iter()
            .enumerate()
            .map(|(k, v)| v + 0.1 * wiggle(k, 1.7))
            .collect();
        let c: Vec<f64> = (0..n).map(|k| wiggle(k, 0.013)).collect();
        let spurious = |k: usize| 10.0 * wiggle(k, 1.7) * (-(k as f64) / 40.0).exp();
        let y = (0..n).map(|k| a[k] + c[k] + spurious(k)).collect();
        (vec![a, b, c], y)
    }

    #[test]
    fn the_folds_choose_a_penalty_that_stops_collinear_terms_cancelling() {
        let (x, y) = collinear(1000);
        let cols: Vec<&[f64]> = x.iter().map(Vec::as_slice).collect();
        let ols = ridge(&cols, &y, RIDGE_GRID[0]).unwrap();
        let (coef, lambda, share) = ridge_by_folds(&x, &y).unwrap();
        // least squares trades the two together columns against each other
        assert!(ols[0] < -2.0 && ols[1] > 3.0, "{ols:?}");
        // the folds pick a penalty, and the pair shares the effect (about 1 in all)
        assert!(lambda > RIDGE_GRID[0], "{lambda}");
        assert!(coef[0].abs() < 2.0 && coef[1].abs() < 2.0, "{coef:?}");
        assert!((coef[0] + coef[1] - 1.0).abs() < 0.05, "{coef:?}");
        // the term of its own keeps most of its effect (a ridge shrinks every coefficient)
        assert!(coef[2] > 0.85 && coef[2] < 1.0, "{coef:?}");
        // and the rows past the spurious effect are predicted better than least squares does
        let rmse_late = |c: &[f64]| {
            let r = (200..1000).map(|k| y[k] - (0..3).map(|j| c[j] * x[j][k]).sum::<f64>());
            crate::metrics::rms_of(r)
        };
        assert!(
            rmse_late(&coef) < 0.5 * rmse_late(&ols),
            "{} {}",
            rmse_late(&coef),
            rmse_late(&ols)
        );
        // the same numbers every time
        assert_eq!(ridge_by_folds(&x, &y).unwrap(), (coef, lambda, share));
    }

    #[test]
    fn independent_terms_keep_about_least_squares() {
        let n = 1000;
        let x: Vec<Vec<f64>> = (0..3)
            .map(|j| {
                (0..n)
                    .map(|k| ((k * (j + 1)) as f64 * 0.011).sin() + j as f64 * 0.1)
                    .collect()
            })
            .collect();
        let y: Vec<f64> = (0..n)
            .map(|k| 2.0 * x[0][k] - 1.0 * x[1][k] + 0.5 * x[2][k] + 0.01 * (k as f64 * 2.3).sin())
            .collect();
        let (coef, lambda, share) = ridge_by_folds(&x, &y).unwrap();
        assert!(lambda <= 1e-4, "{lambda}");
        for (c, want) in coef.iter().zip([2.0, -1.0, 0.5]) {
            assert!((c - want).abs() < 0.01, "{coef:?}");
        }
        // the folds predict all but the 0.01 wiggle: a share of y's squares of about 1e-4
        let ss: f64 = y.iter().map(|v| v * v).sum();
        let wiggle: f64 = (0..n)
            .map(|k| (0.01 * (k as f64 * 2.3).sin()).powi(2))
            .sum();
        let share = share.unwrap();
        assert!(
            share > 0.5 * wiggle / ss && share < 2.0 * wiggle / ss,
            "{share} {}",
            wiggle / ss
        );
        // too few rows for five folds: the smallest penalty, no folds
        let short: Vec<Vec<f64>> = x.iter().map(|c| c[..40].to_vec()).collect();
        let (_, lambda, share) = ridge_by_folds(&short, &y[..40]).unwrap();
        assert_eq!((lambda, share), (RIDGE_GRID[0], None));
    }

    /// Two node rises that move together while the map is fitted and part later, and an error
    /// that follows their mean plus a small effect of neither, which least squares reads from
    /// their difference.
    fn parting(n: usize) -> (Vec<Vec<f64>>, Vec<f64>) {
        let cut = n * 7 / 10;
        let t = |k: usize| k as f64 / n as f64;
        let a: Vec<f64> = (0..n).map(|k| 4.0 * t(k)).collect();
        let b: Vec<f64> = (0..n)
            .map(|k| {
                let wiggle = 0.01 * (k as f64 * 0.37).sin();
                let part = if k >= cut { 0.8 * (t(k) - 0.7) } else { 0.0 };
                4.0 * t(k) + wiggle + part
            })
            .collect();
        // the small effect happens to follow b's wiggle while the map is fitted
        let y = (0..n)
            .map(|k| {
                0.5 * (a[k] + b[k])
                    + if k < cut {
                        0.03 * (k as f64 * 0.37).sin()
                    } else {
                        0.0
                    }
            })
            .collect();
        (vec![a, b], y)
    }

    #[test]
    fn the_forward_penalty_stops_terms_that_part_later_from_cancelling() {
        let (x, y) = parting(1000);
        let lambda = forward_penalty(&x, &y, 0.3).unwrap();
        assert!(lambda > RIDGE_GRID[0], "{lambda}");
        // on the last 30 %: the chosen penalty against least squares, both fitted before it
        let late = |lambda: f64| {
            let fit: Vec<&[f64]> = x.iter().map(|c| &c[..700]).collect();
            let c = ridge(&fit, &y[..700], lambda).unwrap();
            crate::metrics::rms_of((700..1000).map(|k| y[k] - c[0] * x[0][k] - c[1] * x[1][k]))
        };
        assert!(
            late(lambda) < 0.5 * late(RIDGE_GRID[0]),
            "{} {}",
            late(lambda),
            late(RIDGE_GRID[0])
        );
        // terms that stay apart keep least squares; too few rows: the smallest
        let n = 1000;
        let ind: Vec<Vec<f64>> = (0..2)
            .map(|j| {
                (0..n)
                    .map(|k| ((k * (j + 1)) as f64 * 0.011).sin())
                    .collect()
            })
            .collect();
        let yi: Vec<f64> = (0..n).map(|k| 2.0 * ind[0][k] - ind[1][k]).collect();
        assert_eq!(forward_penalty(&ind, &yi, 0.3).unwrap(), RIDGE_GRID[0]);
        assert_eq!(
            forward_penalty(&x, &y[..20], 0.3).unwrap_or(0.0),
            RIDGE_GRID[0]
        );
    }

    #[test]
    fn failing_rows_join_into_disjoint_ranges() {
        assert_eq!(
            union(&[5..9, 20..25], &[1..3, 8..12, 25..30]),
            vec![1..3, 5..12, 20..30]
        );
        assert_eq!(union(&[], &[4..6, 8..9]), vec![4..6, 8..9]);
        let r = Reading {
            values: std::borrow::Cow::Borrowed(&[0.0; 40]),
            failing: vec![5..12, 20..30],
        };
        assert_eq!(r.fitted_rows(25), 25 - 7 - 5);
        assert!(r.reads(4) && !r.reads(5) && !r.reads(11) && r.reads(12));
    }

    /// A probe logged to 0.1 µm on a slow drift (0.01 µm a row, so its readings step by 0.1
    /// every tenth row): second differences of zero in most rows, a noise level of 0; its σ is
    /// the rounding's, 0.1/√12 = 0.029 µm, and the same run in mm gives the same σ in mm.
    /// A smooth probe with no repeated reading and no noise: 0.01 % of its span. One that
    /// never moves: 1.
    #[test]
    fn sigma_of_a_rounded_a_smooth_and_a_still_probe() {
        let rounded: Vec<f64> = (0..2000)
            .map(|k| (k as f64 * 0.01 * 10.0).round() / 10.0)
            .collect();
        let r = Reading {
            values: std::borrow::Cow::Borrowed(&rounded),
            failing: Vec::new(),
        };
        assert_eq!(noise_level(&rounded), 0.0);
        let s = r.sigma(2000);
        assert!((s - 0.1 / 12f64.sqrt()).abs() < 1e-9, "{s}");
        let mm: Vec<f64> = rounded.iter().map(|v| v / 1000.0).collect();
        let r_mm = Reading {
            values: std::borrow::Cow::Borrowed(&mm),
            failing: Vec::new(),
        };
        assert!((r_mm.sigma(2000) * 1000.0 - s).abs() < 1e-9);
        let smooth: Vec<f64> = (0..2000)
            .map(|k| 20.0 * (k as f64 / 2000.0).powi(2))
            .collect();
        let r = Reading {
            values: std::borrow::Cow::Borrowed(&smooth),
            failing: Vec::new(),
        };
        let span = smooth[1999] - smooth[0];
        assert!((r.sigma(2000) - SIGMA_E_FLOOR_SHARE * span).abs() < 1e-12);
        let r = Reading {
            values: std::borrow::Cow::Borrowed(&[3.0; 50]),
            failing: Vec::new(),
        };
        assert_eq!(r.sigma(50), 1.0);
    }
}
