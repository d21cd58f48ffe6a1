"""The exception hierarchy, and model files that must be refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs import errors


@pytest.mark.parametrize(
    "cls, builtin",
    [
        (errors.ParameterError, ValueError),
        (errors.ShapeError, ValueError),
        (errors.DataError, ValueError),
        (errors.DataTypeError, TypeError),
        (errors.MissingColumnError, KeyError),
        (errors.NumericalError, ArithmeticError),
        (errors.ConvergenceError, RuntimeError),
        (errors.NotFittedError, AttributeError),
        (errors.NotFittedError, ValueError),
        (errors.ModelFormatError, ValueError),
    ],
)
def test_hierarchy(cls, builtin):
    assert issubclass(cls, tr.ThermerrError) and issubclass(cls, builtin)
    assert getattr(tr, cls.__name__) is cls


@pytest.fixture
def saved(tmp_path):
    rng = np.random.default_rng(0)
    m = tr.MLR().fit(rng.normal(size=(10, 2)), rng.normal(size=10))
    path = m.save(tmp_path / "m.json")
    return path, json.loads(path.read_text())


@pytest.mark.parametrize(
    "mutate, fragment",
    [
        (lambda d: d.update(format_version=99), "format_version 99"),
        (lambda d: d.update(kind="quantum"), "unknown model kind 'quantum'"),
        (lambda d: d.pop("model"), "missing field .model."),
        (lambda d: d["model"].pop("coef"), "coef"),
        (lambda d: d.update(preprocessing={"kind": "fft"}), "unknown preprocessing"),
    ],
)
def test_bad_model_files(saved, tmp_path, mutate, fragment):
    _, doc = saved
    mutate(doc)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(errors.ModelFormatError, match=fragment) as info:
        tr.load_model(bad)
    assert "bad.json" in str(info.value)


def test_not_json_and_missing(tmp_path):
    p = tmp_path / "x.json"
    p.write_text("{not json")
    with pytest.raises(errors.ModelFormatError, match="not JSON"):
        tr.load_model(p)
    with pytest.raises(FileNotFoundError):
        tr.load_model(tmp_path / "none.json")


def test_save_is_atomic(tmp_path, monkeypatch):
    rng = np.random.default_rng(0)
    m = tr.MLR().fit(rng.normal(size=(10, 2)), rng.normal(size=10))
    target = tmp_path / "m.json"
    target.write_text("previous")

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr("os.replace", boom)
    with pytest.raises(OSError):
        m.save(target)
    assert target.read_text() == "previous"
    assert [p.name for p in tmp_path.iterdir()] == ["m.json"]


def test_no_panic_crosses(tmp_path):
    # kernels refuse bad shapes with exceptions, never PanicException (a BaseException)
    with pytest.raises(tr.ThermerrError):
        tr.MLR().fit(np.ones((0, 2)), np.ones(0))
    with pytest.raises(tr.ThermerrError):
        tr.scores(np.ones(3), np.ones(4))
