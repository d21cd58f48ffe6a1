"""A held-out piece of the training run's own log (the published protocol: train on the first 60 %
of a run, test on 60–80 %): its error is relative to the run's start, so it is predicted from
that start, as a gateway running since then would (``predict_run(run, after=train)``,
``Run.following``, ``thermerr fit --test`` on a file whose clock goes on from the training one's)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.cli import main
from thermerr_rs.errors import DataError

SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]


def _write(run: tr.Run, path, time_s=None):
    cols = ["time_s", *run.names]
    t = run.time_s if time_s is None else time_s
    rows = np.column_stack([t, run.matrix(run.names)])
    path.write_text(",".join(cols) + "\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in rows) + "\n")
    return path


def _cut(path, tmp_path):
    """The run at ``path``, the row where its test part starts (60 %), and the two parts as
    files, cut as a user would: train.csv, then test.csv with the clock as logged."""
    run = tr.read_run(path)
    k = len(run) * 6 // 10
    return run, k, _write(run.slice(0, k), tmp_path / "train.csv"), _write(run.slice(k), tmp_path / "test.csv")


def test_a_later_piece_continues_and_following_rejoins_it(example_run1):
    run = tr.read_run(example_run1)
    k = len(run) * 6 // 10
    head, tail = run.slice(0, k), run.slice(k)
    assert tail.continues(head) and not head.continues(tail)
    joined = tail.following(head)
    np.testing.assert_array_equal(joined.time_s, run.time_s)
    np.testing.assert_array_equal(joined.matrix(joined.names), run.matrix(run.names))
    # a run of its own (its clock from 0) and a piece after a gap of more than 10 steps do not
    assert not tr.read_run(example_run1).continues(head)
    assert run.slice(k + 9).continues(head)  # its first sample 10 steps after the head's last
    assert not run.slice(k + 10).continues(head)


def test_a_restarted_clock_is_moved_after_the_first_run(example_run1):
    run = tr.read_run(example_run1)
    k = len(run) // 2
    head, tail = run.slice(0, k), run.slice(k)
    tail.time_s = tail.time_s - tail.time_s[0]  # as an ISO time column reads: from its own first row
    assert not tail.continues(head)
    joined = tail.following(head)
    assert np.all(np.diff(joined.time_s) > 0)
    np.testing.assert_allclose(joined.time_s, run.time_s, rtol=0, atol=1e-6)


@pytest.mark.parametrize("make", [lambda: tr.MLR(alpha=1.0), lambda: tr.GreyBP(seed=0)], ids=["mlr", "greybp"])
def test_predict_after_equals_the_whole_run(make, example_run1):
    run = tr.read_run(example_run1)
    k = len(run) * 6 // 10
    head, tail = run.slice(0, k), run.slice(k)
    hist = [900.0, 3600.0] if isinstance(make(), tr.MLR) else None
    model = make().fit_run(head, "E_z", SENSORS, inputs="rise", history=hist)
    whole = model.predict_run(run)
    np.testing.assert_array_equal(model.predict_run(tail, after=head), whole[k:])
    # from the piece's own first sample the rises restart at 0: a different (wrong) prediction
    assert np.max(np.abs(model.predict_run(tail) - whole[k:])) > 0.1


def test_following_needs_a_common_column(example_run1):
    run = tr.read_run(example_run1)
    other = tr.Run.from_frame({"time_s": np.arange(5.0), "T_x": np.arange(5.0)})
    with pytest.raises(DataError, match="no column in common"):
        other.following(run)


def test_cli_test_piece_of_the_training_log(example_run1, tmp_path, capsys):
    run, k, train, test = _cut(example_run1, tmp_path)
    out = tmp_path / "m.json"
    args = ["fit", str(train), "--axis", "E_z", "--sensors", ",".join(SENSORS), "--history", "900,3600",
            "--out", str(out), "--no-guard", "--json"]
    assert main([*args, "--test", str(test)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["test_continues_training"] is True
    model = tr.load_model(out)
    expect = tr.scores(run["E_z"][k:], model.predict_run(run)[k:])
    assert report["test"]["rms"] == pytest.approx(expect.rms, rel=1e-12)
    # the same piece with its clock restarted is taken as a run of its own, unless told
    restarted = _write(run.slice(k), tmp_path / "test0.csv", time_s=run.time_s[k:] - run.time_s[k])
    assert main([*args, "--test", str(restarted)]) == 0
    own = json.loads(capsys.readouterr().out)
    assert own["test_continues_training"] is False and own["test"]["rms"] != pytest.approx(expect.rms)
    assert main([*args, "--test", str(restarted), "--test-continues"]) == 0
    told = json.loads(capsys.readouterr().out)
    assert told["test_continues_training"] is True
    assert told["test"]["rms"] == pytest.approx(expect.rms, rel=1e-9)


def test_cli_evaluate_after(example_run1, tmp_path, capsys):
    run, k, train, test = _cut(example_run1, tmp_path)
    out = tmp_path / "m.json"
    assert main(["fit", str(train), "--axis", "E_z", "--sensors", ",".join(SENSORS), "--history", "900",
                 "--out", str(out), "--no-guard", "--quiet"]) == 0
    capsys.readouterr()
    model = tr.load_model(out)
    expect = tr.scores(run["E_z"][k:], model.predict_run(run)[k:])
    assert main(["evaluate", str(out), str(test), "--after", str(train), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["rms"] == pytest.approx(expect.rms, rel=1e-12) and report["after"] == str(train)
    # without --after: the piece's own first row, and a note saying why that may be wrong
    assert main(["evaluate", str(out), str(test)]) == 0
    text = capsys.readouterr().out
    assert "pass --after" in text and f"{expect.rms:.3f}" not in text


def _edge(edge_bin, *args):
    import subprocess

    return subprocess.run([str(edge_bin), *map(str, args)], capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize("guard", [False, True], ids=["plain", "guarded"])
def test_edge_reference_equals_the_library(guard, example_run1, edge_bin, tmp_path):
    # a gateway started mid-run: thermerr-edge --reference TRAIN.csv takes the rises from the
    # training run's first row, as predict_run(run, reference=train) does; without history the
    # prediction is then the whole run's, as a gateway running since its start would give
    run = tr.read_run(example_run1)
    k = len(run) // 2
    head, tail = run.slice(0, k), run.slice(k)
    train, test = _write(head, tmp_path / "train.csv"), _write(tail, tmp_path / "test.csv")
    out = tmp_path / "m.json"
    fit = ["fit", str(train), "--axis", "E_z", "--sensors", ",".join(SENSORS), "--out", str(out), "--quiet"]
    assert main(fit + ([] if guard else ["--no-guard"])) == 0
    model = tr.load_model(out)
    want = model.predict_run(tail, reference=head)
    np.testing.assert_array_equal(want, model.predict_run(run)[k:])
    res = _edge(edge_bin, out, test, "--reference", train)
    assert res.returncode == 0, res.stderr
    got = np.array([float(ln.split(",")[1]) for ln in res.stdout.strip().splitlines()[1:]])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
    if guard:
        assert all(ln.endswith(",ok") for ln in res.stdout.strip().splitlines()[1:])
    # without it, the stream's own first row: the rises restart at 0
    plain = _edge(edge_bin, out, test)
    got0 = np.array([float(ln.split(",")[1]) for ln in plain.stdout.strip().splitlines()[1:]])
    np.testing.assert_allclose(got0, model.predict_run(tail), rtol=1e-9, atol=1e-9)
    assert np.max(np.abs(got0 - want)) > 0.1


def test_edge_reference_with_history_equals_the_library(example_run1, edge_bin, tmp_path):
    run = tr.read_run(example_run1)
    k = len(run) // 2
    head, tail = run.slice(0, k), run.slice(k)
    model = tr.MLR(alpha=1.0).fit_run(head, "E_z", SENSORS, inputs="rise", history=[900.0, 3600.0])
    out = model.save(tmp_path / "m.json")
    train, test = _write(head, tmp_path / "train.csv"), _write(tail, tmp_path / "test.csv")
    res = _edge(edge_bin, out, test, "--reference", train)
    assert res.returncode == 0, res.stderr
    got = np.array([float(ln.split(",")[1]) for ln in res.stdout.strip().splitlines()[1:]])
    np.testing.assert_allclose(got, model.predict_run(tail, reference=head), rtol=1e-9, atol=1e-9)


def test_edge_reference_bad_input_is_one_line_exit_2(example_run1, edge_bin, tmp_path):
    run = tr.read_run(example_run1)
    rise = tr.MLR().fit_run(run, "E_z", SENSORS, inputs="rise").save(tmp_path / "rise.json")
    absolute = tr.MLR().fit_run(run, "E_z", SENSORS, inputs="absolute").save(tmp_path / "abs.json")
    (tmp_path / "empty.csv").write_text("time_s," + ",".join(SENSORS) + "\n")
    (tmp_path / "other.csv").write_text("time_s,T_x\n0,20\n")
    for model, ref, why in [
        (absolute, example_run1, "absolute readings"),
        (rise, tmp_path / "empty.csv", "no data row after the header"),
        (rise, tmp_path / "other.csv", "no column T_s01"),
        (rise, tmp_path / "missing.csv", "missing.csv"),
    ]:
        res = _edge(edge_bin, model, example_run1, "--reference", ref)
        assert res.returncode == 2 and why in res.stderr and len(res.stderr.strip().splitlines()) == 1, res.stderr
        assert res.stdout == ""
    with pytest.raises(tr.ThermerrError, match="absolute readings"):
        tr.load_model(absolute).predict_run(run, reference=run)


def test_a_second_run_on_a_clock_that_ran_on_is_its_own_run(tmp_path, capsys):
    """A run whose clock goes on from the training run's last sample but whose machine does not
    (a cold start logged on a clock that ran on: most temperatures step at its first row) is not
    a continuation: joined, the diagnosis refused it as two runs in one; now it is held out as a
    run of its own, and the command line says why. A piece cut from the same log still
    continues."""
    from thermerr_rs import synthetic as syn

    c = syn.make_case("lathe", "none", 1, hours=(8.0, 4.0), dt=120.0)
    run = tr.Run.from_frame(c.train, source="a.csv")
    n, k = len(run), len(run) * 2 // 3
    head, tail = run.slice(0, k), run.slice(k, n)
    assert tail.continues(head) and tail.seam(head) is None
    t = np.asarray(c.train["time_s"])
    later = {key: (t[:60] + t[-1] + (t[1] - t[0])) if key == "time_s" else np.asarray(v)[:60]
             for key, v in c.test.items()}  # the test run's rows: the training run's would be refused
    second = tr.Run.from_frame(later, source="b.csv")
    assert not second.continues(run)
    why = second.seam(run)
    assert why is not None and f"row {n + 1}: " in why and "temperature columns step at once" in why
    (tmp_path / "m.toml").write_text(c.nominal_toml())
    _write(run, tmp_path / "a.csv")
    _write(second, tmp_path / "b.csv")
    assert main(["diagnose", str(tmp_path / "a.csv"), "--holdout", str(tmp_path / "b.csv"), "--machine",
                 str(tmp_path / "m.toml"), "--out", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert "b.csv's clock goes on from " in out and "a.csv's last sample, but the machine does not" in out, out
    assert "held out as a run of its own" in out and "continues" not in out
    assert json.loads((tmp_path / "d" / "report.json").read_text())["holdout"].startswith("the separate run ")


def test_a_scored_probe_that_starts_away_from_zero_is_warned_of(tmp_path, capsys):
    """A run scored by ``thermerr evaluate`` (or ``fit --test``) whose probe reads away from zero
    at its first reading (a probe not zeroed, or the second half of a log with its clock
    restarted: on the real 46-h run's second half E_ch1 starts at 3.87 µm of the 22.4 it moves)
    carries that reading against the model on every row: one warning line names the file, the
    probe and the reading (the rule of the diagnosis's suspect reading ``start``, in the core),
    and the run is scored as read, exit 0. A probe zeroed at the start, or the piece evaluated
    ``--after`` its log, is not warned of."""
    t = np.arange(0.0, 6 * 3600.0, 60.0)
    temp = 20.0 + 5.0 * (1.0 - np.exp(-t / 7200.0))
    cols = {"time_s": t, "T_a": temp, "E_z": 4.0 * (temp - 20.0)}
    train = _write(tr.Run.from_frame(cols, source="train"), tmp_path / "train.csv")
    warm = _write(tr.Run.from_frame({**cols, "E_z": cols["E_z"] + 5.0}, source="warm"), tmp_path / "warm.csv")
    model = tmp_path / "m.json"
    assert main(["fit", str(train), "--axis", "E_z", "--model", "mlr", "--no-guard", "--out", str(model),
                 "--quiet"]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(model), str(warm)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"thermerr: warning: {warm}: E_z reads 5.00 µm at its first right reading"), err
    assert main(["evaluate", str(model), str(train)]) == 0
    assert capsys.readouterr().err == ""
    assert main(["fit", str(train), "--axis", "E_z", "--model", "mlr", "--no-guard", "--test", str(warm), "--out",
                 str(tmp_path / "m2.json"), "--quiet"]) == 0
    assert "E_z reads 5.00 µm at its first right reading" in capsys.readouterr().err


def test_a_second_run_starting_warm_starts_its_unsensed_part_from_its_first_hour(tmp_path):
    """The same machine's second run of the day, its clock restarted and its probe zeroed: the
    machine starts warm, the bed no sensor reads too. Started at the room's first reading
    (formats.md), the true network holds that run out at 3.8 µm, 27x the probe noise, and the
    diagnosis calls it `unexplained`; with ``unsensed_start = "fit"`` in the machine file the
    bed's start is fitted to the sensed parts' first hour, and the same held-out RMS is within
    3x the noise (0.29 µm; 0.16 on the cold test run)."""
    from thermerr_rs import synthetic as syn

    c = syn.make_case("vmc", "none", 2, hours=(12.0, 4.0), dt=120.0)
    frame = {k: np.asarray(v) for k, v in c.train.items()}
    cut = int(np.searchsorted(frame["time_s"], 8 * 3600.0))
    first = {k: v[:cut] for k, v in frame.items()}
    second = {k: v[cut:] - (v[cut] if k in ("time_s", "E_z") else 0.0) for k, v in frame.items()}
    _write(tr.Run.from_frame(first), tmp_path / "a.csv")
    _write(tr.Run.from_frame(second), tmp_path / "b.csv")
    held = {}
    for start in ("room", "fit"):
        toml = c.nominal_toml()
        if start == "fit":
            toml = toml.replace('ambient = "T_ambient"\n', 'ambient = "T_ambient"\nunsensed_start = "fit"\n', 1)
            assert toml != c.nominal_toml()
        (tmp_path / f"{start}.toml").write_text(toml)
        assert main(["diagnose", str(tmp_path / "a.csv"), "--holdout", str(tmp_path / "b.csv"), "--machine",
                     str(tmp_path / f"{start}.toml"), "--out", str(tmp_path / start), "--quiet"]) == 0
        held[start] = json.loads((tmp_path / start / "report.json").read_text())
    noise = held["room"]["noise_um"]
    assert held["room"]["baseline"]["rmse_um"] > 10 * noise and held["room"]["verdict"] == "unexplained"
    assert held["fit"]["baseline"]["rmse_um"] < 3 * noise, held["fit"]["baseline"]["rmse_um"]
    # the bed's fitted start is in the calibrated file the diagnosis writes, as the file says
    assert 'unsensed_start = "fit"' in (tmp_path / "fit" / "calibrated.toml").read_text()
