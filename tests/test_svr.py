"""ε-SVR by SMO against scikit-learn's SVR (LIBSVM) on the same data, parameters and γ."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from sklearn.exceptions import ConvergenceWarning
from sklearn.svm import SVR as SkSVR

import thermerr_rs as tr
from thermerr_rs.errors import DataError, ParameterError, ShapeError


def seed004_like(n: int = 60, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """4 temperature rises of a spindle warming up (front bearing, headstock, column, bed) and an
    axial drift that depends on them nonlinearly, 3-minute samples."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 3.0
    tau = np.array([25.0, 40.0, 70.0, 90.0])
    amp = np.array([9.0, 6.0, 3.0, 2.0])
    x = amp * (1 - np.exp(-t[:, None] / tau)) + 0.05 * rng.normal(size=(n, 4))
    y = 2.1 * x[:, 0] + 1.2 * x[:, 1] - 0.9 * x[:, 2] + 0.08 * x[:, 0] ** 2 + 0.2 * rng.normal(size=n)
    return x, y


def smooth(n: int, d: int, seed: int, noise: float) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, d))
    y = np.sin(x[:, 0]) + 0.5 * x[:, 1] ** 2 - x[:, 2] * x[:, 3] + noise * rng.normal(size=n)
    return x, y


CASES = {
    # name: (data, C, epsilon, gamma as given to both)
    "seed004_60x4": (seed004_like(), 7.3465, 0.1, 0.0261),
    "smooth_2000x10": (smooth(2000, 10, 1, 0.01), 10.0, 0.05, "scale"),
    "noisy_10000x8": (smooth(10000, 8, 2, 0.3), 1.0, 0.1, 0.125),
}


@pytest.mark.parametrize("name", list(CASES))
def test_equals_scikit_learn(name: str) -> None:
    (x, y), C, eps, gamma = CASES[name]
    ref = SkSVR(C=C, epsilon=eps, gamma=gamma, tol=1e-3).fit(x, y)
    ours = tr.SVR(C=C, epsilon=eps, gamma=gamma, tol=1e-3).fit(x, y)
    # γ="scale" is 1/(d·Var X): the same formula, summed in another order (≤ a few ulp)
    assert ours.gamma_ == pytest.approx(ref._gamma, rel=1e-12)
    # Both stop when the maximal KKT violation drops below tol = 1e-3; two solutions that both
    # meet it differ by O(tol) in the dual and in the decision function, which bounds the
    # tolerances below. Running the same SMO (working-set rule, shrinking, f32 kernel cache),
    # they in fact take the same iterations and land on the same bits on this machine.
    assert ours.n_iter_ == ref.n_iter_
    assert np.array_equal(ours.support_, ref.support_)
    np.testing.assert_allclose(ours.dual_coef_, ref.dual_coef_, rtol=0, atol=C * 1e-3)
    assert ours.intercept_[0] == pytest.approx(ref.intercept_[0], abs=1e-3)
    xt = np.vstack([x[:50], x[:50] + 0.1])
    np.testing.assert_allclose(ours.predict(xt), ref.predict(xt), rtol=0, atol=1e-3)


def test_linear_kernel_and_no_shrinking_equal_scikit_learn() -> None:
    x, y = seed004_like(45, seed=3)
    for kw in ({"kernel": "linear"}, {"kernel": "rbf", "gamma": 0.05, "shrinking": False}):
        ref = SkSVR(C=3.0, epsilon=0.05, **kw).fit(x, y)  # type: ignore[arg-type]
        ours = tr.SVR(C=3.0, epsilon=0.05, **kw).fit(x, y)  # type: ignore[arg-type]
        assert ours.n_iter_ == ref.n_iter_, kw
        assert np.array_equal(ours.support_, ref.support_), kw
        # same tol-derived bounds as above
        np.testing.assert_allclose(ours.predict(x), ref.predict(x), rtol=0, atol=1e-3)


def test_max_iter_stops_early_like_scikit_learn() -> None:
    x, y = smooth(300, 4, 5, 0.1)
    ref = SkSVR(C=10.0, epsilon=0.01, max_iter=50)
    with pytest.warns(Warning):
        ref.fit(x, y)
    with pytest.warns(ConvergenceWarning, match="stopped at max_iter=50"):
        ours = tr.SVR(C=10.0, epsilon=0.01, max_iter=50).fit(x, y)
    assert ours.n_iter_ == ref.n_iter_ == 50
    # converged within the cap: no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        tr.SVR(C=10.0, epsilon=0.01, max_iter=10**6).fit(x, y)
    np.testing.assert_allclose(ours.predict(x), ref.predict(x), rtol=0, atol=1e-9)


def test_an_unconverged_fit_is_scikit_learns_in_every_row_order() -> None:
    """Five rows with a linear kernel (a draw of test_properties.py's row-order property): the SMO
    runs to its cap of 10^6 iterations without meeting tol = 1e-12, scikit-learn's too, and where
    each stops depends on the order of the rows (predictions spread by 3.6e-3 over the 120
    orders, the same for both). Ours is scikit-learn's to the bit in each order: the same working
    set choices on the same path, so the spread is LIBSVM's, not a defect of ours. Six orders
    here (all 120 were checked by hand on 2026-11-28: every one equal to the bit)."""
    x = np.array([[2.0, -29.0], [0.0, 9.0], [1.0, 0.0], [0.0, 0.0], [32.0, 0.0]])
    y = np.array([0.0078125, 0.015625, 2.0, 0.0, 1.0])
    params = dict(C=10.0, epsilon=0.1, kernel="linear", tol=1e-12, shrinking=False, max_iter=10**6)
    preds = []
    for perm in ([0, 1, 2, 3, 4], [4, 3, 2, 1, 0], [1, 0, 3, 2, 4], [2, 4, 0, 1, 3], [3, 2, 4, 0, 1], [0, 4, 1, 3, 2]):
        p = np.array(perm)
        with pytest.warns(ConvergenceWarning, match="max_iter"):
            ours = tr.SVR(**params).fit(x[p], y[p])
        with pytest.warns(Warning):
            ref = SkSVR(**params).fit(x[p], y[p])
        assert ours.n_iter_ == ref.n_iter_ == 10**6
        np.testing.assert_array_equal(ours.predict(x), ref.predict(x))
        preds.append(ours.predict(x))
    assert np.ptp(np.array(preds), axis=0).max() > 1e-4  # the order matters, to both


def test_model_file_round_trip(tmp_path) -> None:
    x, y = seed004_like()
    m = tr.SVR(C=7.3465, gamma=0.0261).fit(x, y)
    path = m.save(tmp_path / "svr.json")
    doc = json.loads(path.read_text())
    assert doc["kind"] == "svr" and doc["params"]["C"] == 7.3465
    back = tr.load_model(path)
    assert isinstance(back, tr.SVR)
    assert np.array_equal(back.predict(x), m.predict(x))  # float_roundtrip JSON: bit-identical


def test_bad_input_is_refused() -> None:
    x, y = seed004_like()
    with pytest.raises(ParameterError, match="C"):
        tr.SVR(C=0.0).fit(x, y)
    with pytest.raises(ParameterError, match="gamma"):
        tr.SVR(gamma="wide").fit(x, y)
    with pytest.raises(ParameterError, match="kernel"):
        tr.SVR(kernel="poly").fit(x, y)
    with pytest.raises(ParameterError, match="max_iter"):
        tr.SVR(max_iter=0).fit(x, y)
    bad = x.copy()
    bad[3, 2] = np.nan
    with pytest.raises(DataError, match="row 3, column 2"):
        tr.SVR().fit(bad, y)
    with pytest.raises(ShapeError):
        tr.SVR().fit(x, y[:-1])
    m = tr.SVR().fit(x, y)
    with pytest.raises(ShapeError, match="4"):
        m.predict(x[:, :3])
