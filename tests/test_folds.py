"""Time-ordered cross-validation (issue 12 point 1): the core's splits are scikit-learn's
``TimeSeriesSplit`` index for index, never train on a sample after the test block, give
scikit-learn's ``cross_val_score`` of the same SVR, and bad splits are one line naming the fold."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from sklearn.model_selection import KFold, TimeSeriesSplit, cross_val_score
from sklearn.svm import SVR as SkSVR

import thermerr_rs as tr
from thermerr_rs import _core
from thermerr_rs.errors import ParameterError, ThermerrError
from thermerr_rs.folds import resolve_cv, time_series_split

GRID = list(itertools.product(
    [2, 5, 6, 10, 17, 45, 100],  # n
    [2, 3, 5, 9],  # n_splits
    [0, 1, 3],  # gap
    [None, 1, 2, 7],  # test_size
    [None, 0, 1, 4, 20],  # max_train_size (0: no limit, as in scikit-learn)
))


def sk_splits(n, n_splits, gap, test_size, max_train_size):
    cv = TimeSeriesSplit(n_splits, gap=gap, test_size=test_size, max_train_size=max_train_size)
    return [(a.tolist(), b.tolist()) for a, b in cv.split(np.zeros((n, 1)))]


@pytest.mark.parametrize("n,n_splits,gap,test_size,max_train_size", GRID)
def test_time_series_split_equals_scikit_learn(n, n_splits, gap, test_size, max_train_size):
    try:
        ref = sk_splits(n, n_splits, gap, test_size, max_train_size)
    except ValueError:
        ref = None
    if ref is None:
        # scikit-learn refuses these (too many splits for n): so does the core, as a ParameterError
        with pytest.raises(ParameterError, match="cv"):
            time_series_split(n, n_splits, gap=gap, test_size=test_size, max_train_size=max_train_size)
        return
    ours = time_series_split(n, n_splits, gap=gap, test_size=test_size, max_train_size=max_train_size)
    assert [(a.tolist(), b.tolist()) for a, b in ours] == ref
    # (b) no test sample inside or before a training block: every training index is more than
    # `gap` samples before every test index of its split
    for train, test in ours:
        assert train.max() + gap < test.min()
    # an int cv of the searches is exactly these splits
    if test_size is None and max_train_size is None:
        assert resolve_cv(n_splits, n, gap=gap) == ref


def test_the_grid_covers_refusals_and_limits():
    ok = [g for g in GRID if _sk_ok(*g)]
    assert 0 < len(ok) < len(GRID)
    assert any(g[4] and g[4] < g[0] // 2 for g in ok)  # max_train_size that bites


def _sk_ok(*g):
    try:
        sk_splits(*g)
        return True
    except ValueError:
        return False


def seed004_like(n: int = 60, seed: int = 0):
    from test_svr import seed004_like as make  # noqa: PLC0415

    return make(n, seed)


@pytest.mark.parametrize("cv", [TimeSeriesSplit(4), TimeSeriesSplit(3, gap=2, test_size=8, max_train_size=25)])
def test_cv_mse_equals_scikit_learn_on_time_splits(cv):
    x, y = seed004_like()
    C, gamma, eps = 7.3465, 0.0261, 0.1
    ref = -cross_val_score(SkSVR(C=C, gamma=gamma, epsilon=eps, tol=1e-3), x, y, cv=cv,
                           scoring="neg_mean_squared_error").mean()
    # the splitter object, its splits as pairs, and the core's own time splits: the same fits
    # (the fold mean is a parallel sum, so equal to its rounding)
    ours = tr.svr_cv_mse(x, y, cv, C=C, gamma=gamma, epsilon=eps)
    pairs = list(cv.split(x))
    assert tr.svr_cv_mse(x, y, pairs, C=C, gamma=gamma, epsilon=eps) == pytest.approx(ours, rel=1e-12)
    if cv.test_size is None and cv.max_train_size is None:
        same = tr.svr_cv_mse(x, y, cv.n_splits, C=C, gamma=gamma, epsilon=eps, gap=cv.gap)
        assert same == pytest.approx(ours, rel=1e-12)
    # Tolerance: both SMOs stop once the maximal KKT violation is below tol = 1e-3, so their
    # predictions may differ by O(tol) (tests/test_svr.py bounds them by 1e-3 absolute). A
    # prediction shift |δ| <= 1e-3 moves a fold's MSE by at most 2·1e-3·RMS(residual) + 1e-6.
    bound = 2e-3 * np.sqrt(ref) + 1e-6
    assert abs(ours - ref) <= bound
    # Observed: the same SMO on the same rows lands on the same bits (test_svr), so the CV errors
    # agree to the rounding of the fold sums.
    assert ours == pytest.approx(ref, rel=1e-9)


def test_tune_svr_objective_at_its_optimum_is_scikit_learns_time_cv():
    x, y = seed004_like()
    res = tr.tune_svr(x, y, cv=3, gap=1, bounds={"C": (0.1, 100.0), "gamma": (1e-3, 1.0)}, pop=6, iters=4,
                      seed=2, progress=False)
    assert res.folds == [(a.tolist(), b.tolist()) for a, b in TimeSeriesSplit(3, gap=1).split(x)]
    ref = -cross_val_score(SkSVR(C=res.C, gamma=res.gamma, epsilon=0.1), x, y, cv=TimeSeriesSplit(3, gap=1),
                           scoring="neg_mean_squared_error").mean()
    # same reasoning as above: the observed agreement is to rounding of the fold sums
    assert res.cv_mse == pytest.approx(ref, rel=1e-9)


def test_kfold_by_name_keeps_the_seed_search():
    x, y = seed004_like()
    xt, yt = x[:45], y[:45]
    kw = dict(bounds={"C": (0.1, 100.0), "gamma": (1e-3, 1.0)}, pop=6, iters=4, seed=1, progress=False)
    kf = tr.tune_svr(xt, yt, cv=5, cv_kind="kfold", **kw)
    # today's folds: the core's shuffled test sets, each trained on the complement
    folds = _core.kfold(45, 5, 1)
    assert kf.folds == [(sorted(set(range(45)) - set(f)), sorted(f)) for f in folds]
    again = tr.tune_svr(xt, yt, cv=kf.folds, **kw)
    assert (again.C, again.gamma, again.cv_mse) == (kf.C, kf.gamma, kf.cv_mse)
    ts = tr.tune_svr(xt, yt, cv=5, **kw)
    assert ts.folds == [(a.tolist(), b.tolist()) for a, b in TimeSeriesSplit(5).split(xt)]
    # a scikit-learn KFold is taken as it is
    sk = tr.svr_cv_mse(xt, yt, KFold(3), C=1.0, gamma=0.1)
    ref = -cross_val_score(SkSVR(C=1.0, gamma=0.1), xt, yt, cv=KFold(3), scoring="neg_mean_squared_error").mean()
    assert sk == pytest.approx(ref, rel=1e-9)


def _one_line(err: BaseException, *words: str) -> None:
    text = str(err)
    assert "\n" not in text
    for w in words:
        assert w in text, text


@pytest.mark.parametrize("splits,words", [
    ([([0, 1, 2], [3, 4]), ([0, 1, 2, 3], [])], ["fold 1", "test set is empty"]),
    ([([0, 1, 2], [3, 4]), ([], [5])], ["fold 1", "training set is empty"]),
    ([([0, 1, 2, 3], [3, 4])], ["fold 0", "index 3", "both"]),
    ([([0, 1, 2], [3, 4]), ([0, 1], [2, 99])], ["fold 1", "test index 99", "out of range"]),
    ([([0, 1, 2], [3, 4]), ([-1, 1], [2])], ["fold 1", "negative"]),
    ([[3, 4], [5, 6]], ["fold 0", "(train, test) pair"]),
    ([], ["at least one"]),
])
def test_bad_splits_are_one_line_naming_the_fold(splits, words):
    x, y = seed004_like(30)
    for call in (lambda: tr.svr_cv_mse(x, y, splits, C=1.0, gamma=0.1),
                 lambda: tr.tune_svr(x, y, cv=splits, pop=4, iters=1, progress=False),
                 lambda: tr.spread_search(x, y, [1.0], cv=splits, progress=False)):
        with pytest.raises(ParameterError) as info:
            call()
        assert isinstance(info.value, ThermerrError)
        _one_line(info.value, "cv", *words)


@pytest.mark.parametrize("kw,words", [
    (dict(cv=30), ["30 time-ordered splits", "31 samples", "30"]),
    (dict(cv=9, gap=5), ["too many splits (9)", "gap 5"]),
    (dict(cv=1), ["at least 2"]),
    (dict(cv=31, cv_kind="kfold"), ["folds <= samples"]),
    (dict(cv=3, cv_kind="kfold", gap=2), ["gap"]),
    (dict(cv=3, cv_kind="leave_one_out"), ["cv_kind"]),
    (dict(cv=TimeSeriesSplit(3), gap=2), ["gap"]),
    (dict(cv="kfold"), ["cv must be"]),
    (dict(cv=3, gap=-1), ["gap"]),
])
def test_too_many_splits_and_bad_options(kw, words):
    x, y = seed004_like(30)
    with pytest.raises(ParameterError) as info:
        tr.tune_svr(x, y, pop=4, iters=1, progress=False, **kw)
    _one_line(info.value, *words)


def test_spread_search_is_time_ordered_by_default():
    from test_preprocessing import series  # noqa: PLC0415

    from thermerr_rs.preprocessing import MinMaxAGO

    x, y = series(41, 1)
    grid = np.arange(1.0, 2.0, 0.25)
    res = tr.spread_search(x, y, grid, progress=False)
    assert res.folds == [(a.tolist(), b.tolist()) for a, b in TimeSeriesSplit(5).split(x)]
    for tr_idx, te in res.folds:
        assert max(tr_idx) < min(te)
    # brute force: per split, ranges of the training samples, AGO from the start, mean band
    expect = []
    for s in grid:
        per = []
        for train, test in TimeSeriesSplit(5).split(x):
            xt, yt = MinMaxAGO.fit(x[train]), MinMaxAGO.fit(y[train])
            x1, y1 = xt.transform(x), yt.transform(y)
            net = tr.RBFNetwork(design="exact", spread=s).fit(x1[train], y1[train])
            r = y[test] - yt.inverse(net.predict(x1))[test]
            per.append(r.max() - r.min())
        expect.append(np.mean(per))
    np.testing.assert_allclose(res.bands, expect, rtol=1e-9)
    assert res.spread == grid[int(np.argmin(expect))]


def test_cli_tune_with_time_folds(tmp_path, capsys):
    from conftest import EXAMPLES

    from thermerr_rs.cli import main

    out = tmp_path / "svr.json"
    argv = ["fit", str(EXAMPLES / "spindle_3000rpm.csv"), "--axis", "E_z", "--model", "svr", "--tune", "cso",
            "--cv", "3", "--pop", "4", "--iters", "3", "--sensors", "T_front_bearing,T_headstock",
            "--out", str(out), "--json"]
    assert main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    assert np.isfinite(report["train"]["rms"]) and isinstance(tr.load_model(out), tr.SVR)
    assert main(argv[:-1] + ["--gap", "2", "--cv-kind", "time"]) == 0
    assert "3 time-ordered splits (gap 2)" in capsys.readouterr().out
    assert main(argv[:-1] + ["--cv-kind", "kfold"]) == 0
    assert "3 shuffled folds" in capsys.readouterr().out
    rc = main(argv[:-1] + ["--cv", "400"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "cv" in err
    with pytest.raises(SystemExit):
        main(argv[:-1] + ["--cv-kind", "shuffle"])
