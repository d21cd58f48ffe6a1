"""The published protocol on the shipped simulated shop run (issue 12 point 6).

The run: ``thermerr_rs.synthetic.make_shop_case(seed=1, hours=46, dt=15)`` with its default
``hidden=None`` — nothing hidden, as shipped: a VMC over 46 h at 15 s (11 041 rows), the shop air
swinging ±1.8 K over a day, the spindle stepped through 0–5000 rpm every 4 h, sixteen
temperatures ``T_t1..T_t16`` (0.03 °C noise) and five probe channels ``E_ch1..E_ch5`` (0.3 µm
noise), each channel linear in the true node rises with a drift map of its own.

The protocol: train on the first 60 % of the rows, test on rows 60–80 % (the last 20 % are not
used); inputs are the 16 temperatures only, as rises since the run's start (the CLI default
``--inputs rise``); the spindle input ``U_spindle_rpm`` is not used. Score: mean absolute error
(µm) per channel on the test rows. The test rows are predicted from the run's start (rows
0..80 %), as a gateway running since then would: rises and history filters are causal, so no
test-row error is seen.

Models, each fitted per channel on the training rows, with no tuning:
  * no compensation: the error minus its training mean;
  * fixed defaults: ``MLR()``, ``RBFNetwork()`` (the constructor's default, design "exact"),
    the CLI's ``--model rbf`` default (``MinMaxScaled(RBFNetwork(design="ols", goal=0.1·n))``),
    ``SVR()``, ``BPNetwork()``, ``GreyBP()``, ``HybridFilterNet()`` (a refusal is printed as such);
  * auto: ``select_model(..., history=[900, 3600])`` — the CLI's ``--model auto`` (its default history)
    (the README's example time constants), 5 time-ordered splits of the training rows, budget
    ``BUDGET_S`` per channel; its fit time includes the whole search and the refit.

    python benches/shop_benchmark.py          # about 5 min on 2 cores (324 s on 2026-11-24)
    python benches/shop_benchmark.py --hidden thermal_lag   # the structure lags its sensors
    python benches/shop_benchmark.py --run RUN.csv --models MLR,SVR   # the protocol on a run of yours
      (every T_* column as an input, every E_* column a channel; docs/methods.md has the figures of
      a real 46-h run measured this way)

Seeded throughout (the case seed 1, every model seed 0): the same seed gives the same MAEs.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

import thermerr_rs as tr
from thermerr_rs.synthetic import SHOP_CHANNELS, make_shop_case

FEATURES = [f"T_t{i}" for i in range(1, 17)]
HISTORY = [900.0, 3600.0]
BUDGET_S = 120.0


def split(n: int) -> tuple[range, range]:
    """Training rows [0, 0.6n) and test rows [0.6n, 0.8n), both rounded down."""
    a, b = n * 6 // 10, n * 8 // 10
    return range(0, a), range(a, b)


def shop_run(seed: int = 1, hours: float = 46.0, dt: float = 15.0, hidden: str | None = None) -> tr.Run:
    """The shop run; ``hidden``: one effect of make_shop_case hidden on every channel."""
    effects = {ch: hidden for ch in SHOP_CHANNELS} if hidden else None
    return tr.Run.from_frame(make_shop_case(seed, hours=hours, dt=dt, hidden=effects).train, source=f"shop seed {seed}")


def fixed_models(n_train: int) -> dict[str, Callable[[], tr.Estimator]]:
    """Every family with its default parameters (the RBF also as the CLI's --model rbf builds it)."""
    return {
        "MLR": lambda: tr.MLR(),
        "RBF exact": lambda: tr.RBFNetwork(),
        "RBF cli-ols": lambda: tr.MinMaxScaled(tr.RBFNetwork(design="ols", goal=0.1 * n_train, seed=0)),
        "SVR": lambda: tr.SVR(),
        "BP": lambda: tr.BPNetwork(),
        "GreyBP": lambda: tr.GreyBP(),
        "Hybrid": lambda: tr.HybridFilterNet(),
    }


def bench(run: tr.Run, channels: list[str], models: dict[str, Callable[[], tr.Estimator]], *,
          auto: bool = True, families: tuple[str, ...] = ("mlr", "rbf", "svr"),
          budget_s: float | None = BUDGET_S, seed: int = 0, log: Callable[[str], None] = print,
          features: list[str] | None = None) -> dict:
    """MAE (µm) and fit time (s) per (channel, model) on the test rows; with ``auto`` also what
    select_model picked per channel and its leaderboard."""
    rows_train, rows_test = split(len(run))
    train = run.slice(0, rows_train.stop)
    upto_test = run.slice(0, rows_test.stop)  # predicted from the run's start; scored on the test rows
    test = slice(rows_test.start, rows_test.stop)
    features = FEATURES if features is None else features
    mae: dict[tuple[str, str], float] = {}
    fit_s: dict[tuple[str, str], float] = {}
    notes: dict[tuple[str, str], str] = {}
    picks: dict[str, tr.ModelSelection] = {}
    for ch in channels:
        y = run[ch]
        mae[ch, "none"] = float(np.mean(np.abs(y[test] - train[ch].mean())))
        for name, make in models.items():
            t0 = time.perf_counter()
            try:
                m = make().fit_run(train, ch, features, inputs="rise")
            except tr.ThermerrError as e:
                notes[ch, name] = f"{type(e).__name__}: {e}"
                log(f"{ch} {name}: refused ({notes[ch, name]})")
                continue
            fit_s[ch, name] = time.perf_counter() - t0
            mae[ch, name] = float(np.mean(np.abs(y[test] - m.predict_run(upto_test)[test])))
            log(f"{ch} {name}: MAE {mae[ch, name]:.3f} µm, fit {fit_s[ch, name]:.2f} s")
        if auto:
            t0 = time.perf_counter()
            sel = tr.select_model(train, ch, features, families=families, history=HISTORY, inputs="rise",
                                  budget_s=budget_s, seed=seed)
            fit_s[ch, "auto"] = time.perf_counter() - t0
            mae[ch, "auto"] = float(np.mean(np.abs(y[test] - sel.model.predict_run(upto_test)[test])))
            picks[ch] = sel
            log(f"{ch} auto: picked {sel.best.candidate.label()}, MAE {mae[ch, 'auto']:.3f} µm, "
                f"search+refit {fit_s[ch, 'auto']:.1f} s, {len(sel.skipped)} skipped")
    return {"mae": mae, "fit_s": fit_s, "notes": notes, "picks": picks,
            "rows": (len(run), len(rows_train), len(rows_test))}


def table(res: dict, channels: list[str], cols: list[str], key: str, fmt: str) -> str:
    lines = [f"{'channel':8s}" + "".join(f"{c:>12s}" for c in cols)]
    for ch in channels:
        cells = [format(res[key][ch, c], fmt) if (ch, c) in res[key] else "refused" for c in cols]
        lines.append(f"{ch:8s}" + "".join(f"{v:>12s}" for v in cells))
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--hidden", choices=["thermal_lag", "ambient_coupling", "speed_growth", "nonlinear_expansion"],
                   help="hide this effect on every channel (default: nothing hidden, the run as shipped)")
    p.add_argument("--run", help="a run CSV of yours instead of the simulated shop run (its T_* columns are the "
                                 "inputs, its E_* columns the channels)")
    p.add_argument("--models", help="the fixed defaults to fit, comma-separated (default: all of "
                                    + ", ".join(fixed_models(0)) + ")")
    args = p.parse_args()
    if args.run:
        run = tr.read_run(args.run)
        features, channels = run.temperatures, run.errors
        what = args.run
    else:
        run = shop_run(seed=1, hidden=args.hidden)
        features, channels = FEATURES, list(SHOP_CHANNELS)
        what = f"shop run seed 1 (hidden: {args.hidden or 'none'})"
    n, n_train, n_test = len(run), len(split(len(run))[0]), len(split(len(run))[1])
    print(f"{what}: {n} rows; train rows 0..{n_train - 1} ({n_train}), "
          f"test rows {n_train}..{n_train + n_test - 1} ({n_test}); inputs {len(features)} T_* rises "
          f"(U_* not used); auto: history {HISTORY} s, budget {BUDGET_S:g} s per channel", flush=True)
    models = fixed_models(n_train)
    if args.models:
        unknown = set(args.models.split(",")) - set(models)
        if unknown:
            p.error(f"unknown models {sorted(unknown)} (known: {', '.join(models)})")
        models = {k: v for k, v in models.items() if k in args.models.split(",")}
    t0 = time.perf_counter()
    res = bench(run, channels, models, log=lambda s: print(s, flush=True), features=features)
    cols = ["none", *models, "auto"]
    print(f"\ntest MAE, µm (rows {n_train}..{n_train + n_test - 1})")
    print(table(res, channels, cols, "mae", ".3f"))
    print("\nfit time, s (auto: the whole search and the refit)")
    print(table(res, channels, cols[1:], "fit_s", ".2f"))
    for (ch, name), note in res["notes"].items():
        print(f"{ch} {name}: {note}")
    print("\nauto picked (top 3 of the leaderboard, CV RMS µm on the training rows):")
    for ch, sel in res["picks"].items():
        top = ", ".join(f"{e.candidate.label()} {e.cv_rms:.3f}" for e in sel.leaderboard[:3])
        print(f"{ch}: {top}; {len(sel.leaderboard)} scored, {len(sel.skipped)} skipped")
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
