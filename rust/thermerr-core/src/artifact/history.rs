//! Temperature history as model inputs: the readings of a static model (MLR, RBF, SVR, BP) at
//! one instant miss how the machine got there, which a seq2seq network reads from the last
//! minutes. Each input reading `x` is followed by its rise over about the last τ seconds,
//! `x − f_τ`, where `f_τ` is a first-order low-pass filter of the reading:
//!
//! f ← x at the run's first sample, then f ← f + (1 − e^(−Δt/τ)) (x − f)
//!
//! with Δt the time since the previous sample (`step_s` when the input has no times). The
//! model's inputs are `[x_1..x_d, x_1 − f_1(τ_1) .. x_d − f_d(τ_1), .., x_d − f_d(τ_k)]`. One
//! owner: the batch [`History::transform`] the library fits with and the streaming
//! [`HistoryState`] the edge keeps run the same arithmetic, row after row.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Most time constants a model may ask for.
pub const MAX_TAUS: usize = 16;

/// The `history` entry of a model file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct History {
    /// the filters' time constants (s)
    pub tau_s: Vec<f64>,
    /// seconds per sample when the input has no times (the training run's median step)
    pub step_s: f64,
}

impl History {
    /// Checks the time constants and the step.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Format(format!("history: {m}")));
        if self.tau_s.is_empty() || self.tau_s.len() > MAX_TAUS {
            return bad(format!(
                "needs 1 to {MAX_TAUS} time constants, got {}",
                self.tau_s.len()
            ));
        }
        if let Some(t) = self.tau_s.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
            return bad(format!(
                "a time constant must be a finite number of seconds > 0, got {t}"
            ));
        }
        if !(self.step_s.is_finite() && self.step_s > 0.0) {
            return bad(format!("step_s must be > 0, got {}", self.step_s));
        }
        Ok(())
    }

    /// Model inputs per reading: the reading and one rise per time constant.
    pub fn width(&self) -> usize {
        1 + self.tau_s.len()
    }

    /// The model inputs of a whole run: `x` row-major with `d` readings per row, `times` one per
    /// row (or `None` for rows `step_s` apart).
    pub fn transform(&self, x: &[f64], d: usize, times: Option<&[f64]>) -> Result<Vec<f64>> {
        self.validate()
            .map_err(|e| Error::param("history", e.to_string()))?;
        if d == 0 || x.len() % d != 0 {
            return Err(Error::Shape(format!(
                "history needs rows of {d} readings, got {} values",
                x.len()
            )));
        }
        let n = x.len() / d;
        if let Some(t) = times {
            if t.len() != n {
                return Err(Error::Shape(format!("{} times for {n} rows", t.len())));
            }
        }
        let mut state = HistoryState::new(self, d);
        let w = d * self.width();
        let mut out = vec![0.0; n * w];
        for (i, (row, o)) in x.chunks_exact(d).zip(out.chunks_exact_mut(w)).enumerate() {
            state.push(self, times.map(|t| t[i]), row, o);
        }
        Ok(out)
    }
}

/// The filters' values over a run, kept sample by sample (no allocation per sample).
#[derive(Clone, Debug)]
pub struct HistoryState {
    f: Vec<f64>,
    t_prev: f64,
    started: bool,
}

impl HistoryState {
    pub fn new(h: &History, d: usize) -> Self {
        HistoryState {
            f: vec![0.0; d * h.tau_s.len()],
            t_prev: 0.0,
            started: false,
        }
    }

    /// Forgets the run.
    pub fn reset(&mut self) {
        self.started = false;
    }

    /// One row of `d` readings at time `t` into `out` (`d × width` model inputs).
    #[inline]
    pub fn push(&mut self, h: &History, t: Option<f64>, x: &[f64], out: &mut [f64]) {
        let d = x.len();
        let t = t.unwrap_or(if self.started {
            self.t_prev + h.step_s
        } else {
            0.0
        });
        out[..d].copy_from_slice(x);
        let dt = if self.started {
            (t - self.t_prev).max(0.0)
        } else {
            0.0
        };
        for (k, tau) in h.tau_s.iter().enumerate() {
            let a = 1.0 - (-dt / tau).exp();
            let f = &mut self.f[k * d..(k + 1) * d];
            let o = &mut out[(k + 1) * d..(k + 2) * d];
            for j in 0..d {
                f[j] = if self.started {
                    f[j] + a * (x[j] - f[j])
                } else {
                    x[j]
                };
                o[j] = x[j] - f[j];
            }
        }
        self.t_prev = t;
        self.started = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_rises_then_decays_with_tau() {
        let h = History {
            tau_s: vec![10.0],
            step_s: 1.0,
        };
        // a unit step at t = 1: the rise jumps to 1 − a and decays as e^(−t/τ)
        let x = [0.0, 1.0, 1.0, 1.0];
        let out = h.transform(&x, 1, None).unwrap();
        let a = 1.0 - (-0.1f64).exp();
        assert_eq!(out[0..2], [0.0, 0.0]);
        assert!((out[3] - (1.0 - a)).abs() < 1e-15);
        assert!((out[5] - (1.0 - a) * (1.0 - a)).abs() < 1e-15);
        assert!((out[7] - (1.0 - a).powi(3)).abs() < 1e-15);
    }

    #[test]
    fn times_and_steps_agree_and_streaming_equals_batch() {
        let h = History {
            tau_s: vec![30.0, 300.0],
            step_s: 15.0,
        };
        let x: Vec<f64> = (0..40)
            .flat_map(|i| [20.0 + 0.1 * i as f64, (i as f64).sin()])
            .collect();
        let t: Vec<f64> = (0..40).map(|i| 15.0 * i as f64).collect();
        let a = h.transform(&x, 2, None).unwrap();
        let b = h.transform(&x, 2, Some(&t)).unwrap();
        assert_eq!(a, b);
        let mut s = HistoryState::new(&h, 2);
        let mut o = vec![0.0; 6];
        for (i, row) in x.chunks_exact(2).enumerate() {
            s.push(&h, Some(t[i]), row, &mut o);
            assert_eq!(o[..], b[i * 6..(i + 1) * 6]);
        }
    }

    #[test]
    fn bad_histories_are_refused() {
        for (tau, step) in [
            (vec![], 1.0),
            (vec![0.0], 1.0),
            (vec![f64::NAN], 1.0),
            (vec![5.0], 0.0),
        ] {
            let h = History {
                tau_s: tau,
                step_s: step,
            };
            assert!(h.validate().unwrap_err().to_string().contains("history"));
        }
    }
}
