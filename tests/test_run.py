"""Run I/O: every bad input of formats.md gets one clear exception naming file, row and column."""

from __future__ import annotations

import numpy as np
import pytest

import thermerr_rs as tr
from thermerr_rs.errors import DataError, MissingColumnError, ParameterError

GOOD = "time_s,T_spindle,T_ambient,E_z,U_spindle_rpm\n0,20.0,20.0,0.0,0\n150,21.5,20.1,3.2,3000\n300,22.4,20.1,5.1,3000\n"


def test_reads_columns_by_prefix(write_csv):
    run = tr.read_run(write_csv(GOOD))
    assert len(run) == 3
    assert run.temperatures == ["T_spindle", "T_ambient"]
    assert run.errors == ["E_z"]
    assert run.inputs == ["U_spindle_rpm"]
    np.testing.assert_array_equal(run.time_s, [0, 150, 300])
    np.testing.assert_array_equal(run["E_z"], [0.0, 3.2, 5.1])
    assert run["T_spindle"].dtype == np.float64
    assert run.matrix(["T_spindle", "E_z"]).shape == (3, 2)


def test_example_run_reads(example_run1):
    run = tr.read_run(example_run1)
    assert len(run.temperatures) == 20
    assert run.errors == ["E_x", "E_y", "E_z"]
    assert np.all(np.diff(run.time_s) == 150)


@pytest.mark.parametrize(
    "content, fragments",
    [
        ("time_s,T_a\n", ["no data rows"]),
        ("t,T_a\n0,1\n", ["no `time_s`"]),
        ("time_s,T_a\n0,1\n150,2\n150,3\n", ["strictly increasing", "row 3", "time_s"]),
        ("time_s,T_a\n0,1\n150,2\n100,3\n", ["strictly increasing", "row 3"]),
        ("time_s,T_a,E_z\n0,1,0\n150,warm,1\n", ["row 2", "`T_a`", "line 3", "not a number"]),
        ("time_s,T_a,E_z\n0,1,0\n150,,1\n", ["row 2", "`T_a`", "missing value"]),
        ("time_s,T_a,E_z\n0,1,0\n150,NaN,1\n", ["row 2", "`T_a`", "missing value"]),
        ("time_s,T_a\n0,1,7\n", ["3 fields", "header has 2"]),
        # a Windows logger's CRLF line ends and a blank line: the file's own line numbers
        ("time_s,T_a,E_z\r\n0,1,0\r\n\r\n150,warm,1\r\n", ["line 4,", "row 2", "`T_a`", "not a number"]),
        ("time_s,T_a,T_a\n0,1,2\n", ["appears twice"]),
    ],
)
def test_bad_files_name_the_place(write_csv, content, fragments):
    path = write_csv(content)
    with pytest.raises(DataError) as info:
        tr.read_run(path)
    msg = str(info.value)
    assert str(path) in msg
    for f in fragments:
        assert f in msg, msg


def test_not_utf8(write_csv):
    path = write_csv(b"time_s,T_a\n0,\xff\xfe\n")
    with pytest.raises(DataError, match="UTF-8"):
        tr.read_run(path)


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.csv"):
        tr.read_run(tmp_path / "nope.csv")


def test_unknown_column_by_name(write_csv):
    run = tr.read_run(write_csv(GOOD))
    with pytest.raises(MissingColumnError) as info:
        run["T_nope"]
    assert "T_nope" in str(info.value) and "T_spindle" in str(info.value)
    assert isinstance(info.value, KeyError)


def test_unknown_prefix_warns(write_csv):
    with pytest.warns(UserWarning, match="operator"):
        run = tr.read_run(write_csv("time_s,T_a,operator\n0,1,bob\n150,2,alice\n"))
    assert run.names == ["T_a"]


def test_nan_policies(write_csv):
    path = write_csv("time_s,T_a,E_z\n0,20,0\n10,,1\n20,22,2\n30,23,\n")
    with pytest.raises(DataError):
        tr.read_run(path)
    dropped = tr.read_run(path, nan="drop")
    np.testing.assert_array_equal(dropped.time_s, [0, 20])
    assert dropped.dropped_rows == [2, 4]
    filled = tr.read_run(path, nan="interpolate")
    np.testing.assert_allclose(filled["T_a"], [20, 21, 22, 23])
    np.testing.assert_allclose(filled["E_z"], [0, 1, 2, 2])
    with pytest.raises(ParameterError, match="nan"):
        tr.read_run(path, nan="zero")


def test_a_column_with_no_values_is_named_with_what_to_do(write_csv):
    """A sensor channel logged but never connected: every cell blank. Interpolating has nothing
    to fill it from and dropping rows leaves none; both errors name the column and say to remove
    it (before, dropping only said that nothing was left)."""
    path = write_csv("time_s,T_a,T_dead,E_z\n0,20,,0\n10,21,,1\n20,22,,2\n")
    with pytest.raises(DataError, match=r"column `T_dead` has no values at all .*remove the column"):
        tr.read_run(path, nan="interpolate")
    with pytest.raises(DataError, match=r"nothing left after dropping \(`T_dead` has no values at all.*remove that column"):
        tr.read_run(path, nan="drop")


def test_from_frame_equals_csv(write_csv):
    pd = pytest.importorskip("pandas")
    path = write_csv(GOOD)
    df = pd.read_csv(path)
    a, b = tr.read_run(path), tr.Run.from_frame(df)
    assert a.names == b.names
    for n in a.names:
        np.testing.assert_array_equal(a[n], b[n])
    bad = df.assign(T_spindle=["a", "b", "c"])
    with pytest.raises(DataError, match="T_spindle"):
        tr.Run.from_frame(bad)
    with pytest.raises(DataError, match="strictly increasing"):
        tr.Run.from_frame(df.assign(time_s=[0, 0, 1]))


def test_from_frame_polars_like_mapping():
    run = tr.Run.from_frame({"time_s": [0.0, 1.0], "T_a": [1.0, 2.0], "E_x": [0.0, 0.5]})
    assert run.errors == ["E_x"]


def test_slice(write_csv):
    run = tr.read_run(write_csv(GOOD))
    part = run.slice(1)
    assert len(part) == 2 and part["E_z"][0] == 3.2
