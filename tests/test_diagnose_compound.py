"""Every pair of the six causes hidden at once (issue 15 point 6), on both topologies and two
seeds: 60 diagnoses of 10 h + 5 h runs at 120 s (tests/test_diagnose_rounds.py's sizes), the
compound matrix of ``benches/diagnose_matrix.py --compound`` (its code, imported from there).

Measured on 2026-11-26 (docs/machine-model.md, "Two effects at once"): both hidden causes named
in 31 of 60 cases, the columns of the hidden causes that have one right in 29 of 40, and a cause
that was not hidden named in 4 of 60 (nonlinear_expansion for a lag with an ambient coupling,
ambient_coupling for speed growth with a source and for a lag with speed growth, speed_growth
for a lag with a nonlinear expansion). Before a sensor drift could be named on its own sensor's
evidence while the error axis got worse (``verdict::DRIFT_OWN_GAIN_PCT``) these were 28, 25
and the same 4. Most misses name one of the two causes, or say
`unexplained` with a remainder, rather than a wrong one.

(It read 31 of 60 the day before, and still does with the previous generator on a CPU whose
OpenBLAS kernel is AVX2: scipy's ``expm`` went through BLAS, whose AVX-512 kernel rounds
differently in the last bit, and three pairs flip on that. The generator now computes without
BLAS, so these runs are the same bits on every CPU, and 28 is the figure.)

Re-measured on 2026-11-27 with three + one candidates calibrated in full per round (four + two
before; docs/machine-model.md, "Fewer full fits"): 33, 32 of 40 and 3, as with four + two since
the simulation's arithmetic was made the same on every CPU; the floors now hold those figures.

Re-measured on 2026-11-28 after the lag took only the node terms (linear and quadratic) in both
the model and the generator (docs/machine-model.md, "The lag is the structure's"): 36, 32 of 40
and 3 (a lag with a nonlinear expansion is named on both machines, a lag with an ambient coupling
on the VMC); the floors hold those figures.

Re-measured on 2026-11-28 after a round with no passing candidate tries its strongest one as a
pair with the best of each other cause (docs/machine-model.md, "Two that pass only together"):
38, 33 of 40 and 3 (a lag with speed growth on the lathe, both seeds; a drifting `T_carriage`
named with a nonlinear expansion, seed 1, where before nothing was). The same day, after the
backward check judges a cause against the better training fit of the rest (its refit or the
round that fitted the same causes): 39, 34 of 40 and 3 (the lathe's room coupling with a source
from `T_hydraulic`, seed 2, where the source was dropped); the floors hold those.

The results are deterministic (seeded runs, deterministic calibration), so the floors below are
the measured figures: a change that names fewer pairs, gets more columns wrong or names more
causes that are not there fails here and must be looked at, not re-measured away.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest


_path = Path(__file__).resolve().parents[1] / "benches" / "diagnose_matrix.py"
_spec = importlib.util.spec_from_file_location("diagnose_matrix", _path)
assert _spec is not None and _spec.loader is not None
dm = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = dm  # its dataclass looks its module up while it is made
_spec.loader.exec_module(dm)

HOURS, DT_S, SEEDS = (10.0, 5.0), 120.0, (1, 2)
BOTH_NAMED_AT_LEAST = 39
COLUMNS_RIGHT_AT_LEAST = 34
NOT_HIDDEN_AT_MOST = 3


@pytest.fixture(scope="module")
def matrix():
    return {(t, p, s): dm.compound_case(t, p, s, HOURS, DT_S)
            for t in ("vmc", "lathe") for p in dm.PAIRS for s in SEEDS}


def _lines(m, keep):
    return "\n".join(f"{t} {'+'.join(p)} {s}: {o.named or o.verdict}" for (t, p, s), o in m.items() if keep(o))


def test_every_pair_is_constructible_and_diagnosed(matrix):
    assert len(matrix) == 2 * 15 * len(SEEDS)


def test_both_causes_named_as_often_as_measured(matrix):
    n = sum(o.both for o in matrix.values())
    assert n >= BOTH_NAMED_AT_LEAST, f"{n}/60 pairs fully named; misses:\n" + _lines(matrix, lambda o: not o.both)


def test_columns_right_as_often_as_measured(matrix):
    ok = sum(o.cols_ok for o in matrix.values())
    n = sum(o.cols_n for o in matrix.values())
    assert n == 40 and ok >= COLUMNS_RIGHT_AT_LEAST, f"{ok}/{n} columns right"


def test_causes_that_are_not_there_are_rare(matrix):
    n = sum(bool(o.extra) for o in matrix.values())
    assert n <= NOT_HIDDEN_AT_MOST, _lines(matrix, lambda o: bool(o.extra))


def test_a_named_pair_lowers_the_held_out_error(matrix):
    """Whenever both are named, the extended model beats the baseline on held-out data."""
    gains = [o.gain for o in matrix.values() if o.both]
    assert gains and min(gains) > 0.0
