"""thermerr_rs.fleet: N runs fitted serially in this process vs on Dask with 1 and 2 workers
(the default threaded scheduler, and a LocalCluster of worker processes).

    python benches/bench_fleet.py [--runs 16] [--model greybp] [--workers 1 2]

The runs are copies of examples/hmc_run1.csv (193 samples, 20 sensors, the shape of a day's run
on a horizontal machining centre). The default model, GM(1,N) + BP (seeded network training,
~0.4 s a run on one core), is long enough for the batch's overhead not to hide the parallelism;
``--model mlr`` shows the other end (a few ms a run: the overhead is all there is). Every batch
is checked to give the serial fit's numbers. Each figure is the best of ``--repeat`` batches; the
cluster's start-up is timed apart from its batches. "CPU s" is this process's CPU time (all its
threads): above the wall time, the threads ran the kernels at once (the GIL released).
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def serial(paths: list[Path], model: str, out: Path) -> list[float]:
    """Each run fitted in turn, in this process, as ``thermerr fit`` would fit it."""
    import thermerr_rs as tr
    from thermerr_rs.fleet import _build

    out.mkdir(parents=True, exist_ok=True)
    rms = []
    for p in paths:
        run = tr.read_run(p)
        est = _build(model, {}, 0, run["E_z"])
        est.fit_run(run, "E_z", run.temperatures, inputs="rise")
        est.save(out / f"{p.stem}.json")
        rms.append(tr.scores(run["E_z"], est.predict_run(run)).rms)
    return rms


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=16)
    ap.add_argument("--model", default="greybp")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=2, help="best of this many batches (default 2)")
    a = ap.parse_args()

    from distributed import Client, LocalCluster

    from thermerr_rs import fleet

    tmp = Path(tempfile.mkdtemp(prefix="bench_fleet_"))
    try:
        runs = tmp / "runs"
        runs.mkdir()
        for i in range(a.runs):
            shutil.copy(ROOT / "examples" / "hmc_run1.csv", runs / f"m{i:03d}.csv")
        paths = fleet.run_paths(runs)
        print(f"{a.runs} runs of 193 samples x 20 sensors, model {a.model}; {os.cpu_count()} CPUs, "
              f"load average {os.getloadavg()[0]:.2f} at the start")

        ref: list[float] = []

        def check(res: list[fleet.RunResult]) -> None:
            got = [r.figures["rms"] for r in res]
            assert all(r.ok for r in res) and got == ref, "a batch differs from the serial fits"

        def timed(fn: Callable[[], Any]) -> tuple[float, float, Any]:
            """Best wall time of ``a.repeat`` calls, this process's CPU time in it, the result."""
            best = (float("inf"), 0.0, None)
            for _ in range(max(1, a.repeat)):
                t0, c0 = time.perf_counter(), time.process_time()
                out = fn()
                wall, cpu = time.perf_counter() - t0, time.process_time() - c0
                if wall < best[0]:
                    best = (wall, cpu, out)
            return best

        base, cpu, ref[:] = timed(lambda: serial(paths, a.model, tmp / "serial"))
        rows = [("serial, in-process loop", base, f"{cpu:8.2f}", "")]
        for w in a.workers:
            s, cpu, res = timed(lambda: fleet.fit_runs(runs, "E_z", a.model, tmp / f"threads{w}", workers=w))
            rows.append((f"fleet, threads, {w} worker{'s' if w > 1 else ''}", s, f"{cpu:8.2f}", ""))
            check(res)
        for w in a.workers:
            t0 = time.perf_counter()
            with LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=None,
                              silence_logs=40) as lc, Client(lc) as client:
                client.run(lambda: __import__("thermerr_rs.fleet"))  # a long-lived cluster has it imported
                start = time.perf_counter() - t0
                s, _, res = timed(lambda: fleet.fit_runs(runs, "E_z", a.model, tmp / f"cluster{w}", scheduler=client))
                rows.append((f"fleet, LocalCluster, {w} worker process{'es' if w > 1 else ''}", s, "       -",
                             f"(+ {start:.1f} s to start the cluster and import thermerr_rs on it)"))
            check(res)

        print(f"{'':40s} {'wall s':>8s} {'CPU s':>8s} {'speed-up':>9s}")
        for name, s, cpu_s, note in rows:
            print(f"{name:40s} {s:8.2f} {cpu_s} {base / s:8.2f}x {note}")
        print(f"load average {os.getloadavg()[0]:.2f} at the end; every batch gave the serial fits' numbers")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
