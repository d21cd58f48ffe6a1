//! Output shaping: how a predicted error becomes an offset a CNC controller accepts.
//!
//! A controller applies a compensation offset per interpolation cycle. It accepts small, bounded
//! offsets in its own unit and register width, and a large step in the offset is a step in the
//! tool path (a mark on the part). So the prediction goes through, in this order:
//!
//! 1. **clamp** to ±`limit_um`, and to what `bits` signed integer codes of `unit_um` can hold;
//! 2. **dead band**: a change smaller than `dead_band_um` from the last offset sent is not sent
//!    (the last offset is kept), so sensor noise does not make the axis dither;
//! 3. **rate limit**: the offset moves at most `max_rate_um_per_s` per second since the last
//!    sample (a large change is spread over the following samples);
//! 4. **quantise** to a multiple of `unit_um` (the controller's unit, e.g. 0.1 µm), never past
//!    the rate limit (the step is rounded toward the last offset when the limit binds).
//!
//! Every setting is optional; with none, the prediction passes unchanged. One [`Shaper`] per
//! run holds the last offset and its time; the library (`predict_run(..., shape=...)`) and the
//! edge (`thermerr-edge --shape ...`) run this one code, so they give the same offsets.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The settings (all optional). Text form: `limit=50,rate=2,deadband=0.5,unit=0.1,bits=16`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shaping {
    /// Largest offset magnitude, µm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit_um: Option<f64>,
    /// Largest change of the offset per second, µm/s (per sample when the input has no time).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_rate_um_per_s: Option<f64>,
    /// Changes smaller than this are not sent, µm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dead_band_um: Option<f64>,
    /// The controller's unit, µm: offsets are multiples of it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_um: Option<f64>,
    /// Width of the controller's signed offset register (codes of `unit_um`), 2..=53.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bits: Option<u32>,
}

fn positive(name: &'static str, v: Option<f64>) -> Result<()> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(Error::param(
            name,
            format!("must be a finite number > 0, got {x}"),
        )),
        _ => Ok(()),
    }
}

impl Shaping {
    /// Refuses settings that cannot be applied.
    pub fn check(&self) -> Result<()> {
        positive("limit_um", self.limit_um)?;
        positive("max_rate_um_per_s", self.max_rate_um_per_s)?;
        positive("unit_um", self.unit_um)?;
        if let Some(d) = self.dead_band_um {
            if !(d.is_finite() && d >= 0.0) {
                return Err(Error::param(
                    "dead_band_um",
                    format!("must be a finite number >= 0, got {d}"),
                ));
            }
        }
        if let Some(b) = self.bits {
            if !(2..=53).contains(&b) {
                return Err(Error::param(
                    "bits",
                    format!("must be within 2..=53, got {b}"),
                ));
            }
            if self.unit_um.is_none() {
                return Err(Error::param(
                    "bits",
                    "needs unit_um: the register holds codes of the controller's unit",
                ));
            }
        }
        Ok(())
    }

    /// Parses the text form `limit=50,rate=2,deadband=0.5,unit=0.1,bits=16` (any subset, any
    /// order; the long field names are accepted too).
    pub fn parse(text: &str) -> Result<Shaping> {
        let mut s = Shaping::default();
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, value) = part
                .split_once('=')
                .ok_or_else(|| Error::param("shape", format!("{part:?} is not key=value")))?;
            let (key, value) = (key.trim(), value.trim());
            let num = || {
                value
                    .parse::<f64>()
                    .map_err(|_| Error::param("shape", format!("{key}: {value:?} is not a number")))
            };
            match key {
                "limit" | "limit_um" => s.limit_um = Some(num()?),
                "rate" | "max_rate_um_per_s" => s.max_rate_um_per_s = Some(num()?),
                "deadband" | "dead_band_um" => s.dead_band_um = Some(num()?),
                "unit" | "unit_um" => s.unit_um = Some(num()?),
                "bits" => {
                    s.bits = Some(value.parse::<u32>().map_err(|_| {
                        Error::param("shape", format!("bits: {value:?} is not a whole number"))
                    })?)
                }
                other => {
                    return Err(Error::param(
                        "shape",
                        format!(
                            "unknown setting {other:?} (known: limit, rate, deadband, unit, bits)"
                        ),
                    ))
                }
            }
        }
        s.check()?;
        Ok(s)
    }

    /// The largest offset magnitude the settings allow (`limit_um` and the register).
    fn bound(&self) -> f64 {
        let mut b = self.limit_um.unwrap_or(f64::INFINITY);
        if let (Some(bits), Some(unit)) = (self.bits, self.unit_um) {
            b = b.min(((1u64 << (bits - 1)) - 1) as f64 * unit);
        }
        b
    }
}

/// The per-run state of the shaping: the last offset sent and when.
#[derive(Clone, Debug)]
pub struct Shaper {
    s: Shaping,
    bound: f64,
    last: Option<(f64, f64)>,
}

impl Shaper {
    pub fn new(s: Shaping) -> Result<Shaper> {
        s.check()?;
        Ok(Shaper {
            bound: s.bound(),
            s,
            last: None,
        })
    }

    /// A new run: the next sample starts without a last offset.
    pub fn reset(&mut self) {
        self.last = None;
    }

    /// The offset to send for prediction `y` (µm) at time `t` (s; the sample count when the
    /// input has no time).
    pub fn apply(&mut self, t: f64, y: f64) -> f64 {
        let (bound, unit) = (self.bound, self.s.unit_um);
        let v = y.clamp(-bound, bound);
        let quantise = |v: f64| match unit {
            Some(u) => (v / u).round() * u,
            None => v,
        };
        // rounding may carry a clamped value half a unit past the bound: one unit back in
        let inside = |q: f64| {
            if q.abs() > bound {
                q - q.signum() * unit.unwrap_or(0.0)
            } else {
                q
            }
        };
        let out = match self.last {
            None => inside(quantise(v)), // a run's first offset: nothing to rate-limit against
            Some((_, last)) if (v - last).abs() < self.s.dead_band_um.unwrap_or(0.0) => last,
            Some((t0, last)) => {
                let max_step = self
                    .s
                    .max_rate_um_per_s
                    .map_or(f64::INFINITY, |r| r * (t - t0).max(0.0));
                let step = (v - last).clamp(-max_step, max_step);
                let mut q = quantise(last + step);
                if let Some(u) = unit {
                    if (q - last).abs() > max_step {
                        q -= step.signum() * u; // rounding never exceeds the rate
                    }
                }
                inside(q)
            }
        };
        self.last = Some((t, out));
        out
    }

    /// A whole series at once (times `t`, predictions `y`), from a fresh state.
    pub fn apply_series(&mut self, t: &[f64], y: &[f64]) -> Result<Vec<f64>> {
        if t.len() != y.len() {
            return Err(Error::Shape(format!(
                "{} times for {} predictions",
                t.len(),
                y.len()
            )));
        }
        self.reset();
        Ok(t.iter()
            .zip(y)
            .map(|(&tk, &yk)| self.apply(tk, yk))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shaper(text: &str) -> Shaper {
        Shaper::new(Shaping::parse(text).unwrap()).unwrap()
    }

    #[test]
    fn nothing_set_passes_the_prediction_through() {
        let mut s = shaper("");
        for (k, y) in [1.234567, -80.0, 1e6].into_iter().enumerate() {
            assert_eq!(s.apply(k as f64, y), y);
        }
    }

    #[test]
    fn clamp_quantise_and_register() {
        let mut s = shaper("limit=50,unit=0.1");
        assert_eq!(s.apply(0.0, 73.0), 50.0);
        assert!((s.apply(1.0, 12.34) - 12.3).abs() < 1e-12);
        assert!((s.apply(2.0, -12.36) - -12.4).abs() < 1e-12);
        // a 8-bit register of 0.1-µm codes holds ±12.7 µm
        let mut s = shaper("unit=0.1,bits=8");
        assert!((s.apply(0.0, 30.0) - 12.7).abs() < 1e-12);
        assert!((s.apply(1.0, -30.0) - -12.7).abs() < 1e-12);
    }

    #[test]
    fn a_large_step_is_spread_at_the_rate() {
        let mut s = shaper("rate=2,unit=0.1");
        assert_eq!(s.apply(0.0, 0.0), 0.0);
        let out: Vec<f64> = (1..=6).map(|k| s.apply(k as f64 * 1.5, 10.0)).collect();
        // 3 µm per 1.5 s, then it settles on the target
        let want = [3.0, 6.0, 9.0, 10.0, 10.0, 10.0];
        for (o, w) in out.iter().zip(want) {
            assert!((o - w).abs() < 1e-9, "{out:?}");
        }
        // rounding never exceeds the rate: 0.25 µm allowed per step, unit 0.1 -> 0.2
        let mut s = shaper("rate=0.25,unit=0.1");
        s.apply(0.0, 0.0);
        let o = s.apply(1.0, 5.0);
        assert!((o - 0.2).abs() < 1e-12, "{o}");
    }

    #[test]
    fn the_dead_band_keeps_the_last_offset() {
        let mut s = shaper("deadband=0.5");
        assert_eq!(s.apply(0.0, 10.0), 10.0);
        assert_eq!(s.apply(1.0, 10.3), 10.0);
        assert_eq!(s.apply(2.0, 9.6), 10.0);
        assert_eq!(s.apply(3.0, 10.6), 10.6);
        s.reset();
        assert_eq!(s.apply(4.0, 10.3), 10.3);
    }

    #[test]
    fn bad_settings_name_themselves() {
        for (text, what) in [
            ("limit=-1", "limit_um"),
            ("rate=0", "max_rate_um_per_s"),
            ("unit=nan", "unit_um"),
            ("bits=16", "needs unit_um"),
            ("unit=0.1,bits=1", "2..=53"),
            ("speed=3", "unknown setting"),
            ("limit", "key=value"),
            ("limit=abc", "not a number"),
        ] {
            let e = Shaping::parse(text).unwrap_err().to_string();
            assert!(e.contains(what), "{text}: {e}");
        }
    }
}
