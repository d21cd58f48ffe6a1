"""Confusion matrix of the diagnosis over synthetic machines: hidden cause x verdict.

    python benches/diagnose_matrix.py [--seeds 1-5]
    python benches/diagnose_matrix.py --timing [--rows 1000,10000,100000]

Each case: a fresh true machine (VMC Z axis or lathe X axis) hiding one effect (or none, or a
periodic disturbance outside the catalogue), a 20 h stepped training run and a 12 h random-duty
held-out run, a nominal model perturbed by 15-35 %. Prints the matrix, the column accuracy and
the time per diagnosis.

``--timing``: the time of one diagnosis of all five axes of the shop run
(:func:`thermerr_rs.synthetic.make_shop_case`: 15-s samples, sixteen sensors, ambient coupling
on E_ch3, speed growth on E_ch1) at each row count, with each axis's verdict.
"""

from __future__ import annotations

import argparse
import time
from collections import Counter

import thermerr_rs as tr
from thermerr_rs import synthetic as syn
from thermerr_rs.thermal import Machine, diagnose


def timing(rows: list[int]) -> None:
    from thermerr_rs.thermal import diagnose_axes

    print(f"{'rows':>8} {'hours':>7} {'seconds':>8}  verdicts (E_ch1..E_ch5)")
    for n in rows:
        hours = (n - 1) * 15.0 / 3600.0
        c = syn.make_shop_case(1, hours=hours, hidden={"E_ch1": "speed_growth", "E_ch3": "ambient_coupling"})
        run = tr.Run.from_frame(c.train, source=f"shop-{n}")
        m = Machine.from_toml(c.nominal_toml())
        t0 = time.perf_counter()
        d = diagnose_axes(run, m)
        dt = time.perf_counter() - t0
        print(f"{len(run):>8} {hours:>7.1f} {dt:>8.1f}  " + ", ".join(d[a].verdict for a in d.axes), flush=True)


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--seeds", default="1-5")
    p.add_argument("--timing", action="store_true")
    p.add_argument("--rows", default="1000,10000,100000")
    args = p.parse_args()
    if args.timing:
        timing([int(v) for v in args.rows.split(",")])
        return
    a, b = (int(v) for v in args.seeds.split("-"))
    verdicts = ["thermal_lag", "ambient_coupling", "speed_growth", "unmodeled_source",
                "nonlinear_expansion", "sensor_drift", "none", "unexplained"]
    table: dict[str, Counter] = {h: Counter() for h in syn.HIDDEN}
    col_ok = col_n = 0
    times = []
    gains: dict[str, list[float]] = {h: [] for h in syn.HIDDEN}
    for topo in ("vmc", "lathe"):
        for h in syn.HIDDEN:
            for seed in range(a, b + 1):
                c = syn.make_case(topo, h, seed)
                t0 = time.perf_counter()
                d = diagnose(tr.Run.from_frame(c.train), Machine.from_toml(c.nominal_toml()), tr.Run.from_frame(c.test))
                times.append(time.perf_counter() - t0)
                table[h][d.verdict] += 1
                gains[h].append(d.gain_pct)
                if c.column:
                    col_n += 1
                    col_ok += d.column == c.column
    print(f"{'hidden / verdict':<20}" + "".join(f"{v[:12]:>13}" for v in verdicts) + "   mean gain %")
    for h in syn.HIDDEN:
        print(f"{h:<20}" + "".join(f"{table[h][v]:>13}" for v in verdicts) + f"   {sum(gains[h]) / len(gains[h]):8.1f}")
    print(f"column right: {col_ok}/{col_n}; time per diagnosis: mean {sum(times) / len(times):.2f} s, max {max(times):.2f} s")


if __name__ == "__main__":
    main()
