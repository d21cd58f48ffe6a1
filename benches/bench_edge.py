"""Per-sample latency of the edge predictor (`thermerr-edge`, no Python) at seed sizes — 4 features;
RBF with 50 centres, SVR with ~50 support vectors, BP 4-7-1, rolling GM(1,N) over 6/8/10 samples + 3-7-1 network,
hybrid filters + 30-unit network — against scikit-learn's `predict` on one sample
(LinearRegression, SVR, MLPRegressor of the BP's shape; the others have no scikit-learn twin) and against our own Python API on one
sample. Edge latencies are measured inside the binary (`--bench-latency N`: a timer around each
`predict_sample`); the Python ones around each call. The note gives the binary's size and peak
resident memory.

    cargo build --release -p thermerr-edge && python benches/compare.py edge
"""

from __future__ import annotations

import json
import subprocess
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]
SIZES = ((4,),)


def edge_binary() -> Path:
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "thermerr-edge"], cwd=ROOT, check=True)
    meta = json.loads(subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps"], cwd=ROOT,
                                     check=True, capture_output=True, text=True).stdout)
    return Path(meta["target_directory"]) / "release" / "thermerr-edge"


def per_call(fn, x_rows: np.ndarray, n: int = 20000) -> tuple[float, float]:
    """p50 and p99 of one call, in seconds."""
    t = np.empty(n)
    k = len(x_rows)
    for i in range(n):
        x = x_rows[i % k : i % k + 1]
        t0 = time.perf_counter_ns()
        fn(x)
        t[i] = time.perf_counter_ns() - t0
    return float(np.percentile(t, 50)) * 1e-9, float(np.percentile(t, 99)) * 1e-9


def rows(sizes=SIZES, repeat: int = 3) -> list[dict]:
    from sklearn.linear_model import LinearRegression
    from sklearn.svm import SVR as SkSVR

    import thermerr_rs as tr

    exe = edge_binary()
    size_mb = exe.stat().st_size / 1e6
    train = tr.read_run(ROOT / "examples" / "hmc_run1.csv")
    test_csv = ROOT / "examples" / "hmc_run2.csv"
    x = train.matrix(SENSORS)
    x = x - x[0]
    y = train["E_z"]
    xt = tr.read_run(test_csv).matrix(SENSORS)
    xt = np.ascontiguousarray(xt - xt[0])
    ours = {
        "MLR": tr.MLR(),
        "RBF k=50": tr.RBFNetwork(design="kmeans", n_centers=50, spread=3.0, seed=0),
        "SVR": tr.SVR(C=10.0, epsilon=0.25, gamma=0.05),
        "BP 4-7-1": tr.BPNetwork(hidden=7, seed=0),
        "GM+BP (6,8,10)": tr.GreyBP(seed=0),
        "hybrid 30 tanh": tr.HybridFilterNet(seed=0),
    }
    from sklearn.neural_network import MLPRegressor

    refs = {"MLR": LinearRegression(), "SVR": SkSVR(C=10.0, epsilon=0.25, gamma=0.05),
            "BP 4-7-1": MLPRegressor(hidden_layer_sizes=(7,), activation="logistic", max_iter=2000, random_state=0)}
    out = []
    with tempfile.TemporaryDirectory() as d:
        for name, m in ours.items():
            m.fit_run(train, "E_z", SENSORS, inputs="rise")
            path = m.save(Path(d) / "m.json")
            r = subprocess.run([str(exe), str(path), str(test_csv), "--bench-latency", "200000"],
                               check=True, capture_output=True, text=True)
            e = json.loads(r.stdout)
            detail = f"{len(m.support_)} SV" if name == "SVR" else ""
            # one row through the Python API (for the grey and filter models a one-row run, so this
            # times the call, not a model with history)
            # (fitted on named run columns, the model warns at unnamed NumPy rows, as scikit-learn does)
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", "X does not have valid feature names", UserWarning)
                py50, py99 = per_call(m.predict, xt)
            if name in refs:
                ref = refs[name].fit(x, y)
                r50, r99 = per_call(ref.predict, xt)
                ref_name = "scikit-learn predict(1 row)"
            else:
                r50, r99, ref_name = py50, py99, "our Python API (no scikit-learn twin)"
            note = f"ref: {ref_name}; {detail + ', ' if detail else ''}binary {size_mb:.2f} MB, peak RSS {e['max_rss_kib'] / 1024:.1f} MiB"
            out.append(dict(task=f"edge {name} p50", size="1 sample x 4", ours_s=e["p50_ns"] * 1e-9, ref_s=r50,
                            ratio=r50 / (e["p50_ns"] * 1e-9), note=note))
            out.append(dict(task=f"edge {name} p99", size="1 sample x 4", ours_s=e["p99_ns"] * 1e-9, ref_s=r99,
                            ratio=r99 / (e["p99_ns"] * 1e-9), note=f"our Python API p50 {py50 * 1e6:.1f} µs, p99 {py99 * 1e6:.1f} µs"))
    return out
