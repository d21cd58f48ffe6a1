"""Training time of the seed networks: our BP network (Rust, batch Adam) against scikit-learn's
MLPRegressor of the same shape and activation (Adam, full batch on these sizes, the same number
of epochs, no early stop), on seed 002's training samples (48 × 5) and on a larger 2000 × 5 set;
and the rolling GM+BP model with Adam against the seed's gradient-descent trainer. The note gives
the final training MSE (normalised) or the held-out RMS each reached."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from _timing import best_of

ROOT = Path(__file__).resolve().parents[1]
SENSORS = ["T_coolant", "T_headstock", "T_x_nut", "T_bed", "T_ambient"]
SIZES = ((48, 5), (2000, 5))
EPOCHS = 2000


def rows(sizes=SIZES, repeat: int = 3) -> list[dict]:
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.neural_network import MLPRegressor

    import thermerr_rs as tr

    run = tr.read_run(ROOT / "examples" / "lathe_run.csv")
    x0, y0 = run.matrix(SENSORS), run["E_x"]
    out = []
    for n, d in sizes:
        if n <= len(y0):
            x, y = np.ascontiguousarray(x0[55:55 + n]), y0[55:55 + n]
        else:
            rng = np.random.default_rng(0)
            x = rng.uniform(20, 30, (n, d))
            y = 2 * (x[:, 0] - 20) + np.sin(x[:, 1]) * 3 + 0.5 * (x[:, 2] - 25) ** 2
        # both on [0, 1]-scaled inputs and target, as our BPNetwork scales them
        xs = (x - x.min(0)) / np.ptp(x, 0)
        ys = (y - y.min()) / np.ptp(y)
        ours = tr.BPNetwork(hidden=7, trainer="adam", max_epochs=EPOCHS, goal=0.0, patience=EPOCHS, seed=0)
        ref = MLPRegressor(hidden_layer_sizes=(7,), activation="logistic", solver="adam", learning_rate_init=0.01,
                           batch_size=n, max_iter=EPOCHS, tol=0.0, n_iter_no_change=EPOCHS, alpha=0.0, random_state=0)
        t_ours = best_of(lambda: ours.fit(x, y), repeat)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            t_ref = best_of(lambda: ref.fit(xs, ys), 1 if n > 500 else repeat)
        mse_ref = float(np.mean((ref.predict(xs) - ys) ** 2))
        note = f"{EPOCHS} epochs; final MSE (scaled) ours {ours.history_[-1]:.2e}, sklearn {mse_ref:.2e}"
        out.append(dict(task="BP 5-7-1 train (Adam)", size=f"{n} x {d}", ours_s=t_ours, ref_s=t_ref, ratio=t_ref / t_ours,
                        note=note))
    x, y = np.ascontiguousarray(x0[55:103]), y0[55:103]
    xv, yv = np.ascontiguousarray(x0[:55]), y0[:55]
    adam = tr.GreyBP(trainer="adam", seed=0)
    seed = tr.GreyBP(trainer="seed", seed=0)
    t_adam = best_of(lambda: adam.fit(x, y), repeat)
    t_seed = best_of(lambda: seed.fit(x, y), repeat)
    ra = tr.scores(yv, adam.predict(xv, yv)).rms
    rs = tr.scores(yv, seed.predict(xv, yv)).rms
    out.append(dict(task="GM+BP train: adam vs seed", size="48 x 5", ours_s=t_adam, ref_s=t_seed, ratio=t_seed / t_adam,
                    note=f"ref = seed's trainer ({len(seed.history_)} epochs to its goal); held-out one-step RMS "
                         f"adam {ra:.2f} µm, seed {rs:.2f} µm"))
    return out
