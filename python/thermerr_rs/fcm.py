"""Fuzzy c-means clustering (Bezdek), in Rust."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import numpy.typing as npt

from . import _core
from ._arrays import F64, as_matrix
from .base import Estimator


class FuzzyCMeans(Estimator):
    """Fuzzy c-means: each row of ``X`` is one object (for sensor selection: one sensor's
    min–max-scaled time series).

    Minimises J_m(U, V) = Σ_k Σ_i u_ik^m ‖x_k − v_i‖² by Bezdek's alternating updates, the same
    iteration as scikit-fuzzy's ``cmeans`` (memberships normalised and floored at machine epsilon,
    distances floored at epsilon so an object on a centre gets membership 1 there). Stops when the
    Frobenius norm of the change of the partition is below ``tol``, or after ``max_iter``.

    Parameters
    ----------
    n_clusters : number of clusters c (2 ≤ c ≤ number of objects).
    m : weighting exponent, > 1.
    tol : stopping threshold on ‖U⁽ᵇ⁺¹⁾ − U⁽ᵇ⁾‖_F.
    max_iter : iteration cap.
    seed : seed of the random initial partition (same seed, same result).
    init : optional initial partition, n_objects × n_clusters (rows are normalised).

    Fitted attributes: ``centers_`` (c × n_features), ``membership_`` (n_objects × c),
    ``labels_`` (largest membership), ``n_iter_``, ``converged_``, ``objective_`` (last J_m),
    ``objective_history_``.
    """

    kind = "fcm"

    def __init__(
        self,
        *,
        n_clusters: int = 4,
        m: float = 2.0,
        tol: float = 1e-5,
        max_iter: int = 1000,
        seed: int | None = None,
        init: Any = None,
    ) -> None:
        self.n_clusters = n_clusters
        self.m = m
        self.tol = tol
        self.max_iter = max_iter
        self.seed = seed
        self.init = init
        self._inner: _core.FcmModel | None = None

    def fit(self, X: Any, y: Any = None) -> FuzzyCMeans:
        x = as_matrix(X)
        init = None if self.init is None else as_matrix(self.init, "init")
        self._inner = _core.FcmModel.fit(
            x,
            n_clusters=int(self.n_clusters),
            m=float(self.m),
            tol=float(self.tol),
            max_iter=int(self.max_iter),
            seed=None if self.seed is None else int(self.seed),
            init=init,
        )
        self.n_features_in_ = x.shape[1]
        return self

    def _predict(self, x: F64) -> npt.NDArray[np.intp]:  # type: ignore[override]
        return np.argmax(self.predict_membership(x), axis=1)

    def predict_membership(self, X: Any) -> F64:
        """Memberships of new objects to the fitted centres."""
        self._check_fitted()
        assert self._inner is not None
        return self._inner.predict_membership(as_matrix(X))

    def _get(self, name: str) -> Any:
        self._check_fitted()
        return getattr(self._inner, name)

    centers_ = property(lambda self: self._get("centers"))
    membership_ = property(lambda self: self._get("membership"))
    labels_ = property(lambda self: np.asarray(self._get("labels"), dtype=np.intp))
    n_iter_ = property(lambda self: self._get("n_iter"))
    converged_ = property(lambda self: self._get("converged"))
    objective_ = property(lambda self: self._get("objective"))
    objective_history_ = property(lambda self: self._get("objective_history"))

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        p = super().get_params(deep)
        if p["init"] is not None:
            p["init"] = np.asarray(p["init"], dtype=np.float64).tolist()
        return p

    def _state(self) -> dict[str, Any]:
        assert self._inner is not None
        state: dict[str, Any] = json.loads(self._inner.to_json())
        return state

    def _restore(self, state: dict[str, Any]) -> None:
        self._inner = _core.FcmModel.from_json(json.dumps(state))
