"""Fuzzy c-means clustering (Bezdek), the clustering step of seed 003's sensor selection."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from . import _core
from ._arrays import F64, feature_names
from .base import Clusterer
from .errors import ParameterError

I64 = npt.NDArray[np.int64]


class FuzzyCMeans(Clusterer):
    """Fuzzy c-means: every object (a row of ``X``) belongs to every cluster with a membership
    in [0, 1], the memberships of an object summing to 1.

    Minimises J_m = Σ_k Σ_i u_ik^m ‖x_k − v_i‖² by Bezdek's alternating updates. The loop is
    scikit-fuzzy's ``skfuzzy.cluster.cmeans`` step for step (memberships normalised and clipped
    at machine epsilon before the centre update, distances clipped at epsilon, stop when the
    Frobenius norm of the membership change is below ``tol``), so with the same initial partition
    both give the same numbers. Note the layouts: scikit-fuzzy takes data as features × objects
    and memberships as clusters × objects; here rows are objects in both.

    Parameters (keyword-only):
        n_clusters: number of clusters, 2 ≤ n_clusters ≤ number of objects.
        m: weighting exponent (fuzziness), > 1; 2 is the usual choice (seed 003).
        tol: stop when ‖U_new − U_old‖_F < tol.
        max_iter: at most this many iterations (``converged_`` tells whether tol was met).
        seed: seed of the random initial partition (ChaCha8; not numpy's stream, so it does not
            reproduce scikit-fuzzy's random start: pass ``init`` for that).
        init: initial partition, n_objects × n_clusters, non-negative, rows summing to 1.

    Fitted attributes: ``centers_`` (n_clusters × n_features), ``membership_`` (n_objects ×
    n_clusters), ``labels_`` (largest membership, first on ties), ``n_iter_`` (iterations run,
    the last one included), ``objective_`` (J_m of the last iteration), ``history_`` (J_m per
    iteration), ``converged_``.

    A point lying on a centre gets membership 1.0 there (its other memberships are below 1e-30,
    not exactly 0), never a division by zero.
    """

    kind = "fcm"
    _inner: _core.FcmModel | None = None
    _required_parameters = ["n_clusters"]  # scikit-learn < 1.6 checks construct with these only
    _xfail_checks = {
        check: "the check sets n_clusters=1, and fuzzy c-means needs at least 2 clusters (the Rust "
        "kernel refuses 1: with one cluster every membership is 1, no partition)"
        for check in ("check_dont_overwrite_parameters", "check_methods_subset_invariance",
                      "check_fit2d_1sample", "check_fit2d_1feature", "check_fit2d_predict1d",
                      "check_dict_unchanged")  # the last on scikit-learn < 1.6 only
    }

    def __init__(
        self,
        *,
        n_clusters: int,
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

    def _fit(self, x: F64, y: Any) -> None:
        init = None
        if self.init is not None:
            try:
                init = np.require(np.asarray(self.init, dtype=np.float64), np.float64, ["C", "A"])
            except (TypeError, ValueError) as e:
                raise ParameterError(f"init must be a numeric matrix: {e}") from None
            if init.ndim != 2:
                raise ParameterError(f"init must be 2-D (n_objects x n_clusters), got shape {init.shape}")
        for name in ("n_clusters", "max_iter"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ParameterError(f"{name} must be a non-negative integer, got {v!r}")
        seed = self.seed
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
            raise ParameterError(f"seed must be a non-negative integer or None, got {seed!r}")
        self._inner = _core.FcmModel.fit(
            x,
            n_clusters=int(self.n_clusters),
            m=float(self.m),
            tol=float(self.tol),
            max_iter=int(self.max_iter),
            seed=None if seed is None else int(seed),
            init=init,
        )

    def predict(self, X: Any) -> I64:  # type: ignore[override]
        """Hard labels of new objects (cluster of largest membership)."""
        return self._model().predict(self._check_X(X, feature_names(X)))

    def predict_membership(self, X: Any) -> F64:
        """Memberships of new objects to the fitted centres (n × n_clusters), as
        scikit-fuzzy's ``cmeans_predict`` gives them."""
        return self._model().predict_membership(self._check_X(X, feature_names(X)))

    def score(self, X: Any, y: Any = None) -> float:
        """Minus J_m of ``X`` under the fitted centres and its predicted memberships
        (higher is better, as scikit-learn's ``KMeans.score``)."""
        x = self._check_X(X, feature_names(X))
        u = self._model().predict_membership(x)
        c = self.centers_
        d2 = np.stack([((x - ci) ** 2).sum(axis=1) for ci in c], axis=1)
        return -float((u ** float(self.m) * d2).sum())

    def _model(self) -> _core.FcmModel:
        self._check_fitted()
        assert self._inner is not None
        return self._inner

    @property
    def centers_(self) -> F64:
        return self._model().centers

    @property
    def membership_(self) -> F64:
        return self._model().membership

    @property
    def labels_(self) -> I64:
        return self._model().labels

    @property
    def n_iter_(self) -> int:
        return self._model().n_iter

    @property
    def objective_(self) -> float:
        return self._model().objective

    @property
    def history_(self) -> F64:
        return self._model().history

    @property
    def converged_(self) -> bool:
        return self._model().converged


