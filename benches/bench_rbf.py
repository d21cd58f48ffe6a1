"""RBF fit/predict: thermerr_rs vs the same work done with numpy/scipy and scikit-learn.

exact design (newrbe): ours = Rust Gaussian matrix + LU of the bordered interpolation system;
reference = numpy Gaussian matrix + numpy.linalg.lstsq (minimum-norm; another exact solution). kmeans design:
ours = k-means (Lloyd, from k-means++) + least squares; reference = scikit-learn KMeans
(n_init=1) + numpy lstsq. Sizes are samples x features; the exact design is O(n³), so the large
size uses the kmeans design only."""

from __future__ import annotations

import numpy as np

from _timing import best_of

SIZES = ((500, 20), (2000, 20), (20000, 20))
B = np.sqrt(np.log(2.0))


def gauss(x, c, spread):
    d2 = (x**2).sum(1)[:, None] - 2 * x @ c.T + (c**2).sum(1)[None, :]
    return np.exp(-((B / spread) ** 2) * np.maximum(d2, 0))


def rows(sizes=SIZES, repeat: int = 3) -> list[dict]:
    from sklearn.cluster import KMeans

    import thermerr_rs as tr

    out = []
    for n, d in sizes:
        rng = np.random.default_rng(0)
        x = rng.uniform(0, 1, (n, d))
        y = np.sin(x.sum(1)) + rng.normal(0, 0.01, n)
        spread = 0.5 * np.sqrt(d)
        r = 1 if n > 5000 else repeat
        if n <= 2000:
            def ref_exact():
                a = np.column_stack([gauss(x, x, spread), np.ones(n)])
                return np.linalg.lstsq(a, y, rcond=None)[0]

            ours = best_of(lambda: tr.RBFNetwork(design="exact", spread=spread).fit(x, y), r)
            ref = best_of(ref_exact, r)
            out.append(dict(task="RBF exact fit", size=f"{n} x {d}", ours_s=ours, ref_s=ref, ratio=ref / ours, note="ours LU bordered, ref lstsq"))
        k = 50

        def ref_kmeans():
            km = KMeans(n_clusters=k, n_init=1, random_state=0).fit(x)
            a = np.column_stack([gauss(x, km.cluster_centers_, spread), np.ones(n)])
            return km, np.linalg.lstsq(a, y, rcond=None)[0]

        ours = best_of(lambda: tr.RBFNetwork(design="kmeans", n_centers=k, spread=spread, seed=0).fit(x, y), r)
        ref = best_of(ref_kmeans, r)
        out.append(dict(task=f"RBF kmeans fit (k={k})", size=f"{n} x {d}", ours_s=ours, ref_s=ref, ratio=ref / ours, note=""))
        net = tr.RBFNetwork(design="kmeans", n_centers=k, spread=spread, seed=0).fit(x, y)
        km, w = ref_kmeans()
        ours = best_of(lambda: net.predict(x), repeat)
        ref = best_of(lambda: np.column_stack([gauss(x, km.cluster_centers_, spread), np.ones(n)]) @ w, repeat)
        out.append(dict(task=f"RBF predict (k={k})", size=f"{n} x {d}", ours_s=ours, ref_s=ref, ratio=ref / ours, note=""))
    return out


if __name__ == "__main__":
    from compare import print_table

    print_table(rows())
