//! Sensor faults on the edge: the `guard` of a model file and the streaming predictor that
//! applies it.
//!
//! A thermocouple that opens reads −273 °C or 1372 °C, a cable that comes loose gives empty
//! fields, a frozen transmitter repeats one value for hours, a ground fault spikes. Fed to a
//! model, each becomes a compensation offset of any size. The guard checks every reading of
//! every feature against limits learnt from the training run ([`Guard::from_training`]):
//!
//! - a plausible range (`min`..`max`): the training range widened by its own span, at least
//!   [`RANGE_MARGIN_FLOOR`] units each way;
//! - a largest rate of change (`max_rate`, units per second) against the last good reading:
//!   [`RATE_FACTOR`] times the fastest change seen in training, at least [`RATE_FLOOR`];
//! - a stuck detector (`stuck_s`): a reading repeated exactly for longer than twice the longest
//!   repeat in training, at least [`STUCK_FLOOR_S`].
//!
//! A faulted reading is replaced by the sensor's last good reading for up to `hold_s` seconds
//! (`held:T_x`). Beyond that the prediction comes from the fallback model fitted without that
//! sensor and stored in the same file (`fallback:T_x`), or, when there is none (two sensors out
//! at once, or a model that carries state from sample to sample), the last output is repeated
//! (`frozen:T_x`). A sensor is good again as soon as a reading passes the checks. Until every
//! sensor has given one good reading nothing is predicted (`waiting:T_x`).
//!
//! Time is the run's `time_s`, or the row count times the training run's median step `step_s`.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::artifact::{Artifact, Header, Predictor};
use crate::error::{Error, Result};
use crate::timeaxis::median_step;

/// The training range is widened by its span, and by at least this many units, each way.
pub const RANGE_MARGIN_FLOOR: f64 = 20.0;
/// The largest rate of change accepted is this many times the fastest seen in training.
pub const RATE_FACTOR: f64 = 5.0;
/// ... and at least this many units per second.
pub const RATE_FLOOR: f64 = 0.01;
/// A value repeated for longer than twice the longest repeat in training, and at least this
/// long (s), is a stuck sensor.
pub const STUCK_FLOOR_S: f64 = 1800.0;
/// Default time a faulted reading is replaced by the last good one (s).
pub const DEFAULT_HOLD_S: f64 = 300.0;

fn format_err(msg: impl Into<String>) -> Error {
    Error::Format(msg.into())
}

/// Limits of one feature's readings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorLimits {
    pub min: f64,
    pub max: f64,
    /// units per second, against the last good reading
    pub max_rate: f64,
    /// seconds one value may repeat before the sensor counts as stuck
    pub stuck_s: f64,
}

/// A model fitted without one feature, used when that feature's sensor has failed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fallback {
    /// the feature it does without
    pub without: String,
    /// a whole model file (without a guard of its own)
    pub model: Value,
}

/// The `guard` entry of a model file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Guard {
    /// one per feature, in the model's order
    pub sensors: Vec<SensorLimits>,
    /// seconds a faulted reading is replaced by the last good one
    pub hold_s: f64,
    /// seconds per row when the input has no `time_s`
    pub step_s: f64,
    #[serde(default)]
    pub fallbacks: Vec<Fallback>,
}

/// A reading the training run repeats exactly for long enough to raise its sensor's `stuck_s`
/// above [`STUCK_FLOOR_S`]: a sensor stuck while the training run was logged (which the model
/// then learnt from, and the guard learnt to accept for twice as long), or a logger's coarse
/// resolution on a steady temperature.
#[derive(Clone, Debug, PartialEq)]
pub struct LongRepeat {
    /// the feature, in the model's order
    pub feature: usize,
    /// the repeat's first row (0-based) and its length (s)
    pub from_row: usize,
    pub seconds: f64,
}

impl Guard {
    /// Limits learnt from a training run: `x` row-major with `d` columns, `times` in seconds
    /// (one per row) or `None` for rows 1 s apart.
    pub fn from_training(x: &[f64], d: usize, times: Option<&[f64]>, hold_s: f64) -> Result<Self> {
        Guard::from_training_with_repeats(x, d, times, hold_s).map(|(g, _)| g)
    }

    /// [`Guard::from_training`], and the training run's [`LongRepeat`]s (the longest of each
    /// sensor that raised its `stuck_s`), for the caller to point out.
    pub fn from_training_with_repeats(
        x: &[f64],
        d: usize,
        times: Option<&[f64]>,
        hold_s: f64,
    ) -> Result<(Self, Vec<LongRepeat>)> {
        if d == 0 || x.len() % d != 0 || x.len() < 2 * d {
            return Err(Error::Shape(format!(
                "the guard needs at least 2 rows of {d} features, got {} values",
                x.len()
            )));
        }
        let n = x.len() / d;
        if let Some(t) = times {
            if t.len() != n {
                return Err(Error::Shape(format!("{} times for {n} rows", t.len())));
            }
        }
        if !(hold_s.is_finite() && hold_s >= 0.0) {
            return Err(Error::param(
                "hold_s",
                format!("must be >= 0 s, got {hold_s}"),
            ));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(Error::Shape(format!(
                "row {}, feature {}: not a finite number",
                i / d,
                i % d
            )));
        }
        let clock: Vec<f64> = (0..n).map(|i| times.map_or(i as f64, |t| t[i])).collect();
        let time = |i: usize| clock[i];
        if let Some(k) = clock
            .windows(2)
            .position(|w| !(w[1] - w[0] > 0.0 && (w[1] - w[0]).is_finite()))
        {
            return Err(Error::Shape(format!(
                "times must increase: row {} is not after row {k}",
                k + 1
            )));
        }
        // every step is positive here, so the median step exists
        let step_s = median_step(&clock).unwrap_or(1.0);
        let mut repeats = Vec::new();
        let sensors = (0..d)
            .map(|j| {
                let col = |i: usize| x[i * d + j];
                let (mut lo, mut hi, mut rate) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
                for i in 0..n {
                    lo = lo.min(col(i));
                    hi = hi.max(col(i));
                    if i > 0 {
                        let dt = time(i) - time(i - 1);
                        rate = rate.max((col(i) - col(i - 1)).abs() / dt);
                    }
                }
                let (repeat_row, repeat) = longest_repeat(n, col, time);
                if 2.0 * repeat > STUCK_FLOOR_S {
                    repeats.push(LongRepeat {
                        feature: j,
                        from_row: repeat_row,
                        seconds: repeat,
                    });
                }
                let margin = (hi - lo).max(RANGE_MARGIN_FLOOR);
                SensorLimits {
                    min: lo - margin,
                    max: hi + margin,
                    max_rate: (RATE_FACTOR * rate).max(RATE_FLOOR),
                    stuck_s: (2.0 * repeat).max(STUCK_FLOOR_S),
                }
            })
            .collect();
        let g = Guard {
            sensors,
            hold_s,
            step_s,
            fallbacks: Vec::new(),
        };
        Ok((g, repeats))
    }

    /// Checks the guard against the model file around it: one limit per feature, finite and
    /// ordered; each fallback a valid model file of a model without state from sample to
    /// sample, reading the same features but the one it does without, for the same target.
    pub fn validate(&self, header: &Header, n_features: usize) -> Result<()> {
        let n_in = header.n_inputs(n_features);
        if self.sensors.len() != n_in {
            return Err(format_err(format!(
                "guard: {} sensor limits for {n_in} features",
                self.sensors.len()
            )));
        }
        let name = |j: usize| {
            header
                .features
                .as_ref()
                .map_or_else(|| format!("feature {j}"), |f| f[j].clone())
        };
        for (j, s) in self.sensors.iter().enumerate() {
            let ok = s.min.is_finite()
                && s.max.is_finite()
                && s.min < s.max
                && s.max_rate.is_finite()
                && s.max_rate > 0.0
                && s.stuck_s.is_finite()
                && s.stuck_s > 0.0;
            if !ok {
                return Err(format_err(format!(
                    "guard: limits of {} must be finite with min < max and max_rate, stuck_s > 0 \
                     (got min {}, max {}, max_rate {}, stuck_s {})",
                    name(j),
                    s.min,
                    s.max,
                    s.max_rate,
                    s.stuck_s
                )));
            }
        }
        if !(self.hold_s.is_finite() && self.hold_s >= 0.0) {
            return Err(format_err(format!(
                "guard: hold_s must be >= 0, got {}",
                self.hold_s
            )));
        }
        if !(self.step_s.is_finite() && self.step_s > 0.0) {
            return Err(format_err(format!(
                "guard: step_s must be > 0, got {}",
                self.step_s
            )));
        }
        if !self.fallbacks.is_empty() {
            self.fallback_predictors(header)?;
        }
        Ok(())
    }

    /// For each feature, the fallback model fitted without it (if there is one), with the
    /// positions of its features among the model's.
    fn fallback_predictors(&self, header: &Header) -> Result<Vec<Option<Stand>>> {
        let features = header.features.as_ref().ok_or_else(|| {
            format_err("guard: fallbacks need the model's feature names (fit it on a run)")
        })?;
        let mut out: Vec<Option<Stand>> = vec![None; features.len()];
        for (k, fb) in self.fallbacks.iter().enumerate() {
            let what = format!("guard: fallback {k} (without {})", fb.without);
            let j = features
                .iter()
                .position(|f| *f == fb.without)
                .ok_or_else(|| {
                    format_err(format!("{what}: the model has no feature {:?}", fb.without))
                })?;
            if out[j].is_some() {
                return Err(format_err(format!("{what}: a second fallback without it")));
            }
            let a = Artifact::from_json(&fb.model.to_string())
                .map_err(|e| format_err(format!("{what}: {e}")))?;
            if a.header.guard.is_some() {
                return Err(format_err(format!("{what}: has a guard of its own")));
            }
            let p = Predictor::new(a);
            if !static_model(&p) {
                return Err(format_err(format!(
                    "{what}: a {} model carries state from sample to sample and cannot stand in",
                    p.kind()
                )));
            }
            let want: Vec<&String> = features.iter().filter(|f| **f != fb.without).collect();
            let got: Vec<&String> = p.features().unwrap_or(&[]).iter().collect();
            if got != want {
                return Err(format_err(format!(
                    "{what}: reads {got:?}, expected the model's features without it ({want:?})"
                )));
            }
            if p.target() != header.target.as_deref() || p.artifact().header.inputs != header.inputs
            {
                return Err(format_err(format!(
                    "{what}: predicts {:?} from {} inputs, the model {:?} from {}",
                    p.target(),
                    p.artifact().header.inputs.as_str(),
                    header.target,
                    header.inputs.as_str()
                )));
            }
            let idx = (0..features.len()).filter(|&i| i != j).collect();
            out[j] = Some((p, idx));
        }
        Ok(out)
    }
}

/// A fallback's predictor and the positions of its features among the model's.
type Stand = (Predictor, Vec<usize>);

/// Whether a model can have fallback models: one whose prediction depends on the current
/// sample only (apart from a rise baseline), as must the fallbacks themselves.
pub fn takes_fallbacks(p: &Predictor) -> bool {
    static_model(p)
}

fn static_model(p: &Predictor) -> bool {
    !p.model().sequential()
        && !p
            .artifact()
            .header
            .preprocessing
            .as_ref()
            .is_some_and(|pre| pre.accumulates())
}

/// What happened to one sensor's reading of the current row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensorStatus {
    Ok,
    /// no good reading yet: nothing can be predicted
    Waiting,
    /// replaced by the last good reading
    Held,
    /// out for longer than `hold_s`; the fallback model without it predicts
    Fallback,
    /// out for longer than `hold_s` and no fallback applies: the last output is repeated
    Frozen,
}

impl SensorStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            SensorStatus::Ok => "ok",
            SensorStatus::Waiting => "waiting",
            SensorStatus::Held => "held",
            SensorStatus::Fallback => "fallback",
            SensorStatus::Frozen => "frozen",
        }
    }
}

#[derive(Clone, Debug)]
struct SensorState {
    last_good: f64,
    last_good_t: f64,
    have_good: bool,
    fault_since: Option<f64>,
    repeat_value: f64,
    repeat_since: f64,
    status: SensorStatus,
}

/// A model with its guard, predicting a run sample by sample from raw readings (NaN for a
/// missing one). Allocates nothing per sample.
#[derive(Clone, Debug)]
pub struct GuardedPredictor {
    main: Predictor,
    guard: Guard,
    names: Vec<String>,
    fallbacks: Vec<Option<Stand>>,
    sensors: Vec<SensorState>,
    x: Vec<f64>,
    xf: Vec<f64>,
    last_y: Option<f64>,
    primed: bool,
    /// Fallbacks primed (their rise baseline set) before the main model: the one without a
    /// sensor that has not read well yet, on the first row where all of its own sensors have.
    fb_primed: Vec<bool>,
    row: usize,
}

impl GuardedPredictor {
    /// The model file's predictor with its guard; `None` when the file has no guard.
    pub fn new(main: Predictor) -> Result<Option<Self>> {
        let header = &main.artifact().header;
        let Some(guard) = header.guard.clone() else {
            return Ok(None);
        };
        let n = main.n_inputs();
        let fallbacks = if static_model(&main) {
            guard.fallback_predictors(header)?
        } else {
            vec![None; n]
        };
        let names = (0..n)
            .map(|j| {
                header
                    .features
                    .as_ref()
                    .map_or_else(|| format!("x{j}"), |f| f[j].clone())
            })
            .collect();
        let fresh = SensorState {
            last_good: 0.0,
            last_good_t: 0.0,
            have_good: false,
            fault_since: None,
            repeat_value: f64::NAN,
            repeat_since: 0.0,
            status: SensorStatus::Waiting,
        };
        Ok(Some(GuardedPredictor {
            main,
            guard,
            names,
            fallbacks,
            sensors: vec![fresh; n],
            x: vec![0.0; n],
            xf: vec![0.0; n.saturating_sub(1)],
            last_y: None,
            primed: false,
            fb_primed: vec![false; n],
            row: 0,
        }))
    }

    pub fn predictor(&self) -> &Predictor {
        &self.main
    }

    /// Seconds per row used when the input has no times.
    pub fn step_s(&self) -> f64 {
        self.guard.step_s
    }

    /// Forgets the run so far.
    pub fn reset(&mut self) {
        self.main.reset();
        for (p, _) in self.fallbacks.iter_mut().flatten() {
            p.reset();
        }
        for s in &mut self.sensors {
            s.have_good = false;
            s.fault_since = None;
            s.repeat_value = f64::NAN;
            s.status = SensorStatus::Waiting;
        }
        self.last_y = None;
        self.primed = false;
        self.fb_primed.iter_mut().for_each(|p| *p = false);
        self.row = 0;
    }

    /// Fixes the rise reference of the main model and of each fallback (its own sensors'
    /// readings of `x`, one per feature of the main model): [`Predictor::set_reference`].
    pub fn set_reference(&mut self, x: &[f64]) -> Result<()> {
        self.main.set_reference(x)?;
        for (p, idx) in self.fallbacks.iter_mut().flatten() {
            let sub: Vec<f64> = idx.iter().map(|&i| x[i]).collect();
            p.set_reference(&sub)?;
        }
        Ok(())
    }

    /// One row of raw readings (NaN for a missing one) at time `t` (seconds; `None` for the
    /// row count times `step_s`): the prediction, or `None` while some sensor has not given a
    /// good reading yet. [`GuardedPredictor::write_status`] tells what was done.
    pub fn step(&mut self, t: Option<f64>, raw: &[f64]) -> Result<Option<f64>> {
        let n = self.x.len();
        if raw.len() != n {
            return Err(Error::Shape(format!(
                "the model takes {n} features, got {}",
                raw.len()
            )));
        }
        let t = t.unwrap_or(self.row as f64 * self.guard.step_s);
        self.row += 1;
        let hold = self.guard.hold_s;
        let mut waiting = false;
        let (mut dead, mut deads): (Option<usize>, usize) = (None, 0);
        let mut out: Option<usize> = None;
        let mut outs = 0usize;
        for (j, (s, lim)) in self.sensors.iter_mut().zip(&self.guard.sensors).enumerate() {
            let v = raw[j];
            let mut good = v.is_finite() && v >= lim.min && v <= lim.max;
            if good && s.have_good {
                let dt = (t - s.last_good_t).max(self.guard.step_s);
                good = (v - s.last_good).abs() <= lim.max_rate * dt;
            }
            if v.is_finite() {
                if v != s.repeat_value {
                    s.repeat_value = v;
                    s.repeat_since = t;
                } else if t - s.repeat_since > lim.stuck_s {
                    good = false;
                }
            }
            if good {
                s.last_good = v;
                s.last_good_t = t;
                s.have_good = true;
                s.fault_since = None;
                s.status = SensorStatus::Ok;
                self.x[j] = v;
                continue;
            }
            let since = *s.fault_since.get_or_insert(t);
            self.x[j] = s.last_good;
            s.status = if !s.have_good {
                if t - since > hold {
                    // never a good reading and out beyond hold_s: only the model without it
                    // can predict (a sensor broken when the gateway starts)
                    dead = Some(j);
                    deads += 1;
                } else {
                    waiting = true;
                }
                SensorStatus::Waiting
            } else if t - since <= hold {
                SensorStatus::Held
            } else {
                out = Some(j);
                outs += 1;
                SensorStatus::Frozen
            };
        }
        if waiting || deads > 0 {
            // the model without a sensor that has not read well yet starts its rise baseline
            // on the first row where every one of its own sensors has, as the main model would
            for j in 0..n {
                if self.fb_primed[j] || self.sensors[j].status != SensorStatus::Waiting {
                    continue;
                }
                let sensors = &self.sensors;
                let Some((p, idx)) = self.fallbacks[j].as_mut() else {
                    continue;
                };
                if idx.iter().all(|&i| sensors[i].status == SensorStatus::Ok) {
                    for (f, &i) in self.xf.iter_mut().zip(idx.iter()) {
                        *f = self.x[i];
                    }
                    p.predict_sample_at(Some(t), &self.xf, None)?;
                    self.fb_primed[j] = true;
                }
            }
        }
        if waiting {
            return Ok(None);
        }
        if deads > 0 {
            // a sensor that never read well, out beyond hold_s: its fallback predicts when it
            // is the only one out and has one (the main model is not primed on its filler, so
            // it starts from its first row with every sensor good); otherwise nothing yet
            return match (deads, dead, outs) {
                (1, Some(j), 0) if self.fallbacks[j].is_some() => {
                    let (p, idx) = self.fallbacks[j].as_mut().expect("checked above");
                    for (f, &i) in self.xf.iter_mut().zip(idx.iter()) {
                        *f = self.x[i];
                    }
                    self.sensors[j].status = SensorStatus::Fallback;
                    let y = p.predict_sample_at(Some(t), &self.xf, None)?;
                    self.last_y = Some(y);
                    Ok(Some(y))
                }
                _ => Ok(None),
            };
        }
        let y_main = self.main.predict_sample_at(Some(t), &self.x, None)?;
        if !self.primed {
            // the fallbacks' rise baseline is the run's first sample, as the main model's
            for (k, fb) in self.fallbacks.iter_mut().enumerate() {
                let Some((p, idx)) = fb.as_mut() else {
                    continue;
                };
                if self.fb_primed[k] {
                    continue;
                }
                for (f, &i) in self.xf.iter_mut().zip(idx.iter()) {
                    *f = self.x[i];
                }
                p.predict_sample_at(Some(t), &self.xf, None)?;
            }
            self.primed = true;
        }
        let y = match (outs, out) {
            (0, _) => y_main,
            (1, Some(j)) if self.fallbacks[j].is_some() => {
                let (p, idx) = self.fallbacks[j].as_mut().expect("checked above");
                for (f, &i) in self.xf.iter_mut().zip(idx.iter()) {
                    *f = self.x[i];
                }
                self.sensors[j].status = SensorStatus::Fallback;
                p.predict_sample_at(Some(t), &self.xf, None)?
            }
            _ => self.last_y.unwrap_or(y_main),
        };
        self.last_y = Some(y);
        Ok(Some(y))
    }

    /// Each sensor's status for the last row.
    pub fn statuses(&self) -> impl Iterator<Item = (&str, SensorStatus)> {
        self.names
            .iter()
            .map(String::as_str)
            .zip(self.sensors.iter().map(|s| s.status))
    }

    /// Whether every sensor was good on the last row.
    pub fn all_ok(&self) -> bool {
        self.sensors.iter().all(|s| s.status == SensorStatus::Ok)
    }

    /// The last row's status as written on an output line: `ok`, or the sensors that were not,
    /// e.g. `held:T_3` or `fallback:T_3;held:T_7` (no commas, no allocation).
    pub fn write_status(&self, w: &mut impl std::fmt::Write) -> std::fmt::Result {
        if self.all_ok() {
            return w.write_str("ok");
        }
        let mut first = true;
        for (name, st) in self.statuses() {
            if st == SensorStatus::Ok {
                continue;
            }
            if !first {
                w.write_char(';')?;
            }
            first = false;
            w.write_str(st.as_str())?;
            w.write_char(':')?;
            w.write_str(name)?;
        }
        Ok(())
    }
}

/// The longest stretch over which a column repeats one reading exactly: its first row
/// (0-based) and its length (s); `(0, 0.0)` when no reading repeats.
fn longest_repeat(
    n: usize,
    col: impl Fn(usize) -> f64,
    time: impl Fn(usize) -> f64,
) -> (usize, f64) {
    let (mut best, mut best_row) = (0.0f64, 0usize);
    let mut start = 0usize;
    for i in 1..n {
        if col(i) != col(i - 1) {
            start = i;
        }
        if time(i) - time(start) > best {
            best = time(i) - time(start);
            best_row = start;
        }
    }
    (best_row, best)
}

/// A jump between two readings is suspect when its rate is more than this many times the
/// column's 99th percentile of rates (on a run of under 400 steps, its fifth-largest) ...
pub const JUMP_FACTOR: f64 = 20.0;
/// ... and more than this many units (K, µm) per median step of the run. On the real 46-h run
/// (15 s, 16 temperatures, 5 probes) the largest step of any column is 2.9 K (a fast sensor
/// whose 99th percentile is 0.52 K: 5.5 times it), of any probe 0.79 µm.
pub const JUMP_FLOOR: f64 = 2.0;
/// A temperature steps where two runs were joined ([`one_run`]) when it moves by this many
/// kelvin or more between two readings (above a 0.1-K logger's tick; on the real 46-h run
/// joined to itself the smallest step back at the join is T_t11's 0.36 K) ...
pub const JOIN_FLOOR: f64 = 0.2;
/// ... and that step is either this many times both steps beside it (a jump out of the column's
/// course, where heat moves a temperature over several readings alike) ...
pub const JOIN_ALONE: f64 = 5.0;
/// ... or faster than this many times the column's 99th percentile of rates (half a jump's
/// [`JUMP_FACTOR`]: the first steps of a run that starts with the spindle on are as fast as
/// the step back at the join), and the column does not come back within half the step over
/// the next [`JOIN_AFTER`] readings (a row the logger garbled is a spike in every column).
pub const JOIN_FACTOR: f64 = 10.0;
/// Readings after a step over which a column must stay away ([`JOIN_FACTOR`]).
pub const JOIN_AFTER: usize = 10;

/// A step of the time axis this many times the median step, and at least [`GAP_FLOOR_S`], is a
/// gap in the log.
pub const GAP_FACTOR: f64 = 10.0;
/// The shortest gap said (s): shorter than a lumped network's time constants.
pub const GAP_FLOOR_S: f64 = 600.0;

/// What is done with a probe (an error axis) that jumps, as its suspect line says it.
pub const FAILING_PROBE: &str = "Its readings from a jump away to a jump back (or to the end of the run) are neither fitted nor scored; mend the rows if the change is real";
/// What is done with a probe that reads one value in every row ([`SuspectKind::Constant`]).
pub const CONSTANT_PROBE: &str = "Its axis shows no drift at all: the model's figures on it are of nothing; mend the probe or leave the column out";
/// What is done with the room's column (`T_ambient`) when it reads one value in every row.
pub const CONSTANT_ROOM: &str = "Or a climate-controlled room on a coarse logger: named the room, it is used as read (a constant room)";
/// What is done with a temperature that reads one value in every row ([`SuspectKind::Constant`]).
pub const CONSTANT_TEMPERATURE: &str = "It carries no temperature to model: identification takes it for neither the room nor a node's sensor, and the diagnosis does not try it as a heat source (named in a machine file, it is used as read). Mend the sensor or leave the column out";
/// What is done with a temperature that jumps ([`Suspect::fails`]), as its suspect line says it.
pub const FAILING_TEMPERATURE: &str = "Identification takes it for neither the room nor a node's sensor (unless each failing stretch is a spike of 600 s or less: bridged by a straight line, as a short gap is), and the diagnosis does not try it as a heat source. Over its failing rows (from a jump away to a jump back, or to the end of the run; a sensor that reads one value from the first row until it jumps, from the start): as a node's sensor it is not fitted; as the room or a boundary it is held at its last right reading, and the model is neither fitted nor scored there. Drop the column or mend the rows if the change is real";

/// The rows (0-based, each the reading after the step) where `col` jumps: a step whose rate is
/// more than [`JUMP_FACTOR`] times the column's 99th percentile of rates and [`JUMP_FLOOR`]
/// units per median step or more. `col` has one finite value per row of `time`.
pub fn jump_rows(col: &[f64], time: &[f64]) -> Vec<usize> {
    if time.len() < 3 || col.len() != time.len() {
        return Vec::new();
    }
    let step = median_step(time).unwrap_or(1.0).max(f64::MIN_POSITIVE);
    jump_rows_at(col, time, step)
}

fn jump_rows_at(col: &[f64], time: &[f64], step: f64) -> Vec<usize> {
    steps_beyond(col, time, step, JUMP_FACTOR, JUMP_FLOOR)
}

/// The rows where `col` steps faster than `factor` times its 99th percentile of rates and more
/// than `floor` units per median `step`.
fn steps_beyond(col: &[f64], time: &[f64], step: f64, factor: f64, floor: f64) -> Vec<usize> {
    let n = time.len();
    // the limit is never below the floor: a column whose every rate is within it has no jump
    // (most columns; this pass allocates nothing, and runs once per simulation on the columns
    // that drive the network: by a product, with a margin far above its rounding)
    let floor = floor / step;
    let safe = 0.999 * floor;
    if (1..n).all(|i| (col[i] - col[i - 1]).abs() <= safe * (time[i] - time[i - 1])) {
        return Vec::new();
    }
    let rates: Vec<f64> = (1..n)
        .map(|i| (col[i] - col[i - 1]).abs() / (time[i] - time[i - 1]).max(f64::MIN_POSITIVE))
        .collect();
    let mut sorted = rates.clone();
    // the 99th percentile, but never one of the four largest: on a short run (under 400
    // steps) a spike's two steps would otherwise be the percentile itself and hide
    let at =
        (((sorted.len() - 1) as f64 * 0.99).round() as usize).min(sorted.len().saturating_sub(5));
    let (_, &mut q99, _) = sorted.select_nth_unstable_by(at, f64::total_cmp);
    let limit = (factor * q99).max(floor);
    (1..n).filter(|&i| rates[i - 1] > limit).collect()
}

/// The rows of a sensor that fails in the run, not to be fitted. A column that jumps
/// ([`jump_rows`]) is taken as right before its first jump. A jump away from the last right
/// reading starts a failing stretch; a later jump ends it if it lands back near that reading
/// (within half the jump's own size: the column returns, wherever the machine took it
/// meanwhile); a stretch no jump ends runs to the end of the run. So a spike, a loose contact
/// or a transmitter stuck at its rail for a while fail from the jump out to the jump back, and
/// an open thermocouple from its fall to the end; a spike that decays over a few readings ends
/// when the column is about back, and a jump further towards the last right reading after that
/// opens no stretch. A column that reads one value from its first row until its first jump
/// and then varies, never near that value again (a sensor connected late, a thermocouple open
/// until mended: [`dead_until`]), fails from the start to that jump. Half-open row ranges, in
/// order; empty for a column that never jumps.
pub fn failing_rows(col: &[f64], time: &[f64]) -> Vec<std::ops::Range<usize>> {
    if col.iter().any(|v| !v.is_finite()) {
        return Vec::new();
    }
    failing_of(col, time, &jump_rows(col, time))
}

/// The failing rows of `col` ([`failing_rows`]) when each failing stretch is a short spike: it
/// starts after the first row, a jump brings the column back before the run ends, and it spans
/// [`GAP_FLOOR_S`] or less from the last right reading to the first right one again (a gap in a
/// log that short is not said: a lumped network's time constants are longer, and a straight line
/// between the right readings misses little). `None` when the column never fails, or when a
/// stretch is longer or open (a sensor dead from the start, or until the end).
pub fn short_failures(col: &[f64], time: &[f64]) -> Option<Vec<std::ops::Range<usize>>> {
    let rows = failing_rows(col, time);
    let short = |r: &std::ops::Range<usize>| {
        r.start >= 1 && r.end < col.len() && time[r.end] - time[r.start - 1] <= GAP_FLOOR_S
    };
    (!rows.is_empty() && rows.iter().all(short)).then_some(rows)
}

/// Whether `col` reads one value from its first row to the jump at row `j` (0-based), for
/// [`STUCK_FLOOR_S`] or longer, varies after it, and never comes back within half the jump of
/// that value: a sensor connected late, or a thermocouple open until it was mended. (An open
/// sensor that falls to its rail at `j` reads one value after the jump, not before it.)
fn dead_until(col: &[f64], time: &[f64], j: usize) -> bool {
    let first = col[0];
    let half = 0.5 * (col[j] - col[j - 1]).abs();
    j >= 2
        && time[j - 1] - time[0] >= STUCK_FLOOR_S
        && col[..j].iter().all(|&v| v == first)
        && col[j..].iter().any(|&v| v != col[j])
        && col[j..].iter().all(|&v| (v - first).abs() > half)
}

/// [`failing_rows`] from the column's jumps.
fn failing_of(col: &[f64], time: &[f64], jumps: &[usize]) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    // a sensor dead from the first row (one reading, its rail value, for [`STUCK_FLOOR_S`] or
    // longer) that comes alive at its first jump and never reads near that value again: its
    // failing rows are the ones before the jump, and its later jumps are judged from there
    let jumps = match jumps.first() {
        Some(&j) if dead_until(col, time, j) => {
            out.push(0..j);
            &jumps[1..]
        }
        _ => jumps,
    };
    // (row the failing stretch started, the last right reading)
    let mut open: Option<(usize, f64)> = None;
    // the right reading before the last stretch that closed: a jump further towards it (the
    // rest of a decaying spike) opens no stretch
    let mut before: Option<f64> = None;
    for &j in jumps {
        match open {
            None => {
                let towards = before.is_some_and(|r| (col[j] - r).abs() < (col[j - 1] - r).abs());
                if !towards {
                    open = Some((j, col[j - 1]));
                }
            }
            Some((start, right)) => {
                if (col[j] - right).abs() <= 0.5 * (col[j] - col[j - 1]).abs() {
                    out.push(start..j);
                    open = None;
                    before = Some(right);
                }
            }
        }
    }
    if let Some((start, _)) = open {
        out.push(start..col.len());
    }
    out
}

/// What a run is, for a file that holds more than one: said when the time goes back to the first row's
/// (the run reader) and when most temperatures step at one row ([`one_run`]).
pub const ONE_RUN: &str = "a second run appended to the first? A run is one stretch of the machine's time, simulated from its first readings: give each run as a file of its own (the diagnosis takes a second as --holdout)";

/// Refuses a run in which at least half of `cols` (three or more) step at the same row
/// ([`JOIN_FLOOR`], [`JOIN_ALONE`], [`JOIN_FACTOR`], [`JOIN_AFTER`]), other than after a gap in
/// the log (which is said as one): one sensor's fault moves one column (a logger module's, the
/// few on it), and heat moves a temperature over several readings; most temperatures stepping
/// at once between two readings and staying there is the machine's state changing
/// under the log: two runs joined into one file with its clock running on, or the log resumed
/// after the machine was reset. Taken as sensor faults, those columns would fail from there on
/// and nothing after it would be fitted or scored; simulated through, the network would be
/// asked to jump. A join where the machine is back about where the first run started (cooled
/// over a night) is no such step, and the network runs through it as through one run. One line
/// naming the file, the row and the columns. `cols` are temperatures: a probe measured now and
/// then and held between (a touch probe's cycle) steps at each measurement, all probes at once.
pub fn one_run(source: &str, names: &[&str], cols: &[&[f64]], time: &[f64]) -> Result<()> {
    let n = time.len();
    if n < 3 || cols.len() < 3 {
        return Ok(());
    }
    let step = median_step(time).unwrap_or(1.0).max(f64::MIN_POSITIVE);
    let gap_limit = (GAP_FACTOR * step).max(GAP_FLOOR_S);
    let mut at: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for (c, col) in cols.iter().enumerate() {
        if col.len() != n || col.iter().any(|v| !v.is_finite()) {
            continue;
        }
        let d = |i: usize| (col[i] - col[i - 1]).abs();
        let fast = steps_beyond(col, time, step, JOIN_FACTOR, 0.0);
        for j in 1..n {
            let a = d(j);
            if a < JOIN_FLOOR || time[j] - time[j - 1] >= gap_limit {
                continue;
            }
            let beside =
                if j >= 2 { d(j - 1) } else { 0.0 }.max(if j + 1 < n { d(j + 1) } else { 0.0 });
            let stays = col[j..n.min(j + JOIN_AFTER)]
                .iter()
                .all(|v| (v - col[j - 1]).abs() > 0.5 * a);
            if stays && (a >= JOIN_ALONE * beside || fast.binary_search(&j).is_ok()) {
                at.entry(j).or_default().push(c);
            }
        }
    }
    let need = cols.len().div_ceil(2).max(3);
    let Some((&row, which)) = at.iter().find(|(_, w)| w.len() >= need) else {
        return Ok(());
    };
    // the largest steps first
    let step = |c: usize| cols[c][row] - cols[c][row - 1];
    let mut largest = which.clone();
    largest.sort_by(|&a, &b| step(b).abs().total_cmp(&step(a).abs()));
    let show: Vec<String> = largest
        .iter()
        .take(4)
        .map(|&c| format!("{} by {:.3} K", names[c], step(c)))
        .collect();
    Err(Error::Parse {
        file: source.to_string(),
        line: None,
        row: Some(row as u64 + 1),
        column: None,
        reason: format!(
            "{} of the {} temperature columns step at once, each far faster than it moves otherwise ({}{}), where a sensor's fault moves its own column: the machine's state changed between two readings, {ONE_RUN}",
            which.len(),
            cols.len(),
            show.join(", "),
            if which.len() > show.len() { ", ..." } else { "" },
        ),
    })
}

/// A probe's first right reading (not in `failing`) when it is further from zero than the probe
/// moves over the whole run (its largest right reading less its smallest): an error measured
/// from the run's start is about zero there, so this one is a raw reading (a capacitive probe's
/// gap) and the error is taken from that reading.
pub fn probe_offset(col: &[f64], failing: &[std::ops::Range<usize>]) -> Option<f64> {
    let (_, start, span) = probe_start(col, failing)?;
    (start.abs() > span).then_some(start)
}

/// A probe's first right reading (not in `failing`): its row, the reading, and what the right
/// readings span (largest less smallest). The start is the first right reading, its noise and
/// all: the mean of the first five readings, tried, took in the drift of the run's first
/// minutes instead (2 µm on the simulated VMC at 120 s per reading, against 0.2 µm of noise).
fn probe_start(col: &[f64], failing: &[std::ops::Range<usize>]) -> Option<(usize, f64, f64)> {
    let right = || {
        col.iter()
            .enumerate()
            .filter(|(k, v)| v.is_finite() && !failing.iter().any(|r| r.contains(k)))
    };
    let (row, &start) = right().next()?;
    let (lo, hi) = crate::metrics::min_max(right().map(|(_, v)| *v));
    Some((row, start, hi - lo))
}

/// What makes a reading suspect.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SuspectKind {
    /// A step far faster than the column ever moves otherwise ([`JUMP_FACTOR`], [`JUMP_FLOOR`]):
    /// an open thermocouple, a loose cable, a spike.
    Jump,
    /// One reading repeated exactly for [`STUCK_FLOOR_S`] or longer: a frozen transmitter, or a
    /// logger's coarse resolution on a steady temperature.
    Repeat,
    /// A gap in the log ([`GAP_FACTOR`] median steps and [`GAP_FLOOR_S`] or longer): the logger
    /// stopped, and what the machine did meanwhile is not in the run. `column` is `time_s`.
    Gap,
    /// One reading in every row of the run, [`STUCK_FLOOR_S`] or longer: a dead or disconnected
    /// sensor (an open thermocouple at its rail from the start), a column that carries nothing
    /// to model.
    Constant,
    /// A probe whose first reading is further from zero than it moves over the run
    /// ([`probe_offset`]): a raw reading, not an error from the run's start. It is taken from
    /// its first reading (`size`: that reading, µm).
    Offset,
    /// A probe that moves, but by less than [`SCALE_FLOOR_UM`] over the whole run (`size`: its
    /// range): error columns are in µm (formats.md) and a machine's thermal drift is microns to
    /// tens of microns, so a probe logged in mm (hundredths) looks like this. Said, not changed.
    Scale,
    /// A probe whose first right reading is away from zero ([`START_AWAY_SHARE`] of what it
    /// moves, [`START_AWAY_FLOOR_UM`] or more) but within its movement (not an [`Offset`]): a
    /// run's drift is predicted from its start, where it is 0, so the reading counts against
    /// every model of the run on every row (`size`: that reading, µm). A piece cut from a longer
    /// log with its clock restarted, or a probe not zeroed at the start. Said, not changed.
    ///
    /// [`Offset`]: SuspectKind::Offset
    Start,
}

/// A probe's first right reading further from zero than this share of what it moves over the
/// run is said ([`SuspectKind::Start`]) ...
pub const START_AWAY_SHARE: f64 = 0.1;
/// ... when it is also this far from zero (µm): several times a probe's noise (0.15-0.3 µm).
pub const START_AWAY_FLOOR_UM: f64 = 2.0;

/// A probe whose whole range over the run is below this (µm), but not zero, is said to be in
/// the wrong unit ([`SuspectKind::Scale`]): less than a probe's own noise (0.15-0.3 µm on the
/// synthetic runs, whose drift ranges over 3 µm and more; the real 46-h run's probes over
/// 20-90 µm), and what the real run reads in mm (0.013-0.09).
pub const SCALE_FLOOR_UM: f64 = 0.5;

/// Readings of a run that the run itself makes suspect. A run to be diagnosed or identified has
/// no clean training run to learn a [`Guard`]'s limits from, so each column is judged against
/// its own steps: the guard's stuck floor, and a jump far beyond the column's usual rate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Suspect {
    pub column: String,
    pub kind: SuspectKind,
    /// The first suspect row (1-based, as the run's errors count rows).
    pub row: usize,
    /// How many jumps (1 for a repeat).
    pub count: usize,
    /// The largest jump (the column's units) or the repeat's length (s).
    pub size: f64,
    /// One line for a person: the file, the column, the rows and what to do.
    pub text: String,
}

impl Suspect {
    /// Whether it shows the column failing: a jump (a step far faster than the column ever
    /// moves otherwise, and [`JUMP_FLOOR`] or more per step: an open thermocouple falling to its
    /// rail value, a loose cable), or one reading in every row (a sensor dead throughout; not
    /// `T_ambient`). A repeat is not: a logger's coarse resolution on a steady temperature gives
    /// one too. Identification takes a failing temperature for neither the
    /// room nor a node's sensor, the diagnosis does not try it as a heat source, and a node's
    /// sensor is not fitted on its [`failing_rows`] ([`FAILING_TEMPERATURE`]).
    pub fn fails(&self) -> bool {
        match self.kind {
            SuspectKind::Jump => true,
            // a room named by convention that reads one value throughout: a climate-controlled
            // room on a coarse logger is a room all the same ([`CONSTANT_ROOM`])
            SuspectKind::Constant => self.column != "T_ambient",
            _ => false,
        }
    }

    /// A probe (`E_*`) that reads one value in every row, in one line naming the run and the
    /// probe ("run.csv: E_ch4 reads one value (12.5) in every row (166710 s): the probe does not
    /// move"); `None` for any other suspect. It has no drift to model, map or diagnose: the one
    /// rule by which `thermerr fit` refuses it, `thermerr init` leaves it out and the diagnosis
    /// of every axis skips it.
    pub fn dead_probe(&self) -> Option<String> {
        if self.kind != SuspectKind::Constant || !self.column.starts_with("E_") {
            return None;
        }
        let what = self.text.split(": a dead or disconnected").next()?;
        Some(format!("{what}: the probe does not move"))
    }

    /// The line saying that a probe's readings fail over some rows (a jump away, and back or
    /// to the end: [`failing_rows`]), for a fit of that probe, which fits every row as read, so
    /// that a re-zeroed or knocked probe's step enters the model as drift; or None.
    pub fn failing_probe(&self) -> Option<String> {
        if self.kind != SuspectKind::Jump || !self.column.starts_with("E_") {
            return None;
        }
        let what = self.text.split(": a sensor fault").next()?;
        Some(format!(
            "{what}: a probe re-zeroed, knocked or loose? A model fitted on it learns the step \
             as drift (every row is fitted as read): fit on the rows before it (cut the run there) or \
             mend them"
        ))
    }

    /// The line saying that a probe's first reading is away from zero but within its movement
    /// ([`SuspectKind::Start`]), for a run a model is scored on: the model predicts the drift
    /// from the run's start, where it is 0, so the reading counts against it on every row; or
    /// None.
    pub fn start_reading(&self) -> Option<String> {
        (self.kind == SuspectKind::Start && self.column.starts_with("E_"))
            .then(|| self.text.clone())
    }

    /// What shows the column failing, in words: its jumps ([`Suspect::jumps`]), or "reads one
    /// value in every row (166710 s)".
    pub fn fault(&self) -> String {
        match self.kind {
            SuspectKind::Constant => {
                format!("reads one value in every row ({:.0} s)", self.size)
            }
            _ => self.jumps(),
        }
    }

    /// A jump's figures in words: "jumps by up to 60.000 K from one reading to the next (2
    /// times, first at row 101)" (µm for a probe `E_*`).
    pub fn jumps(&self) -> String {
        format!(
            "jumps by up to {:.3} {} from one reading to the next ({} time{}, first at row {})",
            self.size,
            if self.column.starts_with("E_") {
                "µm"
            } else {
                "K"
            },
            self.count,
            if self.count == 1 { "" } else { "s" },
            self.row
        )
    }
}

/// The suspect readings of `cols` (named `names`, one value per row of `time`, finite), from
/// the run `source`: per column, its jumps and its longest exact repeat if
/// [`STUCK_FLOOR_S`] or longer. Nothing is changed: the caller reports them.
pub fn suspect_readings(
    source: &str,
    names: &[&str],
    cols: &[&[f64]],
    time: &[f64],
) -> Vec<Suspect> {
    let n = time.len();
    let mut out = Vec::new();
    if n < 3 {
        return out;
    }
    let step = median_step(time).unwrap_or(1.0).max(f64::MIN_POSITIVE);
    let gap_limit = (GAP_FACTOR * step).max(GAP_FLOOR_S);
    let gaps: Vec<(usize, f64)> = (1..n)
        .map(|i| (i, time[i] - time[i - 1]))
        .filter(|&(_, h)| h >= gap_limit)
        .collect();
    if let Some(&(row, _)) = gaps.first() {
        let (count, longest) = (gaps.len(), gaps.iter().map(|g| g.1).fold(0.0, f64::max));
        out.push(Suspect {
            column: "time_s".into(),
            kind: SuspectKind::Gap,
            row: row + 1,
            count,
            size: longest,
            text: format!(
                "{source}: the log has {count} gap{s} of {gap_limit:.0} s or more (its median step is {step} s), the first before row {}, the longest {longest:.0} s: the logger stopped? Across a gap the model holds the inputs and the room at the reading before it, and what the machine did meanwhile is not in the run; the run is used as read",
                row + 1,
                s = if count == 1 { "" } else { "s" },
            ),
        });
    }
    for (name, col) in names.iter().zip(cols) {
        if col.len() != n || col.iter().any(|v| !v.is_finite()) {
            continue;
        }
        let jumps = jump_rows_at(col, time, step);
        let failing = failing_of(col, time, &jumps);
        if let Some(&first) = jumps.first() {
            let count = jumps.len();
            let largest = jumps
                .iter()
                .map(|&k| (col[k] - col[k - 1]).abs())
                .fold(0.0, f64::max);
            let mut sp = Suspect {
                column: name.to_string(),
                kind: SuspectKind::Jump,
                row: first + 1,
                count,
                size: largest,
                text: String::new(),
            };
            sp.text = format!(
                "{source}: {name} {}, more than {JUMP_FACTOR} times the column's usual fastest change: a sensor fault (an open or loose sensor, a spike)? {}",
                sp.jumps(),
                if name.starts_with("E_") { FAILING_PROBE } else { FAILING_TEMPERATURE },
            );
            out.push(sp);
        }
        let (row, seconds) = longest_repeat(n, |i| col[i], |i| time[i]);
        // a temperature's repeat inside its failing rows (the rail value of an open sensor)
        let in_failing = failing.iter().any(|r| r.contains(&row));
        if row == 0 && seconds >= STUCK_FLOOR_S && seconds >= time[n - 1] - time[0] {
            out.push(Suspect {
                column: name.to_string(),
                kind: SuspectKind::Constant,
                row: 1,
                count: 1,
                size: seconds,
                text: format!(
                    "{source}: {name} reads one value ({}) in every row ({seconds:.0} s): a dead or disconnected {}? {}",
                    col[0],
                    if name.starts_with("E_") { "probe" } else { "sensor" },
                    match *name {
                        n if n.starts_with("E_") => CONSTANT_PROBE,
                        "T_ambient" => CONSTANT_ROOM,
                        _ => CONSTANT_TEMPERATURE,
                    },
                ),
            });
        } else if seconds >= STUCK_FLOOR_S {
            out.push(Suspect {
                column: name.to_string(),
                kind: SuspectKind::Repeat,
                row: row + 1,
                count: 1,
                size: seconds,
                text: format!(
                    "{source}: {name} repeats one reading ({}) for {:.0} s from row {}: {}",
                    col[row],
                    seconds,
                    row + 1,
                    match in_failing {
                        true => "inside the rows of its jump, not fitted",
                        false => "a stuck sensor, or a logger's coarse resolution on a steady temperature? The run is used as read",
                    }
                ),
            });
        }
        if name.starts_with("E_") {
            let (lo, hi) = crate::metrics::min_max(col.iter().copied());
            if hi > lo && hi - lo < SCALE_FLOOR_UM {
                out.push(Suspect {
                    column: name.to_string(),
                    kind: SuspectKind::Scale,
                    row: 1,
                    count: 1,
                    size: hi - lo,
                    text: format!(
                        "{source}: {name} moves by {:.4} over the whole run: error columns are in µm (formats.md), and a machine's thermal drift is microns to tens of microns; a probe logged in mm moves by hundredths. If so, multiply the column by 1000; the run is used as read",
                        hi - lo
                    ),
                });
            }
            if let Some((k, v, span)) = probe_start(col, &failing).filter(|&(_, v, span)| {
                v.abs() <= span && v.abs() > (START_AWAY_SHARE * span).max(START_AWAY_FLOOR_UM)
            }) {
                out.push(Suspect {
                    column: name.to_string(),
                    kind: SuspectKind::Start,
                    row: k + 1,
                    count: 1,
                    size: v,
                    text: format!(
                        "{source}: {name} reads {v:.2} µm at its first right reading, {:.0} % of what it moves over the run ({:.1} µm): a run's drift is predicted from its start, where it is 0, so that reading counts against every model of the run on every row. A piece cut from a longer log with its clock restarted (with the log's clock kept, a held-out run, or `thermerr evaluate --after` the log's earlier rows, takes it as the log's tail), or a probe not zeroed at the start? The run is used as read",
                        100.0 * v.abs() / span,
                        span
                    ),
                });
            }
            if let Some(v) = probe_offset(col, &failing) {
                out.push(Suspect {
                    column: name.to_string(),
                    kind: SuspectKind::Offset,
                    row: 1,
                    count: 1,
                    size: v,
                    text: format!(
                        "{source}: {name} reads {v:.3} µm at its first right reading, further from zero than it moves over the whole run: a raw reading (a probe's gap), not the error from the run's start that formats.md asks for? The error is taken from that reading ({name} - {v:.3})"
                    ),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
