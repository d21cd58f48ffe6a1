"""Make the bundled sensor-selection example with the project's thermal simulation.

It looks like seed 003's experiment (Su et al. 2011): a horizontal machining centre, 20
temperature sensors, spindle speeds 3000-6000-4500-3000 rpm, a sample every 150 s, thermal errors
in X, Y and Z. The machine is `hmc_machine.toml`: six structural nodes (front/rear bearing,
spindle motor, headstock, column, bed) and, for each of the 19 sensors on the structure, a small
"skin" node linked to the part it sits on (with its own lag and a share of that part's rise), so
the sensor series fall into a few natural groups — what fuzzy c-means selection should find. The
drift of each axis is linear in the structural nodes' rises plus a small quadratic term on the
front bearing (the `quadratic_um_per_k2` construct).

    python examples/make_hmc_example.py     # rewrites hmc_machine.toml, hmc_run1.csv, hmc_run2.csv

Run 1 is the training run (3000-6000-4500-3000 rpm, 2 h each); run 2 is a different duty cycle
(4500-3000-6000 rpm then a stop) on a warmer day, used as held-out data. Sensor noise 0.03 °C,
probe noise 0.15 µm. Needs only numpy and thermerr_rs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import thermerr_rs as tr
from thermerr_rs.synthetic import to_toml, write_run_csv

STRUCT = [  # name, capacity J/K, conductance to ambient W/K
    ("front_bearing", 1500.0, 0.6), ("rear_bearing", 1800.0, 0.6), ("motor", 5000.0, 2.0),
    ("headstock", 40000.0, 6.0), ("column", 120000.0, 12.0), ("bed", 300000.0, 20.0),
]
LINKS = [("front_bearing", "headstock", 3.0), ("rear_bearing", "headstock", 3.0),
         ("motor", "headstock", 4.0), ("headstock", "column", 8.0), ("column", "bed", 10.0)]
SOURCES = [("front_bearing", 45.0, 1.4), ("rear_bearing", 35.0, 1.4), ("motor", 120.0, 1.1)]
DRIFT = {
    "E_x": {"front_bearing": 0.15, "rear_bearing": -0.05, "motor": 0.10, "headstock": 0.35, "column": -0.25, "bed": 0.10},
    "E_y": {"front_bearing": 0.36, "rear_bearing": 0.16, "motor": 0.08, "headstock": 0.44, "column": -0.24, "bed": -0.12},
    "E_z": {"front_bearing": 0.72, "rear_bearing": 0.36, "motor": 0.14, "headstock": 0.99, "column": 0.50, "bed": -0.32},
}
QUAD = {"E_x": 0.002, "E_y": 0.004, "E_z": 0.009}
# sensor -> (part, share of the part's rise, own lag in s)
SENSORS = [
    ("T_s01", "front_bearing", 1.00, 60), ("T_s02", "front_bearing", 0.85, 200), ("T_s03", "rear_bearing", 1.00, 60),
    ("T_s04", "rear_bearing", 0.90, 300), ("T_s05", "motor", 1.00, 90), ("T_s06", "motor", 0.70, 400),
    ("T_s07", "headstock", 1.00, 300), ("T_s08", "headstock", 0.80, 900), ("T_s09", "headstock", 0.60, 1500),
    ("T_s10", "column", 1.00, 600), ("T_s11", "column", 0.85, 1200), ("T_s12", "column", 0.70, 2400),
    ("T_s13", "bed", 1.00, 900), ("T_s14", "bed", 0.80, 1800), ("T_s15", "front_bearing", 0.55, 900),
    ("T_s16", "motor", 0.45, 1200), ("T_s17", "headstock", 0.40, 2400), ("T_s18", "bed", 0.60, 3600),
    ("T_s19", "column", 0.50, 3600),
]


def machine() -> dict:
    nodes = [{"name": n, "capacity_j_per_k": c, "ambient_w_per_k": g} for n, c, g in STRUCT]
    links = [{"between": [a, b], "w_per_k": g} for a, b, g in LINKS]
    for name, part, share, lag in SENSORS:
        # a skin node: link G_s to its part and G_a to the air, steady share G_s/(G_s+G_a),
        # time constant C/(G_s+G_a) = lag
        g_s = 0.05
        g_a = g_s * (1.0 - share) / share
        nodes.append({"name": name[2:], "capacity_j_per_k": lag * (g_s + g_a), "ambient_w_per_k": g_a,
                      "sensor": name})
        links.append({"between": [part, name[2:]], "w_per_k": g_s})
    nodes = [n if n["ambient_w_per_k"] > 0 else {k: v for k, v in n.items() if k != "ambient_w_per_k"} for n in nodes]
    return {
        "name": "hmc-example",
        "ambient": "T_ambient",
        "nodes": nodes,
        "links": links,
        "sources": [{"node": n, "input": "U_spindle_rpm", "w": w, "ref": 6000.0, "exponent": e} for n, w, e in SOURCES],
        "drift": [{"axis": a, "um_per_k": k, "quadratic_um_per_k2": {"front_bearing": QUAD[a]}} for a, k in DRIFT.items()],
    }


def run(mach: tr.Machine, schedule: list[tuple[float, float]], ambient0: float, amp: float, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    total = sum(d for _, d in schedule)
    t = np.arange(0.0, total + 1.0, 150.0)
    rpm = np.zeros_like(t)
    edge = 0.0
    for speed, dur in schedule:
        rpm[(t >= edge) & (t < edge + dur)] = speed
        edge += dur
    amb = ambient0 + amp * np.sin(2 * np.pi * (t / 86400.0 - 0.25))
    cols = {"time_s": t, "U_spindle_rpm": rpm, "T_ambient": amb}
    for name, *_ in SENSORS:
        cols[name] = np.full(len(t), amb[0])  # the machine starts at the shop's temperature
    for axis in DRIFT:
        cols[axis] = np.zeros(len(t))
    sim = mach.simulate(tr.Run.from_frame(cols))
    out = {"time_s": t, "U_spindle_rpm": rpm}
    for name, *_ in SENSORS:
        out[name] = sim.sensors[name] + rng.normal(0, 0.03, len(t))
    out["T_ambient"] = amb + rng.normal(0, 0.03, len(t))
    for axis in DRIFT:
        out[axis] = sim.drift[axis] + rng.normal(0, 0.15, len(t))
    return out


def main() -> None:
    here = Path(__file__).resolve().parents[1] / "python" / "thermerr_rs" / "examples"  # shipped in the wheel; examples/ links to it
    text = "# the bundled HMC example's machine (made by make_hmc_example.py)\n" + to_toml(machine())
    (here / "hmc_machine.toml").write_text(text)
    mach = tr.Machine.from_toml(text, "hmc_machine.toml")
    h = 7200.0
    write_run_csv(here / "hmc_run1.csv", run(mach, [(3000, h), (6000, h), (4500, h), (3000, h)], 20.5, 0.8, 3))
    write_run_csv(here / "hmc_run2.csv", run(mach, [(4500, h), (3000, h), (6000, h), (0, h)], 21.5, 1.2, 4))
    print(f"wrote hmc_machine.toml, hmc_run1.csv, hmc_run2.csv in {here}")


if __name__ == "__main__":
    main()
