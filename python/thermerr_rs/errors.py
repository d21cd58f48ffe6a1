"""Exceptions raised by thermerr_rs.

Every class derives from :class:`ThermerrError` *and* from the builtin a caller would catch, so
``except ValueError`` keeps working. The Rust binding raises these classes by name.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any


class ThermerrError(Exception):
    """Base class of every error thermerr_rs raises on purpose."""


class ParameterError(ThermerrError, ValueError):
    """A hyper-parameter is out of its domain."""


class ShapeError(ThermerrError, ValueError):
    """Arrays of the wrong shape, empty input, or a feature count the model was not fitted on."""


class DataError(ThermerrError, ValueError):
    """Data that cannot be used: a non-numeric cell, NaN, time not increasing, no rows, ..."""


class DataTypeError(DataError, TypeError):
    """Input of a type that cannot be read as numbers: a sparse matrix, a dict in an object
    array, ... (a :class:`TypeError` too, as numpy and scikit-learn raise it)."""


class MissingColumnError(ThermerrError, KeyError):
    """A column asked for by name is not in the run."""

    def __str__(self) -> str:  # KeyError would quote the whole message
        return str(self.args[0]) if self.args else ""


class NumericalError(ThermerrError, ArithmeticError):
    """A singular system or a similar numerical breakdown."""


class ConvergenceError(ThermerrError, RuntimeError):
    """An iterative method did not meet its tolerance."""


if TYPE_CHECKING:
    from sklearn.exceptions import NotFittedError as _SklearnNotFittedError

    class NotFittedError(ThermerrError, _SklearnNotFittedError):
        """A model was used before ``fit``."""


def _not_fitted_error() -> type:
    from sklearn.exceptions import NotFittedError as _SklearnNotFittedError

    class NotFittedError(ThermerrError, _SklearnNotFittedError):
        """A model was used before ``fit``. Also scikit-learn's ``NotFittedError`` (itself a
        ``ValueError`` and an ``AttributeError``), so scikit-learn's tools recognise it."""

    NotFittedError.__module__ = __name__
    NotFittedError.__qualname__ = "NotFittedError"
    return NotFittedError


def __getattr__(name: str) -> Any:
    # NotFittedError derives from scikit-learn's, whose import takes about a second; it is
    # made on first use, so that a command that never needs scikit-learn (a diagnosis, the
    # command line's start) does not import it
    if name == "NotFittedError":
        cls = _not_fitted_error()
        globals()[name] = cls
        return cls
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class ModelFormatError(ThermerrError, ValueError):
    """A model file that this version cannot read (schema version, kind, missing field)."""


class MissingDependencyError(ThermerrError, ImportError):
    """An optional dependency is not installed; the message names the extra to install."""


class SuspectReadingWarning(UserWarning):
    """A reading of a run that the run itself makes suspect (a jump far beyond the column's usual
    change, one reading repeated for 30 min or more, a gap in the log's time axis): said, and
    used as read, except that identification takes a temperature with a jump for neither the
    room nor a node's sensor, the diagnosis does not try it as a heat source, and the readings
    of a node's sensor or of a probe from a jump away to a jump back (or to the end of the
    run) are neither fitted nor scored. The diagnosis
    lists them in ``report["suspect_readings"]``, identification in its notes; the command line
    prints them as lines of the result instead."""


__all__ = [
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
    "MissingDependencyError",
    "SuspectReadingWarning",
]
