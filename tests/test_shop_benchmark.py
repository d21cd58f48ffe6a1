"""benches/shop_benchmark.py: its time split and a tiny, seeded version of the run (the figures
themselves are in docs/methods.md, "Shop benchmark")."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest


_path = Path(__file__).resolve().parents[1] / "benches" / "shop_benchmark.py"
_spec = importlib.util.spec_from_file_location("shop_benchmark", _path)
assert _spec is not None and _spec.loader is not None
sb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sb)


@pytest.mark.parametrize("n", [5, 10, 11, 961, 11_041])
def test_split_is_in_time_and_covers_60_to_80_percent(n: int) -> None:
    train, test = sb.split(n)
    assert list(train) == list(range(0, n * 6 // 10))
    assert list(test) == [i for i in range(n) if n * 6 // 10 <= i < n * 8 // 10]
    assert max(train) < min(test)  # every test row after every training row
    assert not set(train) & set(test)


def test_tiny_bench_is_finite_and_seeded() -> None:
    def once() -> dict:
        run = sb.shop_run(seed=3, hours=4.0)
        return sb.bench(run, ["E_ch2"], {"MLR": sb.fixed_models(0)["MLR"]}, families=("mlr",),
                        budget_s=None, log=lambda s: None)

    a, b = once(), once()
    assert a["rows"] == (961, 576, 192)
    assert set(a["mae"]) == {("E_ch2", "none"), ("E_ch2", "MLR"), ("E_ch2", "auto")}
    assert all(np.isfinite(v) and v > 0 for v in a["mae"].values())
    assert a["mae"] == b["mae"]
    # the temperatures explain the drift: MLR is far better than no compensation
    assert a["mae"]["E_ch2", "MLR"] < 0.5 * a["mae"]["E_ch2", "none"]
