//! thermerr-core: the compute kernels of thermerr_rs, with no Python in them.
//!
//! Every family follows the same shape (after linfa): `XParams` (a consuming builder with
//! defaults) → `check()` → `XValidParams` → `fit(samples)` → a fitted model that is plain,
//! serialisable data with a `predict` that checks its input.

pub mod error;
pub mod fcm;
pub mod kmeans;
pub mod linalg;
pub mod linear;
pub mod metrics;
pub mod optim;
pub mod rbf;
pub mod run;
pub mod samples;
pub mod swarm;
pub mod thermal;

pub use error::{Error, Result};
pub use samples::{Matrix, Samples};
