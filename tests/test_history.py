"""Temperature history as inputs (issue 12 point 3): each reading plus its rise over about the last
τ seconds (the reading minus a first-order low-pass of it), recorded in the model file and kept as
state by thermerr-edge, equal to the library's predictions."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import _core
from thermerr_rs.synthetic import write_run_csv

SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]
TAUS = [900.0, 3600.0]


def reference(x: np.ndarray, t: np.ndarray, taus: list[float]) -> np.ndarray:
    """The documented filter written out in numpy, independently of the core."""
    out = [x]
    for tau in taus:
        f = np.empty_like(x)
        f[0] = x[0]
        for i in range(1, len(x)):
            a = 1.0 - np.exp(-(t[i] - t[i - 1]) / tau)
            f[i] = f[i - 1] + a * (x[i] - f[i - 1])
        out.append(x - f)
    return np.hstack(out)


def test_the_transform_is_the_documented_filter(example_run1):
    run = tr.read_run(example_run1)
    x = run.input_matrix(SENSORS, "rise")
    got = _core.history_transform(x, run.time_s, TAUS, 150.0)
    assert got.shape == (len(run), 12)
    np.testing.assert_allclose(got, reference(x, run.time_s, TAUS), rtol=1e-12, atol=1e-12)
    # without times the rows are step_s apart: the same on this evenly sampled run
    np.testing.assert_array_equal(_core.history_transform(x, None, TAUS, 150.0), got)


@pytest.mark.parametrize("make", [
    lambda: tr.MLR(),
    lambda: tr.RBFNetwork(design="kmeans", n_centers=12, spread=2.0, seed=0),
    lambda: tr.SVR(C=30.0, epsilon=0.05, gamma=0.05),
], ids=["mlr", "rbf", "svr"])
def test_edge_equals_library(make, example_run1, example_run2, edge_bin, tmp_path):
    model = make().fit_run(tr.read_run(example_run1), "E_z", SENSORS, inputs="rise", history=TAUS)
    path = model.save(tmp_path / "m.json")
    doc = json.loads(path.read_text())
    assert doc["history"] == {"tau_s": TAUS, "step_s": 150.0}
    assert doc["n_features"] == 12 and doc["features"] == SENSORS
    run2 = tr.read_run(example_run2)
    want = model.predict_run(run2)
    np.testing.assert_array_equal(tr.load_model(path).predict_run(run2), want)
    res = subprocess.run([str(edge_bin), str(path), str(example_run2)], capture_output=True, text=True,
                         timeout=60, check=True)
    got = np.array([float(ln.split(",")[1]) for ln in res.stdout.strip().splitlines()[1:]])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
    # with no time column the edge steps by the training step (150 s): the same on this run
    cols = {n: run2[n] for n in SENSORS}
    write_run_csv(tmp_path / "no_time.csv", {"time_s": run2.time_s, **cols})
    text = (tmp_path / "no_time.csv").read_text().splitlines()
    (tmp_path / "no_time.csv").write_text("\n".join(",".join(ln.split(",")[1:]) for ln in text) + "\n")
    res = subprocess.run([str(edge_bin), str(path), str(tmp_path / "no_time.csv")], capture_output=True,
                         text=True, timeout=60, check=True)
    got = np.array([float(ln.split(",")[1]) for ln in res.stdout.strip().splitlines()[1:]])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def lagged_run(seed: int, n: int = 2000, step: float = 60.0) -> tr.Run:
    """A spindle heating a sensor at once and the structure with a 30-min lag: the error follows
    the lagged part, which no function of the current reading alone can give."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * step
    power = np.repeat(rng.uniform(0, 1, size=n // 40 + 1), 40)[:n]
    fast = np.zeros(n)
    slow = np.zeros(n)
    for i in range(1, n):
        fast[i] = fast[i - 1] + (1 - np.exp(-step / 300)) * (8 * power[i] - fast[i - 1])
        slow[i] = slow[i - 1] + (1 - np.exp(-step / 1800)) * (fast[i] - slow[i - 1])
    T = 20 + fast + rng.normal(0, 0.02, n)
    e = 4.0 * slow + rng.normal(0, 0.1, n)
    import pandas as pd

    return tr.Run.from_frame(pd.DataFrame({"time_s": t, "T_spindle": T, "E_z": e}))


def test_history_recovers_a_lag_a_static_model_cannot():
    """Time-ordered: fit on the first 60 %, score the last 40 %. The error follows a 30-min lag
    of the sensor; with a 1800-s history the MLR can represent it, without it cannot. The whole
    run is predicted and its last 40 % scored, as a gateway running since the start would (the
    filters are warm; predicting the slice alone would restart them, a transient of about τ)."""
    pytest.importorskip("pandas")
    run = lagged_run(3)
    cut = int(0.6 * len(run))
    train = run.slice(0, cut)
    rms = lambda m: float(np.sqrt(np.mean((run["E_z"] - m.predict_run(run))[cut:] ** 2)))  # noqa: E731
    plain = tr.MLR().fit_run(train, "E_z", ["T_spindle"])
    hist = tr.MLR().fit_run(train, "E_z", ["T_spindle"], history=[1800.0])
    assert rms(hist) < 0.5 * rms(plain), (rms(hist), rms(plain))
    # the probe noise is 0.1 µm; the rest is the sensor's 0.02 K noise through the fitted weights
    assert rms(hist) < 0.3, rms(hist)


def test_bad_history_is_refused(example_run1, tmp_path):
    run = tr.read_run(example_run1)
    with pytest.raises(tr.ParameterError, match="history"):
        tr.MLR().fit_run(run, "E_z", SENSORS, history=[0.0])
    with pytest.raises(tr.ParameterError, match="history"):
        tr.MLR().fit_run(run, "E_z", SENSORS, history=[])
    model = tr.MLR().fit_run(run, "E_z", SENSORS, history=TAUS)
    doc = model.to_dict()
    doc["history"]["tau_s"] = [900.0] * 4  # 12 inputs are not a whole number of readings x 5
    with pytest.raises(tr.ModelFormatError, match="history: 12 features are not readings × 5"):
        tr.MLR.from_dict(doc)
    doc["history"]["tau_s"] = [900.0]  # 12 inputs would be 6 readings x 2, but 4 are named
    with pytest.raises(tr.ModelFormatError, match=r"4 feature names for 6 features \(12 inputs = readings × 2\)"):
        tr.MLR.from_dict(doc)


def test_a_refit_without_history_forgets_it(example_run1):
    run = tr.read_run(example_run1)
    model = tr.MLR().fit_run(run, "E_z", SENSORS, history=TAUS)
    model.fit_run(run, "E_z", SENSORS)
    assert model.input_history_ is None and "history" not in model.to_dict()
    assert model.n_features_in_ == 4


def test_guard_with_history(example_run1, example_run2):
    run1, run2 = tr.read_run(example_run1), tr.read_run(example_run2)
    model = tr.MLR().fit_run(run1, "E_z", SENSORS, inputs="rise", history=TAUS)
    tr.add_guard(model, run1)
    fb = model.guard_["fallbacks"]
    assert len(fb) == 4 and all(f["model"]["history"]["tau_s"] == TAUS for f in fb)
    cols = {n: run2[n] for n in ["time_s", *SENSORS]}
    out = tr.predict_guarded(model, cols)
    assert set(out.status) == {"ok"}
    np.testing.assert_allclose(out.y, model.predict_run(run2), rtol=1e-12, atol=1e-12)


def test_cli_fit_with_history(example_run1, example_run2, tmp_path):
    from thermerr_rs.cli import main

    out = tmp_path / "m.json"
    assert main(["fit", str(example_run1), "--axis", "E_z", "--sensors", ",".join(SENSORS), "--history",
                 "900,3600", "--test", str(example_run2), "--out", str(out), "--quiet"]) == 0
    assert json.loads(out.read_text())["history"]["tau_s"] == TAUS
    with pytest.raises(SystemExit):
        main(["fit", str(example_run1), "--axis", "E_z", "--history", "0,5", "--out", str(out)])
