"""Endurance of the edge predictor (issue 13 point 4): a week of 1 s samples (604 800 rows) with
injected faults (benches/_endurance.py: dropouts, a stuck sensor, spikes, garbage lines, wrong
field counts, a truncated last line) piped through `thermerr-edge` on stdin, for an MLR and an RBF
model fitted on a clean run. Prints JSON lines:

- ``stream``: exit status, data lines in, output lines, rows/s through the pipe (data lines over the
  wall time from the first byte written to the exit; the generator is not timed), peak resident
  memory of the binary (VmHWM once every complete line is read) and that of a 10 000-row run of the
  same kind (flat memory: the two agree), rejected lines (stderr) against the injected unreadable
  ones, and whether every output line is well formed;
- ``latency``: `--bench-latency N` on the fault-free twin of the week (N = the rows): per-sample
  p50 / p99 / mean inside the binary, and whether p99 is under 5 µs (the issue's bound).

    python benches/bench_endurance.py [--rows 604800] [--seed 7]

The binary: $THERMERR_EDGE_BIN, else `cargo build --release -p thermerr-edge`. Figures:
docs/testing.md ("Endurance").
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _endurance as en  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
LINE = re.compile(rb"\d+,-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?:,[^,\n]+)*")
GUARDED_LINE = re.compile(rb"\d+,-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?,"
                          rb"(?:ok|(?:held|fallback|frozen):\w+(?:;(?:held|fallback|frozen):\w+)*)")
SKIPPED = re.compile(rb"thermerr-edge: line (\d+): .+; skipped")
SMALL = 10_000


def edge_binary() -> Path:
    if os.environ.get("THERMERR_EDGE_BIN"):
        return Path(os.environ["THERMERR_EDGE_BIN"])
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "thermerr-edge"], cwd=ROOT, check=True)
    meta = json.loads(subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps"], cwd=ROOT,
                                     check=True, capture_output=True, text=True).stdout)
    return Path(meta["target_directory"]) / "release" / "thermerr-edge"


def streamed(exe: Path, model: Path, csv: Path, faults: list[en.Fault], n_rows: int, guard: bool = False) -> dict:
    # with the sensor-fault guard only unreadable lines are rejected; the rest carry a status
    rejected = {f.line for f in faults if (f.unreadable if guard else f.rejects(set(en.TEMPS)))}
    line_re = GUARDED_LINE if guard else LINE
    n_lines = n_rows + sum(f.row is None for f in faults)
    s = en.stream(exe, model, csv, expect_lines=1 + n_lines - len(rejected))
    out = s.stdout.split(b"\n")
    body, last = out[1:-1], out[-1]
    reported = [SKIPPED.fullmatch(e) for e in s.stderr.split(b"\n")[:-1]]
    return dict(exit=s.returncode, data_lines=n_lines, output_rows=len(body),
                expected_rows=n_lines - len(rejected), rows_per_s=round(n_lines / s.wall_s), wall_s=round(s.wall_s, 3),
                peak_rss_kib=s.peak_rss_kib, rejected=len(reported),
                rejected_as_injected=all(reported) and {int(m.group(1)) for m in reported if m} == rejected,
                well_formed=last == b"" and all(line_re.fullmatch(b) for b in body),
                held_or_fallback_rows=sum(not b.endswith(b",ok") for b in body) if guard else None)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", type=int, default=7 * en.DAY_S, help="samples at 1 s (default: a week, 604800)")
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args(argv)

    import thermerr_rs as tr

    exe = edge_binary()
    print(json.dumps(dict(machine=f"{platform.machine()}, {os.cpu_count()} CPUs, load average "
                                  f"{os.getloadavg()[0]:.2f} at the start", rows=args.rows, seed=args.seed)))
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        en.write_run(d / "train.csv", 5_000, seed=1, faults=False)
        train = tr.read_run(d / "train.csv")
        models = {
            "MLR": (tr.MLR(), False),
            "MLR + guard": (tr.MLR(), True),
            "RBF k=20": (tr.RBFNetwork(design="kmeans", n_centers=20, spread=3.0, seed=0), False),
        }
        faults = en.write_run(d / "week.csv", args.rows, seed=args.seed)
        en.write_run(d / "clean.csv", args.rows, seed=args.seed, faults=False)
        small = en.write_run(d / "small.csv", SMALL, seed=args.seed)
        counts: dict[str, int] = {}
        for f in faults:
            counts[f.kind] = counts.get(f.kind, 0) + 1
        print(json.dumps(dict(faults=counts, stuck_rows=sum(f.n for f in faults if f.kind == "stuck"))))
        for name, (m, guard) in models.items():
            m.fit_run(train, "E_x", en.TEMPS, inputs="rise")
            if guard:
                tr.add_guard(m, train)
            path = m.save(d / "model.json")
            week = streamed(exe, path, d / "week.csv", faults, args.rows, guard)
            ref = streamed(exe, path, d / "small.csv", small, SMALL, guard)
            week["peak_rss_kib_10k_rows"] = ref["peak_rss_kib"]
            print(json.dumps(dict(model=name, kind="stream", **week)))
            r = subprocess.run([str(exe), str(path), str(d / "clean.csv"), "--bench-latency", str(args.rows)],
                               check=True, capture_output=True, text=True)
            e = json.loads(r.stdout)
            print(json.dumps(dict(model=name, kind="latency", samples=e["samples"], p50_ns=e["p50_ns"],
                                  p99_ns=e["p99_ns"], mean_ns=e["mean_ns"], p99_under_5us=e["p99_ns"] < 5000,
                                  max_rss_kib_all_rows_loaded=e["max_rss_kib"])))
    print(json.dumps(dict(load_average_at_the_end=round(os.getloadavg()[0], 2))))


if __name__ == "__main__":
    main()
