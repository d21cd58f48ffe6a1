//! The time axis of a run, shared by every part that needs its sampling step: the thermal
//! simulation's thinning, a failing-sensor guard's clock and a model's temperature history.

/// The median step of a time axis (s), the upper middle of the steps for an even count; `None`
/// with fewer than two samples or no positive median step. Non-finite steps are ignored.
pub fn median_step(t: &[f64]) -> Option<f64> {
    let mut d: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|v| v.is_finite())
        .collect();
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    let (_, m, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    (*m > 0.0).then_some(*m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_upper_middle_step() {
        assert_eq!(median_step(&[0.0, 15.0, 30.0, 60.0, 75.0]), Some(15.0));
        assert_eq!(median_step(&[0.0, 10.0, 30.0]), Some(20.0));
        assert_eq!(median_step(&[0.0]), None);
        assert_eq!(median_step(&[3.0, 3.0, 3.0]), None);
    }
}
