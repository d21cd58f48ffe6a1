"""Parity of the edge predictor (rust/thermerr-edge, no Python) with the library: every model kind
and preprocessing, fitted here, saved, and run through the `thermerr-edge` binary on a held-out
run."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import MinMaxScaled

ROOT = Path(__file__).resolve().parents[1]
SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]


def models() -> dict[str, tuple[tr.Estimator, str]]:
    return {
        "mlr-absolute": (tr.MLR(), "absolute"),
        "mlr-rise": (tr.MLR(), "rise"),
        "rbf-exact-minmax": (MinMaxScaled(tr.RBFNetwork(design="exact", spread=1.0)), "rise"),
        "rbf-ols-minmax": (MinMaxScaled(tr.RBFNetwork(design="ols", spread=1.0, goal=19.0)), "rise"),
        "rbf-kmeans": (tr.RBFNetwork(design="kmeans", n_centers=12, spread=2.0, seed=3), "rise"),
        "rbf-ago": (tr.AGORegressor(tr.RBFNetwork(design="exact", spread=1.2)), "absolute"),
        "mlr-ago-rise": (tr.AGORegressor(tr.MLR()), "rise"),
        "svr-rise": (tr.SVR(C=30.0, epsilon=0.05, gamma=0.05), "rise"),
        "svr-linear-minmax": (MinMaxScaled(tr.SVR(kernel="linear", C=10.0)), "absolute"),
        "bp-rise": (tr.BPNetwork(max_epochs=800, seed=2), "rise"),
        "greybp-rise": (tr.GreyBP(max_epochs=800, seed=2), "rise"),
        "greybp-seed-absolute": (tr.GreyBP(trainer="seed", seed=2), "absolute"),
        "gm1n-rise": (tr.GM1N(window=6), "rise"),
        "hybrid-rise": (tr.HybridFilterNet(hidden=12, max_epochs=800, seed=2), "rise"),
        "arma-rise": (tr.HybridFilterNet(variant="arma"), "rise"),
        "fnn-minmax": (MinMaxScaled(tr.HybridFilterNet(variant="fnn", hidden=8, max_epochs=500)), "rise"),
        "lrnn-rise": (tr.HybridFilterNet(variant="lrnn", hidden=8, max_epochs=500), "rise"),
    }


@pytest.mark.parametrize("name", list(models()))
def test_edge_equals_library(name: str, edge_bin: Path, example_run1: Path, example_run2: Path, tmp_path: Path) -> None:
    model, inputs = models()[name]
    train = tr.read_run(example_run1)
    if "ago" in name:
        train = train.slice(0, 80)  # AGO models are fitted on a prefix (exact RBF: one neuron per sample)
    model.fit_run(train, "E_z", SENSORS, inputs=inputs)
    path = model.save(tmp_path / "model.json")
    out = subprocess.run([str(edge_bin), str(path), str(example_run2)], check=True, capture_output=True, text=True)
    lines = out.stdout.strip().splitlines()
    assert lines[0] == "time_s,E_z_pred"
    got = np.array([float(l.split(",")[1]) for l in lines[1:]])
    test = tr.read_run(example_run2)
    want = model.predict_run(test)  # grey and filter models: closed loop, as the edge runs them
    assert got.shape == want.shape
    # the same predict code on bit-identical parameters (float_roundtrip JSON) and inputs, printed
    # as shortest round-trip decimals: 1e-9 relative (the bound) is far from binding
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    assert out.stderr == ""


def test_edge_reads_stdin_line_by_line(edge_bin: Path, example_run1: Path, tmp_path: Path) -> None:
    model = tr.MLR().fit_run(tr.read_run(example_run1), "E_z", SENSORS, inputs="rise")
    path = model.save(tmp_path / "m.json")
    text = example_run1.read_text().splitlines()
    proc = subprocess.Popen([str(edge_bin), str(path)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    assert proc.stdin is not None and proc.stdout is not None
    proc.stdin.write(text[0] + "\n" + text[1] + "\n")
    proc.stdin.flush()
    # the answer to the first row arrives before the input ends (a pipe from a data logger)
    assert proc.stdout.readline().strip() == "time_s,E_z_pred"
    first = proc.stdout.readline().strip()
    assert first.startswith("0") and abs(float(first.split(",")[1]) - model.intercept_) < 1e-12
    proc.stdin.close()
    proc.wait(timeout=10)
    assert proc.returncode == 0


def test_edge_refuses_a_wrong_format_version(edge_bin: Path, example_run1: Path, tmp_path: Path) -> None:
    model = tr.MLR().fit_run(tr.read_run(example_run1), "E_z", SENSORS)
    doc = model.to_dict()
    doc["format_version"] = 7
    (tmp_path / "v7.json").write_text(json.dumps(doc))
    r = subprocess.run([str(edge_bin), str(tmp_path / "v7.json"), str(example_run1)], capture_output=True, text=True)
    assert r.returncode == 2 and "format_version 7" in r.stderr
