//! Diagnosis: calibrate the nominal machine (the baseline), then for every cause of the
//! catalogue fit the extension that models it, score everything on held-out data, and name the
//! cause whose extension explains the held-out residual — or `none` when the baseline already
//! leaves only noise, or `unexplained` when a structured residual remains that no extension
//! removes.

use std::collections::BTreeMap;

use rayon::prelude::*;

use super::calibrate::{
    calibrate, default_params, evaluate, fit_initial_offsets, targets, Calibration,
    CalibrationOptions, FreeParam, Param,
};
use super::machine::{Ambient, InputTerm, LinkSpec, Machine, NodeSpec};
use super::sim::RunView;
use crate::error::{Error, Result};

/// The causes the diagnosis knows (formats.md, "Diagnosis report").
pub const CAUSES: [&str; 6] = [
    "thermal_lag",
    "ambient_coupling",
    "speed_growth",
    "unmodeled_source",
    "nonlinear_expansion",
    "sensor_drift",
];

/// Options of [`diagnose`].
#[derive(Clone, Debug)]
pub struct DiagnoseOptions {
    /// Error axis (default: the machine's first drift entry).
    pub axis: Option<String>,
    /// Share of the run held out (its end) when no separate held-out run is given.
    pub holdout_fraction: f64,
    /// Samples of a separate held-out run used to estimate its initial state.
    pub init_window: usize,
    /// A candidate must improve the held-out score by at least this to be named.
    pub min_score: f64,
    /// A baseline whose held-out RMS is within this many noise levels is "none".
    pub noise_ratio: f64,
    pub calibration: CalibrationOptions,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            axis: None,
            holdout_fraction: 0.3,
            init_window: 20,
            min_score: 0.1,
            noise_ratio: 2.0,
            calibration: CalibrationOptions::default(),
        }
    }
}

/// Figures of one model on the held-out data.
#[derive(Clone, Debug, Default)]
pub struct Holdout {
    pub rmse_um: f64,
    pub max_abs_um: f64,
    pub band_um: f64,
    /// Σ of squared normalised residuals (error axis and sensed temperatures).
    pub joint_ssr: f64,
    /// Predicted error on the held-out rows.
    pub predicted: Vec<f64>,
    /// (column, predicted − measured reading) per sensor on the held-out rows.
    pub sensor_residuals: Vec<(String, Vec<f64>)>,
}

/// One extension, fitted and scored.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub cause: String,
    pub column: Option<String>,
    pub node: Option<String>,
    pub parameters: BTreeMap<String, f64>,
    pub calibration: Calibration,
    pub delta_bic: f64,
    pub holdout: Holdout,
    /// 100 · (1 − RMS_ext / RMS_base) of the error axis on held-out data.
    pub gain_pct: f64,
    /// 1 − √(joint SSR_ext / joint SSR_base) on held-out data: the share of the normalised
    /// held-out residual (error and temperatures) the extension removes.
    pub score: f64,
    /// For sensor drift: the gain on that sensor's held-out temperature residual (%).
    pub sensor_gain_pct: Option<f64>,
}

/// The outcome of [`diagnose`].
#[derive(Clone, Debug)]
pub struct Diagnosis {
    pub axis: String,
    pub verdict: String,
    pub column: Option<String>,
    pub evidence: String,
    pub noise_um: f64,
    pub baseline: Calibration,
    pub baseline_holdout: Holdout,
    /// Sorted by score, best first.
    pub candidates: Vec<Candidate>,
    /// Index in `candidates` of the named cause, if any.
    pub chosen: Option<usize>,
    /// The held-out description and its time axis and measured error.
    pub holdout_label: String,
    pub holdout_time: Vec<f64>,
    pub holdout_measured: Vec<f64>,
}

impl Diagnosis {
    /// The extended machine: the chosen candidate's, or the baseline when nothing was named.
    pub fn extended(&self) -> &Machine {
        self.chosen
            .map(|i| &self.candidates[i].calibration.machine)
            .unwrap_or(&self.baseline.machine)
    }

    pub fn extended_holdout(&self) -> &Holdout {
        self.chosen
            .map(|i| &self.candidates[i].holdout)
            .unwrap_or(&self.baseline_holdout)
    }

    pub fn gain_pct(&self) -> f64 {
        self.chosen.map_or(0.0, |i| self.candidates[i].gain_pct)
    }
}

struct Spec {
    cause: &'static str,
    column: Option<String>,
    node: Option<String>,
    machine: Machine,
    extra: Vec<FreeParam>,
}

fn candidates(m: &Machine, axis_index: usize, run: &RunView<'_>) -> Vec<Spec> {
    let mut out = Vec::new();
    let axis = m.drift[axis_index].axis.clone();
    let mut lag = m.clone();
    lag.drift[axis_index].lag_s = Some(1200.0);
    out.push(Spec {
        cause: "thermal_lag",
        column: None,
        node: None,
        machine: lag,
        extra: vec![FreeParam {
            param: Param::Lag(axis_index),
            log: true,
            lo: 30f64.ln(),
            hi: 30000f64.ln(),
            start: 1200f64.ln(),
            prior: None,
        }],
    });
    if matches!(m.ambient, Ambient::Column(_)) {
        let mut amb = m.clone();
        amb.drift[axis_index].ambient_um_per_k = Some(0.0);
        out.push(Spec {
            cause: "ambient_coupling",
            column: None,
            node: None,
            machine: amb,
            extra: Vec::new(),
        });
    }
    let mut inputs: Vec<&str> = m.sources.iter().map(|s| s.input.as_str()).collect();
    inputs.sort_unstable();
    inputs.dedup();
    for input in inputs {
        let Ok(u) = run.col(input) else { continue };
        let umax = u.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        if umax <= 0.0 {
            continue;
        }
        let mut sg = m.clone();
        sg.drift[axis_index].inputs.push(InputTerm {
            input: input.to_string(),
            um: 0.0,
            reference: umax,
            exponent: 2.0,
        });
        let k = sg.drift[axis_index].inputs.len() - 1;
        out.push(Spec {
            cause: "speed_growth",
            column: None,
            node: None,
            machine: sg,
            extra: vec![FreeParam {
                param: Param::InputExponent(axis_index, k),
                log: false,
                lo: 0.5,
                hi: 3.0,
                start: 2.0,
                prior: None,
            }],
        });
    }
    let used: Vec<String> = m.columns().into_iter().map(|(c, _)| c).collect();
    let mut free_cols: Vec<String> = run
        .cols_with_prefix("T_")
        .into_iter()
        .filter(|c| !used.contains(c))
        .collect();
    free_cols.sort();
    for col in &free_cols {
        for (j, node) in m.nodes.iter().enumerate() {
            if node.boundary.is_some() {
                continue;
            }
            let mut src = m.clone();
            let name = format!("source_{}", col.trim_start_matches("T_"));
            src.nodes.push(NodeSpec {
                name: name.clone(),
                capacity_j_per_k: 1.0,
                ambient_w_per_k: 0.0,
                sensor: None,
                boundary: Some(col.clone()),
                sensor_offset_k: 0.0,
                sensor_drift_k_per_h: 0.0,
            });
            src.links.push(LinkSpec {
                between: [node.name.clone(), name],
                w_per_k: 1.0,
            });
            let k = src.links.len() - 1;
            out.push(Spec {
                cause: "unmodeled_source",
                column: Some(col.clone()),
                node: Some(m.nodes[j].name.clone()),
                machine: src,
                extra: vec![FreeParam {
                    param: Param::Link(k),
                    log: true,
                    lo: 0.01f64.ln(),
                    hi: 200f64.ln(),
                    start: 1f64.ln(),
                    prior: None,
                }],
            });
        }
    }
    for name in m.drift[axis_index].um_per_k.keys() {
        let Some(i) = m.node_index(name) else {
            continue;
        };
        if m.nodes[i].boundary.is_some() {
            continue;
        }
        let mut q = m.clone();
        q.drift[axis_index]
            .quadratic_um_per_k2
            .insert(name.clone(), 0.0);
        out.push(Spec {
            cause: "nonlinear_expansion",
            column: None,
            node: Some(name.clone()),
            machine: q,
            extra: Vec::new(),
        });
    }
    for (i, node) in m.nodes.iter().enumerate() {
        if let (Some(col), None) = (&node.sensor, &node.boundary) {
            out.push(Spec {
                cause: "sensor_drift",
                column: Some(col.clone()),
                node: Some(node.name.clone()),
                machine: m.clone(),
                extra: vec![FreeParam {
                    param: Param::SensorDrift(i),
                    log: false,
                    lo: -3.0,
                    hi: 3.0,
                    start: 0.0,
                    prior: None,
                }],
            });
        }
    }
    let _ = axis;
    out
}

/// Scores a calibrated machine on the held-out data.
fn score(
    cal: &Calibration,
    axis: &str,
    train: &RunView<'_>,
    hold: Option<&RunView<'_>>,
    split: usize,
    window: usize,
) -> Result<Holdout> {
    let m = &cal.machine;
    // the start is estimated from the first readings, as `Machine.simulate(run, fit_initial=N)`
    // does, so the reported figures can be reproduced from the written TOML alone
    let (run, from) = match hold {
        Some(h) => (h, 0),
        None => (train, split),
    };
    let init = fit_initial_offsets(m, run, window)?;
    let tg = targets(m, run, axis)?;
    let (_, sim, _) = evaluate(
        m,
        &init,
        run,
        &tg,
        run.len(),
        cal.sigma_t,
        cal.sigma_e,
        false,
    )?;
    let e = &sim.drift[tg.axis_index].1;
    let meas = tg.measured_e;
    let r: Vec<f64> = (from..run.len()).map(|k| meas[k] - e[k]).collect();
    if r.is_empty() {
        return Err(Error::Shape("the held-out part is empty".into()));
    }
    let n = r.len() as f64;
    let rmse = (r.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    let (lo, hi) = r
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    let mut joint: f64 = r.iter().map(|v| (v / cal.sigma_e).powi(2)).sum();
    let nn = m.nodes.len();
    let mut sensor_residuals = Vec::new();
    for &(i, meas_t) in &tg.sensors {
        let node = &m.nodes[i];
        let res: Vec<f64> = (from..run.len())
            .map(|k| {
                sim.temps[k * nn + i]
                    + node.sensor_offset_k
                    + node.sensor_drift_k_per_h * (run.time[k] - run.time[0]) / 3600.0
                    - meas_t[k]
            })
            .collect();
        joint += res.iter().map(|v| (v / cal.sigma_t).powi(2)).sum::<f64>();
        sensor_residuals.push((node.sensor.clone().unwrap_or_default(), res));
    }
    Ok(Holdout {
        rmse_um: rmse,
        max_abs_um: lo.abs().max(hi.abs()),
        band_um: hi - lo,
        joint_ssr: joint,
        predicted: e[from..].to_vec(),
        sensor_residuals,
    })
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// Runs the whole diagnosis. `hold`: a separate held-out run; without one the last
/// `holdout_fraction` of `train` is held out (the model still runs through it from the start,
/// but nothing there is fitted).
pub fn diagnose(
    m: &Machine,
    train: &RunView<'_>,
    hold: Option<&RunView<'_>>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis> {
    let axis = match &opts.axis {
        Some(a) => a.clone(),
        None => m
            .drift
            .first()
            .map(|d| d.axis.clone())
            .ok_or_else(|| Error::param("axis", "the machine has no [[drift]] entry"))?,
    };
    let axis_index = m.drift.iter().position(|d| d.axis == axis).ok_or_else(|| {
        Error::param(
            "axis",
            format!("the machine has no drift entry for `{axis}`"),
        )
    })?;
    let n = train.len();
    let split = if hold.is_some() {
        n
    } else {
        if !(0.05..=0.8).contains(&opts.holdout_fraction) {
            return Err(Error::param("holdout_fraction", "must be within 0.05..0.8"));
        }
        ((n as f64) * (1.0 - opts.holdout_fraction)).round() as usize
    };
    let mut copts = opts.calibration.clone();
    copts.axis = axis.clone();
    copts.fit_rows = Some(split);
    let baseline = calibrate(m, train, &copts, None)?;
    let base_hold = score(&baseline, &axis, train, hold, split, opts.init_window)?;
    let mb = &baseline.machine;
    // extensions are built on the nominal machine, so that bounds and priors are the baseline's
    // (centred on the user's estimate); the search starts from the calibrated values
    let specs = candidates(m, axis_index, train);
    let mut copts_ext = copts.clone();
    copts_ext.sigma_t = Some(baseline.sigma_t);
    copts_ext.sigma_e = Some(baseline.sigma_e);
    let fitted: Vec<Result<Candidate>> = specs
        .into_par_iter()
        .map(|spec| {
            let nominal_free = {
                let mut f = default_params(&spec.machine, &copts_ext);
                f.extend(spec.extra.iter().cloned());
                f
            };
            let mut free = default_params(&spec.machine, &copts_ext);
            for fp in free.iter_mut() {
                let v = match fp.param {
                    Param::InitOffset(i) => Some(baseline.init[i]),
                    Param::Capacity(i) => mb.nodes.get(i).map(|n| n.capacity_j_per_k),
                    Param::AmbientG(i) => mb.nodes.get(i).map(|n| n.ambient_w_per_k),
                    Param::Link(k) => mb.links.get(k).map(|l| l.w_per_k),
                    Param::SourceW(k) => mb.sources.get(k).map(|s| s.w),
                    Param::SourceExponent(k) => mb.sources.get(k).map(|s| s.exponent),
                    _ => None,
                };
                if let Some(v) = v {
                    fp.start = if fp.log { v.ln() } else { v };
                }
            }
            free.extend(spec.extra.iter().cloned());
            let mut cal = calibrate(&spec.machine, train, &copts_ext, Some(free))?;
            if spec.cause == "sensor_drift" {
                // a drifting sensor biases the baseline itself: also fit from the nominal start
                let cold = calibrate(&spec.machine, train, &copts_ext, Some(nominal_free))?;
                if cold.ssr < cal.ssr {
                    cal = cold;
                }
            }
            let h = score(&cal, &axis, train, hold, split, opts.init_window)?;
            let mut parameters = BTreeMap::new();
            let d = &cal.machine.drift[axis_index];
            match spec.cause {
                "thermal_lag" => {
                    parameters.insert("tau_s".into(), d.lag_s.unwrap_or(0.0));
                }
                "ambient_coupling" => {
                    parameters.insert("um_per_k".into(), d.ambient_um_per_k.unwrap_or(0.0));
                }
                "speed_growth" => {
                    if let Some(t) = d.inputs.last() {
                        parameters.insert("um".into(), t.um);
                        parameters.insert("exponent".into(), t.exponent);
                        parameters.insert("ref".into(), t.reference);
                    }
                }
                "unmodeled_source" => {
                    if let Some(l) = cal.machine.links.last() {
                        parameters.insert("w_per_k".into(), l.w_per_k);
                    }
                }
                "nonlinear_expansion" => {
                    if let Some(v) = spec
                        .node
                        .as_ref()
                        .and_then(|n| d.quadratic_um_per_k2.get(n))
                    {
                        parameters.insert("um_per_k2".into(), *v);
                    }
                }
                "sensor_drift" => {
                    if let Some(i) = spec.node.as_ref().and_then(|n| cal.machine.node_index(n)) {
                        parameters
                            .insert("k_per_h".into(), cal.machine.nodes[i].sensor_drift_k_per_h);
                    }
                }
                _ => {}
            }
            let sensor_gain_pct = match (spec.cause, &spec.column) {
                ("sensor_drift", Some(col)) => {
                    let find = |h: &Holdout| {
                        h.sensor_residuals
                            .iter()
                            .find(|(c, _)| c == col)
                            .map(|(_, r)| rms(r))
                    };
                    match (find(&base_hold), find(&h)) {
                        (Some(b), Some(e)) if b > 0.0 => Some(100.0 * (1.0 - e / b)),
                        _ => None,
                    }
                }
                _ => None,
            };
            Ok(Candidate {
                cause: spec.cause.to_string(),
                column: spec.column,
                node: spec.node,
                parameters,
                delta_bic: cal.bic() - baseline.bic(),
                gain_pct: 100.0 * (1.0 - h.rmse_um / base_hold.rmse_um.max(1e-300)),
                score: 1.0 - (h.joint_ssr / base_hold.joint_ssr.max(1e-300)).sqrt(),
                sensor_gain_pct,
                holdout: h,
                calibration: cal,
            })
        })
        .collect();
    let mut cands: Vec<Candidate> = fitted.into_iter().collect::<Result<_>>()?;
    cands.sort_by(|a, b| b.score.total_cmp(&a.score));
    let noise = baseline.sigma_e;
    let ratio = base_hold.rmse_um / noise;
    let best = cands
        .iter()
        .position(|c| c.delta_bic < -10.0 && c.score > 0.0);
    let (verdict, column, chosen, evidence) = match best {
        Some(i) if cands[i].score >= opts.min_score => {
            let c = &cands[i];
            let params: Vec<String> = c.parameters.iter().map(|(k, v)| format!("{k} = {v:.4}")).collect();
            let what = match &c.column {
                Some(col) => format!("{} on `{col}`", c.cause),
                None => match &c.node {
                    Some(nd) => format!("{} on node `{nd}`", c.cause),
                    None => c.cause.clone(),
                },
            };
            let sensor = c
                .sensor_gain_pct
                .map(|g| format!(" and the held-out residual of that sensor by {g:.0} %"))
                .unwrap_or_default();
            (
                c.cause.clone(),
                c.column.clone(),
                Some(i),
                format!(
                    "Extending the calibrated model with {what} ({}) cuts the held-out RMS error of {axis} from {:.2} to {:.2} µm ({:.0} %){sensor}; it removes {:.0} % of the normalised held-out residual, the most of {} candidate extensions, and improves the training fit by ΔBIC = {:.0}.",
                    params.join(", "),
                    base_hold.rmse_um,
                    c.holdout.rmse_um,
                    c.gain_pct,
                    100.0 * c.score,
                    cands.len(),
                    c.delta_bic
                ),
            )
        }
        _ if ratio <= opts.noise_ratio => (
            "none".to_string(),
            None,
            None,
            format!(
                "The calibrated model leaves a held-out RMS error of {:.2} µm on {axis}, within {:.1}× the probe noise ({:.2} µm); no extension removes {:.0} % of the held-out residual (best: {}).",
                base_hold.rmse_um,
                ratio,
                noise,
                100.0 * opts.min_score,
                cands.first().map(|c| format!("{} {:.0} %", c.cause, 100.0 * c.score)).unwrap_or_default()
            ),
        ),
        _ => (
            "unexplained".to_string(),
            None,
            None,
            format!(
                "The calibrated model leaves a structured held-out RMS error of {:.2} µm on {axis} ({:.1}× the probe noise of {:.2} µm), and no catalogued extension removes {:.0} % of it (best: {}).",
                base_hold.rmse_um,
                ratio,
                noise,
                100.0 * opts.min_score,
                cands.first().map(|c| format!("{} {:.0} %", c.cause, 100.0 * c.score)).unwrap_or_default()
            ),
        ),
    };
    let (label, time, measured) = match hold {
        Some(h) => (
            format!("the separate run {}", h.source),
            h.time.to_vec(),
            h.col(&axis)?.to_vec(),
        ),
        None => (
            format!(
                "the last {:.0} % of {} ({} of {} samples)",
                100.0 * opts.holdout_fraction,
                train.source,
                n - split,
                n
            ),
            train.time[split..].to_vec(),
            train.col(&axis)?[split..].to_vec(),
        ),
    };
    Ok(Diagnosis {
        axis,
        verdict,
        column,
        evidence,
        noise_um: noise,
        baseline,
        baseline_holdout: base_hold,
        candidates: cands,
        chosen,
        holdout_label: label,
        holdout_time: time,
        holdout_measured: measured,
    })
}
