"""Sensor selection by fuzzy c-means (seed 003, Su et al. 2011)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._arrays import F64
from .errors import DataError, ParameterError
from .fcm import FuzzyCMeans
from .run import Run


@dataclass(frozen=True)
class SensorSelection:
    """Result of :func:`select_sensors`.

    ``selected``: the chosen column per cluster, in cluster order. ``clusters``: cluster → its
    sensors. ``correlations``: sensor → Pearson ρ with the error. ``membership``: sensors ×
    clusters. ``sensors``: the candidate columns in the order of ``membership``'s rows.
    """

    axis: str
    sensors: list[str]
    selected: list[str]
    clusters: dict[int, list[str]]
    correlations: dict[str, float]
    membership: F64
    labels: list[int]

    def __str__(self) -> str:
        head = f"{'sensor':<16} {'cluster':>7} {'membership':>10} {'rho':>8}  selected"
        lines = [f"error: {self.axis}", head, "-" * len(head)]
        order = sorted(range(len(self.sensors)), key=lambda k: (self.labels[k], -abs(self.correlations[self.sensors[k]])))
        for k in order:
            name = self.sensors[k]
            mark = "  *" if name in self.selected else ""
            lines.append(
                f"{name:<16} {self.labels[k] + 1:>7} {self.membership[k, self.labels[k]]:>10.3f} "
                f"{self.correlations[name]:>8.4f}{mark}"
            )
        lines.append(f"selected: {', '.join(self.selected)}")
        return "\n".join(lines)


def pick_per_cluster(labels: Sequence[int], correlations: Sequence[float]) -> dict[int, int]:
    """Seed 003's rule: in each cluster, the member whose |ρ| with the error is largest.

    Returns cluster → index of the chosen member (ties: the first in order).
    """
    if len(labels) != len(correlations):
        raise ParameterError("labels and correlations differ in length")
    best: dict[int, int] = {}
    for k, (lab, rho) in enumerate(zip(labels, correlations)):
        if lab not in best or abs(rho) > abs(correlations[best[lab]]):
            best[lab] = k
    return dict(sorted(best.items()))


def _error_series(run: Run, axis: str | Sequence[str]) -> tuple[str, F64]:
    if isinstance(axis, str):
        return axis, np.asarray(run[axis], dtype=np.float64)
    names = list(axis)
    if not names:
        raise ParameterError("axis: give an E_* column or a list of them")
    cols = np.column_stack([run[a] for a in names])
    # composite error: the resultant displacement (Euclidean norm of the axes' errors), the
    # magnitude that seed 003 correlates against when it combines X, Y and Z
    return "|" + ",".join(names) + "|", np.sqrt(np.sum(cols**2, axis=1))


def select_sensors(
    run: Run,
    axis: str | Sequence[str],
    n_clusters: int = 4,
    seed: int | None = 0,
    *,
    m: float = 2.0,
    sensors: Sequence[str] | None = None,
    tol: float = 1e-5,
    max_iter: int = 1000,
) -> SensorSelection:
    """Seed 003's procedure: each temperature series, min–max scaled to [0, 1], is one object;
    fuzzy c-means groups them into ``n_clusters``; each sensor goes to its cluster of largest
    membership; in each cluster the sensor whose |Pearson ρ| with the error is largest is kept.

    ``axis``: an ``E_*`` column, or a list of them for a composite error (their Euclidean norm).
    ``sensors``: candidate columns (default: every ``T_*`` column of the run).
    """
    label, err = _error_series(run, axis)
    names = list(sensors) if sensors is not None else run.temperatures
    if len(names) < n_clusters:
        raise ParameterError(f"{len(names)} sensors cannot form {n_clusters} clusters")
    series = []
    for name in names:
        s = np.asarray(run[name], dtype=np.float64)
        lo, hi = s.min(), s.max()
        if hi - lo <= 0:
            raise DataError(f"{run.source}: column `{name}` is constant; it cannot be clustered")
        series.append((s - lo) / (hi - lo))
    x = np.ascontiguousarray(np.vstack(series))
    if np.ptp(err) <= 0:
        raise DataError(f"{run.source}: the error {label} is constant; nothing to correlate with")
    rho = [float(np.corrcoef(run[n], err)[0, 1]) for n in names]
    fcm = FuzzyCMeans(n_clusters=n_clusters, m=m, tol=tol, max_iter=max_iter, seed=seed).fit(x)
    labels = [int(v) for v in fcm.labels_]
    chosen = pick_per_cluster(labels, rho)
    clusters: Mapping[int, list[str]] = {
        c: [names[k] for k in range(len(names)) if labels[k] == c] for c in sorted(set(labels))
    }
    return SensorSelection(
        axis=label,
        sensors=names,
        selected=[names[k] for k in chosen.values()],
        clusters=dict(clusters),
        correlations=dict(zip(names, rho)),
        membership=fcm.membership_,
        labels=labels,
    )
