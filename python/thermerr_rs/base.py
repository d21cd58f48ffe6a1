"""What every estimator shares: it is a scikit-learn estimator (parameters from ``__init__``,
``get_params``/``set_params``, ``clone``, tags), fitted attributes end in ``_``, the input it was
fitted on is checked at ``predict``, and models are saved as versioned JSON files (never pickle).

The bases to derive from: :class:`Regressor`, :class:`SequenceModel` (a regressor whose
prediction depends on the order of samples) and :class:`Clusterer`; :class:`Estimator` is their
common root."""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import numpy as np
from sklearn.base import BaseEstimator, ClusterMixin, MetaEstimatorMixin, RegressorMixin

from . import _core
from ._arrays import F64, as_matrix, as_target, check_features, feature_names, series_name
from ._io import write_atomic
from .errors import ModelFormatError, NotFittedError, ParameterError, ShapeError
from .run import median_step

#: Schema version of the model files this library writes and reads (the core's).
FORMAT_VERSION: int = _core.FORMAT_VERSION

_REGISTRY: dict[str, type[Estimator]] = {}
#: meta-estimators that wrap a model with input preprocessing, by the ``preprocessing.kind``
#: they write into the model file (the file stays the inner model's, so the edge reads it too)
_WRAPPERS: dict[str, Any] = {}

E = TypeVar("E", bound="Estimator")


class Estimator(BaseEstimator):  # type: ignore[misc]
    """Common root of every thermerr_rs estimator, a scikit-learn ``BaseEstimator``.

    Subclasses declare ``kind`` and implement ``_fit`` and ``_predict`` (``_fitted`` and
    ``_restore`` when the fitted binding object is not ``_inner``); ``__init__`` only stores its
    keyword parameters (scikit-learn's rule)."""

    kind: ClassVar[str] = ""
    #: names of the columns the model was fitted on, when known (a run or a DataFrame)
    feature_names_in_: list[str] | None = None
    #: name of the target column (e.g. ``"E_z"``), when known
    target_name_: str | None = None
    #: how ``fit_run``/``predict_run`` build inputs from a run's columns: ``"absolute"`` readings,
    #: or ``"rise"`` (each reading minus the run's first sample, like the error itself)
    inputs_: str = "absolute"
    n_features_in_: int
    #: the model file's ``history`` entry when fitted with ``fit_run(..., history=...)``
    input_history_: dict[str, Any] | None = None
    #: the model file's ``guard`` entry when given one by :func:`thermerr_rs.add_guard`
    guard_: dict[str, Any] | None = None
    #: the fitted model (Rust, or the fitted inner estimator of a wrapper); None until ``fit``
    _inner: Any = None
    #: scikit-learn estimator checks this class fails on purpose, with the reason: given to
    #: ``check_estimator(expected_failed_checks=...)`` on scikit-learn >= 1.6, and the
    #: ``_xfail_checks`` tag before
    _xfail_checks: ClassVar[dict[str, str]] = {}

    def __init_subclass__(cls, **kw: Any) -> None:
        super().__init_subclass__(**kw)
        if cls.kind:
            _REGISTRY[cls.kind] = cls
        pre = cls.__dict__.get("preprocessing_kind")
        if pre:
            _WRAPPERS[pre] = cls

    # -- parameters and tags --------------------------------------------------------------
    def set_params(self: E, **params: Any) -> E:
        valid = self.get_params(deep=True)  # nested ones too: estimator__C
        for k in params:
            if k not in valid:
                raise ParameterError(f"{type(self).__name__} has no parameter {k!r} (it has {list(valid)})")
        super().set_params(**params)
        return self

    # tags: scikit-learn >= 1.6 reads __sklearn_tags__ (and takes the expected failures as
    # check_estimator's expected_failed_checks), older releases merge the _more_tags of each class
    def __sklearn_tags__(self) -> Any:
        return super().__sklearn_tags__()

    def _more_tags(self) -> dict[str, Any]:
        return {"_xfail_checks": dict(self._xfail_checks)}

    def __sklearn_is_fitted__(self) -> bool:
        return self._inner is not None

    # -- fit / predict --------------------------------------------------------------------
    def fit(self: E, X: Any, y: Any) -> E:
        return self._fit_checked(X, y, names=feature_names(X), target=series_name(y))

    def _fit_checked(self: E, X: Any, y: Any, *, names: list[str] | None, target: str | None,
                     inputs: str = "absolute", **fit_kw: Any) -> E:
        """Check ``X`` and ``y``, fit, and record what the model was fitted on."""
        x = as_matrix(X, one_d=False)
        yv = as_target(y, x.shape[0], type(self).__name__)
        n_min = self._min_samples()
        if x.shape[0] < n_min:
            raise ShapeError(f"{type(self).__name__} needs at least {n_min} samples to fit, "
                             f"got n_samples = {x.shape[0]}")
        self._fit(x, yv, **fit_kw)
        return self._fitted_on(x, names, target, inputs)

    def _fitted_on(self: E, x: F64, names: list[str] | None, target: str | None = None,
                   inputs: str = "absolute") -> E:
        self.n_features_in_ = x.shape[1]
        self.guard_ = None  # a guard learnt on an earlier fit no longer applies
        self.input_history_ = None  # fit_run sets it after fitting with a history
        self.feature_names_in_ = names
        self.target_name_ = target
        self.inputs_ = inputs
        return self

    def predict(self, X: Any) -> F64:
        return self._predict(self._check_X(X, feature_names(X)))

    def _check_X(self, X: Any, names: list[str] | None) -> F64:
        """``X`` (whose columns are ``names``) checked against what the model was fitted on."""
        self._check_fitted()
        x = as_matrix(X, one_d=False)
        check_features(type(self).__name__, self.n_features_in_, self.feature_names_in_, x.shape[1], names)
        return x

    def _predict_columns(self, x: F64) -> F64:
        """Predict from a matrix whose columns are ``feature_names_in_``, in order (built from a
        run by the library itself, so no feature-name warning)."""
        return self._predict(self._check_X(x, self.feature_names_in_))

    def fit_run(self: E, run: Any, target: str, features: list[str], *, inputs: str = "absolute",
                history: Sequence[float] | None = None) -> E:
        """Fit on the named columns of a :class:`thermerr_rs.Run`.

        ``inputs="rise"`` models the error from each sensor's rise since the run's first sample
        (the error is itself relative to the run's start), which carries over between runs that
        start at different shop temperatures; ``"absolute"`` uses the readings as they are.

        ``history`` (time constants in seconds, e.g. ``[900, 3600]``): the model also reads each
        sensor's rise over about the last τ seconds (the reading minus a first-order low-pass of
        it), so that a static model sees how the machine got where it is. Recorded in the model
        file; ``thermerr-edge`` keeps the filters as state. The arithmetic is the core's
        (``thermerr_core::artifact::History``).
        """
        run.check_fit_columns(target, list(features))
        run = _bridged_for_fit(run, list(features))
        hist = _history(history, run.time_s)
        x = run_inputs(run, list(features), inputs, hist)
        self._fit_checked(x, run[target], names=list(features), target=target, inputs=inputs)
        self.input_history_ = hist
        return self

    def predict_run(self, run: Any, *, shape: Any = None, after: Any = None, reference: Any = None) -> F64:
        """Predict a run from the columns (and input form) the model was fitted on.

        ``shape`` (e.g. ``"limit=50,rate=2,unit=0.1"``): return the offsets a CNC would be sent
        instead of the raw predictions (:func:`thermerr_rs.shape_offsets`, the same code as
        ``thermerr-edge --shape``).

        ``after`` (a :class:`~thermerr_rs.Run`): ``run`` continues that run (e.g. the test rows
        cut from the log whose first rows trained the model): it is predicted as the end of
        ``after`` followed by ``run`` (:meth:`Run.following`), so that rises are taken from
        ``after``'s start, as the error itself is, and history filters run on through the join;
        only ``run``'s rows are returned. Without it, rises start at ``run``'s first sample: right
        for a run of its own (the probes zeroed at its start), wrong for a piece of a longer one.

        ``reference`` (a :class:`~thermerr_rs.Run`): the rises are taken from its first sample
        instead of ``run``'s (history filters still start at ``run``'s first sample): what
        ``thermerr-edge --reference RUN.csv`` does for a gateway started in the middle of a run."""
        if after is not None:
            return _continued(self.predict_run, run, after, shape, reference=reference)
        y = self._predict_columns(self._run_matrix(run, reference))
        if shape is None:
            return y
        from .shaping import shape_offsets

        return shape_offsets(run.time_s, y, shape)

    def _run_matrix(self, run: Any, reference: Any = None) -> F64:
        self._check_fitted()
        if not self.feature_names_in_:
            raise ModelFormatError("this model does not record its feature columns; use predict(X)")
        if reference is not None and self.inputs_ != "rise":
            raise ParameterError("reference: the model reads absolute readings, not rises")
        return run_inputs(run, self.feature_names_in_, self.inputs_, getattr(self, "input_history_", None),
                          reference=reference)

    def _check_fitted(self) -> None:
        if self._inner is None:
            raise NotFittedError(f"this {type(self).__name__} is not fitted yet: call fit first")

    # subclass hooks
    def _min_samples(self) -> int:
        """The fewest samples ``fit`` can work with (checked before fitting)."""
        return 1

    def _fit(self, x: F64, y: Any) -> None:
        """Fit on the checked inputs ``x`` and target ``y`` (``None`` for a clusterer)."""
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
        head = self._header()
        head["history"] = getattr(self, "input_history_", None)  # fit_run(history=...)
        head["guard"] = getattr(self, "guard_", None)  # thermerr_rs.add_guard
        try:
            header = json.dumps(head, allow_nan=False)
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


class Regressor(RegressorMixin, Estimator):  # type: ignore[misc]
    """Base of the regressors: scikit-learn's regressor tags and ``score`` (R²) over the
    ``fit(X, y)``, ``predict(X)``, ``fit_run`` and ``predict_run`` of :class:`Estimator`."""

    #: scikit-learn's ``poor_score`` tag: not expected to score well on the random, unordered
    #: data of scikit-learn's checks
    _poor_score: ClassVar[bool] = False

    def __sklearn_tags__(self) -> Any:
        tags = super().__sklearn_tags__()
        tags.regressor_tags.poor_score = self._poor_score
        return tags

    def _more_tags(self) -> dict[str, Any]:
        return {"poor_score": self._poor_score}


class SequenceModel(Regressor):
    """Base of the regressors of a time-ordered series: the prediction of a sample depends on
    the samples before it, so the order of samples matters at ``fit`` and ``predict`` (rows are
    time steps; never shuffle them: cross-validate with ``TimeSeriesSplit``).

    scikit-learn has no tag for this; it is declared through the checks that assume order does
    not matter (``_xfail_checks``) and the ``poor_score`` tag (its checks fit unordered random
    data)."""

    _xfail_checks: ClassVar[dict[str, str]] = {
        "check_methods_sample_order_invariance": "a sequence model: the prediction of a sample "
        "depends on the samples before it, so reordering the samples changes it",
        "check_methods_subset_invariance": "a sequence model: the prediction of a sample depends "
        "on the samples before it, so predicting one sample at a time changes it",
    }
    _poor_score: ClassVar[bool] = True


class _Wrapper(MetaEstimatorMixin):  # type: ignore[misc]
    """Mixin of the estimators that wrap another (its parameters show as ``estimator__...``)."""

    def __getstate__(self) -> dict[str, Any]:
        # unfitted, the state is the parameters given to __init__ (the nested ones are not)
        if getattr(self, "_inner", None) is None:
            return {"params": self.get_params(deep=False)}
        state: dict[str, Any] = super().__getstate__()
        return state


class Clusterer(ClusterMixin, Estimator):  # type: ignore[misc]
    """Base of the clusterers: ``fit(X)``, ``labels_``, ``predict(X)``."""

    def fit(self: E, X: Any, y: Any = None) -> E:
        """Cluster the rows of ``X``; ``y`` is ignored (scikit-learn convention)."""
        x = as_matrix(X, one_d=False)
        self._fit(x, None)
        return self._fitted_on(x, feature_names(X))


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


def _continued(predict: Any, run: Any, after: Any, shape: Any, **kw: Any) -> F64:
    """``predict`` (a ``predict_run``) of ``run`` as the continuation of ``after``: the rows of
    both as one run, ``run``'s returned (the one owner of ``predict_run(after=...)``)."""
    y: F64 = predict(run.following(after), shape=shape, **kw)
    return np.ascontiguousarray(y[len(after):])


def _bridged_for_fit(run: Any, features: list[str]) -> Any:
    """``run`` with its input temperatures' short spikes bridged (:meth:`Run.bridged`), each said
    as a :class:`~thermerr_rs.errors.SuspectReadingWarning`; a temperature that fails for longer
    is warned of and fitted as read. A spike of hundreds of kelvin fitted as read pulls a linear
    model's coefficients (measured on the real 46-h run's first half, ``T_t8`` at 1372 °C for 11
    rows: E_ch3 held out on the second half 12.54 µm against 6.95 µm without the spike)."""
    from .errors import SuspectReadingWarning

    mended, said = run.bridged(features)
    for line in said:
        warnings.warn(f"{run.source}: {line}: bridged by a straight line for the fit", SuspectReadingWarning,
                      stacklevel=3)
    for text in mended.failing(features):
        warnings.warn(f"{text} (the fit reads it as it is)", SuspectReadingWarning, stacklevel=3)
    return mended


def _history(taus: Sequence[float] | None, time_s: F64) -> dict[str, Any] | None:
    """The model file's ``history`` entry for time constants ``taus`` on a run sampled at
    ``time_s`` (``step_s``: its median step, used where a stream has no times)."""
    if taus is None:
        return None
    return {"tau_s": [float(t) for t in taus], "step_s": median_step(time_s)}


def run_inputs(run: Any, features: list[str], inputs: str, history: dict[str, Any] | None, *,
               reference: Any = None) -> F64:
    """A model's inputs from a run: the named columns as ``inputs`` says (absolute or rise; with
    a ``reference`` run, rises from its first sample), then, with a ``history`` entry, each
    reading's rises over its time constants."""
    x: F64 = run.input_matrix(features, inputs, reference)
    if history is not None:
        x = _core.history_transform(x, run.time_s, history["tau_s"], history["step_s"])
    return x


def _import_families() -> None:
    """Define every estimator class, so that each ``kind`` and preprocessing is registered (the
    package imports them on first use, not at its own import)."""
    from . import fcm, grey, hybrid, linear, preprocessing, rbf, svr  # noqa: F401


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
    _import_families()
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
        est.guard_ = header.get("guard")
        est.input_history_ = header.get("history")
        return est
    wrapped: Estimator = _WRAPPERS[pre["kind"]]._wrap_restored(
        est, _core.Preprocessing.from_json(json.dumps(pre), n_features)
    )
    wrapped.guard_ = header.get("guard")
    wrapped.input_history_ = header.get("history")
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
