"""Hyper-parameter defaults live in the core: every estimator's keyword defaults equal
``_core.default_params(kind)``, and a fit keyword left out takes the core's value. The training
history is part of the fitted model, so it survives a model file."""

from __future__ import annotations

import inspect
import json
from typing import Any

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import _core
from thermerr_rs.errors import ParameterError

ESTIMATORS = [tr.MLR, tr.RBFNetwork, tr.SVR, tr.BPNetwork, tr.GreyBP, tr.GM1N, tr.HybridFilterNet]


def core_defaults(kind: str) -> dict[str, Any]:
    """The core's checked defaults, the network's flattened into the model's."""
    d = _core.default_params(kind)
    d.update(d.pop("net", {}))
    return d


def as_core(name: str, value: Any) -> tuple[str, Any]:
    """A Python keyword and its default as the core names and stores it."""
    if name == "hidden":
        return "hidden_sizes", [value] if isinstance(value, int) else list(value)
    if name == "C":
        return "c", value
    if name == "max_iter" and value == -1:  # scikit-learn's "no limit"
        return name, None
    return name, list(value) if isinstance(value, tuple) else value


@pytest.mark.parametrize("cls", ESTIMATORS, ids=lambda c: c.kind)
def test_python_defaults_are_the_cores(cls: type[tr.Estimator]) -> None:
    core = core_defaults(cls.kind)
    for name, p in inspect.signature(cls.__init__).parameters.items():
        if name == "self":
            continue
        key, value = as_core(name, p.default)
        assert key in core, f"{cls.__name__}({name}=...) has no core parameter"
        assert core[key] == value, f"{cls.__name__}({name}={p.default!r}) but the core has {core[key]!r}"


def test_core_defaults_as_documented() -> None:
    assert core_defaults("greybp")["trainer"] == "adam"  # docs/methods.md: the default trainer
    assert core_defaults("bp")["trainer"] == "adam"
    assert core_defaults("hybrid")["goal"] == 0.0
    with pytest.raises(ParameterError, match="kind"):
        _core.default_params("lstm")


def test_left_out_keywords_take_the_core_defaults() -> None:
    rng = np.random.default_rng(0)
    x = rng.uniform(size=(40, 3))
    y = np.sin(3 * x[:, 0]) + x[:, 1] * x[:, 2]
    pairs = [
        (_core.RbfModel.fit(x, y), tr.RBFNetwork().fit(x, y)._inner),
        (_core.SvrModel.fit(x, y), tr.SVR().fit(x, y)._inner),
        (_core.BpModel.fit(x, y, max_epochs=200), tr.BPNetwork(max_epochs=200).fit(x, y)._inner),
    ]
    for a, b in pairs:
        assert a is not None and b is not None
        np.testing.assert_array_equal(a.predict(x), b.predict(x))
    np.testing.assert_array_equal(pairs[2][0].history, pairs[2][1].history)


def test_names_are_refused_with_the_allowed_ones() -> None:
    x, y = np.arange(20.0).reshape(10, 2), np.arange(10.0)
    with pytest.raises(ParameterError, match='"exact", "ols" or "kmeans", got "magic"'):
        _core.RbfModel.fit(x, y, design="magic")
    with pytest.raises(ParameterError, match='"rbf" or "linear", got "poly"'):
        _core.SvrModel.fit(x, y, kernel="poly")
    with pytest.raises(ParameterError, match="trainer"):
        tr.BPNetwork(trainer="lbfgs").fit(x, y)


@pytest.mark.parametrize("make", [
    lambda: tr.BPNetwork(max_epochs=50, goal=0.0),
    lambda: tr.GreyBP(max_epochs=50, goal=0.0),
    lambda: tr.HybridFilterNet(hidden=5, max_epochs=50),
], ids=["bp", "greybp", "hybrid"])
def test_history_survives_the_model_file(make: Any) -> None:
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.0, 0.1, size=(60, 2)), axis=0)
    y = 3.0 * t[:, 0] - t[:, 1] + 0.1 * np.sin(np.arange(60) / 5)
    m = make().fit(t, y)
    assert len(m.history_) == 50
    back = type(m).from_dict(json.loads(m.to_json()))
    np.testing.assert_array_equal(back.history_, m.history_)
