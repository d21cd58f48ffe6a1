//! Run I/O and figures of merit.

use std::path::PathBuf;

use numpy::{PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use thermerr_core::dialect::{rename_columns, Dialect, Rename};
use thermerr_core::metrics;
use thermerr_core::run::{NanPolicy, Run};

use crate::{slice1, vec_to_py, PyErrWrap};

fn run_to_dict<'py>(py: Python<'py>, run: Run) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let n = run.len();
    let k = run.names.len();
    let mut data = Vec::with_capacity(n * k);
    for i in 0..n {
        data.extend(run.columns.iter().map(|c| c[i]));
    }
    let arr = numpy::PyArray1::from_vec(py, data).reshape([n, k])?;
    d.set_item("source", run.source)?;
    d.set_item("time_s", vec_to_py(py, run.time_s))?;
    d.set_item("names", run.names)?;
    d.set_item("data", arr)?;
    d.set_item("ignored", run.ignored)?;
    d.set_item("dropped_rows", run.dropped_rows)?;
    d.set_item("interpolated", run.interpolated)?;
    Ok(d)
}

/// Reads and validates a run CSV, its header's names mapped by `rename` (`OLD=NEW` each,
/// `thermerr_core::dialect::Rename`); returns its pieces as a dict (the Python `Run` wraps it).
#[pyfunction]
#[pyo3(signature = (path, nan = "error", delimiter = ",", decimal = ".", rename = Vec::new()))]
fn read_run<'py>(
    py: Python<'py>,
    path: PathBuf,
    nan: &str,
    delimiter: &str,
    decimal: &str,
    rename: Vec<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let policy: NanPolicy = nan.parse().map_err(PyErrWrap)?;
    let d = Dialect::new(delimiter, decimal).map_err(PyErrWrap)?;
    let renames = parse_renames(&rename)?;
    let run = crate::detach(py, || Run::read_csv_with(&path, policy, d, &renames))?;
    run_to_dict(py, run)
}

fn parse_renames(rename: &[String]) -> PyResult<Vec<Rename>> {
    let r: thermerr_core::Result<Vec<Rename>> = rename.iter().map(|r| Rename::parse(r)).collect();
    Ok(r.map_err(PyErrWrap)?)
}

/// A header's names of `source` as `read_run(..., rename=)` reads them
/// (`thermerr_core::dialect::rename_columns`).
#[pyfunction]
fn renamed_header(source: &str, names: Vec<String>, rename: Vec<String>) -> PyResult<Vec<String>> {
    let mut names = names;
    rename_columns(source, &mut names, &parse_renames(&rename)?).map_err(PyErrWrap)?;
    Ok(names)
}

/// Validates in-memory columns (`data` is n × len(names), with `time_s` among the names, or
/// `time` in seconds since the epoch).
#[pyfunction]
#[pyo3(signature = (source, names, data, nan = "error"))]
fn run_from_columns<'py>(
    py: Python<'py>,
    source: &str,
    names: Vec<String>,
    data: PyReadonlyArray2<'py, f64>,
    nan: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let policy: NanPolicy = nan.parse().map_err(PyErrWrap)?;
    let (n, k) = (data.shape()[0], data.shape()[1]);
    let view = data.as_array();
    let columns: Vec<Vec<f64>> = (0..k)
        .map(|j| (0..n).map(|i| view[(i, j)]).collect())
        .collect();
    let run = Run::from_columns(source, names, columns, policy, None).map_err(PyErrWrap)?;
    run_to_dict(py, run)
}

/// A DataFrame's `time` column of ISO-8601 strings in seconds since the epoch (the core's reading
/// of a CSV's `time` cells); `None` is a missing time.
#[pyfunction]
fn iso_seconds<'py>(
    py: Python<'py>,
    source: &str,
    cells: Vec<Option<String>>,
) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
    let cells: Vec<&str> = cells.iter().map(|c| c.as_deref().unwrap_or("")).collect();
    let out = thermerr_core::run::iso_seconds(source, &cells).map_err(PyErrWrap)?;
    Ok(vec_to_py(py, out))
}

/// Whether the core reads a column of this name as data (`T_`, `E_`, `U_`); others are ignored.
#[pyfunction]
fn is_data_column(name: &str) -> bool {
    thermerr_core::run::is_data_column(name)
}

/// Why a cell of `column` is not a number, in the CSV reader's words (`thermerr_core::run`).
#[pyfunction]
fn not_a_number(column: &str, cell: &str) -> String {
    thermerr_core::dialect::not_a_number(column, cell)
}

/// A field delimiter as a user writes it (`tab`, `\\t`, `comma`, `semicolon`, or the character
/// itself) as the character (`thermerr_core::dialect::Dialect::delimiter_named`).
#[pyfunction]
fn delimiter_named(text: &str) -> String {
    thermerr_core::dialect::Dialect::delimiter_named(text).to_string()
}

/// What makes probe `name` of run `source` unfit to be a fit's target, or suspect as a run to
/// score a model on: the line saying that it reads one value in every row
/// (`thermerr_core::guard::Suspect::dead_probe`), the line saying that it fails over some rows
/// (`Suspect::failing_probe`), and the line saying that its first reading is away from zero
/// (`Suspect::start_reading`: a probe not zeroed, a piece of a longer log); None for each that
/// it does not.
#[pyfunction]
fn probe_faults<'py>(
    source: &str,
    name: &str,
    values: PyReadonlyArray1<'py, f64>,
    time: PyReadonlyArray1<'py, f64>,
) -> PyResult<(Option<String>, Option<String>, Option<String>)> {
    use thermerr_core::guard::Suspect;
    let (v, t) = (slice1(&values)?, slice1(&time)?);
    let found = thermerr_core::guard::suspect_readings(source, &[name], &[v], t);
    Ok((
        found.iter().find_map(Suspect::dead_probe),
        found.iter().find_map(Suspect::failing_probe),
        found.iter().find_map(Suspect::start_reading),
    ))
}

/// A temperature of a run to fit on: its values with short spikes bridged
/// (`thermerr_core::run::Run::bridged`) and the line saying so, or, when it fails otherwise (a
/// jump that does not come back within the short gap, `Suspect::fails`), the suspect reading's
/// line; None for what does not apply.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn bridge_column<'py>(
    py: Python<'py>,
    source: &str,
    name: &str,
    values: PyReadonlyArray1<'py, f64>,
    time: PyReadonlyArray1<'py, f64>,
) -> PyResult<(
    Option<Bound<'py, numpy::PyArray1<f64>>>,
    Option<String>,
    Option<String>,
)> {
    let (v, t) = (slice1(&values)?, slice1(&time)?);
    if v.len() != t.len() {
        return Err(PyErrWrap(thermerr_core::Error::Shape(format!(
            "{source}: {name} has {} values for {} times",
            v.len(),
            t.len()
        )))
        .into());
    }
    let one = Run {
        source: source.to_string(),
        time_s: t.to_vec(),
        names: vec![name.to_string()],
        columns: vec![v.to_vec()],
        ignored: Vec::new(),
        dropped_rows: Vec::new(),
        interpolated: 0,
    };
    if let Some((mut mended, bridges)) = one.bridged(&[name]) {
        let said = bridges.first().map(|b| b.said());
        let col = mended.columns.pop().unwrap_or_default();
        return Ok((Some(vec_to_py(py, col)), said, None));
    }
    let failing = thermerr_core::guard::suspect_readings(source, &[name], &[v], t)
        .into_iter()
        .find(|sp| sp.fails())
        .map(|sp| sp.text);
    Ok((None, None, failing))
}

/// Refuses a held-out run holding a stretch of the training run's rows, or rows taken from its
/// log in turn (`thermerr_core::run::check_unseen`): each run's clock and the same columns of
/// each, in one order; one line naming both files and the rows, a `DataError`.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn check_unseen(
    py: Python<'_>,
    train_source: &str,
    train_time: PyReadonlyArray1<'_, f64>,
    train: PyReadonlyArray2<'_, f64>,
    held_source: &str,
    held_time: PyReadonlyArray1<'_, f64>,
    held: PyReadonlyArray2<'_, f64>,
) -> PyResult<()> {
    let columns = |a: &PyReadonlyArray2<'_, f64>| -> Vec<Vec<f64>> {
        let v = a.as_array();
        (0..v.ncols()).map(|j| v.column(j).to_vec()).collect()
    };
    let (t, h) = (columns(&train), columns(&held));
    let (tt, ht) = (
        train_time.as_array().to_vec(),
        held_time.as_array().to_vec(),
    );
    crate::detach_short(py, || {
        let tc: Vec<&[f64]> = t.iter().map(Vec::as_slice).collect();
        let hc: Vec<&[f64]> = h.iter().map(Vec::as_slice).collect();
        use thermerr_core::run::{check_unseen, Logged};
        check_unseen(
            Logged {
                source: train_source,
                time: &tt,
                cols: &tc,
            },
            Logged {
                source: held_source,
                time: &ht,
                cols: &hc,
            },
        )
    })
}

/// Predictions shaped into CNC offsets (`thermerr_core::shape`), from a fresh state: `spec` in
/// the text form `limit=50,rate=2,deadband=0.5,unit=0.1,bits=16`.
#[pyfunction]
fn shape_series<'py>(
    py: Python<'py>,
    spec: &str,
    time: PyReadonlyArray1<'py, f64>,
    y: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
    let mut shaper = thermerr_core::shape::Shaping::parse(spec)
        .and_then(thermerr_core::shape::Shaper::new)
        .map_err(PyErrWrap)?;
    let out = shaper
        .apply_series(slice1(&time)?, slice1(&y)?)
        .map_err(PyErrWrap)?;
    Ok(vec_to_py(py, out))
}

/// Figures of merit of `predicted` against `measured`, as a dict.
#[pyfunction]
#[pyo3(signature = (measured, predicted, zero_tol = None))]
fn scores<'py>(
    py: Python<'py>,
    measured: PyReadonlyArray1<'py, f64>,
    predicted: PyReadonlyArray1<'py, f64>,
    zero_tol: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let s =
        metrics::scores(slice1(&measured)?, slice1(&predicted)?, zero_tol).map_err(PyErrWrap)?;
    let d = PyDict::new(py);
    d.set_item("n", s.n)?;
    d.set_item("rms", s.rms)?;
    d.set_item("max_abs", s.max_abs)?;
    d.set_item("band", s.band)?;
    d.set_item("min_residual", s.min_residual)?;
    d.set_item("max_residual", s.max_residual)?;
    d.set_item("mean_accuracy", s.mean_accuracy)?;
    d.set_item("accuracy_excluded", s.accuracy_excluded)?;
    d.set_item("zero_tol", s.zero_tol)?;
    d.set_item("compensation_rate", s.compensation_rate)?;
    d.set_item("rms_measured", s.rms_measured)?;
    Ok(d)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_run, m)?)?;
    m.add_function(wrap_pyfunction!(run_from_columns, m)?)?;
    m.add_function(wrap_pyfunction!(iso_seconds, m)?)?;
    m.add_function(wrap_pyfunction!(is_data_column, m)?)?;
    m.add_function(wrap_pyfunction!(not_a_number, m)?)?;
    m.add_function(wrap_pyfunction!(delimiter_named, m)?)?;
    m.add_function(wrap_pyfunction!(probe_faults, m)?)?;
    m.add_function(wrap_pyfunction!(bridge_column, m)?)?;
    m.add_function(wrap_pyfunction!(scores, m)?)?;
    m.add_function(wrap_pyfunction!(shape_series, m)?)?;
    m.add_function(wrap_pyfunction!(check_unseen, m)?)?;
    m.add_function(wrap_pyfunction!(renamed_header, m)?)?;
    Ok(())
}
