"""Seed 004's search: CSO over (log10 C, log10 γ) of an RBF ε-SVR by 5-fold CV MSE on 45
samples, population 20 × 100 generations. Ours: `tune_svr` (Rust CSO, each generation's points
fit native and parallel). Reference: pymetaheuristic's chicken swarm optimiser (`chicken_so`;
mealpy's "CSO" is cat swarm, another method) driving scikit-learn's SVR through
`cross_val_score` on the same folds, same population, generations and bounds. The note gives the
CV MSE each reached (different random streams: compare the values, not the points).

pymetaheuristic is optional (``pip install ".[bench]"``); without it the row says so.

``python benches/bench_tune.py --shop`` runs the same budget at a real size (issue 12 point 4):
the shipped shop run's training rows (``make_shop_case(1)``, first 60 % = 6 624 rows × 16
temperature rises, target ``E_ch1``; ``--channel`` picks another), 5 time-ordered folds, the
seed's bounds C ∈ [0.1, 100], γ ∈ [1e-3, 1]. Ours twice: the default search (``thin="auto"``:
the swarm on every 6th row, its 16 best points scored on every row) and the plain search on every
row (``thin=1``: the same path, bit for bit, as fitting every fold of every point), each with its
CV MSE on every row and the test MAE (rows 60-80 %) of its refitted SVR. The references would
take hours, so their time is extrapolated, and said to be: scikit-learn's 5-fold
``cross_val_score`` timed at ``SAMPLE`` points drawn uniformly in the log box plus the search's
optimum, times the search's 2 020 evaluations (pymetaheuristic's ``chicken_so`` adds nothing
measurable to that); ``GridSearchCV(n_jobs=2)`` timed on a 3 × 3 grid of the box, per point,
times 2 020. About 15 minutes on 2 cores (``--no-plain``: about 2 minutes)."""

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


SAMPLE = 6


def shop_rows(channel: str = "E_ch1", plain: bool = True) -> list[dict]:
    """The seed-004 budget on the shop run's training rows (see the module docstring)."""
    import sys
    import time
    from pathlib import Path

    import thermerr_rs as tr

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from shop_benchmark import FEATURES, shop_run, split

    run = shop_run()
    rows, test = split(len(run))
    x_all = run.matrix(FEATURES)
    x_all = x_all - x_all[0]
    x, y = x_all[rows], run[channel][rows]
    bounds = {"C": (0.1, 100.0), "gamma": (1e-3, 1.0)}
    size = f"{x.shape[0]} x {x.shape[1]}, 5 time folds"
    searches = [("default (thin auto)", "auto")] + ([("plain (thin 1)", 1)] if plain else [])
    out, res = [], {}
    for label, thin in searches:
        t0 = time.perf_counter()
        r = tr.tune_svr(x, y, bounds=bounds, pop=20, iters=100, seed=0, progress=False, thin=thin)
        t = time.perf_counter() - t0
        mae = float(np.mean(np.abs(r.model.predict(x_all[test]) - run[channel][test])))
        res[label] = (r, t, mae)
        print(f"ours {label}: {t:.0f} s, thin {r.thin}, C {r.C:.6g} gamma {r.gamma:.6g} CV MSE {r.cv_mse:.6g}, "
              f"test MAE {mae:.4f} um, {r.n_fits} fold fits", flush=True)
    from sklearn.model_selection import GridSearchCV, TimeSeriesSplit, cross_val_score
    from sklearn.svm import SVR

    best = res[searches[0][0]][0]
    cv = TimeSeriesSplit(5)
    rng = np.random.default_rng(0)
    pts = [(10 ** rng.uniform(-1, 2), 10 ** rng.uniform(-3, 0)) for _ in range(SAMPLE)] + [(best.C, best.gamma)]
    t0 = time.perf_counter()
    for c, g in pts:
        cross_val_score(SVR(C=c, gamma=g), x, y, cv=cv, scoring="neg_mean_squared_error")
    per_eval = (time.perf_counter() - t0) / len(pts)
    grid = {"C": np.logspace(-1, 2, 3), "gamma": np.logspace(-3, 0, 3)}
    t0 = time.perf_counter()
    GridSearchCV(SVR(), grid, cv=cv, scoring="neg_mean_squared_error", n_jobs=2).fit(x, y)
    per_grid = (time.perf_counter() - t0) / 9
    n = 20 * 101  # the seed's budget: the initial population and 100 generations
    for label, _ in searches:
        r, t, mae = res[label]
        note = f"{channel}: CV MSE {r.cv_mse:.6g}, test MAE {mae:.4f} um; {r.n_fits} fold fits"
        out.append(dict(task=f"CSO-SVR search, {label} vs sklearn cross_val_score x {n} (extrapolated)", size=size,
                        ours_s=t, ref_s=per_eval * n, ratio=per_eval * n / t,
                        note=note + f"; sklearn {per_eval:.2f} s per 5-fold evaluation, mean of {len(pts)} points"))
        out.append(dict(task=f"CSO-SVR search, {label} vs GridSearchCV(n_jobs=2) x {n} (extrapolated)", size=size,
                        ours_s=t, ref_s=per_grid * n, ratio=per_grid * n / t,
                        note=note + f"; GridSearchCV {per_grid:.2f} s per point on a 3 x 3 grid"))
    return out


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shop", action="store_true", help="the seed-004 budget on the shop run (about 15 min)")
    ap.add_argument("--channel", default="E_ch1", help="the shop run's probe channel of --shop (default E_ch1)")
    ap.add_argument("--no-plain", action="store_true", help="--shop without the plain search (about 2 min)")
    args = ap.parse_args()
    for row in (shop_rows(args.channel, not args.no_plain) if args.shop else rows()):
        print(f"{row['task']:<70} {row['size']:<26} ours {row['ours_s']:8.2f} s  ref {row['ref_s']:9.2f} s  "
              f"x{row['ratio']:.1f}  {row['note']}")
