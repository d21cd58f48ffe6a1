"""Fuzzy c-means against scikit-fuzzy's cmeans, from the same initial partition."""

from __future__ import annotations

import numpy as np
import pytest
import skfuzzy

import thermerr_rs as tr
from thermerr_rs.errors import DataError, ParameterError, ShapeError


def sensor_series(n_sensors: int = 20, n_samples: int = 300, seed: int = 0) -> np.ndarray:
    """Min-max scaled first-order responses to a stepped spindle schedule, four time-constant
    groups plus noise: what seed 003 clusters."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_samples) * 150.0
    speed = np.select([t < 0.25 * t[-1], t < 0.5 * t[-1], t < 0.75 * t[-1]], [3000, 6000, 4500], 3000)
    q = (speed / 6000.0) ** 1.3
    out = []
    for k in range(n_sensors):
        tau = [900.0, 3000.0, 9000.0, 30000.0][k % 4] * rng.uniform(0.8, 1.25)
        y = np.zeros(n_samples)
        for i in range(1, n_samples):
            y[i] = y[i - 1] + (150.0 / tau) * (q[i - 1] - y[i - 1])
        y = y + rng.normal(0, 0.01, n_samples)
        out.append((y - y.min()) / (y.max() - y.min()))
    return np.array(out)


def blobs(n: int, d: int, c: int, spread: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    centres = rng.normal(0, 4, (c, d))
    return np.vstack([centres[k % c] + rng.normal(0, spread, d) for k in range(n)])


DATASETS = {
    "separated blobs": lambda: blobs(90, 3, 3, 0.5, 1),
    "overlapping blobs": lambda: blobs(200, 5, 4, 3.0, 2),
    "20 sensor series x 300 samples": lambda: sensor_series(20, 300, 3),
    "40 sensor series x 500 samples": lambda: sensor_series(40, 500, 4),
}


@pytest.mark.parametrize("name", DATASETS)
@pytest.mark.parametrize("m", [2.0, 1.7])
def test_equals_skfuzzy(name, m):
    x = DATASETS[name]()
    c = 4 if "sensor" in name else (3 if "separated" in name else 4)
    rng = np.random.default_rng(11)
    u0 = rng.random((x.shape[0], c))
    u0 /= u0.sum(axis=1, keepdims=True)
    ours = tr.FuzzyCMeans(n_clusters=c, m=m, tol=1e-8, max_iter=500, init=u0).fit(x)
    cntr, u, _, _, jm, p, _ = skfuzzy.cluster.cmeans(x.T, c, m, error=1e-8, maxiter=500, init=u0.T)
    # same iteration, same floors and stopping rule: the two differ only by floating-point
    # summation order (~1e-15 per step), which a contracting iteration keeps far below 1e-8
    assert ours.n_iter_ == p
    np.testing.assert_allclose(ours.membership_, u.T, rtol=0, atol=1e-8)
    np.testing.assert_allclose(ours.centers_, cntr, rtol=1e-8, atol=1e-8)
    assert ours.objective_ == pytest.approx(jm[-1], rel=1e-8)
    np.testing.assert_allclose(ours.objective_history_, jm, rtol=1e-8)


def test_stops_like_skfuzzy_at_loose_tol():
    x = sensor_series(20, 300, 5)
    u0 = np.random.default_rng(1).random((20, 4))
    ours = tr.FuzzyCMeans(n_clusters=4, tol=1e-3, init=u0).fit(x)
    *_, p, _ = skfuzzy.cluster.cmeans(x.T, 4, 2.0, error=1e-3, maxiter=1000, init=u0.T)
    assert ours.n_iter_ == p


def test_seed_determinism_and_valid_partition():
    x = sensor_series(20, 200, 6)
    a = tr.FuzzyCMeans(n_clusters=4, seed=3).fit(x)
    b = tr.FuzzyCMeans(n_clusters=4, seed=3).fit(x)
    c = tr.FuzzyCMeans(n_clusters=4, seed=4).fit(x)
    np.testing.assert_array_equal(a.membership_, b.membership_)
    for f in (a, c):
        np.testing.assert_allclose(f.membership_.sum(axis=1), 1.0, atol=1e-12)
        assert f.converged_
    assert not np.array_equal(a.membership_, c.membership_)  # another seed, another start


def test_coinciding_point():
    x = np.array([[0.0, 0.0], [0.0, 0.0], [10.0, 10.0]])
    f = tr.FuzzyCMeans(n_clusters=2, init=[[1, 0], [1, 0], [0, 1]]).fit(x)
    assert np.isfinite(f.membership_).all()
    assert f.membership_[0, 0] == pytest.approx(1.0, abs=1e-12)
    assert f.predict_membership([[10.0, 10.0]])[0, 1] == pytest.approx(1.0, abs=1e-12)


def test_predict_membership_matches_skfuzzy():
    x = blobs(60, 3, 3, 0.8, 7)
    f = tr.FuzzyCMeans(n_clusters=3, seed=1).fit(x)
    new = blobs(10, 3, 3, 1.0, 8)
    u, *_ = skfuzzy.cluster.cmeans_predict(new.T, f.centers_, 2.0, error=1e-12, maxiter=1)
    # one membership update from the same centres: float rounding only
    np.testing.assert_allclose(f.predict_membership(new), u.T, atol=1e-12)
    np.testing.assert_array_equal(f.predict(new), np.argmax(u, axis=0))


def test_bad_input(tmp_path):
    x = blobs(20, 2, 2, 0.5, 0)
    with pytest.raises(ParameterError, match="n_clusters"):
        tr.FuzzyCMeans(n_clusters=1).fit(x)
    with pytest.raises(ParameterError, match="21 clusters"):
        tr.FuzzyCMeans(n_clusters=21).fit(x)
    with pytest.raises(ParameterError, match="m"):
        tr.FuzzyCMeans(n_clusters=2, m=0.5).fit(x)
    with pytest.raises(ParameterError, match="init"):
        tr.FuzzyCMeans(n_clusters=2, init=np.ones((3, 2))).fit(x)
    bad = x.copy()
    bad[3, 1] = np.nan
    with pytest.raises(DataError, match="row 3, column 1"):
        tr.FuzzyCMeans(n_clusters=2).fit(bad)
    f = tr.FuzzyCMeans(n_clusters=2, seed=0).fit(x)
    with pytest.raises(ShapeError):
        f.predict_membership(np.ones((2, 5)))
    back = tr.load_model(f.save(tmp_path / "fcm.json"))
    np.testing.assert_array_equal(back.predict_membership(x), f.predict_membership(x))
    np.testing.assert_array_equal(back.centers_, f.centers_)
