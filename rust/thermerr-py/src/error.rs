//! Maps every core error to an exception class of `thermerr_rs.errors`.
//!
//! The classes live in Python so that they can inherit from both `ThermerrError` and the builtin
//! a user would catch (`ValueError`, `KeyError`, ...); the binding imports each once, on first
//! use, and keeps it.

use pyo3::exceptions::{PyFileNotFoundError, PyKeyboardInterrupt, PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;
use thermerr_core::Error;

/// Newtype that lets `?` turn a core error into a Python exception (orphan rule).
pub struct PyErrWrap(pub Error);

impl From<Error> for PyErrWrap {
    fn from(e: Error) -> Self {
        PyErrWrap(e)
    }
}

/// The exception classes of `thermerr_rs.errors`, imported once each (on first use) and kept.
struct Class {
    cell: PyOnceLock<Py<PyType>>,
    name: &'static str,
}

impl Class {
    const fn new(name: &'static str) -> Self {
        Class {
            cell: PyOnceLock::new(),
            name,
        }
    }

    fn err(&self, msg: String) -> PyErr {
        Python::attach(
            |py| match self.cell.import(py, "thermerr_rs.errors", self.name) {
                Ok(cls) => PyErr::from_type(cls.clone(), msg),
                Err(e) => {
                    PyRuntimeError::new_err(format!("{msg} (and thermerr_rs.errors failed: {e})"))
                }
            },
        )
    }
}

static PARAMETER: Class = Class::new("ParameterError");
static SHAPE: Class = Class::new("ShapeError");
static DATA: Class = Class::new("DataError");
static MISSING_COLUMN: Class = Class::new("MissingColumnError");
static NUMERICAL: Class = Class::new("NumericalError");
static CONVERGENCE: Class = Class::new("ConvergenceError");
static MODEL_FORMAT: Class = Class::new("ModelFormatError");

impl From<PyErrWrap> for PyErr {
    fn from(e: PyErrWrap) -> PyErr {
        let msg = e.0.to_string();
        match e.0 {
            Error::InvalidParam { .. } => PARAMETER.err(msg),
            Error::Shape(_) => SHAPE.err(msg),
            Error::NonFinite { .. } => DATA.err(msg),
            Error::Parse { .. } => DATA.err(msg),
            Error::MissingColumn { .. } => MISSING_COLUMN.err(msg),
            Error::Io { ref source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
                PyFileNotFoundError::new_err(msg)
            }
            Error::Io { .. } => PyOSError::new_err(msg),
            Error::Numerical(_) => NUMERICAL.err(msg),
            Error::Convergence(_) => CONVERGENCE.err(msg),
            Error::Format(_) => MODEL_FORMAT.err(msg),
            Error::Interrupted => PyKeyboardInterrupt::new_err(msg),
        }
    }
}

pub type PyRes<T> = Result<T, PyErrWrap>;
