"""ε-SVR fit and predict: thermerr_rs (Rust SMO) vs scikit-learn's SVR (LIBSVM), same data, C,
epsilon, γ and tol. The note checks that both reach the same model: the number of support
vectors, the SMO iterations and the largest difference of the test predictions."""

from __future__ import annotations

import numpy as np

from _timing import best_of

# (n, d, C, epsilon): seed 004's size, then the issue's larger sets
SIZES = ((60, 4, 7.3465, 0.1), (2000, 10, 10.0, 0.05), (10000, 8, 1.0, 0.1))


def data(n: int, d: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, d))
    y = np.sin(x[:, 0]) + 0.5 * x[:, 1] ** 2 - x[:, 2] * x[:, 3] + 0.1 * rng.normal(size=n)
    return x, y


def rows(sizes=SIZES, repeat: int = 3) -> list[dict]:
    from sklearn.svm import SVR as SkSVR

    import thermerr_rs as tr

    out = []
    for n, d, C, eps in sizes:
        x, y = data(n, d)
        xt, _ = data(2000, d, seed=1)
        gamma = 1.0 / d
        r = 1 if n > 5000 else repeat
        ours_t = best_of(lambda: tr.SVR(C=C, epsilon=eps, gamma=gamma).fit(x, y), r)
        ref_t = best_of(lambda: SkSVR(C=C, epsilon=eps, gamma=gamma).fit(x, y), r)
        ours = tr.SVR(C=C, epsilon=eps, gamma=gamma).fit(x, y)
        ref = SkSVR(C=C, epsilon=eps, gamma=gamma).fit(x, y)
        diff = float(np.abs(ours.predict(xt) - ref.predict(xt)).max())
        same = f"nSV {len(ours.support_)}/{len(ref.support_)}, iter {ours.n_iter_}/{ref.n_iter_}, max|dpred| {diff:.1e}"
        out.append(dict(task="SVR fit", size=f"{n} x {d}", ours_s=ours_t, ref_s=ref_t, ratio=ref_t / ours_t, note=same))
        ours_p = best_of(lambda: ours.predict(xt), repeat)
        ref_p = best_of(lambda: ref.predict(xt), repeat)
        out.append(dict(task="SVR predict 2000 rows", size=f"{n} x {d}", ours_s=ours_p, ref_s=ref_p, ratio=ref_p / ours_p, note=""))
        one = xt[:1]
        ours_1 = best_of(lambda: ours.predict(one), 200)
        ref_1 = best_of(lambda: ref.predict(one), 200)
        out.append(dict(task="SVR predict 1 row", size=f"{n} x {d}", ours_s=ours_1, ref_s=ref_1, ratio=ref_1 / ours_1, note="Python API, per call"))
    return out
