"""The machine's lumped thermal network (formats.md "Machine model"): load, simulate, calibrate,
and diagnose what the simulation gets wrong."""

from __future__ import annotations

import json
import os
import sys
import warnings
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from . import _core
from ._arrays import F64
from ._io import write_atomic
from .errors import DataError, SuspectReadingWarning
from .run import Run

#: The baseline network rules ``diagnose(network=...)`` takes (the core's list).
NETWORK_RULES: tuple[str, ...] = tuple(_core.NETWORK_RULES)


def _run_args(run: Run) -> tuple[str, F64, list[str], F64]:
    return run.source, run.time_s, list(run.names), run.matrix(list(run.names))


@dataclass(frozen=True)
class Simulation:
    """Simulated node temperatures (``nodes``: samples × nodes, in ``node_names`` order), sensor
    readings by column and each drift axis by name, on the run's time axis."""

    time_s: F64
    node_names: list[str]
    nodes: F64
    sensors: dict[str, F64]
    drift: dict[str, F64]


class Machine:
    """A machine model: the lumped thermal network and its drift map, read from TOML.

    ``Machine.load(path)`` validates the file (unknown nodes, duplicate names, non-positive
    capacities, negative conductances, a network with a node that reaches neither the ambient nor
    a boundary, ...) and names the file and entry of any problem. ``simulate(run)`` runs it on a
    run's inputs and boundary columns; ``calibrate(run, axis)`` fits it to a run.
    """

    def __init__(self, inner: _core.MachineModel) -> None:
        self._inner = inner

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Machine:
        return cls(_core.MachineModel.load(os.fspath(path)))

    @classmethod
    def from_toml(cls, text: str, file: str = "<string>") -> Machine:
        return cls(_core.MachineModel.from_toml(text, file))

    @classmethod
    def identify(cls, run: Run, axes: str | list[str] | None = None, *, nodes: int | None = None,
                 ambient: str | None = None, inputs: str | list[str] | None = None,
                 train_fraction: float = 0.7, seed: int = 0,
                 max_iter: int = 100, holdout: Run | None = None,
                 progress: bool | None = None) -> tuple[Machine, dict[str, Any]]:
        """Identify a starting network from a run alone (docs/machine-model.md, "Starting from
        data"): pick the ambient, group the other sensors into nodes by fuzzy c-means, place the
        sources, link the nodes by response order, set values from each node's time constant and
        calibrate on the first ``train_fraction`` of the run; then a node no sensor reads (a bed,
        a base) behind the slowest node, kept when it lowers the training fit's BIC and its time
        constant is within the training rows; then a drift of one sensor's reading beside the
        network, kept for the calibration when it is most of the training misfit. A temperature that a first-order lag
        (at most 30 min) of another one reproduces within 3 noise levels is a second sensor on
        that part: a member of its node, not a node. A run with no ``U_*`` input column is
        driven by the temperature that rises most over the ambient, as a boundary node linked to
        the nodes that warm first with it (a note says so; the diagnosis on such a network is
        weaker: docs/machine-model.md, "A run with no input column").

        ``axes``: the error columns to map, the first of which calibrates the network (default
        every ``E_*`` column in the natural order of their names, but a probe that reads one
        value in every row, left out with a note; named, such a probe is a :class:`ShapeError`).
        Temperatures and inputs are taken in the natural order of their names too, so the run's
        column order does not change the network. Returns the machine
        and a summary: ``ambient`` (``column``, ``rule``, ``reason``), ``nodes`` (each with
        ``sensor``, ``members``, ``tau_fit_s``, ``tau_s``, ``heated_by``), ``axes`` (each with
        ``train_rmse_um``, ``holdout_rmse_um`` and ``holdout_uncompensated_um``, the held-out RMS of
        the drift itself), ``copies`` (second sensors on a part: each
        ``column``, the node's sensor ``of``, ``tau_s``, ``gain``, ``noise_ratio``), ``spare``,
        ``links``, ``sources``, ``node_rule``, ``unsensed`` (the node no sensor reads tried behind
        the slowest node: ``name``, ``linked_to``, ``kept`` (when it lowers the training BIC and settles within the training rows),
        ``ssr_without``, ``ssr_with``, ``tau_s``), ``sensor_drift`` (the drift of one sensor's
        reading calibrated beside the network, the best of the sensed nodes': ``node``, ``sensor``,
        ``k_per_h``, ``share`` of the training misfit it removes, ``slowest_tau_s``, ``kept``
        when it removes at least half and the training rows last that time constant; kept, the
        network's values are the ones calibrated beside it, and the file has no drift term),
        ``network_fit`` (which fit of the network's values the file keeps, step 8 of
        docs/machine-model.md: ``with_axis``, the network calibrated with the first axis, and
        ``temperatures``, the one calibrated on the temperatures alone, each the drift maps'
        blocked-fold squared error over the probes' squares summed over the axes; ``kept``,
        ``"axis"`` or ``"temperatures"``, the lower; ``None`` with one axis), ``suspect_readings`` (readings the run itself
        makes suspect, as in a diagnosis's report; also warned as
        :class:`~thermerr_rs.errors.SuspectReadingWarning`) and
        ``toml``, the file with a comment on every choice (what ``thermerr init`` writes), and
        ``stage_s``, the wall time of each stage in seconds (``screening``, ``structure``,
        ``calibration_and_checks``, ``drift_maps``), in the order they ran.
        ``progress``: a bar of the stages done (default: when stderr is a terminal).
        ``inputs``: the ``U_*`` columns that heat the machine (default every one; a column that
        heats nothing, a program number or a tool number, would be given heat sources all the
        same, since a run's temperatures cannot tell it from a heat source that moves with the
        spindle: name the real ones).
        ``holdout``: a separate run to hold out (the same machine, another day): every row of
        ``run`` trains (``train_fraction`` is not used), and the held-out figures are of
        ``holdout``, simulated from its own first readings; the summary's ``holdout_run`` names it
        (``None``: the held-out rows are the last ``1 - train_fraction`` of ``run``). A
        ``holdout`` that continues ``run`` (its clock goes on from ``run``'s last sample: a log cut
        in two) is joined to it and held out as its tail, as :func:`diagnose` does.
        Bad input (no ``T_*`` column, no ``E_*`` axis, an unknown ``ambient`` or input, more ``nodes``
        than sensors, a ``holdout`` without a column the network reads) raises a :class:`~thermerr_rs.errors.DataError` naming the run and the entry.
        """
        ax = [axes] if isinstance(axes, str) else (list(axes) if axes is not None else None)
        ins = [inputs] if isinstance(inputs, str) else (list(inputs) if inputs is not None else None)
        run, holdout, train_rows = _joined(run, holdout)
        with _progress_bar(progress, "identification", unit="stage", stage_word="stage") as cb:
            inner, summary = _core.MachineModel.identify(*_run_args(run),
                                                         _run_args(holdout) if holdout is not None else None,
                                                         axes=ax, nodes=nodes, ambient=ambient,
                                                         inputs=ins, train_fraction=train_fraction,
                                                         train_rows=train_rows, seed=seed,
                                                         max_iter=max_iter, progress=cb)
        s: dict[str, Any] = json.loads(summary)
        _warn_suspects(sp["text"] for sp in s["suspect_readings"])
        return cls(inner), s

    def to_toml(self) -> str:
        return self._inner.to_toml()

    @property
    def fitted_start(self) -> dict[str, float]:
        """The start the machine's figures are from (``thermerr init``: zero, the first readings,
        as any run starts; ``calibrate`` and a diagnosis's TOMLs: the start their fit ended at):
        K added to each node's first reading, on the run named in the file's ``[start]`` table
        (``to_dict()["start"]["run"]``). Another run starts from its own readings. Raises :class:`DataError` for a machine
        without one (written by hand, or by an older version)."""
        start = (self.to_dict().get("start") or {}).get("initial_k")
        if start is None:
            raise DataError(f"machine {self.name!r} has no fitted start (no [start] table): its values "
                            "were not fitted by thermerr init, calibrate or diagnose")
        return {str(k): float(v) for k, v in start.items()}

    def to_dict(self) -> dict[str, Any]:
        """The machine's fields as plain data, with the TOML's structure (docs/formats.md):
        ``name``, ``ambient``, ``nodes``, ``links``, ``sources``, ``drift`` and, for a network
        identified from data, ``identified``."""
        out: dict[str, Any] = json.loads(self._inner.to_json())
        return out

    def save(self, path: str | os.PathLike[str]) -> Path:
        return write_atomic(path, self.to_toml())

    @property
    def name(self) -> str:
        return self._inner.name

    @property
    def nodes(self) -> list[str]:
        return self._inner.nodes

    @property
    def axes(self) -> list[str]:
        return self._inner.axes

    @property
    def sensors(self) -> list[str]:
        return self._inner.sensors

    def columns(self) -> list[str]:
        """Every run column the machine reads."""
        return self._inner.columns()

    def simulate(self, run: Run, *, fit_initial: int = 0,
                 initial_k: dict[str, float] | Literal["fitted"] | None = None,
                 after: Run | None = None) -> Simulation:
        """Simulate ``run`` from its inputs and boundary columns. ``fit_initial=N`` estimates the
        sensed nodes' initial temperatures from the first N readings (least squares) instead of
        taking the first reading as it is; ``initial_k`` gives the start instead, K added to each
        named node's start (a diagnosis report's ``baseline.initial_k`` reproduces its figures);
        ``"fitted"``: the start the file's values were fitted from (:attr:`fitted_start`), for
        the run it names.

        ``after``: ``run`` is a later piece of a log whose earlier rows are ``after``. The network
        starts from ``after``'s first readings and runs on through the join
        (:meth:`Run.following`), so the drift is relative to the log's start, as the piece's
        measured error is; the result holds ``run``'s rows only. Without it the network starts
        from ``run``'s own first readings, with zero drift there."""
        whole = run if after is None else run.following(after)
        if initial_k == "fitted":
            initial_k = self.fitted_start
        d = self._inner.simulate(*_run_args(whole), fit_initial=int(fit_initial),
                                 initial_k=None if initial_k is None else {str(k): float(v) for k, v in initial_k.items()})
        if after is None:
            return Simulation(run.time_s, d["node_names"], d["nodes"], d["sensors"], d["drift"])
        k = len(whole) - len(run)
        return Simulation(run.time_s, d["node_names"], d["nodes"][k:],
                          {c: v[k:] for c, v in d["sensors"].items()}, {a: v[k:] for a, v in d["drift"].items()})

    def calibrate(self, run: Run, axis: str | None = None, *, bound_factor: float = 3.0,
                  max_iter: int = 60) -> tuple[Machine, dict[str, Any]]:
        """Fit capacities, conductances, sources and drift coefficients to ``run``; returns the
        calibrated machine (its fitted start in its ``[start]`` table) and a dict of fit figures:
        ``sigma_t``, ``sigma_e``, ``ssr``, ``n_data``, ``n_params``, ``bic``, ``n_iter``,
        ``converged``, ``init_offsets``, ``axis``, and the axis's RMS (µm, over the rows its
        probe reads) from the fitted start, ``rmse_um``, and from the first readings as they
        are, ``first_reading_rmse_um``."""
        ax = axis or self.axes[0]
        inner, info = self._inner.calibrate(*_run_args(run), axis=ax, bound_factor=bound_factor, max_iter=max_iter)
        return Machine(inner), info

    def __repr__(self) -> str:
        return f"Machine({self.name!r}, nodes={self.nodes}, axes={self.axes})"


@dataclass
class Diagnosis:
    """The outcome of :func:`diagnose`: ``verdict`` (the first named cause, ``"none"`` or
    ``"unexplained"``), ``column``, ``evidence``, held-out figures of the ``baseline`` and
    ``extended`` models, ``gain_pct``, round 1's ``candidates`` with their scores, and the
    ``calibrated``/``extended`` machines.

    Several effects at once: ``causes`` lists every named cause in the order the rounds accepted
    it (``cause``, ``column``, ``node``, ``axis``, ``gain_pct`` of its round, ``params`` in the
    final model, ``round``, ``rmse_um`` after its round); ``rounds`` what each round tried;
    ``remainder_um`` the held-out RMS above the probe noise that the final model leaves
    unexplained (0 when within ``noise_ratio`` noise levels). ``extended`` is the model with every
    named cause."""

    report: dict[str, Any]
    series: dict[str, Any]
    calibrated: Machine
    extended: Machine
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def axis(self) -> str:
        return str(self.report["axis"])

    @property
    def verdict(self) -> str:
        return str(self.report["verdict"])

    @property
    def column(self) -> str | None:
        return self.report["column"]

    @property
    def evidence(self) -> str:
        return str(self.report["evidence"])

    @property
    def gain_pct(self) -> float:
        return float(self.report["gain_pct"])

    @property
    def candidates(self) -> list[dict[str, Any]]:
        return list(self.report["candidates"])

    @property
    def causes(self) -> list[dict[str, Any]]:
        """Every named cause in the order accepted (empty for ``none`` and ``unexplained``), each
        with ``alternatives``: the other columns whose candidate of the same cause passed the same
        round's rule and held the axis out within 5 % of it or better (the run does not tell
        them apart)."""
        return list(self.report["causes"])

    @property
    def rounds(self) -> list[dict[str, Any]]:
        return list(self.report["rounds"])

    @property
    def remainder_um(self) -> float:
        """Held-out RMS above the probe noise that no named cause explains (µm), 0 if none."""
        return float(self.report["remainder_um"])

    def write(self, out_dir: str | os.PathLike[str]) -> Path:
        """Write report.json, calibrated.toml, extended.toml and report.html into ``out_dir``."""
        from .report import write_report

        return write_report(out_dir, self.report, self.series, self.calibrated.to_toml(), self.extended.to_toml(),
                            self.extended.to_dict())

    def __str__(self) -> str:
        return (self._text() + _suspect_lines(self.report.get("suspect_readings", []))
                + (_identified_line((self.report.get("identification") or {}).get("driven_by"))
                   if self.report.get("identified") else ""))

    @property
    def baseline_unique(self) -> bool:
        """False when the baseline is recalibrated and either start of its calibration (the file's
        values, and every network parameter 25 % off them) stopped at the iteration limit, or the
        second start fits the training rows as well (within 5 %) or better and holds out
        differently (``report["baseline_network"]["second_start"]``); True otherwise, and for a
        kept or shared network (one solution)."""
        bn = self.report["baseline_network"]
        return bn["network"] != "recalibrated" or bool(bn.get("second_start", {}).get("unique", True))

    def _text(self) -> str:
        from .report import cause_label

        b, e = self.report["baseline"], self.report["extended"]
        head = cause_label(self.causes[0], "column ") if self.column and self.causes else self.verdict
        more = ""
        if len(self.causes) > 1:
            more += "causes: " + ", ".join(cause_label(c) for c in self.causes) + "\n"
        if self.causes and self.remainder_um > 0:
            more += f"unexplained remainder: {self.remainder_um:.3f} µm RMS above the probe noise\n"
        return (f"verdict: {head}\n{self.evidence}\n{more}"
                f"held-out RMS: baseline {b['rmse_um']:.3f} µm, extended {e['rmse_um']:.3f} µm, gain {self.gain_pct:.1f} %")


def _unique_suspects(lists: Iterable[list[dict[str, Any]]]) -> list[dict[str, Any]]:
    """The suspect readings of several reports, each once (every axis scans the same
    temperatures), in the order first seen."""
    seen: dict[str, dict[str, Any]] = {}
    for items in lists:
        for sp in items:
            seen.setdefault(sp["text"], sp)
    return list(seen.values())


def _suspect_lines(items: list[dict[str, Any]]) -> str:
    return "".join(f"\nwarning: {sp['text']}" for sp in items)


def _warn_suspects(texts: Iterable[str]) -> None:
    for t in texts:
        warnings.warn(t, SuspectReadingWarning, stacklevel=3)


def _identified_line(driven_by: str | None = None) -> str:
    from .report import identified_caveat

    return f"\nnote: the network was identified from data (thermerr init), {identified_caveat(driven_by)}"


@contextmanager
def _progress_bar(show: bool | None, desc: str, unit: str = "fit",
                  stage_word: str = "round") -> Iterator[Callable[[int, int, int], None] | None]:
    """A tqdm bar of the work a long call has done out of that planned so far (a diagnosis's
    calibrations: the plan grows when a round starts; an identification's stages), with the
    round or stage reached; shown on a terminal (``show=None``: when stderr is one), and closed
    however the call ends."""
    if not (sys.stderr.isatty() if show is None else show):
        yield None
        return
    from tqdm import tqdm

    bar = tqdm(total=0, desc=desc, unit=unit, leave=False)

    def update(done: int, planned: int, stage: int) -> None:
        bar.total = planned
        bar.n = done
        bar.set_description(f"{desc}, {stage_word} {stage}" if stage else desc, refresh=False)
        bar.refresh()

    try:
        yield update
    finally:
        bar.close()


def _joined(run: Run, holdout: Run | None) -> tuple[Run, Run | None, int | None]:
    """A held-out run that continues ``run`` (cut from the same log, :meth:`Run.continues`): its
    errors and temperatures go on from ``run``'s start, so it is joined to ``run``
    (:meth:`Run.following`) and held out from ``len(run)`` on, as the tail of one run is; the
    model runs on through the join from the training run's start. As a separate run its first
    readings would be taken for a start, and its error, relative to the log's start, would look
    like tens of µm of drift. Anything else is returned as given; a ``holdout`` holding a
    stretch of ``run``'s rows, or rows taken from its log in turn, is refused
    (:meth:`Run.check_unseen`: its "held-out" figures would be the training fit's)."""
    if holdout is not None:
        holdout.check_unseen(run)
    if holdout is None or not holdout.continues(run):
        return run, holdout, None
    return holdout.following(run), None, len(run)


def diagnose(run: Run, machine: Machine, holdout: Run | None = None, *, axis: str | None = None,
             holdout_fraction: float = 0.3, min_score: float = 0.1, noise_ratio: float = 2.0,
             network: str = "auto", progress: bool | None = None) -> Diagnosis:
    """Calibrate ``machine`` on ``run`` (its first 70 % when no ``holdout`` run is given), fit the
    extension of every catalogued cause, score all on the held-out data and name the cause; then
    go on in rounds on the extended machine while a further cause passes (docs/machine-model.md).

    Every figure in the result is on held-out data: the ``holdout`` run, or the last
    ``holdout_fraction`` of ``run``. A ``holdout`` run that continues ``run`` (its clock goes on
    from ``run``'s last sample: a log cut in two) is joined to it and held out as its tail, the
    model running on from ``run``'s start. ``network``: the baseline's thermal network —
    ``"auto"`` (default: as ``"recalibrate"``, except that a network identified from data
    (:meth:`Machine.identify`, ``thermerr init``) is kept when its recalibration is not unique:
    a start stops at the iteration limit, or a second start fits the training rows as well and
    holds out differently),
    ``"recalibrate"`` (every capacity, conductance and source fitted on the training rows
    and this axis, from the file's values and from a second start 25 % off them;
    ``report["baseline_network"]["second_start"]`` says whether the second start ends elsewhere,
    and ``taken`` when it fits the training rows better by more than 5 % and so is the
    baseline), ``"keep"`` (the machine's network as given, only the initial offsets and the
    drift map fitted: a network identified from this very run, or one you trust), ``"best"``
    (both, and the one with the smaller held-out residual of the error and the temperatures
    together, noise-normalised; ``report["baseline_network"]`` gives
    both held-out RMS) or ``"shared"`` (the machine's one network, calibrated on the training
    rows and the temperatures alone, then kept with this axis's start and drift map fitted).
    Candidates still refit the network with their extension.
    ``progress``: a bar of the calibrations done (default: when stderr is a terminal).
    """
    run, holdout, train_rows = _joined(run, holdout)
    with _progress_bar(progress, "diagnosis") as cb:
        d = machine._inner.diagnose(*_run_args(run), _run_args(holdout) if holdout is not None else None,
                                    axis=axis, holdout_fraction=holdout_fraction, train_rows=train_rows,
                                    min_score=min_score, noise_ratio=noise_ratio, network=network, progress=cb)
    out = _diagnosis(d)
    _warn_suspects(sp["text"] for sp in out.report.get("suspect_readings", []))
    return out


def _diagnosis(d: dict[str, Any]) -> Diagnosis:
    cal = Machine(_core.MachineModel.from_toml(d["calibrated_toml"], "calibrated.toml"))
    ext = Machine(_core.MachineModel.from_toml(d["extended_toml"], "extended.toml"))
    return Diagnosis(json.loads(d["report"]), d["series"], cal, ext, {"calibration": d["calibration"]})


@dataclass
class AxesDiagnosis:
    """The outcome of :func:`diagnose_axes`: one :class:`Diagnosis` per error axis (``by_axis``,
    in the order diagnosed; ``d["E_y"]`` is one of them). ``report`` is the summary written as
    report.json: every axis's verdict, causes (each with its ``axis``), gain and remainder.
    ``skipped``: the axes left out, each with the one line that says why (every axis diagnosed
    by default, and a probe dead throughout or failing over the held-out rows: nothing to
    diagnose there); report.json's ``"skipped"``."""

    by_axis: dict[str, Diagnosis]
    run: str
    machine: str
    skipped: dict[str, str] = field(default_factory=dict)

    def __getitem__(self, axis: str) -> Diagnosis:
        return self.by_axis[axis]

    @property
    def axes(self) -> list[str]:
        return list(self.by_axis)

    @property
    def causes(self) -> list[dict[str, Any]]:
        """Every named cause of every axis, axis by axis, each in its axis's order of acceptance."""
        return [c for d in self.by_axis.values() for c in d.causes]

    @property
    def report(self) -> dict[str, Any]:
        return {
            "axes": self.axes,
            "run": self.run,
            "machine": self.machine,
            "verdicts": {a: d.verdict for a, d in self.by_axis.items()},
            "causes": self.causes,
            "gain_pct": {a: d.gain_pct for a, d in self.by_axis.items()},
            "remainder_um": {a: d.remainder_um for a, d in self.by_axis.items()},
            "baseline_rmse_um": {a: d.report["baseline"]["rmse_um"] for a, d in self.by_axis.items()},
            "baseline_network": {a: d.report["baseline_network"]["network"] for a, d in self.by_axis.items()},
            "baseline_unique": {a: d.baseline_unique for a, d in self.by_axis.items()},
            "extended_rmse_um": {a: d.report["extended"]["rmse_um"] for a, d in self.by_axis.items()},
            "reports": {a: f"{a}.report.json" for a in self.by_axis},
            "identified": any(d.report["identified"] for d in self.by_axis.values()),
            # the run the network was identified from had no input column: the driving temperature
            "driven_by": next((d.report["identification"].get("driven_by") for d in self.by_axis.values()
                               if d.report.get("identification")), None),
            "suspect_readings": _unique_suspects(d.report.get("suspect_readings", []) for d in self.by_axis.values()),
            "skipped": dict(self.skipped),
        }

    def write(self, out_dir: str | os.PathLike[str]) -> Path:
        """Write the summary (report.json, report.html) and, per axis, ``<axis>.report.json``,
        ``<axis>.report.html``, ``<axis>.calibrated.toml`` and ``<axis>.extended.toml`` into
        ``out_dir``, as one set (all or nothing)."""
        from .report import write_axes_report

        return write_axes_report(out_dir, self.report, {
            a: (d.report, d.series, d.calibrated.to_toml(), d.extended.to_toml(), d.extended.to_dict())
            for a, d in self.by_axis.items()
        })

    def __str__(self) -> str:
        text = "\n\n".join(f"== {a} ==\n{d._text()}" for a, d in self.by_axis.items())
        moved = [a for a, d in self.by_axis.items() if not d.baseline_unique]
        if moved:
            text += (f"\nnote: the recalibrated baseline is not unique on {', '.join(moved)}: a start stopped at "
                     "the iteration limit, or from a second start it fits the training rows as well (within 5 %) or "
                     "better and holds out differently (see each axis's evidence); --network best or keep gives a "
                     "baseline with one solution")
        text += "".join(f"\nwarning: {a} not diagnosed: {why}" for a, why in self.skipped.items())
        return (text + _suspect_lines(self.report["suspect_readings"])
                + (_identified_line(self.report["driven_by"]) if self.report["identified"] else ""))


def diagnose_axes(run: Run, machine: Machine, holdout: Run | None = None, *, axes: list[str] | None = None,
                  holdout_fraction: float = 0.3, min_score: float = 0.1,
                  noise_ratio: float = 2.0, network: str = "auto",
                  progress: bool | None = None) -> AxesDiagnosis:
    """:func:`diagnose` for several error axes at once (default: every drift entry of the
    machine), in parallel. Each axis is diagnosed on the shared temperatures and its own error
    column, with its own calibration of the network and its own causes and remainder.
    ``network``: as for :func:`diagnose`, per axis; under ``"shared"`` the one network is
    calibrated once (on the temperatures alone) and every axis keeps it.
    ``progress``: one bar of every axis's calibrations (default: when stderr is a terminal).
    A ``holdout`` that continues ``run`` is joined to it, as for :func:`diagnose`.
    With ``axes`` not given, an axis whose probe gives nothing to diagnose on this run (one value
    in every row; fewer than 10 held-out rows that can be scored, the probe, the room or a
    boundary failing over the rest) is left out with a :class:`SuspectReadingWarning` and listed
    in ``skipped``, and the other axes are diagnosed; it is a :class:`ShapeError` only when no
    axis is left. An axis named in ``axes`` is diagnosed or refused (:class:`ShapeError`)."""
    run, holdout, train_rows = _joined(run, holdout)
    with _progress_bar(progress, "diagnosis of the axes") as cb:
        ds, skipped = machine._inner.diagnose_axes(*_run_args(run), _run_args(holdout) if holdout is not None else None,
                                          axes=list(axes or []), holdout_fraction=holdout_fraction,
                                          train_rows=train_rows, min_score=min_score, noise_ratio=noise_ratio,
                                          network=network, progress=cb)
    out = {d.axis: d for d in map(_diagnosis, ds)}
    res = AxesDiagnosis(out, run.source, machine._inner.file, dict(skipped))
    _warn_suspects(sp["text"] for sp in res.report["suspect_readings"])
    _warn_suspects(f"{a} not diagnosed: {why}" for a, why in skipped)
    return res
