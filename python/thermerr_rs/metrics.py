"""Figures of merit (methods.md): one module used by every model, CLI command and report."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from . import _core
from ._arrays import as_vector


@dataclass(frozen=True)
class Scores:
    """Figures of merit of a prediction, residual ``r = measured − predicted`` (µm).

    ``mean_accuracy`` is the mean over samples of ``1 − |r|/|e|``, leaving out the samples whose
    measured error ``|e|`` is at most ``zero_tol`` (listed in ``accuracy_excluded``); it is
    ``None`` when every sample was left out. ``compensation_rate`` is ``1 − RMS(r)/RMS(e)``.
    """

    n: int
    rms: float
    max_abs: float
    band: float
    min_residual: float
    max_residual: float
    mean_accuracy: float | None
    accuracy_excluded: list[int] = field(repr=False)
    zero_tol: float
    compensation_rate: float | None
    rms_measured: float

    def as_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)

    def summary(self) -> dict[str, Any]:
        """The figures with ``accuracy_excluded`` as its count, ``n_accuracy_excluded``: what
        the CLI's ``--json`` and a fleet's summary print (a run of days leaves out thousands of
        rows, one line each in the JSON)."""
        d = self.as_dict()
        d["n_accuracy_excluded"] = len(d.pop("accuracy_excluded"))
        return d

    def __str__(self) -> str:
        def pct(v: float | None) -> str:
            return "n/a" if v is None else f"{100 * v:.2f} %"

        lines = [
            f"samples               {self.n}",
            f"RMS residual          {self.rms:.4g} µm   (before compensation {self.rms_measured:.4g} µm)",
            f"max |residual|        {self.max_abs:.4g} µm",
            f"residual band         {self.band:.4g} µm   ({self.min_residual:.4g} … {self.max_residual:.4g})",
            f"mean accuracy         {pct(self.mean_accuracy)}"
            + (
                f"   ({len(self.accuracy_excluded)} samples with |e| <= {self.zero_tol:.3g} µm left out)"
                if self.accuracy_excluded
                else ""
            ),
            f"compensation rate     {pct(self.compensation_rate)}",
        ]
        return "\n".join(lines)


def scores(measured: Any, predicted: Any, *, zero_tol: float | None = None) -> Scores:
    """Figures of merit of ``predicted`` against ``measured`` (same length, finite).

    ``zero_tol``: measured errors with ``|e| <= zero_tol`` are left out of the mean accuracy
    (default: 5 % of ``max |e|``).
    """
    m = as_vector(measured, "measured")
    p = as_vector(predicted, "predicted", n=m.shape[0])
    return Scores(**_core.scores(m, p, zero_tol))
