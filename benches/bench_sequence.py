"""Fit and predict times of the sequence models (issue 12 point 5): ``HybridFilterNet`` and
``GreyBP`` with their default parameters on a realistic long run.

The run (plain numpy, seeded): ``--rows`` samples (10 000 by default) at 15 s (≈ 42 h), 16
temperature columns — the shop air with a daily swing, and 15 structure sensors, each a
first-order lag (time constants 10 min to 6 h) of the ambient plus its share of a stepped
spindle heat input (levels redrawn every 30–120 min, idle spells included) — 0.03 °C sensor
noise; one error axis (µm) that follows four hidden nodes with their own lags (so the sensors
explain it only in part) with 0.3 µm probe noise. Train on the first 60 %, test on the rest;
the held-out RMS (µm, on the last 40 %; the whole run is predicted so the lags carry over from the
training part) is closed loop and one step ahead (the measured previous error in the lags),
against predicting the training mean and against MLR on the same temperatures.

    python benches/bench_sequence.py            # 10 000 rows
    python benches/bench_sequence.py --full     # also fit on all rows, scored on a second run

Measured on this 2-core machine, shared with other jobs (load average 4–9; wall time noisy),
fit on the 6 000 training rows (and on all 10 000 with ``--full``), RMS in µm on the last 4 000:

Before (main at 4afad9e, full-batch training):
    model              fit s  epochs  closed RMS  1-step RMS
    train mean                             4.974
    MLR                0.018               0.351
    HybridFilterNet   89.550    4365       0.339       0.333    (all 10 000 rows: 142.1 s)
    GreyBP            27.076    8000       4.973       4.974    (all 10 000 rows:  41.8 s)

After (the large-n rule, docs/methods.md "Small networks"):
    model              fit s   cpu s  pred s  epochs  closed RMS  1-step RMS
    HybridFilterNet    1.036   0.667   0.027      93       0.339       0.334
    HybridFilterNet all   1.053   0.691              56       3.980       3.425   (on run 2)
    GreyBP             0.178   0.091   0.208      38       4.993       4.993
    GreyBP all         0.331   0.191              41      13.168      13.172   (on run 2)
    (run 2: train mean 12.265, MLR 4.651)

GreyBP stays at the training mean with either trainer: some rolling GM(1,N) windows blow up on a
run this long and the min–max scaled network inputs then carry almost nothing.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import thermerr_rs as tr


def make_run(n: int = 10_000, dt: float = 15.0, n_sensors: int = 16, seed: int = 0, t_noise: float = 0.03,
             e_noise: float = 0.3) -> tuple[np.ndarray, np.ndarray]:
    """Temperatures (n × n_sensors, °C; column 0 the ambient) and an error (µm), with white noise of
    ``t_noise`` °C and ``e_noise`` µm."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    day = 86_400.0
    amb = 21.0 + 2.5 * np.sin(2 * np.pi * (t - 8 * 3600) / day) + 0.4 * np.sin(2 * np.pi * t / 5400.0 + 1.0)
    # stepped spindle heat: a level held 30–120 min, a third of the spells idle
    power = np.empty(n)
    k = 0
    while k < n:
        span = int(rng.integers(120, 480))
        power[k:k + span] = 0.0 if rng.random() < 0.33 else rng.uniform(0.3, 1.0)
        k += span

    def lag(u: np.ndarray, tau: float) -> np.ndarray:
        a = np.exp(-dt / tau)
        out = np.empty_like(u)
        s = u[0]
        for i, v in enumerate(u):
            s = a * s + (1 - a) * v
            out[i] = s
        return out

    cols = [amb]
    taus = np.geomspace(600.0, 6 * 3600.0, n_sensors - 1)
    gains = rng.uniform(2.0, 12.0, n_sensors - 1)
    share = rng.uniform(0.0, 1.0, n_sensors - 1)
    for tau, g, s in zip(taus, gains, share):
        cols.append(lag(amb, 0.5 * tau) + g * lag(s * power + (1 - s) * lag(power, 2 * tau), tau))
    temps = np.column_stack(cols) + rng.normal(0, t_noise, (n, n_sensors))
    # the error: hidden nodes with their own lags, relative to the run's start
    hidden = [lag(power, 1800.0) * 8.0, lag(power, 7200.0) * 10.0, lag(amb, 3600.0) - amb[0],
              lag(power, 400.0) * 3.0]
    err = 1.6 * hidden[0] + 1.1 * hidden[1] - 2.0 * hidden[2] + 1.5 * hidden[3]
    err = err - err[0] + rng.normal(0, e_noise, n)
    return temps, err


def rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=10_000)
    ap.add_argument("--full", action="store_true", help="also time a fit on all rows")
    ap.add_argument("--only", choices=("hybrid", "greybp"), default=None)
    args = ap.parse_args()
    x, y = make_run(args.rows)
    x2, y2 = make_run(args.rows, seed=1)
    cut = int(0.6 * len(y))
    xt, yt, xv, yv = x[:cut], y[:cut], x[cut:], y[cut:]
    print(f"{len(y)} rows × {x.shape[1]} sensors; train {cut}, test {len(y) - cut}; "
          f"error range {y.min():.1f} .. {y.max():.1f} µm, sd {y.std():.2f}")
    print(f"{'model':<16} {'fit s':>7} {'cpu s':>7} {'pred s':>7} {'epochs':>7} {'closed RMS':>11} {'1-step RMS':>11}")
    print(f"{'train mean':<16} {'':>7} {'':>7} {'':>7} {'':>7} {rms(yv, yt.mean()):11.3f} {'':>11}"
          + (f"   (all rows, on run 2: {rms(y2, y.mean()):.3f})" if args.full else ""))
    t0 = time.perf_counter()
    mlr = tr.MLR().fit(xt, yt)
    t1 = time.perf_counter()
    print(f"{'MLR':<16} {t1 - t0:7.3f} {'':>7} {'':>7} {'':>7} {rms(yv, mlr.predict(xv)):11.3f} {'':>11}"
          + (f"   (all rows, on run 2: {rms(y2, tr.MLR().fit(x, y).predict(x2)):.3f})" if args.full else ""))
    models = {"hybrid": tr.HybridFilterNet, "greybp": tr.GreyBP}
    for name, cls in models.items():
        if args.only and args.only != name:
            continue
        t0, c0 = time.perf_counter(), time.process_time()
        m = cls().fit(xt, yt)
        t1, c1 = time.perf_counter(), time.process_time()
        # predict the whole run (the state carries over from the training part) and score the
        # held-out rows only
        closed = m.predict(x)[cut:]
        one = m.predict(x, y)[cut:]
        t2 = time.perf_counter()
        print(f"{cls.__name__:<16} {t1 - t0:7.3f} {c1 - c0:7.3f} {t2 - t1:7.3f} {len(m.history_):7d} "
              f"{rms(yv, closed):11.3f} {rms(yv, one):11.3f}")
        if args.full:
            # all rows; scored on an independent second run (another seed)
            t0, c0 = time.perf_counter(), time.process_time()
            m = cls().fit(x, y)
            t1, c1 = time.perf_counter(), time.process_time()
            print(f"{cls.__name__ + ' all':<16} {t1 - t0:7.3f} {c1 - c0:7.3f} {'':>7} {len(m.history_):7d} "
                  f"{rms(y2, m.predict(x2)):11.3f} {rms(y2, m.predict(x2, y2)):11.3f}")


if __name__ == "__main__":
    main()
