//! The English sentence that states the verdict and the figures behind it.

use super::verdict::{supported, Verdict};
use super::{Candidate, Holdout};

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
pub fn named(cands: &[Candidate], i: usize, base: &Holdout, axis: &str) -> String {
    let c = &cands[i];
    let params: Vec<String> = c
        .parameters
        .iter()
        .map(|(k, v)| format!("{k} = {v:.4}"))
        .collect();
    let what = match (&c.column, &c.node) {
        (Some(col), _) => format!("{} on `{col}`", c.cause),
        (None, Some(nd)) => format!("{} on node `{nd}`", c.cause),
        (None, None) => c.cause.to_string(),
    };
    let sensor = c
        .sensor_gain_pct
        .map(|g| format!(" and the held-out residual of that sensor by {g:.0} %"))
        .unwrap_or_default();
    let among = if i == 0 {
        format!("{} candidate extensions", cands.len())
    } else {
        format!(
            "the {} of {} candidate extensions that lower the held-out error and improve the training fit",
            cands.iter().filter(|x| supported(x)).count(),
            cands.len()
        )
    };
    format!(
        "Extending the calibrated model with {what} ({}) {}{sensor}; it removes {:.0} % of the normalised held-out residual, the most of {among}, and improves the training fit by ΔBIC = {:.0}.",
        params.join(", "),
        error_change(axis, base, c),
        100.0 * c.score,
        c.delta_bic
    )
}

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
            let why = if c.score >= min_score && c.gain_pct <= 0.0 {
                format!(", which {}", error_change(axis, base, c))
            } else {
                String::new()
            };
            format!("{} {:.0} %{why}", c.cause, 100.0 * c.score)
        })
        .unwrap_or_default();
    let (b, ratio, min) = (base.rmse_um, base.rmse_um / noise_um, 100.0 * min_score);
    if verdict == Verdict::None {
        format!(
            "The calibrated model leaves a held-out RMS error of {b:.2} µm on {axis}, within {ratio:.1}× the probe noise ({noise_um:.2} µm); no extension removes {min:.0} % of the held-out residual (best: {best})."
        )
    } else {
        format!(
            "The calibrated model leaves a structured held-out RMS error of {b:.2} µm on {axis} ({ratio:.1}× the probe noise of {noise_um:.2} µm), and no catalogued extension removes {min:.0} % of it (best: {best})."
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{baseline, candidate};
    use super::*;
    use crate::thermal::diagnose::Cause;

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
    fn a_named_runner_up_is_not_called_the_best_of_all() {
        let base = baseline();
        let cands = [
            candidate(Cause::UnmodeledSource, 0.45, 6.81, -400.0),
            candidate(Cause::ThermalLag, 0.2, 2.0, -30.0),
        ];
        let s = named(&cands, 1, &base, "E_z");
        assert!(
            s.contains("the most of the 1 of 2 candidate extensions that lower"),
            "{s}"
        );
    }
}
