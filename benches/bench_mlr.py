"""MLR fit/predict: thermerr_rs vs scikit-learn LinearRegression, same data."""

from __future__ import annotations

import numpy as np

from _timing import best_of

SIZES = ((500, 20), (5000, 200), (20000, 2000))  # samples x features


def rows(sizes=SIZES, repeat: int = 3) -> list[dict]:
    from sklearn.linear_model import LinearRegression

    import thermerr_rs as tr

    out = []
    for n, d in sizes:
        rng = np.random.default_rng(0)
        x = rng.normal(20, 3, (n, d))
        y = x @ rng.normal(size=d) + rng.normal(0, 0.1, n)
        r = 1 if n * d > 1e7 else repeat
        ours_s = best_of(lambda: tr.MLR().fit(x, y), r)
        ref_s = best_of(lambda: LinearRegression().fit(x, y), r)
        a, b = tr.MLR().fit(x, y), LinearRegression().fit(x, y)
        diff = float(np.max(np.abs(a.predict(x) - b.predict(x))))
        out.append(dict(task="MLR fit", size=f"{n} x {d}", ours_s=ours_s, ref_s=ref_s,
                        ratio=ref_s / ours_s, note=f"max |pred diff| {diff:.1e}"))
        xs = x[: min(n, 1000)]
        ours_p = best_of(lambda: a.predict(xs), repeat)
        ref_p = best_of(lambda: b.predict(xs), repeat)
        out.append(dict(task="MLR predict", size=f"{xs.shape[0]} x {d}", ours_s=ours_p, ref_s=ref_p,
                        ratio=ref_p / ours_p, note=""))
    return out


if __name__ == "__main__":
    from compare import print_table

    print_table(rows())
