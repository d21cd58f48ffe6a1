"""What every estimator shares: scikit-learn-style parameters, fitted attributes ending in
``_``, and versioned JSON model files (never pickle)."""

from __future__ import annotations

import inspect
import json
import os
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import numpy as np

from . import _core
from ._arrays import F64, as_matrix, as_vector
from ._io import write_atomic
from .errors import ModelFormatError, NotFittedError, ParameterError

#: Schema version of the model files this library writes and reads (the core's).
FORMAT_VERSION: int = _core.FORMAT_VERSION

_REGISTRY: dict[str, type[Estimator]] = {}
#: meta-estimators that wrap a model with input preprocessing, by the ``preprocessing.kind``
#: they write into the model file (the file stays the inner model's, so the edge reads it too);
#: filled when their classes are defined, like ``_REGISTRY``
_WRAPPERS: dict[str, Any] = {}

E = TypeVar("E", bound="Estimator")


class Estimator:
    """Base class: subclasses declare ``kind`` and implement ``_fit``, ``_predict``,
    ``_state`` and ``_restore``."""

    kind: ClassVar[str] = ""
    #: names of the columns the model was fitted on, when known (a run or a DataFrame)
    feature_names_in_: list[str] | None = None
    #: name of the target column (e.g. ``"E_z"``), when known
    target_name_: str | None = None
    #: how ``fit_run``/``predict_run`` build inputs from a run's columns: ``"absolute"`` readings,
    #: or ``"rise"`` (each reading minus the run's first sample, like the error itself)
    inputs_: str = "absolute"

    def __init_subclass__(cls, **kw: Any) -> None:
        super().__init_subclass__(**kw)
        if cls.kind:
            _REGISTRY[cls.kind] = cls
        pre = cls.__dict__.get("preprocessing_kind")
        if pre:
            _WRAPPERS[pre] = cls

    # -- parameters ---------------------------------------------------------------------
    @classmethod
    def _param_names(cls) -> list[str]:
        sig = inspect.signature(cls.__init__)
        return [p for p in sig.parameters if p != "self"]

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        return {p: getattr(self, p) for p in self._param_names()}

    def set_params(self: E, **params: Any) -> E:
        valid = self._param_names()
        for k, v in params.items():
            if k not in valid:
                raise ParameterError(f"{type(self).__name__} has no parameter {k!r} (it has {valid})")
            setattr(self, k, v)
        return self

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({args})"

    # -- fit / predict --------------------------------------------------------------------
    def fit(self: E, X: Any, y: Any) -> E:
        names = _column_names(X)
        x = as_matrix(X)
        yv = as_vector(y, n=x.shape[0])
        self._fit(x, yv)
        self.n_features_in_ = x.shape[1]
        self.feature_names_in_ = names
        self.target_name_ = getattr(y, "name", None) if isinstance(getattr(y, "name", None), str) else None
        return self

    def predict(self, X: Any) -> F64:
        self._check_fitted()
        return self._predict(as_matrix(X))

    def fit_run(self: E, run: Any, target: str, features: list[str], *, inputs: str = "absolute") -> E:
        """Fit on the named columns of a :class:`thermerr_rs.Run`.

        ``inputs="rise"`` models the error from each sensor's rise since the run's first sample
        (the error is itself relative to the run's start), which carries over between runs that
        start at different shop temperatures; ``"absolute"`` uses the readings as they are.
        """
        if inputs not in ("absolute", "rise"):
            raise ParameterError(f'inputs must be "absolute" or "rise", got {inputs!r}')
        self.fit(_run_inputs(run, features, inputs), run[target])
        self.feature_names_in_ = list(features)
        self.target_name_ = target
        self.inputs_ = inputs
        return self

    def predict_run(self, run: Any) -> F64:
        """Predict a run from the columns (and input form) the model was fitted on."""
        self._check_fitted()
        if not self.feature_names_in_:
            raise ModelFormatError("this model does not record its feature columns; use predict(X)")
        return self.predict(_run_inputs(run, self.feature_names_in_, self.inputs_))

    def score(self, X: Any, y: Any) -> float:
        """Coefficient of determination R², as scikit-learn's regressors define it."""
        yv = as_vector(y)
        p = self.predict(X)
        ss_res = float(np.sum((yv - p) ** 2))
        ss_tot = float(np.sum((yv - yv.mean()) ** 2))
        return 1.0 - ss_res / ss_tot if ss_tot > 0 else 0.0

    def _check_fitted(self) -> None:
        if getattr(self, "_inner", None) is None:
            raise NotFittedError(f"this {type(self).__name__} is not fitted yet: call fit first")

    # subclass hooks
    def _fit(self, x: F64, y: F64) -> None:
        raise NotImplementedError

    def _predict(self, x: F64) -> F64:
        raise NotImplementedError

    def _fitted(self) -> Any:
        """The binding object holding the fitted core model (what the file's ``model`` is)."""
        self._check_fitted()
        return self._inner

    def _restore(self, fitted: Any) -> None:
        """Takes the fitted binding object read from a model file."""
        self._inner = fitted

    # -- model files: written and read by the core (thermerr_core::artifact) ---------------
    def _file_kind(self) -> str:
        return self.kind

    def _header(self) -> dict[str, Any]:
        """Everything in the file around the fitted model, its kind and feature count."""
        from . import __version__

        return {
            "library": f"thermerr_rs {__version__}",
            "params": _jsonable(self.get_params()),
            "features": self.feature_names_in_,
            "target": self.target_name_,
            "inputs": self.inputs_,
            "preprocessing": None,
        }

    def to_json(self) -> str:
        """The model file's text; the core validates the model before it writes it."""
        self._check_fitted()
        try:
            header = json.dumps(self._header(), allow_nan=False)
        except (TypeError, ValueError) as e:
            raise ModelFormatError(f"cannot save the parameters of this model: {e}") from None
        text: str = _core.write_model(self._file_kind(), header, self._fitted())
        return text

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = json.loads(self.to_json())
        return out

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the model as versioned JSON, atomically."""
        return write_atomic(path, self.to_json())

    @classmethod
    def from_dict(cls, doc: dict[str, Any]) -> Estimator:
        return _from_dict(doc, expect=cls)

    def __getstate__(self) -> dict[str, Any]:
        return {"json": self.to_json()} if getattr(self, "_inner", None) is not None else {
            "params": self.get_params()
        }

    def __setstate__(self, st: dict[str, Any]) -> None:
        if "json" in st:
            other = _from_text(st["json"], expect=type(self))
            self.__dict__.update(other.__dict__)
        else:
            type(self).__init__(self, **st["params"])


def _run_inputs(run: Any, features: list[str], inputs: str) -> F64:
    x = run.matrix(features)
    if inputs == "rise":
        x = np.ascontiguousarray(x - x[0])
    return x


def _column_names(X: Any) -> list[str] | None:
    cols = getattr(X, "columns", None)
    if cols is None:
        return None
    names = [str(c) for c in cols]
    return names or None


def _jsonable(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return v


def _from_dict(doc: Any, expect: type[Estimator] | None = None) -> Estimator:
    if not isinstance(doc, dict):
        raise ModelFormatError("a model file holds a JSON object")
    try:
        text = json.dumps(doc, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise ModelFormatError(f"not a model file: {e}") from None
    return _from_text(text, expect)


def _from_text(text: str, expect: type[Estimator] | None = None) -> Estimator:
    """The estimator of a model file's text: the core reads and validates the whole file and
    hands back the fitted model; this picks the estimator class of its ``kind``."""
    kind, n_features, header_json, fitted = _core.read_model(text)
    header = json.loads(header_json)
    cls = _REGISTRY.get(kind)
    if cls is None:
        raise ModelFormatError(f"unknown model kind {kind!r} (known: {sorted(_REGISTRY)})")
    pre = header.get("preprocessing")
    if expect is not None and expect is not Estimator and not issubclass(cls, expect):
        wrapper = _WRAPPERS.get(pre["kind"]) if pre else None
        if wrapper is None or not issubclass(wrapper, expect):
            raise ModelFormatError(f"the file holds a {kind!r} model, not a {expect.kind or expect.__name__!r}")
    try:
        est = cls(**header["params"])
    except TypeError as e:
        raise ModelFormatError(f"{kind} model: bad parameters: {e}") from None
    est._restore(fitted)
    est.n_features_in_ = n_features
    est.feature_names_in_ = header.get("features")
    est.target_name_ = header.get("target")
    est.inputs_ = header.get("inputs", "absolute")
    if not pre:
        return est
    wrapped: Estimator = _WRAPPERS[pre["kind"]]._wrap_restored(
        est, _core.Preprocessing.from_json(json.dumps(pre), n_features)
    )
    return wrapped


def load_model(path: str | os.PathLike[str]) -> Estimator:
    """Read a model file written by ``save``; the class is chosen by its ``kind``."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"{p}: no such model file") from None
    except UnicodeDecodeError:
        raise ModelFormatError(f"{p}: not UTF-8 text") from None
    try:
        return _from_text(text)
    except ModelFormatError as e:
        raise ModelFormatError(f"{p}: {e}") from None
