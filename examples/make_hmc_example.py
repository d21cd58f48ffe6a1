"""Make the bundled example: a horizontal machining centre warmed by stepped spindle speeds.

It looks like seed 003's experiment (Su et al. 2011): 20 temperature sensors, spindle speeds
3000-6000-4500-3000 rpm, a sample every 150 s, thermal errors in X, Y and Z. The numbers come from
a small lumped thermal network (front/rear bearing, spindle motor, headstock, column, bed, shop
air) integrated here with plain numpy, so this script needs nothing but numpy:

    python examples/make_hmc_example.py            # rewrites examples/hmc_run1.csv, hmc_run2.csv

Run 1 is the training run (3000-6000-4500-3000 rpm, 2 h each); run 2 is a different duty cycle
(4500-3000-6000 rpm then a stop) on another day, used as held-out data. Each of the 20 sensors
reads one of the network's nodes (several sensors sit on the same part, with their own local
lag, gain and noise), so the sensor series fall into a few natural groups - what fuzzy c-means
sensor selection should find. The errors are linear in the node temperature rises plus a small
quadratic term and probe noise (0.15 µm), a few tens of µm in all.

When the project's thermal simulation lands (`thermerr predict`), this example will be
regenerated from a machine TOML instead.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

NODES = ["front_bearing", "rear_bearing", "motor", "headstock", "column", "bed"]
CAP = np.array([1500.0, 1800.0, 5000.0, 40000.0, 120000.0, 300000.0])  # J/K
G_AMB = np.array([0.6, 0.6, 2.0, 6.0, 12.0, 20.0])  # W/K
LINKS = [(0, 3, 3.0), (1, 3, 3.0), (2, 3, 4.0), (3, 4, 8.0), (4, 5, 10.0)]
# heat at 6000 rpm (W) and exponent: bearings ~ n^1.4, motor ~ n^1.1
Q_REF = np.array([45.0, 35.0, 120.0, 0.0, 0.0, 0.0])
EXPO = np.array([1.4, 1.4, 1.1, 1.0, 1.0, 1.0])
# µm per K of each node's rise, per axis
DRIFT = {
    "E_x": np.array([0.15, -0.05, 0.10, 0.35, -0.25, 0.10]),
    "E_y": np.array([0.36, 0.16, 0.08, 0.44, -0.24, -0.12]),
    "E_z": np.array([0.72, 0.36, 0.14, 0.99, 0.50, -0.32]),
}
QUAD = {"E_x": 0.002, "E_y": 0.004, "E_z": 0.009}  # µm/K² on the front bearing rise

# sensor -> (node, gain on the node's rise, own lag in s); 20 sensors as in seed 003
SENSORS = [
    ("T_s01", 0, 1.00, 60), ("T_s02", 0, 0.85, 200), ("T_s03", 1, 1.00, 60),
    ("T_s04", 1, 0.90, 300), ("T_s05", 2, 1.00, 90), ("T_s06", 2, 0.70, 400),
    ("T_s07", 3, 1.00, 300), ("T_s08", 3, 0.80, 900), ("T_s09", 3, 0.60, 1500),
    ("T_s10", 4, 1.00, 600), ("T_s11", 4, 0.85, 1200), ("T_s12", 4, 0.70, 2400),
    ("T_s13", 5, 1.00, 900), ("T_s14", 5, 0.80, 1800), ("T_s15", 0, 0.55, 900),
    ("T_s16", 2, 0.45, 1200), ("T_s17", 3, 0.40, 2400), ("T_s18", 5, 0.60, 3600),
    ("T_s19", 4, 0.50, 3600), ("T_ambient", -1, 1.00, 0),
]


def simulate(schedule: list[tuple[float, float]], ambient0: float, amp: float, seed: int) -> dict:
    """Integrate the network (1 s steps, implicit Euler) and sample every 150 s."""
    rng = np.random.default_rng(seed)
    n = len(NODES)
    a = np.zeros((n, n))
    for i, j, g in LINKS:
        a[i, j] += g
        a[j, i] += g
        a[i, i] -= g
        a[j, j] -= g
    a[np.diag_indices(n)] -= G_AMB
    a /= CAP[:, None]
    dt = 1.0
    step = np.linalg.inv(np.eye(n) - dt * a)
    total = int(sum(d for _, d in schedule))
    t_all = np.arange(0, total + 1, dt)
    rpm = np.zeros_like(t_all)
    edge = 0.0
    for speed, dur in schedule:
        rpm[(t_all >= edge) & (t_all < edge + dur)] = speed
        edge += dur
    amb = ambient0 + amp * np.sin(2 * np.pi * (t_all / 86400.0 - 0.25))
    temp = np.full(n, amb[0])
    sensor_state = np.full(len(SENSORS), amb[0])
    rows = []
    for k, t in enumerate(t_all):
        if k % 150 == 0:
            rows.append((t, rpm[k], amb[k], temp.copy(), sensor_state.copy()))
        q = Q_REF * np.where(rpm[k] > 0, (rpm[k] / 6000.0) ** EXPO, 0.0)
        rhs = temp + dt * (q / CAP + G_AMB / CAP * amb[k])
        temp = step @ rhs
        for s, (_, node, gain, lag) in enumerate(SENSORS):
            target = amb[k] if node < 0 else amb[k] + gain * (temp[node] - amb[k])
            sensor_state[s] = target if lag == 0 else sensor_state[s] + dt / (lag + dt) * (target - sensor_state[s])
    out: dict = {"time_s": [], "U_spindle_rpm": []}
    for name, *_ in SENSORS:
        out[name] = []
    for axis in DRIFT:
        out[axis] = []
    t0_temp = rows[0][3]
    for t, r, _amb, temp_k, sens in rows:
        out["time_s"].append(t)
        out["U_spindle_rpm"].append(r)
        for s, (name, *_rest) in enumerate(SENSORS):
            out[name].append(sens[s] + rng.normal(0, 0.03))
        rise = temp_k - t0_temp
        for axis, k in DRIFT.items():
            e = float(k @ rise + QUAD[axis] * rise[0] ** 2)
            out[axis].append(e + rng.normal(0, 0.15))
    return out


def write(path: Path, cols: dict) -> None:
    names = list(cols)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        for i in range(len(cols["time_s"])):
            w.writerow([f"{cols[n][i]:.0f}" if n in ("time_s", "U_spindle_rpm") else f"{cols[n][i]:.3f}" for n in names])


def main() -> None:
    here = Path(__file__).resolve().parent
    h = 7200.0
    run1 = simulate([(3000, h), (6000, h), (4500, h), (3000, h)], ambient0=20.5, amp=0.8, seed=3)
    run2 = simulate([(4500, h), (3000, h), (6000, h), (0, h)], ambient0=21.5, amp=1.2, seed=4)
    write(here / "hmc_run1.csv", run1)
    write(here / "hmc_run2.csv", run2)
    print(f"wrote {here / 'hmc_run1.csv'} and {here / 'hmc_run2.csv'} ({len(run1['time_s'])} samples each)")


if __name__ == "__main__":
    main()
