//! The English sentence that states the verdict and the figures behind it.

use std::collections::BTreeMap;

use super::rounds::{Accepted, Round, MIN_SHARE_OF_EXCESS};
use super::verdict::{supported, Verdict, MAX_DELTA_BIC};
use super::{
    BaselineNetwork, Candidate, Cause, Fit, Holdout, NetworkRule, NetworkUsed, StartCheck,
    SECOND_START_FACTOR, TRAINING_TIE,
};

/// Which network the baseline has, when it is not the default (recalibrated on the axis).
pub fn network(b: &BaselineNetwork, axis: &str) -> String {
    match (b.rule, b.recalibrated_rmse_um, b.kept_rmse_um) {
        (NetworkRule::Auto, Some(_), Some(k)) if b.network == NetworkUsed::Kept => {
            let why = b
                .second_start
                .as_ref()
                .map_or_else(String::new, |s| not_unique(s, axis));
            format!(
                " The network was identified from data, and its recalibration on this axis is not \
                 unique: {why}. The training rows cannot choose a recalibrated network, so the \
                 baseline keeps the identified network (rule `auto`; only its start and the \
                 drift map fitted), which has one solution: {k:.2} µm held out."
            )
        }
        (NetworkRule::Recalibrate | NetworkRule::Auto, _, _) => String::new(),
        (NetworkRule::Shared, _, _) => " The baseline's network is the machine's one network, \
             calibrated once on the temperatures alone; only the start and the drift map of this \
             axis are fitted to it."
            .to_string(),
        (NetworkRule::Best, Some(r), Some(k)) if b.network == NetworkUsed::Kept => format!(
            " The baseline keeps the machine's network as given (only its start and the drift map \
             fitted): it leaves the smaller held-out residual of the error and the temperatures \
             together (noise-normalised) than the network recalibrated on this axis; on {axis} \
             alone {k:.2} µm against {r:.2} µm."
        ),
        (NetworkRule::Best, Some(r), Some(k)) => format!(
            " The baseline's network is recalibrated on this axis: it leaves the smaller held-out \
             residual of the error and the temperatures together (noise-normalised) than the \
             network as given; on {axis} alone {r:.2} µm against {k:.2} µm."
        ),
        _ => " The baseline keeps the machine's network as given (only its start and the drift \
              map fitted)."
            .to_string(),
    }
}

/// Why the drift map was fitted with a ridge penalty (nothing when it was not).
pub fn drift_penalty(b: &BaselineNetwork, axis: &str) -> String {
    match &b.drift_penalty {
        Some(p) => format!(
            " Fitted by least squares, the baseline's drift map of {axis} cancelled: `{}` at \
             {:.3} µm/K alone swings {:.1} µm RMS over the training rows where the axis drifts \
             {:.1} µm, so a fraction of a kelvin in that node moves the axis by many µm. The \
             baseline and every candidate are therefore fitted with a ridge penalty on the drift \
             map's node terms, toward the file's values (λ = {:.0e}, relative to their mean \
             square: the one with which the map fitted to the first part of the training rows \
             best predicts the rest).",
            p.node, p.coefficient, p.term_um, p.drift_um, p.lambda
        ),
        None => String::new(),
    }
}

/// What a second start of the recalibrated baseline says, when it ends elsewhere held out.
pub fn second_start(b: &BaselineNetwork, axis: &str) -> String {
    let Some(s) = b
        .second_start
        .as_ref()
        .filter(|_| b.network == NetworkUsed::Recalibrated)
    else {
        return String::new();
    };
    let taken = if s.taken {
        format!(
            " The calibration from the machine file's values stopped in a poorer minimum: \
             started with every network parameter {:.0} % off them, it fits the training rows \
             better (SSR {:.2}x), so that calibration is the baseline ({:.2} µm held out on \
             {axis}; {:.2} µm from the file's values).",
            100.0 * (SECOND_START_FACTOR - 1.0),
            s.training_ssr_ratio,
            s.rmse_um,
            s.first_rmse_um,
        )
    } else {
        String::new()
    };
    match (s.unique, s.taken) {
        (true, _) => taken,
        (false, true) => format!(
            "{taken} Two minima of one calibration may not be all of them: the training rows do \
             not pin the network down, and `--network keep` or `best` (for a network identified \
             from this run, or one you trust) gives a baseline with one solution."
        ),
        (false, false) => format!(
            " The baseline's calibration is not unique on this run: {}. The training rows do not \
             pin the network down, and what is named here was found from the file's values; \
             `--network keep` or `best` (for a network identified from this run, or one you \
             trust) gives a baseline with one solution.",
            not_unique(s, axis)
        ),
    }
}

/// How many of round 1's full fits stopped at the iteration limit (nothing when none did).
pub fn unsettled(cands: &[Candidate]) -> String {
    let full = cands.iter().filter(|c| c.fit == Fit::Full).count();
    let stopped = cands
        .iter()
        .filter(|c| c.fit == Fit::Full && !c.converged)
        .count();
    match stopped {
        0 => String::new(),
        _ => format!(
            " {stopped} of round 1's {full} full fits stopped at the iteration limit before \
             settling and are scored where they stopped (`converged: false` in the candidates): \
             their figures are not those of a settled fit."
        ),
    }
}

/// Why a recalibration is not unique.
fn not_unique(s: &StartCheck, axis: &str) -> String {
    let first = s.first_rmse_um;
    if !s.converged {
        format!(
            "from the file's values or from every network parameter {:.0} % off, the search \
             stopped at its iteration limit without settling (held out {first:.2} and {:.2} µm \
             on {axis}), so where it stopped is no solution to rely on",
            100.0 * (SECOND_START_FACTOR - 1.0),
            s.rmse_um,
        )
    } else {
        format!(
            "started with every network parameter {:.0} % off the machine file's values, it fits \
             the training rows as well (SSR {:.2}x, within {tie:.0} % or better) and holds out \
             {:.2} µm on {axis} against {first:.2} µm",
            100.0 * (SECOND_START_FACTOR - 1.0),
            s.training_ssr_ratio,
            s.rmse_um,
            tie = 100.0 * (TRAINING_TIE - 1.0),
        )
    }
}

/// "cause on `column`", "cause on node `node`" or "cause".
fn place(cause: impl std::fmt::Display, column: Option<&str>, node: Option<&str>) -> String {
    match (column, node) {
        (Some(col), _) => format!("{cause} on `{col}`"),
        (None, Some(nd)) => format!("{cause} on node `{nd}`"),
        (None, None) => cause.to_string(),
    }
}

/// What the extension does to the held-out RMS error: it may only "cut" it when it is lower.
fn error_change(axis: &str, base: &Holdout, c: &Candidate) -> String {
    let (b, e) = (base.rmse_um, c.holdout.rmse_um);
    if e < b {
        format!(
            "cuts the held-out RMS error of {axis} from {b:.2} to {e:.2} µm ({:.0} %)",
            c.gain_pct
        )
    } else {
        format!("does not cut the held-out RMS error of {axis} ({b:.2} → {e:.2} µm)")
    }
}

/// The sentence for the named candidate `cands[i]` (`cands` sorted by score, best first).
/// A named cause's fitted parameters as the evidence states them, `name = value, ...`; then, for
/// one that ended at a bound of the search ([`Cause::search_range`], within 0.1 %), that it did:
/// the data asked for more than the cause may model, and the value is that bound, not an
/// estimate.
pub fn params_text(cause: Cause, params: &BTreeMap<String, f64>) -> String {
    let list: Vec<String> = params
        .iter()
        .map(|(k, v)| format!("{k} = {v:.4}"))
        .collect();
    let at_bound: Vec<String> = params
        .iter()
        .filter_map(|(k, &v)| {
            let (lo, hi) = cause.search_range(k)?;
            let bound = if v >= hi / 1.001 {
                "ceiling"
            } else if v <= lo * 1.001 {
                "floor"
            } else {
                return None;
            };
            Some(format!(
                "; {k} ended at the search's {bound}: the data ask for more than this cause may \
                 model, so that value is the bound, not an estimate"
            ))
        })
        .collect();
    list.join(", ") + &at_bound.concat()
}

pub fn named(cands: &[Candidate], i: usize, base: &Holdout, axis: &str) -> String {
    let c = &cands[i];
    let what = place(c.cause, c.column.as_deref(), c.node.as_deref());
    let sensor = match c.sensor_gain_pct {
        Some(g) if c.holdout.rmse_um < base.rmse_um => {
            format!(" and the held-out residual of that sensor by {g:.0} %")
        }
        Some(g) => format!(
            ", but cuts the held-out residual of that sensor by {g:.0} % (the drifting reading \
             had stood in for another effect on {axis}, which the later rounds look for)"
        ),
        None => String::new(),
    };
    let among = if i == 0 {
        format!("{} candidate extensions", cands.len())
    } else {
        format!(
            "the {} of {} candidate extensions that meet the rule for naming a cause",
            cands.iter().filter(|x| supported(x)).count(),
            cands.len()
        )
    };
    format!(
        "Extending the calibrated model with {what} ({}) {}{sensor}; it removes {:.0} % of the normalised held-out residual, the most of {among}, and improves the training fit by ΔBIC = {:.0}.",
        params_text(c.cause, &c.parameters),
        error_change(axis, base, c),
        100.0 * c.score,
        c.delta_bic
    )
}

/// The sentences for a first named cause that was accepted after round 1: round 1's cause
/// (`first`), which the backward check dropped, then the named one; `last`: the final model's
/// held-out figures, with `n_named` causes in all.
pub fn named_later(
    first: Option<&Candidate>,
    c: &Accepted,
    base: &Holdout,
    last: &Holdout,
    axis: &str,
    n_named: usize,
) -> String {
    let round_1 = first.map_or(String::new(), |f| {
        format!(
            "Round 1 accepted {} (it {}), which the backward check drops (below). ",
            place(f.cause, f.column.as_deref(), f.node.as_deref()),
            error_change(axis, base, f)
        )
    });
    format!(
        "{round_1}The first cause that passes the backward check is {} ({}), accepted in round {}; {} the held-out RMS error of {axis} falls from {:.2} to {:.2} µm.",
        place(c.cause, c.column.as_deref(), c.node.as_deref()),
        params_text(c.cause, &c.params),
        c.round,
        if n_named > 1 {
            "with the other named causes"
        } else {
            "on its own (the only cause named)"
        },
        base.rmse_um,
        last.rmse_um
    )
}

/// The sentences on the rounds after the first, on the causes the backward check dropped and on
/// the remainder (`named`: some cause is named). Empty when round 1 was the only round.
pub fn rounds(
    rounds: &[Round],
    dropped: &[Accepted],
    remainder_um: f64,
    noise_um: f64,
    axis: &str,
    named: bool,
    min_score: f64,
) -> String {
    let mut out = String::new();
    // a pair is two entries, its lead then its partner; two pairs may follow each other
    let mut partner_next = false;
    for (k, r) in rounds.iter().enumerate() {
        let what = r
            .cause
            .map(|c| place(c, r.column.as_deref(), r.node.as_deref()));
        if r.paired {
            let is_partner = partner_next;
            partner_next = !partner_next;
            if is_partner {
                continue;
            }
            // the lead speaks for the pair; the partner is the next entry
            if let (Some(what), Some(p)) = (what, rounds.get(k + 1).filter(|p| p.paired)) {
                let partner = p.cause.map_or(String::new(), |c| {
                    place(c, p.column.as_deref(), p.node.as_deref())
                });
                out.push_str(&format!(
                    " Rounds {} and {} take {what} and {partner} as a pair: no single extension passed (alone {what}, the strongest by training evidence with ΔBIC = {:.0}, moves the held-out RMS error of {axis} from {:.2} to {:.2} µm); fitted together they lower it to {:.2} µm ({:.0} %), {:.0} % of what stayed above the probe noise, ΔBIC = {:.0}, and each passes a later round's rule against the other alone.",
                    r.round,
                    p.round,
                    r.delta_bic,
                    r.rmse_before_um,
                    r.rmse_um,
                    p.rmse_um,
                    p.gain_pct,
                    100.0 * p.excess_share,
                    p.delta_bic
                ));
            }
            continue;
        }
        if r.round == 1 {
            continue; // round 1's sentence comes first, from the verdict
        }
        match (what, r.accepted) {
            (Some(what), true) => out.push_str(&format!(
                " Round {} adds {what}, fitted together with the causes before it: the held-out RMS error of {axis} falls from {:.2} to {:.2} µm ({:.0} %), {:.0} % of what stayed above the probe noise, ΔBIC = {:.0}.",
                r.round,
                r.rmse_before_um,
                r.rmse_um,
                r.gain_pct,
                100.0 * r.excess_share,
                r.delta_bic
            )),
            (Some(what), false) => {
                // the round's best is supported (ΔBIC, gains): say which bar of the rule it misses
                let share = 100.0 * r.excess_share.max(0.0);
                let why = if r.excess_share < MIN_SHARE_OF_EXCESS {
                    format!(
                        "removing {share:.0} % of what stays above the probe noise, {:.0} % needed",
                        100.0 * MIN_SHARE_OF_EXCESS
                    )
                } else {
                    format!(
                        "removing {share:.0} % of what stays above the probe noise but only {:.1} % of the normalised held-out residual (error and temperatures), {:.0} % needed",
                        100.0 * r.score,
                        100.0 * min_score
                    )
                };
                out.push_str(&format!(
                    " In round {} no further extension passes (best: {what}, {why}).",
                    r.round
                ))
            }
            (None, _) => out.push_str(&format!(
                " In round {} no further extension lowers the held-out error.",
                r.round
            )),
        }
    }
    for d in dropped {
        out.push_str(&format!(
            " {} (round {}) is dropped: refitted without it, the other causes leave too little for it to pass a round's rule again ({:.0} % of what stays above the probe noise, {:.0} % of the normalised held-out residual, ΔBIC below {:.0}).",
            place(d.cause, d.column.as_deref(), d.node.as_deref()),
            d.round,
            100.0 * MIN_SHARE_OF_EXCESS,
            100.0 * min_score,
            MAX_DELTA_BIC
        ));
    }
    if named && remainder_um > 0.0 {
        out.push_str(&format!(
            " A structured held-out residual of {remainder_um:.2} µm RMS above the probe noise ({noise_um:.2} µm) remains that no catalogued cause explains."
        ));
    }
    out
}

/// The sentences on the named causes whose column the run cannot single out: each with the
/// other columns whose candidate passed the same round's rule and held the axis out as well
/// ([`super::rounds::ALTERNATIVE_RMSE_SHARE`]). Empty when there are none.
pub fn alternatives(causes: &[Accepted], axis: &str) -> String {
    let mut out = String::new();
    for c in causes.iter().filter(|c| !c.alternatives.is_empty()) {
        let Some(col) = c.column.as_deref() else {
            continue;
        };
        let others: Vec<String> = c
            .alternatives
            .iter()
            .map(|a| format!("`{}` ({:.2} µm)", a.column, a.rmse_um))
            .collect();
        out.push_str(&format!(
            " The run does not single out `{col}`: {} on {} passes the same rule and holds {axis} out as well (within {:.0} % of {:.2} µm with `{col}`) or better, so the {} may be at either place; a sensor or a test that separates them decides.",
            c.cause,
            others.join(", "),
            100.0 * super::rounds::ALTERNATIVE_RMSE_SHARE,
            c.rmse_um,
            match c.cause {
                super::Cause::SensorDrift => "drifting reading",
                _ => "effect",
            }
        ));
    }
    out
}

/// The sentence when round 1 accepted `first` but the backward check dropped every cause (the
/// rounds' sentences then say which and why): `verdict` is the baseline's, `none` or
/// `unexplained`.
pub fn all_dropped(
    verdict: Verdict,
    first: &Candidate,
    base: &Holdout,
    noise_um: f64,
    axis: &str,
) -> String {
    let (b, ratio) = (base.rmse_um, base.rmse_um / noise_um);
    let left = if verdict == Verdict::None {
        format!("a held-out RMS error of {b:.2} µm on {axis}, within {ratio:.1}× the probe noise ({noise_um:.2} µm)")
    } else {
        format!("a structured held-out RMS error of {b:.2} µm on {axis} ({ratio:.1}× the probe noise of {noise_um:.2} µm)")
    };
    format!(
        "Round 1 accepted {} (it {}), but the backward check dropped it and every cause after it, \
         as said below: no cause is named, and the calibrated model leaves {left}.",
        place(first.cause, first.column.as_deref(), first.node.as_deref()),
        error_change(axis, base, first)
    )
}

/// A best candidate that lowers the error's held-out RMS by this much (%), and by twice its
/// score or more, has both said: on a long run whose network misses its temperatures the
/// normalised residual is mostly theirs (a week's ambient coupling: 64 % of the error, 5 % of
/// the residual).
const ERROR_GAIN_SAID_PCT: f64 = 10.0;

/// The sentence when no cause is named (`verdict` is `none` or `unexplained`).
pub fn unnamed(
    verdict: Verdict,
    cands: &[Candidate],
    base: &Holdout,
    noise_um: f64,
    axis: &str,
    min_score: f64,
) -> String {
    let best = cands
        .first()
        .map(|c| {
            let why = match super::verdict::unsupported_because(c) {
                Some(reason) if c.score >= min_score => format!(", {reason}"),
                _ if c.score >= min_score && c.gain_pct <= 0.0 => {
                    format!(", which {}", error_change(axis, base, c))
                }
                _ => String::new(),
            };
            // a score far below what the candidate does to the error: both, as they are
            let error =
                match c.gain_pct >= ERROR_GAIN_SAID_PCT && c.gain_pct >= 2.0 * 100.0 * c.score {
                    true => format!(", though {:.0} % of the error's held-out RMS", c.gain_pct),
                    false => String::new(),
                };
            format!("{} {:.0} %{error}{why}", c.cause, 100.0 * c.score)
        })
        .unwrap_or_default();
    let (b, ratio, min) = (base.rmse_um, base.rmse_um / noise_um, 100.0 * min_score);
    if verdict == Verdict::None {
        format!(
            "The calibrated model leaves a held-out RMS error of {b:.2} µm on {axis}, within {ratio:.1}× the probe noise ({noise_um:.2} µm); no extension that may be named removes {min:.0} % of the held-out residual (best: {best})."
        )
    } else {
        format!(
            "The calibrated model leaves a structured held-out RMS error of {b:.2} µm on {axis} ({ratio:.1}× the probe noise of {noise_um:.2} µm), and no catalogued extension that may be named removes {min:.0} % of the normalised held-out residual (error and temperatures) (best: {best})."
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{baseline, candidate, holdout};
    use super::*;
    use crate::thermal::diagnose::Cause;

    /// A parameter the search stopped at its bound is stated as a bound: a source's link at its
    /// ceiling, a lag at its floor; inside the range, or a linear term, only its value.
    #[test]
    fn a_parameter_at_a_bound_of_the_search_is_said_to_be_one() {
        let p = |pairs: &[(&str, f64)]| -> BTreeMap<String, f64> {
            pairs.iter().map(|&(k, v)| (k.to_string(), v)).collect()
        };
        let mut c = candidate(Cause::UnmodeledSource, 0.6, 1.0, -50.0);
        c.parameters = p(&[("w_per_k", 200.0)]);
        let s = named(std::slice::from_ref(&c), 0, &baseline(), "E_z");
        assert!(
            s.contains("(w_per_k = 200.0000; w_per_k ended at the search's ceiling: the data ask for more than this cause may model, so that value is the bound, not an estimate)"),
            "{s}"
        );
        let s = params_text(Cause::UnmodeledSource, &p(&[("w_per_k", 10.8)]));
        assert_eq!(s, "w_per_k = 10.8000");
        assert!(params_text(Cause::ThermalLag, &p(&[("tau_s", 30.0)]))
            .contains("tau_s ended at the search's floor"));
        assert!(!params_text(Cause::ThermalLag, &p(&[("tau_s", 1200.0)])).contains("search's"));
        // a linear term has no bound to be at
        let s = params_text(Cause::AmbientCoupling, &p(&[("um_per_k", 1e6)]));
        assert_eq!(s, "um_per_k = 1000000.0000");
        let s = params_text(
            Cause::SpeedGrowth,
            &p(&[("exponent", 3.0), ("ref", 5000.0), ("um", 1.0)]),
        );
        assert!(
            s.starts_with("exponent = 3.0000, ref = 5000.0000, um = 1.0000; exponent ended at the search's ceiling"),
            "{s}"
        );
    }

    #[test]
    fn says_cuts_only_when_the_error_is_cut() {
        let base = baseline();
        let better = candidate(Cause::ThermalLag, 0.6, 1.0, -50.0);
        let s = named(std::slice::from_ref(&better), 0, &base, "E_z");
        assert!(
            s.contains("cuts the held-out RMS error of E_z from 2.55 to 1.00 µm (61 %)"),
            "{s}"
        );
        assert!(s.contains("the most of 1 candidate extensions"), "{s}");
        // the tester's kJ/K machine: a higher joint score, a worse error
        let worse = candidate(Cause::UnmodeledSource, 0.45, 6.81, -400.0);
        let s = named(std::slice::from_ref(&worse), 0, &base, "E_z");
        assert!(!s.contains("cuts"), "{s}");
        assert!(s.contains("does not cut the held-out RMS error of E_z (2.55 → 6.81 µm)"));
        let s = unnamed(Verdict::Unexplained, &[worse], &base, 0.1, "E_z", 0.1);
        assert!(!s.contains("cuts"), "{s}");
        assert!(
            s.contains("(best: unmodeled_source 45 %, which does not cut"),
            "{s}"
        );
    }

    #[test]
    fn a_later_cause_left_alone_and_a_dropped_one_are_said_as_they_are() {
        let accepted = |round: usize, column: &str| Accepted {
            cause: Cause::UnmodeledSource,
            column: Some(column.into()),
            node: Some("t8".into()),
            axis: "E_z".into(),
            gain_pct: 30.0,
            params: Default::default(),
            round,
            rmse_um: 1.0,
            alternatives: Vec::new(),
            spec: None,
        };
        let (base, last) = (baseline(), holdout(1.5));
        assert_eq!(alternatives(&[accepted(1, "T_t5")], "E_z"), "");
        let mut tied = accepted(1, "T_t7");
        tied.alternatives = vec![super::super::rounds::Alternative {
            column: "T_t11".into(),
            node: Some("t2".into()),
            rmse_um: 0.98,
            score: 0.3,
        }];
        let s = alternatives(&[tied], "E_z");
        assert!(
            s.contains("does not single out `T_t7`: unmodeled_source on `T_t11` (0.98 µm)")
                && s.contains("within 5 % of 1.00 µm with `T_t7`) or better"),
            "{s}"
        );
        // round 1's cause, dropped later, is said before the first named one
        let speed = candidate(Cause::SpeedGrowth, 0.2, 2.2, -50.0);
        let alone = named_later(Some(&speed), &accepted(3, "T_t5"), &base, &last, "E_z", 1);
        assert!(
            alone.starts_with("Round 1 accepted speed_growth (it cuts the held-out RMS error of E_z from 2.55 to 2.20 µm")
                && alone.contains("which the backward check drops (below). The first cause that passes the backward check is unmodeled_source on `T_t5`"),
            "{alone}"
        );
        assert!(
            alone.contains("on its own (the only cause named)"),
            "{alone}"
        );
        assert!(alone.contains("from 2.55 to 1.50 µm"), "{alone}");
        let with = named_later(None, &accepted(3, "T_t5"), &base, &last, "E_z", 2);
        assert!(with.contains("with the other named causes"), "{with}");
        assert!(with.starts_with("The first cause"), "{with}");
        let s = rounds(&[], &[accepted(1, "T_t7")], 0.0, 0.05, "E_z", true, 0.1);
        assert!(
            s.contains("(round 1) is dropped")
                && s.contains("25 % of what stays above the probe noise, 10 % of the normalised held-out residual, ΔBIC below -10"),
            "{s}"
        );
        assert!(!s.contains("as well"), "{s}");
    }

    #[test]
    fn two_pairs_in_a_row_are_said_as_two_pairs() {
        let entry = |round: usize, cause: Cause| Round {
            round,
            cause: Some(cause),
            column: None,
            node: None,
            rmse_before_um: 2.0,
            rmse_um: 1.0,
            gain_pct: 50.0,
            score: 0.3,
            delta_bic: -50.0,
            excess_share: 0.7,
            accepted: true,
            kept: true,
            candidates: 10,
            paired: true,
        };
        let rs = [
            entry(1, Cause::ThermalLag),
            entry(2, Cause::SpeedGrowth),
            entry(3, Cause::AmbientCoupling),
            entry(4, Cause::NonlinearExpansion),
        ];
        let s = rounds(&rs, &[], 0.0, 0.05, "E_z", true, 0.1);
        assert!(
            s.contains("Rounds 1 and 2 take thermal_lag and speed_growth as a pair")
                && s.contains(
                    "Rounds 3 and 4 take ambient_coupling and nonlinear_expansion as a pair"
                ),
            "{s}"
        );
        assert!(!s.contains("Rounds 2 and 3"), "{s}");
    }

    #[test]
    fn a_best_candidate_that_may_not_be_named_says_why_and_a_dropped_round_1_is_said() {
        let base = baseline();
        let mut bic = candidate(Cause::ThermalLag, 0.45, 1.0, -5.0);
        bic.delta_bic = -5.0;
        let s = unnamed(Verdict::Unexplained, &[bic.clone()], &base, 0.1, "E_z", 0.1);
        assert!(s.contains("(best: thermal_lag 45 %, not named: it does not improve the training fit enough (ΔBIC = -5"), "{s}");
        assert!(
            s.contains("no catalogued extension that may be named removes 10 %"),
            "{s}"
        );
        // a score far below the error's gain: both said
        let weak = candidate(Cause::AmbientCoupling, 0.05, 0.9, -3800.0);
        let s = unnamed(Verdict::Unexplained, &[weak], &base, 0.1, "E_z", 0.1);
        assert!(
            s.contains("removes 10 % of the normalised held-out residual (error and temperatures) (best: ambient_coupling 5 %, though 65 % of the error's held-out RMS)"),
            "{s}"
        );
        let s = all_dropped(Verdict::Unexplained, &bic, &base, 0.1, "E_z");
        assert!(s.starts_with("Round 1 accepted thermal_lag (it cuts the held-out RMS error of E_z from 2.55 to 1.00 µm"), "{s}");
        assert!(
            s.contains("no cause is named")
                && s.contains("structured held-out RMS error of 2.55 µm"),
            "{s}"
        );
    }

    #[test]
    fn a_named_runner_up_is_not_called_the_best_of_all() {
        let base = baseline();
        let cands = [
            candidate(Cause::UnmodeledSource, 0.45, 6.81, -400.0),
            candidate(Cause::ThermalLag, 0.2, 2.0, -30.0),
        ];
        let s = named(&cands, 1, &base, "E_z");
        assert!(
            s.contains("the most of the 1 of 2 candidate extensions that meet the rule"),
            "{s}"
        );
    }
}
