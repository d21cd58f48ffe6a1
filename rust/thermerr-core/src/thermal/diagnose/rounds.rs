//! Several effects at once: after round 1 (today's diagnosis) names a cause, its extended
//! machine becomes the baseline and the catalogue is tried again on it — each new candidate
//! calibrated together with the accepted extensions — until no candidate passes or
//! [`MAX_ROUNDS`] rounds have run. Then a backward check refits without each accepted cause in
//! turn and drops any that no longer passes against the others.

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::Serialize;

use super::candidates::{self, Baseline, Spec};
use super::cause::Cause;
use super::score::{self, HeldOut};
use super::verdict::{nameable, supported, MAX_DELTA_BIC};
use super::{Candidate, DiagnoseOptions, Fit, Holdout};
use crate::error::{Error, Result};
use crate::progress;
use crate::thermal::calibrate::{Calibration, FreeParam};
use crate::thermal::machine::Machine;
use crate::thermal::sim::RunView;

/// Rounds in all, round 1 included.
pub const MAX_ROUNDS: usize = 4;

/// Share of what is still unexplained — the held-out excess, RMS² above the noise level² — that
/// the winner of a round after the first must remove. A quarter, not a half: with two effects of
/// similar size, each one alone removes only about half of the excess of the model without it,
/// and a first effect that is the smaller one removes less; asking for half said "unexplained"
/// whenever the second effect was large.
pub const MIN_SHARE_OF_EXCESS: f64 = 0.25;

/// How close another column's candidate of the same cause must come to the accepted one to be
/// reported as an equal explanation: its held-out RMS error of the axis at most this much
/// above the accepted candidate's (relative). On the real 46-h run, sources from `T_t7` and
/// `T_t11` held `E_ch1` out at 2.95 and 2.94 µm, and which one won moved with the fit's
/// resolution (every 45 s, 60 s, 90 s or 120 s of the run): the run cannot tell them apart.
pub const ALTERNATIVE_RMSE_SHARE: f64 = 0.05;

/// Another column that explains the held-out error as well as an accepted cause's
/// (`report.json` "causes"[i]."alternatives").
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Alternative {
    pub column: String,
    pub node: Option<String>,
    /// Held-out RMS of the error axis with this candidate instead (µm).
    pub rmse_um: f64,
    pub score: f64,
}

/// The candidates of `cands` that are `chosen`'s cause on another column, pass the same rule
/// (`ok`) and hold the axis out within [`ALTERNATIVE_RMSE_SHARE`] of it: the best one per
/// column, best first.
pub fn alternatives(
    cands: &[Candidate],
    chosen: &Candidate,
    ok: impl Fn(&Candidate) -> bool,
) -> Vec<Alternative> {
    let Some(col) = chosen.column.as_deref() else {
        return Vec::new();
    };
    let limit = chosen.holdout.rmse_um * (1.0 + ALTERNATIVE_RMSE_SHARE);
    let mut out: Vec<Alternative> = Vec::new();
    let mut near: Vec<&Candidate> = cands
        .iter()
        .filter(|c| c.cause == chosen.cause && c.column.as_deref().is_some_and(|c| c != col))
        .filter(|c| c.holdout.rmse_um <= limit && ok(c))
        .collect();
    near.sort_by(|a, b| a.holdout.rmse_um.total_cmp(&b.holdout.rmse_um));
    for c in near {
        let column = c.column.clone().unwrap_or_default();
        if out.iter().all(|a| a.column != column) {
            out.push(Alternative {
                column,
                node: c.node.clone(),
                rmse_um: c.holdout.rmse_um,
                score: c.score,
            });
        }
    }
    out
}

/// One accepted cause, in the order accepted (`report.json` "causes").
#[derive(Clone, Debug, Serialize)]
pub struct Accepted {
    pub cause: Cause,
    pub column: Option<String>,
    pub node: Option<String>,
    pub axis: String,
    /// 100 · (1 − RMS_after / RMS_before) on held-out data, of the round that accepted it.
    pub gain_pct: f64,
    /// Its fitted parameters in the final model (calibrated with the other accepted causes).
    pub params: BTreeMap<String, f64>,
    pub round: usize,
    /// Held-out RMS of the error axis after the round that accepted it (µm).
    pub rmse_um: f64,
    /// Other columns whose candidate of the same cause passed that round's rule and held the
    /// axis out as well (within [`ALTERNATIVE_RMSE_SHARE`]): the run does not tell them apart.
    pub alternatives: Vec<Alternative>,
    #[serde(skip)]
    pub spec: Option<Spec>,
}

/// One round (`report.json` "rounds"): its best supported candidate and whether it was accepted.
#[derive(Clone, Debug, Serialize)]
pub struct Round {
    pub round: usize,
    /// The best-scoring supported candidate (`None`: no candidate was supported).
    pub cause: Option<Cause>,
    pub column: Option<String>,
    pub node: Option<String>,
    /// Held-out RMS of the error axis before the round and with its best candidate (µm).
    pub rmse_before_um: f64,
    pub rmse_um: f64,
    pub gain_pct: f64,
    pub score: f64,
    pub delta_bic: f64,
    /// Share of the held-out excess above the noise that the best candidate removes.
    pub excess_share: f64,
    pub accepted: bool,
    /// Still named after the backward check.
    pub kept: bool,
    /// Candidates fitted in the round.
    pub candidates: usize,
    /// Accepted as one of a pair ([`pair`]): this round's cause did not pass alone, and it was
    /// fitted together with the next round's (the lead, its figures alone) or the previous
    /// round's (the partner, its figures those of the pair against the model before both).
    pub paired: bool,
}

/// The rounds' result.
pub(super) struct Outcome {
    /// The accepted causes that passed the backward check, in the order accepted.
    pub causes: Vec<Accepted>,
    /// The ones the backward check dropped.
    pub dropped: Vec<Accepted>,
    pub rounds: Vec<Round>,
    /// The final model (all of `causes` together), its figures against the baseline; `None`
    /// when no cause is named.
    pub joint: Option<Candidate>,
}

/// What every round needs besides its baseline.
pub(super) struct Context<'r, 'a> {
    pub nominal: &'r Machine,
    pub train: &'r RunView<'a>,
    pub held: &'r HeldOut<'r, 'a>,
    pub axis: &'r str,
    pub opts: &'r DiagnoseOptions,
    pub noise: f64,
}

/// Share of the held-out excess of `before` (RMS² above `noise`²) that `after` removes; 0 when
/// `before` has none.
pub fn excess_share(before: &Holdout, after: &Holdout, noise: f64) -> f64 {
    let n2 = noise * noise;
    let b = before.rmse_um.powi(2) - n2;
    if b <= 0.0 || !b.is_finite() {
        return 0.0;
    }
    1.0 - (after.rmse_um.powi(2) - n2).max(0.0) / b
}

/// The rule of a round after the first (and of the backward check): today's evidence rule
/// (supported, score ≥ `min_score`) and at least [`MIN_SHARE_OF_EXCESS`] of the excess of
/// `before` removed.
pub fn passes(c: &Candidate, before: &Holdout, noise: f64, opts: &DiagnoseOptions) -> bool {
    supported(c)
        && c.score >= opts.min_score
        && excess_share(before, &c.holdout, noise) >= MIN_SHARE_OF_EXCESS
}

/// Whether the backward check may drop the cause that `full` (the joint model, its figures
/// against the refit without that cause) holds beyond the refit `without`: it does not pass a
/// round's rule against that refit ([`passes`]), and that refit holds out no worse than the
/// baseline `base`. A refit that holds out worse than the baseline is no model of the run and
/// shows no cause redundant: on a real 46-h run (0.1 % of its temperature cells interpolated),
/// without a source from `T_t5`, the nonlinear expansion refitted from the pair's values fitted
/// the training rows better than the pair's own fit (so the source failed on ΔBIC) and held out
/// 24.0 µm against the pair's 7.7 and the baseline's 16.2; both causes were dropped and the axis
/// said `unexplained` at 16.2 µm.
pub fn redundant(
    full: &Candidate,
    without: &Holdout,
    base: &Holdout,
    noise: f64,
    opts: &DiagnoseOptions,
) -> bool {
    !passes(full, without, noise, opts) && without.rmse_um <= base.rmse_um
}

/// `full`'s figures against another fit (`cal`, `hold`) of the same data.
fn against(full: &Candidate, cal: &Calibration, hold: &Holdout) -> Candidate {
    let mut c = full.clone();
    c.score = score::joint_score(hold, &full.holdout);
    c.gain_pct = score::gain_pct(hold, &full.holdout);
    c.delta_bic = full.calibration.bic() - cal.bic();
    c.sensor_gain_pct = match (c.cause, &c.column) {
        (Cause::SensorDrift, Some(col)) => score::sensor_gain_pct(hold, &full.holdout, col),
        _ => None,
    };
    c
}

fn round_entry(
    round: usize,
    cands: &[Candidate],
    best: Option<usize>,
    before: &Holdout,
    accepted: bool,
    noise: f64,
) -> Round {
    entry(
        round,
        best.map(|i| &cands[i]),
        cands.len(),
        before,
        accepted,
        noise,
    )
}

fn entry(
    round: usize,
    c: Option<&Candidate>,
    n_cands: usize,
    before: &Holdout,
    accepted: bool,
    noise: f64,
) -> Round {
    Round {
        round,
        cause: c.map(|c| c.cause),
        column: c.and_then(|c| c.column.clone()),
        node: c.and_then(|c| c.node.clone()),
        rmse_before_um: before.rmse_um,
        rmse_um: c.map_or(before.rmse_um, |c| c.holdout.rmse_um),
        gain_pct: c.map_or(0.0, |c| c.gain_pct),
        score: c.map_or(0.0, |c| c.score),
        delta_bic: c.map_or(0.0, |c| c.delta_bic),
        excess_share: c.map_or(0.0, |c| excess_share(before, &c.holdout, noise)),
        accepted,
        kept: accepted,
        candidates: n_cands,
        paired: false,
    }
}

/// Partners a pair's lead is fitted with: the best-scoring candidate of each other cause.
pub const PAIR_PARTNERS: usize = Cause::ALL.len() - 1;

/// Two causes that pass together where neither passes alone. With two effects hidden, the
/// one whose extension improves the training fit most can make the held-out error worse on
/// its own — it takes up the other effect too, and carries that into the held-out rows — so a
/// round would stop with both unnamed. Its lead is the best-scoring fully fitted candidate with
/// the training evidence ([`MAX_DELTA_BIC`]) that fails the round's rule (`ok`) and whose
/// column may be named; it is fitted together with the best candidate of each other cause
/// (from the lead's and the partner's fitted values). A pair is taken when the joint model
/// passes the round's rule against the current model and, against each of the two alone,
/// the later rounds' rule ([`passes`]): each member earns its place beside the other. The
/// best such pair by score; `None` when there is none. The backward check then refits without
/// each, as for every accepted cause.
fn pair(
    cx: &Context<'_, '_>,
    b: &Baseline<'_>,
    cands: &[Candidate],
    taken: &[&Spec],
    ok: &(dyn Fn(&Candidate) -> bool + Sync),
) -> Result<Option<(usize, Candidate)>> {
    let (noise, opts, axis_index) = (cx.noise, cx.opts, b.axis_index);
    let Some(lead) = cands.iter().position(|c| {
        c.fit == Fit::Full
            && c.spec.is_some()
            && c.delta_bic < MAX_DELTA_BIC
            && c.score > 0.0
            && nameable(c)
            && !ok(c)
    }) else {
        return Ok(None);
    };
    let l = &cands[lead];
    let Some(ls) = l.spec.as_ref() else {
        return Ok(None);
    };
    let mut partners: Vec<usize> = Vec::new();
    for (k, c) in cands.iter().enumerate() {
        let fresh = partners.iter().all(|&q| cands[q].cause != c.cause);
        if c.cause != l.cause
            && fresh
            && nameable(c)
            && c.spec
                .as_ref()
                .is_some_and(|s| !candidates::overlaps(s, ls, axis_index))
        {
            partners.push(k);
        }
    }
    partners.truncate(PAIR_PARTNERS);
    crate::interrupt::check()?;
    progress::plan(opts.progress.as_deref(), partners.len());
    let fits = partners
        .into_par_iter()
        .map(|k| {
            crate::interrupt::check()?;
            let p = &cands[k];
            let Some(ps) = p.spec.as_ref() else {
                return Ok(None);
            };
            let chain: Vec<&Spec> = taken.iter().copied().chain([ls, ps]).collect();
            let Some(spec) = candidates::rebuild(cx.nominal, &chain, axis_index, cx.train) else {
                return Ok(None);
            };
            // the accepted extensions and the lead's from the lead's fit, the partner's from its own
            let n = ls.extra.len().min(spec.extra.len());
            let mut extra =
                candidates::carry(&spec.extra[..n], &spec.machine, &l.calibration.machine);
            extra.extend(candidates::carry(
                &spec.extra[n..],
                &spec.machine,
                &p.calibration.machine,
            ));
            let j = candidates::fit(
                Spec { extra, ..spec },
                b,
                cx.train,
                cx.held,
                Some(&l.calibration),
            );
            progress::step(opts.progress.as_deref());
            let j = j?;
            let each = passes(
                &against(&j, &l.calibration, &l.holdout),
                &l.holdout,
                noise,
                opts,
            ) && passes(
                &against(&j, &p.calibration, &p.holdout),
                &p.holdout,
                noise,
                opts,
            );
            Ok((ok(&j) && each).then_some((lead, j)))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(fits
        .into_iter()
        .flatten()
        .max_by(|a, b| a.1.score.total_cmp(&b.1.score)))
}

/// An accepted cause: its round, its candidate, its alternatives.
type Taken = (usize, Candidate, Vec<Alternative>);

/// The two entries of an accepted pair (rounds `r` and `r + 1`, the lead first) and their
/// accepted causes: the lead with the pair's figures (the round that accepted it is the pair's),
/// the partner as the pair's joint model, whose calibration is the current model.
fn accept_pair(
    r: usize,
    cands: &[Candidate],
    (lead, joint): (usize, Candidate),
    before: &Holdout,
    noise: f64,
) -> ([Round; 2], [Taken; 2]) {
    let l = &cands[lead];
    let mut first = entry(r, Some(l), cands.len(), before, true, noise);
    first.paired = true;
    let mut second = entry(r + 1, Some(&joint), cands.len(), before, true, noise);
    second.paired = true;
    let mut a = joint.clone();
    a.cause = l.cause;
    a.column = l.column.clone();
    a.node = l.node.clone();
    a.sensor_gain_pct = l.sensor_gain_pct;
    a.spec = l.spec.clone();
    (
        [first, second],
        [(r, a, Vec::new()), (r + 1, joint, Vec::new())],
    )
}

/// Runs rounds 2.. after round 1 (`cands1`, sorted by score, its named index `chosen1`), then
/// the backward check. `fit_round(machine, baseline, carried, taken)` fits one round's
/// candidates (sorted by score, best first).
pub(super) fn run<F>(
    cx: &Context<'_, '_>,
    base: &Baseline<'_>,
    cands1: &[Candidate],
    chosen1: Option<usize>,
    fit_round: F,
) -> Result<Outcome>
where
    F: Fn(&Machine, &Baseline<'_>, &[FreeParam], &[&Spec]) -> Result<Vec<Candidate>>,
{
    let (noise, opts, axis_index) = (cx.noise, cx.opts, base.axis_index);
    let best1 = cands1.iter().position(supported);
    // (round, candidate, its alternatives); the last one's calibration is the current model
    let first_rule = |c: &Candidate| supported(c) && c.score >= opts.min_score;
    let mut rounds = Vec::new();
    let mut accepted: Vec<Taken> = Vec::new();
    // the rounds whose accepted candidate is a pair's lead (its calibration is the pair's)
    let mut pair_leads: Vec<usize> = Vec::new();
    match chosen1 {
        Some(i) => {
            rounds.push(round_entry(1, cands1, Some(i), base.holdout, true, noise));
            accepted.push((
                1,
                cands1[i].clone(),
                alternatives(cands1, &cands1[i], first_rule),
            ));
        }
        None => {
            rounds.push(round_entry(1, cands1, best1, base.holdout, false, noise));
            let found = if base.holdout.rmse_um / noise > opts.noise_ratio {
                progress::stage(opts.progress.as_deref(), 2);
                pair(cx, base, cands1, &[], &first_rule)?
            } else {
                None
            };
            let Some(found) = found else {
                return Ok(Outcome {
                    causes: Vec::new(),
                    dropped: Vec::new(),
                    rounds,
                    joint: None,
                });
            };
            pair_leads.push(1);
            let (entries, taken) = accept_pair(1, cands1, found, base.holdout, noise);
            rounds.clear();
            rounds.extend(entries);
            accepted.extend(taken);
        }
    }
    let mut r = accepted.len() + 1;
    while r <= MAX_ROUNDS {
        let cur = &accepted[accepted.len() - 1].1;
        if cur.holdout.rmse_um / noise <= opts.noise_ratio {
            break; // only noise is left
        }
        let Some(spec) = cur.spec.as_ref() else {
            break;
        };
        crate::interrupt::check()?;
        progress::stage(opts.progress.as_deref(), r);
        let carried = candidates::carry(&spec.extra, &spec.machine, &cur.calibration.machine);
        let taken: Vec<&Spec> = accepted
            .iter()
            .filter_map(|(_, c, _)| c.spec.as_ref())
            .collect();
        let b = Baseline::new(
            &cur.calibration,
            &cur.holdout,
            base.options.clone(),
            axis_index,
            base.mates,
        );
        let cands = fit_round(&spec.machine, &b, &carried, &taken)?;
        let best = cands.iter().position(supported);
        let rule = |c: &Candidate| passes(c, &cur.holdout, noise, opts);
        let ok = best.is_some_and(|j| rule(&cands[j]));
        if let (Some(j), true) = (best, ok) {
            rounds.push(round_entry(r, &cands, best, &cur.holdout, true, noise));
            let alt = alternatives(&cands, &cands[j], rule);
            accepted.push((r, cands[j].clone(), alt));
            r += 1;
            continue;
        }
        let found = if r < MAX_ROUNDS {
            pair(cx, &b, &cands, &taken, &rule)?
        } else {
            None
        };
        match found {
            Some(found) => {
                pair_leads.push(r);
                let (entries, two) = accept_pair(r, &cands, found, &cur.holdout, noise);
                rounds.extend(entries);
                accepted.extend(two);
                r += 2;
            }
            None => {
                rounds.push(round_entry(r, &cands, best, &cur.holdout, false, noise));
                break;
            }
        }
    }
    // backward check: without each accepted cause in turn, does it still pass against the rest?
    // The models already fitted, by the rounds of the causes they hold: a refit without a cause
    // starts from the joint model's values and can stop in a worse minimum than the round that
    // fitted the same causes did, and a cause is not judged against a worse fit than one known.
    let mut known: Vec<(Vec<usize>, Candidate)> = Vec::new();
    for (i, (r, c, _)) in accepted.iter().enumerate() {
        if !pair_leads.contains(r) {
            known.push((accepted[..=i].iter().map(|a| a.0).collect(), c.clone()));
        }
    }
    let mut joint = accepted[accepted.len() - 1].1.clone();
    let mut dropped = Vec::new();
    while accepted.len() >= 2 {
        progress::plan(opts.progress.as_deref(), accepted.len());
        let fits = (0..accepted.len())
            .into_par_iter()
            .map(|j| {
                crate::interrupt::check()?;
                let chain: Vec<&Spec> = accepted
                    .iter()
                    .enumerate()
                    .filter(|&(k, _)| k != j)
                    .filter_map(|(_, (_, c, _))| c.spec.as_ref())
                    .collect();
                let spec = candidates::rebuild(cx.nominal, &chain, axis_index, cx.train)
                    .ok_or_else(|| {
                        Error::Numerical("an accepted extension could not be rebuilt".into())
                    })?;
                let extra =
                    candidates::carry(&spec.extra, &spec.machine, &joint.calibration.machine);
                let b = Baseline::new(
                    &joint.calibration,
                    &joint.holdout,
                    base.options.clone(),
                    axis_index,
                    base.mates,
                );
                let reduced = candidates::fit(Spec { extra, ..spec }, &b, cx.train, cx.held, None);
                progress::step(opts.progress.as_deref());
                let mut reduced = reduced?;
                let rest: Vec<usize> = accepted
                    .iter()
                    .enumerate()
                    .filter(|&(k, _)| k != j)
                    .map(|(_, a)| a.0)
                    .collect();
                if let Some((_, k)) = known.iter().find(|(rs, _)| *rs == rest) {
                    if k.calibration.ssr < reduced.calibration.ssr {
                        reduced = k.clone();
                    }
                }
                let full = against(&joint, &reduced.calibration, &reduced.holdout);
                Ok((j, full, reduced))
            })
            .collect::<Result<Vec<_>>>()?;
        let weakest = fits
            .into_iter()
            .filter(|(_, full, reduced)| {
                redundant(full, &reduced.holdout, base.holdout, noise, opts)
            })
            .min_by(|a, b| a.1.score.total_cmp(&b.1.score));
        match weakest {
            None => break,
            Some((j, _, reduced)) => {
                dropped.push(accepted.remove(j));
                joint = reduced;
            }
        }
    }
    if !dropped.is_empty() && accepted.len() == 1 {
        // what is left is checked against the baseline with round 1's rule
        let c = against(&joint, base.calibration, base.holdout);
        if !(supported(&c) && c.score >= opts.min_score) {
            dropped.push(accepted.remove(0));
        }
    }
    let to_entry = |(round, c, alternatives): (usize, Candidate, Vec<Alternative>)| {
        let params = match &c.spec {
            Some(s) => candidates::parameters(s, &joint.calibration.machine, axis_index),
            None => c.parameters.clone(),
        };
        Accepted {
            cause: c.cause,
            column: c.column.clone(),
            node: c.node.clone(),
            axis: cx.axis.to_string(),
            gain_pct: c.gain_pct,
            params,
            round,
            rmse_um: c.holdout.rmse_um,
            alternatives,
            spec: c.spec,
        }
    };
    let kept: Vec<usize> = accepted.iter().map(|(r, _, _)| *r).collect();
    for r in rounds.iter_mut() {
        r.kept = r.accepted && kept.contains(&r.round);
    }
    let joint = (!accepted.is_empty()).then(|| against(&joint, base.calibration, base.holdout));
    Ok(Outcome {
        causes: accepted.into_iter().map(to_entry).collect(),
        dropped: dropped.into_iter().map(to_entry).collect(),
        rounds,
        joint,
    })
}

/// The unexplained remainder: RMS of the final held-out residual above the noise,
/// √max(0, RMS² − noise²), when it is above `noise_ratio` noise levels (the rule that says
/// `unexplained`); 0 otherwise.
pub fn remainder_um(last: &Holdout, noise: f64, opts: &DiagnoseOptions) -> f64 {
    if last.rmse_um / noise > opts.noise_ratio {
        (last.rmse_um.powi(2) - noise * noise).max(0.0).sqrt()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{baseline, candidate, holdout};
    use super::*;

    #[test]
    fn a_later_round_must_remove_a_quarter_of_the_excess() {
        let opts = DiagnoseOptions::default();
        let before = baseline(); // 2.55 µm
        let noise = 0.5;
        // excess 2.55² − 0.5² = 6.2525; 2.3 µm leaves 5.04: 19 % removed
        let small = candidate(Cause::ThermalLag, 0.3, 2.3, -50.0);
        assert!(
            (excess_share(&before, &small.holdout, noise) - (1.0 - 5.04 / 6.2525)).abs() < 1e-9
        );
        assert!(!passes(&small, &before, noise, &opts));
        // 2.1 µm leaves 4.16: 33 % removed
        let enough = candidate(Cause::ThermalLag, 0.3, 2.1, -50.0);
        assert!(passes(&enough, &before, noise, &opts));
        // but not without the training evidence
        let weak = candidate(Cause::ThermalLag, 0.3, 2.1, -5.0);
        assert!(!passes(&weak, &before, noise, &opts));
        // nothing above the noise: nothing to remove
        assert_eq!(excess_share(&before, &enough.holdout, 3.0), 0.0);
    }

    #[test]
    fn alternatives_are_other_columns_of_the_cause_that_hold_out_as_well_and_pass() {
        let at = |cause: Cause, col: &str, rmse: f64, dbic: f64| {
            let mut c = candidate(cause, 0.3, rmse, dbic);
            c.column = Some(col.into());
            c
        };
        let chosen = at(Cause::UnmodeledSource, "T_a", 2.0, -50.0);
        let cands = vec![
            chosen.clone(),
            at(Cause::UnmodeledSource, "T_b", 2.09, -50.0), // within 5 %
            at(Cause::UnmodeledSource, "T_b", 2.05, -40.0), // the same column, better: kept once
            at(Cause::UnmodeledSource, "T_c", 1.9, -50.0),  // better held out
            at(Cause::UnmodeledSource, "T_d", 2.11, -50.0), // 5.5 % worse
            at(Cause::UnmodeledSource, "T_e", 2.0, -5.0),   // fails the rule (ΔBIC)
            at(Cause::UnmodeledSource, "T_a", 1.95, -50.0), // the chosen column on another node
            at(Cause::SensorDrift, "T_f", 2.0, -50.0),      // another cause
        ];
        let ok = |c: &Candidate| supported(c);
        let alt = alternatives(&cands, &chosen, ok);
        let cols: Vec<&str> = alt.iter().map(|a| a.column.as_str()).collect();
        assert_eq!(cols, ["T_c", "T_b"]);
        assert_eq!(alt[1].rmse_um, 2.05);
        // nothing close: none
        assert!(alternatives(&cands[..1], &chosen, ok).is_empty());
        // a cause without a column has none
        let lag = candidate(Cause::ThermalLag, 0.3, 2.0, -50.0);
        assert!(alternatives(&cands, &lag, ok).is_empty());
    }

    #[test]
    fn a_refit_that_holds_out_worse_than_the_baseline_shows_no_cause_redundant() {
        let opts = DiagnoseOptions::default();
        let base = baseline(); // 2.55 µm
        let noise = 0.1;
        // the joint model fits the training rows worse than the refit without the cause
        // (ΔBIC > 0 against it), so the cause does not pass against that refit
        let joint = candidate(Cause::UnmodeledSource, 0.5, 1.2, 240.0);
        let worse = holdout(3.8);
        assert!(!passes(&joint, &worse, noise, &opts));
        assert!(!redundant(&joint, &worse, &base, noise, &opts));
        // the same joint model against a refit that holds out better than the baseline
        let better = holdout(1.8);
        assert!(redundant(&joint, &better, &base, noise, &opts));
        // and a cause that passes against its refit is never redundant
        let strong = candidate(Cause::UnmodeledSource, 0.5, 1.2, -50.0);
        assert!(passes(&strong, &better, noise, &opts));
        assert!(!redundant(&strong, &better, &base, noise, &opts));
    }

    #[test]
    fn the_remainder_is_the_rms_above_the_noise_past_the_ratio() {
        let opts = DiagnoseOptions::default();
        let h = baseline(); // 2.55 µm
        assert!((remainder_um(&h, 1.0, &opts) - (2.55f64.powi(2) - 1.0).sqrt()).abs() < 1e-12);
        assert_eq!(remainder_um(&h, 1.3, &opts), 0.0); // within 2 noise levels
    }
}
