"""A long synthetic run for the large-n tests of the sequence models."""

from __future__ import annotations

import numpy as np

def long_run(n: int = 10_000, dt: float = 15.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A logged run far longer than the seed's (benches/bench_sequence.py, smaller): 16
    temperatures (the ambient with a daily swing, 15 first-order lags of it and of a stepped
    spindle heat), an error that follows hidden nodes with lags of their own, sensor and probe
    noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    amb = 21.0 + 2.5 * np.sin(2 * np.pi * (t - 8 * 3600) / 86_400.0)
    power = np.empty(n)
    k = 0
    while k < n:
        span = int(rng.integers(120, 480))
        power[k:k + span] = 0.0 if rng.random() < 0.33 else rng.uniform(0.3, 1.0)
        k += span

    def lag(u: np.ndarray, tau: float) -> np.ndarray:
        a, s, out = np.exp(-dt / tau), u[0], np.empty_like(u)
        for i, v in enumerate(u):
            s = a * s + (1 - a) * v
            out[i] = s
        return out

    cols = [amb] + [lag(amb, 0.5 * tau) + g * lag(power, tau)
                    for tau, g in zip(np.geomspace(600.0, 6 * 3600.0, 15), rng.uniform(2.0, 12.0, 15))]
    temps = np.column_stack(cols) + rng.normal(0, 0.03, (n, 16))
    err = 12.0 * lag(power, 1800.0) + 11.0 * lag(power, 7200.0) - 2.0 * (lag(amb, 3600.0) - amb[0])
    return temps, err - err[0] + rng.normal(0, 0.3, n)

