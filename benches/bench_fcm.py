"""Fuzzy c-means: thermerr_rs against scikit-fuzzy's ``cmeans`` on the same data and the same
initial partition.

Equal work: both get the same ``init`` and the same iteration cap with a tolerance of 1e-300,
so they run the cap (on the smallest size ours can stop a little earlier, when the membership
change is exactly 0.0), and the figure compared is the time per iteration: total fit time /
iterations run, so our extra initial centre pass and all call overheads count on our side. Data: objects × features, four blobs with unit noise, 4 clusters, m = 2.
"""

from __future__ import annotations

import time

import numpy as np
import skfuzzy

from thermerr_rs import FuzzyCMeans

N_CLUSTERS = 4


def _iters(n: int, d: int) -> int:
    # 20 to 100 iterations: the largest size takes scikit-fuzzy a few seconds per fit
    return int(max(20, min(100, 2e9 // (4 * n * d * N_CLUSTERS))))


def _data(n: int, d: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((n, d))
    x += 0.05 * (np.arange(n) % N_CLUSTERS)[:, None]
    u0 = rng.random((n, N_CLUSTERS))
    return np.ascontiguousarray(x), u0 / u0.sum(axis=1, keepdims=True)


def _best(f, repeat: int) -> float:
    """Fastest time per iteration over `repeat` fits (f returns the iterations it ran)."""
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        k = f()
        best = min(best, (time.perf_counter() - t) / k)
    return best


def rows(sizes=((20, 500), (200, 5000), (2000, 20000)), repeat=3) -> list[dict]:
    out = []
    for n, d in sizes:
        x, u0 = _data(n, d)
        it = _iters(n, d)
        tol = 1e-300  # never met in practice: both run exactly `it` iterations
        xt, u0t = x.T, u0.T.copy()

        def ref() -> int:
            return int(skfuzzy.cluster.cmeans(xt, N_CLUSTERS, 2.0, tol, it, init=u0t)[5])

        def ours() -> int:
            return FuzzyCMeans(n_clusters=N_CLUSTERS, tol=tol, max_iter=it, init=u0).fit(x).n_iter_

        ours_s = _best(ours, repeat)
        ref_s = _best(ref, repeat)
        out.append(
            {
                "task": f"fcm fit, c={N_CLUSTERS}, per iteration ({it} it.)",
                "size": f"{n}x{d}",
                "ours_s": ours_s,
                "ref_s": ref_s,
                "ratio": ref_s / ours_s,
            }
        )
    return out


if __name__ == "__main__":
    print(f"{'task':<40} {'size':>11} {'ours_s':>10} {'ref_s':>10} {'ratio':>7}")
    for r in rows():
        print(f"{r['task']:<40} {r['size']:>11} {r['ours_s']:>10.3g} {r['ref_s']:>10.3g} {r['ratio']:>7.1f}")
