"""The baseline's network rule (`network=` / `thermerr diagnose --network`): recalibrated on the
axis, kept as the machine file gives it, the better of the two held out, one network shared by
every axis (calibrated on the temperatures alone), or `auto` (the default): recalibrated, but an
identified network is kept when its recalibration is not unique.

Why the rule exists: on a real 46-h run, recalibrating an identified network on one axis fitted
the training rows better while the held-out error grew (docs/machine-model.md, "A real measured
run"). These tests check the rule does what it says on a synthetic case: a kept network is the
machine's own, `best` reports both baselines and keeps the one with the smaller held-out
residual, `auto` recalibrates a written network and keeps an identified one only when a second
start of its recalibration ends elsewhere, and a wrong rule is one clear error."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.cli import main
from thermerr_rs.errors import ThermerrError
from thermerr_rs.thermal import Machine, diagnose


def _thermal(m: Machine) -> list[float]:
    d = m.to_dict()
    return ([n["capacity_j_per_k"] for n in d["nodes"]] + [n["ambient_w_per_k"] for n in d["nodes"]]
            + [lk["w_per_k"] for lk in d["links"]] + [s["w"] for s in d["sources"]])


@pytest.fixture(scope="module")
def case():
    c = syn.make_case("vmc", "sensor_drift", 2, hours=(8.0, 4.0), dt=120.0)
    return (tr.Run.from_frame(c.train, source="train.csv"), Machine.from_toml(c.nominal_toml()),
            tr.Run.from_frame(c.test, source="test.csv"), c)


def _files(case, tmp_path):
    _, m, _, c = case
    run_csv, toml = tmp_path / "run.csv", tmp_path / "m.toml"
    syn.write_run_csv(run_csv, c.train)
    toml.write_text(m.to_toml())
    return run_csv, toml


def test_keep_leaves_the_network_as_given(case):
    train, m, test, _ = case
    d = diagnose(train, m, test, network="keep", progress=False)
    assert d.report["baseline_network"] == {"rule": "keep", "network": "kept"}
    # the calibrated machine's capacities, conductances and sources are the file's (the TOML
    # round trip writes them with their digits)
    assert _thermal(d.calibrated) == pytest.approx(_thermal(m), rel=1e-9)
    assert "keeps the machine's network as given" in d.evidence


def test_auto_is_the_default_and_recalibrates_a_written_network(case):
    train, m, test, _ = case
    d = diagnose(train, m, test, progress=False)
    bn = d.report["baseline_network"]
    assert {k: bn[k] for k in ("rule", "network")} == {"rule": "auto", "network": "recalibrated"}
    assert _thermal(d.calibrated) != pytest.approx(_thermal(m), rel=1e-3)
    # on a network written by a person, auto is recalibrate, figure for figure
    r = diagnose(train, m, test, network="recalibrate", progress=False)
    assert (r.verdict, r.report["baseline"], r.report["extended"]) == (d.verdict, d.report["baseline"], d.report["extended"])


def _identified_case(topology, hidden, seed, dt=120.0):
    c = syn.make_case(topology, hidden, seed, hours=(8.0, 4.0), dt=dt)
    train, test = tr.Run.from_frame(c.train, source="train.csv"), tr.Run.from_frame(c.test, source="test.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ident, _ = Machine.identify(train)
    return train, ident, test


def test_auto_keeps_an_identified_network_whose_recalibration_is_not_unique():
    """The identified VMC, a sensor drift hidden (seed 1), 8 h at 60 s: from the second start the
    recalibration fits the training rows as well (SSR 1.03x, within the rule's 5 % tie,
    ``TRAINING_TIE``) and holds out 0.88 µm against 1.44 µm (measured 2026-11-28, after
    identification added the unsensed node behind the slowest node; before, the rate sweep's
    sensor drift of seed 1 at 120 s was such a case, and before that the lathe's lag of seed 2:
    both now recalibrate to one solution, as every case of the 8-h sweep at 120 s, seeds 1-4,
    does). `auto` keeps the identified network, says why, and its baseline and verdict are the
    ones `keep` gives."""
    train, ident, test = _identified_case("vmc", "sensor_drift", 1, dt=60.0)
    d = diagnose(train, ident, test, progress=False)
    bn = d.report["baseline_network"]
    assert (bn["rule"], bn["network"], bn["second_start"]["unique"]) == ("auto", "kept", False)
    assert bn["second_start"]["training_ssr_ratio"] <= 1.05  # TRAINING_TIE: a tie
    assert "so the baseline keeps the identified network (rule `auto`" in d.evidence
    assert not bn["second_start"]["taken"]  # within the tie: the file's start is the recalibration
    assert bn["second_start"]["first_rmse_um"] == bn["recalibrated_rmse_um"]
    assert f"holds out {bn['second_start']['rmse_um']:.2f} µm on {d.axis} against {bn['recalibrated_rmse_um']:.2f} µm" in d.evidence
    kept = diagnose(train, ident, test, network="keep", progress=False)
    assert d.report["baseline"] == kept.report["baseline"]
    assert d.verdict == kept.verdict
    assert d.baseline_unique


def test_auto_recalibrates_an_identified_network_whose_recalibration_is_unique():
    """The identified VMC of the rate sweep, a lag hidden (seed 1): the second start ends where
    the first does (or fits worse), so `auto` recalibrates, figure for figure as `recalibrate`."""
    train, ident, test = _identified_case("vmc", "thermal_lag", 1)
    d = diagnose(train, ident, test, progress=False)
    bn = d.report["baseline_network"]
    assert (bn["rule"], bn["network"], bn["second_start"]["unique"]) == ("auto", "recalibrated", True)
    r = diagnose(train, ident, test, network="recalibrate", progress=False)
    assert (r.verdict, r.report["baseline"], r.report["extended"]) == (d.verdict, d.report["baseline"], d.report["extended"])


def _second_start_rule(d) -> bool:
    """`unique` as the docs define it, from the report's own figures."""
    ss = d.report["baseline_network"]["second_start"]
    first = ss["first_rmse_um"]
    moved = abs(ss["rmse_um"] - first) > max(0.1 * first, d.report["noise_um"])
    return ss["converged"] and (ss["training_ssr_ratio"] > 1.05 or not moved)


def _taken_rule(d) -> bool:
    """`taken` as the docs define it: both starts settled and the second fits the training rows
    better by more than the 5 % tie."""
    ss = d.report["baseline_network"]["second_start"]
    return ss["converged"] and ss["training_ssr_ratio"] * 1.05 < 1.0


def test_a_recalibrated_baseline_is_calibrated_again_from_a_second_start(case):
    """The recalibrated baseline is fitted a second time, every network parameter 25 % off the
    file's values (same bounds and priors), and the report says whether it ends elsewhere. Here
    the second start ends at a worse training fit (SSR 1.9x): one solution, nothing said. A kept
    network has one solution and no second start."""
    train, m, test, _ = case
    d = diagnose(train, m, test, progress=False)
    ss = d.report["baseline_network"]["second_start"]
    assert set(ss) == {"rmse_um", "first_rmse_um", "training_ssr_ratio", "converged", "unique", "taken"}
    assert ss["unique"] and _second_start_rule(d) and ss["training_ssr_ratio"] > 1.05
    assert not ss["taken"] and not _taken_rule(d)
    assert ss["first_rmse_um"] == d.report["baseline"]["rmse_um"]
    assert "not unique on this run" not in d.evidence and "poorer minimum" not in d.evidence
    kept = diagnose(train, m, test, network="keep", progress=False)
    assert "second_start" not in kept.report["baseline_network"]


def test_a_second_start_that_fits_the_training_rows_better_is_the_baseline_and_said():
    """``make_case("vmc", "sensor_drift", 4)`` (20 h + 12 h at 60 s): a drifting sensor the
    baseline cannot model. From the file's values the calibration stops in a poorer minimum; from
    the second start it fits the training rows far better (SSR 0.31x) and holds out 6.92 µm
    against 3.81 µm (measured 2026-11-28). Both are minima of one objective, so the better one
    is the baseline (since 2026-11-28; before, the file's start was, and the check only
    reported); the evidence gives both figures and still says the network is not pinned down,
    and the drift is named on its column."""
    c = syn.make_case("vmc", "sensor_drift", 4)
    d = diagnose(tr.Run.from_frame(c.train, source="train.csv"), Machine.from_toml(c.nominal_toml()),
                 tr.Run.from_frame(c.test, source="test.csv"), progress=False)
    ss = d.report["baseline_network"]["second_start"]
    assert not ss["unique"] and not _second_start_rule(d)
    assert ss["taken"] and _taken_rule(d)
    assert ss["rmse_um"] == d.report["baseline"]["rmse_um"] != ss["first_rmse_um"]
    assert (f"fits the training rows better (SSR {ss['training_ssr_ratio']:.2f}x), so that calibration is "
            f"the baseline ({ss['rmse_um']:.2f} µm held out on {d.axis}; {ss['first_rmse_um']:.2f} µm "
            "from the file's values)") in d.evidence
    assert "the training rows do not pin the network down" in d.evidence
    assert (d.verdict, d.column) == ("sensor_drift", c.column)


def test_best_keeps_the_baseline_with_the_smaller_held_out_residual(case):
    train, m, test, _ = case
    kept = diagnose(train, m, test, network="keep", progress=False)
    recal = diagnose(train, m, test, network="recalibrate", progress=False)
    best = diagnose(train, m, test, network="best", progress=False)
    bn = best.report["baseline_network"]
    assert bn["rule"] == "best"
    assert bn["kept_rmse_um"] == pytest.approx(kept.report["baseline"]["rmse_um"], rel=1e-9)
    assert bn["recalibrated_rmse_um"] == pytest.approx(recal.report["baseline"]["rmse_um"], rel=1e-9)
    # the choice is by the joint held-out residual (error and temperatures, noise-normalised),
    # the score every candidate is judged by; the baseline is then exactly the chosen one's
    assert (bn["network"] == "kept") == (bn["kept_joint_ssr"] < bn["recalibrated_joint_ssr"])
    chosen = kept if bn["network"] == "kept" else recal
    assert best.report["baseline"]["rmse_um"] == pytest.approx(chosen.report["baseline"]["rmse_um"], rel=1e-9)
    assert best.verdict == chosen.verdict


def test_a_wrong_rule_is_one_clear_error(case, tmp_path, capsys):
    train, m, test, _ = case
    with pytest.raises(ThermerrError, match="network.*`fast` is not one of auto, recalibrate, keep, best, shared"):
        diagnose(train, m, test, network="fast", progress=False)
    run_csv, toml = _files(case, tmp_path)
    with pytest.raises(SystemExit) as e:
        main(["diagnose", str(run_csv), "--machine", str(toml), "--out", str(tmp_path / "d"), "--network", "fast"])
    assert e.value.code == 2
    assert "--network" in capsys.readouterr().err
    assert not (tmp_path / "d").exists()


def test_the_cli_writes_the_rule_into_the_report(case, tmp_path):
    run_csv, toml = _files(case, tmp_path)
    assert main(["diagnose", str(run_csv), "--machine", str(toml), "--out", str(tmp_path / "d"),
                 "--network", "keep", "--quiet"]) == 0
    rep = json.loads((tmp_path / "d" / "report.json").read_text())
    assert rep["baseline_network"]["network"] == "kept"


def test_the_summary_of_several_axes_names_each_baseline_network(case, tmp_path):
    from thermerr_rs.thermal import diagnose_axes

    train, m, test, _ = case
    multi = diagnose_axes(train, m, test, network="best", progress=False)
    chosen = {a: multi[a].report["baseline_network"]["network"] for a in multi.axes}
    assert set(chosen.values()) <= {"kept", "recalibrated"}
    assert multi.report["baseline_network"] == chosen
    page = (multi.write(tmp_path / "d").parent / "report.html").read_text()
    assert "<th>baseline network</th>" in page
    assert all(f"<td>{v}</td>" in page for v in chosen.values())


def test_the_summary_names_the_axes_whose_baseline_is_not_unique():
    """The summary of several axes (here the VMC case whose recalibrated baseline has two
    solutions): ``baseline_unique`` and the printed note follow each axis's report."""
    from thermerr_rs.thermal import diagnose_axes

    c = syn.make_case("vmc", "sensor_drift", 4)
    train = tr.Run.from_frame(c.train, source="train.csv")
    multi = diagnose_axes(train, Machine.from_toml(c.nominal_toml()), tr.Run.from_frame(c.test, source="test.csv"),
                          progress=False)
    want = {a: multi[a].report["baseline_network"]["second_start"]["unique"] for a in multi.axes}
    assert multi.report["baseline_unique"] == want
    assert want == {"E_z": False}
    assert "note: the recalibrated baseline is not unique on E_z" in str(multi)


@pytest.fixture(scope="module")
def shop():
    """Five probes on one machine, a room coupling hidden on E_ch3 (12 h at 60 s)."""
    c = syn.make_shop_case(2, hours=12.0, dt=60.0, hidden={"E_ch3": "ambient_coupling"})
    return c, Machine.from_toml(c.nominal_toml())


def test_shared_is_one_network_for_every_axis(shop):
    from thermerr_rs.thermal import diagnose_axes

    c, m = shop
    run = tr.Run.from_frame(c.train, source="shop.csv")
    multi = diagnose_axes(run, m, network="shared", progress=False)
    nets = {a: _thermal(multi[a].calibrated) for a in multi.axes}
    first = nets[multi.axes[0]]
    assert all(v == pytest.approx(first, rel=1e-12) for v in nets.values()), nets
    # calibrated, not the file's
    assert first != pytest.approx(_thermal(m), rel=1e-3)
    assert all(multi[a].report["baseline_network"] == {"rule": "shared", "network": "shared"} for a in multi.axes)
    assert "one network, calibrated once on the temperatures alone" in multi[multi.axes[0]].evidence
    # a single axis's diagnosis under `shared` has the same network
    one = diagnose(run, m, axis="E_ch1", network="shared", progress=False)
    assert _thermal(one.calibrated) == pytest.approx(first, rel=1e-12)


def test_the_shared_network_does_not_bend_to_an_axis(shop):
    """Calibrated on the temperatures alone: a probe that reads something else entirely (here a
    ramp of 50 µm added to E_ch3) leaves the network every axis keeps as it was; the network
    recalibrated on that axis moves."""
    c, m = shop
    bent = dict(c.train)
    bent["E_ch3"] = np.asarray(bent["E_ch3"]) + np.linspace(0.0, 50.0, len(bent["E_ch3"]))
    runs = [tr.Run.from_frame(f, source="shop.csv") for f in (c.train, bent)]
    shared = [_thermal(diagnose(r, m, axis="E_ch3", network="shared", progress=False).calibrated) for r in runs]
    assert shared[0] == pytest.approx(shared[1], rel=1e-12)
    recal = [_thermal(diagnose(r, m, axis="E_ch3", progress=False).calibrated) for r in runs]
    assert recal[0] != pytest.approx(recal[1], rel=1e-3)


def test_shared_needs_a_sensed_node(case, tmp_path, capsys):
    """No node has a `sensor`: there is no temperature to calibrate one network on; one clear
    line, exit 2, nothing written."""
    train, m, test, c = case
    text = "\n".join(line for line in m.to_toml().splitlines() if not line.startswith("sensor"))
    blind = Machine.from_toml(text)
    with pytest.raises(ThermerrError, match="network.*`shared`.*none of its nodes a `sensor`"):
        diagnose(train, blind, test, network="shared", progress=False)
    run_csv, toml = tmp_path / "run.csv", tmp_path / "m.toml"
    syn.write_run_csv(run_csv, c.train)
    toml.write_text(text)
    assert main(["diagnose", str(run_csv), "--machine", str(toml), "--out", str(tmp_path / "d"),
                 "--network", "shared", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "`shared`" in err[0], err
    assert not (tmp_path / "d").exists()
