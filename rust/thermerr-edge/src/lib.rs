//! thermerr-edge: evaluates a thermerr_rs model file on a gateway beside the machine — no Python,
//! no BLAS, no allocation per sample.
//!
//! It reads the versioned JSON envelope the library writes (`docs/formats.md`): `format_version`,
//! `kind`, `n_features`, `features`, `target`, `inputs` (`"absolute"` or `"rise"`),
//! `preprocessing` (`null`, `minmax` or `minmax_ago`) and `model`. Prediction calls the same
//! `predict_one` of `thermerr-core` (built without its training code) that the Python library
//! calls, so the edge and the library agree by construction.
//!
//! Kinds: `mlr`, `rbf`, `svr`, `bp`, `greybp`, `gm1n`, `hybrid`. Models that depend on the past
//! (inputs as rises since the first sample, 1-AGO preprocessing, the grey and filter models' past
//! errors) keep their state in the [`Predictor`], in buffers sized when the model is loaded; call
//! [`Predictor::reset`] at the start of a new run.

pub mod capi;

use std::path::Path;

use serde::Deserialize;
use serde_json::Value;
use thermerr_core::grey::{GreyBpModel, GreyState};
use thermerr_core::hybrid::{HybridModel, HybridState};
use thermerr_core::linear::LinearRegression;
use thermerr_core::nn::BpModel;
use thermerr_core::rbf::RbfNetwork;
use thermerr_core::svr::{Kernel, SvrModel};

/// The model-file schema version this crate reads.
pub const FORMAT_VERSION: u64 = 1;

/// Everything that can go wrong loading a model or predicting.
#[derive(Debug, thiserror::Error)]
pub enum EdgeError {
    /// The model file cannot be read.
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The model file is not one this crate can evaluate.
    #[error("model file: {0}")]
    Format(String),
    /// A sample of the wrong length or with a non-finite value.
    #[error("{0}")]
    Input(String),
}

impl EdgeError {
    fn format(msg: impl Into<String>) -> Self {
        EdgeError::Format(msg.into())
    }
}

pub type Result<T, E = EdgeError> = std::result::Result<T, E>;

#[derive(Deserialize)]
struct Envelope {
    format_version: Value,
    kind: String,
    n_features: usize,
    #[serde(default)]
    features: Option<Vec<String>>,
    #[serde(default)]
    target: Option<String>,
    #[serde(default)]
    inputs: Option<String>,
    #[serde(default)]
    preprocessing: Option<Value>,
    model: Value,
}

#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum Preprocessing {
    Minmax {
        x_min: Vec<f64>,
        x_max: Vec<f64>,
    },
    MinmaxAgo {
        x_min: Vec<f64>,
        x_max: Vec<f64>,
        y_min: f64,
        y_max: f64,
    },
}

/// The fitted model of one kind.
#[derive(Clone, Debug)]
pub enum Model {
    Mlr(LinearRegression),
    Rbf(RbfNetwork),
    Svr(SvrModel),
    /// BP network on scaled temperatures (seed 002's baseline)
    Bp(BpModel),
    /// rolling GM(1,N) (+ BP network), seed 002; `kind` "greybp" or "gm1n"
    Grey(GreyBpModel, &'static str),
    /// LR/MA/AR filters (+ network), seed 000
    Hybrid(HybridModel),
}

impl Model {
    /// The `kind` names this crate evaluates.
    pub const KINDS: [&'static str; 7] = ["mlr", "rbf", "svr", "bp", "greybp", "gm1n", "hybrid"];

    fn parse(kind: &str, model: Value) -> Result<Self> {
        let bad = |e: serde_json::Error| EdgeError::format(format!("{kind} model: {e}"));
        let m = match kind {
            "mlr" => Model::Mlr(serde_json::from_value(model).map_err(bad)?),
            "rbf" => Model::Rbf(serde_json::from_value(model).map_err(bad)?),
            "svr" => Model::Svr(serde_json::from_value(model).map_err(bad)?),
            "bp" => Model::Bp(serde_json::from_value(model).map_err(bad)?),
            "greybp" => Model::Grey(serde_json::from_value(model).map_err(bad)?, "greybp"),
            "gm1n" => Model::Grey(serde_json::from_value(model).map_err(bad)?, "gm1n"),
            "hybrid" => Model::Hybrid(serde_json::from_value(model).map_err(bad)?),
            other => {
                return Err(EdgeError::format(format!(
                    "unknown model kind {other:?} (this edge evaluates: {})",
                    Self::KINDS.join(", ")
                )))
            }
        };
        m.validate()?;
        Ok(m)
    }

    fn validate(&self) -> Result<()> {
        let fail = |m: String| Err(EdgeError::format(m));
        match self {
            Model::Mlr(m) if m.coef.is_empty() => fail("mlr model: no coefficients".into()),
            Model::Rbf(m) if m.weights.len() != m.centers.nrows() => fail(format!(
                "rbf model: {} weights for {} centres",
                m.weights.len(),
                m.centers.nrows()
            )),
            Model::Rbf(m) if m.spread.is_nan() || m.spread <= 0.0 => {
                fail(format!("rbf model: spread must be > 0, got {}", m.spread))
            }
            Model::Svr(m) if m.dual_coef.len() != m.support_vectors.nrows() => fail(format!(
                "svr model: {} dual coefficients for {} support vectors",
                m.dual_coef.len(),
                m.support_vectors.nrows()
            )),
            Model::Svr(SvrModel {
                kernel: Kernel::Rbf { gamma },
                ..
            }) if gamma.is_nan() || *gamma <= 0.0 => {
                fail(format!("svr model: gamma must be > 0, got {gamma}"))
            }
            _ => Ok(()),
        }
    }

    pub fn kind(&self) -> &'static str {
        match self {
            Model::Mlr(_) => "mlr",
            Model::Rbf(_) => "rbf",
            Model::Svr(_) => "svr",
            Model::Bp(_) => "bp",
            Model::Grey(_, k) => k,
            Model::Hybrid(_) => "hybrid",
        }
    }

    pub fn n_features(&self) -> usize {
        match self {
            Model::Mlr(m) => m.n_features(),
            Model::Rbf(m) => m.n_features(),
            Model::Svr(m) => m.n_features(),
            Model::Bp(m) => m.n_features(),
            Model::Grey(m, _) => m.n_features(),
            Model::Hybrid(m) => m.n_features(),
        }
    }

    /// Whether the model itself carries state from sample to sample (past errors).
    pub fn sequential(&self) -> bool {
        matches!(self, Model::Grey(..) | Model::Hybrid(_))
    }
}

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
            Model::Grey(g, _) => ModelState::Grey(Box::new(GreyState::new(g))),
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

/// One sample through the core's own predict code (no allocation on success).
#[inline]
fn predict_model(
    model: &Model,
    state: &mut ModelState,
    x: &[f64],
    measured_prev: Option<f64>,
) -> Result<f64> {
    let input = |e: thermerr_core::Error| EdgeError::Input(e.to_string());
    Ok(match (model, state) {
        (Model::Mlr(m), _) => m.predict_one(x),
        (Model::Rbf(m), _) => m.predict_one(x),
        (Model::Svr(m), _) => m.predict_one(x),
        (Model::Bp(m), ModelState::Scratch(s)) => m.predict_one(x, s),
        (Model::Grey(m, _), ModelState::Grey(s)) => s.push(m, x, measured_prev).map_err(input)?,
        (Model::Hybrid(m), ModelState::Hybrid(s)) => s.push(m, x, measured_prev).map_err(input)?,
        _ => {
            return Err(EdgeError::Input(
                "model state does not match its kind".into(),
            ))
        }
    })
}

/// Input scaling recorded in the model file.
#[derive(Clone, Debug)]
enum Pre {
    None,
    /// x ← (x − lo) / (hi − lo)
    MinMax {
        lo: Vec<f64>,
        span: Vec<f64>,
    },
    /// as MinMax, then 1-AGO over time; the output is differenced back and de-normalised
    MinMaxAgo {
        lo: Vec<f64>,
        span: Vec<f64>,
        y_lo: f64,
        y_span: f64,
    },
}

/// A loaded model with its per-run state.
#[derive(Clone, Debug)]
pub struct Predictor {
    model: Model,
    pre: Pre,
    rise: bool,
    features: Option<Vec<String>>,
    target: Option<String>,
    // per-run state, sized at load time
    first: Vec<f64>,
    have_first: bool,
    acc: Vec<f64>,
    y1_prev: f64,
    buf: Vec<f64>,
    state: ModelState,
}

impl Predictor {
    /// Reads a model file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let p = path.as_ref();
        let text = std::fs::read_to_string(p).map_err(|source| EdgeError::Io {
            path: p.display().to_string(),
            source,
        })?;
        Self::from_json(&text).map_err(|e| match e {
            EdgeError::Format(m) => EdgeError::Format(format!("{}: {m}", p.display())),
            other => other,
        })
    }

    /// Parses the JSON text of a model file.
    pub fn from_json(text: &str) -> Result<Self> {
        let env: Envelope =
            serde_json::from_str(text).map_err(|e| EdgeError::format(e.to_string()))?;
        if env.format_version.as_u64() != Some(FORMAT_VERSION) {
            return Err(EdgeError::format(format!(
                "format_version {} is not supported (this edge reads {FORMAT_VERSION})",
                env.format_version
            )));
        }
        let model = Model::parse(&env.kind, env.model)?;
        let n = env.n_features;
        if model.n_features() != n {
            return Err(EdgeError::format(format!(
                "n_features is {n} but the {} model takes {}",
                env.kind,
                model.n_features()
            )));
        }
        if let Some(f) = &env.features {
            if f.len() != n {
                return Err(EdgeError::format(format!(
                    "{} feature names for {n} features",
                    f.len()
                )));
            }
        }
        let rise = match env.inputs.as_deref() {
            None | Some("absolute") => false,
            Some("rise") => true,
            Some(other) => {
                return Err(EdgeError::format(format!(
                    "inputs {other:?} is not \"absolute\" or \"rise\""
                )))
            }
        };
        let pre = match env.preprocessing {
            None | Some(Value::Null) => Pre::None,
            Some(v) => {
                let p: Preprocessing = serde_json::from_value(v)
                    .map_err(|e| EdgeError::format(format!("preprocessing: {e}")))?;
                let ranges = |lo: Vec<f64>, hi: Vec<f64>| -> Result<(Vec<f64>, Vec<f64>)> {
                    if lo.len() != n || hi.len() != n {
                        return Err(EdgeError::format(format!(
                            "preprocessing ranges have {} and {} entries for {n} features",
                            lo.len(),
                            hi.len()
                        )));
                    }
                    let span: Vec<f64> = hi.iter().zip(&lo).map(|(h, l)| h - l).collect();
                    if let Some(j) = span.iter().position(|s| s.is_nan() || *s <= 0.0) {
                        return Err(EdgeError::format(format!(
                            "preprocessing range of feature {j} is empty"
                        )));
                    }
                    Ok((lo, span))
                };
                match p {
                    Preprocessing::Minmax { x_min, x_max } => {
                        let (lo, span) = ranges(x_min, x_max)?;
                        Pre::MinMax { lo, span }
                    }
                    Preprocessing::MinmaxAgo {
                        x_min,
                        x_max,
                        y_min,
                        y_max,
                    } => {
                        let (lo, span) = ranges(x_min, x_max)?;
                        Pre::MinMaxAgo {
                            lo,
                            span,
                            y_lo: y_min,
                            y_span: y_max - y_min,
                        }
                    }
                }
            }
        };
        let state = ModelState::new(&model);
        Ok(Predictor {
            state,
            model,
            pre,
            rise,
            features: env.features,
            target: env.target,
            first: vec![0.0; n],
            have_first: false,
            acc: vec![0.0; n],
            y1_prev: 0.0,
            buf: vec![0.0; n],
        })
    }

    pub fn model(&self) -> &Model {
        &self.model
    }

    pub fn kind(&self) -> &'static str {
        self.model.kind()
    }

    pub fn n_features(&self) -> usize {
        self.buf.len()
    }

    /// The run columns the model reads, in order (if it was fitted on a run).
    pub fn features(&self) -> Option<&[String]> {
        self.features.as_deref()
    }

    /// The error column the model predicts (e.g. `E_z`), if recorded.
    pub fn target(&self) -> Option<&str> {
        self.target.as_deref()
    }

    /// Whether predictions depend on earlier samples of the run.
    pub fn stateful(&self) -> bool {
        self.rise || matches!(self.pre, Pre::MinMaxAgo { .. }) || self.model.sequential()
    }

    /// Forgets the run so far: the next sample starts a new run.
    pub fn reset(&mut self) {
        self.have_first = false;
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
        let n = self.buf.len();
        if x.len() != n {
            return Err(EdgeError::Input(format!(
                "the model takes {n} features, got {}",
                x.len()
            )));
        }
        if let Some(j) = x.iter().position(|v| !v.is_finite()) {
            return Err(EdgeError::Input(format!(
                "feature {j} is not a finite number ({})",
                x[j]
            )));
        }
        if self.rise && !self.have_first {
            self.first.copy_from_slice(x);
            self.have_first = true;
        }
        for (j, b) in self.buf.iter_mut().enumerate() {
            *b = if self.rise {
                x[j] - self.first[j]
            } else {
                x[j]
            };
        }
        let (model, state) = (&self.model, &mut self.state);
        Ok(match &self.pre {
            Pre::None => predict_model(model, state, &self.buf, measured_prev)?,
            Pre::MinMax { lo, span } => {
                for ((b, l), s) in self.buf.iter_mut().zip(lo).zip(span) {
                    *b = (*b - l) / s;
                }
                predict_model(model, state, &self.buf, measured_prev)?
            }
            Pre::MinMaxAgo {
                lo,
                span,
                y_lo,
                y_span,
            } => {
                for (((b, a), l), s) in self.buf.iter_mut().zip(&mut self.acc).zip(lo).zip(span) {
                    *a += (*b - l) / s;
                    *b = *a;
                }
                let y1 = predict_model(model, state, &self.buf, measured_prev)?;
                let y = (y1 - self.y1_prev) * y_span + y_lo;
                self.y1_prev = y1;
                y
            }
        })
    }
}
