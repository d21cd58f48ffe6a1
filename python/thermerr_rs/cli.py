"""The ``thermerr`` command line: one entry point, one subcommand per job.

    thermerr fit RUN.csv --axis E_z --model mlr|rbf|svr|greybp|gm1n|bp|hybrid [--tune cso|pso] [--sensors auto|T_a,T_b] --out MODEL.json
    thermerr evaluate MODEL.json RUN.csv
    thermerr select-sensors RUN.csv --axis E_z
    thermerr predict RUN.csv --machine M.toml --out PRED.csv
    thermerr init RUN.csv --axis E_z [--axis E_y] --out M.toml [--nodes N] [--ambient COL]
    thermerr calibrate RUN.csv --machine M.toml --out CAL.toml
    thermerr diagnose RUN.csv --machine M.toml --out DIR [--holdout TEST.csv]
    thermerr stiffness MODEL.json RUN.csv [--at SECONDS] [--eta 0.5]
    thermerr examples [DIR]
    thermerr fleet fit|evaluate|diagnose DIR_OR_RUNS... [--scheduler ADDR] [--workers N]  (exit 1: some runs failed)

Exit status: 0 done; 1 the computation failed on valid input (a numerical failure, no
convergence) or an output could not be written (a full disk); 2 a usage error or bad input (a
one-line message on stderr names what and where); 130 interrupted (Ctrl-C); 141 the reader of
standard output went away (``thermerr ... | head``), silently.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from . import __version__, _core
from .errors import ConvergenceError, NumericalError, SuspectReadingWarning, ThermerrError
from .metrics import Scores, scores
from .run import Run, read_run

if TYPE_CHECKING:
    from .base import Estimator

# The estimators (and scikit-learn, whose import takes about a second) are imported by the
# commands that use them, not at start: `thermerr diagnose`, `init` or `--help` never need them.


def _progress_enabled(args: argparse.Namespace) -> bool:
    return not args.quiet and sys.stderr.isatty()


def _say(args: argparse.Namespace, *text: Any) -> None:
    if not args.quiet:
        print(*text)


def _stage(args: argparse.Namespace, text: str) -> None:
    """A line on stderr saying what a long step is doing (also on a pipe or in a log)."""
    if not args.quiet:
        print(f"thermerr: {text}", file=sys.stderr, flush=True)


def _finite(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by None (JSON has no NaN or Infinity)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def _print_json(obj: Any) -> None:
    print(json.dumps(_finite(obj), indent=1, allow_nan=False))


def _read(args: argparse.Namespace, path: str) -> Run:
    run = read_run(path, nan=args.nan, delimiter=args.delimiter, decimal=args.decimal, rename=args.rename)
    # what --nan changed is said: a result read from mended rows is not a result of the file
    if not getattr(args, "quiet", False):
        if run.interpolated:
            print(f"thermerr: {path}: {run.interpolated} missing value(s) filled by linear "
                  "interpolation in time (--nan interpolate)", file=sys.stderr)
        if run.dropped_rows:
            print(f"thermerr: {path}: {len(run.dropped_rows)} row(s) with a missing value dropped "
                  f"(--nan drop; first: row {run.dropped_rows[0]})", file=sys.stderr)
    return run


def _delimiter(text: str) -> str:
    """A delimiter as written on the command line (``tab``, ``semicolon``, ...): the core's names."""
    return _core.delimiter_named(text)


def _int_at_least(lo: int) -> Any:
    """An argparse type: a whole number >= ``lo`` (a negative count is a usage error, not a
    traceback from deep inside)."""

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if v < lo:
            raise argparse.ArgumentTypeError(f"must be at least {lo}, got {v}")
        return v

    return parse


_positive_int = _int_at_least(1)
_nonneg_int = _int_at_least(0)


def _thin(text: str) -> int | str:
    """An argparse type for --thin: 'auto' or a whole number >= 1."""
    if text == "auto":
        return text
    try:
        return _positive_int(text)
    except argparse.ArgumentTypeError as e:
        raise argparse.ArgumentTypeError(f"must be 'auto' or a whole number >= 1 ({e})") from None


def _taus(text: str) -> list[float]:
    """An argparse type: comma-separated time constants in seconds, each > 0; ``none``: no history
    (an empty list, which ``--model auto`` takes as "do not try one")."""
    if text.strip().lower() == "none":
        return []
    try:
        taus = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a list of seconds, e.g. 900,3600") from None
    if not taus or any(not (0 < t < float("inf")) for t in taus):
        raise argparse.ArgumentTypeError(f"time constants must be finite numbers of seconds > 0, got {text!r}")
    return taus


def _nonneg_float(text: str) -> float:
    """An argparse type: a finite number >= 0 (e.g. seconds)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (v >= 0 and v != float("inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text}")
    return v


def _check_out(out: str, *inputs: str | None) -> None:
    """Refuse an output path that is one of the command's inputs (it would overwrite it)."""
    target = os.path.realpath(out)
    for given in inputs:
        if given and os.path.realpath(given) == target:
            raise ThermerrError(f"--out {out} is the input file {given}: it would be overwritten; "
                                "choose another path")


def _check_holdout(run: str, hold: str | None, flag: str) -> None:
    """Refuse a held-out run that is the training run's own file: its "held-out" figures would be
    the training fit's."""
    if hold and os.path.realpath(hold) == os.path.realpath(run):
        raise ThermerrError(f"{flag} {hold} is the training run {run}: held-out figures need rows the fit has "
                            "not seen; give another run")


def _sensors(args: argparse.Namespace, run: Run) -> list[str]:
    if args.sensors in (None, "all"):
        names = run.temperatures
    elif args.sensors == "auto":
        from .selection import select_sensors

        sel = select_sensors(run, args.axis, n_clusters=args.n_clusters, seed=args.seed)
        _say(args, f"sensor selection (fuzzy c-means, {args.n_clusters} clusters):")
        _say(args, sel)
        _say(args)
        names = list(sel.selected)
    else:
        names = [s.strip() for s in args.sensors.split(",") if s.strip()]
        for n in names:
            run[n]  # raises MissingColumnError naming the column and the file
    if not names:
        raise ThermerrError(f"{run.source}: no T_* sensor columns to model with")
    return names


def _make_svr(args: argparse.Namespace, run: Run, sensors: list[str]) -> Estimator:
    from .svr import SVR

    if not args.tune:
        return SVR(C=args.C, epsilon=args.epsilon, gamma=args.gamma if args.gamma is not None else "scale")
    from .base import _history, run_inputs
    from .swarm import tune_svr

    x = run_inputs(run, sensors, args.inputs, _history(args.history or None, run.time_s))
    res = tune_svr(x, run[args.axis], method=args.tune, cv=args.cv,
                   cv_kind=args.cv_kind, gap=args.gap, epsilon=args.epsilon, pop=args.pop or 20,
                   iters=args.iters or 100, seed=args.seed, thin=args.thin, progress=_progress_enabled(args))
    how = (f"{args.cv} time-ordered splits (gap {args.gap})" if args.cv_kind == "time"
           else f"{args.cv} shuffled folds")
    thinned = (f"; searched on one row in {res.thin}, its best points scored on every row"
               if res.thin > 1 else "")
    _say(args, f"{args.tune.upper()} search: C = {res.C:.5g}, gamma = {res.gamma:.5g}, "
               f"CV MSE {res.cv_mse:.4g} µm² over {how} ({res.n_evals} evaluations{thinned})")
    if res.at_bounds:
        _say(args, f"note: the best point is on the search box's edge ({', '.join(res.at_bounds)}): "
                   "the optimum may lie beyond it")
    return SVR(C=res.C, epsilon=args.epsilon, gamma=res.gamma)


def _make_model(args: argparse.Namespace, n_train: int) -> Estimator:
    hidden = {} if args.hidden is None else {"hidden": args.hidden}  # else each family's default
    if args.model == "mlr":
        from .linear import MLR

        return MLR(alpha=args.alpha)
    if args.model in ("greybp", "gm1n", "bp"):
        from .grey import GM1N, BPNetwork, GreyBP

        if args.model == "gm1n":
            return GM1N(window=args.window)
        if args.model == "bp":
            return BPNetwork(**hidden, trainer=args.trainer, seed=args.seed)
        return GreyBP(windows=tuple(args.windows), **hidden, trainer=args.trainer, seed=args.seed)
    if args.model == "hybrid":
        from .hybrid import HybridFilterNet

        limit = args.limit if args.limit is not None else max(50.0, 1.5 * args._max_abs_error)
        return HybridFilterNet(variant=args.variant, **hidden, trainer=args.trainer, seed=args.seed,
                               limit=limit)
    from .rbf import RBFNetwork

    rbf = RBFNetwork(
        design=args.design,
        spread=args.spread,
        goal=args.goal if args.goal is not None else 0.1 * n_train,
        max_neurons=args.max_neurons,
        max_candidates=args.max_candidates,
        n_centers=args.n_centers,
        seed=args.seed,
    )
    from .pipeline import MinMaxScaled

    return MinMaxScaled(rbf)


def _print_scores(args: argparse.Namespace, title: str, s: Scores, source: str = "",
                  why: str = "; compensating with it would make the machine worse") -> None:
    """The figures under ``title``, and a note when the model leaves more error on ``source``
    than no compensation at all (its RMS residual above the measured error's RMS), ``why``
    ending it."""
    if args.json:
        return
    print(f"{title}:")
    print("  " + str(s).replace("\n", "\n  "))
    if s.rms > s.rms_measured:
        _say(args, f"note: the model leaves more error than no compensation{' on ' + source if source else ''} "
                   f"(RMS {s.rms:.4g} µm against {s.rms_measured:.4g} µm){why}")


#: how the figures of a model fed its own previous outputs were taken (the grey and hybrid models)
CLOSED_LOOP = "closed loop: the model's own previous outputs fill its history, as on a gateway without a probe"
ONE_STEP = ("one step ahead: the measured error of the step before is given, as with a probe on the machine "
            "(seed 002's protocol)")


def _loop(model: Any) -> str:
    """`` (closed loop: ...)`` after the title of a grey or filter model's figures, else ``""``."""
    from .grey import _Sequential

    return f" ({CLOSED_LOOP})" if isinstance(model, _Sequential) else ""


def _one_step(args: argparse.Namespace, title: str, model: Any, run: Run, target: str,
              closed: Any, after: Run | None = None) -> Scores | None:
    """A model whose prediction feeds on the errors before it (GM(1,N), GM+BP, the hybrid filter
    network) is scored closed loop by default; its one-step-ahead figures are printed too (and
    returned), with a note when closed loop it never leaves one value (a rolling GM started from
    the run's zero error keeps predicting it). ``None`` for any other model, or when ``target``
    is not the column the model was fitted to (its one-step history is that column)."""
    from .grey import _Sequential

    if not isinstance(model, _Sequential) or target != getattr(model, "target_name_", None):
        return None
    import numpy as np

    closed = np.asarray(closed)
    if closed.size and np.ptp(closed) == 0.0:
        _say(args, f"note: closed loop, the model predicts {float(closed[0]):.4g} µm on every sample of "
                   f"{run.source}: fed its own outputs from the start, its history never leaves that value "
                   "(the one-step figures below are what it does with the measured errors)")
    s = scores(run[target], model.predict_run(run, one_step=True, after=after))
    why = (": a rolling GM(1,N) fitted to a few samples of slowly changing temperatures is a near-singular "
           "system whose time response can grow without bound (docs/methods.md, GM(1,N))"
           if getattr(model, "kind", "") in ("gm1n", "greybp") else "")
    _print_scores(args, f"{title}, {ONE_STEP}", s, f"{run.source}, even one step ahead",
                  f"{why}; compare --model mlr, rbf or svr")
    return s


def cmd_fit(args: argparse.Namespace) -> int:
    _check_out(args.out, args.run, args.test)
    _check_holdout(args.run, args.test, "--test")
    run = _read(args, args.run)
    run[args.axis]
    test_run = _read(args, args.test) if args.test else None
    if test_run is not None:
        test_run.check_unseen(run)
    sensors = _sensors(args, run)
    with warnings.catch_warnings(record=True) as seen:  # the fits below check the same again
        warnings.simplefilter("always", SuspectReadingWarning)
        run.check_fit_columns(args.axis, sensors)
        # the run the fit reads (short spikes of its temperatures bridged): the model, its
        # training scores and the guard's limits are learned from it
        from .base import _bridged_for_fit  # the estimators' module imports scikit-learn

        run = _bridged_for_fit(run, sensors)
    for w in seen:
        print(f"thermerr: warning: {w.message}", file=sys.stderr)
    args._max_abs_error = float(abs(run[args.axis]).max())
    selection = None
    if args.model == "auto":
        from .model_selection import select_model

        bar: Any = None
        if _progress_enabled(args):  # a bar on a terminal, a line per candidate in a log
            from tqdm import tqdm

            bar = tqdm(desc="model selection", unit="candidate", leave=False)

        def step(k: int, n: int, label: str) -> None:
            if bar is None:
                _stage(args, f"candidate {k}/{n}: {label}")
                return
            bar.total = n
            bar.n = k - 1  # candidate k starts: k - 1 are scored
            bar.set_postfix_str(label, refresh=False)
            bar.refresh()

        from .model_selection import AUTO_HISTORY

        history = list(AUTO_HISTORY) if args.history is None else args.history
        try:
            selection = select_model(run, args.axis, sensors, history=history, inputs=args.inputs,
                                     cv=args.cv, gap=args.gap, budget_s=args.budget, seed=args.seed,
                                     tune=args.tune, tune_pop=args.pop or 10, tune_iters=args.iters or 10,
                                     rule=args.select, progress=step)
        finally:
            if bar is not None:
                bar.close()
        model = selection.model
        _say(args, f"leaderboard ({selection.n_splits} time-ordered splits of the training run, gap {selection.gap}):")
        _say(args, "  " + str(selection).replace("\n", "\n  "))
    else:
        if args.model == "svr":
            model = _make_svr(args, run, sensors)
        else:
            model = _make_model(args, len(run))
        model.fit_run(run, args.axis, sensors, inputs=args.inputs, history=args.history or None)
    name = selection.best.candidate.label() if selection is not None else args.model
    _say(args, f"fitted {name} on {len(run)} samples of {run.source}: {args.axis} from {', '.join(sensors)}")
    report: dict[str, Any] = {"model": name, "axis": args.axis, "sensors": sensors}
    if selection is not None:
        report["selection"] = selection.to_dict()
    closed = model.predict_run(run)
    train = scores(run[args.axis], closed)
    report["train"] = train.summary()
    loop = _loop(model)
    _print_scores(args, f"training run{loop}", train, run.source)
    one = _one_step(args, "training run", model, run, args.axis, closed)
    if one is not None:
        report["train_one_step"] = one.summary()
    if test_run is not None:
        after = None
        if args.test_continues or test_run.continues(run):
            # a piece of the training run's log: its error is relative to that run's start
            after = run
            why = ("--test-continues" if args.test_continues else
                   f"its clock starts {test_run.time_s[0] - run.time_s[-1]:g} s after the training run's last sample")
            _say(args, f"{test_run.source} continues {run.source} ({why}): predicted from the training run's "
                       "start, as a gateway running since then (rises and history go on through the join)")
        if after is None:
            _start_warning(test_run, args.axis)
        closed = model.predict_run(test_run, after=after)
        held = scores(test_run[args.axis], closed)
        report["test"] = held.summary()
        report["test_continues_training"] = after is not None
        _print_scores(args, f"held-out run {test_run.source}{loop}", held, test_run.source)
        one = _one_step(args, f"held-out run {test_run.source}", model, test_run, args.axis, closed, after)
        if one is not None:
            report["test_one_step"] = one.summary()
    if not args.no_guard:
        from .guard import add_guard

        _stage(args, "learning the sensor-fault guard")

        def fallback(k: int, n: int, sensor: str) -> None:
            _stage(args, f"fallback model {k}/{n} (without {sensor}; --no-fallbacks skips them)")

        add_guard(model, run, hold_s=args.hold, fallbacks=not args.no_fallbacks, progress=fallback)
        guard = model.guard_
        assert guard is not None  # add_guard sets it
        n_fb = len(guard["fallbacks"])
        report["guard"] = {"hold_s": args.hold, "fallbacks": n_fb}
        _say(args, f"sensor-fault guard: limits for {len(sensors)} sensors, hold {args.hold:g} s, "
                   f"{n_fb} fallback models" + ("" if n_fb else " (the output freezes when a sensor stays out)"))
    path = model.save(args.out)
    report["out"] = str(path)
    if args.json:
        _print_json(report)
    else:
        _say(args, f"model written to {path}")
    return 0


def _piece_note(args: argparse.Namespace, run: Run, after: Run | None, start: str) -> None:
    """The notes of a command that starts from a run's first row (``start`` says what that means
    for it): a clock that starts late may be a later piece of a longer log, whose error is relative
    to the log's start (pass ``--after``); an ``--after`` run the clock does not go on from."""
    if after is None and run.time_s[0] > 0:
        _say(args, f"note: {run.source}'s clock starts at {run.time_s[0]:g} s: if it is a later piece of a longer "
                   f"log, pass --after with that log's earlier rows ({start})")
    if after is not None and not run.continues(after):
        _say(args, f"note: {run.source}'s clock does not go on from {after.source}'s: it is moved to start one "
                   "sampling step after it")


def _start_warning(run: Run, target: str) -> None:
    """Warns (one line on stderr) when the scored run's probe reads away from zero at its start
    (:meth:`Run.start_note`): its scores carry that reading on every row."""
    note = run.start_note(target)
    if note:
        print(f"thermerr: warning: {note}", file=sys.stderr)


def cmd_evaluate(args: argparse.Namespace) -> int:
    from .base import Estimator, load_model

    model = load_model(args.model)
    run = _read(args, args.run)
    target = args.axis or model.target_name_
    if not target:
        raise ThermerrError(f"{args.model} does not record its target axis: pass --axis")
    after = _read(args, args.after) if args.after else None
    if after is not None:
        run.check_unseen(after)  # a piece that overlaps the log before it: rows counted twice
    if getattr(model, "inputs_", None) == "rise" or after is not None:
        _piece_note(args, run, after, "its rises are taken from its own first row")
    if after is None:
        _start_warning(run, target)
    closed = model.predict_run(run, after=after)
    s = scores(run[target], closed)
    if not args.json:
        wrapped = getattr(model, "estimator", None)  # the model inside a preprocessing wrapper
        inner = wrapped if isinstance(wrapped, Estimator) else model
        pre = f" ({type(model).__name__})" if inner is not model else ""
        _print_scores(args, f"{inner.kind} model{pre} {args.model} on {run.source}, axis {target}{_loop(model)}", s,
                      run.source)
    one = _one_step(args, f"{run.source}, axis {target}", model, run, target, closed, after)
    if args.json:
        extra = {} if one is None else {"one_step": one.summary()}
        _print_json({"axis": target, **s.summary(), "after": args.after, **extra})
    return 0


def cmd_select(args: argparse.Namespace) -> int:
    from .selection import select_sensors

    run = _read(args, args.run)
    axes = [a.strip() for a in args.axis.split(",") if a.strip()]
    sel = select_sensors(run, axes[0] if len(axes) == 1 else axes, n_clusters=args.n_clusters, seed=args.seed)
    if args.json:
        _print_json(sel.to_dict())
    else:
        print(sel)
    return 0


def _iso_stamps(path: str, delimiter: str, run: Run, rename: list[str]) -> list[str] | None:
    """A run file's ISO-8601 ``time`` cells as written, for the rows ``run`` kept (None when the
    file has a ``time_s`` column or no ``time``): what ``thermerr predict`` echoes, as
    ``thermerr-edge`` does, instead of seconds since the first row."""
    import csv

    with open(path, newline="", encoding="utf-8-sig") as f:
        rows = csv.reader(f, delimiter=delimiter)
        header = _core.renamed_header(path, [h.strip() for h in next(rows, [])], rename)
        if "time_s" in header or "time" not in header:
            return None
        k = header.index("time")
        cells = [r[k].strip() for r in rows if any(c.strip() for c in r)]
    dropped = set(run.dropped_rows)  # 1-based data rows
    kept = [c for i, c in enumerate(cells, start=1) if i not in dropped]
    if len(kept) != len(run):  # the reader and this count differ: seconds are safer than a shift
        warnings.warn(f"{path}: the time column's cells could not be matched to the rows read; "
                      "writing time_s", UserWarning, stacklevel=2)
        return None
    return kept


def cmd_predict(args: argparse.Namespace) -> int:
    from ._io import write_atomic
    from .thermal import Machine

    _check_out(args.out, args.run, args.machine, args.after)
    machine = Machine.load(args.machine)
    run = _read(args, args.run)
    after = _read(args, args.after) if args.after else None
    _piece_note(args, run, after, "the network starts from its own first readings, with zero drift there")
    if args.start == "fitted" and args.fit_initial:
        raise ThermerrError("--start fitted and --fit-initial both set the start: give one")
    fitted = machine.to_dict().get("start") or {}
    first_run = after if after is not None else run  # the run the simulation starts on
    same = bool(fitted) and os.path.basename(first_run.source) == os.path.basename(str(fitted.get("run")))
    offset = any(v != 0.0 for v in (fitted.get("initial_k") or {}).values())
    if args.start == "first" and not args.fit_initial and same and offset:
        _say(args, f"note: {args.machine}'s values were fitted on a run named {fitted['run']} from a start of "
                   "their own; this simulation starts from the first readings as they are (--start fitted "
                   "starts from the fitted start, as the file's figures do)")
    if args.start == "fitted" and fitted and not same:
        _say(args, f"note: the fitted start belongs to the run {fitted['run']}, not to {first_run.source}: "
                   "each node starts from this run's first reading plus that run's offset")
    sim = machine.simulate(run, fit_initial=args.fit_initial, after=after,
                           initial_k="fitted" if args.start == "fitted" else None)
    stamps = _iso_stamps(args.run, args.delimiter, run, args.rename)
    cols: dict[str, Any] = {"time": stamps} if stamps is not None else {"time_s": run.time_s}
    cols.update({f"{a}_pred": v for a, v in sim.drift.items()})
    cols.update({f"{c}_pred": v for c, v in sim.sensors.items()})
    names = list(cols)
    lines = [",".join(names)]
    for i in range(len(run)):
        lines.append(",".join(cols[n][i] if n == "time" else f"{cols[n][i]:.6f}" for n in names))
    write_atomic(args.out, "\n".join(lines) + "\n")
    if args.json:
        _print_json({"out": args.out, "columns": names[1:], "samples": len(run), "after": args.after})
    else:
        _say(args, f"wrote {args.out}: {', '.join(names[1:])} for {len(run)} samples")
    return 0


def _say_how_held_out(args: argparse.Namespace, run: Run, hold: Run | None) -> None:
    """init's and diagnose's words for a `--holdout` run whose clock goes on from RUN's last
    sample: the tail of one run (:meth:`Run.continues`), or a run of its own when the machine
    does not go on through the seam."""
    if hold is None:
        return
    seam = hold.seam(run)
    if seam is not None:
        _say(args, f"note: {hold.source}'s clock goes on from {run.source}'s last sample, but the machine does not "
                   f"({seam}): held out as a run of its own, simulated from its first readings")
    elif hold.continues(run):
        _say(args, f"{hold.source} continues {run.source} (its clock starts {hold.time_s[0] - run.time_s[-1]:g} s after "
                   f"{run.source}'s last sample): held out as the tail of one run, the model running on from "
                   f"{run.source}'s start")


def cmd_init(args: argparse.Namespace) -> int:
    from ._io import write_atomic
    from .thermal import Machine

    _check_out(args.out, args.run, args.holdout)
    _check_holdout(args.run, args.holdout, "--holdout")
    run = _read(args, args.run)
    hold = _read(args, args.holdout) if args.holdout else None
    _say_how_held_out(args, run, hold)
    _stage(args, f"identifying a thermal network from {run.source} ...")
    t0 = time.perf_counter()
    _, s = Machine.identify(run, args.axis, nodes=args.nodes, ambient=args.ambient, inputs=args.input,
                            seed=args.seed, holdout=hold, progress=_progress_enabled(args))
    _stage(args, f"identified in {time.perf_counter() - t0:.1f} s: " + _stage_times(s["stage_s"]))
    write_atomic(args.out, s["toml"])
    if args.json:
        _print_json({k: v for k, v in s.items() if k != "toml"} | {"out": args.out})
        return 0
    amb = s["ambient"]
    _say(args, f"ambient: {amb['column']} ({amb['reason']})")
    _say(args, f"nodes: {s['node_rule']}")
    for nd in s["nodes"]:
        others = f"; its other sensors (not in the model): {', '.join(nd['members'][1:])}" if len(nd["members"]) > 1 else ""
        heat = f"; heated by {', '.join(nd['heated_by'])}" if nd["heated_by"] else ""
        _say(args, f"  {nd['name']:<20} sensor {nd['sensor']}, time constant {nd['tau_s']:.0f} s "
                   f"(first-order fit {nd['tau_fit_s']:.0f} s){heat}{others}")
    u = s.get("unsensed")
    if u and u["kept"]:
        _say(args, f"  {u['name']:<20} no sensor: a part behind {u['linked_to']} (the slowest node), "
                   f"time constant {u['tau_s']:.0f} s")
    if s["copies"]:
        _say(args, "second sensors on a part (lagged copies of a node's sensor, not nodes): " + ", ".join(
            f"{c['column']} ~ {c['of']} (lag {c['tau_s']:.0f} s)" for c in s["copies"]))
    where = (f"{s['holdout_run']}, {s['holdout_rows']} rows" if s.get("holdout_run")
             else f"last {s['holdout_rows']} rows")
    for a in s["axes"]:
        v = a["holdout_rmse_um"]  # None: the probe reads none of the held-out rows
        held = (f"{v:.3f} µm (no compensation: {a['holdout_uncompensated_um']:.3f} µm)"
                if isinstance(v, float) and math.isfinite(v) else "none (its probe reads none of the held-out rows)")
        # the results: printed under --quiet too, as every command's are
        print(f"{a['axis']}: training RMS {a['train_rmse_um']:.3f} µm, "
              f"held-out RMS {held} ({where}; "
              f"probe noise {a['noise_um']:.2f} µm; simulated from the first readings, as any run is)")
    for note in s["notes"]:
        _say(args, f"note: {note}")
    print(f"wrote {args.out}")
    return 0


def cmd_calibrate(args: argparse.Namespace) -> int:
    from .thermal import Machine

    _check_out(args.out, args.run, args.machine)
    machine = Machine.load(args.machine)
    run = _read(args, args.run)
    _stage(args, f"calibrating {args.machine} on {run.source} ...")
    cal, info = machine.calibrate(run, args.axis)
    axis = info["axis"]
    cal.save(args.out)
    if args.json:
        _print_json(info)
        return 0
    # the results: printed under --quiet too, as every command's are
    print(f"calibrated {args.machine} on {run.source} ({info['n_iter']} iterations, "
          f"normalised RMS residual {(info['ssr'] / info['n_data']) ** 0.5:.2f}); wrote {args.out}")
    print(f"{axis}: RMS {info['rmse_um']:.3f} µm on {run.source} from the start fitted with the values ([start] "
          f"in {args.out}; thermerr predict --start fitted), {info['first_reading_rmse_um']:.3f} µm from the "
          "first readings as they are")
    if not info["converged"]:
        _say(args, f"note: the search stopped at its iteration limit ({info['n_iter']}) without settling: the values "
                   "are where it stopped, not a solution to rely on")
    return 0


#: the diagnosis's stages in the order they run (report.json keeps them in key order)
_STAGES = ("baseline", "round_1", "later_rounds_and_check")


def _stage_times(st: dict[str, float]) -> str:
    """Each stage's wall time, in the order they ran: the diagnosis's by :data:`_STAGES` (its
    report keeps them in key order), any other call's in the order given (an identification's)."""
    order = sorted(st, key=lambda k: _STAGES.index(k)) if set(st) <= set(_STAGES) else list(st)
    return ", ".join(f"{k.replace('_', ' ')} {st[k]:.1f} s" for k in order)


def _warm_report() -> None:
    """Import matplotlib and draw one small figure (its fonts loaded), for the report to come:
    run in a thread while the diagnosis runs in the core, which releases the GIL, so that the
    report's first figure does not pay for them (0.3 s of the 1.0 s the real run's five reports
    took). Nothing happens without matplotlib (the report then has no plots)."""
    import io

    try:
        from matplotlib.figure import Figure
    except ImportError:
        return
    fig = Figure(figsize=(2, 1))
    ax = fig.subplots()
    ax.plot([0.0, 1.0], [0.0, 1.0], ".-", label="µm")
    ax.set_xlabel("h")
    ax.legend()
    fig.savefig(io.BytesIO(), format="png", dpi=50)


def cmd_diagnose(args: argparse.Namespace) -> int:
    import threading

    from .thermal import AxesDiagnosis, Diagnosis, Machine, diagnose, diagnose_axes

    for given in (args.run, args.machine, args.holdout):
        if given and os.path.realpath(os.path.dirname(os.path.abspath(given))) == os.path.realpath(args.out):
            raise ThermerrError(f"--out {args.out} holds the input {given}: choose another directory")
    _check_holdout(args.run, args.holdout, "--holdout")
    machine = Machine.load(args.machine)
    run = _read(args, args.run)
    hold = _read(args, args.holdout) if args.holdout else None
    _say_how_held_out(args, run, hold)
    axes = args.axis or machine.axes
    warm = threading.Thread(target=_warm_report, name="thermerr-warm-report", daemon=True)
    warm.start()
    if len(axes) > 1:
        _stage(args, f"diagnosing {args.machine} on {run.source}, {len(axes)} axes ({', '.join(axes)}) in "
                     "parallel: calibrating each baseline, screening every candidate extension ...")
        t0 = time.perf_counter()
        # every axis by default: a probe with nothing to diagnose is left out, not fatal
        multi = diagnose_axes(run, machine, hold, axes=args.axis, network=args.network,
                              progress=_progress_enabled(args))
        _stage(args, f"diagnosed {len(multi.axes)} axes in {time.perf_counter() - t0:.1f} s"
                     + "".join(f"; {a} left out (see below)" for a in multi.skipped))
        for a in multi.axes:
            _stage(args, f"  {a}: " + _stage_times(multi[a].report.get("stage_s", {})))
        result: Diagnosis | AxesDiagnosis = multi
    else:
        _stage(args, f"diagnosing {args.machine} on {run.source}: calibrating the baseline, screening "
                     "every candidate extension ...")
        t0 = time.perf_counter()
        result = diagnose(run, machine, hold, axis=axes[0] if axes else None, network=args.network,
                          progress=_progress_enabled(args))
        _stage(args, f"diagnosed in {time.perf_counter() - t0:.1f} s: " + _stage_times(result.report.get("stage_s", {})))
    warm.join()  # the figures are drawn by one thread at a time
    page = result.write(args.out)
    if args.json:
        _print_json(result.report)
    else:
        print(result)
        print(f"report: {page}")
    return 0


def cmd_stiffness(args: argparse.Namespace) -> int:
    from .base import load_model
    from .stiffness import key_thermal_stiffness

    model = load_model(args.model)
    run = _read(args, args.run)
    res = key_thermal_stiffness(model, run, at=args.at, eta=args.eta, target=args.axis)
    if args.json:
        _print_json(res.to_dict())
    else:
        print(res.table())
    return 0


def cmd_fleet(args: argparse.Namespace) -> int:
    from . import fleet

    if args.scheduler is not None and args.workers is not None:
        raise ThermerrError("--workers sets the local scheduler's threads; with --scheduler the cluster has its own")
    sched = {"scheduler": args.scheduler, "workers": args.workers, "nan": args.nan, "delimiter": args.delimiter,
             "decimal": args.decimal, "rename": args.rename}
    if args.fleet_command == "fit":
        sensors: Any = args.sensors if args.sensors in ("all", "auto") else [
            s.strip() for s in args.sensors.split(",") if s.strip()]
        rows = fleet.fit_runs(args.runs, args.axis, args.model, args.out, seed=args.seed, inputs=args.inputs,
                              sensors=sensors, n_clusters=args.n_clusters, **sched)
    elif args.fleet_command == "evaluate":
        rows = fleet.evaluate_runs(args.model, args.runs, args.axis, out_dir=args.out, **sched)
    else:
        rows = fleet.diagnose_runs(args.runs, args.machine, args.out, axis=args.axis, network=args.network,
                                   **sched)
    failed = [r for r in rows if not r.ok]
    if args.json:
        print(json.dumps({"n_runs": len(rows), "n_failed": len(failed), "runs": [r.as_dict() for r in rows]},
                         indent=1, default=str))
    else:
        print(fleet.table(rows))
        if args.out:
            _say(args, f"summary: {args.out}/{fleet.SUMMARY}.json, {fleet.SUMMARY}.csv")
    if failed:
        names = ", ".join(r.run for r in failed)
        print(f"thermerr: {len(failed)} of {len(rows)} runs failed: {names}", file=sys.stderr)
        return 1
    return 0


def cmd_examples(args: argparse.Namespace) -> int:
    from . import examples

    written = examples.copy_to(args.dir)
    if args.json:
        _print_json({"dir": args.dir, "files": [p.name for p in written]})
        return 0
    d = args.dir
    print(f"copied {len(written)} example files into {d}/: {', '.join(p.name for p in written)}")
    print("try:")
    print(f"  thermerr diagnose {d}/vmc_run.csv --machine {d}/vmc_nominal.toml --out out/diagnosis")
    print(f"  thermerr fit {d}/hmc_run1.csv --axis E_z --model rbf --sensors auto --test {d}/hmc_run2.csv "
          "--out out/rbf.json")
    print(f"  thermerr fit {d}/spindle_3000rpm.csv --axis E_z --model svr --tune cso "
          f"--test {d}/spindle_2000rpm.csv --out out/svr.json")
    return 0


def build_parser() -> argparse.ArgumentParser:
    from .thermal import NETWORK_RULES

    p = argparse.ArgumentParser(prog="thermerr", description="Machine-tool thermal error models and diagnosis.")
    p.add_argument("--version", action="version", version=f"thermerr_rs {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    def common(sp: argparse.ArgumentParser) -> None:
        sp.add_argument("--nan", choices=["error", "drop", "interpolate"], default="error",
                        help="missing values in the run: refuse them (error, the default), fill each "
                             "linearly in time (interpolate: the choice for the thermal network), or "
                             "remove their rows (drop: one blank cell takes the whole row)")
        sp.add_argument("--delimiter", type=_delimiter, default=",",
                        help="field separator of the run CSVs: ',' (default), ';', 'tab', ...")
        sp.add_argument("--decimal", choices=[".", ","], default=".",
                        help="decimal mark of the run CSVs: '.' (default) or ',' (20,5 as a "
                             "spreadsheet in a German or French locale writes it, with --delimiter ';')")
        sp.add_argument("--rename", action="append", default=[], metavar="OLD=NEW",
                        help="map a header name of the run CSVs to the run format's, e.g. "
                             "'Time (s)=time_s'; a '*' in OLD stands for any text and is put back "
                             "where NEW has one ('Temp * (°C)=T_*', 'Disp * (um)=E_*'); repeat it "
                             "for each (the first that matches a column renames it)")
        sp.add_argument("--quiet", action="store_true", help="no progress or chatter (the results are still printed; --json prints only them)")
        sp.add_argument("--json", action="store_true", help="print results as JSON")

    f = sub.add_parser("fit", help="fit a thermal error model to a run and save it")
    f.add_argument("run", help="measured run CSV")
    f.add_argument("--axis", required=True, help="error column to model, e.g. E_z")
    f.add_argument("--model", choices=["mlr", "rbf", "svr", "greybp", "gm1n", "bp", "hybrid", "auto"], default="mlr",
                   help="family to fit, or 'auto': MLR, RBF and SVR candidates (with and without --history, 900,3600 unless given) scored "
                        "on --cv time-ordered splits of the run, the best refitted (default mlr)")
    f.add_argument("--select", choices=["1se", "min"], default="1se",
                   help="--model auto: the winner is the simplest candidate within one standard error of the "
                        "lowest CV RMS (1se, default: MLR before RBF/SVR, then the strongest ridge) or the lowest (min)")
    f.add_argument("--budget", type=float, default=None, metavar="SECONDS",
                   help="--model auto: start no new candidate after this many seconds")
    f.add_argument("--sensors", default="all", help="'all' (default), 'auto' (fuzzy c-means selection) or T_a,T_b,...")
    f.add_argument("--n-clusters", type=_positive_int, default=4, help="clusters for --sensors auto (default 4)")
    f.add_argument("--seed", type=_nonneg_int, default=0, help="seed of every stochastic step (default 0)")
    f.add_argument("--alpha", type=_nonneg_float, default=0.0,
                   help="MLR: ridge penalty on the slopes, in the units of the centred inputs' sums of squares "
                        "(default 0: least squares; --model auto tries 0 and 1 to 1000 in half-decade steps)")
    f.add_argument("--design", choices=["exact", "ols", "kmeans"], default="ols", help="RBF design (default ols)")
    f.add_argument("--spread", type=float, default=1.0, help="RBF spread on [0,1]-scaled inputs (default 1.0)")
    f.add_argument("--goal", type=float, default=None,
                   help="RBF sum-squared error goal in µm² (default: 0.1 µm² per training sample)")
    f.add_argument("--max-neurons", type=_positive_int, default=None)
    f.add_argument("--max-candidates", type=_positive_int, default=500,
                   help="RBF ols: candidate centres; above this many samples a seeded k-means++ pool of "
                        "this many (default 500; at least the sample count: the exhaustive search)")
    f.add_argument("--n-centers", type=_positive_int, default=None, help="centres of the kmeans design")
    f.add_argument("--C", type=float, default=1.0, help="SVR box constraint (default 1; searched with --tune)")
    f.add_argument("--epsilon", type=float, default=0.1, help="SVR tube half-width in µm (default 0.1)")
    f.add_argument("--gamma", type=float, default=None, help="SVR RBF gamma (default: 'scale'; searched with --tune)")
    f.add_argument("--tune", choices=["cso", "pso"], default=None,
                   help="search SVR C and gamma by cross-validated MSE with chicken swarm or particle swarm (seed 004); "
                        "with --model auto, one more SVR candidate so tuned (per --history setting)")
    f.add_argument("--cv", type=_positive_int, default=5, help="splits of the --tune search and of --model auto (default 5)")
    f.add_argument("--cv-kind", choices=["time", "kfold"], default="time",
                   help="time: each split trains on the samples before its test block (scikit-learn's "
                        "TimeSeriesSplit, default); kfold: the seed's shuffled folds (trains on later samples too)")
    f.add_argument("--gap", type=_nonneg_int, default=0,
                   help="samples left out between training and test blocks of --cv-kind time (default 0)")
    f.add_argument("--pop", type=_positive_int, default=None,
                   help="swarm population of --tune (default 20; 10 with --model auto)")
    f.add_argument("--iters", type=_positive_int, default=None,
                   help="swarm generations of --tune (default 100; 10 with --model auto)")
    f.add_argument("--thin", type=_thin, default="auto",
                   help="--tune searches on every k-th row, then scores its best points on every row: "
                        "'auto' (default: at most 1000 training rows per split) or k (1: every row)")
    f.add_argument("--windows", type=_positive_int, nargs="+", default=[6, 8, 10], help="GM(1,N) windows of greybp (default 6 8 10)")
    f.add_argument("--window", type=_positive_int, default=8, help="GM(1,N) window of gm1n (default 8)")
    f.add_argument("--hidden", type=_positive_int, default=None, help="hidden units of bp/greybp (7) or hybrid (30)")
    f.add_argument("--trainer", choices=["adam", "seed"], default="adam",
                   help="network trainer: adam (default) or the seed's gradient descent with momentum")
    f.add_argument("--variant", choices=["hybrid", "arma", "lrnn", "fnn"], default="hybrid",
                   help="seed 000 variant of --model hybrid (default hybrid)")
    f.add_argument("--limit", type=float, default=None,
                   help="output limit of --model hybrid in µm (default: 50, the seed's, or 1.5x the largest "
                        "training error if that is larger)")
    f.add_argument("--inputs", choices=["rise", "absolute"], default="rise",
                   help="model from each sensor's rise since the run's start (default) or absolute readings")
    f.add_argument("--history", type=_taus, default=None, metavar="TAU,...",
                   help="also read each sensor's rise over about the last TAU seconds (first-order filters), "
                        "e.g. 900,3600; kept as state on the edge. --model auto tries 900,3600 beside none "
                        "unless given ('none': no history)")
    f.add_argument("--test", help="a held-out run to score the model on; a run whose time_s clock goes on from the "
                                   "training run's (a later piece of the same log) is predicted as its continuation")
    f.add_argument("--test-continues", action="store_true",
                   help="--test is the continuation of the training run even if its clock does not say so "
                        "(an ISO time column counts from its own first row): predict it from the training run's start")
    f.add_argument("--no-guard", action="store_true",
                   help="write no sensor-fault guard (default: limits learnt from the run and, for mlr/rbf/svr/bp, "
                        "one fallback model without each sensor, for thermerr-edge)")
    f.add_argument("--no-fallbacks", action="store_true",
                   help="a guard without fallback models (one fit fewer per sensor): a sensor out beyond --hold "
                        "freezes the output")
    f.add_argument("--hold", type=_nonneg_float, default=300.0,
                   help="seconds the edge holds a faulty sensor's last good reading before it falls back (default 300)")
    f.add_argument("--out", required=True, help="model file to write (JSON)")
    common(f)
    f.set_defaults(func=cmd_fit)

    e = sub.add_parser("evaluate", help="figures of merit of a saved model on a run")
    e.add_argument("model", help="model JSON written by 'thermerr fit'")
    e.add_argument("run", help="measured run CSV")
    e.add_argument("--axis", default=None, help="error column (default: the model's target)")
    e.add_argument("--after", metavar="EARLIER.csv",
                   help="the run is a later piece of a log whose earlier rows are EARLIER.csv (e.g. the training "
                        "run): predict it from EARLIER.csv's start, as a gateway running since then")
    common(e)
    e.set_defaults(func=cmd_evaluate)

    s = sub.add_parser("select-sensors", help="pick one sensor per fuzzy c-means cluster (seed 003)")
    s.add_argument("run", help="measured run CSV")
    s.add_argument("--axis", required=True, help="error column, or several comma-separated for a composite")
    s.add_argument("--n-clusters", type=_positive_int, default=4)
    s.add_argument("--seed", type=_nonneg_int, default=0)
    common(s)
    s.set_defaults(func=cmd_select)

    pr = sub.add_parser("predict", help="simulate a run with a machine model (thermal network)")
    pr.add_argument("run", help="measured run CSV (its inputs and boundary columns drive the model)")
    pr.add_argument("--machine", required=True, help="machine TOML")
    pr.add_argument("--out", required=True, help="CSV to write: time_s, E_<axis>_pred, T_<sensor>_pred")
    pr.add_argument("--fit-initial", type=_nonneg_int, default=0, metavar="N",
                    help="estimate the sensed nodes' start from the first N readings (default: first reading)")
    pr.add_argument("--start", choices=["first", "fitted"], default="first",
                    help="the nodes' start: their first readings as they are (default), or 'fitted': the start "
                         "the machine's values were fitted from (its [start] table, written by init, calibrate "
                         "and diagnose), for the run it names")
    pr.add_argument("--after", metavar="EARLIER.csv",
                    help="the run is a later piece of a log whose earlier rows are EARLIER.csv: simulate from "
                         "EARLIER.csv's start (drift relative to the log's start) and write the run's rows")
    common(pr)
    pr.set_defaults(func=cmd_predict)

    ini = sub.add_parser("init", help="identify a starting machine model (thermal network TOML) from a run")
    ini.add_argument("run", help="measured run CSV (time_s, U_* inputs, T_* temperatures, E_* axes)")
    ini.add_argument("--axis", action="append", default=None,
                     help="error axis to map, repeatable; the first calibrates the network (default: every "
                          "E_* column, in the natural order of their names)")
    ini.add_argument("--out", required=True, help="machine TOML to write")
    ini.add_argument("--nodes", type=_positive_int, default=None,
                     help="number of nodes (default: the smallest Xie-Beni index over 2-5)")
    ini.add_argument("--ambient", default=None, help="the ambient column (default: T_ambient, else the coldest)")
    ini.add_argument("--input", action="append", default=None, metavar="U_COL",
                     help="an input that heats the machine, repeatable (default: every U_* column; "
                          "name the real heat inputs when the log carries others, e.g. a program number)")
    ini.add_argument("--seed", type=int, default=0, help="seed of the fuzzy c-means start (default 0)")
    ini.add_argument("--holdout", default=None, metavar="RUN2",
                     help="a separate run to hold out (the same machine, another day): every row of the run "
                          "trains (default: its last 30 %% is held out); RUN2 continuing the run's clock (a log "
                          "cut in two) is held out as its tail")
    common(ini)
    ini.set_defaults(func=cmd_init)

    ca = sub.add_parser("calibrate", help="fit a machine model's parameters to a run")
    ca.add_argument("run", help="measured run CSV")
    ca.add_argument("--machine", required=True, help="nominal machine TOML")
    ca.add_argument("--axis", default=None, help="error axis (default: the machine's first)")
    ca.add_argument("--out", required=True, help="calibrated machine TOML to write")
    common(ca)
    ca.set_defaults(func=cmd_calibrate)

    dg = sub.add_parser("diagnose", help="name what the machine model gets wrong, extend it, measure the gain")
    dg.add_argument("run", help="measured run CSV")
    dg.add_argument("--machine", required=True, help="nominal machine TOML")
    dg.add_argument("--out", required=True, help="directory for report.json, report.html, calibrated.toml, extended.toml")
    dg.add_argument("--holdout", default=None, help="a separate held-out run (default: the last 30 %% of RUN); one whose clock goes on "
                         "from RUN's last sample (a log cut in two) is held out as RUN's tail")
    dg.add_argument("--axis", action="append", default=None,
                    help="error axis; repeat for several (default: every drift entry of the machine). "
                         "Several axes write a summary report.json/report.html and <axis>.report.json, "
                         "<axis>.report.html, <axis>.calibrated.toml, <axis>.extended.toml")
    dg.add_argument("--network", choices=NETWORK_RULES, default="auto",
                    help="the baseline's thermal network: auto (default): recalibrate, but keep a network "
                         "`thermerr init` identified when its recalibration is not unique (a start stops at the "
                         "iteration limit, or a second start fits the training rows as well and holds out "
                         "differently); recalibrate it on the training "
                         "rows and the axis, keep it as the machine file gives it (only the start and the drift map "
                         "fitted: a network `thermerr init` identified from this run, or one you trust), or "
                         "best: both, and the one with the smaller held-out residual of the error and the "
                         "temperatures together (noise-normalised), or shared: one network for every axis, "
                         "calibrated once on the temperatures alone, each axis fitting its start and drift map")
    common(dg)
    dg.set_defaults(func=cmd_diagnose)

    ex = sub.add_parser("examples", help="copy the bundled example runs and machine models into a directory")
    ex.add_argument("dir", nargs="?", default="thermerr-examples", help="where to copy them (default thermerr-examples)")
    common(ex)
    ex.set_defaults(func=cmd_examples)

    st = sub.add_parser("stiffness", help="key thermal stiffness: which sensor's element governs the axis (seed 001)")
    st.add_argument("model", help="model JSON written by 'thermerr fit'")
    st.add_argument("run", help="measured run CSV")
    st.add_argument("--at", type=float, default=None, help="time in s of the sample to use (default: thermal equilibrium)")
    st.add_argument("--eta", type=float, default=0.5, help="temperature step in °C (default 0.5)")
    st.add_argument("--axis", default=None, help="error column (default: the model's target)")
    common(st)
    st.set_defaults(func=cmd_stiffness)

    fl = sub.add_parser("fleet", help="fit, evaluate or diagnose many runs in parallel on Dask (exit 1: some failed)")
    flsub = fl.add_subparsers(dest="fleet_command", required=True)
    runs_help = "a directory (every *.csv in it) or run files"
    flf = flsub.add_parser("fit", help="one model per run, saved as OUT/<run>.json")
    flf.add_argument("runs", nargs="+", help=runs_help)
    flf.add_argument("--axis", required=True, help="error column to model, e.g. E_z")
    flf.add_argument("--model", choices=["mlr", "rbf", "svr", "greybp", "gm1n", "bp", "hybrid"], default="mlr")
    flf.add_argument("--sensors", default="all",
                     help="'all' (default), 'auto' (fuzzy c-means per run) or T_a,T_b,...")
    flf.add_argument("--n-clusters", type=int, default=4, help="clusters for --sensors auto (default 4)")
    flf.add_argument("--seed", type=int, default=0, help="seed of every run's stochastic steps (default 0)")
    flf.add_argument("--inputs", choices=["rise", "absolute"], default="rise")
    flf.add_argument("--out", required=True, help="directory for the models and fleet-summary.{json,csv}")
    fle = flsub.add_parser("evaluate", help="figures of merit of one saved model on every run")
    fle.add_argument("model", help="model JSON written by 'thermerr fit'")
    fle.add_argument("runs", nargs="+", help=runs_help)
    fle.add_argument("--axis", default=None, help="error column (default: the model's target)")
    fle.add_argument("--out", default=None, help="directory for fleet-summary.{json,csv} (default: none written)")
    fld = flsub.add_parser("diagnose", help="diagnose every run against one machine model, a report per run")
    fld.add_argument("runs", nargs="+", help=runs_help)
    fld.add_argument("--machine", required=True, help="nominal machine TOML")
    fld.add_argument("--axis", action="append", default=None,
                     help="error axis; repeat for several (default: every drift entry of the machine, as thermerr "
                          "diagnose). Several axes write OUT/<run>/ as thermerr diagnose does: a summary report and "
                          "<axis>.report.*")
    fld.add_argument("--network", choices=NETWORK_RULES, default="auto",
                     help="the baseline's thermal network, as for thermerr diagnose (default auto)")
    fld.add_argument("--out", required=True,
                     help="directory for OUT/<run>/report.* and fleet-summary.{json,csv}")
    for sp in (flf, fle, fld):
        sp.add_argument("--scheduler", default=None, metavar="ADDR",
                        help="a dask scheduler, host:port or tcp://... (default: threads on this machine)")
        sp.add_argument("--workers", type=int, default=None, help="threads of the local scheduler (default: CPUs)")
        common(sp)
        sp.set_defaults(func=cmd_fleet)
    return p


def _exit_code(e: BaseException) -> int:
    """1 when valid input could not be computed or written; 2 for bad usage or input."""
    if isinstance(e, (NumericalError, ConvergenceError)):
        return 1
    if isinstance(e, (FileNotFoundError, IsADirectoryError, NotADirectoryError, PermissionError)):
        return 2
    if isinstance(e, OSError):  # a full disk, an I/O error
        return 1
    return 2


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.json:
        args.quiet = True
    with warnings.catch_warnings():
        # the result's own lines say them (warning: ..., note: suspect reading: ...)
        warnings.filterwarnings("ignore", category=SuspectReadingWarning)
        # any other warning is one line, as an error is (not Python's file, line and source)
        warnings.showwarning = _one_line_warning
        return _run(args)


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                      file: Any = None, line: str | None = None) -> None:
    print(f"thermerr: warning: {message}", file=sys.stderr)


def _run(args: argparse.Namespace) -> int:
    try:
        rc: int = args.func(args)
        sys.stdout.flush()
        return rc
    except BrokenPipeError:
        # the reader went away (| head): say nothing, and keep Python from complaining at exit
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141
    except KeyboardInterrupt:
        print("thermerr: interrupted", file=sys.stderr)
        return 130
    except (ThermerrError, OSError, KeyError, ValueError) as e:
        msg = str(e.args[0]) if isinstance(e, KeyError) and e.args else str(e)
        if isinstance(e, OSError) and e.filename and str(e.filename) not in msg:
            msg = f"{e.filename}: {msg}"
        print(f"thermerr: error: {msg}", file=sys.stderr)
        return _exit_code(e)


if __name__ == "__main__":
    sys.exit(main())
