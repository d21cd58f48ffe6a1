//! The hybrid LR/MA/AR filter + feed-forward network of seed 000 (Kang et al. 2007), and the
//! variants it is compared with.
//!
//! Filters (all coefficients by least squares on the training runs):
//! - LR: Ȳ1(n) = a0 + Σ_i a_i T_i(n)
//! - MA: Ȳ2(n) = b0 + Σ_{j=1..J} Σ_i b_ji T_i(n−j)
//! - AR: Ȳ3(n) = c0 + Σ_{k=1..K} c_k Ŷ(n−k) + c_LR Ȳ1(n) + c_MA Ȳ2(n)
//!
//! The network gets C_Y·[Ȳ1, Ȳ2, Ȳ3] (plus its biases), has a tanh hidden layer and a tanh output
//! scaled by `limit` (seed 000: 30 hidden nodes, outputs within ±50 µm); it is trained on the
//! error divided by `limit`. Ŷ(n−k) is the model's own final output at n−k: while training, the
//! measured error stands in for it (series-parallel); while predicting, the model's previous
//! outputs are fed back (closed loop) unless the caller gives the measured previous error (one
//! step ahead). At the start of a run the missing lags take the first sample's temperatures and an
//! error of 0 (errors are relative to the run's start); training skips those samples.
//!
//! Variants: `Hybrid` (the three filters + network), `Arma` (the AR filter alone), `LrNn` (the
//! LR filter + network), `Fnn` (the network on C_Y·T, no filters).

// index loops read like the filter formulas above
#![allow(clippy::needless_range_loop)]

use serde::{Deserialize, Serialize};

use std::str::FromStr;

use crate::error::{parse_name, Error, Result};
use crate::nn::{Act, BpParams, BpValidParams, Mlp};

/// Which filters feed the network (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Variant {
    Hybrid,
    Arma,
    LrNn,
    Fnn,
}

impl Variant {
    const NAMES: [(&'static str, Variant); 4] = [
        ("hybrid", Variant::Hybrid),
        ("arma", Variant::Arma),
        ("lrnn", Variant::LrNn),
        ("fnn", Variant::Fnn),
    ];
}

impl FromStr for Variant {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_name("variant", s, &Self::NAMES)
    }
}

/// A fitted filter model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HybridModel {
    pub variant: Variant,
    pub n_temps: usize,
    pub ma_lags: usize,
    pub ar_lags: usize,
    pub c_y: f64,
    /// [a0, a_1..a_m]
    pub lr: Vec<f64>,
    /// [b0, b_{1,1..m}, …, b_{J,1..m}]
    pub ma: Vec<f64>,
    /// [c0, c_1..c_K, c_LR, c_MA]
    pub ar: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub net: Option<Mlp>,
    /// Training MSE (of the error / limit) of the network after each epoch; empty for the ARMA
    /// filter and in files written before it was kept.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub history: Vec<f64>,
}

impl HybridModel {
    pub fn n_features(&self) -> usize {
        self.n_temps
    }

    fn n_net_inputs(&self) -> usize {
        match self.variant {
            Variant::Hybrid => 3,
            Variant::LrNn => 1,
            Variant::Fnn => self.n_temps,
            Variant::Arma => 0,
        }
    }

    /// Checks a model read from a file.
    pub fn validate(&self) -> Result<()> {
        let m = self.n_temps;
        let bad = |s: String| Err(Error::Format(format!("hybrid model: {s}")));
        if m == 0 || self.ma_lags == 0 {
            return bad("needs temperatures and at least one MA lag".into());
        }
        let state = self.ma_lags.saturating_mul(m).saturating_add(self.ar_lags);
        if state > crate::artifact::MAX_STATE_VALUES {
            return bad(format!(
                "{} MA lags over {m} temperatures and {} AR lags would keep {state} values per run (at most {})",
                self.ma_lags,
                self.ar_lags,
                crate::artifact::MAX_STATE_VALUES
            ));
        }
        if Some(self.lr.len()) != m.checked_add(1)
            || Some(self.ma.len()) != self.ma_lags.checked_mul(m).and_then(|v| v.checked_add(1))
        {
            return bad("LR or MA coefficient count does not match".into());
        }
        if Some(self.ar.len()) != self.ar_lags.checked_add(3) {
            return bad("AR coefficient count does not match".into());
        }
        for (name, v) in [("lr", &self.lr), ("ma", &self.ma), ("ar", &self.ar)] {
            crate::samples::require_finite_model("hybrid", name, v)?;
        }
        crate::samples::require_finite_model("hybrid", "c_y", &[self.c_y])?;
        match (&self.net, self.variant) {
            (None, Variant::Arma) => Ok(()),
            (Some(net), v) if v != Variant::Arma => {
                net.validate().map_err(Error::Format)?;
                if net.n_inputs() != self.n_net_inputs() {
                    return bad(format!(
                        "the network takes {} inputs, the variant gives {}",
                        net.n_inputs(),
                        self.n_net_inputs()
                    ));
                }
                Ok(())
            }
            _ => bad("network presence does not match the variant".into()),
        }
    }

    /// The three filter outputs at one step, given the current temperatures, the J previous
    /// temperature rows (most recent first) and the K previous outputs (most recent first).
    fn filters(&self, t: &[f64], past_t: &[f64], past_y: &[f64]) -> [f64; 3] {
        let m = self.n_temps;
        let mut y1 = self.lr[0];
        for i in 0..m {
            y1 += self.lr[i + 1] * t[i];
        }
        let mut y2 = self.ma[0];
        for j in 0..self.ma_lags {
            for i in 0..m {
                y2 += self.ma[1 + j * m + i] * past_t[j * m + i];
            }
        }
        let mut y3 = self.ar[0];
        for k in 0..self.ar_lags {
            y3 += self.ar[1 + k] * past_y[k];
        }
        y3 += self.ar[1 + self.ar_lags] * y1 + self.ar[2 + self.ar_lags] * y2;
        [y1, y2, y3]
    }

    /// The model's output from the filters (or the temperatures, for the FNN).
    fn output(&self, t: &[f64], f: [f64; 3], scratch: &mut [f64]) -> f64 {
        let Some(net) = &self.net else {
            return f[2];
        };
        let k = self.n_net_inputs();
        let (x, s) = scratch.split_at_mut(k);
        match self.variant {
            Variant::Hybrid => {
                for j in 0..3 {
                    x[j] = self.c_y * f[j];
                }
            }
            Variant::LrNn => x[0] = self.c_y * f[0],
            Variant::Fnn => {
                for i in 0..k {
                    x[i] = self.c_y * t[i];
                }
            }
            Variant::Arma => {}
        }
        net.predict_one(x, s)
    }

    /// Predicts a run: closed loop, or one step ahead from the measured errors.
    pub fn predict(&self, temps: &[f64], measured: Option<&[f64]>) -> Result<Vec<f64>> {
        let mut st = HybridState::new(self);
        crate::sequence::run_series("hybrid", temps, self.n_temps, measured, |row, prev| {
            st.push(self, row, prev)
        })
    }
}

/// The streaming state over one run: the last J temperature rows and K outputs.
#[derive(Clone, Debug)]
pub struct HybridState {
    m: usize,
    past_t: Vec<f64>,
    past_y: Vec<f64>,
    started: bool,
    scratch: Vec<f64>,
}

impl HybridState {
    pub fn new(model: &HybridModel) -> Self {
        let m = model.n_temps;
        HybridState {
            m,
            past_t: vec![0.0; model.ma_lags * m],
            past_y: vec![0.0; model.ar_lags],
            started: false,
            scratch: vec![
                0.0;
                model.n_net_inputs() + model.net.as_ref().map_or(0, |n| n.scratch_len())
            ],
        }
    }

    pub fn reset(&mut self) {
        self.started = false;
    }

    /// The next sample's temperatures (and the measured error of the previous sample, if known);
    /// returns this sample's predicted error. Allocates nothing.
    pub fn push(
        &mut self,
        model: &HybridModel,
        temps: &[f64],
        measured_prev: Option<f64>,
    ) -> Result<f64> {
        let m = self.m;
        crate::sequence::check_step(temps, m, measured_prev)?;
        if !self.started {
            // missing lags: the first sample's temperatures and an error of 0
            for j in 0..model.ma_lags {
                self.past_t[j * m..(j + 1) * m].copy_from_slice(temps);
            }
            self.past_y.iter_mut().for_each(|v| *v = 0.0);
            self.started = true;
        } else if let Some(y) = measured_prev {
            // the previous output slot holds the model's own value: the measurement replaces it
            if let Some(first) = self.past_y.first_mut() {
                *first = y;
            }
        }
        let f = model.filters(temps, &self.past_t, &self.past_y);
        let out = model.output(temps, f, &mut self.scratch);
        // shift the lags: this sample becomes the most recent
        if model.ma_lags > 0 {
            self.past_t.copy_within(..(model.ma_lags - 1) * m, m);
            self.past_t[..m].copy_from_slice(temps);
        }
        if model.ar_lags > 0 {
            self.past_y.copy_within(..model.ar_lags - 1, 1);
            self.past_y[0] = out;
        }
        Ok(out)
    }
}

/// Hyper-parameters of a filter model; a consuming builder with seed 000's defaults, checked by
/// [`HybridParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub struct HybridParams(HybridValidParams);

/// Checked hyper-parameters; [`HybridValidParams::fit`] fits the filters and the network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HybridValidParams {
    pub variant: Variant,
    pub ma_lags: usize,
    pub ar_lags: usize,
    pub c_y: f64,
    /// Output limit of the network's tanh output, in the error's units.
    pub limit: f64,
    /// The network (its `output_scale` is replaced by `limit`).
    pub net: BpValidParams,
}

impl Default for HybridParams {
    /// The hybrid variant with 1 MA and 2 AR lags, C_Y = 0.02, outputs within ±50; a network of
    /// 30 tanh units with a tanh output, initial weights in [−0.5, 0.5], trained by Adam (lr 0.01)
    /// for at most 10 000 epochs with an MSE goal of 0, patience 500, seed 0, and the large-n
    /// rule of [`BpParams::default`] ([`BpValidParams::large_n`]).
    fn default() -> Self {
        let net = BpParams::new()
            .hidden_sizes(vec![30])
            .hidden_activation(Act::Tanh)
            .output_activation(Act::Tanh)
            .init(0.5)
            .max_epochs(10_000)
            .goal(Some(0.0));
        HybridParams(HybridValidParams {
            variant: Variant::Hybrid,
            ma_lags: 1,
            ar_lags: 2,
            c_y: 0.02,
            limit: 50.0,
            net: net.0,
        })
    }
}

impl HybridParams {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn variant(mut self, variant: Variant) -> Self {
        self.0.variant = variant;
        self
    }

    /// Previous temperature rows of the MA filter, >= 1.
    pub fn ma_lags(mut self, ma_lags: usize) -> Self {
        self.0.ma_lags = ma_lags;
        self
    }

    /// Previous errors of the AR filter.
    pub fn ar_lags(mut self, ar_lags: usize) -> Self {
        self.0.ar_lags = ar_lags;
        self
    }

    /// Scale of the network's inputs, > 0.
    pub fn c_y(mut self, c_y: f64) -> Self {
        self.0.c_y = c_y;
        self
    }

    /// Limit of the network's output in the error's units, > 0.
    pub fn limit(mut self, limit: f64) -> Self {
        self.0.limit = limit;
        self
    }

    /// Adjusts the network, starting from this model's: `.net(|n| n.hidden_sizes(vec![8]))`.
    pub fn net(mut self, f: impl FnOnce(BpParams) -> BpParams) -> Self {
        self.0.net = f(BpParams(self.0.net)).0;
        self
    }

    /// Validates everything that does not depend on the data (the network's parameters only
    /// when the variant has a network).
    pub fn check(self) -> Result<HybridValidParams> {
        let mut p = self.0;
        if p.ma_lags == 0 {
            return Err(Error::param("ma_lags", "must be >= 1"));
        }
        if !(p.c_y.is_finite() && p.c_y > 0.0) {
            return Err(Error::param("c_y", format!("must be > 0, got {}", p.c_y)));
        }
        if !(p.limit.is_finite() && p.limit > 0.0) {
            return Err(Error::param(
                "limit",
                format!("must be > 0, got {}", p.limit),
            ));
        }
        if p.variant != Variant::Arma {
            p.net = BpParams(p.net).output_scale(1.0).check()?;
        }
        Ok(p)
    }
}

#[cfg(feature = "fit")]
impl HybridValidParams {
    /// Fits on one or more runs stacked in `temps`/`y`; `starts` lists the first row of every run
    /// after the first (lags never cross a run boundary).
    pub fn fit(
        &self,
        temps: crate::samples::Samples<'_>,
        y: &[f64],
        starts: &[usize],
    ) -> Result<HybridModel> {
        use crate::linalg::lstsq;
        temps.require_finite("X")?;
        crate::samples::check_target(y, temps.nrows())?;
        let (n, m) = (temps.nrows(), temps.ncols());
        let mut run_start = vec![0usize; n];
        let mut bounds: Vec<usize> = starts.to_vec();
        bounds.sort_unstable();
        if bounds.iter().any(|&s| s == 0 || s >= n) {
            return Err(Error::param(
                "starts",
                "run starts must lie inside the data",
            ));
        }
        for k in 0..n {
            run_start[k] = bounds.iter().rev().find(|&&s| s <= k).copied().unwrap_or(0);
        }
        let lag = self.ma_lags.max(self.ar_lags);
        let rows: Vec<usize> = (0..n).filter(|&k| k - run_start[k] >= lag).collect();
        if rows.len() < m * self.ma_lags + self.ar_lags + 4 {
            return Err(Error::Shape(format!(
                "{} usable samples are too few for {m} temperatures with {} MA and {} AR lags",
                rows.len(),
                self.ma_lags,
                self.ar_lags
            )));
        }
        let design = |cols: usize, f: &dyn Fn(usize, &mut [f64])| -> faer::Mat<f64> {
            let mut a = faer::Mat::zeros(rows.len(), cols);
            let mut buf = vec![0.0; cols];
            for (r, &k) in rows.iter().enumerate() {
                f(k, &mut buf);
                for (c, v) in buf.iter().enumerate() {
                    a[(r, c)] = *v;
                }
            }
            a
        };
        let yt: Vec<f64> = rows.iter().map(|&k| y[k]).collect();
        let lr = lstsq(
            design(1 + m, &|k, b| {
                b[0] = 1.0;
                b[1..].copy_from_slice(temps.row(k));
            })
            .as_ref(),
            &yt,
        )?;
        let jm = self.ma_lags * m;
        let ma = lstsq(
            design(1 + jm, &|k, b| {
                b[0] = 1.0;
                for j in 0..self.ma_lags {
                    b[1 + j * m..1 + (j + 1) * m].copy_from_slice(temps.row(k - j - 1));
                }
            })
            .as_ref(),
            &yt,
        )?;
        let lr_out = |k: usize| lr[0] + (0..m).map(|i| lr[i + 1] * temps.get(k, i)).sum::<f64>();
        let ma_out = |k: usize| {
            let mut s = ma[0];
            for j in 0..self.ma_lags {
                for i in 0..m {
                    s += ma[1 + j * m + i] * temps.get(k - j - 1, i);
                }
            }
            s
        };
        let kk = self.ar_lags;
        let ar = lstsq(
            design(3 + kk, &|k, b| {
                b[0] = 1.0;
                for l in 0..kk {
                    b[1 + l] = y[k - l - 1];
                }
                b[1 + kk] = lr_out(k);
                b[2 + kk] = ma_out(k);
            })
            .as_ref(),
            &yt,
        )?;
        let mut model = HybridModel {
            variant: self.variant,
            n_temps: m,
            ma_lags: self.ma_lags,
            ar_lags: kk,
            c_y: self.c_y,
            lr,
            ma,
            ar,
            net: None,
            history: Vec::new(),
        };
        if self.variant != Variant::Arma {
            let k_in = model.n_net_inputs();
            let mut xs = Vec::with_capacity(rows.len() * k_in);
            let mut past_t = vec![0.0; jm];
            let mut past_y = vec![0.0; kk];
            for &k in &rows {
                for j in 0..self.ma_lags {
                    past_t[j * m..(j + 1) * m].copy_from_slice(temps.row(k - j - 1));
                }
                for l in 0..kk {
                    past_y[l] = y[k - l - 1];
                }
                let f = model.filters(temps.row(k), &past_t, &past_y);
                match self.variant {
                    Variant::Hybrid => xs.extend(f.iter().map(|v| self.c_y * v)),
                    Variant::LrNn => xs.push(self.c_y * f[0]),
                    Variant::Fnn => xs.extend(temps.row(k).iter().map(|v| self.c_y * v)),
                    Variant::Arma => {}
                }
            }
            let targets: Vec<f64> = yt.iter().map(|v| v / self.limit).collect();
            let largest = yt.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if largest >= self.limit {
                return Err(Error::param(
                    "limit",
                    format!(
                        "the error reaches ±{largest} but the network's output is limited to ±{}",
                        self.limit
                    ),
                ));
            }
            let tr = self.net.train(
                crate::samples::Samples::new(&xs, rows.len(), k_in)?,
                &targets,
            )?;
            let mut net = tr.net;
            net.output_scale = self.limit;
            model.history = tr.history;
            model.net = Some(net);
        }
        Ok(model)
    }
}

#[cfg(all(test, feature = "fit"))]
mod tests {
    use super::*;
    use crate::nn::Trainer;

    fn data(n: usize) -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..n)
            .flat_map(|k| {
                let s = k as f64 / 20.0;
                [
                    20.0 + 6.0 * (1.0 - (-s).exp()),
                    20.0 + 3.0 * (s * 0.7).sin().abs(),
                ]
            })
            .collect();
        let mut y = vec![0.0; n];
        for k in 1..n {
            y[k] = 0.6 * y[k - 1] + 1.2 * (t[2 * k] - 20.0) + 0.8 * (t[2 * k - 1] - 20.0);
        }
        (t, y)
    }

    fn params(variant: Variant) -> HybridParams {
        HybridParams::new()
            .variant(variant)
            .ma_lags(1)
            .ar_lags(2)
            .c_y(0.02)
            .limit(50.0)
            .net(|n| {
                n.hidden_sizes(vec![10])
                    .init(0.5)
                    .trainer(Trainer::Adam)
                    .lr(0.01)
                    .max_epochs(1500)
                    .goal(Some(1e-7))
                    .patience(300)
                    .seed(2)
            })
    }

    #[test]
    fn streaming_equals_batch_for_every_variant() {
        let (t, y) = data(120);
        let s = crate::samples::Samples::new(&t, 120, 2).unwrap();
        for v in [Variant::Hybrid, Variant::Arma, Variant::LrNn, Variant::Fnn] {
            let model = params(v).check().unwrap().fit(s, &y, &[]).unwrap();
            model.validate().unwrap();
            assert_eq!(model.history.is_empty(), v == Variant::Arma);
            let closed = model.predict(&t, None).unwrap();
            let one = model.predict(&t, Some(&y)).unwrap();
            let mut st = HybridState::new(&model);
            for k in 0..120 {
                assert_eq!(
                    st.push(&model, &t[2 * k..2 * k + 2], None).unwrap(),
                    closed[k]
                );
            }
            let back: HybridModel =
                serde_json::from_str(&serde_json::to_string(&model).unwrap()).unwrap();
            assert_eq!(back.predict(&t, Some(&y)).unwrap(), one);
            assert_eq!(back.history, model.history);
        }
        // one step ahead, the ARMA filter follows this autoregressive process closely (its LR and
        // MA outputs are least-squares fits, not the process's exact terms, so not exactly)
        let arma = params(Variant::Arma)
            .check()
            .unwrap()
            .fit(s, &y, &[])
            .unwrap();
        let one = arma.predict(&t, Some(&y)).unwrap();
        let n = y.len() as f64;
        let mean = y.iter().sum::<f64>() / n;
        let sd = (y.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt();
        let rms = (one[3..]
            .iter()
            .zip(&y[3..])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            / (n - 3.0))
            .sqrt();
        assert!(rms < 0.05 * sd, "rms {rms} vs sd {sd}");
    }

    #[test]
    fn refuses_errors_beyond_the_limit_and_bad_starts() {
        let (t, y) = data(60);
        let s = crate::samples::Samples::new(&t, 60, 2).unwrap();
        let p = params(Variant::Hybrid).limit(1.0).check().unwrap();
        assert!(p.fit(s, &y, &[]).is_err());
        let p = params(Variant::Hybrid).check().unwrap();
        assert!(p.fit(s, &y, &[60]).is_err());
        assert!(params(Variant::Hybrid).ma_lags(0).check().is_err());
        assert!(params(Variant::Hybrid).c_y(0.0).check().is_err());
        // the ARMA filter has no network, so its network's parameters are not checked
        assert!(params(Variant::Hybrid).net(|n| n.lr(0.0)).check().is_err());
        assert!(params(Variant::Arma).net(|n| n.lr(0.0)).check().is_ok());
    }

    #[test]
    fn names_parse_as_serde_reads_them() {
        crate::error::assert_names_agree(&Variant::NAMES);
    }

    #[test]
    fn autotraits() {
        fn is_send_sync<T: Send + Sync>() {}
        is_send_sync::<HybridParams>();
        is_send_sync::<HybridValidParams>();
        is_send_sync::<HybridModel>();
    }
}
