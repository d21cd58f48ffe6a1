"""Fuzzy c-means: thermerr_rs vs scikit-fuzzy's cmeans, same data, same initial partition, and
the same number of iterations (a fixed iteration count: both run exactly ``iters`` updates, so the
table compares equal work)."""

from __future__ import annotations

import numpy as np

from _timing import best_of

SIZES = ((20, 500), (200, 5000), (2000, 20000))  # objects x features
C = 4


def rows(sizes=SIZES, repeat: int = 3, iters: int = 30) -> list[dict]:
    import skfuzzy

    import thermerr_rs as tr

    out = []
    for n, d in sizes:
        rng = np.random.default_rng(0)
        x = np.cumsum(rng.normal(size=(n, d)), axis=1)
        x = (x - x.min(axis=1, keepdims=True)) / np.ptp(x, axis=1, keepdims=True)
        u0 = rng.random((n, C))
        u0 /= u0.sum(axis=1, keepdims=True)
        r = 1 if n * d >= 4e7 else repeat
        # tol = 0 (never met): both run exactly `iters` iterations
        ours = best_of(lambda: tr.FuzzyCMeans(n_clusters=C, tol=1e-300, max_iter=iters, init=u0).fit(x), r)
        ref = best_of(lambda: skfuzzy.cluster.cmeans(x.T, C, 2.0, error=0.0, maxiter=iters, init=u0.T), r)
        a = tr.FuzzyCMeans(n_clusters=C, tol=1e-300, max_iter=iters, init=u0).fit(x)
        _, u, *_ = skfuzzy.cluster.cmeans(x.T, C, 2.0, error=0.0, maxiter=iters, init=u0.T)
        diff = float(np.max(np.abs(a.membership_ - u.T)))
        out.append(dict(task=f"FCM fit ({iters} iter)", size=f"{n} x {d}", ours_s=ours, ref_s=ref,
                        ratio=ref / ours, note=f"max |U diff| {diff:.1e}"))
    return out


if __name__ == "__main__":
    from compare import print_table

    print_table(rows())
