"""The diagnosis must find an effect hidden in synthetic data, name its column where it has one,
gain on held-out data, and say "none" when nothing is hidden — on two machine topologies and
several seeds. Every case is a fresh machine, duty cycle and nominal-parameter perturbation."""

from __future__ import annotations

import json
import re
import sys

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.cli import main
from thermerr_rs.thermal import Machine, diagnose

SEEDS = (1, 2, 3)
TOPOLOGIES = ("vmc", "lathe")
# the bar: above 50 % held-out gain for lag, ambient coupling and speed growth
MIN_GAIN = {"thermal_lag": 50.0, "ambient_coupling": 50.0, "speed_growth": 50.0}


def run_case(topology, hidden, seed):
    c = syn.make_case(topology, hidden, seed)
    d = diagnose(tr.Run.from_frame(c.train, source="train"), Machine.from_toml(c.nominal_toml()),
                 tr.Run.from_frame(c.test, source="test"))
    return c, d


# Known misses, measured and reported in the issue note rather than hidden: here the hidden
# effect barely shows on the held-out run (baseline held-out RMS 0.35 µm, 2.2x the probe noise).
# strict: should it start passing, the test says so.
KNOWN_MISSES = {("vmc", "ambient_coupling", 2)}
CASES = [
    pytest.param(t, h, s, marks=pytest.mark.xfail(strict=True, reason="effect too weak on held-out data"))
    if (t, h, s) in KNOWN_MISSES
    else (t, h, s)
    for t in TOPOLOGIES
    for h in syn.HIDDEN
    for s in SEEDS
]


@pytest.mark.parametrize("topology, hidden, seed", CASES)
def test_hidden_effect_is_named(topology, hidden, seed):
    c, d = run_case(topology, hidden, seed)
    expect = {"periodic": "unexplained"}.get(hidden, hidden)
    assert d.verdict == expect, d.evidence
    if hidden in ("sensor_drift", "unmodeled_source"):
        assert d.column == c.column
    else:
        assert d.column is None
    if hidden in MIN_GAIN:
        assert d.gain_pct > MIN_GAIN[hidden], d.evidence
    if hidden == "sensor_drift":
        chosen = next(x for x in d.candidates if x["cause"] == "sensor_drift" and x["column"] == c.column)
        assert chosen["sensor_gain_pct"] > 25.0
    if hidden in ("none", "periodic"):
        assert d.gain_pct == 0.0
    if expect not in ("none", "unexplained"):
        assert d.report["extended"]["rmse_um"] < d.report["baseline"]["rmse_um"]


def test_without_holdout_uses_the_end_of_the_run_and_writes_the_report(tmp_path, capsys):
    c = syn.make_case("vmc", "speed_growth", 5)
    run = tmp_path / "run.csv"
    syn.write_run_csv(run, c.train)
    nominal = tmp_path / "nominal.toml"
    nominal.write_text(c.nominal_toml())
    out = tmp_path / "report"
    assert main(["diagnose", str(run), "--machine", str(nominal), "--out", str(out)]) == 0
    assert "verdict: speed_growth" in capsys.readouterr().out
    rep = json.loads((out / "report.json").read_text())
    for key in ("axis", "verdict", "column", "baseline", "extended", "gain_pct", "candidates"):
        assert key in rep
    assert rep["verdict"] == "speed_growth" and "last 30 %" in rep["holdout"]
    assert {"cause", "column", "score", "gain_pct", "parameters", "evidence"} - set(rep["candidates"][0]) == {"evidence"}
    html = (out / "report.html").read_text()
    # two time plots; the candidates' gains are bars in their table, the named one in green
    assert html.index("Verdict") < html.index("<img") and html.count("data:image/png;base64") == 2
    table = html[html.index("Candidates (round 1)"):]
    assert table.count("display:inline-block") == len(rep["candidates"]) and table.count("background:#2a7") == 1
    # both machines load back and simulate with the same code from the start the report gives
    # (the calibration's own, on the tail of the training run), giving the reported figures
    full = tr.read_run(run)
    split = round(len(full) * 0.7)
    for name, key in (("extended.toml", "extended"), ("calibrated.toml", "baseline")):
        sim = Machine.load(out / name).simulate(full, initial_k=rep[key]["initial_k"])
        r = full["E_z"][split:] - sim.drift["E_z"][split:]
        # same code, same numbers: only the TOML's decimal round trip separates them
        assert np.sqrt(np.mean(r**2)) == pytest.approx(rep[key]["rmse_um"], rel=1e-9)
    assert Machine.load(out / "extended.toml").to_toml().count("[[drift.inputs]]") == 1


def test_a_held_out_run_cut_from_the_same_log_is_joined_not_restarted(tmp_path, capsys):
    """A log cut in two (train.csv, then test.csv whose clock goes on): the held-out file's
    error is relative to the log's start, not its own. Before, it was diagnosed as a separate
    run started from its own first readings: on the real 46-h run cut at 70 % the baselines held
    out 7.5-26.5 µm instead of 2.4-11.9 µm and an ambient coupling and a speed growth were named
    that the whole run does not show. Now it is the tail of one run, as without --holdout."""
    c = syn.make_case("vmc", "speed_growth", 5)
    syn.write_run_csv(tmp_path / "run.csv", c.train)
    (tmp_path / "nominal.toml").write_text(c.nominal_toml())
    full = tr.read_run(tmp_path / "run.csv")
    cut = round(len(full) * 0.7)
    lines = (tmp_path / "run.csv").read_text().splitlines()
    (tmp_path / "train.csv").write_text("\n".join(lines[:cut + 1]) + "\n")
    (tmp_path / "test.csv").write_text("\n".join(lines[:1] + lines[cut + 1:]) + "\n")
    m = Machine.load(tmp_path / "nominal.toml")
    whole = diagnose(full, m)
    joined = diagnose(tr.read_run(tmp_path / "train.csv"), m, tr.read_run(tmp_path / "test.csv"))
    assert joined.verdict == whole.verdict == "speed_growth"
    assert joined.report["baseline"]["rmse_um"] == whole.report["baseline"]["rmse_um"]
    assert joined.report["extended"]["rmse_um"] == whole.report["extended"]["rmse_um"]
    assert "joined to the training run it continues" in joined.report["holdout"]
    assert main(["diagnose", str(tmp_path / "train.csv"), "--holdout", str(tmp_path / "test.csv"), "--machine",
                 str(tmp_path / "nominal.toml"), "--out", str(tmp_path / "d")]) == 0
    out = capsys.readouterr().out
    assert "test.csv continues" in out and "verdict: speed_growth" in out


def test_report_write_is_atomic(tmp_path, monkeypatch):
    c = syn.make_case("lathe", "none", 4, hours=(8.0, 4.0))
    d = diagnose(tr.Run.from_frame(c.train), Machine.from_toml(c.nominal_toml()), tr.Run.from_frame(c.test))
    import thermerr_rs.report as rep

    def boom(*a, **k):
        raise RuntimeError("matplotlib failed")

    monkeypatch.setattr(rep, "_plots", boom)
    with pytest.raises(RuntimeError):
        d.write(tmp_path / "out")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_deterministic():
    c = syn.make_case("vmc", "thermal_lag", 9, hours=(10.0, 5.0))
    args = (tr.Run.from_frame(c.train), Machine.from_toml(c.nominal_toml()), tr.Run.from_frame(c.test))
    a, b = diagnose(*args), diagnose(*args)
    assert a.report["candidates"] == b.report["candidates"]
    assert np.array_equal(a.series["extended"], b.series["extended"])


@pytest.fixture(scope="module")
def small():
    c = syn.make_case("lathe", "none", 4, hours=(8.0, 4.0))
    return diagnose(tr.Run.from_frame(c.train), Machine.from_toml(c.nominal_toml()), tr.Run.from_frame(c.test))


def test_a_cause_is_named_only_when_it_cuts_the_error():
    from conftest import EXAMPLES

    # a tester's machine file with capacities in kJ/K instead of J/K
    text = (EXAMPLES / "vmc_nominal.toml").read_text()
    kj = re.sub(r"(capacity_j_per_k = )([0-9.]+)", lambda m: f"{m[1]}{float(m[2]) / 1000}", text)
    d = diagnose(tr.read_run(EXAMPLES / "vmc_run.csv"), Machine.from_toml(kj, "kj.toml"))
    base, ext = d.report["baseline"]["rmse_um"], d.report["extended"]["rmse_um"]
    if d.verdict in ("none", "unexplained"):
        assert ext == base
    else:
        assert ext < base, d.evidence
    assert ("cuts" in d.evidence) == (ext < base), d.evidence


def test_report_leaves_the_matplotlib_backend_alone(small, tmp_path):
    import matplotlib
    import matplotlib.pyplot as plt

    before = matplotlib.get_backend()
    matplotlib.use("svg")
    try:
        small.write(tmp_path / "out")
        assert matplotlib.get_backend() == "svg" and plt.get_fignums() == []
    finally:
        matplotlib.use(before)
    assert (tmp_path / "out" / "report.html").read_text().count("data:image/png;base64") == 2


def test_report_without_matplotlib(small, tmp_path, monkeypatch):
    for name in ("matplotlib", "matplotlib.figure"):
        monkeypatch.setitem(sys.modules, name, None)
    out = tmp_path / "out"
    small.write(out)
    assert json.loads((out / "report.json").read_text()) == small.report
    assert (out / "calibrated.toml").read_text() == small.calibrated.to_toml()
    assert (out / "extended.toml").read_text() == small.extended.to_toml()
    html = (out / "report.html").read_text()
    assert "pip install thermerr_rs[report]" in html and "<img" not in html


def test_a_column_the_run_cannot_tell_apart_is_reported_beside_the_named_one():
    """A second sensor beside the unmodelled source's column (its reading plus 0.02 K of noise):
    the run cannot tell the two places apart, so the cause names one column and lists the other
    as explaining the held-out error as well — in report.json, the evidence and the verdict
    line. Without the twin the same case lists no alternative."""
    c = syn.make_case("vmc", "unmodeled_source", 1)
    machine = Machine.from_toml(c.nominal_toml())
    plain = diagnose(tr.Run.from_frame(c.train, source="train"), machine, tr.Run.from_frame(c.test, source="test"))
    assert plain.verdict == "unmodeled_source" and plain.column == c.column, plain.evidence
    assert plain.causes[0]["alternatives"] == []
    assert "does not single out" not in plain.evidence

    rng = np.random.default_rng(7)
    train, test = dict(c.train), dict(c.test)
    for frame in (train, test):
        col = np.asarray(frame[c.column])
        frame["T_twin"] = col + rng.normal(0.0, 0.02, col.size)
    d = diagnose(tr.Run.from_frame(train, source="train"), machine, tr.Run.from_frame(test, source="test"))
    assert d.verdict == "unmodeled_source", d.evidence
    first = d.causes[0]
    named = {first["column"]} | {a["column"] for a in first["alternatives"]}
    assert {c.column, "T_twin"} <= named, d.evidence
    for a in first["alternatives"]:
        assert a["rmse_um"] <= first["rmse_um"] * 1.05
    assert "does not single out" in d.evidence
    assert "or as well" in str(d).splitlines()[0]


def test_the_cli_warms_the_report_in_a_thread_and_needs_no_matplotlib(monkeypatch):
    """`thermerr diagnose` imports matplotlib and draws one small figure in a thread while the
    core diagnoses: it touches no pyplot state, and without matplotlib it does nothing."""
    import matplotlib.pyplot as plt

    from thermerr_rs import cli

    before = plt.get_fignums()
    cli._warm_report()
    assert plt.get_fignums() == before
    for name in ("matplotlib", "matplotlib.figure"):
        monkeypatch.setitem(sys.modules, name, None)
    assert cli._warm_report() is None


def test_suspect_readings_are_said_not_changed(tmp_path, capsys):
    """A sensor that fails in the run (a thermocouple open for one reading, then frozen for
    an hour) is pointed out with its rows, by the command line, in report.json and as a
    SuspectReadingWarning in Python; the clean run gets none."""
    from thermerr_rs.errors import SuspectReadingWarning

    c = syn.make_case("vmc", "speed_growth", 5)
    clean = dict(c.train)
    bad = {k: np.array(v, dtype=float).copy() for k, v in clean.items()}
    col = bad["T_column"]
    col[100] += 60.0  # open for one reading: rows 101 (in) and 102 (out), 1-based
    col[200:240] = col[200]  # frozen from row 201 for 39 steps
    step = float(np.median(np.diff(bad["time_s"])))
    frozen_s = 39 * step
    assert frozen_s >= 1800.0, "the frozen stretch must reach the stuck floor"
    run, nominal = tmp_path / "bad.csv", tmp_path / "nominal.toml"
    syn.write_run_csv(run, bad)
    nominal.write_text(c.nominal_toml())
    out = tmp_path / "report"
    assert main(["diagnose", str(run), "--machine", str(nominal), "--out", str(out)]) == 0
    printed = capsys.readouterr()
    lines = [ln for ln in printed.out.splitlines() if ln.startswith("warning: ")]
    assert len(lines) == 2, printed.out
    assert "T_column jumps by up to 60.0" in lines[0] and "first at row 101" in lines[0]
    assert "T_column repeats one reading" in lines[1] and f"for {frozen_s:.0f} s from row 201" in lines[1]
    assert "SuspectReadingWarning" not in printed.err  # the CLI says it once, as a line
    rep = json.loads((out / "report.json").read_text())
    assert (out / "report.html").read_text().count("T_column jumps by up to 60.0") == 1
    assert [(s["column"], s["kind"], s["row"], s["count"]) for s in rep["suspect_readings"]] == [
        ("T_column", "jump", 101, 2), ("T_column", "repeat", 201, 1)]
    with pytest.warns(SuspectReadingWarning, match="T_column jumps"):
        d = diagnose(tr.read_run(run), Machine.from_toml(c.nominal_toml()), progress=False)
    assert len(d.report["suspect_readings"]) == 2 and str(d).count("\nwarning: ") == 2
    with pytest.warns(SuspectReadingWarning, match="T_column repeats"):
        _, s = Machine.identify(tr.read_run(run))
    assert sum(n.startswith("suspect reading: ") for n in s["notes"]) == 2
    assert [(x["column"], x["kind"]) for x in s["suspect_readings"]] == [("T_column", "jump"), ("T_column", "repeat")]
    # the clean run: nothing suspect
    d = diagnose(tr.Run.from_frame(clean, source="clean"), Machine.from_toml(c.nominal_toml()), progress=False)
    assert d.report["suspect_readings"] == [] and "warning:" not in str(d)


def test_a_failing_column_is_not_tried_as_a_heat_source():
    """A spare thermocouple that opens in the training rows (-200 °C from then on) is said as a
    suspect reading and not tried as an unmodelled source (its fault would be fitted as heat and
    take the place of a real column among the few tried): the diagnosis is the one of the run
    without it, to the bit. On the real 46-h run with a spare column set to -200 from row 3000
    (a failure made for the check), that column took a place among the four columns tried and
    the unmodelled source from `T_t5` on `E_ch4` went unnamed."""
    from thermerr_rs.errors import SuspectReadingWarning

    c = syn.make_case("vmc", "unmodeled_source", 1, hours=(8.0, 4.0), dt=120.0)
    m = Machine.from_toml(c.nominal_toml())
    clean = diagnose(tr.Run.from_frame(c.train), m, tr.Run.from_frame(c.test), progress=False)
    dead = np.array(c.train["T_hydraulic"], dtype=float) + 1.0
    dead[len(dead) // 3:] = -200.0
    train = dict(c.train, T_dead=dead)
    test = dict(c.test, T_dead=np.full(len(c.test["time_s"]), -200.0))
    with pytest.warns(SuspectReadingWarning, match="T_dead jumps"):
        d = diagnose(tr.Run.from_frame(train), m, tr.Run.from_frame(test), progress=False)
    assert "T_dead" not in {x.get("column") for x in d.report["candidates"]}
    assert d.verdict == clean.verdict == "unmodeled_source" and d.column == clean.column == "T_hydraulic"
    assert d.report["candidates"] == clean.report["candidates"]
    assert np.array_equal(d.series["extended"], clean.series["extended"])


def test_a_second_reading_of_the_room_is_not_tried_as_a_heat_source():
    """A second thermometer in the room (a logger that also writes a ``T_ambient`` beside the
    sensor the network reads as the room, or two room sensors): a source from it is the room
    read twice, an ambient coupling under another name, and on the real 46-h run with a copy of
    its room column added it took one of the four places among the columns tried, so the source
    from ``T_t5`` on ``E_ch4`` went untried and the axis ended at 7.64 µm left against 3.24
    (found 2026-11-29). Its rise follows the room's (r >= 0.99), so it is not tried, and the
    diagnosis is the one of the run without it, to the bit."""
    c = syn.make_case("vmc", "ambient_coupling", 1, hours=(8.0, 4.0), dt=120.0)
    m = Machine.from_toml(c.nominal_toml())
    clean = diagnose(tr.Run.from_frame(c.train), m, tr.Run.from_frame(c.test), progress=False)
    rng = np.random.default_rng(0)

    def with_copy(cols):
        room = np.asarray(cols["T_ambient"], dtype=float)
        return dict(cols, T_room2=room + 0.3 + rng.normal(0.0, 0.02, room.shape))

    d = diagnose(tr.Run.from_frame(with_copy(c.train)), m, tr.Run.from_frame(with_copy(c.test)), progress=False)
    assert "T_room2" not in {x.get("column") for x in d.report["candidates"]}
    assert d.verdict == clean.verdict == "ambient_coupling"
    assert d.report["candidates"] == clean.report["candidates"]
    assert np.array_equal(d.series["extended"], clean.series["extended"])


@pytest.mark.parametrize("cause", ["none", "ambient_coupling", "unmodeled_source"])
def test_a_node_sensor_that_fails_is_not_fitted_on_its_failing_rows(cause):
    """The machine file's sensor of a node (``T_headstock``) opens halfway through the training
    rows and reads -200 °C from then on. Its readings from the jump on are not fitted
    (``guard::failing_rows``), so the diagnosis is that of the clean run: the same verdict and
    column, the baseline's held-out RMS within 30 % of the clean run's (the node's second half
    of training readings is lost; measured 0.98x-1.16x on these cases). Before, the network
    was fitted to the rail value: every case came out ``unexplained``, held out at 7.6-43 µm
    against 0.14-0.94 µm clean."""
    from thermerr_rs.errors import SuspectReadingWarning

    c = syn.make_case("vmc", cause, 1, hours=(8.0, 4.0), dt=120.0)
    m = Machine.from_toml(c.nominal_toml())
    assert any(n.get("sensor") == "T_headstock" for n in m.to_dict()["nodes"])
    clean = diagnose(tr.Run.from_frame(c.train), m, tr.Run.from_frame(c.test), progress=False)
    bad = {k: np.array(v, dtype=float) for k, v in c.train.items()}
    bad["T_headstock"][len(bad["time_s"]) // 2:] = -200.0
    with pytest.warns(SuspectReadingWarning, match="T_headstock jumps.*as a node's sensor it is not fitted"):
        d = diagnose(tr.Run.from_frame(bad), m, tr.Run.from_frame(c.test), progress=False)
    assert (d.verdict, d.column) == (clean.verdict, clean.column), str(d)
    assert d.verdict == cause
    ratio = d.report["baseline"]["rmse_um"] / clean.report["baseline"]["rmse_um"]
    assert ratio < 1.3, ratio


@pytest.mark.parametrize("cause", ["none", "unmodeled_source", "ambient_coupling"])
def test_a_room_sensor_that_fails_is_held_and_its_rows_not_fitted(cause):
    """The room's sensor (``T_ambient``, which drives the network) opens halfway through the
    training rows (-200 °C from then on). The model is driven by its last right reading there,
    and those rows are not fitted: no cause is named that is not hidden. With 4 h of training
    left, nothing hidden is still ``none`` and the unmodelled source is still named; the room
    coupling is not (``unexplained``: the room it needs is not measured). Before, every case
    named an unmodelled source from ``T_cabinet`` (the room's stand-in), held out at 7.8-10 µm
    on seed 1."""
    from thermerr_rs.errors import SuspectReadingWarning

    c = syn.make_case("vmc", cause, 1, hours=(8.0, 4.0), dt=120.0)
    m = Machine.from_toml(c.nominal_toml())
    assert m.to_dict()["ambient"] == "T_ambient"
    bad = {k: np.array(v, dtype=float) for k, v in c.train.items()}
    bad["T_ambient"][len(bad["time_s"]) // 2:] = -200.0
    with pytest.warns(SuspectReadingWarning, match="T_ambient jumps.*as the room or a boundary it is held"):
        d = diagnose(tr.Run.from_frame(bad), m, tr.Run.from_frame(c.test), progress=False)
    expect = {"none": "none", "unmodeled_source": "unmodeled_source", "ambient_coupling": "unexplained"}
    assert d.verdict == expect[cause], str(d)
    assert d.column in (None, "T_hydraulic"), str(d)


@pytest.mark.parametrize("column", ["T_headstock", "T_ambient"])
def test_a_sensor_dead_from_the_start_fails_until_it_comes_alive(column):
    """A node's sensor or the room's reads its rail value (-200 °C) for the first third of the
    training rows (2.6 h) and is connected from then on. Before, the jump that brought it to life
    was read as its failing: the rows after it (the right ones) were not fitted, the node started
    from -200 °C and the room was held there. Now the rows before the jump fail (``guard``'s
    ``dead_until``), the node starts from its first right reading and the room is held at it: the
    verdict is the clean run's and the baseline holds out within 30 % of it. On the real 46-h
    run with ``T_t8`` (a node's sensor) so for 12.5 h, E_ch1 and E_ch2 go from 48.7 and 34.3 µm
    held out, both "unmodeled_source", to the clean run's verdicts (speed growth 2.90 -> 2.30 µm,
    unexplained 2.26 µm); with the room's ``T_t4`` so, the diagnosis refused to run ("no
    held-out row can be scored") and now runs."""
    from thermerr_rs.errors import SuspectReadingWarning

    c = syn.make_case("vmc", "unmodeled_source", 1, hours=(8.0, 4.0), dt=120.0)
    m = Machine.from_toml(c.nominal_toml())
    clean = diagnose(tr.Run.from_frame(c.train), m, tr.Run.from_frame(c.test), progress=False)
    bad = {k: np.array(v, dtype=float) for k, v in c.train.items()}
    bad[column][: len(bad["time_s"]) // 3] = -200.0
    with pytest.warns(SuspectReadingWarning, match=f"{column} jumps"):
        d = diagnose(tr.Run.from_frame(bad), m, tr.Run.from_frame(c.test), progress=False)
    assert (d.verdict, d.column) == (clean.verdict, clean.column) == ("unmodeled_source", "T_hydraulic"), str(d)
    ratio = d.report["baseline"]["rmse_um"] / clean.report["baseline"]["rmse_um"]
    assert ratio < 1.3, ratio


@pytest.mark.parametrize("cause", ["none", "ambient_coupling", "speed_growth"])
def test_a_probe_that_fails_is_neither_fitted_nor_scored(cause):
    """The probe drops out for three readings in the middle of the training run (-999 µm) and
    spikes once (9 999 µm) in the held-out run of 121 readings: those rows are neither fitted
    nor scored, so the diagnosis is the clean run's (the same verdict; the baseline's held-out
    RMS within 20 % of the clean run's: the fit lost three rows and the thinning picks other
    rows, measured 1.01x-1.06x). Before, each case came out ``unexplained`` with a held-out RMS
    of about 900 µm: the spike alone, over 121 rows."""
    from thermerr_rs.errors import SuspectReadingWarning

    c = syn.make_case("vmc", cause, 1, hours=(8.0, 4.0), dt=120.0)
    m = Machine.from_toml(c.nominal_toml())
    clean = diagnose(tr.Run.from_frame(c.train), m, tr.Run.from_frame(c.test), progress=False)
    train = {k: np.array(v, dtype=float) for k, v in c.train.items()}
    test = {k: np.array(v, dtype=float) for k, v in c.test.items()}
    n = len(train["E_z"])
    train["E_z"][n // 2:n // 2 + 3] = -999.0
    test["E_z"][len(test["E_z"]) // 2] = 9999.0
    with pytest.warns(SuspectReadingWarning, match="E_z jumps.*neither fitted nor scored"):
        d = diagnose(tr.Run.from_frame(train), m, tr.Run.from_frame(test), progress=False)
    assert [(s["column"], s["kind"], s["count"]) for s in d.report["suspect_readings"]] == [
        ("E_z", "jump", 2), ("E_z", "jump", 2)]  # the training run's, then the held-out run's
    assert d.verdict == clean.verdict == cause, str(d)
    ratio = d.report["baseline"]["rmse_um"] / clean.report["baseline"]["rmse_um"]
    assert ratio < 1.2, ratio


def test_a_probe_that_fails_in_the_held_out_rows_is_scored_where_it_reads(tmp_path, capsys):
    """The probe unplugged (reading -999 µm) in the held-out part of the run: the held-out figures are
    over the rows before, and the evidence says over how many. Unplugged before the held-out
    part starts, there is nothing to score: one line naming the file, the axis and the row,
    exit 2, nothing written."""
    c = syn.make_case("vmc", "none", 2, hours=(8.0, 4.0), dt=120.0)
    nominal = tmp_path / "nominal.toml"
    nominal.write_text(c.nominal_toml())
    train = {k: np.array(v, dtype=float) for k, v in c.train.items()}
    n = len(train["time_s"])
    split = round(n * 0.7)  # the default held-out fraction: the last 30 %
    for at, name in ((split + 20, "late.csv"), (split - 20, "early.csv")):
        run = dict(train, E_z=train["E_z"].copy())
        run["E_z"][at:] = -999.0
        syn.write_run_csv(tmp_path / name, run)
    out = tmp_path / "late"
    assert main(["diagnose", str(tmp_path / "late.csv"), "--machine", str(nominal), "--out", str(out)]) == 0
    rep = json.loads((out / "report.json").read_text())
    assert f"are over 20 of its {n - split} held-out rows: on the rest the probe, the room or a boundary fails" in rep["evidence"]
    capsys.readouterr()
    out = tmp_path / "early"
    assert main(["diagnose", str(tmp_path / "early.csv"), "--machine", str(nominal), "--out", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("thermerr: error")]
    assert len(err) == 1 and f"early.csv: 0 of the {n - split} held-out rows of E_z" in err[0], err
    assert f"fails over rows {split - 20 + 1}-{n}" in err[0], err
    assert not out.exists()


def test_a_probe_that_never_moves_is_refused(tmp_path, capsys):
    """A probe dead for the whole run (one reading in every row): before, the diagnosis said
    ``none`` (0.00 µm held out, nothing to explain), a verdict on nothing. Now it stops with one
    line naming the file and the axis, exit 2, nothing written; the other axes are diagnosed
    with ``--axis``."""
    c = syn.make_case("vmc", "none", 2, hours=(8.0, 4.0), dt=120.0)
    nominal = tmp_path / "nominal.toml"
    nominal.write_text(c.nominal_toml())
    run = {k: np.array(v, dtype=float) for k, v in c.train.items()}
    run["E_z"][:] = 0.0
    syn.write_run_csv(tmp_path / "dead.csv", run)
    out = tmp_path / "d"
    assert main(["diagnose", str(tmp_path / "dead.csv"), "--machine", str(nominal), "--out", str(out)]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("thermerr: error")]
    assert len(err) == 1 and "dead.csv: E_z reads one value (0) in every row" in err[0], err
    assert "the probe does not move, nothing to diagnose" in err[0], err
    assert not out.exists()
    from thermerr_rs.errors import ShapeError, ThermerrError

    with pytest.raises(ShapeError, match="E_z reads one value") as e:
        diagnose(tr.Run.from_frame(run), Machine.from_toml(c.nominal_toml()), progress=False)
    assert isinstance(e.value, ThermerrError)


def test_a_probe_that_does_not_start_at_zero_is_taken_from_its_first_reading():
    """A capacitive probe logged as its raw gap (800 µm at the start, moving 20-30 µm): formats.md
    asks for the error from the run's start, and before, the model (which starts every drift
    at zero) was fitted to the offset: on the real 46-h run with 500-900 µm added to its probes,
    the baselines held out 17.6-308 µm. Now a probe whose first reading is further from zero
    than it moves over the whole run is taken from that reading (said as a suspect reading, kind
    ``offset``): the diagnosis is that of the run with each probe less its first reading, to the
    last bit of the figures. That reading carries the probe's noise into every row: on this
    case the clean probe starts at -0.19 µm, and the clean run names the room coupling where
    the run taken from its first reading (either way) is ``unexplained`` (docs)."""
    from thermerr_rs.errors import SuspectReadingWarning

    c = syn.make_case("vmc", "ambient_coupling", 1, hours=(8.0, 4.0), dt=120.0)
    m = Machine.from_toml(c.nominal_toml())
    zeroed = [dict(p, E_z=np.asarray(p["E_z"]) - p["E_z"][0]) for p in (c.train, c.test)]
    raw = [dict(p, E_z=np.asarray(p["E_z"]) + 800.0) for p in (c.train, c.test)]
    ref = diagnose(tr.Run.from_frame(zeroed[0]), m, tr.Run.from_frame(zeroed[1]), progress=False)
    with pytest.warns(SuspectReadingWarning, match=r"E_z reads (799|800)\.\d+ µm at its first right reading"):
        d = diagnose(tr.Run.from_frame(raw[0]), m, tr.Run.from_frame(raw[1]), progress=False)
    assert (d.verdict, d.column) == (ref.verdict, ref.column), str(d)
    kinds = [(x["column"], x["kind"]) for x in d.report["suspect_readings"]]
    assert ("E_z", "offset") in kinds, kinds
    # the same figures but for rounding: 800 + x - (800 + x0) differs from x - x0 by ~1e-13 µm,
    # and the iterative calibration stops elsewhere by that much more (measured 3e-6 relative)
    assert d.report["baseline"]["rmse_um"] == pytest.approx(ref.report["baseline"]["rmse_um"], rel=1e-4)
    assert d.report["extended"]["rmse_um"] == pytest.approx(ref.report["extended"]["rmse_um"], rel=1e-4)
    # the clean probe starts within its own movement of zero: used as read, nothing said
    clean = diagnose(tr.Run.from_frame(c.train), m, tr.Run.from_frame(c.test), progress=False)
    assert not any(x["kind"] == "offset" for x in clean.report["suspect_readings"])

def test_a_gap_in_the_log_is_said(tmp_path, capsys):
    """The logger off for an hour in the training rows: the command line, report.json and the
    Python warning say where (the row after the gap) and how long, as the time axis's suspect
    reading (kind ``gap``); the model holds the inputs across it, so a user learns why the
    residual may misbehave there. A run without a gap gets none (test above)."""
    from thermerr_rs.errors import SuspectReadingWarning

    c = syn.make_case("vmc", "none", 3, hours=(8.0, 4.0), dt=120.0)
    keep = np.ones(len(c.train["time_s"]), dtype=bool)
    keep[100:130] = False  # 30 readings of 120 s missing: a gap of 3720 s before row 101
    train = {k: np.asarray(v)[keep] for k, v in c.train.items()}
    run, nominal = tmp_path / "gap.csv", tmp_path / "nominal.toml"
    syn.write_run_csv(run, train)
    nominal.write_text(c.nominal_toml())
    out = tmp_path / "report"
    assert main(["diagnose", str(run), "--machine", str(nominal), "--out", str(out)]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("warning: ")]
    assert len(lines) == 1 and "the log has 1 gap of 1200 s or more" in lines[0], lines
    assert "the first before row 101, the longest 3720 s" in lines[0]
    rep = json.loads((out / "report.json").read_text())
    assert [(s["column"], s["kind"], s["row"], s["count"], s["size"]) for s in rep["suspect_readings"]] == [
        ("time_s", "gap", 101, 1, 3720.0)]
    with pytest.warns(SuspectReadingWarning, match="the log has 1 gap"):
        Machine.identify(tr.read_run(run))


TWIN_NODES = """
name = "twin"
ambient = "T_room"
[[nodes]]
name = "a"
capacity_j_per_k = 20000.0
ambient_w_per_k = 2.0
sensor = "T_a"
[[nodes]]
name = "b"
capacity_j_per_k = 24000.0
ambient_w_per_k = 2.0
sensor = "T_b"
[[links]]
between = ["a", "b"]
w_per_k = 1.0
[[sources]]
node = "a"
input = "U_spindle_rpm"
w = 60.0
ref = 6000.0
[[sources]]
node = "b"
input = "U_spindle_rpm"
w = 60.0
ref = 6000.0
[[drift]]
axis = "E_x"
um_per_k = { a = 1.0, b = 1.0 }
"""


def _twin_run(spurious_um_per_k: float) -> tr.Run:
    """24 h at 60 s of two nodes heated alike (their rises differ by at most 1.4 K), the error
    their sum plus, for the first 55 % of the run, ``spurious_um_per_k`` times their difference
    (then held where it was): an effect of neither node that follows their small difference while
    the map is fitted, and stops."""
    t = np.arange(0.0, 24 * 3600 + 1, 60.0)
    rng = np.random.default_rng(3)
    u = np.repeat(rng.choice([0, 2000, 4000, 6000], size=13), 120)[: len(t)].astype(float)
    cols = {"time_s": t, "U_spindle_rpm": u, "T_room": 20.0 + 0.3 * np.sin(2 * np.pi * t / 86400),
            "T_a": np.full_like(t, 20.0), "T_b": np.full_like(t, 20.0), "E_x": np.zeros_like(t)}
    sim = Machine.from_toml(TWIN_NODES).simulate(tr.Run.from_frame(cols))
    ra, rb = (sim.sensors[c] - sim.sensors[c][0] for c in ("T_a", "T_b"))
    cut = int(0.55 * len(t))
    diff = np.where(np.arange(len(t)) < cut, ra - rb, (ra - rb)[cut])
    cols["T_a"] = sim.sensors["T_a"] + rng.normal(0, 0.01, len(t))
    cols["T_b"] = sim.sensors["T_b"] + rng.normal(0, 0.01, len(t))
    cols["E_x"] = ra + rb + spurious_um_per_k * diff + rng.normal(0, 0.05, len(t))
    return tr.Run.from_frame(cols, source="twin.csv")


def test_a_baseline_drift_map_whose_terms_cancel_is_fitted_with_a_penalty():
    """Least squares reads the spurious effect from the two nodes' difference: node `a` at
    +19.2 µm/K (the file: 1), a term swinging 245 µm where the axis drifts 40. The penalty chosen
    forward in time (the map fitted to the first 70 % of the training rows, predicting the rest)
    is applied to the baseline and every candidate, and the report says so. Measured: the
    baseline held out 24.6 µm before (least squares), 17.9 µm with the penalty (lambda 3e-3)."""
    d = diagnose(_twin_run(20.0), Machine.from_toml(TWIN_NODES))
    pen = d.report["baseline_network"].get("drift_penalty")
    assert pen is not None, d.report["baseline_network"]
    assert 1e-6 < pen["lambda"] <= 1.0
    assert pen["node"] in ("a", "b")
    assert abs(pen["term_um"]) > 3 * pen["drift_um"]
    assert "ridge penalty" in d.evidence and f"`{pen['node']}`" in d.evidence
    assert d.report["baseline"]["rmse_um"] < 20.0
    # the same nodes and error without the spurious effect: no cancelling, no penalty, no word
    plain = diagnose(_twin_run(0.0), Machine.from_toml(TWIN_NODES))
    assert "drift_penalty" not in plain.report["baseline_network"]
    assert "ridge penalty" not in plain.evidence


@pytest.mark.parametrize("topology", TOPOLOGIES)
def test_a_fast_logged_run_with_nothing_hidden_says_none(topology):
    """A run logged like a real one (36 h of training, 12 h held out, every 15 s) is calibrated
    on every 4th row; a spindle step between two kept rows must still bring its heat when it
    happened. Before the thinned steps took the mean power of their rows, the nominal network
    left 0.6 µm held out on the VMC (4x the probe noise) with nothing hidden, and said
    ``unexplained``: the diagnosis then named 12 of 20 hidden causes at this shape with the
    nominal network, and 20 of 20 after (docs/machine-model.md, "Long runs sampled fast")."""
    c = syn.make_case(topology, "none", 1, hours=(36.0, 12.0), dt=15.0)
    d = diagnose(tr.Run.from_frame(c.train, source="train"), Machine.from_toml(c.nominal_toml()),
                 tr.Run.from_frame(c.test, source="test"), progress=False)
    assert d.verdict == "none", d.evidence
    assert d.remainder_um == 0.0
    # the held-out error is the probe's noise, not a misfit of the model
    assert d.report["baseline"]["rmse_um"] < 1.5 * d.report["noise_um"], d.evidence
