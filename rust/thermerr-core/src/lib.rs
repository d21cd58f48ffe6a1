//! thermerr-core: the compute kernels of thermerr_rs, with no Python in them.
//!
//! Every family follows the same shape (after linfa): `XParams` (a consuming builder with
//! defaults) → `check()` → `XValidParams` → `fit(samples)` → a fitted model that is plain,
//! serialisable data with a `predict` that checks its input.
//!
//! With the default feature `fit` off, only the fitted models' prediction code is built (no faer,
//! no rayon): `thermerr-edge` uses exactly that, so the edge and the library share one `predict`
//! per model kind.

pub mod artifact;
pub mod dialect;
pub mod error;
#[cfg(feature = "fit")]
pub mod fcm;
pub mod grey;
pub mod guard;
pub mod hybrid;
pub mod interrupt;
#[cfg(feature = "fit")]
pub mod kmeans;
#[cfg(feature = "fit")]
pub mod linalg;
pub mod linear;
pub mod metrics;
pub mod nn;
#[cfg(feature = "fit")]
pub mod optim;
#[cfg(feature = "fit")]
pub mod portable;
#[cfg(feature = "fit")]
pub mod progress;
pub mod rbf;
#[cfg(feature = "fit")]
pub mod run;
pub mod samples;
pub mod sequence;
pub mod shape;
pub mod svr;
#[cfg(feature = "fit")]
pub mod swarm;
#[cfg(feature = "fit")]
pub mod thermal;
pub mod timeaxis;
#[cfg(feature = "fit")]
pub mod tune;

pub use error::{Error, Result};
pub use samples::{Matrix, Samples};
