"""The contact in time: each engine's impact step by step against the laws' impulse process.

The paper's Fig. 1 draws the contact velocities along the impulse process, with the
accumulated normal impulse ``P`` as the clock: inside each phase ``v_n`` and ``v_t`` are
straight lines in ``P`` (docs/theory.md, 'Routh's diagram and collision types'; the law's
path is :func:`planar_impact.impulse_process`). :func:`history_figure` draws the same axes
with every engine run of a single-point scenario as the points it passed through, one per
engine step (the record's ``diagnostics["history"]``, :mod:`harness.run.history`): a
sequential-impulse engine jumps to its end in one or two steps, MuJoCo's soft contact walks
the path in tens of steps, and the third panel shows how deep each engine let the bodies
overlap on the way.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from pathlib import Path

from harness.laws import PROCESS_LAWS  # drawn as paths (the others end off the process)
from harness.plotting import new_figure, save_png
from harness.report.views import LAW_STYLE, engine_style
from harness.run.records import ANALYTIC, Record
from planar_impact import impulse_process


def history_records(records: Sequence[Record]) -> list[Record]:
    """The engine records with a stored history of one contact point (drawable runs)."""
    drawn = []
    for record in records:
        diagnostics = record.diagnostics or {}
        history = diagnostics.get("history")
        if (record.source != ANALYTIC and history and history.get("normal_impulse")
                and diagnostics.get("max_contact_points") == 1):
            drawn.append(record)
    return drawn


def history_inputs(name: str, records_digest: str) -> list:
    """What the figure depends on (for :func:`harness.report.figure_cache.render_once`): this
    module and the scenario's records (their digest,
    :func:`harness.report.figure_cache.scenario_digests`)."""
    source = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()
    return [name, source, records_digest]


def history_figure(name: str, records: Sequence[Record], path: Path,
                   tag: str | None = None) -> Path | None:
    """``v_n`` and ``v_t`` against the accumulated normal impulse, each law's path and every
    engine's steps; the penetration per step beside them. ``None`` when no engine run of the
    scenario has a single-contact history."""
    runs = history_records(records)
    laws = [r for r in records if r.source == ANALYTIC and r.ok]
    if not runs or not laws:
        return None
    d = laws[0].diagnostics or {}
    mnn, mnt, mtt, mu, e = (d.get(k) for k in ("mnn", "mnt", "mtt", "mu", "e"))
    vn_approach, vt_approach = laws[0].vn_approach, laws[0].vt_approach
    figure = new_figure(10.5, 3.3)
    ax_vn, ax_vt, ax_depth = figure.subplots(1, 3)
    for law in PROCESS_LAWS:
        if not any(r.law == law for r in laws):
            continue
        colour, style, label = LAW_STYLE[law]
        try:
            process = impulse_process(mnn, mnt, mtt, vn_approach, vt_approach, mu, e, law)
        except ValueError:  # a jam: the law has no path to draw
            continue
        impulses = [vertex.normal_impulse for vertex in process.path]
        ax_vn.plot(impulses, [v.vn for v in process.path], color=colour, ls=style, lw=1.3,
                   label=label, zorder=2)
        ax_vt.plot(impulses, [v.vt for v in process.path], color=colour, ls=style, lw=1.3,
                   zorder=2)
    for record in runs:
        history = record.diagnostics["history"]
        colour, marker = engine_style(record.source)
        accurate = record.preset == "accurate"
        style = {"color": colour, "marker": marker, "ms": 4.5 if accurate else 6,
                 "markerfacecolor": colour if accurate else "none", "lw": 1.0,
                 "ls": "-" if accurate else "--", "zorder": 4 if accurate else 3}
        steps = history["contact_steps"]
        label = (f"{record.label} ({steps} step{'s' if steps != 1 else ''}, "
                 f"{history['source']})")
        impulses = history["normal_impulse"]
        ax_vn.plot(impulses, history["vn"], label=label, **style)
        ax_vt.plot(impulses, history["vt"], **style)
        ax_depth.plot(impulses, [1e3 * depth for depth in history["penetration"]], **style)
    for ax in (ax_vn, ax_vt):
        ax.axhline(0.0, color="0.6", lw=0.8, zorder=1)
        ax.set_xlabel("accumulated normal impulse P [N s]")
    ax_vn.set_ylabel("v_n [m/s]")
    ax_vt.set_ylabel("v_t [m/s]")
    ax_depth.set_xlabel("accumulated normal impulse P [N s]")
    ax_depth.set_ylabel("penetration [mm]")
    ax_vn.set_title("normal contact velocity (compression ends at 0)", fontsize=11)
    ax_vt.set_title("tangential contact velocity (sticking at 0)", fontsize=11)
    ax_depth.set_title("deepest overlap per step", fontsize=11)
    handles, labels = ax_vn.get_legend_handles_labels()
    columns = max(1, math.ceil(len(labels) / 4))
    figure.legend(handles, labels, loc="outside lower center", ncols=min(columns, 4),
                  fontsize=9, frameon=False)
    figure.suptitle(f"{name}: the contact step by step (filled: accurate, hollow: defaults)",
                    fontsize=11)
    return save_png(figure, path, tag=tag)


__all__ = ["history_figure", "history_inputs", "history_records"]
