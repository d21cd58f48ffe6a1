//! The model file: its one owner.
//!
//! A model file is versioned JSON (`docs/formats.md`, "Model files"): an envelope
//! (`format_version`, `kind`, `library`, `params`, `n_features`, `features`, `target`, `inputs`,
//! `preprocessing`) around the fitted `model` of one kind. This module reads and writes it for
//! the Python binding and for `thermerr-edge` alike (it builds with and without the `fit`
//! feature), and runs one `validate()` per fitted type on every load, so that a file whose parts
//! disagree is refused with a message naming the part, never evaluated and never a panic.
//!
//! The input side of a model is data here too: [`Inputs`] (absolute readings or rises since the
//! run's first sample) and [`Preprocessing`] (min–max scaling, optionally with 1-AGO over time).
//! Their arithmetic has one owner, [`Preprocessing::scale_row`] and friends, used by the batch
//! transforms the library fits with and by the streaming [`Predictor`] the edge runs.

mod history;
mod stream;

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::error::{Error, Result};
use crate::grey::GreyBpModel;
use crate::guard::Guard;
use crate::hybrid::HybridModel;
use crate::linear::MlrModel;
use crate::nn::{scale01, BpModel};
use crate::rbf::RbfModel;
use crate::svr::SvrModel;

pub use history::{History, HistoryState};
pub use stream::{Latency, Predictor};

/// The model-file schema version this crate reads and writes.
pub const FORMAT_VERSION: u64 = 1;

/// Largest per-run state a model file may ask for (values kept per sample: windows × features,
/// lags × features). A file beyond it is refused instead of allocating gigabytes.
pub const MAX_STATE_VALUES: usize = 1 << 24;

fn format_err(msg: impl Into<String>) -> Error {
    Error::Format(msg.into())
}

/// How a model's inputs are built from a run's columns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Inputs {
    /// the readings as they are
    #[default]
    Absolute,
    /// each reading minus the run's first sample (like the error, relative to the run's start)
    Rise,
}

impl std::str::FromStr for Inputs {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "absolute" => Ok(Inputs::Absolute),
            "rise" => Ok(Inputs::Rise),
            other => Err(Error::param(
                "inputs",
                format!("must be \"absolute\" or \"rise\", got {other:?}"),
            )),
        }
    }
}

impl Inputs {
    pub fn as_str(self) -> &'static str {
        match self {
            Inputs::Absolute => "absolute",
            Inputs::Rise => "rise",
        }
    }
}

/// Input scaling recorded in a model file: the model was fitted on scaled inputs and predicts
/// from raw readings. A feature whose training range has zero width (a constant column) maps to
/// 0.5, the middle of [0, 1], at fit and at prediction alike ([`crate::nn::scale01`]): the one
/// rule for a constant column everywhere in the library.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Preprocessing {
    /// x ← (x − x_min) / (x_max − x_min)
    Minmax { x_min: Vec<f64>, x_max: Vec<f64> },
    /// as `Minmax`, then 1-AGO (running sum) over the run; the model's output is differenced
    /// back (IAGO) and de-normalised by the error's training range (seed 001)
    MinmaxAgo {
        x_min: Vec<f64>,
        x_max: Vec<f64>,
        y_min: f64,
        y_max: f64,
    },
}

impl Preprocessing {
    /// The `kind` name written into the file.
    pub fn kind(&self) -> &'static str {
        match self {
            Preprocessing::Minmax { .. } => "minmax",
            Preprocessing::MinmaxAgo { .. } => "minmax_ago",
        }
    }

    fn ranges(&self) -> (&[f64], &[f64]) {
        match self {
            Preprocessing::Minmax { x_min, x_max }
            | Preprocessing::MinmaxAgo { x_min, x_max, .. } => (x_min, x_max),
        }
    }

    /// The training ranges of `x` (row-major, `d` columns) for a fresh preprocessing of this
    /// kind (`y` is the target, needed by `minmax_ago`).
    pub fn fit(kind: &str, x: &[f64], d: usize, y: &[f64]) -> Result<Self> {
        if d == 0 || x.is_empty() || x.len() % d != 0 {
            return Err(Error::Shape(format!(
                "preprocessing needs a non-empty matrix of {d} columns, got {} values",
                x.len()
            )));
        }
        let mut lo = vec![f64::INFINITY; d];
        let mut hi = vec![f64::NEG_INFINITY; d];
        for row in x.chunks_exact(d) {
            for j in 0..d {
                lo[j] = lo[j].min(row[j]);
                hi[j] = hi[j].max(row[j]);
            }
        }
        match kind {
            "minmax" => Ok(Preprocessing::Minmax {
                x_min: lo,
                x_max: hi,
            }),
            "minmax_ago" => {
                if y.is_empty() {
                    return Err(Error::Shape("minmax_ago needs the target".into()));
                }
                let (y_min, y_max) = crate::metrics::min_max(y.iter().copied());
                Ok(Preprocessing::MinmaxAgo {
                    x_min: lo,
                    x_max: hi,
                    y_min,
                    y_max,
                })
            }
            other => Err(Error::param(
                "preprocessing",
                format!("must be \"minmax\" or \"minmax_ago\", got {other:?}"),
            )),
        }
    }

    /// Checks the ranges against the model's feature count: each a finite, ordered range whose
    /// width is finite too (1e308 to -1e308 would scale every reading to 0 or overflow).
    pub fn validate(&self, n_features: usize) -> Result<()> {
        let (lo, hi) = self.ranges();
        if lo.len() != n_features || hi.len() != n_features {
            return Err(format_err(format!(
                "preprocessing ranges have {} and {} entries for {n_features} features",
                lo.len(),
                hi.len()
            )));
        }
        if let Some(j) = (0..n_features).find(|&j| !(hi[j] - lo[j]).is_finite() || hi[j] < lo[j]) {
            return Err(format_err(format!(
                "preprocessing range of feature {j} is not a finite, ordered range ({} to {})",
                lo[j], hi[j]
            )));
        }
        if let Preprocessing::MinmaxAgo { y_min, y_max, .. } = self {
            if !(y_max - y_min).is_finite() || y_max < y_min {
                return Err(format_err(format!(
                    "preprocessing target range is not a finite, ordered range ({y_min} to {y_max})"
                )));
            }
        }
        Ok(())
    }

    /// Whether the transform accumulates over the run (1-AGO).
    pub fn accumulates(&self) -> bool {
        matches!(self, Preprocessing::MinmaxAgo { .. })
    }

    /// Scales one row in place (min–max, before any accumulation).
    #[inline]
    pub fn scale_row(&self, row: &mut [f64]) {
        let (lo, hi) = self.ranges();
        for ((v, l), h) in row.iter_mut().zip(lo).zip(hi) {
            *v = scale01(*v, *l, *h);
        }
    }

    /// The model's accumulated output `y1` back to an error, given the previous accumulated
    /// output (IAGO, then de-normalisation); the identity for `minmax`.
    #[inline]
    pub fn output(&self, y1: f64, y1_prev: f64) -> f64 {
        match self {
            Preprocessing::Minmax { .. } => y1,
            Preprocessing::MinmaxAgo { y_min, y_max, .. } => {
                (y1 - y1_prev) * (y_max - y_min) + y_min
            }
        }
    }

    /// The target a model is fitted to: `minmax_ago` scales and accumulates it; `minmax` leaves
    /// it as it is.
    pub fn transform_target(&self, y: &[f64]) -> Vec<f64> {
        match self {
            Preprocessing::Minmax { .. } => y.to_vec(),
            Preprocessing::MinmaxAgo { y_min, y_max, .. } => {
                let mut acc = 0.0;
                y.iter()
                    .map(|&v| {
                        acc += scale01(v, *y_min, *y_max);
                        acc
                    })
                    .collect()
            }
        }
    }

    /// Transforms a whole run's inputs (row-major, `d` per row) as the streaming path does, row
    /// after row from the run's start.
    pub fn transform(&self, x: &[f64], d: usize) -> Result<Vec<f64>> {
        let n = self.ranges().0.len();
        if d != n || x.len() % d.max(1) != 0 {
            return Err(Error::Shape(format!(
                "preprocessing takes {n} features, got rows of {d}"
            )));
        }
        let mut out = x.to_vec();
        let mut acc = vec![0.0; d];
        for row in out.chunks_exact_mut(d.max(1)) {
            self.scale_row(row);
            if self.accumulates() {
                for (v, a) in row.iter_mut().zip(acc.iter_mut()) {
                    *a += *v;
                    *v = *a;
                }
            }
        }
        Ok(out)
    }

    /// The model's outputs over a whole run back to errors (see [`Preprocessing::output`]).
    pub fn inverse(&self, y1: &[f64]) -> Vec<f64> {
        let mut prev = 0.0;
        y1.iter()
            .map(|&v| {
                let out = self.output(v, prev);
                prev = v;
                out
            })
            .collect()
    }
}

/// The fitted model of one kind.
#[derive(Clone, Debug, PartialEq)]
pub enum Model {
    Mlr(MlrModel),
    Rbf(RbfModel),
    Svr(SvrModel),
    /// BP network on scaled temperatures (seed 002's baseline)
    Bp(BpModel),
    /// rolling GM(1,N) + BP network (seed 002)
    GreyBp(GreyBpModel),
    /// one rolling GM(1,N) alone (a `GreyBpModel` with one window and no network)
    Gm1n(GreyBpModel),
    /// LR/MA/AR filters (+ network), seed 000
    Hybrid(HybridModel),
}

/// Kinds of model files that hold something other than an error model.
const NOT_ERROR_MODELS: [(&str, &str); 1] = [("fcm", "a sensor clustering (fuzzy c-means)")];

impl Model {
    /// The `kind` names of error models, as written in the file.
    pub const KINDS: [&'static str; 7] = ["mlr", "rbf", "svr", "bp", "greybp", "gm1n", "hybrid"];

    /// The `kind` written into the file.
    pub fn kind(&self) -> &'static str {
        match self {
            Model::Mlr(_) => "mlr",
            Model::Rbf(_) => "rbf",
            Model::Svr(_) => "svr",
            Model::Bp(_) => "bp",
            Model::GreyBp(_) => "greybp",
            Model::Gm1n(_) => "gm1n",
            Model::Hybrid(_) => "hybrid",
        }
    }

    /// Parses the `model` field of a file of kind `kind`, and validates it.
    pub fn from_value(kind: &str, model: Value) -> Result<Self> {
        fn de<T: serde::de::DeserializeOwned>(kind: &str, v: Value) -> Result<T> {
            serde_json::from_value(v).map_err(|e| format_err(format!("{kind} model: {e}")))
        }
        let m = match kind {
            "mlr" => Model::Mlr(de(kind, model)?),
            "rbf" => Model::Rbf(de(kind, model)?),
            "svr" => Model::Svr(de(kind, model)?),
            "bp" => Model::Bp(de(kind, model)?),
            "greybp" => Model::GreyBp(de(kind, model)?),
            "gm1n" => Model::Gm1n(de(kind, model)?),
            "hybrid" => Model::Hybrid(de(kind, model)?),
            other => {
                if let Some((_, what)) = NOT_ERROR_MODELS.iter().find(|(k, _)| *k == other) {
                    return Err(format_err(format!(
                        "kind {other:?} is {what}, not an error model (error models: {})",
                        Self::KINDS.join(", ")
                    )));
                }
                return Err(format_err(format!(
                    "unknown model kind '{other}' (known: {})",
                    Self::KINDS.join(", ")
                )));
            }
        };
        m.validate()?;
        Ok(m)
    }

    /// The `model` field of the file.
    pub fn to_value(&self) -> Result<Value> {
        let v = match self {
            Model::Mlr(m) => serde_json::to_value(m),
            Model::Rbf(m) => serde_json::to_value(m),
            Model::Svr(m) => serde_json::to_value(m),
            Model::Bp(m) => serde_json::to_value(m),
            Model::GreyBp(m) | Model::Gm1n(m) => serde_json::to_value(m),
            Model::Hybrid(m) => serde_json::to_value(m),
        };
        v.map_err(|e| format_err(e.to_string()))
    }

    /// The consistency checks of the fitted type: shapes agree, numbers finite, per-run state of
    /// a bounded size. Run on every load.
    pub fn validate(&self) -> Result<()> {
        let kind = self.kind();
        let r = match self {
            Model::Mlr(m) => m.validate(),
            Model::Rbf(m) => m.validate(),
            Model::Svr(m) => m.validate(),
            Model::Bp(m) => m.validate().map_err(Error::Format),
            Model::GreyBp(m) => m.validate(),
            Model::Gm1n(m) => m.validate().and_then(|_| {
                if m.net.is_some() || m.windows.len() != 1 {
                    Err(format_err("a gm1n model has one window and no network"))
                } else {
                    Ok(())
                }
            }),
            Model::Hybrid(m) => m.validate(),
        };
        r.map_err(|e| match e {
            Error::Format(msg) if msg.starts_with(kind) => Error::Format(msg),
            Error::Format(msg) => Error::Format(format!("{kind} model: {msg}")),
            other => other,
        })
    }

    pub fn n_features(&self) -> usize {
        match self {
            Model::Mlr(m) => m.n_features(),
            Model::Rbf(m) => m.n_features(),
            Model::Svr(m) => m.n_features(),
            Model::Bp(m) => m.n_features(),
            Model::GreyBp(m) | Model::Gm1n(m) => m.n_features(),
            Model::Hybrid(m) => m.n_features(),
        }
    }

    /// Whether the model itself carries state from sample to sample (its past outputs or errors).
    pub fn sequential(&self) -> bool {
        matches!(self, Model::GreyBp(_) | Model::Gm1n(_) | Model::Hybrid(_))
    }
}

/// Everything in a model file around the fitted model (and its kind and feature count).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Header {
    /// who wrote it (e.g. `thermerr_rs 0.1.0`)
    pub library: Option<String>,
    /// the estimator's parameters, as given to its constructor
    pub params: Map<String, Value>,
    /// the run columns the model reads, in order (when fitted on a run or a data frame)
    pub features: Option<Vec<String>>,
    /// the error column it predicts
    pub target: Option<String>,
    pub inputs: Inputs,
    pub preprocessing: Option<Preprocessing>,
    /// temperature history as inputs ([`History`]), when fitted with it
    #[serde(skip_serializing_if = "Option::is_none")]
    pub history: Option<History>,
    /// sensor-fault limits and fallback models ([`crate::guard`]), when fitted with them
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guard: Option<Guard>,
}

impl Header {
    /// The readings a model of `n_features` inputs takes per sample: its features, or with a
    /// history, the readings the history is built from.
    pub fn n_inputs(&self, n_features: usize) -> usize {
        match &self.history {
            Some(h) => n_features / h.width(),
            None => n_features,
        }
    }

    /// Checks the header against the model's feature count.
    pub fn validate(&self, n_features: usize) -> Result<()> {
        if let Some(h) = &self.history {
            h.validate()?;
            if n_features % h.width() != 0 {
                return Err(format_err(format!(
                    "history: {n_features} features are not readings × {} (each reading and its \
                     {} rises)",
                    h.width(),
                    h.tau_s.len()
                )));
            }
        }
        let n_in = self.n_inputs(n_features);
        if let Some(f) = &self.features {
            if f.len() != n_in {
                let with = match &self.history {
                    Some(h) => format!(" ({n_features} inputs = readings × {})", h.width()),
                    None => String::new(),
                };
                return Err(format_err(format!(
                    "{} feature names for {n_in} features{with}",
                    f.len()
                )));
            }
        }
        if let Some(p) = &self.preprocessing {
            p.validate(n_features)?;
        }
        if let Some(g) = &self.guard {
            g.validate(self, n_features)?;
        }
        Ok(())
    }
}

/// The envelope as it is on disk, before validation.
#[derive(Deserialize)]
struct RawFile {
    format_version: Value,
    kind: String,
    #[serde(default)]
    library: Option<String>,
    #[serde(default)]
    params: Option<Map<String, Value>>,
    n_features: usize,
    #[serde(default)]
    features: Option<Vec<String>>,
    #[serde(default)]
    target: Option<String>,
    #[serde(default)]
    inputs: Option<String>,
    #[serde(default)]
    preprocessing: Option<Value>,
    #[serde(default)]
    history: Option<Value>,
    #[serde(default)]
    guard: Option<Value>,
    model: Value,
}

fn read_preprocessing(v: Option<Value>) -> Result<Option<Preprocessing>> {
    let v = match v {
        None | Some(Value::Null) => return Ok(None),
        Some(v) => v,
    };
    let kind = v.get("kind").and_then(Value::as_str).unwrap_or("");
    if !matches!(kind, "minmax" | "minmax_ago") {
        return Err(format_err(format!(
            "unknown preprocessing {v} (known kinds: minmax, minmax_ago)"
        )));
    }
    serde_json::from_value(v)
        .map(Some)
        .map_err(|e| format_err(format!("preprocessing: {e}")))
}

/// Reads the envelope of a model file of any kind: checks the version and the inputs, and hands
/// the `model` field on as JSON. The kind's own parser (for error models,
/// [`Model::from_value`]) reads the rest; then [`Header::validate`] checks the header against
/// the model's feature count.
pub fn read_envelope(text: &str) -> Result<(String, usize, Header, Value)> {
    let raw: RawFile = serde_json::from_str(text).map_err(|e| {
        if e.is_syntax() || e.is_eof() {
            format_err(format!("not JSON ({e})"))
        } else {
            format_err(e.to_string())
        }
    })?;
    if raw.format_version.as_u64() != Some(FORMAT_VERSION) {
        return Err(format_err(format!(
            "format_version {} is not supported (this version reads {FORMAT_VERSION})",
            raw.format_version
        )));
    }
    let n = raw.n_features;
    if n == 0 {
        return Err(format_err("n_features must be at least 1"));
    }
    let inputs = match raw.inputs.as_deref() {
        None => Inputs::Absolute,
        Some(s) => s
            .parse()
            .map_err(|_| format_err(format!("inputs {s:?} is not \"absolute\" or \"rise\"")))?,
    };
    let header = Header {
        library: raw.library,
        params: raw.params.unwrap_or_default(),
        features: raw.features,
        target: raw.target,
        inputs,
        preprocessing: read_preprocessing(raw.preprocessing)?,
        history: match raw.history {
            None | Some(Value::Null) => None,
            Some(v) => {
                Some(serde_json::from_value(v).map_err(|e| format_err(format!("history: {e}")))?)
            }
        },
        guard: match raw.guard {
            None | Some(Value::Null) => None,
            Some(v) => {
                Some(serde_json::from_value(v).map_err(|e| format_err(format!("guard: {e}")))?)
            }
        },
    };
    Ok((raw.kind, n, header, raw.model))
}

/// Writes a model file of any kind from its header and `model` field.
pub fn write_envelope(
    kind: &str,
    n_features: usize,
    header: &Header,
    model: Value,
) -> Result<String> {
    check_model_finite(&model)?;
    let mut doc = serde_json::json!({
        "format_version": FORMAT_VERSION,
        "kind": kind,
        "library": header.library,
        "params": header.params,
        "n_features": n_features,
        "features": header.features,
        "target": header.target,
        "inputs": header.inputs,
        "preprocessing": header.preprocessing,
        "model": model,
    });
    if let Some(h) = &header.history {
        doc["history"] = serde_json::to_value(h).map_err(|e| format_err(e.to_string()))?;
    }
    if let Some(g) = &header.guard {
        // validated with the header (finite limits): serde_json would write NaN as null
        doc["guard"] = serde_json::to_value(g).map_err(|e| format_err(e.to_string()))?;
    }
    serde_json::to_string_pretty(&doc).map_err(|e| format_err(e.to_string()))
}

/// serde_json turns a non-finite f64 into `null`; no fitted model has a null of its own.
fn check_model_finite(model: &Value) -> Result<()> {
    fn has_null(v: &Value) -> bool {
        match v {
            Value::Null => true,
            Value::Array(a) => a.iter().any(has_null),
            Value::Object(o) => o.values().any(has_null),
            _ => false,
        }
    }
    if has_null(model) {
        return Err(format_err(
            "the model holds a non-finite number and cannot be saved",
        ));
    }
    Ok(())
}

/// A whole model file: the header and a validated error model.
#[derive(Clone, Debug, PartialEq)]
pub struct Artifact {
    pub header: Header,
    pub model: Model,
}

impl Artifact {
    /// Reads and validates the text of a model file.
    pub fn from_json(text: &str) -> Result<Self> {
        let (kind, n, header, model) = read_envelope(text)?;
        let model = Model::from_value(&kind, model)?;
        if model.n_features() != n {
            return Err(format_err(format!(
                "n_features is {n} but the {kind} model takes {}",
                model.n_features()
            )));
        }
        header.validate(n)?;
        Ok(Artifact { header, model })
    }

    /// Reads and validates a model file.
    pub fn load(path: impl AsRef<std::path::Path>) -> Result<Self> {
        let p = path.as_ref();
        let text = std::fs::read_to_string(p).map_err(|source| Error::Io {
            path: p.to_path_buf(),
            source,
        })?;
        Self::from_json(&text).map_err(|e| match e {
            Error::Format(m) => Error::Format(format!("{}: {m}", p.display())),
            other => other,
        })
    }

    /// The text of the model file (validated first: what is written can be read back).
    pub fn to_json(&self) -> Result<String> {
        self.model.validate()?;
        self.header.validate(self.model.n_features())?;
        write_envelope(
            self.model.kind(),
            self.model.n_features(),
            &self.header,
            self.model.to_value()?,
        )
    }

    pub fn n_features(&self) -> usize {
        self.model.n_features()
    }
}

#[cfg(test)]
mod tests;
