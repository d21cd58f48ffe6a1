"""thermerr_rs: machine-tool thermal error — models, compensation and physics diagnosis.

The compute kernels are Rust (``thermerr_rs._core``); this package is a thin, typed API over
them. See the README for the command line (``thermerr``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ._core import __version__
from .errors import (
    ConvergenceError,
    DataError,
    DataTypeError,
    MissingColumnError,
    ModelFormatError,
    NumericalError,
    ParameterError,
    ShapeError,
    ThermerrError,
)
from .run import Run, read_run

if TYPE_CHECKING:
    from .base import FORMAT_VERSION, Clusterer, Estimator, Regressor, SequenceModel, load_model
    from . import examples
    from .errors import NotFittedError
    from .fcm import FuzzyCMeans
    from .folds import kfold_split, time_series_split
    from .grey import GM1N, BPNetwork, GreyBP
    from .guard import GuardedPrediction, add_guard, predict_guarded
    from .hybrid import HybridFilterNet
    from .linear import MLR
    from .metrics import Scores, scores
    from .model_selection import ModelSelection, select_model
    from .preprocessing import AGORegressor, MinMaxAGO, MinMaxScaled, spread_search
    from .rbf import RBFNetwork
    from .selection import SensorSelection, select_sensors
    from .shaping import shape_offsets
    from .stiffness import StiffnessResult, key_thermal_stiffness
    from .svr import SVR
    from .swarm import SwarmResult, TuneResult, cso, pso, svr_cv_mse, tune_svr
    from .thermal import AxesDiagnosis, Diagnosis, Machine, Simulation, diagnose, diagnose_axes

# Every other name is imported on first use (PEP 562): the estimators build on scikit-learn's base
# classes, whose import takes about a second, and a diagnosis or the command line's start needs
# none of them.
_LAZY: dict[str, str] = {
    'FORMAT_VERSION': '.base',
    'Clusterer': '.base',
    'Estimator': '.base',
    'Regressor': '.base',
    'SequenceModel': '.base',
    'load_model': '.base',
    'NotFittedError': '.errors',
    'examples': '.examples',  # a module
    'FuzzyCMeans': '.fcm',
    'kfold_split': '.folds',
    'time_series_split': '.folds',
    'GM1N': '.grey',
    'BPNetwork': '.grey',
    'GreyBP': '.grey',
    'GuardedPrediction': '.guard',
    'add_guard': '.guard',
    'predict_guarded': '.guard',
    'HybridFilterNet': '.hybrid',
    'MLR': '.linear',
    'Scores': '.metrics',
    'scores': '.metrics',
    'ModelSelection': '.model_selection',
    'select_model': '.model_selection',
    'AGORegressor': '.preprocessing',
    'MinMaxAGO': '.preprocessing',
    'MinMaxScaled': '.preprocessing',
    'spread_search': '.preprocessing',
    'RBFNetwork': '.rbf',
    'SensorSelection': '.selection',
    'select_sensors': '.selection',
    'shape_offsets': '.shaping',
    'StiffnessResult': '.stiffness',
    'key_thermal_stiffness': '.stiffness',
    'SVR': '.svr',
    'SwarmResult': '.swarm',
    'TuneResult': '.swarm',
    'cso': '.swarm',
    'pso': '.swarm',
    'svr_cv_mse': '.swarm',
    'tune_svr': '.swarm',
    'AxesDiagnosis': '.thermal',
    'Diagnosis': '.thermal',
    'Machine': '.thermal',
    'Simulation': '.thermal',
    'diagnose': '.thermal',
    'diagnose_axes': '.thermal',
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    loaded = importlib.import_module(module, __name__)
    value = loaded if module == "." + name else getattr(loaded, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "__version__",
    "FORMAT_VERSION",
    "examples",
    "Estimator",
    "Regressor",
    "SequenceModel",
    "Clusterer",
    "load_model",
    "Run",
    "read_run",
    "Scores",
    "scores",
    "shape_offsets",
    "add_guard",
    "predict_guarded",
    "GuardedPrediction",
    "select_model",
    "ModelSelection",
    "MLR",
    "FuzzyCMeans",
    "SensorSelection",
    "select_sensors",
    "RBFNetwork",
    "MinMaxAGO",
    "MinMaxScaled",
    "AGORegressor",
    "spread_search",
    "SVR",
    "GreyBP",
    "GM1N",
    "BPNetwork",
    "HybridFilterNet",
    "cso",
    "pso",
    "SwarmResult",
    "tune_svr",
    "TuneResult",
    "svr_cv_mse",
    "time_series_split",
    "kfold_split",
    "key_thermal_stiffness",
    "StiffnessResult",
    "Machine",
    "Simulation",
    "AxesDiagnosis",
    "Diagnosis",
    "diagnose",
    "diagnose_axes",
    "ThermerrError",
    "ParameterError",
    "ShapeError",
    "DataError",
    "DataTypeError",
    "MissingColumnError",
    "NumericalError",
    "ConvergenceError",
    "NotFittedError",
    "ModelFormatError",
]
