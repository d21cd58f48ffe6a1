//! Exact simulation of the lumped network: C dT/dt = G·(T_j − T_i) + G_a (T_amb − T) + Q(u),
//! inputs and boundary temperatures held between samples, each step the exact solution
//! x⁺ = Φ x + Γ f with Φ = e^{Mh} and Γ = ∫₀ʰ e^{Ms} ds (both by one scaled Taylor series and
//! its doublings, what e^{[[M, I], [0, 0]]·h} holds in its top blocks), cached per distinct step
//! length.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use nalgebra::DMatrix;

use super::machine::{Ambient, DriftSpec, Machine, UnsensedStart};
use crate::error::{Error, Result};
use crate::portable;
use crate::run::Run;

/// A column's failing rows ([`crate::guard::failing_rows`]).
pub type Failing = Arc<Vec<std::ops::Range<usize>>>;

/// Named columns of a run, borrowed.
pub struct RunView<'a> {
    pub source: String,
    pub time: &'a [f64],
    cols: HashMap<&'a str, &'a [f64]>,
    /// Each column's failing rows, found once per view: a calibration simulates its view
    /// thousands of times, and each simulation holds the failing stretches of the room.
    failing: Mutex<HashMap<String, Failing>>,
    /// A thinned view's inputs over each of its steps ([`Thinned`]): what its sources see.
    held: Option<&'a HashMap<String, StepInput>>,
}

/// The inputs (`U_*` columns) of a thinned run over each of its steps, so that a source's power
/// over a thinned step is the mean of the powers the original rows of that step hold, each
/// weighted by its share of the step: thinned row `k`'s step holds the values
/// `value[start[k]..start[k + 1]]` for the shares `share[..]` of it (consecutive equal values
/// merged, so a step over which the input holds is one entry). Picking every k-th input instead
/// moves each change of the input to the next kept row: on a 15-s run fitted every 60 s a
/// spindle step came up to 45 s late, and the calibrated network left 0.6 µm held out where the
/// noise was 0.15 µm (a false `unexplained`).
#[derive(Clone, Debug, Default)]
struct StepInput {
    value: Vec<f64>,
    share: Vec<f64>,
    start: Vec<usize>,
}

impl<'a> RunView<'a> {
    pub fn new(run: &'a Run) -> Self {
        RunView {
            source: run.source.clone(),
            time: &run.time_s,
            cols: run
                .names
                .iter()
                .zip(&run.columns)
                .map(|(n, c)| (n.as_str(), c.as_slice()))
                .collect(),
            failing: Mutex::default(),
            held: None,
        }
    }

    /// Refuses a file that holds two runs joined, its clock running on
    /// ([`crate::guard::one_run`] on every `T_*` column): what a network is fitted or
    /// diagnosed on is one run.
    pub fn one_run(&self) -> Result<()> {
        let mut names: Vec<&str> = self
            .cols
            .keys()
            .copied()
            .filter(|c| c.starts_with("T_"))
            .collect();
        names.sort_unstable();
        let cols: Vec<&[f64]> = names.iter().map(|c| self.cols[c]).collect();
        crate::guard::one_run(&self.source, &names, &cols, self.time)
    }

    /// Input `name`'s values through `f`, one per row, for the forcing of the step that starts
    /// there: on a thinned view the weighted mean over the original rows of the step
    /// ([`StepInput`]), else the row's own.
    pub fn held_power(&self, name: &str, mut f: impl FnMut(f64) -> f64) -> Result<Vec<f64>> {
        let col = self.col(name)?;
        // the power for the last input value (stepped inputs repeat it for hours)
        let mut last: (f64, f64) = (f64::NAN, 0.0);
        let mut power = |v: f64| {
            if v.to_bits() != last.0.to_bits() {
                last = (v, f(v));
            }
            last.1
        };
        match self.held.and_then(|h| h.get(name)) {
            Some(h) => Ok((0..col.len())
                .map(|k| {
                    let r = h.start[k]..h.start[k + 1];
                    h.value[r.clone()]
                        .iter()
                        .zip(&h.share[r])
                        .map(|(&v, &w)| w * power(v))
                        .sum()
                })
                .collect()),
            None => Ok(col.iter().map(|&v| power(v)).collect()),
        }
    }

    /// The rows of column `name` where the run shows its sensor failing
    /// ([`crate::guard::failing_rows`]), computed on first use and kept with the view.
    pub fn failing(&self, name: &str) -> Result<Failing> {
        let lock = || self.failing.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(f) = lock().get(name) {
            return Ok(f.clone());
        }
        let f: Failing = Arc::new(crate::guard::failing_rows(self.col(name)?, self.time));
        lock().insert(name.to_string(), f.clone());
        Ok(f)
    }

    pub fn col(&self, name: &str) -> Result<&'a [f64]> {
        self.cols
            .get(name)
            .copied()
            .ok_or_else(|| Error::MissingColumn {
                file: self.source.clone(),
                column: name.to_string(),
                available: {
                    let mut v: Vec<&str> = self.cols.keys().copied().collect();
                    v.sort_unstable();
                    v.join(", ")
                },
            })
    }

    /// Names of the columns starting with `prefix`.
    pub fn cols_with_prefix(&self, prefix: &str) -> Vec<String> {
        self.cols
            .keys()
            .filter(|c| c.starts_with(prefix))
            .map(|c| c.to_string())
            .collect()
    }

    pub fn has(&self, name: &str) -> bool {
        self.cols.contains_key(name)
    }

    pub fn len(&self) -> usize {
        self.time.len()
    }

    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// The first `rows` rows (all of them when the run is shorter). A simulation is causal and
    /// its terms are taken against the first row, so on these rows it gives what it gives on the
    /// whole run.
    pub fn head(&self, rows: usize) -> RunView<'a> {
        let rows = rows.min(self.len());
        RunView {
            source: self.source.clone(),
            time: &self.time[..rows],
            cols: self.cols.iter().map(|(n, c)| (*n, &c[..rows])).collect(),
            failing: Mutex::default(),
            // a step's entries are found from its row, so the first rows' are the same
            held: self.held,
        }
    }
}

/// Simulated node temperatures, sensor readings and drift axes.
#[derive(Clone, Debug)]
pub struct Simulation {
    pub node_names: Vec<String>,
    /// n_steps × n_nodes, row-major.
    pub temps: Vec<f64>,
    /// (column, predicted reading) per sensed node, in node order.
    pub sensors: Vec<(String, Vec<f64>)>,
    /// (axis, predicted error) per drift entry.
    pub drift: Vec<(String, Vec<f64>)>,
}

impl Simulation {
    pub fn node(&self, k: usize) -> Vec<f64> {
        let n = self.node_names.len();
        self.temps.chunks_exact(n).map(|r| r[k]).collect()
    }
}

/// The network reduced to its simulated (non-boundary) nodes.
struct Network {
    dyn_nodes: Vec<usize>,
    /// node index → position among dynamic nodes
    pos: Vec<Option<usize>>,
    m: DMatrix<f64>,
    cap: Vec<f64>,
    g_amb: Vec<f64>,
    /// (dynamic position, boundary node index, conductance)
    bnd_links: Vec<(usize, usize, f64)>,
}

fn network(mach: &Machine) -> Network {
    let nn = mach.nodes.len();
    let dyn_nodes: Vec<usize> = (0..nn)
        .filter(|&i| mach.nodes[i].boundary.is_none())
        .collect();
    let mut pos = vec![None; nn];
    for (p, &i) in dyn_nodes.iter().enumerate() {
        pos[i] = Some(p);
    }
    let nd = dyn_nodes.len();
    let cap: Vec<f64> = dyn_nodes
        .iter()
        .map(|&i| mach.nodes[i].capacity_j_per_k)
        .collect();
    let g_amb: Vec<f64> = dyn_nodes
        .iter()
        .map(|&i| mach.nodes[i].ambient_w_per_k)
        .collect();
    let mut m = DMatrix::<f64>::zeros(nd, nd);
    let mut bnd_links = Vec::new();
    for p in 0..nd {
        m[(p, p)] -= g_amb[p];
    }
    for l in &mach.links {
        let (Some(a), Some(b)) = (
            mach.node_index(&l.between[0]),
            mach.node_index(&l.between[1]),
        ) else {
            continue;
        };
        let g = l.w_per_k;
        match (pos[a], pos[b]) {
            (Some(pa), Some(pb)) => {
                m[(pa, pb)] += g;
                m[(pb, pa)] += g;
                m[(pa, pa)] -= g;
                m[(pb, pb)] -= g;
            }
            (Some(pa), None) => {
                m[(pa, pa)] -= g;
                bnd_links.push((pa, b, g));
            }
            (None, Some(pb)) => {
                m[(pb, pb)] -= g;
                bnd_links.push((pb, a, g));
            }
            (None, None) => {}
        }
    }
    for p in 0..nd {
        for q in 0..nd {
            m[(p, q)] /= cap[p];
        }
    }
    Network {
        dyn_nodes,
        pos,
        m,
        cap,
        g_amb,
        bnd_links,
    }
}

/// How the simulated nodes start.
#[derive(Clone, Debug, Default)]
pub enum Init {
    /// formats.md: a sensed node at its sensor's first reading (less its offset), an unsensed
    /// node at the ambient's first reading.
    #[default]
    FirstReading,
    /// As `FirstReading`, plus a per-node offset (K), e.g. fitted by calibration.
    Offsets(Vec<f64>),
}

fn ambient_series<'a>(mach: &Machine, run: &RunView<'a>) -> Result<std::borrow::Cow<'a, [f64]>> {
    Ok(match &mach.ambient {
        Ambient::Column(c) => driving(run, c)?,
        Ambient::Constant(v) => std::borrow::Cow::Owned(vec![*v; run.len()]),
    })
}

/// A temperature column that drives the network (the room, a boundary node), with each
/// stretch where the run shows its sensor failing ([`crate::guard::failing_rows`]: an open
/// thermocouple at its rail, a spike) held at the last right reading before it (at the first
/// one after it for a sensor dead from the first row): the model is driven across it as across
/// a gap in the log. A column that never fails is borrowed as is.
pub fn driving<'a>(run: &RunView<'a>, c: &str) -> Result<std::borrow::Cow<'a, [f64]>> {
    let col = run.col(c)?;
    let failing = run.failing(c)?;
    if failing.is_empty() {
        return Ok(std::borrow::Cow::Borrowed(col));
    }
    let mut held = col.to_vec();
    for r in failing.iter().cloned() {
        // a stretch starts at a jump, or at row 0 for a sensor dead from the start: held at the
        // first right reading after it there
        let right = match r.start {
            0 => col[r.end.min(col.len() - 1)],
            s => col[s - 1],
        };
        held[r].fill(right);
    }
    Ok(std::borrow::Cow::Owned(held))
}

/// Every `k`-th row of a run, owned (see [`crate::thermal::calibrate::FIT_STEP_S`]), with its
/// inputs over each thinned step for the sources' power ([`StepInput`]).
pub struct Thinned {
    source: String,
    time: Vec<f64>,
    cols: Vec<(String, Vec<f64>)>,
    inputs: HashMap<String, StepInput>,
}

impl Thinned {
    pub fn of(run: &RunView<'_>, k: usize) -> Thinned {
        let k = k.max(1);
        let every = |c: &[f64]| c.iter().step_by(k).copied().collect::<Vec<f64>>();
        let n = run.len();
        let time = every(run.time);
        // thinned row i's step covers original rows i·k .. (i+1)·k, each by its own step's
        // share of it; the last row's is the row itself
        let steps: Vec<(usize, usize)> = (0..time.len())
            .map(|i| (i * k, ((i + 1) * k).min(n)))
            .map(|(a, z)| if z >= n { (a, a + 1) } else { (a, z) })
            .collect();
        let inputs = run
            .cols
            .iter()
            .filter(|(name, _)| name.starts_with("U_"))
            .map(|(name, c)| {
                let mut h = StepInput::default();
                for &(a, z) in &steps {
                    let first = h.value.len();
                    h.start.push(first);
                    let span = run.time[z.min(n - 1)] - run.time[a];
                    for j in a..z {
                        let w = if span > 0.0 {
                            (run.time[j + 1] - run.time[j]) / span
                        } else {
                            1.0 / (z - a) as f64
                        };
                        if h.value.len() > first
                            && h.value[h.value.len() - 1].to_bits() == c[j].to_bits()
                        {
                            *h.share.last_mut().expect("a value has its share") += w;
                        } else {
                            h.value.push(c[j]);
                            h.share.push(w);
                        }
                    }
                    // a step over which the input holds is its one value, exactly
                    if h.value.len() == first + 1 {
                        h.share[first] = 1.0;
                    }
                }
                h.start.push(h.value.len());
                (name.to_string(), h)
            })
            .collect();
        Thinned {
            source: run.source.clone(),
            time,
            cols: run
                .cols
                .iter()
                .map(|(n, c)| (n.to_string(), every(c)))
                .collect(),
            inputs,
        }
    }

    pub fn view(&self) -> RunView<'_> {
        RunView {
            source: self.source.clone(),
            time: &self.time,
            cols: self
                .cols
                .iter()
                .map(|(n, c)| (n.as_str(), c.as_slice()))
                .collect(),
            failing: Mutex::default(),
            held: Some(&self.inputs),
        }
    }
}

pub use crate::timeaxis::median_step;

/// Distinct step lengths whose transition matrices are kept at once when each is built on
/// demand (by its own series).
const MAX_STEP_LENGTHS: usize = 1024;
/// Widest range of step lengths (in grid steps) whose matrices are built by products.
const CHAIN_SPAN: i64 = 4096;
/// The n × n products of one transition by its own series (20 terms and a few doublings): a
/// chain of products (two per grid step of the range) builds the distinct step lengths only
/// when it takes fewer. A log with a few rows dropped has a few lengths far apart (60, 75, 90,
/// 105 s thinned from 15 s: 1 440 grid steps), where the chain took 2 880 products per
/// simulation against 4 series; a jittering logger has hundreds close together, where it pays.
const SERIES_PRODUCTS: i64 = 30;
/// Values (f64) of the transitions a chain keeps at once: the chain builds every distinct length
/// of the run in one go, however many there are (a jittering logger's thousands).
const MAX_CHAIN_VALUES: usize = 1 << 22;

/// Whether the distinct step lengths `steps` (grid steps, ascending) of an `nd`-node network are
/// built by a chain of products rather than each by its own series: more than two, within
/// [`CHAIN_SPAN`], fewer products than the series take ([`SERIES_PRODUCTS`]), and all kept at
/// once within [`MAX_CHAIN_VALUES`].
fn chain_pays(steps: &[i64], nd: usize) -> bool {
    let (Some(&lo), Some(&hi)) = (steps.first(), steps.last()) else {
        return false;
    };
    steps.len() > 2
        && hi - lo <= CHAIN_SPAN
        && 2 * (hi - lo) < SERIES_PRODUCTS * steps.len() as i64
        && steps.len() * 2 * nd * nd <= MAX_CHAIN_VALUES
}

/// The time axis on a grid of `q` seconds, a power of two near 1/1000 of the mean step.
///
/// Each distinct step length needs its own transition (Φ, Γ); a logger that jitters (±0.5 s on
/// 60-s samples) would make every step distinct. On the grid, a run on whole (or binary-fraction)
/// seconds keeps its exact steps, and a jittered one has a few dozen distinct step lengths; each
/// time moves by at most q/2 (30 ms at 60-s sampling) and the moves do not accumulate, because
/// the times are rounded, not the steps. A logger whose stamps spread wider (15-s samples
/// anywhere from 11 to 19 s apart: a thousand lengths on the 1/128-s grid, each simulation
/// then building a thousand transitions) is put on a coarser grid, see [`Steps::of`].
struct Ticks {
    q: f64,
}

impl Ticks {
    fn new(t: &[f64]) -> Self {
        let n = t.len();
        let mean = if n > 1 {
            (t[n - 1] - t[0]) / (n - 1) as f64
        } else {
            1.0
        };
        let e = if mean.is_finite() && mean > 0.0 {
            portable::log2(mean / 1024.0).floor().clamp(-40.0, 40.0)
        } else {
            0.0
        };
        Ticks {
            q: 2f64.powi(e as i32),
        }
    }

    fn at(&self, t: f64) -> i64 {
        (t / self.q).round() as i64
    }

    /// Each step of `t` in ticks and the distinct lengths, ascending.
    fn steps(&self, t: &[f64]) -> (Vec<i64>, Vec<i64>) {
        let at: Vec<i64> = t.iter().map(|&v| self.at(v)).collect();
        let dt: Vec<i64> = at.windows(2).map(|w| w[1] - w[0]).collect();
        let mut distinct = dt.clone();
        distinct.dedup(); // a logger's steps repeat: the sort below sees a handful of values
        distinct.sort_unstable();
        distinct.dedup();
        (dt, distinct)
    }
}

/// Distinct step lengths on the grid above which it is made coarser (a widely jittering
/// logger), by doublings: at most [`MAX_COARSENING`] of them, and never past one second.
const MAX_GRID_LENGTHS: usize = 128;
/// At most 2³: the coarsest grid is about 1/128 of the mean step, so a time moves by at most
/// 1/256 of a step (59 ms at 15 s), where a thermal network's fastest node takes minutes.
const MAX_COARSENING: u32 = 3;

/// Simulates the machine over the run's time axis and inputs.
pub fn simulate(mach: &Machine, run: &RunView<'_>, init: &Init) -> Result<Simulation> {
    let temps = simulate_nodes(mach, run, init)?;
    finish(mach, run, temps)
}

/// A run's time axis on its tick grid: what every simulation over the run shares (a search
/// simulates the same rows thousands of times).
pub struct Steps {
    q: f64,
    /// each step in ticks (the times are rounded, not the steps)
    dt: Vec<i64>,
    /// the distinct step lengths, ascending
    distinct: Vec<i64>,
    /// each step's place in `distinct` (a simulation looks its matrices up by it)
    kind: Vec<u32>,
}

impl Steps {
    /// The steps of the times `t` on the grid of [`Ticks`]: made coarser (doubled, at most
    /// [`MAX_COARSENING`] times, never past one second, so that whole seconds stay exact) while
    /// the steps take more than [`MAX_GRID_LENGTHS`] distinct lengths. A run on whole seconds,
    /// or a few lengths (rows dropped), keeps its grid and its exact steps.
    pub fn of(t: &[f64]) -> Steps {
        let mut ticks = Ticks::new(t);
        let (mut dt, mut distinct) = ticks.steps(t);
        for _ in 0..MAX_COARSENING {
            if distinct.len() <= MAX_GRID_LENGTHS || 2.0 * ticks.q > 1.0 {
                break;
            }
            ticks.q *= 2.0;
            (dt, distinct) = ticks.steps(t);
        }
        let kind = dt
            .iter()
            .map(|d| distinct.binary_search(d).unwrap_or(0) as u32)
            .collect();
        Steps {
            q: ticks.q,
            dt,
            distinct,
            kind,
        }
    }
}

/// Node temperatures only (n_steps × n_nodes, row-major), boundary nodes included.
pub fn simulate_nodes(mach: &Machine, run: &RunView<'_>, init: &Init) -> Result<Vec<f64>> {
    simulate_nodes_on(mach, run, init, &Steps::of(run.time))
}

/// [`simulate_nodes`] with the run's [`Steps`] computed once by the caller.
pub fn simulate_nodes_on(
    mach: &Machine,
    run: &RunView<'_>,
    init: &Init,
    steps: &Steps,
) -> Result<Vec<f64>> {
    let n_t = run.len();
    if n_t == 0 {
        return Err(Error::Shape("cannot simulate an empty run".into()));
    }
    if steps.dt.len() + 1 != n_t {
        return Err(Error::Shape(format!(
            "{}: the steps were computed for {} rows, the run has {n_t}",
            run.source,
            steps.dt.len() + 1
        )));
    }
    let nn = mach.nodes.len();
    let net = network(mach);
    let nd = net.dyn_nodes.len();
    let amb = ambient_series(mach, run)?;
    let bnd_held: Vec<Option<std::borrow::Cow<'_, [f64]>>> = mach
        .nodes
        .iter()
        .map(|n| n.boundary.as_deref().map(|c| driving(run, c)).transpose())
        .collect::<Result<_>>()?;
    let bnd: Vec<Option<&[f64]>> = bnd_held.iter().map(|b| b.as_deref()).collect();
    let srcs: Vec<(usize, &str, f64, f64, f64)> = mach
        .sources
        .iter()
        .map(|s| {
            let i = mach
                .node_index(&s.node)
                .ok_or_else(|| Error::Format(format!("unknown node {}", s.node)))?;
            let p = net.pos[i]
                .ok_or_else(|| Error::Format(format!("source on boundary node {}", s.node)))?;
            Ok((p, s.input.as_str(), s.w, s.reference, s.exponent))
        })
        .collect::<Result<_>>()?;
    let mut x: Vec<f64> = Vec::with_capacity(nd);
    // the positions whose start no reading gives
    let mut unread: Vec<usize> = Vec::new();
    for (p, &i) in net.dyn_nodes.iter().enumerate() {
        let node = &mach.nodes[i];
        let mut v = match &node.sensor {
            // a sensor dead from the first row tells nothing of the node's start: the node
            // starts as an unsensed one
            Some(c) if run.failing(c)?.first().is_some_and(|r| r.start == 0) => {
                unread.push(p);
                amb[0]
            }
            Some(c) => run.col(c)?[0] - node.sensor_offset_k,
            None => {
                unread.push(p);
                amb[0]
            }
        };
        if let Init::Offsets(off) = init {
            v += off.get(i).copied().unwrap_or(0.0);
        }
        x.push(v);
    }
    let mut out = vec![0.0; n_t * nn];
    let mflat: Vec<f64> = (0..nd * nd).map(|i| net.m[(i / nd, i % nd)]).collect();
    // the forcing Γ·C⁻¹·(G_a·T_amb + Σ G·T_bnd + Σ Q) as a few scalar drivers per step (the
    // ambient, each boundary node, each source's power) times fixed vectors: with `drivers`
    // columns B (nd × nv, the conductances and unit powers over the capacities), each step is
    // x⁺ = Φ x + (Γ·B)·d_k
    let bnd_nodes: Vec<usize> = {
        let mut b: Vec<usize> = net.bnd_links.iter().map(|&(_, b, _)| b).collect();
        b.sort_unstable();
        b.dedup();
        b
    };
    let nv = 1 + bnd_nodes.len() + srcs.len();
    let mut b_in = vec![0.0; nd * nv];
    for p in 0..nd {
        b_in[p * nv] = net.g_amb[p] / net.cap[p];
    }
    for &(p, b, g) in &net.bnd_links {
        let v = 1 + bnd_nodes.iter().position(|&x| x == b).unwrap_or(0);
        b_in[p * nv + v] += g / net.cap[p];
    }
    for (s, &(p, ..)) in srcs.iter().enumerate() {
        b_in[p * nv + 1 + bnd_nodes.len() + s] += 1.0 / net.cap[p];
    }
    let mut drv = vec![0.0; n_t * nv];
    for (k, d) in drv.chunks_exact_mut(nv).enumerate() {
        d[0] = amb[k];
        for (v, &b) in bnd_nodes.iter().enumerate() {
            d[1 + v] = bnd[b].map_or(0.0, |c| c[k]);
        }
    }
    for (s, (_, input, w, r, e)) in srcs.iter().enumerate() {
        let v = 1 + bnd_nodes.len() + s;
        let power = run.held_power(input, |uk| {
            if uk > 0.0 {
                w * portable::powf(uk / r, *e)
            } else {
                0.0
            }
        })?;
        for (k, p) in power.into_iter().enumerate().take(n_t) {
            drv[k * nv + v] = p;
        }
    }
    let mut march = March {
        nd,
        nv,
        nn,
        dyn_nodes: &net.dyn_nodes,
        bnd: &bnd,
        b_in: &b_in,
        drv: &drv,
        steps,
        table: vec![None; steps.distinct.len()],
        built: 0,
        m: &mflat,
    };
    if chain_pays(&steps.distinct, nd) {
        march.chain();
    }
    if mach.unsensed_start == UnsensedStart::Fit && !unread.is_empty() {
        let mut read = super::calibrate::sensed(mach, run)?;
        read.retain(|sn| net.pos[sn.node].is_some_and(|p| !unread.contains(&p)));
        let low = read
            .iter()
            .map(|r| r.reading.values[0])
            .fold(amb[0], f64::min);
        let high = read
            .iter()
            .map(|r| r.reading.values[0])
            .fold(amb[0], f64::max);
        for (p, v) in fitted_start(mach, &mut march, &x, &unread, &read, run.time)? {
            x[p] = v.clamp(low, high);
        }
    }
    match nd {
        1 => march.run_n::<1>(&mut x, &mut out)?,
        2 => march.run_n::<2>(&mut x, &mut out)?,
        3 => march.run_n::<3>(&mut x, &mut out)?,
        4 => march.run_n::<4>(&mut x, &mut out)?,
        5 => march.run_n::<5>(&mut x, &mut out)?,
        6 => march.run_n::<6>(&mut x, &mut out)?,
        7 => march.run_n::<7>(&mut x, &mut out)?,
        8 => march.run_n::<8>(&mut x, &mut out)?,
        _ => march.run_n::<0>(&mut x, &mut out)?,
    }
    if !crate::linalg::all_finite(&out) {
        return Err(Error::Numerical(
            "the simulation produced non-finite temperatures".into(),
        ));
    }
    Ok(out)
}

/// The rows a fitted start reads ([`UnsensedStart::Fit`]): the run's first hour.
pub const START_FIT_S: f64 = 3600.0;

/// The starts of the nodes at positions `unread` (no reading gives them) that make the sensed
/// nodes `read` follow their readings best over the run's first [`START_FIT_S`] (least squares:
/// the network is linear in its start), each as (position, start). The other nodes start at
/// `x`. Nothing when the window holds fewer than three rows or no sensed node; a node the sensed
/// ones do not feel at all keeps its start (the least squares' minimum-norm solution).
fn fitted_start(
    mach: &Machine,
    march: &mut March<'_>,
    x: &[f64],
    unread: &[usize],
    read: &[super::calibrate::Sensed<'_>],
    t: &[f64],
) -> Result<Vec<(usize, f64)>> {
    let w = t.iter().take_while(|&&v| v - t[0] <= START_FIT_S).count();
    if w < 3 || read.is_empty() {
        return Ok(Vec::new());
    }
    let nn = march.nn;
    let mut sim = |x0: &[f64]| -> Result<Vec<f64>> {
        let (mut xs, mut out) = (x0.to_vec(), vec![0.0; w * nn]);
        march.run_n::<0>(&mut xs, &mut out)?;
        Ok(out)
    };
    let base = sim(x)?;
    let (cols, rhs) = super::calibrate::start_system(mach, read, t, w, &base, unread.len(), |j| {
        let mut xu = x.to_vec();
        xu[unread[j]] += 1.0;
        sim(&xu)
    })?;
    let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
    let Ok(a) = crate::linalg::lstsq_columns(&refs, &rhs) else {
        return Ok(Vec::new());
    };
    Ok(unread
        .iter()
        .zip(a)
        .filter(|(_, v)| v.is_finite())
        .map(|(&u, v)| (u, x[u] + v))
        .collect())
}

/// One step of the network: Φ = e^{Mh} and Γ = ∫₀ʰ e^{Ms} ds (n × n, row-major), so that
/// x⁺ = Φ x + Γ f for a forcing f held over the step.
struct Transition {
    phi: Vec<f64>,
    gam: Vec<f64>,
}

/// a · b of two n × n row-major matrices.
fn matmul(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut c = vec![0.0; n * n];
    for i in 0..n {
        for k in 0..n {
            let aik = a[i * n + k];
            for j in 0..n {
                c[i * n + j] += aik * b[k * n + j];
            }
        }
    }
    c
}

impl Transition {
    /// Φ and Γ of a step `h` of `m` (n × n): both Taylor series at τ = h/2^s with ‖M τ‖ ≤ 1/2
    /// (20 terms: truncation below 1e-20 relative), then s doublings Φ(2τ) = Φ(τ)²,
    /// Γ(2τ) = Γ(τ) + Φ(τ)·Γ(τ). The same numbers as reading both off e^{[[M, I], [0, 0]]·h},
    /// with n × n products instead of 2n × 2n ones.
    fn of(m: &[f64], n: usize, h: f64) -> Transition {
        let norm = m.iter().fold(0.0_f64, |a, v| a.max(v.abs())) * n as f64 * h.abs();
        let s = if norm > 0.5 {
            portable::log2(norm / 0.5).ceil() as i32
        } else {
            0
        };
        let tau = h / 2f64.powi(s);
        let a: Vec<f64> = m.iter().map(|v| v * tau).collect();
        let mut term = vec![0.0; n * n];
        for i in 0..n {
            term[i * n + i] = 1.0;
        }
        let mut phi = term.clone();
        let mut g = term.clone(); // Σ A^k/(k+1)!
        for k in 1..=20 {
            term = matmul(&term, &a, n);
            let kf = k as f64;
            for ((t, p), q) in term.iter_mut().zip(phi.iter_mut()).zip(g.iter_mut()) {
                *t /= kf;
                *p += *t;
                *q += *t / (kf + 1.0);
            }
        }
        let mut t = Transition {
            phi,
            gam: g.iter().map(|v| v * tau).collect(),
        };
        for _ in 0..s {
            t = t.then(&t, n);
        }
        t
    }

    /// This step followed by `next`: Φ = Φ_next·Φ, Γ = Γ_next + Φ_next·Γ.
    fn then(&self, next: &Transition, n: usize) -> Transition {
        let mut gam = matmul(&next.phi, &self.gam, n);
        for (g, v) in gam.iter_mut().zip(&next.gam) {
            *g += v;
        }
        Transition {
            phi: matmul(&next.phi, &self.phi, n),
            gam,
        }
    }
}

/// The stepping of [`simulate_nodes`]: everything fixed over the run, the transition matrices
/// cached per step length.
struct March<'s> {
    nd: usize,
    nv: usize,
    nn: usize,
    dyn_nodes: &'s [usize],
    bnd: &'s [Option<&'s [f64]>],
    /// nd × nv, row-major: the drivers' columns before the step's Γ
    b_in: &'s [f64],
    /// n_t × nv, row-major: the drivers of each step
    drv: &'s [f64],
    steps: &'s Steps,
    /// per distinct step length (`steps.distinct`): Φ (nd × nd) then Γ·B (nd × nv), row-major,
    /// once built (all at once by a chain, or each on demand)
    table: Vec<Option<Box<[f64]>>>,
    /// entries built on demand and kept (at most [`MAX_STEP_LENGTHS`])
    built: usize,
    /// the network's matrix M (nd × nd, row-major)
    m: &'s [f64],
}

impl March<'_> {
    /// [`March::run`] for `N` nodes and the run's number of drivers.
    fn run_n<const N: usize>(&mut self, x: &mut [f64], out: &mut [f64]) -> Result<()> {
        match self.nv {
            1 => self.run::<N, 1>(x, out),
            2 => self.run::<N, 2>(x, out),
            3 => self.run::<N, 3>(x, out),
            4 => self.run::<N, 4>(x, out),
            _ => self.run::<N, 0>(x, out),
        }
    }

    /// Fills `out` (n_t × nn) from the start `x`. `N`: the number of simulated nodes, `V`: the
    /// number of drivers, when they are small (the loops then unroll and the state stays in
    /// registers), 0 for any other. The same operations in the same order for every `N`, `V`.
    fn run<const N: usize, const V: usize>(
        &mut self,
        x: &mut [f64],
        out: &mut [f64],
    ) -> Result<()> {
        let nd = if N > 0 { N } else { self.nd };
        let nv = if V > 0 { V } else { self.nv };
        let nn = self.nn;
        let n_t = out.len() / nn;
        // the state and the next state on the stack for a small network (the loop below then
        // keeps them in registers), on the heap for a large one
        let mut small = [[0.0; 8]; 2];
        let mut big = if nd > small[0].len() {
            vec![vec![0.0; nd]; 2]
        } else {
            Vec::new()
        };
        let (xs, xn): (&mut [f64], &mut [f64]) = if nd <= small[0].len() {
            let [a, b] = &mut small;
            (&mut a[..nd], &mut b[..nd])
        } else {
            let (a, b) = big.split_at_mut(1);
            (&mut a[0][..], &mut b[0][..])
        };
        xs.copy_from_slice(&x[..nd]);
        let bnd: Vec<(usize, &[f64])> = self
            .bnd
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.map(|c| (i, c)))
            .collect();
        for k in 0..n_t {
            let row = &mut out[k * nn..(k + 1) * nn];
            for (&i, &v) in self.dyn_nodes.iter().zip(xs.iter()) {
                row[i] = v;
            }
            for &(i, col) in &bnd {
                row[i] = col[k];
            }
            if k + 1 == n_t {
                break;
            }
            if k % 1024 == 0 {
                crate::interrupt::check()?;
            }
            let kind = self.steps.kind[k] as usize;
            if self.table[kind].is_none() {
                self.build(kind);
            }
            let Some(entry) = &self.table[kind] else {
                return Err(Error::Numerical(format!(
                    "no transition for a step of {} ticks",
                    self.steps.dt[k]
                )));
            };
            let (phi, w) = entry.split_at(nd * nd);
            let d = &self.drv[k * nv..(k + 1) * nv];
            for p in 0..nd {
                let pr = &phi[p * nd..(p + 1) * nd];
                let mut acc = 0.0;
                for q in 0..nd {
                    acc += pr[q] * xs[q];
                }
                let wr = &w[p * nv..(p + 1) * nv];
                for v in 0..nv {
                    acc += wr[v] * d[v];
                }
                xn[p] = acc;
            }
            xs.copy_from_slice(xn);
        }
        x[..nd].copy_from_slice(xs);
        Ok(())
    }

    /// Builds the table's entry `kind` on demand (by its own series); at most
    /// [`MAX_STEP_LENGTHS`] kept at once.
    fn build(&mut self, kind: usize) {
        if self.built >= MAX_STEP_LENGTHS {
            self.table.iter_mut().for_each(|e| *e = None);
            self.built = 0;
        }
        let h = self.steps.distinct[kind] as f64 * self.steps.q;
        let t = Transition::of(self.m, self.nd, h);
        self.table[kind] = Some(self.entry(&t));
        self.built += 1;
    }

    /// Every entry of the table at once, for many distinct step lengths close together (a
    /// jittering logger): a step of m + 1 ticks is one of m followed by one of one tick, so
    /// Φ(m+1) = Φ(1)·Φ(m) and Γ(m+1)·B = Γ(1)·B + Φ(1)·(Γ(m)·B): one series for the shortest
    /// step and one for the tick, then per tick up to the longest an n × n product and an
    /// n × (drivers) one, instead of a series each ([`chain_pays`]).
    fn chain(&mut self) {
        let (nd, nv, st) = (self.nd, self.nv, self.steps);
        let steps = &st.distinct;
        let (Some(&lo), Some(&hi)) = (steps.first(), steps.last()) else {
            return;
        };
        let one = self.entry(&Transition::of(self.m, nd, st.q));
        let (phi1, w1) = one.split_at(nd * nd);
        let mut e = self.entry(&Transition::of(self.m, nd, lo as f64 * st.q));
        let mut want = (0..steps.len()).peekable();
        for m in lo..=hi {
            if let Some(i) = want.next_if(|&i| steps[i] == m) {
                self.table[i] = Some(e.clone());
            }
            if m == hi {
                break;
            }
            let (phi, w) = e.split_at(nd * nd);
            let mut next = vec![0.0; nd * (nd + nv)];
            let (np, nw) = next.split_at_mut(nd * nd);
            for r in 0..nd {
                for k in 0..nd {
                    let a = phi1[r * nd + k];
                    for c in 0..nd {
                        np[r * nd + c] += a * phi[k * nd + c];
                    }
                    for c in 0..nv {
                        nw[r * nv + c] += a * w[k * nv + c];
                    }
                }
                for c in 0..nv {
                    nw[r * nv + c] += w1[r * nv + c];
                }
            }
            e = next.into_boxed_slice();
        }
    }

    /// Φ then Γ·B of the transition `t`, as one entry of the table.
    fn entry(&self, t: &Transition) -> Box<[f64]> {
        let (nd, nv) = (self.nd, self.nv);
        let mut e = Vec::with_capacity(nd * (nd + nv));
        e.extend_from_slice(&t.phi);
        for p in 0..nd {
            for v in 0..nv {
                e.push(
                    (0..nd)
                        .map(|q| t.gam[p * nd + q] * self.b_in[q * nv + v])
                        .sum(),
                );
            }
        }
        e.into_boxed_slice()
    }
}

/// Sensor readings and drift from node temperatures.
pub fn finish(mach: &Machine, run: &RunView<'_>, temps: Vec<f64>) -> Result<Simulation> {
    let nn = mach.nodes.len();
    let t = run.time;
    let mut sensors = Vec::new();
    for (i, node) in mach.nodes.iter().enumerate() {
        if let Some(c) = &node.sensor {
            let r: Vec<f64> = temps
                .chunks_exact(nn)
                .zip(t)
                .map(|(row, tk)| node.sensor_reads(row[i], tk - t[0]))
                .collect();
            sensors.push((c.clone(), r));
        }
    }
    let mut drift = Vec::new();
    for d in &mach.drift {
        let terms = drift_terms(mach, d, run, &temps)?;
        let mut thermal = vec![0.0; run.len()];
        for (coef, series) in &terms.lagged {
            for (a, b) in thermal.iter_mut().zip(series) {
                *a += coef * b;
            }
        }
        let mut e = match d.lag_s {
            Some(tau) => lag(t, &thermal, tau),
            None => thermal,
        };
        for (coef, series) in &terms.instant {
            for (a, b) in e.iter_mut().zip(series) {
                *a += coef * b;
            }
        }
        drift.push((d.axis.clone(), e));
    }
    Ok(Simulation {
        node_names: mach.nodes.iter().map(|n| n.name.clone()).collect(),
        temps,
        sensors,
        drift,
    })
}

/// The terms of one drift axis as (coefficient, series): `lagged` ones pass through the axis'
/// lag (if any), `instant` ones do not. Every series is zero at t = 0. The lag is the
/// structure's (its bulk follows its sensors late), so it takes the node terms, linear and
/// quadratic; the room (`ambient_um_per_k`), a spare column and the inputs act directly.
pub struct DriftTerms {
    pub lagged: Vec<(f64, Vec<f64>)>,
    pub instant: Vec<(f64, Vec<f64>)>,
    pub labels_lagged: Vec<String>,
    pub labels_instant: Vec<String>,
}

pub fn drift_terms(
    mach: &Machine,
    d: &DriftSpec,
    run: &RunView<'_>,
    temps: &[f64],
) -> Result<DriftTerms> {
    let nn = mach.nodes.len();
    let rise = |i: usize| -> Vec<f64> {
        let t0 = temps[i];
        temps.chunks_exact(nn).map(|r| r[i] - t0).collect()
    };
    let mut out = DriftTerms {
        lagged: Vec::new(),
        instant: Vec::new(),
        labels_lagged: Vec::new(),
        labels_instant: Vec::new(),
    };
    for (name, k) in &d.um_per_k {
        let i = mach
            .node_index(name)
            .ok_or_else(|| Error::Format(format!("unknown node {name}")))?;
        out.lagged.push((*k, rise(i)));
        out.labels_lagged.push(format!("um_per_k.{name}"));
    }
    for (name, q) in &d.quadratic_um_per_k2 {
        let i = mach
            .node_index(name)
            .ok_or_else(|| Error::Format(format!("unknown node {name}")))?;
        out.lagged
            .push((*q, rise(i).iter().map(|v| v * v).collect()));
        out.labels_lagged
            .push(format!("quadratic_um_per_k2.{name}"));
    }
    // the room and a spare column act on the axis directly, not through the structure's lag
    if let Some(k_amb) = d.ambient_um_per_k {
        let amb = ambient_series(mach, run)?;
        out.instant
            .push((k_amb, amb.iter().map(|v| v - amb[0]).collect()));
        out.labels_instant.push("ambient_um_per_k".into());
    }
    for c in &d.columns {
        let col = run.col(&c.column)?;
        out.instant
            .push((c.um_per_k, col.iter().map(|v| v - col[0]).collect()));
        out.labels_instant.push(format!("columns.{}", c.column));
    }
    for term in &d.inputs {
        let u = run.col(&term.input)?;
        let f = |v: f64| {
            if v > 0.0 {
                portable::powf(v / term.reference, term.exponent)
            } else {
                0.0
            }
        };
        let u0 = f(u[0]);
        // the power for the last input value (stepped inputs repeat it for hours)
        let mut last = (u[0], u0);
        let series = u
            .iter()
            .map(|&v| {
                if v.to_bits() != last.0.to_bits() {
                    last = (v, f(v));
                }
                last.1 - u0
            })
            .collect();
        out.instant.push((term.um, series));
        out.labels_instant.push(format!("inputs.{}", term.input));
    }
    Ok(out)
}

/// First-order lag z' = (y − z)/τ, z(0) = y(0), exact for y linear between samples.
pub fn lag(t: &[f64], y: &[f64], tau: f64) -> Vec<f64> {
    let mut z = Vec::with_capacity(y.len());
    let Some(&first) = y.first() else { return z };
    z.push(first);
    // (step, a, w) of the last step: a logger's steps repeat, and exp is the loop's cost
    let mut last = (f64::NAN, 0.0, 0.0);
    for k in 1..y.len() {
        let h = t[k] - t[k - 1];
        if h.to_bits() != last.0.to_bits() {
            let a = portable::exp(-h / tau);
            let w = if h > 0.0 {
                1.0 - (tau / h) * (1.0 - a)
            } else {
                1.0
            };
            last = (h, a, w);
        }
        let (_, a, w) = last;
        let prev = z[k - 1];
        z.push(a * prev + (1.0 - a) * y[k - 1] + w * (y[k] - y[k - 1]));
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chain_builds_the_step_lengths_only_where_it_takes_fewer_products() {
        // 15-s rows thinned to 60 s with a few rows dropped: 60, 75, 90, 105 s on a 1/32-s
        // grid, four lengths 1 440 grid steps apart: each by its own series
        let q = 1.0 / 32.0;
        let dropped: Vec<i64> = [60.0, 75.0, 90.0, 105.0]
            .iter()
            .map(|s| (s / q) as i64)
            .collect();
        assert!(!chain_pays(&dropped, 5));
        // a logger jittering by up to ±2 s on 60 s: 129 lengths within 256 grid steps
        let jitter: Vec<i64> = (-64..=64).map(|k| (60.0 / q) as i64 + 2 * k).collect();
        assert!(chain_pays(&jitter, 5));
        // two lengths, or one: their series
        assert!(!chain_pays(&jitter[..2], 5) && !chain_pays(&[1920], 5));
        // the same lengths held at once for a network too large to keep them all: each on demand
        assert!(!chain_pays(&jitter, 200));
    }

    #[test]
    fn the_chain_builds_the_same_matrices_as_a_series_per_step_length() {
        // three nodes in a row to the room, two drivers (the room and a source on the first);
        // 60-s samples jittering by ±0.5 s: 33 lengths on the 1/32-s grid, where the chain pays
        let (nd, nv) = (3, 2);
        let (c, g) = ([800.0, 5000.0, 20000.0], [0.5, 3.0, 6.0]);
        let link = [4.0, 8.0];
        let mut m = vec![0.0; nd * nd];
        for p in 0..nd {
            m[p * nd + p] -= g[p];
        }
        for (p, &w) in link.iter().enumerate() {
            m[p * nd + p + 1] += w;
            m[(p + 1) * nd + p] += w;
            m[p * nd + p] -= w;
            m[(p + 1) * nd + p + 1] -= w;
        }
        for p in 0..nd {
            for q in 0..nd {
                m[p * nd + q] /= c[p];
            }
        }
        let b_in: Vec<f64> = (0..nd)
            .flat_map(|p| [g[p] / c[p], if p == 0 { 1.0 / c[0] } else { 0.0 }])
            .collect();
        let t: Vec<f64> = (0..400)
            .map(|k| k as f64 * 60.0 + 0.5 * (1.7 * k as f64).sin())
            .collect();
        let steps = Steps::of(&t);
        assert!(chain_pays(&steps.distinct, nd) && steps.distinct.len() > 20);
        let drv = vec![0.0; t.len() * nv];
        let mut march = March {
            nd,
            nv,
            nn: nd,
            dyn_nodes: &[0, 1, 2],
            bnd: &[None, None, None],
            b_in: &b_in,
            drv: &drv,
            steps: &steps,
            table: vec![None; steps.distinct.len()],
            built: 0,
            m: &m,
        };
        march.chain();
        for (i, &len) in steps.distinct.iter().enumerate() {
            let series = march.entry(&Transition::of(&m, nd, len as f64 * steps.q));
            let chained = march.table[i].as_deref().unwrap();
            for (a, b) in chained.iter().zip(series.iter()) {
                // a few hundred products of a contraction: rounding of order 1e-14 per product
                assert!(
                    (a - b).abs() <= 1e-12 * b.abs().max(1e-3),
                    "length {len}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn a_widely_jittering_logger_is_put_on_a_coarser_grid_and_whole_seconds_stay_exact() {
        // 15-s samples stamped anywhere from 11 to 19 s apart (in ms): ~1 000 lengths on the
        // 1/128-s grid; two doublings (1/32 s, ~250 lengths) are not enough, the third is
        let t: Vec<f64> = (0..2000)
            .map(|k| k as f64 * 15.0 + (2.0 * (2.3 * k as f64).sin() * 1000.0).round() / 1000.0)
            .collect();
        let s = Steps::of(&t);
        assert_eq!(s.q, 1.0 / 16.0);
        assert!(s.distinct.len() <= MAX_GRID_LENGTHS, "{}", s.distinct.len());
        // each time moves by at most half a tick, and the moves do not accumulate
        let mut at = t[0] / s.q;
        for (k, d) in s.dt.iter().enumerate() {
            at += *d as f64;
            assert!(
                (at * s.q - t[k + 1]).abs() <= s.q / 2.0 + 1e-9,
                "row {}",
                k + 1
            );
        }
        // every step finds its length
        for (d, &i) in s.dt.iter().zip(&s.kind) {
            assert_eq!(s.distinct[i as usize], *d);
        }
        // whole seconds, hundreds of lengths (a logger writing on change): coarser, not past 1 s,
        // every step exact
        let mut t = vec![0.0];
        for k in 1..3000_i64 {
            t.push(t[k as usize - 1] + (1 + (k * 7919) % 400) as f64);
        }
        let s = Steps::of(&t);
        assert!(s.q <= 1.0);
        for (k, d) in s.dt.iter().enumerate() {
            assert_eq!(*d as f64 * s.q, t[k + 1] - t[k], "row {}", k + 1);
        }
        // a 15-s log with rows dropped: a few lengths, the grid of the mean step as before
        let t: Vec<f64> = (0..2000_i64)
            .filter(|k| k % 7 != 3)
            .map(|k| k as f64 * 15.0)
            .collect();
        let s = Steps::of(&t);
        assert_eq!(s.q, 1.0 / 64.0);
        assert_eq!(s.distinct, vec![960, 1920]);
    }
}
