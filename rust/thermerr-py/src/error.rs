//! Maps every core error to an exception class of `thermerr_rs.errors`.
//!
//! The classes live in Python so that they can inherit from both `ThermerrError` and the builtin
//! a user would catch (`ValueError`, `KeyError`, ...); the binding looks them up by name.

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::PyType;
use thermerr_core::Error;

/// Newtype that lets `?` turn a core error into a Python exception (orphan rule).
pub struct PyErrWrap(pub Error);

impl From<Error> for PyErrWrap {
    fn from(e: Error) -> Self {
        PyErrWrap(e)
    }
}

fn raise(class: &str, msg: String) -> PyErr {
    Python::attach(|py| {
        let cls = py
            .import("thermerr_rs.errors")
            .and_then(|m| m.getattr(class))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
        match cls {
            Ok(cls) => PyErr::from_type(cls, msg),
            Err(e) => {
                PyRuntimeError::new_err(format!("{msg} (and thermerr_rs.errors failed: {e})"))
            }
        }
    })
}

impl From<PyErrWrap> for PyErr {
    fn from(e: PyErrWrap) -> PyErr {
        let msg = e.0.to_string();
        match e.0 {
            Error::InvalidParam { .. } => raise("ParameterError", msg),
            Error::Shape(_) => raise("ShapeError", msg),
            Error::NonFinite { .. } => raise("DataError", msg),
            Error::Parse { .. } => raise("DataError", msg),
            Error::MissingColumn { .. } => raise("MissingColumnError", msg),
            Error::Io { ref source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
                PyFileNotFoundError::new_err(msg)
            }
            Error::Io { .. } => PyOSError::new_err(msg),
            Error::Numerical(_) => raise("NumericalError", msg),
            Error::Convergence(_) => raise("ConvergenceError", msg),
            Error::Format(_) => raise("ModelFormatError", msg),
        }
    }
}

pub type PyRes<T> = Result<T, PyErrWrap>;
