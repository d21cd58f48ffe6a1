"""Sensor faults: the guard a model file carries to the edge.

A broken thermocouple reads -273 or 1372 degC, a loose cable gives empty fields, a frozen
transmitter repeats one value, a ground fault spikes; each would go through a model into a
compensation offset of any size. :func:`add_guard` learns per-sensor limits from the training run
(a plausible range, a largest rate of change, a stuck-value time) and fits one fallback model
without each sensor; they are written into the model file. ``thermerr-edge`` and
:func:`predict_guarded` then replace a faulty reading by the last good one for ``hold_s``
seconds (status ``held:T_x``), predict with the fallback model beyond that
(``fallback:T_x``), or repeat the last output when none applies (``frozen:T_x``). The rules and
their numbers are the core's (``thermerr_core::guard``); docs/edge.md explains them.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _core
from ._arrays import F64
from .base import Estimator
from .errors import ModelFormatError, ShapeError
from .run import Run

#: default seconds a faulty reading is replaced by the last good one
DEFAULT_HOLD_S = 300.0


@dataclass(frozen=True)
class GuardedPrediction:
    """Predictions of a guarded model over a run (NaN while a sensor has not yet given a good
    reading) and each row's status (``ok``, ``held:T_x``, ``fallback:T_x``, ``frozen:T_x``,
    ``waiting:T_x``, several joined by ``;``)."""

    y: F64
    status: list[str]


def _features(model: Estimator) -> list[str]:
    names = getattr(model, "feature_names_in_", None)
    if not names or not getattr(model, "target_name_", None):
        raise ModelFormatError("a guard needs a model fitted on a run (fit_run), which records its columns")
    return list(names)


def add_guard(model: Estimator, run: Run, *, hold_s: float = DEFAULT_HOLD_S, fallbacks: bool = True,
              progress: Callable[[int, int, str], None] | None = None) -> Estimator:
    """Learn sensor-fault limits from ``run`` (the model's training run) and, with ``fallbacks``,
    fit one model without each sensor (same estimator and parameters, same run); store them in
    ``model.guard_``, written into the model file by ``save``. Fallbacks are fitted only for
    models whose prediction depends on the current sample alone (MLR, RBF, SVR, BP); for the
    others a sensor out beyond ``hold_s`` freezes the output. The fallbacks cost one fit per
    sensor (``fallbacks=False`` skips them); ``progress(k, n, sensor)`` is called before each.
    Returns ``model``."""
    from sklearn.base import clone

    features = _features(model)
    target = model.target_name_
    assert target is not None
    guard_json, takes_fallbacks, repeats = _core.guard_from_training(
        model.to_json(), np.ascontiguousarray(run.matrix(features)), run.time_s, float(hold_s)
    )
    for j, row, seconds in repeats:
        warnings.warn(
            f"{run.source}: {features[j]} repeats one reading for {seconds:.0f} s from row {row + 1} of the "
            f"training run: if that sensor was stuck, the model learnt from it and the guard will call it "
            f"stuck only after {2 * seconds:.0f} s (fit on a run without it); a logger's coarse resolution "
            "on a steady temperature repeats too",
            UserWarning,
            stacklevel=2,
        )
    guard: dict[str, Any] = json.loads(guard_json)
    history = getattr(model, "input_history_", None)
    taus = history["tau_s"] if history else None
    if fallbacks and takes_fallbacks and len(features) >= 2:
        for k, name in enumerate(features):
            if progress is not None:
                progress(k + 1, len(features), name)
            rest = [f for f in features if f != name]
            reduced = clone(model).fit_run(run, target, rest, inputs=model.inputs_, history=taus)
            guard["fallbacks"].append({"without": name, "model": reduced.to_dict()})
    model.guard_ = guard
    model.to_json()  # the core validates the whole file, guard included, now rather than at save
    return model


def _columns(data: Run | Mapping[str, Any], features: list[str]) -> tuple[F64, F64 | None]:
    if isinstance(data, Run):
        return np.ascontiguousarray(data.matrix(features)), data.time_s
    missing = [f for f in features if f not in data]
    if missing:
        raise ShapeError(f"the data has no column {', '.join(missing)}")
    x = np.column_stack([np.asarray(data[f], dtype=np.float64) for f in features])
    times = np.asarray(data["time_s"], dtype=np.float64) if "time_s" in data else None
    return np.ascontiguousarray(x), times


def predict_guarded(model: Estimator, data: Run | Mapping[str, Any]) -> GuardedPrediction:
    """Predict ``data`` (a :class:`Run`, or a mapping of column name to values such as a pandas
    DataFrame, where missing readings are NaN) row by row through the model's guard, exactly as
    ``thermerr-edge`` does."""
    features = _features(model)
    if getattr(model, "guard_", None) is None:
        raise ModelFormatError("this model has no guard: call thermerr_rs.add_guard(model, run) first")
    x, times = _columns(data, features)
    y, status = _core.predict_guarded(model.to_json(), x, times)
    return GuardedPrediction(y, status)
