//! Grey model GM(1,N) and the rolling GM + BP network of seed 002 (Zhang & Yang 2011).
//!
//! GM(1,N) on a window of w samples (methods.md §4): x1 = the error series, x2..xN the
//! temperatures; 1-AGO of every series; background value z1(k) = ½(x1⁽¹⁾(k) + x1⁽¹⁾(k−1));
//! [a, b2..bN] by least squares from rows [−z1(k), x2⁽¹⁾(k), …, xN⁽¹⁾(k)] and targets x1⁽⁰⁾(k),
//! k = 2..w — the seed's (BᵀB)⁻¹BᵀY; when the window has fewer equations than unknowns (w − 1 < N),
//! the minimum-norm solution Bᵀ(BBᵀ)⁻¹Y. Time response
//! x̂1⁽¹⁾(k+1) = (x1⁽⁰⁾(1) − S(k+1)/a)·e^(−ak) + S(k+1)/a, S = Σ bᵢ xᵢ⁽¹⁾, restored by differencing;
//! as a → 0 its limit x1⁽⁰⁾(1) + S(k+1)·k.
//!
//! The rolling model: at every step k, a GM(1,N) per window length w (6, 8, 10) is refitted on the
//! w previous samples and predicts the error at k from the temperatures up to k. Those
//! predictions, min–max normalised by their training ranges, feed a BP network (3-7-1, sigmoid
//! hidden, linear output) whose output is the normalised error.
//!
//! Prediction is streaming ([`GreyState`]): the windows hold the *measured* previous error when
//! the caller knows it (seed 002's one-step-ahead protocol) and the model's own previous output
//! otherwise (closed loop, what a compensating controller does). At the start of a run the windows
//! shrink to the samples there are; with fewer than 3 past samples the prediction is the last
//! error known (0 at the first sample: errors are relative to the run's start).

// index loops read like the formulas of methods.md §4
#![allow(clippy::needless_range_loop)]

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::nn::{scale01, BpParams, BpValidParams, Mlp};
#[cfg(feature = "fit")]
use crate::samples::Samples;

/// Smallest number of past samples a window needs (two equations).
pub const MIN_WINDOW: usize = 3;

/// Solves the small least-squares problem min ‖Bθ − y‖ (B row-major, `rows × cols`) as the seed
/// writes it, (BᵀB)⁻¹Bᵀy, or the minimum-norm Bᵀ(BBᵀ)⁻¹y when rows < cols. `work` needs
/// max(rows, cols)² + max(rows, cols) values. `false` if the system is singular.
pub fn small_lstsq(
    b: &[f64],
    rows: usize,
    cols: usize,
    y: &[f64],
    theta: &mut [f64],
    work: &mut [f64],
) -> bool {
    let n = rows.min(cols);
    let (a, rest) = work.split_at_mut(n * n);
    let r = &mut rest[..n];
    if rows >= cols {
        for i in 0..cols {
            for j in 0..cols {
                let mut s = 0.0;
                for k in 0..rows {
                    s += b[k * cols + i] * b[k * cols + j];
                }
                a[i * n + j] = s;
            }
            let mut s = 0.0;
            for k in 0..rows {
                s += b[k * cols + i] * y[k];
            }
            r[i] = s;
        }
        if !gauss_solve(a, r, n) {
            return false;
        }
        theta[..cols].copy_from_slice(r);
    } else {
        for i in 0..rows {
            for j in 0..rows {
                let mut s = 0.0;
                for k in 0..cols {
                    s += b[i * cols + k] * b[j * cols + k];
                }
                a[i * n + j] = s;
            }
            r[i] = y[i];
        }
        if !gauss_solve(a, r, n) {
            return false;
        }
        for (k, t) in theta[..cols].iter_mut().enumerate() {
            let mut s = 0.0;
            for i in 0..rows {
                s += b[i * cols + k] * r[i];
            }
            *t = s;
        }
    }
    theta[..cols].iter().all(|v| v.is_finite())
}

/// Gaussian elimination with partial pivoting of the n × n system a·x = r (x into r).
fn gauss_solve(a: &mut [f64], r: &mut [f64], n: usize) -> bool {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return false;
    }
    for c in 0..n {
        let mut p = c;
        for i in c + 1..n {
            if a[i * n + c].abs() > a[p * n + c].abs() {
                p = i;
            }
        }
        if a[p * n + c].abs() <= 1e-14 * scale {
            return false;
        }
        if p != c {
            for j in 0..n {
                a.swap(c * n + j, p * n + j);
            }
            r.swap(c, p);
        }
        for i in c + 1..n {
            let f = a[i * n + c] / a[c * n + c];
            if f != 0.0 {
                for j in c..n {
                    a[i * n + j] -= f * a[c * n + j];
                }
                r[i] -= f * r[c];
            }
        }
    }
    for c in (0..n).rev() {
        let mut s = r[c];
        for j in c + 1..n {
            s -= a[c * n + j] * r[j];
        }
        r[c] = s / a[c * n + c];
    }
    true
}

/// Work space of one GM(1,N) fit over windows of up to `w_max` samples with `m` temperatures.
#[derive(Clone, Debug)]
pub struct GmWork {
    m: usize,
    b: Vec<f64>,
    y: Vec<f64>,
    ago1: Vec<f64>,
    agot: Vec<f64>,
    /// [a, b2..bN] of the last fit
    pub theta: Vec<f64>,
    solve: Vec<f64>,
}

impl GmWork {
    pub fn new(w_max: usize, m: usize) -> Self {
        let cols = m + 1;
        let big = w_max.max(cols);
        GmWork {
            m,
            b: vec![0.0; w_max * cols],
            y: vec![0.0; w_max],
            ago1: vec![0.0; w_max + 1],
            agot: vec![0.0; (w_max + 1) * m],
            theta: vec![0.0; cols],
            solve: vec![0.0; big * big + big],
        }
    }

    /// Fits GM(1,N) on the window `e[0..w]` (errors) with temperatures `t[0..w]` (row-major,
    /// `m` per row) and returns the restored prediction of the error at the next sample, whose
    /// temperatures are `t_next`. `None` if the fit is singular.
    pub fn predict_next(&mut self, e: &[f64], t: &[f64], t_next: &[f64]) -> Option<f64> {
        let (w, m) = (e.len(), self.m);
        let cols = m + 1;
        if w < 2 {
            return None;
        }
        // 1-AGO of the window and of the temperatures including the next sample
        let mut s = 0.0;
        for (k, v) in e.iter().enumerate() {
            s += v;
            self.ago1[k] = s;
        }
        for j in 0..m {
            let mut s = 0.0;
            for k in 0..=w {
                s += if k < w { t[k * m + j] } else { t_next[j] };
                self.agot[k * m + j] = s;
            }
        }
        // rows k = 1..w−1 (0-based): [−z1(k), x2⁽¹⁾(k), …]
        let rows = w - 1;
        for k in 1..w {
            let row = &mut self.b[(k - 1) * cols..k * cols];
            row[0] = -0.5 * (self.ago1[k] + self.ago1[k - 1]);
            row[1..].copy_from_slice(&self.agot[k * m..(k + 1) * m]);
            self.y[k - 1] = e[k];
        }
        if !small_lstsq(
            &self.b,
            rows,
            cols,
            &self.y,
            &mut self.theta,
            &mut self.solve,
        ) {
            return None;
        }
        let x1 = e[0];
        let resp = |this: &Self, k: usize| -> f64 {
            let a = this.theta[0];
            let s: f64 = this.theta[1..]
                .iter()
                .zip(&this.agot[k * m..(k + 1) * m])
                .map(|(b, x)| b * x)
                .sum();
            if a.abs() < 1e-12 {
                x1 + s * k as f64
            } else {
                (x1 - s / a) * (-a * k as f64).exp() + s / a
            }
        };
        let v = resp(self, w) - resp(self, w - 1);
        v.is_finite().then_some(v)
    }
}

/// A fitted rolling GM(1,N) + BP model (`net = None`: one window's GM alone).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GreyBpModel {
    pub windows: Vec<usize>,
    pub n_temps: usize,
    /// Training ranges of each window's GM prediction (the network's input scaling).
    pub gm_min: Vec<f64>,
    pub gm_max: Vec<f64>,
    /// Training range of the error (the network's output scaling).
    pub y_min: f64,
    pub y_max: f64,
    /// absent for a GM alone
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub net: Option<Mlp>,
    /// Training MSE (normalised) of the network after each epoch; empty for a GM alone and in
    /// files written before it was kept.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub history: Vec<f64>,
}

impl GreyBpModel {
    pub fn n_features(&self) -> usize {
        self.n_temps
    }

    pub fn w_max(&self) -> usize {
        self.windows.iter().copied().max().unwrap_or(0)
    }

    /// Checks a model read from a file.
    pub fn validate(&self) -> Result<()> {
        let k = self.windows.len();
        if k == 0 || self.windows.iter().any(|&w| w < MIN_WINDOW) || self.n_temps == 0 {
            return Err(Error::Format(format!(
                "greybp model: windows {:?} (each >= {MIN_WINDOW}) over {} temperatures",
                self.windows, self.n_temps
            )));
        }
        let state = self.w_max().saturating_mul(self.n_temps + 1);
        if state > crate::artifact::MAX_STATE_VALUES {
            return Err(Error::Format(format!(
                "greybp model: windows {:?} over {} temperatures would keep {state} values per run (at most {})",
                self.windows,
                self.n_temps,
                crate::artifact::MAX_STATE_VALUES
            )));
        }
        if self.gm_min.len() != k || self.gm_max.len() != k {
            return Err(Error::Format(
                "greybp model: one GM range per window".into(),
            ));
        }
        crate::samples::require_finite_model("greybp", "gm_min", &self.gm_min)?;
        crate::samples::require_finite_model("greybp", "gm_max", &self.gm_max)?;
        crate::samples::require_finite_model("greybp", "y_min/y_max", &[self.y_min, self.y_max])?;
        match &self.net {
            Some(net) => {
                net.validate().map_err(Error::Format)?;
                if net.n_inputs() != k {
                    return Err(Error::Format(format!(
                        "greybp model: the network takes {} inputs for {k} windows",
                        net.n_inputs()
                    )));
                }
            }
            None if k != 1 => {
                return Err(Error::Format(
                    "greybp model without a network must have one window".into(),
                ))
            }
            None => {}
        }
        Ok(())
    }

    /// Combines the windows' GM predictions into the model's output.
    pub fn combine(&self, gm: &[f64], scratch: &mut [f64]) -> f64 {
        match &self.net {
            None => gm[0],
            Some(net) => {
                let k = gm.len();
                let (x, s) = scratch.split_at_mut(k);
                for (j, xv) in x.iter_mut().enumerate() {
                    *xv = scale01(gm[j], self.gm_min[j], self.gm_max[j]);
                }
                let out = net.predict_one(x, s);
                out * (self.y_max - self.y_min) + self.y_min
            }
        }
    }

    /// Predicts a whole series: closed loop, or one step ahead from `measured` errors.
    pub fn predict(&self, temps: &[f64], measured: Option<&[f64]>) -> Result<Vec<f64>> {
        let mut st = GreyState::new(self);
        let kind = if self.net.is_some() { "greybp" } else { "gm1n" };
        crate::sequence::run_series(kind, temps, self.n_temps, measured, |row, prev| {
            st.push(self, row, prev)
        })
    }
}

/// The streaming state of a [`GreyBpModel`] over one run: ring buffers of the last `w_max`
/// errors and temperatures; nothing is allocated per step.
#[derive(Clone, Debug)]
pub struct GreyState {
    m: usize,
    cap: usize,
    /// errors and temperatures of the last `cap` samples, oldest first after `len` is reached
    e: Vec<f64>,
    t: Vec<f64>,
    len: usize,
    /// the model's output at the previous sample
    last_out: f64,
    have_prev: bool,
    prev_t: Vec<f64>,
    work: GmWork,
    gm: Vec<f64>,
    scratch: Vec<f64>,
}

impl GreyState {
    pub fn new(model: &GreyBpModel) -> Self {
        let (m, cap) = (model.n_temps, model.w_max());
        let k = model.windows.len();
        GreyState {
            m,
            cap,
            e: vec![0.0; cap],
            t: vec![0.0; cap * m],
            len: 0,
            last_out: 0.0,
            have_prev: false,
            prev_t: vec![0.0; m],
            work: GmWork::new(cap, m),
            gm: vec![0.0; k],
            scratch: vec![0.0; k + model.net.as_ref().map_or(0, |n| n.scratch_len())],
        }
    }

    pub fn reset(&mut self) {
        self.len = 0;
        self.last_out = 0.0;
        self.have_prev = false;
    }

    /// The next sample's temperatures; `measured_prev` is the measured error of the previous
    /// sample if known. Returns the predicted error of this sample.
    pub fn push(
        &mut self,
        model: &GreyBpModel,
        temps: &[f64],
        measured_prev: Option<f64>,
    ) -> Result<f64> {
        let m = self.m;
        crate::sequence::check_step(temps, m, measured_prev)?;
        // the previous sample's error joins the history
        if self.have_prev {
            let e_prev = measured_prev.unwrap_or(self.last_out);
            if self.len == self.cap {
                self.e.copy_within(1.., 0);
                self.t.copy_within(m.., 0);
                self.len -= 1;
            }
            self.e[self.len] = e_prev;
            let (l, pt) = (self.len, &self.prev_t);
            self.t[l * m..(l + 1) * m].copy_from_slice(pt);
            self.len += 1;
        }
        let out = if self.len < MIN_WINDOW {
            if self.len == 0 {
                0.0
            } else {
                self.e[self.len - 1]
            }
        } else {
            let mut ok = true;
            for (j, &w) in model.windows.iter().enumerate() {
                let w = w.min(self.len);
                let s = self.len - w;
                match self.work.predict_next(
                    &self.e[s..self.len],
                    &self.t[s * m..self.len * m],
                    temps,
                ) {
                    Some(v) => self.gm[j] = v,
                    None => {
                        ok = false;
                        break;
                    }
                }
            }
            if ok {
                model.combine(&self.gm, &mut self.scratch)
            } else {
                // a singular window (e.g. constant readings): hold the last error
                self.e[self.len - 1]
            }
        };
        self.prev_t.copy_from_slice(temps);
        self.have_prev = true;
        self.last_out = out;
        Ok(out)
    }
}

/// Hyper-parameters of the rolling GM + BP model; a consuming builder with seed 002's windows
/// and network, checked by [`GreyBpParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub struct GreyBpParams(GreyBpValidParams);

/// Checked hyper-parameters; [`GreyBpValidParams::fit`] fits the windows and trains the network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GreyBpValidParams {
    /// Lengths of the GM(1,N) windows, each at least [`MIN_WINDOW`].
    pub windows: Vec<usize>,
    /// The network that combines the windows' predictions.
    pub net: BpValidParams,
}

impl Default for GreyBpParams {
    /// Windows of 6, 8 and 10 samples; the network of [`BpParams::default`] (with its large-n
    /// rule, [`BpValidParams::large_n`]).
    fn default() -> Self {
        GreyBpParams(GreyBpValidParams {
            windows: vec![6, 8, 10],
            net: BpParams::default().0,
        })
    }
}

impl GreyBpParams {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn windows(mut self, windows: Vec<usize>) -> Self {
        self.0.windows = windows;
        self
    }

    /// Adjusts the network, starting from this model's: `.net(|n| n.trainer(Trainer::Gd))`.
    pub fn net(mut self, f: impl FnOnce(BpParams) -> BpParams) -> Self {
        self.0.net = f(BpParams(self.0.net)).0;
        self
    }

    /// Validates everything that does not depend on the data.
    pub fn check(self) -> Result<GreyBpValidParams> {
        let GreyBpValidParams { windows, net } = self.0;
        check_windows(&windows)?;
        Ok(GreyBpValidParams {
            windows,
            net: BpParams(net).check()?,
        })
    }
}

/// Hyper-parameters of a rolling GM(1,N) alone (seed 002's "GM"); checked by
/// [`Gm1nParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub struct Gm1nParams(Gm1nValidParams);

/// Checked hyper-parameters; [`Gm1nValidParams::fit`] gives a [`GreyBpModel`] without network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Gm1nValidParams {
    /// Length of the window, at least [`MIN_WINDOW`].
    pub window: usize,
}

impl Default for Gm1nParams {
    /// A window of 8 samples.
    fn default() -> Self {
        Gm1nParams(Gm1nValidParams { window: 8 })
    }
}

impl Gm1nParams {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn window(mut self, window: usize) -> Self {
        self.0.window = window;
        self
    }

    pub fn check(self) -> Result<Gm1nValidParams> {
        check_windows(&[self.0.window])?;
        Ok(self.0)
    }
}

fn check_windows(windows: &[usize]) -> Result<()> {
    if windows.is_empty() || windows.iter().any(|&w| w < MIN_WINDOW) {
        return Err(Error::param(
            "windows",
            format!("need window lengths >= {MIN_WINDOW}, got {windows:?}"),
        ));
    }
    Ok(())
}

#[cfg(feature = "fit")]
impl GreyBpValidParams {
    /// Fits on a time-ordered training series: `temps` (n × m), `y` the measured errors. The
    /// network learns from the steps k ≥ max(windows), where every window is full.
    pub fn fit(&self, temps: Samples<'_>, y: &[f64]) -> Result<GreyBpModel> {
        fit_rolling(&self.windows, Some(&self.net), temps, y)
    }
}

#[cfg(feature = "fit")]
impl Gm1nValidParams {
    /// Fits on a time-ordered training series: `temps` (n × m), `y` the measured errors.
    pub fn fit(&self, temps: Samples<'_>, y: &[f64]) -> Result<GreyBpModel> {
        fit_rolling(&[self.window], None, temps, y)
    }
}

/// The GM(1,N) predictions of every window over the training series, their ranges, and (with
/// `net`) the network trained on them.
#[cfg(feature = "fit")]
fn fit_rolling(
    windows: &[usize],
    net: Option<&BpValidParams>,
    temps: Samples<'_>,
    y: &[f64],
) -> Result<GreyBpModel> {
    temps.require_finite("X")?;
    crate::samples::check_target(y, temps.nrows())?;
    let (n, m) = (temps.nrows(), temps.ncols());
    let w_max = *windows.iter().max().unwrap_or(&MIN_WINDOW);
    if n < w_max + 5 {
        return Err(Error::Shape(format!(
            "{n} samples are too few: the longest window is {w_max}, and at least 5 more are needed to train on"
        )));
    }
    let mut work = GmWork::new(w_max, m);
    let k = windows.len();
    let mut feats = Vec::with_capacity((n - w_max) * k);
    let mut targets = Vec::with_capacity(n - w_max);
    for step in w_max..n {
        let mut row = Vec::with_capacity(k);
        for &w in windows {
            let s = step - w;
            match work.predict_next(
                &y[s..step],
                &temps.as_slice()[s * m..step * m],
                temps.row(step),
            ) {
                Some(v) => row.push(v),
                None => break,
            }
        }
        if row.len() == k {
            feats.extend(row);
            targets.push(y[step]);
        }
    }
    if targets.len() < 5 {
        return Err(Error::Numerical(
            "the GM(1,N) windows are singular on this data (constant readings?)".into(),
        ));
    }
    let mut gm_min = vec![0.0; k];
    let mut gm_max = vec![0.0; k];
    for j in 0..k {
        let (lo, hi) = crate::metrics::min_max(feats.iter().skip(j).step_by(k).copied());
        gm_min[j] = lo;
        gm_max[j] = hi;
    }
    let (y_min, y_max) = crate::metrics::min_max(targets.iter().copied());
    let mut model = GreyBpModel {
        windows: windows.to_vec(),
        n_temps: m,
        gm_min,
        gm_max,
        y_min,
        y_max,
        net: None,
        history: Vec::new(),
    };
    if let Some(np) = net {
        let xs: Vec<f64> = feats
            .chunks(k)
            .flat_map(|r| {
                r.iter()
                    .enumerate()
                    .map(|(j, &v)| scale01(v, model.gm_min[j], model.gm_max[j]))
            })
            .collect();
        let ys: Vec<f64> = targets.iter().map(|&v| scale01(v, y_min, y_max)).collect();
        let tr = np.train(Samples::new(&xs, ys.len(), k)?, &ys)?;
        model.history = tr.history;
        model.net = Some(tr.net);
    }
    Ok(model)
}

#[cfg(all(test, feature = "fit"))]
mod tests {
    use super::*;

    #[test]
    fn small_lstsq_solves_over_and_under_determined_systems() {
        // overdetermined, exact: y = 2·c0 − c1
        let b = [1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0];
        let y = [2.0, -1.0, 1.0, 3.0];
        let mut th = [0.0; 2];
        let mut work = vec![0.0; 4 * 4 + 4];
        assert!(small_lstsq(&b, 4, 2, &y, &mut th, &mut work));
        assert!((th[0] - 2.0).abs() < 1e-12 && (th[1] + 1.0).abs() < 1e-12);
        // underdetermined: one equation x + y = 2 → minimum norm (1, 1)
        assert!(small_lstsq(&[1.0, 1.0], 1, 2, &[2.0], &mut th, &mut work));
        assert!((th[0] - 1.0).abs() < 1e-12 && (th[1] - 1.0).abs() < 1e-12);
        // singular
        assert!(!small_lstsq(
            &[1.0, 2.0, 2.0, 4.0],
            2,
            2,
            &[1.0, 2.0],
            &mut th,
            &mut work
        ));
    }

    #[test]
    fn streaming_equals_batch_and_closed_loop_differs_from_one_step() {
        let n = 60;
        let m = 2;
        let t: Vec<f64> = (0..n)
            .flat_map(|k| {
                let s = k as f64 / 10.0;
                [
                    20.0 + 5.0 * (1.0 - (-s).exp()),
                    20.0 + 2.0 * (1.0 - (-s / 3.0).exp()),
                ]
            })
            .collect();
        let y: Vec<f64> = t
            .chunks(2)
            .map(|r| 3.0 * (r[0] - 20.0) + 1.5 * (r[1] - 20.0))
            .collect();
        let p = GreyBpParams::new()
            .windows(vec![6, 8])
            .net(|n| {
                n.hidden_sizes(vec![5])
                    .init(1.0)
                    .trainer(crate::nn::Trainer::Adam)
                    .lr(0.01)
                    .max_epochs(2000)
                    .goal(Some(1e-5))
                    .patience(200)
                    .seed(1)
            })
            .check()
            .unwrap();
        let s = Samples::new(&t, n, m).unwrap();
        let model = p.fit(s, &y).unwrap();
        let one = model.predict(&t, Some(&y)).unwrap();
        let closed = model.predict(&t, None).unwrap();
        // one step ahead on smooth data follows the measured error closely
        let rms = (one[10..]
            .iter()
            .zip(&y[10..])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            / (n - 10) as f64)
            .sqrt();
        assert!(rms < 0.2, "one-step RMS {rms}");
        assert_ne!(one, closed);
        let mut st = GreyState::new(&model);
        for k in 0..n {
            let v = st.push(&model, &t[k * m..(k + 1) * m], None).unwrap();
            assert_eq!(v, closed[k]);
        }
        let json = serde_json::to_string(&model).unwrap();
        let back: GreyBpModel = serde_json::from_str(&json).unwrap();
        assert_eq!(back.predict(&t, None).unwrap(), closed);
        assert!(!back.history.is_empty());
        assert_eq!(back.history, model.history);
        // GM alone: one window, no network, no history written
        let gm = Gm1nParams::new().check().unwrap().fit(s, &y).unwrap();
        assert_eq!((gm.windows.clone(), gm.net.is_none()), (vec![8], true));
        assert!(!serde_json::to_string(&gm).unwrap().contains("history"));
    }

    #[test]
    fn bad_params_are_refused() {
        assert!(GreyBpParams::new().windows(vec![2, 8]).check().is_err());
        assert!(GreyBpParams::new().windows(vec![]).check().is_err());
        assert!(GreyBpParams::new().net(|n| n.lr(-1.0)).check().is_err());
        assert!(Gm1nParams::new().window(2).check().is_err());
        let d = GreyBpParams::new().check().unwrap();
        assert_eq!(d.windows, vec![6, 8, 10]);
        assert_eq!(d.net.trainer, crate::nn::Trainer::Adam);
    }

    #[test]
    fn autotraits() {
        fn is_send_sync<T: Send + Sync>() {}
        is_send_sync::<GreyBpParams>();
        is_send_sync::<GreyBpValidParams>();
        is_send_sync::<Gm1nParams>();
        is_send_sync::<Gm1nValidParams>();
        is_send_sync::<GreyBpModel>();
    }
}
