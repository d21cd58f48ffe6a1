"""Endurance data for the edge predictor (issue 13 point 4): a long run at 1 s with injected
sensor and transport faults, written in chunks, and a runner that streams a file through
`thermerr-edge` over a pipe and measures its peak resident memory.

Shared by `benches/bench_endurance.py` (a week, 604 800 rows) and `tests/test_endurance.py` (a
size CI can afford). It lives here, beside the bench that is its full-size user, rather than in
tests/: benches/ is a plain folder of scripts that `compare.py` already puts on `sys.path`, pytest
never collects it (`testpaths = ["tests"]`), and the test adds it to `sys.path` the same way. Only
NumPy is needed (no SciPy: the spindle is piecewise constant, so the first-order heating has a
closed form per segment, and the ambient cycle's lag has a closed form too).

The run: `time_s` (integer seconds), six temperatures `T_1`..`T_6` (°C), `U_spindle_rpm`, `E_x`
(µm). The shop air follows a daily cycle (coldest near 04:00); each sensor sees it through its own
lag, plus the heat of the spindle through a first-order response of its own time constant; the
spindle runs a random programme of 10–90 min segments by day and stands still at night; `E_x` is
a fixed mix of the sensors' heating plus noise. All of it is deterministic from `seed`, and the
fault-free twin of a faulty file (`faults=False`, same seed) has the same samples, so the good
rows of both are identical text.

Faults (`write_run(..., faults=True)`), at rows picked from a separate random stream, never in the
first `WARMUP` rows (a `rise` model takes its reference there), never two on one sample:

- ``nan``, ``empty``: a dropout, one field written as ``NaN``/``nan`` or left empty, in a
  temperature (a model feature) or in ``U_spindle_rpm``/``E_x`` (not features of the test's models);
- ``stuck``: ``T_3`` repeats one value for hours (one window a day; `Fault.n` rows);
- ``spike``: one sample of an open thermocouple, 1372 or -273 °C (type K full scale);
- ``bytes``: an extra line of random bytes (never a newline; at least one byte that is not UTF-8);
- ``text``: an extra line of printable ASCII without digits (valid UTF-8 that is no number);
- ``fields``: a sample written with one field missing or one too many;
- ``truncated``: the last sample cut in the middle of ``T_4``, with no newline.

The file's lines: the header is line 1; `Fault.line` is the line that carries the fault (the first
line of a stuck window). ``bytes``, ``text``, ``fields`` and ``truncated`` lines can never be read
as a sample (`Fault.unreadable`); a dropout makes its row unreadable only for a model that reads
that column.
"""

from __future__ import annotations

import os
import subprocess
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

TEMPS = [f"T_{k}" for k in range(1, 7)]
COLUMNS = ["time_s", *TEMPS, "U_spindle_rpm", "E_x"]
HEADER = ",".join(COLUMNS)
DAY_S = 86_400
WARMUP = 100  # no fault in the first rows
STUCK_COLUMN = "T_3"

# per sensor: lag of the shop air (s), heating time constant (s), heating gain (°C at full speed)
_AIR_LAG_S = np.array([600.0, 1800.0, 3600.0, 5400.0, 900.0, 7200.0])
_TAU_S = np.array([300.0, 900.0, 1800.0, 3600.0, 600.0, 5400.0])
_GAIN_C = np.array([9.0, 6.0, 4.5, 3.0, 7.5, 2.0])
_ERROR_UM_PER_C = np.array([1.8, -0.6, 2.4, 1.1, -0.9, 3.0])
_AIR_MEAN_C, _AIR_AMPL_C = 20.0, 2.5
_SPEEDS = np.array([0.0, 0.0, 1500.0, 3000.0, 4500.0, 6000.0, 8000.0])
_MAX_RPM = 8000.0

UNREADABLE = frozenset({"bytes", "text", "fields", "truncated"})


@dataclass(frozen=True)
class Fault:
    """One injected fault: its kind, the file line carrying it (header = line 1), the sample it
    alters or replaces (None for an inserted line), the column (None for a whole line) and, for a
    stuck window, its length in rows."""

    kind: str
    line: int
    row: int | None
    column: str | None = None
    n: int = 1

    @property
    def unreadable(self) -> bool:
        """The line can never be read as a sample, whatever the model reads."""
        return self.kind in UNREADABLE

    def rejects(self, features: list[str] | set[str]) -> bool:
        """Whether a reader that refuses non-finite inputs must skip this line for a model
        reading `features` (a dropout in a column the model does not read is harmless)."""
        return self.unreadable or (self.kind in ("nan", "empty") and self.column in features)


def _air(t: np.ndarray, lag_s: float) -> np.ndarray:
    """The daily air cycle (coldest near 04:00) seen through a first-order lag: steady state."""
    w = 2.0 * np.pi / DAY_S
    phase = w * (t - 10.0 * 3600.0)  # sin's zero crossing rising at 10:00 -> minimum near 04:00
    gain = 1.0 / np.sqrt(1.0 + (w * lag_s) ** 2)
    return _AIR_MEAN_C + _AIR_AMPL_C * gain * np.sin(phase - np.arctan(w * lag_s))


def _segments(n_rows: int, rng: np.random.Generator):
    """The spindle programme: (start, stop, rpm) segments of 10–90 min; still from 22:00 to 06:00."""
    t = 0
    while t < n_rows:
        length = int(rng.integers(600, 5401))
        stop = min(t + length, n_rows)
        hour = (t % DAY_S) / 3600.0
        rpm = 0.0 if (hour >= 22.0 or hour < 6.0) else float(rng.choice(_SPEEDS))
        yield t, stop, rpm
        t = stop


def samples(n_rows: int, seed: int = 0, chunk: int = 8192):
    """The fault-free samples, in chunks: yields (t, temps (k×6), rpm (k,), e_x (k,))."""
    rng = np.random.default_rng([seed, 0])
    heat = np.zeros(6)  # each sensor's heating above its air, °C
    for start, stop, rpm in _segments(n_rows, rng):
        target = _GAIN_C * (rpm / _MAX_RPM) ** 1.5
        for a in range(start, stop, chunk):
            b = min(a + chunk, stop)
            t = np.arange(a, b, dtype=float)
            # exact response of tau dh/dt = target - h over the segment, from h(start) = heat
            decay = np.exp(-np.outer(t - start + 1.0, 1.0 / _TAU_S))
            h = target + (heat - target) * decay
            air = np.stack([_air(t, lag) for lag in _AIR_LAG_S], axis=1)
            temps = air + h + rng.normal(0.0, 0.02, size=h.shape)
            e_x = h @ _ERROR_UM_PER_C + 0.8 * (air[:, 0] - _AIR_MEAN_C) + rng.normal(0.0, 0.15, size=len(t))
            yield t.astype(np.int64), temps, np.full(len(t), rpm), e_x
        heat = target + (heat - target) * np.exp(-(stop - start) / _TAU_S)


def _fault_plan(n_rows: int, seed: int) -> tuple[dict[int, tuple[str, str | None]], list[tuple[int, int]],
                                                 dict[int, list[str]]]:
    """Which rows carry which fault: per-row faults, stuck windows (start, length), and the kinds of
    extra lines inserted before a row."""
    rng = np.random.default_rng([seed, 1])
    last = n_rows - 1  # the truncated line
    stuck: list[tuple[int, int]] = []
    for day in range(max(1, n_rows // DAY_S)):
        length = min(int(rng.integers(2 * 3600, 4 * 3600 + 1)), max(0, (n_rows - 2 * WARMUP) // 4))
        if length < 2:
            break
        lo = max(WARMUP, day * DAY_S)
        hi = min((day + 1) * DAY_S, last) - length
        if hi <= lo:
            break
        stuck.append((int(rng.integers(lo, hi)), length))
    taken = np.zeros(n_rows, dtype=bool)
    taken[:WARMUP] = True
    taken[last] = True
    for s, length in stuck:
        taken[s : s + length] = True
    free = np.flatnonzero(~taken)
    n_drop, n_spike, n_fields = max(4, n_rows // 1000), max(2, n_rows // 2500), max(2, n_rows // 5000)
    picks = rng.choice(free, size=min(len(free), n_drop + n_spike + n_fields), replace=False)
    per_row: dict[int, tuple[str, str | None]] = {}
    drop_cols = [*TEMPS, "U_spindle_rpm", "E_x"]
    for k, row in enumerate(picks.tolist()):
        if k < n_drop:
            per_row[row] = (str(rng.choice(["nan", "empty"])), drop_cols[k % len(drop_cols)])
        elif k < n_drop + n_spike:
            per_row[row] = ("spike", TEMPS[int(rng.integers(0, 6))])
        else:
            per_row[row] = ("fields", None)
    inserted: dict[int, list[str]] = {}
    n_extra = max(4, n_rows // 2500)
    for k, row in enumerate(rng.integers(WARMUP, last, size=n_extra).tolist()):
        inserted.setdefault(row, []).append("bytes" if k % 2 == 0 else "text")
    return per_row, stuck, inserted


def _garbage(kind: str, rng: np.random.Generator) -> bytes:
    if kind == "bytes":
        b = bytearray(rng.integers(0, 256, size=int(rng.integers(1, 121)), dtype=np.uint8).tobytes())
        b = bytearray(x if x != 0x0A else 0x0B for x in b)  # a newline would split the line
        b[int(rng.integers(0, len(b)))] = int(rng.choice([0xC0, 0xC1, 0xF5, 0xFE, 0xFF]))  # never UTF-8
        return bytes(b)
    alphabet = np.frombuffer(b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ,;:._-+ #!?()", dtype=np.uint8)
    body = rng.choice(alphabet, size=int(rng.integers(1, 80))).tobytes()
    return b"x" + body  # never blank (a blank line is no sample and no error)


def write_run(path: str | os.PathLike[str], n_rows: int, seed: int = 0, *, faults: bool = True,
              chunk: int = 8192) -> list[Fault]:
    """Write `n_rows` samples at 1 s to `path` (with the faults above when `faults`), chunk by chunk;
    return the injected faults in line order (empty without faults)."""
    if n_rows < 4 * WARMUP:
        raise ValueError(f"n_rows must be at least {4 * WARMUP}")
    per_row, stuck, inserted = _fault_plan(n_rows, seed) if faults else ({}, [], {})
    stuck_at = {s: length for s, length in stuck}
    grng = np.random.default_rng([seed, 2])
    out: list[Fault] = []
    line = 1
    held = 0.0
    stuck_left = 0
    k3 = COLUMNS.index(STUCK_COLUMN)
    template = "%d," + "%.3f," * len(TEMPS) + "%.0f,%.3f\n"
    special = set(per_row) | set(inserted) | {n_rows - 1}
    with open(path, "wb") as f:
        f.write(HEADER.encode() + b"\n")
        for t, temps, rpm, e_x in samples(n_rows, seed, chunk):
            buf: list[str] = []
            values = np.column_stack([t, temps, rpm, e_x]).tolist()
            for row, v in zip(t.tolist(), values):
                if row in stuck_at:
                    stuck_left, held = stuck_at[row], v[k3]
                    out.append(Fault("stuck", line + 1 + len(inserted.get(row, ())), row, STUCK_COLUMN, stuck_left))
                if stuck_left > 0:
                    v[k3] = held  # the same float, so the same text all along the window
                    stuck_left -= 1
                if not faults or row not in special:
                    line += 1
                    buf.append(template % tuple(v))
                    continue
                for kind in inserted.get(row, ()):
                    line += 1
                    buf.append(_garbage(kind, grng).decode("latin-1") + "\n")
                    out.append(Fault(kind, line, None))
                line += 1
                fields = (template % tuple(v))[:-1].split(",")
                fault = per_row.get(row)
                if fault is not None:
                    kind, col = fault
                    k = COLUMNS.index(col) if col is not None else -1
                    if kind in ("nan", "empty"):
                        fields[k] = "" if kind == "empty" else str(grng.choice(["NaN", "nan"]))
                    elif kind == "spike":
                        fields[k] = str(grng.choice(["1372.0", "-273.0"]))
                    elif kind == "fields":
                        if grng.random() < 0.5:
                            del fields[int(grng.integers(1, len(fields)))]
                        else:
                            fields.insert(int(grng.integers(1, len(fields))), fields[1])
                    out.append(Fault(kind, line, row, col))
                text = ",".join(fields)
                if row == n_rows - 1:
                    # cut in the middle of T_4: fewer fields than the header, and no newline
                    cut = text.index(",", len(",".join(fields[:4])) + 1) - 2
                    buf.append(text[:cut])
                    out.append(Fault("truncated", line, row, "T_4"))
                else:
                    buf.append(text + "\n")
            f.write("".join(buf).encode("latin-1"))  # latin-1: the garbage bytes go out as they are
    return sorted(out, key=lambda fl: fl.line)


def clean_rows(faults: list[Fault], n_rows: int) -> np.ndarray:
    """The samples no fault touched (a boolean mask over the rows)."""
    ok = np.ones(n_rows, dtype=bool)
    for fl in faults:
        if fl.row is not None:
            ok[fl.row : fl.row + fl.n] = False
    return ok


# --- streaming through the binary -----------------------------------------------------------


@dataclass
class Streamed:
    returncode: int
    stdout: bytes
    stderr: bytes
    peak_rss_kib: int | None  # VmHWM of the child once it has read every complete line
    wall_s: float  # from the first byte written to the exit


def _vmhwm(pid: int) -> int | None:
    try:
        with open(f"/proc/{pid}/status") as f:
            for ln in f:
                if ln.startswith("VmHWM:"):
                    return int(ln.split()[1])
    except OSError:
        return None
    return None


def stream(exe: str | os.PathLike[str], model: str | os.PathLike[str], csv: str | os.PathLike[str], *,
           expect_lines: int | None = None, block: int = 1 << 16, settle_s: float = 30.0) -> Streamed:
    """Pipe `csv` into `exe model` (stdin, not the file argument) block by block; read its stdout
    and stderr as they come.

    Peak memory: `/proc/<pid>/status` VmHWM (the high-water mark of the binary's own address space;
    a `wait4` rusage would also count the Python parent's pages the child had before its exec). To
    read it just before the exit, everything up to the last newline is written, then, once stdout
    holds `expect_lines` lines (header included; or after `settle_s`), VmHWM is read, the rest (a
    truncated last line) written and stdin closed. Without `expect_lines` the last of the readings
    taken every 10 ms while it runs is given."""
    data_path = Path(csv)
    proc = subprocess.Popen([os.fspath(exe), os.fspath(model)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, bufsize=0)
    assert proc.stdin is not None and proc.stdout is not None and proc.stderr is not None
    chunks: list[bytes] = []
    errs: list[bytes] = []
    counted = [0]
    reached = threading.Event()
    done = threading.Event()
    hwm: list[int | None] = [None]
    out_fd, err_fd = proc.stdout.fileno(), proc.stderr.fileno()

    def read_out() -> None:
        while True:
            b = os.read(out_fd, 1 << 20)
            if not b:
                break
            chunks.append(b)
            counted[0] += b.count(b"\n")
            if expect_lines is not None and counted[0] >= expect_lines:
                reached.set()
        reached.set()

    def read_err() -> None:
        while b := os.read(err_fd, 1 << 16):
            errs.append(b)

    def poll() -> None:
        while not done.wait(0.01):
            v = _vmhwm(proc.pid)
            if v is not None:
                hwm[0] = v

    threads = [threading.Thread(target=fn, daemon=True) for fn in (read_out, read_err, poll)]
    for th in threads:
        th.start()
    t0 = time.perf_counter()
    tail = b""
    try:
        with open(data_path, "rb") as f:
            pending = b""
            while b := f.read(block):
                pending += b
                cut = pending.rfind(b"\n") + 1
                if cut:
                    proc.stdin.write(pending[:cut])
                    pending = pending[cut:]
            tail = pending
        if expect_lines is not None:
            reached.wait(settle_s)
            v = _vmhwm(proc.pid)  # still alive: its stdin is open
            if v is not None:
                hwm[0] = v
        if tail:
            proc.stdin.write(tail)
    except BrokenPipeError:
        pass
    finally:
        try:
            proc.stdin.close()
        except BrokenPipeError:
            pass
    rc = proc.wait()
    wall = time.perf_counter() - t0
    done.set()
    for th in threads:
        th.join()
    return Streamed(rc, b"".join(chunks), b"".join(errs), hwm[0], wall)
