"""Input scaling in front of any estimator, recorded in the model file so that a model fitted on
scaled inputs predicts from raw sensor readings (on the edge too). The class lives in
:mod:`thermerr_rs.preprocessing`; this module keeps its old import path."""

from __future__ import annotations

from .preprocessing import MinMaxScaled

__all__ = ["MinMaxScaled"]
