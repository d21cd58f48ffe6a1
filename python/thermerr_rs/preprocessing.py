"""Seed 001's preprocessing (Yang et al. 2011): min–max normalise every series, accumulate once
(1-AGO, x⁽¹⁾(k) = Σ_{j≤k} x⁽⁰⁾(j)) to damp noise, model the accumulated series, then difference
back (IAGO) and de-normalise; and the grid search of the RBF spread that minimises the held-out
residual band."""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np
from sklearn.base import clone

from ._arrays import F64, as_matrix, as_vector
from .base import _WRAPPERS, Estimator, SequenceModel, _Wrapper
from .errors import DataError, ParameterError


def ago(x: Any) -> F64:
    """1-AGO along time (axis 0)."""
    return np.cumsum(np.asarray(x, dtype=np.float64), axis=0)


def iago(x1: Any) -> F64:
    """Inverse of :func:`ago`: the first value kept, then first differences."""
    a = np.asarray(x1, dtype=np.float64)
    return np.diff(a, axis=0, prepend=np.zeros((1,) + a.shape[1:]))


@dataclass
class MinMaxAGO:
    """Min–max scaling to [0, 1] by given ranges, then 1-AGO; ``inverse`` undoes both."""

    lo: F64
    hi: F64

    @classmethod
    def fit(cls, x: Any) -> MinMaxAGO:
        a = np.asarray(x, dtype=np.float64)
        lo, hi = a.min(axis=0), a.max(axis=0)
        if np.any(hi - lo <= 0):
            raise DataError("a constant series cannot be min-max normalised")
        return cls(lo, hi)

    def transform(self, x: Any) -> F64:
        return ago((np.asarray(x, dtype=np.float64) - self.lo) / (self.hi - self.lo))

    def inverse(self, x1: Any) -> F64:
        return iago(x1) * (self.hi - self.lo) + self.lo


class AGORegressor(_Wrapper, SequenceModel):
    """Wraps an estimator with seed 001's transform: a clone of ``estimator`` (the estimator
    passed is left untouched) is fitted on the normalised, accumulated inputs and target, and
    predicts by IAGO and de-normalisation.

    The accumulation runs over time, so ``predict`` needs a contiguous sequence of samples from
    the start of a run. The file written by ``save`` is the inner estimator's, with
    ``"preprocessing": {"kind": "minmax_ago", "x_min", "x_max", "y_min", "y_max"}``.

    Fitted attributes: ``estimator_`` (the fitted clone), ``x_tf_``, ``y_tf_`` (the transforms).
    """

    kind = ""
    preprocessing_kind = "minmax_ago"

    def __init__(self, estimator: Estimator) -> None:
        self.estimator = estimator

    @property
    def estimator_(self) -> Estimator:
        """The fitted clone of ``estimator``."""
        self._check_fitted()
        inner: Estimator = self._inner
        return inner

    def _min_samples(self) -> int:
        return 2  # min-max scaling needs two different values

    def _fit(self, x: F64, y: F64) -> None:
        self.x_tf_ = MinMaxAGO.fit(x)
        self.y_tf_ = MinMaxAGO.fit(y)
        inner = clone(self.estimator)
        inner.fit(np.ascontiguousarray(self.x_tf_.transform(x)), self.y_tf_.transform(y))
        self._inner = inner

    def _predict(self, x: F64) -> F64:
        y1 = self._inner._predict_columns(np.ascontiguousarray(self.x_tf_.transform(x)))
        out: F64 = self.y_tf_.inverse(y1)
        return out

    def to_dict(self) -> dict[str, Any]:
        self._check_fitted()
        doc = self._inner.to_dict()
        doc.update(features=self.feature_names_in_, target=self.target_name_, inputs=self.inputs_)
        doc["preprocessing"] = {
            "kind": self.preprocessing_kind,
            "x_min": [float(v) for v in self.x_tf_.lo],
            "x_max": [float(v) for v in self.x_tf_.hi],
            "y_min": float(self.y_tf_.lo),
            "y_max": float(self.y_tf_.hi),
        }
        return doc

    @classmethod
    def _wrap_restored(cls, inner: Estimator, pre: dict[str, Any]) -> AGORegressor:
        out = cls(inner)
        out.x_tf_ = MinMaxAGO(as_matrix(pre["x_min"]).ravel(), as_matrix(pre["x_max"]).ravel())
        out.y_tf_ = MinMaxAGO(np.float64(pre["y_min"]), np.float64(pre["y_max"]))  # type: ignore[arg-type]
        out._inner = inner
        out.n_features_in_ = inner.n_features_in_
        out.feature_names_in_ = inner.feature_names_in_
        out.target_name_ = inner.target_name_
        out.inputs_ = inner.inputs_
        return out


_WRAPPERS[AGORegressor.preprocessing_kind] = AGORegressor


@dataclass(frozen=True)
class SpreadSearch:
    """Result of :func:`spread_search`: the best spread, its held-out residual band, and the
    band of every spread tried."""

    spread: float
    band: float
    spreads: F64
    bands: F64
    test_index: F64

    def __str__(self) -> str:
        return f"best spread {self.spread:.4g}: held-out residual band {self.band:.4g} ({len(self.spreads)} spreads tried)"


def seed001_test_index(n: int) -> F64:
    """Seed 001's split: ⌈n/2⌉ samples at equal spacing are the test set."""
    k = math.ceil(n / 2)
    return np.unique(np.round(np.linspace(0, n - 1, k)).astype(np.int64))  # type: ignore[no-any-return]


def spread_search(
    X: Any,
    y: Any,
    spreads: Any = None,
    *,
    test_index: Any = None,
    design: str = "exact",
    progress: bool | None = None,
    **rbf_params: Any,
) -> SpreadSearch:
    """Seed 001's protocol: min–max normalise and 1-AGO the whole series, train an RBF network on
    the training samples of the accumulated series for every spread of the grid, predict the whole
    accumulated series, restore it (IAGO, de-normalise), and keep the spread whose residual band
    (max − min of measured − predicted) on the test samples is smallest.

    ``spreads`` default: 1.0 to 3.0 in steps of 0.01 (the seed starts at 1.0 and finds 1.21).
    ``test_index`` default: :func:`seed001_test_index`. A progress bar shows on a terminal unless
    ``progress=False``.
    """
    from .rbf import RBFNetwork

    x = as_matrix(X)
    yv = as_vector(y, n=x.shape[0])
    grid = np.arange(1.0, 3.0 + 1e-9, 0.01) if spreads is None else np.asarray(spreads, dtype=np.float64).ravel()
    if grid.size == 0 or np.any(grid <= 0):
        raise ParameterError("spreads must be a non-empty grid of positive numbers")
    n = x.shape[0]
    test = seed001_test_index(n) if test_index is None else np.asarray(test_index, dtype=np.int64)
    if test.size == 0 or test.min() < 0 or test.max() >= n:
        raise ParameterError(f"test_index must select rows within 0..{n - 1}")
    train = np.setdiff1d(np.arange(n), test)
    if train.size < 2:
        raise ParameterError("too few training samples left")
    xt, yt = MinMaxAGO.fit(x), MinMaxAGO.fit(yv)
    x1, y1 = np.ascontiguousarray(xt.transform(x)), yt.transform(yv)
    show = sys.stderr.isatty() if progress is None else progress
    it: Any = grid
    if show:
        from tqdm import tqdm

        it = tqdm(grid, desc="spread search", unit="spread")
    bands = np.empty(grid.size)
    for k, s in enumerate(it):
        net = RBFNetwork(design=design, spread=float(s), **rbf_params).fit(x1[train], y1[train])
        pred = yt.inverse(net.predict(x1))
        r = yv[test] - pred[test]
        bands[k] = float(r.max() - r.min())
    best = int(np.argmin(bands))
    return SpreadSearch(float(grid[best]), float(bands[best]), grid, bands, test.astype(np.float64))
