"""Seed 004's search: CSO over (log10 C, log10 γ) of an RBF ε-SVR by 5-fold CV MSE on 45
samples, population 20 × 100 generations. Ours: `tune_svr` (Rust CSO, every population × fold
fit native and parallel). Reference: pymetaheuristic's chicken swarm optimiser (`chicken_so`;
mealpy's "CSO" is cat swarm, another method) driving scikit-learn's SVR through
`cross_val_score` on the same folds, same population, generations and bounds. The note gives the
CV MSE each reached (different random streams: compare the values, not the points).

pymetaheuristic is optional (``pip install ".[bench]"``); without it the row says so."""

from __future__ import annotations

import numpy as np

from _timing import best_of

SIZES = ((45, 4),)


def rows(sizes=SIZES, repeat: int = 3) -> list[dict]:
    import sys
    from pathlib import Path

    import thermerr_rs as tr

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from seed004 import load

    x, y = load(3000)
    idx = np.random.default_rng(0).permutation(len(y))[:45]
    x, y = x[np.sort(idx)], y[np.sort(idx)]
    bounds = {"C": (0.1, 100.0), "gamma": (1e-3, 1.0)}
    folds = tr.kfold_split(len(y), 5, seed=0)  # the seed's shuffled folds, as (train, test)
    res = {}

    def ours():
        res["ours"] = tr.tune_svr(x, y, method="cso", cv=folds, bounds=bounds, pop=20, iters=100, seed=0, progress=False)

    t_ours = best_of(ours, repeat)
    try:
        from pymetaheuristic import optimize
    except ImportError:
        return [dict(task="CSO-SVR search (pop 20 x 100)", size="45 x 4, 5-fold", ours_s=t_ours, ref_s=float("nan"),
                     ratio=float("nan"), note=f"CV MSE {res['ours'].cv_mse:.4g}; pymetaheuristic not installed")]
    from sklearn.model_selection import cross_val_score
    from sklearn.svm import SVR

    cv = folds

    def objective(v):
        m = SVR(C=10 ** v[0], gamma=10 ** v[1])
        return float(-cross_val_score(m, x, y, cv=cv, scoring="neg_mean_squared_error").mean())

    lo = [np.log10(bounds["C"][0]), np.log10(bounds["gamma"][0])]
    hi = [np.log10(bounds["C"][1]), np.log10(bounds["gamma"][1])]

    def ref():
        res["ref"] = optimize("chicken_so", target_function=objective, min_values=lo, max_values=hi,
                              max_steps=100, seed=0, size=20, g=10)

    t_ref = best_of(ref, 1)
    o, r = res["ours"], res["ref"]
    note = (f"CV MSE ours {o.cv_mse:.4g} ({o.n_evals} evals), pymetaheuristic+sklearn {r.best_fitness:.4g} "
            f"({r.evaluations} evals)")
    return [dict(task="CSO-SVR search (pop 20 x 100)", size="45 x 4, 5-fold", ours_s=t_ours, ref_s=t_ref,
                 ratio=t_ref / t_ours, note=note)]
