//! A small dense feed-forward network with one output, as seeds 000 and 002 use: sigmoid or tanh
//! hidden layers, a sigmoid, tanh or linear output scaled by `output_scale` (seed 000 limits its
//! tanh output to ±50 µm), trained on the batch mean squared error.
//!
//! Trainers: the seeds' batch gradient descent with momentum (learning rate, momentum, an epoch
//! cap and an MSE goal, as MATLAB's `traingdm`), and Adam (Kingma & Ba 2015) on the same batch
//! objective, stopped at the goal or when the training MSE has not improved by 1e-6 (relative)
//! for `patience` epochs. Initial weights are uniform in [−r, r] from a seeded ChaCha8 stream.

// index loops read like the backpropagation formulas they implement
#![allow(clippy::needless_range_loop)]

use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::{parse_name, Error, Result};
#[cfg(feature = "fit")]
use crate::samples::{check_target, Samples};

/// Activation of a layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Act {
    Sigmoid,
    Tanh,
    Linear,
}

impl FromStr for Act {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_name("activation", s, &Self::NAMES)
    }
}

impl Act {
    const NAMES: [(&'static str, Act); 3] = [
        ("sigmoid", Act::Sigmoid),
        ("tanh", Act::Tanh),
        ("linear", Act::Linear),
    ];

    #[inline]
    fn f(self, v: f64) -> f64 {
        match self {
            Act::Sigmoid => 1.0 / (1.0 + (-v).exp()),
            Act::Tanh => v.tanh(),
            Act::Linear => v,
        }
    }

    /// Derivative expressed through the activation's value a = f(v).
    #[cfg(feature = "fit")]
    #[inline]
    fn df(self, a: f64) -> f64 {
        match self {
            Act::Sigmoid => a * (1.0 - a),
            Act::Tanh => 1.0 - a * a,
            Act::Linear => 1.0,
        }
    }
}

/// A fitted network: `sizes` = [inputs, hidden..., 1]; layer l maps sizes[l] → sizes[l+1] with
/// `weights[l]` (row-major, sizes[l+1] × sizes[l]) and `biases[l]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mlp {
    pub sizes: Vec<usize>,
    pub hidden: Act,
    pub output: Act,
    pub output_scale: f64,
    pub weights: Vec<Vec<f64>>,
    pub biases: Vec<Vec<f64>>,
}

impl Mlp {
    pub fn n_inputs(&self) -> usize {
        self.sizes[0]
    }

    /// Length of the scratch buffer [`Mlp::predict_one`] needs.
    pub fn scratch_len(&self) -> usize {
        2 * self.sizes.iter().copied().max().unwrap_or(1)
    }

    /// Checks the shapes (a model read from a file).
    pub fn validate(&self) -> std::result::Result<(), String> {
        let l = self.sizes.len();
        if l < 2 || self.sizes[l - 1] != 1 || self.sizes.contains(&0) {
            return Err(format!(
                "network sizes {:?}: need [inputs, hidden..., 1]",
                self.sizes
            ));
        }
        if self.weights.len() != l - 1 || self.biases.len() != l - 1 {
            return Err("network: one weight matrix and bias vector per layer".into());
        }
        for k in 0..l - 1 {
            if Some(self.weights[k].len()) != self.sizes[k].checked_mul(self.sizes[k + 1])
                || self.biases[k].len() != self.sizes[k + 1]
            {
                return Err(format!("network layer {k}: wrong weight or bias count"));
            }
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !self.output_scale.is_finite()
            || !self.weights.iter().all(|w| finite(w))
            || !self.biases.iter().all(|b| finite(b))
        {
            return Err("network: weights, biases and output_scale must be finite".into());
        }
        Ok(())
    }

    /// One sample, no allocation (`scratch` of at least [`Mlp::scratch_len`]).
    pub fn predict_one(&self, x: &[f64], scratch: &mut [f64]) -> f64 {
        let w = scratch.len() / 2;
        let (a, b) = scratch.split_at_mut(w);
        a[..x.len()].copy_from_slice(x);
        let last = self.weights.len() - 1;
        let (mut cur, mut nxt) = (a, b);
        for (l, (wm, bs)) in self.weights.iter().zip(&self.biases).enumerate() {
            let (n_in, n_out) = (self.sizes[l], self.sizes[l + 1]);
            let act = if l == last { self.output } else { self.hidden };
            for o in 0..n_out {
                let row = &wm[o * n_in..(o + 1) * n_in];
                let mut s = bs[o];
                for (wv, xv) in row.iter().zip(&cur[..n_in]) {
                    s += wv * xv;
                }
                nxt[o] = act.f(s);
            }
            std::mem::swap(&mut cur, &mut nxt);
        }
        cur[0] * self.output_scale
    }
}

/// Min–max scaling to [0, 1] by a training range; a range of zero width maps to its middle, 0.5.
#[inline]
pub fn scale01(v: f64, lo: f64, hi: f64) -> f64 {
    let span = hi - lo;
    if span > 0.0 {
        (v - lo) / span
    } else {
        0.5
    }
}

/// A BP network regressor on min–max scaled inputs and output (seed 002's "BP alone").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BpModel {
    pub x_min: Vec<f64>,
    pub x_max: Vec<f64>,
    pub y_min: f64,
    pub y_max: f64,
    pub net: Mlp,
    /// Training MSE (on the scaled target) after each epoch; empty in files written before it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub history: Vec<f64>,
}

impl BpModel {
    pub fn n_features(&self) -> usize {
        self.x_min.len()
    }

    /// Checks a model read from a file.
    pub fn validate(&self) -> std::result::Result<(), String> {
        self.net.validate()?;
        if self.x_max.len() != self.x_min.len() || self.net.n_inputs() != self.x_min.len() {
            return Err("bp model: input ranges do not match the network".into());
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(&self.x_min) || !finite(&self.x_max) || !finite(&[self.y_min, self.y_max]) {
            return Err("bp model: scaling ranges must be finite".into());
        }
        Ok(())
    }

    /// Scratch length of [`BpModel::predict_one`].
    pub fn scratch_len(&self) -> usize {
        self.n_features() + self.net.scratch_len()
    }

    /// One sample, no allocation.
    pub fn predict_one(&self, x: &[f64], scratch: &mut [f64]) -> f64 {
        let (xs, s) = scratch.split_at_mut(self.n_features());
        for (j, v) in xs.iter_mut().enumerate() {
            *v = scale01(x[j], self.x_min[j], self.x_max[j]);
        }
        self.net.predict_one(xs, s) * (self.y_max - self.y_min) + self.y_min
    }

    pub fn predict(&self, x: crate::samples::Samples<'_>) -> Result<Vec<f64>> {
        crate::linear::check_features(x.ncols(), self.n_features())?;
        x.require_finite("X")?;
        let mut scratch = vec![0.0; self.scratch_len()];
        crate::samples::require_finite_predictions(
            "bp",
            x.rows()
                .map(|r| self.predict_one(r, &mut scratch))
                .collect(),
        )
    }
}

/// How a network is trained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Trainer {
    /// The seeds' batch gradient descent with momentum: Δ ← momentum·Δ − lr·∇, until MSE ≤ goal
    /// or `max_epochs`.
    #[serde(rename = "seed", alias = "gd")]
    Gd,
    /// Batch Adam (β1 0.9, β2 0.999), until MSE ≤ goal, `max_epochs`, or no relative improvement
    /// of 1e-6 in `patience` epochs.
    #[serde(rename = "adam")]
    Adam,
}

impl Trainer {
    const NAMES: [(&'static str, Trainer); 3] = [
        ("seed", Trainer::Gd),
        ("gd", Trainer::Gd),
        ("adam", Trainer::Adam),
    ];

    /// The MSE goal when none is given: 0.01 for the seed's trainer, 1e-5 for Adam.
    pub fn default_goal(self) -> f64 {
        match self {
            Trainer::Gd => 0.01,
            Trainer::Adam => 1e-5,
        }
    }
}

impl FromStr for Trainer {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_name("trainer", s, &Self::NAMES)
    }
}

/// Hyper-parameters of a BP network and its training; a consuming builder with the defaults of
/// seed 002's network, checked by [`BpParams::check`]. The rolling GM + BP and the hybrid filter
/// models hold one for their network.
#[derive(Clone, Debug, PartialEq)]
pub struct BpParams(pub(crate) BpValidParams);

/// Checked hyper-parameters; [`BpValidParams::fit`] trains a [`BpModel`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BpValidParams {
    /// Hidden layer widths.
    pub hidden_sizes: Vec<usize>,
    pub hidden_activation: Act,
    pub output_activation: Act,
    pub output_scale: f64,
    /// Initial weights and biases uniform in [−init, init].
    pub init: f64,
    pub trainer: Trainer,
    pub lr: f64,
    /// Momentum of the seed's trainer (Adam ignores it).
    pub momentum: f64,
    pub max_epochs: usize,
    /// MSE goal; `None`: [`Trainer::default_goal`].
    pub goal: Option<f64>,
    /// Epochs without improvement after which Adam stops (the seed's trainer ignores it).
    pub patience: usize,
    pub seed: u64,
    /// Rows from which Adam trains by the large-n rule (`None`: never; the seed's trainer never
    /// does): 10 % of the rows held back for validation in ten stretches
    /// ([`large_n_validation`]), mini-batches of [`LARGE_N_BATCH`] rows in an order shuffled by
    /// the seed (ChaCha8, stream 1), at most max([`LARGE_N_MIN_EPOCHS`],
    /// ⌈[`LARGE_N_BUDGET`] / training rows⌉) epochs (and `max_epochs`), stopped at the MSE goal
    /// (of an epoch's mini-batches) or when the validation MSE has not improved by 1e-6
    /// (relative) for min(`patience`, [`LARGE_N_PATIENCE`]) epochs; the network of the lowest
    /// validation MSE is kept, and the history holds each epoch's mean mini-batch MSE.
    #[serde(default)]
    pub large_n: Option<usize>,
}

impl Default for BpParams {
    /// 7 sigmoid hidden units, linear output of scale 1, initial weights in [−1, 1]; Adam with
    /// lr 0.01 (momentum 0.9 for the seed's trainer), at most 8000 epochs, the trainer's MSE goal,
    /// patience 500, seed 0; the large-n rule from [`LARGE_N_DEFAULT`] training rows on (the
    /// seeds' runs, a few hundred rows, never reach it).
    fn default() -> Self {
        BpParams(BpValidParams {
            hidden_sizes: vec![7],
            hidden_activation: Act::Sigmoid,
            output_activation: Act::Linear,
            output_scale: 1.0,
            init: 1.0,
            trainer: Trainer::Adam,
            lr: 0.01,
            momentum: 0.9,
            max_epochs: 8000,
            goal: None,
            patience: 500,
            seed: 0,
            large_n: Some(LARGE_N_DEFAULT),
        })
    }
}

impl BpParams {
    pub fn new() -> Self {
        Self::default()
    }

    /// Hidden layer widths, each >= 1.
    pub fn hidden_sizes(mut self, sizes: Vec<usize>) -> Self {
        self.0.hidden_sizes = sizes;
        self
    }

    pub fn hidden_activation(mut self, act: Act) -> Self {
        self.0.hidden_activation = act;
        self
    }

    pub fn output_activation(mut self, act: Act) -> Self {
        self.0.output_activation = act;
        self
    }

    /// Factor on the output activation (finite, non-zero).
    pub fn output_scale(mut self, scale: f64) -> Self {
        self.0.output_scale = scale;
        self
    }

    /// Half-width of the uniform initial weights, > 0.
    pub fn init(mut self, init: f64) -> Self {
        self.0.init = init;
        self
    }

    pub fn trainer(mut self, trainer: Trainer) -> Self {
        self.0.trainer = trainer;
        self
    }

    /// Learning rate, > 0.
    pub fn lr(mut self, lr: f64) -> Self {
        self.0.lr = lr;
        self
    }

    /// Momentum of the seed's trainer, in [0, 1).
    pub fn momentum(mut self, momentum: f64) -> Self {
        self.0.momentum = momentum;
        self
    }

    pub fn max_epochs(mut self, max_epochs: usize) -> Self {
        self.0.max_epochs = max_epochs;
        self
    }

    /// MSE goal (`None`: the trainer's default).
    pub fn goal(mut self, goal: Option<f64>) -> Self {
        self.0.goal = goal;
        self
    }

    pub fn patience(mut self, patience: usize) -> Self {
        self.0.patience = patience;
        self
    }

    /// Seed of the initial weights (ChaCha8).
    pub fn seed(mut self, seed: u64) -> Self {
        self.0.seed = seed;
        self
    }

    /// Rows from which Adam trains by the large-n rule ([`BpValidParams::large_n`]); `None`:
    /// never. At least [`LARGE_N_MIN`].
    pub fn large_n(mut self, large_n: Option<usize>) -> Self {
        self.0.large_n = large_n;
        self
    }

    /// Validates every parameter (none depends on the data).
    pub fn check(self) -> Result<BpValidParams> {
        let p = self.0;
        if let Some(l) = p.large_n {
            if l < LARGE_N_MIN {
                return Err(Error::param(
                    "large_n",
                    format!("must be >= {LARGE_N_MIN} (or none), got {l}"),
                ));
            }
        }
        if p.hidden_sizes.contains(&0) {
            return Err(Error::param("hidden", "layer widths must be >= 1"));
        }
        if !(p.init > 0.0 && p.init.is_finite()) {
            return Err(Error::param("init", format!("must be > 0, got {}", p.init)));
        }
        if !(p.output_scale.is_finite() && p.output_scale != 0.0) {
            return Err(Error::param("output_scale", "must be finite and non-zero"));
        }
        if p.trainer == Trainer::Gd && !(0.0..1.0).contains(&p.momentum) {
            return Err(Error::param(
                "momentum",
                format!("must be in [0, 1), got {}", p.momentum),
            ));
        }
        if !(p.lr > 0.0 && p.lr.is_finite()) {
            return Err(Error::param("lr", format!("must be > 0, got {}", p.lr)));
        }
        if p.max_epochs == 0 {
            return Err(Error::param("max_epochs", "must be >= 1"));
        }
        Ok(p)
    }
}

/// A trained network and its training record.
#[derive(Clone, Debug)]
pub struct Trained {
    pub net: Mlp,
    /// Training MSE after each epoch.
    pub history: Vec<f64>,
}

/// Rows per mini-batch of the large-n rule.
pub const LARGE_N_BATCH: usize = 128;
/// Sample gradients the large-n rule spends at most: its epoch cap is
/// max([`LARGE_N_MIN_EPOCHS`], ⌈budget / training rows⌉).
pub const LARGE_N_BUDGET: usize = 500_000;
/// Fewest epochs of the large-n rule's cap.
pub const LARGE_N_MIN_EPOCHS: usize = 20;
/// Largest patience (in epochs, on the validation MSE) of the large-n rule.
pub const LARGE_N_PATIENCE: usize = 20;
/// `large_n` of every network ([`BpParams::default`]: BP alone, and the networks of the hybrid
/// filter and of the rolling GM + BP): the seeds' runs have a few hundred rows, a long logged run
/// tens of thousands.
pub const LARGE_N_DEFAULT: usize = 2000;
/// Smallest accepted `large_n`.
pub const LARGE_N_MIN: usize = 100;

/// The rows the large-n rule holds back for validation: the rows are cut into blocks of
/// ⌈n / 100⌉ consecutive rows and every tenth block (the 10th, 20th, …) is held back — 10 % of
/// the rows, in ten stretches spread over the run (neighbouring samples of a run are nearly
/// equal, so single held-back rows would validate on what the network trains on).
pub fn large_n_validation(n: usize, row: usize) -> bool {
    let block = n.div_ceil(100).max(1);
    (row / block) % 10 == 9
}

/// The layout of a network's parameters as one vector (weights of every layer, then biases of
/// every layer: the order of [`params_mut`]) and scratch space for back-propagation.
#[cfg(feature = "fit")]
struct Flat {
    sizes: Vec<usize>,
    hidden: Act,
    output: Act,
    scale: f64,
    woff: Vec<usize>,
    boff: Vec<usize>,
    aoff: Vec<usize>,
    acts: Vec<f64>,
    delta: Vec<f64>,
}

#[cfg(feature = "fit")]
impl Flat {
    fn new(net: &Mlp) -> Self {
        let nl = net.weights.len();
        let mut woff = Vec::with_capacity(nl);
        let mut boff = Vec::with_capacity(nl);
        let mut aoff = Vec::with_capacity(nl + 1);
        let mut o = 0;
        for w in &net.weights {
            woff.push(o);
            o += w.len();
        }
        for b in &net.biases {
            boff.push(o);
            o += b.len();
        }
        let mut a = 0;
        for &s in &net.sizes {
            aoff.push(a);
            a += s;
        }
        Flat {
            sizes: net.sizes.clone(),
            hidden: net.hidden,
            output: net.output,
            scale: net.output_scale,
            woff,
            boff,
            aoff,
            acts: vec![0.0; a],
            delta: vec![0.0; a],
        }
    }

    fn theta(net: &Mlp) -> Vec<f64> {
        flat(net).collect()
    }

    fn store(theta: &[f64], net: &mut Mlp) {
        for (p, v) in params_mut(net).zip(theta) {
            *p = *v;
        }
    }

    /// Forward pass of one row into `self.acts`; the output activation.
    #[inline]
    fn forward(&mut self, theta: &[f64], row: &[f64]) -> f64 {
        let nl = self.sizes.len() - 1;
        self.acts[..row.len()].copy_from_slice(row);
        for l in 0..nl {
            let (n_in, n_out) = (self.sizes[l], self.sizes[l + 1]);
            let act = if l == nl - 1 {
                self.output
            } else {
                self.hidden
            };
            let (lo, hi) = self.acts.split_at_mut(self.aoff[l + 1]);
            let a_in = &lo[self.aoff[l]..];
            let wl = &theta[self.woff[l]..self.woff[l] + n_in * n_out];
            let bl = &theta[self.boff[l]..self.boff[l] + n_out];
            for ((w, b), out) in wl.chunks_exact(n_in).zip(bl).zip(&mut hi[..n_out]) {
                let s = b + w.iter().zip(a_in).map(|(a, b)| a * b).sum::<f64>();
                *out = act.f(s);
            }
        }
        self.acts[self.aoff[nl]]
    }

    /// Sum of squared errors over `rows` (by index into `x`, in order), forward only.
    fn sse(&mut self, theta: &[f64], x: Samples<'_>, y: &[f64], rows: Option<&[usize]>) -> f64 {
        let mut sse = 0.0;
        let mut one = |this: &mut Self, i: usize| {
            let e = this.forward(theta, x.row(i)) * this.scale - y[i];
            sse += e * e;
        };
        match rows {
            None => (0..x.nrows()).for_each(|i| one(self, i)),
            Some(r) => r.iter().for_each(|&i| one(self, i)),
        }
        sse
    }

    /// Gradient of the MSE over `rows` (all rows for `None`) into `grad`; returns the sum of
    /// squared errors. The arithmetic, and its order, of the per-sample loop it replaced.
    fn grad(
        &mut self,
        theta: &[f64],
        x: Samples<'_>,
        y: &[f64],
        rows: Option<&[usize]>,
        grad: &mut [f64],
    ) -> f64 {
        grad.iter_mut().for_each(|g| *g = 0.0);
        let n = rows.map_or(x.nrows(), <[usize]>::len) as f64;
        let mut sse = 0.0;
        let mut one = |this: &mut Self, i: usize| {
            let out = this.forward(theta, x.row(i));
            let e = out * this.scale - y[i];
            sse += e * e;
            this.backward(theta, out, e, n, grad);
        };
        match rows {
            None => (0..x.nrows()).for_each(|i| one(self, i)),
            Some(r) => r.iter().for_each(|&i| one(self, i)),
        }
        sse
    }

    #[inline]
    fn backward(&mut self, theta: &[f64], out: f64, e: f64, n: f64, grad: &mut [f64]) {
        let nl = self.sizes.len() - 1;
        // d(e²)/d(out) = 2e·scale; through the output activation
        self.delta[self.aoff[nl]] = 2.0 * e * self.scale * self.output.df(out) / n;
        for l in (0..nl).rev() {
            let (n_in, n_out) = (self.sizes[l], self.sizes[l + 1]);
            let (a0, a1) = (self.aoff[l], self.aoff[l + 1]);
            let (wo, bo) = (self.woff[l], self.boff[l]);
            let (dlo, dhi) = self.delta.split_at_mut(a1);
            let d_out = &dhi[..n_out];
            let a_in = &self.acts[a0..a1];
            for (o, &d) in d_out.iter().enumerate() {
                grad[bo + o] += d;
                let gw = &mut grad[wo + o * n_in..wo + (o + 1) * n_in];
                for (g, a) in gw.iter_mut().zip(a_in) {
                    *g += d * a;
                }
            }
            if l > 0 {
                let wl = &theta[wo..wo + n_in * n_out];
                for k in 0..n_in {
                    let mut s = 0.0;
                    for o in 0..n_out {
                        s += wl[o * n_in + k] * d_out[o];
                    }
                    dlo[a0 + k] = s * self.hidden.df(a_in[k]);
                }
            }
        }
    }
}

#[cfg(feature = "fit")]
impl BpValidParams {
    /// The initial network of this seed.
    fn init_net(&self, n_inputs: usize) -> Mlp {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(self.seed);
        let mut sizes = vec![n_inputs];
        sizes.extend(&self.hidden_sizes);
        sizes.push(1);
        let r = self.init;
        let mut u = || rng.random_range(-r..=r);
        let weights = (0..sizes.len() - 1)
            .map(|l| (0..sizes[l] * sizes[l + 1]).map(|_| u()).collect())
            .collect();
        let biases = (0..sizes.len() - 1)
            .map(|l| (0..sizes[l + 1]).map(|_| u()).collect())
            .collect();
        Mlp {
            sizes,
            hidden: self.hidden_activation,
            output: self.output_activation,
            output_scale: self.output_scale,
            weights,
            biases,
        }
    }

    /// Whether the large-n rule trains on `n` rows (Adam only).
    pub fn uses_large_n(&self, n: usize) -> bool {
        self.trainer == Trainer::Adam && self.large_n.is_some_and(|l| n >= l)
    }

    /// Trains the network itself on the rows of `x` to the targets `y` (in output units, i.e.
    /// including the scale), with no scaling of its own.
    pub(crate) fn train(&self, x: Samples<'_>, y: &[f64]) -> Result<Trained> {
        x.require_finite("X")?;
        check_target(y, x.nrows())?;
        if self.uses_large_n(x.nrows()) {
            return self.train_large(x, y);
        }
        let mut net = self.init_net(x.ncols());
        let mut fl = Flat::new(&net);
        let mut theta = Flat::theta(&net);
        let mut grad = vec![0.0; theta.len()];
        let n = x.nrows() as f64;
        let (lr, max_epochs) = (self.lr, self.max_epochs);
        let goal = self.goal.unwrap_or(self.trainer.default_goal());
        let history = match self.trainer {
            Trainer::Gd => {
                let momentum = self.momentum;
                let mut vel = vec![0.0; theta.len()];
                let mut hist = Vec::new();
                for _ in 0..max_epochs {
                    crate::interrupt::check()?;
                    let mse = fl.grad(&theta, x, y, None, &mut grad) / n;
                    hist.push(mse);
                    if !mse.is_finite() {
                        return Err(Error::Numerical("the training error diverged".into()));
                    }
                    if mse <= goal {
                        break;
                    }
                    for ((p, v), g) in theta.iter_mut().zip(&mut vel).zip(&grad) {
                        *v = momentum * *v - lr * g;
                        *p += *v;
                    }
                }
                hist
            }
            Trainer::Adam => {
                let patience = self.patience;
                let mut m = vec![0.0; theta.len()];
                let mut v = vec![0.0; theta.len()];
                let mut hist = Vec::new();
                let mut best = f64::INFINITY;
                let mut best_theta = theta.clone();
                let mut since = 0usize;
                for t in 1..=max_epochs {
                    if t % 64 == 0 {
                        crate::interrupt::check()?;
                    }
                    let mse = fl.grad(&theta, x, y, None, &mut grad) / n;
                    hist.push(mse);
                    if !mse.is_finite() {
                        return Err(Error::Numerical("the training error diverged".into()));
                    }
                    if mse < best * (1.0 - 1e-6) {
                        best = mse;
                        best_theta.copy_from_slice(&theta);
                        since = 0;
                    } else {
                        since += 1;
                    }
                    if mse <= goal || since >= patience {
                        break;
                    }
                    adam_step(&mut theta, &mut m, &mut v, &grad, lr, t);
                }
                if fl.sse(&theta, x, y, None) / n > best {
                    theta = best_theta;
                }
                hist
            }
        };
        Flat::store(&theta, &mut net);
        Ok(Trained { net, history })
    }

    /// The large-n rule (module documentation of [`BpValidParams::large_n`]): Adam on seeded
    /// shuffled mini-batches, an epoch cap from a budget of sample gradients, early stopping on
    /// held-back blocks of rows, the network of the lowest validation MSE kept.
    fn train_large(&self, x: Samples<'_>, y: &[f64]) -> Result<Trained> {
        use rand::seq::SliceRandom;
        use rand::SeedableRng;
        let n = x.nrows();
        let (mut train, mut val) = (Vec::new(), Vec::new());
        for i in 0..n {
            if large_n_validation(n, i) {
                val.push(i);
            } else {
                train.push(i);
            }
        }
        let mut net = self.init_net(x.ncols());
        let mut fl = Flat::new(&net);
        let mut theta = Flat::theta(&net);
        let mut grad = vec![0.0; theta.len()];
        let (mut m, mut v) = (vec![0.0; theta.len()], vec![0.0; theta.len()]);
        let goal = self.goal.unwrap_or(self.trainer.default_goal());
        let max_epochs = self
            .max_epochs
            .min(LARGE_N_MIN_EPOCHS.max(LARGE_N_BUDGET.div_ceil(train.len())));
        let patience = self.patience.clamp(1, LARGE_N_PATIENCE);
        // the order of the rows: the model's seed on a stream of its own (the initial weights
        // take stream 0)
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(1);
        let mut best = fl.sse(&theta, x, y, Some(&val)) / val.len() as f64;
        let mut best_theta = theta.clone();
        let mut since = 0usize;
        let mut hist = Vec::new();
        let mut t = 0usize;
        for _ in 0..max_epochs {
            crate::interrupt::check()?;
            train.shuffle(&mut rng);
            let mut sse = 0.0;
            for batch in train.chunks(LARGE_N_BATCH) {
                sse += fl.grad(&theta, x, y, Some(batch), &mut grad);
                t += 1;
                adam_step(&mut theta, &mut m, &mut v, &grad, self.lr, t);
            }
            let mse = sse / train.len() as f64;
            hist.push(mse);
            if !mse.is_finite() {
                return Err(Error::Numerical("the training error diverged".into()));
            }
            let val_mse = fl.sse(&theta, x, y, Some(&val)) / val.len() as f64;
            if val_mse < best * (1.0 - 1e-6) {
                best = val_mse;
                best_theta.copy_from_slice(&theta);
                since = 0;
            } else {
                since += 1;
            }
            if mse <= goal || since >= patience {
                break;
            }
        }
        Flat::store(&best_theta, &mut net);
        Ok(Trained { net, history: hist })
    }

    /// Fits a [`BpModel`]: inputs and target min–max scaled by the training ranges.
    pub fn fit(&self, x: Samples<'_>, y: &[f64]) -> Result<BpModel> {
        x.require_finite("X")?;
        check_target(y, x.nrows())?;
        let d = x.ncols();
        let mut x_min = vec![f64::INFINITY; d];
        let mut x_max = vec![f64::NEG_INFINITY; d];
        for r in x.rows() {
            for j in 0..d {
                x_min[j] = x_min[j].min(r[j]);
                x_max[j] = x_max[j].max(r[j]);
            }
        }
        let y_min = y.iter().copied().fold(f64::INFINITY, f64::min);
        let y_max = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let xs: Vec<f64> = x
            .rows()
            .flat_map(|r| (0..d).map(move |j| (j, r[j])))
            .map(|(j, v)| scale01(v, x_min[j], x_max[j]))
            .collect();
        let ys: Vec<f64> = y.iter().map(|&v| scale01(v, y_min, y_max)).collect();
        let t = self.train(Samples::new(&xs, y.len(), d)?, &ys)?;
        Ok(BpModel {
            x_min,
            x_max,
            y_min,
            y_max,
            net: t.net,
            history: t.history,
        })
    }
}

/// One Adam step (β1 0.9, β2 0.999, ε 1e-8) at step `t` (from 1).
#[cfg(feature = "fit")]
#[inline]
fn adam_step(theta: &mut [f64], m: &mut [f64], v: &mut [f64], grad: &[f64], lr: f64, t: usize) {
    let (b1, b2, eps) = (0.9f64, 0.999f64, 1e-8);
    let (c1, c2) = (1.0 - b1.powi(t as i32), 1.0 - b2.powi(t as i32));
    for (((p, mm), vv), &g) in theta.iter_mut().zip(m).zip(v).zip(grad) {
        *mm = b1 * *mm + (1.0 - b1) * g;
        *vv = b2 * *vv + (1.0 - b2) * g * g;
        *p -= lr * (*mm / c1) / ((*vv / c2).sqrt() + eps);
    }
}

#[cfg(feature = "fit")]
fn params_mut(net: &mut Mlp) -> impl Iterator<Item = &mut f64> {
    net.weights
        .iter_mut()
        .chain(net.biases.iter_mut())
        .flat_map(|v| v.iter_mut())
}

#[cfg(feature = "fit")]
fn flat(net: &Mlp) -> impl Iterator<Item = f64> + '_ {
    net.weights
        .iter()
        .chain(net.biases.iter())
        .flat_map(|v| v.iter().copied())
}

/// Batch MSE = mean((ŷ − y)²) and its gradient (as an `Mlp` holding the partial derivatives).
#[cfg(feature = "fit")]
pub fn mse_grad(net: &Mlp, x: Samples<'_>, y: &[f64]) -> (f64, Mlp) {
    let mut fl = Flat::new(net);
    let theta = Flat::theta(net);
    let mut g = vec![0.0; theta.len()];
    let sse = fl.grad(&theta, x, y, None, &mut g);
    let mut grad = net.clone();
    Flat::store(&g, &mut grad);
    (sse / x.nrows() as f64, grad)
}

#[cfg(all(test, feature = "fit"))]
mod tests {
    use super::*;

    fn params(trainer: Trainer) -> BpParams {
        BpParams::new()
            .hidden_sizes(vec![7])
            .init(1.0)
            .trainer(trainer)
            .seed(3)
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let x: Vec<f64> = (0..20)
            .flat_map(|i| [i as f64 / 10.0, (i as f64).sin()])
            .collect();
        let y: Vec<f64> = x.chunks(2).map(|r| r[0] * r[1] + 0.3).collect();
        let s = Samples::new(&x, 20, 2).unwrap();
        for (hidden, output, scale) in [
            (Act::Sigmoid, Act::Linear, 1.0),
            (Act::Tanh, Act::Tanh, 50.0),
        ] {
            let p = params(Trainer::Gd)
                .lr(0.01)
                .momentum(0.9)
                .max_epochs(1)
                .goal(Some(0.0))
                .hidden_activation(hidden)
                .output_activation(output)
                .output_scale(scale)
                .hidden_sizes(vec![5, 3])
                .check()
                .unwrap();
            let net = p.init_net(2);
            let (_, g) = mse_grad(&net, s, &y);
            let analytic: Vec<f64> = flat(&g).collect();
            let n_params = analytic.len();
            for k in 0..n_params {
                let h = 1e-6;
                let mut a = net.clone();
                *params_mut(&mut a).nth(k).unwrap() += h;
                let mut b = net.clone();
                *params_mut(&mut b).nth(k).unwrap() -= h;
                let fd = (mse_grad(&a, s, &y).0 - mse_grad(&b, s, &y).0) / (2.0 * h);
                let rel = (fd - analytic[k]).abs() / analytic[k].abs().max(1e-3);
                assert!(rel < 1e-6, "param {k}: fd {fd} vs {}", analytic[k]);
            }
        }
    }

    #[test]
    fn trainers_fit_a_smooth_function_and_are_deterministic() {
        let x: Vec<f64> = (0..40).map(|i| i as f64 / 39.0).collect();
        let y: Vec<f64> = x.iter().map(|v| (3.0 * v).sin()).collect();
        let s = Samples::new(&x, 40, 1).unwrap();
        let adam = params(Trainer::Adam)
            .lr(0.05)
            .max_epochs(5000)
            .goal(Some(1e-4))
            .patience(500)
            .check()
            .unwrap();
        let a = adam.train(s, &y).unwrap();
        // measured: reaches the 1e-4 goal in about 1–2 thousand epochs
        assert!(
            *a.history.last().unwrap() <= 1e-4 * 1.01,
            "{:?}",
            a.history.last()
        );
        let b = adam.train(s, &y).unwrap();
        assert_eq!(a.net, b.net);
        let gd = params(Trainer::Gd)
            .lr(0.5)
            .momentum(0.9)
            .max_epochs(3000)
            .goal(Some(1e-3))
            .check()
            .unwrap()
            .train(s, &y)
            .unwrap();
        assert!(*gd.history.last().unwrap() < 1e-2);
        let mut scratch = vec![0.0; a.net.scratch_len()];
        let p = a.net.predict_one(&[0.5], &mut scratch);
        assert!((p - 1.5f64.sin()).abs() < 0.05);
    }

    #[test]
    fn large_n_holds_back_ten_stretches_of_rows() {
        for n in [100, 2000, 9_990, 10_001] {
            let held: Vec<usize> = (0..n).filter(|&i| large_n_validation(n, i)).collect();
            // whole blocks of consecutive rows, every tenth: about 10 %
            assert!(
                (held.len() as f64 / n as f64 - 0.1).abs() < 0.02,
                "{n}: {}",
                held.len()
            );
            let stretches = 1 + held.windows(2).filter(|w| w[1] != w[0] + 1).count();
            assert_eq!(stretches, 10, "{n}");
        }
    }

    #[test]
    fn large_n_rule_trains_on_mini_batches_deterministically() {
        let n = 3000;
        let x: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| (3.0 * v).sin() + 0.01 * ((i * 7919) % 13) as f64 / 13.0)
            .collect();
        let s = Samples::new(&x, n, 1).unwrap();
        let p = |large: Option<usize>| {
            params(Trainer::Adam)
                .lr(0.01)
                .max_epochs(4000)
                .goal(Some(0.0))
                .patience(500)
                .large_n(large)
                .check()
                .unwrap()
        };
        let big = p(Some(2000));
        assert!(big.uses_large_n(n) && !big.uses_large_n(n - 1001));
        let a = big.train(s, &y).unwrap();
        let cap = LARGE_N_MIN_EPOCHS.max(LARGE_N_BUDGET.div_ceil(n - 300));
        assert!(!a.history.is_empty() && a.history.len() <= cap);
        let b = big.train(s, &y).unwrap();
        assert_eq!((a.net.clone(), a.history.clone()), (b.net, b.history));
        // the network fits the curve about as well as 4000 full-batch epochs
        let full = p(None).train(s, &y).unwrap();
        assert_eq!(full.history.len(), 4000);
        let mse = |net: &Mlp| mse_grad(net, s, &y).0;
        assert!(
            mse(&a.net) < 2.0 * mse(&full.net).max(1e-4),
            "{} vs {}",
            mse(&a.net),
            mse(&full.net)
        );
        // the seed's trainer never takes the rule
        let gd = params(Trainer::Gd).large_n(Some(2000)).check().unwrap();
        assert!(!gd.uses_large_n(n));
        assert!(params(Trainer::Adam).large_n(Some(99)).check().is_err());
    }

    #[test]
    fn bp_model_keeps_its_history_through_json() {
        let x: Vec<f64> = (0..30).map(|i| i as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| (v / 9.0).sin()).collect();
        let s = Samples::new(&x, 30, 1).unwrap();
        let m = params(Trainer::Gd)
            .max_epochs(50)
            .goal(Some(0.0))
            .check()
            .unwrap()
            .fit(s, &y)
            .unwrap();
        assert_eq!(m.history.len(), 50);
        let back: BpModel = serde_json::from_str(&serde_json::to_string(&m).unwrap()).unwrap();
        assert_eq!(back, m);
        // a file written before the history was kept still loads
        let mut old = serde_json::to_value(&m).unwrap();
        old.as_object_mut().unwrap().remove("history");
        let old: BpModel = serde_json::from_value(old).unwrap();
        assert!(old.history.is_empty());
    }

    #[test]
    fn bad_params_are_refused() {
        assert!(BpParams::new().hidden_sizes(vec![3, 0]).check().is_err());
        assert!(BpParams::new().lr(0.0).check().is_err());
        assert!(BpParams::new().max_epochs(0).check().is_err());
        // momentum only matters to the seed's trainer
        assert!(BpParams::new().momentum(1.0).check().is_ok());
        assert!(BpParams::new()
            .trainer(Trainer::Gd)
            .momentum(1.0)
            .check()
            .is_err());
    }

    #[test]
    fn names_parse_as_serde_reads_them() {
        crate::error::assert_names_agree(&Act::NAMES);
        crate::error::assert_names_agree(&Trainer::NAMES);
        let e = "lbfgs".parse::<Trainer>().unwrap_err().to_string();
        assert!(
            e.contains("`trainer`") && e.contains(r#""adam", got "lbfgs""#),
            "{e}"
        );
    }

    #[test]
    fn autotraits() {
        fn is_send_sync<T: Send + Sync>() {}
        is_send_sync::<BpParams>();
        is_send_sync::<BpValidParams>();
        is_send_sync::<BpModel>();
    }
}
