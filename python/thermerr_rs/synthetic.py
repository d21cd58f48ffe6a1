"""Synthetic machines and runs with a hidden effect: the project's test bench for diagnosis.

This is deliberately separate code from the Rust simulation it is used to test: a plain
numpy integrator (exact zero-order-hold steps through the matrix exponential of the augmented
system, computed by :func:`_expm` without BLAS, so that a seed gives the same run to the last
bit on every CPU) of a "true" machine that may carry one effect the nominal model lacks:

=====================  ===================================================================
``thermal_lag``        the structure's drift (its linear and quadratic terms on the nodes)
                       follows the temperatures through a first-order lag τ
``ambient_coupling``   the shop air moves the error directly: + k_amb·(T_amb − T_amb(0)),
                       not through a lag
``speed_growth``       instantaneous growth with spindle speed: + g·(n/n_ref)²
``unmodeled_source``   a heat source outside the model (a hydraulic unit) whose temperature
                       is measured in ``T_hydraulic`` heats a node through a conductance
``nonlinear_expansion`` + q·ΔT² on one node's rise
``sensor_drift``       one sensor's reading drifts away from its node at r K/h
``periodic``           (outside the catalogue) a periodic disturbance A·sin(2πt/P)
``none``               nothing hidden
=====================  ===================================================================

:func:`make_multi_case` hides several of them at once (``("ambient_coupling", "sensor_drift")``),
each with the parameters it would have alone.

Every run also carries a distractor column ``T_cabinet`` (an electrical cabinet that heats up
but touches nothing), so a diagnosis that names a column must find the right one. Sensor noise
0.03 °C, probe noise 0.15 µm. The *nominal* machine returned with a case has every parameter
perturbed by 15–35 % and none of the hidden effect.

"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

CAUSES = (
    "thermal_lag",
    "ambient_coupling",
    "speed_growth",
    "unmodeled_source",
    "nonlinear_expansion",
    "sensor_drift",
)
HIDDEN = (*CAUSES, "periodic", "none")
DUTIES = ("stepped", "run_stop", "random")


def machine(topology: str) -> dict[str, Any]:
    """A true machine in the TOML schema of formats.md, as a dict."""
    if topology == "vmc":
        return {
            "name": "vmc-synthetic",
            "ambient": "T_ambient",
            "nodes": [
                {"name": "front_bearing", "capacity_j_per_k": 1800.0, "ambient_w_per_k": 0.7, "sensor": "T_front_bearing"},
                {"name": "spindle_motor", "capacity_j_per_k": 6000.0, "ambient_w_per_k": 2.5, "sensor": "T_spindle_motor"},
                {"name": "headstock", "capacity_j_per_k": 30000.0, "ambient_w_per_k": 4.0, "sensor": "T_headstock"},
                {"name": "column", "capacity_j_per_k": 90000.0, "ambient_w_per_k": 9.0, "sensor": "T_column"},
                {"name": "bed", "capacity_j_per_k": 250000.0, "ambient_w_per_k": 15.0},
            ],
            "links": [
                {"between": ["front_bearing", "headstock"], "w_per_k": 4.0},
                {"between": ["spindle_motor", "headstock"], "w_per_k": 5.0},
                {"between": ["headstock", "column"], "w_per_k": 8.0},
                {"between": ["column", "bed"], "w_per_k": 12.0},
            ],
            "sources": [
                {"node": "front_bearing", "input": "U_spindle_rpm", "w": 70.0, "ref": 6000.0, "exponent": 1.4},
                {"node": "spindle_motor", "input": "U_spindle_rpm", "w": 120.0, "ref": 6000.0, "exponent": 1.1},
            ],
            "drift": [
                {"axis": "E_z", "um_per_k": {"front_bearing": 0.8, "headstock": 3.2, "column": 1.8, "bed": -0.6}},
            ],
        }
    if topology == "lathe":
        return {
            "name": "lathe-synthetic",
            "ambient": "T_ambient",
            "nodes": [
                {"name": "spindle_bearing", "capacity_j_per_k": 2500.0, "ambient_w_per_k": 0.9, "sensor": "T_spindle_bearing"},
                {"name": "headstock", "capacity_j_per_k": 40000.0, "ambient_w_per_k": 5.0, "sensor": "T_headstock"},
                {"name": "x_nut", "capacity_j_per_k": 900.0, "ambient_w_per_k": 0.8, "sensor": "T_x_nut"},
                {"name": "carriage", "capacity_j_per_k": 20000.0, "ambient_w_per_k": 3.0, "sensor": "T_carriage"},
                {"name": "bed", "capacity_j_per_k": 200000.0, "ambient_w_per_k": 14.0, "sensor": "T_bed"},
            ],
            "links": [
                {"between": ["spindle_bearing", "headstock"], "w_per_k": 5.0},
                {"between": ["headstock", "bed"], "w_per_k": 10.0},
                {"between": ["x_nut", "carriage"], "w_per_k": 3.0},
                {"between": ["carriage", "bed"], "w_per_k": 6.0},
            ],
            "sources": [
                {"node": "spindle_bearing", "input": "U_spindle_rpm", "w": 60.0, "ref": 4000.0, "exponent": 1.3},
                {"node": "x_nut", "input": "U_feed_mm_min", "w": 25.0, "ref": 5000.0, "exponent": 1.0},
            ],
            "drift": [
                {"axis": "E_x", "um_per_k": {"spindle_bearing": 1.0, "headstock": 2.8, "x_nut": 1.5, "carriage": 0.9, "bed": -0.4}},
            ],
        }
    raise ValueError(f"unknown topology {topology!r} (vmc, lathe)")


@dataclass
class Case:
    """One synthetic experiment: training and held-out runs (column dicts), the true and the
    nominal machine (TOML dicts), and what was hidden."""

    topology: str
    hidden: str
    seed: int
    column: str | None
    params: dict[str, float]
    train: dict[str, np.ndarray]
    test: dict[str, np.ndarray]
    truth: dict[str, Any]
    nominal: dict[str, Any]
    axis: str = field(default="")
    #: with several hidden effects (:func:`make_multi_case`): each effect's column or ``None``
    columns: dict[str, str | None] = field(default_factory=dict)

    def nominal_toml(self) -> str:
        return to_toml(self.nominal)


def duty(kind: str, t: np.ndarray, ref_rpm: float, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Spindle speed (and feed) schedules: stepped speeds, run–stop cycles, random duty."""
    hours = t / 3600.0
    if kind == "stepped":
        levels = np.array([0.5, 1.0, 0.75, 0.5, 0.0]) * ref_rpm
        rpm = levels[np.minimum((hours / (hours[-1] / 5 + 1e-9)).astype(int), 4)]
    elif kind == "run_stop":
        on = (np.floor(hours / 1.5) % 2 == 0) & (hours < 0.8 * hours[-1])
        rpm = np.where(on, 0.8 * ref_rpm, 0.0)
    elif kind == "random":
        n_seg = max(4, int(hours[-1] / 0.75))
        edges = np.sort(rng.uniform(0, hours[-1], n_seg))
        vals = rng.choice([0.0, 0.3, 0.5, 0.7, 0.9, 1.0], size=n_seg + 1) * ref_rpm
        rpm = vals[np.searchsorted(edges, hours)]
    else:
        raise ValueError(f"unknown duty {kind!r}")
    feed = np.where(rpm > 0, 2000.0 + 3000.0 * (rpm / ref_rpm), 0.0)
    return {"U_spindle_rpm": rpm.astype(float), "U_feed_mm_min": feed.astype(float)}


def _system(m: dict[str, Any], extra_links: list[tuple[str, str, float]]) -> tuple:
    names = [n["name"] for n in m["nodes"]]
    idx = {n: i for i, n in enumerate(names)}
    cap = np.array([n["capacity_j_per_k"] for n in m["nodes"]])
    g_amb = np.array([n.get("ambient_w_per_k", 0.0) for n in m["nodes"]])
    a = np.zeros((len(names), len(names)))
    for link in m["links"]:
        i, j = idx[link["between"][0]], idx[link["between"][1]]
        g = link["w_per_k"]
        a[i, j] += g
        a[j, i] += g
        a[i, i] -= g
        a[j, j] -= g
    a[np.diag_indices(len(names))] -= g_amb
    b_bnd = np.zeros(len(names))
    for node, _col, g in extra_links:
        a[idx[node], idx[node]] -= g
        b_bnd[idx[node]] += g
    return names, idx, cap, g_amb, a, b_bnd


def _expm(a: np.ndarray) -> np.ndarray:
    """e^A by scaling and squaring of a Taylor series, in Python floats with exactly summed
    products (``math.fsum``): no BLAS, whose kernels (chosen by CPU: AVX2 or AVX-512) round
    differently in the last bit, and a borderline diagnosis of a synthetic run flips on that.
    Scaled to a norm ≤ 1/4, 18 terms leave a truncation below 1e-27; the squarings lose what
    scipy's ``expm`` loses (tests/test_synthetic.py checks the runs against an ODE solver)."""
    m = [[float(v) for v in row] for row in a]
    n = len(m)
    norm = max((sum(abs(v) for v in row) for row in m), default=0.0)
    s = max(0, math.ceil(math.log2(norm / 0.25))) if norm > 0.25 else 0
    m = [[v * 2.0**-s for v in row] for row in m]

    def mul(p: list[list[float]], q: list[list[float]]) -> list[list[float]]:
        cols = list(zip(*q))
        return [[math.fsum(x * y for x, y in zip(row, col)) for col in cols] for row in p]

    eye = [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    out, term = eye, eye
    for k in range(1, 19):
        term = [[v / k for v in row] for row in mul(term, m)]
        out = [[x + y for x, y in zip(ro, rt)] for ro, rt in zip(out, term)]
    for _ in range(s):
        out = mul(out, out)
    return np.array(out)


def simulate_truth(
    m: dict[str, Any],
    cols: dict[str, np.ndarray],
    *,
    lag_s: float | None = None,
    source: tuple[str, str, float] | None = None,
) -> dict[str, np.ndarray]:
    """Exact zero-order-hold integration of the true network; returns node temperatures (by
    node name) and the instantaneous and lagged drift of each axis (keys ``drift:<axis>``)."""
    extra = [source] if source else []
    names, idx, cap, g_amb, a, b_bnd = _system(m, extra)
    n = len(names)
    t = cols["time_s"]
    amb = cols[m["ambient"]]
    drift = m["drift"][0]
    k = np.zeros(n)
    for node, v in drift["um_per_k"].items():
        k[idx[node]] = v
    x = np.array([cols[nd["sensor"]][0] if "sensor" in nd else amb[0] for nd in m["nodes"]], dtype=float)
    x0 = x.copy()
    e0 = float((k * x0).sum())
    z = 0.0  # lagged drift state (relative)
    temps = np.empty((len(t), n))
    e_inst = np.empty(len(t))
    e_lag = np.empty(len(t))
    cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}
    for s in range(len(t)):
        temps[s] = x
        e_inst[s] = (k * x).sum() - e0
        e_lag[s] = z if lag_s else e_inst[s]
        if s == len(t) - 1:
            break
        h = float(t[s + 1] - t[s])
        q = np.zeros(n)
        for src in m["sources"]:
            u = cols[src["input"]][s]
            q[idx[src["node"]]] += src["w"] * (u / src["ref"]) ** src["exponent"] if u > 0 else 0.0
        forcing = (q + g_amb * amb[s] + (b_bnd * cols[source[1]][s] if source else 0.0)) / cap
        # state w = [x, z]: dw/dt = M w + f, with dz/dt = (k·x − e0 − z)/τ; exact ZOH step
        # w+ = Φ w + Γ f, Φ = e^{Mh}, Γ = ∫₀ʰ e^{Ms} ds, both read off expm of [[M, I], [0, 0]]·h
        f_aug = np.concatenate([forcing, [-e0 / lag_s if lag_s else 0.0]])
        pair = cache.get(h)
        if pair is None:
            dim = n + 1
            big = np.zeros((2 * dim, 2 * dim))
            big[:n, :n] = a / cap[:, None]
            if lag_s:
                big[n, :n] = k / lag_s
                big[n, n] = -1.0 / lag_s
            big[:dim, dim:] = np.eye(dim)
            ex = _expm(big * h)
            pair = (ex[:dim, :dim], ex[:dim, dim:])
            cache[h] = pair
        phi, gam = pair
        # products and sums without BLAS (whose kernels differ by CPU in the last bit)
        state = (phi * np.concatenate([x, [z]])).sum(axis=1) + (gam * f_aug).sum(axis=1)
        x, z = state[:n], state[n]
    out = {nm: temps[:, i] for i, nm in enumerate(names)}
    out["drift:inst"] = e_inst
    out["drift:lag"] = e_lag
    return out


def _ambient(t: np.ndarray, rng: np.random.Generator, base: float) -> np.ndarray:
    phase = rng.uniform(0, 2 * np.pi)
    walk = np.cumsum(rng.normal(0, 0.02, len(t)))
    walk -= np.linspace(0, walk[-1], len(t))
    return base + 1.8 * np.sin(2 * np.pi * t / 86400.0 + phase) + 0.3 * walk


def _side_columns(t: np.ndarray, amb: np.ndarray, rpm: np.ndarray, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """T_hydraulic (a unit that warms while the spindle runs, with a chiller cycle) and
    T_cabinet (a distractor that never touches the structure)."""
    dt = np.diff(t, prepend=t[0])
    h = np.zeros(len(t))
    for i in range(1, len(t)):
        target = 9.0 if rpm[i - 1] > 0 else 1.0
        h[i] = h[i - 1] + dt[i] / 2400.0 * (target - h[i - 1])
    chiller = 1.2 * np.sin(2 * np.pi * t / 5400.0 + rng.uniform(0, 6.28))
    cab = 4.0 * (1 - np.exp(-t / 5000.0)) + 0.8 * np.sin(2 * np.pi * t / 3100.0 + rng.uniform(0, 6.28))
    return {"T_hydraulic": amb + h + chiller, "T_cabinet": amb + cab}


def _perturb(m: dict[str, Any], rng: np.random.Generator, lo: float = 0.15, hi: float = 0.35) -> dict[str, Any]:
    out = copy.deepcopy(m)

    def f() -> float:
        return float(1.0 + rng.choice([-1, 1]) * rng.uniform(lo, hi))

    for nd in out["nodes"]:
        nd["capacity_j_per_k"] = round(nd["capacity_j_per_k"] * f(), 3)
        if nd.get("ambient_w_per_k"):
            nd["ambient_w_per_k"] = round(nd["ambient_w_per_k"] * f(), 4)
    for ln in out["links"]:
        ln["w_per_k"] = round(ln["w_per_k"] * f(), 4)
    for src in out["sources"]:
        src["w"] = round(src["w"] * f(), 3)
        src["exponent"] = round(src["exponent"] * (1 + rng.uniform(-0.1, 0.1)), 3)
    for dr in out["drift"]:
        dr["um_per_k"] = {kk: round(v * f(), 4) for kk, v in dr["um_per_k"].items()}
    out["name"] = out["name"].replace("synthetic", "nominal")
    return out


def _run(
    m: dict[str, Any],
    effects: dict[str, dict[str, Any]],
    duty_kind: str,
    hours: float,
    dt: float,
    rng: np.random.Generator,
    *,
    noise: bool = True,
) -> dict[str, np.ndarray]:
    t = np.arange(0.0, hours * 3600.0 + 1e-9, dt)
    src0 = m["sources"][0]
    cols: dict[str, np.ndarray] = {"time_s": t}
    inputs = duty(duty_kind, t, src0["ref"], rng)
    used_inputs = {s["input"] for s in m["sources"]}
    cols.update({k: v for k, v in inputs.items() if k in used_inputs})
    amb = _ambient(t, rng, rng.uniform(19.0, 23.0))
    cols["T_ambient"] = amb
    cols.update(_side_columns(t, amb, cols["U_spindle_rpm"], rng))
    # sensed nodes start at (noise-free) ambient: the machine starts cold
    for nd in m["nodes"]:
        if "sensor" in nd:
            cols[nd["sensor"]] = np.full(len(t), amb[0])
    src = effects.get("unmodeled_source")
    source = (src["node"], "T_hydraulic", src["g"]) if src else None
    effect_lag = effects.get("thermal_lag")
    sim = simulate_truth(m, cols, lag_s=effect_lag["tau"] if effect_lag else None, source=source)
    axis = m["drift"][0]["axis"]
    e = sim["drift:lag"].copy()
    if hp := effects.get("ambient_coupling"):
        e += hp["k_amb"] * (amb - amb[0])
    if hp := effects.get("speed_growth"):
        rpm = cols["U_spindle_rpm"]
        e += hp["g"] * (rpm / src0["ref"]) ** 2 - hp["g"] * (rpm[0] / src0["ref"]) ** 2
    if hp := effects.get("nonlinear_expansion"):
        rise = sim[hp["node"]] - sim[hp["node"]][0]
        # the structure's expansion, so through the structure's lag as its linear part is
        e += hp["q"] * (rise**2 if effect_lag is None else lag(t, rise**2, effect_lag["tau"]))
    if hp := effects.get("periodic"):
        e += hp["amp"] * np.sin(2 * np.pi * t / hp["period_s"])
    for nd in m["nodes"]:
        if "sensor" in nd:
            cols[nd["sensor"]] = sim[nd["name"]].copy()
    if hp := effects.get("sensor_drift"):
        cols[hp["column"]] = cols[hp["column"]] + hp["rate_k_per_h"] * t / 3600.0
    if noise:
        for name in list(cols):
            if name.startswith("T_"):
                cols[name] = cols[name] + rng.normal(0, 0.03, len(t))
        e = e + rng.normal(0, 0.15, len(t))
    cols[axis] = e
    return cols


def _draw(m: dict[str, Any], hidden: str, rng: np.random.Generator) -> tuple[dict[str, Any], str | None]:
    """The hidden effect's true parameters (drawn from ``rng``) and the column it shows in."""
    drift = m["drift"][0]["um_per_k"]
    strong = max(drift, key=lambda kk: abs(drift[kk]))
    hp: dict[str, Any] = {}
    column: str | None = None
    if hidden == "thermal_lag":
        hp = {"tau": float(rng.uniform(1200, 2400))}
    elif hidden == "ambient_coupling":
        hp = {"k_amb": float(rng.choice([-1, 1]) * rng.uniform(2.0, 3.5))}
    elif hidden == "speed_growth":
        hp = {"g": float(rng.choice([-1, 1]) * rng.uniform(3.0, 5.0))}
    elif hidden == "unmodeled_source":
        hp = {"node": strong, "g": float(rng.uniform(1.5, 3.0))}
        column = "T_hydraulic"
    elif hidden == "nonlinear_expansion":
        sensed = [nd["name"] for nd in m["nodes"] if "sensor" in nd and nd["name"] in drift]
        node = sensed[0]
        hp = {"node": node, "q": float(np.sign(drift[node]) * rng.uniform(0.012, 0.02))}
    elif hidden == "sensor_drift":
        sensed = [nd for nd in m["nodes"] if "sensor" in nd]
        pick = sensed[int(rng.integers(len(sensed)))]
        column = pick["sensor"]
        hp = {"column": column, "rate_k_per_h": float(rng.choice([-1, 1]) * rng.uniform(0.12, 0.2))}
    elif hidden == "periodic":
        hp = {"amp": float(rng.uniform(1.5, 2.5)), "period_s": float(rng.uniform(2400, 3600))}
    return hp, column


def make_case(
    topology: str,
    hidden: str,
    seed: int,
    *,
    train_duty: str = "stepped",
    test_duty: str = "random",
    hours: tuple[float, float] = (20.0, 12.0),
    dt: float = 60.0,
    noise: bool = True,
) -> Case:
    """A training run and a held-out run of a true ``topology`` machine hiding ``hidden``."""
    if hidden not in HIDDEN:
        raise ValueError(f"unknown hidden effect {hidden!r} (one of {HIDDEN})")
    rng = np.random.default_rng(seed)
    m = machine(topology)
    hp, column = _draw(m, hidden, rng)
    effects = {hidden: hp} if hidden != "none" else {}
    train = _run(m, effects, train_duty, hours[0], dt, rng, noise=noise)
    test = _run(m, effects, test_duty, hours[1], dt, rng, noise=noise)
    nominal = _perturb(m, rng)
    assert [nd["name"] for nd in m["nodes"]] == [nd["name"] for nd in nominal["nodes"]]
    params = {k: v for k, v in hp.items() if isinstance(v, float)}
    return Case(topology, hidden, seed, column, params, train, test, m, nominal, axis=m["drift"][0]["axis"])


def make_multi_case(
    topology: str,
    hidden: tuple[str, ...],
    seed: int,
    *,
    params: dict[str, dict[str, Any]] | None = None,
    train_duty: str = "stepped",
    test_duty: str = "random",
    hours: tuple[float, float] = (20.0, 12.0),
    dt: float = 60.0,
    noise: bool = True,
) -> Case:
    """Like :func:`make_case`, with several effects hidden at once (each drawn as it is alone, in
    the given order; ``params`` overrides drawn values, e.g. ``{"periodic": {"period_s": 7200}}``).
    ``Case.hidden`` is the effects joined by ``+``; ``Case.columns`` maps each effect to its
    column (``None`` where it has none); ``Case.params`` keys are ``effect.name``."""
    if len(set(hidden)) != len(hidden) or not hidden:
        raise ValueError(f"hidden effects must be distinct and at least one, got {hidden!r}")
    for h in hidden:
        if h not in HIDDEN or h == "none":
            raise ValueError(f"unknown hidden effect {h!r} (one of {HIDDEN[:-1]})")
    rng = np.random.default_rng(seed)
    m = machine(topology)
    effects: dict[str, dict[str, Any]] = {}
    columns: dict[str, str | None] = {}
    for h in hidden:
        hp, col = _draw(m, h, rng)
        hp.update((params or {}).get(h, {}))
        effects[h] = hp
        columns[h] = hp.get("column", col)
    train = _run(m, effects, train_duty, hours[0], dt, rng, noise=noise)
    test = _run(m, effects, test_duty, hours[1], dt, rng, noise=noise)
    nominal = _perturb(m, rng)
    flat = {f"{h}.{k}": float(v) for h, hp in effects.items() for k, v in hp.items() if isinstance(v, (int, float))}
    first = next((c for c in columns.values() if c), None)
    return Case(topology, "+".join(hidden), seed, first, flat, train, test, m, nominal,
                axis=m["drift"][0]["axis"], columns=columns)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(float(v))
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def to_toml(m: dict[str, Any]) -> str:
    """Write a machine dict in the formats.md TOML layout."""
    lines = []
    for k, v in m.items():
        if not isinstance(v, list):
            lines.append(f"{k} = {_toml_value(v)}")
    for table in ("nodes", "links", "sources", "drift"):
        for entry in m.get(table, []):
            lines.append("")
            lines.append(f"[[{table}]]")
            lines.extend(f"{k} = {_toml_value(v)}" for k, v in entry.items())
    return "\n".join(lines) + "\n"


def write_run_csv(path: Any, cols: dict[str, np.ndarray]) -> None:
    """Write a run's columns as CSV (atomically)."""
    from ._io import write_atomic

    names = list(cols)
    rows = [",".join(names)]
    for i in range(len(cols["time_s"])):
        rows.append(",".join(f"{cols[n][i]:.6g}" if n != "time_s" else f"{cols[n][i]:.1f}" for n in names))
    write_atomic(path, "\n".join(rows) + "\n")


#: The shop run's sixteen temperature columns: which true node (or room / side column) each
#: sensor reads. ``T_t6`` follows the room; no column is named as the ambient.
SHOP_SENSORS = {
    "T_t1": "front_bearing", "T_t2": "spindle_motor", "T_t3": "headstock", "T_t4": "column",
    "T_t5": "bed", "T_t6": "room", "T_t7": "cabinet", "T_t8": "hydraulic",
    "T_t9": "front_bearing", "T_t10": "spindle_motor", "T_t11": "headstock", "T_t12": "column",
    "T_t13": "bed", "T_t14": "headstock", "T_t15": "column", "T_t16": "front_bearing",
}
SHOP_CHANNELS = ("E_ch1", "E_ch2", "E_ch3", "E_ch4", "E_ch5")


def make_shop_case(
    seed: int,
    *,
    hours: float = 46.0,
    dt: float = 15.0,
    hidden: dict[str, str] | None = None,
    noise_um: float = 0.3,
) -> Case:
    """A run shaped like a real measured one: ``hours`` at ``dt`` s (46 h at 15 s = 11 041 rows),
    sixteen temperatures ``T_t1..T_t16`` (the room is ``T_t6``, not marked; eight are second
    sensors on the same parts, each behind a small first-order lag of its own), the spindle stepped
    through 0–5000 rpm every 4 h, the shop air swinging ±1.8 K over a day, and five probe channels
    ``E_ch1..E_ch5``, each with its own drift map over the true VMC's nodes.

    ``hidden`` maps a channel to an effect of :data:`CAUSES` it carries (``ambient_coupling``,
    ``speed_growth``, ``thermal_lag`` or ``nonlinear_expansion``; per-channel effects only). The
    case's ``train`` is the whole run (hold out its end), ``test`` is empty; ``nominal`` is the
    true machine perturbed by 15–35 %, its sensors named ``T_t1..T_t4``, the ambient ``T_t6``, a
    drift entry per channel."""
    rng = np.random.default_rng(seed)
    hidden = dict(hidden or {})
    for ch, h in hidden.items():
        if ch not in SHOP_CHANNELS or h not in ("ambient_coupling", "speed_growth", "thermal_lag", "nonlinear_expansion"):
            raise ValueError(f"cannot hide {h!r} on {ch!r}")
    m = machine("vmc")
    m["sources"] = [dict(s, ref=5000.0) for s in m["sources"]]
    t = np.arange(0.0, hours * 3600.0 + 1e-9, dt)
    levels = rng.choice([0.0, 1000.0, 2000.0, 3000.0, 4000.0, 5000.0], size=int(hours // 4) + 2)
    rpm = levels[(t // (4 * 3600.0)).astype(int)]
    amb = _ambient(t, rng, 21.0)
    cols: dict[str, np.ndarray] = {"time_s": t, "U_spindle_rpm": rpm, "T_ambient": amb}
    for nd in m["nodes"]:
        if "sensor" in nd:
            cols[nd["sensor"]] = np.full(len(t), amb[0])
    sim = simulate_truth(m, cols)
    side = _side_columns(t, amb, rpm, rng)
    node_names = [nd["name"] for nd in m["nodes"]]
    out: dict[str, np.ndarray] = {"time_s": t, "U_spindle_rpm": rpm}
    first_of: dict[str, str] = {}
    for col, src in SHOP_SENSORS.items():
        if src == "room":
            v = amb.copy()
        elif src in ("cabinet", "hydraulic"):
            v = side["T_cabinet" if src == "cabinet" else "T_hydraulic"].copy()
        elif src not in first_of:
            first_of[src] = col
            v = sim[src].copy()
        else:  # a second sensor on the part: a lag of its own and a slightly smaller rise
            tau, gain = rng.uniform(300.0, 900.0), rng.uniform(0.8, 1.0)
            rise = lag(t, sim[src] - sim[src][0], tau)
            v = sim[src][0] + gain * rise
        out[col] = v + rng.normal(0, 0.03, len(t))
    drifts = []
    params: dict[str, float] = {}
    for ch in SHOP_CHANNELS:
        k = {n: float(v * rng.uniform(0.5, 1.5)) for n, v in m["drift"][0]["um_per_k"].items()}
        e = sum(k[n] * (sim[n] - sim[n][0]) for n in k)
        effect = hidden.get(ch)
        if effect == "ambient_coupling":
            params[f"{ch}.k_amb"] = kk = float(rng.choice([-1, 1]) * rng.uniform(2.0, 3.5))
            e = e + kk * (amb - amb[0])
        elif effect == "speed_growth":
            params[f"{ch}.g"] = g = float(rng.choice([-1, 1]) * rng.uniform(3.0, 5.0))
            e = e + g * (rpm / 5000.0) ** 2 - g * (rpm[0] / 5000.0) ** 2
        elif effect == "thermal_lag":
            params[f"{ch}.tau"] = tau = float(rng.uniform(1200, 2400))
            e = lag(t, e, tau)
        elif effect == "nonlinear_expansion":
            params[f"{ch}.q"] = q = float(np.sign(k["headstock"]) * rng.uniform(0.012, 0.02))
            e = e + q * (sim["headstock"] - sim["headstock"][0]) ** 2
        out[ch] = e + rng.normal(0, noise_um, len(t))
        drifts.append({"axis": ch, "um_per_k": k})
    truth = dict(m, drift=drifts)
    nominal = _perturb(truth, rng)
    for nd in nominal["nodes"]:
        if "sensor" in nd:
            nd["sensor"] = first_of[nd["name"]]
    nominal["ambient"] = "T_t6"
    nominal["name"] = "shop-nominal"
    assert set(node_names) >= set(first_of)
    return Case("shop", "+".join(f"{c}:{h}" for c, h in hidden.items()) or "none", seed, None, params,
                out, {}, truth, nominal, axis=SHOP_CHANNELS[0])


def lag(t: np.ndarray, y: np.ndarray, tau: float) -> np.ndarray:
    """First-order lag of ``y`` with time constant ``tau`` (exact for a held input), from y[0]."""
    z = np.empty_like(y)
    z[0] = y[0]
    for i in range(1, len(y)):
        a = np.exp(-(t[i] - t[i - 1]) / tau)
        z[i] = a * z[i - 1] + (1 - a) * y[i - 1]
    return z
