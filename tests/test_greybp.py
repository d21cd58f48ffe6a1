"""Seed 002: GM(1,N) against a direct numpy transcription of methods.md §4, the rolling GM + BP
model, its baselines, model files and refusals."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from _long_run import long_run

import thermerr_rs as tr
from thermerr_rs import _core
from thermerr_rs.errors import DataError, ParameterError, ShapeError

EX = Path(__file__).resolve().parents[1] / "examples"
SENSORS = ["T_coolant", "T_headstock", "T_x_nut", "T_bed", "T_ambient"]


def gm1n_numpy(e: np.ndarray, t: np.ndarray, t_next: np.ndarray) -> tuple[np.ndarray, float]:
    """methods.md §4 written out: 1-AGO, background values, least squares, time response,
    restoration by differencing (min-norm pseudo-inverse when underdetermined)."""
    x1 = np.cumsum(e)
    xt = np.cumsum(np.vstack([t, t_next]), axis=0)
    w = len(e)
    z = 0.5 * (x1[1:] + x1[:-1])
    B = np.column_stack([-z, xt[1:w]])
    Y = e[1:]
    if B.shape[0] >= B.shape[1]:
        theta = np.linalg.solve(B.T @ B, B.T @ Y)  # the seed's (BᵀB)⁻¹BᵀY
    else:
        theta = np.linalg.pinv(B) @ Y
    a, b = theta[0], theta[1:]

    def resp(k: int) -> float:
        s = float(b @ xt[k])
        return (e[0] - s / a) * np.exp(-a * k) + s / a

    return theta, resp(w) - resp(w - 1)


@pytest.mark.parametrize("w", [12, 8, 6])
def test_gm1n_equals_the_formulas(w: int) -> None:
    run = tr.read_run(EX / "lathe_run.csv")
    x, y = run.matrix(SENSORS), run["E_x"]
    for start in (0, 40, 90):
        e, t, tn = y[start:start + w], x[start:start + w], x[start + w]
        theta, pred = _core.gm1n_window(np.ascontiguousarray(e), np.ascontiguousarray(t), np.ascontiguousarray(tn))
        ref_theta, ref_pred = gm1n_numpy(e, t, tn)
        B = np.column_stack([-0.5 * (np.cumsum(e)[1:] + np.cumsum(e)[:-1]), np.cumsum(t, axis=0)[1:]])
        # both solve the same small system in double precision, ours by Gaussian elimination,
        # numpy by LAPACK (or an SVD when underdetermined): they agree to about
        # cond(BᵀB)·1e-16 relative, which the bound below scales with
        cond = np.linalg.cond(B.T @ B if B.shape[0] >= B.shape[1] else B @ B.T)
        tol = max(1e-10, cond * 1e-15)
        np.testing.assert_allclose(theta, ref_theta, rtol=tol, atol=tol * np.abs(ref_theta).max())
        assert pred == pytest.approx(ref_pred, rel=tol, abs=tol * max(1.0, abs(ref_pred)))


def seed002_split():
    run = tr.read_run(EX / "lathe_run.csv")
    x, y = run.matrix(SENSORS), run["E_x"]
    return (x[55:103], y[55:103]), (x[:55], y[:55])


def test_greybp_one_step_beats_gm_and_bp_alone() -> None:
    (xt, yt), (xv, yv) = seed002_split()
    gm = tr.GM1N(window=8).fit(xt, yt)
    bp = tr.BPNetwork(seed=0).fit(xt, yt)
    gbp = tr.GreyBP(seed=0).fit(xt, yt)
    rms = lambda p: tr.scores(yv, p).rms  # noqa: E731
    # measured on this run (benches/greybp_compare.py): GM 6.35, BP 6.66, GM+BP 5.07 µm
    assert rms(gbp.predict(xv, yv)) < rms(gm.predict(xv, yv))
    assert rms(gbp.predict(xv, yv)) < rms(bp.predict(xv))


def test_greybp_is_deterministic_and_round_trips(tmp_path) -> None:
    (xt, yt), (xv, yv) = seed002_split()
    a = tr.GreyBP(trainer="seed", seed=4).fit(xt, yt)
    b = tr.GreyBP(trainer="seed", seed=4).fit(xt, yt)
    assert np.array_equal(a.predict(xv), b.predict(xv))
    assert not np.array_equal(a.predict(xv), tr.GreyBP(trainer="seed", seed=5).fit(xt, yt).predict(xv))
    for m in (a, tr.GM1N().fit(xt, yt), tr.BPNetwork(seed=1).fit(xt, yt)):
        path = m.save(tmp_path / f"{m.kind}.json")
        doc = json.loads(path.read_text())
        assert doc["kind"] == m.kind
        back = tr.load_model(path)
        assert type(back) is type(m)
        assert np.array_equal(back.predict(xv), m.predict(xv))
        if m.kind != "bp":
            assert np.array_equal(back.predict(xv, yv), m.predict(xv, yv))


def test_seed_trainer_stops_at_its_goal_and_adam_goes_lower() -> None:
    (xt, yt), _ = seed002_split()
    seed = tr.GreyBP(trainer="seed").fit(xt, yt)
    adam = tr.GreyBP(trainer="adam").fit(xt, yt)
    assert seed.history_[-1] <= 0.01 or len(seed.history_) == 8000
    assert adam.history_.min() < seed.history_[-1]


def test_bad_input_is_refused() -> None:
    (xt, yt), _ = seed002_split()
    with pytest.raises(ShapeError, match="too few"):
        tr.GreyBP().fit(xt[:12], yt[:12])
    with pytest.raises(ParameterError, match="windows"):
        tr.GreyBP(windows=(2, 8)).fit(xt, yt)
    with pytest.raises(ParameterError, match="trainer"):
        tr.GreyBP(trainer="lbfgs").fit(xt, yt)
    bad = xt.copy()
    bad[4, 1] = np.nan
    with pytest.raises(DataError, match="row 4, column 1"):
        tr.GreyBP().fit(bad, yt)
    m = tr.GM1N().fit(xt, yt)
    with pytest.raises(ShapeError):
        m.predict(xt[:, :3])
    with pytest.raises(ShapeError):
        m.predict(xt, yt[:-1])
    with pytest.raises(DataError):
        m.predict(bad)


def test_gm1n_equals_the_formulas_to_1e10_when_well_conditioned() -> None:
    # measured temperature windows are nearly collinear after the 1-AGO (cond(BᵀB) 1e8–1e11 on
    # the lathe run, so any two solvers differ by up to ~1e-6 there, see above); on random
    # series the system is well conditioned and the two agree to 1e-10 as the issue asks
    rng = np.random.default_rng(0)
    for w, m in [(12, 3), (8, 2), (10, 5)]:
        e, t, tn = rng.normal(size=w), rng.normal(size=(w, m)), rng.normal(size=m)
        theta, pred = _core.gm1n_window(e, t, tn)
        ref_theta, ref_pred = gm1n_numpy(e, t, tn)
        np.testing.assert_allclose(theta, ref_theta, rtol=1e-10, atol=1e-12)
        assert pred == pytest.approx(ref_pred, rel=1e-10, abs=1e-12)


def test_large_n_rule_on_a_long_run() -> None:
    # 6 000 training rows: the network trains by the large-n rule (mini-batches, held-back
    # validation blocks, capped epochs), deterministically. On a run this long some of the
    # rolling GM(1,N) windows blow up (restored predictions of 1e10–1e19 µm on this run: e^(−ak)
    # with a fitted a < 0), so the network's min–max scaled inputs carry almost nothing and
    # GM + BP predicts about the training mean — with the full-batch trainer too (before the
    # rule: 8 000 epochs, 4.973 µm against the mean's 4.974 on benches/bench_sequence.py's run).
    # The test asks for that, not for more.
    x, y = long_run()
    cut = 6000
    rms = lambda p: float(np.sqrt(np.mean((p[cut:] - y[cut:]) ** 2)))  # noqa: E731
    mean_rms = rms(np.full_like(y, y[:cut].mean()))
    m = tr.GreyBP().fit(x[:cut], y[:cut])
    rows = cut - 10  # the steps where the longest window is full
    assert 1 <= len(m.history_) <= max(20, -(-500_000 // (rows - rows // 10)))
    one, closed = rms(m.predict(x, y)), rms(m.predict(x))
    assert np.isfinite([one, closed]).all()
    assert one < 1.05 * mean_rms and closed < 1.05 * mean_rms
    again = tr.GreyBP().fit(x[:cut], y[:cut])
    assert np.array_equal(again.history_, m.history_)
    assert np.array_equal(again.predict(x, y), m.predict(x, y))
    # the seed's trainer keeps its full-batch epochs whatever the length
    seed = tr.GreyBP(trainer="seed", max_epochs=15, goal=0.0).fit(x[:3000], y[:3000])
    assert len(seed.history_) == 15
    with pytest.raises(ParameterError, match="large_n"):
        tr.GreyBP(large_n=99).fit(x[:200], y[:200])


def test_bp_alone_takes_the_large_n_rule_on_a_long_run() -> None:
    # BP alone (a static regressor of the temperatures) on the same 6 000 rows: full batch it
    # trains 8 000 epochs in 16 s and holds out at 0.404 µm (measured 2026-11-27; MLR 0.346, the
    # training mean 4.20); by the rule 93 epochs in 0.2 s, 0.406 µm. The test asks for the rule's
    # epochs, determinism, and a fit within 1.5x MLR's held-out error (full batch is too slow here).
    x, y = long_run()
    cut = 6000
    rms = lambda p: float(np.sqrt(np.mean((p[cut:] - y[cut:]) ** 2)))  # noqa: E731
    m = tr.BPNetwork().fit(x[:cut], y[:cut])
    assert 1 <= len(m.history_) <= max(20, -(-500_000 // (cut - cut // 10)))
    assert rms(m.predict(x)) < 1.5 * rms(tr.MLR().fit(x[:cut], y[:cut]).predict(x))
    assert np.array_equal(tr.BPNetwork().fit(x[:cut], y[:cut]).predict(x), m.predict(x))
    # below large_n rows (the seeds' runs) it is the full-batch method, bit for bit
    short = dict(max_epochs=50, patience=1000)
    a = tr.BPNetwork(**short).fit(x[:1500], y[:1500])
    b = tr.BPNetwork(**short, large_n=None).fit(x[:1500], y[:1500])
    assert len(a.history_) == 50 and np.array_equal(a.predict(x), b.predict(x))
    with pytest.raises(ParameterError, match="large_n"):
        tr.BPNetwork(large_n=99).fit(x[:200], y[:200])
