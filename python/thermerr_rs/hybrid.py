"""Seed 000 (Kang et al. 2007): LR, MA and AR filters fitted by least squares, their outputs
scaled by C_Y into a tanh network; with the ARMA, FNN and LR/NN variants for comparison."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _core
from ._arrays import F64, feature_names, series_name
from .base import _bridged_for_fit
from .errors import ShapeError
from .grey import _large_n, _Sequential


class HybridFilterNet(_Sequential):
    """The hybrid filter + network of seed 000 and its comparison variants.

    ``variant``: ``"hybrid"`` (LR, MA and AR filter outputs × ``c_y`` into a network),
    ``"arma"`` (the AR filter alone: lagged errors plus the LR and MA outputs), ``"lrnn"`` (the LR
    filter × ``c_y`` into a network), ``"fnn"`` (temperatures × ``c_y`` into a network).
    ``ma_lags`` previous temperature rows feed the MA filter, ``ar_lags`` previous errors the AR
    filter. The network has ``hidden`` tanh units and a tanh output scaled by ``limit`` (seed 000:
    30 units, ±50 µm), initial weights uniform in [−0.5, 0.5]; ``trainer="seed"`` is batch gradient
    descent with momentum for ``max_epochs`` (10 000) iterations, ``"adam"`` Adam until a
    500-epoch plateau. Fit on one time-ordered run, or several with ``fit(X, y, starts=[...])``
    (the first row of each run after the first); predict closed loop or one step ahead.

    **Large n** (``large_n``, 2000 rows by default; ``None``: never; the seed's trainer never): when
    the network trains on at least ``large_n`` rows, Adam trains it on mini-batches instead of the
    whole batch. The rows are cut into blocks of ⌈n/100⌉ consecutive rows and every tenth block is
    held back for validation (10 %, in ten stretches over the run); the others are visited in
    mini-batches of 128 in an order shuffled by ``seed``; at most max(20, ⌈500 000 / training rows⌉)
    epochs (and ``max_epochs``); training stops at the MSE goal or when the validation MSE has not
    improved by 1e-6 (relative) in min(``patience``, 20) epochs, and the network of the lowest
    validation MSE is kept. ``history_`` then holds each epoch's mean mini-batch MSE. Below
    ``large_n`` rows (the seeds' runs) training is the full-batch method, unchanged.
    """

    kind = "hybrid"
    _inner: _core.HybridModel | None = None

    def __init__(self, *, variant: str = "hybrid", ma_lags: int = 1, ar_lags: int = 2, c_y: float = 0.02,
                 limit: float = 50.0, hidden: int = 30, trainer: str = "adam", lr: float = 0.01,
                 momentum: float = 0.9, max_epochs: int = 10000, patience: int = 500, seed: int = 0,
                 large_n: int | None = 2000) -> None:
        self.variant = variant
        self.ma_lags = ma_lags
        self.ar_lags = ar_lags
        self.c_y = c_y
        self.limit = limit
        self.hidden = hidden
        self.trainer = trainer
        self.lr = lr
        self.momentum = momentum
        self.max_epochs = max_epochs
        self.patience = patience
        self.seed = seed
        self.large_n = large_n

    def fit(self, X: Any, y: Any, starts: list[int] | None = None) -> HybridFilterNet:  # type: ignore[override]
        """Fit on one time-ordered run, or on several stacked: ``starts`` are the first rows of
        the runs after the first (no lag crosses from one run into the next)."""
        return self._fit_checked(X, y, names=feature_names(X), target=series_name(y),
                                 starts=starts)

    def _min_samples(self) -> int:
        return max(int(self.ma_lags), int(self.ar_lags)) + 1  # one sample past the longest lag

    def _fit(self, x: F64, y: F64, starts: list[int] | None = None) -> None:
        self._inner = _core.HybridModel.fit(
            x, y, starts=[int(s) for s in (starts or [])], variant=str(self.variant), ma_lags=int(self.ma_lags),
            ar_lags=int(self.ar_lags), c_y=float(self.c_y), limit=float(self.limit), hidden=int(self.hidden),
            trainer=str(self.trainer), lr=float(self.lr), momentum=float(self.momentum),
            max_epochs=int(self.max_epochs), patience=int(self.patience), seed=int(self.seed),
            large_n=_large_n(self.large_n),
        )

    def fit_runs(self, runs: list[Any], target: str, features: list[str], *, inputs: str = "absolute") -> HybridFilterNet:
        """Fit on several runs (their lags never cross from one run into the next)."""
        if not runs:
            raise ShapeError("no runs to fit on")
        for r in runs:
            r.check_fit_columns(target, list(features))
        runs = [_bridged_for_fit(r, list(features)) for r in runs]
        xs = [r.input_matrix(features, inputs) for r in runs]
        ys = [r[target] for r in runs]
        starts = [int(s) for s in np.cumsum([len(v) for v in ys])[:-1]]
        return self._fit_checked(np.vstack(xs), np.concatenate(ys), names=list(features), target=target,
                                 inputs=inputs, starts=starts)

    @property
    def filters_(self) -> tuple[F64, F64, F64]:
        """Coefficients of the LR ([a0, a_i]), MA ([b0, b_ji] lag-major) and AR
        ([c0, c_1..c_K, c_LR, c_MA]) filters."""
        self._check_fitted()
        assert self._inner is not None
        lr, ma, ar = self._inner.filters
        return np.asarray(lr), np.asarray(ma), np.asarray(ar)



