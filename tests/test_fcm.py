"""Fuzzy c-means against scikit-fuzzy's cmeans, plus determinism, edge cases and errors."""

from __future__ import annotations

import numpy as np
import pytest
import skfuzzy
from _thermal import minmax_rows, sensor_series

from thermerr_rs import DataError, FuzzyCMeans, ParameterError, load_model

# Both implementations run the same sequence of operations (normalise + clip u, centres from
# u^m, distances clipped at eps, ratio-normalised powers, Frobenius-norm stop); they differ only
# in summation order (BLAS / cdist vs our blocked sums), i.e. ~1e-16 per step. Near its fixed
# point an FCM step is a contraction, so these do not grow; 1e-8 leaves a wide margin for that
# and still catches any real difference in the algorithm (one more or one less iteration, or a
# different clip, moves the memberships by ~tol = 1e-5 or more).
ATOL = 1e-8


def _blobs(centres, n_per, spread, seed):
    rng = np.random.default_rng(seed)
    c = np.asarray(centres, dtype=float)
    return np.vstack([ci + spread * rng.standard_normal((n_per, c.shape[1])) for ci in c])


def _init(n, c, seed):
    u = np.random.default_rng(seed).random((n, c))
    return u / u.sum(axis=1, keepdims=True)


def _sensors():
    # 20 sensors of seed 003's kind: time constants from 10 min to 3 h, 300 samples at 150 s
    taus = np.geomspace(600.0, 11000.0, 20)
    gains = np.linspace(2.0, 12.0, 20)
    return minmax_rows(sensor_series(300, taus, gains, noise=0.03, seed=3))


DATASETS = {
    "separated": (_blobs([[0, 0], [8, 8], [0, 9]], 50, 1.0, 0), 3),
    "overlapping": (_blobs([[0, 0, 0], [1.5, 0, 0], [0, 1.5, 1]], 100, 1.0, 1), 3),
    "sensors": (_sensors(), 4),
    # three identical points per cluster: centres land on data points (distance clipped at eps)
    "on_centre": (np.array([[0.0], [0.0], [0.0], [5.0], [5.0], [5.0]]), 2),
}


@pytest.mark.parametrize("name", list(DATASETS))
@pytest.mark.parametrize("m", [2.0, 1.7])
def test_matches_skfuzzy(name, m):
    x, c = DATASETS[name]
    u0 = _init(x.shape[0], c, seed=42)
    tol, max_iter = 1e-5, 1000
    cntr, u, _, _, jm, p, _ = skfuzzy.cluster.cmeans(x.T, c, m, tol, max_iter, init=u0.T.copy())
    f = FuzzyCMeans(n_clusters=c, m=m, tol=tol, max_iter=max_iter, init=u0).fit(x)
    assert f.n_iter_ == p
    assert f.converged_
    np.testing.assert_allclose(f.membership_, u.T, rtol=0, atol=ATOL)
    np.testing.assert_allclose(f.centers_, cntr, rtol=0, atol=ATOL * max(1.0, np.abs(x).max()))
    # the objective is a sum of n*c terms; relative agreement is the meaningful measure
    np.testing.assert_allclose(f.history_, jm, rtol=1e-9, atol=1e-12)
    assert f.objective_ == f.history_[-1]
    # and the partition is a partition
    np.testing.assert_allclose(f.membership_.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_array_equal(f.labels_, np.argmax(f.membership_, axis=1))


def test_max_iter_cap_matches_skfuzzy():
    x, c = DATASETS["overlapping"]
    u0 = _init(x.shape[0], c, seed=1)
    cntr, u, _, _, jm, p, _ = skfuzzy.cluster.cmeans(x.T, c, 2.0, 1e-5, 7, init=u0.T.copy())
    f = FuzzyCMeans(n_clusters=c, tol=1e-5, max_iter=7, init=u0).fit(x)
    assert p == f.n_iter_ == 7 and not f.converged_
    np.testing.assert_allclose(f.membership_, u.T, rtol=0, atol=ATOL)
    np.testing.assert_allclose(f.centers_, cntr, rtol=0, atol=ATOL)


def test_predict_membership_matches_cmeans_predict():
    x, c = DATASETS["overlapping"]
    f = FuzzyCMeans(n_clusters=c, seed=3).fit(x)
    new = _blobs([[0.5, 0.5, 0.5]], 40, 2.0, 9)
    u, *_ = skfuzzy.cluster.cmeans_predict(new.T, f.centers_, 2.0, 1e-5, 100, init=_init(40, c, 0).T.copy())
    np.testing.assert_allclose(f.predict_membership(new), u.T, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(f.predict(new), np.argmax(u, axis=0))


def test_point_on_a_centre_has_membership_one_and_no_nan():
    x, c = DATASETS["on_centre"]
    f = FuzzyCMeans(n_clusters=c, seed=0).fit(x)
    u = f.membership_
    assert np.all(np.isfinite(u)) and np.all(np.isfinite(f.centers_))
    assert np.all(u.max(axis=1) == 1.0)
    at_centres = f.predict_membership(f.centers_)
    assert np.all(np.isfinite(at_centres))
    np.testing.assert_array_equal(np.diag(at_centres), 1.0)


def test_same_seed_same_result_different_seeds_valid():
    x, c = DATASETS["sensors"]
    a = FuzzyCMeans(n_clusters=c, seed=5).fit(x)
    b = FuzzyCMeans(n_clusters=c, seed=5).fit(x)
    np.testing.assert_array_equal(a.membership_, b.membership_)
    np.testing.assert_array_equal(a.centers_, b.centers_)
    assert a.n_iter_ == b.n_iter_
    for s in range(6):
        f = FuzzyCMeans(n_clusters=c, seed=s).fit(x)
        u = f.membership_
        assert u.shape == (x.shape[0], c)
        assert np.all(u >= 0) and np.all(u <= 1)
        np.testing.assert_allclose(u.sum(axis=1), 1.0, atol=1e-12)
        assert np.all(np.diff(f.history_) <= 1e-12 * f.history_[:-1])  # J_m never increases


def test_different_seeds_start_differently():
    x, c = DATASETS["overlapping"]
    a = FuzzyCMeans(n_clusters=c, seed=1, max_iter=1).fit(x)
    b = FuzzyCMeans(n_clusters=c, seed=2, max_iter=1).fit(x)
    assert not np.array_equal(a.membership_, b.membership_)


@pytest.mark.parametrize(
    "kw",
    [
        {"n_clusters": 1},
        {"n_clusters": 7},  # more clusters than the 6 objects
        {"n_clusters": 2, "m": 1.0},
        {"n_clusters": 2, "m": float("nan")},
        {"n_clusters": 2, "tol": 0.0},
        {"n_clusters": 2, "max_iter": 0},
        {"n_clusters": 2, "init": np.full((5, 2), 0.5)},  # wrong number of rows
        {"n_clusters": 2, "init": np.full((6, 3), 1 / 3)},  # wrong number of columns
        {"n_clusters": 2, "init": np.tile([1.5, -0.5], (6, 1))},  # negative
        {"n_clusters": 2, "init": np.full((6, 2), 0.6)},  # rows sum to 1.2
        {"n_clusters": 2, "seed": -1},
    ],
)
def test_bad_params_raise(kw):
    x = np.arange(12.0).reshape(6, 2)
    with pytest.raises(ParameterError):
        FuzzyCMeans(**kw).fit(x)


def test_nan_input_raises_data_error():
    x = np.arange(12.0).reshape(6, 2)
    x[3, 1] = np.nan
    with pytest.raises(DataError, match="row 3, column 1"):
        FuzzyCMeans(n_clusters=2).fit(x)


def test_save_load_round_trip(tmp_path):
    x, c = DATASETS["sensors"]
    f = FuzzyCMeans(n_clusters=c, seed=7).fit(x)
    path = f.save(tmp_path / "fcm.json")
    g = load_model(path)
    assert isinstance(g, FuzzyCMeans)
    new = _sensors()[::-1] * 0.9 + 0.05
    np.testing.assert_array_equal(g.predict_membership(new), f.predict_membership(new))
    np.testing.assert_array_equal(g.predict(new), f.predict(new))
    np.testing.assert_array_equal(g.membership_, f.membership_)
    np.testing.assert_array_equal(g.centers_, f.centers_)
    assert g.n_iter_ == f.n_iter_ and g.objective_ == f.objective_
    assert g.get_params() == f.get_params()


def test_predict_checks_features():
    x, c = DATASETS["separated"]
    f = FuzzyCMeans(n_clusters=c, seed=0).fit(x)
    from thermerr_rs import ShapeError

    with pytest.raises(ShapeError):
        f.predict(np.zeros((3, 5)))
