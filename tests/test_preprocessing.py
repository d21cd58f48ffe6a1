"""Seed 001's preprocessing: min-max + 1-AGO, IAGO, the AGO meta-estimator and the spread search."""

from __future__ import annotations

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.preprocessing import MinMaxAGO, ago, iago, seed001_test_index


def series(n=41, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 240, n)
    temps = np.column_stack([20 + 15 * (1 - np.exp(-t / tau)) for tau in (30, 60, 120)])
    temps += rng.normal(0, 0.05, temps.shape)
    err = 190 * (1 - np.exp(-t / 50)) + rng.normal(0, 0.3, n)
    return temps, err


def test_ago_round_trip():
    x = np.random.default_rng(0).normal(size=(20, 3))
    np.testing.assert_allclose(iago(ago(x)), x, atol=1e-12)
    tf = MinMaxAGO.fit(x)
    np.testing.assert_allclose(tf.inverse(tf.transform(x)), x, atol=1e-12)


def test_seed001_split():
    idx = seed001_test_index(41)
    assert len(idx) == 21 and idx[0] == 0 and idx[-1] == 40 and np.all(np.diff(idx) == 2)


def test_ago_regressor_with_mlr_and_file(tmp_path):
    x, y = series()
    m = tr.AGORegressor(tr.MLR()).fit(x, y)
    direct = tr.MLR().fit(ago((x - x.min(0)) / np.ptp(x, 0)), ago((y - y.min()) / np.ptp(y)))
    expect = iago(direct.predict(ago((x - x.min(0)) / np.ptp(x, 0)))) * np.ptp(y) + y.min()
    np.testing.assert_allclose(m.predict(x), expect, rtol=1e-10, atol=1e-9)
    back = tr.load_model(m.save(tmp_path / "ago.json"))
    assert isinstance(back, tr.AGORegressor)
    np.testing.assert_allclose(back.predict(x), m.predict(x), rtol=0, atol=1e-12)


def brute_force_bands(x, y, spreads, test):
    train = np.setdiff1d(np.arange(len(y)), test)
    xt, yt = MinMaxAGO.fit(x), MinMaxAGO.fit(y)
    x1, y1 = xt.transform(x), yt.transform(y)
    out = []
    for s in spreads:
        net = tr.RBFNetwork(design="exact", spread=s).fit(x1[train], y1[train])
        r = y[test] - yt.inverse(net.predict(x1))[test]
        out.append(r.max() - r.min())
    return np.array(out)


def test_spread_search_finds_the_minimum_of_the_curve():
    x, y = series(41, 1)
    grid = np.arange(1.0, 2.0, 0.05)
    # seed 001's own protocol (interleaved test samples); the time-ordered default: test_folds
    res = tr.spread_search(x, y, grid, test_index=seed001_test_index(41), progress=False)
    expect = brute_force_bands(x, y, grid, seed001_test_index(41))
    np.testing.assert_allclose(res.bands, expect, rtol=1e-9)
    assert res.spread == pytest.approx(grid[int(np.argmin(expect))])
    assert res.band == pytest.approx(expect.min())
    assert "best spread" in str(res)
    with pytest.raises(tr.ParameterError):
        tr.spread_search(x, y, [-1.0], progress=False)
