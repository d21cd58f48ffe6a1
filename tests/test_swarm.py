"""CSO and PSO on the standard test functions; SVR tuning by cross-validated MSE against
scikit-learn's cross-validation of the same SVR on the same folds."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.model_selection import cross_val_score
from sklearn.svm import SVR as SkSVR

import thermerr_rs as tr
from thermerr_rs.errors import ParameterError

RASTRIGIN_2 = [(-5.12, 5.12)] * 2


def rastrigin(x: np.ndarray) -> float:
    return float(10 * len(x) + np.sum(x**2 - 10 * np.cos(2 * np.pi * x)))


@pytest.mark.parametrize("method", [tr.cso, tr.pso])
def test_sphere_and_rosenbrock_reach_their_optimum(method) -> None:
    # budgets and tolerances measured over seeds 0-4 with a wide margin (observed: sphere ~1e-12
    # and below, Rosenbrock < 1e-4); the optimum is 0 at 0 and at (1, 1)
    for seed in range(3):
        s = method("sphere", [(-5.0, 5.0)] * 5, pop=30, iters=300, seed=seed)
        assert s.fun < 1e-6 and np.abs(s.x).max() < 1e-2
        r = method("rosenbrock", [(-2.0, 2.0)] * 2, pop=30, iters=300, seed=seed)
        assert r.fun < 1e-3 and np.allclose(r.x, 1.0, atol=0.05)


def test_rastrigin_global_minimum_with_cso() -> None:
    # the global minimum is 0 at the origin, local minima sit at every integer point (f ≥ 1):
    # reaching f < 1e-6 means the global basin was found
    hits = sum(tr.cso("rastrigin", RASTRIGIN_2, pop=20, iters=100, seed=s).fun < 1e-6 for s in range(5))
    assert hits >= 4


def test_callable_equals_builtin_and_same_seed_same_result() -> None:
    a = tr.cso("rastrigin", RASTRIGIN_2, pop=20, iters=50, seed=3)
    b = tr.cso(rastrigin, RASTRIGIN_2, pop=20, iters=50, seed=3)
    c = tr.cso(lambda p: [rastrigin(r) for r in p], RASTRIGIN_2, pop=20, iters=50, seed=3, vectorized=True)
    # the same points are evaluated in the same order; numpy's cos and Rust's may differ in the
    # last ulp, so the best values agree to rounding, not necessarily to the bit
    assert a.fun == pytest.approx(b.fun, abs=1e-12) and a.fun == pytest.approx(c.fun, abs=1e-12)
    again = tr.cso(rastrigin, RASTRIGIN_2, pop=20, iters=50, seed=3)
    assert np.array_equal(b.x, again.x) and np.array_equal(b.history, again.history)
    other = tr.cso(rastrigin, RASTRIGIN_2, pop=20, iters=50, seed=4)
    assert not np.array_equal(b.x, other.x)
    assert len(a.history) == 50 and a.n_evals == 20 * 51 and np.all(np.diff(a.history) <= 0)


def test_objective_exceptions_and_bad_parameters() -> None:
    def boom(x: np.ndarray) -> float:
        raise RuntimeError("objective failed")

    with pytest.raises(RuntimeError, match="objective failed"):
        tr.cso(boom, RASTRIGIN_2)
    with pytest.raises(ParameterError, match="bounds"):
        tr.pso("sphere", [(1.0, -1.0)])
    with pytest.raises(ParameterError, match="unknown built-in"):
        tr.cso("ackley", RASTRIGIN_2)
    with pytest.raises(ParameterError, match="pop"):
        tr.cso("sphere", RASTRIGIN_2, pop=1)
    nan_best = tr.pso(lambda x: float("nan") if x[0] > 0 else float(x @ x), [(-1.0, 1.0)] * 2, seed=0)
    assert np.isfinite(nan_best.fun) and nan_best.x[0] <= 0  # NaN counts as +inf


def seed004_like(n: int = 60, seed: int = 0):
    from test_svr import seed004_like as make  # noqa: PLC0415

    return make(n, seed)


def test_cv_mse_equals_scikit_learn_cross_validation() -> None:
    x, y = seed004_like()
    folds = tr.swarm._core.kfold(45, 5, 7)
    cv = [(np.setdiff1d(np.arange(45), f), np.asarray(f)) for f in folds]
    ours = tr.svr_cv_mse(x[:45], y[:45], cv, C=7.3465, gamma=0.0261)
    ref = -cross_val_score(SkSVR(C=7.3465, gamma=0.0261), x[:45], y[:45], cv=cv,
                           scoring="neg_mean_squared_error").mean()
    # the same SMO on the same folds (see test_svr): equal to rounding of the fold sums
    assert ours == pytest.approx(ref, rel=1e-9)


@pytest.mark.parametrize("method", ["cso", "pso"])
def test_tune_svr_improves_on_defaults_and_is_deterministic(method: str) -> None:
    x, y = seed004_like()
    xt, yt = x[:45], y[:45]
    res = tr.tune_svr(xt, yt, method=method, bounds={"C": (0.1, 100.0), "gamma": (1e-3, 1.0)},
                      pop=10, iters=20, seed=1, progress=False)
    assert 0.1 <= res.C <= 100 and 1e-3 <= res.gamma <= 1.0
    default = tr.svr_cv_mse(xt, yt, res.folds, C=1.0, gamma=1.0 / (4 * xt.var()))
    assert res.cv_mse < default
    # the reported CV MSE is the objective at the reported point, and the refitted model is the
    # SVR with those parameters on all the training data
    assert res.cv_mse == pytest.approx(tr.svr_cv_mse(xt, yt, res.folds, C=res.C, gamma=res.gamma), rel=1e-12)
    ref = tr.SVR(C=res.C, gamma=res.gamma).fit(xt, yt)
    assert np.array_equal(res.model.predict(x), ref.predict(x))
    again = tr.tune_svr(xt, yt, method=method, bounds={"C": (0.1, 100.0), "gamma": (1e-3, 1.0)},
                        pop=10, iters=20, seed=1, progress=False)
    assert (again.C, again.gamma, again.cv_mse) == (res.C, res.gamma, res.cv_mse)
    assert len(res.history) == 20 and res.n_evals == 10 * 21  # initial population + 20 generations


def test_the_pruned_search_is_the_plain_search() -> None:
    """tune_svr stops a point once its first folds rule it out and fits no (point, fold) twice;
    the swarm only asks whether a point beats its member's memory, so the result must be the
    plain search's: CSO driving the full CV MSE of every point, bit for bit."""
    x, y = seed004_like(90, seed=3)
    bounds = {"C": (0.1, 100.0), "gamma": (1e-3, 1.0)}
    res = tr.tune_svr(x, y, cv=4, bounds=bounds, pop=8, iters=12, seed=5, progress=False)
    lo, hi = np.log10([0.1, 1e-3]), np.log10([100.0, 1.0])

    def full(v: np.ndarray) -> float:
        return tr.svr_cv_mse(x, y, res.folds, C=10 ** v[0], gamma=10 ** v[1])

    plain = tr.cso(full, list(zip(lo, hi)), pop=8, iters=12, seed=5)
    assert (res.C, res.gamma, res.cv_mse) == (10 ** plain.x[0], 10 ** plain.x[1], plain.fun)
    assert np.array_equal(res.history, plain.history)
    assert res.n_fits < res.n_evals * 4


def test_a_best_point_on_the_box_edge_is_named() -> None:
    x, y = seed004_like(90, seed=3)
    # a nearly linear target: the search runs into the smallest gamma and the largest C it may
    res = tr.tune_svr(x, y, cv=4, bounds={"C": (0.1, 1.0), "gamma": (1e-3, 1e-2)}, pop=6, iters=6, seed=5,
                      progress=False)
    assert res.at_bounds and all("bound" in e for e in res.at_bounds), res
    inside = tr.tune_svr(x, y, cv=4, bounds={"C": (0.1, 100.0), "gamma": (1e-3, 1.0)}, pop=8, iters=12, seed=5,
                         progress=False)
    def near(v: float, ends: tuple[float, float]) -> bool:
        return any(abs(v - e) <= 1e-9 * e for e in ends)

    on_edge = {"C": near(inside.C, (0.1, 100.0)), "gamma": near(inside.gamma, (1e-3, 1.0))}
    assert {e.split(" ")[0] for e in inside.at_bounds} == {k for k, v in on_edge.items() if v}


def test_warm_started_search_reports_the_cold_objective_and_is_deterministic() -> None:
    x, y = seed004_like(90, seed=3)
    kw = dict(cv=4, bounds={"C": (0.1, 100.0), "gamma": (1e-3, 1.0)}, pop=8, iters=12, seed=5, progress=False)
    warm = tr.tune_svr(x, y, warm_start=True, **kw)
    # its CV MSE is the objective at its point with cold solvers, as anyone recomputes it
    assert warm.cv_mse == tr.svr_cv_mse(x, y, warm.folds, C=warm.C, gamma=warm.gamma)
    again = tr.tune_svr(x, y, warm_start=True, **kw)
    assert (again.C, again.gamma, again.cv_mse, again.n_fits) == (warm.C, warm.gamma, warm.cv_mse, warm.n_fits)


def test_tune_svr_refuses_bad_input() -> None:
    x, y = seed004_like()
    with pytest.raises(ParameterError, match="unknown keys"):
        tr.tune_svr(x, y, bounds={"epsilon": (0.0, 1.0)}, progress=False)
    with pytest.raises(ParameterError, match="cv"):
        tr.tune_svr(x, y, cv=1, progress=False)
    with pytest.raises(ParameterError, match="method"):
        tr.tune_svr(x, y, method="ga", progress=False)
    with pytest.raises(ParameterError, match="C"):
        tr.tune_svr(x, y, bounds={"C": (0.0, 1.0)}, progress=False)


def run_like(n: int = 2400, seed: int = 0):
    """A run-like series: two slow temperatures with noise and a drift that lags one of them."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / n
    temps = np.column_stack([np.sin(6 * t) + 0.5 * t, np.cos(3 * t) * t])
    x = temps + rng.normal(0, 0.01, temps.shape)
    y = 4 * temps[:, 0] + 2 * np.tanh(temps[:, 1]) + rng.normal(0, 0.05, n)
    return x, y


def test_a_thinned_search_reports_the_full_objective_at_its_point() -> None:
    x, y = run_like()
    # 4 time-ordered splits of 2 400 rows: the largest trains on 1 920, so "auto" takes every 2nd
    r = tr.tune_svr(x, y, cv=4, pop=6, iters=4, seed=3, progress=False)
    assert r.thin == 2
    # the reported CV MSE is the objective on every row at the returned point, as svr_cv_mse
    # (and so scikit-learn's cross_val_score) gives it
    assert r.cv_mse == tr.svr_cv_mse(x, y, r.folds, C=r.C, gamma=r.gamma)
    sk = -cross_val_score(SkSVR(C=r.C, gamma=r.gamma), x, y, cv=r.folds,
                          scoring="neg_mean_squared_error").mean()
    # the same SMO on the same folds (see test_svr): equal to rounding of the fold sums
    assert r.cv_mse == pytest.approx(sk, rel=1e-9)
    again = tr.tune_svr(x, y, cv=4, pop=6, iters=4, seed=3, progress=False)
    assert (again.C, again.gamma, again.cv_mse) == (r.C, r.gamma, r.cv_mse)
    # the refitted model is the SVR at that point on every row
    ref = tr.SVR(C=r.C, gamma=r.gamma).fit(x, y)
    np.testing.assert_array_equal(r.model.predict(x[:50]), ref.predict(x[:50]))


def test_thin_one_is_the_plain_search_and_small_runs_are_not_thinned() -> None:
    x, y = run_like(600)
    plain = tr.tune_svr(x, y, pop=6, iters=3, seed=1, progress=False, thin=1, warm_start=False)
    one = tr.tune_svr(x, y, pop=6, iters=3, seed=1, progress=False, thin=1)
    auto = tr.tune_svr(x, y, pop=6, iters=3, seed=1, progress=False)
    assert plain.thin == one.thin == auto.thin == 1
    for r in (one, auto):
        assert (r.C, r.gamma, r.cv_mse, r.n_fits) == (plain.C, plain.gamma, plain.cv_mse, plain.n_fits)
        np.testing.assert_array_equal(r.history, plain.history)


def test_bad_thinning_is_one_parameter_error() -> None:
    x, y = seed004_like()
    for bad in (0, -2, "half"):
        with pytest.raises(ParameterError, match="thin"):
            tr.tune_svr(x, y, thin=bad, progress=False)
    # 60 rows in 5 time-ordered splits: every 50th row is row 0 or 50, no test row in fold 0
    with pytest.raises(ParameterError, match="fold 0 without a test row"):
        tr.tune_svr(x, y, thin=50, progress=False)


def test_the_bar_says_when_a_thinned_search_scores_on_every_row(capsys) -> None:
    x, y = run_like()
    tr.tune_svr(x, y, cv=4, pop=4, iters=2, seed=3, progress=True)
    err = capsys.readouterr().err
    assert "CSO-SVR on 1 row in 2" in err and "3/3" in err
    assert "then=scoring the best on every row" in err
    tr.tune_svr(x[:600], y[:600], pop=4, iters=2, seed=3, progress=True)
    err = capsys.readouterr().err
    assert "CSO-SVR: " in err and "every row" not in err
