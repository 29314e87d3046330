"""``impact-harness report``: ``reports/index.html`` and ``reports/summary.md`` from results.

::

    impact-harness report                                  # reports/results.json -> reports/
    impact-harness report --results /tmp/r.json --out /tmp/report

The HTML page is self-contained (inline CSS, no scripts, no external assets); its figures are
PNG files in ``<out>/figures/`` beside it, and the Table 3 reproduction
(``<out>/paper-table3.md`` and ``.png``, written by ``impact-harness paper``) is embedded
when present. Matplotlib (Agg) draws the figures; nothing here touches an engine or re-solves
a scenario except the impulse paths of Routh's graph, which ``planar_impact.impulse_process``
walks from the contact-space numbers stored in the results.

What the page shows, in order: what this is; the headline heat maps (departure of every
engine and preset from Poisson and from Stronge, per scenario); the split of each engine's
departure into the law it solves and how well it solves it; the gates; per scenario the
post-impact velocities of every law and engine side by side, the energy change and the
impulse diagram (Fig. 1 of the paper), or for sweeps the post-impact quantities against the
swept parameter with the Poisson type boundaries marked; Table 3; versions and settings.
"""

from __future__ import annotations

import argparse
import html
import math
import re
import time
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from harness.results import ANALYTIC, DEFAULT_RESULTS, Record, Results, read_results

FIGURES = "figures"
LAW_ORDER = ("poisson", "stronge", "stronge-paper", "newton", "newton-lcp")
HEADLINE_LAWS = ("poisson", "stronge")
LAW_STYLE = {  # colour, line style, label
    "poisson": ("black", "-", "Poisson"),
    "stronge": ("tab:red", "-", "Stronge (exact)"),
    "stronge-paper": ("tab:purple", "--", "Stronge (paper's mapping)"),
    "newton": ("tab:gray", "-.", "Newton (process)"),
    "newton-lcp": ("tab:brown", ":", "newton-lcp (engines' law)"),
}
ENGINE_STYLE = {"pymunk": ("tab:blue", "o"), "pybullet": ("tab:orange", "s"),
                "mujoco": ("tab:green", "^")}
TYPE_NAMES = {1: "stick in compression", 2: "stick in restitution",
              3: "reverse slide from compression", 4: "reverse slide from restitution",
              5: "forward slide"}
# Split figure: law parts below X_FLOOR (the law equals Poisson there) are drawn at X_FLOOR.
X_FLOOR = 1.5e-4
# Heat-map colour range (relative departure): below 1e-4 counts as "agrees".
HEAT_MIN, HEAT_MAX = 1e-4, 1.0


# --------------------------------------------------------------------------------------------
# Formatting
# --------------------------------------------------------------------------------------------
def fmt_departure(value) -> str:
    """A departure as a percentage: ``20.7%``, ``0.18%``, ``2e-12%``, ``0``; ``n/a``."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    percent = 100.0 * value
    if percent == 0:
        return "0"
    if percent < 0.01:
        return f"{percent:.0e}%"
    return f"{percent:.3g}%"


def fmt_number(value, digits: int = 4) -> str:
    if value is None:
        return "–"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan"
    if abs(value) < 5e-13:
        return "0"
    return f"{value:.{digits}g}"


def slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", name)


def _esc(text) -> str:
    return html.escape(str(text), quote=True)


# --------------------------------------------------------------------------------------------
# Data views
# --------------------------------------------------------------------------------------------
def engine_scenarios(results: Results) -> list[str]:
    """Scenarios with engine records, in run order."""
    return [name for name in results.scenario_names()
            if any(r.source != ANALYTIC for r in results.for_scenario(name))]


def worst_departure(records: Iterable[Record], law: str) -> tuple[float, bool, bool]:
    """Largest departure from ``law`` over a scenario's points; (value, any flagged, all skipped)."""
    records = list(records)
    values = [r.departure.get(law) for r in records if not r.skipped]
    values = [v for v in values if v is not None and math.isfinite(v)]
    flagged = any(not r.ok and not r.skipped for r in records)
    skipped = bool(records) and all(r.skipped for r in records)
    return (max(values) if values else math.nan), flagged, skipped


def departure_grid(results: Results, law: str, labels: Sequence[str]):
    """``(scenarios, values[s, l], flagged[s, l], skipped[s, l])``, max over sweep points."""
    names = engine_scenarios(results)
    values = np.full((len(names), len(labels)), np.nan)
    flagged = np.zeros_like(values, dtype=bool)
    skipped = np.zeros_like(values, dtype=bool)
    for i, name in enumerate(names):
        records = results.for_scenario(name)
        for j, label in enumerate(labels):
            subset = [r for r in records if r.source != ANALYTIC and r.label == label]
            if subset:
                values[i, j], flagged[i, j], skipped[i, j] = worst_departure(subset, law)
            else:
                skipped[i, j] = True
    return names, values, flagged, skipped


def split_rows(results: Results) -> list[dict]:
    """The departure split of every engine record (metrics.departure_split)."""
    from harness.metrics import departure_split

    lcp = {(r.scenario, r.point["index"]): r for r in results.records
           if r.source == ANALYTIC and r.law == "newton-lcp" and r.ok}
    rows = []
    for record in results.records:
        if record.source == ANALYTIC or record.skipped or record.u_after is None:
            continue
        law_record = lcp.get((record.scenario, record.point["index"]))
        if law_record is None:
            continue
        split = departure_split(record.departure, law_record.departure)
        rows.append({"scenario": record.scenario, "point": record.point["label"],
                     "label": record.label, "engine": record.source, "preset": record.preset,
                     "status": record.status, **split})
    return rows


# --------------------------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------------------------
def _figure(width: float, height: float):
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _save(figure, path: Path, dpi: int = 100, tag: str | None = None) -> Path:
    """Save a PNG; ``tag`` (the digest of the figure's inputs) goes into its metadata."""
    figure.savefig(path, dpi=dpi, metadata={TAG_KEY: tag} if tag else None)
    return path


TAG_KEY = "impact-harness-inputs"
_VOLATILE = ("wall_time_s", "cached")


def _stable(record: Record) -> dict:
    """A record without what changes between identical runs (times, cache flags)."""
    data = record.as_dict()
    for key in _VOLATILE:
        data.pop(key, None)
    if data.get("diagnostics"):
        data["diagnostics"] = {k: v for k, v in data["diagnostics"].items()
                               if k != "engine_wall_time_s"}
    return data


def _digest(kind: str, payload) -> str:
    """Digest of a figure's inputs and of the code drawing it (this module, matplotlib)."""
    import hashlib
    import json

    import matplotlib

    source = Path(__file__).read_bytes()
    text = json.dumps([kind, payload], sort_keys=True, default=str)
    return hashlib.sha256(source + matplotlib.__version__.encode() + text.encode()).hexdigest()


def _png_tag(path: Path) -> str | None:
    """The inputs digest stored in a PNG by :func:`_save` (None if absent/unreadable)."""
    try:
        from PIL import Image

        with Image.open(path) as image:
            return image.text.get(TAG_KEY)
    except Exception:  # a missing or broken file is simply redrawn
        return None


def _render(kind: str, path: Path, payload, draw) -> Path | None:
    """Draw a figure unless ``path`` already holds one drawn from the same inputs."""
    tag = _digest(kind, payload)
    if path.exists() and _png_tag(path) == tag:
        return path
    return draw(path, tag)


def heatmap_figure(results: Results, path: Path, tag: str | None = None) -> Path | None:
    """Departure from Poisson and from Stronge: scenario × engine, one panel per law × preset."""
    from matplotlib.colors import LogNorm

    labels = results.engine_labels()
    if not labels:
        return None
    presets = list(dict.fromkeys(label.split(".")[1] for label in labels))
    names = engine_scenarios(results)
    panels = [(law, preset) for law in HEADLINE_LAWS for preset in presets]
    figure = _figure(2.2 + 0.95 * len(labels) * len(HEADLINE_LAWS), 1.3 + 0.25 * len(names))
    axes = figure.subplots(1, len(panels), sharey=True, squeeze=False)[0]
    norm = LogNorm(vmin=HEAT_MIN, vmax=HEAT_MAX)
    cmap = _heat_cmap()
    image = None
    for ax, (law, preset) in zip(axes, panels):
        panel_labels = [label for label in labels if label.endswith("." + preset)]
        _, values, flagged, skipped = departure_grid(results, law, panel_labels)
        shown = np.where(np.isfinite(values), np.clip(values, HEAT_MIN, HEAT_MAX), np.nan)
        image = ax.imshow(np.ma.masked_invalid(shown), cmap=cmap, norm=norm, aspect="auto")
        for i in range(len(names)):
            for j in range(len(panel_labels)):
                if skipped[i, j] or not np.isfinite(values[i, j]):
                    text, colour = ("skipped" if skipped[i, j] else "n/a"), "0.35"
                else:
                    text = fmt_departure(values[i, j]) + (" !" if flagged[i, j] else "")
                    colour = "white" if values[i, j] > 0.08 else "black"
                ax.text(j, i, text, ha="center", va="center", fontsize=7.5, color=colour)
        ax.set_xticks(range(len(panel_labels)), [label.split(".")[0] for label in panel_labels],
                      fontsize=8.5)
        ax.xaxis.tick_top()
        ax.set_title(f"from {LAW_STYLE[law][2]} — {preset}", fontsize=9, pad=16)
        ax.set_yticks(range(len(names)), [_row_name(results, n) for n in names], fontsize=8.5)
        ax.tick_params(length=0)
    figure.colorbar(image, ax=list(axes), shrink=0.6, pad=0.01,
                    label="departure ‖u − u_law‖_M / ‖u_before‖_M")
    return _save(figure, path, dpi=110, tag=tag)


def _heat_cmap():
    from matplotlib import colormaps

    return colormaps["YlOrRd"].with_extremes(bad="0.92")


def _row_name(results: Results, name: str) -> str:
    info = results.scenarios.get(name, {})
    sweep = info.get("sweep")
    return f"{name} (max of {len(sweep['values'])})" if sweep else name


def split_figure(rows: Sequence[dict], path: Path, tag: str | None = None) -> Path | None:
    """Law part vs solve part of every engine record, log–log, one panel per preset."""
    if not rows:
        return None
    presets = list(dict.fromkeys(row["preset"] for row in rows))
    floor = 1e-12
    figure = _figure(4.6 * len(presets), 4.2)
    axes = figure.subplots(1, len(presets), sharex=True, sharey=True, squeeze=False)[0]
    for ax, preset in zip(axes, presets):
        for engine, (colour, marker) in ENGINE_STYLE.items():
            subset = [r for r in rows if r["preset"] == preset and r["engine"] == engine
                      and math.isfinite(r["law_part"]) and math.isfinite(r["solve_part"])]
            if not subset:
                continue
            x = np.maximum([r["law_part"] for r in subset], X_FLOOR)
            y = np.maximum([r["solve_part"] for r in subset], floor)
            ax.scatter(x, y, s=22, marker=marker, color=colour, alpha=0.75, label=engine,
                       edgecolors="none")
        ax.plot([floor, 10], [floor, 10], color="0.5", lw=0.8, ls="--")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(1e-4, 3)
        ax.set_ylim(floor / 3, 3)
        ax.axhline(1e-6, color="0.8", lw=0.6)
        ax.axvline(X_FLOOR, color="0.85", lw=0.6)
        ax.set_xlabel("law part: newton-lcp vs Poisson\n(≤ 1.5e-4, e.g. the laws agree, drawn at 1.5e-4)")
        ax.set_title(f"{preset}", fontsize=10)
        ax.text(0.03, 0.97, "above the diagonal: the solve\n(engine vs its own law) dominates",
                transform=ax.transAxes, va="top", fontsize=7, color="0.3")
        ax.text(0.97, 0.45, "below the diagonal:\nthe law itself dominates",
                transform=ax.transAxes, ha="right", va="top", fontsize=7, color="0.3")
        ax.grid(True, which="major", color="0.93")
    axes[0].set_ylabel("solve part: engine vs newton-lcp\n(values ≤ 1e-12 drawn at 1e-12)")
    axes[-1].legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8, frameon=False)
    return _save(figure, path, tag=tag)


def impulse_figure(name: str, records: Sequence[Record], path: Path, tag: str | None = None) -> Path | None:
    """Routh's graph (Fig. 1): I_t against I_n, each law's path and every end point."""
    from planar_impact import impulse_process

    laws = [r for r in records if r.source == ANALYTIC and r.ok]
    if not laws:
        return None
    d = laws[0].diagnostics or {}
    mnn, mnt, mtt, mu, e = (d.get(k) for k in ("mnn", "mnt", "mtt", "mu", "e"))
    vn, vt = laws[0].vn_approach, laws[0].vt_approach
    figure = _figure(4.6, 3.4)
    ax = figure.subplots()
    extent = max([abs(r.normal_impulse) for r in records if r.normal_impulse is not None
                  and math.isfinite(r.normal_impulse)] + [1e-12])
    for law in ("newton", "poisson", "stronge"):
        if not any(r.law == law for r in laws):
            continue
        colour, style, label = LAW_STYLE[law]
        try:
            process = impulse_process(mnn, mnt, mtt, vn, vt, mu, e, law)
        except ValueError:
            continue
        xs = [v.normal_impulse for v in process.path]
        ys = [v.tangential_impulse for v in process.path]
        ax.plot(xs, ys, color=colour, ls=style, lw=1.4, label=label, zorder=3)
        ax.plot(xs[-1:], ys[-1:], "o", color=colour, ms=4, zorder=3)
    for r in laws:
        if r.law in ("stronge-paper", "newton-lcp") and r.normal_impulse is not None:
            colour, _, label = LAW_STYLE[r.law]
            ax.plot([r.normal_impulse], [r.tangential_impulse], "D", ms=6, zorder=6,
                    markerfacecolor="none", markeredgecolor=colour, markeredgewidth=1.5,
                    label=label)
    for r in records:
        if r.source == ANALYTIC or r.normal_impulse is None or r.tangential_impulse is None:
            continue
        if not (math.isfinite(r.normal_impulse) and math.isfinite(r.tangential_impulse)):
            continue
        colour, marker = ENGINE_STYLE.get(r.source, ("k", "x"))
        filled = r.preset == "accurate"
        ax.plot([r.normal_impulse], [r.tangential_impulse], marker, ms=7, zorder=5,
                markerfacecolor=colour if filled else "none", markeredgecolor=colour,
                label=f"{r.label}" + ("" if r.ok else f" ({r.status})"))
    # Routh's lines: compression ends (v_n = 0) and sticking (v_t = 0), and the cone.
    x = np.linspace(0.0, 1.15 * extent, 50)
    ax.plot(x, mu * x, color="0.75", lw=0.8, ls=":")
    ax.plot(x, -mu * x, color="0.75", lw=0.8, ls=":", label="friction cone |I_t| = μ I_n")
    if abs(mnt) > 1e-14 * mnn:
        ax.plot(x, -(vn + mnn * x) / mnt, color="tab:cyan", lw=0.8, ls="--", label="v_n = 0")
    else:
        ax.axvline(-vn / mnn, color="tab:cyan", lw=0.8, ls="--", label="v_n = 0")
    ax.plot(x, -(vt + mnt * x) / mtt, color="tab:olive", lw=0.8, ls="--", label="v_t = 0")
    ys = [r.tangential_impulse for r in records if r.tangential_impulse is not None
          and math.isfinite(r.tangential_impulse)]
    span = max([abs(y) for y in ys] + [mu * extent, 0.1 * extent])
    ax.set_ylim(-1.25 * span, 1.25 * span)
    ax.set_xlim(0, 1.15 * extent)
    ax.axhline(0, color="0.85", lw=0.6)
    ax.set_xlabel("normal impulse I_n [N s]")
    ax.set_ylabel("tangential impulse I_t [N s]")
    ax.set_title(f"{name}: impulse diagram (Routh)", fontsize=9)
    flagged = [r.label for r in records if r.source != ANALYTIC and not r.ok and not r.skipped]
    if flagged:
        ax.text(0.02, 0.02, "flagged by the engine: " + ", ".join(flagged), fontsize=7,
                transform=ax.transAxes, color="tab:red")
    return _save(figure, path, dpi=90, tag=tag)


def impulse_legend_figure(path: Path, tag: str | None = None) -> Path:
    """The key shared by every impulse diagram (drawn once, not on each diagram)."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=LAW_STYLE[law][0], ls=LAW_STYLE[law][1], lw=1.4,
                      label=f"{LAW_STYLE[law][2]}: impulse path")
               for law in ("poisson", "stronge", "newton")]
    handles += [Line2D([], [], ls="none", marker="D", markerfacecolor="none", ms=6,
                       markeredgewidth=1.5, markeredgecolor=LAW_STYLE[law][0],
                       label=f"{LAW_STYLE[law][2]}: end point")
                for law in ("stronge-paper", "newton-lcp")]
    for engine, (colour, marker) in ENGINE_STYLE.items():
        handles.append(Line2D([], [], ls="none", marker=marker, ms=7, markerfacecolor=colour,
                              markeredgecolor=colour, label=f"{engine} accurate"))
        handles.append(Line2D([], [], ls="none", marker=marker, ms=7, markerfacecolor="none",
                              markeredgecolor=colour, label=f"{engine} defaults"))
    handles += [Line2D([], [], color="0.75", ls=":", label="friction cone |I_t| = μ I_n"),
                Line2D([], [], color="tab:cyan", ls="--", label="v_n = 0 (end of compression)"),
                Line2D([], [], color="tab:olive", ls="--", label="v_t = 0 (slip stops)")]
    figure = _figure(9.5, 1.0)
    figure.legend(handles=handles, loc="center", ncol=4, fontsize=7.5, frameon=False)
    return _save(figure, path, dpi=90, tag=tag)


def type_boundaries(law_records: Sequence[Record]) -> list[tuple[float, int, int]]:
    """``(parameter value, type before, type after)`` where the Poisson type changes.

    The boundary lies somewhere between two sweep points; it is drawn midway.
    """
    points = sorted((r.point["value"], r.collision_type) for r in law_records
                    if r.law == "poisson" and r.ok and r.point.get("value") is not None)
    return [((a + b) / 2, ta, tb) for (a, ta), (b, tb) in zip(points, points[1:]) if ta != tb]


def sweep_figure(name: str, info: dict, records: Sequence[Record], path: Path, tag: str | None = None) -> Path | None:
    """Post-impact quantities against the swept parameter; laws lines, engines points."""
    sweep = info.get("sweep") or {}
    parameter = sweep.get("parameter", "parameter")
    laws = [r for r in records if r.source == ANALYTIC]
    engines = [r for r in records if r.source != ANALYTIC and r.u_after is not None]
    panels = [("vn_separation", "v_n after [m/s]"), ("vt_separation", "v_t after [m/s]"),
              ("energy_change", "energy change [J]")]
    if engines:
        panels.append(("departure", "engine departure from Poisson\n(0 drawn at 1e-16)"))
    figure = _figure(9.5, 5.6 if len(panels) > 3 else 3.2)
    grid = figure.subplots(2 if len(panels) > 3 else 1, 2 if len(panels) > 3 else 3,
                           squeeze=False)
    axes = grid.ravel()
    boundaries = type_boundaries(laws)
    for ax, (field, label) in zip(axes, panels):
        if field != "departure":
            for law in LAW_ORDER:
                subset = sorted((r.point["value"], getattr(r, field)) for r in laws
                                if r.law == law and r.ok)
                if subset:
                    colour, style, law_label = LAW_STYLE[law]
                    ax.plot(*zip(*subset), color=colour, ls=style, lw=1.3, label=law_label)
        for engine_label in dict.fromkeys(r.label for r in engines):
            subset = [r for r in engines if r.label == engine_label]
            engine, preset = engine_label.split(".")
            colour, marker = ENGINE_STYLE.get(engine, ("k", "x"))
            if field == "departure":  # exact agreement (0) drawn at the 1e-16 floor
                pts = [(r.point["value"], max(r.departure.get("poisson") or 0.0, 1e-16))
                       for r in subset if r.departure.get("poisson") is not None]
            else:
                pts = [(r.point["value"], getattr(r, field)) for r in subset]
            pts = [(x, y) for x, y in pts if y is not None and math.isfinite(y)]
            if pts:
                ax.plot(*zip(*pts), marker, ms=5, ls="none", label=engine_label,
                        markerfacecolor=colour if preset == "accurate" else "none",
                        markeredgecolor=colour)
        if field == "departure":
            ax.set_yscale("log")
        for value, before, after in boundaries:
            ax.axvline(value, color="0.6", lw=0.8, ls="--")
            ax.text(value, 1.0, f"{before}→{after}", transform=ax.get_xaxis_transform(),
                    ha="center", va="bottom", fontsize=7, color="0.35")
        ax.set_xlabel(parameter)
        ax.set_ylabel(label)
        ax.grid(True, color="0.93")
    handles, labels = axes[0].get_legend_handles_labels()
    for ax in axes[1:]:
        h, l = ax.get_legend_handles_labels()
        handles += h
        labels += l
    unique = dict(zip(labels, handles))
    figure.legend(unique.values(), unique.keys(), loc="outside lower center",
                  ncol=min(6, len(unique)), fontsize=7, frameon=False)
    figure.suptitle(f"{name}: sweep of {parameter} (dashed: Poisson type changes)", fontsize=9)
    return _save(figure, path, dpi=90, tag=tag)


# --------------------------------------------------------------------------------------------
# HTML
# --------------------------------------------------------------------------------------------
CSS = """
body{font-family:-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:0 auto;max-width:1280px;
padding:0 18px 40px;color:#222;line-height:1.45}
h1{font-size:1.7em;margin:.6em 0 .2em} h2{border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:1.6em}
h3{margin:1.4em 0 .3em} .lead{font-size:1.04em;max-width:62em}
.facts{color:#555;font-size:.92em} .facts b{color:#222}
table{border-collapse:collapse;font-size:.8em;margin:.4em 0 .8em}
th,td{border:1px solid #ddd;padding:2px 6px;text-align:right;white-space:nowrap}
th{background:#f4f4f4} td.l,th.l{text-align:left}
tr.engine td{background:#fbfbf6} tr.flag td{background:#fff1f0}
img{max-width:100%;height:auto} figure{margin:.6em 0} figcaption{font-size:.85em;color:#555}
.pair{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start}
.pair img.diagram{width:400px;max-width:100%}
.fail{color:#b00;font-weight:bold} .pass{color:#070} .muted{color:#777}
nav{font-size:.85em;columns:3} code{background:#f4f4f4;padding:0 3px}
details{margin:.3em 0 .8em} summary{cursor:pointer;color:#335}
"""


def _header_cell(text: str) -> str:
    """A header with its unit (``"v_x [m/s]"``) on a second line, to keep columns narrow."""
    name, bracket, unit = str(text).partition(" [")
    return _esc(name) + (f"<br><span class='muted'>[{_esc(unit)}</span>" if bracket else "")


def _table(header: Sequence[str], rows: Sequence[Sequence], left: int = 1,
           row_classes: Sequence[str] | None = None) -> str:
    out = ["<table><tr>" + "".join(
        f'<th class="l">{_header_cell(h)}</th>' if i < left else f"<th>{_header_cell(h)}</th>"
        for i, h in enumerate(header)) + "</tr>"]
    for k, row in enumerate(rows):
        cls = f' class="{row_classes[k]}"' if row_classes and row_classes[k] else ""
        out.append(f"<tr{cls}>" + "".join(
            f'<td class="l">{cell}</td>' if i < left else f"<td>{cell}</td>"
            for i, cell in enumerate(row)) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _sorted_point_records(records: Sequence[Record]) -> list[Record]:
    laws = sorted((r for r in records if r.source == ANALYTIC),
                  key=lambda r: LAW_ORDER.index(r.law) if r.law in LAW_ORDER else 99)
    from harness.scenarios import ENGINES, PRESETS

    engines = sorted((r for r in records if r.source != ANALYTIC),
                     key=lambda r: (PRESETS.index(r.preset) if r.preset in PRESETS else 9,
                                    ENGINES.index(r.source) if r.source in ENGINES else 9))
    return laws + engines


def velocity_table(records: Sequence[Record], speed_labels: Sequence[str]) -> str:
    """Post-impact speeds of every law and engine at one point, side by side."""
    ordered = _sorted_point_records(records)
    size = len(ordered[0].u_before) if ordered and ordered[0].u_before else len(speed_labels)
    labels = list(speed_labels) if len(speed_labels) == size else [f"u{i + 1}" for i in range(size)]
    header = ["source", *labels, "v_n after [m/s]", "v_t after [m/s]", "ΔE [J]", "type",
              "from Poisson", "from Stronge", "status"]
    rows, classes = [], []
    if ordered and ordered[0].u_before:
        rows.append(["<i>before</i>", *(fmt_number(v) for v in ordered[0].u_before),
                     fmt_number(ordered[0].vn_approach), fmt_number(ordered[0].vt_approach),
                     "", "", "", "", ""])
        classes.append("")
    for r in ordered:
        speeds = r.u_after or [None] * size
        name = (LAW_STYLE.get(r.law, (None, None, r.law))[2] if r.source == ANALYTIC
                else f"<b>{_esc(r.label)}</b>")
        status = _esc(r.status if len(r.status) < 60 else r.status[:57] + "…")
        rows.append([name, *(fmt_number(v) for v in speeds), fmt_number(r.vn_separation),
                     fmt_number(r.vt_separation), fmt_number(r.energy_change),
                     "–" if r.collision_type is None else str(r.collision_type),
                     fmt_departure(r.departure.get("poisson")),
                     fmt_departure(r.departure.get("stronge")),
                     status if r.status != "ok" else "ok"])
        classes.append("" if r.source == ANALYTIC else ("engine" if r.ok else "engine flag"))
    if all(r.ok for r in ordered):  # every status "ok": the column says nothing
        header, rows = header[:-1], [row[:-1] for row in rows]
    return _table(header, rows, row_classes=classes)


def scenario_section(name: str, info: dict, records: Sequence[Record], figures: dict) -> str:
    parts = [f'<div class="scenario" id="{_esc(slug(name))}">',
             f"<h3>{_esc(name)}</h3>"]
    tags = ", ".join(info.get("tags", []))
    parts.append(f"<p>{_esc(info.get('description', ''))} <span class='muted'>"
                 f"[{_esc(info.get('system', ''))}; tags: {_esc(tags)}]</span></p>")
    laws = [r for r in records if r.source == ANALYTIC and r.law == "poisson" and r.ok]
    if info.get("sweep"):
        if name in figures.get("sweep", {}):
            parts.append(f'<figure><img src="{FIGURES}/{figures["sweep"][name]}" '
                         f'alt="sweep of {_esc(name)}"></figure>')
        points = list(dict.fromkeys(r.point["index"] for r in records))
        types = " → ".join(str(r.collision_type) for r in sorted(laws, key=lambda r: r.point["index"]))
        parts.append(f"<p>Poisson types along the sweep: {_esc(types)}.</p>")
        parts.append(f"<details><summary>post-impact velocities at each of the {len(points)} "
                     "points</summary>")
        for index in points:
            subset = [r for r in records if r.point["index"] == index]
            parts.append(f"<p><b>{_esc(subset[0].point['label'])}</b></p>")
            parts.append(velocity_table(subset, info.get("speed_labels", [])))
        parts.append("</details>")
    else:
        if laws:
            d = laws[0].diagnostics or {}
            ctype = laws[0].collision_type
            parts.append(f"<p>Poisson: type {ctype} ({_esc(TYPE_NAMES.get(ctype, ''))}), "
                         f"Table 1 case {d.get('case')}; μ = {fmt_number(d.get('mu'))}, "
                         f"e = {fmt_number(d.get('e'))}.</p>")
        diagram = ""
        if name in figures.get("impulse", {}):
            diagram = (f'<img class="diagram" src="{FIGURES}/{figures["impulse"][name]}" '
                       f'alt="impulse diagram of {_esc(name)}">')
        parts.append(f'<div class="pair"><div>{velocity_table(records, info.get("speed_labels", []))}'
                     f"</div>{diagram}</div>")
    parts.append("</div>")
    return "\n".join(parts)


def markdown_to_html(text: str, heading_shift: int = 1) -> str:
    """The small Markdown subset the harness writes: headings, paragraphs, tables, images,
    lists, ``code`` and **bold**."""
    def inline(line: str) -> str:
        line = _esc(line)
        line = re.sub(r"!\[([^\]]*)\]\(([^)]+)\)", r'<img src="\2" alt="\1">', line)
        line = re.sub(r"\[([^\]]+)\]\(([^)]+)\)", r'<a href="\2">\1</a>', line)
        line = re.sub(r"`([^`]+)`", r"<code>\1</code>", line)
        return re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", line)

    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        line = lines[i]
        if not line.strip():
            i += 1
            continue
        heading = re.match(r"^(#+)\s+(.*)", line)
        if heading:
            level = min(6, len(heading.group(1)) + heading_shift)
            out.append(f"<h{level}>{inline(heading.group(2))}</h{level}>")
            i += 1
        elif line.startswith("|"):
            block = []
            while i < len(lines) and lines[i].startswith("|"):
                block.append([c.strip() for c in lines[i].strip().strip("|").split("|")])
                i += 1
            header, body = block[0], [r for r in block[1:] if not all(
                re.fullmatch(r":?-+:?", c) for c in r)]
            out.append(_table(header, [[inline(c) for c in r] for r in body]))
        elif re.match(r"^\s*[-*] ", line):
            items = []
            while i < len(lines) and re.match(r"^\s*[-*] ", lines[i]):
                item = re.sub(r"^\s*[-*] ", "", lines[i])
                items.append(f"<li>{inline(item)}</li>")
                i += 1
            out.append("<ul>" + "".join(items) + "</ul>")
        else:
            paragraph = []
            while i < len(lines) and lines[i].strip() and not re.match(r"^(#|\||\s*[-*] )",
                                                                       lines[i]):
                paragraph.append(lines[i])
                i += 1
            out.append(f"<p>{inline(' '.join(paragraph))}</p>")
    return "\n".join(out)


def _settings_table(provenance: dict) -> str:
    settings = provenance.get("engine_settings", {})
    parts = []
    for engine, presets in settings.items():
        names = list(presets)
        keys = list(dict.fromkeys(k for p in presets.values() for k in p))
        rows = []
        for key in keys:
            values = [presets[p].get(key) for p in names]
            cells = [_esc(json_short(v)) for v in values]
            if len(set(map(json_short, values))) > 1:
                cells = [f"<b>{c}</b>" for c in cells]
            rows.append([f"<code>{_esc(key)}</code>", *cells])
        version = provenance.get("engine_versions", {}).get(engine, "")
        parts.append(f"<h4>{_esc(engine)} {_esc(version)}</h4>")
        parts.append(_table(["setting", *names], rows))
    return "\n".join(parts) or "<p>No engine ran.</p>"


def json_short(value) -> str:
    import json

    if isinstance(value, float):
        return f"{value:.6g}"
    return json.dumps(value) if not isinstance(value, str) else value


def gates_html(provenance: dict) -> str:
    gates = provenance.get("gates", [])
    if not gates:
        return "<p>No scenario in this run declares a gate.</p>"
    rows = []
    for g in gates:
        cls = "fail" if g["status"] == "FAIL" else ("pass" if g["status"] == "pass" else "muted")
        rows.append([_esc(g["scenario"]), _esc(g["gate"]), _esc(g["record"]), _esc(g["law"]),
                     fmt_departure(g["departure"]), fmt_departure(g["max_departure"]),
                     f'<span class="{cls}">{_esc(g["status"])}</span>'])
    return _table(["scenario", "gate", "record", "law", "departure", "max", "result"], rows,
                  left=4)


def split_table(rows: Sequence[dict]) -> str:
    """Per scenario and engine.preset: the largest total, law part and solve part."""
    grouped: dict[tuple, list] = {}
    for row in rows:
        grouped.setdefault((row["scenario"], row["label"]), []).append(row)
    labels = list(dict.fromkeys(row["label"] for row in rows))
    scenarios = list(dict.fromkeys(row["scenario"] for row in rows))
    body = []
    for scenario in scenarios:
        law_part = max((r["law_part"] for r in rows if r["scenario"] == scenario
                        and math.isfinite(r["law_part"])), default=math.nan)
        cells = [_esc(scenario), fmt_departure(law_part)]
        for label in labels:
            group = grouped.get((scenario, label), [])
            solve = max((r["solve_part"] for r in group if math.isfinite(r["solve_part"])),
                        default=math.nan)
            cells.append(fmt_departure(solve))
        body.append(cells)
    return _table(["scenario", "law part (newton-lcp vs Poisson)",
                   *[f"solve: {label}" for label in labels]], body)


def versions_html(provenance: dict) -> str:
    versions = provenance.get("versions", {})
    git = provenance.get("git", {})
    machine = provenance.get("machine", {})
    cache = provenance.get("cache", {})
    rows = [[_esc(k), _esc(v if v is not None else "not installed")] for k, v in versions.items()]
    rows += [["git commit", _esc(f"{git.get('commit')}" + (" (uncommitted changes)"
                                                          if git.get("dirty") else ""))],
             ["code version", _esc(str(provenance.get("code_version", ""))[:16])],
             ["machine", _esc(f"{machine.get('platform')}, {machine.get('cpu_count')} cores")],
             ["results written", _esc(provenance.get("created_utc", ""))],
             ["command", f"<code>{_esc(' '.join(provenance.get('command', [])))}</code>"],
             ["engine runs", _esc(f"{cache.get('engine_runs')} ({cache.get('simulated')} "
                                  f"simulated, {cache.get('hits')} from the cache)")],
             ["run wall time", _esc(f"{provenance.get('wall_time_s', 0):.2f} s")]]
    for engine, reason in provenance.get("engines_missing", {}).items():
        rows.append([_esc(f"skipped {engine}"), _esc(reason)])
    return _table(["item", "value"], rows, left=2)


def write_html(results: Results, out_dir: Path, figures: dict, rows: Sequence[dict]) -> Path:
    prov = results.provenance
    names = results.scenario_names()
    gates = prov.get("gates", [])
    failed = [g for g in gates if g["status"] == "FAIL"]
    engine_records = [r for r in results.records if r.source != ANALYTIC]
    flagged = [r for r in engine_records if not r.ok and not r.skipped]
    skipped = [r for r in engine_records if r.skipped]
    labels = results.engine_labels()
    engines = sorted({label.split(".")[0] for label in labels})
    git = prov.get("git", {})
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             "<title>Planar impact with friction: engines against the exact laws</title>",
             f"<style>{CSS}</style></head><body>",
             "<h1>Planar impact with friction: physics engines against the exact laws</h1>"]
    parts.append(
        '<p class="lead">Every scenario here is one planar rigid-body impact with Coulomb '
        "friction (a disk, rod, box or polygon hitting the ground or another body). Each is "
        "solved exactly under five impact laws by <code>planar_impact</code> (Poisson's and "
        "Stronge's hypotheses after Djerassi 2009, Newton's, and the velocity-level "
        "<code>newton-lcp</code> law that sequential-impulse engines solve) and simulated by "
        f"the physics engines {_esc(', '.join(engines) or '(none)')} with their out-of-the-box "
        "<i>defaults</i> and with <i>accurate</i> settings. The <b>departure</b> of an engine "
        "from a law is the error of its post-impact velocities in the kinetic-energy norm, "
        "relative to the motion before the impact: ‖u<sub>engine</sub> − u<sub>law</sub>‖"
        "<sub>M</sub> / ‖u<sub>before</sub>‖<sub>M</sub> (0 = identical, 10% = a tenth of the "
        "motion is wrong).</p>")
    parts.append(
        f'<p class="facts"><b>{len(names)}</b> scenarios, <b>{len(results.records)}</b> '
        f"records; engine runs: <b>{len(engine_records)}</b> "
        f"({len(flagged)} flagged, {len(skipped)} skipped); gates: "
        + (f'<span class="fail">{len(failed)} of {len(gates)} FAILED</span>' if failed
           else f'<span class="pass">{len(gates)} passed</span>')
        + f"; commit <code>{_esc(str(git.get('commit'))[:10])}</code>, "
        f"{_esc(prov.get('created_utc', ''))}.</p>")
    if "heatmap" in figures:
        parts.append(
            f'<figure><img src="{FIGURES}/{figures["heatmap"]}" alt="departure heat map">'
            "<figcaption>Departure from Poisson (left pair) and from exact Stronge (right pair), "
            "engines out of the box (<i>defaults</i>) and tuned (<i>accurate</i>). Sweeps show "
            "their largest departure over the sweep. “!” marks a run the engine itself flagged "
            "(multi-contact, no separation …); grey cells were skipped. Light = agrees, dark "
            "red = far off.</figcaption></figure>")
    parts.append(
        "<p>Most of the departure of pymunk and pybullet is the <b>law</b>, not the solver: "
        "they solve <code>newton-lcp</code> (restitution as a target on the normal velocity, "
        "Coulomb friction at the end state), which differs from Poisson and Stronge wherever "
        "the slip stops or reverses during the impact. The next figure separates the two.</p>")
    parts.append("<nav><b>Contents</b><br><a href='#split'>Law vs solve</a><br>"
                 "<a href='#gates'>Gates</a><br><a href='#scenarios'>Scenarios</a><br>"
                 + "".join(f"&nbsp;&nbsp;<a href='#{_esc(slug(n))}'>{_esc(n)}</a><br>"
                           for n in names)
                 + "<a href='#table3'>Table 3 of the paper</a><br>"
                 "<a href='#versions'>Versions and settings</a></nav>")
    parts.append("<h2 id='split'>Why engines depart: the law they solve vs how well they "
                 "solve it</h2>")
    parts.append(
        "<p>Each point is one engine run. <b>Law part</b>: how far the engines' own law "
        "(<code>newton-lcp</code>) is from Poisson at that impact; <b>solve part</b>: how far "
        "the engine is from <code>newton-lcp</code>. The total departure from Poisson is at "
        "most their sum.</p>")
    if "split" in figures:
        parts.append(f'<figure><img src="{FIGURES}/{figures["split"]}" alt="departure split">'
                     "</figure>")
    if rows:
        parts.append("<details><summary>the numbers (largest over sweep points)</summary>"
                     + split_table(rows) + "</details>")
    parts.append("<h2 id='gates'>Gates</h2><p>Tolerance gates declared by the scenarios "
                 "(<code>[expect.gate]</code>); a failing gate makes <code>impact-harness "
                 "run</code> exit non-zero.</p>" + gates_html(prov))
    parts.append("<h2 id='scenarios'>Scenarios</h2><p>Per scenario: post-impact speeds of "
                 "every law and engine (engine rows shaded; red when the engine flagged the "
                 "run), contact velocities after the impact (v<sub>n</sub>, v<sub>t</sub>, in "
                 "the contact frame), energy change and collision type (Poisson/Stronge 1–5: "
                 + "; ".join(f"{k} {v}" for k, v in TYPE_NAMES.items())
                 + "; Newton laws and engines: 1 stick, 2 reverse slide, 3 forward slide). "
                 "The impulse diagram is Routh's graph (the paper's Fig. 1): the path of each "
                 "law's impulse and every end point; filled engine markers are "
                 "<i>accurate</i>, hollow <i>defaults</i>. Sweeps show post-impact "
                 "quantities against the swept parameter instead, laws as lines and engines "
                 "as points, with the points where the Poisson collision type changes "
                 "dashed.</p>")
    if "legend" in figures:
        parts.append(f'<figure><img src="{FIGURES}/{figures["legend"]}" '
                     'alt="key of the impulse diagrams"></figure>')
    for name in names:
        parts.append(scenario_section(name, results.scenarios.get(name, {}),
                                      results.for_scenario(name), figures))
    parts.append("<h2 id='table3'>Table 3 of the paper reproduced</h2>")
    paper = out_dir / "paper-table3.md"
    if paper.exists():
        parts.append("<p>From <a href='paper-table3.md'>paper-table3.md</a>, written by "
                     "<code>impact-harness paper</code>.</p>")
        parts.append(markdown_to_html(paper.read_text(encoding="utf-8"), heading_shift=2))
    else:
        parts.append("<p class='muted'>Not generated: run <code>impact-harness paper</code> "
                     "(or <code>impact-harness suite</code>).</p>")
    parts.append("<h2 id='versions'>Versions and settings</h2>" + versions_html(prov))
    parts.append("<h3>Engine settings per preset</h3><p>Bold where the presets differ. "
                 "Scenario files may override settings "
                 "(<code>[engine_settings.&lt;engine&gt;]</code>); the overrides are in each "
                 "record's diagnostics in <code>results.json</code>.</p>" + _settings_table(prov))
    parts.append(f"<p class='muted'>Report generated {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} "
                 "by <code>impact-harness report</code>.</p></body></html>")
    path = out_dir / "index.html"
    path.write_text("\n".join(parts), encoding="utf-8")
    return path


# --------------------------------------------------------------------------------------------
# Markdown summary
# --------------------------------------------------------------------------------------------
def write_summary(results: Results, out_dir: Path) -> Path:
    prov = results.provenance
    labels = results.engine_labels()
    lines = ["# Planar impact with friction: engines against the exact laws", "",
             "Departure of each engine (and preset) from the exact laws, "
             "`‖u_engine − u_law‖_M / ‖u_before‖_M` (relative error of the post-impact "
             "velocities in the kinetic-energy norm; sweeps: the largest over the sweep). "
             "`!` marks a run the engine flagged, `skipped` an engine that did not run. "
             "Figures, per-scenario tables and settings: [index.html](index.html); the "
             "paper's Table 3: [paper-table3.md](paper-table3.md).", ""]
    for law in HEADLINE_LAWS:
        names, values, flagged, skipped = departure_grid(results, law, labels)
        lines += [f"## Departure from {LAW_STYLE[law][2]}", "",
                  "| scenario | " + " | ".join(labels) + " |",
                  "|---|" + "---:|" * len(labels)]
        for i, name in enumerate(names):
            cells = ["skipped" if skipped[i, j] else
                     fmt_departure(values[i, j]) + (" !" if flagged[i, j] else "")
                     for j in range(len(labels))]
            lines.append(f"| {_row_name(results, name)} | " + " | ".join(cells) + " |")
        lines.append("")
    gates = prov.get("gates", [])
    lines += ["## Gates", ""]
    if gates:
        lines += ["| scenario | gate | record | law | departure | max | result |",
                  "|---|---|---|---|---:|---:|---|"]
        for g in gates:
            lines.append(f"| {g['scenario']} | {g['gate']} | {g['record']} | {g['law']} | "
                         f"{fmt_departure(g['departure'])} | {fmt_departure(g['max_departure'])}"
                         f" | {g['status']} |")
    else:
        lines.append("No gates in this run.")
    flagged = [r for r in results.records if r.source != ANALYTIC and not r.ok]
    lines += ["", "## Runs not ok", ""]
    lines += [f"- {r.scenario} {r.point['label']} {r.label}: {r.status}" for r in flagged] or [
        "None."]
    versions = prov.get("versions", {})
    git = prov.get("git", {})
    lines += ["", "## Versions", "",
              ", ".join(f"{k} {v}" for k, v in versions.items() if v is not None) + ".",
              f"Commit `{git.get('commit')}`" + (" (uncommitted changes)" if git.get("dirty")
                                                  else "")
              + f"; results written {prov.get('created_utc', '')}.", ""]
    path = out_dir / "summary.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    return path


# --------------------------------------------------------------------------------------------
# Entry points
# --------------------------------------------------------------------------------------------
def write_report(results: Results, out_dir: Path | str) -> dict:
    """Write index.html, summary.md and the figures; returns the paths written."""
    import matplotlib

    matplotlib.use("Agg")
    out_dir = Path(out_dir)
    figure_dir = out_dir / FIGURES
    figure_dir.mkdir(parents=True, exist_ok=True)
    figures: dict = {"impulse": {}, "sweep": {}}
    if _render("legend", figure_dir / "impulse-legend.png", [],
               lambda path, tag: impulse_legend_figure(path, tag)):
        figures["legend"] = "impulse-legend.png"
    stable = {name: [_stable(r) for r in results.for_scenario(name)]
              for name in results.scenario_names()}
    if _render("heatmap", figure_dir / "heatmap.png", stable,
               lambda path, tag: heatmap_figure(results, path, tag)):
        figures["heatmap"] = "heatmap.png"
    rows = split_rows(results)
    if _render("split", figure_dir / "split.png", rows,
               lambda path, tag: split_figure(rows, path, tag)):
        figures["split"] = "split.png"
    for name in results.scenario_names():
        records = results.for_scenario(name)
        info = results.scenarios.get(name, {})
        if info.get("sweep"):
            file = f"sweep-{slug(name)}.png"
            if _render("sweep", figure_dir / file, [name, info, stable[name]],
                       lambda path, tag: sweep_figure(name, info, records, path, tag)):
                figures["sweep"][name] = file
        else:
            file = f"impulse-{slug(name)}.png"
            if _render("impulse", figure_dir / file, [name, stable[name]],
                       lambda path, tag: impulse_figure(name, records, path, tag)):
                figures["impulse"][name] = file
    wanted = {figures.get("heatmap"), figures.get("split"), figures.get("legend"),
              *figures["impulse"].values(),
              *figures["sweep"].values()}
    for stale in figure_dir.glob("*.png"):  # figures of scenarios no longer in the results
        if stale.name not in wanted:
            stale.unlink()
    html_path = write_html(results, out_dir, figures, rows)
    summary = write_summary(results, out_dir)
    return {"html": html_path, "summary": summary, "figures": sorted(figure_dir / f for f in wanted if f)}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--results", type=Path, default=DEFAULT_RESULTS,
                        help=f"results file from `impact-harness run` (default: {DEFAULT_RESULTS})")
    parser.add_argument("--out", type=Path, default=Path("reports"),
                        help="output directory (default: reports)")


def main(args) -> int:
    try:
        results = read_results(args.results)
    except (FileNotFoundError, ValueError) as error:
        print(f"impact-harness report: {error}")
        return 2
    start = time.perf_counter()
    written = write_report(results, args.out)
    print(f"wrote {written['html']} and {written['summary']} with {len(written['figures'])} "
          f"figures in {time.perf_counter() - start:.1f} s")
    return 0


__all__ = ["add_arguments", "fmt_departure", "main", "markdown_to_html", "write_report"]
