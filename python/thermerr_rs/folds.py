"""Cross-validation splits for runs: time-ordered by default.

A thermal-error run is a time series; a shuffled fold, or the complement of a fold, trains on
samples measured after the ones it is scored on, and reports an error no machine will see.
Every search in this package (:func:`~thermerr_rs.tune_svr`, :func:`~thermerr_rs.svr_cv_mse`,
:func:`~thermerr_rs.spread_search`, ``thermerr fit --tune``) takes the same ``cv``:

* an ``int`` ``k``: ``cv_kind="time"`` (the default) gives scikit-learn's
  ``TimeSeriesSplit(n_splits=k, gap=gap)`` computed in the Rust core — each training set the
  samples before its test block, ``gap`` samples left out between them; ``cv_kind="kfold"``
  gives the seed's shuffled k-fold (shuffled by ``seed``, each training set the complement);
* a scikit-learn splitter (anything with ``.split(X)``), e.g. ``TimeSeriesSplit(3, test_size=20)``;
* an iterable of ``(train, test)`` index arrays.

Splits are checked in the core: indices in range, training and test sets non-empty and
disjoint; a bad one raises :class:`~thermerr_rs.errors.ParameterError` naming the fold.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from . import _core
from .errors import ParameterError

CvKind = Literal["time", "kfold"]
CV_KINDS: tuple[str, ...] = ("time", "kfold")
Splits = list[tuple[list[int], list[int]]]
I64 = npt.NDArray[np.int64]


def _count(v: Any, name: str, low: int) -> int:
    if isinstance(v, bool) or not isinstance(v, numbers.Integral) or int(v) < low:
        raise ParameterError(f"{name} must be an integer >= {low}, got {v!r}")
    return int(v)


def time_series_split(
    n: int, n_splits: int = 5, *, gap: int = 0, test_size: int | None = None, max_train_size: int | None = None
) -> list[tuple[I64, I64]]:
    """scikit-learn's ``TimeSeriesSplit(n_splits, gap=gap, test_size=test_size,
    max_train_size=max_train_size).split`` over ``n`` samples, index for index, computed by the
    Rust core: ``n_splits`` consecutive test blocks ending at the last sample, each training set
    the samples before its block less the ``gap`` just before it."""
    pairs = _core.time_series_split(
        _count(n, "n", 0), _count(n_splits, "n_splits", 0), gap=_count(gap, "gap", 0),
        test_size=None if test_size is None else _count(test_size, "test_size", 0),
        max_train_size=None if max_train_size is None else _count(max_train_size, "max_train_size", 0),
    )
    return [(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)) for a, b in pairs]


def kfold_split(n: int, n_splits: int = 5, *, seed: int | None = 0) -> list[tuple[I64, I64]]:
    """The seed's shuffled k-fold (``KFold`` fold sizes, shuffled by ``seed``, in order if
    ``None``) as (train, test) pairs, each training set the complement of its test set. Not for
    time series: see :func:`time_series_split`."""
    pairs = _core.kfold_splits(_count(n, "n", 0), _count(n_splits, "n_splits", 0),
                               None if seed is None else int(seed))
    return [(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)) for a, b in pairs]


def _indices(v: Any, fold: int, name: str) -> list[int]:
    a = np.asarray(v)
    if a.ndim != 1 or not (a.dtype.kind in "iu" or a.size == 0):
        raise ParameterError(f"invalid parameter `cv`: fold {fold}: the {name} set must be a 1-d array of integer indices")
    if a.size and a.min() < 0:
        raise ParameterError(f"invalid parameter `cv`: fold {fold}: {name} index {int(a.min())} is negative")
    return [int(i) for i in a]


def resolve_cv(cv: Any, n: int, X: Any = None, *, cv_kind: str = "time", gap: int = 0,
               seed: int | None = 0) -> Splits:
    """The (train, test) splits ``cv`` stands for over ``n`` samples (see the module docstring),
    checked by the core. ``X`` is what a splitter's ``.split`` is given (default ``n`` rows)."""
    if cv_kind not in CV_KINDS:
        raise ParameterError(f"cv_kind must be \"time\" or \"kfold\", got {cv_kind!r}")
    gap = _count(gap, "gap", 0)
    if isinstance(cv, numbers.Integral) and not isinstance(cv, bool):
        if cv_kind == "kfold":
            if gap:
                raise ParameterError("gap applies to time-ordered folds only (cv_kind=\"time\")")
            return _core.kfold_splits(n, _count(cv, "cv", 0), None if seed is None else int(seed))
        return _core.time_series_split(n, _count(cv, "cv", 0), gap=gap)
    if cv_kind != "time" or gap:
        raise ParameterError("cv_kind and gap apply to an int cv; give them to the splitter instead")
    if isinstance(cv, (str, bytes, bool)) or cv is None:
        raise ParameterError(
            f"cv must be a number of folds, a scikit-learn splitter or (train, test) index pairs, got {cv!r}")
    if hasattr(cv, "split"):
        cv = cv.split(np.zeros((n, 1)) if X is None else X)
    if not isinstance(cv, Iterable):
        raise ParameterError(
            f"cv must be a number of folds, a scikit-learn splitter or (train, test) index pairs, got {cv!r}")
    out: Splits = []
    for f, pair in enumerate(cv):
        if not _is_pair(pair):
            raise ParameterError(f"invalid parameter `cv`: fold {f} is not a (train, test) pair of index arrays")
        train, test = pair
        out.append((_indices(train, f, "training"), _indices(test, f, "test")))
    _core.check_splits(out, n)
    return out


def _is_pair(p: Any) -> bool:
    try:
        return len(p) == 2 and all(np.ndim(s) == 1 for s in p)
    except TypeError:
        return False
