"""Multiple linear regression."""

from __future__ import annotations

from typing import Any

from . import _core
from ._arrays import F64
from .base import Regressor


class MLR(Regressor):
    """Ordinary least squares ``y = intercept_ + X @ coef_`` (the seeds' "multiple linear
    regression" baseline). Equals scikit-learn's ``LinearRegression`` on the same data.

    ``alpha`` > 0 adds an L2 penalty on the slopes (ridge regression; the intercept is not
    penalised) and then equals scikit-learn's ``Ridge(alpha)``. It is in the units of the
    inputs' squares times rows (no scaling is applied), and keeps many correlated inputs (a
    temperature history) from extrapolating wildly when they are fitted on a short run.

    Fitted attributes: ``coef_`` (n_features,), ``intercept_`` (float), ``n_features_in_``.
    """

    kind = "mlr"
    _inner: _core.MlrModel | None = None

    def __init__(self, *, fit_intercept: bool = True, alpha: float = 0.0) -> None:
        self.fit_intercept = fit_intercept
        self.alpha = alpha

    def _min_samples(self) -> int:
        return 2 if self.fit_intercept else 1  # one sample cannot tell an intercept from slopes

    def _fit(self, x: F64, y: F64) -> None:
        self._inner = _core.MlrModel.fit(x, y, fit_intercept=bool(self.fit_intercept), alpha=float(self.alpha))

    def _predict(self, x: F64) -> F64:
        assert self._inner is not None
        return self._inner.predict(x)

    @property
    def coef_(self) -> F64:
        self._check_fitted()
        assert self._inner is not None
        return self._inner.coef

    @property
    def intercept_(self) -> float:
        self._check_fitted()
        assert self._inner is not None
        return self._inner.intercept


