"""Seed 002's comparison (Zhang & Yang 2011) on the turning-centre example: samples 56–103 train,
samples 1–55 validate (1-based, as the seed), 5 temperatures (coolant, headstock, X nut, bed,
ambient) as read ("absolute") and as rises since the run's first sample ("rise"), the X-axis error
in µm.

GM = a rolling GM(1,N) over the 8 previous samples; BP = a 5-7-1 network on the temperatures;
GM+BP = rolling GM(1,N) over 6, 8 and 10 samples combined by a 3-7-1 network. Models that use past
errors are shown one step ahead (the measured error of the previous sample enters, seed 002's
protocol) and closed loop (their own previous output enters, as a compensating controller would
run them); "persistence" (the previous measured error as the prediction) is the floor a one-step
model has to beat. Trainers: "seed" = batch gradient descent with momentum (lr 0.01, momentum 0.9,
≤ 8000 epochs, MSE goal 0.01 on the normalised error), "adam" = Adam to an MSE goal of 1e-5 or a
500-epoch plateau. Seed 0 for every network; MLR for reference.

    python benches/greybp_compare.py
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import thermerr_rs as tr

EX = Path(__file__).resolve().parents[1] / "examples"
SENSORS = ["T_coolant", "T_headstock", "T_x_nut", "T_bed", "T_ambient"]


def main() -> list[dict]:
    rows = []
    for inputs in ("absolute", "rise"):
        print(f"inputs: {inputs}")
        rows += table(inputs)
        print()
    return rows


def table(inputs: str) -> list[dict]:
    run = tr.read_run(EX / "lathe_run.csv")
    x, y = run.matrix(SENSORS), run["E_x"]
    if inputs == "rise":
        x = np.ascontiguousarray(x - x[0])  # rises since the run's first sample
    tr_i, va_i = slice(55, 103), slice(0, 55)
    models = {
        "MLR": tr.MLR(),
        "GM (w=8)": tr.GM1N(window=8),
        "BP, seed trainer": tr.BPNetwork(trainer="seed"),
        "BP, adam": tr.BPNetwork(trainer="adam"),
        "GM+BP, seed trainer": tr.GreyBP(trainer="seed"),
        "GM+BP, adam": tr.GreyBP(trainer="adam"),
    }
    rows = []
    print(f"{'model':<22} {'mode':<13} {'RMS µm':>8} {'max µm':>8} {'band µm':>8} {'train s':>8} {'epochs':>7}")
    # the floor any one-step model must beat: the previous measured error as the prediction
    yv = y[va_i]
    s = tr.scores(yv, np.concatenate([[0.0], yv[:-1]]))
    rows.append(dict(model="persistence", mode="one step", rms=s.rms, max=s.max_abs, band=s.band, train_s=0.0, epochs=0))
    print(f"{'persistence':<22} {'one step':<13} {s.rms:>8.3f} {s.max_abs:>8.3f} {s.band:>8.3f} {0.0:>8.3f} {0:>7}")
    for name, m in models.items():
        t0 = time.perf_counter()
        m.fit(x[tr_i], y[tr_i])
        dt = time.perf_counter() - t0
        epochs = len(getattr(m, "history_", []))
        sequential = isinstance(m, (tr.GM1N, tr.GreyBP))
        modes = [("one step", True), ("closed loop", False)] if sequential else [("-", False)]
        for mode, one in modes:
            pred = m.predict(x[va_i], y[va_i]) if one else m.predict(x[va_i])
            s = tr.scores(y[va_i], pred)
            rows.append(dict(model=name, mode=mode, rms=s.rms, max=s.max_abs, band=s.band, train_s=dt, epochs=epochs))
            print(f"{name:<22} {mode:<13} {s.rms:>8.3f} {s.max_abs:>8.3f} {s.band:>8.3f} {dt:>8.3f} {epochs:>7}")
    return rows


if __name__ == "__main__":
    main()
