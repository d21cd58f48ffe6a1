"""Make the seed-004 spindle example with the project's thermal simulation.

It looks like seed 004's experiment (Liu et al. 2022): a precision CNC spindle idling at
3000 rpm for 3 h, 4 temperature sensors (front bearing, headstock, column, bed), a sample every
3 min (60 samples after the start), the axial thermal drift E_z measured by a probe. Two more runs
at 2000 and 4000 rpm on other days test how a model trained at 3000 rpm carries over.

The machine is `spindle_machine.toml`: front and rear bearings and the motor heat the headstock,
which leaks into the column and the bed; the axial drift is linear in the part rises plus a
quadratic term on the front bearing (the bearing preload grows with temperature) — enough of a
nonlinearity that a kernel model can beat a linear one. Sensor noise 0.03 °C, probe noise 0.3 µm.

    python examples/make_spindle_example.py   # rewrites spindle_machine.toml, spindle_{2000,3000,4000}rpm.csv
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import thermerr_rs as tr
from thermerr_rs.synthetic import to_toml, write_run_csv

NODES = [  # name, capacity J/K, conductance to ambient W/K, sensor column
    ("front_bearing", 1200.0, 0.5, "T_front_bearing"),
    ("rear_bearing", 1500.0, 0.5, None),
    ("motor", 4000.0, 1.5, None),
    ("headstock", 30000.0, 5.0, "T_headstock"),
    ("column", 100000.0, 10.0, "T_column"),
    ("bed", 250000.0, 18.0, "T_bed"),
]
LINKS = [("front_bearing", "headstock", 2.5), ("rear_bearing", "headstock", 2.5),
         ("motor", "headstock", 3.5), ("headstock", "column", 7.0), ("column", "bed", 9.0)]
SOURCES = [("front_bearing", 40.0, 1.5), ("rear_bearing", 30.0, 1.5), ("motor", 90.0, 1.2)]
DRIFT = {"front_bearing": 1.1, "rear_bearing": 0.4, "motor": 0.2, "headstock": 1.4, "column": 0.6, "bed": -0.3}
QUAD = {"front_bearing": 0.03}


def machine() -> dict:
    nodes = []
    for name, c, g, sensor in NODES:
        n: dict = {"name": name, "capacity_j_per_k": c, "ambient_w_per_k": g}
        if sensor:
            n["sensor"] = sensor
        nodes.append(n)
    return {
        "name": "spindle-example",
        "ambient": "T_ambient",
        "nodes": nodes,
        "links": [{"between": [a, b], "w_per_k": g} for a, b, g in LINKS],
        "sources": [{"node": n, "input": "U_spindle_rpm", "w": w, "ref": 3000.0, "exponent": e} for n, w, e in SOURCES],
        "drift": [{"axis": "E_z", "um_per_k": DRIFT, "quadratic_um_per_k2": QUAD}],
    }


def run(mach: tr.Machine, rpm: float, ambient0: float, seed: int) -> dict:
    """3 h at a constant speed, a sample every 3 min (61 rows: the start and 60 samples)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 3 * 3600.0 + 1.0, 180.0)
    amb = ambient0 + 0.4 * np.sin(2 * np.pi * t / 86400.0)
    sensors = [s for *_, s in NODES if s]
    cols = {"time_s": t, "U_spindle_rpm": np.full(len(t), rpm), "T_ambient": amb, "E_z": np.zeros(len(t))}
    for s in sensors:
        cols[s] = np.full(len(t), amb[0])  # the machine starts at the shop's temperature
    sim = mach.simulate(tr.Run.from_frame(cols))
    out = {"time_s": t, "U_spindle_rpm": cols["U_spindle_rpm"]}
    for s in sensors:
        out[s] = sim.sensors[s] + rng.normal(0, 0.03, len(t))
    out["T_ambient"] = amb + rng.normal(0, 0.03, len(t))
    out["E_z"] = sim.drift["E_z"] + rng.normal(0, 0.3, len(t))
    return out


def main() -> None:
    here = Path(__file__).resolve().parents[1] / "python" / "thermerr_rs" / "examples"  # shipped in the wheel; examples/ links to it
    text = "# the seed-004 spindle example's machine (made by make_spindle_example.py)\n" + to_toml(machine())
    (here / "spindle_machine.toml").write_text(text)
    mach = tr.Machine.from_toml(text, "spindle_machine.toml")
    for rpm, amb, seed in [(3000, 20.0, 11), (2000, 21.0, 12), (4000, 19.5, 13)]:
        write_run_csv(here / f"spindle_{rpm}rpm.csv", run(mach, rpm, amb, seed))
    print(f"wrote spindle_machine.toml and spindle_{{2000,3000,4000}}rpm.csv in {here}")


if __name__ == "__main__":
    main()
