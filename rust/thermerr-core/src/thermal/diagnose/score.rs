//! Held-out figures of a calibrated machine, and how a candidate compares with the baseline.

use super::Holdout;
use crate::error::{Error, Result};
use crate::metrics;
use crate::thermal::calibrate::{
    evaluate, fit_initial_offsets, named_offsets, targets, Calibration,
};
use crate::thermal::sim::RunView;

/// The held-out data: rows `from..` of `run`, simulated from its start.
pub(super) struct HeldOut<'r, 'a> {
    pub run: &'r RunView<'a>,
    pub from: usize,
    /// Readings used to estimate the initial state.
    pub window: usize,
    pub axis: &'r str,
}

/// Scores a calibrated machine on the held-out data.
pub(super) fn holdout(cal: &Calibration, held: &HeldOut<'_, '_>) -> Result<Holdout> {
    let (m, run, from) = (&cal.machine, held.run, held.from);
    // The start. The last part of the training run is the training simulation running on, so
    // it starts where the calibration's fit put it (its initial offsets, fitted on the training
    // rows only). A separate run has a start of its own, estimated from its first readings.
    // (Re-estimating the tail's start from the run's first 20 readings instead put an
    // identified network's slow nodes up to 2 K off, since its first minutes are its weakest
    // fit, and that offset lasting hours was then "explained" by causes: on the 46-h shop runs,
    // 22 causes named on 60 axes with nothing hidden; 7 with the calibrated start. The nominal
    // machines named 55 and 54 of 60.) Either start is reported (`initial_k`), so the figures
    // are reproduced by `Machine.simulate(run, initial_k=...)` from the written TOML.
    let init = if from > 0 {
        cal.init.clone()
    } else {
        fit_initial_offsets(m, run, held.window)?
    };
    let tg = targets(m, run, held.axis)?;
    let (_, sim, _) = evaluate(
        m,
        &init,
        run,
        &tg,
        run.len(),
        cal.sigma_t,
        cal.sigma_e,
        None,
    )?;
    let e = &sim.drift[tg.axis_index].1;
    if from >= run.len() {
        return Err(Error::Shape("the held-out part is empty".into()));
    }
    let y: &[f64] = &tg.error.values;
    // a failing probe's rows are not scored
    let fig = match tg.error.failing.is_empty() {
        true => metrics::scores(&y[from..], &e[from..], None)?,
        false => {
            let (y_kept, e_kept) = (
                tg.error.kept(y, from..run.len()),
                tg.error.kept(e, from..run.len()),
            );
            if y_kept.is_empty() {
                return Err(Error::Shape(format!(
                    "{}: no held-out row of {} can be scored (from row {}): the probe, the room or a boundary fails over all of them; mend those rows, or diagnose the other axes alone (--axis, or axes= in Python)",
                    run.source,
                    held.axis,
                    from + 1
                )));
            }
            metrics::scores(&y_kept, &e_kept, None)?
        }
    };
    let mut joint: f64 = (from..run.len())
        .filter(|&k| tg.error.reads(k))
        .map(|k| ((y[k] - e[k]) / cal.sigma_e).powi(2))
        .sum();
    let nn = m.nodes.len();
    let mut sensor_residuals = Vec::new();
    for sn in &tg.sensors {
        let (i, meas_t) = (sn.node, &*sn.reading.values);
        let node = &m.nodes[i];
        // a failing sensor's rows that are not fitted are not scored either: 0 there
        let res: Vec<f64> = (from..run.len())
            .map(|k| match sn.reading.reads(k) {
                true => {
                    node.sensor_reads(sim.temps[k * nn + i], run.time[k] - run.time[0]) - meas_t[k]
                }
                false => 0.0,
            })
            .collect();
        joint += res.iter().map(|v| (v / cal.sigma_t).powi(2)).sum::<f64>();
        sensor_residuals.push((node.sensor.clone().unwrap_or_default(), res));
    }
    Ok(Holdout {
        initial_k: named_offsets(m, &init),
        rmse_um: fig.rms,
        max_abs_um: fig.max_abs,
        band_um: fig.band,
        joint_ssr: joint,
        predicted: e[from..].to_vec(),
        sensor_residuals,
    })
}

/// 100 · (1 − RMS_ext / RMS_base) of the error axis.
pub(super) fn gain_pct(base: &Holdout, ext: &Holdout) -> f64 {
    100.0 * (1.0 - ext.rmse_um / base.rmse_um.max(1e-300))
}

/// 1 − √(joint SSR_ext / joint SSR_base).
pub(super) fn joint_score(base: &Holdout, ext: &Holdout) -> f64 {
    1.0 - (ext.joint_ssr / base.joint_ssr.max(1e-300)).sqrt()
}

/// The gain (%) on the held-out temperature residual of sensor `col`.
pub(super) fn sensor_gain_pct(base: &Holdout, ext: &Holdout, col: &str) -> Option<f64> {
    match (base.sensor_residual(col), ext.sensor_residual(col)) {
        (Some(b), Some(e)) => {
            let (b, e) = (metrics::rms(b), metrics::rms(e));
            (b > 0.0).then(|| 100.0 * (1.0 - e / b))
        }
        _ => None,
    }
}
