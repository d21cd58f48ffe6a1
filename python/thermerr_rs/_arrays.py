"""Input normalisation shared by every estimator: one place that turns user input into the
C-contiguous float64 arrays the Rust kernels borrow, with errors that say what is wrong."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from .errors import DataError, ShapeError

F64 = npt.NDArray[np.float64]


def as_matrix(x: Any, name: str = "X") -> F64:
    """2-D float64, C-contiguous, finite, non-empty; a 1-D input is one feature."""
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise DataError(f"{name} must be numeric: {e}") from None
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2:
        raise ShapeError(f"{name} must be 2-D (samples x features), got {arr.ndim}-D")
    if arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ShapeError(f"{name} is empty (shape {arr.shape})")
    bad = ~np.isfinite(arr)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise DataError(f"{name} contains a non-finite value at row {r}, column {c}")
    return np.require(arr, np.float64, ["C", "A"])


def as_vector(y: Any, name: str = "y", n: int | None = None) -> F64:
    """1-D float64, contiguous, finite; of length ``n`` when given."""
    try:
        arr = np.asarray(y, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise DataError(f"{name} must be numeric: {e}") from None
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
        raise DataError(f"{name} contains a non-finite value at index {int(np.argmax(bad))}")
    return np.require(arr, np.float64, ["C", "A"])
