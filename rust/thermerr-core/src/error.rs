//! One error enum for the whole core. The Python binding maps every variant to an exception.

use std::path::PathBuf;

/// Result alias used throughout the core.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Every way a kernel or a reader can refuse its input or fail.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A hyper-parameter is out of its domain.
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParam { name: &'static str, reason: String },

    /// Arrays of the wrong shape, or empty where data is required.
    #[error("{0}")]
    Shape(String),

    /// A NaN or infinity where finite numbers are required.
    #[error("{what} contains a non-finite value at row {row}, column {col}")]
    NonFinite {
        what: String,
        row: usize,
        col: usize,
    },

    /// A file could not be opened or read.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// A file could be read but its content is invalid. `row` counts data rows from 1 (the header
    /// is row 0); `line` is the 1-based line in the file.
    #[error("{}", format_parse(.file, .line, .row, .column, .reason))]
    Parse {
        file: String,
        line: Option<u64>,
        row: Option<u64>,
        column: Option<String>,
        reason: String,
    },

    /// A column asked for by name is not in the data.
    #[error("{file}: no column named `{column}` (columns are: {available})")]
    MissingColumn {
        file: String,
        column: String,
        available: String,
    },

    /// A linear system that cannot be solved, a distance that collapsed, and the like.
    #[error("numerical failure: {0}")]
    Numerical(String),

    /// An iterative method ran out of iterations before meeting its tolerance.
    #[error("did not converge: {0}")]
    Convergence(String),

    /// A model file that is not what this version of the library writes.
    #[error("model file: {0}")]
    Format(String),

    /// The call was interrupted (Ctrl-C) through [`crate::interrupt::request`].
    #[error("interrupted")]
    Interrupted,
}

fn format_parse(
    file: &str,
    line: &Option<u64>,
    row: &Option<u64>,
    column: &Option<String>,
    reason: &str,
) -> String {
    let mut s = file.to_string();
    if let Some(l) = line {
        s.push_str(&format!(", line {l}"));
    }
    if let Some(r) = row {
        s.push_str(&format!(", row {r}"));
    }
    if let Some(c) = column {
        s.push_str(&format!(", column `{c}`"));
    }
    s.push_str(": ");
    s.push_str(reason);
    s
}

impl Error {
    pub(crate) fn param(name: &'static str, reason: impl Into<String>) -> Self {
        Error::InvalidParam {
            name,
            reason: reason.into(),
        }
    }
}

/// The value of a parameter enum named `s` in `names` (its `FromStr`), or an
/// [`Error::InvalidParam`] listing the names allowed: `must be "a", "b" or "c", got "x"`.
pub(crate) fn parse_name<T: Copy>(param: &'static str, s: &str, names: &[(&str, T)]) -> Result<T> {
    if let Some((_, v)) = names.iter().find(|(n, _)| *n == s) {
        return Ok(*v);
    }
    let quoted: Vec<String> = names.iter().map(|(n, _)| format!("{n:?}")).collect();
    let list = match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => quoted.concat(),
    };
    Err(Error::param(param, format!("must be {list}, got {s:?}")))
}

/// Asserts that every name of a parameter enum parses (`FromStr`) and deserialises (serde) to
/// the same value, and that serde writes it back under the first name given for it.
#[cfg(all(test, feature = "fit"))]
pub(crate) fn assert_names_agree<T>(names: &[(&str, T)])
where
    T: std::str::FromStr<Err = Error>
        + serde::Serialize
        + serde::de::DeserializeOwned
        + PartialEq
        + std::fmt::Debug
        + Copy,
{
    for (n, v) in names {
        assert_eq!(n.parse::<T>().unwrap(), *v, "{n}");
        let de: T = serde_json::from_str(&format!("{n:?}")).unwrap();
        assert_eq!(de, *v, "{n}");
        let first = names.iter().find(|(_, w)| w == v).unwrap().0;
        assert_eq!(serde_json::to_string(v).unwrap(), format!("{first:?}"));
    }
    assert!(matches!(
        "no such name".parse::<T>(),
        Err(Error::InvalidParam { .. })
    ));
}
