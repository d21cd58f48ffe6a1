"""ε-support vector regression (seed 004), solved in Rust by SMO as LIBSVM does."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from sklearn.exceptions import ConvergenceWarning

from . import _core
from ._arrays import F64
from .base import Regressor
from .errors import ParameterError


class SVR(Regressor):
    """ε-SVR with scikit-learn's parameters and fitted attributes.

    The dual is solved by SMO exactly as LIBSVM (scikit-learn's ``SVR``) solves it: second-order
    working-set selection (Fan, Chen & Lin 2005), shrinking, an LRU cache of single-precision
    kernel columns of ``cache_size`` MiB, and the stopping rule "largest KKT violation < tol".

    Parameters
    ----------
    C : box constraint of the dual variables (penalty on errors beyond the tube).
    epsilon : half-width of the ε-insensitive tube, in the target's units.
    kernel : ``"rbf"`` — k(x, x') = exp(−γ‖x − x'‖²) — or ``"linear"``.
    gamma : ``"scale"`` (1 / (n_features · X.var())), ``"auto"`` (1 / n_features) or a number.
    tol : stopping tolerance. shrinking : use LIBSVM's shrinking heuristic.
    cache_size : kernel cache in MiB. max_iter : iteration cap, −1 for none (a fit stopped by it
    warns with scikit-learn's ``ConvergenceWarning``, as scikit-learn's ``SVR`` does).

    Fitted attributes: ``support_``, ``support_vectors_``, ``dual_coef_`` (shape (1, n_SV)),
    ``intercept_`` (shape (1,)), ``n_iter_``, ``gamma_`` (the resolved γ).
    """

    kind = "svr"
    _inner: _core.SvrModel | None = None

    def __init__(
        self,
        *,
        C: float = 1.0,
        epsilon: float = 0.1,
        kernel: str = "rbf",
        gamma: str | float = "scale",
        tol: float = 1e-3,
        shrinking: bool = True,
        cache_size: float = 200.0,
        max_iter: int = -1,
    ) -> None:
        self.C = C
        self.epsilon = epsilon
        self.kernel = kernel
        self.gamma = gamma
        self.tol = tol
        self.shrinking = shrinking
        self.cache_size = cache_size
        self.max_iter = max_iter

    def _fit(self, x: F64, y: F64) -> None:
        gamma: str | float = self.gamma if isinstance(self.gamma, str) else float(self.gamma)
        max_iter = int(self.max_iter)
        if max_iter < -1 or max_iter == 0:
            raise ParameterError(f"max_iter must be -1 (no limit) or positive, got {max_iter}")
        self._inner = _core.SvrModel.fit(
            x, y, c=float(self.C), epsilon=float(self.epsilon), kernel=str(self.kernel),
            gamma=gamma, tol=float(self.tol), shrinking=bool(self.shrinking),
            cache_size=float(self.cache_size), max_iter=None if max_iter == -1 else max_iter,
        )
        if max_iter != -1 and self._inner.n_iter >= max_iter:
            # as scikit-learn's SVR says it: a fit cut off by the cap is not the solution
            warnings.warn(f"SVR: the solver stopped at max_iter={max_iter} before its stopping rule "
                          f"(largest KKT violation < tol={self.tol}) was met, so the fit is not converged; "
                          "scale X and y (e.g. StandardScaler) or raise max_iter", ConvergenceWarning,
                          stacklevel=3)

    def _predict(self, x: F64) -> F64:
        assert self._inner is not None
        return self._inner.predict(x)

    @classmethod
    def _from_core(cls, inner: _core.SvrModel, n_features: int, **params: Any) -> SVR:
        """An SVR of ``params`` around a model already fitted in Rust on ``n_features`` inputs
        (:func:`thermerr_rs.tune_svr`'s refit on all the data)."""
        model = cls(**params)
        model._inner = inner
        model.n_features_in_ = n_features
        return model

    def _model(self) -> _core.SvrModel:
        self._check_fitted()
        assert self._inner is not None
        return self._inner

    @property
    def support_(self) -> np.ndarray:
        return np.asarray(self._model().support, dtype=np.int32)

    @property
    def support_vectors_(self) -> F64:
        return self._model().support_vectors

    @property
    def dual_coef_(self) -> F64:
        return self._model().dual_coef.reshape(1, -1)

    @property
    def intercept_(self) -> F64:
        return np.array([self._model().intercept])

    @property
    def n_iter_(self) -> int:
        return self._model().n_iter

    @property
    def gamma_(self) -> float | None:
        return self._model().gamma


