"""Machine files, simulation and calibration through the Python API and the command line."""

from __future__ import annotations

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.cli import main
from thermerr_rs.errors import DataError, MissingColumnError
from thermerr_rs.thermal import Machine


@pytest.fixture(scope="module")
def case():
    return syn.make_case("vmc", "none", 11, hours=(8.0, 4.0))


def test_true_machine_simulates_like_the_reference_integrator(case):
    # the Rust simulation (exact ZOH, Taylor-series matrix exponential) against the generator's
    # scipy expm integration of the same true machine, noise-free
    quiet = syn.make_case("lathe", "none", 2, hours=(6.0, 1.0), noise=False)
    m = Machine.from_toml(syn.to_toml(quiet.truth), "truth.toml")
    run = tr.Run.from_frame(quiet.train)
    sim = m.simulate(run)
    ref = syn.simulate_truth(quiet.truth, quiet.train)
    for k, name in enumerate(sim.node_names):
        np.testing.assert_allclose(sim.nodes[:, k], ref[name], atol=1e-9)
    np.testing.assert_allclose(sim.drift["E_x"], quiet.train["E_x"], atol=1e-9)


def test_load_errors_name_file_and_entry(tmp_path, case):
    text = case.nominal_toml()
    p = tmp_path / "m.toml"
    p.write_text(text.replace('node = "front_bearing"', 'node = "rear_bearing"', 1))
    with pytest.raises(DataError, match=r"m\.toml.*sources\[0\].*unknown node `rear_bearing`"):
        Machine.load(p)
    p.write_text(text + "\n[[links]]\nbetween = [\"bed\", \"bed\"]\nw_per_k = 1.0\n")
    with pytest.raises(DataError, match="two different nodes"):
        Machine.load(p)
    with pytest.raises(FileNotFoundError):
        Machine.load(tmp_path / "none.toml")
    m = Machine.from_toml(text)
    run = tr.Run.from_frame({k: v for k, v in case.train.items() if k != "U_spindle_rpm"})
    with pytest.raises(DataError, match="U_spindle_rpm"):
        m.simulate(run)


def test_round_trip_and_calibration(tmp_path, case):
    nominal = Machine.from_toml(case.nominal_toml())
    run = tr.Run.from_frame(case.train)
    before = nominal.simulate(run).drift["E_z"]
    cal, info = nominal.calibrate(run)
    after = cal.simulate(run).drift["E_z"]
    rms = lambda r: float(np.sqrt(np.mean(r**2)))  # noqa: E731
    assert rms(after - run["E_z"]) < 0.3 * rms(before - run["E_z"])
    # the calibrated model explains the run to near the probe noise (0.15 µm)
    assert rms(after - run["E_z"]) < 0.3
    path = cal.save(tmp_path / "cal.toml")
    back = Machine.load(path)
    np.testing.assert_array_equal(back.simulate(run).drift["E_z"], cal.simulate(run).drift["E_z"])


def test_a_later_piece_of_a_log_is_simulated_from_the_log_s_start(tmp_path, case, capsys):
    """A piece cut from a longer log, with the log's earlier rows given as ``after``, is simulated
    as the tail of the whole log: the same numbers as simulating the whole log and keeping its
    tail. On its own it starts from its own readings with zero drift, which is the wrong start for
    an error measured from the log's start (here the warm machine's drift is far from zero)."""
    nominal = Machine.from_toml(case.nominal_toml())
    run = tr.Run.from_frame(case.train)
    k = len(run) // 2
    head, tail = run.slice(0, k), run.slice(k)
    whole = nominal.simulate(run)
    joined = nominal.simulate(tail, after=head)
    np.testing.assert_array_equal(joined.time_s, tail.time_s)
    np.testing.assert_array_equal(joined.drift["E_z"], whole.drift["E_z"][k:])
    np.testing.assert_array_equal(joined.nodes, whole.nodes[k:])
    for c, v in whole.sensors.items():
        np.testing.assert_array_equal(joined.sensors[c], v[k:])
    alone = nominal.simulate(tail).drift["E_z"]
    assert alone[0] == 0.0 and abs(whole.drift["E_z"][k]) > 5.0
    # the command line: --after gives the same rows; without it, a note says how to pass it
    syn.write_run_csv(tmp_path / "head.csv", {n: head[n] for n in ["time_s", *head.names]})
    syn.write_run_csv(tmp_path / "tail.csv", {n: tail[n] for n in ["time_s", *tail.names]})
    (tmp_path / "m.toml").write_text(case.nominal_toml())
    out = tmp_path / "pred.csv"
    args = ["predict", str(tmp_path / "tail.csv"), "--machine", str(tmp_path / "m.toml"), "--out", str(out)]
    h, t = tr.read_run(tmp_path / "head.csv"), tr.read_run(tmp_path / "tail.csv")  # as the command reads them
    assert main([*args, "--after", str(tmp_path / "head.csv")]) == 0
    written = tr.read_run(out)["E_z_pred"]
    np.testing.assert_allclose(written, nominal.simulate(t, after=h).drift["E_z"], rtol=0, atol=5e-7)  # 6 decimals
    assert "note" not in capsys.readouterr().out
    assert main(args) == 0
    assert "pass --after with that log's earlier rows" in capsys.readouterr().out
    np.testing.assert_allclose(tr.read_run(out)["E_z_pred"], nominal.simulate(t).drift["E_z"], rtol=0, atol=5e-7)
    assert np.max(np.abs(written - tr.read_run(out)["E_z_pred"])) > 5.0


def test_predict_and_calibrate_cli(tmp_path, case, capsys):
    nominal = tmp_path / "nominal.toml"
    nominal.write_text(case.nominal_toml())
    runf = tmp_path / "run.csv"
    syn.write_run_csv(runf, case.train)
    out = tmp_path / "pred.csv"
    assert main(["predict", str(runf), "--machine", str(nominal), "--out", str(out)]) == 0
    pred = tr.read_run(out)
    assert "E_z_pred" in pred.names and "T_front_bearing_pred" in pred.names
    assert main(["calibrate", str(runf), "--machine", str(nominal), "--out", str(tmp_path / "cal.toml")]) == 0
    Machine.load(tmp_path / "cal.toml")
    assert main(["predict", str(runf), "--machine", str(tmp_path / "none.toml"), "--out", str(out)]) == 2
    assert "none.toml" in capsys.readouterr().err
