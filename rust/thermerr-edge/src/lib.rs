//! thermerr-edge: evaluates a thermerr_rs model file on a gateway beside the machine — no Python,
//! no BLAS, no allocation per sample.
//!
//! The model file, its validation and the per-run state (inputs as rises since the first sample,
//! 1-AGO preprocessing, the grey and filter models' past outputs) belong to
//! [`thermerr_core::artifact`], built here without its training code: the edge and the Python
//! library read the same files through the same code and predict through the same `predict_one`,
//! so they agree by construction. This crate adds the error type the CLI and the C ABI report,
//! the streaming command-line filter (`main.rs`, its line parser in [`filter`]) and the C ABI ([`capi`]).
//!
//! Kinds: `mlr`, `rbf`, `svr`, `bp`, `greybp`, `gm1n`, `hybrid`. Call [`Predictor::reset`] at the
//! start of a new run.

pub mod capi;
pub mod filter;

use std::path::Path;

pub use thermerr_core::artifact::{Artifact, Inputs, Model, Preprocessing, FORMAT_VERSION};
pub use thermerr_core::guard::GuardedPredictor;

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

pub type Result<T, E = EdgeError> = std::result::Result<T, E>;

fn format_error(e: thermerr_core::Error) -> EdgeError {
    match e {
        thermerr_core::Error::Format(m) => EdgeError::Format(m),
        other => EdgeError::Format(other.to_string()),
    }
}

/// A loaded model with its per-run state (the core's [`thermerr_core::artifact::Predictor`]).
#[derive(Clone, Debug)]
pub struct Predictor(thermerr_core::artifact::Predictor);

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

    /// Parses and validates the JSON text of a model file.
    pub fn from_json(text: &str) -> Result<Self> {
        thermerr_core::artifact::Predictor::from_json(text)
            .map(Predictor)
            .map_err(format_error)
    }

    pub fn model(&self) -> &Model {
        self.0.model()
    }

    pub fn kind(&self) -> &'static str {
        self.0.kind()
    }

    /// The readings a sample holds (one per feature column; a model with a history makes its
    /// own inputs from them).
    pub fn n_inputs(&self) -> usize {
        self.0.n_inputs()
    }

    /// The model's own inputs per sample.
    pub fn n_features(&self) -> usize {
        self.0.n_features()
    }

    /// The run columns the model reads, in order (if it was fitted on a run).
    pub fn features(&self) -> Option<&[String]> {
        self.0.features()
    }

    /// The error column the model predicts (e.g. `E_z`), if recorded.
    pub fn target(&self) -> Option<&str> {
        self.0.target()
    }

    /// Whether predictions depend on earlier samples of the run.
    pub fn stateful(&self) -> bool {
        self.0.stateful()
    }

    /// The model with its sensor-fault guard ([`thermerr_core::guard`]); `None` when the file
    /// has no guard.
    pub fn guarded(&self) -> Result<Option<GuardedPredictor>> {
        GuardedPredictor::new(self.0.clone()).map_err(format_error)
    }

    /// Forgets the run so far: the next sample starts a new run.
    pub fn reset(&mut self) {
        self.0.reset()
    }

    /// Fixes the readings the rises are taken from (the core's
    /// [`thermerr_core::artifact::Predictor::set_reference`]).
    pub fn set_reference(&mut self, x: &[f64]) -> Result<()> {
        self.0.set_reference(x).map_err(format_error)
    }

    /// Per-sample latency of `n` predictions cycling through `rows` (the core's
    /// [`thermerr_core::artifact::Predictor::latency`]).
    pub fn latency(
        &mut self,
        rows: &[Vec<f64>],
        n: usize,
    ) -> Result<thermerr_core::artifact::Latency> {
        self.0
            .latency(rows, n)
            .map_err(|e| EdgeError::Input(e.to_string()))
    }

    /// Predicts the next sample of the run (one reading per feature, in the model's order).
    /// Models that use past errors (grey, filter models) feed back their own previous output:
    /// closed loop, as a compensating controller runs. Allocates nothing unless it fails.
    #[inline]
    pub fn predict_sample(&mut self, x: &[f64]) -> Result<f64> {
        self.predict_sample_measured(x, None)
    }

    /// As [`Predictor::predict_sample`], at time `t` in seconds (a model with a history filters
    /// its readings over the time since the previous sample; `None`: its training step).
    #[inline]
    pub fn predict_sample_at(&mut self, t: Option<f64>, x: &[f64]) -> Result<f64> {
        self.0
            .predict_sample_at(t, x, None)
            .map_err(|e| EdgeError::Input(e.to_string()))
    }

    /// As [`Predictor::predict_sample`], with the measured error of the previous sample when it
    /// is known (one step ahead, for models that use past errors; ignored by the others).
    #[inline]
    pub fn predict_sample_measured(
        &mut self,
        x: &[f64],
        measured_prev: Option<f64>,
    ) -> Result<f64> {
        self.0
            .predict_sample_measured(x, measured_prev)
            .map_err(|e| EdgeError::Input(e.to_string()))
    }
}
