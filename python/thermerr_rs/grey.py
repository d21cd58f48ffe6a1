"""Seed 002 (Zhang & Yang 2011): rolling grey models GM(1,N) combined by a BP network, with GM
alone and BP alone for comparison. Trained and evaluated in Rust."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _core
from ._arrays import F64, as_vector, feature_names
from .base import Regressor, SequenceModel, _continued
from .errors import ModelFormatError


def _net_kw(est: Any) -> dict[str, Any]:
    """The network keywords; ``goal=None`` is the trainer's goal (0.01 seed, 1e-5 Adam)."""
    return dict(
        trainer=str(est.trainer), lr=float(est.lr), momentum=float(est.momentum),
        max_epochs=int(est.max_epochs), goal=None if est.goal is None else float(est.goal),
        patience=int(est.patience), seed=int(est.seed),
    )


def _large_n(v: int | None) -> int:
    """``large_n`` as the core takes it: 0 for never."""
    if v is None:
        return 0
    v = int(v)
    if v <= 0:
        from .errors import ParameterError

        raise ParameterError(f"invalid parameter `large_n`: must be >= 100 (or None), got {v}")
    return v


class _Sequential(SequenceModel):
    """A model of a time-ordered series whose prediction at step k uses the errors before k."""

    def predict(self, X: Any, y_measured: Any = None) -> F64:  # type: ignore[override]
        """Closed loop (the model's own previous outputs fill the windows), or one step ahead
        from the measured errors ``y_measured`` (the error of step k−1 enters at step k)."""
        return self._predict(self._check_X(X, feature_names(X)), y_measured)

    def _predict_columns(self, x: F64, y_measured: Any = None) -> F64:
        return self._predict(self._check_X(x, self.feature_names_in_), y_measured)

    def _predict(self, x: F64, y_measured: Any = None) -> F64:
        y = None if y_measured is None else as_vector(y_measured, n=x.shape[0])
        out: F64 = self._inner.predict(x, y)
        return out

    def predict_run(self, run: Any, *, one_step: bool = False, shape: Any = None, after: Any = None,
                    reference: Any = None) -> F64:
        """Predict a run closed loop, or one step ahead from its measured target column;
        ``shape``, ``after`` and ``reference`` as in :meth:`Estimator.predict_run`."""
        if after is not None:
            return _continued(self.predict_run, run, after, shape, one_step=one_step, reference=reference)
        x = self._run_matrix(run, reference)
        if one_step:
            if not self.target_name_:
                raise ModelFormatError("this model does not record its target column")
            y = self._predict_columns(x, run[self.target_name_])
        else:
            y = self._predict_columns(x)
        if shape is None:
            return y
        from .shaping import shape_offsets

        return shape_offsets(run.time_s, y, shape)


    @property
    def history_(self) -> F64:
        """Training MSE (normalised) after each epoch of the network."""
        self._check_fitted()
        h: F64 = self._inner.history
        return h


class GreyBP(_Sequential):
    """Rolling GM(1,N) models over ``windows`` previous samples (6, 8 and 10 by default), each
    refitted at every step, whose predictions — min–max normalised by their training ranges —
    feed a BP network (``hidden`` sigmoid units, linear output) trained to the normalised error.

    ``trainer="seed"`` is seed 002's batch gradient descent with momentum (lr 0.01, momentum 0.9,
    ≤ 8000 epochs, MSE goal 0.01, initial weights uniform in [−1, 1]); ``"adam"`` trains the same
    network with Adam until the MSE goal (1e-5 by default) or a 500-epoch plateau. Fit on a
    time-ordered series; see :meth:`predict` for closed-loop and one-step-ahead prediction.

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

    kind = "greybp"
    _inner: _core.GreyModel | None = None

    def __init__(self, *, windows: tuple[int, ...] | list[int] = (6, 8, 10), hidden: int = 7,
                 trainer: str = "adam", lr: float = 0.01, momentum: float = 0.9, max_epochs: int = 8000,
                 goal: float | None = None, patience: int = 500, seed: int = 0,
                 large_n: int | None = 2000) -> None:
        self.windows = windows
        self.hidden = hidden
        self.trainer = trainer
        self.lr = lr
        self.momentum = momentum
        self.max_epochs = max_epochs
        self.goal = goal
        self.patience = patience
        self.seed = seed
        self.large_n = large_n

    def _fit(self, x: F64, y: F64) -> None:
        self._inner = _core.GreyModel.fit(x, y, windows=[int(w) for w in self.windows],
                                          hidden=int(self.hidden), large_n=_large_n(self.large_n),
                                          **_net_kw(self))



class GM1N(_Sequential):
    """A rolling GM(1,N) alone: refitted on the ``window`` previous samples at every step, its
    restored time response is the prediction (seed 002's "GM" baseline)."""

    kind = "gm1n"
    _inner: _core.GreyModel | None = None

    def __init__(self, *, window: int = 8) -> None:
        self.window = window

    def _fit(self, x: F64, y: F64) -> None:
        self._inner = _core.GreyModel.fit_gm1n(x, y, window=int(self.window))


    @property
    def history_(self) -> F64:
        return np.empty(0)


class BPNetwork(Regressor):
    """A BP network regressor on the temperatures (seed 002's "BP" baseline): inputs and error
    min–max scaled by the training ranges, ``hidden`` sigmoid units (a list for several layers),
    linear output; trainers and the large-n rule (``large_n``, 2000 rows by default) as in
    :class:`GreyBP`."""

    kind = "bp"
    _inner: _core.BpModel | None = None

    def __init__(self, *, hidden: int | list[int] = 7, trainer: str = "adam", lr: float = 0.01,
                 momentum: float = 0.9, max_epochs: int = 8000, goal: float | None = None,
                 patience: int = 500, seed: int = 0, large_n: int | None = 2000) -> None:
        self.hidden = hidden
        self.trainer = trainer
        self.lr = lr
        self.momentum = momentum
        self.max_epochs = max_epochs
        self.goal = goal
        self.patience = patience
        self.seed = seed
        self.large_n = large_n

    def _fit(self, x: F64, y: F64) -> None:
        hidden = [int(self.hidden)] if isinstance(self.hidden, (int, np.integer)) else [int(h) for h in self.hidden]
        self._inner = _core.BpModel.fit(x, y, hidden=hidden, large_n=_large_n(self.large_n), **_net_kw(self))

    def _predict(self, x: F64) -> F64:
        assert self._inner is not None
        return self._inner.predict(x)



    @property
    def history_(self) -> F64:
        self._check_fitted()
        assert self._inner is not None
        return self._inner.history
