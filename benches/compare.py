"""One run, one table: thermerr_rs side by side with the reference implementations.

    pip install ".[test]"            # release build of the extension + scikit-learn, scikit-fuzzy
    python benches/compare.py        # all families
    python benches/compare.py mlr    # one family (mlr, fcm, rbf, svr, tune, nets, thermal, edge)
    python benches/compare.py --quick   # smaller sizes only

ratio = reference time / our time (> 1: we are faster). Times are the best of a few runs, in s.
Speed is measured here, never asserted in the tests.
"""

from __future__ import annotations

import argparse
import importlib
import os
import platform
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

FAMILIES = ["mlr", "fcm", "rbf", "svr", "tune", "nets", "thermal", "edge"]


def print_table(rows: list[dict]) -> None:
    head = f"{'task':<24} {'size':>16} {'thermerr_rs (s)':>16} {'reference (s)':>14} {'ratio':>8}  note"
    print(head)
    print("-" * len(head))
    for r in rows:
        print(f"{r['task']:<24} {r['size']:>16} {r['ours_s']:>16.4g} {r['ref_s']:>14.4g} "
              f"{r['ratio']:>7.1f}x  {r.get('note', '')}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("families", nargs="*", default=FAMILIES)
    p.add_argument("--quick", action="store_true", help="only the smaller sizes")
    args = p.parse_args()
    import numpy as np

    import thermerr_rs

    print(f"thermerr_rs {thermerr_rs.__version__}, numpy {np.__version__}, Python {platform.python_version()}, "
          f"{platform.machine()}, {os.cpu_count()} cpus")
    rows: list[dict] = []
    for fam in args.families:
        mod = importlib.import_module(f"bench_{fam}")
        kw = {"sizes": mod.SIZES[:2]} if args.quick and hasattr(mod, "SIZES") else {}
        rows.extend(mod.rows(**kw))
    print_table(rows)


if __name__ == "__main__":
    main()
