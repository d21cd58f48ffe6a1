"""Seed 000: the LR/MA/AR filters against numpy least squares on the same regressors, the
network variants, model files and refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.errors import DataError, ParameterError, ShapeError

SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13", "T_ambient"]
FAST = dict(hidden=10, max_epochs=1500, patience=200)


@pytest.fixture(scope="module")
def runs(example_run1_mod, example_run2_mod):
    return tr.read_run(example_run1_mod), tr.read_run(example_run2_mod)


@pytest.fixture(scope="module")
def example_run1_mod():
    from conftest import EXAMPLES

    return EXAMPLES / "hmc_run1.csv"


@pytest.fixture(scope="module")
def example_run2_mod():
    from conftest import EXAMPLES

    return EXAMPLES / "hmc_run2.csv"


def test_filters_equal_numpy_least_squares(runs) -> None:
    run, _ = runs
    x, y = run.matrix(SENSORS), run["E_z"]
    m = tr.HybridFilterNet(variant="arma", ma_lags=2, ar_lags=3).fit(x, y)
    lr, ma, ar = m.filters_
    k0 = 3  # max(ma_lags, ar_lags): the first samples lack their lags and are not fitted
    rows = np.arange(k0, len(y))
    one = np.ones(len(rows))
    ref_lr = np.linalg.lstsq(np.column_stack([one, x[rows]]), y[rows], rcond=None)[0]
    ref_ma = np.linalg.lstsq(np.column_stack([one, x[rows - 1], x[rows - 2]]), y[rows], rcond=None)[0]
    y1 = np.column_stack([one, x[rows]]) @ ref_lr
    y2 = np.column_stack([one, x[rows - 1], x[rows - 2]]) @ ref_ma
    ref_ar = np.linalg.lstsq(np.column_stack([one, y[rows - 1], y[rows - 2], y[rows - 3], y1, y2]), y[rows], rcond=None)[0]
    # both are least-squares solutions of the same full-rank systems (ours: Householder QR,
    # numpy: SVD); the designs' condition numbers are ~1e4 (temperatures near 20 °C), so the two
    # agree to about cond·eps ≈ 1e-12 of the largest coefficient (observed 1e-13 to 1e-14)
    for ours, ref in ((lr, ref_lr), (ma, ref_ma), (ar, ref_ar)):
        np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-10 * np.abs(ref).max())


def test_variants_train_and_hybrid_beats_fnn_one_step(runs) -> None:
    run, test = runs
    res = {}
    for v in ("arma", "fnn", "lrnn", "hybrid"):
        m = tr.HybridFilterNet(variant=v, seed=0, **FAST).fit_run(run, "E_z", SENSORS, inputs="rise")
        res[v] = tr.scores(test["E_z"], m.predict_run(test, one_step=True)).rms
        assert np.isfinite(res[v])
    # the AR lags carry the measured error one step ahead; a static network cannot use it
    assert res["hybrid"] < res["fnn"] and res["arma"] < res["fnn"]


def test_deterministic_and_round_trips(runs, tmp_path) -> None:
    run, test = runs
    a = tr.HybridFilterNet(seed=3, **FAST).fit_run(run, "E_z", SENSORS, inputs="rise")
    b = tr.HybridFilterNet(seed=3, **FAST).fit_run(run, "E_z", SENSORS, inputs="rise")
    assert np.array_equal(a.predict_run(test), b.predict_run(test))
    path = a.save(tmp_path / "h.json")
    assert json.loads(path.read_text())["kind"] == "hybrid"
    back = tr.load_model(path)
    assert isinstance(back, tr.HybridFilterNet)
    assert np.array_equal(back.predict_run(test), a.predict_run(test))
    assert np.array_equal(back.predict_run(test, one_step=True), a.predict_run(test, one_step=True))


def test_several_runs_and_refusals(runs) -> None:
    run, test = runs
    m = tr.HybridFilterNet(variant="lrnn", **FAST).fit_runs([run, test], "E_z", SENSORS, inputs="rise")
    assert np.isfinite(m.predict_run(test)).all()
    x, y = run.matrix(SENSORS), run["E_z"]
    with pytest.raises(ParameterError, match="limit"):
        tr.HybridFilterNet(limit=5.0, **FAST).fit(x, y)
    with pytest.raises(ParameterError, match="variant"):
        tr.HybridFilterNet(variant="lstm").fit(x, y)
    with pytest.raises(ParameterError, match="trainer"):
        tr.HybridFilterNet(trainer="sgd").fit(x, y)
    with pytest.raises(ShapeError, match="too few"):
        tr.HybridFilterNet(**FAST).fit(x[:8], y[:8])
    bad = x.copy()
    bad[7, 2] = np.inf
    with pytest.raises(DataError, match="row 7, column 2"):
        tr.HybridFilterNet(**FAST).fit(bad, y)
    m = tr.HybridFilterNet(variant="arma").fit(x, y)
    with pytest.raises(ShapeError):
        m.predict(x[:, :2])
