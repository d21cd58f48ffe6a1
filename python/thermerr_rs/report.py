"""The diagnosis report: ``report.json``, the two machine TOMLs and ``report.html`` (a page a
person reads: the verdict and its evidence first, then the plots, made with matplotlib when it is
installed and embedded in the page). Everything is rendered in memory first, then each file is written to a
temporary name and renamed into place, so a failure leaves no half-written report."""

from __future__ import annotations

import base64
import html
import io
import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._io import write_set

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: the time plots' margins, inches: the y tick labels and label (left), the x tick labels and
#: label (bottom), the legend's row above the plot (top)
MARGIN_IN = {"left": 0.85, "right": 0.2, "bottom": 0.55, "top": 0.4}

NO_PLOTS = "<p>The plots need matplotlib: <code>pip install thermerr_rs[report]</code>.</p>"


def also(columns: list[str]) -> str:
    """``, or as well T_b, T_c``: the other columns that explain the held-out error as well as a
    named one (empty when there are none)."""
    return f", or as well {', '.join(columns)}" if columns else ""


def cause_label(cause: dict[str, Any], word: str = "") -> str:
    """``cause (column)`` of a named cause, with the other columns that explain the held-out
    error as well (``alternatives``): ``unmodeled_source (T_t7, or as well T_t11)``; ``word``
    goes before the column (``"column "``)."""
    col = cause.get("column")
    if not col:
        return str(cause["cause"])
    return f"{cause['cause']} ({word}{col}{also([a['column'] for a in cause.get('alternatives') or []])})"


def _png(fig: Figure) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _legend(ax: Axes) -> None:
    """The legend in a row above the plot: never over the data, and no search for the emptiest
    corner (``loc="best"`` scans every plotted point, 11 000 on a day's run at 15 s)."""
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=3, fontsize=8, frameon=False)


def _plots(series: dict[str, Any], report: dict[str, Any]) -> list[tuple[str, str]] | None:
    """The figures as (title, base64 PNG); ``None`` without matplotlib. Drawn on ``Figure``
    objects: no pyplot, so the caller's backend and open figures are left alone."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        return None

    def axes(width: float, height: float) -> tuple[Figure, Axes]:
        """A figure of one plot, its margins set in inches (:data:`MARGIN_IN`): the time plots
        always have the same furniture, and a layout engine would draw each figure once more
        only to measure it (constrained layout: the real run's five reports took 2.8 s instead
        of 2.4 s, medians of five)."""
        fig = Figure(figsize=(width, height))
        fig.subplots_adjust(left=MARGIN_IN["left"] / width, right=1 - MARGIN_IN["right"] / width,
                            bottom=MARGIN_IN["bottom"] / height, top=1 - MARGIN_IN["top"] / height)
        return fig, fig.subplots()

    out = []
    t = np.asarray(series["time_s"]) / 3600.0
    axis = report["axis"]
    meas, base, ext = (np.asarray(series[k]) for k in ("measured", "baseline", "extended"))
    verdict = report["verdict"]
    fig, ax = axes(9, 3.6)
    ax.plot(t, meas, ".", ms=2.5, color="0.35", label=f"measured {axis}")
    ax.plot(t, base, "-", color="tab:red", lw=1.3, label="calibrated model (baseline)")
    if verdict not in ("none", "unexplained"):
        ax.plot(t, ext, "-", color="tab:green", lw=1.3, label=f"extended: {verdict}")
    ax.set_xlabel("time on the held-out data (h)")
    ax.set_ylabel("thermal error (µm)")
    _legend(ax)
    ax.grid(alpha=0.3)
    out.append(("Held-out run: measured error and the models", _png(fig)))

    fig, ax = axes(9, 3.2)
    ax.plot(t, meas - base, "-", color="tab:red", lw=1, label=f"baseline residual (RMS {report['baseline']['rmse_um']:.2f} µm)")
    if verdict not in ("none", "unexplained"):
        ax.plot(t, meas - ext, "-", color="tab:green", lw=1,
                label=f"extended residual (RMS {report['extended']['rmse_um']:.2f} µm)")
    noise = report.get("noise_um")
    if noise:
        ax.axhspan(-2 * noise, 2 * noise, color="0.85", label=f"±2σ probe noise ({noise:.2f} µm)")
    ax.axhline(0, color="0.3", lw=0.6)
    ax.set_xlabel("time on the held-out data (h)")
    ax.set_ylabel("residual (µm)")
    _legend(ax)
    ax.grid(alpha=0.3)
    out.append(("Residuals before and after the extension", _png(fig)))

    extra = series.get("sensor")
    if extra:
        fig, ax = axes(9, 3.2)
        ax.plot(t, extra["baseline_residual"], color="tab:red", lw=1, label="baseline")
        ax.plot(t, extra["extended_residual"], color="tab:green", lw=1, label="extended")
        ax.set_ylabel(f"{extra['column']} residual (°C)")
        ax.set_xlabel("time on the held-out data (h)")
        _legend(ax)
        ax.grid(alpha=0.3)
        out.append((f"Temperature residual of {extra['column']}", _png(fig)))
    return out


def _layers(network: dict[str, Any]) -> list[list[str]]:
    """Nodes in columns by their link distance from the heated nodes (the sources' nodes, else
    the first node), each column in file order; a node no link reaches goes last."""
    names = [n["name"] for n in network["nodes"]]
    nbrs: dict[str, list[str]] = {n: [] for n in names}
    for link in network.get("links", []):
        a, b = link["between"]
        nbrs[a].append(b)
        nbrs[b].append(a)
    depth = {s["node"]: 0 for s in network.get("sources", [])} or {names[0]: 0}
    frontier = list(depth)
    while frontier:
        nxt = []
        for a in frontier:
            for b in nbrs[a]:
                if b not in depth:
                    depth[b] = depth[a] + 1
                    nxt.append(b)
        frontier = nxt
    last = max(depth.values()) + 1
    cols: list[list[str]] = [[] for _ in range(last + 1)]
    for n in names:
        cols[depth.get(n, last)].append(n)
    return [c for c in cols if c]


def network_svg(network: dict[str, Any], causes: list[dict[str, Any]]) -> str:
    """The thermal network as an SVG drawing: inputs (left) heating their nodes, the nodes in
    columns by link distance from the heated ones, links, each node's sensor, the ambient (bottom)
    with the nodes that lose heat to it, and the drift axes (right) with the nodes they read.
    What the named causes added is written in green beside the part it changed."""
    esc = html.escape
    cols = _layers(network)
    nodes = {n["name"]: n for n in network["nodes"]}
    inputs = sorted({s["input"] for s in network.get("sources", [])})
    drift = network.get("drift", [])
    node_w, node_h, gap_x, gap_y, left, top = 160, 54, 90, 40, 170, 30
    rows = max(len(c) for c in cols + [inputs, drift])
    width = left + len(cols) * (node_w + gap_x) + 180
    height = top + rows * (node_h + gap_y) + 60
    pos: dict[str, tuple[float, float]] = {}
    for i, col in enumerate(cols):
        for j, n in enumerate(col):
            pos[n] = (left + i * (node_w + gap_x), top + j * (node_h + gap_y))
    amb_y, right = height - 40, width - 160
    out = [f"<svg xmlns='http://www.w3.org/2000/svg' width='{width}' height='{height}' "
           f"viewBox='0 0 {width} {height}' font-family='sans-serif' font-size='12'>",
           "<defs><marker id='arr' markerWidth='8' markerHeight='8' refX='7' refY='4' orient='auto'>"
           "<path d='M0,0 L8,4 L0,8 z' fill='#c44'/></marker></defs>"]
    amb = network["ambient"]
    amb_label = f"ambient: {amb}" if isinstance(amb, str) else f"ambient: {amb} °C"
    out.append(f"<rect x='{left}' y='{amb_y}' width='{right - 40 - left}' height='24' fill='#e8f0f8' stroke='#89a'/>"
               f"<text x='{left + 8}' y='{amb_y + 16}'>{esc(amb_label)}</text>")
    for n, (x, y) in pos.items():  # losses to the ambient, under everything else
        if nodes[n].get("ambient_w_per_k", 0.0) > 0:
            out.append(f"<line x1='{x + node_w / 2}' y1='{y + node_h}' x2='{x + node_w / 2}' y2='{amb_y}' "
                       "stroke='#89a' stroke-dasharray='3,3'/>")
    for k, d in enumerate(drift):  # what each axis reads
        y = top + k * (node_h + gap_y)
        for n, v in d.get("um_per_k", {}).items():
            if n in pos and v != 0:
                x, yy = pos[n]
                out.append(f"<line x1='{x + node_w}' y1='{yy + node_h / 2}' x2='{right}' y2='{y + node_h / 2}' "
                           "stroke='#b90' stroke-opacity='0.6' stroke-dasharray='1,3'/>")
    for link in network.get("links", []):
        (x1, y1), (x2, y2) = pos[link["between"][0]], pos[link["between"][1]]
        mx, my = (x1 + x2) / 2 + node_w / 2, (y1 + y2) / 2 + node_h / 2
        out.append(f"<line x1='{x1 + node_w / 2}' y1='{y1 + node_h / 2}' x2='{x2 + node_w / 2}' y2='{y2 + node_h / 2}' "
                   "stroke='#555' stroke-width='2'/>"
                   f"<text x='{mx}' y='{my - 5}' fill='#555' font-size='10' text-anchor='middle'>{link['w_per_k']:.3g} W/K</text>")
    for i, name in enumerate(inputs):
        y = top + i * (node_h + gap_y)
        out.append(f"<rect x='10' y='{y}' width='120' height='{node_h}' rx='4' fill='#fdecea' stroke='#c44'/>"
                   f"<text x='16' y='{y + 31}'>{esc(name)}</text>")
        for s in network["sources"]:
            if s["input"] == name:
                x2, y2 = pos[s["node"]]
                out.append(f"<line x1='130' y1='{y + node_h / 2}' x2='{x2 - 2}' y2='{y2 + node_h / 2}' stroke='#c44' "
                           "marker-end='url(#arr)'/>")
    for n, (x, y) in pos.items():
        nd = nodes[n]
        fill = "#eef7ee" if nd.get("boundary") else "#fff"
        out.append(f"<rect x='{x}' y='{y}' width='{node_w}' height='{node_h}' rx='6' fill='{fill}' stroke='#333'/>"
                   f"<text x='{x + 8}' y='{y + 17}' font-weight='bold'>{esc(n)}</text>"
                   f"<text x='{x + 8}' y='{y + 31}' font-size='10' fill='#555'>C {nd['capacity_j_per_k']:.3g} J/K</text>")
        sensor = nd.get("sensor") or nd.get("boundary")
        if sensor:
            kind = "sensor" if nd.get("sensor") else "follows"
            out.append(f"<circle cx='{x + 12}' cy='{y + 43}' r='4' fill='#48c'/>"
                       f"<text x='{x + 20}' y='{y + 47}' font-size='10' fill='#48c'>{kind} {esc(sensor)}</text>")
    for k, d in enumerate(drift):
        y = top + k * (node_h + gap_y)
        out.append(f"<rect x='{right}' y='{y}' width='120' height='{node_h}' rx='4' fill='#fff8e0' stroke='#b90'/>"
                   f"<text x='{right + 8}' y='{y + 31}'>{esc(d['axis'])}</text>")
    for c in causes:  # what the named causes added, beside the part they changed
        text = c["cause"] + (f" ({c['column']})" if c.get("column") else "")
        if c.get("node") in pos:
            x, y = pos[c["node"]]
            out.append(f"<text x='{x}' y='{y + node_h + 13}' font-size='10' fill='#2a7'>+ {esc(text)}</text>")
        else:
            k = next((i for i, d in enumerate(drift) if d["axis"] == c.get("axis")), 0)
            extra = sum(1 for o in causes[:causes.index(c)] if o.get("node") not in pos and o.get("axis") == c.get("axis"))
            y = top + k * (node_h + gap_y) + node_h + 13 + 12 * extra
            out.append(f"<text x='{right}' y='{y}' font-size='10' fill='#2a7'>+ {esc(text)}</text>")
    out.append("</svg>")
    return "".join(out)


def _gain_bar(gain: float, top: float, named: bool) -> str:
    """A candidate's held-out gain as a bar in its table row (green: the named one; red: a gain
    below zero), scaled to the largest |gain| of the round. In the table, not a figure: a chart
    of 30-odd labelled bars was the costliest image of the report (0.37 of 0.77 s per axis on
    the real run) and said what the table says. ``top``: the largest |gain| of the round (> 0)."""
    color = "#2a7" if named else ("#bbb" if gain >= 0 else "#d66")
    return (f"<span style='display:inline-block;width:{120 * abs(gain) / top:.0f}px;height:.8em;"
            f"background:{color}'></span> {gain:.1f}")


def render_html(report: dict[str, Any], series: dict[str, Any], network: dict[str, Any] | None = None) -> str:
    """The HTML page: verdict and evidence first, then the figures, then the table."""
    esc = html.escape
    verdict = report["verdict"]
    col = f" — column <code>{esc(str(report['column']))}</code>" if report.get("column") else ""
    first = (report.get("causes") or [{}])[0]
    if report.get("column") and first.get("alternatives"):
        col += " (or as well " + ", ".join(f"<code>{esc(str(a['column']))}</code>" for a in first["alternatives"]) + ")"
    cands = report.get("candidates", [])
    named = cands[0] if cands and verdict not in ("none", "unexplained") else None
    top = max((abs(c["gain_pct"]) for c in cands), default=0.0) or 1.0
    rows = "".join(
        f"<tr><td>{esc(c['cause'])}</td><td>{esc(str(c.get('column') or ''))}</td><td>{esc(str(c.get('node') or ''))}</td>"
        f"<td>{_gain_bar(c['gain_pct'], top, c is named)}</td><td>{c['score']:.3f}</td>"
        f"<td>{c.get('delta_bic', float('nan')):.1f}</td>"
        f"<td>{esc(json.dumps(c.get('parameters', {})))}</td></tr>"
        for c in cands
    )
    round_rows = "".join(
        f"<tr><td>{r['round']}</td><td>{esc(r['cause'] or '—')}</td><td>{esc(str(r.get('column') or ''))}</td>"
        f"<td>{r['rmse_before_um']:.3f}</td><td>{r['rmse_um']:.3f}</td><td>{r['gain_pct']:.1f}</td>"
        f"<td>{100 * r['excess_share']:.0f}</td>"
        f"<td>{'named' if r['kept'] else ('dropped by the backward check' if r['accepted'] else 'not accepted')}"
        f"{' (as a pair)' if r.get('paired') else ''}</td></tr>"
        for r in report.get("rounds", [])
    )
    rem = report.get("remainder_um", 0.0)
    remainder = (f"<p>Unexplained remainder: <b>{rem:.3f} µm</b> held-out RMS above the probe noise, "
                 "left by every named cause together.</p>" if rem > 0 else
                 "<p>Unexplained remainder: none (the final held-out residual is within the noise ratio).</p>")
    plots = _plots(series, report)
    figs = NO_PLOTS if plots is None else "".join(
        f"<figure><img alt='{esc(title)}' src='data:image/png;base64,{png}'><figcaption>{esc(title)}</figcaption></figure>"
        for title, png in plots
    )
    b, e = report["baseline"], report["extended"]
    drawing = "" if network is None else (
        "<h2>The network</h2><p>Inputs (red) heat their nodes; nodes are linked by conduction (grey, "
        "W/K) and lose heat to the ambient (dashed); blue dots are the sensors, yellow boxes the drift "
        "axes and the nodes they read. In green: what the named causes added.</p>"
        f"<figure>{network_svg(network, report.get('causes', []))}</figure>")
    ident_info = report.get("identification")
    ident = "" if not report.get("identified") or not ident_info else (
        f"<p>The network was <b>identified from data</b> by <code>thermerr init</code> from "
        f"<code>{esc(str(ident_info['source']))}</code> ({ident_info['train_rows']} training rows, "
        f"{ident_info['holdout_rows']} held out; ambient rule: {esc(str(ident_info['ambient_rule']))}; "
        f"nodes: {esc(str(ident_info['node_rule']))}), {esc(identified_caveat(ident_info.get('driven_by')))}</p>")
    suspects = suspects_html(report.get("suspect_readings", []))
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>thermerr diagnosis: {esc(verdict)}</title>
<style>body{{font-family:system-ui,sans-serif;max-width:980px;margin:2em auto;padding:0 1em;color:#222}}
.verdict{{font-size:1.6em;margin:.2em 0}} .evidence{{font-size:1.1em;background:#f4f6f8;padding:.8em;border-left:4px solid #2a7}}
table{{border-collapse:collapse;font-size:.9em}} td,th{{border:1px solid #ccc;padding:.25em .6em;text-align:left}}
figure{{margin:1.5em 0}} img{{max-width:100%}} figcaption{{color:#555;font-size:.9em}}</style></head><body>
<p>thermerr diagnosis of <code>{esc(report.get('run', ''))}</code> against <code>{esc(report.get('machine', ''))}</code>, axis <b>{esc(report['axis'])}</b></p>
<p class="verdict">Verdict: <b>{esc(verdict)}</b>{col}</p>
<p class="evidence">{esc(report.get('evidence', ''))}</p>
{suspects}
<table><tr><th></th><th>RMS (µm)</th><th>max |r| (µm)</th><th>band (µm)</th></tr>
<tr><td>calibrated model (baseline)</td><td>{b['rmse_um']:.3f}</td><td>{b['max_abs_um']:.3f}</td><td>{b['band_um']:.3f}</td></tr>
<tr><td>extended model (every named cause)</td><td>{e['rmse_um']:.3f}</td><td>{e['max_abs_um']:.3f}</td><td>{e['band_um']:.3f}</td></tr></table>
<p>All figures are on data held out from calibration ({esc(report.get('holdout', ''))}). Gain: {report['gain_pct']:.1f} %.</p>
<h2>Rounds</h2>
<table><tr><th>round</th><th>cause</th><th>column</th><th>held-out RMS before (µm)</th><th>held-out RMS after (µm)</th><th>gain (%)</th><th>of the excess (%)</th><th></th></tr>{round_rows}</table>
{remainder}
{ident}
{drawing}
{figs}
<h2>Candidates (round 1), scored on the held-out data</h2>
<table><tr><th>cause</th><th>column</th><th>node</th><th>held-out gain (%): 1 − RMS(extended)/RMS(baseline)</th><th>score</th><th>ΔBIC (train)</th><th>parameters</th></tr>{rows}</table>
<p style="color:#777;font-size:.85em">calibrated.toml: the nominal model after calibration; extended.toml: calibrated plus the extension of every named cause.
Both load back with <code>thermerr_rs.Machine.load</code> and simulate with the same code.</p>
</body></html>
"""


def write_report(
    out_dir: str | os.PathLike[str],
    report: dict[str, Any],
    series: dict[str, Any],
    calibrated_toml: str,
    extended_toml: str,
    network: dict[str, Any] | None = None,
) -> Path:
    """Render everything, then write the four files into ``out_dir`` as one set (all or nothing;
    a previous output there is replaced whole, see ``_io.write_set``). ``network``: the extended
    machine as :meth:`Machine.to_dict` gives it, drawn in the page."""
    page = render_html(report, series, network)
    doc = json.dumps(report, indent=1, allow_nan=False)
    out = write_set(out_dir, {
        "calibrated.toml": calibrated_toml,
        "extended.toml": extended_toml,
        "report.json": doc,
        "report.html": page,
    })
    return out / "report.html"


#: what a diagnosis says when its network came from ``thermerr init`` (the page, the summary
#: page and the printed result)
IDENTIFIED_CAVEAT = (
    "not written by a person: a cause named here, or an unexplained remainder, may also be a "
    "shortcoming of the identified network (its node count, its links, its sensors); compare with "
    "thermerr init --nodes N or a network written from the drawings, and with thermerr diagnose "
    "--network best, which also tries the network exactly as identified (recalibrating it on one "
    "axis can overfit a real run; the default, auto, keeps it only where the recalibration is not "
    "unique)")


def identified_caveat(driven_by: str | None = None) -> str:
    """:data:`IDENTIFIED_CAVEAT`, and when the run had no input column (``driven_by``, the
    temperature that drives the identified network) what that does to the diagnosis."""
    if not driven_by:
        return IDENTIFIED_CAVEAT
    return (f"{IDENTIFIED_CAVEAT}. The run it was identified from had no input column, so {driven_by} drives "
            "the network (a boundary node): on simulated runs without their inputs, diagnoses on such networks "
            "named the hidden cause in 3 of 28 cases and a cause not hidden in 12 (docs/machine-model.md, "
            "\"A run with no input column\"); read a cause named here as \"the network misses something\", and "
            "log the inputs (U_ columns) to diagnose")


def suspects_html(items: list[dict[str, Any]]) -> str:
    """The suspect readings of the run(s) (a jump, a long exact repeat), one line each; nothing
    when there are none."""
    if not items:
        return ""
    lines = "".join(f"<li>{html.escape(sp['text'])}</li>" for sp in items)
    return f"<div style='border-left:4px solid #c80;padding:.2em .8em'><b>Suspect readings</b><ul>{lines}</ul></div>"


def render_axes_html(summary: dict[str, Any]) -> str:
    """The summary page of a diagnosis of several axes: a row per axis, linking its own page."""
    esc = html.escape
    rows = []
    for a in summary["axes"]:
        causes = ", ".join(cause_label(c) for c in summary["causes"] if c["axis"] == a) or "—"
        rows.append(
            f"<tr><td><a href='{esc(a)}.report.html'>{esc(a)}</a></td><td>{esc(summary['verdicts'][a])}</td>"
            f"<td>{esc(causes)}</td><td>{esc(summary.get('baseline_network', {}).get(a, 'recalibrated'))}</td>"
            f"<td>{summary['baseline_rmse_um'][a]:.3f}</td>"
            f"<td>{summary['extended_rmse_um'][a]:.3f}</td><td>{summary['gain_pct'][a]:.1f}</td>"
            f"<td>{summary['remainder_um'][a]:.3f}</td></tr>")
    return (
        "<!doctype html><html><head><meta charset='utf-8'><title>thermerr diagnosis</title>"
        "<style>body{font-family:sans-serif;margin:2em}td,th{padding:.3em .8em;text-align:left}</style>"
        f"</head><body><h1>Diagnosis of {len(summary['axes'])} axes</h1>"
        f"<p>run <code>{esc(summary['run'])}</code>, machine <code>{esc(summary['machine'])}</code>; "
        "every figure on held-out data</p>"
        + (f"<p>The network was <b>identified from data</b> by <code>thermerr init</code>, "
           f"{esc(identified_caveat(summary.get('driven_by')))}</p>" if summary.get("identified") else "")
        + suspects_html(summary.get("suspect_readings", []))
        + "".join(f"<p><b>{esc(a)} not diagnosed</b>: {esc(why)}</p>"
                  for a, why in summary.get("skipped", {}).items())
        + "<table><tr><th>axis</th><th>verdict</th><th>causes</th><th>baseline network</th>"
        "<th>baseline RMS (µm)</th><th>extended RMS (µm)</th><th>gain (%)</th>"
        "<th>unexplained remainder (µm)</th></tr>" + "".join(rows) + "</table></body></html>\n")


def write_axes_report(
    out_dir: str | os.PathLike[str],
    summary: dict[str, Any],
    per_axis: dict[str, tuple[dict[str, Any], dict[str, Any], str, str, dict[str, Any] | None]],
) -> Path:
    """Write the summary and every axis's four files (``<axis>.report.json`` ...) into
    ``out_dir`` as one set (all or nothing, as :func:`write_report`)."""
    files: dict[str, str] = {
        "report.json": json.dumps(summary, indent=1, allow_nan=False),
        "report.html": render_axes_html(summary),
    }
    for a, (report, series, cal, ext, network) in per_axis.items():
        files[f"{a}.report.json"] = json.dumps(report, indent=1, allow_nan=False)
        files[f"{a}.report.html"] = render_html(report, series, network)
        files[f"{a}.calibrated.toml"] = cal
        files[f"{a}.extended.toml"] = ext
    out = write_set(out_dir, files)
    return out / "report.html"
