"""Several effects at once (issue 15 point 2): the diagnosis goes on in rounds after a named
cause, names every hidden effect with its column, and reports what no cause explains.

Every case is a fresh synthetic machine (``thermerr_rs.synthetic.make_multi_case``: each effect
drawn as it would be alone) with a 10 h training run (stepped duty) and a 5 h held-out run
(random duty), sampled every 120 s — shorter and coarser than test_diagnose.py's 20 h + 12 h
every 60 s, so that the file stays near its time budget (each round re-fits ~20 candidates).

Rates observed with this configuration (seeds 1–2, the tests; 4 of 6 pair cases fully named):

* vmc, ambient_coupling + sensor_drift: seed 1 both named; seed 2 only the sensor drift — in the
  10 h training run the ambient coupling does not improve the training fit (ΔBIC +7 in round 1,
  nothing supported in round 2), so the rule rightly refuses it, and 2.35–2.6 µm stay as the
  remainder. xfail (strict=False) rather than a looser rule.
* vmc, thermal_lag + speed_growth: both named on seeds 1 and 2 (speed growth in round 1, the lag
  in round 2, final held-out RMS 0.16–0.18 µm, noise 0.15 µm).
* lathe, speed_growth + unmodeled_source (T_hydraulic): both named on seed 1 (the source in
  round 1, the growth in round 2). On seed 2 round 2 adds the growth (held-out 1.02 -> 0.20 µm),
  but the backward check drops it: the source refitted alone fits the training run better than
  the joint fit did (BIC 1920 against 2113: the joint calibration sat in a worse minimum), so the
  growth is not supported against it. Refitting the joint from the source-only fit (tried, not
  kept) fits the training run far better (BIC 308) but holds out at 0.51 µm, and against the
  source alone the growth then removes 0.5 % of the normalised held-out residual (error and
  temperatures), under the 10 % bar: dropped either way. A known miss; 0.87 µm is reported as
  the remainder. (With the previous generator, whose runs differed in the last bit on an AVX2
  CPU, seed 2 named both; and with 12 h + 6 h runs round 1 names the decoy T_cabinet. Since the
  simulation's step and the drift map's solve were rewritten for speed on 2026-11-26, other
  roundings of the same equations, seed 2 names both again: the test xpasses.) This pair is not
  robust to the run or to the last bits of the arithmetic, so the mark stays non-strict.

Seed 3 (run by hand, not tested): lag + growth and growth + source both named; ambient + sensor
drift names only the ambient coupling (0.35 µm remainder at 0.16 µm noise). Single effects with
these short runs (seed 1 of six causes, by hand): one cause each, except vmc unmodeled_source,
where round 1 names the decoy T_cabinet, round 2 adds T_hydraulic and the backward check keeps
both (the verdict stays round 1's decoy); with test_diagnose.py's 20 h + 12 h runs round 1 names
T_hydraulic.
"""

from __future__ import annotations

import functools
import json
import math

import pytest

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.thermal import Machine, diagnose

HOURS = (10.0, 5.0)
DT_S = 120.0
SEEDS = (1, 2)
PAIRS = (
    ("vmc", ("ambient_coupling", "sensor_drift")),
    ("vmc", ("thermal_lag", "speed_growth")),
    ("lathe", ("speed_growth", "unmodeled_source")),
)
# measured misses, reported rather than tuned away (see the module docstring)
KNOWN_MISSES = {
    ("vmc", ("ambient_coupling", "sensor_drift"), 2): "the 10 h training run does not support the "
    "ambient coupling (ΔBIC > −10): only the sensor drift is named",
    ("lathe", ("speed_growth", "unmodeled_source"), 2): "the backward check drops the speed growth "
    "(the source alone fits the training run better than the joint fit): only the source is named",
}
# the periodic disturbance outside the catalogue: a sine of period 2 h
PERIODIC = {"amp": 1.5, "period_s": 7200.0}
REPORT_FIELDS = {"cause", "column", "node", "axis", "gain_pct", "params"}


@functools.lru_cache(maxsize=None)
def run_multi(topology, hidden, seed):
    params = {"periodic": PERIODIC} if "periodic" in hidden else None
    c = syn.make_multi_case(topology, hidden, seed, hours=HOURS, dt=DT_S, params=params)
    d = diagnose(tr.Run.from_frame(c.train, source="train"), Machine.from_toml(c.nominal_toml()),
                 tr.Run.from_frame(c.test, source="test"))
    return c, d


@functools.lru_cache(maxsize=None)
def run_single(topology, hidden, seed):
    c = syn.make_case(topology, hidden, seed, hours=HOURS, dt=DT_S)
    d = diagnose(tr.Run.from_frame(c.train, source="train"), Machine.from_toml(c.nominal_toml()),
                 tr.Run.from_frame(c.test, source="test"))
    return c, d


def _pair_cases():
    for topology, pair in PAIRS:
        for seed in SEEDS:
            why = KNOWN_MISSES.get((topology, pair, seed))
            marks = [pytest.mark.xfail(strict=False, reason=why)] if why else []
            yield pytest.param(topology, pair, seed, marks=marks, id=f"{topology}-{'+'.join(pair)}-{seed}")


def _check_report(d):
    """The report's causes are the named ones, in the order accepted, with their fields."""
    for x in d.causes:
        assert REPORT_FIELDS <= set(x), x
        assert x["axis"] == d.report["axis"]
        assert x["gain_pct"] > 0.0, x  # every named cause lowered the held-out error in its round
    accepted = [(r["cause"], r["column"]) for r in d.rounds if r["kept"]]
    assert accepted == [(x["cause"], x["column"]) for x in d.causes]
    if d.causes:
        assert d.verdict == d.causes[0]["cause"] and d.column == d.causes[0]["column"]
        assert d.report["extended"]["rmse_um"] < d.report["baseline"]["rmse_um"]
    json.dumps(d.report, allow_nan=False)


@pytest.mark.parametrize("topology, pair, seed", list(_pair_cases()))
def test_two_hidden_effects_are_both_named(topology, pair, seed):
    c, d = run_multi(topology, pair, seed)
    named = {x["cause"]: x["column"] for x in d.causes}
    assert sorted(named) == sorted(pair), d.evidence
    for h in pair:
        assert named[h] == c.columns[h], d.evidence
    _check_report(d)


def test_two_causes_that_pass_only_together_are_named_as_a_pair():
    """lathe, unmodeled_source (T_hydraulic) + nonlinear_expansion, seed 4 (10 h + 5 h at 120 s):
    the source is by far the strongest on the training rows (ΔBIC −4253) but alone it makes the
    held-out error worse (0.60 -> 0.95 µm: it takes up the expansion too), and no other candidate
    passes, so without pairs the verdict was `unexplained`. Fitted with the best candidate of
    each other cause, the source passes together with one (the round's rule against the
    calibrated model, and each member against the other alone); the next round adds the
    expansion and the backward check drops what the pair had brought along (measured 2026-11-28:
    the room coupling), leaving both hidden causes, 0.60 -> 0.21 µm held out."""
    c, d = run_multi("lathe", ("unmodeled_source", "nonlinear_expansion"), 4)
    lead = d.rounds[0]
    assert lead["paired"] and lead["accepted"] and d.rounds[1]["paired"], d.rounds
    assert (lead["cause"], lead["column"]) == ("unmodeled_source", c.columns["unmodeled_source"])
    assert lead["rmse_um"] > lead["rmse_before_um"], lead  # alone, it did not pass
    assert d.rounds[1]["rmse_um"] < lead["rmse_before_um"]  # together they do
    assert "as a pair" in d.evidence
    named = {x["cause"]: x["column"] for x in d.causes}
    assert named == {"unmodeled_source": "T_hydraulic", "nonlinear_expansion": None}, d.evidence
    assert d.remainder_um == 0.0, d.evidence
    _check_report(d)


def test_the_backward_check_judges_against_the_better_known_fit():
    """lathe, ambient_coupling + unmodeled_source (T_hydraulic), seed 4: round 1 names the room
    coupling (2.52 -> 0.95 µm held out), round 2 the source (-> 0.66 µm). The backward check's
    refit of the coupling alone, from the joint model's values, stopped in a worse minimum than
    round 1's fit of it; judged against that refit, the source was dropped, then the coupling
    against the baseline from it: nothing named (`unexplained`, 2.51 µm). Against the better of
    the two training fits both stay."""
    c, d = run_multi("lathe", ("ambient_coupling", "unmodeled_source"), 4)
    named = {x["cause"]: x["column"] for x in d.causes}
    assert named == {"ambient_coupling": None, "unmodeled_source": c.columns["unmodeled_source"]}, d.evidence
    assert [r["kept"] for r in d.rounds if r["accepted"]] == [True, True]
    assert d.report["extended"]["rmse_um"] < 0.35 * d.report["baseline"]["rmse_um"]
    _check_report(d)


def test_a_cause_and_a_periodic_remainder():
    """A thermal lag plus a 1.5 µm sine of period 2 h on the probe (lathe, seed 1): the lag is
    named, and the sine, which no cause explains, stays as the remainder, of about its RMS
    (1.06 µm; observed 1.10 µm). Observed on other cause + sine cases (10 h + 5 h runs, not
    tested, for time): lathe speed_growth seeds 1–2 and vmc speed_growth seed 1 named with a
    remainder of 0.9–1.2 µm, but on two of them (lathe and vmc seed 1) round 2 also accepts a
    nonlinear_expansion that absorbs part of the sine (22–24 % gain, 40 % of the excess); vmc
    speed_growth seed 3 gives `unexplained` (the sine hides the growth in round 1)."""
    _, d = run_multi("lathe", ("thermal_lag", "periodic"), 1)
    assert d.verdict == "thermal_lag", d.evidence
    assert d.causes[0]["cause"] == "thermal_lag"
    sine_rms = PERIODIC["amp"] / math.sqrt(2)
    assert d.remainder_um > 0.5 * sine_rms, d.evidence
    assert "remains that no catalogued cause explains" in d.evidence
    _check_report(d)


def test_the_periodic_remainder_is_not_taken_for_a_cause():
    _, d = run_multi("lathe", ("thermal_lag", "periodic"), 1)
    assert [x["cause"] for x in d.causes] == ["thermal_lag"], d.evidence


def test_nothing_hidden_names_nothing():
    _, d = run_single("vmc", "none", 1)
    assert d.verdict == "none", d.evidence
    assert d.causes == [] and d.remainder_um == 0.0
    assert [r["accepted"] for r in d.rounds] == [False]
    assert d.gain_pct == 0.0


def test_a_single_effect_gives_exactly_one_cause():
    c, d = run_single("lathe", "thermal_lag", 1)
    assert d.verdict == "thermal_lag", d.evidence
    assert [x["cause"] for x in d.causes] == ["thermal_lag"]
    assert d.causes[0]["round"] == 1 and d.causes[0]["params"]["tau_s"] > 0
    _check_report(d)


def test_the_report_lists_the_rounds_and_the_remainder(tmp_path):
    _, d = run_multi("vmc", ("thermal_lag", "speed_growth"), 1)
    page = d.write(tmp_path / "out")
    rep = json.loads((tmp_path / "out" / "report.json").read_text())
    assert rep["causes"] == d.causes and rep["remainder_um"] == d.remainder_um
    html = page.read_text()
    assert "<h2>Rounds</h2>" in html and "Unexplained remainder" in html
    for x in d.causes:
        assert f"<td>{x['round']}</td><td>{x['cause']}</td>" in html
    # the extended machine holds every named cause and reproduces the reported figure
    ext = Machine.load(tmp_path / "out" / "extended.toml").to_toml()
    assert "lag_s" in ext and "[[drift.inputs]]" in ext
