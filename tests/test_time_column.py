"""A run's clock as a logger writes it: a ``time`` column of ISO-8601 date-times instead of
``time_s`` (formats.md allows either). The CSV reader, ``Run.from_frame`` and thermerr-edge read
it with the core's one parser (``thermerr_core::timeaxis::IsoClock``); a run's ``time_s`` then
counts seconds from its first row, so everything downstream sees the same numbers as from the
``time_s`` file."""

from __future__ import annotations

import json
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.cli import main

SENSORS = ["T_s01", "T_s07", "T_s10", "T_s13"]
START = np.datetime64("2025-10-25T22:00:00", "s")


def _iso(time_s: np.ndarray, sep: str = "T") -> list[str]:
    return [str(START + np.timedelta64(int(round(t)), "s")).replace("T", sep) for t in time_s]


def with_dates(src: Path, dst: Path, stamps: list[str]) -> Path:
    """``src`` with its ``time_s`` column replaced by a ``time`` column of ``stamps``."""
    lines = src.read_text().splitlines()
    head = lines[0].split(",")
    k = head.index("time_s")
    head[k] = "time"
    out = [",".join(head)]
    for stamp, line in zip(stamps, lines[1:]):
        f = line.split(",")
        f[k] = stamp
        out.append(",".join(f))
    dst.write_text("\n".join(out) + "\n")
    return dst


def test_a_date_time_column_reads_as_seconds_from_the_start(example_run1, tmp_path):
    ref = tr.read_run(example_run1)
    for sep in ("T", " "):
        run = tr.read_run(with_dates(example_run1, tmp_path / "dated.csv", _iso(ref.time_s, sep)))
        np.testing.assert_array_equal(run.time_s, ref.time_s)
        assert run.names == ref.names and not run.ignored
        np.testing.assert_array_equal(run.matrix(run.names), ref.matrix(ref.names))


def test_offsets_count_real_seconds_across_a_clock_change(tmp_path):
    # Berlin leaves summer time at 03:00+02:00 = 02:00+01:00: written with offsets, 15-s steps
    stamps = ["2025-10-26T02:59:30+02:00", "2025-10-26T02:59:45+02:00", "2025-10-26T02:00:00+01:00",
              "2025-10-26T02:00:15+01:00"]
    p = tmp_path / "dst.csv"
    p.write_text("time,T_a,E_x\n" + "".join(f"{s},{20 + i},{i}\n" for i, s in enumerate(stamps)))
    np.testing.assert_array_equal(tr.read_run(p).time_s, [0.0, 15.0, 30.0, 45.0])
    # the same wall clock without offsets steps back an hour: refused, naming the row
    p.write_text("time,T_a,E_x\n" + "".join(f"{s[:19]},{20 + i},{i}\n" for i, s in enumerate(stamps)))
    with pytest.raises(tr.DataError, match=r"row 3, column `time`: time is not strictly increasing \(-3585 s"):
        tr.read_run(p)


@pytest.mark.parametrize(("cell", "why"), [
    ("10/25/2025 22:00:15", "a date with slashes is day or month first by locale"),
    ("150", "a number of seconds belongs in a `time_s` column"),
    ("2025-10-25T22:00:15Z", "has a UTC offset but the column's first date-time does not"),
    ("", "time is missing"),
])
def test_a_bad_date_time_is_one_line_naming_row_and_column(cell, why, tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text(f"time,T_a,E_x\n2025-10-25T22:00:00,20,0\n{cell},21,1\n")
    with pytest.raises(tr.DataError, match="row 2") as e:
        tr.read_run(p, nan="drop")
    assert "`time`" in str(e.value) and why in str(e.value) and "\n" not in str(e.value)
    assert main(["fit", str(p), "--axis", "E_x", "--model", "mlr", "--out", str(tmp_path / "m.json")]) == 2
    assert not (tmp_path / "m.json").exists()


def test_date_times_under_time_s_name_the_fix(tmp_path, capsys):
    """The converse of the above: a logger's date-times in a column named ``time_s`` are refused
    on one line that names the column to rename, from Python and from the command line (exit 2,
    nothing written)."""
    p = tmp_path / "dated.csv"
    p.write_text("time_s,T_a,E_x\n2025-10-25 22:00:00,20,0\n2025-10-25 22:00:15,21,1\n")
    with pytest.raises(tr.DataError, match=r"row 1, column `time_s`: .* name the column `time`") as e:
        tr.read_run(p)
    assert "\n" not in str(e.value)
    assert main(["init", str(p), "--out", str(tmp_path / "m.toml")]) == 2
    assert not (tmp_path / "m.toml").exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "name the column `time`" in err[0], err
    # a frame's datetime64 column under `time_s` (numpy would cast it to nanoseconds), with or
    # without a time zone, and its text: the same words
    pd = pytest.importorskip("pandas")
    stamps = pd.Series(pd.to_datetime(["2025-10-25 22:00:00", "2025-10-25 22:00:15"]))
    for col in (stamps, stamps.dt.tz_localize("Europe/Berlin"), stamps.astype(str)):
        frame = pd.DataFrame({"time_s": col, "T_a": [20.0, 21.0], "E_x": [0.0, 1.0]})
        with pytest.raises(tr.DataError, match=r"row 1, column `time_s`: \"2025-10-25 22:00:00.*name the column `time`"):
            tr.Run.from_frame(frame)


def test_frames_carry_date_times_in_every_usual_form(example_run1):
    pd = pytest.importorskip("pandas")
    ref = tr.read_run(example_run1)
    df = pd.read_csv(example_run1)
    stamps = pd.to_datetime(_iso(ref.time_s))
    forms = {
        "strings": df.drop(columns="time_s").assign(time=_iso(ref.time_s)),
        "datetime64": df.drop(columns="time_s").assign(time=stamps),
        # the same instants on Berlin's clocks, which leave summer time during this run
        "tz-aware": df.drop(columns="time_s").assign(time=stamps.tz_localize("UTC").tz_convert("Europe/Berlin")),
        "DatetimeIndex": df.drop(columns="time_s").set_index(stamps),
        "tz-aware index": df.drop(columns="time_s").set_index(stamps.tz_localize("UTC")),
    }
    for label, frame in forms.items():
        run = tr.Run.from_frame(frame)
        np.testing.assert_array_equal(run.time_s, ref.time_s, err_msg=label)
        np.testing.assert_array_equal(run.matrix(SENSORS), ref.matrix(SENSORS), err_msg=label)
    bad = forms["strings"].assign(time=["yesterday"] + _iso(ref.time_s)[1:])
    with pytest.raises(tr.DataError, match=r"row 1, column `time`: \"yesterday\" is not an ISO-8601"):
        tr.Run.from_frame(bad)
    with pytest.raises(tr.DataError, match="belongs in a `time_s` column"):
        tr.Run.from_frame(df.rename(columns={"time_s": "time"}))
    # a text column outside the data (an operator's name) is ignored with a warning, as in a CSV;
    # text in a data column is refused naming its first cell
    with pytest.warns(UserWarning, match="operator"):
        run = tr.Run.from_frame(df.assign(operator="bob"))
    assert run.ignored == ["operator"]
    t = df.assign(T_s07=df["T_s07"].astype(object))
    t.loc[4, "T_s07"] = "open"
    with pytest.raises(tr.DataError, match=r"row 5, column `T_s07`: \"open\" is not a number"):
        tr.Run.from_frame(t)


def test_fit_and_edge_on_a_dated_run_equal_the_time_s_run(example_run1, example_run2, edge_bin, tmp_path):
    """A history model (its state steps by the time between rows) fitted on the dated file is the
    model fitted on the time_s file, bit for bit; the gateway fed the dated stream echoes the
    date-times and predicts what it predicts from the time_s stream."""
    r1, r2 = tr.read_run(example_run1), tr.read_run(example_run2)
    dated1 = with_dates(example_run1, tmp_path / "dated1.csv", _iso(r1.time_s))
    dated2 = with_dates(example_run2, tmp_path / "dated2.csv", _iso(r2.time_s))
    args = ["--axis", "E_z", "--model", "mlr", "--sensors", ",".join(SENSORS), "--history", "900,3600"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["fit", str(example_run1), *args, "--out", str(tmp_path / "a.json")]) == 0
        assert main(["fit", str(dated1), *args, "--out", str(tmp_path / "b.json")]) == 0
    a, b = (json.loads((tmp_path / f).read_text()) for f in ("a.json", "b.json"))
    a.pop("provenance", None), b.pop("provenance", None)
    assert a == b
    outs = []
    for run in (example_run2, dated2):
        res = subprocess.run([str(edge_bin), str(tmp_path / "a.json"), str(run)], capture_output=True, text=True,
                             timeout=60, check=True)
        outs.append([ln.split(",") for ln in res.stdout.strip().splitlines()])
    plain, dated = outs
    # (the guard learnt by `thermerr fit` adds a status column)
    assert plain[0][:2] == ["time_s", "E_z_pred"] and dated[0] == ["time", *plain[0][1:]]
    assert [r[0] for r in dated[1:]] == _iso(r2.time_s)
    want = tr.load_model(tmp_path / "a.json").predict_run(r2)
    np.testing.assert_array_equal(np.array([float(r[1]) for r in plain[1:]]), np.array([float(r[1]) for r in dated[1:]]))
    np.testing.assert_allclose(np.array([float(r[1]) for r in dated[1:]]), want, rtol=1e-9, atol=1e-9)
    # a bad date-time on the stream is a skipped line naming the column, as a bad number is
    lines = dated2.read_text().splitlines()
    lines[3] = "yesterday," + lines[3].split(",", 1)[1]
    res = subprocess.run([str(edge_bin), str(tmp_path / "a.json")], input="\n".join(lines) + "\n",
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 0 and "line 4: column `time`:" in res.stderr
    assert len(res.stdout.strip().splitlines()) == len(lines) - 1


def test_predict_echoes_the_dated_time_column(tmp_path):
    # thermerr predict on a dated run writes its `time` cells as written (as thermerr-edge does),
    # the same predictions as from the time_s file; a row dropped for a gap drops its stamp too
    root = Path(__file__).resolve().parents[1] / "examples"
    src, machine = root / "vmc_run.csv", root / "vmc_nominal.toml"
    ref = tr.read_run(src)
    stamps = _iso(ref.time_s)
    dated = with_dates(src, tmp_path / "dated.csv", stamps)
    assert main(["predict", str(src), "--machine", str(machine), "--out", str(tmp_path / "a.csv"), "--quiet"]) == 0
    assert main(["predict", str(dated), "--machine", str(machine), "--out", str(tmp_path / "b.csv"), "--quiet"]) == 0
    a = (tmp_path / "a.csv").read_text().splitlines()
    b = (tmp_path / "b.csv").read_text().splitlines()
    assert a[0].startswith("time_s,") and b[0] == "time," + a[0].split(",", 1)[1]
    assert [line.split(",", 1)[0] for line in b[1:]] == stamps
    assert [line.split(",", 1)[1] for line in b[1:]] == [line.split(",", 1)[1] for line in a[1:]]
    # a gap dropped with --nan drop: that row's stamp goes with it
    gap = _with_a_gap(dated, tmp_path / "gap.csv")
    assert main(["predict", str(gap), "--machine", str(machine), "--out", str(tmp_path / "c.csv"), "--quiet",
                 "--nan", "drop"]) == 0
    c = (tmp_path / "c.csv").read_text().splitlines()
    assert [line.split(",", 1)[0] for line in c[1:]] == stamps[:2] + stamps[3:]


def _with_a_gap(src, dest):
    """``src`` written to ``dest`` with its first temperature of data row 3 left empty."""
    lines = src.read_text().splitlines()
    head = lines[0].split(",")
    cells = lines[3].split(",")
    cells[head.index(next(h for h in head if h.startswith("T_")))] = ""
    lines[3] = ",".join(cells)
    dest.write_text("\n".join(lines) + "\n")
    return dest


@pytest.mark.parametrize("nan, said", [("interpolate", "1 missing value(s) filled by linear interpolation in time"),
                                       ("drop", "1 row(s) with a missing value dropped (--nan drop; first: row 3)")])
def test_what_nan_changed_is_said(tmp_path, capsys, nan, said):
    """A result read from mended rows is not one of the file as logged: the command says how many
    values --nan filled or how many rows it dropped (a run with 0.1 % of its cells interpolated
    can move a diagnosis), and --quiet keeps it silent."""
    root = Path(__file__).resolve().parents[1] / "examples"
    src, machine = root / "vmc_run.csv", root / "vmc_nominal.toml"
    gap = _with_a_gap(src, tmp_path / "gap.csv")
    args = ["predict", str(gap), "--machine", str(machine), "--out", str(tmp_path / "p.csv"), "--nan", nan]
    assert main(args) == 0
    assert f"thermerr: {gap}: {said}" in capsys.readouterr().err
    assert main([*args, "--quiet"]) == 0
    assert "missing value" not in capsys.readouterr().err


def test_a_day_first_date_with_dots_reads_as_the_same_clock(tmp_path):
    """A logger or a spreadsheet in a German locale writes `04.03.2025 08:00:15` (with `;` and a
    decimal comma): the same seconds as the ISO-8601 column, through the CSV reader and the CLI."""
    iso = tmp_path / "iso.csv"
    iso.write_text("time,T_a,E_x\n2025-03-04T23:59:45,20.5,0\n2025-03-05T00:00:00,21,1\n2025-03-05T00:00:15,22,2\n")
    de = tmp_path / "de.csv"
    de.write_text("time;T_a;E_x\n04.03.2025 23:59:45;20,5;0\n5.3.2025 0:00:00;21;1\n05.03.2025 00:00:15;22;2\n")
    a, b = tr.read_run(iso), tr.read_run(de, delimiter=";", decimal=",")
    np.testing.assert_array_equal(b.time_s, [0.0, 15.0, 30.0])
    np.testing.assert_array_equal(a.time_s, b.time_s)
    np.testing.assert_array_equal(a.matrix(a.names), b.matrix(b.names))
