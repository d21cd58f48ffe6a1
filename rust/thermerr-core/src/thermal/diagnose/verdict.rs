//! The rule that names a cause, or says `none` or `unexplained`.

use std::fmt;

use serde::{Serialize, Serializer};

use super::candidates::{LAG_RANGE_S, SOURCE_RANGE_W_PER_K};
use super::cause::Cause;
use super::{Candidate, DiagnoseOptions, Holdout};

/// A candidate must improve the training fit by at least this much BIC (ΔBIC below it).
pub const MAX_DELTA_BIC: f64 = -10.0;

/// What the diagnosis concludes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The cause whose extension explains the held-out residual.
    Cause(Cause),
    /// The baseline already leaves only noise.
    None,
    /// A structured residual remains that no extension removes.
    Unexplained,
}

impl Verdict {
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Cause(c) => c.as_str(),
            Verdict::None => "none",
            Verdict::Unexplained => "unexplained",
        }
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Serialize for Verdict {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// A sensor drift that removes at least this share (%) of its own sensor's held-out residual may
/// be named although the error axis's held-out RMS does not fall: with a second effect hidden, the
/// drifting reading had been standing in for it, and correcting the reading exposes it (the next
/// round then looks for it). Measured on the compound matrix (seeds 1-2): 28 -> 31 of 60 pairs
/// both named, columns right 25 -> 29 of 40, nothing more named that was not hidden; the
/// single-cause matrix unchanged (79 of 80). 25 % and 75 % gave the same counts.
pub const DRIFT_OWN_GAIN_PCT: f64 = 50.0;

/// Whether a candidate may be named at all: it improves the training fit, removes part of the
/// joint held-out residual, and lowers the held-out RMS of the error axis — or, for a sensor
/// drift, removes most of its own sensor's held-out residual ([`DRIFT_OWN_GAIN_PCT`]). Not: a
/// sensor drift
/// that the sensor's own part-mates contradict (they drift with it: the part warms, the sensor
/// is fine), nor a sensor drift that leaves that sensor's own held-out residual no better (a
/// drift goes on past the training rows, so correcting it must help there too; measured on a real
/// 46-h run: a drift named on `T_t16` from a network stand-in worsened it by 8 %), nor an
/// unmodelled source whose column is another sensor on a part the network already has
/// (`mate_of`), nor a lag or a source left at the floor of its range ([`at_floor`]; such a
/// candidate may still lead or join a pair, whose joint fit searches its term again).
pub fn supported(c: &Candidate) -> bool {
    c.delta_bic < MAX_DELTA_BIC
        && c.score > 0.0
        && (c.gain_pct > 0.0 || c.sensor_gain_pct.is_some_and(|g| g >= DRIFT_OWN_GAIN_PCT))
        && nameable(c)
        && at_floor(c).is_none()
}

/// The conditions of [`supported`] on the candidate's column, whatever its figures: its part's
/// other sensors do not contradict a sensor drift, a drift's own sensor is no worse held out,
/// and a source's column is not another sensor on a part the network has.
pub fn nameable(c: &Candidate) -> bool {
    c.mates.as_ref().is_none_or(|m| m.corroborate)
        && c.sensor_gain_pct.is_none_or(|g| g > 0.0)
        && c.mate_of.is_none()
}

/// A candidate's own term within this factor of the floor of its range has not left it.
pub const FLOOR_FACTOR: f64 = 1.5;

/// The parameter, its value and its floor when a lag or an unmodelled source ended at the floor
/// of its range ([`FLOOR_FACTOR`]): there the extension does nothing, and what the candidate
/// gains is the refit of the network that comes with it, not the cause. Seen 2026-11-28 on the
/// real 46-h run, an identified network calibrated within a factor 10 (a trial): a source from
/// `T_t11` ended at 0.0101 W/K (floor 0.01) and "cut" E_ch2's held-out error by 39 %.
pub fn at_floor(c: &Candidate) -> Option<(&'static str, f64, f64)> {
    let (name, floor) = match c.cause {
        Cause::UnmodeledSource => ("w_per_k", SOURCE_RANGE_W_PER_K.0),
        Cause::ThermalLag => ("tau_s", LAG_RANGE_S.0),
        _ => return None,
    };
    let v = *c.parameters.get(name)?;
    (v <= floor * FLOOR_FACTOR).then_some((name, v, floor))
}

/// Why [`supported`] refuses `c`, in words for the evidence (the first condition it fails);
/// `None` when it is supported. A lower held-out RMS of the error axis is left to the caller,
/// which says the change in the axis's own words.
pub fn unsupported_because(c: &Candidate) -> Option<String> {
    let col = c.column.as_deref().unwrap_or("its column");
    if c.delta_bic >= MAX_DELTA_BIC {
        return Some(format!(
            "not named: it does not improve the training fit enough (ΔBIC = {:.0}, below {MAX_DELTA_BIC} needed)",
            c.delta_bic
        ));
    }
    if let Some(m) = &c.mate_of {
        return Some(format!(
            "not named: `{col}` follows the node sensor `{m}` (another sensor on a part the network has)"
        ));
    }
    if let Some(m) = c.mates.as_ref().filter(|m| !m.corroborate) {
        return Some(format!(
            "not named: the other sensors on `{col}`'s part ({}) do not show the drift (the part warms; the sensor reads it)",
            m.columns.join(", ")
        ));
    }
    if let Some((name, v, floor)) = at_floor(c) {
        return Some(format!(
            "not named: its own term ended at the floor of its range ({name} = {v:.4}, floor {floor}): the extension does nothing, and what it gains is the network's refit"
        ));
    }
    if let Some(g) = c.sensor_gain_pct.filter(|g| *g <= 0.0) {
        return Some(format!(
            "not named: it leaves `{col}`'s own held-out residual no better ({g:+.0} %)"
        ));
    }
    None
}

/// The verdict and the index of the named candidate in `cands` (sorted by score, best first):
/// the best supported candidate if its score reaches `min_score`; otherwise `none` when the
/// baseline's held-out RMS is within `noise_ratio` noise levels, else `unexplained`.
pub fn rule(
    cands: &[Candidate],
    base: &Holdout,
    noise_um: f64,
    opts: &DiagnoseOptions,
) -> (Verdict, Option<usize>) {
    match cands.iter().position(supported) {
        Some(i) if cands[i].score >= opts.min_score => (Verdict::Cause(cands[i].cause), Some(i)),
        _ if base.rmse_um / noise_um <= opts.noise_ratio => (Verdict::None, None),
        _ => (Verdict::Unexplained, None),
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{baseline, candidate};
    use super::*;

    #[test]
    fn a_drift_its_part_mates_share_is_not_named() {
        let base = baseline();
        let mut drift = candidate(Cause::SensorDrift, 0.6, 1.0, -50.0);
        drift.mates = Some(super::super::candidates::Mates {
            columns: vec!["T_b".into()],
            trend_k_per_h: 0.001,
            corroborate: false,
        });
        let cands = [drift.clone(), candidate(Cause::ThermalLag, 0.3, 2.0, -50.0)];
        let (v, i) = rule(&cands, &base, 1.0, &DiagnoseOptions::default());
        assert_eq!((v, i), (Verdict::Cause(Cause::ThermalLag), Some(1)));
        drift.mates.as_mut().unwrap().corroborate = true;
        let (v, _) = rule(&[drift], &base, 1.0, &DiagnoseOptions::default());
        assert_eq!(v, Verdict::Cause(Cause::SensorDrift));
    }

    #[test]
    fn a_drift_that_worsens_its_own_sensor_held_out_is_not_named() {
        let base = baseline();
        let mut drift = candidate(Cause::SensorDrift, 0.6, 1.0, -50.0);
        drift.sensor_gain_pct = Some(-8.0);
        let cands = [drift.clone(), candidate(Cause::ThermalLag, 0.3, 2.0, -50.0)];
        let (v, i) = rule(&cands, &base, 1.0, &DiagnoseOptions::default());
        assert_eq!((v, i), (Verdict::Cause(Cause::ThermalLag), Some(1)));
        drift.sensor_gain_pct = Some(15.0);
        let (v, _) = rule(&[drift], &base, 1.0, &DiagnoseOptions::default());
        assert_eq!(v, Verdict::Cause(Cause::SensorDrift));
    }

    #[test]
    fn a_drift_its_own_sensor_confirms_may_leave_the_error_worse() {
        let base = baseline();
        // the error's held-out RMS rises (2.55 -> 3.0 µm): a second effect had been hidden
        let mut drift = candidate(Cause::SensorDrift, 0.15, 3.0, -500.0);
        drift.sensor_gain_pct = Some(92.0);
        let (v, _) = rule(&[drift.clone()], &base, 1.0, &DiagnoseOptions::default());
        assert_eq!(v, Verdict::Cause(Cause::SensorDrift));
        // its own sensor barely better: not enough to name it against the error axis
        drift.sensor_gain_pct = Some(DRIFT_OWN_GAIN_PCT - 1.0);
        let (v, _) = rule(&[drift], &base, 1.0, &DiagnoseOptions::default());
        assert_eq!(v, Verdict::Unexplained);
        // any other cause must cut the error
        let lag = candidate(Cause::ThermalLag, 0.15, 3.0, -500.0);
        assert!(!supported(&lag));
    }

    #[test]
    fn names_the_best_supported_candidate() {
        let base = baseline();
        let cands = [
            candidate(Cause::ThermalLag, 0.6, 1.0, -50.0),
            candidate(Cause::SensorDrift, 0.3, 2.0, -50.0),
        ];
        let opts = DiagnoseOptions::default();
        assert_eq!(
            rule(&cands, &base, 0.1, &opts),
            (Verdict::Cause(Cause::ThermalLag), Some(0))
        );
    }

    #[test]
    fn never_names_a_cause_that_raises_the_error() {
        // the kJ/K machine: the joint residual falls, the error axis gets worse
        let base = baseline();
        let worse = candidate(Cause::UnmodeledSource, 0.45, 6.81, -400.0);
        let opts = DiagnoseOptions::default();
        assert_eq!(
            rule(std::slice::from_ref(&worse), &base, 0.1, &opts),
            (Verdict::Unexplained, None)
        );
        assert_eq!(
            rule(std::slice::from_ref(&worse), &base, 2.0, &opts),
            (Verdict::None, None)
        );
        // the next supported candidate is named instead
        let lag = candidate(Cause::ThermalLag, 0.2, 2.0, -30.0);
        assert_eq!(
            rule(&[worse, lag], &base, 0.1, &opts),
            (Verdict::Cause(Cause::ThermalLag), Some(1))
        );
    }

    #[test]
    fn a_source_or_a_lag_left_at_its_floor_is_not_named() {
        // the real run's E_ch2: a source at 0.0101 W/K "cut" the error by 39 % (the refit's)
        let base = baseline();
        let opts = DiagnoseOptions::default();
        let mut src = candidate(Cause::UnmodeledSource, 0.4, 2.0, -250.0);
        src.parameters.insert("w_per_k".into(), 0.0101);
        let mut lag = candidate(Cause::ThermalLag, 0.3, 2.5, -50.0);
        lag.parameters.insert("tau_s".into(), 31.0);
        assert!(!supported(&src) && !supported(&lag));
        assert!(unsupported_because(&src).is_some_and(|w| w.contains("floor")));
        assert_eq!(
            rule(&[src.clone(), lag.clone()], &base, 0.1, &opts),
            (Verdict::Unexplained, None)
        );
        // off the floor both are named as before
        src.parameters.insert("w_per_k".into(), 0.5);
        lag.parameters.insert("tau_s".into(), 600.0);
        assert!(supported(&src) && supported(&lag));
        assert_eq!(
            rule(&[src, lag], &base, 0.1, &opts),
            (Verdict::Cause(Cause::UnmodeledSource), Some(0))
        );
    }

    #[test]
    fn needs_the_bic_and_the_score() {
        let base = baseline();
        let opts = DiagnoseOptions::default();
        for c in [
            candidate(Cause::ThermalLag, 0.5, 1.0, -5.0),
            candidate(Cause::ThermalLag, 0.05, 1.0, -50.0),
        ] {
            assert_eq!(rule(&[c], &base, 0.1, &opts).0, Verdict::Unexplained);
        }
    }

    #[test]
    fn serialises_as_its_name() {
        for (v, name) in [
            (Verdict::Cause(Cause::SpeedGrowth), "\"speed_growth\""),
            (Verdict::None, "\"none\""),
            (Verdict::Unexplained, "\"unexplained\""),
        ] {
            assert_eq!(serde_json::to_string(&v).unwrap(), name);
        }
    }
}
