"""Fleet scale: fit, evaluate or diagnose many runs at once on Dask (``pip install thermerr_rs[fleet]``).

A factory has hundreds of machines and a run per machine per day. Each function here takes
``runs`` — a directory (every ``*.csv`` in it, sorted by name) or a list of CSV paths — and runs
**one task per run**, in parallel, through ``dask.delayed``::

    from thermerr_rs import fleet

    rows = fleet.fit_runs("runs/2024-06-01", "E_z", out_dir="models", model="mlr")
    rows = fleet.evaluate_runs("models/m042.json", ["runs/m042_tue.csv", "runs/m042_wed.csv"])
    rows = fleet.diagnose_runs("runs/vmc", "vmc_nominal.toml", out_dir="diagnoses",
                               scheduler="tcp://10.0.0.5:8786")

Each returns one :class:`RunResult` per run, **in input order**. A bad run does not stop the
batch: its record has ``ok=False`` and ``error``, a one-line message naming the file; the other
runs go on. Every output is written atomically, one per run, named after the run's stem
(``<stem>.json`` models, ``<stem>/`` diagnosis reports), and the summary
(``fleet-summary.json`` and ``fleet-summary.csv``) is written last, once every task has ended.

Schedulers (``scheduler=``):

* ``None`` (default) or ``"threads"``: dask's threaded scheduler on this machine, ``workers``
  threads (default: the CPU count). The Rust kernels release the GIL while they compute, so
  threads run the fits in parallel without starting processes (a ``LocalCluster`` costs a second
  or two to start, and pickles every model and result across processes), and a one-off batch
  needs nothing set up or torn down. What holds the GIL — the thin Python around each kernel —
  is short next to the kernels.
* ``"sync"``: one task after another in this thread (for debugging).
* an address, ``"host:port"`` or ``"tcp://host:port"``: a ``distributed`` scheduler (a
  ``dask scheduler`` / ``dask worker`` cluster, or a ``LocalCluster``'s ``scheduler_address``).
  The workers read the runs and write the outputs themselves, so the paths must mean the same
  on the workers as here (a shared file system).
* a ``distributed.Client``: used as it is (and left open).

Determinism: a task's numbers depend only on its run and the arguments (every run is fitted with
the same ``seed``, as ``thermerr fit --seed`` would fit it alone), never on which worker ran it or
how many there were; only ``seconds`` varies.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, Union

from . import _core
from ._io import write_atomic
from .errors import MissingDependencyError, ParameterError, ThermerrError

if TYPE_CHECKING:
    from .base import Estimator

#: what ``runs`` may be: a directory of ``*.csv`` runs, or the run files themselves
Runs = Union[str, "os.PathLike[str]", Sequence[Union[str, "os.PathLike[str]"]]]

#: the model families ``fit_runs`` builds by name (the ``--model`` choices of ``thermerr fit``)
MODELS = ("mlr", "rbf", "svr", "greybp", "gm1n", "bp", "hybrid")

SUMMARY = "fleet-summary"

_INSTALL = "the fleet functions need dask[distributed]: pip install thermerr_rs[fleet]"


@dataclass
class RunResult:
    """What became of one run of a batch.

    ``run`` is the run file as given, ``name`` its stem (what its outputs are named after),
    ``ok`` whether the task succeeded, ``error`` the one-line message when it did not (it names
    the file), ``out`` the file or directory written for the run, ``figures`` the task's
    numbers (scores for fit/evaluate, the verdict and held-out RMS for diagnose) and ``seconds``
    the task's wall time on its worker."""

    run: str
    name: str
    ok: bool
    error: str | None = None
    out: str | None = None
    figures: dict[str, Any] = field(default_factory=dict)
    seconds: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


# -- inputs ------------------------------------------------------------------------------------

def run_paths(runs: Runs) -> list[Path]:
    """The run files of ``runs``: every ``*.csv`` of a directory (sorted by name), or the given
    paths in their order (a directory in the list contributes its ``*.csv`` files; a
    ``fleet-summary.csv`` left there by an earlier batch is not a run). Refuses an
    empty set and two runs with the same stem (their outputs would collide)."""
    items = [runs] if isinstance(runs, (str, os.PathLike)) else list(runs)
    out: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            found = sorted(q for q in p.glob("*.csv") if q.is_file() and q.stem != SUMMARY)
            if not found:
                raise ThermerrError(f"{p}: no *.csv runs in this directory")
            out.extend(found)
        elif p.exists():
            out.append(p)
        else:
            raise ThermerrError(f"{p}: no such run file or directory")
    if not out:
        raise ThermerrError("no runs given")
    seen: dict[str, Path] = {}
    for p in out:
        if p.stem == SUMMARY:
            raise ThermerrError(f"{p}: a run may not be called {SUMMARY} (the summary's name)")
        if p.stem in seen:
            raise ThermerrError(f"{seen[p.stem]} and {p} have the same name {p.stem!r}: their outputs would collide")
        seen[p.stem] = p
    return out


# -- the per-run tasks (module-level functions: picklable for a distributed cluster) -----------

def _one_line(text: str) -> str:
    return " ".join(text.split())


# Ctrl-C on the local threads: only the main thread sees the signal, so it sets _STOP (a task
# not yet started, or about to write, stops) and asks the running kernels to stop (_halt).
_STOP = threading.Event()
_ACTIVE = [0]
_ACTIVE_LOCK = threading.Lock()


def _unless_stopped() -> None:
    """Raise KeyboardInterrupt once the batch was interrupted: called before a task starts and
    before it writes, so that nothing is written after Ctrl-C."""
    if _STOP.is_set():
        raise KeyboardInterrupt


def _halt(timeout_s: float = 5.0) -> None:
    """After Ctrl-C in the main thread: stop the tasks running on the local threads. Each
    interrupted kernel clears the core's stop request when it returns, so it is repeated until
    no task runs (or ``timeout_s``), then withdrawn for the next call."""
    _STOP.set()
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        with _ACTIVE_LOCK:
            if _ACTIVE[0] == 0:
                break
        _core.request_interrupt()
        time.sleep(0.02)
    _core.clear_interrupt()


def _guarded(path: str, work: Callable[[], tuple[str | None, dict[str, Any]]]) -> RunResult:
    """Run ``work`` for one run; any failure becomes the record's one-line ``error``."""
    name = Path(path).stem
    t0 = time.perf_counter()
    _unless_stopped()
    with _ACTIVE_LOCK:
        _ACTIVE[0] += 1
    try:
        out, figures = work()
    except (KeyboardInterrupt, SystemExit, GeneratorExit):
        raise
    except BaseException as e:  # noqa: BLE001 -- a bad run must not end the batch (a Rust panic is a BaseException)
        msg = str(e.args[0]) if isinstance(e, KeyError) and e.args else str(e)
        if not isinstance(e, (ThermerrError, OSError, KeyError, ValueError)):
            msg = f"{type(e).__name__}: {msg}"
        msg = _one_line(msg) or type(e).__name__
        if path not in msg and Path(path).name not in msg:
            msg = f"{path}: {msg}"
        return RunResult(path, name, False, error=msg, seconds=time.perf_counter() - t0)
    finally:
        with _ACTIVE_LOCK:
            _ACTIVE[0] -= 1
    return RunResult(path, name, True, out=out, figures=figures, seconds=time.perf_counter() - t0)


def _score_figures(s: Any) -> dict[str, Any]:
    return _finite(s.summary())


def _finite(d: dict[str, Any]) -> dict[str, Any]:
    """Non-finite floats as ``None``: the summary is strict JSON."""
    return {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in d.items()}


def _build(model: str | Estimator, params: Mapping[str, Any], seed: int, y: Any) -> Estimator:
    """A fresh, unfitted estimator: by family name with ``thermerr fit``'s defaults, or a clone."""
    from sklearn.base import clone

    from .base import Estimator

    if isinstance(model, Estimator):
        est: Estimator = clone(model)
        return est
    kw = dict(params)
    if model == "mlr":
        from .linear import MLR

        return MLR(**kw)
    if model == "svr":
        from .svr import SVR

        return SVR(**kw)
    if model in ("greybp", "gm1n", "bp"):
        from .grey import GM1N, BPNetwork, GreyBP

        if model == "gm1n":
            return GM1N(**kw)
        kw.setdefault("hidden", 7)
        kw.setdefault("seed", seed)
        return BPNetwork(**kw) if model == "bp" else GreyBP(**kw)
    if model == "hybrid":
        import numpy as np

        from .hybrid import HybridFilterNet

        kw.setdefault("hidden", 30)
        kw.setdefault("seed", seed)
        kw.setdefault("limit", max(50.0, 1.5 * float(np.max(np.abs(y)))))
        return HybridFilterNet(**kw)
    if model == "rbf":
        from .pipeline import MinMaxScaled
        from .rbf import RBFNetwork

        kw.setdefault("design", "ols")
        kw.setdefault("spread", 1.0)
        kw.setdefault("goal", 0.1 * len(y))
        kw.setdefault("seed", seed)
        return MinMaxScaled(RBFNetwork(**kw))
    raise ThermerrError(f"unknown model {model!r} (known: {', '.join(MODELS)})")


def _fit_task(path: str, axis: str, model: str | Estimator, params: Mapping[str, Any],
              sensors: Sequence[str] | str | None, seed: int, inputs: str, reading: dict[str, Any],
              n_clusters: int, out_dir: str) -> RunResult:
    def work() -> tuple[str | None, dict[str, Any]]:
        from .metrics import scores
        from .run import read_run

        run = read_run(path, **reading)  # type: ignore[arg-type]
        y = run[axis]
        if sensors in (None, "all"):
            names = run.temperatures
        elif sensors == "auto":
            from .selection import select_sensors

            names = list(select_sensors(run, axis, n_clusters=n_clusters, seed=seed).selected)
        else:
            names = [sensors] if isinstance(sensors, str) else list(sensors)
            for n in names:
                run[n]  # names the missing column and the file
        if not names:
            raise ThermerrError(f"{path}: no T_* sensor columns to model with")
        est = _build(model, params, seed, y)
        est.fit_run(run, axis, names, inputs=inputs)
        train = scores(y, est.predict_run(run))
        _unless_stopped()
        out = est.save(Path(out_dir) / f"{Path(path).stem}.json")
        return str(out), {"model": est.kind, "axis": axis, "sensors": ",".join(names), **_score_figures(train)}

    return _guarded(path, work)


def _evaluate_task(path: str, model_json: str, axis: str | None, reading: dict[str, Any]) -> RunResult:
    def work() -> tuple[str | None, dict[str, Any]]:
        from .base import _from_text
        from .metrics import scores
        from .run import read_run

        model = _from_text(model_json)
        run = read_run(path, **reading)  # type: ignore[arg-type]
        target = axis or model.target_name_
        if not target:
            raise ThermerrError("the model does not record its target axis: pass axis")
        return None, {"axis": target, **_score_figures(scores(run[target], model.predict_run(run)))}

    return _guarded(path, work)


def _diagnosis_figures(d: Any) -> dict[str, Any]:
    """One axis's diagnosis as summary figures."""
    b, e = d.report["baseline"], d.report["extended"]
    alts = [a["column"] for a in d.causes[0]["alternatives"]] if d.column and d.causes else []
    return {"verdict": d.verdict, "column": d.column, "alternatives": ",".join(alts), "gain_pct": d.gain_pct,
            "baseline_rms": float(b["rmse_um"]), "extended_rms": float(e["rmse_um"]),
            "remainder_um": float(d.remainder_um), "baseline_unique": d.baseline_unique}


def _diagnose_task(path: str, machine_toml: str, machine_file: str, axes: list[str],
                   holdout_fraction: float, reading: dict[str, Any], out_dir: str, network: str) -> RunResult:
    def work() -> tuple[str | None, dict[str, Any]]:
        from .run import read_run
        from .thermal import Machine, diagnose, diagnose_axes

        machine = Machine.from_toml(machine_toml, machine_file)
        run = read_run(path, **reading)  # type: ignore[arg-type]
        target = Path(out_dir) / Path(path).stem
        todo = axes or machine.axes
        if len(todo) == 1:
            d = diagnose(run, machine, axis=todo[0], holdout_fraction=holdout_fraction, network=network,
                         progress=False)
            _unless_stopped()
            d.write(target)
            suspect = sorted({sp["column"] for sp in d.report.get("suspect_readings", [])})
            return str(target), _finite({"axis": todo[0], **_diagnosis_figures(d), "suspect": ",".join(suspect)})
        # several axes, as `thermerr diagnose` writes them: a summary and <axis>.report.* per axis;
        # every axis by default (`axes` empty), where a probe with nothing to diagnose is left out
        multi = diagnose_axes(run, machine, axes=axes or None, holdout_fraction=holdout_fraction,
                              network=network, progress=False)
        _unless_stopped()
        multi.write(target)
        figures: dict[str, Any] = {"axes": ",".join(multi.axes)}
        for a in multi.axes:
            figures.update({f"{a}.{k}": v for k, v in _diagnosis_figures(multi[a]).items()})
        figures["suspect"] = ",".join(sorted({sp["column"] for sp in multi.report["suspect_readings"]}))
        figures["skipped"] = ",".join(multi.skipped)
        return str(target), _finite(figures)

    return _guarded(path, work)


# -- scheduling ----------------------------------------------------------------------------------

def _import_dask() -> Any:
    try:
        import dask
    except ImportError:
        raise MissingDependencyError(_INSTALL) from None
    return dask


def _client_for(address: str) -> Any:
    try:
        from distributed import Client
    except ImportError:
        raise MissingDependencyError(_INSTALL) from None
    try:
        return Client(address, timeout="10s", set_as_default=False)
    except (OSError, ValueError) as e:
        raise ThermerrError(f"cannot reach the dask scheduler at {address}: {_one_line(str(e))}") from None


def _compute(fn: Callable[..., RunResult], paths: Sequence[Path], args: tuple[Any, ...],
             scheduler: Any, workers: int | None, kind: str) -> list[RunResult]:
    """One delayed task per run; the records in input order. A task that dies at the dask level
    (a worker killed, a result that cannot be sent back) becomes that run's error."""
    dask = _import_dask()
    tasks = [dask.delayed(fn, pure=False)(str(p), *args, dask_key_name=f"fleet-{kind}-{i}-{p.stem}")
             for i, p in enumerate(paths)]
    if scheduler is None or scheduler in ("threads", "sync"):
        if workers is not None and workers < 1:
            raise ThermerrError(f"workers must be at least 1, got {workers}")
        _STOP.clear()
        try:
            if scheduler == "sync":
                results: list[RunResult] = list(dask.compute(*tasks, scheduler="sync"))
            else:
                results = list(dask.compute(*tasks, scheduler="threads", num_workers=workers))
        except KeyboardInterrupt:
            _halt()
            raise
        return results
    if isinstance(scheduler, str):
        client = _client_for(scheduler)
        try:
            return _gather(client, tasks, paths)
        finally:
            client.close()
    if hasattr(scheduler, "compute") and hasattr(scheduler, "gather"):
        return _gather(scheduler, tasks, paths)
    raise ThermerrError(f"scheduler must be None, 'threads', 'sync', an address or a distributed.Client, "
                        f"got {scheduler!r}")


def _gather(client: Any, tasks: list[Any], paths: Sequence[Path]) -> list[RunResult]:
    futures = client.compute(tasks)
    out: list[RunResult] = []
    for p, f in zip(paths, futures):
        try:
            out.append(f.result())
        except Exception as e:  # noqa: BLE001 -- the task itself never raises; this is the cluster's failure
            out.append(RunResult(str(p), p.stem, False, error=f"{p}: {type(e).__name__}: {_one_line(str(e))}"))
    return out


# -- the summary -----------------------------------------------------------------------------

def write_summary(results: Sequence[RunResult], out_dir: str | os.PathLike[str]) -> tuple[Path, Path]:
    """Write ``fleet-summary.json`` (the records) and ``fleet-summary.csv`` (one row per run:
    run, name, ok, error, out, seconds, then every figure) into ``out_dir``, atomically."""
    d = Path(out_dir)
    doc = json.dumps({"n_runs": len(results), "n_failed": sum(not r.ok for r in results),
                      "runs": [r.as_dict() for r in results]}, indent=1, allow_nan=False, default=str)
    keys: list[str] = []
    for r in results:
        keys.extend(k for k in r.figures if k not in keys and not isinstance(r.figures[k], (list, dict)))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["run", "name", "ok", "error", "out", "seconds", *keys])
    for r in results:
        w.writerow([r.run, r.name, r.ok, r.error or "", r.out or "", f"{r.seconds:.3f}",
                    *("" if r.figures.get(k) is None else r.figures[k] for k in keys)])
    js = write_atomic(d / f"{SUMMARY}.json", doc)
    cs = write_atomic(d / f"{SUMMARY}.csv", buf.getvalue())
    return js, cs


def table(results: Sequence[RunResult]) -> str:
    """The records as a plain-text table, one line per run: its name, ``ok`` or ``FAILED``, the
    main figures (RMS residual and compensation rate, or the diagnosis verdict and held-out
    RMS), and the output or the error message. A diagnosis of several axes takes a line per
    axis."""

    def figs(r: RunResult) -> list[str]:
        f = r.figures
        if not r.ok:
            return [""]
        if "verdict" in f or "axes" in f:
            from .report import also

            def one(pre: str) -> str:
                alts = also(f[pre + "alternatives"].split(",") if f.get(pre + "alternatives") else [])
                col = f" ({f[pre + 'column']}{alts})" if f.get(pre + "column") else ""
                return (f"{f[pre + 'verdict']}{col}: RMS {f[pre + 'baseline_rms']:.3f} -> "
                        f"{f[pre + 'extended_rms']:.3f} µm, gain {f[pre + 'gain_pct']:.1f} %")

            sus = f"; suspect readings in {f['suspect'].replace(',', ', ')}" if f.get("suspect") else ""
            if "axes" in f:
                lines = [f"{a} {one(a + '.')}" for a in f["axes"].split(",")]
                lines += [f"{a} not diagnosed: its probe gives nothing to diagnose (report.json says why)"
                          for a in f.get("skipped", "").split(",") if a]
                return [*lines[:-1], lines[-1] + sus]
            return [one("") + sus]
        rate = f.get("compensation_rate")
        rate_s = "n/a" if rate is None else f"{100 * rate:.1f} %"
        return [f"{f['axis']}: n {f['n']}, RMS {f['rms']:.4g} µm, max {f['max_abs']:.4g} µm, compensation {rate_s}"]

    rows: list[tuple[str, str, str, str]] = []
    for r in results:
        lines = figs(r)
        rows.append((r.name, "ok" if r.ok else "FAILED", lines[0], (r.out or "") if r.ok else (r.error or "")))
        rows.extend(("", "", more, "") for more in lines[1:])
    head = ("run", "status", "figures", "output / error")
    widths = [max(len(h), *(len(row[k]) for row in rows)) for k, h in enumerate(head[:3])]
    out = []
    for row in (head, *rows):
        out.append("  ".join(c.ljust(w) for c, w in zip(row[:3], widths)) + "  " + row[3])
    return "\n".join(line.rstrip() for line in out)


def _reading(nan: str, delimiter: str, decimal: str, rename: Sequence[str]) -> dict[str, Any]:
    """How every task reads its run (:func:`~thermerr_rs.read_run`'s ``nan``, ``delimiter``,
    ``decimal`` and ``rename``)."""
    return {"nan": nan, "delimiter": delimiter, "decimal": decimal, "rename": list(rename)}


# -- the public functions --------------------------------------------------------------------

Scheduler = Union[None, str, Any]


def fit_runs(
    runs: Runs,
    axis: str,
    model: str | Estimator = "mlr",
    out_dir: str | os.PathLike[str] = ".",
    *,
    sensors: Sequence[str] | Literal["all", "auto"] | None = None,
    params: Mapping[str, Any] | None = None,
    seed: int = 0,
    inputs: Literal["rise", "absolute"] = "rise",
    nan: Literal["error", "drop", "interpolate"] = "error",
    delimiter: str = ",",
    decimal: str = ".",
    rename: Sequence[str] = (),
    n_clusters: int = 4,
    scheduler: Scheduler = None,
    workers: int | None = None,
) -> list[RunResult]:
    """Fit one model per run and save each as ``out_dir/<stem>.json``.

    ``model``: a family name (``"mlr"``, ``"rbf"``, ``"svr"``, ``"greybp"``, ``"gm1n"``,
    ``"bp"``, ``"hybrid"``, built with ``thermerr fit``'s defaults, ``params`` passed to its
    constructor — the ``RBFNetwork`` inside ``MinMaxScaled`` for ``"rbf"``) or an unfitted
    estimator, cloned for every run. ``sensors``: ``None``/``"all"`` every ``T_*`` column,
    ``"auto"`` fuzzy c-means selection per run (``n_clusters``), or the column names. ``seed``
    seeds every stochastic step of every run alike. ``inputs``: the sensors' ``"rise"`` since
    the run's start (default, as the CLI) or ``"absolute"`` readings. ``nan``, ``delimiter``,
    ``decimal``, ``rename``: how each run is read, as :func:`~thermerr_rs.read_run`. ``scheduler``/``workers``:
    see the module's docstring.

    Returns one :class:`RunResult` per run, in input order; ``figures`` holds the training
    scores (``rms``, ``max_abs``, ``compensation_rate``, ...), the model kind and the sensors.
    """
    if isinstance(model, str) and model not in MODELS:
        raise ThermerrError(f"unknown model {model!r} (known: {', '.join(MODELS)})")
    if inputs not in ("rise", "absolute"):
        raise ThermerrError(f'inputs must be "rise" or "absolute", got {inputs!r}')
    paths = run_paths(runs)
    sens: Sequence[str] | str | None = sensors if sensors is None or isinstance(sensors, str) else list(sensors)
    args = (axis, model, dict(params or {}), sens, int(seed), inputs, _reading(nan, delimiter, decimal, rename),
            int(n_clusters), str(out_dir))
    results = _compute(_fit_task, paths, args, scheduler, workers, "fit")
    write_summary(results, out_dir)
    return results


def evaluate_runs(
    model_or_path: Estimator | str | os.PathLike[str],
    runs: Runs,
    axis: str | None = None,
    *,
    out_dir: str | os.PathLike[str] | None = None,
    nan: Literal["error", "drop", "interpolate"] = "error",
    delimiter: str = ",",
    decimal: str = ".",
    rename: Sequence[str] = (),
    scheduler: Scheduler = None,
    workers: int | None = None,
) -> list[RunResult]:
    """Score one fitted model (an estimator or a model file) on every run.

    ``axis`` defaults to the model's target. ``figures`` holds the scores of each run (``rms``,
    ``max_abs``, ``band``, ``mean_accuracy``, ``compensation_rate``, ...). Nothing is written per
    run; with ``out_dir`` the summary is written there. A model file that cannot be read is
    refused before any task starts (``ModelFormatError``/``FileNotFoundError``).
    """
    from .base import Estimator, load_model

    model = model_or_path if isinstance(model_or_path, Estimator) else load_model(model_or_path)
    text = model.to_json()  # each task reads its own copy: no model object shared between threads
    paths = run_paths(runs)
    results = _compute(_evaluate_task, paths, (text, axis, _reading(nan, delimiter, decimal, rename)), scheduler, workers,
                       "evaluate")
    if out_dir is not None:
        write_summary(results, out_dir)
    return results


def diagnose_runs(
    runs: Runs,
    machine: Any,
    out_dir: str | os.PathLike[str],
    *,
    axis: str | Sequence[str] | None = None,
    holdout_fraction: float = 0.3,
    nan: Literal["error", "drop", "interpolate"] = "error",
    delimiter: str = ",",
    decimal: str = ".",
    rename: Sequence[str] = (),
    network: str = "auto",
    scheduler: Scheduler = None,
    workers: int | None = None,
) -> list[RunResult]:
    """Diagnose every run against one nominal machine (a :class:`~thermerr_rs.Machine` or its
    TOML file) on ``axis`` (one axis, several, or by default every axis of the machine, as
    ``thermerr diagnose``) and write each report into ``out_dir/<stem>/``: for one axis
    ``report.json``, ``report.html``, ``calibrated.toml``, ``extended.toml``; for several, as
    :meth:`~thermerr_rs.thermal.AxesDiagnosis.write`, the summary ``report.json`` and
    ``report.html`` and per axis ``<axis>.report.json``, ``<axis>.report.html``,
    ``<axis>.calibrated.toml``, ``<axis>.extended.toml``. Each run is calibrated on its first
    70 % and scored on the rest (``holdout_fraction``). ``figures`` for one axis: ``axis``,
    ``verdict``, ``column`` (with
    ``alternatives``: the other columns that explain the held-out error as well, comma-separated,
    as ``sensors`` of a fit; see :attr:`~thermerr_rs.thermal.Diagnosis.causes`), ``suspect``
    (the columns with suspect readings, comma-separated: a jump or a frozen reading, or
    ``time_s`` for a gap in the log, listed in the run's ``report.json`` as
    ``suspect_readings``), ``gain_pct``,
    ``baseline_rms`` and ``extended_rms`` (held-out, µm), ``remainder_um`` (the unexplained
    remainder) and ``baseline_unique`` (False where a
    recalibrated baseline has a second solution: :attr:`~thermerr_rs.thermal.Diagnosis.baseline_unique`);
    for several axes: ``axes`` (comma-separated), the same figures per axis as ``<axis>.verdict``,
    ``<axis>.gain_pct``, ... (one column each in ``fleet-summary.csv``), ``suspect``, and
    ``skipped``: by default every axis is diagnosed, and an axis whose probe gives nothing to
    diagnose on that run (dead throughout, or failing over its held-out rows) is left out of that
    run's diagnosis and named here (comma-separated; why, in the run's ``report.json``), the
    others diagnosed. ``axes`` lists the axes diagnosed.
    An axis the machine does not map is refused before any task starts.
    ``network``: the baseline's network
    rule, as for :func:`~thermerr_rs.thermal.diagnose`. A machine file that cannot be read, or a
    rule that is not one of them, is refused before any task starts.
    """
    from .thermal import NETWORK_RULES, Machine

    m = machine if isinstance(machine, Machine) else Machine.load(machine)
    source = str(machine) if isinstance(machine, (str, os.PathLike)) else f"{m.name}.toml"
    paths = run_paths(runs)
    if network not in NETWORK_RULES:
        raise ParameterError(f"network: `{network}` is not one of {', '.join(NETWORK_RULES)}")
    axes = m.axes if axis is None else [axis] if isinstance(axis, str) else list(axis)
    unknown = [a for a in axes if a not in m.axes]
    if unknown or not axes:
        raise ParameterError(f"axis: {', '.join(unknown) or 'none given'}: {source} maps "
                             f"{', '.join(m.axes) or 'no axis'}")
    # every axis: passed as none named, so that a run's dead probe is left out, not the run failed
    args = (m.to_toml(), source, [] if axis is None else axes, float(holdout_fraction),
            _reading(nan, delimiter, decimal, rename), str(out_dir), network)
    results = _compute(_diagnose_task, paths, args, scheduler, workers, "diagnose")
    write_summary(results, out_dir)
    return results


__all__ = ["RunResult", "fit_runs", "evaluate_runs", "diagnose_runs", "run_paths", "write_summary", "table", "MODELS"]
