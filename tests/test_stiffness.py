"""Key thermal stiffness (seed 001) on a simulated machine whose X-axis drift is dominated by one
element (the ballscrew's rear support)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.errors import ModelFormatError, ParameterError

# four heated elements on separate inputs, each with its own sensor; the drift of E_x is 6 µm/K
# from the screw support and at most 0.4 µm/K from the others
MACHINE = """
name = "gantry-x"
ambient = "T_ambient"
[[nodes]]
name = "screw_support"
capacity_j_per_k = 6000.0
ambient_w_per_k = 2.0
sensor = "T_screw_support"
[[nodes]]
name = "nut"
capacity_j_per_k = 3000.0
ambient_w_per_k = 1.5
sensor = "T_nut"
[[nodes]]
name = "motor"
capacity_j_per_k = 9000.0
ambient_w_per_k = 3.0
sensor = "T_motor"
[[nodes]]
name = "wall"
capacity_j_per_k = 40000.0
ambient_w_per_k = 6.0
sensor = "T_wall"
[[links]]
between = ["screw_support", "nut"]
w_per_k = 0.3
[[links]]
between = ["motor", "wall"]
w_per_k = 0.5
[[sources]]
node = "screw_support"
input = "U_a"
w = 40.0
ref = 1.0
[[sources]]
node = "nut"
input = "U_b"
w = 30.0
ref = 1.0
[[sources]]
node = "motor"
input = "U_c"
w = 60.0
ref = 1.0
[[sources]]
node = "wall"
input = "U_d"
w = 80.0
ref = 1.0
[[drift]]
axis = "E_x"
um_per_k = { screw_support = 6.0, nut = 0.4, motor = -0.3, wall = 0.25 }
"""
SENSORS = ["T_screw_support", "T_nut", "T_motor", "T_wall"]


def simulated_run(seed: int = 0) -> tr.Run:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 6 * 3600.0 + 1, 60.0)
    cols: dict[str, np.ndarray] = {"time_s": t, "T_ambient": np.full(len(t), 20.0), "E_x": np.zeros(len(t))}
    for k, name in enumerate("abcd"):
        # independent on/off duty in 20-60 min blocks for the first 4 h, then all on (equilibrium)
        u = np.zeros(len(t))
        edge = 0.0
        while edge < 4 * 3600:
            dur = rng.uniform(1200, 3600)
            u[(t >= edge) & (t < edge + dur)] = rng.choice([0.0, 1.0])
            edge += dur
        u[t >= 4 * 3600] = 1.0
        cols[f"U_{name}"] = u
    for s in SENSORS:
        cols[s] = np.full(len(t), 20.0)
    sim = tr.Machine.from_toml(MACHINE).simulate(tr.Run.from_frame(cols))
    for s in SENSORS:
        cols[s] = sim.sensors[s] + rng.normal(0, 0.02, len(t))
    cols["E_x"] = sim.drift["E_x"] + rng.normal(0, 0.1, len(t))
    return tr.Run.from_frame(cols)


@pytest.fixture(scope="module")
def fitted() -> tuple[tr.MLR, tr.Run]:
    run = simulated_run()
    return tr.MLR().fit_run(run, "E_x", SENSORS, inputs="rise"), run


def test_flags_the_dominant_element_only(fitted) -> None:
    model, run = fitted
    res = tr.key_thermal_stiffness(model, run)
    assert res.time_s >= 3 * 3600  # the equilibrium lies in the final, steady part of the run
    assert res.flagged == ["T_screw_support"], res.table()
    # the model's sensitivity to the dominant element is its drift coefficient (6 µm/K), within
    # what 0.1 µm probe noise over 361 samples leaves of a least-squares coefficient
    assert res.sensitivity[0] == pytest.approx(6.0, rel=0.05)
    assert res.stiffness[0] == pytest.approx(1 / res.sensitivity[0])


def test_result_keeps_its_sign_for_eta_between_03_and_07(fitted) -> None:
    model, run = fitted
    res = [tr.key_thermal_stiffness(model, run, eta=eta) for eta in (0.3, 0.5, 0.7)]
    assert {tuple(r.flagged) for r in res} == {("T_screw_support",)}
    # the flagged element's ε keeps its sign (the weak ones sit inside the band, where the
    # model's own residual at that sample can tip them either way)
    assert {np.sign(r.epsilon[0]) for r in res} == {1.0}
    assert {tuple(np.sign(r.sensitivity)) for r in res} == {(1.0, 1.0, -1.0, 1.0)}


def test_sequence_models_and_a_given_time(fitted) -> None:
    _, run = fitted
    rbf = tr.AGORegressor(tr.RBFNetwork(design="exact", spread=1.2)).fit_run(run.slice(0, 200), "E_x", SENSORS)
    res = tr.key_thermal_stiffness(rbf, run.slice(0, 200), at=150 * 60.0)
    assert res.index == 150 and len(res.epsilon) == 4 and np.all(np.isfinite(res.epsilon))


def test_bad_calls_are_refused(fitted) -> None:
    model, run = fitted
    with pytest.raises(ParameterError, match="eta"):
        tr.key_thermal_stiffness(model, run, eta=0.0)
    with pytest.raises(ParameterError, match="outside the run"):
        tr.key_thermal_stiffness(model, run, at=-5.0)
    bare = tr.MLR().fit(run.matrix(SENSORS), run["E_x"])
    with pytest.raises(ModelFormatError, match="fit_run"):
        tr.key_thermal_stiffness(bare, run)


def test_command_line(fitted, tmp_path, capsys) -> None:
    from thermerr_rs.cli import main
    from thermerr_rs.synthetic import write_run_csv

    model, run = fitted
    mpath = model.save(tmp_path / "m.json")
    cols = {"time_s": run.time_s, **{n: run[n] for n in run.names}}
    write_run_csv(tmp_path / "run.csv", cols)
    assert main(["stiffness", str(mpath), str(tmp_path / "run.csv"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["flagged"] == ["T_screw_support"]
    assert main(["stiffness", str(mpath), str(tmp_path / "run.csv"), "--eta", "nan"]) == 2
    assert "eta" in capsys.readouterr().err
