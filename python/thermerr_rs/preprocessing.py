"""Seed 001's preprocessing (Yang et al. 2011): min–max normalise every series, accumulate once
(1-AGO, x⁽¹⁾(k) = Σ_{j≤k} x⁽⁰⁾(j)) to damp noise, model the accumulated series, then difference
back (IAGO) and de-normalise; and the grid search of the RBF spread that minimises the held-out
residual band."""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from sklearn.base import clone

from ._arrays import F64, as_matrix, as_vector
from . import _core
from .base import Estimator, Regressor, SequenceModel, _Wrapper
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
    """Min–max scaling to [0, 1] by given ranges, then 1-AGO; ``inverse`` undoes both, for one
    series (1-D) or one per column (2-D). The arithmetic is the core's, as in
    :class:`AGORegressor` and on the edge: a series whose range has zero width maps to 0.5."""

    lo: F64
    hi: F64

    @classmethod
    def fit(cls, x: Any) -> MinMaxAGO:
        a = np.asarray(x, dtype=np.float64)
        if a.size == 0:
            raise DataError("an empty series cannot be min-max normalised")
        return cls(a.min(axis=0), a.max(axis=0))

    def _column(self, j: int | None) -> Any:
        lo, hi = (self.lo, self.hi) if j is None else (self.lo[j], self.hi[j])
        doc = {"kind": "minmax_ago", "x_min": [float(lo)], "x_max": [float(hi)],
               "y_min": float(lo), "y_max": float(hi)}
        return _core.Preprocessing.from_json(json.dumps(doc), 1)

    def transform(self, x: Any) -> F64:
        a = np.ascontiguousarray(x, dtype=np.float64)
        if a.ndim == 1:
            out: F64 = self._column(None).transform_target(a)
            return out
        return np.column_stack([self._column(j).transform_target(np.ascontiguousarray(a[:, j]))
                                for j in range(a.shape[1])])

    def inverse(self, x1: Any) -> F64:
        a = np.ascontiguousarray(x1, dtype=np.float64)
        if a.ndim == 1:
            out: F64 = self._column(None).inverse(a)
            return out
        return np.column_stack([self._column(j).inverse(np.ascontiguousarray(a[:, j]))
                                for j in range(a.shape[1])])


class _Preprocessed(_Wrapper, Estimator):
    """An estimator fitted on preprocessed inputs (and target); the arithmetic is the core's
    (``thermerr_core::artifact::Preprocessing``), the same the edge runs. A clone of
    ``estimator`` is fitted (the estimator passed is left untouched). The file written by
    ``save`` is the inner estimator's with a ``"preprocessing"`` entry, so the edge reads it.

    Fitted attributes: ``estimator_`` (the fitted clone), ``pre_`` (the core's preprocessing,
    with ``transform``, ``transform_target``, ``inverse``)."""

    kind = ""  # not a model kind of its own: see ``preprocessing`` in the file
    preprocessing_kind: ClassVar[str] = ""

    def __init__(self, estimator: Estimator) -> None:
        self.estimator = estimator

    @property
    def estimator_(self) -> Estimator:
        """The fitted clone of ``estimator``."""
        self._check_fitted()
        inner: Estimator = self._inner
        return inner

    def _min_samples(self) -> int:
        return 2  # a training range needs two samples

    def _fit(self, x: F64, y: Any) -> None:
        self.pre_ = _core.Preprocessing.fit(self.preprocessing_kind, x, y)
        inner = clone(self.estimator)
        inner.fit(self.pre_.transform(x), self.pre_.transform_target(y))
        self._inner = inner

    def _predict(self, x: F64) -> F64:
        out: F64 = self.pre_.inverse(self._inner._predict_columns(self.pre_.transform(x)))
        return out

    def _file_kind(self) -> str:
        return self.estimator_._file_kind()

    def _fitted(self) -> Any:
        return self.estimator_._fitted()

    def _header(self) -> dict[str, Any]:
        head = self.estimator_._header()
        head.update(features=self.feature_names_in_, target=self.target_name_, inputs=self.inputs_,
                    preprocessing=json.loads(self.pre_.to_json()))
        return head

    @classmethod
    def _wrap_restored(cls, inner: Estimator, pre: Any) -> _Preprocessed:
        out = cls(inner)
        out.pre_ = pre
        out._inner = inner
        out.n_features_in_ = inner.n_features_in_
        out.feature_names_in_ = inner.feature_names_in_
        out.target_name_ = inner.target_name_
        out.inputs_ = inner.inputs_
        return out


class MinMaxScaled(_Preprocessed, Regressor):
    """``estimator`` fitted on inputs min–max scaled to [0, 1] by the training ranges (a
    constant column maps to 0.5).

    MATLAB users know this as ``mapminmax`` before ``newrb``: RBF spreads are then comparable
    across sensors. The file written by ``save`` is the inner estimator's, with
    ``"preprocessing": {"kind": "minmax", "x_min": [...], "x_max": [...]}``.
    """

    preprocessing_kind = "minmax"


class AGORegressor(_Preprocessed, SequenceModel):
    """Wraps an estimator with seed 001's transform: it is fitted on the normalised, accumulated
    inputs and target, and predicts by IAGO and de-normalisation.

    The accumulation runs over time, so ``predict`` needs a contiguous sequence of samples from
    the start of a run. The file written by ``save`` is the inner estimator's, with
    ``"preprocessing": {"kind": "minmax_ago", "x_min", "x_max", "y_min", "y_max"}``.
    """

    preprocessing_kind = "minmax_ago"


@dataclass(frozen=True)
class SpreadSearch:
    """Result of :func:`spread_search`: the best spread, its held-out residual band, the band of
    every spread tried, every held-out sample (``test_index``) and the (train, test) index pairs
    used (``folds``)."""

    spread: float
    band: float
    spreads: F64
    bands: F64
    test_index: F64
    folds: list[tuple[list[int], list[int]]] = field(default_factory=list, repr=False)

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
    cv: Any = 5,
    cv_kind: str = "time",
    gap: int = 0,
    test_index: Any = None,
    design: str = "exact",
    progress: bool | None = None,
    **rbf_params: Any,
) -> SpreadSearch:
    """Seed 001's spread search, validated in time order: for every split of ``cv`` and every
    spread of the grid, min–max normalise (by the training samples' ranges) and 1-AGO the series
    from its start, train an RBF network on the training samples of the accumulated series,
    predict the accumulated series, restore it (IAGO, de-normalise), and take the residual band
    (max − min of measured − predicted) on the split's test samples; keep the spread whose band,
    averaged over the splits, is smallest.

    ``cv`` as in :func:`~thermerr_rs.tune_svr` (see :mod:`thermerr_rs.folds`): by default 5
    time-ordered splits (scikit-learn's ``TimeSeriesSplit(5, gap=gap)``: every network is trained
    on samples before the ones it is scored on); ``cv_kind="kfold"`` for shuffled folds, a
    scikit-learn splitter, or (train, test) index pairs. ``test_index`` instead gives seed 001's
    own protocol: one split, the given test samples (e.g. :func:`seed001_test_index`, ⌈n/2⌉
    equally spaced samples) against all the others, normalised by the whole series' ranges —
    interleaved, so it trains on samples after the ones it scores.

    ``spreads`` default: 1.0 to 3.0 in steps of 0.01 (the seed starts at 1.0 and finds 1.21).
    A progress bar shows on a terminal unless ``progress=False``.
    """
    from .folds import resolve_cv
    from .rbf import RBFNetwork

    x = as_matrix(X)
    yv = as_vector(y, n=x.shape[0])
    grid = np.arange(1.0, 3.0 + 1e-9, 0.01) if spreads is None else np.asarray(spreads, dtype=np.float64).ravel()
    if grid.size == 0 or np.any(grid <= 0):
        raise ParameterError("spreads must be a non-empty grid of positive numbers")
    n = x.shape[0]
    seed_protocol = test_index is not None
    if seed_protocol:
        test = np.asarray(test_index, dtype=np.int64)
        if test.size == 0 or test.min() < 0 or test.max() >= n:
            raise ParameterError(f"test_index must select rows within 0..{n - 1}")
        train = np.setdiff1d(np.arange(n), test)
        if train.size < 2:
            raise ParameterError("too few training samples left")
        folds = [([int(i) for i in train], [int(i) for i in test])]
    else:
        folds = resolve_cv(cv, n, X, cv_kind=cv_kind, gap=gap)
        for f, (tr, _) in enumerate(folds):
            if len(tr) < 2:
                raise ParameterError(f"invalid parameter `cv`: fold {f}: too few training samples ({len(tr)})")
    prepared = []
    for tr, te in folds:
        rows = slice(None) if seed_protocol else np.asarray(tr)
        xt, yt = MinMaxAGO.fit(x[rows]), MinMaxAGO.fit(yv[rows])
        prepared.append((np.asarray(tr), np.asarray(te), yt, np.ascontiguousarray(xt.transform(x)),
                         yt.transform(yv)))
    show = sys.stderr.isatty() if progress is None else progress
    it: Any = grid
    if show:
        from tqdm import tqdm

        it = tqdm(grid, desc="spread search", unit="spread")
    bands = np.empty(grid.size)
    for k, s in enumerate(it):
        per = []
        for rows_train, rows_test, yt, x1, y1 in prepared:
            net = RBFNetwork(design=design, spread=float(s), **rbf_params).fit(x1[rows_train], y1[rows_train])
            pred = yt.inverse(net.predict(x1))
            r = yv[rows_test] - pred[rows_test]
            per.append(float(r.max() - r.min()))
        bands[k] = float(np.mean(per))
    best = int(np.argmin(bands))
    test = np.unique(np.concatenate([np.asarray(te, dtype=np.int64) for _, te in folds]))
    return SpreadSearch(float(grid[best]), float(bands[best]), grid, bands, test.astype(np.float64), folds)
