"""Seed 004 reproduced (Liu et al. 2022): MLR, PSO-SVR and CSO-SVR on a spindle idling at
3000 rpm for 3 h, 4 sensors, a sample every 3 min (60 samples), 45 random samples for training and
15 for test; then the model trained at 3000 rpm predicts runs at 2000 and 4000 rpm.

The runs come from the project's thermal simulation (examples/make_spindle_example.py); inputs
are each sensor's rise since the start of the run, the target the axial drift E_z in µm. The
swarms search (C, γ) of an RBF ε-SVR (ε = 0.1 µm) on log10 scales within C ∈ [0.1, 100],
γ ∈ [1e-3, 1], minimising the 5-fold CV MSE on the 45 training samples, population 20 ×
100 generations (the seed's budget), seed 0.

    python benches/seed004.py            # prints the table (and the search times)
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import thermerr_rs as tr

EX = Path(__file__).resolve().parents[1] / "examples"
SENSORS = ["T_front_bearing", "T_headstock", "T_column", "T_bed"]


def load(rpm: int) -> tuple[np.ndarray, np.ndarray]:
    run = tr.read_run(EX / f"spindle_{rpm}rpm.csv")
    x = run.matrix(SENSORS)
    x = x - x[0]
    return x[1:], run["E_z"][1:]  # the 60 samples after the start


def main(seed: int = 0) -> list[dict]:
    x, y = load(3000)
    rng = np.random.default_rng(seed)
    idx = rng.permutation(len(y))
    tr_i, te_i = np.sort(idx[:45]), np.sort(idx[45:])
    bounds = {"C": (0.1, 100.0), "gamma": (1e-3, 1.0)}
    models: dict[str, tr.Estimator] = {"MLR": tr.MLR().fit(x[tr_i], y[tr_i])}
    info = {}
    for method in ("pso", "cso"):
        t0 = time.perf_counter()
        # 45 random samples: no time order to keep; the seed's shuffled 5-fold
        res = tr.tune_svr(x[tr_i], y[tr_i], method=method, cv=5, cv_kind="kfold", bounds=bounds, pop=20, iters=100, seed=seed, progress=False)
        info[method] = (time.perf_counter() - t0, res)
        models[f"{method.upper()}-SVR"] = res.model
    sets = {"3000 rpm train": (x[tr_i], y[tr_i]), "3000 rpm test": (x[te_i], y[te_i])}
    for rpm in (2000, 4000):
        sets[f"{rpm} rpm"] = load(rpm)
    rows = []
    print(f"{'model':<9} {'data':<15} {'mean acc. %':>11} {'RMS µm':>8} {'max µm':>8} {'band µm':>8}")
    for name, m in models.items():
        for label, (xs, ys) in sets.items():
            s = tr.scores(ys, m.predict(xs))
            acc = 100 * s.mean_accuracy if s.mean_accuracy is not None else float("nan")
            rows.append(dict(model=name, data=label, acc=acc, rms=s.rms, max=s.max_abs, band=s.band))
            print(f"{name:<9} {label:<15} {acc:>11.2f} {s.rms:>8.3f} {s.max_abs:>8.3f} {s.band:>8.3f}")
    for method, (dt, res) in info.items():
        print(f"{method.upper()}-SVR: C = {res.C:.4g}, gamma = {res.gamma:.4g}, 5-fold CV MSE {res.cv_mse:.4g} µm², "
              f"{res.n_evals} evaluations x 5 folds in {dt:.2f} s")
    return rows


if __name__ == "__main__":
    main()
