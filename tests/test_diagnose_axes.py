"""Several error axes in one diagnosis, on a run shaped like a real measured one (issue 15 points 3
and 4): 46 h at 15 s (11 041 rows), sixteen temperatures with no column named as the room, the
spindle stepped every 4 h, the shop air swinging over the day, five probe channels with their own
drift maps. One channel hides an ambient coupling, one a speed growth, one nothing: each axis must
get its own verdict, and the written output must hold the summary and every axis's report.

Also: calibration thins a run sampled faster than once a minute (every k-th sample, k = ⌊60 s /
step⌋), so calibrating a 15-s run is exactly calibrating its every-4th-row subsample."""

from __future__ import annotations

import json

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.cli import main
from thermerr_rs.errors import ThermerrError
from thermerr_rs.thermal import Machine, diagnose_axes

HIDDEN = {"E_ch1": "speed_growth", "E_ch3": "ambient_coupling"}
AXES = ["E_ch1", "E_ch2", "E_ch3"]


@pytest.fixture(scope="module")
def shop():
    c = syn.make_shop_case(1, hidden=HIDDEN)
    return c, tr.Run.from_frame(c.train, source="shop.csv"), Machine.from_toml(c.nominal_toml(), "shop.toml")


@pytest.fixture(scope="module")
def diagnosed(shop):
    _, run, m = shop
    return diagnose_axes(run, m, axes=AXES)


def test_the_shop_run_is_shaped_like_a_real_one(shop):
    c, run, m = shop
    assert len(run) == 11041 and np.all(np.diff(run.time_s) == 15.0)
    temps = [n for n in run.names if n.startswith("T_")]
    assert len(temps) == 16 and "T_ambient" not in run.names
    assert [n for n in run.names if n.startswith("E_")] == list(syn.SHOP_CHANNELS)
    assert m.axes == list(syn.SHOP_CHANNELS)
    amb = run["T_t6"]
    assert 2.0 < amb.max() - amb.min() < 6.0  # the shop air's swing over two days


def test_each_axis_gets_its_own_verdict(diagnosed):
    assert diagnosed.axes == AXES
    got = {a: diagnosed[a].verdict for a in AXES}
    assert got == {"E_ch1": "speed_growth", "E_ch2": "none", "E_ch3": "ambient_coupling"}, {
        a: diagnosed[a].evidence for a in AXES}
    for a in ("E_ch1", "E_ch3"):
        d = diagnosed[a]
        assert d.report["axis"] == a
        # the hidden effect stands clear of the probe noise on held-out data, and the named
        # cause takes all of it: what is left is the noise (E_ch1 0.48 -> 0.31 µm, E_ch3
        # 2.01 -> 0.31 µm, noise 0.30 µm). (A gain above 50 % was asked before the tail was
        # scored from the calibration's own start: the old start's offset inflated E_ch1's
        # baseline to 0.97 µm, all of it "removed".)
        noise = d.report["noise_um"]
        assert d.report["baseline"]["rmse_um"] > 1.5 * noise, d.evidence
        assert d.report["extended"]["rmse_um"] < 1.1 * noise, d.evidence
        assert [c["axis"] for c in d.causes] == [a] * len(d.causes)
    assert diagnosed["E_ch2"].causes == [] and diagnosed["E_ch2"].remainder_um == 0.0


def test_each_axis_equals_its_own_diagnosis(shop, diagnosed):
    """The parallel run of several axes is the single-axis diagnosis of each, figure for figure."""
    from thermerr_rs.thermal import diagnose

    _, run, m = shop
    alone = diagnose(run, m, axis="E_ch2")
    a, b = dict(alone.report), dict(diagnosed["E_ch2"].report)
    assert set(a.pop("stage_s")) == set(b.pop("stage_s")) == {"baseline", "round_1", "later_rounds_and_check"}
    assert a == b  # everything but the wall times


def test_the_summary_and_every_axis_are_written(diagnosed, tmp_path):
    out = diagnosed.write(tmp_path / "diag")
    assert out.name == "report.html"
    names = sorted(p.name for p in (tmp_path / "diag").iterdir())
    assert names == sorted(["report.json", "report.html"] + [
        f"{a}.{f}" for a in AXES for f in ("report.json", "report.html", "calibrated.toml", "extended.toml")])
    summary = json.loads((tmp_path / "diag" / "report.json").read_text())
    assert summary["axes"] == AXES
    assert summary["verdicts"] == {a: diagnosed[a].verdict for a in AXES}
    assert {c["axis"] for c in summary["causes"]} == {"E_ch1", "E_ch3"}
    assert set(summary["remainder_um"]) == set(AXES)
    per = json.loads((tmp_path / "diag" / "E_ch3.report.json").read_text())
    assert per == diagnosed["E_ch3"].report
    Machine.load(tmp_path / "diag" / "E_ch3.extended.toml")


def test_cli_diagnoses_the_axes_given(shop, tmp_path, capsys):
    c, _, _ = shop
    run_csv, toml = tmp_path / "shop.csv", tmp_path / "shop.toml"
    syn.write_run_csv(run_csv, {k: v for k, v in c.train.items()})
    toml.write_text(c.nominal_toml())
    out = tmp_path / "out"
    assert main(["diagnose", str(run_csv), "--machine", str(toml), "--out", str(out),
                 "--axis", "E_ch2", "--axis", "E_ch3"]) == 0
    text = capsys.readouterr().out
    assert "== E_ch2 ==" in text and "== E_ch3 ==" in text
    assert json.loads((out / "report.json").read_text())["verdicts"]["E_ch3"] == "ambient_coupling"


def test_an_axis_the_machine_lacks_is_one_clear_error(shop, tmp_path, capsys):
    _, run, m = shop
    with pytest.raises(ThermerrError, match="no drift entry for `E_ch9`"):
        diagnose_axes(run, m, axes=["E_ch1", "E_ch9"])
    with pytest.raises(ThermerrError, match="`E_ch1` is given twice"):
        diagnose_axes(run, m, axes=["E_ch1", "E_ch1"])


def test_a_probe_with_nothing_to_diagnose_is_left_out_of_every_axis(tmp_path, capsys):
    """A factory's run where one probe is dead throughout (E_ch2 reads 0 in every row) and one
    is re-zeroed by 40 µm before the held-out part and never back (E_ch4): by default (every
    axis) both are left out, each with the one line that says why, and the other three are
    diagnosed exactly as when asked for by name; before, the whole diagnosis stopped with exit
    2 on the first of them. Named with --axis, such a probe is refused as before; with every
    probe dead there is nothing to diagnose (exit 2, nothing written)."""
    from thermerr_rs.errors import ShapeError, SuspectReadingWarning

    c = syn.make_shop_case(2, hours=12.0, dt=60.0, hidden={"E_ch3": "ambient_coupling"})
    cols = {k: np.array(v, dtype=float) for k, v in c.train.items()}
    n = len(cols["time_s"])
    cols["E_ch2"][:] = 0.0
    cols["E_ch4"][round(0.6 * n):] -= 40.0  # held out: the last 30 %
    run_csv, toml = tmp_path / "shop.csv", tmp_path / "shop.toml"
    syn.write_run_csv(run_csv, cols)
    toml.write_text(c.nominal_toml())
    out = tmp_path / "out"
    assert main(["diagnose", str(run_csv), "--machine", str(toml), "--out", str(out)]) == 0
    cap = capsys.readouterr()
    summary = json.loads((out / "report.json").read_text())
    kept = ["E_ch1", "E_ch3", "E_ch5"]
    assert summary["axes"] == kept
    assert list(summary["skipped"]) == ["E_ch2", "E_ch4"]
    assert "shop.csv: E_ch2 reads one value (0) in every row" in summary["skipped"]["E_ch2"]
    assert f"shop.csv: 0 of the {n - round(0.7 * n)} held-out rows of E_ch4" in summary["skipped"]["E_ch4"]
    assert f"fails over rows {round(0.6 * n) + 1}-{n}" in summary["skipped"]["E_ch4"]
    assert sorted(p.name for p in out.iterdir() if p.name.startswith("E_ch2") or p.name.startswith("E_ch4")) == []
    assert "E_ch2 not diagnosed" in (out / "report.html").read_text()
    lines = [ln for ln in cap.out.splitlines() if "not diagnosed" in ln]
    assert [ln.split(":")[0] for ln in lines] == ["warning", "warning"], cap.out
    assert summary["verdicts"]["E_ch3"] == "ambient_coupling", summary["verdicts"]
    # the axes that are diagnosed come out as when asked for by name, figure for figure
    named = diagnose_axes(tr.read_run(run_csv), Machine.load(toml), axes=kept, progress=False)
    for a in kept:
        got = json.loads((out / f"{a}.report.json").read_text())
        want = dict(named[a].report)
        got.pop("stage_s"), want.pop("stage_s")
        assert got == json.loads(json.dumps(want)), a
    # Python: the same, said as a suspect-reading warning per axis left out
    with pytest.warns(SuspectReadingWarning) as rec:
        res = diagnose_axes(tr.read_run(run_csv), Machine.load(toml), progress=False)
    assert [str(w.message).split(":")[0] for w in rec if "not diagnosed" in str(w.message)] == [
        "E_ch2 not diagnosed", "E_ch4 not diagnosed"]
    assert res.axes == kept and list(res.skipped) == ["E_ch2", "E_ch4"]
    assert "warning: E_ch2 not diagnosed" in str(res)
    # named: refused, one line, nothing written
    for axis, says in (("E_ch2", "E_ch2 reads one value (0)"), ("E_ch4", "held-out rows of E_ch4")):
        out = tmp_path / f"named_{axis}"
        assert main(["diagnose", str(run_csv), "--machine", str(toml), "--out", str(out),
                     "--axis", "E_ch1", "--axis", axis]) == 2
        err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("thermerr: error")]
        assert len(err) == 1 and says in err[0], err
        assert not out.exists()
    # every probe dead: nothing to diagnose
    for a in syn.SHOP_CHANNELS:
        cols[a][:] = 0.0
    syn.write_run_csv(tmp_path / "dead.csv", cols)
    out = tmp_path / "dead"
    with pytest.raises(ShapeError, match="no axis can be diagnosed: .*dead.csv: E_ch1 reads one value"):
        diagnose_axes(tr.read_run(tmp_path / "dead.csv"), Machine.load(toml), progress=False)
    assert main(["diagnose", str(tmp_path / "dead.csv"), "--machine", str(toml), "--out", str(out)]) == 2
    assert not out.exists()


def test_a_fast_run_is_calibrated_on_every_kth_sample(shop):
    """15-s samples: k = 4. Calibrating the run and calibrating its every-4th-row subsample (which
    is sampled at 60 s and so not thinned again) give the same machine, parameter for parameter."""
    c, run, m = shop
    short = {k: v[:2400] for k, v in c.train.items()}
    sub = {k: v[::4] for k, v in short.items()}
    a, info_a = m.calibrate(tr.Run.from_frame(short), "E_ch1", max_iter=15)
    b, info_b = m.calibrate(tr.Run.from_frame(sub), "E_ch1", max_iter=15)
    assert a.to_toml() == b.to_toml()
    assert info_a["n_data"] == info_b["n_data"] == 600 * 5  # 4 sensors and the axis, 600 rows


def test_the_progress_counts_every_calibration_of_every_axis():
    """The bar's counts (issue 15 point 4): calls while the diagnosis runs, never more done than
    planned, the plan growing as rounds start, the round reached; one count for all axes."""
    c = syn.make_shop_case(2, hours=6.0, hidden={"E_ch1": "speed_growth"})
    run = tr.Run.from_frame(c.train, source="shop")
    seen = []
    m = Machine.from_toml(c.nominal_toml())
    d = m._inner.diagnose_axes(*tr.thermal._run_args(run), None, axes=["E_ch1", "E_ch2"],
                               progress=lambda *a: seen.append(a))
    assert len(d) == 2 and seen
    assert all(done <= planned for done, planned, _ in seen)
    assert [s[1] for s in seen] == sorted(s[1] for s in seen)  # the plan only grows
    assert [s[0] for s in seen] == sorted(s[0] for s in seen)
    assert seen[-1][1] >= 2 * 10  # two baselines and round 1's candidates of two axes at least
    assert all(stage >= 1 for _, planned, stage in seen if planned)  # round 1 starts with the plan


def test_a_progress_callback_that_interrupts_stops_the_diagnosis():
    c = syn.make_shop_case(2, hours=6.0, hidden={})
    run = tr.Run.from_frame(c.train, source="shop")

    def stop(done, planned, stage):
        raise KeyboardInterrupt

    m = Machine.from_toml(c.nominal_toml())
    with pytest.raises(KeyboardInterrupt):
        m._inner.diagnose(*tr.thermal._run_args(run), None, progress=stop)
    # the interrupt is spent: the next call runs to its end
    assert tr.thermal.diagnose(run, m, axis="E_ch2", progress=False).verdict


def test_the_bar_is_drawn_when_asked(capsys):
    c = syn.make_shop_case(2, hours=6.0, hidden={})
    run = tr.Run.from_frame(c.train, source="shop")
    tr.thermal.diagnose(run, Machine.from_toml(c.nominal_toml()), axis="E_ch2", progress=True)
    err = capsys.readouterr().err
    assert "diagnosis, round 1" in err and "fit" in err
    tr.thermal.diagnose(run, Machine.from_toml(c.nominal_toml()), axis="E_ch2", progress=False)
    assert capsys.readouterr().err == ""
