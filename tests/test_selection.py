"""Seed 003's sensor selection: the pure per-cluster pick on the seed's own numbers, and the
whole pipeline on a synthetic run whose sensor groups are known."""

from __future__ import annotations

import numpy as np
import pytest
from _thermal import DT_S, first_order, sensor_series, spindle_steps

from thermerr_rs import DataError, MissingColumnError, ParameterError, Run
from thermerr_rs.selection import SensorSelection, pick_per_cluster, select_sensors

# Seed 003, |rho| of sensors 1-20 with the composite error (methods.md, second reading).
SEED003_RHO = [.5068, .4430, .0227, .6148, .4720, .5308, .4587, .2333, .4769, .4988,
               .4588, .4410, .4696, .2193, .1708, .0732, .5195, .1077, .6014, .5830]

# Seed 003, Table 1: final fuzzy partition, one row per class, columns = sensors 1-20. Three
# cells are garbled in the extracted text (sensor 12, classes 1 and 3; sensor 20, class 4);
# they are filled from the columns' sums to 1 and are far below each column's maximum, so they
# cannot change the hardening.
SEED003_U = np.array([
    [.0794, .6171, .0217, .0524, .8440, .0745, .9566, .3156, .9173, .0413,
     .8209, .1015, .9080, .0284, .0729, .0476, .1261, .0611, .0364, .0257],
    [.0174, .1852, .9100, .1719, .0325, .2270, .0151, .3983, .0204, .0094,
     .0651, .0245, .0288, .9291, .7616, .8276, .0268, .8351, .1660, .0954],
    [.0101, .0615, .0597, .7451, .0159, .6628, .0062, .1883, .0094, .0058,
     .0247, .0146, .0131, .0333, .1352, .1069, .0166, .0824, .7777, .8663],
    [.8931, .1362, .0086, .0306, .1075, .0357, .0221, .0978, .0529, .9435,
     .0893, .8593, .0501, .0092, .0303, .0178, .8305, .0214, .0199, .0127],
])


def test_seed003_table_hardens_to_the_published_clusters():
    np.testing.assert_allclose(SEED003_U.sum(axis=0), 1.0, atol=2e-4)  # table rounding
    labels = SEED003_U.argmax(axis=0)
    clusters = {c: [k + 1 for k in range(20) if labels[k] == c] for c in range(4)}
    assert clusters == {
        0: [2, 5, 7, 9, 11, 13],
        1: [3, 8, 14, 15, 16, 18],
        2: [4, 6, 19, 20],
        3: [1, 10, 12, 17],
    }


def test_seed003_pick_gives_sensors_9_8_4_17():
    # By the numbers: {2,5,7,9,11,13} -> 9 (.4769), {3,8,14,15,16,18} -> 8 (.2333),
    # {4,6,19,20} -> 4 (.6148), {1,10,12,17} -> 17 (.5195 > .5068 of sensor 1).
    # The published claim (sensors 4, 8, 9, 17) follows from the published numbers.
    labels = SEED003_U.argmax(axis=0)
    names = list(range(1, 21))
    assert pick_per_cluster(labels, SEED003_RHO, names) == [9, 8, 4, 17]
    by_name = dict(zip(names, map(int, labels)))
    assert pick_per_cluster(by_name, dict(zip(names, SEED003_RHO))) == [9, 8, 4, 17]
    # the sign of rho does not matter, only its magnitude
    signed = [-r if k % 2 else r for k, r in enumerate(SEED003_RHO)]
    assert pick_per_cluster(labels, signed, names) == [9, 8, 4, 17]


def test_pick_ties_and_lengths():
    assert pick_per_cluster([0, 0, 1], [0.5, -0.5, 0.1]) == [0, 2]
    with pytest.raises(ParameterError):
        pick_per_cluster([0, 1], [0.1])


# --- a synthetic run with three known groups of sensors -----------------------------------------
GROUPS = {
    "fast": ["T_f1", "T_f2", "T_f3", "T_f4"],  # spindle bearings: tau 8-12 min
    "slow": ["T_s1", "T_s2", "T_s3", "T_s4"],  # headstock / column: tau 2.5-3.5 h
    "air": ["T_a1", "T_a2", "T_a3"],  # shop air: a slow daily swing, no spindle heat
}


def _run(n=300, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT_S
    cols = {"time_s": t}
    fast = sensor_series(n, [480, 600, 660, 720], [8, 6, 7, 5], 0.03, seed)
    slow = sensor_series(n, [9000, 10000, 11000, 12600], [4, 5, 3, 6], 0.03, seed + 1)
    for name, row in zip(GROUPS["fast"], fast):
        cols[name] = row
    for name, row in zip(GROUPS["slow"], slow):
        cols[name] = row
    for k, name in enumerate(GROUPS["air"]):
        cols[name] = 21 + 2 * np.sin(2 * np.pi * t / 86400 + 0.1 * k) + 0.03 * rng.standard_normal(n)
    heat = (spindle_steps(n) / 6000.0) ** 1.4
    cols["U_spindle_rpm"] = spindle_steps(n)
    cols["E_z"] = -9 * first_order(heat, 700) - 6 * first_order(heat, 10500) + 0.2 * rng.standard_normal(n)
    cols["E_x"] = 3 * first_order(heat, 10000) + 1.5 * (cols["T_a2"] - 21) + 0.2 * rng.standard_normal(n)
    return Run.from_frame(cols, source="synthetic")


def test_recovers_known_groups_and_picks_best_correlated():
    run = _run()
    sel = select_sensors(run, "E_z", n_clusters=3, seed=0)
    assert isinstance(sel, SensorSelection)
    found = sorted(sorted(v) for v in sel.clusters.values())
    assert found == sorted(sorted(v) for v in GROUPS.values())
    # per cluster, the selected sensor has the largest |rho| (checked independently)
    for members in sel.clusters.values():
        rho = {s: abs(np.corrcoef(run[s], run["E_z"])[0, 1]) for s in members}
        chosen = [s for s in sel.selected if s in members]
        assert chosen == [max(rho, key=rho.get)]
        for s in members:
            assert sel.correlations[s] == pytest.approx(np.corrcoef(run[s], run["E_z"])[0, 1], abs=1e-12)
    assert list(sel.clusters) == sorted(sel.clusters)
    assert sel.selected == [pick_per_cluster([0] * len(v), [sel.correlations[s] for s in v], v)[0]
                            for v in sel.clusters.values()]
    assert sel.membership.shape == (11, 3)
    np.testing.assert_allclose(sel.membership.sum(axis=1), 1.0, atol=1e-12)
    text = str(sel)
    for s in sel.sensors:
        assert s in text
    assert text.count("*") == 3


def test_same_seed_same_selection():
    run = _run()
    a = select_sensors(run, "E_z", n_clusters=3, seed=4)
    b = select_sensors(run, "E_z", n_clusters=3, seed=4)
    assert a.selected == b.selected
    np.testing.assert_array_equal(a.membership, b.membership)


def test_composite_axis():
    run = _run()
    sel = select_sensors(run, ["E_x", "E_z"], n_clusters=3, seed=0)
    assert sel.axis == ["E_x", "E_z"]
    assert sum(sel.weights.values()) == pytest.approx(1.0)
    rms = {a: np.sqrt(np.mean(run[a] ** 2)) for a in ("E_x", "E_z")}
    assert sel.weights["E_z"] == pytest.approx(rms["E_z"] / (rms["E_x"] + rms["E_z"]))
    target = sel.weights["E_x"] * np.abs(run["E_x"]) + sel.weights["E_z"] * np.abs(run["E_z"])
    for s in sel.sensors:
        assert sel.correlations[s] == pytest.approx(np.corrcoef(run[s], target)[0, 1], abs=1e-12)
    assert "composite" in str(sel)


def test_sensor_subset():
    run = _run()
    sel = select_sensors(run, "E_z", n_clusters=2, sensors=GROUPS["fast"] + GROUPS["slow"])
    assert sorted(sorted(v) for v in sel.clusters.values()) == [sorted(GROUPS["fast"]), sorted(GROUPS["slow"])]


def test_errors():
    run = _run()
    with pytest.raises(MissingColumnError, match="E_y"):
        select_sensors(run, "E_y")
    with pytest.raises(MissingColumnError, match="E_q"):
        select_sensors(run, ["E_z", "E_q"])
    with pytest.raises(MissingColumnError, match="T_nope"):
        select_sensors(run, "E_z", sensors=["T_f1", "T_nope", "T_s1"], n_clusters=2)
    with pytest.raises(ParameterError):
        select_sensors(run, "E_z", n_clusters=4, sensors=["T_f1", "T_s1", "T_a1"])
    with pytest.raises(ParameterError):
        select_sensors(run, "U_spindle_rpm")
    cols = {n: run[n] for n in ["time_s", *run.names]}
    cols["T_dead"] = np.full(len(run), 20.5)
    with pytest.raises(DataError, match="T_dead"):
        select_sensors(Run.from_frame(cols), "E_z", n_clusters=3)
