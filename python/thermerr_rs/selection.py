"""Temperature-sensor selection by fuzzy c-means (seed 003, Su et al. 2011).

Each temperature series, min–max scaled to [0, 1], is one object; fuzzy c-means groups the
series that move together; the partition is hardened by the largest membership; in each
cluster the sensor whose Pearson correlation with the thermal error is largest in magnitude is
kept. Sensors in one cluster carry nearly the same information, so one per cluster gives a
small, weakly coupled set of model inputs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._arrays import F64
from .errors import DataError, ParameterError
from .fcm import FuzzyCMeans


@dataclass
class SensorSelection:
    """Result of :func:`select_sensors`.

    ``selected``: the kept sensor per cluster, in cluster order (empty clusters keep none).
    ``clusters``: {cluster index: sensor names}, hardened by the largest membership.
    ``correlations``: {sensor: Pearson ρ with the error} (signed; selection uses |ρ|).
    ``membership``: n_sensors × n_clusters fuzzy partition, rows in ``sensors`` order.
    ``axis``: the error column, or the list of columns combined into a composite error.
    ``weights``: {error column: weight in the composite} ({axis: 1.0} for one axis).
    ``model``: the fitted :class:`FuzzyCMeans` (objects = sensors).
    """

    selected: list[str]
    clusters: dict[int, list[str]]
    correlations: dict[str, float]
    membership: F64
    axis: str | list[str]
    sensors: list[str] = field(default_factory=list)
    weights: dict[str, float] = field(default_factory=dict)
    model: FuzzyCMeans | None = field(default=None, repr=False)

    @property
    def labels(self) -> dict[str, int]:
        """{sensor: hardened cluster index}."""
        return {s: k for k, names in self.clusters.items() for s in names}

    def to_dict(self) -> dict[str, Any]:
        """The selection as plain data (what ``thermerr select-sensors --json`` prints)."""
        return {
            "axis": self.axis,
            "selected": list(self.selected),
            "clusters": {str(k): list(v) for k, v in self.clusters.items()},
            "correlations": {k: float(v) for k, v in self.correlations.items()},
            "weights": {k: float(v) for k, v in self.weights.items()},
            "sensors": list(self.sensors),
            "membership": [[float(v) for v in row] for row in np.asarray(self.membership)],
        }

    def __str__(self) -> str:
        if isinstance(self.axis, str):
            target = self.axis
        else:
            target = "composite of " + ", ".join(f"{a} ({self.weights.get(a, 0.0):.3f})" for a in self.axis)
        labels = self.labels
        width = max([len("sensor")] + [len(s) for s in self.sensors])
        lines = [
            f"sensor selection: {len(self.sensors)} sensors -> {len(self.selected)}, "
            f"{self.membership.shape[1]} clusters, error = {target}",
            f"{'sensor':<{width}}  cluster  membership      rho  selected",
        ]
        order = sorted(range(len(self.sensors)), key=lambda k: (labels[self.sensors[k]], k))
        for k in order:
            s = self.sensors[k]
            c = labels[s]
            mark = "*" if s in self.selected else ""
            lines.append(
                f"{s:<{width}}  {c:>7d}  {self.membership[k, c]:>10.4f}  {self.correlations[s]:>7.4f}  {mark:^8}"
            )
        lines.append("selected: " + ", ".join(self.selected))
        return "\n".join(lines)


def pick_per_cluster(
    labels: Sequence[int] | Mapping[Any, int],
    correlations: Sequence[float] | Mapping[Any, float],
    names: Sequence[Any] | None = None,
) -> list[Any]:
    """The pure selection step: in each cluster (ascending label), the member with the largest
    |correlation|; on a tie, the first one in order.

    ``labels`` and ``correlations`` are either sequences aligned with ``names`` (default: the
    indices 0..n-1) or mappings from name to value (then ``names`` defaults to the keys of
    ``labels``, in order). Returns one name per non-empty cluster.
    """
    if isinstance(labels, Mapping):
        keys = list(labels) if names is None else list(names)
        lab = [int(labels[k]) for k in keys]
    else:
        lab = [int(v) for v in labels]
        keys = list(range(len(lab))) if names is None else list(names)
    if isinstance(correlations, Mapping):
        rho = [float(correlations[k]) for k in keys]
    else:
        rho = [float(v) for v in correlations]
    if not (len(lab) == len(rho) == len(keys)):
        raise ParameterError(
            f"labels ({len(lab)}), correlations ({len(rho)}) and names ({len(keys)}) differ in length"
        )
    if any(not np.isfinite(r) for r in rho):
        raise DataError("a correlation is not finite")
    best: dict[int, int] = {}
    for k, c in enumerate(lab):
        if c not in best or abs(rho[k]) > abs(rho[best[c]]):
            best[c] = k
    return [keys[best[c]] for c in sorted(best)]


def _pearson(a: F64, b: F64) -> float:
    a = a - a.mean()
    b = b - b.mean()
    return float((a @ b) / np.sqrt((a @ a) * (b @ b)))


def _error_target(run: Any, axis: str | Sequence[str]) -> tuple[F64, dict[str, float], str | list[str]]:
    axes = [axis] if isinstance(axis, str) else list(axis)
    if not axes:
        raise ParameterError("axis: give an E_* column or a list of them")
    cols = []
    for a in axes:
        col = np.asarray(run[a], dtype=np.float64)  # MissingColumnError names an unknown column
        if not str(a).startswith("E_"):
            raise ParameterError(f"axis {a!r} is not an error column (E_*)")
        if not np.all(np.isfinite(col)):
            raise DataError(f"error column `{a}` holds a non-finite value")
        if np.ptp(col) == 0:
            raise DataError(f"error column `{a}` is constant; it cannot be correlated")
        cols.append(col)
    if len(axes) == 1:
        return cols[0], {axes[0]: 1.0}, axis if isinstance(axis, str) else axes
    rms = np.array([np.sqrt(np.mean(c**2)) for c in cols])
    w = rms / rms.sum()
    target = np.sum([wi * np.abs(c) for wi, c in zip(w, cols)], axis=0)
    return target, {a: float(wi) for a, wi in zip(axes, w)}, axes


def select_sensors(
    run: Any,
    axis: str | Sequence[str],
    n_clusters: int = 4,
    seed: int = 0,
    m: float = 2.0,
    sensors: Sequence[str] | None = None,
) -> SensorSelection:
    """Seed 003's sensor selection on a :class:`thermerr_rs.Run`.

    ``axis``: an ``E_*`` column, or a list of them for a composite error. Seed 003 correlated
    with a composite of X, Y and Z "combined by their shares"; here the composite is
    e(t) = Σ_a w_a |E_a(t)| with w_a = RMS(E_a) / Σ_b RMS(E_b): each axis weighted by its share
    of the total error, magnitudes so that axes with opposite sign conventions do not cancel
    (errors are measured from the run's start, so |E_a| is the drift's size). For one axis the
    signed series is used as is. The weights are in ``SensorSelection.weights``.

    ``sensors``: the ``T_*`` columns to choose from (default: all of the run's).
    ``n_clusters``, ``m``, ``seed``: fuzzy c-means parameters (seed 003: 4 clusters, m = 2).

    Errors: an unknown column → MissingColumnError naming it; fewer sensors than clusters →
    ParameterError; a constant series (zero range, cannot be scaled) → DataError naming it.
    """
    names = list(run.temperatures) if sensors is None else [str(s) for s in sensors]
    if isinstance(n_clusters, bool) or not isinstance(n_clusters, (int, np.integer)):
        raise ParameterError(f"n_clusters must be an integer, got {n_clusters!r}")
    if len(names) < max(int(n_clusters), 2):
        raise ParameterError(
            f"{len(names)} sensors cannot form {n_clusters} clusters (need at least as many sensors as clusters)"
        )
    if len(set(names)) != len(names):
        raise ParameterError("sensors: a column is listed twice")
    target, weights, axis_out = _error_target(run, axis)
    series = []
    for s in names:
        col = np.asarray(run[s], dtype=np.float64)
        if not np.all(np.isfinite(col)):
            raise DataError(f"sensor column `{s}` holds a non-finite value")
        lo, hi = float(col.min()), float(col.max())
        if hi == lo:
            raise DataError(f"sensor column `{s}` is constant ({lo}); it cannot be min-max scaled")
        series.append((col - lo) / (hi - lo))
    objects = np.ascontiguousarray(np.vstack(series))
    model = FuzzyCMeans(n_clusters=int(n_clusters), m=m, seed=seed).fit(objects)
    u = model.membership_
    labels = [int(v) for v in model.labels_]
    rho = {s: _pearson(np.asarray(run[s], dtype=np.float64), target) for s in names}
    selected = pick_per_cluster(labels, [rho[s] for s in names], names)
    clusters: dict[int, list[str]] = {}
    for s, c in zip(names, labels):
        clusters.setdefault(c, []).append(s)
    return SensorSelection(
        selected=selected,
        clusters=dict(sorted(clusters.items())),
        correlations=rho,
        membership=u,
        axis=axis_out,
        sensors=names,
        weights=weights,
        model=model,
    )
