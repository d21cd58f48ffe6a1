"""Model files have one owner (the core's ``artifact``): what the library writes, the library and
the edge read through the same validation. Hundreds of mutated files go through both; none may
panic (a ``PanicException`` in Python, exit 101 or an abort on the edge) or predict from an
inconsistent model."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pytest

import thermerr_rs as tr

SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]


def fitted_models(run1: Path) -> dict[str, tr.Estimator]:
    train = tr.read_run(run1)
    out: dict[str, tr.Estimator] = {
        "mlr": tr.MLR(),
        "rbf-minmax": tr.MinMaxScaled(tr.RBFNetwork(design="ols", spread=1.0, goal=20.0)),
        "rbf-ago": tr.AGORegressor(tr.RBFNetwork(design="kmeans", n_centers=6, spread=1.2, seed=1)),
        "svr": tr.SVR(C=30.0, epsilon=0.05, gamma=0.05),
        "bp": tr.BPNetwork(hidden=4, max_epochs=100, seed=1),
        "greybp": tr.GreyBP(max_epochs=100, seed=1),
        "gm1n": tr.GM1N(window=6),
        "hybrid": tr.HybridFilterNet(hidden=4, max_epochs=100, seed=1),
    }
    for name, m in out.items():
        m.fit_run(train.slice(0, 80), "E_z", SENSORS, inputs="absolute" if "ago" in name else "rise")
    return out


def mutations(doc: Any) -> Iterator[tuple[str, Any]]:
    """Every entry of the document replaced, shortened, lengthened, retyped or removed, one at a
    time (long numeric arrays: their first and last entries stand for the rest)."""
    paths: list[tuple[Any, ...]] = []

    def walk(v: Any, path: tuple[Any, ...]) -> None:
        if isinstance(v, dict):
            for k, x in v.items():
                paths.append(path + (k,))
                walk(x, path + (k,))
        elif isinstance(v, list):
            idx = range(len(v)) if len(v) <= 4 or not all(isinstance(x, (int, float)) for x in v) else (0, len(v) - 1)
            for i in idx:
                paths.append(path + (i,))
                walk(v[i], path + (i,))

    walk(doc, ())
    for p in paths:
        here: Any = doc
        for k in p:
            here = here[k]
        values: list[Any] = [None, "x", -1, 0, 10**9, 1e300, True, {}]
        if isinstance(here, list):
            values += [here[:-1], here + here[:1], []]
        for v in values:
            m = copy.deepcopy(doc)
            parent = m
            for k in p[:-1]:
                parent = parent[k]
            parent[p[-1]] = v
            yield f"{'/'.join(map(str, p))}={json.dumps(v)[:20]}", m
        m = copy.deepcopy(doc)
        parent = m
        for k in p[:-1]:
            parent = parent[k]
        if isinstance(parent, dict):
            del parent[p[-1]]
            yield f"{'/'.join(map(str, p))} removed", m


def test_mutated_model_files_are_refused_or_predict_in_python_and_on_the_edge(
    example_run1: Path, example_run2: Path, edge_bin: Path, tmp_path: Path
) -> None:
    x = tr.read_run(example_run2).slice(0, 12)
    n_files = n_loaded = 0
    edge_files: list[tuple[str, Path]] = []
    for name, model in fitted_models(example_run1).items():
        for k, (what, doc) in enumerate(mutations(model.to_dict())):
            n_files += 1
            path = tmp_path / f"{name}-{k}.json"
            path.write_text(json.dumps(doc))
            edge_files.append((f"{name} {what}", path))
            try:
                m = tr.load_model(path)
            except tr.ThermerrError:
                continue
            n_loaded += 1
            try:
                m.predict_run(x)
            except tr.ThermerrError:
                pass
    assert n_files > 500, n_files
    assert 50 < n_loaded < n_files, (n_loaded, n_files)
    # the edge: exit 0 (predicted) or 2 (a clear refusal), never a panic (101) or a signal
    bad = []
    for what, path in edge_files:
        r = subprocess.run([str(edge_bin), str(path), str(example_run2)], capture_output=True, text=True)
        if r.returncode not in (0, 2) or "panicked" in r.stderr:
            bad.append(f"{what}: exit {r.returncode} {r.stderr.strip()[:200]}")
    assert not bad, "\n".join(bad[:20])


@pytest.mark.parametrize(
    ("name", "path", "value", "message"),
    [
        ("rbf-minmax", ["model", "weights"], "extra", "weights for"),
        ("rbf-minmax", ["model", "weights"], "fewer", "weights for"),
        ("svr", ["model", "dual_coef"], "extra", "dual coefficients"),
        ("svr", ["model", "dual_coef"], "fewer", "dual coefficients"),
        ("svr", ["model", "kernel", "gamma"], 0.0, "gamma"),
        ("bp", ["model", "net", "sizes"], [4, 9, 1], "layer"),
        ("greybp", ["model", "windows"], [10**9, 8, 10], "values per run"),
        ("rbf-minmax", ["preprocessing", "x_max"], [1.0], "preprocessing"),
    ],
)
def test_inconsistent_model_files_are_refused_where_they_are_read(
    name: str, path: list[str], value: Any, message: str, example_run1: Path, edge_bin: Path, tmp_path: Path
) -> None:
    doc = fitted_models(example_run1)[name].to_dict()
    parent = doc
    for k in path[:-1]:
        parent = parent[k]
    if value == "extra":
        parent[path[-1]] = parent[path[-1]] + [0.5]
    elif value == "fewer":
        parent[path[-1]] = parent[path[-1]][:-1]
    else:
        parent[path[-1]] = value
    f = tmp_path / "bad.json"
    f.write_text(json.dumps(doc))
    with pytest.raises(tr.ModelFormatError, match=message):
        tr.load_model(f)
    r = subprocess.run([str(edge_bin), str(f), str(example_run1)], capture_output=True, text=True)
    assert r.returncode == 2 and message in r.stderr, r.stderr


def test_a_file_written_by_the_cli_loads_in_a_fresh_interpreter(example_run1: Path, tmp_path: Path) -> None:
    """`thermerr fit --model rbf` writes a min–max scaled model; a user's plain
    ``import thermerr_rs`` must read it (the wrappers register themselves on import)."""
    out = tmp_path / "rbf.json"
    subprocess.run([sys.executable, "-m", "thermerr_rs.cli", "fit", str(example_run1), "--axis", "E_z",
                    "--sensors", ",".join(SENSORS), "--model", "rbf", "--out", str(out)],
                   check=True, capture_output=True, text=True)
    assert json.loads(out.read_text())["preprocessing"]["kind"] == "minmax"
    code = ("import sys, thermerr_rs as tr; m = tr.load_model(sys.argv[1]); "
            "print(type(m).__name__, m.predict_run(tr.read_run(sys.argv[2]))[:2])")
    r = subprocess.run([sys.executable, "-c", code, str(out), str(example_run1)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("MinMaxScaled")


def test_a_constant_column_scales_to_the_middle_in_the_library_and_on_the_edge(
    example_run1: Path, edge_bin: Path, tmp_path: Path
) -> None:
    run = tr.read_run(example_run1)
    cols = {"time_s": run.time_s, **{n: run[n] for n in SENSORS}, "T_dead": np.full(len(run), 21.5),
            "E_z": run["E_z"]}
    from thermerr_rs.synthetic import write_run_csv

    write_run_csv(tmp_path / "run.csv", cols)
    run = tr.read_run(tmp_path / "run.csv")
    feats = SENSORS + ["T_dead"]
    m = tr.MinMaxScaled(tr.MLR()).fit_run(run, "E_z", feats)
    assert m.pre_.transform(np.ascontiguousarray(run.matrix(feats)))[:, -1].tolist() == [0.5] * len(run)
    want = m.predict_run(run)
    path = m.save(tmp_path / "m.json")
    r = subprocess.run([str(edge_bin), str(path), str(tmp_path / "run.csv")], check=True, capture_output=True,
                       text=True)
    got = np.array([float(l.split(",")[1]) for l in r.stdout.strip().splitlines()[1:]])
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def test_saved_files_read_back_equal_and_carry_the_core_version(example_run1: Path, tmp_path: Path) -> None:
    for name, m in fitted_models(example_run1).items():
        back = tr.load_model(m.save(tmp_path / f"{name}.json"))
        assert back.to_json() == m.to_json(), name
        assert json.loads(m.to_json())["format_version"] == tr.FORMAT_VERSION == 1
