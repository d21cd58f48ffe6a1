"""Box-bounded swarm minimisers in Rust — chicken swarm optimisation (Meng et al. 2014) and
particle swarm — and seed 004's tuning of an ε-SVR by cross-validated error."""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _core
from ._arrays import F64, as_matrix, as_vector
from .errors import ParameterError
from .folds import Splits, resolve_cv
from .svr import SVR

Objective = str | Callable[[F64], float] | Callable[[F64], Sequence[float]]


@dataclass(frozen=True)
class SwarmResult:
    """Best point ``x`` and value ``fun`` found, the best value after each generation
    (``history``, ``iters`` entries), and the number of objective evaluations (the initial
    population included)."""

    x: F64
    fun: float
    history: F64
    n_evals: int


def _bounds(bounds: Any) -> list[tuple[float, float]]:
    try:
        out = [(float(lo), float(hi)) for lo, hi in bounds]
    except (TypeError, ValueError):
        raise ParameterError("bounds must be a sequence of (low, high) pairs") from None
    return out


def _run(f: Objective, bounds: Any, vectorized: bool, **kw: Any) -> SwarmResult:
    x, fun, hist, n = _core.swarm_minimize(f, _bounds(bounds), vectorized=vectorized, **kw)
    return SwarmResult(np.asarray(x), float(fun), np.asarray(hist), int(n))


def cso(
    f: Objective,
    bounds: Sequence[tuple[float, float]],
    *,
    pop: int = 20,
    iters: int = 100,
    G: int = 10,
    roosters: float = 0.2,
    hens: float = 0.6,
    fl: tuple[float, float] = (0.4, 1.0),
    seed: int = 0,
    vectorized: bool = False,
) -> SwarmResult:
    """Chicken swarm optimisation (Meng et al. 2014) of ``f`` over the box ``bounds``.

    ``f`` is a callable taking a point (1-D array) and returning a float — or, with
    ``vectorized=True``, taking the population (pop × dim) and returning pop floats — or the name of
    a built-in objective (``"sphere"``, ``"rosenbrock"``, ``"rastrigin"``), evaluated natively
    without the GIL. Every G generations the swarm is ranked: the best ``roosters``·pop are roosters, the
    worst (1 − roosters − hens)·pop chicks, the rest hens; moves follow methods.md §6 with each
    chicken's personal best as memory. Non-finite values count as +∞. The same seed gives the
    same result.
    """
    return _run(f, bounds, vectorized, method="cso", pop=int(pop), iters=int(iters), g=int(G),
                roosters=float(roosters), hens=float(hens), fl=(float(fl[0]), float(fl[1])), seed=int(seed))


def pso(
    f: Objective,
    bounds: Sequence[tuple[float, float]],
    *,
    pop: int = 20,
    iters: int = 100,
    w: float = 0.7298,
    c1: float = 1.49618,
    c2: float = 1.49618,
    vmax_frac: float = 0.2,
    seed: int = 0,
    vectorized: bool = False,
) -> SwarmResult:
    """Global-best particle swarm (inertia ``w``, cognitive ``c1``, social ``c2``; velocities
    clamped to ``vmax_frac`` of each range) of ``f`` over ``bounds``; ``f`` as in :func:`cso`."""
    return _run(f, bounds, vectorized, method="pso", pop=int(pop), iters=int(iters), w=float(w),
                c1=float(c1), c2=float(c2), vmax_frac=float(vmax_frac), seed=int(seed))


@dataclass
class TuneResult:
    """Outcome of :func:`tune_svr`: the best ``C`` and ``gamma``, their cross-validated MSE, the
    best CV MSE after each generation, the evaluations spent (``n_evals`` points; ``n_fits`` SVR
    fits of one fold, fewer than ``n_evals × folds`` because a point met before is not refitted and
    a point whose first folds already rule it out stops there — the result is the same as with
    every fold fitted), the SVR refitted on all the data, and the (train, test) index pairs used
    (``folds``; pass them back as ``cv``). ``cv_mse`` is the objective at (``C``, ``gamma``) with
    every fold's solver started cold, as :func:`svr_cv_mse` gives it; ``history`` holds the values
    the search saw (with ``warm_start``, those of warm-started solvers: equal to O(tol)).
    ``at_bounds`` names each parameter that ended on an edge of the search box (e.g.
    ``"C = 100 (upper bound)"``): the optimum may lie beyond it, so widen ``bounds`` there.
    ``thin`` is the thinning the search ran with (1: every row; see :func:`tune_svr`); after a
    thinned search ``history`` holds the thinned objective's values and ``cv_mse`` the full
    one's at the returned point."""

    C: float
    gamma: float
    cv_mse: float
    history: F64
    n_evals: int
    n_fits: int
    model: SVR
    folds: Splits = field(repr=False)
    at_bounds: tuple[str, ...] = ()
    thin: int = 1


def tune_svr(
    X: Any,
    y: Any,
    *,
    method: str = "cso",
    cv: Any = 5,
    cv_kind: str = "time",
    gap: int = 0,
    bounds: dict[str, tuple[float, float]] | None = None,
    scale: str = "log",
    epsilon: float = 0.1,
    tol: float = 1e-3,
    pop: int = 20,
    iters: int = 100,
    seed: int = 0,
    warm_start: bool | None = None,
    thin: int | str = "auto",
    progress: bool | None = None,
    **swarm: Any,
) -> TuneResult:
    """Seed 004: search (C, γ) of an RBF ε-SVR minimising the cross-validated MSE.

    ``method`` ``"cso"`` or ``"pso"``. ``cv`` (see :mod:`thermerr_rs.folds`): an int ``k`` is
    ``k`` time-ordered splits (scikit-learn's ``TimeSeriesSplit(k, gap=gap)``: each model trained
    on the samples before its test block, ``gap`` samples left out between them) — or, with
    ``cv_kind="kfold"``, the seed's ``k`` shuffled folds (shuffled by ``seed``, each trained on the
    complement, i.e. also on later samples: not an honest error for a run); a scikit-learn
    splitter (anything with ``.split(X)``) or an iterable of ``(train, test)`` index arrays is used
    as it is. ``bounds`` ``{"C": (lo, hi), "gamma": (lo, hi)}`` (default C in
    [0.01, 1000], γ in [1e-4, 10]); ``scale="log"`` searches log10 of both, ``"linear"`` the values
    as they are (the seed's). A generation's points are fitted natively in parallel without the
    GIL, each its folds in turn (those that tell most per unit of work first); a point stops as soon
    as its folds so far exceed its member's memory (it cannot move it), and no (point, fold) is
    fitted twice — neither changes the search (``n_fits`` counts what was fitted). Up to 8 192
    rows, the squared distances are formed once for the search (16 n² bytes, at most 1 GiB) and
    each fit reads them. ``warm_start=True`` starts each fold's solver from the nearest solution
    already found on that fold (within half a decade of C and γ): every solution still meets the
    stopping rule, but its last digits differ from a cold start's, so the search may take another
    path; ``False`` gives the plain search bit for bit; ``None`` (the default) warm-starts only the
    first stage of a thinned search, which only ranks points.

    ``thin`` (an int ``k`` ≥ 1, or ``"auto"``): with ``k`` > 1 the swarm runs on every ``k``-th row
    (rows 0, k, 2k, …; each split keeps its rows among them) and each of its fits takes C·k, so
    that the loss summed over a k-th of the rows weighs as the whole sum; then the 16 best points
    it fitted on every fold are scored on every row, cold, and a compass search on every row
    starts from the best of them (at most 8 rounds of its 4 neighbours, a sixteenth of the box
    first, the step halved when none is better). The point returned carries its CV MSE on every
    row — the objective :func:`svr_cv_mse` gives there (``history`` holds the thinned search's
    values). ``"auto"`` (the default) thins so that the largest training set
    has at most 1 000 rows, and not at all up to that; ``thin=1`` is the plain search on every
    row. Neighbouring rows of a run sampled every few seconds carry nearly the same information,
    so the thinned objective ranks (C, γ) much as the full one does, at a fraction of the cost
    (docs/methods.md has the measurements). A progress bar shows on a terminal unless
    ``progress=False``. Extra keywords go to the swarm (``G``, ``roosters``, ``hens``, ``fl``,
    ``w``, ``c1``, ``c2``, ``vmax_frac``).
    """
    x = as_matrix(X)
    yv = as_vector(y, n=x.shape[0])
    b = {"C": (0.01, 1000.0), "gamma": (1e-4, 10.0)}
    if bounds:
        unknown = set(bounds) - set(b)
        if unknown:
            raise ParameterError(f"bounds has unknown keys {sorted(unknown)} (known: C, gamma)")
        b.update(bounds)
    folds = resolve_cv(cv, x.shape[0], X, cv_kind=cv_kind, gap=gap, seed=seed)
    known = {"G": "g", "roosters": "roosters", "hens": "hens", "fl": "fl", "w": "w", "c1": "c1",
             "c2": "c2", "vmax_frac": "vmax_frac"}
    extra = {}
    for k, v in swarm.items():
        if k not in known:
            raise ParameterError(f"tune_svr got an unknown keyword {k!r}")
        extra[known[k]] = v
    if isinstance(thin, str):
        if thin != "auto":
            raise ParameterError(f"invalid parameter `thin`: must be \"auto\" or an int >= 1, got {thin!r}")
        k_thin: int | None = None
    else:
        k_thin = int(thin)
        if k_thin < 1:
            raise ParameterError(f"invalid parameter `thin`: must be \"auto\" or an int >= 1, got {thin!r}")
    every = int(_core.auto_thin(folds)) if k_thin is None else k_thin
    show = sys.stderr.isatty() if progress is None else progress
    bar: Any = None
    cb = None
    if show:
        from tqdm import tqdm

        desc = f"{method.upper()}-SVR" + (f" on 1 row in {every}" if every > 1 else "")
        bar = tqdm(total=iters + 1, desc=desc, unit="gen")

        def cb(gen: int, best: float) -> None:
            # after a thinned search's last generation its best points are scored on every row
            then = {"then": "scoring the best on every row"} if every > 1 and gen == iters else {}
            bar.set_postfix(cv_mse=f"{best:.4g}", **then, refresh=False)
            bar.update(1)

    try:
        c, g, mse, hist, n, fits, used, inner = _core.tune_svr(
            x, yv, folds, method=method, c_bounds=(float(b["C"][0]), float(b["C"][1])),
            gamma_bounds=(float(b["gamma"][0]), float(b["gamma"][1])), scale=scale, epsilon=float(epsilon),
            tol=float(tol), pop=int(pop), iters=int(iters), seed=int(seed), warm_start=None if warm_start is None else bool(warm_start),
            thin=every, progress=cb, **extra,
        )
    finally:
        if bar is not None:
            bar.close()
    model = SVR._from_core(inner, x.shape[1], C=c, epsilon=epsilon, gamma=g, tol=tol)
    edges = []
    for name, v in (("C", c), ("gamma", g)):
        lo, hi = b[name]
        # on the log scale the edge comes back through 10**log10(bound): equal to ~1e-15
        for bound, side in ((lo, "lower"), (hi, "upper")):
            if abs(v - bound) <= 1e-9 * abs(bound):
                edges.append(f"{name} = {bound:g} ({side} bound)")
    return TuneResult(float(c), float(g), float(mse), np.asarray(hist), int(n), int(fits), model, folds,
                      tuple(edges), int(used))


def svr_cv_mse(X: Any, y: Any, cv: Any = 5, *, C: float, gamma: float, epsilon: float = 0.1,
               tol: float = 1e-3, cv_kind: str = "time", gap: int = 0, seed: int = 0) -> float:
    """Mean over the splits of ``cv`` (as in :func:`tune_svr`; e.g. ``TuneResult.folds``) of the
    held-out MSE of an RBF ε-SVR trained on each split's training set — the objective
    :func:`tune_svr` minimises, and scikit-learn's ``-cross_val_score(SVR(...), X, y, cv=...,
    scoring="neg_mean_squared_error").mean()``."""
    x = as_matrix(X)
    yv = as_vector(y, n=x.shape[0])
    folds = resolve_cv(cv, x.shape[0], X, cv_kind=cv_kind, gap=gap, seed=seed)
    return float(_core.svr_cv_mse(x, yv, folds, c=float(C),
                                  gamma=float(gamma), epsilon=float(epsilon), tol=float(tol)))
