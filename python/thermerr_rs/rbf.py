"""Radial basis function networks (seeds 001 and 003), trained in Rust."""

from __future__ import annotations

from typing import Any

from . import _core
from ._arrays import F64
from .base import Regressor


class RBFNetwork(Regressor):
    """Gaussian hidden layer with MATLAB's ``radbas`` convention, φ(r) = exp(−(0.8326·r/spread)²)
    (φ = 0.5 at r = spread), and a linear output with a bias.

    Parameters
    ----------
    design : ``"exact"`` — MATLAB ``newrbe``: one neuron per training sample, weights solved
        exactly from the bordered interpolation system [Φ 1; 1ᵀ 0][w; b] = [y; 0] (LU; the
        minimum-norm least-squares solution if that is singular), so it interpolates the
        training data (MATLAB's ``/`` picks another of the exact solutions). ``"ols"`` — MATLAB ``newrb``: forward orthogonal least
        squares (Chen, Cowan, Grant 1991), adding the training vector that lowers the
        sum-squared error most, until the error reaches ``goal`` or ``max_neurons``. On at
        most ``max_candidates`` samples every training vector is a candidate (the exhaustive
        newrb search); on more, the candidates are ``max_candidates`` training vectors picked by
        k-means++ (D² sampling, seeded by ``seed``), so a fit costs O(n·m) memory and per
        neuron instead of O(n²), and it adds at most ``max_candidates`` neurons.
        ``"kmeans"`` — k-means centres (k-means++ seeded by ``seed``), least-squares weights.
    spread : width of every neuron, in input units.
    goal : sum-squared-error goal of the ``"ols"`` design (MATLAB's current ``newrb`` takes a
        *mean* squared error: multiply by the number of samples to compare).
    max_neurons : cap of the ``"ols"`` design (default: the number of samples).
    n_centers : centres of the ``"kmeans"`` design (default: min(n, 10)).
    seed : seed of the k-means++ start (``"kmeans"``) and of the candidate pool (``"ols"`` on
        more than ``max_candidates`` samples); ``None`` is 0.
    rule : ``"ols"`` (largest error reduction) or ``"max_error"`` (the training vector with the
        largest current residual, as seed 003's text describes newrb).
    max_candidates : candidate pool of the ``"ols"`` design (default 500): with more training
        samples than this, the candidates are a seeded k-means++ pool of this many samples. Set
        it to at least the number of samples for the exhaustive search (memory n², time n² per
        neuron: minutes and gigabytes at 10 000 samples).

    Fitted attributes: ``centers_``, ``weights_``, ``bias_``, ``n_neurons_``, ``selected_``
    (training indices of the centres, exact/ols), ``sse_history_`` (ols: SSE after the bias and
    after each neuron).
    """

    kind = "rbf"
    _inner: _core.RbfModel | None = None

    def __init__(
        self,
        *,
        design: str = "exact",
        spread: float = 1.0,
        goal: float = 0.0,
        max_neurons: int | None = None,
        n_centers: int | None = None,
        seed: int | None = None,
        rule: str = "ols",
        max_candidates: int = 500,
    ) -> None:
        self.design = design
        self.spread = spread
        self.goal = goal
        self.max_neurons = max_neurons
        self.n_centers = n_centers
        self.seed = seed
        self.rule = rule
        self.max_candidates = max_candidates

    def _fit(self, x: F64, y: F64) -> None:
        self._inner = _core.RbfModel.fit(
            x, y, design=str(self.design), spread=float(self.spread), goal=float(self.goal),
            max_neurons=None if self.max_neurons is None else int(self.max_neurons),
            n_centers=None if self.n_centers is None else int(self.n_centers),
            seed=None if self.seed is None else int(self.seed), rule=str(self.rule),
            max_candidates=int(self.max_candidates),
        )

    def _predict(self, x: F64) -> F64:
        assert self._inner is not None
        return self._inner.predict(x)

    def _get(self, name: str) -> Any:
        self._check_fitted()
        return getattr(self._inner, name)

    centers_ = property(lambda self: self._get("centers"))
    weights_ = property(lambda self: self._get("weights"))
    bias_ = property(lambda self: self._get("bias"))
    selected_ = property(lambda self: self._get("selected"))
    sse_history_ = property(lambda self: self._get("sse_history"))
    n_neurons_ = property(lambda self: int(self._get("centers").shape[0]))


