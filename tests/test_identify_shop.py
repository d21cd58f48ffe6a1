"""``thermerr init`` then ``thermerr diagnose`` on a run shaped like a real one with nothing hidden
(issue 15 points 1 and 2: no false alarm): the 46-h shop run at 15 s, sixteen temperatures, no
column named as the room, five probe channels (``synthetic.make_shop_case``, seeds 2 and 3).

The identified 3-node network does not fit such a run to the probe noise (held-out 0.5-1.7 µm
against 0.30 µm), so on most axes the honest answer is ``unexplained`` (or ``none``), not a
cause. Measured on 2026-11-25: a cause named on 3 of the 10 axes (``sensor_drift`` with a held-out
gain of 3-15 %), where scoring the tail from a start re-estimated from the run's first 20
readings (before 912746f) named one on all 10 (its slow nodes started up to 2 K off). The bar is the measured
figure: more causes named where none is hidden fails here and must be looked at."""

from __future__ import annotations

import warnings

import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.thermal import Machine, diagnose_axes

SEEDS = (2, 3)
NAMED_AT_MOST = 3


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
