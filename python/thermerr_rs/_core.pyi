# Stubs of the Rust extension module thermerr_rs._core (checked by mypy.stubtest in CI).
# Each family has its own section; the user-facing docs live in the Python wrappers.
from collections.abc import Callable
from typing import Any, TypeAlias, final

import numpy as np
import numpy.typing as npt

_F64: TypeAlias = npt.NDArray[np.float64]

__version__: str
FORMAT_VERSION: int
NETWORK_RULES: list[str]

def request_interrupt() -> None: ...
def clear_interrupt() -> None: ...
def read_model(text: str) -> tuple[str, int, str, Any]: ...
def write_model(kind: str, header: str, inner: Any) -> str: ...
def guard_from_training(
    text: str, x: _F64, times: _F64 | None, hold_s: float
) -> tuple[str, bool, list[tuple[int, int, float]]]: ...
def median_step(times: _F64) -> float | None: ...
def history_transform(x: _F64, times: _F64 | None, tau_s: list[float], step_s: float) -> _F64: ...
def predict_guarded(text: str, x: _F64, times: _F64 | None) -> tuple[_F64, list[str]]: ...
def sample_latency(text: str, x: _F64, n: int) -> tuple[float, float, float]: ...

@final
class Preprocessing:
    @staticmethod
    def fit(kind: str, x: _F64, y: _F64 | None = None) -> Preprocessing: ...
    @staticmethod
    def from_json(text: str, n_features: int) -> Preprocessing: ...
    def to_json(self) -> str: ...
    @property
    def kind(self) -> str: ...
    def transform(self, x: _F64) -> _F64: ...
    def transform_target(self, y: _F64) -> _F64: ...
    def inverse(self, y1: _F64) -> _F64: ...

# --- run I/O and figures of merit -------------------------------------------------------------
def read_run(path: str, nan: str = "error", delimiter: str = ",", decimal: str = ".",
             rename: list[str] = ...) -> dict[str, Any]: ...
def run_from_columns(source: str, names: list[str], data: _F64, nan: str = "error") -> dict[str, Any]: ...
def delimiter_named(text: str) -> str: ...
def iso_seconds(source: str, cells: list[str | None]) -> _F64: ...
def is_data_column(name: str) -> bool: ...
def not_a_number(column: str, cell: str) -> str: ...
def one_run(source: str, time: _F64, names: list[str], data: _F64) -> None: ...
def probe_faults(source: str, name: str, values: _F64, time: _F64) -> tuple[str | None, str | None, str | None]: ...
def bridge_column(source: str, name: str, values: _F64, time: _F64) -> tuple[_F64 | None, str | None, str | None]: ...
def scores(measured: _F64, predicted: _F64, zero_tol: float | None = None) -> dict[str, Any]: ...
def shape_series(spec: str, time: _F64, y: _F64) -> _F64: ...
def check_unseen(train_source: str, train_time: _F64, train: _F64, held_source: str, held_time: _F64, held: _F64) -> None: ...
def renamed_header(source: str, names: list[str], rename: list[str]) -> list[str]: ...

# --- multiple linear regression -----------------------------------------------------------------
@final
class MlrModel:
    @staticmethod
    def fit(x: _F64, y: _F64, *, fit_intercept: bool | None = None, alpha: float | None = None) -> MlrModel: ...
    def predict(self, x: _F64) -> _F64: ...
    @property
    def coef(self) -> _F64: ...
    @property
    def intercept(self) -> float: ...
    @property
    def n_features(self) -> int: ...

# --- fuzzy c-means ------------------------------------------------------------------------------
@final
class FcmModel:
    @staticmethod
    def fit(
        x: _F64,
        *,
        n_clusters: int,
        m: float = 2.0,
        tol: float = 1e-5,
        max_iter: int = 1000,
        seed: int | None = None,
        init: _F64 | None = None,
    ) -> FcmModel: ...
    def predict_membership(self, x: _F64) -> _F64: ...
    def predict(self, x: _F64) -> npt.NDArray[np.int64]: ...
    @property
    def centers(self) -> _F64: ...
    @property
    def membership(self) -> _F64: ...
    @property
    def labels(self) -> npt.NDArray[np.int64]: ...
    @property
    def history(self) -> _F64: ...
    @property
    def m(self) -> float: ...
    @property
    def n_iter(self) -> int: ...
    @property
    def objective(self) -> float: ...
    @property
    def converged(self) -> bool: ...
    @property
    def n_clusters(self) -> int: ...
    @property
    def n_features(self) -> int: ...

# --- RBF networks -------------------------------------------------------------------------------
@final
class RbfModel:
    @staticmethod
    def fit(
        x: _F64,
        y: _F64,
        *,
        design: str | None = None,
        spread: float | None = None,
        goal: float | None = None,
        max_neurons: int | None = None,
        n_centers: int | None = None,
        seed: int | None = None,
        rule: str | None = None,
        max_candidates: int | None = None,
    ) -> RbfModel: ...
    def predict(self, x: _F64) -> _F64: ...
    @property
    def centers(self) -> _F64: ...
    @property
    def weights(self) -> _F64: ...
    @property
    def bias(self) -> float: ...
    @property
    def selected(self) -> list[int]: ...
    @property
    def sse_history(self) -> _F64: ...
    @property
    def n_features(self) -> int: ...

def kmeans(x: _F64, init: _F64, max_iter: int = 300) -> tuple[_F64, list[int], int, float]: ...

# --- thermal network ----------------------------------------------------------------------------
@final
class MachineModel:
    @staticmethod
    def load(path: str) -> MachineModel: ...
    @staticmethod
    def from_toml(text: str, file: str = "<string>") -> MachineModel: ...
    @staticmethod
    def identify(
        source: str,
        time: _F64,
        names: list[str],
        data: _F64,
        holdout: tuple[str, _F64, list[str], _F64] | None = None,
        *,
        axes: list[str] | None = None,
        nodes: int | None = None,
        ambient: str | None = None,
        inputs: list[str] | None = None,
        train_fraction: float = 0.7,
        train_rows: int | None = None,
        seed: int = 0,
        max_iter: int = 100,
        progress: Callable[[int, int, int], object] | None = None,
    ) -> tuple[MachineModel, str]: ...
    def to_toml(self) -> str: ...
    def to_json(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def file(self) -> str: ...
    @property
    def nodes(self) -> list[str]: ...
    @property
    def axes(self) -> list[str]: ...
    @property
    def sensors(self) -> list[str]: ...
    def columns(self) -> list[str]: ...
    def simulate(
        self, source: str, time: _F64, names: list[str], data: _F64, *, fit_initial: int = 0,
        initial_k: dict[str, float] | None = None,
    ) -> dict[str, Any]: ...
    def calibrate(
        self,
        source: str,
        time: _F64,
        names: list[str],
        data: _F64,
        *,
        axis: str,
        bound_factor: float = 3.0,
        max_iter: int = 60,
    ) -> tuple[MachineModel, dict[str, Any]]: ...
    def diagnose(
        self,
        source: str,
        time: _F64,
        names: list[str],
        data: _F64,
        holdout: tuple[str, _F64, list[str], _F64] | None = None,
        *,
        axis: str | None = None,
        holdout_fraction: float = 0.3,
        train_rows: int | None = None,
        min_score: float = 0.1,
        noise_ratio: float = 2.0,
        network: str = "auto",
        progress: Callable[[int, int, int], object] | None = None,
    ) -> dict[str, Any]:
        """The diagnosis in rounds: ``report`` (report.json as JSON text: the round-1 fields, plus
        ``causes`` — each accepted cause's ``cause``, ``column``, ``node``, ``axis``, ``gain_pct``,
        ``params``, ``round``, ``rmse_um`` in the order accepted —, ``remainder_um`` and ``rounds``),
        ``calibration``, ``series``, ``calibrated_toml`` and ``extended_toml`` (every named cause).
        ``progress`` is called with ``(done, planned, round)`` of the calibrations every 50 ms
        while they change."""
        ...
    def diagnose_axes(
        self,
        source: str,
        time: _F64,
        names: list[str],
        data: _F64,
        holdout: tuple[str, _F64, list[str], _F64] | None = None,
        *,
        axes: list[str],
        holdout_fraction: float = 0.3,
        train_rows: int | None = None,
        min_score: float = 0.1,
        noise_ratio: float = 2.0,
        network: str = "auto",
        progress: Callable[[int, int, int], object] | None = None,
    ) -> tuple[list[dict[str, Any]], list[tuple[str, str]]]:
        """``diagnose`` of every axis in ``axes`` (empty: every drift entry), in parallel; a list
        of its dicts in ``axes`` order, and the axes left out as ``(axis, reason)`` (``axes``
        empty: a probe that gives nothing to diagnose on the run)."""
        ...

# --- support vector regression -------------------------------------------------------------------
@final
class SvrModel:
    @staticmethod
    def fit(
        x: _F64,
        y: _F64,
        *,
        c: float | None = None,
        epsilon: float | None = None,
        kernel: str | None = None,
        gamma: str | float | None = None,
        tol: float | None = None,
        shrinking: bool | None = None,
        cache_size: float | None = None,
        max_iter: int | None = None,
    ) -> SvrModel: ...
    def predict(self, x: _F64) -> _F64: ...
    @property
    def support_vectors(self) -> _F64: ...
    @property
    def dual_coef(self) -> _F64: ...
    @property
    def support(self) -> list[int]: ...
    @property
    def intercept(self) -> float: ...
    @property
    def n_iter(self) -> int: ...
    @property
    def gamma(self) -> float | None: ...
    @property
    def n_features(self) -> int: ...

# --- swarm search and SVR tuning ----------------------------------------------------------------
def swarm_minimize(
    f: Any,
    bounds: list[tuple[float, float]],
    *,
    method: str = "cso",
    pop: int = 20,
    iters: int = 100,
    g: int = 10,
    roosters: float = 0.2,
    hens: float = 0.6,
    fl: tuple[float, float] = ...,  # (0.4, 1.0)
    w: float = 0.7298,
    c1: float = 1.49618,
    c2: float = 1.49618,
    vmax_frac: float = 0.2,
    seed: int = 0,
    vectorized: bool = False,
) -> tuple[list[float], float, list[float], int]: ...
_Splits = list[tuple[list[int], list[int]]]

def kfold(n: int, k: int, seed: int | None = None) -> list[list[int]]: ...
def kfold_splits(n: int, k: int, seed: int | None = None) -> _Splits: ...
def time_series_split(
    n: int, n_splits: int, *, gap: int = 0, test_size: int | None = None, max_train_size: int | None = None
) -> _Splits: ...
def check_splits(splits: _Splits, n: int) -> None: ...
def auto_thin(splits: _Splits) -> int: ...
def svr_cv_mse(
    x: _F64, y: _F64, splits: _Splits, *, c: float, gamma: float, epsilon: float = 0.1, tol: float = 1e-3
) -> float: ...
def tune_svr(
    x: _F64,
    y: _F64,
    splits: _Splits,
    *,
    method: str = "cso",
    c_bounds: tuple[float, float] = ...,  # (0.01, 1000.0)
    gamma_bounds: tuple[float, float] = ...,  # (1e-4, 10.0)
    scale: str = "log",
    epsilon: float = 0.1,
    tol: float = 1e-3,
    pop: int = 20,
    iters: int = 100,
    g: int = 10,
    roosters: float = 0.2,
    hens: float = 0.6,
    fl: tuple[float, float] = ...,  # (0.4, 1.0)
    w: float = 0.7298,
    c1: float = 1.49618,
    c2: float = 1.49618,
    vmax_frac: float = 0.2,
    seed: int = 0,
    warm_start: bool | None = None,
    thin: int | None = None,
    progress: Any = None,
) -> tuple[float, float, float, list[float], int, int, int, SvrModel]: ...

# --- seed 002: grey models and BP networks -------------------------------------------------------
@final
class GreyModel:
    @staticmethod
    def fit(
        x: _F64,
        y: _F64,
        *,
        windows: list[int] | None = None,
        hidden: int | None = None,
        trainer: str | None = None,
        lr: float | None = None,
        momentum: float | None = None,
        max_epochs: int | None = None,
        goal: float | None = None,
        patience: int | None = None,
        init: float | None = None,
        seed: int | None = None,
        large_n: int | None = None,  # rows from which Adam takes the large-n rule; 0: never
    ) -> GreyModel: ...
    @staticmethod
    def fit_gm1n(x: _F64, y: _F64, *, window: int | None = None) -> GreyModel: ...
    def predict(self, x: _F64, y: _F64 | None = None) -> _F64: ...
    @property
    def windows(self) -> list[int]: ...
    @property
    def history(self) -> _F64: ...
    @property
    def n_features(self) -> int: ...

@final
class BpModel:
    @staticmethod
    def fit(
        x: _F64,
        y: _F64,
        *,
        hidden: list[int] | None = None,
        trainer: str | None = None,
        lr: float | None = None,
        momentum: float | None = None,
        max_epochs: int | None = None,
        goal: float | None = None,
        patience: int | None = None,
        init: float | None = None,
        seed: int | None = None,
        large_n: int | None = None,  # rows from which Adam takes the large-n rule; 0: never
    ) -> BpModel: ...
    def predict(self, x: _F64) -> _F64: ...
    @property
    def history(self) -> _F64: ...
    @property
    def n_features(self) -> int: ...

def gm1n_window(e: _F64, t: _F64, t_next: _F64) -> tuple[_F64, float]: ...

# --- seed 000: hybrid filter + network ----------------------------------------------------------
@final
class HybridModel:
    @staticmethod
    def fit(
        x: _F64,
        y: _F64,
        *,
        starts: list[int] = ...,
        variant: str | None = None,
        ma_lags: int | None = None,
        ar_lags: int | None = None,
        c_y: float | None = None,
        limit: float | None = None,
        hidden: int | None = None,
        trainer: str | None = None,
        lr: float | None = None,
        momentum: float | None = None,
        max_epochs: int | None = None,
        goal: float | None = None,
        patience: int | None = None,
        init: float | None = None,
        seed: int | None = None,
        large_n: int | None = None,  # rows from which Adam takes the large-n rule; 0: never
    ) -> HybridModel: ...
    def predict(self, x: _F64, y: _F64 | None = None) -> _F64: ...
    @property
    def filters(self) -> tuple[list[float], list[float], list[float]]: ...
    @property
    def history(self) -> _F64: ...
    @property
    def n_features(self) -> int: ...

# --- defaults -----------------------------------------------------------------------------------
def default_params(kind: str) -> dict[str, Any]:
    """The core's default hyper-parameters of a model kind ("mlr", "rbf", "svr", "bp", "greybp",
    "gm1n", "hybrid"); every ``fit`` keyword left as ``None`` takes these."""
