"""The thermerr command line, run as a user would."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.cli import main


def test_fit_and_evaluate_mlr(example_run1, example_run2, tmp_path, capsys):
    out = tmp_path / "m.json"
    assert main(["fit", str(example_run1), "--axis", "E_z", "--model", "mlr", "--out", str(out),
                 "--test", str(example_run2)]) == 0
    text = capsys.readouterr().out
    assert "training run" in text and "held-out run" in text and "RMS residual" in text
    model = tr.load_model(out)
    assert model.target_name_ == "E_z" and model.inputs_ == "rise"
    assert main(["evaluate", str(out), str(example_run2), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["axis"] == "E_z"
    # the bundled example is linear in the node temperatures up to a small quadratic term:
    # a 20-sensor MLR must compensate most of it on the held-out run
    assert report["compensation_rate"] > 0.9
    # the rows left out of the mean accuracy as a count (a run of days leaves out thousands,
    # one line each when listed); the Python API keeps the list
    run2 = tr.read_run(example_run2)
    s = tr.scores(run2["E_z"], model.predict_run(run2))
    assert "accuracy_excluded" not in report
    assert report["n_accuracy_excluded"] == len(s.accuracy_excluded) > 0


def test_fit_mlr_alpha_is_the_ridge_of_the_python_api(example_run1, tmp_path, capsys):
    out = tmp_path / "ridge.json"
    assert main(["fit", str(example_run1), "--axis", "E_z", "--model", "mlr", "--alpha", "10",
                 "--no-guard", "--out", str(out), "--quiet"]) == 0
    saved = tr.load_model(out)
    run = tr.read_run(example_run1)
    sensors = run.temperatures
    ref = tr.MLR(alpha=10.0).fit_run(run, "E_z", sensors)
    # the same fit of the same rows: equal to the last bits, not within a tolerance of a method
    np.testing.assert_allclose(saved.coef_, ref.coef_, rtol=1e-12, atol=1e-12)
    plain = tr.MLR().fit_run(run, "E_z", sensors)
    assert np.abs(saved.coef_).sum() < np.abs(plain.coef_).sum()  # the penalty shrinks the slopes
    with pytest.raises(SystemExit) as bad:  # argparse: usage and one line, exit 2
        main(["fit", str(example_run1), "--axis", "E_z", "--alpha", "-1", "--out", str(out)])
    assert bad.value.code == 2 and "argument --alpha: must be a finite number >= 0" in capsys.readouterr().err


def test_bad_input_is_one_line(example_run1, tmp_path, capsys):
    rc = main(["fit", str(example_run1), "--axis", "E_q", "--out", str(tmp_path / "m.json")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "E_q" in err
    rc = main(["evaluate", str(tmp_path / "none.json"), str(example_run1)])
    assert rc == 2 and "none.json" in capsys.readouterr().err
    rc = main(["fit", str(example_run1), "--axis", "E_z", "--sensors", "T_s01,T_bogus",
               "--out", str(tmp_path / "m.json")])
    assert rc == 2 and "T_bogus" in capsys.readouterr().err
    assert not (tmp_path / "m.json").exists()


def test_a_dead_probe_is_not_modelled(example_run1, tmp_path, capsys):
    """A probe that reads one value in every row (unplugged): before, `thermerr fit` wrote a
    model that "compensated" 100 % of its offset (RMS 12.5 -> 0 µm on the real run's E_ch4 set
    to 12.5). Now it is refused, one line naming the file and the probe, exit 2, nothing
    written; Python's fit_run raises the same."""
    from thermerr_rs.errors import ShapeError

    lines = example_run1.read_text().splitlines()
    col = lines[0].split(",").index("E_z")
    rows = [ln.split(",") for ln in lines[1:]]
    for r in rows:
        r[col] = "12.5"
    p = tmp_path / "dead.csv"
    p.write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")
    out = tmp_path / "m.json"
    assert main(["fit", str(p), "--axis", "E_z", "--out", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err == [f"thermerr: error: {p}: E_z reads one value (12.5) in every row "
                   f"({float(rows[-1][0]) - float(rows[0][0]):.0f} s): the probe does not move, nothing to model; "
                   "mend the probe"], err
    assert not out.exists()
    run = tr.read_run(p)
    with pytest.raises(ShapeError, match="E_z reads one value"):
        tr.MLR().fit_run(run, "E_z", run.temperatures)
    tr.MLR().fit_run(run, "E_x", run.temperatures)  # the other probe moves


def test_a_probe_that_jumps_is_said_before_it_is_fitted(example_run1, tmp_path, capsys):
    """A probe re-zeroed mid-run (the real run's E_ch3 40 µm lower from 30 h on): `thermerr fit`
    fitted across the step without a word (RMS 7.3 µm where the run's own fit is lower). Now it
    says so, one line naming the file, the probe and the first row, and fits as read (the user
    decides where the run is right); Python's fit_run warns the same. A run without a step
    says nothing."""
    from thermerr_rs.errors import SuspectReadingWarning

    lines = example_run1.read_text().splitlines()
    col = lines[0].split(",").index("E_z")
    rows = [ln.split(",") for ln in lines[1:]]
    k = len(rows) * 2 // 3
    for r in rows[k:]:
        r[col] = repr(float(r[col]) - 40.0)
    p = tmp_path / "rezero.csv"
    p.write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")
    out = tmp_path / "m.json"
    assert main(["fit", str(p), "--axis", "E_z", "--model", "mlr", "--no-fallbacks", "--quiet",
                 "--out", str(out)]) == 0
    warned = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert len(warned) == 1 and warned[0].startswith(f"thermerr: warning: {p}: E_z jumps by up to 40"), warned
    assert f"first at row {k + 1})" in warned[0] and "learns the step as drift" in warned[0]
    assert out.exists()
    run = tr.read_run(p)
    with pytest.warns(SuspectReadingWarning, match="E_z jumps"):
        tr.MLR().fit_run(run, "E_z", run.temperatures)
    assert main(["fit", str(example_run1), "--axis", "E_z", "--model", "mlr", "--no-fallbacks", "--quiet",
                 "--out", str(tmp_path / "m2.json")]) == 0
    assert "warning" not in capsys.readouterr().err


def test_a_temperature_spike_is_bridged_before_it_is_fitted(example_run1, tmp_path, capsys):
    """A thermocouple's glitch in an input: before, `thermerr fit` and ``fit_run`` fitted the
    spike as read without a word, and the guard learned its limits from it (on the real 46-h
    run's first half with T_t8 at 1372 °C for 11 rows, E_ch3 held out on the second half 12.54
    µm against 6.95 µm clean). Now an input temperature whose failing stretches all come back
    within 600 s is bridged by a straight line in time (the rule ``init`` uses, the core's
    ``Run::bridged``), said in one line, and the model is the one fitted on the bridged run
    (measured there: 6.97 µm); the array API ``fit(X, y)`` bridges nothing."""
    from thermerr_rs.errors import SuspectReadingWarning

    run = tr.read_run(example_run1)
    feats = run.temperatures
    j, k = run.names.index("T_s05"), len(run) // 2
    spiked = run._data.copy()
    spiked[k, j] = 1372.0
    parts = {"time_s": run.time_s, "names": run.names, "ignored": [], "dropped_rows": [], "interpolated": 0}
    spiky = tr.Run({**parts, "source": "spiky.csv", "data": spiked})
    with pytest.warns(SuspectReadingWarning,
                      match=rf"T_s05: 1 short spike \(1 row, first at row {k + 1}\).*bridged by a straight line for the fit") as w:
        m = tr.MLR().fit_run(spiky, "E_z", feats)
    assert w[0].filename == __file__  # the warning points at the caller's fit_run
    line = spiked.copy()
    line[k, j] = np.interp(run.time_s[k], run.time_s[[k - 1, k + 1]], spiked[[k - 1, k + 1], j])
    ref = tr.MLR().fit_run(tr.Run({**parts, "source": "line.csv", "data": line}), "E_z", feats)
    # the core's straight line is numpy's to the bit here (150-s steps, a midpoint)
    assert np.array_equal(m.predict_run(run), ref.predict_run(run))
    raw = tr.MLR().fit(spiky.matrix(feats), spiky["E_z"])
    assert np.abs(m.predict_run(run) - raw.predict(run.matrix(feats))).max() > 0.05  # measured 0.12 µm
    # the command line says it once, and the guard's limits are learned from the bridged run
    p = tmp_path / "spiky.csv"
    np.savetxt(p, np.column_stack([run.time_s, spiked]), delimiter=",", header=",".join(["time_s", *run.names]),
               comments="")
    out = tmp_path / "m.json"
    assert main(["fit", str(p), "--axis", "E_z", "--model", "mlr", "--no-fallbacks", "--quiet",
                 "--out", str(out)]) == 0
    warned = [ln for ln in capsys.readouterr().err.splitlines() if "warning" in ln]
    assert len(warned) == 1 and "T_s05: 1 short spike" in warned[0] and "for the fit" in warned[0], warned
    guard = json.loads(out.read_text())["guard"]
    limits = dict(zip(json.loads(out.read_text())["features"], guard["sensors"]))
    assert limits["T_s05"]["max"] < 100.0, limits["T_s05"]


def test_a_warning_is_one_line(example_run1, tmp_path):
    """A column the reader ignores is said on one line, as an error is, not with Python's file,
    line number and source line (seen on a logger's export with a comment column)."""
    lines = example_run1.read_text().splitlines()
    p = tmp_path / "with_comment.csv"
    p.write_text("\n".join([lines[0] + ",comment"] + [ln + ",ok" for ln in lines[1:]]) + "\n")
    r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", "fit", str(p), "--axis", "E_x",
                        "--out", str(tmp_path / "m.json"), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stderr.splitlines() == [
        f"thermerr: warning: {p}: ignoring columns without a T_/E_/U_ prefix: comment (a sensor among them "
        "is read when named so: --rename 'OLD=NEW', read_run(rename=))"], r.stderr


def test_console_script_runs(example_run1, tmp_path):
    r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", "--version"], capture_output=True, text=True)
    assert r.returncode == 0 and "thermerr_rs" in r.stdout
    r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", "fit", str(example_run1), "--axis", "E_x",
                        "--out", str(tmp_path / "m.json"), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    # --quiet drops the chatter and progress, keeps the results
    assert "fitted" not in r.stdout and "model written" not in r.stdout
    assert "training run" in r.stdout


@pytest.mark.parametrize("argv", [["fit"], ["evaluate"], ["nonsense"]])
def test_usage_errors(argv):
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2


def test_fit_svr_tuned_by_cso(tmp_path, capsys):
    from conftest import EXAMPLES

    out = tmp_path / "svr.json"
    sensors = "T_front_bearing,T_headstock,T_column,T_bed"
    argv = ["fit", str(EXAMPLES / "spindle_3000rpm.csv"), "--axis", "E_z", "--model", "svr", "--tune", "cso",
            "--pop", "8", "--iters", "10", "--sensors", sensors, "--out", str(out), "--json"]
    assert main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    model = tr.load_model(out)
    assert isinstance(model, tr.SVR) and model.kind == "svr"
    # the tuned parameters are the search's, and the same seed gives the same model
    assert main(argv[:-3] + ["--out", str(tmp_path / "again.json"), "--json"]) == 0
    capsys.readouterr()
    assert tr.load_model(tmp_path / "again.json").get_params() == model.get_params()
    assert report["train"]["rms"] < 1.0


@pytest.mark.parametrize("model", ["greybp", "gm1n", "bp", "hybrid"])
def test_fit_sequential_and_network_models(model, tmp_path, capsys):
    from conftest import EXAMPLES

    out = tmp_path / f"{model}.json"
    argv = ["fit", str(EXAMPLES / "lathe_run.csv"), "--axis", "E_x", "--model", model, "--inputs", "absolute",
            "--sensors", "T_coolant,T_headstock,T_x_nut,T_bed,T_ambient", "--out", str(out), "--json"]
    assert main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    m = tr.load_model(out)
    assert m.kind == model and np.isfinite(report["train"]["rms"])
    assert main(["evaluate", str(out), str(EXAMPLES / "lathe_run.csv"), "--json"]) == 0
    evaluated = json.loads(capsys.readouterr().out)
    # a model fed its own previous outputs is scored closed loop, and one step ahead too (the
    # measured error of the step before given): the same numbers as the Python API's
    if model == "bp":
        assert "train_one_step" not in report and "one_step" not in evaluated
        return
    run = tr.read_run(EXAMPLES / "lathe_run.csv")
    one = tr.scores(run["E_x"], m.predict_run(run, one_step=True)).as_dict()
    closed = tr.scores(run["E_x"], m.predict_run(run)).as_dict()
    assert report["train_one_step"]["rms"] == one["rms"] and report["train"]["rms"] == closed["rms"]
    assert evaluated["one_step"]["rms"] == one["rms"] and evaluated["rms"] == closed["rms"]
    assert one["rms"] != closed["rms"]


def test_a_model_worse_than_no_compensation_is_called_so(tmp_path, capsys):
    # a probe wired the other way round: the model, right on its own run, doubles the error
    from conftest import EXAMPLES

    out = tmp_path / "m.json"
    assert main(["fit", str(EXAMPLES / "lathe_run.csv"), "--axis", "E_x", "--no-guard", "--out", str(out),
                 "--quiet"]) == 0
    text = (EXAMPLES / "lathe_run.csv").read_text().splitlines()
    k = text[0].split(",").index("E_x")
    flipped = [text[0]] + [",".join(f"{-float(v)!r}" if j == k else v for j, v in enumerate(r.split(",")))
                           for r in text[1:]]
    (tmp_path / "flipped.csv").write_text("\n".join(flipped) + "\n")
    capsys.readouterr()
    assert main(["evaluate", str(out), str(tmp_path / "flipped.csv")]) == 0
    said = capsys.readouterr().out
    assert "note: the model leaves more error than no compensation on" in said
    assert "compensating with it would make the machine worse" in said
    assert main(["evaluate", str(out), str(EXAMPLES / "lathe_run.csv")]) == 0
    assert "no compensation on" not in capsys.readouterr().out


def test_a_sequence_model_says_how_it_was_scored_and_when_closed_loop_stands_still(tmp_path, capsys):
    """GM(1,N) alone, closed loop from a run's zero error, predicts that zero throughout
    (docs/methods.md): the command says so beside the figures, and gives the one-step ones."""
    from conftest import EXAMPLES

    out = tmp_path / "gm.json"
    assert main(["fit", str(EXAMPLES / "lathe_run.csv"), "--axis", "E_x", "--model", "gm1n", "--no-guard",
                 "--sensors", "T_coolant,T_headstock,T_x_nut", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "training run (closed loop: the model's own previous outputs fill its history" in text
    assert "training run, one step ahead: the measured error of the step before is given" in text
    assert "note: closed loop, the model predicts 0 µm on every sample of" in text
    run = tr.read_run(EXAMPLES / "lathe_run.csv")
    assert not np.any(tr.load_model(out).predict_run(run))


def test_examples_are_shipped_with_the_package(tmp_path):
    # a pip-installed user has no examples/ directory: the command copies the bundled files out
    r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", "examples", str(tmp_path / "ex")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "ex" / "vmc_run.csv").read_bytes() == tr.examples.path("vmc_run.csv").read_bytes()
    run = tr.read_run(tmp_path / "ex" / "hmc_run1.csv")
    assert len(run) > 100 and "E_z" in run.names


def test_the_command_line_and_a_diagnosis_start_without_scikit_learn(tmp_path):
    """Importing scikit-learn takes about a second; the package imports its estimators (which
    build on scikit-learn's base classes) on first use, so `thermerr --help`, `init` and
    `diagnose`, and `tr.diagnose` in Python, never import it."""
    code = (
        "import sys, thermerr_rs as tr\n"
        "from thermerr_rs.cli import main\n"
        "assert main(['examples', sys.argv[1]]) == 0\n"
        "assert main(['diagnose', sys.argv[1] + '/vmc_run.csv', '--machine', sys.argv[1] + '/vmc_nominal.toml',"
        " '--out', sys.argv[1] + '/d', '--quiet']) == 0\n"
        "assert 'sklearn' not in sys.modules, 'scikit-learn was imported'\n"
        "tr.MLR  # an estimator imports it\n"
        "assert 'sklearn' in sys.modules\n"
    )
    res = subprocess.run([sys.executable, "-c", code, str(tmp_path / "ex")], capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr

