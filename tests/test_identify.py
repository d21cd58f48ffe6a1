"""Identify a starting network from a run alone (issue 15 point 1: ``Machine.identify``,
``thermerr init``), then diagnose with it as with the hand-written nominal machine.

Rates at which the diagnosis names the hidden cause (and its column, where it has one), with the
machine identified from the training run WITHOUT the nominal TOML, and with the nominal TOML of
``synthetic.make_case`` (perturbed true parameters). Runs of 8 h training / 4 h held out at 120-s
sampling, seeds 1 and 2, measured by ``test_rate_sweep`` (about 10 s for the 40 diagnoses, so it
runs by default), and runs of 24 h / 4 h at 60 s by ``test_rate_sweep_long`` (about 35 s):

=================  ==========  ==========================  ==========================
topology           cause       identified (seeds 1, 2)     nominal TOML (seeds 1, 2)
=================  ==========  ==========================  ==========================
vmc                ambient     2/2                         2/2
vmc                unmodeled   2/2                         2/2
vmc                lag         2/2                         2/2
vmc                drift       2/2                         2/2
vmc                none        2/2                         2/2
lathe              ambient     2/2                         2/2
lathe              unmodeled   2/2                         2/2
lathe              lag         2/2                         2/2
lathe              drift       2/2                         2/2
lathe              none        2/2                         2/2
all                            20/20                       20/20
=================  ==========  ==========================  ==========================

Measured 2026-11-28 after identification added a node no sensor reads behind the slowest node
(step 9 of docs/machine-model.md, "Starting from data": the VMC's bed, which the true machine
has and no sensor reads). Before it, 17/20: the identified VMC 8/10 (it absorbed the sensor
drift of seed 1, called an unmodelled source, and took the room for an effect where nothing
is hidden, seed 1), a strict xfail here, and the lathe 9/10. With it the VMC is 10/10 and both
machines are within the brief's bar (within one case of the nominal's count). Over seeds 1-4
(``python benches/diagnose_matrix.py --identified --seeds 1-4``): 30/40 against 38/40 (29/40
before the unsensed node). On the 24-h runs the unsensed node matters most: see
``test_rate_sweep_long``.

Measured 2026-11-29 after that node was calibrated within a diagnosis's bounds and prior
(identify.rs ``refining``): the lathe's source of seed 2 named on its column (it named
``T_cabinet``: 19/20). Over seeds 1-16 (the bench, ``--seeds 1-8`` and ``--seeds 9-16``):
128/160 against the nominal's 152/160 (121/160 before the refinement).

History: 8/20 before identification calibrated from two starts and built the tree from both
nodes' heat balances; 15/20 before the simulation's step was rewritten (the same equations,
other roundings); 16/20 before a spare column entered a node's heat balance; 17/20 from
2026-11-26 to the unsensed node.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.cli import main
from thermerr_rs.errors import DataError, SuspectReadingWarning, ThermerrError
from thermerr_rs.thermal import Machine, diagnose

from _signals import ctrl_c
from conftest import EXAMPLES

HOURS, DT_S = (8.0, 4.0), 120.0
CAUSES = ("ambient_coupling", "unmodeled_source", "thermal_lag", "sensor_drift", "none")
# the brief's bar: the identified machine names the hidden cause within one case of the nominal
MAX_SHORTFALL = 1


def _run(cols, source):
    return tr.Run.from_frame(cols, source=source)


def _hit(case, d):
    if d.verdict != case.hidden:
        return False
    return d.column == case.column if case.hidden in ("sensor_drift", "unmodeled_source") else True


def _both(topology, hidden, seed, hours=HOURS, dt=DT_S):
    c = syn.make_case(topology, hidden, seed, hours=hours, dt=dt)
    train, test = _run(c.train, "train.csv"), _run(c.test, "test.csv")
    ident, _ = Machine.identify(train)
    d_id = diagnose(train, ident, test)
    d_nom = diagnose(train, Machine.from_toml(c.nominal_toml()), test)
    return c, d_id, d_nom


def _sweep(topology, hours, dt):
    rates = {}
    for hidden in CAUSES:
        for seed in (1, 2):
            c, d_id, d_nom = _both(topology, hidden, seed, hours, dt)
            a, b = rates.get(hidden, (0, 0))
            rates[hidden] = (a + _hit(c, d_id), b + _hit(c, d_nom))
    print(topology, rates)
    total_id = sum(a for a, _ in rates.values())
    total_nom = sum(b for _, b in rates.values())
    assert total_id >= total_nom - MAX_SHORTFALL, rates


@pytest.mark.parametrize("topology", ["vmc", "lathe"])
def test_rate_sweep(topology):
    _sweep(topology, HOURS, DT_S)


@pytest.mark.parametrize("topology", ["vmc", "lathe"])
def test_rate_sweep_long(topology):
    """The sweep on 24-h training runs at 60 s (4 h held out): a longer run shows the slow parts.
    Measured 2026-11-28, seeds 1-2: identified VMC 9/10 (a sensor drift of seed 1
    ``unexplained``) and lathe 10/10, nominal 10/10 each. Without the unsensed node behind the
    slowest node the identified VMC named 6/10 here (a sensor drift ``unexplained`` twice; with
    nothing hidden an unmodelled source and a speed growth): the VMC's bed, which no sensor
    reads, shows on a day-long run. Seeds 1-4 (the bench, ``--hours 24,4 --dt 60``): identified
    38/40 against nominal 40/40 (31/40 before the unsensed node). Since the node is calibrated
    within a diagnosis's bounds (2026-11-29) seeds 1-2 name 20/20 (the VMC's drift of seed 1
    too), seeds 1-8 77/80 against 80/80 (76/80 before)."""
    _sweep(topology, (24.0, 4.0), 60.0)


def test_a_node_slower_than_the_training_rows_is_said_to_be_hardly_determined():
    """On the real 46-h run one node calibrates to 278 h on 32 h of training rows: the run shows
    it warming, not where it settles. A 2-h VMC run (the column's time constant 2.2 h on 1.4 h
    of training rows; the unsensed node behind it would take 4.0 h and is not kept) gets the
    note; an 8-h run, whose slowest node (the unsensed one, kept) takes 2.2 h, not. A kept
    unsensed node is within the training rows by its own rule, so the check of it here guards
    only the file's rounding."""
    def slow_notes(hours):
        c = syn.make_case("vmc", "none", 1, hours=(hours, 1.0), dt=60.0)
        m, s = Machine.identify(_run(c.train, "short.csv"))
        span = c.train["time_s"][s["train_rows"] - 1] - c.train["time_s"][0]
        nodes = s["nodes"] + ([s["unsensed"]] if s["unsensed"] and s["unsensed"]["kept"] else [])
        slow = [n["name"] for n in nodes if n["tau_s"] > span]
        return slow, [x for x in s["notes"] if x.startswith("calibrated time constant longer than")], s["toml"]

    slow, notes, toml = slow_notes(2.0)
    assert slow and len(notes) == 1 and all(f"{n} (" in notes[0] for n in slow)
    assert "# note: calibrated time constant longer than the training rows last" in toml
    assert slow_notes(8.0)[:2] == ([], [])


@pytest.mark.parametrize("topology", ["vmc", "lathe"])
def test_distinct_parts_are_not_lagged_copies(topology):
    """A part heated through another follows it as a lag too (the headstock behind the bearing:
    within 1.4-2.7 noise levels on these 8-h runs), but with a smaller rise (gain 0.2-0.44) or a
    longer lag (the lathe's bed behind the carriage): each keeps its node."""
    for seed in (1, 2):
        c = syn.make_case(topology, "none", seed, hours=HOURS, dt=DT_S)
        m, s = Machine.identify(_run(c.train, "train.csv"))
        assert s["copies"] == [], (seed, s["copies"])


def test_a_duplicate_a_dead_sensor_and_a_second_room_reading_make_no_node():
    """A column logged twice is a lagged copy at lag 0; a constant (a dead sensor) and a second
    reading of the room vary by less than 2 noise levels (the reading, or its rise over the
    ambient) and are left out. Before, the duplicate and the constant each became a node and a
    network of only duplicated sensors held out 45 µm."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    plain, s0 = Machine.identify(_run(c.train, "plain.csv"))
    cols = dict(c.train)
    cols["T_dup"] = cols["T_front_bearing"].copy()
    cols["T_flat"] = np.full(len(cols["time_s"]), 21.5)
    cols["T_room2"] = cols["T_ambient"] + 0.03 * np.random.default_rng(0).normal(size=len(cols["time_s"]))
    # the dead sensor is also pointed out as a suspect reading (the whole run one value), and
    # as one that fails it is left out before the rule of the 2 noise levels is reached
    with pytest.warns(SuspectReadingWarning, match=r"T_flat reads one value \(21.5\) in every row"):
        m, s = Machine.identify(_run(cols, "extra.csv"))
    # a column and its exact duplicate explain each other alike: the first by name (columns are
    # taken in the natural order of their names) carries the node, the other is its copy
    assert m.sensors == ["T_dup" if x == "T_front_bearing" else x for x in plain.sensors]
    assert [(x["column"], x["of"], x["tau_s"]) for x in s["copies"]] == [("T_front_bearing", "T_dup", 0.0)]
    left = {x.split(":")[0]: x for x in s["spare"]}
    assert "reads one value in every row" in left["T_flat"]
    assert "rise over the ambient varies" in left["T_room2"]
    assert s["axes"][0]["holdout_rmse_um"] == pytest.approx(s0["axes"][0]["holdout_rmse_um"], rel=1e-9)


def test_more_nodes_asked_than_parts_keeps_the_copies_as_nodes():
    c = syn.make_shop_case(2, hours=12.0, hidden={})
    run = _run(c.train, "shop.csv")
    _, s = Machine.identify(run, "E_ch1", nodes=3)
    assert len(s["nodes"]) == 3 and s["copies"]
    _, s = Machine.identify(run, "E_ch1", nodes=6)
    assert len(s["nodes"]) == 6 and s["copies"] == []
    assert any("lagged copies" in n and "are nodes as well" in n for n in s["notes"])


def test_ambient_without_its_name_is_the_coldest_column():
    c = syn.make_case("vmc", "none", 4, hours=HOURS, dt=DT_S)
    cols = {("T_t7" if k == "T_ambient" else k): v for k, v in c.train.items()}
    m, s = Machine.identify(_run(cols, "renamed.csv"))
    assert s["ambient"]["column"] == "T_t7"
    assert s["ambient"]["rule"] == "coldest"
    assert "coldest reading" in s["ambient"]["reason"] and "T_t7" in s["ambient"]["reason"]
    assert 'ambient = "T_t7"' in s["toml"]
    assert "# ambient (coldest): no T_ambient column: T_t7 is the coldest" in s["toml"]
    assert "T_t7" not in m.sensors


def test_the_named_and_the_given_ambient():
    c = syn.make_case("lathe", "none", 2, hours=HOURS, dt=DT_S)
    _, s = Machine.identify(_run(c.train, "run.csv"))
    assert s["ambient"]["column"] == "T_ambient" and s["ambient"]["rule"] == "named"
    cols = dict(c.train)
    cols["T_room"] = cols.pop("T_ambient")
    _, s = Machine.identify(_run(cols, "run.csv"), ambient="T_room")
    assert s["ambient"] == {"column": "T_room", "rule": "given", "reason": "T_room was given as the ambient"}


def test_distractors_are_left_out_and_the_network_fits():
    c = syn.make_case("lathe", "none", 1, hours=HOURS, dt=DT_S)
    m, s = Machine.identify(_run(c.train, "run.csv"))
    spare = " ".join(s["spare"])
    assert "T_cabinet" in spare and "T_hydraulic" in spare
    assert set(m.sensors) == {"T_spindle_bearing", "T_headstock", "T_x_nut", "T_carriage", "T_bed"}
    # the true lathe's links: spindle_bearing-headstock, headstock-bed, x_nut-carriage, carriage-bed
    for n in s["nodes"]:
        assert n["tau_s"] > 0 and n["tau_fit_s"] > 0
    ax = s["axes"][0]
    assert ax["axis"] == "E_x"
    # probe noise is 0.15 µm: the identified network explains the held-out 30 % within 3x of it
    assert ax["holdout_rmse_um"] < 0.45, s["axes"]
    heated = {n["name"]: n["heated_by"] for n in s["nodes"]}
    assert heated["spindle_bearing"] == ["U_spindle_rpm"] and heated["x_nut"] == ["U_feed_mm_min"]


@pytest.mark.parametrize("seed", [1, 2])
def test_heat_from_a_spare_column_enters_the_balance_not_the_network(seed):
    """The lathe's hydraulic unit heats the headstock (the hidden source): in the headstock's heat
    balance the spare column T_hydraulic alone removes most of the misfit (measured 56-63 % on
    seeds 1-2, 0.56-0.96 over the VMC and lathe seeds 1-7), so it enters that balance and a
    note says so, but it stays a spare column. Without that, the balance read the hydraulic
    heat as the headstock's own (its loss to the room 0.003 W/K against the true 6.3) and the
    diagnosis with the identified network said ``none`` on seed 1. With nothing hidden, no
    spare column is let in (the best leaves 82-100 % of a balance's misfit)."""
    c = syn.make_case("lathe", "unmodeled_source", seed, hours=HOURS, dt=DT_S)
    m, s = Machine.identify(_run(c.train, "run.csv"))
    hits = [n for n in s["notes"] if "(a spare column) in headstock's heat balance" in n]
    assert len(hits) == 1 and hits[0].startswith("T_hydraulic "), s["notes"]
    assert "T_hydraulic" not in m.sensors and any(x.startswith("T_hydraulic:") for x in s["spare"])
    assert not any("source_" in n or "outside" in n for n in m.nodes)
    c = syn.make_case("lathe", "none", seed, hours=HOURS, dt=DT_S)
    _, s = Machine.identify(_run(c.train, "run.csv"))
    assert not any("(a spare column) in" in n for n in s["notes"]), s["notes"]


def _kept_tree(s):
    """The tree identification kept and the note that says so."""
    note = next(n for n in s["notes"] if " trees tried (" in n)
    return int(note.split(" is kept")[0].split("tree ")[-1].split(" ")[0]), note


def test_a_later_link_the_run_clearly_refutes_is_moved():
    """The links' rule trusts the links both heat balances ask for; a tree with one of them moved
    is calibrated too and kept when it fits the training rows 5x better (``LATER_TREE_MARGIN``).
    On the 36-h VMC run at 15 s with nothing hidden (seed 1) the rule joined the column to the
    motor; the tree joining it to the headstock, as the true machine does, fits 6x better, and
    the diagnosis says ``none``. Before the moved trees, the rule's tree held out 0.60 µm (4x
    the probe noise) and the diagnosis said ``unexplained`` (measured 2026-11-29)."""
    c = syn.make_case("vmc", "none", 1, hours=(36.0, 12.0), dt=15.0)
    train, test = _run(c.train, "train.csv"), _run(c.test, "test.csv")
    m, s = Machine.identify(train)
    kept, note = _kept_tree(s)
    assert "trees 4-5 with a later link of the rule's moved" in note and kept in (4, 5), note
    links = {frozenset(x["between"]) for x in m.to_dict()["links"]}
    assert frozenset({"headstock", "column"}) in links, links
    assert frozenset({"spindle_motor", "column"}) not in links, links
    assert diagnose(train, m, test).verdict == "none"


def test_a_moved_link_that_fits_only_somewhat_better_is_not_taken():
    """The margin's other side: on the 8-h lathe run hiding an unmodelled source (seed 4), a tree
    with a later link moved fits the training rows 4.6x better than the rule's, because the moved
    link carries the hidden source's heat. Kept on the best fit alone, the diagnosis said
    ``unexplained`` (and over seeds 1-8 the lathe's sources were named 1/8 instead of 6/8); under
    the 5x margin the rule's tree stays and the source is named from ``T_hydraulic``."""
    c = syn.make_case("lathe", "unmodeled_source", 4, hours=HOURS, dt=DT_S)
    train, test = _run(c.train, "train.csv"), _run(c.test, "test.csv")
    m, s = Machine.identify(train)
    kept, note = _kept_tree(s)
    assert kept == 1, note
    d = diagnose(train, m, test)
    assert (d.verdict, d.column) == ("unmodeled_source", "T_hydraulic")


def test_a_drifting_sensor_is_not_read_as_its_parts_heat():
    """A thermocouple drifting 0.185 K/h over a day and a half (the 36-h lathe at 15 s, seed 5,
    ``T_carriage``): without a drift beside it, identification bent the carriage's capacity,
    losses and links around the drift and the diagnosis said ``unexplained`` (1.90 µm held
    out). Calibrated beside the network, the drift removes 97 % of the training misfit (at
    least ``DRIFT_NUISANCE_SHARE``, half, asked), its rate comes out within 1 % of the true one
    (5 % allowed: the term also takes up what the network misfits), the file carries no drift
    term, and the diagnosis names the drift of ``T_carriage``. The same lathe with nothing
    hidden: the best drift removes under 1 % and is not kept (measured 2026-11-29)."""
    c = syn.make_case("lathe", "sensor_drift", 5, hours=(36.0, 12.0), dt=15.0)
    train, test = _run(c.train, "train.csv"), _run(c.test, "test.csv")
    m, s = Machine.identify(train)
    d = s["sensor_drift"]
    assert d["kept"] and d["sensor"] == "T_carriage" and d["share"] > 0.9, d
    assert d["k_per_h"] == pytest.approx(c.params["rate_k_per_h"], rel=0.05)
    assert any("a drift of T_carriage's reading calibrated beside the network" in n for n in s["notes"])
    assert "sensor_drift_k_per_h" not in s["toml"]
    dg = diagnose(train, m, test)
    assert (dg.verdict, dg.column) == ("sensor_drift", "T_carriage")

    c0 = syn.make_case("lathe", "none", 5, hours=(36.0, 12.0), dt=15.0)
    _, s0 = Machine.identify(_run(c0.train, "train.csv"))
    assert not s0["sensor_drift"]["kept"] and s0["sensor_drift"]["share"] < 0.01, s0["sensor_drift"]


@pytest.mark.parametrize("topology", ["vmc", "lathe"])
def test_the_order_of_the_runs_columns_does_not_change_the_network(topology):
    """A logger writes its columns in any order. The same run with its temperature (and input)
    columns reversed gives the same file, value for value: temperatures and inputs are taken in
    the natural order of their names, and fuzzy c-means keeps the least objective of 20 starts.
    Before (2026-11-29) every synthetic run checked (VMC and lathe seeds 1-3, the shop runs
    seeds 1-2) gave another file reversed, and the real 46-h run reversed clustered into other
    nodes (held out E_ch3 17.1 against 12.5 µm)."""
    c = syn.make_case(topology, "none", 1, hours=HOURS, dt=DT_S)
    names = list(c.train)
    moved = [n for n in names if n.startswith(("T_", "U_"))]
    rest = [n for n in names if n not in moved]
    reordered = {n: c.train[n] for n in rest[:1] + moved[::-1] + rest[1:]}
    assert list(reordered) != names

    def values(cols):
        m, _ = Machine.identify(_run(cols, "run.csv"))
        return m.to_dict()

    assert values(reordered) == values(c.train)


def test_the_order_of_a_shop_runs_columns_does_not_change_the_network():
    """The same with sixteen temperatures and five probes (the shop run, 12 h at 15 s), every
    column but the time reversed: the probes too are taken in the natural order of their names
    when not given, so the first of them, which calibrates the network, is ``E_ch1`` either way.
    Before (2026-11-29) the reversed run gave another file; the real 46-h run with its columns
    shuffled (``E_ch3`` first) held out 6.76 µm on E_ch3 against the run's 12.48."""
    c = syn.make_shop_case(1, hours=12.0)
    names = list(c.train)
    reversed_ = {n: c.train[n] for n in names[:1] + names[1:][::-1]}
    a, sa = Machine.identify(_run(c.train, "run.csv"))
    b, sb = Machine.identify(_run(reversed_, "run.csv"))
    assert a.to_dict() == b.to_dict()
    assert [x["axis"] for x in sb["axes"]] == [f"E_ch{k}" for k in range(1, 6)]


def test_fixed_node_count_and_clusters_listed():
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    m, s = Machine.identify(_run(c.train, "run.csv"), nodes=2)
    # the count asked is of the clustered nodes; the unsensed node behind the slowest comes on top
    assert s["n_nodes"] == 2 and s["unsensed"]["kept"]
    assert m.nodes == [n["name"] for n in s["nodes"]] + [s["unsensed"]["name"]]
    members = [x for n in s["nodes"] for x in n["members"]]
    assert sorted(members) == sorted(["T_front_bearing", "T_spindle_motor", "T_headstock", "T_column"])
    for n in s["nodes"]:
        assert n["members"][0] == n["sensor"]
        if len(n["members"]) > 1:
            assert f"# other sensors of this cluster (not in the model): {', '.join(n['members'][1:])}" in s["toml"]


def test_no_more_sensors_than_the_node_limit_are_a_node_each_and_the_rule_says_why():
    """With as many clusters as sensors each sensor is alone and the Xie-Beni index is 0 by
    construction: it cannot choose there. The VMC's four screened sensors are four nodes (as
    before, when the index of 4 clusters printed 0.000 and won), and the rule says why instead of
    printing an index that could not lose; asked for fewer, they are clustered."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    run = _run(c.train, "run.csv")
    _, s = Machine.identify(run)
    assert s["n_nodes"] == 4 and s["node_rule"].startswith("4 sensors besides the ambient, at most 5 nodes: one node each")
    assert "Xie-Beni index is 0 by construction" in s["node_rule"]
    _, s3 = Machine.identify(run, nodes=3)
    assert s3["n_nodes"] == 3 and "fuzzy c-means" in s3["node_rule"]


def test_toml_round_trips_and_states_every_choice(tmp_path):
    c = syn.make_case("vmc", "none", 2, hours=HOURS, dt=DT_S)
    run = _run(c.train, "run.csv")
    m, s = Machine.identify(run)
    path = tmp_path / "m.toml"
    path.write_text(s["toml"])
    back = Machine.load(path)
    assert back.to_toml() == m.to_toml()
    sim_a, sim_b = back.simulate(run), m.simulate(run)
    np.testing.assert_allclose(sim_a.drift["E_z"], sim_b.drift["E_z"])
    text = s["toml"]
    for phrase in ("# ambient (named)", "# nodes:", "tau fit", "calibrated", "# links:", "# sources:",
                   "initial slope", "# drift of E_z", "held-out RMS", "# left out: T_cabinet"):
        assert phrase in text, phrase


def test_several_axes():
    c = syn.make_case("lathe", "none", 3, hours=HOURS, dt=DT_S)
    cols = dict(c.train)
    rng = np.random.default_rng(0)
    cols["E_y"] = 0.4 * cols["E_x"] + rng.normal(0, 0.15, len(cols["E_x"]))
    m, s = Machine.identify(_run(cols, "run.csv"))
    assert m.axes == ["E_x", "E_y"] and [a["axis"] for a in s["axes"]] == ["E_x", "E_y"]
    m1, s1 = Machine.identify(_run(cols, "run.csv"), "E_y")
    assert m1.axes == ["E_y"]


def test_a_probe_logged_in_mm_gives_the_same_network():
    """The same run with its probe in mm (×1e-3) weighs the probe alike in the network's
    calibration: the same time constants, the figures in the probe's unit. An absolute floor of
    0.02 µm on the probe's σ weighed a probe in mm a thousand times less (the real 46-h run's
    E_ch3 held out 12.5 µm read in µm, 5 in mm); on this case the training RMS in mm was 4.8 %
    off. What still differs: the drift coefficients' weak priors are in µm/K (formats.md) and do
    not scale, which in mm makes them weaker still: here the figures and time constants agree
    within 0.1 % (measured), so 1 % separates them from the old floor's 4.8 %. (In nm the same
    priors become strong: training RMS 2.8 % apart on this case; left as is, a probe in nm being
    rare.)"""
    c = syn.make_case("lathe", "none", 3, hours=HOURS, dt=DT_S)
    cols = dict(c.train)
    _, s = Machine.identify(_run(cols, "run.csv"))
    cols["E_x"] = np.asarray(cols["E_x"]) / 1000.0
    with pytest.warns(SuspectReadingWarning, match="logged in mm"):
        _, s2 = Machine.identify(_run(cols, "run.csv"))
    for a, b in zip(s["axes"], s2["axes"], strict=True):
        for key in ("train_rmse_um", "holdout_rmse_um", "holdout_uncompensated_um"):
            assert b[key] * 1000.0 == pytest.approx(a[key], rel=0.01), key
    assert [n["tau_s"] for n in s2["nodes"]] == pytest.approx([n["tau_s"] for n in s["nodes"]], rel=0.01)


def test_a_dead_probe_is_left_out_of_every_axis_and_refused_by_name(tmp_path, capsys):
    """A probe that reads one value in every row (E_y at 0): before, init wrote its axis with a
    drift map of zeros, which every diagnosis then left out. Now with every axis it is left out
    of the file with a note (the network and the other axis's map are those of the run without
    it), named with --axis it is refused (exit 2, one line, nothing written), and with every
    probe dead there is nothing to map."""
    c = syn.make_case("lathe", "none", 3, hours=HOURS, dt=DT_S)
    cols = dict(c.train)
    without = tmp_path / "clean.csv"
    syn.write_run_csv(without, cols)
    cols["E_y"] = np.zeros_like(cols["E_x"])
    run = tmp_path / "dead.csv"
    syn.write_run_csv(run, cols)
    out = tmp_path / "m.toml"
    assert main(["init", str(run), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"note: E_y left out of the file: {run}: E_y reads one value (0) in every row" in text, text
    assert "suspect reading" not in text  # the left-out axis's own suspect lines: said by the note
    assert Machine.load(out).axes == ["E_x"]
    assert main(["init", str(without), "--axis", "E_x", "--out", str(tmp_path / "clean.toml")]) == 0
    capsys.readouterr()
    body = [ln for ln in out.read_text().splitlines() if not ln.startswith(("#", "name", "source", "run ="))]
    clean = [ln for ln in (tmp_path / "clean.toml").read_text().splitlines()
             if not ln.startswith(("#", "name", "source", "run ="))]
    assert body == clean
    for args, says in ((["--axis", "E_y"], "E_y reads one value (0) in every row"),
                       (["--axis", "E_x", "--axis", "E_y"], "or leave the axis out")):
        bad = tmp_path / "bad.toml"
        assert main(["init", str(run), "--out", str(bad), *args]) == 2
        err = [x for x in capsys.readouterr().err.splitlines() if x.startswith("thermerr: error:")]
        assert len(err) == 1 and says in err[0], err
        assert not bad.exists()
    cols["E_x"] = np.full_like(cols["E_x"], 3.5)
    syn.write_run_csv(run, cols)
    with pytest.raises(ThermerrError, match="E_x reads one value .*; .*E_y reads one value .*mend the probe$"):
        Machine.identify(_run(cols, "dead.csv"))


def test_inputs_that_heat_are_the_ones_named(tmp_path, capsys):
    """A log with a U_* column that heats nothing (a random on/off state, independent of the
    spindle): by default it is taken as a heat input like every U_* column (on the real 46-h
    run such a column was given sources on three of the five nodes and moved the spindle's),
    and a note says so; named with --input, the others are the heat inputs and the file is the
    one of the run without that column. An input the run lacks, or given twice, is one line,
    exit 2, nothing written."""
    c = syn.make_case("lathe", "none", 1, hours=HOURS, dt=DT_S)
    cols = dict(c.train)
    rng = np.random.default_rng(7)
    flips = np.sort(rng.uniform(0, cols["time_s"][-1], 8))
    cols["U_program"] = (np.searchsorted(flips, cols["time_s"]) % 2).astype(float)
    run = tmp_path / "run.csv"
    syn.write_run_csv(run, cols)
    out = tmp_path / "m.toml"
    assert main(["init", str(run), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "note: inputs: every U_* column is taken as a heat input (U_feed_mm_min, U_program, U_spindle_rpm)" in text
    named = ["--input", "U_spindle_rpm", "--input", "U_feed_mm_min"]
    assert main(["init", str(run), "--out", str(out), *named]) == 0
    text = capsys.readouterr().out
    assert "note: inputs: U_feed_mm_min, U_spindle_rpm (given); not taken as heat inputs: U_program" in text
    assert "U_program" not in [s["input"] for s in Machine.load(out).to_dict()["sources"]]
    # every one named: no note asking to name them
    assert main(["init", str(run), "--out", str(tmp_path / "all.toml"), *named, "--input", "U_program"]) == 0
    assert "note: inputs" not in capsys.readouterr().out
    without = tmp_path / "without.csv"
    syn.write_run_csv(without, {k: v for k, v in cols.items() if k != "U_program"})
    assert main(["init", str(without), "--out", str(tmp_path / "w.toml")]) == 0
    capsys.readouterr()

    def body(p):
        return [ln for ln in p.read_text().splitlines() if not ln.startswith(("#", "name", "source", "run ="))]

    assert body(out) == body(tmp_path / "w.toml")
    for args, says in ((["--input", "U_spindle"], "input `U_spindle`: not an input column of the run "
                        "(U_* columns: U_spindle_rpm, U_feed_mm_min, U_program)"),
                       (["--input", "U_program", "--input", "U_program"], "input `U_program`: given twice")):
        bad = tmp_path / "bad.toml"
        assert main(["init", str(run), "--out", str(bad), *args]) == 2
        err = [x for x in capsys.readouterr().err.splitlines() if x.startswith("thermerr: error:")]
        assert len(err) == 1 and str(run) in err[0] and says in err[0], err
        assert not bad.exists()
    m, s = Machine.identify(_run(cols, "run.csv"), inputs="U_spindle_rpm")
    assert {x["input"] for x in m.to_dict()["sources"]} == {"U_spindle_rpm"}


@pytest.mark.filterwarnings("ignore:shop.csv. T_t17 repeats one reading")  # the 0.1-K logger's, said
def test_a_chilled_coolant_is_not_the_room_and_a_room_is_known_by_its_name():
    """A spindle chiller's coolant at 18 °C, colder than the shop and cycling ±0.4 K every
    15 min with its control loop: the coldest rule took it for the room, and on the real 46-h run
    init then stopped ("no temperature warms with any input"). A column that cycles within the
    hour is passed over (and said), and the room is the coldest of the rest; a steady room on a
    0.1-K logger, which varies by its noise alone, is not passed over. A column named as the
    room (T_room, T_Amb, ...) is the ambient by its name."""
    c = syn.make_shop_case(1, hours=24.0, dt=60.0)  # (on 12 h the rule takes T_t13, a part)
    cols = dict(c.train)
    t = cols["time_s"]
    rng = np.random.default_rng(3)
    _, plain = Machine.identify(_run(cols, "shop.csv"))
    assert plain["ambient"]["column"] == "T_t6" and plain["ambient"]["rule"] == "coldest"
    cooled = dict(cols, T_t17=18.0 + 0.4 * np.sin(2 * np.pi * t / 900.0) + rng.normal(0, 0.02, len(t)))
    _, s = Machine.identify(_run(cooled, "shop.csv"))
    assert s["ambient"]["column"] == "T_t6", s["ambient"]
    assert "T_t17 is colder in 100 % of them, but it cycles within the hour" in s["ambient"]["reason"]
    # the room held by a climate control and logged at 0.1 K: its noise is all it shows
    steady = dict(cooled, T_t17=np.round(20.0 + rng.normal(0, 0.03, len(t)), 1))
    _, s = Machine.identify(_run(steady, "shop.csv"))
    assert s["ambient"]["column"] == "T_t17", s["ambient"]
    named = {("T_Room" if k == "T_t6" else k): v for k, v in cols.items()}
    _, s = Machine.identify(_run(named, "shop.csv"))
    assert s["ambient"]["column"] == "T_Room" and s["ambient"]["rule"] == "named"


def test_cli_init_writes_and_prints(tmp_path, capsys):
    c = syn.make_case("lathe", "none", 1, hours=HOURS, dt=DT_S)
    run = tmp_path / "run.csv"
    syn.write_run_csv(run, c.train)
    out = tmp_path / "machine.toml"
    assert main(["init", str(run), "--axis", "E_x", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "ambient: T_ambient" in text
    assert "E_x: training RMS" in text and "held-out RMS" in text
    assert text.count("time constant") == 5
    # the probe's noise (0.15 µm in this run) printed for scale; a network that fits within twice
    # it gets no warning
    assert "probe noise 0.16 µm" in text and "note: held out" not in text
    assert Machine.load(out).axes == ["E_x"]
    # one node cannot hold the lathe: the held-out error is many times the noise, and init says
    # what that means for a diagnosis
    assert main(["init", str(run), "--axis", "E_x", "--out", str(tmp_path / "one.toml"), "--nodes", "1"]) == 0
    text = capsys.readouterr().out
    assert "note: held out, this network leaves more than 2x the probe noise on E_x (" in text
    assert "--nodes N" in text and "# note: held out" in (tmp_path / "one.toml").read_text()
    assert out.read_text().startswith("# Identified by `thermerr init`")
    # --quiet drops the chatter (the choices, the notes), keeps the results (it printed nothing)
    assert main(["init", str(run), "--axis", "E_x", "--out", str(tmp_path / "q.toml"), "--quiet"]) == 0
    cap = capsys.readouterr()
    lines = cap.out.splitlines()
    assert [x.split(":")[0] for x in lines] == ["E_x", f"wrote {tmp_path / 'q.toml'}"], lines
    assert "held-out RMS" in lines[0] and cap.err == "", cap.err


def _bad_runs(tmp_path, c):
    base = dict(c.train)
    no_t = {k: v for k, v in base.items() if not k.startswith("T_")}
    no_e = {k: v for k, v in base.items() if not k.startswith("E_")}
    return {
        "no T": (no_t, [], "T_* columns"),
        "no E": (no_e, [], "E_* columns"),
        "unknown ambient": (base, ["--ambient", "T_nope"], "ambient `T_nope`"),
        "too many nodes": (base, ["--nodes", "9"], "nodes = 9"),
        "unknown axis": (base, ["--axis", "E_q"], "axis `E_q`"),
    }


@pytest.mark.parametrize("kind", ["no T", "no E", "unknown ambient", "too many nodes", "unknown axis"])
def test_cli_bad_input_exit_2_one_line_nothing_written(tmp_path, capsys, kind):
    c = syn.make_case("lathe", "none", 1, hours=(3.0, 1.0), dt=DT_S)
    cols, extra, entry = _bad_runs(tmp_path, c)[kind]
    run = tmp_path / "bad.csv"
    syn.write_run_csv(run, cols)
    out = tmp_path / "m.toml"
    assert main(["init", str(run), "--out", str(out), *extra]) == 2
    err = [x for x in capsys.readouterr().err.splitlines() if x.startswith("thermerr: error:")]
    assert len(err) == 1, err
    assert str(run) in err[0] and entry in err[0], err[0]
    assert not out.exists()


def _joined(cols, restart_clock=False):
    """A run followed by itself: the clock running on (two runs joined into one log) or starting
    again at the first row's time."""
    t = np.asarray(cols["time_s"])
    later = t if restart_clock else t + t[-1] + (t[1] - t[0])
    return {k: np.concatenate([np.asarray(v), later if k == "time_s" else np.asarray(v)]) for k, v in cols.items()}


def test_two_runs_joined_in_one_file_are_refused_naming_the_row(tmp_path, capsys):
    """Two runs joined with the clock running on: every column steps back to its cold reading at
    one row. Taken as sensor faults, every probe failed from there on and `init` wrote a file with
    no held-out figure on any axis (exit 0; the real run joined to itself), and the diagnosis
    said "mend the probes". One line naming the file and the row instead, nothing written, from
    the command line, `Machine.identify`, `diagnose`, `Machine.calibrate`, `Machine.simulate`
    and `thermerr predict` alike."""
    c = syn.make_case("lathe", "none", 1, hours=(3.0, 1.0), dt=DT_S)
    n = len(c.train["time_s"])
    run = tmp_path / "joined.csv"
    syn.write_run_csv(run, _joined(c.train))
    out = tmp_path / "m.toml"
    assert main(["init", str(run), "--out", str(out)]) == 2
    err = [x for x in capsys.readouterr().err.splitlines() if x.startswith("thermerr: error:")]
    assert len(err) == 1, err
    assert f"joined.csv, row {n + 1}: " in err[0] and "step at once" in err[0], err[0]
    assert "a second run appended to the first?" in err[0], err[0]
    assert not out.exists()
    joined = _run(_joined(c.train), "joined.csv")
    with pytest.raises(DataError, match=rf"joined\.csv, row {n + 1}: .* columns step at once"):
        Machine.identify(joined)
    nominal = Machine.from_toml(c.nominal_toml())
    with pytest.raises(DataError, match=rf"joined\.csv, row {n + 1}: "):
        diagnose(joined, nominal)
    # held out: the test run joined to itself (the training run's rows in it would be refused
    # first, as rows the fit trains on)
    m = len(c.test["time_s"])
    with pytest.raises(DataError, match=rf"joined\.csv, row {m + 1}: "):
        diagnose(_run(c.train, "train.csv"), nominal, _run(_joined(c.test), "joined.csv"))
    with pytest.raises(DataError, match=rf"joined\.csv, row {n + 1}: "):
        nominal.calibrate(joined)
    with pytest.raises(DataError, match=rf"joined\.csv, row {n + 1}: "):
        nominal.simulate(joined)
    (tmp_path / "nominal.toml").write_text(c.nominal_toml())
    pred = tmp_path / "pred.csv"
    assert main(["predict", str(run), "--machine", str(tmp_path / "nominal.toml"), "--out", str(pred)]) == 2
    assert "step at once" in capsys.readouterr().err and not pred.exists()
    # the run alone is one run; the clock starting again is the reader's refusal, saying why
    Machine.identify(_run(c.train, "train.csv"))
    syn.write_run_csv(run, _joined(c.train, restart_clock=True))
    assert main(["init", str(run), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"row {n + 1}, column `time_s`: time is not strictly increasing" in err, err
    assert "back to the first row's: a second run appended to the first?" in err, err
    assert not out.exists()


def test_python_bad_input_is_a_thermerr_error():
    c = syn.make_case("lathe", "none", 1, hours=(3.0, 1.0), dt=DT_S)
    run = _run(c.train, "bad.csv")
    with pytest.raises(DataError, match=r"bad\.csv: ambient `T_nope`"):
        Machine.identify(run, ambient="T_nope")
    with pytest.raises(ThermerrError, match=r"bad\.csv: nodes = 8"):
        Machine.identify(run, nodes=8)
    with pytest.raises(ThermerrError, match="E_\\* columns"):
        Machine.identify(_run({k: v for k, v in c.train.items() if not k.startswith("E_")}, "bad.csv"))


def test_the_report_says_the_network_was_identified(tmp_path):
    """issue 15 point 5: `identified` and its summary in report.json, the network drawn in
    report.html; a network written by hand reports `identified: false` and no summary."""
    c = syn.make_case("vmc", "ambient_coupling", 1, hours=HOURS, dt=DT_S)
    train, test = _run(c.train, "train.csv"), _run(c.test, "test.csv")
    m, s = Machine.identify(train)
    info = Machine.from_toml(s["toml"]).to_dict()["identified"]
    assert info["source"] == "train.csv" and info["ambient_rule"] == "named"
    assert info["train_rows"] == s["train_rows"] and info["holdout_rows"] == s["holdout_rows"]
    assert set(info["holdout_rmse_um"]) == {"E_z"}
    d = diagnose(train, m, test)
    assert d.report["identified"] is True and d.report["identification"] == info
    page = Path(d.write(tmp_path / "rep")).read_text()
    assert "identified from data" in page and page.count("<svg") == 1
    for n in m.nodes:
        assert f">{n}</text>" in page, n
    assert "or an unexplained remainder, may also be a shortcoming" in page
    assert str(d).endswith("the default, auto, keeps it only where the recalibration is not unique)")  # the printed result says it too
    nominal = diagnose(train, Machine.from_toml(c.nominal_toml()), test)
    assert nominal.report["identified"] is False and "identification" not in nominal.report
    assert "identified from data" not in Path(nominal.write(tmp_path / "nom")).read_text()
    assert "identified" not in str(nominal)
    # several axes: the summary page and the printed result carry it once
    from thermerr_rs.thermal import diagnose_axes

    both = diagnose_axes(train, m, test)
    assert str(both).count("note: the network was identified") == 1
    assert "identified from data" in Path(both.write(tmp_path / "axes")).read_text()


def test_an_unknown_key_in_the_identified_table_is_one_line():
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    _, s = Machine.identify(_run(c.train, "train.csv"))
    text = s["toml"].replace("[identified]\n", "[identified]\nsurce = \"x\"\n")
    with pytest.raises(ThermerrError) as e:
        Machine.from_toml(text, "m.toml")
    msg = str(e.value)
    assert "m.toml" in msg and "surce" in msg and "\n" not in msg


def test_the_file_states_the_start_its_figures_are_from(tmp_path, capsys):
    """init's figures are from the sensors' first readings, where a simulation of any run starts
    (its drift maps are fitted to the temperatures simulated from there): the file's ``[start]``
    table holds zero offsets, and a plain ``simulate(run)`` reproduces the stated figures. A
    machine calibrated again carries its own start (fitted, ±1 K), which reproduces its own
    figures."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    run = _run(c.train, "run.csv")
    m, s = Machine.identify(run)
    start = m.fitted_start
    assert set(start) == set(m.nodes) and all(v == 0.0 for v in start.values())
    assert m.to_dict()["start"]["run"] == "run.csv"
    ident = m.to_dict()["identified"]
    k = ident["train_rows"]
    rms = lambda r: float(np.sqrt(np.mean(r**2)))  # noqa: E731
    plain = m.simulate(run).drift["E_z"] - run["E_z"]
    np.testing.assert_array_equal(m.simulate(run, initial_k="fitted").drift["E_z"] - run["E_z"], plain)
    # the file's figures are rounded to 4 significant digits
    np.testing.assert_allclose([rms(plain[:k]), rms(plain[k:])],
                               [ident["train_rmse_um"]["E_z"], ident["holdout_rmse_um"]["E_z"]], rtol=5e-4)
    a = s["axes"][0]
    np.testing.assert_allclose([rms(plain[:k]), rms(plain[k:])], [a["train_rmse_um"], a["holdout_rmse_um"]],
                               rtol=1e-9)
    assert "simulated from the first readings, as any run is" in s["toml"]
    # calibrated again: a start of its own, the one its fit ended at
    cal, info = m.calibrate(run)
    assert cal.fitted_start == dict(zip(m.nodes, info["init_offsets"]))
    assert any(v != 0.0 for v in cal.fitted_start.values())
    # a machine written by hand has none, and says so
    with pytest.raises(DataError, match="no fitted start"):
        Machine.from_toml(c.nominal_toml()).simulate(run, initial_k="fitted")
    # an entry that names no node is one line naming it
    bad = s["toml"].replace("initial_k = { ", "initial_k = { t_nope = 0.5, ")
    with pytest.raises(ThermerrError, match=r"m\.toml: start\.initial_k `t_nope`: no node of that name"):
        Machine.from_toml(bad, "m.toml")
    # the command line: --start fitted writes the fitted start's simulation; without it, on a run
    # of the fitted run's name, a note says what the file's figures are from, when they are from
    # a start of their own (a calibration's), not when from the first readings (init's)
    syn.write_run_csv(tmp_path / "run.csv", c.train)
    (tmp_path / "m.toml").write_text(s["toml"])
    (tmp_path / "cal0.toml").write_text(cal.to_toml())
    out = tmp_path / "pred.csv"
    args = ["predict", str(tmp_path / "run.csv"), "--machine", str(tmp_path / "cal0.toml"), "--out", str(out)]
    assert main([*args, "--start", "fitted"]) == 0
    assert "note" not in capsys.readouterr().out
    read = tr.read_run(tmp_path / "run.csv")
    np.testing.assert_allclose(tr.read_run(out)["E_z_pred"], cal.simulate(read, initial_k="fitted").drift["E_z"],
                               rtol=0, atol=5e-7)  # 6 decimals written
    assert main(args) == 0
    assert "from a start of their own" in capsys.readouterr().out
    assert main(["predict", str(tmp_path / "run.csv"), "--machine", str(tmp_path / "m.toml"), "--out", str(out)]) == 0
    assert "note" not in capsys.readouterr().out
    assert main([*args, "--start", "fitted", "--fit-initial", "3"]) == 2
    capsys.readouterr()
    syn.write_run_csv(tmp_path / "other.csv", c.train)
    assert main(["predict", str(tmp_path / "other.csv"), "--machine", str(tmp_path / "cal0.toml"), "--out", str(out),
                 "--start", "fitted"]) == 0
    assert "the fitted start belongs to the run run.csv, not to" in capsys.readouterr().out
    # thermerr calibrate states both figures and writes its start
    cal_out = tmp_path / "cal.toml"
    assert main(["calibrate", str(tmp_path / "run.csv"), "--machine", str(tmp_path / "m.toml"),
                 "--out", str(cal_out), "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    back = Machine.load(cal_out)
    assert js["rmse_um"] == pytest.approx(rms(back.simulate(read, initial_k="fitted").drift["E_z"] - read["E_z"]))
    assert js["first_reading_rmse_um"] == pytest.approx(rms(back.simulate(read).drift["E_z"] - read["E_z"]))


def test_calibrate_scores_the_rows_its_probe_reads():
    """calibrate's RMS figures leave out the rows where the run shows the probe failing (a jump
    away and back), as every fit and score of the core does: here 50 µm added to 100 rows."""
    run = tr.read_run(EXAMPLES / "vmc_run.csv")
    cols = {n: run[n].copy() for n in run.names}
    cols["E_z"][300:400] += 50.0
    bad = tr.Run.from_frame({"time_s": run.time_s, **cols})
    cal, info = Machine.load(EXAMPLES / "vmc_nominal.toml").calibrate(bad)
    r = cal.simulate(bad, initial_k="fitted").drift["E_z"] - bad["E_z"]
    keep = np.ones(len(r), bool)
    keep[300:400] = False
    assert info["rmse_um"] == pytest.approx(float(np.sqrt(np.mean(r[keep] ** 2))), rel=1e-12)
    assert float(np.sqrt(np.mean(r**2))) > 50 * info["rmse_um"]


def test_a_drift_map_whose_node_terms_cancel_is_noted():
    """A drift map whose largest node term swings 3x or more the axis's whole drift (RMS over
    the training rows) is a small difference of large numbers: init says so. On the simulated
    machines the largest term is below the drift (0.34-0.69 of it); here the error is made the
    difference of two sensors that warm nearly together (front bearing and spindle motor,
    r(a)/r(a - 0.987 b) = 17.7), and the note names the axis."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    _, s = Machine.identify(_run(c.train, "run.csv"))
    assert not [n for n in s["notes"] if "cancel" in n]
    cols = dict(c.train)
    a, b = cols["T_front_bearing"], cols["T_spindle_motor"]
    rng = np.random.default_rng(0)
    cols["E_z"] = 30.0 * ((a - a[0]) - 0.987 * (b - b[0])) + rng.normal(0.0, 0.1, len(a))
    _, s = Machine.identify(_run(cols, "run.csv"))
    (note,) = [n for n in s["notes"] if "cancel" in n]
    assert note.startswith("the drift map's node terms cancel on E_z (") and "µm/K alone swings" in note
    assert "# note: the drift map's node terms cancel on E_z" in s["toml"]


def test_an_axis_held_out_worse_than_no_compensation_is_noted():
    """Where the file's held-out RMS of an axis is above that of predicting no drift at all
    (compensating with it would add error; on the real 46-h run E_ch5, 25.7 against 21.7 µm),
    init says so and names the axis. Here the probe stops seeing the drift over the held-out
    rows (it falls back to zero, with its noise, over ten readings: smoothly enough not to be a
    fault), so the drift the file predicts there is error; with the probe as simulated, or a
    probe that sees only its noise (within the `none` bar), no note."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    cols = dict(c.train)
    # a probe that sees no drift, only its noise: within the `none` bar nothing is said
    cols["E_y"] = np.random.default_rng(1).normal(0.0, 0.1, len(cols["E_z"]))
    _, s = Machine.identify(_run(cols, "run.csv"), axes=["E_z", "E_y"])
    assert not [n for n in s["notes"] if "no compensation" in n]
    cols = dict(c.train)
    k = s["train_rows"]
    fade = np.clip((k + 10 - np.arange(len(cols["E_z"]))) / 10.0, 0.0, 1.0)
    noise = np.random.default_rng(0).normal(0.0, 0.1, len(fade))  # a probe reading zero still has its noise
    cols["E_z"] = np.asarray(cols["E_z"], dtype=float) * fade + (1.0 - fade) * noise
    _, s = Machine.identify(_run(cols, "run.csv"))
    assert not s["suspect_readings"]
    (note,) = [n for n in s["notes"] if "no compensation" in n]
    (ax,) = s["axes"]
    none = float(np.sqrt(np.mean(cols["E_z"][s["train_rows"]:] ** 2)))
    assert ax["holdout_uncompensated_um"] == pytest.approx(none, rel=1e-12)  # the same sum, another order
    assert note.startswith(f"held out, the file predicts E_z ({ax['holdout_rmse_um']:.1f} µm against {none:.1f} µm) "
                           "worse than no compensation at all")
    assert "# note: held out, the file predicts E_z" in s["toml"]


def test_a_probe_spike_in_the_training_rows_does_not_enter_the_drift_map():
    """The drift map for a new run (ridge on the simulated rises, its penalty by blocked folds)
    fits the rows the probe reads: a 500 µm spike on three training rows, a fault, leaves every
    coefficient within 0.01 µm/K of the clean run's (measured: 0.0005 at most). Fitted, three
    rows of 500 µm among 168 move least squares on the same rises by 2-24 µm/K."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    clean, _ = Machine.identify(_run(c.train, "run.csv"))
    cols = dict(c.train)
    e = np.array(cols["E_z"], dtype=float)
    e[50:53] += 500.0
    cols["E_z"] = e
    with pytest.warns(SuspectReadingWarning):
        spiked, s = Machine.identify(_run(cols, "run.csv"))
    assert [r["column"] for r in s["suspect_readings"]] == ["E_z"]
    (a,), (b,) = clean.to_dict()["drift"], spiked.to_dict()["drift"]
    assert a["um_per_k"].keys() == b["um_per_k"].keys()
    for k, v in a["um_per_k"].items():
        assert abs(b["um_per_k"][k] - v) < 0.01, (k, v, b["um_per_k"][k])


def test_a_probe_that_reads_none_of_the_held_out_rows_has_no_held_out_figure(tmp_path, capsys):
    """The probe jumps to zero where the held-out rows begin and stays there: a fault, so none
    of those rows is scored. The file is written and loads (it once held a NaN, which TOML
    refuses), with no held-out figure for the axis; init says so in words."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    _, s = Machine.identify(_run(c.train, "run.csv"))
    cols = dict(c.train)
    e = np.array(cols["E_z"], dtype=float)
    e[s["train_rows"]:] = 0.0
    cols["E_z"] = e
    with pytest.warns(SuspectReadingWarning):
        m, s = Machine.identify(_run(cols, "run.csv"))
    assert s["axes"][0]["holdout_rmse_um"] is None
    assert "E_z" not in m.to_dict()["identified"]["holdout_rmse_um"]
    assert "held-out RMS none (its probe reads none of the held-out rows)" in s["toml"]
    syn.write_run_csv(tmp_path / "run.csv", cols)
    assert main(["init", str(tmp_path / "run.csv"), "--out", str(tmp_path / "m.toml")]) == 0
    assert "held-out RMS none (its probe reads none of the held-out rows)" in capsys.readouterr().out
    Machine.load(tmp_path / "m.toml")


def test_an_input_no_node_sensor_warms_with_is_placed_by_the_cluster_members():
    """With few nodes a node's sensor is its cluster's most typical, often a slow one, and none
    may warm with an input. On the real 46-h run ``--nodes 2`` and ``--nodes 3`` then stopped
    with "no temperature warms with any input", though the spindle warms several sensors. The
    source goes where the members of each node's cluster warm fastest with it. Here (the
    simulated lathe, 2 nodes) the x-axis nut, which the feed heats, sits in the spindle bearing's
    cluster: the feed heats that node, where before it drove no source (held out 1.41 against
    1.81 µm, measured 2026-11-27)."""
    c = syn.make_case("lathe", "none", 2, hours=HOURS, dt=DT_S)
    _, s = Machine.identify(_run(c.train, "run.csv"), nodes=2)
    (node,) = [n for n in s["nodes"] if "T_x_nut" in n["members"]]
    assert node["sensor"] != "T_x_nut" and "U_feed_mm_min" in node["heated_by"]
    assert "no node's own sensor warms with U_feed_mm_min: its heat is placed by the sensors of each node's " \
           "cluster that warm fastest with it" in s["notes"]
    assert not [n for n in s["notes"] if n.startswith("no node warms with")]
    # with the default node count every node's own sensor that warms with an input places it
    _, s = Machine.identify(_run(c.train, "run.csv"))
    assert not [n for n in s["notes"] if "own sensor" in n]


def test_a_full_fit_never_ends_worse_than_the_screen_it_nests():
    # measured: on this identified lathe the full fit of the source from T_hydraulic into the
    # spindle bearing, warm-started from the baseline, stopped in a poorer minimum (ΔBIC +94:
    # a model that contains the baseline fitting the training rows worse than it, and worse than
    # its own screen); the full fit is then searched again from the screen's values
    c = syn.make_case("lathe", "unmodeled_source", 2, hours=HOURS, dt=DT_S)
    train, test = _run(c.train, "train.csv"), _run(c.test, "test.csv")
    ident, _ = Machine.identify(train)
    d = diagnose(train, ident, test)
    full = [x for x in d.report["candidates"]
            if x["fit"] == "full" and x["cause"] == "unmodeled_source" and x["column"] == "T_hydraulic"]
    assert full, [(x["cause"], x.get("column"), x["fit"]) for x in d.report["candidates"]]
    assert all(x["delta_bic"] < 0 for x in full), [(x.get("node"), x["delta_bic"]) for x in full]


def test_a_sensor_that_fails_is_neither_the_room_nor_a_node():
    """A thermocouple that opens a quarter of the way into the run and reads its rail value
    (-200 °C) from then on is the coldest reading of the run: before, identification took it for
    the room and built every node's balance on it. Now a temperature the run shows failing (a
    jump, guard's ``Suspect.fails``) is left out as a spare column, saying why, and the network
    is the one identified without it; given as the ambient, it is used all the same."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    cols = {("T_room" if k == "T_ambient" else k): np.array(v, dtype=float) for k, v in c.train.items()}
    plain, s0 = Machine.identify(_run(cols, "plain.csv"))
    dead = cols["T_cabinet"].copy()
    at = len(dead) // 4
    dead[at:] = -200.0
    broken = dict(cols, T_dead=dead)
    with pytest.warns(SuspectReadingWarning, match="T_dead jumps by up to"):
        m, s = Machine.identify(_run(broken, "broken.csv"))
    assert s0["ambient"]["column"] == "T_room"
    assert s["ambient"]["column"] == "T_room", s["ambient"]
    assert "T_dead" not in m.sensors and m.sensors == plain.sensors
    left = {x.split(":")[0]: x for x in s["spare"]}
    assert f"first at row {at + 1}" in left["T_dead"] and "a sensor fault" in left["T_dead"]
    assert s["axes"][0]["holdout_rmse_um"] == pytest.approx(s0["axes"][0]["holdout_rmse_um"], rel=1e-9)
    # the user's word stands: given as the ambient, the failing column is the ambient
    with pytest.warns(SuspectReadingWarning):
        _, s2 = Machine.identify(_run(broken, "broken.csv"), ambient="T_dead")
    assert s2["ambient"]["column"] == "T_dead" and "T_dead" not in {x.split(":")[0] for x in s2["spare"]}



def test_identification_times_its_stages_and_draws_a_bar_when_asked(capsys, tmp_path):
    """On a 1-Hz log of days `init` runs for seconds with nothing on screen: the summary now has
    each stage's wall time in the order they ran, the command line says them, and a terminal gets
    a bar of the stages (the core counts them for the binding's callback, which sees every stage
    done, never more than planned)."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    run = _run(c.train, "train.csv")
    seen = []
    _, text = tr._core.MachineModel.identify(*tr.thermal._run_args(run), None, progress=lambda *a: seen.append(a))
    s = json.loads(text)
    assert list(s["stage_s"]) == ["screening", "structure", "calibration_and_checks", "drift_maps"]
    assert all(v >= 0.0 for v in s["stage_s"].values())
    assert seen and seen[-1] == (4, 4, 4), seen
    assert all(done <= planned for done, planned, _ in seen)
    Machine.identify(run, progress=True)
    err = capsys.readouterr().err
    assert "identification, stage" in err and "stage" in err
    Machine.identify(run, progress=False)
    assert capsys.readouterr().err == ""
    path = tmp_path / "train.csv"
    np.savetxt(path, np.column_stack(list(c.train.values())), delimiter=",", header=",".join(c.train), comments="")
    assert main(["init", str(path), "--out", str(tmp_path / "m.toml")]) == 0
    err = capsys.readouterr().err
    assert "identified in " in err and "screening" in err and "drift maps" in err, err


def test_a_node_sensor_with_a_short_spike_stays_a_node_sensor():
    """A thermocouple's glitch: two readings at the rail (-200 °C) in the middle of the run, then
    right again. Before, any jump made the column fail, and the network lost the sensor of the
    node the spindle heats for two rows of 241. Now a temperature whose every failing stretch
    comes back within 600 s (guard's ``short_failures``, the gap a log may have unsaid) is
    bridged by a straight line for identification and stays a node's sensor; the spike is still
    said. Measured on the simulated VMC (seed 1): the same sensors, held out 0.3285 µm against
    0.3304 µm on the clean run (each node sensor spiked in turn: 0.327-0.330), so 5 % bounds a
    straight line over two rows. Out for longer than that (6 rows, 840 s), it fails as before."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    cols = {k: np.array(v, dtype=float) for k, v in c.train.items()}
    plain, s0 = Machine.identify(_run(cols, "plain.csv"))
    assert "T_front_bearing" in plain.sensors
    y = cols["T_front_bearing"].copy()
    at = len(y) // 3
    y[at:at + 2] = -200.0
    with pytest.warns(SuspectReadingWarning, match="T_front_bearing jumps by up to"):
        m, s = Machine.identify(_run(dict(cols, T_front_bearing=y), "spike.csv"))
    assert m.sensors == plain.sensors
    assert "T_front_bearing" not in {x.split(":")[0] for x in s["spare"]}
    said = [x for x in s["notes"] if x.startswith("T_front_bearing: 1 short spike")]
    assert said and f"2 rows, first at row {at + 1}" in said[0] and "bridged" in said[0], s["notes"]
    assert s["axes"][0]["holdout_rmse_um"] == pytest.approx(s0["axes"][0]["holdout_rmse_um"], rel=0.05)
    # six rows out (840 s from the last right reading to the next): a sensor fault, left out
    y[at:at + 6] = -200.0
    with pytest.warns(SuspectReadingWarning):
        m, s = Machine.identify(_run(dict(cols, T_front_bearing=y), "long.csv"))
    assert "T_front_bearing" not in m.sensors
    assert "a sensor fault" in {x.split(":")[0]: x for x in s["spare"]}["T_front_bearing"]


def test_a_run_without_inputs_is_driven_by_its_hottest_temperature(tmp_path):
    """A logger that recorded temperatures and probes but no spindle speed: before, init stopped
    ("the run has no input column: nothing would heat the network"). Now the temperature that
    rises most over the ambient drives the network as a boundary node, linked to the nodes that
    warm first with it, and everything else is identified as with an input. On the simulated
    VMC (its heat enters at the front bearing) that is ``T_front_bearing``; held out, the file
    leaves a small part of the drift (measured 1.2 of 32 µm on seed 1). From the command line
    the file loads back and the diagnosis runs on it."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    cols = {k: v for k, v in c.train.items() if not k.startswith("U_")}
    m, s = Machine.identify(_run(cols, "nou.csv"))
    d = m.to_dict()
    assert [n["boundary"] for n in d["nodes"] if n.get("boundary")] == ["T_front_bearing"]
    assert d["sources"] == []
    assert any(sorted(l["between"]) == sorted(["front_bearing", x["name"]])
               for l in d["links"] for x in d["nodes"] if x.get("sensor")), d["links"]
    assert any("no input column" in x and "T_front_bearing" in x for x in s["notes"]), s["notes"]
    assert "boundary = \"T_front_bearing\"" in s["toml"] and "[[sources]]" not in s["toml"]
    ax = s["axes"][0]
    assert ax["holdout_rmse_um"] < 0.1 * ax["holdout_uncompensated_um"], ax
    # as a user does it: a CSV without U_ columns, init, then diagnose with the file
    train = tmp_path / "train.csv"
    test = tmp_path / "test.csv"
    for path, part in ((train, c.train), (test, c.test)):
        keep = [k for k in part if not k.startswith("U_")]
        np.savetxt(path, np.column_stack([part[k] for k in keep]), delimiter=",",
                   header=",".join(keep), comments="")
    toml = tmp_path / "m.toml"
    assert main(["init", str(train), "--out", str(toml)]) == 0
    assert main(["diagnose", str(train), "--machine", str(toml), "--holdout", str(test),
                 "--out", str(tmp_path / "d")]) == 0
    rep = json.loads((tmp_path / "d" / "report.json").read_text())
    assert rep["identification"]["driven_by"] == "T_front_bearing", rep.get("identification")
    assert "so T_front_bearing drives the network" in (tmp_path / "d" / "report.html").read_text()
    # the Python result says it too; a file identified with its inputs does not
    d = diagnose(_run(cols, "nou.csv"), Machine.load(toml), progress=False)
    assert "no input column, so T_front_bearing drives the network" in str(d)
    assert "no input column" not in str(diagnose(_run(c.train, "u.csv"), Machine.identify(_run(c.train, "u.csv"))[0],
                                                 progress=False))


def test_a_sensor_dead_in_every_row_is_neither_the_room_nor_a_node():
    """A thermocouple open for the whole run reads its rail value (-200 °C) in every row: no jump
    shows it failing, and before it was the coldest reading, so identification took it for the
    room (on the real 46-h run with ``T_t3`` so: "no temperature warms with any input", no file
    at all). A column with one reading in every row (guard's ``constant``) is now left out as a
    spare column, as a jumping one is, and the network is the one identified without it."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    cols = {("T_room" if k == "T_ambient" else k): np.array(v, dtype=float) for k, v in c.train.items()}
    plain, s0 = Machine.identify(_run(cols, "plain.csv"))
    broken = dict(cols, T_dead=np.full(len(cols["time_s"]), -200.0))
    with pytest.warns(SuspectReadingWarning, match=r"T_dead reads one value \(-200\) in every row"):
        m, s = Machine.identify(_run(broken, "broken.csv"))
    assert s["ambient"]["column"] == "T_room", s["ambient"]
    assert "T_dead" not in m.sensors and m.sensors == plain.sensors
    left = {x.split(":")[0]: x for x in s["spare"]}
    assert "reads one value in every row" in left["T_dead"] and "a sensor fault" in left["T_dead"]
    assert s["axes"][0]["holdout_rmse_um"] == pytest.approx(s0["axes"][0]["holdout_rmse_um"], rel=1e-9)
    kinds = {(x["column"], x["kind"]) for x in s["suspect_readings"]}
    assert ("T_dead", "constant") in kinds, kinds
    # a room named by convention that reads one value throughout is a climate-controlled room on
    # a coarse logger as likely as a dead sensor: it stays the room (before this rule it was too)
    still = dict(c.train, T_ambient=np.full(len(cols["time_s"]), 20.0))
    with pytest.warns(SuspectReadingWarning, match="climate-controlled room"):
        _, s3 = Machine.identify(_run(still, "lab.csv"))
    assert s3["ambient"]["column"] == "T_ambient", s3["ambient"]


LONG_INIT = textwrap.dedent("""\
    import sys, numpy as np, thermerr_rs as tr
    from thermerr_rs import synthetic as syn
    c = syn.make_shop_case(1, hours=46.0, dt=15.0)
    t = np.arange(0.0, c.train["time_s"][-1] + 1.0, 1.0)  # every second, as a fast logger writes
    cols = {k: (t if k == "time_s" else np.interp(t, c.train["time_s"], v)) for k, v in c.train.items()}
    run = tr.Run.from_frame(cols, source="long.csv")
    print("ready", flush=True)
    try:
        tr.Machine.identify(run)
    except KeyboardInterrupt:
        print("interrupted", flush=True)
        sys.exit(130)
    print("finished", flush=True)
    """)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process")
def test_ctrl_c_stops_init_on_a_long_run():
    """A 46-h run at 1 s (165 600 rows, 16 temperatures): the pairwise lagged-copy fits and the
    first-order fits ran for tens of seconds without looking for Ctrl-C (measured: stopped 24.8 s
    after it on the simulated shop, 20-28 s on the real run resampled to 1 s); now within a
    fraction of a second (0.14 s). The bound leaves room for a loaded CI machine."""
    p = subprocess.Popen([sys.executable, "-c", LONG_INIT], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    out, err, waited = ctrl_c(p, 3.0, 60)  # 3 s: inside the screening of the columns
    assert p.returncode == 130 and "interrupted" in out, (out, err)
    assert waited < 10, waited


def test_a_part_no_sensor_reads_is_tried_behind_the_slowest_node(tmp_path, capsys):
    """The synthetic VMC's bed carries no sensor and sits behind its column. Identification
    tries a node no sensor reads behind the slowest calibrated node and keeps it when the
    training BIC falls and its time constant is within the training rows: on the 8-h run it is
    kept behind the column (about 2.2 h on 5.6 h of training rows), with no drift term of its
    own, written last among the nodes with its comment, printed by init. On a 2-h run it would
    take about 4 h on 1.4 h of training rows: not kept, and the note says why."""
    c = syn.make_case("vmc", "none", 1, hours=HOURS, dt=DT_S)
    m, s = Machine.identify(_run(c.train, "run.csv"))
    u = s["unsensed"]
    span = c.train["time_s"][s["train_rows"] - 1] - c.train["time_s"][0]
    assert u["kept"] and u["linked_to"] == "column" and 0 < u["tau_s"] <= span, u
    assert u["ssr_with"] < u["ssr_without"]
    d = m.to_dict()
    assert m.nodes[-1] == u["name"] and "sensor" not in d["nodes"][-1]
    assert [sorted(x["between"]) for x in d["links"] if u["name"] in x["between"]] == [sorted(["column", u["name"]])]
    assert all(u["name"] not in x["um_per_k"] for x in d["drift"])
    assert f"# {u['name']}: a part no sensor reads, behind column (the slowest node)" in s["toml"]
    assert Machine.from_toml(s["toml"]).to_dict()["nodes"] == d["nodes"]
    short = syn.make_case("vmc", "none", 1, hours=(2.0, 1.0), dt=60.0)
    _, s2 = Machine.identify(_run(short.train, "short.csv"))
    assert not s2["unsensed"]["kept"]
    assert any("was tried and not kept: its calibrated time constant" in n and "longer than the training rows" in n
               for n in s2["notes"]), s2["notes"]
    run = tmp_path / "run.csv"
    syn.write_run_csv(run, c.train)
    assert main(["init", str(run), "--out", str(tmp_path / "m.toml")]) == 0
    assert f"{u['name']}" in capsys.readouterr().out.split("no sensor: a part behind column")[0].splitlines()[-1]


def test_the_part_no_sensor_reads_is_refined_from_its_guess_not_identified_again():
    """The unsensed node starts from a physical guess (3x the slowest node's capacity, its ambient
    conductance to the room and as the link) beside a network calibrated already, so it is
    calibrated within a diagnosis's bounds and prior (a factor 3, a factor 2 as one σ), not
    identification's factor 10. On the 8-h VMC with nothing hidden, seed 5, the factor 10 took
    it from τ = 1.7 h to 13.5 h on 5.6 h of training rows (the true bed: 2.6 h): not kept, and
    the diagnosis's baseline then missed the held-out run by 1.18 µm (its ``T_column`` by
    0.49 K while the room fell 1.7 K). Refined, it settles at 3.1 h and is kept, and the
    baseline misses by 0.41 µm (the nominal TOML: 0.26; noise 0.17, so still ``unexplained``
    there: what the sweep counts, 61/80 on seeds 1-8, is in the module docstring)."""
    c = syn.make_case("vmc", "none", 5, hours=HOURS, dt=DT_S)
    bed = next(n for n in c.truth["nodes"] if n["name"] == "bed")
    g = bed["ambient_w_per_k"] + sum(x["w_per_k"] for x in c.truth["links"] if "bed" in x["between"])
    true_tau = bed["capacity_j_per_k"] / g
    train, test = _run(c.train, "train.csv"), _run(c.test, "test.csv")
    m, s = Machine.identify(train)
    u = s["unsensed"]
    assert u["kept"] and u["linked_to"] == "column", u
    # within the factor of a diagnosis's prior of the true bed (measured 1.19x; 5.3x before)
    assert true_tau / 2 < u["tau_s"] < true_tau * 2, (u["tau_s"], true_tau)
    d = diagnose(train, m, test)
    assert d.report["baseline"]["rmse_um"] < 1.18 / 2, d.report["baseline"]


def test_a_separate_holdout_run_trains_on_every_row_and_is_scored_from_its_first_readings(tmp_path):
    """``holdout=`` (``thermerr init --holdout``): the held-out figures are of the other run,
    simulated by the written file from that run's first readings, as any run is; every row of
    the training run trains. A held-out run that continues the training run is its tail."""
    c = syn.make_case("vmc", "none", 1, hours=(8, 4), dt=120.0)
    train = tr.Run.from_frame(c.train, source="train")
    test = tr.Run.from_frame(c.test, source="test")
    m, s = Machine.identify(train, holdout=test)
    assert (s["train_rows"], s["holdout_rows"], s["holdout_run"]) == (len(train), len(test), "test")
    back = Machine.from_toml(s["toml"])
    assert back.to_dict()["identified"]["holdout_run"] == "test"
    # the figure a user recomputes: the file simulated on the held-out run against its probe
    e = test.matrix(["E_z"])[:, 0]
    pred = back.simulate(test).drift["E_z"]
    got = s["axes"][0]["holdout_rmse_um"]
    assert got == pytest.approx(float(np.sqrt(np.mean((pred - e) ** 2))), rel=1e-6)
    assert s["axes"][0]["holdout_uncompensated_um"] == pytest.approx(float(np.sqrt(np.mean(e**2))), rel=1e-9)
    # a run cut in two: the second piece is held out as the tail of one run
    n, k = len(train), int(0.7 * len(train))
    head = tr.Run.from_frame({name: np.asarray(v)[:k] for name, v in c.train.items()}, source="head")
    tail = tr.Run.from_frame({name: np.asarray(v)[k:] for name, v in c.train.items()}, source="tail")
    _, whole = Machine.identify(train)
    _, cut = Machine.identify(head, holdout=tail)
    assert cut["holdout_run"] is None and (cut["train_rows"], cut["holdout_rows"]) == (k, n - k)
    assert whole["train_rows"] == k
    assert [a["holdout_rmse_um"] for a in cut["axes"]] == pytest.approx(
        [a["holdout_rmse_um"] for a in whole["axes"]], rel=1e-9)
    # a held-out run without a column the network reads: one line naming it
    short = tr.Run.from_frame({k2: v for k2, v in c.test.items() if k2 != "T_column"}, source="short")
    with pytest.raises(DataError, match="short"):
        Machine.identify(train, holdout=short)
    # the command line
    for name, part in (("train", c.train), ("test", c.test)):
        cols = list(part)
        np.savetxt(tmp_path / f"{name}.csv", np.column_stack([np.asarray(part[k2]) for k2 in cols]),
                   delimiter=",", header=",".join(cols), comments="")
    out = tmp_path / "m.toml"
    r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", "init", str(tmp_path / "train.csv"),
                        "--holdout", str(tmp_path / "test.csv"), "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "E_z: training RMS" in r.stdout and f"({tmp_path / 'test.csv'}, {len(test)} rows;" in r.stdout, r.stdout
    assert Machine.load(out).to_dict()["identified"]["holdout_run"] == str(tmp_path / "test.csv")
    # a log cut in two, on the command line: said, and held out as the tail
    for name, sl in (("head", slice(0, k)), ("tail", slice(k, n))):
        cols = list(c.train)
        np.savetxt(tmp_path / f"{name}.csv", np.column_stack([np.asarray(c.train[k2])[sl] for k2 in cols]),
                   delimiter=",", header=",".join(cols), comments="")
    r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", "init", str(tmp_path / "head.csv"),
                        "--holdout", str(tmp_path / "tail.csv"), "--out", str(tmp_path / "cut.toml")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "tail.csv continues " in r.stdout + r.stderr and f"(last {n - k} rows;" in r.stdout, r.stdout + r.stderr


def test_the_file_keeps_the_fit_whose_drift_maps_predict_the_training_folds_better():
    """Step 8, "Which fit": the network calibrated with the first axis and the one calibrated
    on the temperatures alone; the file keeps the one whose drift maps predict the probes
    better across blocked folds of the training rows, says so in a note, and reports both."""
    c = syn.make_shop_case(1, hours=12.0)
    run = tr.Run.from_frame(c.train, source="shop")
    m, s = Machine.identify(run)
    f = s["network_fit"]
    axes = [a["axis"] for a in s["axes"]]
    assert f["axis"] == axes[0]
    for k in ("with_axis", "temperatures"):
        # per axis a share of its squares, summed: between exact and no better than zero drift
        assert 0.0 < f[k] < len(axes), f
    assert f["kept"] == ("temperatures" if f["temperatures"] < f["with_axis"] else "axis"), f
    kept = "calibrated on the temperatures alone" if f["kept"] == "temperatures" else f"calibrated with {axes[0]}"
    assert any(n.startswith(f"the network's values are the ones {kept}") for n in s["notes"]), s["notes"]
    assert f"the network's values are the ones {kept}" in s["toml"]
    # the same run gives the same choice
    assert Machine.identify(run)[1]["network_fit"] == f


def test_a_holdout_with_the_training_runs_own_rows_is_refused(tmp_path):
    """A held-out run that is the training run (its file, or a copy) would report the training
    fit as held out: init, diagnose and fit refuse it in one line, exit 2, nothing written."""
    c = syn.make_case("vmc", "none", 1, hours=(4, 2), dt=120.0)
    train = tr.Run.from_frame(c.train, source="train")
    copy = tr.Run.from_frame(c.train, source="copy")
    with pytest.raises(DataError, match="copy: rows 1-[0-9]+ are rows 1-[0-9]+ of train"):
        Machine.identify(train, holdout=copy)
    with pytest.raises(DataError, match="copy: rows 1-[0-9]+ are rows 1-[0-9]+ of train"):
        diagnose(train, Machine.from_toml(c.nominal_toml()), copy)
    cols = list(c.train)
    path = tmp_path / "run.csv"
    np.savetxt(path, np.column_stack([np.asarray(c.train[k]) for k in cols]), delimiter=",",
               header=",".join(cols), comments="")
    (tmp_path / "m.toml").write_text(c.nominal_toml())
    for argv in (["init", str(path), "--holdout", str(path), "--out", str(tmp_path / "o.toml")],
                 ["diagnose", str(path), "--machine", str(tmp_path / "m.toml"), "--holdout", str(path),
                  "--out", str(tmp_path / "d")],
                 ["fit", str(path), "--axis", "E_z", "--model", "mlr", "--test", str(path),
                  "--out", str(tmp_path / "o.json")]):
        r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", *argv], capture_output=True, text=True)
        assert r.returncode == 2, (argv, r.stderr)
        assert "is the training run" in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.toml", "run.csv"]


def test_a_held_out_run_whose_probes_start_away_from_zero_is_said():
    """A separate held-out run is predicted from its start, where the drift is 0: a run whose
    probe reads 20 µm there (a log cut in two with its clock restarted, a probe not zeroed)
    counts that against the file on every row, and a suspect reading of kind `start` says so,
    naming the axis and the reading; a run of its own, zeroed at its start, draws none."""
    c = syn.make_case("vmc", "none", 1, hours=(4, 2), dt=120.0)
    train = tr.Run.from_frame(c.train, source="train")
    _, s = Machine.identify(train, holdout=tr.Run.from_frame(c.test, source="test"))
    assert not any(sp["kind"] == "start" for sp in s["suspect_readings"]), s["suspect_readings"]
    shifted = {k: (np.asarray(v) + 20.0 if k == "E_z" else v) for k, v in c.test.items()}
    with pytest.warns(SuspectReadingWarning, match="warm: E_z reads"):
        _, s = Machine.identify(train, holdout=tr.Run.from_frame(shifted, source="warm"))
    start = [sp for sp in s["suspect_readings"] if sp["kind"] == "start"]
    assert [(sp["column"], sp["row"]) for sp in start] == [("E_z", 1)], s["suspect_readings"]
    assert abs(start[0]["size"] - 20.0) < 0.5, start  # 20 µm and the first reading's noise
    note = [n for n in s["notes"] if "start" in n and n.startswith("suspect reading: warm: E_z reads ")]
    assert len(note) == 1 and "a run's drift is predicted from its start, where it is 0" in note[0], s["notes"]


def _refused_as_held_out(train, held, tmp_path) -> list[str]:
    """``held`` given as the held-out run of ``train`` to init, diagnose (with ``tmp_path``'s
    m.toml) and fit: each exits 2 with one error line, which are returned."""
    lines = []
    for argv in (["init", str(train), "--holdout", str(held), "--out", str(tmp_path / "o.toml")],
                 ["diagnose", str(train), "--machine", str(tmp_path / "m.toml"), "--holdout", str(held), "--out",
                  str(tmp_path / "d")],
                 ["fit", str(train), "--axis", "E_z", "--model", "mlr", "--test", str(held), "--out",
                  str(tmp_path / "o.json")]):
        r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", *argv], capture_output=True, text=True)
        assert r.returncode == 2, (argv, r.stderr)
        err = [line for line in r.stderr.splitlines() if line.startswith("thermerr: error:")]
        assert len(err) == 1, r.stderr
        lines.append(err[0])
    return lines


def test_a_holdout_cut_from_the_training_run_is_refused(tmp_path):
    """A held-out run cut from the training run's log (its tail, the clock kept or restarted)
    holds rows the fit trains on: init, diagnose and fit --test refuse it in one line naming
    both files and the rows, exit 2, before anything is fitted and with nothing written; a run
    of its own from the same machine is not refused; nor is the piece evaluated "after" the log
    it was cut from."""
    c = syn.make_case("vmc", "none", 1, hours=(4, 2), dt=120.0)
    cols = list(c.train)
    whole = np.column_stack([np.asarray(c.train[k]) for k in cols])
    tail = whole[60:].copy()
    tail[:, cols.index("time_s")] -= tail[0, cols.index("time_s")]  # the clock restarted
    paths = {}
    for name, data in (("run", whole), ("tail", tail), ("other", np.column_stack(
            [np.asarray(c.test[k]) for k in cols]))):
        paths[name] = tmp_path / f"{name}.csv"
        np.savetxt(paths[name], data, delimiter=",", header=",".join(cols), comments="")
    train = tr.Run.from_frame(c.train, source="run")
    piece = tr.Run.from_frame({k: tail[:, i] for i, k in enumerate(cols)}, source="tail")
    n = len(whole)
    with pytest.raises(DataError, match=f"^tail: rows 1-{n - 60} are rows 61-{n} of run "):
        Machine.identify(train, holdout=piece)
    # another run of the same machine, on the same duty: no refusal
    tr.Run.from_frame(c.test, source="other").check_unseen(train)
    (tmp_path / "m.toml").write_text(c.nominal_toml())
    for err in _refused_as_held_out(paths["run"], paths["tail"], tmp_path):
        assert f"tail.csv: rows 1-{n - 60} are rows 61-{n} of {paths['run']}" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.toml", "other.csv", "run.csv", "tail.csv"]
    # a model evaluated on the piece "after" the log it was cut from: its rows would count twice
    model = tmp_path / "model.json"
    fit = ["fit", str(paths["run"]), "--axis", "E_z", "--model", "mlr", "--no-guard", "--out", str(model)]
    subprocess.run([sys.executable, "-m", "thermerr_rs.cli", *fit], capture_output=True, check=True)
    r = subprocess.run([sys.executable, "-m", "thermerr_rs.cli", "evaluate", str(model), str(paths["tail"]),
                        "--after", str(paths["run"])], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith(f"thermerr: error: {paths['tail']}: rows 1-"), r.stderr


def test_rows_taken_from_the_training_log_in_turn_are_refused_as_held_out(tmp_path):
    """The classic split of a table (odd rows to train, even rows to test, or every third row
    held out) validates a time series out of time order: each held-out row has training rows on
    either side, a sampling step away, so its "held-out" figures are nearly training figures (under
    init the real 46-h run's odd rows held out E_ch5 to 4.69 µm, training 4.61, where its last
    30 % held out 19.9). Its
    rows are not the training run's, so they are not shared rows: they sit between the training
    run's on its clock and read as they do within three typical steps in every column. init,
    diagnose and fit --test refuse it in one line, exit 2, nothing written; ``diagnose(...,
    holdout=)`` raises the same ``DataError``. The synthetic test run (its own duty, the same
    clock from 0) is not refused, as in the test above."""
    c = syn.make_case("vmc", "none", 1, hours=(8, 4), dt=60.0)
    cols = list(c.train)
    whole = np.column_stack([np.asarray(c.train[k]) for k in cols])
    paths = {}
    for name, data in (("even", whole[::2]), ("odd", whole[1::2]), ("two", whole[np.arange(len(whole)) % 3 != 2]),
                       ("third", whole[2::3])):
        paths[name] = tmp_path / f"{name}.csv"
        np.savetxt(paths[name], data, delimiter=",", header=",".join(cols), comments="")
    even, odd = tr.read_run(paths["even"]), tr.read_run(paths["odd"])
    with pytest.raises(DataError, match=r"odd.csv: \d+ of its \d+ rows .* fall between rows .* of .*even.csv on its clock"):
        diagnose(even, Machine.from_toml(c.nominal_toml()), odd)
    with pytest.raises(DataError, match="rows taken from the training log in turn"):
        tr.read_run(paths["third"]).check_unseen(tr.read_run(paths["two"]))
    tr.Run.from_frame(c.test, source="other").check_unseen(even)  # a run of its own: not refused
    (tmp_path / "m.toml").write_text(c.nominal_toml())
    for err in _refused_as_held_out(paths["even"], paths["odd"], tmp_path):
        assert "rows taken from the training log in turn" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["even.csv", "m.toml", "odd.csv", "third.csv", "two.csv"]
