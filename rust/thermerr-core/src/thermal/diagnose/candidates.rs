//! The extended machines, one per cause and place, and their calibration.

use super::cause::Cause;
use super::score::{self, HeldOut};
use super::{Candidate, Fit, Holdout};
use crate::error::Result;
use crate::portable;
use crate::thermal::calibrate::{
    apply, calibrate, default_params, sensor_drift_param, Calibration, CalibrationOptions,
    FreeParam, Param,
};
use crate::thermal::machine::{Ambient, InputTerm, LinkSpec, Machine, NodeSpec};
use crate::thermal::sim::RunView;
use serde::Serialize;
use std::collections::HashMap;
use std::sync::Mutex;

/// One extension before fitting: the extended machine and its extra free parameters.
#[derive(Clone, Debug)]
pub struct Spec {
    pub cause: Cause,
    pub column: Option<String>,
    pub node: Option<String>,
    pub machine: Machine,
    pub extra: Vec<FreeParam>,
}

impl Spec {
    fn new(cause: Cause, machine: Machine, extra: Vec<FreeParam>) -> Self {
        Spec {
            cause,
            column: None,
            node: None,
            machine,
            extra,
        }
    }
}

/// A positive parameter searched in log space within `[lo, hi]`.
fn log_param(param: Param, lo: f64, hi: f64, start: f64) -> FreeParam {
    FreeParam {
        param,
        log: true,
        lo: portable::ln(lo),
        hi: portable::ln(hi),
        start: portable::ln(start),
        prior: None,
    }
}

fn linear_param(param: Param, lo: f64, hi: f64, start: f64) -> FreeParam {
    FreeParam {
        param,
        log: false,
        lo,
        hi,
        start,
        prior: None,
    }
}

/// The range of a thermal lag's time constant (s); at its floor a lag does nothing.
pub const LAG_RANGE_S: (f64, f64) = (30.0, 30000.0);
/// The range of an unmodelled source's link (W/K); at its floor the source does nothing.
pub const SOURCE_RANGE_W_PER_K: (f64, f64) = (0.01, 200.0);
/// The range of a speed growth's exponent.
pub const GROWTH_EXPONENT_RANGE: (f64, f64) = (0.5, 3.0);

pub(super) fn thermal_lag(m: &Machine, axis: usize) -> Spec {
    let mut lag = m.clone();
    lag.drift[axis].lag_s = Some(1200.0);
    Spec::new(
        Cause::ThermalLag,
        lag,
        vec![log_param(
            Param::Lag(axis),
            LAG_RANGE_S.0,
            LAG_RANGE_S.1,
            1200.0,
        )],
    )
}

/// Only for a measured ambient: a constant one is absorbed by the drift map's offset.
pub(super) fn ambient_coupling(m: &Machine, axis: usize) -> Option<Spec> {
    if !matches!(m.ambient, Ambient::Column(_)) {
        return None;
    }
    let mut amb = m.clone();
    amb.drift[axis].ambient_um_per_k = Some(0.0);
    Some(Spec::new(Cause::AmbientCoupling, amb, Vec::new()))
}

/// One per input that drives a source and moves in the run.
pub(super) fn speed_growth(m: &Machine, axis: usize, run: &RunView<'_>) -> Vec<Spec> {
    let mut inputs: Vec<&str> = m.sources.iter().map(|s| s.input.as_str()).collect();
    inputs.sort_unstable();
    inputs.dedup();
    let mut out = Vec::new();
    for input in inputs {
        let Ok(u) = run.col(input) else { continue };
        let umax = u.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        if umax <= 0.0 {
            continue;
        }
        let mut sg = m.clone();
        sg.drift[axis].inputs.push(InputTerm {
            input: input.to_string(),
            um: 0.0,
            reference: umax,
            exponent: 2.0,
        });
        let k = sg.drift[axis].inputs.len() - 1;
        out.push(Spec::new(
            Cause::SpeedGrowth,
            sg,
            vec![linear_param(
                Param::InputExponent(axis, k),
                GROWTH_EXPONENT_RANGE.0,
                GROWTH_EXPONENT_RANGE.1,
                2.0,
            )],
        ));
    }
    out
}

/// The `T_*` columns of the run that the machine does not use.
pub(super) fn free_columns(m: &Machine, run: &RunView<'_>) -> Vec<String> {
    let used: Vec<String> = m.columns().into_iter().map(|(c, _)| c).collect();
    let mut free: Vec<String> = run
        .cols_with_prefix("T_")
        .into_iter()
        .filter(|c| !used.contains(c))
        .collect();
    free.sort();
    free
}

/// `free` ranked by how strongly each column's rise since the start follows the baseline's
/// training residual of the error axis (|Pearson r| over the fitted rows), strongest first; ties
/// keep the name order. An unmodelled source shows as a residual that tracks its temperature.
pub(super) fn rank_by_residual(
    free: Vec<String>,
    run: &RunView<'_>,
    residual: &[f64],
) -> Result<Vec<String>> {
    let rows = residual.len();
    let mut scored = Vec::with_capacity(free.len());
    for col in free {
        let c = run.col(&col)?;
        let rise: Vec<f64> = c[..rows].iter().map(|v| v - c[0]).collect();
        scored.push((pearson(&rise, residual).abs(), col));
    }
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    Ok(scored.into_iter().map(|(_, c)| c).collect())
}

/// Pearson correlation; 0 when either series is constant.
fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()).max(1) as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (dx, dy) = (x - ma, y - mb);
        sab += dx * dy;
        saa += dx * dx;
        sbb += dy * dy;
    }
    if saa <= 0.0 || sbb <= 0.0 || !(saa * sbb).is_finite() {
        0.0
    } else {
        sab / (saa * sbb).sqrt()
    }
}

/// One per given `T_*` column × simulated node: the column as a boundary node linked to it.
pub(super) fn unmodeled_source(m: &Machine, free_cols: &[String]) -> Vec<Spec> {
    let mut out = Vec::new();
    for col in free_cols {
        for node in m.nodes.iter().filter(|n| n.boundary.is_none()) {
            let mut src = m.clone();
            let name = format!("source_{}", col.trim_start_matches("T_"));
            src.nodes.push(NodeSpec::boundary_on(name.clone(), col));
            src.links.push(LinkSpec {
                between: [node.name.clone(), name],
                w_per_k: 1.0,
            });
            let k = src.links.len() - 1;
            out.push(Spec {
                column: Some(col.clone()),
                node: Some(node.name.clone()),
                ..Spec::new(
                    Cause::UnmodeledSource,
                    src,
                    vec![log_param(
                        Param::Link(k),
                        SOURCE_RANGE_W_PER_K.0,
                        SOURCE_RANGE_W_PER_K.1,
                        1.0,
                    )],
                )
            });
        }
    }
    out
}

/// One per simulated node of the drift map.
pub(super) fn nonlinear_expansion(m: &Machine, axis: usize) -> Vec<Spec> {
    let mut out = Vec::new();
    for name in m.drift[axis].um_per_k.keys() {
        let Some(i) = m.node_index(name) else {
            continue;
        };
        if m.nodes[i].boundary.is_some() {
            continue;
        }
        let mut q = m.clone();
        q.drift[axis].quadratic_um_per_k2.insert(name.clone(), 0.0);
        out.push(Spec {
            node: Some(name.clone()),
            ..Spec::new(Cause::NonlinearExpansion, q, Vec::new())
        });
    }
    out
}

/// One per sensed simulated node.
pub(super) fn sensor_drift(m: &Machine) -> Vec<Spec> {
    let mut out = Vec::new();
    for (i, node) in m.nodes.iter().enumerate() {
        if let (Some(col), None) = (&node.sensor, &node.boundary) {
            out.push(Spec {
                column: Some(col.clone()),
                node: Some(node.name.clone()),
                ..Spec::new(Cause::SensorDrift, m.clone(), vec![sensor_drift_param(i)])
            });
        }
    }
    out
}

/// What every candidate is fitted and scored against.
pub(super) struct Baseline<'a> {
    pub calibration: &'a Calibration,
    pub holdout: &'a Holdout,
    /// Calibration options of the extensions (the baseline's noise levels).
    pub options: CalibrationOptions,
    pub axis_index: usize,
    /// [`node_sensor_mate`], worked out once per diagnosis.
    pub mates: &'a MateMemo,
}

/// [`node_sensor_mate`] by column, kept for a whole diagnosis: every unmodelled-source candidate
/// on a column (screened, then fitted in full, in every round of every axis) asks it again of
/// the same training rows. The key holds everything the answer depends on besides the view: the
/// column, the node sensors, the fitted rows and the ambient.
#[derive(Default)]
pub struct MateMemo(Mutex<HashMap<MateKey, Option<String>>>);

type MateKey = (String, Vec<String>, usize, String);

impl MateMemo {
    /// [`node_sensor_mate`] of `col` on machine `m`, from the memo when it was asked before.
    fn get(&self, m: &Machine, train: &RunView<'_>, rows: usize, col: &str) -> Option<String> {
        let sensors = m.nodes.iter().filter_map(|n| n.sensor.clone()).collect();
        let ambient = match &m.ambient {
            Ambient::Column(c) => c.clone(),
            Ambient::Constant(v) => format!("{:x}", v.to_bits()),
        };
        let key = (col.to_string(), sensors, rows, ambient);
        let lock = || self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(v) = lock().get(&key) {
            return v.clone();
        }
        let v = node_sensor_mate(m, train, rows, col);
        lock().insert(key, v.clone());
        v
    }
}

impl<'a> Baseline<'a> {
    pub fn new(
        calibration: &'a Calibration,
        holdout: &'a Holdout,
        options: CalibrationOptions,
        axis_index: usize,
        mates: &'a MateMemo,
    ) -> Self {
        Baseline {
            calibration,
            holdout,
            options,
            axis_index,
            mates,
        }
    }
}

/// The start of a search from the calibrated baseline's values (where the spec's machine has
/// them; extension parameters keep their own start).
fn warm_start(mut free: Vec<FreeParam>, base: &Calibration) -> Vec<FreeParam> {
    let mb = &base.machine;
    for fp in free.iter_mut() {
        let v = match fp.param {
            Param::InitOffset(i) => Some(base.init[i]),
            Param::Capacity(i) => mb.nodes.get(i).map(|n| n.capacity_j_per_k),
            Param::AmbientG(i) => mb.nodes.get(i).map(|n| n.ambient_w_per_k),
            Param::Link(k) => mb.links.get(k).map(|l| l.w_per_k),
            Param::SourceW(k) => mb.sources.get(k).map(|s| s.w),
            Param::SourceExponent(k) => mb.sources.get(k).map(|s| s.exponent),
            _ => None,
        };
        if let Some(v) = v {
            fp.start = if fp.log { portable::ln(v) } else { v };
        }
    }
    free
}

/// Calibrates one extension on `train` (the whole network refitted with it, from the current
/// model's values) and scores it on the held-out data. `screened`: the extension's screening
/// fit, which the full fit nests (the same model with the network held): a full fit that ends
/// fitting the training rows worse than it stopped in a poorer minimum, and is searched again
/// from the screen's values; the better of the two is kept.
pub(super) fn fit(
    spec: Spec,
    base: &Baseline<'_>,
    train: &RunView<'_>,
    held: &HeldOut<'_, '_>,
    screened: Option<&Calibration>,
) -> Result<Candidate> {
    let with_extra = |mut f: Vec<FreeParam>| {
        f.extend(spec.extra.iter().cloned());
        f
    };
    let nominal = default_params(&spec.machine, &base.options);
    let warm = with_extra(warm_start(nominal.clone(), base.calibration));
    let mut cal = calibrate(&spec.machine, train, &base.options, Some(warm))?;
    if let Some(sc) = screened.filter(|sc| cal.ssr > sc.ssr) {
        let from_screen = warm_start(with_extra(nominal.clone()), sc);
        let again = calibrate(&spec.machine, train, &base.options, Some(from_screen))?;
        if again.ssr < cal.ssr {
            cal = again;
        }
    }
    if spec.cause == Cause::SensorDrift {
        // a drifting sensor biases the baseline itself: also fit from the nominal start
        let cold = calibrate(
            &spec.machine,
            train,
            &base.options,
            Some(with_extra(nominal)),
        )?;
        if cold.ssr < cal.ssr {
            cal = cold;
        }
    }
    scored(spec, cal, base, train, held, Fit::Full)
}

/// The screening fit of one extension: the thermal network held at the current model's
/// calibrated values, only the extension's parameters, the initial offsets and the linear drift
/// terms searched. A handful of parameters instead of every capacity and conductance, so each
/// candidate costs a fraction of a full calibration; the best ones are then [`fit`] in full.
pub(super) fn screen(
    spec: Spec,
    base: &Baseline<'_>,
    train: &RunView<'_>,
    held: &HeldOut<'_, '_>,
) -> Result<Candidate> {
    let thermal = warm_start(
        default_params(&spec.machine, &base.options),
        base.calibration,
    );
    let x: Vec<f64> = thermal.iter().map(|f| f.start.clamp(f.lo, f.hi)).collect();
    let (held_machine, _) = apply(&spec.machine, &thermal, &x);
    let opts = CalibrationOptions {
        thermal: false,
        ..base.options.clone()
    };
    let mut free = warm_start(default_params(&held_machine, &opts), base.calibration);
    free.extend(spec.extra.iter().cloned());
    let mut cal = calibrate(&held_machine, train, &opts, Some(free))?;
    // the network's parameters count as fitted (they were, for the current model), so that the
    // BIC compares like with like
    cal.n_params += thermal
        .iter()
        .filter(|f| !matches!(f.param, Param::InitOffset(_)))
        .count();
    scored(spec, cal, base, train, held, Fit::Screen)
}

/// The other sensors on a drifting sensor's part, and what they say of the drift.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Mates {
    /// Temperature columns the machine does not read whose rise over the training rows follows
    /// the sensor's (Pearson r ≥ [`MATE_R`]): other sensors on the same part.
    pub columns: Vec<String>,
    /// The least-squares trend of the sensor minus the mates' mean over the training rows, K/h.
    pub trend_k_per_h: f64,
    /// Whether that trend carries the fitted drift: the same sign and at least
    /// [`MATE_SHARE`] of its size.
    pub corroborate: bool,
}

/// How closely another sensor's rise must follow the drifting sensor's to count as its mate.
pub const MATE_R: f64 = 0.99;
/// The share of a fitted sensor drift that its mates' difference must show.
pub const MATE_SHARE: f64 = 0.5;

/// A sensor drift of `k_per_h` on `col`, checked against the run's other sensors on the same
/// part: a sensor that really drifts leaves its mates behind at its drift rate, while a part that
/// warms (what a network too coarse to follow it would call a drift) takes its mates along.
/// `None` when the run has no mate for `col` (nothing to check: the candidate stands on the
/// diagnosis's other evidence).
pub fn mates(
    m: &Machine,
    train: &RunView<'_>,
    rows: usize,
    col: &str,
    k_per_h: f64,
) -> Option<Mates> {
    let rx = rise_of(train, rows, col)?;
    let n = rx.len();
    let x = train.col(col).ok()?;
    let mut columns = Vec::new();
    let mut mean = vec![0.0; n];
    // in name order, so that the mean is summed the same way on every call
    for c in free_columns(m, train) {
        // r >= MATE_R only, not a lagged copy: the difference's trend below compares raw
        // readings, and a copy's smaller rise (gain 0.8) and lag have trends of their own (a
        // real 0.04 K/h drift on the shop run's T_t1 read -0.048 K/h against its two copies)
        if c == col || !follows(&rx, train, &c) {
            continue;
        }
        let Ok(v) = train.col(&c) else { continue };
        mean.iter_mut().zip(&v[..n]).for_each(|(a, b)| *a += b);
        columns.push(c);
    }
    if columns.is_empty() {
        return None;
    }
    let k = columns.len() as f64;
    let d: Vec<f64> = (0..n).map(|i| x[i] - mean[i] / k).collect();
    let t: Vec<f64> = train.time[..n].iter().map(|s| s / 3600.0).collect();
    let (tm, dm) = (
        t.iter().sum::<f64>() / n as f64,
        d.iter().sum::<f64>() / n as f64,
    );
    let sxx: f64 = t.iter().map(|a| (a - tm).powi(2)).sum();
    let sxy: f64 = t.iter().zip(&d).map(|(a, b)| (a - tm) * (b - dm)).sum();
    let trend = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let corroborate = trend * k_per_h > 0.0 && trend.abs() >= MATE_SHARE * k_per_h.abs();
    Some(Mates {
        columns,
        trend_k_per_h: trend,
        corroborate,
    })
}

/// The node sensor of `m` on whose part `col` sits ([`same_part`]): `col` is then another
/// sensor on a part the network already has, not a heat source outside it (an unmodelled source
/// there would only be that part read twice).
pub fn node_sensor_mate(
    m: &Machine,
    train: &RunView<'_>,
    rows: usize,
    col: &str,
) -> Option<String> {
    let rx = rise_of(train, rows, col)?;
    m.nodes
        .iter()
        .filter_map(|nd| nd.sensor.as_deref())
        .find(|s| same_part(m, train, &rx, col, s))
        .map(str::to_string)
}

/// Whether `col` is a second reading of `m`'s room: its rise over the first `rows` rows follows
/// the ambient column's ([`follows`]). A heat source from it would be the room read twice (an
/// ambient coupling under another name), so the diagnosis does not try it as one.
pub(super) fn reads_the_room(m: &Machine, train: &RunView<'_>, rows: usize, col: &str) -> bool {
    match &m.ambient {
        Ambient::Column(c) if c != col => {
            rise_of(train, rows, col).is_some_and(|rx| follows(&rx, train, c))
        }
        _ => false,
    }
}

/// Whether column `other` reads the same part as `col` (whose [`rise_of`] is `rx`): its rise
/// follows at Pearson r ≥ [`MATE_R`], or one is a lagged copy of the other by identification's
/// rule ([`is_lagged_copy`](crate::thermal::identify::is_lagged_copy)). A second sensor a few
/// minutes behind a fast part (the spindle motor) falls below r = 0.99 while reading that part.
fn same_part(m: &Machine, train: &RunView<'_>, rx: &[f64], col: &str, other: &str) -> bool {
    if follows(rx, train, other) {
        return true;
    }
    let n = rx.len();
    let (Ok(a), Ok(b)) = (train.col(col), train.col(other)) else {
        return false;
    };
    let amb: Vec<f64> = match &m.ambient {
        Ambient::Column(c) => match train.col(c) {
            Ok(v) => v[..n].to_vec(),
            Err(_) => return false,
        },
        Ambient::Constant(v) => vec![*v; n],
    };
    let t = &train.time[..n];
    use crate::thermal::identify::is_lagged_copy;
    is_lagged_copy(t, &a[..n], &b[..n], &amb) || is_lagged_copy(t, &b[..n], &a[..n], &amb)
}

/// A column's rise since its first reading over the first `rows` rows; `None` for a column the
/// run lacks or fewer than three rows.
fn rise_of(train: &RunView<'_>, rows: usize, col: &str) -> Option<Vec<f64>> {
    let v = train.col(col).ok()?;
    let n = rows.min(v.len());
    (n >= 3).then(|| v[..n].iter().map(|a| a - v[0]).collect())
}

/// Whether column `other` rises as `rx` (a [`rise_of`]) does, at Pearson r ≥ [`MATE_R`]: a
/// sensor on the same part.
fn follows(rx: &[f64], train: &RunView<'_>, other: &str) -> bool {
    rise_of(train, rx.len(), other).is_some_and(|r| crate::metrics::pearson(rx, &r) >= MATE_R)
}

fn scored(
    spec: Spec,
    cal: Calibration,
    base: &Baseline<'_>,
    train: &RunView<'_>,
    held: &HeldOut<'_, '_>,
    fit: Fit,
) -> Result<Candidate> {
    let h = score::holdout(&cal, held)?;
    let sensor_gain_pct = match (spec.cause, &spec.column) {
        (Cause::SensorDrift, Some(col)) => score::sensor_gain_pct(base.holdout, &h, col),
        _ => None,
    };
    let rows = base.options.fit_rows.unwrap_or(train.len());
    let mate_of = match (spec.cause, &spec.column) {
        (Cause::UnmodeledSource, Some(col)) => base.mates.get(&spec.machine, train, rows, col),
        _ => None,
    };
    let mates = match (spec.cause, &spec.column, &spec.node) {
        (Cause::SensorDrift, Some(col), Some(node)) => cal
            .machine
            .node_index(node)
            .map(|i| cal.machine.nodes[i].sensor_drift_k_per_h)
            .and_then(|k| mates(&spec.machine, train, rows, col, k)),
        _ => None,
    };
    Ok(Candidate {
        cause: spec.cause,
        parameters: parameters(&spec, &cal.machine, base.axis_index),
        column: spec.column.clone(),
        node: spec.node.clone(),
        delta_bic: cal.bic() - base.calibration.bic(),
        gain_pct: score::gain_pct(base.holdout, &h),
        score: score::joint_score(base.holdout, &h),
        sensor_gain_pct,
        mates,
        mate_of,
        fit,
        converged: cal.converged,
        holdout: h,
        calibration: cal,
        spec: Some(spec),
    })
}

/// The input of a speed-growth extension (its drift entry's last input term).
fn growth_input(s: &Spec, axis: usize) -> Option<&str> {
    (s.cause == Cause::SpeedGrowth)
        .then(|| {
            s.machine.drift[axis]
                .inputs
                .last()
                .map(|t| t.input.as_str())
        })
        .flatten()
}

/// Whether `a` models what the already accepted `b` models: the same cause on the same place
/// (column for a source or a sensor, node for a nonlinear expansion, input for a speed growth;
/// a lag or an ambient coupling is one per axis). Such a candidate is not fitted again.
pub(super) fn overlaps(a: &Spec, b: &Spec, axis: usize) -> bool {
    a.cause == b.cause
        && match a.cause {
            Cause::UnmodeledSource | Cause::SensorDrift => a.column == b.column,
            Cause::NonlinearExpansion => a.node == b.node,
            Cause::SpeedGrowth => growth_input(a, axis) == growth_input(b, axis),
            Cause::ThermalLag | Cause::AmbientCoupling => true,
        }
}

/// Whether `a` is the same extension as `b` (cause, column, node and input).
pub(super) fn same(a: &Spec, b: &Spec, axis: usize) -> bool {
    a.cause == b.cause
        && a.column == b.column
        && a.node == b.node
        && growth_input(a, axis) == growth_input(b, axis)
}

/// The fitted parameters of extension `s` in the calibrated machine `m`, which may carry other
/// extensions too: a source's link and a growth's input term are found by name, not as the last.
pub(super) fn parameters(
    s: &Spec,
    m: &Machine,
    axis: usize,
) -> std::collections::BTreeMap<String, f64> {
    let named = |pairs: &[(&str, f64)]| {
        pairs
            .iter()
            .map(|&(k, v)| (k.to_string(), v))
            .collect::<std::collections::BTreeMap<_, _>>()
    };
    match s.cause {
        Cause::UnmodeledSource => {
            let src = s.machine.links.last().map(|l| &l.between);
            m.links
                .iter()
                .find(|l| Some(&l.between) == src)
                .map_or_else(Default::default, |l| named(&[("w_per_k", l.w_per_k)]))
        }
        Cause::SpeedGrowth => {
            let input = growth_input(s, axis);
            m.drift[axis]
                .inputs
                .iter()
                .find(|t| Some(t.input.as_str()) == input)
                .map_or_else(Default::default, |t| {
                    named(&[("um", t.um), ("exponent", t.exponent), ("ref", t.reference)])
                })
        }
        c => c.parameters(m, axis, s.node.as_deref()),
    }
}

/// The value of an extension parameter of machine `target` in the calibrated machine `from`
/// (matched by name: node, link ends, input), in search space, within the parameter's bounds.
fn carried(fp: &FreeParam, target: &Machine, from: &Machine) -> Option<f64> {
    let v = match fp.param {
        Param::Lag(d) => from.drift.get(d)?.lag_s,
        Param::SensorDrift(i) => from
            .node_index(&target.nodes.get(i)?.name)
            .map(|j| from.nodes[j].sensor_drift_k_per_h),
        Param::InputExponent(d, k) => {
            let input = &target.drift.get(d)?.inputs.get(k)?.input;
            from.drift
                .get(d)?
                .inputs
                .iter()
                .find(|t| &t.input == input)
                .map(|t| t.exponent)
        }
        Param::Link(k) => {
            let ends = &target.links.get(k)?.between;
            from.links
                .iter()
                .find(|l| &l.between == ends)
                .map(|l| l.w_per_k)
        }
        _ => None,
    }?;
    let v = if fp.log {
        portable::ln(v.max(1e-300))
    } else {
        v
    };
    v.is_finite().then(|| v.clamp(fp.lo, fp.hi))
}

/// `extra` (the extension parameters of machine `target`) starting from their values in the
/// calibrated machine `from` where it has them.
pub(super) fn carry(extra: &[FreeParam], target: &Machine, from: &Machine) -> Vec<FreeParam> {
    extra
        .iter()
        .map(|fp| {
            let mut fp = fp.clone();
            if let Some(v) = carried(&fp, target, from) {
                fp.start = v;
            }
            fp
        })
        .collect()
}

/// The extensions `chain` (accepted in this order, each spec carrying its own extension only)
/// rebuilt on the nominal machine `m`: one spec whose machine holds them all and whose extra
/// parameters are all of theirs. `None` if one of them cannot be rebuilt (it cannot happen for a
/// chain that was built on `m`).
pub(super) fn rebuild(
    m: &Machine,
    chain: &[&Spec],
    axis: usize,
    run: &RunView<'_>,
) -> Option<Spec> {
    let mut cur: Option<Spec> = None;
    for own in chain {
        let on = cur.as_ref().map_or(m, |c| &c.machine);
        let cols: Vec<String> = own.column.iter().cloned().collect();
        let next = own
            .cause
            .specs(on, axis, run, &cols)
            .into_iter()
            .find(|s| same(s, own, axis))?;
        cur = Some(match cur {
            None => next,
            Some(prev) => {
                let mut extra = prev.extra;
                extra.extend(next.extra.iter().cloned());
                Spec { extra, ..next }
            }
        });
    }
    cur
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::{NanPolicy, Run};

    const TWO: &str = r#"
name = "two"
ambient = "T_ambient"
[[nodes]]
name = "a"
capacity_j_per_k = 1000.0
ambient_w_per_k = 2.0
sensor = "T_a"
[[nodes]]
name = "b"
capacity_j_per_k = 5000.0
ambient_w_per_k = 4.0
[[links]]
between = ["a", "b"]
w_per_k = 3.0
[[sources]]
node = "a"
input = "U_rpm"
w = 50.0
ref = 1000.0
exponent = 1.0
[[drift]]
axis = "E_z"
um_per_k = { a = 1.0, b = 2.0 }
"#;

    #[test]
    fn a_drift_is_corroborated_only_by_mates_it_leaves_behind() {
        let m = Machine::from_toml(TWO, "two.toml").unwrap();
        // 48 h at 15 min: the part warms 20 K on a first-order curve; T_b and T_c sit on it
        // too, T_far does not follow it (r < 0.99)
        let n = 193;
        let t: Vec<f64> = (0..n).map(|k| 900.0 * k as f64).collect();
        let part: Vec<f64> = t
            .iter()
            .map(|s| 20.0 + 20.0 * (1.0 - portable::exp(-s / 20_000.0)))
            .collect();
        let with = |drift_k_per_h: f64| -> Run {
            let ta: Vec<f64> = part
                .iter()
                .zip(&t)
                .map(|(p, s)| p + drift_k_per_h * s / 3600.0)
                .collect();
            let far: Vec<f64> = t.iter().map(|s| 20.0 + (s / 40_000.0).sin()).collect();
            let names = [
                "time_s",
                "T_ambient",
                "T_a",
                "T_b",
                "T_c",
                "T_far",
                "U_rpm",
                "E_z",
            ];
            let cols = vec![
                t.clone(),
                vec![20.0; n],
                ta,
                part.clone(),
                part.iter().map(|p| p + 0.1).collect(),
                far,
                vec![1000.0; n],
                vec![0.0; n],
            ];
            Run::from_columns(
                "<t>",
                names.iter().map(|s| s.to_string()).collect(),
                cols,
                NanPolicy::Error,
                None,
            )
            .unwrap()
        };
        // the sensor drifts 0.01 K/h (0.5 K over the run, r with its mates still above 0.99):
        // the mates show it
        let run = with(0.01);
        let got = mates(&m, &RunView::new(&run), n, "T_a", 0.01).unwrap();
        assert_eq!(got.columns, ["T_b", "T_c"]);
        assert!((got.trend_k_per_h - 0.01).abs() < 1e-9, "{got:?}");
        assert!(got.corroborate);
        // a drift fitted where the sensor follows its mates exactly: not corroborated
        let run = with(0.0);
        let got = mates(&m, &RunView::new(&run), n, "T_a", 0.01).unwrap();
        assert!(
            got.trend_k_per_h.abs() < 1e-9 && !got.corroborate,
            "{got:?}"
        );
        // the wrong sign is no corroboration either
        assert!(
            !mates(&m, &RunView::new(&with(0.01)), n, "T_a", -0.01)
                .unwrap()
                .corroborate
        );
        // no mate, no check
        assert_eq!(mates(&m, &RunView::new(&run), n, "T_far", 0.01), None);
        // as an unmodelled source, T_b would be the part T_a already measures; T_far would not
        let view = RunView::new(&run);
        assert_eq!(
            node_sensor_mate(&m, &view, n, "T_b").as_deref(),
            Some("T_a")
        );
        assert_eq!(node_sensor_mate(&m, &view, n, "T_far"), None);
    }

    #[test]
    fn a_second_reading_of_the_room_is_the_room_not_a_source() {
        // the room cycles 3 K a day; T_room2 reads it 0.05 K warm, T_part warms on its own
        let m = Machine::from_toml(TWO, "two.toml").unwrap();
        let n = 193;
        let t: Vec<f64> = (0..n).map(|k| 900.0 * k as f64).collect();
        let room: Vec<f64> = t
            .iter()
            .map(|s| 20.0 + 1.5 * (s / 86_400.0 * std::f64::consts::TAU).sin())
            .collect();
        let part: Vec<f64> = t
            .iter()
            .map(|s| 20.0 + 20.0 * (1.0 - portable::exp(-s / 20_000.0)))
            .collect();
        let names = ["time_s", "T_ambient", "T_a", "T_room2", "U_rpm", "E_z"];
        let cols = vec![
            t.clone(),
            room.clone(),
            part,
            room.iter().map(|r| r + 0.05).collect(),
            vec![1000.0; n],
            vec![0.0; n],
        ];
        let names = names.iter().map(|s| s.to_string()).collect();
        let run = Run::from_columns("<t>", names, cols, NanPolicy::Error, None).unwrap();
        let view = RunView::new(&run);
        assert!(reads_the_room(&m, &view, n, "T_room2"));
        assert!(!reads_the_room(&m, &view, n, "T_a"));
        assert!(!reads_the_room(&m, &view, n, "T_ambient"));
    }

    #[test]
    fn a_chain_is_rebuilt_without_one_of_its_extensions_and_keeps_its_fitted_values() {
        let m = Machine::from_toml(TWO, "two.toml").unwrap();
        let names = ["time_s", "T_ambient", "T_a", "U_rpm", "T_x", "T_y", "E_z"];
        let cols = names
            .iter()
            .enumerate()
            .map(|(j, _)| (0..20).map(|k| (k * (j + 1)) as f64).collect())
            .collect();
        let names = names.iter().map(|s| s.to_string()).collect();
        let run = Run::from_columns("<t>", names, cols, NanPolicy::Error, None).unwrap();
        let view = RunView::new(&run);
        let on = |specs: Vec<Spec>, node: &str| {
            specs
                .into_iter()
                .find(|s| s.node.as_deref() == Some(node))
                .unwrap()
        };
        // accepted in this order: a source on T_x at a, a drifting T_a, a source on T_y at b
        let s1 = on(unmodeled_source(&m, &["T_x".into()]), "a");
        let s2 = on(sensor_drift(&s1.machine), "a");
        let s3 = on(unmodeled_source(&s2.machine, &["T_y".into()]), "b");
        let n = m.links.len();
        let full = rebuild(&m, &[&s1, &s2, &s3], 0, &view).unwrap();
        assert_eq!(full.machine.links.len(), n + 2);
        assert_eq!(full.extra.len(), 3);
        // without the first source, the second one's link moves down an index
        let red = rebuild(&m, &[&s2, &s3], 0, &view).unwrap();
        assert_eq!(red.machine.links.len(), n + 1);
        assert_eq!(
            red.machine.links[n].between,
            ["b", "source_y"].map(String::from)
        );
        assert!(matches!(red.extra[1].param, Param::Link(k) if k == n));
        // fitted values are carried by name, not by index
        let mut fitted = full.machine.clone();
        fitted.links[n].w_per_k = 0.5; // T_x → a
        fitted.links[n + 1].w_per_k = 7.5; // T_y → b
        fitted.nodes[0].sensor_drift_k_per_h = 0.2;
        let carried = carry(&red.extra, &red.machine, &fitted);
        assert_eq!(carried[0].start, 0.2);
        assert!((carried[1].start - portable::ln(7.5f64)).abs() < 1e-12);
        assert_eq!(parameters(&s1, &fitted, 0)["w_per_k"], 0.5);
        assert_eq!(parameters(&s3, &fitted, 0)["w_per_k"], 7.5);
        // the same cause on the same column is not tried again, on another column it is
        let again = on(unmodeled_source(&full.machine, &["T_x".into()]), "b");
        assert!(overlaps(&again, &s1, 0) && !overlaps(&s3, &s1, 0));
        assert!(!overlaps(&s2, &s1, 0));
    }
}
