"""thermerr_rs: machine-tool thermal error — models, compensation and physics diagnosis.

The compute kernels are Rust (``thermerr_rs._core``); this package is a thin, typed API over
them. See the README for the command line (``thermerr``).
"""

from __future__ import annotations

from ._core import __version__
from .base import FORMAT_VERSION, Clusterer, Estimator, Regressor, SequenceModel, load_model
from .errors import (
    ConvergenceError,
    DataError,
    DataTypeError,
    MissingColumnError,
    ModelFormatError,
    NotFittedError,
    NumericalError,
    ParameterError,
    ShapeError,
    ThermerrError,
)
from . import examples
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
from .run import Run, read_run
from .selection import SensorSelection, select_sensors
from .shaping import shape_offsets
from .stiffness import StiffnessResult, key_thermal_stiffness
from .svr import SVR
from .swarm import SwarmResult, TuneResult, cso, pso, svr_cv_mse, tune_svr
from .thermal import AxesDiagnosis, Diagnosis, Machine, Simulation, diagnose, diagnose_axes

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
