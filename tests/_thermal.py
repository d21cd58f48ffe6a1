"""Synthetic thermal series shared by the FCM and selection tests and the FCM bench."""

from __future__ import annotations

import numpy as np

DT_S = 150.0  # seed 003 sampled every 150 s


def spindle_steps(n: int) -> np.ndarray:
    """Seed 003's stepped spindle programme 3000-6000-4500-3000 rpm, a quarter of the run each."""
    rpm = np.empty(n)
    for k, v in enumerate((3000.0, 6000.0, 4500.0, 3000.0)):
        rpm[k * n // 4 : (k + 1) * n // 4] = v
    return rpm


def first_order(u: np.ndarray, tau_s: float, dt: float = DT_S) -> np.ndarray:
    """Exact discretisation of tau dy/dt = u - y, y(0) = 0, input held between samples."""
    a = np.exp(-dt / tau_s)
    y = np.empty_like(u)
    acc = 0.0
    for k, v in enumerate(u):
        acc = a * acc + (1.0 - a) * v
        y[k] = acc
    return y


def sensor_series(n_samples: int, taus_s, gains, noise: float, seed: int) -> np.ndarray:
    """One row per sensor: 20 °C plus gain × first-order response to the heat of the spindle
    (∝ (rpm/6000)^1.4) with time constant tau, plus white noise (°C)."""
    rng = np.random.default_rng(seed)
    heat = (spindle_steps(n_samples) / 6000.0) ** 1.4
    rows = [20.0 + g * first_order(heat, t) for t, g in zip(taus_s, gains)]
    x = np.vstack(rows)
    return x + noise * rng.standard_normal(x.shape)


def minmax_rows(x: np.ndarray) -> np.ndarray:
    lo = x.min(axis=1, keepdims=True)
    hi = x.max(axis=1, keepdims=True)
    return np.ascontiguousarray((x - lo) / (hi - lo))
