"""The report's figures (matplotlib, Agg): the heat map, the impulse and sweep figures of a
scenario, the split figure. Each is drawn through the figure cache
(:mod:`harness.report.figure_cache`), which redraws it only when its inputs change.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from harness.engines import engine_names, preset_label
from harness.laws import PROCESS_LAWS
from harness.plotting import (  # shared with the survey's figures
    new_figure,
    percent_axis,
    save_png,
)
from harness.report.views import (
    HEADLINE_LAWS,
    HEAT_MAX,
    HEAT_MIN,
    LAW_ORDER,
    LAW_STYLE,
    X_FLOOR,
    departure_cell,
    departure_grid,
    engine_labels,
    engine_roles,
    engine_scenarios,
    engine_style,
    flagged_count,
    fmt_departure,
    label_records,
    parameter_name,
    row_name,
    single_contact,
)
from harness.run.records import ANALYTIC, Record, Results
from planar_impact import impulse_process


def offset_transform(ax, index: int, count: int, step_points: float = 4.0):
    """Data coordinates shifted sideways by ``step_points`` per engine, so that engines
    landing on the same point are drawn side by side; the values themselves are unchanged."""
    from matplotlib.transforms import offset_copy

    shift = (index - (count - 1) / 2) * step_points
    return offset_copy(ax.transData, fig=ax.figure, x=shift, y=0.0, units="points")


FLAG_STYLE = {"marker": "o", "markerfacecolor": "none", "markeredgecolor": "red",
              "markeredgewidth": 1.4, "ms": 12}  # a red ring around a run the engine flagged

def heatmap_figure(results: Results, path: Path, tag: str | None = None,
                   groups: dict[str, list[str]] | None = None) -> Path | None:
    """Departure from Poisson and from Stronge: scenario × engine, one panel per law × preset.

    With ``groups`` (``{family: scenario names}``, the report of many scenarios) a row is a
    family instead of a scenario: its colour is the median over the family's scenarios of
    each scenario's largest departure, its text ``median / max``, and ``(k!)`` counts the
    flagged runs of the whole family (none of them in a value).
    """
    from matplotlib.colors import LogNorm

    labels = engine_labels(results)
    if not labels:
        return None
    roles = engine_roles(results)  # parallel to labels: a panel per preset role
    presets = list(dict.fromkeys(role for _, role in roles))
    names = engine_scenarios(results)
    if groups is not None:
        present = set(names)
        groups = {family: [n for n in members if n in present]
                  for family, members in groups.items()}
        groups = {family: members for family, members in groups.items() if members}
        rows = [f"{family} ({len(members)})" for family, members in groups.items()]
    else:
        rows = [row_name(results, n) for n in names]
    if not rows:
        return None
    panels = [(law, preset) for law in HEADLINE_LAWS for preset in presets]
    # each scenario's runs by label once (a scan of its records per cell was most of the time)
    grouped = {name: label_records(results.for_scenario(name)) for name in names}
    if groups is None:  # the panels side by side
        figure = new_figure(2.6 + 1.15 * len(labels) * len(HEADLINE_LAWS), 1.8 + 0.3 * len(rows))
        axes = figure.subplots(1, len(panels), sharey=True, squeeze=False)[0]
    else:  # wider cells ("median / max"): a row of panels per law
        figure = new_figure(2.6 + 1.8 * len(labels), 2 * (1.2 + 0.3 * len(rows)))
        axes = figure.subplots(len(HEADLINE_LAWS), len(presets), sharey=True,
                               squeeze=False).ravel()
    norm = LogNorm(vmin=HEAT_MIN, vmax=HEAT_MAX)
    cmap = heat_cmap()
    image = None
    for ax, (law, preset) in zip(axes, panels):
        panel_labels = [label for label, (_, role) in zip(labels, roles) if role == preset]
        _, values, flagged, skipped = departure_grid(results, law, panel_labels, names,
                                                     grouped)
        if groups is not None:
            values, flagged, skipped, texts = family_cells(grouped, groups, names, values,
                                                           skipped, panel_labels)
        else:
            texts = [[("skipped" if skipped[i, j] else "n/a") if skipped[i, j]
                      or not np.isfinite(values[i, j])
                      else departure_cell(grouped[name].get(label, []), law)
                      for j, label in enumerate(panel_labels)] for i, name in enumerate(names)]
        shown = np.where(np.isfinite(values), np.clip(values, HEAT_MIN, HEAT_MAX), np.nan)
        image = ax.imshow(np.ma.masked_invalid(shown), cmap=cmap, norm=norm, aspect="auto")
        for i in range(len(rows)):
            for j in range(len(panel_labels)):
                colour = ("0.35" if skipped[i, j] or not np.isfinite(values[i, j])
                          else "white" if values[i, j] > 0.08 else "black")
                ax.text(j, i, texts[i][j], ha="center", va="center", fontsize=9,
                        color=colour, fontweight="bold" if flagged[i, j] else "normal")
        ax.set_xticks(range(len(panel_labels)), [label.split(".")[0] for label in panel_labels],
                      fontsize=9.5)
        ax.xaxis.tick_top()
        ax.set_title(f"from {LAW_STYLE[law][2]} — {role_title(preset, roles)}", fontsize=11,
                     pad=18)
        ax.set_yticks(range(len(rows)), rows, fontsize=9.5)
        ax.tick_params(length=0)
    # Short label: the colour bar can be as short as one row (the caption gives the formula).
    bar = figure.colorbar(image, ax=list(axes), shrink=1.0 if len(rows) < 8 else 0.6,
                          pad=0.01, label="departure [%]")
    percent_axis(bar.ax.yaxis)
    return save_png(figure, path, dpi=110, tag=tag)


def family_cells(grouped: dict[str, dict[str, list[Record]]], groups: dict[str, list[str]],
                 names: Sequence[str], values: np.ndarray, skipped: np.ndarray,
                 labels: Sequence[str]):
    """Per family (rows of :func:`heatmap_figure` with ``groups``): the median of the
    scenarios' values, flagged and skipped cells, and the texts ``median / max (k!)``;
    ``grouped``: each scenario's engine runs by label (:func:`views.label_records`)."""
    row = {name: i for i, name in enumerate(names)}
    shape = (len(groups), len(labels))
    medians = np.full(shape, np.nan)
    flagged = np.zeros(shape, dtype=bool)
    all_skipped = np.zeros(shape, dtype=bool)
    texts = []
    for g, members in enumerate(groups.values()):
        index = [row[name] for name in members]
        line = []
        for j, label in enumerate(labels):
            column = values[index, j]
            finite = column[np.isfinite(column)]
            all_skipped[g, j] = bool(skipped[index, j].all())
            count = sum(flagged_count(grouped[name].get(label, [])) for name in members)
            flagged[g, j] = count > 0
            if finite.size:
                medians[g, j] = float(np.median(finite))
                text = f"{fmt_departure(medians[g, j])} / {fmt_departure(float(finite.max()))}"
            else:
                text = "skipped" if all_skipped[g, j] else "n/a"
            line.append(text + (f" ({count}!)" if count else ""))
        texts.append(line)
    return medians, flagged, all_skipped, texts


def role_title(role: str, pairs) -> str:
    """A preset role as a panel title, with the engines' own names for it:
    ``"accurate (mujoco: matched-bounce)"``."""
    renamed = [f"{engine}: {preset_label(engine, role)}" for engine, r in pairs
               if r == role and preset_label(engine, role) != role]
    return f"{role} ({', '.join(renamed)})" if renamed else role


def heat_cmap():
    from matplotlib import colormaps

    return colormaps["YlOrRd"].with_extremes(bad="0.92")


#: Above this many points of one engine in a panel of the split figure, its markers are an
#: image in the SVG twin (``rasterized``): at 1,000 scenarios, 16,000 vector markers took half
#: the figure's time to write and made an SVG of megabytes.
RASTER_POINTS = 500


def split_figure(rows: Sequence[dict], path: Path, tag: str | None = None) -> Path | None:
    """Law part vs solve part of every engine record, log–log, one panel per preset."""
    if not rows:
        return None
    presets = list(dict.fromkeys(row["preset"] for row in rows))
    floor = 1e-12
    figure = new_figure(4.6 * len(presets), 4.2)
    axes = figure.subplots(1, len(presets), sharex=True, sharey=True, squeeze=False)[0]
    for ax, preset in zip(axes, presets):
        for engine in engine_names():
            colour, marker = engine_style(engine)
            subset = [r for r in rows if r["preset"] == preset and r["engine"] == engine
                      and math.isfinite(r["law_part"]) and math.isfinite(r["solve_part"])]
            if not subset:
                continue
            x = np.maximum([r["law_part"] for r in subset], X_FLOOR)
            y = np.maximum([r["solve_part"] for r in subset], floor)
            flagged = np.array([r["status"] != "ok" for r in subset])
            # Thousands of markers: an image in the SVG twin (its axes and text stay vector),
            # which otherwise took half the figure's time to write; the PNG is the same.
            dense = len(subset) > RASTER_POINTS
            ax.scatter(x[~flagged], y[~flagged], s=22, marker=marker, color=colour, alpha=0.75,
                       label=engine, edgecolors="none", rasterized=dense)
            if flagged.any():
                ax.scatter(x[flagged], y[flagged], s=40, marker=marker, facecolors="none",
                           edgecolors="red", linewidths=1.2, label="flagged by the engine",
                           rasterized=dense)
        ax.plot([floor, 10], [floor, 10], color="0.5", lw=0.8, ls="--")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(1e-4, 3)
        ax.set_ylim(floor / 3, 3)
        ax.axhline(1e-6, color="0.8", lw=0.6)
        ax.axvline(X_FLOOR, color="0.85", lw=0.6)
        ax.set_xlabel("law part: newton-lcp vs Poisson [%]")
        percent_axis(ax.xaxis)
        percent_axis(ax.yaxis)
        pairs = {(r["engine"], r["preset"]) for r in rows}
        ax.set_title(role_title(preset, sorted(pairs)), fontsize=11)
        ax.grid(True, which="major", color="0.93")
    axes[0].set_ylabel("solve part: engine vs newton-lcp [%]")
    figure.suptitle("Above the dashed diagonal the solve (engine vs its own law) dominates, "
                    "below it the law. Values below the axes' ends are drawn at them.",
                    fontsize=10)
    handles = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    flag = handles.pop("flagged by the engine", None)
    if flag is not None:  # last in the key
        handles["flagged by the engine"] = flag
    axes[-1].legend(handles.values(), handles.keys(), loc="center left",
                    bbox_to_anchor=(1.01, 0.5), fontsize=9, frameon=False)
    return save_png(figure, path, tag=tag)


def impulse_figure(name: str, records: Sequence[Record], path: Path,
                   tag: str | None = None) -> Path | None:
    """Routh's graph (Fig. 1): I_t against I_n, each law's path and every end point."""
    laws = [r for r in records if r.source == ANALYTIC and r.ok]
    if not laws:
        return None
    d = laws[0].diagnostics or {}
    mnn, mnt, mtt, mu, e = (d.get(k) for k in ("mnn", "mnt", "mtt", "mu", "e"))
    vn, vt = laws[0].vn_approach, laws[0].vt_approach
    engine_labels_here = {r.label for r in records if r.source != ANALYTIC}
    key_rows = (len(engine_labels_here) + 8) // 2  # laws, end points, Routh's lines, ring
    figure = new_figure(5.2, 3.6 + 0.2 * key_rows)
    ax = figure.subplots()
    extent = max([abs(r.normal_impulse) for r in records if r.normal_impulse is not None
                  and math.isfinite(r.normal_impulse)] + [1e-12])
    for law in PROCESS_LAWS:
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
    drawn = [r for r in records if r.source != ANALYTIC and r.normal_impulse is not None
             and r.tangential_impulse is not None and math.isfinite(r.normal_impulse)
             and math.isfinite(r.tangential_impulse)]
    ys_all = [abs(r.tangential_impulse) for r in drawn] + [mu * extent]
    for r, index, count in coincident_groups(
            drawn, lambda r: (r.normal_impulse, r.tangential_impulse),
            (0.02 * extent, 0.02 * max(ys_all + [1e-12]))):
        colour, marker = engine_style(r.source)
        filled = r.preset == "accurate"
        transform = offset_transform(ax, index, count, step_points=6.0)
        ax.update_datalim([(r.normal_impulse, r.tangential_impulse)])
        ax.plot([r.normal_impulse], [r.tangential_impulse], marker, ms=7, zorder=5,
                markerfacecolor=colour if filled else "none", markeredgecolor=colour,
                transform=transform, label=r.label)
        if not r.ok:
            ax.plot([r.normal_impulse], [r.tangential_impulse], zorder=7, ls="none",
                    transform=transform, **FLAG_STYLE)
    # Routh's lines: compression ends (v_n = 0) and sticking (v_t = 0), and the cone.
    x = np.linspace(0.0, 1.15 * extent, 50)
    ax.plot(x, mu * x, color="0.75", lw=0.8, ls=":")
    ax.plot(x, -mu * x, color="0.75", lw=0.8, ls=":", label="friction cone |I_t| = μ I_n")
    if abs(mnt) > 1e-14 * mnn:
        ax.plot(x, -(vn + mnn * x) / mnt, color="tab:cyan", lw=0.8, ls="--",
                label="v_n = 0 (end of compression)")
    else:
        ax.axvline(-vn / mnn, color="tab:cyan", lw=0.8, ls="--",
                   label="v_n = 0 (end of compression)")
    ax.plot(x, -(vt + mnt * x) / mtt, color="tab:olive", lw=0.8, ls="--",
            label="v_t = 0 (slip stops)")
    ys = [r.tangential_impulse for r in records if r.tangential_impulse is not None
          and math.isfinite(r.tangential_impulse)]
    span = max([abs(y) for y in ys] + [mu * extent, 0.1 * extent])
    ax.set_ylim(-1.25 * span, 1.25 * span)
    ax.set_xlim(0, 1.15 * extent)
    ax.axhline(0, color="0.85", lw=0.6)
    ax.set_xlabel("normal impulse I_n [N s]")
    ax.set_ylabel("tangential impulse I_t [N s]")
    ax.set_title(f"{name}: impulse diagram (Routh)", fontsize=11)
    impulse_key(figure, ax, flagged=any(not r.ok for r in drawn))
    return save_png(figure, path, dpi=90, tag=tag)


def impulse_key(figure, ax, flagged: bool) -> None:
    """The diagram's own key, below the axes (outside the data): what this diagram draws,
    each label once (engines at the same point each draw their marker), and the red ring
    when a run here is flagged, so that the PNG reads on its own (the page has no shared
    key)."""
    from matplotlib.lines import Line2D

    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles))
    if flagged:
        unique["flagged by the engine"] = Line2D([], [], ls="none", **FLAG_STYLE)
    figure.legend(unique.values(), unique.keys(), loc="outside lower center", ncols=2,
                  fontsize=8.5, frameon=False, handlelength=1.6, columnspacing=1.0)


def coincident_groups(records, position, tolerance):
    """``(record, index, count)``: records whose positions lie within ``tolerance`` (per
    coordinate) of an earlier one share a group, and get consecutive indexes in it, so that
    :func:`offset_transform` can draw them side by side."""
    groups: list[tuple[tuple, list]] = []
    for record in records:
        x, y = position(record)
        for (gx, gy), members in groups:
            if abs(x - gx) <= tolerance[0] and abs(y - gy) <= tolerance[1]:
                members.append(record)
                break
        else:
            groups.append(((x, y), [record]))
    return [(record, index, len(members)) for _, members in groups
            for index, record in enumerate(members)]


def type_boundaries(law_records: Sequence[Record]) -> list[tuple[float, int, int]]:
    """``(parameter value, type before, type after)`` where the Poisson type changes.

    The boundary lies somewhere between two sweep points; it is drawn midway.
    """
    points = sorted((r.point["value"], r.collision_type) for r in law_records
                    if r.law == "poisson" and r.ok and r.point.get("value") is not None)
    return [((a + b) / 2, ta, tb) for (a, ta), (b, tb) in itertools.pairwise(points)
            if ta != tb]


DEPARTURE_FLOOR = 1e-16  # exact agreement drawn here on the log axis (1e-14%)


#: A sweep whose positive values span at least this factor is drawn on a logarithmic axis
#: (the tilts 0.01° … 3°: on a linear one, four of six points share the first 1%).
LOG_SWEEP_SPAN = 100.0


def log_sweep_axis(values: Sequence[float]) -> bool:
    """Whether a sweep over ``values`` is drawn on a logarithmic axis: all positive and
    spanning :data:`LOG_SWEEP_SPAN` or more."""
    values = [float(v) for v in values if v is not None]
    return bool(values) and min(values) > 0 and max(values) >= LOG_SWEEP_SPAN * min(values)


def sweep_figure(name: str, info: dict, records: Sequence[Record], path: Path,
                 tag: str | None = None) -> Path | None:
    """Post-impact quantities against the swept parameter; laws lines, engines points."""
    sweep = info.get("sweep") or {}
    parameter = sweep.get("parameter", "parameter")
    log_x = log_sweep_axis(sweep.get("values") or [r.point["value"] for r in records])
    laws = [r for r in records if r.source == ANALYTIC]
    engines = [r for r in records if r.source != ANALYTIC and r.u_after is not None]
    panels = [("vn_separation", "v_n after [m/s]"), ("vt_separation", "v_t after [m/s]"),
              ("energy_change", "energy change [J]")]
    # a flat face's or a tilt's runs depart from their own reference (its primary), not
    # from the single-contact laws, which their records do not hold
    own = {id(r): ("poisson" if single_contact(r) else
                   ((r.diagnostics or {}).get("reference") or {}).get("primary"))
           for r in engines}
    if engines:
        against = ("Poisson" if set(own.values()) == {"poisson"} else "its reference"
                   if len(set(own.values())) > 1 else str(next(iter(own.values()))))
        panels.append(("departure", f"engine departure from {against} [%]\n"
                                    "(0 drawn at 1e-14%)"))
    figure = new_figure(9.5, 5.6 if len(panels) > 3 else 3.2)
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
        points = []  # (record, x, y) of every engine run drawn on this panel
        for r in engines:
            if field == "departure":  # exact agreement (0) drawn at the DEPARTURE_FLOOR
                value = r.departure.get(own[id(r)]) if own[id(r)] else None
                y = None if value is None else max(value, DEPARTURE_FLOOR)
            else:
                y = getattr(r, field)
            if y is not None and math.isfinite(y):
                points.append((r, r.point["value"], y))
        position = {id(r): (x, y) for r, x, y in points}
        if field == "departure":  # log axis: coincide = within 1% of a decade
            def key(r, position=position):
                return position[id(r)][0], math.log10(position[id(r)][1])
            tolerance = (1e-9, 0.01)
        else:  # coincide = within 1% of the panel's range
            def key(r, position=position):
                return position[id(r)]
            y_span = float(np.ptp([y for _, _, y in points])) if points else 0.0
            tolerance = (1e-9, 0.01 * (y_span or 1.0))
        groups = coincident_groups([r for r, _, _ in points], key, tolerance)
        for r, index, count in groups:
            x, y = position[id(r)]
            colour, marker = engine_style(r.source)
            transform = offset_transform(ax, index, count, step_points=4.0)
            ax.update_datalim([(x, y)])  # shifted artists do not count for autoscaling
            ax.plot([x], [y], marker, ms=5, ls="none", label=r.label, transform=transform,
                    markerfacecolor=colour if r.preset == "accurate" else "none",
                    markeredgecolor=colour)
            if not r.ok:
                ax.plot([x], [y], ls="none", transform=transform, label="flagged by the engine",
                        **{**FLAG_STYLE, "ms": 10})
        ax.autoscale_view()
        if log_x:
            ax.set_xscale("log")
        if field == "departure" and points:  # a log axis needs a value to scale
            ax.set_yscale("log")
            percent_axis(ax.yaxis)
        for value, before, after in boundaries:
            ax.axvline(value, color="0.6", lw=0.8, ls="--")
            ax.text(value, 1.0, f"{before}→{after}", transform=ax.get_xaxis_transform(),
                    ha="center", va="bottom", fontsize=9, color="0.35")
        ax.set_xlabel(parameter_name(parameter))
        ax.set_ylabel(label)
        ax.grid(True, color="0.93")
    handles, labels = axes[0].get_legend_handles_labels()
    for ax in axes[1:]:
        panel_handles, panel_labels = ax.get_legend_handles_labels()
        handles += panel_handles
        labels += panel_labels
    unique = dict(zip(labels, handles))
    figure.legend(unique.values(), unique.keys(), loc="outside lower center",
                  ncol=min(4, len(unique)), fontsize=9, frameon=False)
    figure.suptitle(f"{name}: sweep of {parameter_name(parameter)} (dashed: Poisson type "
                    "changes)", fontsize=11)
    return save_png(figure, path, dpi=90, tag=tag)
