"""MLR equals scikit-learn's LinearRegression on the same data (and Ridge with ``alpha``)."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression, Ridge

import thermerr_rs as tr
from thermerr_rs.errors import DataError, NotFittedError, ShapeError


@pytest.mark.parametrize("n, d, seed", [(60, 4, 0), (500, 20, 1), (2000, 50, 2)])
def test_equals_sklearn(n, d, seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(20, 3, (n, d)) + rng.normal(0, 1, (n, 1))  # correlated, offset like temperatures
    y = x @ rng.normal(0, 2, d) + 5 + rng.normal(0, 0.3, n)
    ours = tr.MLR().fit(x, y)
    ref = LinearRegression().fit(x, y)
    # both solve the same well-conditioned centred least-squares problem (QR vs SVD):
    # agreement to ~1e-9 relative is what backward-stable solvers give at cond ~1e2-1e3
    np.testing.assert_allclose(ours.coef_, ref.coef_, rtol=1e-9, atol=1e-12)
    assert ours.intercept_ == pytest.approx(ref.intercept_, rel=1e-9)
    xt = rng.normal(20, 3, (50, d))
    np.testing.assert_allclose(ours.predict(xt), ref.predict(xt), rtol=1e-9)


def test_rank_deficient_equals_sklearn():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(40, 3))
    x = np.column_stack([x, x[:, 0] + x[:, 1]])  # exactly collinear column
    y = x[:, 0] - 2 * x[:, 2] + rng.normal(0, 0.1, 40)
    ours = tr.MLR().fit(x, y)
    ref = LinearRegression().fit(x, y)
    # minimum-norm solution on both sides (SVD with the same eps*max(m,n) cut-off)
    np.testing.assert_allclose(ours.coef_, ref.coef_, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(ours.predict(x), ref.predict(x), rtol=1e-9, atol=1e-10)


def test_no_intercept_equals_sklearn():
    rng = np.random.default_rng(4)
    x = rng.normal(size=(30, 3))
    y = x @ [1.0, 2.0, 3.0] + 0.5
    ours = tr.MLR(fit_intercept=False).fit(x, y)
    ref = LinearRegression(fit_intercept=False).fit(x, y)
    np.testing.assert_allclose(ours.coef_, ref.coef_, rtol=1e-10)
    assert ours.intercept_ == 0.0


@pytest.mark.parametrize("alpha, fit_intercept", [(0.5, True), (10.0, True), (1e3, False)])
def test_ridge_equals_sklearn(alpha, fit_intercept):
    rng = np.random.default_rng(5)
    base = rng.normal(0, 3, (300, 1))
    x = base + rng.normal(0, 0.05, (300, 12))  # twelve nearly collinear readings, like a history
    y = x @ rng.normal(0, 1, 12) + 2 + rng.normal(0, 0.3, 300)
    ours = tr.MLR(alpha=alpha, fit_intercept=fit_intercept).fit(x, y)
    ref = Ridge(alpha=alpha, fit_intercept=fit_intercept, solver="cholesky").fit(x, y)
    # the same strictly convex problem: ours by QR of A stacked on sqrt(alpha) I, the reference by
    # Cholesky of A'A + alpha I (cond ~1e4 at most here): agreement to ~1e-8 relative
    np.testing.assert_allclose(ours.coef_, ref.coef_, rtol=1e-8, atol=1e-10)
    assert ours.intercept_ == pytest.approx(ref.intercept_, rel=1e-8, abs=1e-10)
    # the penalty shrinks: the slopes' norm is below the plain fit's
    assert np.linalg.norm(ours.coef_) < np.linalg.norm(tr.MLR(fit_intercept=fit_intercept).fit(x, y).coef_)


@pytest.mark.parametrize("alpha", [-1.0, float("nan"), float("inf")])
def test_ridge_alpha_must_be_finite_and_not_negative(alpha):
    x = np.arange(20.0).reshape(10, 2)
    with pytest.raises(tr.ParameterError, match="alpha"):
        tr.MLR(alpha=alpha).fit(x, x[:, 0])


def test_estimator_conventions(tmp_path):
    rng = np.random.default_rng(5)
    x, y = rng.normal(size=(20, 2)), rng.normal(size=20)
    m = tr.MLR()
    with pytest.raises(NotFittedError):
        m.predict(x)
    assert m.get_params() == {"fit_intercept": True, "alpha": 0.0}
    assert m.set_params(fit_intercept=False).fit_intercept is False
    m.set_params(fit_intercept=True).fit(x, y)
    with pytest.raises(ShapeError, match="2"):
        m.predict(np.ones((3, 3)))
    with pytest.raises(DataError, match="row 1, column 0"):
        m.fit(np.array([[1.0, 2.0], [np.nan, 1.0]]), [1.0, 2.0])
    with pytest.raises(ShapeError):
        m.fit(x, y[:-1])
    path = m.save(tmp_path / "mlr.json")
    back = tr.load_model(path)
    np.testing.assert_array_equal(back.predict(x), m.predict(x))
    assert isinstance(back, tr.MLR)
    ridge = tr.MLR(alpha=2.0).fit(x, y)
    back = tr.load_model(ridge.save(tmp_path / "ridge.json"))
    np.testing.assert_array_equal(back.predict(x), ridge.predict(x))
    assert back.get_params()["alpha"] == 2.0
