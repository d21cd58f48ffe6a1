//! The thermal network: machine files, simulation, calibration and diagnosis.

use std::path::PathBuf;

use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Arc;

use thermerr_core::progress::Progress;
use thermerr_core::run::Run;
use thermerr_core::thermal::calibrate::{calibrate, CalibrationOptions, Reading};
use thermerr_core::thermal::diagnose::{
    diagnose, diagnose_axes, Cause, DiagnoseOptions, Diagnosis, Verdict,
};
use thermerr_core::thermal::identify::{identify, IdentifyOptions};
use thermerr_core::thermal::{simulate, Init, Machine, RunView};

use crate::{slice1, vec_to_py, PyErrWrap};

/// A run handed over from Python: source, time, names and the n × k data matrix.
fn core_run(
    source: &str,
    time: &PyReadonlyArray1<'_, f64>,
    names: Vec<String>,
    data: &PyReadonlyArray2<'_, f64>,
) -> PyResult<Run> {
    let t = slice1(time)?.to_vec();
    let (n, k) = (data.shape()[0], data.shape()[1]);
    if n != t.len() || k != names.len() {
        return Err(PyErrWrap(thermerr_core::Error::Shape(format!(
            "run data is {n} x {k} for {} times and {} names",
            t.len(),
            names.len()
        )))
        .into());
    }
    let view = data.as_array();
    let columns = (0..k)
        .map(|j| (0..n).map(|i| view[(i, j)]).collect())
        .collect();
    Ok(Run {
        source: source.to_string(),
        time_s: t,
        names,
        columns,
        ignored: Vec::new(),
        dropped_rows: Vec::new(),
        interpolated: 0,
    })
}

/// A machine model (formats.md TOML) — the Python `Machine` wraps it.
#[pyclass(frozen, module = "thermerr_rs._core", name = "MachineModel")]
pub struct PyMachine {
    pub inner: Machine,
    pub file: String,
}

#[pymethods]
impl PyMachine {
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let inner = Machine::load(&path).map_err(PyErrWrap)?;
        Ok(PyMachine {
            inner,
            file: path.display().to_string(),
        })
    }

    #[staticmethod]
    #[pyo3(signature = (text, file = "<string>"))]
    fn from_toml(text: &str, file: &str) -> PyResult<Self> {
        Ok(PyMachine {
            inner: Machine::from_toml(text, file).map_err(PyErrWrap)?,
            file: file.to_string(),
        })
    }

    fn to_toml(&self) -> PyResult<String> {
        Ok(self.inner.to_toml().map_err(PyErrWrap)?)
    }

    /// The machine's fields as JSON text (the TOML's structure, formats.md).
    fn to_json(&self) -> PyResult<String> {
        Ok(self.inner.to_json().map_err(PyErrWrap)?)
    }

    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    #[getter]
    fn file(&self) -> String {
        self.file.clone()
    }

    #[getter]
    fn nodes(&self) -> Vec<String> {
        self.inner.nodes.iter().map(|n| n.name.clone()).collect()
    }

    #[getter]
    fn axes(&self) -> Vec<String> {
        self.inner.drift.iter().map(|d| d.axis.clone()).collect()
    }

    #[getter]
    fn sensors(&self) -> Vec<String> {
        self.inner
            .nodes
            .iter()
            .filter_map(|n| n.sensor.clone())
            .collect()
    }

    /// Every run column the machine reads.
    fn columns(&self) -> Vec<String> {
        self.inner.columns().into_iter().map(|(c, _)| c).collect()
    }

    /// Simulates a run: dict with `nodes` (n × n_nodes), `node_names`, `sensors` {column: series},
    /// `drift` {axis: series}.
    #[pyo3(signature = (source, time, names, data, *, fit_initial = 0, initial_k = None))]
    #[allow(clippy::too_many_arguments)]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        source: &str,
        time: PyReadonlyArray1<'py, f64>,
        names: Vec<String>,
        data: PyReadonlyArray2<'py, f64>,
        fit_initial: usize,
        initial_k: Option<std::collections::BTreeMap<String, f64>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let run = core_run(source, &time, names, &data)?;
        let sim = crate::detach(py, || {
            let view = RunView::new(&run);
            self.inner
                .check_columns(&self.file, &run.source, |c| view.has(c))?;
            view.one_run()?;
            let init = if let Some(named) = &initial_k {
                if fit_initial > 0 {
                    return Err(thermerr_core::Error::InvalidParam {
                        name: "initial_k",
                        reason: "give the start (initial_k) or estimate it (fit_initial), not both"
                            .into(),
                    });
                }
                Init::Offsets(thermerr_core::thermal::calibrate::offsets_by_name(
                    &self.inner,
                    named,
                )?)
            } else if fit_initial > 0 {
                Init::Offsets(thermerr_core::thermal::calibrate::fit_initial_offsets(
                    &self.inner,
                    &view,
                    fit_initial,
                )?)
            } else {
                Init::FirstReading
            };
            simulate(&self.inner, &view, &init)
        })?;
        let d = PyDict::new(py);
        let nn = sim.node_names.len();
        let nodes = numpy::PyArray1::from_vec(py, sim.temps.clone());
        d.set_item(
            "nodes",
            numpy::PyArrayMethods::reshape(&nodes, [sim.temps.len() / nn.max(1), nn])?,
        )?;
        d.set_item("node_names", sim.node_names.clone())?;
        let s = PyDict::new(py);
        for (c, v) in sim.sensors {
            s.set_item(c, vec_to_py(py, v))?;
        }
        d.set_item("sensors", s)?;
        let e = PyDict::new(py);
        for (a, v) in sim.drift {
            e.set_item(a, vec_to_py(py, v))?;
        }
        d.set_item("drift", e)?;
        Ok(d)
    }

    /// Identifies a starting network from a run (thermal::identify); returns the machine and
    /// the summary as JSON text (its `toml` field is the commented file).
    #[staticmethod]
    #[pyo3(signature = (source, time, names, data, holdout = None, *, axes = None, nodes = None, ambient = None, inputs = None, train_fraction = 0.7, train_rows = None, seed = 0, max_iter = 100, progress = None))]
    #[allow(clippy::too_many_arguments)]
    fn identify<'py>(
        py: Python<'py>,
        source: &str,
        time: PyReadonlyArray1<'py, f64>,
        names: Vec<String>,
        data: PyReadonlyArray2<'py, f64>,
        holdout: PyHoldout<'py>,
        axes: Option<Vec<String>>,
        nodes: Option<usize>,
        ambient: Option<String>,
        inputs: Option<Vec<String>>,
        train_fraction: f64,
        train_rows: Option<usize>,
        seed: u64,
        max_iter: usize,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<(PyMachine, String)> {
        let run = core_run(source, &time, names, &data)?;
        let hold = holdout
            .as_ref()
            .map(|(s, t, n, d)| core_run(s, t, n.clone(), d))
            .transpose()?;
        let opts = IdentifyOptions {
            axes: axes.unwrap_or_default(),
            nodes,
            ambient,
            inputs: inputs.unwrap_or_default(),
            train_fraction,
            train_rows,
            seed,
            max_iter,
            progress: progress.as_ref().map(|_| Arc::new(Progress::new())),
            ..IdentifyOptions::default()
        };
        let watch = progress.zip(opts.progress.clone());
        let mut last = None;
        let tick = move |py: Python<'_>| {
            if let Some((cb, counts)) = &watch {
                report_progress(py, cb, counts, &mut last);
            }
        };
        let id = crate::detach_ticking(py, || identify(&run, hold.as_ref(), &opts), tick)?;
        let summary = serde_json::to_string(&id)
            .map_err(|e| PyErrWrap(thermerr_core::Error::Format(e.to_string())))?;
        Ok((
            PyMachine {
                inner: id.machine,
                file: format!("{source} (identified)"),
            },
            summary,
        ))
    }

    /// Calibrates on a run; returns (calibrated machine, info dict).
    #[pyo3(signature = (source, time, names, data, *, axis, bound_factor = 3.0, max_iter = 60))]
    #[allow(clippy::too_many_arguments)]
    fn calibrate<'py>(
        &self,
        py: Python<'py>,
        source: &str,
        time: PyReadonlyArray1<'py, f64>,
        names: Vec<String>,
        data: PyReadonlyArray2<'py, f64>,
        axis: String,
        bound_factor: f64,
        max_iter: usize,
    ) -> PyResult<(PyMachine, Bound<'py, PyDict>)> {
        let run = core_run(source, &time, names, &data)?;
        let opts = CalibrationOptions {
            axis,
            bound_factor,
            max_iter,
            ..CalibrationOptions::default()
        };
        let axis = opts.axis.clone();
        let (cal, figures) = crate::detach(py, || {
            let view = RunView::new(&run);
            self.inner
                .check_columns(&self.file, &run.source, |c| view.has(c))?;
            view.one_run()?;
            let cal = calibrate(&self.inner, &view, &opts, None)?;
            // the axis's RMS over the rows its probe reads, from the fitted start and from the
            // first readings as they are (where a simulation of a run starts)
            let e = Reading::of(&view, &axis)?;
            let mut figures = Vec::new();
            for init in [Init::Offsets(cal.init.clone()), Init::FirstReading] {
                let sim = simulate(&cal.machine, &view, &init)?;
                let pred = sim.drift.iter().find(|(a, _)| *a == axis).map(|(_, p)| p);
                figures.push(pred.map_or(f64::NAN, |p| e.rmse(p, 0..view.len())));
            }
            Ok((cal, figures))
        })?;
        let d = PyDict::new(py);
        d.set_item("sigma_t", cal.sigma_t)?;
        d.set_item("sigma_e", cal.sigma_e)?;
        d.set_item("ssr", cal.ssr)?;
        d.set_item("n_data", cal.n_data)?;
        d.set_item("n_params", cal.n_params)?;
        d.set_item("bic", cal.bic())?;
        d.set_item("n_iter", cal.n_iter)?;
        d.set_item("converged", cal.converged)?;
        d.set_item("init_offsets", cal.init.clone())?;
        d.set_item("axis", &axis)?;
        d.set_item("rmse_um", figures[0])?;
        d.set_item("first_reading_rmse_um", figures[1])?;
        Ok((
            PyMachine {
                inner: cal.machine,
                file: format!("{} (calibrated)", self.file),
            },
            d,
        ))
    }

    /// The full diagnosis; returns a dict: `report` (report.json as JSON text), `calibration`
    /// (the baseline's fit figures), `series` and the calibrated/extended TOML.
    #[pyo3(signature = (source, time, names, data, holdout = None, *, axis = None, holdout_fraction = 0.3, train_rows = None, min_score = 0.1, noise_ratio = 2.0, network = "auto", progress = None))]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn diagnose<'py>(
        &self,
        py: Python<'py>,
        source: &str,
        time: PyReadonlyArray1<'py, f64>,
        names: Vec<String>,
        data: PyReadonlyArray2<'py, f64>,
        holdout: PyHoldout<'py>,
        axis: Option<String>,
        holdout_fraction: f64,
        train_rows: Option<usize>,
        min_score: f64,
        noise_ratio: f64,
        network: &str,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (opts, watch) = diagnose_options(
            axis,
            holdout_fraction,
            train_rows,
            min_score,
            noise_ratio,
            network,
            progress,
        )?;
        let diag = self.on_runs(
            py,
            source,
            &time,
            names,
            &data,
            &holdout,
            watch,
            |m, v, h| diagnose(m, v, h, &opts),
        )?;
        diagnosis_dict(py, &diag, &self.file)
    }

    /// The diagnosis of every axis in `axes`, one per axis in parallel, each on the shared
    /// temperatures and its own error column; a list of `diagnose`'s dicts in `axes` order, and
    /// the axes left out (every drift entry, `axes` empty: a probe with nothing to diagnose) as
    /// `(axis, reason)`.
    #[pyo3(signature = (source, time, names, data, holdout = None, *, axes, holdout_fraction = 0.3, train_rows = None, min_score = 0.1, noise_ratio = 2.0, network = "auto", progress = None))]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn diagnose_axes<'py>(
        &self,
        py: Python<'py>,
        source: &str,
        time: PyReadonlyArray1<'py, f64>,
        names: Vec<String>,
        data: PyReadonlyArray2<'py, f64>,
        holdout: PyHoldout<'py>,
        axes: Vec<String>,
        holdout_fraction: f64,
        train_rows: Option<usize>,
        min_score: f64,
        noise_ratio: f64,
        network: &str,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<(Vec<Bound<'py, PyDict>>, Vec<(String, String)>)> {
        let (opts, watch) = diagnose_options(
            None,
            holdout_fraction,
            train_rows,
            min_score,
            noise_ratio,
            network,
            progress,
        )?;
        let (diags, skipped) = self.on_runs(
            py,
            source,
            &time,
            names,
            &data,
            &holdout,
            watch,
            |m, v, h| diagnose_axes(m, v, h, &axes, &opts),
        )?;
        let diags = diags
            .iter()
            .map(|d| diagnosis_dict(py, d, &self.file))
            .collect::<PyResult<_>>()?;
        Ok((
            diags,
            skipped.into_iter().map(|s| (s.axis, s.reason)).collect(),
        ))
    }
}

/// A held-out run handed over from Python: source, time, names and data.
type PyHoldout<'py> = Option<(
    String,
    PyReadonlyArray1<'py, f64>,
    Vec<String>,
    PyReadonlyArray2<'py, f64>,
)>;

impl PyMachine {
    /// Converts the run (and the held-out run), checks their columns against the machine and
    /// runs `f` on them with the GIL released (Ctrl-C honoured). With `progress`, its callable
    /// gets `(done, planned, stage)` of the counts while `f` runs (see [`report_progress`]).
    #[allow(clippy::too_many_arguments)]
    fn on_runs<'py, T: Send>(
        &self,
        py: Python<'py>,
        source: &str,
        time: &PyReadonlyArray1<'py, f64>,
        names: Vec<String>,
        data: &PyReadonlyArray2<'py, f64>,
        holdout: &PyHoldout<'py>,
        progress: Watch,
        f: impl FnOnce(&Machine, &RunView<'_>, Option<&RunView<'_>>) -> thermerr_core::Result<T> + Send,
    ) -> PyResult<T> {
        let run = core_run(source, time, names, data)?;
        let hold = holdout
            .as_ref()
            .map(|(s, t, n, d)| core_run(s, t, n.clone(), d))
            .transpose()?;
        let mut last = None;
        let tick = move |py: Python<'_>| {
            if let Some((cb, counts)) = &progress {
                report_progress(py, cb, counts, &mut last);
            }
        };
        crate::detach_ticking(
            py,
            || {
                let view = RunView::new(&run);
                self.inner
                    .check_columns(&self.file, &run.source, |c| view.has(c))?;
                let hview = hold.as_ref().map(RunView::new);
                if let Some(h) = &hview {
                    self.inner
                        .check_columns(&self.file, &h.source, |c| h.has(c))?;
                }
                f(&self.inner, &view, hview.as_ref())
            },
            tick,
        )
    }
}

/// A diagnosis's options from the binding's arguments; with a progress callable, the counts it
/// is fed from (the options count into them).
type Watch = Option<(Py<PyAny>, Arc<Progress>)>;

fn diagnose_options(
    axis: Option<String>,
    holdout_fraction: f64,
    train_rows: Option<usize>,
    min_score: f64,
    noise_ratio: f64,
    network: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<(DiagnoseOptions, Watch)> {
    let counts = progress.as_ref().map(|_| Arc::new(Progress::new()));
    let opts = DiagnoseOptions {
        axis,
        holdout_fraction,
        train_rows,
        min_score,
        noise_ratio,
        network: network.parse().map_err(PyErrWrap)?,
        progress: counts.clone(),
        ..DiagnoseOptions::default()
    };
    Ok((opts, progress.zip(counts)))
}

/// Calls a Python progress callable with `(done, planned, stage)` when the counts changed
/// since `last`. A failing callable does not stop the call; a `KeyboardInterrupt` raised in it
/// stops it like Ctrl-C.
fn report_progress(
    py: Python<'_>,
    cb: &Py<PyAny>,
    counts: &Progress,
    last: &mut Option<(usize, usize, usize)>,
) {
    let now = counts.snapshot();
    if *last == Some(now) {
        return;
    }
    *last = Some(now);
    if let Err(e) = cb.call1(py, now) {
        if e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py) {
            thermerr_core::interrupt::request();
        }
    }
}

fn diagnosis_dict<'py>(
    py: Python<'py>,
    diag: &Diagnosis,
    file: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let report = serde_json::to_string(&diag.report(file))
        .map_err(|e| PyErrWrap(thermerr_core::Error::Format(e.to_string())))?;
    out.set_item("report", report)?;
    let cal = PyDict::new(py);
    cal.set_item("bic", diag.baseline.bic())?;
    cal.set_item("sigma_t", diag.baseline.sigma_t)?;
    cal.set_item("sigma_e", diag.baseline.sigma_e)?;
    cal.set_item("n_iter", diag.baseline.n_iter)?;
    cal.set_item("converged", diag.baseline.converged)?;
    out.set_item("calibration", cal)?;
    out.set_item(
        "calibrated_toml",
        diag.baseline.machine.to_toml().map_err(PyErrWrap)?,
    )?;
    out.set_item(
        "extended_toml",
        diag.extended().to_toml().map_err(PyErrWrap)?,
    )?;
    let (base, ext) = (&diag.baseline_holdout, diag.extended_holdout());
    let series = PyDict::new(py);
    series.set_item("time_s", vec_to_py(py, diag.holdout_time.clone()))?;
    series.set_item("measured", vec_to_py(py, diag.holdout_measured.clone()))?;
    series.set_item("baseline", vec_to_py(py, base.predicted.clone()))?;
    series.set_item("extended", vec_to_py(py, ext.predicted.clone()))?;
    if let (Verdict::Cause(Cause::SensorDrift), Some(col)) = (diag.verdict, &diag.column) {
        if let (Some(b), Some(e)) = (base.sensor_residual(col), ext.sensor_residual(col)) {
            let s = PyDict::new(py);
            s.set_item("column", col)?;
            s.set_item("baseline_residual", vec_to_py(py, b.to_vec()))?;
            s.set_item("extended_residual", vec_to_py(py, e.to_vec()))?;
            series.set_item("sensor", s)?;
        }
    }
    out.set_item("series", series)?;
    Ok(out)
}

/// Refuses a run that holds two runs joined (`guard::one_run` on its `T_*` columns): one line
/// naming the source and the row, a `DataError`.
#[pyfunction]
fn one_run(
    py: Python<'_>,
    source: &str,
    time: PyReadonlyArray1<'_, f64>,
    names: Vec<String>,
    data: PyReadonlyArray2<'_, f64>,
) -> PyResult<()> {
    let run = core_run(source, &time, names, &data)?;
    crate::detach(py, || RunView::new(&run).one_run())?;
    Ok(())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(one_run, m)?)?;
    m.add_class::<PyMachine>()
}
