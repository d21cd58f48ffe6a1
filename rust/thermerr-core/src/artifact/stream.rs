//! A loaded model file with its per-run state: what `thermerr-edge` runs sample by sample.

use super::{Artifact, HistoryState, Inputs, Model, Preprocessing};
use crate::error::{Error, Result};
use crate::grey::GreyState;
use crate::hybrid::HybridState;

/// Per-run state and scratch space of a model, sized at load time.
#[derive(Clone, Debug)]
enum ModelState {
    None,
    Scratch(Vec<f64>),
    Grey(Box<GreyState>),
    Hybrid(Box<HybridState>),
}

impl ModelState {
    fn new(m: &Model) -> Self {
        match m {
            Model::Bp(b) => ModelState::Scratch(vec![0.0; b.scratch_len()]),
            Model::GreyBp(g) | Model::Gm1n(g) => ModelState::Grey(Box::new(GreyState::new(g))),
            Model::Hybrid(h) => ModelState::Hybrid(Box::new(HybridState::new(h))),
            _ => ModelState::None,
        }
    }

    fn reset(&mut self) {
        match self {
            ModelState::Grey(s) => s.reset(),
            ModelState::Hybrid(s) => s.reset(),
            _ => {}
        }
    }
}

/// One sample through the family's own predict code (no allocation on success).
#[inline]
fn predict_model(
    model: &Model,
    state: &mut ModelState,
    x: &[f64],
    measured_prev: Option<f64>,
) -> Result<f64> {
    Ok(match (model, state) {
        (Model::Mlr(m), _) => m.predict_one(x),
        (Model::Rbf(m), _) => m.predict_one(x),
        (Model::Svr(m), _) => m.predict_one(x),
        (Model::Bp(m), ModelState::Scratch(s)) => m.predict_one(x, s),
        (Model::GreyBp(m) | Model::Gm1n(m), ModelState::Grey(s)) => s.push(m, x, measured_prev)?,
        (Model::Hybrid(m), ModelState::Hybrid(s)) => s.push(m, x, measured_prev)?,
        _ => return Err(Error::Format("model state does not match its kind".into())),
    })
}

/// A prediction that is a finite number, or the error naming the model (no allocation on
/// success).
#[inline]
fn finite(kind: &str, y: f64) -> Result<f64> {
    if y.is_finite() {
        Ok(y)
    } else {
        Err(crate::samples::non_finite_prediction(kind, None, y))
    }
}

/// A validated model file with its per-run state (inputs as rises, 1-AGO accumulation, the
/// grey and filter models' past outputs), in buffers sized when it is built.
#[derive(Clone, Debug)]
pub struct Predictor {
    artifact: Artifact,
    // per-run state
    first: Vec<f64>,
    have_first: bool,
    /// the rise reference was given ([`Predictor::set_reference`]) and outlives a reset
    fixed_first: bool,
    /// the readings after the rise, before the history is added (the model's inputs without one)
    raw: Vec<f64>,
    history: Option<HistoryState>,
    acc: Vec<f64>,
    y1_prev: f64,
    buf: Vec<f64>,
    state: ModelState,
}

impl Predictor {
    pub fn new(artifact: Artifact) -> Self {
        let n = artifact.n_features();
        let n_in = artifact.header.n_inputs(n);
        Predictor {
            state: ModelState::new(&artifact.model),
            history: artifact
                .header
                .history
                .as_ref()
                .map(|h| HistoryState::new(h, n_in)),
            artifact,
            first: vec![0.0; n_in],
            have_first: false,
            fixed_first: false,
            raw: vec![0.0; n_in],
            acc: vec![0.0; n],
            y1_prev: 0.0,
            buf: vec![0.0; n],
        }
    }

    /// Reads and validates the text of a model file.
    pub fn from_json(text: &str) -> Result<Self> {
        Ok(Self::new(Artifact::from_json(text)?))
    }

    pub fn artifact(&self) -> &Artifact {
        &self.artifact
    }

    pub fn model(&self) -> &Model {
        &self.artifact.model
    }

    pub fn kind(&self) -> &'static str {
        self.artifact.model.kind()
    }

    /// The model's inputs per sample (with a history: the readings and their rises).
    pub fn n_features(&self) -> usize {
        self.buf.len()
    }

    /// The readings a sample holds: one per feature column (`features`).
    pub fn n_inputs(&self) -> usize {
        self.raw.len()
    }

    /// The run columns the model reads, in order (if it was fitted on a run).
    pub fn features(&self) -> Option<&[String]> {
        self.artifact.header.features.as_deref()
    }

    /// The error column the model predicts (e.g. `E_z`), if recorded.
    pub fn target(&self) -> Option<&str> {
        self.artifact.header.target.as_deref()
    }

    /// Whether predictions depend on earlier samples of the run.
    pub fn stateful(&self) -> bool {
        let h = &self.artifact.header;
        h.inputs == Inputs::Rise
            || h.history.is_some()
            || h.preprocessing
                .as_ref()
                .is_some_and(Preprocessing::accumulates)
            || self.artifact.model.sequential()
    }

    /// Times `n` calls of [`Predictor::predict_sample`], cycling through `rows` (one reading per
    /// feature each) with a reset at the start of every pass: the per-sample latency of the
    /// model as `thermerr-edge` runs it (one owner for the edge's `--bench-latency` and the
    /// library's model selection).
    pub fn latency<R: AsRef<[f64]>>(&mut self, rows: &[R], n: usize) -> Result<Latency> {
        if rows.is_empty() || n == 0 {
            return Err(Error::Shape("no rows to time".into()));
        }
        let mut ns = Vec::with_capacity(n);
        let mut checksum = 0.0;
        for k in 0..n {
            let i = k % rows.len();
            if i == 0 {
                self.reset();
            }
            let t = std::time::Instant::now();
            checksum += self.predict_sample(rows[i].as_ref())?;
            ns.push(t.elapsed().as_nanos() as f64);
        }
        ns.sort_by(f64::total_cmp);
        let q = |f: f64| ns[((ns.len() - 1) as f64 * f).round() as usize];
        Ok(Latency {
            samples: n,
            p50_ns: q(0.5),
            p99_ns: q(0.99),
            mean_ns: ns.iter().sum::<f64>() / n as f64,
            checksum,
        })
    }

    /// Fixes the readings the rises are taken from (one per feature, in the model's order),
    /// instead of the run's first sample: for a stream that starts in the middle of a run (a
    /// gateway restarted on a warm machine), whose error is still relative to the run's start.
    /// Kept across [`Predictor::reset`]. An error for a model that reads absolute readings, or
    /// for a wrong count or a reading that is not finite.
    pub fn set_reference(&mut self, x: &[f64]) -> Result<()> {
        if self.artifact.header.inputs != Inputs::Rise {
            return Err(Error::param(
                "reference",
                "the model reads absolute readings, not rises: a rise reference means nothing to it",
            ));
        }
        if x.len() != self.first.len() {
            return Err(Error::Shape(format!(
                "the rise reference needs {} readings, got {}",
                self.first.len(),
                x.len()
            )));
        }
        if let Some(j) = x.iter().position(|v| !v.is_finite()) {
            return Err(Error::Shape(format!(
                "reading {j} of the rise reference is not a finite number ({})",
                x[j]
            )));
        }
        self.first.copy_from_slice(x);
        self.have_first = true;
        self.fixed_first = true;
        Ok(())
    }

    /// Forgets the run so far: the next sample starts a new run (from the fixed rise reference,
    /// if one was set).
    pub fn reset(&mut self) {
        self.have_first = self.fixed_first;
        if let Some(h) = &mut self.history {
            h.reset();
        }
        self.acc.iter_mut().for_each(|v| *v = 0.0);
        self.y1_prev = 0.0;
        self.state.reset();
    }

    /// Predicts the next sample of the run (one reading per feature, in the model's order).
    /// Models that use past errors (grey, filter models) feed back their own previous output:
    /// closed loop, as a compensating controller runs. Allocates nothing unless it fails.
    pub fn predict_sample(&mut self, x: &[f64]) -> Result<f64> {
        self.predict_sample_measured(x, None)
    }

    /// As [`Predictor::predict_sample`], with the measured error of the previous sample when it
    /// is known (one step ahead, for models that use past errors; ignored by the others).
    pub fn predict_sample_measured(
        &mut self,
        x: &[f64],
        measured_prev: Option<f64>,
    ) -> Result<f64> {
        self.predict_sample_at(None, x, measured_prev)
    }

    /// As [`Predictor::predict_sample_measured`], at time `t` (seconds): a model with a history
    /// filters its readings over the time since the previous sample (`step_s` without times).
    pub fn predict_sample_at(
        &mut self,
        t: Option<f64>,
        x: &[f64],
        measured_prev: Option<f64>,
    ) -> Result<f64> {
        let n = self.raw.len();
        if x.len() != n {
            return Err(Error::Shape(format!(
                "the model takes {n} features, got {}",
                x.len()
            )));
        }
        if let Some(j) = x.iter().position(|v| !v.is_finite()) {
            return Err(Error::Shape(format!(
                "feature {j} is not a finite number ({})",
                x[j]
            )));
        }
        let rise = self.artifact.header.inputs == Inputs::Rise;
        if rise && !self.have_first {
            self.first.copy_from_slice(x);
            self.have_first = true;
        }
        for (j, r) in self.raw.iter_mut().enumerate() {
            *r = if rise { x[j] - self.first[j] } else { x[j] };
        }
        match (&mut self.history, &self.artifact.header.history) {
            (Some(state), Some(h)) => state.push(h, t, &self.raw, &mut self.buf),
            _ => self.buf.copy_from_slice(&self.raw),
        }
        let (model, state) = (&self.artifact.model, &mut self.state);
        let kind = model.kind();
        let Some(pre) = &self.artifact.header.preprocessing else {
            let y = predict_model(model, state, &self.buf, measured_prev)?;
            return finite(kind, y);
        };
        pre.scale_row(&mut self.buf);
        if pre.accumulates() {
            for (b, a) in self.buf.iter_mut().zip(&mut self.acc) {
                *a += *b;
                *b = *a;
            }
        }
        let y1 = predict_model(model, state, &self.buf, measured_prev)?;
        let y = pre.output(y1, self.y1_prev);
        self.y1_prev = y1;
        finite(kind, y)
    }
}

/// Per-sample latency of a [`Predictor`] ([`Predictor::latency`]), in nanoseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Latency {
    pub samples: usize,
    pub p50_ns: f64,
    pub p99_ns: f64,
    pub mean_ns: f64,
    /// The sum of the predictions, so that the work cannot be optimised away.
    pub checksum: f64,
}
