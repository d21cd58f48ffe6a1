"""Make the seed-002 turning-centre example with the project's thermal simulation.

Like seed 002's experiment (Zhang & Yang 2011): a CNC turning centre's X axis, 5 temperatures
(coolant, headstock, X-axis nut, bed, ambient), 130 samples every 5 min (650 min) through
run–stop–run cycles while machining. The machine is `lathe_machine.toml`: the spindle heats the
headstock, the X feed the ballscrew nut, the pump the coolant, which washes over the bed; the X
error grows with the nut and the headstock and shrinks with the bed, plus a quadratic term on the
nut. Sensor noise 0.03 °C, probe noise 0.3 µm.

    python examples/make_lathe_example.py   # rewrites lathe_machine.toml and lathe_run.csv
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import thermerr_rs as tr
from thermerr_rs.synthetic import to_toml, write_run_csv

NODES = [  # name, capacity J/K, conductance to ambient W/K, sensor
    ("coolant", 60000.0, 25.0, "T_coolant"),
    ("headstock", 45000.0, 6.0, "T_headstock"),
    ("x_nut", 2500.0, 1.2, "T_x_nut"),
    ("bed", 200000.0, 15.0, "T_bed"),
]
LINKS = [("coolant", "bed", 8.0), ("headstock", "bed", 5.0), ("x_nut", "bed", 0.8)]
SOURCES = [("headstock", "U_spindle_rpm", 160.0, 2000.0, 1.3), ("x_nut", "U_x_feed", 25.0, 1.0, 1.0),
           ("coolant", "U_pump", 300.0, 1.0, 1.0)]
DRIFT = {"headstock": 2.2, "x_nut": 3.5, "bed": -1.4, "coolant": 0.4}
QUAD = {"x_nut": 0.08}


def machine() -> dict:
    nodes = [{"name": n, "capacity_j_per_k": c, "ambient_w_per_k": g, "sensor": s} for n, c, g, s in NODES]
    return {
        "name": "lathe-example",
        "ambient": "T_ambient",
        "nodes": nodes,
        "links": [{"between": [a, b], "w_per_k": g} for a, b, g in LINKS],
        "sources": [{"node": n, "input": u, "w": w, "ref": r, "exponent": e} for n, u, w, r, e in SOURCES],
        "drift": [{"axis": "E_x", "um_per_k": DRIFT, "quadratic_um_per_k2": QUAD}],
    }


def main() -> None:
    here = Path(__file__).resolve().parents[1] / "python" / "thermerr_rs" / "examples"  # shipped in the wheel; examples/ links to it
    text = "# the seed-002 turning-centre example's machine (made by make_lathe_example.py)\n" + to_toml(machine())
    (here / "lathe_machine.toml").write_text(text)
    mach = tr.Machine.from_toml(text, "lathe_machine.toml")
    rng = np.random.default_rng(21)
    t = np.arange(130) * 300.0
    minute = t / 60.0
    # run–stop–run: machining 0–150, stop 150–260, machining 260–420, stop 420–500, machining 500–650 min
    on = ((minute < 150) | ((minute >= 260) & (minute < 420)) | (minute >= 500)).astype(float)
    rpm = on * np.where(minute < 260, 1800.0, np.where(minute < 500, 2400.0, 2000.0))
    feed = on * (0.6 + 0.4 * rng.random(len(t)))
    amb = 19.5 + 1.5 * np.sin(2 * np.pi * (t / 86400.0 - 0.1))
    cols = {"time_s": t, "U_spindle_rpm": rpm, "U_x_feed": feed, "U_pump": on, "T_ambient": amb,
            "E_x": np.zeros(len(t))}
    sensors = [s for *_, s in NODES]
    for s in sensors:
        cols[s] = np.full(len(t), amb[0])
    sim = mach.simulate(tr.Run.from_frame(cols))
    out = {k: cols[k] for k in ("time_s", "U_spindle_rpm", "U_x_feed", "U_pump")}
    for s in sensors:
        out[s] = sim.sensors[s] + rng.normal(0, 0.03, len(t))
    out["T_ambient"] = amb + rng.normal(0, 0.03, len(t))
    out["E_x"] = sim.drift["E_x"] + rng.normal(0, 0.3, len(t))
    write_run_csv(here / "lathe_run.csv", out)
    print(f"wrote lathe_machine.toml and lathe_run.csv in {here}")


if __name__ == "__main__":
    main()
