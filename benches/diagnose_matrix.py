"""Confusion matrix of the diagnosis over synthetic machines: hidden cause x verdict.

    python benches/diagnose_matrix.py [--seeds 1-5]
    python benches/diagnose_matrix.py --timing [--rows 1000,10000,100000]

Each case: a fresh true machine (VMC Z axis or lathe X axis) hiding one effect (or none, or a
periodic disturbance outside the catalogue), a 20 h stepped training run and a 12 h random-duty
held-out run, a nominal model perturbed by 15-35 %. Prints the matrix, the column accuracy and
the time per diagnosis.

``--compound``: every pair of the six causes (15 pairs) hidden at once, on both topologies, for
each seed (:func:`thermerr_rs.synthetic.make_multi_case`; ``--hours 10,5 --dt 120`` by default,
the sizes of tests/test_diagnose_rounds.py). Per case: the causes named, whether both hidden
ones are among them, whether their columns are right, any cause named that was not hidden, the
held-out gain and the remainder; then a table per pair and the time per diagnosis.

    python benches/diagnose_matrix.py --compound [--seeds 1-2] [--hours 10,5] [--dt 120]

``--identified``: the rate sweep of tests/test_identify.py at any run length: each cause of
:data:`SWEEP` (and none) hidden on both topologies, for each seed, diagnosed once with the
network ``Machine.identify`` builds from the training run alone and once with the nominal TOML;
per cell the cases named right (the cause, and its column where it has one) by each, every miss
with its verdict, and the time of identification and of a diagnosis (``--hours 8,4 --dt 120`` by
default, the test's sizes).

    python benches/diagnose_matrix.py --identified [--seeds 1-2] [--hours 24,4] [--dt 60]

``--timing``: the time of one diagnosis of all five axes of the shop run
(:func:`thermerr_rs.synthetic.make_shop_case`: 15-s samples, sixteen sensors, ambient coupling
on E_ch3, speed growth on E_ch1) at each row count, with each axis's verdict.
"""

from __future__ import annotations

import argparse
import itertools
import time
from collections import Counter
from dataclasses import dataclass

import numpy as np

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


def diagnosed(c: syn.Case) -> tuple[tr.thermal.Diagnosis, float]:
    """The diagnosis of a synthetic case (training run, nominal machine, held-out run) and its time."""
    t0 = time.perf_counter()
    d = diagnose(tr.Run.from_frame(c.train, source="train"), Machine.from_toml(c.nominal_toml()),
                 tr.Run.from_frame(c.test, source="test"))
    return d, time.perf_counter() - t0


PAIRS = list(itertools.combinations(syn.CAUSES, 2))


@dataclass
class Outcome:
    """One compound case: the causes named (cause -> column), both hidden causes among them,
    columns right of the hidden causes that have one, the causes named that were not hidden,
    the held-out gain and remainder, the time."""

    named: dict[str, str | None]
    verdict: str
    both: bool
    cols_ok: int
    cols_n: int
    extra: list[str]
    gain: float
    remainder_um: float
    seconds: float


def compound_case(topo: str, pair: tuple[str, ...], seed: int, hours: tuple[float, float], dt: float) -> Outcome:
    """Diagnose one pair hidden at once (make_multi_case raises ValueError if it cannot be made)."""
    c = syn.make_multi_case(topo, pair, seed, hours=hours, dt=dt)
    d, dt_s = diagnosed(c)
    named = {x["cause"]: x["column"] for x in d.causes}
    with_col = [h for h in pair if c.columns.get(h)]
    return Outcome(
        named=named,
        verdict=d.verdict,
        both=all(h in named for h in pair),
        cols_ok=sum(named.get(h) == c.columns[h] for h in with_col),
        cols_n=len(with_col),
        extra=[f"{k}({v})" if v else k for k, v in named.items() if k not in pair],
        gain=d.gain_pct,
        remainder_um=d.remainder_um,
        seconds=dt_s,
    )


def compound(seeds: range, hours: tuple[float, float], dt: float) -> None:
    pairs = PAIRS
    rows: list[tuple[str, tuple[str, ...], Outcome | None]] = []
    for topo in ("vmc", "lathe"):
        for pair in pairs:
            for seed in seeds:
                try:
                    o = compound_case(topo, pair, seed, hours, dt)
                except ValueError as e:
                    print(f"{topo} {'+'.join(pair)} {seed}: not constructible: {e}", flush=True)
                    rows.append((topo, pair, None))
                    continue
                rows.append((topo, pair, o))
                got = ", ".join(f"{k}({v})" if v else k for k, v in o.named.items()) or o.verdict
                print(f"{topo:<6} {'+'.join(pair):<40} {seed}: {'both' if o.both else 'MISS':<5} "
                      f"named: {got}; gain {o.gain:.0f} %, remainder {o.remainder_um:.2f} µm, "
                      f"{o.seconds:.1f} s", flush=True)
    print(f"\n{'topology':<7} {'pair':<40} {'both named':>10} {'columns':>8} {'gain %':>7}  other causes named")
    for topo in ("vmc", "lathe"):
        for pair in pairs:
            outs = [r[2] for r in rows if r[0] == topo and r[1] == pair and r[2] is not None]
            if not outs:
                print(f"{topo:<7} {'+'.join(pair):<40} {'not constructible':>10}")
                continue
            n_both = sum(g.both for g in outs)
            cols = f"{sum(g.cols_ok for g in outs)}/{sum(g.cols_n for g in outs)}" if any(g.cols_n for g in outs) else "-"
            others = sorted({e for g in outs for e in g.extra})
            print(f"{topo:<7} {'+'.join(pair):<40} {f'{n_both}/{len(outs)}':>10} {cols:>8} "
                  f"{np.mean([g.gain for g in outs]):7.1f}  {', '.join(others)}")
    done = [o for _, _, o in rows if o is not None]
    print(f"\nboth named: {sum(g.both for g in done)}/{len(done)}; columns right: {sum(g.cols_ok for g in done)}/"
          f"{sum(g.cols_n for g in done)}; a cause named that was not hidden: {sum(bool(g.extra) for g in done)}/{len(done)}")
    times = [o.seconds for o in done]
    if times:
        print(f"time per diagnosis: mean {np.mean(times):.1f} s, max {max(times):.1f} s ({hours[0]:g} h + {hours[1]:g} h at {dt:g} s)")


#: the causes of the identification's rate sweep (tests/test_identify.py), then none
SWEEP = ("ambient_coupling", "unmodeled_source", "thermal_lag", "sensor_drift", "none")


def named_right(c: syn.Case, d: tr.thermal.Diagnosis) -> bool:
    """The hidden cause is the verdict, with its column where it has one."""
    return d.verdict == c.hidden and (d.column == c.column or c.hidden not in ("sensor_drift", "unmodeled_source"))


def identified(seeds: range, hours: tuple[float, float], dt: float) -> None:
    totals = {"identified": 0, "nominal": 0}
    n_cases = 0
    t_id: list[float] = []
    t_diag: list[float] = []
    print(f"{'topology':<8} {'hidden':<18} {'identified':>10} {'nominal':>8}  misses (seed: verdict/column)")
    for topo in ("vmc", "lathe"):
        sub = {"identified": 0, "nominal": 0}
        for h in SWEEP:
            hits = {"identified": 0, "nominal": 0}
            misses: list[str] = []
            for seed in seeds:
                c = syn.make_case(topo, h, seed, hours=hours, dt=dt)
                train = tr.Run.from_frame(c.train, source="train")
                test = tr.Run.from_frame(c.test, source="test")
                t0 = time.perf_counter()
                m_id, _ = Machine.identify(train)
                t_id.append(time.perf_counter() - t0)
                for which, m in (("identified", m_id), ("nominal", Machine.from_toml(c.nominal_toml()))):
                    t0 = time.perf_counter()
                    d = diagnose(train, m, test)
                    t_diag.append(time.perf_counter() - t0)
                    if named_right(c, d):
                        hits[which] += 1
                    else:
                        misses.append(f"{which} {seed}: {d.verdict}" + (f"/{d.column}" if d.column else ""))
                n_cases += 1
            for which in hits:
                sub[which] += hits[which]
                totals[which] += hits[which]
            a, b = f"{hits['identified']}/{len(seeds)}", f"{hits['nominal']}/{len(seeds)}"
            print(f"{topo:<8} {h:<18} {a:>10} {b:>8}  " + "; ".join(misses), flush=True)
        k = len(seeds) * len(SWEEP)
        a, b = f"{sub['identified']}/{k}", f"{sub['nominal']}/{k}"
        print(f"{topo:<8} {'all':<18} {a:>10} {b:>8}", flush=True)
    print(f"\nnamed right: identified {totals['identified']}/{n_cases}, nominal {totals['nominal']}/{n_cases} "
          f"({hours[0]:g} h + {hours[1]:g} h at {dt:g} s); identification mean {np.mean(t_id):.2f} s, "
          f"diagnosis mean {np.mean(t_diag):.2f} s")


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--seeds", default="1-5", help="a seed (3) or a range of them (1-5)")
    p.add_argument("--timing", action="store_true")
    p.add_argument("--rows", default="1000,10000,100000")
    p.add_argument("--compound", action="store_true")
    p.add_argument("--identified", action="store_true")
    p.add_argument("--hours", default=None,
                   help="--compound, --identified: training and held-out hours (default 10,5 and 8,4)")
    p.add_argument("--dt", type=float, default=120.0, help="--compound, --identified: sampling step (s)")
    args = p.parse_args()
    if args.timing:
        timing([int(v) for v in args.rows.split(",")])
        return
    try:
        first, _, last = args.seeds.partition("-")
        a = int(first)
        b = int(last) if last else a
        if b < a:
            raise ValueError
    except ValueError:
        p.error(f"--seeds {args.seeds!r}: give a seed (3) or a range (1-5)")
    if args.compound or args.identified:
        hours = args.hours or ("10,5" if args.compound else "8,4")
        h_train, h_test = (float(v) for v in hours.split(","))
        (compound if args.compound else identified)(range(a, b + 1), (h_train, h_test), args.dt)
        return
    verdicts = ["thermal_lag", "ambient_coupling", "speed_growth", "unmodeled_source",
                "nonlinear_expansion", "sensor_drift", "none", "unexplained"]
    table: dict[str, Counter] = {h: Counter() for h in syn.HIDDEN}
    col_ok = col_n = 0
    moved: list[str] = []
    times = []
    gains: dict[str, list[float]] = {h: [] for h in syn.HIDDEN}
    for topo in ("vmc", "lathe"):
        for h in syn.HIDDEN:
            for seed in range(a, b + 1):
                c = syn.make_case(topo, h, seed)
                d, dt_s = diagnosed(c)
                times.append(dt_s)
                table[h][d.verdict] += 1
                gains[h].append(d.gain_pct)
                if not d.baseline_unique:
                    moved.append(f"{topo}/{h}/{seed} ({d.verdict})")
                if c.column:
                    col_n += 1
                    col_ok += d.column == c.column
    print(f"{'hidden / verdict':<20}" + "".join(f"{v[:12]:>13}" for v in verdicts) + "   mean gain %")
    for h in syn.HIDDEN:
        print(f"{h:<20}" + "".join(f"{table[h][v]:>13}" for v in verdicts) + f"   {sum(gains[h]) / len(gains[h]):8.1f}")
    print(f"column right: {col_ok}/{col_n}; time per diagnosis: mean {sum(times) / len(times):.2f} s, max {max(times):.2f} s")
    print(f"baseline not unique (a second start ends elsewhere held out, or a start stops at the "
          f"iteration limit): {len(moved)}/{len(times)}" + (f": {', '.join(moved)}" if moved else ""))


if __name__ == "__main__":
    main()
