"""Model selection on a run: every family, time-ordered folds of the training run only.

:func:`select_model` scores a small, fixed set of candidates per family (MLR; RBF k-means over
centres and spread; SVR over C and gamma; each with and without temperature history) by the
mean held-out RMS of time-ordered splits (:func:`thermerr_rs.time_series_split`: each split trains
on the samples before its test block). The inputs (rises, history filters) are built over the
whole training run first, as a gateway running since the run's start would see them; only the
fit is restricted to each split's training rows. The winner is refitted on the whole run.

The leaderboard lists, per candidate: the CV RMS and its spread over splits, the median fit time
of one split, the edge latency per sample (the last split's model timed sample by sample by the
code and loop ``thermerr-edge --bench-latency`` runs, on its inputs as built: the history
filters' own cost, a few multiply-adds per reading, is not in it) and the prediction time per
sample through the library (a batch call, Python included; ``to_dict`` only). The winner,
refitted with its rises and history, is then timed the edge's way from raw readings
(``edge_latency_us``: median and 99th percentile per sample). The CV errors are deterministic for a seed (the times are measured). A
budget in seconds stops starting new candidates once spent (the ones scored so far are ranked).

The winner is chosen by the one-standard-error rule (``rule="1se"``, the default; Hastie,
Tibshirani & Friedman, *The Elements of Statistical Learning*, §7.10, and glmnet's
``lambda.1se``): among the candidates whose CV RMS is within one standard error of the lowest
(the splits' sample standard deviation over √splits), the simplest: MLR before the kernel
models, then the strongest ridge, then the lowest CV RMS. The splits of a run's training part
test each model on a stretch it never saw (the first split trains on a sixth of it), so their
mean differs between candidates by less than its own spread; the rule then takes the model that
extrapolates most plainly. ``rule="min"`` takes the lowest CV RMS (the rule before 2026-11-25).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _core
from .base import Estimator, _history, run_inputs
from .errors import ParameterError
from .folds import time_series_split
from .run import Run

#: per-sample predictions timed for a candidate's edge latency (cycling through its test rows)
EDGE_SAMPLES = 1000

#: families :func:`select_model` knows, in the order they are tried
FAMILIES: tuple[str, ...] = ("mlr", "rbf", "svr")

#: how :func:`select_model` picks its winner from the leaderboard: the one-standard-error rule
#: (the default) or the lowest CV RMS
RULES: tuple[str, ...] = ("1se", "min")

#: the temperature history ``thermerr fit --model auto`` tries beside none when ``--history`` is
#: not given: each reading's rise over about the last 15 min and 1 h (the time constants of a
#: machine's structure behind its surface sensors; docs/methods.md, the lagged shop run)
AUTO_HISTORY: tuple[float, ...] = (900.0, 3600.0)

#: the MLR ridge penalties α :func:`select_model` tries (0: least squares), a path in steps of a
#: half decade as glmnet's is a log grid: the one-standard-error rule takes the strongest ridge
#: inside its band, so a coarser path makes that pick jump (docs/methods.md, the real run)
RIDGE_PATH: tuple[float, ...] = (0.0, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0)


@dataclass(frozen=True)
class Candidate:
    """One estimator setting of a family (``history``: time constants in s, or None)."""

    family: str
    params: dict[str, Any]
    history: tuple[float, ...] | None
    #: an SVR whose C and gamma a swarm searches on the same splits: (method, pop, iters)
    tune: tuple[str, int, int] | None = None

    def make(self, seed: int) -> Estimator:
        from .linear import MLR
        from .rbf import RBFNetwork
        from .svr import SVR

        if self.family == "mlr":
            return MLR(**self.params)
        if self.family == "rbf":
            return RBFNetwork(design="kmeans", seed=seed, **self.params)
        if self.family == "svr":
            return SVR(**self.params)
        raise ParameterError(f"unknown family {self.family!r} (known: {', '.join(FAMILIES)})")

    def label(self) -> str:
        parts = [f"{k}={v:.4g}" if isinstance(v, float) and self.tune else f"{k}={v}"
                 for k, v in self.params.items() if k != "epsilon"]
        if self.tune:
            parts.append(f"tuned={self.tune[0]} {self.tune[1]}x{self.tune[2]}")
        if self.history:
            parts.append("history=" + "/".join(f"{t:g}" for t in self.history))
        return f"{self.family}({', '.join(parts)})"


def candidates(families: Sequence[str], history: Sequence[float] | None,
               tune: tuple[str, int, int] | None = None) -> list[Candidate]:
    """The fixed grid: MLR along :data:`RIDGE_PATH`, least squares and ridge penalties α from 1
    to 1000 in half-decade steps (inputs in K: a long history of correlated readings fitted on a
    short early split extrapolates wildly without one); RBF k-means with 10/20/40 centres ×
    spread 0.5/1/2 (in the inputs' units, K of rise); SVR with C 1/10/100 × gamma 0.01/0.1/'scale'; with ``tune`` (method, pop,
    iters) and the SVR family, one more SVR whose C and gamma the swarm searches. With
    ``history``, each again with those time constants. In the order they are scored: family by
    family in ``families``' order (MLR, the cheapest, first), each without and then with
    history, so a ``budget_s`` that runs out skips the costliest family's last candidates and
    never the history of the cheap ones (on the real run the winners were MLRs with history)."""
    grid: dict[str, list[dict[str, Any]]] = {
        "mlr": [{"alpha": a} if a else {} for a in RIDGE_PATH],
        "rbf": [{"n_centers": k, "spread": s} for k in (10, 20, 40) for s in (0.5, 1.0, 2.0)],
        "svr": [{"C": c, "gamma": g, "epsilon": 0.1} for c in (1.0, 10.0, 100.0) for g in (0.01, 0.1, "scale")],
    }
    unknown = [f for f in families if f not in grid]
    if unknown:
        raise ParameterError(f"unknown families {unknown} (known: {', '.join(FAMILIES)})")
    hists: list[tuple[float, ...] | None] = [None]
    if history:
        hists.append(tuple(float(t) for t in history))
    out: list[Candidate] = []
    for f in families:  # family by family, each without and then with history: cheapest first
        for h in hists:
            out += [Candidate(f, p, h) for p in grid[f]]
            if tune is not None and f == "svr":
                out.append(Candidate("svr", {"epsilon": 0.1}, h, tune=tune))
    return out


@dataclass
class Entry:
    candidate: Candidate
    cv_rms: float
    cv_rms_std: float
    fit_s: float
    predict_us: float
    #: median per-sample latency on the edge's code (the last split's model), µs
    edge_us: float = float("nan")

    def as_dict(self) -> dict[str, Any]:
        return {"model": self.candidate.label(), "family": self.candidate.family,
                "params": self.candidate.params, "history": list(self.candidate.history or []) or None,
                "tuned": list(self.candidate.tune) if self.candidate.tune else None,
                "cv_rms_um": self.cv_rms, "cv_rms_std_um": self.cv_rms_std, "fit_s": self.fit_s,
                "edge_us_per_sample": self.edge_us, "predict_us_per_sample": self.predict_us}


def simplicity(c: Candidate) -> tuple[int, float]:
    """The order of the one-standard-error rule, simplest first: MLR before the kernel models
    (RBF, SVR), then the stronger ridge."""
    if c.family == "mlr":
        return (0, -float(c.params.get("alpha", 0.0)))
    return (1, 0.0)


def pick(board: Sequence[Entry], n_splits: int, rule: str = "1se") -> int:
    """The winner's index in ``board`` (sorted by CV RMS, lowest first) by ``rule``: ``"min"``,
    the lowest CV RMS; ``"1se"``, the simplest candidate (:func:`simplicity`; ties by CV RMS)
    whose CV RMS is at most the lowest plus its standard error, the splits' sample standard
    deviation over √splits."""
    if rule not in RULES:
        raise ParameterError(f"rule must be one of {', '.join(RULES)}, got {rule!r}")
    if rule == "min" or n_splits < 2:
        return 0
    best = board[0]
    bar = best.cv_rms + best.cv_rms_std / np.sqrt(n_splits - 1)  # std (ddof 0) · √(k/(k-1)) / √k
    within = [i for i, e in enumerate(board) if e.cv_rms <= bar]
    return min(within, key=lambda i: (simplicity(board[i].candidate), board[i].cv_rms))


@dataclass
class ModelSelection:
    """Result of :func:`select_model`: the ``leaderboard`` (lowest CV RMS first), the winner
    (``best``, ``leaderboard[winner]``, chosen by ``rule``) refitted on the whole run
    (``model``), the splits used, and candidates not scored within the budget."""

    leaderboard: list[Entry]
    model: Estimator
    n_splits: int
    gap: int
    skipped: list[str] = field(default_factory=list)
    #: the winner's per-sample latency on the edge, µs: (median, 99th percentile)
    edge_latency_us: tuple[float, float] | None = None
    #: the winner's index in the leaderboard, and the rule that chose it (:data:`RULES`)
    winner: int = 0
    rule: str = "min"

    @property
    def best(self) -> Entry:
        return self.leaderboard[self.winner]

    def to_dict(self) -> dict[str, Any]:
        lat = self.edge_latency_us
        return {"leaderboard": [e.as_dict() for e in self.leaderboard], "n_splits": self.n_splits,
                "gap": self.gap, "skipped": self.skipped, "rule": self.rule, "winner": self.winner,
                "edge_latency_us": None if lat is None else {"p50": lat[0], "p99": lat[1]}}

    def __str__(self) -> str:
        return self.table()

    def table(self, top: int | None = 10) -> str:
        """The leaderboard as text, the ``top`` best (all with ``None``)."""
        lines = [f"  {'model':44s} {'CV RMS µm':>10s} {'±':>7s} {'fit s':>7s} {'edge µs':>8s}"]
        shown = list(range(len(self.leaderboard) if top is None else min(top, len(self.leaderboard))))
        if self.winner not in shown:
            shown.append(self.winner)
        for i in shown:
            e = self.leaderboard[i]
            mark = "* " if i == self.winner else "  "
            lines.append(f"{mark}{e.candidate.label():44s} {e.cv_rms:10.3f} {e.cv_rms_std:7.3f} {e.fit_s:7.2f} "
                         f"{e.edge_us:8.2f}")
        if len(shown) < len(self.leaderboard):
            lines.append(f"... and {len(self.leaderboard) - len(shown)} more (to_dict() / --json has them all)")
        if self.rule == "1se":
            lines.append(f"* the winner: the simplest within one standard error of the lowest CV RMS "
                         f"({self.leaderboard[0].cv_rms:.3f} + {self.leaderboard[0].cv_rms_std / np.sqrt(max(self.n_splits - 1, 1)):.3f} µm; "
                         "MLR before RBF/SVR, then the strongest ridge; rule='min' / --select min: the lowest)")
        else:
            lines.append("* the winner: the lowest CV RMS")
        if self.skipped:
            lines.append(f"({len(self.skipped)} candidates not scored within the budget)")
        if self.edge_latency_us is not None:
            p50, p99 = self.edge_latency_us
            lines.append(f"winner on the edge (thermerr-edge's code, sample by sample): {p50:.2f} µs per sample "
                         f"(p99 {p99:.2f} µs)")
        return "\n".join(lines)


def select_model(run: Run, axis: str, features: Sequence[str], *, families: Sequence[str] = FAMILIES,
                 history: Sequence[float] | None = None, inputs: str = "rise", cv: int = 5, gap: int = 0,
                 budget_s: float | None = None, seed: int = 0, tune: str | None = None,
                 tune_pop: int = 10, tune_iters: int = 10, rule: str = "1se",
                 progress: Callable[[int, int, str], None] | None = None) -> ModelSelection:
    """Score every candidate of ``families`` on time-ordered splits of ``run`` (the training run
    only), rank them by mean held-out RMS, pick the winner by ``rule`` (``"1se"``: the simplest
    within one standard error of the lowest, the default; ``"min"``: the lowest; module
    docstring), refit it on the whole run and return both.

    ``tune`` (``"cso"`` or ``"pso"``) adds, per history setting, an SVR whose C and γ
    :func:`~thermerr_rs.tune_svr` searches (``tune_pop`` × ``tune_iters``, in its default box
    C ∈ [0.01, 1000], γ ∈ [1e-4, 10], the search's seed ``seed``) by the mean MSE over the same
    splits, then scored like every other candidate. Its CV RMS, like the grid's, is measured on
    the splits it was chosen on; a search tries more points than the grid, so it is the more
    optimistic of the two (only a held-out run says by how much)."""
    features = list(features)
    run.check_fit_columns(axis, features)
    if budget_s is not None and not budget_s > 0:
        raise ParameterError(f"budget_s must be > 0 seconds, got {budget_s}")
    y = np.asarray(run[axis], dtype=np.float64)
    splits = time_series_split(len(run), cv, gap=gap)
    if tune is not None and tune not in ("cso", "pso"):
        raise ParameterError(f"tune must be 'cso' or 'pso', got {tune!r}")
    if rule not in RULES:
        raise ParameterError(f"rule must be one of {', '.join(RULES)}, got {rule!r}")
    cands = candidates(families, history, (tune, int(tune_pop), int(tune_iters)) if tune else None)
    inputs_by_hist: dict[tuple[float, ...] | None, np.ndarray] = {}
    board: list[Entry] = []
    skipped: list[str] = []
    start = time.perf_counter()
    for k, c in enumerate(cands):
        if budget_s is not None and board and time.perf_counter() - start > budget_s:
            skipped.append(c.label())
            continue
        if progress is not None:
            progress(k + 1, len(cands), c.label())
        if c.history not in inputs_by_hist:
            inputs_by_hist[c.history] = run_inputs(run, features, inputs, _history(c.history, run.time_s))
        x = inputs_by_hist[c.history]
        if c.tune is not None:
            from .swarm import tune_svr

            method, pop, iters = c.tune
            res = tune_svr(x, y, method=method, cv=splits, pop=pop, iters=iters, seed=seed,
                           progress=False)
            c = Candidate("svr", {"C": res.C, "gamma": res.gamma, "epsilon": 0.1}, c.history, tune=c.tune)
        rms, fit_s, pred_us = [], [], []
        for train, test in splits:
            m = c.make(seed)
            t0 = time.perf_counter()
            m.fit(x[train], y[train])
            t1 = time.perf_counter()
            pred = m.predict(x[test])
            t2 = time.perf_counter()
            rms.append(float(np.sqrt(np.mean((y[test] - pred) ** 2))))
            fit_s.append(t1 - t0)
            pred_us.append((t2 - t1) / len(test) * 1e6)
        rows = np.ascontiguousarray(x[test], dtype=np.float64)  # the last split's model and rows
        edge_ns, _, _ = _core.sample_latency(m.to_json(), rows, EDGE_SAMPLES)
        board.append(Entry(c, float(np.mean(rms)), float(np.std(rms)), float(np.median(fit_s)),
                           float(np.median(pred_us)), edge_ns / 1e3))
    board.sort(key=lambda e: (e.cv_rms, e.fit_s))
    winner = pick(board, len(splits), rule)
    win = board[winner].candidate
    model = win.make(seed).fit_run(run, axis, features, inputs=inputs, history=win.history)
    return ModelSelection(board, model, len(splits), gap, skipped, edge_latency(model, run), winner, rule)


def edge_latency(model: Estimator, run: Run, samples: int | None = None) -> tuple[float, float]:
    """Per-sample latency of a fitted model as ``thermerr-edge`` runs it (the core's predictor,
    one reading row at a time, rises and history filters included), over ``run``'s readings
    (cycled, restarting the run at each pass; ``samples`` default: the run's length, at least
    1 000 and at most 5 000): (median, 99th percentile) in µs."""
    text = model.to_json()
    features = json.loads(text).get("features")  # the readings the edge takes, in its order
    if not features:
        raise ParameterError("edge_latency needs a model fitted on a run (fit_run): its file names no features")
    n = samples if samples is not None else min(max(len(run), 1000), 5000)
    if n < 1:
        raise ParameterError(f"samples must be >= 1, got {n}")
    x = np.ascontiguousarray(run.matrix(list(features)), dtype=np.float64)
    p50, p99, _ = _core.sample_latency(text, x, int(n))
    return p50 / 1e3, p99 / 1e3
