"""thermerr_rs.fleet and `thermerr fleet`: batches of runs on Dask, with the default (threaded)
scheduler and on a 2-worker LocalCluster, checked number for number against fitting each run
alone in this process."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("dask", reason="thermerr_rs.fleet needs dask: pip install thermerr_rs[fleet]")
distributed = pytest.importorskip("distributed", reason="thermerr_rs.fleet needs dask[distributed]")

import thermerr_rs as tr  # noqa: E402
from thermerr_rs import fleet  # noqa: E402
from thermerr_rs.cli import main  # noqa: E402

from _signals import ctrl_c  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CORRUPT = "time_s,T_a,E_z\n0,20.0,0.1\n60,x,0.2\n"


@pytest.fixture(scope="module")
def cluster():
    """A 2-worker LocalCluster (worker processes, one thread each) for the whole module."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as lc:
        yield lc


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> Path:
    """Four small runs shaped like the HMC example (two whole runs, two slices) and a corrupt one."""
    d = tmp_path_factory.mktemp("runs")
    shutil.copy(EXAMPLES / "hmc_run1.csv", d / "m01.csv")
    shutil.copy(EXAMPLES / "hmc_run2.csv", d / "m02.csv")
    lines = (EXAMPLES / "hmc_run1.csv").read_text().splitlines()
    (d / "m03.csv").write_text("\n".join(lines[:121]) + "\n")  # header + 120 samples
    lines = (EXAMPLES / "hmc_run2.csv").read_text().splitlines()
    (d / "m04.csv").write_text("\n".join([lines[0], *lines[40:]]) + "\n")
    (d / "m05_bad.csv").write_text(CORRUPT)
    return d


GOOD = ["m01", "m02", "m03", "m04"]
SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]
BP = {"hidden": 5, "max_epochs": 150}  # a seeded stochastic fit, kept short


def _serial(path: Path, model: str) -> tuple[dict, tr.Scores]:
    """The model of one run fitted alone in this process, as `thermerr fit` would: its file and
    its training scores."""
    run = tr.read_run(path)
    est = tr.MLR() if model == "mlr" else tr.BPNetwork(seed=0, **BP)
    est.fit_run(run, "E_z", SENSORS, inputs="rise")
    return est.to_dict(), tr.scores(run["E_z"], est.predict_run(run))


def _check_fit(rows: list[fleet.RunResult], runs: Path, out: Path, model: str) -> None:
    assert [r.name for r in rows] == [*GOOD, "m05_bad"]  # input (sorted) order
    assert [r.ok for r in rows] == [True] * 4 + [False]
    bad = rows[-1]
    assert "m05_bad.csv" in bad.error and "x" in bad.error and "\n" not in bad.error
    assert bad.out is None and not (out / "m05_bad.json").exists()
    for r in rows[:4]:
        doc, sc = _serial(runs / f"{r.name}.csv", model)
        saved = json.loads((out / f"{r.name}.json").read_text())
        assert r.out == str(out / f"{r.name}.json")
        assert saved["model"] == doc["model"]  # the fitted numbers, bit for bit
        assert r.figures["rms"] == sc.rms and r.figures["compensation_rate"] == sc.compensation_rate
        assert r.figures["n"] == len(tr.read_run(runs / f"{r.name}.csv"))
    summary = json.loads((out / "fleet-summary.json").read_text())
    assert summary["n_runs"] == 5 and summary["n_failed"] == 1
    with open(out / "fleet-summary.csv", newline="") as fh:
        table = list(csv.DictReader(fh))
    assert [t["ok"] for t in table] == ["True"] * 4 + ["False"]
    assert float(table[0]["rms"]) == pytest.approx(rows[0].figures["rms"], rel=1e-12)


def test_import_does_not_import_dask():
    code = "import sys, thermerr_rs, thermerr_rs.fleet, thermerr_rs.cli; assert 'dask' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_missing_dask_names_the_extra(runs, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "dask", None)  # import dask -> ImportError
    with pytest.raises(tr.ThermerrError, match=r"pip install thermerr_rs\[fleet\]") as e:
        fleet.fit_runs(runs, "E_z", out_dir=tmp_path)
    assert isinstance(e.value, ImportError)


def test_fit_default_scheduler_equals_serial(runs, tmp_path):
    out = tmp_path / "mlr"
    rows = fleet.fit_runs(runs, "E_z", "mlr", out, sensors=SENSORS, workers=2)
    _check_fit(rows, runs, out, "mlr")


def test_fit_seeded_on_local_cluster_equals_serial(runs, tmp_path, cluster):
    """A seeded network: the same numbers on a 2-worker cluster, on 1 thread and serially."""
    with distributed.Client(cluster) as client:
        rows = fleet.fit_runs(runs, "E_z", "bp", tmp_path / "c", sensors=SENSORS, params=BP, scheduler=client)
    _check_fit(rows, runs, tmp_path / "c", "bp")
    one = fleet.fit_runs(runs, "E_z", "bp", tmp_path / "t", sensors=SENSORS, params=BP, workers=1)
    assert [r.figures for r in one] == [r.figures for r in rows]


def test_cli_fit_and_evaluate_on_scheduler_address(runs, tmp_path, cluster, capsys):
    out = tmp_path / "models"
    addr = cluster.scheduler_address
    rc = main(["fleet", "fit", str(runs), "--axis", "E_z", "--sensors", ",".join(SENSORS), "--out", str(out),
               "--scheduler", addr])
    cap = capsys.readouterr()
    assert rc == 1  # one run failed
    assert "m05_bad.csv" in cap.err and "1 of 5 runs failed" in cap.err
    lines = cap.out.splitlines()
    assert [ln.split()[:2] for ln in lines[1:6]] == [[n, "ok"] for n in GOOD] + [["m05_bad", "FAILED"]]
    recorded = json.loads((out / "fleet-summary.json").read_text())["runs"]
    _check_fit([fleet.RunResult(**r) for r in recorded], runs, out, "mlr")

    # the good runs only: exit 0; one model scored on every run, on the cluster
    good = [str(runs / f"{n}.csv") for n in GOOD]
    rc = main(["fleet", "evaluate", str(out / "m01.json"), *good, "--json", "--scheduler", addr])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["n_failed"] == 0 and [r["name"] for r in doc["runs"]] == GOOD
    model = tr.load_model(out / "m01.json")
    for r in doc["runs"]:
        run = tr.read_run(r["run"])
        s = tr.scores(run["E_z"], model.predict_run(run))
        assert r["figures"]["rms"] == s.rms and r["figures"]["max_abs"] == s.max_abs
    # the model's own run is fitted well; another machine's run less so, but compensated
    assert doc["runs"][0]["figures"]["compensation_rate"] > 0.95
    assert doc["runs"][1]["figures"]["rms"] > doc["runs"][0]["figures"]["rms"]


def test_evaluate_default_scheduler_records_bad_run(runs, tmp_path):
    model = tr.MLR().fit_run(tr.read_run(runs / "m01.csv"), "E_z", SENSORS, inputs="rise")
    rows = fleet.evaluate_runs(model, runs, out_dir=tmp_path)
    assert [r.ok for r in rows] == [True] * 4 + [False]
    assert "m05_bad.csv" in rows[-1].error
    run = tr.read_run(runs / "m04.csv")
    assert rows[3].figures["rms"] == tr.scores(run["E_z"], model.predict_run(run)).rms
    assert (tmp_path / "fleet-summary.csv").exists()


def test_diagnose_two_vmc_runs_on_cluster(tmp_path, cluster, capsys):
    """Two copies of the start of the VMC example (the first 400 samples, to keep it short)."""
    d = tmp_path / "vmc"
    d.mkdir()
    lines = (EXAMPLES / "vmc_run.csv").read_text().splitlines()
    for name in ("vmc_a.csv", "vmc_b.csv"):
        (d / name).write_text("\n".join(lines[:401]) + "\n")
    machine = EXAMPLES / "vmc_nominal.toml"
    out = tmp_path / "diag"
    rc = main(["fleet", "diagnose", str(d), "--machine", str(machine), "--out", str(out), "--json",
               "--scheduler", cluster.scheduler_address])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    ref = tr.diagnose(tr.read_run(d / "vmc_a.csv"), tr.Machine.load(machine))
    assert [r["name"] for r in doc["runs"]] == ["vmc_a", "vmc_b"]
    for r in doc["runs"]:
        f = r["figures"]
        assert r["ok"] and f["verdict"] == ref.verdict and f["gain_pct"] == ref.gain_pct
        assert f["baseline_rms"] == ref.report["baseline"]["rmse_um"]
        assert f["baseline_unique"] is ref.baseline_unique
        rep = json.loads((out / r["name"] / "report.json").read_text())
        assert rep["verdict"] == ref.verdict
        assert (out / r["name"] / "report.html").exists() and (out / r["name"] / "calibrated.toml").exists()
    assert json.loads((out / "fleet-summary.json").read_text())["n_failed"] == 0


def test_diagnose_bad_run_default_scheduler(tmp_path):
    (tmp_path / "bad.csv").write_text(CORRUPT)
    (tmp_path / "short.csv").write_text("time_s,T_ambient,E_z\n0,20,0\n60,20,0\n")
    rows = fleet.diagnose_runs(tmp_path, EXAMPLES / "vmc_nominal.toml", tmp_path / "out")
    assert [r.ok for r in rows] == [False, False]
    assert "bad.csv" in rows[0].error and "short.csv" in rows[1].error
    assert not (tmp_path / "out" / "bad").exists()
    assert json.loads((tmp_path / "out" / "fleet-summary.json").read_text())["n_failed"] == 2


def test_bad_usage_is_exit_2(runs, tmp_path, capsys):
    base = ["fleet", "fit", "--axis", "E_z", "--out", str(tmp_path / "o")]
    assert main([*base, str(tmp_path / "nothing")]) == 2
    assert "nothing" in capsys.readouterr().err
    assert main([*base, str(runs), "--scheduler", "127.0.0.1:8786", "--workers", "2"]) == 2
    assert "--workers" in capsys.readouterr().err
    other = tmp_path / "other"
    other.mkdir()
    shutil.copy(runs / "m01.csv", other / "m01.csv")
    assert main([*base, str(runs / "m01.csv"), str(other / "m01.csv")]) == 2
    assert "same name" in capsys.readouterr().err
    assert main(["fleet", "evaluate", str(tmp_path / "none.json"), str(runs)]) == 2
    assert "none.json" in capsys.readouterr().err
    assert main(["fleet", "diagnose", str(runs), "--machine", str(tmp_path / "m.toml"), "--out", str(tmp_path)]) == 2
    assert not (tmp_path / "o").exists()  # nothing written before the input was accepted


def test_all_ok_is_exit_0_and_rerun_skips_the_summary(runs, tmp_path, capsys):
    d = tmp_path / "r"
    d.mkdir()
    for n in GOOD[:2]:
        shutil.copy(runs / f"{n}.csv", d / f"{n}.csv")
    assert main(["fleet", "fit", str(d), "--axis", "E_z", "--out", str(d), "--quiet"]) == 0
    assert "summary" not in capsys.readouterr().out  # --quiet: the table only
    # the summary CSV now in the directory is not taken for a run
    assert main(["fleet", "fit", str(d), "--axis", "E_z", "--out", str(d), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["n_failed"] == 0 and [r["name"] for r in doc["runs"]] == GOOD[:2]
    assert json.loads((d / "fleet-summary.json").read_text())["n_runs"] == 2
    m = tr.load_model(d / "m01.json")
    assert m.feature_names_in_ == tr.read_run(d / "m01.csv").temperatures and m.inputs_ == "rise"
    assert np.isfinite(m.predict_run(tr.read_run(d / "m02.csv"))).all()


def test_diagnose_passes_the_network_rule_to_every_run(tmp_path):
    """`--network` reaches each run's diagnosis (threads here): the same figures as diagnose()
    with that rule, and the rule recorded in each report; a wrong rule is refused up front."""
    d = tmp_path / "vmc"
    d.mkdir()
    lines = (EXAMPLES / "vmc_run.csv").read_text().splitlines()
    (d / "vmc_a.csv").write_text("\n".join(lines[:401]) + "\n")
    machine = EXAMPLES / "vmc_nominal.toml"
    rows = fleet.diagnose_runs(d, machine, tmp_path / "out", network="best")
    ref = tr.diagnose(tr.read_run(d / "vmc_a.csv"), tr.Machine.load(machine), network="best", progress=False)
    assert rows[0].ok and rows[0].figures["baseline_rms"] == ref.report["baseline"]["rmse_um"]
    alts = ",".join(a["column"] for a in ref.causes[0]["alternatives"]) if ref.column and ref.causes else ""
    assert rows[0].figures["alternatives"] == alts and rows[0].figures["suspect"] == ""
    rep = json.loads((tmp_path / "out" / "vmc_a" / "report.json").read_text())
    assert rep["baseline_network"] == ref.report["baseline_network"]
    # a run whose column-sensor spikes for one reading: its figures name the column
    cells = [ln.split(",") for ln in lines[:401]]
    k = cells[0].index("T_column")
    cells[200][k] = str(float(cells[200][k]) + 60.0)
    (d / "vmc_b.csv").write_text("\n".join(",".join(c) for c in cells) + "\n")
    with pytest.warns(tr.errors.SuspectReadingWarning, match="vmc_b.csv: T_column jumps"):
        rows = fleet.diagnose_runs(d, machine, tmp_path / "out3", network="best")
    assert [(r.name, r.figures["suspect"]) for r in rows] == [("vmc_a", ""), ("vmc_b", "T_column")]
    assert "suspect readings in T_column" in fleet.table(rows).splitlines()[-1]
    with pytest.raises(tr.ThermerrError, match="network: `fast`"):
        fleet.diagnose_runs(d, machine, tmp_path / "out2", network="fast")
    assert not (tmp_path / "out2").exists()


def test_the_table_and_summary_carry_a_verdicts_alternatives(tmp_path):
    """A diagnosis whose column the run cannot single out: the table says `or as well`, and the
    summary CSV has the alternatives as a comma-separated figure, as a fit's sensors."""
    figs = {"verdict": "unmodeled_source", "column": "T_a", "alternatives": "T_b,T_c", "suspect": "",
            "gain_pct": 40.0, "baseline_rms": 2.0, "extended_rms": 1.2, "baseline_unique": True}
    plain = dict(figs, alternatives="", suspect="T_d,T_e")
    rows = [fleet.RunResult(run="m1.csv", name="m1", ok=True, out="o/m1", figures=figs),
            fleet.RunResult(run="m2.csv", name="m2", ok=True, out="o/m2", figures=plain)]
    text = fleet.table(rows).splitlines()
    assert "unmodeled_source (T_a, or as well T_b, T_c): RMS 2.000 -> 1.200" in text[-2]
    assert "unmodeled_source (T_a): RMS" in text[-1] and "gain 40.0 %; suspect readings in T_d, T_e" in text[-1]
    assert "suspect" not in text[-2]
    fleet.write_summary(rows, tmp_path)
    with open(tmp_path / "fleet-summary.csv", newline="") as fh:
        got = [(r["alternatives"], r["suspect"]) for r in csv.DictReader(fh)]
    assert got == [("T_b,T_c", ""), ("", "T_d,T_e")]


def test_diagnose_takes_every_axis_of_the_machine_as_thermerr_diagnose(tmp_path, capsys):
    """A machine of three axes (the bundled HMC): by default each run is diagnosed on every
    axis, with the same figures as diagnose_axes() on that run alone, written as `thermerr
    diagnose` writes several axes; the summary has a column per axis and figure, the table a line
    per axis. One --axis keeps the one-axis layout; an axis the machine lacks is refused first."""
    d = tmp_path / "hmc"
    d.mkdir()
    for n in ("hmc_run1", "hmc_run2"):
        shutil.copy(EXAMPLES / f"{n}.csv", d / f"{n}.csv")
    machine = EXAMPLES / "hmc_machine.toml"
    out = tmp_path / "out"
    rows = fleet.diagnose_runs(d, machine, out)
    axes = tr.Machine.load(machine).axes
    assert len(axes) == 3 and all(r.ok for r in rows)
    for r in rows:
        ref = tr.diagnose_axes(tr.read_run(d / f"{r.name}.csv"), tr.Machine.load(machine), progress=False)
        assert r.figures["axes"] == ",".join(axes)
        for a in axes:
            assert r.figures[f"{a}.verdict"] == ref[a].verdict
            assert r.figures[f"{a}.baseline_rms"] == ref[a].report["baseline"]["rmse_um"]
            assert r.figures[f"{a}.extended_rms"] == ref[a].report["extended"]["rmse_um"]
            assert r.figures[f"{a}.remainder_um"] == ref[a].remainder_um
            assert (out / r.name / f"{a}.report.json").exists() and (out / r.name / f"{a}.extended.toml").exists()
        assert json.loads((out / r.name / "report.json").read_text())["axes"] == axes
    with open(out / "fleet-summary.csv", newline="") as f:
        header = next(csv.reader(f))
    assert {f"{a}.verdict" for a in axes} <= set(header)
    lines = fleet.table(rows).splitlines()
    assert len(lines) == 1 + 2 * len(axes) and lines[1].split()[:3] == ["hmc_run1", "ok", axes[0]]
    # one axis: the one-axis layout and figures
    one = fleet.diagnose_runs(d / "hmc_run1.csv", machine, tmp_path / "one", axis="E_y")
    assert one[0].figures["axis"] == "E_y" and (tmp_path / "one" / "hmc_run1" / "report.json").exists()
    assert main(["fleet", "diagnose", str(d), "--machine", str(machine), "--out", str(tmp_path / "bad"),
                 "--axis", "E_q"]) == 2
    assert "E_q" in capsys.readouterr().err and not (tmp_path / "bad").exists()


@pytest.mark.filterwarnings("ignore:E_y not diagnosed")  # said in the figures and the table
def test_diagnose_leaves_out_a_runs_dead_probe_and_diagnoses_the_rest(tmp_path):
    """One machine of the fleet with a probe dead throughout (the bundled HMC's run, E_y reading
    0 in every row): by default (every axis) that run is diagnosed on the other axes, the dead
    one named in its figures (``skipped``) and its table line, not the whole run failed."""
    d = tmp_path / "hmc"
    d.mkdir()
    with open(EXAMPLES / "hmc_run1.csv", newline="") as f:
        rows_in = list(csv.DictReader(f))
    for r in rows_in:
        r["E_y"] = "0"
    with open(d / "dead_y.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows_in[0]))
        w.writeheader()
        w.writerows(rows_in)
    machine = EXAMPLES / "hmc_machine.toml"
    rows = fleet.diagnose_runs(d, machine, tmp_path / "out")
    assert [r.ok for r in rows] == [True], rows[0].error
    axes = [a for a in tr.Machine.load(machine).axes if a != "E_y"]
    assert rows[0].figures["axes"] == ",".join(axes) and rows[0].figures["skipped"] == "E_y"
    assert "E_y not diagnosed" in fleet.table(rows)
    summary = json.loads((tmp_path / "out" / "dead_y" / "report.json").read_text())
    assert "E_y reads one value (0) in every row" in summary["skipped"]["E_y"]


FLEET_CTRL_C = textwrap.dedent("""\
    import sys, thermerr_rs as tr
    from thermerr_rs import fleet, synthetic as syn
    d, out = sys.argv[1], sys.argv[2]
    for seed in range(1, 5):
        c = syn.make_case("vmc", "none", seed, hours=(8.0, 4.0), dt=60.0)
        syn.write_run_csv(f"{d}/run{seed}.csv", c.train)
    slow = tr.BPNetwork(max_epochs=10**8, patience=10**8, large_n=None)  # runs for hours
    print("ready", flush=True)
    try:
        fleet.fit_runs(d, "E_z", slow, out, workers=2)
    except KeyboardInterrupt:
        print("interrupted", flush=True)
        # the next batch in this process starts clean
        rows = fleet.fit_runs(f"{d}/run1.csv", "E_z", "mlr", f"{out}-after", workers=2)
        print("after", rows[0].ok, flush=True)
        sys.exit(130)
    print("finished", flush=True)
    """)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process")
def test_ctrl_c_stops_a_fleet_on_threads_and_nothing_is_written_after_it(tmp_path):
    """Only the main thread sees Ctrl-C, and the fits run on dask's threads. Before the fleet
    passed the interrupt on, they ran to their end and wrote their models after Ctrl-C (on the
    real run: 7.9 s, and two diagnosis reports written). Now the running kernels stop, no task
    starts or writes after it, and the next batch in the same process runs normally. The bound
    leaves room for a loaded CI machine (the product's aim is a second: 0.5 s measured)."""
    runs, out = tmp_path / "runs", tmp_path / "out"
    runs.mkdir()
    p = subprocess.Popen([sys.executable, "-c", FLEET_CTRL_C, str(runs), str(out)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    stdout, err, waited = ctrl_c(p, 2.0, 60)  # 2 s: inside the first two fits, which would run for hours
    assert p.returncode == 130 and "interrupted" in stdout, (stdout, err)
    assert "after True" in stdout, (stdout, err)
    assert not list(out.glob("*.json")) if out.exists() else True  # no model, no summary
    assert waited < 20, waited


def test_every_task_reads_its_run_with_the_delimiter_and_decimal_given(runs, tmp_path, capsys):
    """`thermerr fleet` took --delimiter (and --decimal) and read every run with a comma all the
    same: each run of a German spreadsheet failed on its header. Now each task reads as told, and
    the figures are those of the same runs written with points."""
    d, de = tmp_path / "dot", tmp_path / "de"
    d.mkdir()
    de.mkdir()
    for n in GOOD[:2]:
        shutil.copy(runs / f"{n}.csv", d / f"{n}.csv")
        (de / f"{n}.csv").write_text((runs / f"{n}.csv").read_text().replace(",", ";").replace(".", ","))
    assert main(["fleet", "fit", str(d), "--axis", "E_z", "--out", str(tmp_path / "o1"), "--json"]) == 0
    dot = json.loads(capsys.readouterr().out)
    assert main(["fleet", "fit", str(de), "--axis", "E_z", "--out", str(tmp_path / "o2"), "--json",
                 "--delimiter", ";", "--decimal", ","]) == 0
    comma = json.loads(capsys.readouterr().out)
    assert [r["figures"] for r in comma["runs"]] == [r["figures"] for r in dot["runs"]]
    rows = fleet.evaluate_runs(tmp_path / "o1" / "m01.json", de, delimiter=";", decimal=",")
    assert all(r.ok for r in rows) and rows[1].figures == fleet.evaluate_runs(
        tmp_path / "o1" / "m01.json", d)[1].figures
