"""``thermerr init`` then ``thermerr diagnose`` on a run shaped like a real one (issue 15 points 1
and 2): the 46-h shop run at 15 s, sixteen temperatures, no column named as the room, five probe
channels (``synthetic.make_shop_case``, seeds 2 and 3). Eight of the sixteen temperatures are
second sensors on a part, each a few minutes behind the part's first sensor.

Identification recognises them as lagged copies (a first-order lag of another temperature within
3 noise levels at a gain near 1) and builds its nodes on the parts' first sensors; it calibrates
three trees (the fastest node's first link as the links' rule picks it, and the next two
candidates) and keeps the best fit (since 2026-11-29 also the trees with a later link moved, kept
only at a 5x better fit: never on these runs, so the figures below hold). Measured on 2026-11-25 (seeds 1-4, 60 axes, per seed nothing
hidden / three effects / two effects; the nominal TOML of the true network gets 54 of 60):

=================================================  ==============  ==============================
identified network                                 right verdicts  causes named where none hidden
=================================================  ==============  ==============================
3 nodes, lagged copies as sensors (before)         9 of 60         0
5 nodes on the first sensors, the rule's tree      42 of 60        0
the same, the best of three trees (now)            54 of 60        0
=================================================  ==============  ==============================

The rule's tree linked the bearing to the bed on seed 1 (``unexplained`` on all 15 axes, held
out 0.6-1.2 µm); there the diagnosis had named ``unmodeled_source`` from ``T_t10`` (a lagged copy
of the motor's ``T_t2``, r = 0.988 with it) on 4 axes until it took a lagged copy of a node's
sensor for that part. The misses now are the nominal's: weak nonlinear expansions and two weak
speed growths (held out 0.34-0.46 µm, under the ``none`` bar of 2x the 0.30 µm noise).
Held out with nothing hidden, the identified network leaves 0.30-0.55 µm on seeds 1-10 (it was
0.43-1.40 µm on seeds 1-3). With nothing hidden no cause is named on seeds 2 and 3, and with
three effects hidden every one is named on its axis and the other two axes say ``none``. The
bars are the measured figures: a miss fails here and must be looked at."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.thermal import Machine, diagnose_axes

SEEDS = (2, 3)
NAMED_AT_MOST = 0


HIDDEN = {"E_ch1": "speed_growth", "E_ch3": "ambient_coupling", "E_ch4": "thermal_lag"}


def _identified(seed, hidden):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = tr.Run.from_frame(syn.make_shop_case(seed, hidden=hidden).train, source=f"shop{seed}.csv")
        machine, summary = Machine.identify(run)
        return run, machine, summary, diagnose_axes(run, machine)


@pytest.fixture(scope="module")
def identified():
    return {seed: _identified(seed, {}) for seed in SEEDS}


@pytest.fixture(scope="module")
def verdicts(identified):
    return {(seed, a): d[a] for seed, (_, _, _, d) in identified.items() for a in d.axes}


def test_second_sensors_join_their_part(identified):
    first = {}
    for col, part in syn.SHOP_SENSORS.items():
        first.setdefault(part, col)
    for seed, (_, machine, s, _) in identified.items():
        # the nodes carry the five parts' first sensors, not a lagged copy
        assert sorted(machine.sensors, key=lambda c: int(c[3:])) == ["T_t1", "T_t2", "T_t3", "T_t4", "T_t5"], seed
        copies = {c["column"]: c["of"] for c in s["copies"]}
        want = {c: first[p] for c, p in syn.SHOP_SENSORS.items() if first.get(p) != c and p not in ("room", "cabinet", "hydraulic")}
        assert copies == want, seed
        # the copies are named in the file and listed under their node
        assert "# second sensor: T_t9 follows T_t1" in s["toml"]
        t1 = next(n for n in s["nodes"] if n["sensor"] == "T_t1")
        assert set(t1["members"]) == {"T_t1", "T_t9", "T_t16"}
        # held out within the diagnosis's `none` bar (2x the probe noise) on every axis
        for a in s["axes"]:
            assert a["holdout_rmse_um"] <= 2.0 * a["noise_um"], (seed, a)


def test_hidden_effects_are_named_on_the_identified_network():
    for seed in SEEDS:
        _, _, _, d = _identified(seed, HIDDEN)
        got = {a: d[a].verdict for a in d.axes}
        assert got == {a: HIDDEN.get(a, "none") for a in d.axes}, (seed, got)


def test_nothing_hidden_names_few_causes(verdicts):
    named = {k: d.verdict for k, d in verdicts.items() if d.verdict not in ("none", "unexplained")}
    assert len(verdicts) == 5 * len(SEEDS)
    assert len(named) <= NAMED_AT_MOST, named


def test_what_the_identified_network_leaves_is_reported(verdicts):
    for (seed, a), d in verdicts.items():
        noise = d.report["noise_um"]
        if d.verdict == "unexplained":
            assert d.remainder_um > 0.0, (seed, a)
        if d.verdict == "none":
            # `none` only where the held-out error is within the rule's 2x the probe noise
            assert d.report["baseline"]["rmse_um"] <= 2.0 * noise, (seed, a)


def test_a_drifting_sensor_is_still_named_beside_its_part_mates():
    """The part-mate check refuses a drift the sensor's mates share; it must not refuse a real
    one. T_t1 (the front bearing's first sensor, a node sensor of the nominal machine; T_t9 and
    T_t16 sit on the same part) drifts 0.04 K/h over a 24-h run."""
    c = syn.make_shop_case(5, hours=24.0, hidden={})
    cols = dict(c.train)
    cols["T_t1"] = cols["T_t1"] + 0.04 * cols["time_s"] / 3600.0
    from thermerr_rs.thermal import diagnose

    d = diagnose(tr.Run.from_frame(cols, source="drift.csv"), Machine.from_toml(c.nominal_toml()), axis="E_ch1")
    assert (d.verdict, d.column) == ("sensor_drift", "T_t1"), d.evidence
    named = next(x for x in d.candidates if x["cause"] == "sensor_drift" and x["column"] == "T_t1")
    assert named["parameters"]["k_per_h"] == pytest.approx(0.04, rel=0.05)
    # the drift takes T_t1 off its mates' curve (r < 0.99), so there is nothing for them to contradict
    assert named.get("mates") is None or named["mates"]["corroborate"]


def test_a_lagged_copy_of_a_node_sensor_is_not_an_unmodelled_source():
    """``T_t10`` is a copy of the motor's ``T_t2`` 5-15 min behind it (r = 0.988 on so fast a
    part, under the r >= 0.99 of the part-mate rule). When seed 1's identified tree lacked the
    motor's link, it stood in for it as an unmodelled source on 4 axes. It is the motor read
    twice: refused, reported as ``mate_of``."""
    _, machine, s, d = _identified(1, {})
    assert "T_t2" in machine.sensors and {"column": "T_t10", "of": "T_t2"}.items() <= next(
        c for c in s["copies"] if c["column"] == "T_t10").items()
    named = {a: d[a].verdict for a in d.axes if d[a].verdict not in ("none", "unexplained")}
    assert named == {}
    t10 = [c for a in d.axes for c in d[a].candidates if c["cause"] == "unmodeled_source" and c["column"] == "T_t10"]
    assert t10 and all(c["mate_of"] == "T_t2" for c in t10)


def test_a_logger_that_rounds_to_a_tenth_of_a_kelvin():
    """The same run with every temperature rounded to 0.1 K, as many loggers write it. The
    median absolute second difference read 0.061 K of noise on every rounded column (the
    readings' true error is 0.042 K) and 0 on slow ones: the cabinet passed the screening and
    became a node, a headstock sensor was screened out, and the network held out 9-13 µm.
    Identification's noise (the trimmed RMS of second differences, at least the quantisation's
    RMS) gives the unrounded run's network."""
    c = syn.make_shop_case(2, hidden={})
    cols = {k: (np.round(v, 1) if k.startswith("T_") else v) for k, v in c.train.items()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        machine, s = Machine.identify(tr.Run.from_frame(cols, source="rounded.csv"))
    assert sorted(machine.sensors) == ["T_t1", "T_t2", "T_t3", "T_t4", "T_t5"]
    assert len(s["copies"]) == 8
    assert sorted(x.split(":")[0] for x in s["spare"]) == ["T_t7", "T_t8"]
    for a in s["axes"]:
        assert a["holdout_rmse_um"] <= 2.0 * a["noise_um"], a
