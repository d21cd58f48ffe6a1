"""Input checks shared by every estimator: one place that turns user input into the
C-contiguous float64 arrays the Rust kernels borrow, with errors that say what is wrong, and the
checks of a fitted estimator's input (feature count and names) that scikit-learn's tools rely on.
Messages follow scikit-learn's wording where its estimator checks look for it."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import numpy.typing as npt

from .errors import DataError, DataTypeError, ShapeError

F64 = npt.NDArray[np.float64]


def _float_array(x: Any, name: str) -> npt.NDArray[np.float64]:
    """``x`` as a float64 array of any shape; sparse, complex and non-numeric input refused."""
    from scipy.sparse import issparse  # here, not at import: a diagnosis never needs it

    if issparse(x):
        raise DataTypeError(
            f"{name} is a sparse matrix, but dense data is required: use {name}.toarray()"
        )
    try:
        is_complex = np.iscomplexobj(x)
    except (TypeError, ValueError):  # ragged nesting: the conversion below says so
        is_complex = False
    if is_complex:
        raise DataError(f"Complex data not supported: {name} must hold real numbers")
    try:
        return np.asarray(x, dtype=np.float64)
    except TypeError as e:  # e.g. a dict in an object array
        raise DataTypeError(f"{name} must be numeric: {e}") from None
    except ValueError as e:  # e.g. a word in a column of numbers
        raise DataError(f"{name} must be numeric: {e}") from None


def as_matrix(x: Any, name: str = "X", *, one_d: bool = True) -> F64:
    """2-D float64, C-contiguous, finite, non-empty. A 1-D input is one feature, or refused
    with ``one_d=False`` (as estimators refuse it: one sample or one feature is ambiguous)."""
    arr = _float_array(x, name)
    if arr.ndim == 1:
        if not one_d:
            raise ShapeError(
                f"{name} must be 2-D (samples x features), got a 1-D array of {arr.shape[0]} values. "
                f"Reshape your data either using {name}.reshape(-1, 1) if your data has a single "
                f"feature or {name}.reshape(1, -1) if it contains a single sample."
            )
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2:
        raise ShapeError(f"{name} must be 2-D (samples x features), got {arr.ndim}-D")
    for axis, what in ((0, "sample"), (1, "feature")):
        if arr.shape[axis] == 0:
            raise ShapeError(
                f"{name} has 0 {what}(s) (shape={arr.shape}) while a minimum of 1 is required."
            )
    bad = ~np.isfinite(arr)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise DataError(f"{name} contains {_non_finite(arr[r, c])} at row {r}, column {c}")
    return np.require(arr, np.float64, ["C", "A"])


def as_vector(y: Any, name: str = "y", n: int | None = None) -> F64:
    """1-D float64, contiguous, finite; of length ``n`` when given."""
    arr = _float_array(y, name)
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.ravel()
    if arr.ndim != 1:
        raise ShapeError(f"{name} must be 1-D, got shape {arr.shape}")
    if arr.size == 0:
        raise ShapeError(f"{name} is empty")
    if n is not None and arr.shape[0] != n:
        raise ShapeError(f"X has {n} rows but {name} has {arr.shape[0]} values")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(f"{name} contains {_non_finite(arr[i])} at index {i}")
    return np.require(arr, np.float64, ["C", "A"])


def _non_finite(v: float) -> str:
    return "NaN" if np.isnan(v) else "infinity"


def as_target(y: Any, n: int, estimator: str) -> F64:
    """The target of ``estimator.fit``: a vector of ``n`` values. A column vector is accepted
    with scikit-learn's ``DataConversionWarning``; any other 2-D ``y`` is refused."""
    if y is None:
        raise ShapeError(f"{estimator} requires y to be passed, but the target y is None")
    arr = _float_array(y, "y")
    if arr.ndim == 2 and arr.shape[1] == 1:
        from sklearn.exceptions import DataConversionWarning

        warnings.warn(
            "A column-vector y was passed when a 1d array was expected. Please change the shape "
            "of y to (n_samples,), for example using ravel().",
            DataConversionWarning,
            stacklevel=4,
        )
        arr = arr.ravel()
    elif arr.ndim != 1:
        raise ShapeError(f"y should be a 1d array, got an array of shape {arr.shape} instead.")
    return as_vector(arr, "y", n=n)


def feature_names(X: Any) -> list[str] | None:
    """Column names of a data frame (pandas, polars, ...), when all of them are strings, as
    scikit-learn reads them; ``None`` for arrays."""
    cols = getattr(X, "columns", None)
    if cols is None:
        return None
    names = list(cols)
    if names and all(isinstance(c, str) for c in names):
        return [str(c) for c in names]
    return None


def series_name(y: Any) -> str | None:
    """The name of a named column (a pandas or polars Series), else ``None``."""
    name = getattr(y, "name", None)
    return name if isinstance(name, str) else None


def check_features(
    estimator: str, n_in: int, names_in: list[str] | None, n: int, names: list[str] | None
) -> None:
    """Check input of ``n`` columns named ``names`` (``None``: unnamed) against what
    ``estimator`` was fitted on. Columns named differently or in another order are refused; a
    named input to a model fitted without names, or the reverse, warns as scikit-learn does."""
    if names is not None and names_in is not None:
        if names != list(names_in):
            raise ShapeError(_names_mismatch(list(names_in), names))
    elif names is not None:
        warnings.warn(f"X has feature names, but {estimator} was fitted without feature names",
                      UserWarning, stacklevel=4)
    elif names_in is not None:
        warnings.warn(f"X does not have valid feature names, but {estimator} was fitted with "
                      "feature names", UserWarning, stacklevel=4)
    if n != n_in:
        raise ShapeError(f"X has {n} features, but {estimator} is expecting {n_in} features as input.")


def _names_mismatch(fitted: list[str], given: list[str]) -> str:
    def listed(names: list[str]) -> str:
        shown = [f"- {v}\n" for v in names[:5]]
        return "".join(shown) + ("- ...\n" if len(names) > 5 else "")

    unseen = sorted(set(given) - set(fitted))
    missing = sorted(set(fitted) - set(given))
    msg = "The feature names should match those that were passed during fit.\n"
    if unseen:
        msg += "Feature names unseen at fit time:\n" + listed(unseen)
    if missing:
        msg += "Feature names seen at fit time, yet now missing:\n" + listed(missing)
    if not unseen and not missing:
        msg += "Feature names must be in the same order as they were in fit.\n"
    return msg + f"Fitted on: {', '.join(fitted)}\nGiven:     {', '.join(given)}"
