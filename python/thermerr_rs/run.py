"""Measured runs: ``time_s`` plus ``T_*`` temperatures, ``E_*`` errors and ``U_*`` inputs."""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from typing import Any, Literal

import numpy as np

from . import _core
from ._arrays import F64
from .errors import DataError, MissingColumnError, ParameterError, ShapeError, SuspectReadingWarning

NanPolicy = Literal["error", "drop", "interpolate"]

#: a run whose clock starts at most this many sampling steps after another's last sample is its
#: continuation (:meth:`Run.continues`)
CONTINUATION_STEPS = 10


def median_step(time_s: Any) -> float:
    """The median sampling step of a clock, in s (the core's rule; 1 s when it has none)."""
    step = _core.median_step(np.ascontiguousarray(time_s, dtype=np.float64))
    return 1.0 if step is None else float(step)


def _date_times(col: Any, source: str) -> F64:
    """A frame's ``time`` column in seconds since the epoch: ``datetime64`` values (UTC for
    time-zone aware ones) converted here, strings read by the core's ISO-8601 reader (as a CSV's
    ``time`` cells are)."""
    dt: Any = getattr(col, "dt", None)
    if getattr(dt, "tz", None) is not None:  # pandas, time-zone aware: the instants in UTC
        col = dt.tz_convert("UTC").dt.tz_localize(None)
    if getattr(getattr(col, "dtype", None), "tz", None) is not None:  # a time-zone aware index
        col = col.tz_convert("UTC").tz_localize(None)
    arr = np.asarray(col.to_numpy() if hasattr(col, "to_numpy") else col)
    if arr.dtype.kind == "M":
        ns = arr.astype("datetime64[ns]")
        out = ns.astype(np.int64).astype(np.float64) / 1e9
        out[np.isnat(ns)] = np.nan
        return out
    if arr.dtype.kind in "iufb":
        raise DataError(
            f"{source}: column `time`: holds numbers; `time` is for date-times "
            "(a number of seconds belongs in a `time_s` column)"
        )
    cells = [None if v is None or (isinstance(v, float) and np.isnan(v)) else str(v) for v in arr.tolist()]
    return _core.iso_seconds(source, cells)


def _not_a_number(source: str, name: str, col: Any) -> str:
    """The refusal of a data column holding text, naming its first such cell as the CSV reader does."""
    for i, v in enumerate(np.asarray(col, dtype=object).tolist()):
        try:
            float(v)
        except (TypeError, ValueError):
            return f"{source}, row {i + 1}, column `{name}`: {_core.not_a_number(name, str(v))}"
    return f"{source}: column `{name}` is not numeric"


class Run:
    """A validated measured run. Columns are float64 numpy arrays, by name: ``run["T_spindle"]``.

    ``temperatures``, ``errors`` and ``inputs`` list the ``T_*``, ``E_*`` and ``U_*`` names in
    file order. Parsing and validation happen in Rust; see :func:`read_run`.
    """

    def __init__(self, parts: dict[str, Any]) -> None:
        self.source: str = parts["source"]
        self.time_s: F64 = np.asarray(parts["time_s"], dtype=np.float64)
        self.names: list[str] = list(parts["names"])
        self._data: F64 = np.asarray(parts["data"], dtype=np.float64)
        self.ignored: list[str] = list(parts["ignored"])
        self.dropped_rows: list[int] = list(parts["dropped_rows"])
        self.interpolated: int = int(parts["interpolated"])
        self._index = {n: k for k, n in enumerate(self.names)}
        if self.ignored:
            warnings.warn(
                f"{self.source}: ignoring columns without a T_/E_/U_ prefix: {', '.join(self.ignored)} "
                "(a sensor among them is read when named so: --rename 'OLD=NEW', read_run(rename=))",
                UserWarning,
                stacklevel=3,
            )

    @classmethod
    def from_frame(cls, df: Any, *, nan: NanPolicy = "error", source: str = "<DataFrame>") -> Run:
        """Build a run from a pandas or polars DataFrame (or any mapping of column → values).

        The clock is a ``time_s`` column (seconds), else a ``time`` column of date-times
        (``datetime64``, time-zone aware or not, or ISO-8601 strings read as :func:`read_run`
        reads them), else a pandas ``DatetimeIndex``; a run's ``time_s`` then counts seconds
        from its first row."""
        names = [str(c) for c in df.columns] if hasattr(df, "columns") else [str(k) for k in df]
        index: Any = getattr(df, "index", None)
        from_index = (
            "time_s" not in names and "time" not in names and getattr(getattr(index, "dtype", None), "kind", "") == "M"
        )
        if from_index:
            names = ["time", *names]
        cols = []
        for name in names:
            col: Any = index if from_index and name == "time" else df[name]
            if name == "time" and "time_s" not in names:
                cols.append(_date_times(col, source))
                continue
            if hasattr(col, "to_numpy"):
                col = col.to_numpy()
            if name == "time_s" and getattr(getattr(col, "dtype", None), "kind", "") == "M" and len(col):
                # date-times under the name of seconds: numpy would cast them to nanoseconds
                cell = str(np.datetime_as_string(np.asarray(col)[0], unit="s")).replace("T", " ")
                raise DataError(f"{source}, row 1, column `time_s`: {_core.not_a_number(name, cell)}")
            try:
                cols.append(np.asarray(col, dtype=np.float64))
            except (TypeError, ValueError):
                if name == "time_s" or _core.is_data_column(name):
                    raise DataError(_not_a_number(source, name, col)) from None
                # a text column the core ignores (a note, an operator's name): ignored with a
                # warning, as in a CSV
                cols.append(np.full(len(col), np.nan))
        if not cols:
            raise DataError(f"{source}: no columns")
        data = np.ascontiguousarray(np.column_stack(cols), dtype=np.float64)
        return cls(_core.run_from_columns(source, names, data, nan))

    def __len__(self) -> int:
        return int(self.time_s.shape[0])

    def __contains__(self, name: object) -> bool:
        return name == "time_s" or name in self._index

    def __getitem__(self, name: str) -> F64:
        if name == "time_s":
            return self.time_s
        k = self._index.get(name)
        if k is None:
            raise MissingColumnError(
                f"{self.source}: no column named `{name}` (columns are: {', '.join(self.names)})"
            )
        col: F64 = self._data[:, k]
        return col

    def _prefixed(self, prefix: str) -> list[str]:
        return [n for n in self.names if n.startswith(prefix)]

    @property
    def temperatures(self) -> list[str]:
        return self._prefixed("T_")

    @property
    def errors(self) -> list[str]:
        return self._prefixed("E_")

    @property
    def inputs(self) -> list[str]:
        return self._prefixed("U_")

    def matrix(self, names: list[str]) -> F64:
        """The named columns as a C-contiguous (samples × len(names)) float64 matrix."""
        if not names:
            raise DataError("no columns asked for")
        return np.ascontiguousarray(np.column_stack([self[n] for n in names]))

    def bridged(self, columns: list[str]) -> tuple[Run, list[str]]:
        """This run with each temperature of ``columns`` whose failing stretches are all short
        spikes (a jump away that comes back within 600 s: a thermocouple's glitch, a contact
        loose for a moment) bridged by a straight line in time between the right readings on
        either side, and a line per column bridged ("T_t8: 1 short spike (11 rows, first at row
        3001), each back within 600 s"); the run itself and no lines when there is none. The
        rule is the core's (``Run::bridged``, which ``thermerr init`` uses too); a column that
        fails for longer is left as read (:meth:`failing`)."""
        data: F64 | None = None
        said: list[str] = []
        for name in columns:
            if not name.startswith("T_"):
                continue
            mended, line, _ = _core.bridge_column(self.source, name, np.ascontiguousarray(self[name]),
                                                  np.ascontiguousarray(self.time_s))
            if mended is None or line is None:
                continue
            if data is None:
                data = self._data.copy()
            data[:, self._index[name]] = mended
            said.append(line)
        if data is None:
            return self, []
        parts: dict[str, Any] = {"source": self.source, "time_s": self.time_s, "names": self.names, "data": data,
                                 "ignored": [], "dropped_rows": self.dropped_rows,
                                 "interpolated": self.interpolated}
        return Run(parts), said

    def failing(self, columns: list[str]) -> list[str]:
        """The suspect-reading lines of the temperatures among ``columns`` that the run shows
        failing beyond a short spike: a jump that does not come back within 600 s (an open
        thermocouple, a sensor dead for hours), or one reading in every row (a dead or
        disconnected sensor)."""
        out = []
        for name in columns:
            if name.startswith("T_"):
                _, _, text = _core.bridge_column(self.source, name, np.ascontiguousarray(self[name]),
                                                 np.ascontiguousarray(self.time_s))
                if text is not None:
                    out.append(text)
        return out

    def check_fit_columns(self, target: str, features: list[str]) -> None:
        """Checks the columns of a fit before anything is computed: the
        target is an error (``E_*``) column and no input is an error column (a model fitted with
        its own target, or another probe's error, among its inputs looks perfect and compensates
        nothing), and the target moves: a probe that reads one value in every row (dead,
        unplugged) has no drift, and a model of it would report a perfect compensation of
        nothing. A target that jumps away (and back, or to the end: a probe re-zeroed or knocked)
        is warned of (:class:`~thermerr_rs.errors.SuspectReadingWarning`) and fitted as read.
        Every ``fit_run`` goes through here."""
        if not target.startswith("E_"):
            raise ParameterError(f"{self.source}: the target `{target}` is not an error column (E_*); "
                                 f"error columns are: {', '.join(self.errors) or 'none'}")
        leaks = [f for f in features if f.startswith("E_")]
        if leaks:
            raise ParameterError(f"{self.source}: error column(s) {', '.join(leaks)} among the inputs; "
                                 "inputs are temperatures (T_*) and machine inputs (U_*)")
        if not features:
            raise ParameterError(f"{self.source}: no input columns given")
        for name in [target, *features]:
            self[name]  # raises MissingColumnError naming the column and the file
        dead, failing, _ = self._probe_faults(target)
        if dead is not None:
            raise ShapeError(f"{dead}, nothing to model; mend the probe")
        if failing is not None:
            warnings.warn(failing, SuspectReadingWarning, stacklevel=3)

    def _probe_faults(self, target: str) -> tuple[str | None, str | None, str | None]:
        return _core.probe_faults(self.source, target, np.ascontiguousarray(self[target], dtype=np.float64),
                                  np.ascontiguousarray(self.time_s, dtype=np.float64))

    def start_note(self, target: str) -> str | None:
        """The line saying that probe ``target`` reads away from zero at this run's first right
        reading (at least 10 % of what it moves over the run, and 2 µm, but within its movement:
        a probe not zeroed at the start, or a piece of a longer log with its clock restarted),
        or None. A model predicts a run's drift from its start, where it is 0, so that reading
        counts against it on every row of the run's scores: ``thermerr evaluate`` and ``fit
        --test`` warn with it (the run is scored as read). The same rule as the suspect reading
        ``start`` of a diagnosis (docs/machine-model.md)."""
        return self._probe_faults(target)[2]

    def input_matrix(self, features: list[str], form: str = "absolute", reference: Run | None = None) -> F64:
        """The model inputs built from the named columns: ``form="absolute"`` the readings as
        they are, ``"rise"`` each reading minus the run's first sample (like the error itself,
        which is relative to the run's start), or minus ``reference``'s first sample when given.
        What ``fit_run``/``predict_run`` feed a model."""
        if form not in ("absolute", "rise"):
            raise ParameterError(f'the input form must be "absolute" or "rise", got {form!r}')
        x = self.matrix(features)
        if form == "rise":
            x0 = x[0] if reference is None else reference.matrix(features)[0]
            x = np.ascontiguousarray(x - x0)
        return x

    def slice(self, start: int | None = None, stop: int | None = None) -> Run:
        """Rows ``start:stop`` as a new run (time is kept as measured)."""
        sl = slice(start, stop)
        parts: dict[str, Any] = {
            "source": self.source,
            "time_s": self.time_s[sl].copy(),
            "names": self.names,
            "data": self._data[sl].copy(),
            "ignored": [],
            "dropped_rows": [],
            "interpolated": 0,
        }
        if parts["time_s"].shape[0] == 0:
            raise DataError(f"{self.source}: rows {start}:{stop} select nothing")
        return Run(parts)

    def check_unseen(self, training: Run) -> None:
        """Refuses this run as held-out data for a fit on ``training`` (a ``DataError``, one line
        naming both files and the rows) when it holds a stretch of ``training``'s rows: ten or
        more changing rows in a row that read, in every column both have, exactly as
        ``training``'s do (a piece cut from the training log, its clock kept or restarted, or a
        copy). Its "held-out" figures would be scored on rows the fit trains on. Nor rows taken from
        the training log in turn (odd rows to train and even rows to hold out, every third row, a
        thinned copy): at least half of this run's rows fall on ``training``'s clock between two
        of its consecutive samples and read within three typical steps of them in every column,
        so every held-out row has training rows beside it (time series are validated in time
        order). Two runs of one machine do not read alike row for row; a piece cut out and
        resampled at another step is not recognised."""
        names = [n for n in training.names if n in self._index]
        if names:
            _core.check_unseen(training.source, training.time_s, training.matrix(names), self.source, self.time_s,
                               self.matrix(names))

    def continues(self, before: Run) -> bool:
        """Whether this run is the continuation of ``before``, cut from the same log: its clock
        starts after ``before``'s last sample by at most :data:`CONTINUATION_STEPS` of
        ``before``'s sampling steps (a run cut out of a ``time_s`` log keeps its clock; one with
        an ISO ``time`` column counts from its own first row and is never taken as one), and the
        machine goes on through the seam (:meth:`seam` is None)."""
        return self._clock_continues(before) and self.seam(before) is None

    def _clock_continues(self, before: Run) -> bool:
        gap = float(self.time_s[0] - before.time_s[-1])
        return 0.0 < gap <= CONTINUATION_STEPS * median_step(before.time_s)

    def seam(self, before: Run) -> str | None:
        """Why this run, whose clock goes on from ``before``'s, is another run all the same: most
        of its temperatures step away from ``before``'s last readings at its first row (a run
        started later on a logger whose clock ran on), in one line naming the row; None when
        the clock does not go on or the machine does."""
        if not self._clock_continues(before):
            return None
        joined = self.following(before)
        try:
            _core.one_run(joined.source, joined.time_s, list(joined.names), joined.matrix(list(joined.names)))
        except DataError as e:
            return str(e)
        return None

    def following(self, before: Run) -> Run:
        """``before``'s rows, then this run's: one run, as a logger running through both would
        have written it, so that rises are taken from ``before``'s start and history filters run
        on through the join (``predict_run(run, after=before)``). The columns are those both runs
        have, in this run's order. A clock that does not go on after ``before``'s last sample (an
        ISO ``time`` column counts from its own first row) is moved to start one sampling step
        after it."""
        names = [n for n in self.names if n in before._index]
        if not names:
            raise DataError(f"{self.source}: no column in common with {before.source}")
        time = self.time_s
        if time[0] <= before.time_s[-1]:
            time = time - time[0] + before.time_s[-1] + median_step(self.time_s)
        parts: dict[str, Any] = {
            "source": f"{before.source} + {self.source}",
            "time_s": np.concatenate([before.time_s, time]),
            "names": names,
            "data": np.concatenate([before.matrix(names), self.matrix(names)]),
            "ignored": [],
            "dropped_rows": [],
            "interpolated": 0,
        }
        return Run(parts)

    def __repr__(self) -> str:
        return (
            f"Run({self.source!r}, {len(self)} samples, {len(self.temperatures)} T, "
            f"{len(self.errors)} E, {len(self.inputs)} U)"
        )


def read_run(path: str | os.PathLike[str], nan: NanPolicy = "error", *, delimiter: str = ",",
             decimal: str = ".", rename: Sequence[str] = ()) -> Run:
    """Read and validate a run CSV (formats.md, "Measured run").

    ``nan``: ``"error"`` (default) refuses a missing value, naming its row and column;
    ``"drop"`` drops rows with any missing value; ``"interpolate"`` fills gaps linearly in time.
    Every refusal names the file, and the row and column where there is one. Columns without a
    ``T_``/``E_``/``U_`` prefix are ignored with a warning. ``delimiter``: the field separator
    (``";"`` for files from a spreadsheet set to a decimal comma's locale, ``"\t"``, ...; or
    by name: ``"tab"``, ``"semicolon"``, ``"comma"``); a
    header that looks separated by another one says so. ``decimal``: the decimal mark, ``"."``
    (default) or ``","`` (``20,5`` for 20.5, as such a spreadsheet writes; then a point in a
    number is refused, not read as a thousands separator). ``rename``: header names mapped to
    the run format's before anything else is read, ``"OLD=NEW"`` each, the first that matches a
    column renaming it; ``*`` in OLD stands for any text, put back where NEW has one (a logger's
    ``Time (s)``, ``Temp t1 (°C)``, ``Disp ch1 (um)``: ``["Time (s)=time_s", "Temp * (°C)=T_*",
    "Disp * (um)=E_*"]``). A rename that matches no column is refused, naming the columns.
    """
    return Run(_core.read_run(os.fspath(path), nan, delimiter, decimal, list(rename)))
