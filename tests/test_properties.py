"""Property-based tests (hypothesis) of the readers and the static estimators.

The readers' promise: any input gives a valid result or a :class:`thermerr_rs.ThermerrError`
subclass naming what is wrong, never another exception. The estimators': finite predictions of
the right shape, independent of the order of the training rows, linear in the target (MLR).

The Rust side has matching ``cargo fuzz`` targets (``fuzz/``, run by ``.ci/fuzz``); see
docs/testing.md.
"""

from __future__ import annotations

import copy
import json
import math
import os
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, assume, example, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra import numpy as hnp  # noqa: E402
from sklearn.exceptions import ConvergenceWarning  # noqa: E402

import thermerr_rs as tr  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "tests" / "fixtures"
EXAMPLES = ROOT / "examples"

# The whole file runs in well under a minute on a 2-core machine; THERMERR_PROPERTY_SCALE=N runs
# N times as many examples (a deeper search, e.g. before a release).
_SCALE = max(1, int(os.environ.get("THERMERR_PROPERTY_SCALE", "1")))
FAST = settings(max_examples=60 * _SCALE, deadline=None, suppress_health_check=[HealthCheck.too_slow])
SLOW = settings(max_examples=25 * _SCALE, deadline=None, suppress_health_check=[HealthCheck.too_slow])

_TMP = tempfile.TemporaryDirectory(prefix="thermerr-properties-")


def _tmp_file(name: str, content: str | bytes) -> Path:
    """A file in a directory of this module's (hypothesis runs many examples per test, so the
    function-scoped ``tmp_path`` is not an option)."""
    p = Path(_TMP.name) / name
    if isinstance(content, bytes):
        p.write_bytes(content)
    else:
        p.write_text(content, encoding="utf-8")
    return p


# -- (a) read_run on generated CSV text ------------------------------------------------------

COLUMN_NAMES = ["time_s", "T_a", "T_b", "E_x", "E_z", "U_rpm", "note", "T_", "E_"]

# a cell: its text and the number the reader should make of it (None: not a number)
_GOOD_NUMBERS = st.one_of(
    st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False),
    st.sampled_from([0.0, -0.0, 1e308, -1e308, 1.7976931348623157e308, -1.7976931348623157e308, 5e-324]),
    st.integers(min_value=-10**6, max_value=10**6).map(float),
)


def _number_text(v: float) -> st.SearchStrategy[str]:
    r = repr(v)
    variants = [r, f" {r} ", f'"{r}"']
    if v == int(v) and abs(v) < 1e15:
        variants.append(str(int(v)))
    return st.sampled_from(variants)


_CELLS: st.SearchStrategy[tuple[str, float | None]] = st.one_of(
    _GOOD_NUMBERS.flatmap(lambda v: _number_text(v).map(lambda t: (t, v))),
    st.sampled_from([("NaN", math.nan), ("nan", math.nan), ("", math.nan), ('""', math.nan)]),
    st.sampled_from([("abc", None), ("inf", None), ("-inf", None), ("1e400", None), ("1,5", None),
                     ("0x10", None), ("1_000", None), ("--1", None), ('"1', None), ("\u00b5", None)]),
)


@st.composite
def csv_texts(draw: Any) -> tuple[str, list[str], list[list[tuple[str, float | None]]]]:
    names = draw(st.lists(st.sampled_from(COLUMN_NAMES), min_size=1, max_size=5))
    if draw(st.booleans()) and "time_s" not in names:
        names.insert(0, "time_s")
    n = draw(st.integers(min_value=0, max_value=8))
    rows = []
    t = draw(st.floats(min_value=-1e3, max_value=1e3, allow_nan=False))
    for _ in range(n):
        row = [draw(_CELLS) for _ in names]
        if "time_s" in names and draw(st.integers(0, 9)) < 8:  # mostly a good, increasing time
            t += draw(st.floats(min_value=0.5, max_value=100.0))
            row[names.index("time_s")] = (repr(t), t)
        rows.append(row)
    lines = [",".join(names)]
    for row in rows:
        if draw(st.integers(0, 9)) == 0:
            lines.append("")  # empty lines are skipped
        lines.append(",".join(text for text, _ in row))
    # a row of one empty cell is an empty line, which is no row at all
    rows = [row for row in rows if ",".join(text for text, _ in row) != ""]
    return "\n".join(lines) + draw(st.sampled_from(["", "\n", "\r\n"])), names, rows


def _read(text: str, nan: str) -> tr.Run | BaseException:
    p = _tmp_file("run.csv", text)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # columns without a prefix
            return tr.read_run(p, nan=nan)  # type: ignore[arg-type]
    except tr.ThermerrError as e:
        assert str(e), "a refusal says what is wrong"
        return e


def _is_data(name: str) -> bool:
    return any(name.startswith(p) and len(name) > len(p) for p in ("T_", "E_", "U_"))


@FAST
@given(csv_texts(), st.sampled_from(["error", "drop", "interpolate"]))
# found by the csv_run fuzz target: the gap between ±1e308 was filled with -inf (fixed in the
# core's interpolation; an extension built before that fix fails here)
@example(("time_s,T_a\n0,1e308\n1,\n2,-1e308\n", ["time_s", "T_a"],
          [[("0", 0.0), ("1e308", 1e308)], [("1", 1.0), ("", math.nan)], [("2", 2.0), ("-1e308", -1e308)]]),
         "interpolate")
# found here (2026-11-28): a quote never closed ran to the end of the file, and the reader
# returned the rows before it, or read the cell as the number after the quote
@example(('time_s,note\n\n1.0,0.0\n\n2.0,0.0\n\n4.0,"1\n\n5.0,0.0', ["time_s", "note"],
          [[("1.0", 1.0), ("0.0", None)], [("2.0", 2.0), ("0.0", None)], [("4.0", 4.0), ('"1', None)],
           [("5.0", 5.0), ("0.0", None)]]), "error")
@example(('time_s,T_a\n\n1.0,"1', ["time_s", "T_a"], [[("1.0", 1.0), ('"1', None)]]), "error")
def test_read_run_returns_the_numbers_or_refuses(case: Any, nan: str) -> None:
    text, names, rows = case
    got = _read(text, nan)
    if isinstance(got, BaseException):
        return
    run = got
    # what was accepted is what the file says
    assert "time_s" in names and len(set(names)) == len(names)
    assert run.names == [n for n in names if _is_data(n)]
    assert all(v is not None for row in rows for k, (_, v) in enumerate(row)
               if names[k] == "time_s" or _is_data(names[k])), "a non-number was accepted"
    t_col = names.index("time_s")
    keep = [i for i in range(len(rows)) if i + 1 not in run.dropped_rows]
    assert len(run) == len(keep) > 0
    np.testing.assert_array_equal(run.time_s, [rows[i][t_col][1] for i in keep])
    assert np.all(np.diff(run.time_s) > 0)
    for name in run.names:
        col = run[name]
        assert col.shape == (len(run),) and col.dtype == np.float64
        assert np.all(np.isfinite(col)), f"{nan}: {name} = {col}"
        want = np.array([rows[i][names.index(name)][1] for i in keep], dtype=np.float64)
        known = ~np.isnan(want)
        np.testing.assert_array_equal(col[known], want[known])
        if nan != "interpolate":
            assert known.all()
        elif known.any():  # a filled value lies between the values around it
            assert np.all(col >= want[known].min()) and np.all(col <= want[known].max())


@FAST
@given(
    st.lists(st.sampled_from(["T_a", "T_b", "E_x", "U_rpm"]), min_size=1, max_size=4, unique=True),
    st.lists(st.floats(min_value=0.001, max_value=1e3), min_size=1, max_size=10),
    st.data(),
)
def test_read_run_reads_every_good_file(cols: list[str], steps: list[float], data: Any) -> None:
    """A well-formed file is always read, to the exact numbers written."""
    t = np.cumsum(steps)
    values = data.draw(hnp.arrays(np.float64, (len(t), len(cols)),
                                  elements=st.floats(min_value=-1e12, max_value=1e12)))  # MAX_ABS_VALUE
    lines = [",".join(["time_s", *cols])]
    for i in range(len(t)):
        lines.append(",".join([repr(float(t[i]))] + [repr(float(v)) for v in values[i]]))
    run = _read("\n".join(lines) + "\n", "error")
    assert isinstance(run, tr.Run), run
    np.testing.assert_array_equal(run.time_s, t)
    for k, c in enumerate(cols):
        np.testing.assert_array_equal(run[c], values[:, k])


@FAST
@given(st.binary(max_size=300))
def test_read_run_on_any_bytes(raw: bytes) -> None:
    p = _tmp_file("bytes.csv", raw)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            tr.read_run(p, nan="interpolate")
    except tr.ThermerrError:
        pass


# -- (b) load_model on mutated model files ---------------------------------------------------

FEATURES = ["T_s01", "T_s07", "T_s10", "T_s13"]


@pytest.fixture(scope="module")
def small_run() -> tr.Run:
    return tr.read_run(FIXTURES / "run_60.csv").slice(0, 30)


@pytest.fixture(scope="module")
def saved_models(small_run: tr.Run) -> dict[str, dict[str, Any]]:
    """The JSON of real model files: MLR, RBF and SVR fitted on a small example run."""
    out = {}
    for name, est in [("mlr", tr.MLR()), ("rbf", tr.RBFNetwork(spread=5.0)), ("svr", tr.SVR(C=10.0))]:
        est.fit_run(small_run, "E_z", FEATURES)
        p = est.save(Path(_TMP.name) / f"{name}.json")
        out[name] = json.loads(p.read_text())
    return out


def _leaves(doc: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Paths of every value in the document (containers included, so a whole list or object can
    be replaced or deleted)."""
    out = [path] if path else []
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _leaves(v, (*path, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc[:6]):  # a few items of each list are enough
            out += _leaves(v, (*path, i))
    return out


_REPLACEMENTS = st.one_of(
    st.sampled_from([1e308, -1e308, 0, -1, -1.5, 2**63, "NaN", "inf", "", None, True, [], {}, [1.0], [[1.0]]]),
    st.floats(allow_nan=False, allow_infinity=False),
    st.integers(min_value=-10**20, max_value=10**20),
    st.text(max_size=5),
)


def _mutate(doc: Any, path: tuple[Any, ...], how: str, new: Any) -> None:
    parent = doc
    for k in path[:-1]:
        parent = parent[k]
    key = path[-1]
    old = parent[key]
    if how == "delete":
        del parent[key]
    elif how == "shorten" and isinstance(old, list):
        parent[key] = old[:-1]
    elif how == "lengthen" and isinstance(old, list):
        parent[key] = old + old[-1:] if old else [0.0]
    elif how == "scale" and isinstance(old, (int, float)) and not isinstance(old, bool):
        parent[key] = old * 1e300
    else:
        parent[key] = new


@SLOW
@given(
    kind=st.sampled_from(["mlr", "rbf", "svr"]),
    mutations=st.lists(st.tuples(st.integers(min_value=0), st.sampled_from(["replace", "delete", "shorten",
                                                                             "lengthen", "scale"]),
                                 _REPLACEMENTS), min_size=1, max_size=3),
)
def test_load_model_on_mutated_files(saved_models: dict[str, Any], small_run: tr.Run, kind: str,
                                     mutations: list[Any]) -> None:
    doc = copy.deepcopy(saved_models[kind])
    for pick, how, new in mutations:
        paths = _leaves(doc)
        if not paths:
            break
        _mutate(doc, paths[pick % len(paths)], how, new)
    p = _tmp_file("model.json", json.dumps(doc))
    try:
        model = tr.load_model(p)
    except tr.ThermerrError as e:
        assert str(e)
        return
    try:
        y = model.predict_run(small_run)  # the columns and input form the file names
    except tr.ThermerrError as e:
        assert str(e)
        return
    assert y.shape == (len(small_run),)
    assert np.all(np.isfinite(y)), f"a loaded {kind} model predicts {y[~np.isfinite(y)][:3]}"


def test_a_model_whose_prediction_overflows_raises(saved_models: dict[str, Any], small_run: tr.Run) -> None:
    """Found by test_load_model_on_mutated_files (a coefficient scaled by 1e300): the file loads,
    and its predictions overflowed to inf with no error. The core now refuses a non-finite
    prediction with a NumericalError naming the model (an extension built before that fix fails
    here)."""
    doc = copy.deepcopy(saved_models["mlr"])
    doc["model"]["coef"] = [1e308] * len(doc["model"]["coef"])
    model = tr.load_model(_tmp_file("overflow.json", json.dumps(doc)))
    with pytest.raises(tr.NumericalError, match="mlr model: the prediction for sample 0 is not a finite"):
        model.predict_run(small_run)


@FAST
@given(st.text(max_size=400))
def test_load_model_on_any_text(text: str) -> None:
    p = _tmp_file("any.json", text)
    try:
        tr.load_model(p)
    except tr.ThermerrError:
        pass


# -- (c) Machine.from_toml on mutated machine files ------------------------------------------

MACHINES = sorted(EXAMPLES.glob("*.toml"))
_TOML_VALUES = st.sampled_from(["1e308", "-1e308", "0", "-1", "-0.0", "nan", "inf", "-inf", '"x"', '""',
                                "[]", "[1.0]", '["a", "a"]', "true", "{}", "1979-05-27", "'T_a'",
                                "9223372036854775807", "1e-320"])


@SLOW
@given(
    machine=st.sampled_from(MACHINES),
    mutations=st.lists(st.tuples(st.integers(min_value=0), st.sampled_from(["value", "delete", "duplicate",
                                                                             "rename"]),
                                 _TOML_VALUES), min_size=1, max_size=3),
)
def test_machine_from_toml_on_mutated_text(machine: Path, mutations: list[Any]) -> None:
    lines = machine.read_text().splitlines()
    for pick, how, value in mutations:
        k = pick % len(lines)
        line = lines[k]
        if how == "delete":
            del lines[k]
        elif how == "duplicate":
            lines.insert(k, line)
        elif "=" in line and how == "value":
            lines[k] = line.split("=", 1)[0] + "= " + value
        elif "=" in line and how == "rename":
            lines[k] = "renamed_" + line.lstrip()
        if not lines:
            break
    text = "\n".join(lines) + "\n"
    try:
        m = tr.Machine.from_toml(text, "mutated.toml")
    except tr.ThermerrError as e:
        assert str(e).startswith("mutated.toml"), str(e)
        return
    # what loads writes back and loads back the same
    back = m.to_toml()
    again = tr.Machine.from_toml(back, "written-back.toml")
    assert again.to_toml() == back
    assert m.nodes and all(isinstance(n, str) for n in m.nodes)


@FAST
@given(st.text(max_size=300))
def test_machine_from_any_text(text: str) -> None:
    try:
        tr.Machine.from_toml(text, "any.toml")
    except tr.ThermerrError:
        pass


# -- (d) estimators ------------------------------------------------------------------------

_ELEMENTS = st.floats(min_value=-100, max_value=100, allow_nan=False, allow_subnormal=False)


@st.composite
def xy(draw: Any, min_rows: int = 4) -> tuple[np.ndarray, np.ndarray]:
    n = draw(st.integers(min_value=min_rows, max_value=12))
    d = draw(st.integers(min_value=1, max_value=3))
    x = draw(hnp.arrays(np.float64, (n, d), elements=_ELEMENTS))
    y = draw(hnp.arrays(np.float64, (n,), elements=_ELEMENTS))
    return x, y


def _fit_predict(est: Any, x: np.ndarray, y: np.ndarray) -> np.ndarray | None:
    try:
        est.fit(x, y)
    except tr.ThermerrError:
        return None  # e.g. a singular design: refused with a reason, not a crash
    p = est.predict(x)
    assert p.shape == (x.shape[0],) and p.dtype == np.float64
    assert np.all(np.isfinite(p)), p
    return p


def _well_conditioned(x: np.ndarray) -> bool:
    design = np.column_stack([np.ones(len(x)), x])
    return bool(np.linalg.matrix_rank(design) == design.shape[1] and np.linalg.cond(design) < 1e4)


@FAST
@given(xy(), st.sampled_from(["mlr", "rbf", "svr"]))
def test_estimators_predict_finite_numbers_of_the_right_shape(data: Any, kind: str) -> None:
    x, y = data
    est = {"mlr": tr.MLR(), "rbf": tr.RBFNetwork(spread=50.0), "svr": tr.SVR(C=10.0)}[kind]
    p = _fit_predict(est, x, y)
    if p is not None and kind == "mlr" and _well_conditioned(x):
        # one more finite check on points it was not fitted on
        q = est.predict(x[::-1] + 1.0)
        assert np.all(np.isfinite(q))


# Tolerance for row order. MLR is a direct least-squares solve: permuting the rows only permutes
# the order of the sums in the factorisation, so the predictions differ by rounding, of order
# cond(X) * 1e-16 relative; with cond < 1e4 (filtered) that is < 1e-12, and 1e-9 leaves a wide
# margin. SVR's dual is solved iteratively and stops at `tol`: with a different row order SMO
# takes a different path to the same optimum (unique in w; the kernel matrix is fixed by the
# pairs, whatever their order) and stops at a slightly different point, so the comparison is run
# with tol=1e-12 and no shrinking, where the stopping points agree to ~1e-12 relative, and the
# same 1e-9 relative (of the predictions' scale) holds.
RTOL = 1e-9


def _close(a: np.ndarray, b: np.ndarray, scale: float) -> None:
    np.testing.assert_allclose(a, b, rtol=RTOL, atol=RTOL * max(scale, 1e-300))


@FAST
@given(xy(), st.randoms(use_true_random=False))
def test_mlr_does_not_depend_on_row_order(data: Any, rnd: Any) -> None:
    x, y = data
    assume(_well_conditioned(x))
    perm = np.array(rnd.sample(range(len(x)), len(x)))
    p = tr.MLR().fit(x, y).predict(x)
    q = tr.MLR().fit(x[perm], y[perm]).predict(x)
    _close(q, p, float(np.max(np.abs(y))))


# the assume()s below drop degenerate problems by design (ties, every alpha at a bound); on some
# draws that is most of them, which Hypothesis's filter health check reports as an error (seen
# once in CI: 5 kept, 50 dropped). The examples kept are checked as strictly as before.
@settings(SLOW, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(xy(), st.randoms(use_true_random=False), st.sampled_from(["rbf", "linear"]))
def test_svr_does_not_depend_on_row_order(data: Any, rnd: Any, kernel: str) -> None:
    x, y = data
    # ties (repeated rows, repeated targets) make the dual degenerate: many optima, and which one
    # SMO stops at depends on the order it visits them (found by this test); the property is about
    # the generic problem, whose optimum is unique
    assume(len(np.unique(x, axis=0)) == len(x) and len(np.unique(y)) == len(y))
    perm = np.array(rnd.sample(range(len(x)), len(x)))
    params = dict(C=10.0, epsilon=0.1, kernel=kernel, gamma=0.01, tol=1e-12, shrinking=False, max_iter=10**6)
    try:
        with warnings.catch_warnings():
            # a fit stopped at max_iter has not reached the optimum, so where it stops depends on
            # the path, as scikit-learn's does to the bit (test_svr.py's unconverged case): the
            # property is about the optimum
            warnings.simplefilter("error", ConvergenceWarning)
            a = tr.SVR(**params).fit(x, y)
            b = tr.SVR(**params).fit(x[perm], y[perm])
    except (tr.ConvergenceError, ConvergenceWarning):
        assume(False)
        return
    # w is unique, the intercept only when some support vector is clearly free (1e-6 C < |alpha| <
    # (1 - 1e-6) C; an alpha a hair off its bound is a kink the solver only approaches): with
    # every alpha at a bound the optimal intercepts form an interval and SMO returns its middle,
    # which depends on the path (found by this test: four rows with x = 0, a linear kernel)
    for m in (a, b):
        coef = np.abs(np.asarray(m.dual_coef_)).ravel()
        assume(bool(np.any((coef > 1e-6 * params["C"]) & (coef < (1 - 1e-6) * params["C"]))))
    _close(b.predict(x), a.predict(x), float(np.max(np.abs(y))))


@FAST
@given(xy(), st.one_of(st.floats(min_value=-1e3, max_value=-1e-3), st.floats(min_value=1e-3, max_value=1e3),
                       st.just(0.0)))
def test_mlr_is_linear_in_the_target(data: Any, c: float) -> None:
    x, y = data
    assume(_well_conditioned(x))
    p = tr.MLR().fit(x, y).predict(x)
    q = tr.MLR().fit(x, c * y).predict(x)
    _close(q, c * p, abs(c) * float(np.max(np.abs(y))))
