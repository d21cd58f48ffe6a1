"""The synthetic-run generator is itself checked: its exact zero-order-hold integration against
scipy's adaptive ODE solver, and its TOML against the standard library's parser."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from thermerr_rs import synthetic as syn


def _rhs_factory(m, cols, k_idx):
    names, idx, cap, g_amb, a, _ = syn._system(m, [])
    t = cols["time_s"]

    def rhs(tt, x):
        s = min(np.searchsorted(t, tt, side="right") - 1, len(t) - 2)
        q = np.zeros(len(names))
        for src in m["sources"]:
            u = cols[src["input"]][s]
            q[idx[src["node"]]] += src["w"] * (u / src["ref"]) ** src["exponent"] if u > 0 else 0.0
        return (a @ x + q + g_amb * cols[m["ambient"]][s]) / cap

    return rhs, idx


@pytest.mark.parametrize("topology", ["vmc", "lathe"])
def test_exact_zoh_equals_adaptive_solver(topology):
    case = syn.make_case(topology, "none", 3, hours=(4.0, 1.0), dt=300.0, noise=False)
    m, cols = case.truth, case.train
    sim = syn.simulate_truth(m, cols)
    rhs, idx = _rhs_factory(m, cols, None)
    t = cols["time_s"]
    x = np.array([sim[n["name"]][0] for n in m["nodes"]])
    for s in range(len(t) - 1):
        sol = solve_ivp(rhs, (t[s], t[s + 1]), x, method="LSODA", rtol=1e-11, atol=1e-11,
                        first_step=1.0, max_step=t[s + 1] - t[s])
        x = sol.y[:, -1]
        got = np.array([sim[n["name"]][s + 1] for n in m["nodes"]])
        # adaptive solver at rtol 1e-11 over a ~300 s interval: agreement to ~1e-7 K
        np.testing.assert_allclose(got, x, atol=1e-7)
        x = got  # restart each interval from the exact value (inputs jump at samples)


def test_lag_reaches_63_percent_at_tau():
    m = syn.machine("vmc")
    t = np.arange(0, 20000.0, 10.0)
    cols = {"time_s": t, "T_ambient": np.full(len(t), 20.0), "U_spindle_rpm": np.full(len(t), 6000.0),
            "T_front_bearing": np.full(len(t), 20.0), "T_spindle_motor": np.full(len(t), 20.0),
            "T_headstock": np.full(len(t), 20.0), "T_column": np.full(len(t), 20.0)}
    fast = syn.simulate_truth(m, cols)
    lagged = syn.simulate_truth(m, cols, lag_s=1e-3)  # a negligible lag follows the drift
    np.testing.assert_allclose(lagged["drift:lag"][1:], fast["drift:inst"][1:], rtol=1e-3, atol=1e-6)


def test_nominal_toml_parses_and_differs():
    case = syn.make_case("lathe", "sensor_drift", 5)
    doc = tomllib.loads(case.nominal_toml())
    assert [n["name"] for n in doc["nodes"]] == [n["name"] for n in case.truth["nodes"]]
    ratios = [a["capacity_j_per_k"] / b["capacity_j_per_k"] for a, b in zip(doc["nodes"], case.truth["nodes"])]
    assert all(abs(r - 1) >= 0.149 for r in ratios)  # perturbed by 15 % or more
    assert case.column in case.train and case.column.startswith("T_")


def test_cases_are_seeded_and_realistic():
    a = syn.make_case("vmc", "ambient_coupling", 1)
    b = syn.make_case("vmc", "ambient_coupling", 1)
    np.testing.assert_array_equal(a.train["E_z"], b.train["E_z"])
    e = a.train["E_z"]
    assert 20 < np.ptp(e) < 120  # tens of µm of thermal error
    assert "T_cabinet" in a.train and "T_hydraulic" in a.train


@pytest.mark.parametrize("topology", ["vmc", "lathe"])
def test_a_lag_takes_the_expansion_and_not_the_room(topology):
    """With a thermal lag hidden, the nonlinear expansion (the structure's own) goes through it
    and the ambient coupling (the room, acting directly) does not: the same draws with the term
    set to zero differ by exactly lag(q·ΔT²) and by k_amb·ΔT_amb, as the model reads lag_s."""
    pair = ("thermal_lag", "nonlinear_expansion", "ambient_coupling")
    node = next(nd for nd in syn.machine(topology)["nodes"] if "sensor" in nd)
    on = {"node": node["name"]}
    zero = {"nonlinear_expansion": {**on, "q": 0.0}, "ambient_coupling": {"k_amb": 0.0}}
    full = syn.make_multi_case(topology, pair, 3, hours=(4.0, 1.0), dt=120.0, noise=False,
                               params={"nonlinear_expansion": on})
    base = syn.make_multi_case(topology, pair, 3, hours=(4.0, 1.0), dt=120.0, noise=False, params=zero)
    axis, t = full.axis, full.train["time_s"]
    p = full.params
    rise = full.train[node["sensor"]] - full.train[node["sensor"]][0]
    amb = full.train["T_ambient"]
    want = (syn.lag(t, p["nonlinear_expansion.q"] * rise**2, p["thermal_lag.tau"])
            + p["ambient_coupling.k_amb"] * (amb - amb[0]))
    np.testing.assert_allclose(full.train[axis] - base.train[axis], want, atol=1e-9)
    # and the lag matters here: the expansion unlagged would differ by far more than that
    assert np.abs(p["nonlinear_expansion.q"] * rise**2 - syn.lag(t, p["nonlinear_expansion.q"] * rise**2,
                                                                   p["thermal_lag.tau"])).max() > 0.1
