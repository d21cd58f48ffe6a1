//! The machine TOML (formats.md, "Machine model") and the extension constructs the diagnosis
//! adds. Every construct is optional and absent by default, so a nominal file is exactly the
//! formats.md schema; every file this module writes loads back and simulates identically.
//!
//! | construct | where | meaning | unit |
//! |---|---|---|---|
//! | `sensor_offset_k` | node | the sensor reads node + offset | K |
//! | `sensor_drift_k_per_h` | node | the sensor reading drifts away from the node at this rate (sensor_drift) | K/h |
//! | `lag_s` | drift | the node terms of the drift (linear and quadratic: the structure's) follow through a first-order lag (thermal_lag); the ambient, column and input terms act directly | s |
//! | `ambient_um_per_k` | drift | direct term on the ambient's change since t = 0 (ambient_coupling) | µm/K |
//! | `quadratic_um_per_k2` | drift | term on the square of a node's rise (nonlinear_expansion) | µm/K² |
//! | `[[drift.inputs]]` `input`, `um`, `ref`, `exponent` | drift | instantaneous term um·((u/ref)^exponent − (u₀/ref)^exponent) (speed_growth) | µm |
//! | `[[drift.columns]]` `column`, `um_per_k` | drift | direct term on a measured temperature column's change | µm/K |
//!
//! An unmodelled heat source whose temperature is measured (unmodeled_source) needs no new
//! construct: it is a node with `boundary = "T_<column>"` and a link to the node it heats.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn one() -> f64 {
    1.0
}

/// Where a node whose start no reading gives (no sensor, or a sensor dead from the first row)
/// starts a run (the machine file's `unsensed_start`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UnsensedStart {
    /// At the room's first reading (formats.md): right for a run that starts cold, a machine
    /// that stood overnight.
    #[default]
    Room,
    /// Fitted to the run's first hour: the start that makes the sensed nodes follow their
    /// readings best (least squares; the network is linear in its start), within the range
    /// of the room's and the sensors' first readings. A second run of the day starts warm, its
    /// unsensed parts too, and the sensed parts' first hour shows how warm.
    Fit,
}

impl UnsensedStart {
    pub fn is_room(&self) -> bool {
        *self == UnsensedStart::Room
    }
}

/// The ambient: a run column, or a constant in °C.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Ambient {
    Column(String),
    Constant(f64),
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSpec {
    pub name: String,
    pub capacity_j_per_k: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub ambient_w_per_k: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub boundary: Option<String>,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub sensor_offset_k: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub sensor_drift_k_per_h: f64,
}

impl NodeSpec {
    /// What the node's sensor reads when the node is at `temp`, `since_s` seconds after the
    /// run's first row: `temp` + its offset + its drift (formats.md, `sensor_offset_k` and
    /// `sensor_drift_k_per_h`).
    pub fn sensor_reads(&self, temp: f64, since_s: f64) -> f64 {
        temp + self.sensor_offset_k + self.sensor_drift_k_per_h * since_s / 3600.0
    }

    /// A boundary node named `name` whose temperature is the column `col` (not simulated: its
    /// capacity is never used, and it loses no heat to the room of its own).
    pub fn boundary_on(name: String, col: &str) -> NodeSpec {
        NodeSpec {
            name,
            capacity_j_per_k: 1.0,
            ambient_w_per_k: 0.0,
            sensor: None,
            boundary: Some(col.to_string()),
            sensor_offset_k: 0.0,
            sensor_drift_k_per_h: 0.0,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    #[serde(deserialize_with = "two_names")]
    pub between: [String; 2],
    pub w_per_k: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SourceSpec {
    pub node: String,
    pub input: String,
    pub w: f64,
    #[serde(rename = "ref")]
    pub reference: f64,
    #[serde(default = "one")]
    pub exponent: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputTerm {
    pub input: String,
    pub um: f64,
    #[serde(rename = "ref")]
    pub reference: f64,
    #[serde(default = "one")]
    pub exponent: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColumnTerm {
    pub column: String,
    pub um_per_k: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriftSpec {
    pub axis: String,
    pub um_per_k: BTreeMap<String, f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lag_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient_um_per_k: Option<f64>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub quadratic_um_per_k2: BTreeMap<String, f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub inputs: Vec<InputTerm>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub columns: Vec<ColumnTerm>,
}

/// A machine: lumped thermal network + drift map (formats.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Machine {
    pub name: String,
    pub ambient: Ambient,
    /// How a node no reading starts begins a run: at the room's first reading (formats.md, the
    /// default) or fitted to the run's first hour (`unsensed_start = "fit"`).
    #[serde(default, skip_serializing_if = "UnsensedStart::is_room")]
    pub unsensed_start: UnsensedStart,
    pub nodes: Vec<NodeSpec>,
    #[serde(default)]
    pub links: Vec<LinkSpec>,
    #[serde(default)]
    pub sources: Vec<SourceSpec>,
    #[serde(default)]
    pub drift: Vec<DriftSpec>,
    /// Present when the network was identified from data by `thermerr init`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identified: Option<Identified>,
    /// Present when the values were fitted (`init`, `calibrate`, a diagnosis): their start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<FittedStart>,
}

/// The `[identified]` table: where an identified network came from (`thermerr init`), kept in
/// the file so that a diagnosis of it can say so (`report.json` `identified`). Remove the table
/// after rewriting the network by hand.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Identified {
    /// The run it was identified from, and its training and held-out rows.
    pub source: String,
    pub train_rows: usize,
    pub holdout_rows: usize,
    /// A separate held-out run's source (`thermerr init --holdout`); absent: the held-out rows
    /// are the last of `source`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holdout_run: Option<String>,
    /// The ambient column's rule (`given`, `named`, `coldest`) and the node count's rule.
    pub ambient_rule: String,
    pub node_rule: String,
    /// Each axis's training and held-out RMS (µm) right after identification, from the start
    /// in `[start]`.
    #[serde(default)]
    pub train_rmse_um: BTreeMap<String, f64>,
    #[serde(default)]
    pub holdout_rmse_um: BTreeMap<String, f64>,
    /// The run had no input column: the temperature column that drives the network (a boundary
    /// node), on which a diagnosis is weaker (docs/machine-model.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub driven_by: Option<String>,
}

/// The `[start]` table: the start a calibration fitted along with the file's values, on the run
/// it names. A simulation starts each node from its first reading (formats.md); a calibration
/// also fits an offset to that (±1 K), and the file's values, its figures and a diagnosis's were
/// fitted from that start. It belongs to that run: another run starts from its own readings
/// unless told otherwise (`Machine.simulate(run, initial_k="fitted")`,
/// `thermerr predict --start fitted`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FittedStart {
    /// The run the start was fitted on, as it was named.
    pub run: String,
    /// K added to each named node's first reading (its sensor's, or the ambient's for an
    /// unsensed node).
    pub initial_k: BTreeMap<String, f64>,
}

/// `between` names exactly two nodes (a fixed-size array would silently drop a third).
fn two_names<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<[String; 2], D::Error> {
    let v = Vec::<String>::deserialize(d)?;
    <[String; 2]>::try_from(v).map_err(|v| {
        serde::de::Error::custom(format!(
            "`between` names exactly two nodes, got {}: {v:?}",
            v.len()
        ))
    })
}

/// An error in entry `entry` of file `file`.
pub(crate) fn bad(file: &str, entry: impl Into<String>, reason: impl Into<String>) -> Error {
    Error::Parse {
        file: file.to_string(),
        line: None,
        row: None,
        column: None,
        reason: format!("{}: {}", entry.into(), reason.into()),
    }
}

impl Machine {
    /// A copy to write fitted values into: without the `[start]` the old values were fitted
    /// from, which is not the start of the new ones (the fit that ends sets its own).
    pub fn refit_copy(&self) -> Machine {
        Machine {
            start: None,
            ..self.clone()
        }
    }

    /// Reads and validates a machine TOML file.
    pub fn load(path: &Path) -> Result<Machine> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| match source.kind() {
            std::io::ErrorKind::InvalidData => bad(&file, "file", "not valid UTF-8"),
            _ => Error::Io {
                path: path.to_path_buf(),
                source,
            },
        })?;
        Machine::from_toml(&text, &file)
    }

    /// Parses and validates TOML text; `file` names it in errors.
    pub fn from_toml(text: &str, file: &str) -> Result<Machine> {
        let m: Machine = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|s| text[..s.start.min(text.len())].matches('\n').count() as u64 + 1);
            Error::Parse {
                file: file.to_string(),
                line,
                row: None,
                column: None,
                reason: e.message().to_string(),
            }
        })?;
        m.validate(file)?;
        Ok(m)
    }

    /// The TOML text of this machine (loads back to an equal machine).
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self)
            .map_err(|e| Error::Format(format!("cannot write the machine as TOML: {e}")))
    }

    /// The machine's fields as JSON text, with the TOML's structure.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string(self)
            .map_err(|e| Error::Format(format!("cannot write the machine as JSON: {e}")))
    }

    pub fn node_index(&self, name: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.name == name)
    }

    /// Checks names, signs, references and that the network is not singular.
    pub fn validate(&self, file: &str) -> Result<()> {
        if self.nodes.is_empty() {
            return Err(bad(file, "nodes", "a machine needs at least one node"));
        }
        if let Ambient::Constant(v) = self.ambient {
            if !v.is_finite() {
                return Err(bad(
                    file,
                    "ambient",
                    "must be a column name or a finite number",
                ));
            }
        }
        let mut index = HashMap::new();
        for (k, n) in self.nodes.iter().enumerate() {
            let at = format!("nodes[{k}] `{}`", n.name);
            if index.insert(n.name.as_str(), k).is_some() {
                return Err(bad(file, at, "duplicate node name"));
            }
            if !(n.capacity_j_per_k.is_finite() && n.capacity_j_per_k > 0.0) {
                return Err(bad(
                    file,
                    at,
                    format!("capacity_j_per_k must be > 0, got {}", n.capacity_j_per_k),
                ));
            }
            if !(n.ambient_w_per_k.is_finite() && n.ambient_w_per_k >= 0.0) {
                return Err(bad(
                    file,
                    at,
                    format!("ambient_w_per_k must be >= 0, got {}", n.ambient_w_per_k),
                ));
            }
            if n.sensor.is_some() && n.boundary.is_some() {
                return Err(bad(
                    file,
                    at,
                    "a node is either sensed or a boundary, not both",
                ));
            }
            if !(n.sensor_offset_k.is_finite() && n.sensor_drift_k_per_h.is_finite()) {
                return Err(bad(file, at, "sensor offset and drift must be finite"));
            }
        }
        let node = |name: &str, at: &str| -> Result<usize> {
            index
                .get(name)
                .copied()
                .ok_or_else(|| bad(file, at, format!("unknown node `{name}`")))
        };
        let mut adj = vec![Vec::new(); self.nodes.len()];
        for (k, l) in self.links.iter().enumerate() {
            let at = format!("links[{k}] {:?}", l.between);
            let (a, b) = (node(&l.between[0], &at)?, node(&l.between[1], &at)?);
            if a == b {
                return Err(bad(file, at, "a link joins two different nodes"));
            }
            if !(l.w_per_k.is_finite() && l.w_per_k >= 0.0) {
                return Err(bad(
                    file,
                    at,
                    format!("w_per_k must be >= 0, got {}", l.w_per_k),
                ));
            }
            if l.w_per_k > 0.0 {
                adj[a].push(b);
                adj[b].push(a);
            }
        }
        for (k, s) in self.sources.iter().enumerate() {
            let at = format!("sources[{k}] on `{}`", s.node);
            let i = node(&s.node, &at)?;
            if self.nodes[i].boundary.is_some() {
                return Err(bad(
                    file,
                    at,
                    "a boundary node's temperature is given: it takes no source",
                ));
            }
            if !(s.w.is_finite() && s.w >= 0.0) {
                return Err(bad(file, at, format!("w must be >= 0, got {}", s.w)));
            }
            if !(s.reference.is_finite() && s.reference > 0.0) {
                return Err(bad(
                    file,
                    at,
                    format!("ref must be > 0, got {}", s.reference),
                ));
            }
            if !s.exponent.is_finite() {
                return Err(bad(file, at, "exponent must be finite"));
            }
        }
        for (k, d) in self.drift.iter().enumerate() {
            let at = format!("drift[{k}] `{}`", d.axis);
            if !d.axis.starts_with("E_") {
                return Err(bad(file, at, "axis must name an E_* column"));
            }
            if let Some(j) = self.drift[..k].iter().position(|o| o.axis == d.axis) {
                return Err(bad(
                    file,
                    at,
                    format!("drift[{j}] already maps this axis: one [[drift]] per axis"),
                ));
            }
            for (j, c) in d.columns.iter().enumerate() {
                if !c.um_per_k.is_finite() {
                    return Err(bad(
                        file,
                        &at,
                        format!(
                            "columns[{j}] `{}`: um_per_k must be finite, got {}",
                            c.column, c.um_per_k
                        ),
                    ));
                }
            }
            if let Some(a) = d.ambient_um_per_k {
                if !a.is_finite() {
                    return Err(bad(file, &at, "ambient_um_per_k must be finite"));
                }
            }
            for (name, v) in d.um_per_k.iter().chain(&d.quadratic_um_per_k2) {
                node(name, &at)?;
                if !v.is_finite() {
                    return Err(bad(
                        file,
                        &at,
                        format!("coefficient of `{name}` must be finite"),
                    ));
                }
            }
            if let Some(l) = d.lag_s {
                if !(l.is_finite() && l > 0.0) {
                    return Err(bad(file, at, format!("lag_s must be > 0, got {l}")));
                }
            }
            for t in &d.inputs {
                if !(t.reference.is_finite()
                    && t.reference > 0.0
                    && t.um.is_finite()
                    && t.exponent.is_finite())
                {
                    return Err(bad(
                        file,
                        &at,
                        format!(
                            "input term on `{}`: ref > 0 and finite um/exponent",
                            t.input
                        ),
                    ));
                }
            }
        }
        // every simulated node must reach a fixed temperature (ambient or a boundary)
        let fixed: Vec<bool> = self
            .nodes
            .iter()
            .map(|n| n.boundary.is_some() || n.ambient_w_per_k > 0.0)
            .collect();
        let mut reach = fixed.clone();
        let mut stack: Vec<usize> = (0..self.nodes.len()).filter(|&i| fixed[i]).collect();
        while let Some(i) = stack.pop() {
            for &j in &adj[i] {
                if !reach[j] {
                    reach[j] = true;
                    stack.push(j);
                }
            }
        }
        if let Some(i) = reach.iter().position(|r| !r) {
            return Err(bad(
                file,
                format!("nodes[{i}] `{}`", self.nodes[i].name),
                "reaches neither the ambient nor a boundary through its links: the network is singular",
            ));
        }
        if let Some(st) = &self.start {
            for (name, k) in &st.initial_k {
                let at = format!("start.initial_k `{name}`");
                if !index.contains_key(name.as_str()) {
                    return Err(bad(file, at, "no node of that name"));
                }
                if !k.is_finite() {
                    return Err(bad(file, at, "must be a finite number of K"));
                }
            }
        }
        Ok(())
    }

    /// Every run column the machine reads (ambient, sensors, boundaries, inputs, drift columns).
    pub fn columns(&self) -> Vec<(String, String)> {
        let mut out = Vec::new();
        if let Ambient::Column(c) = &self.ambient {
            out.push((c.clone(), "ambient".to_string()));
        }
        for (k, n) in self.nodes.iter().enumerate() {
            if let Some(s) = &n.sensor {
                out.push((s.clone(), format!("nodes[{k}] `{}` sensor", n.name)));
            }
            if let Some(b) = &n.boundary {
                out.push((b.clone(), format!("nodes[{k}] `{}` boundary", n.name)));
            }
        }
        for (k, s) in self.sources.iter().enumerate() {
            out.push((s.input.clone(), format!("sources[{k}] input")));
        }
        for (k, d) in self.drift.iter().enumerate() {
            for t in &d.inputs {
                out.push((t.input.clone(), format!("drift[{k}] input term")));
            }
            for t in &d.columns {
                out.push((t.column.clone(), format!("drift[{k}] column term")));
            }
        }
        out
    }

    /// Errors naming the entry whose column a run lacks.
    pub fn check_columns(
        &self,
        file: &str,
        run_source: &str,
        has: impl Fn(&str) -> bool,
    ) -> Result<()> {
        for (col, entry) in self.columns() {
            if !has(&col) {
                return Err(bad(
                    file,
                    entry,
                    format!("column `{col}` is not in the run {run_source}"),
                ));
            }
        }
        Ok(())
    }
}
