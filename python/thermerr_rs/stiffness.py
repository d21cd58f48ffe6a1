"""Key thermal stiffness identification (seed 001, Yang et al. 2011).

Thermal stiffness is a part's temperature rise per unit of thermal deformation (°C/µm). Once a
model maps temperatures to the error, take one sample at thermal equilibrium, raise one sensor's
temperature by η at a time, predict, and compare with the measured error: ε_i = ê_i − e. The
sensors whose ε_i stands outside the model's own residual band (ê − e over the run) mark the parts
whose stiffness governs the axis — a small temperature change there moves the tool more than the
model's error does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._arrays import F64
from .base import Estimator
from .errors import DataError, ModelFormatError, ParameterError


@dataclass(frozen=True)
class StiffnessResult:
    """Outcome of :func:`key_thermal_stiffness`, one entry per model input (sensor)."""

    sensors: list[str]
    #: the sample used and its time
    index: int
    time_s: float
    eta: float
    #: measured error and the model's prediction at that sample, µm
    measured: float
    predicted: float
    #: ε_i = ê_i − e for each sensor raised by η, µm
    epsilon: F64
    #: the model's sensitivity (ê_i − ê)/η, µm/°C, and the thermal stiffness η/(ê_i − ê), °C/µm
    sensitivity: F64
    stiffness: F64
    #: the residual band of the model on the run: min and max of ê − e, µm
    band: tuple[float, float]
    #: sensors whose ε_i lies outside the band
    flagged: list[str]

    def table(self) -> str:
        lo, hi = self.band
        lines = [
            f"key thermal stiffness at t = {self.time_s:g} s (sample {self.index}), eta = {self.eta:g} °C: "
            f"measured {self.measured:.3f} µm, model {self.predicted:.3f} µm, residual band [{lo:.3f}, {hi:.3f}] µm",
            f"{'sensor':<24} {'epsilon µm':>11} {'µm/°C':>9} {'°C/µm':>9}  key",
        ]
        for k, s in enumerate(self.sensors):
            st = self.stiffness[k]
            lines.append(
                f"{s:<24} {self.epsilon[k]:>11.3f} {self.sensitivity[k]:>9.3f} "
                f"{(f'{st:.3f}' if np.isfinite(st) else 'inf'):>9}  {'yes' if s in self.flagged else ''}"
            )
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        return {
            "sensors": self.sensors, "index": self.index, "time_s": self.time_s, "eta": self.eta,
            "measured": self.measured, "predicted": self.predicted,
            "epsilon": self.epsilon.tolist(), "sensitivity": self.sensitivity.tolist(),
            "stiffness": [float(v) if np.isfinite(v) else None for v in self.stiffness],
            "band": list(self.band), "flagged": self.flagged,
        }


def equilibrium_index(run: Any, sensors: list[str]) -> int:
    """The sample in the second half of the run where the sensors change least: the smallest
    largest rate of change, each sensor's rate taken relative to its range over the run
    (centred differences over ±max(1, n/40) samples)."""
    x = run.matrix(sensors)
    t = run.time_s
    n = len(t)
    if n < 5:
        raise DataError(f"{run.source}: {n} samples are too few to find a thermal equilibrium")
    w = max(1, n // 40)
    span = np.ptp(x, axis=0)
    span[span <= 0] = 1.0
    k = np.arange(w, n - w)
    rate = np.abs(x[k + w] - x[k - w]) / (t[k + w] - t[k - w])[:, None] / span
    score = rate.max(axis=1)
    half = k >= n // 2
    if not half.any():
        half[:] = True
    return int(k[half][np.argmin(score[half])])


def key_thermal_stiffness(
    model: Estimator,
    run: Any,
    at: float | None = None,
    eta: float = 0.5,
    *,
    target: str | None = None,
) -> StiffnessResult:
    """Seed 001's key thermal stiffness identification on any fitted model of the library.

    ``model`` must have been fitted on a run (``fit_run``), so that it knows its sensor columns,
    input form and target. ``at`` is a time in seconds (the nearest sample is used); by default the
    sample at thermal equilibrium (:func:`equilibrium_index`). ``eta`` is the temperature step in
    °C (the seed: 0.1 is too small to see, 1.0 leaves the training range). Models that read a
    sequence (AGO preprocessing, grey or filter models) are fed the run up to that sample with the
    step applied to its last row.
    """
    feats = getattr(model, "feature_names_in_", None)
    if not feats:
        raise ModelFormatError("the model does not record its sensor columns: fit it with fit_run")
    tgt = target or getattr(model, "target_name_", None)
    if not tgt:
        raise ModelFormatError("the model does not record its target axis: pass target=")
    if not (np.isfinite(eta) and eta != 0):
        raise ParameterError(f"eta must be a finite, non-zero temperature step, got {eta!r}")
    e = run[tgt]
    inputs = getattr(model, "inputs_", "absolute")
    if at is None:
        k = equilibrium_index(run, list(feats))
    else:
        if not np.isfinite(at) or at < run.time_s[0] or at > run.time_s[-1]:
            raise ParameterError(
                f"at={at!r} s is outside the run ({run.time_s[0]:g} to {run.time_s[-1]:g} s)")
        k = int(np.argmin(np.abs(run.time_s - at)))
    x = run.input_matrix(list(feats), inputs)
    # the columns are the model's own, in its order: predict without the feature-name warning
    predict = model._predict_columns
    pred = np.asarray(predict(x), dtype=np.float64)
    resid = pred - e
    band = (float(resid.min()), float(resid.max()))
    seq = np.ascontiguousarray(x[: k + 1])
    base = float(predict(seq)[-1])
    eps = np.empty(len(feats))
    for i in range(len(feats)):
        xs = seq.copy()
        xs[-1, i] += eta
        eps[i] = float(predict(xs)[-1]) - e[k]
    sens = (eps + e[k] - base) / eta
    with np.errstate(divide="ignore"):
        stiff = np.where(sens != 0, 1.0 / np.where(sens != 0, sens, 1.0), np.inf)
    flagged = [f for f, v in zip(feats, eps) if v < band[0] or v > band[1]]
    return StiffnessResult(list(feats), k, float(run.time_s[k]), float(eta), float(e[k]), base,
                           eps, sens, stiff, band, flagged)
