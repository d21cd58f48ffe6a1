# Stubs of the Rust extension module thermerr_rs._core (checked by mypy.stubtest in CI).
# Each family has its own section; the user-facing docs live in the Python wrappers.
from typing import Any, final

import numpy as np
import numpy.typing as npt

from typing import TypeAlias

_F64: TypeAlias = npt.NDArray[np.float64]

__version__: str

# --- run I/O and figures of merit -------------------------------------------------------------
def read_run(path: str, nan: str = "error") -> dict[str, Any]: ...
def run_from_columns(source: str, names: list[str], data: _F64, nan: str = "error") -> dict[str, Any]: ...
def scores(measured: _F64, predicted: _F64, zero_tol: float | None = None) -> dict[str, Any]: ...

# --- multiple linear regression -----------------------------------------------------------------
@final
class MlrModel:
    @staticmethod
    def fit(x: _F64, y: _F64, *, fit_intercept: bool = True) -> MlrModel: ...
    def predict(self, x: _F64) -> _F64: ...
    @property
    def coef(self) -> _F64: ...
    @property
    def intercept(self) -> float: ...
    @property
    def n_features(self) -> int: ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str) -> MlrModel: ...

# --- fuzzy c-means ------------------------------------------------------------------------------

# --- RBF networks -------------------------------------------------------------------------------
