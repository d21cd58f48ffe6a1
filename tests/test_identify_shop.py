"""``thermerr init`` then ``thermerr diagnose`` on a run shaped like a real one with nothing hidden
(issue 15 points 1 and 2: no false alarm): the 46-h shop run at 15 s, sixteen temperatures, no
column named as the room, five probe channels (``synthetic.make_shop_case``, seeds 2 and 3).

The identified 3-node network does not fit such a run to the probe noise (held-out 0.5-1.7 µm
against 0.30 µm), so on most axes the honest answer is ``unexplained`` (or ``none``), not a
cause. Measured on 2026-11-25: no cause named on the 10 axes. Before, scoring the tail from a
start re-estimated from the run's first 20 readings named one on all 10 (its slow nodes started
up to 2 K off); from the calibration's start, ``sensor_drift`` was still named on 3 (held-out
gains of 3-15 %) on sensors whose part-mates in the run drift with them (``T_t13`` and the bed's
``T_t5``: the trend of their difference is -0.0009 K/h against a fitted -0.027 K/h), which the
diagnosis now refuses. The bar is the measured figure: a cause named where none is hidden fails
here and must be looked at."""

from __future__ import annotations

import warnings

import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.thermal import Machine, diagnose_axes

SEEDS = (2, 3)
NAMED_AT_MOST = 0


@pytest.fixture(scope="module")
def verdicts():
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for seed in SEEDS:
            run = tr.Run.from_frame(syn.make_shop_case(seed, hidden={}).train, source=f"shop{seed}.csv")
            machine, _ = Machine.identify(run)
            d = diagnose_axes(run, machine)
            for a in d.axes:
                out[(seed, a)] = d[a]
    return out


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
