"""Output shaping: a predicted error turned into the offset a CNC controller accepts.

A controller applies a compensation offset per interpolation cycle, in its own unit and register
width; a large step in the offset is a step in the tool path. ``shape_offsets`` clamps the
prediction (``limit_um``, and what ``bits`` signed codes of ``unit_um`` can hold), keeps the last
offset while the change stays within ``dead_band_um``, moves at most ``max_rate_um_per_s`` per
second, and quantises to ``unit_um`` — in that order, by the same Rust code as
``thermerr-edge --shape``, so the library and the gateway send the same offsets.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Union

import numpy as np

from . import _core
from ._arrays import F64
from .errors import ParameterError

#: A shaping: the text form ``"limit=50,rate=2,deadband=0.5,unit=0.1,bits=16"`` or a mapping of
#: ``limit_um``, ``max_rate_um_per_s``, ``dead_band_um``, ``unit_um``, ``bits``.
ShapeSpec = Union[str, Mapping[str, Any]]


def spec_text(shape: ShapeSpec) -> str:
    """The text form of a shaping (what ``thermerr-edge --shape`` takes)."""
    if isinstance(shape, str):
        return shape
    if isinstance(shape, Mapping):
        return ",".join(f"{k}={v}" for k, v in shape.items() if v is not None)
    raise ParameterError(f"shape must be a text like 'limit=50,unit=0.1' or a mapping, got {type(shape).__name__}")


def shape_offsets(time_s: Any, predicted: Any, shape: ShapeSpec) -> F64:
    """The offsets to send for ``predicted`` (µm) at times ``time_s`` (s), from a fresh state."""
    t = np.ascontiguousarray(time_s, dtype=np.float64)
    y = np.ascontiguousarray(predicted, dtype=np.float64)
    out: F64 = _core.shape_series(spec_text(shape), t, y)
    return out
