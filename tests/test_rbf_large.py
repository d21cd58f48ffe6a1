"""The ols design above its candidate cap (issue 12 point 4: real runs are 6 000–11 000 rows x 16
sensors): a seeded k-means++ pool of `max_candidates` training vectors replaces the exhaustive
search. What it must keep: determinism, the exhaustive search whenever n <= max_candidates, and
a sensible model. Speed is measured in benches/bench_rbf.py, never here."""

from __future__ import annotations

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.errors import ParameterError


def thermal_run(n: int, d: int = 16, seed: int = 0):
    """Four latent heat sources with first-order lags mixed into `d` correlated sensors; the
    error a smooth nonlinear function of the sources and of an unseen fast response, plus 0.5 µm
    noise (benches/bench_rbf.py has the same generator)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 10.0
    load = np.repeat(rng.choice([0.0, 0.4, 0.7, 1.0], size=n // 360 + 1), 360)[:n]

    def lag(u, tau):
        a, acc, out = np.exp(-10.0 / tau), u[0], np.empty_like(u)
        for i, v in enumerate(u):
            acc = a * acc + (1 - a) * v
            out[i] = acc
        return out

    spindle, column = 12.0 * lag(load, 900.0), 6.0 * lag(load, 4000.0)
    ambient = 2.0 * np.sin(2 * np.pi * t / 86400.0 + rng.uniform(0, 6)) + 0.5 * lag(rng.normal(size=n), 3000.0)
    coolant = 1.5 * lag(load, 2000.0) + 0.3 * np.sin(2 * np.pi * t / 1800.0)
    src = np.column_stack([spindle, column, ambient, coolant])
    mix = rng.uniform(0.1, 1.0, (4, d)) * rng.choice([0.2, 1.0], size=(4, d))
    x = 20.0 + src @ mix + rng.normal(0, 0.03, (n, d))
    y = (8.0 * np.tanh(spindle / 6.0) + 0.15 * column * coolant + 1.2 * np.sin(ambient)
         + 0.04 * spindle * column + 1.5 * lag(load, 300.0) * np.cos(coolant)
         + rng.normal(0, 0.5, n))
    return x, y


def rms(a, b):
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def test_pool_beats_linear_regression_held_out():
    n = 1500  # > max_candidates = 500: the pool path
    x, _ = thermal_run(n + 500, seed=1)
    # a target far from linear in the (correlated) sensors
    xs = (x - x.min(0)) / (x.max(0) - x.min(0))
    noise = np.random.default_rng(7).normal(0, 0.2, len(x))
    y = 4 * np.sin(4 * xs[:, 0]) * np.cos(3 * xs[:, 5]) + 3 * (xs[:, 9] - 0.5) ** 2 + noise
    # shuffled split: held-out rows inside the training ranges (an RBF does not extrapolate)
    idx = np.random.default_rng(2).permutation(len(y))
    tr_i, te_i = idx[:n], idx[n:]
    # as the command line fits it: min-max scaled inputs, spread 1, goal 0.1 µm² per sample
    net = tr.MinMaxScaled(tr.RBFNetwork(design="ols", spread=1.0, goal=0.1 * n)).fit(x[tr_i], y[tr_i])
    mlr = tr.MLR().fit(x[tr_i], y[tr_i])
    inner = net.estimator_
    assert 1 <= inner.n_neurons_ <= 500
    assert len(set(inner.selected_)) == inner.n_neurons_
    hist = inner.sse_history_
    assert np.all(np.diff(hist) <= 1e-9 * hist[0])
    assert hist[-1] <= 0.1 * n < hist[-2]
    # the training SSE of the model is the last one of the selection
    assert ((net.predict(x[tr_i]) - y[tr_i]) ** 2).sum() == pytest.approx(hist[-1], rel=1e-6)
    e_rbf, e_mlr = rms(net.predict(x[te_i]), y[te_i]), rms(mlr.predict(x[te_i]), y[te_i])
    # noise 0.2, target std ~1.9: the linear model leaves ~1.4
    assert e_rbf < 0.5 * e_mlr, (e_rbf, e_mlr)
    assert e_rbf < 0.5, e_rbf


def test_pool_on_a_run_the_goal_is_out_of_reach():
    # the command line's goal below the noise: the selection runs to the pool's end
    n = 800
    x, y = thermal_run(n, seed=2)
    net = tr.MinMaxScaled(tr.RBFNetwork(design="ols", spread=1.0, goal=0.1 * n, max_candidates=120)).fit(x, y)
    assert net.estimator_.n_neurons_ <= 120
    assert len(net.estimator_.sse_history_) == net.estimator_.n_neurons_ + 1
    assert np.isfinite(net.predict(x)).all()


def test_pool_is_deterministic_and_seeded():
    x, y = thermal_run(700, seed=3)
    x = (x - x.min(0)) / (x.max(0) - x.min(0))
    kw = dict(design="ols", spread=1.0, max_neurons=30, max_candidates=100)
    a = tr.RBFNetwork(**kw).fit(x, y)
    b = tr.RBFNetwork(**kw).fit(x, y)
    c = tr.RBFNetwork(seed=5, **kw).fit(x, y)
    assert a.selected_ == b.selected_
    np.testing.assert_array_equal(a.weights_, b.weights_)
    assert a.n_neurons_ == 30 and c.n_neurons_ == 30
    assert a.selected_ != c.selected_  # another pool
    # the pool caps the network
    assert tr.RBFNetwork(design="ols", spread=1.0, max_candidates=20).fit(x, y).n_neurons_ <= 20


def test_exhaustive_search_up_to_the_cap():
    x, y = thermal_run(150, seed=4)
    x = (x - x.min(0)) / (x.max(0) - x.min(0))
    kw = dict(design="ols", spread=1.0, max_neurons=25)
    base = tr.RBFNetwork(**kw).fit(x, y)  # 150 <= 500: every sample a candidate
    for m in (150, 151, 10_000):
        other = tr.RBFNetwork(max_candidates=m, **kw).fit(x, y)
        assert other.selected_ == base.selected_
        np.testing.assert_array_equal(other.weights_, base.weights_)
        np.testing.assert_array_equal(other.sse_history_, base.sse_history_)
    pooled = tr.RBFNetwork(max_candidates=149, **kw).fit(x, y)
    assert pooled.n_neurons_ == 25


def test_max_candidates_is_checked():
    x, y = thermal_run(50, seed=5)
    with pytest.raises(ParameterError, match="max_candidates"):
        tr.RBFNetwork(design="ols", max_candidates=0).fit(x, y)
