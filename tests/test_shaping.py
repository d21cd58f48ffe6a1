"""Output shaping for the CNC: the library and the edge send the same offsets, and each rule
(clamp, dead band, rate, quantum, register) holds on a real-shaped run."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

import thermerr_rs as tr

SPEC = "limit=15,rate=0.02,deadband=0.3,unit=0.1,bits=12"


@pytest.fixture
def fitted(example_run1, tmp_path):
    run = tr.read_run(example_run1)
    model = tr.MLR().fit_run(run, "E_z", ["T_s01", "T_s07", "T_s10", "T_s13"], inputs="rise")
    path = tmp_path / "m.json"
    model.save(path)
    return model, path


def test_every_rule_holds(fitted, example_run2):
    model, _ = fitted
    run = tr.read_run(example_run2)
    raw = model.predict_run(run)
    out = model.predict_run(run, shape=SPEC)
    assert np.abs(raw).max() > 15  # the clamp has something to do on this run
    assert np.abs(out).max() <= 15 + 1e-9
    codes = out / 0.1
    np.testing.assert_allclose(codes, np.round(codes), atol=1e-6)  # whole units of 0.1 µm
    dt = np.diff(run.time_s)
    steps = np.abs(np.diff(out))
    assert np.all(steps <= 0.02 * dt + 1e-9)  # never faster than the rate
    moved = steps > 0
    assert np.all(steps[moved] >= 0.1 - 1e-9)  # a change is at least one unit
    # the offsets follow the prediction: after the rate allows it, within the dead band + a unit
    settled = np.abs(out - np.clip(raw, -15, 15))
    assert np.median(settled) < 0.3 + 0.1


def test_mapping_and_text_forms_agree(fitted, example_run2):
    model, _ = fitted
    run = tr.read_run(example_run2)
    by_text = model.predict_run(run, shape=SPEC)
    by_map = model.predict_run(run, shape={"limit_um": 15, "max_rate_um_per_s": 0.02, "dead_band_um": 0.3,
                                           "unit_um": 0.1, "bits": 12})
    np.testing.assert_array_equal(by_text, by_map)
    np.testing.assert_array_equal(tr.shape_offsets(run.time_s, model.predict_run(run), SPEC), by_text)


def test_bad_settings_are_parameter_errors(fitted, example_run2):
    model, _ = fitted
    run = tr.read_run(example_run2)
    with pytest.raises(tr.ParameterError, match="bits"):
        model.predict_run(run, shape="bits=16")
    with pytest.raises(tr.ParameterError, match="unknown setting"):
        model.predict_run(run, shape="speed=1")


def test_the_edge_sends_the_same_offsets(edge_bin, fitted, example_run2):
    model, path = fitted
    run = tr.read_run(example_run2)
    r = subprocess.run([str(edge_bin), str(path), str(example_run2), "--shape", SPEC],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.strip().splitlines()
    assert lines[0] == "time_s,E_z_pred,E_z_offset"
    table = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    np.testing.assert_allclose(table[:, 1], model.predict_run(run), rtol=1e-12, atol=1e-9)
    # bit-equal: the same Rust code on the same predictions (the edge's predictions equal the
    # library's to ~1e-12, far below the half unit at which a rounding could differ)
    np.testing.assert_array_equal(table[:, 2], model.predict_run(run, shape=SPEC))
    r = subprocess.run([str(edge_bin), str(path), str(example_run2), "--shape", "rate=-1"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "max_rate_um_per_s" in r.stderr
