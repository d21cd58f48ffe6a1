"""RBF networks: exact interpolation, OLS order against a direct greedy search, k-means against
scikit-learn, accuracy on a smooth function, conventions."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.cluster import KMeans

import thermerr_rs as tr
from thermerr_rs import _core
from thermerr_rs.errors import DataError, ParameterError, ShapeError

B = np.sqrt(np.log(2.0))  # MATLAB radbas: 0.8326


def smooth(x):
    return np.sin(2 * x[:, 0]) + 0.5 * np.cos(3 * x[:, 1]) + 0.3 * x[:, 0] * x[:, 1]


def data(n=60, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 1, (n, 2))
    return x, smooth(x)


def phi(x, c, spread):
    d2 = ((x[:, None, :] - c[None, :, :]) ** 2).sum(-1)
    return np.exp(-((B / spread) ** 2) * d2)


def test_radbas_convention():
    c = np.array([[0.0, 0.0]])
    net = tr.RBFNetwork(design="exact", spread=0.7).fit(np.vstack([c, [[5.0, 5.0]]]), [1.0, 0.0])
    # φ(spread) = 0.5 exactly: the prediction at distance `spread` from a lone centre is w/2 + b
    w, b = net.weights_[0], net.bias_
    assert net.predict([[0.7, 0.0]])[0] == pytest.approx(0.5 * w + b + net.weights_[1] * phi(np.array([[0.7, 0.0]]), np.array([[5.0, 5.0]]), 0.7)[0, 0], rel=1e-12)


def test_exact_interpolates():
    x, y = data(50)
    net = tr.RBFNetwork(design="exact", spread=0.3).fit(x, y)
    assert net.n_neurons_ == 50
    # cond(Φ) is ~1e4 at this spread and density: interpolation holds to ~1e-9 of |y|
    np.testing.assert_allclose(net.predict(x), y, atol=1e-9)


def greedy_reference(x, y, spread, goal, cap):
    """Direct, slow greedy search: try every remaining training vector as the next centre, solve
    the output layer (with bias) by least squares, keep the one with the smallest SSE."""
    chosen, sse_hist = [], [float(((y - y.mean()) ** 2).sum())]
    while len(chosen) < cap and sse_hist[-1] > goal:
        best = None
        for j in range(len(x)):
            if j in chosen:
                continue
            a = np.column_stack([phi(x, x[chosen + [j]], spread), np.ones(len(x))])
            coef, *_ = np.linalg.lstsq(a, y, rcond=None)
            sse = float(((a @ coef - y) ** 2).sum())
            if best is None or sse < best[0]:
                best = (sse, j)
        chosen.append(best[1])
        sse_hist.append(best[0])
    return chosen, sse_hist


@pytest.mark.parametrize("spread, goal", [(0.3, 0.05), (0.6, 0.01)])
def test_ols_order_equals_direct_greedy(spread, goal):
    x, y = data(40, seed=3)
    net = tr.RBFNetwork(design="ols", spread=spread, goal=goal).fit(x, y)
    order, hist = greedy_reference(x, y, spread, goal, 40)
    assert net.selected_ == order
    # Gram-Schmidt recursion vs fresh least squares per step: rounding only
    np.testing.assert_allclose(net.sse_history_, hist, rtol=1e-7, atol=1e-10)
    assert net.sse_history_[-1] <= goal < net.sse_history_[-2]
    assert ((net.predict(x) - y) ** 2).sum() == pytest.approx(net.sse_history_[-1], rel=1e-6, abs=1e-10)


def test_ols_cap_and_max_error_rule():
    x, y = data(40, seed=4)
    net = tr.RBFNetwork(design="ols", spread=0.4, max_neurons=5).fit(x, y)
    assert net.n_neurons_ == 5
    me = tr.RBFNetwork(design="ols", spread=0.4, max_neurons=3, rule="max_error").fit(x, y)
    # the first pick of the max-error rule is the sample farthest from the mean
    assert me.selected_[0] == int(np.argmax(np.abs(y - y.mean())))


@pytest.mark.parametrize("k, seed", [(3, 0), (5, 1), (8, 2)])
def test_kmeans_equals_sklearn(k, seed):
    rng = np.random.default_rng(seed)
    centres = rng.normal(0, 5, (k, 3))
    x = np.vstack([c + rng.normal(0, 1.0, (40, 3)) for c in centres])
    init = x[rng.choice(len(x), k, replace=False)]
    ref = KMeans(n_clusters=k, init=init, n_init=1, algorithm="lloyd", tol=0.0, max_iter=300).fit(x)
    c, labels, n_iter, inertia = _core.kmeans(np.ascontiguousarray(x), np.ascontiguousarray(init), 300)
    np.testing.assert_array_equal(labels, ref.labels_)
    # same iteration; scikit-learn works on mean-centred data with a GEMM distance: rounding only
    np.testing.assert_allclose(c, ref.cluster_centers_, rtol=1e-10, atol=1e-10)
    assert n_iter == ref.n_iter_
    assert inertia == pytest.approx(ref.inertia_, rel=1e-9)


@pytest.mark.parametrize("design, tol", [("exact", 0.01), ("ols", 0.05), ("kmeans", 0.1)])
def test_predicts_a_smooth_function(design, tol):
    x, y = data(200, seed=5)
    xt = np.random.default_rng(6).uniform(0.05, 0.95, (100, 2))
    net = tr.RBFNetwork(design=design, spread=0.5, goal=0.02, n_centers=30, seed=0).fit(x, y)
    err = np.abs(net.predict(xt) - smooth(xt)).max()
    # the function spans ~2.5; the stated accuracy per design (exact: interpolation of 200
    # samples; ols: goal 0.02 SSE; kmeans: 30 centres)
    assert err < tol, err


def test_conventions(tmp_path):
    x, y = data(30)
    with pytest.raises(ParameterError, match="spread"):
        tr.RBFNetwork(spread=0).fit(x, y)
    with pytest.raises(ParameterError, match="design"):
        tr.RBFNetwork(design="magic").fit(x, y)
    with pytest.raises(ParameterError, match="n_centers"):
        tr.RBFNetwork(design="kmeans", n_centers=31).fit(x, y)
    bad = x.copy()
    bad[2, 1] = np.nan
    with pytest.raises(DataError):
        tr.RBFNetwork().fit(bad, y)
    net = tr.RBFNetwork(design="kmeans", n_centers=6, seed=3).fit(x, y)
    again = tr.RBFNetwork(design="kmeans", n_centers=6, seed=3).fit(x, y)
    np.testing.assert_array_equal(net.centers_, again.centers_)
    with pytest.raises(ShapeError):
        net.predict(np.ones((2, 3)))
    back = tr.load_model(net.save(tmp_path / "rbf.json"))
    np.testing.assert_array_equal(back.predict(x), net.predict(x))
    assert back.get_params() == net.get_params()
