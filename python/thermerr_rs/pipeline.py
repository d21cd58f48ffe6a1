"""Input scaling in front of any estimator, recorded in the model file so that a model fitted on
scaled inputs predicts from raw sensor readings (on the edge too)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._arrays import F64, as_matrix
from .base import _WRAPPERS, Estimator, Regressor, _from_dict, _Wrapper
from .errors import DataError


class MinMaxScaled(_Wrapper, Regressor):
    """``estimator`` fitted on inputs min–max scaled to [0, 1] by the training ranges.

    MATLAB users know this as ``mapminmax`` before ``newrb``: RBF spreads are then comparable
    across sensors. The file written by ``save`` is the inner estimator's, with
    ``"preprocessing": {"kind": "minmax", "x_min": [...], "x_max": [...]}``.
    """

    kind = ""  # not a model kind of its own: see ``preprocessing`` in the file
    preprocessing_kind = "minmax"

    def __init__(self, estimator: Estimator) -> None:
        self.estimator = estimator

    def _fit(self, x: F64, y: F64) -> None:
        lo, hi = x.min(axis=0), x.max(axis=0)
        const = np.flatnonzero(hi - lo <= 0)
        if const.size:
            raise DataError(f"input column {int(const[0])} is constant: it cannot be min-max scaled")
        self.x_min_, self.x_max_ = lo, hi
        self.estimator.fit(self._scale(x), y)
        self._inner = self.estimator

    def _scale(self, x: F64) -> F64:
        return np.ascontiguousarray((x - self.x_min_) / (self.x_max_ - self.x_min_))

    def _predict(self, x: F64) -> F64:
        return self._inner._predict_columns(self._scale(x))

    def to_dict(self) -> dict[str, Any]:
        self._check_fitted()
        doc = self.estimator.to_dict()
        doc["features"] = self.feature_names_in_
        doc["target"] = self.target_name_
        doc["inputs"] = self.inputs_
        doc["preprocessing"] = {
            "kind": self.preprocessing_kind,
            "x_min": [float(v) for v in self.x_min_],
            "x_max": [float(v) for v in self.x_max_],
        }
        return doc

    @classmethod
    def _wrap_restored(cls, inner: Estimator, pre: dict[str, Any]) -> MinMaxScaled:
        out = cls(inner)
        out.x_min_ = as_matrix(pre["x_min"], "x_min").ravel()
        out.x_max_ = as_matrix(pre["x_max"], "x_max").ravel()
        if out.x_min_.shape != out.x_max_.shape or out.x_min_.shape[0] != inner.n_features_in_:
            raise DataError("preprocessing x_min/x_max do not match the model's feature count")
        out._inner = inner
        out.n_features_in_ = inner.n_features_in_
        out.feature_names_in_ = inner.feature_names_in_
        out.target_name_ = inner.target_name_
        out.inputs_ = inner.inputs_
        return out

    @classmethod
    def from_dict(cls, doc: dict[str, Any]) -> Estimator:
        return _from_dict(doc)


_WRAPPERS[MinMaxScaled.preprocessing_kind] = MinMaxScaled
