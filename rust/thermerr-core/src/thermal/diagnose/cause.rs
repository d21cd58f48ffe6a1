//! The catalogue of causes: what each one adds to the machine and which parameters it fits.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::candidates::{self, Spec};
use crate::error::Error;
use crate::thermal::machine::Machine;
use crate::thermal::sim::RunView;

/// A cause of thermal error the diagnosis can name (formats.md, "Diagnosis report").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Cause {
    /// The error follows the temperatures with a first-order lag.
    ThermalLag,
    /// The ambient temperature moves the axis directly.
    AmbientCoupling,
    /// An input (spindle speed) moves the axis directly, as a power of its level.
    SpeedGrowth,
    /// A heat source the network lacks, seen by an unused `T_*` column.
    UnmodeledSource,
    /// A node's expansion grows with the square of its temperature rise.
    NonlinearExpansion,
    /// A sensor's reading drifts linearly in time.
    SensorDrift,
}

impl Cause {
    /// Every cause, in the order candidates are built and reported.
    pub const ALL: [Cause; 6] = [
        Cause::ThermalLag,
        Cause::AmbientCoupling,
        Cause::SpeedGrowth,
        Cause::UnmodeledSource,
        Cause::NonlinearExpansion,
        Cause::SensorDrift,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Cause::ThermalLag => "thermal_lag",
            Cause::AmbientCoupling => "ambient_coupling",
            Cause::SpeedGrowth => "speed_growth",
            Cause::UnmodeledSource => "unmodeled_source",
            Cause::NonlinearExpansion => "nonlinear_expansion",
            Cause::SensorDrift => "sensor_drift",
        }
    }

    /// The extensions of `m` that model this cause for drift entry `axis` on `run` (none when
    /// the machine or the run has nothing for it, e.g. no unused `T_*` column).
    pub fn specs(
        self,
        m: &Machine,
        axis: usize,
        run: &RunView<'_>,
        source_columns: &[String],
    ) -> Vec<Spec> {
        match self {
            Cause::ThermalLag => vec![candidates::thermal_lag(m, axis)],
            Cause::AmbientCoupling => candidates::ambient_coupling(m, axis).into_iter().collect(),
            Cause::SpeedGrowth => candidates::speed_growth(m, axis, run),
            Cause::UnmodeledSource => candidates::unmodeled_source(m, source_columns),
            Cause::NonlinearExpansion => candidates::nonlinear_expansion(m, axis),
            Cause::SensorDrift => candidates::sensor_drift(m),
        }
    }

    /// The range the search allows the fitted parameter `name` of [`Cause::parameters`]
    /// (`None`: a linear term, not bounded by the search).
    pub fn search_range(self, name: &str) -> Option<(f64, f64)> {
        use super::candidates::{GROWTH_EXPONENT_RANGE, LAG_RANGE_S, SOURCE_RANGE_W_PER_K};
        match (self, name) {
            (Cause::ThermalLag, "tau_s") => Some(LAG_RANGE_S),
            (Cause::UnmodeledSource, "w_per_k") => Some(SOURCE_RANGE_W_PER_K),
            (Cause::SpeedGrowth, "exponent") => Some(GROWTH_EXPONENT_RANGE),
            _ => None,
        }
    }

    /// This cause's fitted parameters, read from the calibrated extension `m` (drift entry
    /// `axis`; `node`: the spec's node).
    pub fn parameters(self, m: &Machine, axis: usize, node: Option<&str>) -> BTreeMap<String, f64> {
        let d = &m.drift[axis];
        let named = |pairs: &[(&str, f64)]| {
            pairs
                .iter()
                .map(|&(k, v)| (k.to_string(), v))
                .collect::<BTreeMap<_, _>>()
        };
        match self {
            Cause::ThermalLag => named(&[("tau_s", d.lag_s.unwrap_or(0.0))]),
            Cause::AmbientCoupling => named(&[("um_per_k", d.ambient_um_per_k.unwrap_or(0.0))]),
            Cause::SpeedGrowth => d.inputs.last().map_or_else(BTreeMap::new, |t| {
                named(&[("um", t.um), ("exponent", t.exponent), ("ref", t.reference)])
            }),
            Cause::UnmodeledSource => m
                .links
                .last()
                .map_or_else(BTreeMap::new, |l| named(&[("w_per_k", l.w_per_k)])),
            Cause::NonlinearExpansion => node
                .and_then(|n| d.quadratic_um_per_k2.get(n))
                .map_or_else(BTreeMap::new, |v| named(&[("um_per_k2", *v)])),
            Cause::SensorDrift => node
                .and_then(|n| m.node_index(n))
                .map_or_else(BTreeMap::new, |i| {
                    named(&[("k_per_h", m.nodes[i].sensor_drift_k_per_h)])
                }),
        }
    }
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for Cause {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        Cause::ALL
            .into_iter()
            .find(|c| c.as_str() == s)
            .ok_or_else(|| {
                let known: Vec<&str> = Cause::ALL.iter().map(|c| c.as_str()).collect();
                Error::param(
                    "cause",
                    format!("unknown cause `{s}` (known: {})", known.join(", ")),
                )
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_through_str_and_serde() {
        for c in Cause::ALL {
            assert_eq!(c.as_str().parse::<Cause>().unwrap(), c);
            assert_eq!(c.to_string(), c.as_str());
            assert_eq!(
                serde_json::to_string(&c).unwrap(),
                format!("\"{}\"", c.as_str())
            );
        }
        assert!("thermal lag".parse::<Cause>().is_err());
    }
}
