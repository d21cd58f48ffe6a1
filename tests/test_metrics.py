"""Figures of merit against direct numpy formulas."""

from __future__ import annotations

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.errors import DataError, ShapeError


def test_against_numpy():
    rng = np.random.default_rng(1)
    e = np.linspace(0, 30, 200) + rng.normal(0, 0.5, 200)
    p = e + rng.normal(0, 0.8, 200)
    s = tr.scores(e, p)
    r = e - p
    # identical formulas in float64: only summation order differs
    assert s.rms == pytest.approx(np.sqrt(np.mean(r**2)), rel=1e-12)
    assert s.max_abs == pytest.approx(np.abs(r).max(), rel=1e-15)
    assert s.band == pytest.approx(r.max() - r.min(), rel=1e-12)
    keep = np.abs(e) > 0.05 * np.abs(e).max()
    assert s.accuracy_excluded == list(np.flatnonzero(~keep))
    assert len(s.accuracy_excluded) > 0
    assert s.mean_accuracy == pytest.approx(np.mean(1 - np.abs(r[keep]) / np.abs(e[keep])), rel=1e-12)
    assert s.compensation_rate == pytest.approx(1 - s.rms / np.sqrt(np.mean(e**2)), rel=1e-12)
    assert "mean accuracy" in str(s)


def test_zero_tol_and_degenerate():
    s = tr.scores([0.0, 0.0], [0.1, -0.1])
    assert s.mean_accuracy is None and s.compensation_rate is None
    s = tr.scores([1.0, 2.0], [1.0, 2.0], zero_tol=1.5)
    assert s.accuracy_excluded == [0] and s.mean_accuracy == 1.0


def test_bad_input():
    with pytest.raises(ShapeError):
        tr.scores([1.0, 2.0], [1.0])
    with pytest.raises(ShapeError):
        tr.scores([], [])
    with pytest.raises(DataError):
        tr.scores([1.0, np.nan], [1.0, 2.0])
