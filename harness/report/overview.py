"""The overview sections at the top of ``index.html``, each made of every scenario's runs:
the headline departures as coloured tables (one row per scenario), what each engine and
preset solves ("Why"), the law-vs-solve split, the gates, and the page's counts."""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Sequence

import numpy as np

from harness.engines import preset_label, source_label
from harness.report.fragments import Prepared, split_order
from harness.report.markup import html_table
from harness.report.views import (
    HEADLINE_LAWS,
    HEAT_MAX,
    HEAT_MIN,
    LAW_STYLE,
    engine_roles,
    engine_why,
    escape_html,
    fmt_departure,
    fmt_overrides,
    preset_why,
    record_label,
    run_notes,
    slug,
    split_overrides,
)
from harness.run.records import ANALYTIC, Record, Results


def record_counts(results: Results) -> list[int]:
    """``[records, engine runs, flagged engine runs, skipped engine runs]``, as the page's
    facts line counts them."""
    engine_records = [r for r in results.records if r.source != ANALYTIC]
    return [len(results.records), len(engine_records),
            sum(not r.ok and not r.skipped for r in engine_records),
            sum(r.skipped for r in engine_records)]


#: The heat map's colours (:func:`harness.report.figures.heat_cmap`, ColorBrewer's YlOrRd as
#: matplotlib defines it): the nine RGB stops, spread evenly over [0, 1].
HEAT_STOPS = (
    (1.0, 1.0, 0.8),
    (1.0, 0.92941176470588238, 0.62745098039215685),
    (0.99607843137254903, 0.85098039215686272, 0.46274509803921571),
    (0.99607843137254903, 0.69803921568627447, 0.29803921568627451),
    (0.99215686274509807, 0.55294117647058827, 0.23529411764705882),
    (0.9882352941176471, 0.30588235294117649, 0.16470588235294117),
    (0.8901960784313725, 0.10196078431372549, 0.10980392156862745),
    (0.74117647058823533, 0.0, 0.14901960784313725),
    (0.50196078431372548, 0.0, 0.14901960784313725),
)
HEAT_LEVELS = 256  # entries of the colour map's table, as matplotlib's


def heat_colours(values: np.ndarray) -> np.ndarray:
    """``(..., 3)`` integer RGB (0-255) of departures on the heat map's colour scale: the
    colours matplotlib gives them (``heat_cmap()(LogNorm(HEAT_MIN, HEAT_MAX)(values))``,
    NaN drawn as ``HEAT_MIN``), computed as it does, without importing it (a warm report
    draws nothing, and matplotlib was a tenth of its time).
    """
    stops = np.asarray(HEAT_STOPS)
    x = np.linspace(0.0, 1.0, len(stops))
    grid = np.linspace(0.0, 1.0, HEAT_LEVELS)
    ind = np.searchsorted(x, grid)[1:-1]
    distance = (grid[1:-1] - x[ind - 1]) / (x[ind] - x[ind - 1])
    table = np.concatenate([stops[:1], distance[:, None] * (stops[ind] - stops[ind - 1])
                            + stops[ind - 1], stops[-1:]])
    table = np.clip(table, 0.0, 1.0)
    clipped = np.clip(np.nan_to_num(values, nan=HEAT_MIN), HEAT_MIN, HEAT_MAX)
    ends = np.log10(np.array([HEAT_MIN, HEAT_MAX], dtype=float))
    level = (np.log10(np.asarray(clipped, dtype=float)) - ends[0]) / (ends[1] - ends[0])
    level = level * HEAT_LEVELS
    level[level == HEAT_LEVELS] = HEAT_LEVELS - 1
    return np.rint(255 * table[level.astype(int)]).astype(int)


def departure_table_html(names: Sequence[str], prepared: Prepared) -> str:
    """The headline heat map's cells as an HTML table (one row per scenario, linked to its
    section), coloured as the figure: cheap at any number of rows, where an image is not.
    The cells are the scenarios' views (:func:`harness.report.fragments.scenario_view`)."""
    labels = prepared.labels
    if not labels:
        return ""
    header = ["scenario"] + [f"{LAW_STYLE[law][2]}: {label}" for law in HEADLINE_LAWS
                             for label in labels]
    rows = [[f"<a href='#{escape_html(slug(name))}'>{escape_html(name)}</a>"]
            for name in names]
    for law in HEADLINE_LAWS:
        cells = [prepared.views[name][law] for name in names]
        values = np.array([[cell[0] for cell in row] for row in cells], dtype=float)
        values = values.reshape(len(names), len(labels))
        rgb = heat_colours(values)  # all cells at once (a call per cell was most of the time)
        for i, row in enumerate(cells):
            for j, (value, flagged, skipped, text) in enumerate(row):
                if skipped or not math.isfinite(value):  # "skipped", "flagged (2!)"
                    kind = "heat flagged" if flagged else "muted"
                    rows[i].append(f"<span class='{kind}'>{escape_html(text)}</span>")
                    continue
                colour = "#{:02x}{:02x}{:02x}".format(*rgb[i, j])
                ink = "#000" if flagged or value <= 0.08 else "#fff"  # as on the figure
                text = escape_html(text)
                if flagged:  # hatched as on the figure: some runs are not in the value
                    text = f"<b>{text}</b>"
                rows[i].append(f"<span class='heat{' flagged' if flagged else ''}' "
                               f"style='background-color:{colour};color:{ink}'>{text}</span>")
    return html_table(header, rows)


def cached_departure_table(names: Sequence[str], prepared: Prepared) -> str:
    """:func:`departure_table_html`, kept in the report's cache under its scenarios' names
    and records digests (a family's table changes only with its scenarios' records)."""
    inputs = json.dumps([[name, prepared.digests.get(name, "")] for name in names])
    key = f"departures\0{hashlib.sha256(inputs.encode()).hexdigest()}"
    return prepared.cache.get(key, lambda: departure_table_html(names, prepared))


def why_html(results: Results) -> str:
    """Per engine and preset present: the law it solves, its biases, the settings that
    matter, and the notes its runs carry (with how many runs carry each)."""
    roles = engine_roles(results)
    command = (results.provenance or {}).get("settings_overrides") or {}
    given = {engine: values for engine, values in command.items() if values}
    labels = [source_label(engine, role) for engine, role in roles]
    engines = list(dict.fromkeys(engine for engine, _ in roles))
    if not engines:
        return "<p>No engine ran.</p>"
    runs_of: dict[str, list[Record]] = {}  # one pass: a scan of every record per label was slow
    for record in results.records:
        if record.source != ANALYTIC:
            runs_of.setdefault(record_label(record), []).append(record)
    parts = ['<dl class="why">']
    for engine in engines:
        parts.append(f"<dt>{escape_html(engine)}</dt><dd>"
                     f"{escape_html(engine_why(engine))}"
                     "</dd>")
        for label, (source, role) in zip(labels, roles):
            if source != engine:
                continue
            preset = preset_label(engine, role)
            text = preset_why(engine, role)
            runs = runs_of.get(label, [])
            notes: dict[str, int] = {}
            for run in runs:
                for note in run_notes(run):
                    notes[note] = notes.get(note, 0) + 1
            flagged = sum(1 for r in runs if not r.ok and not r.skipped)
            by_scenario = sum(1 for r in runs if split_overrides(r, command)[1])
            extra = [f"{count} of {len(runs)} runs note: “{escape_html(note)}”"
                     for note, count in notes.items()]
            if flagged:
                extra.append(f"{flagged} of {len(runs)} runs flagged by the engine")
            if given.get(engine):
                values = escape_html(fmt_overrides(given[engine]))
                extra.append(f"every run with <code>--set {values}</code> (not the preset: "
                             "the text above describes the preset)")
            if by_scenario:
                extra.append(f"{by_scenario} of {len(runs)} runs with their scenario's "
                             "overrides")
            head = f"<b>{escape_html(preset)}</b>" + (
                "" if preset == role else f" (in the <i>{escape_html(role)}</i> role)")
            parts.append(f"<dd>{head}: {escape_html(text)}"
                         + ("<br><span class='muted'>" + "; ".join(extra) + ".</span>"
                            if extra else "") + "</dd>")
    parts.append("</dl>")
    return "\n".join(parts)


def gates_html(provenance: dict) -> str:
    gates = provenance.get("gates", [])
    if not gates:
        return "<p>No scenario in this run declares a gate.</p>"
    # a sweep's gate is checked at each point: the point tells its rows apart
    points = any(g.get("point") for g in gates)
    rows = []
    for g in gates:
        cls = "fail" if g["status"] == "FAIL" else ("pass" if g["status"] == "pass" else "muted")
        rows.append([escape_html(g["scenario"]),
                     *([escape_html(g.get("point") or "")] if points else []),
                     escape_html(g["gate"]), escape_html(g["record"]), escape_html(g["law"]),
                     fmt_departure(g["departure"]), fmt_departure(g["max_departure"]),
                     f'<span class="{cls}">{escape_html(g["status"])}</span>'])
    return html_table(["scenario", *(["point"] if points else []), "gate", "record", "law",
                       "departure", "max", "result"], rows, left=5 if points else 4)


def split_table(results: Results, prepared: Prepared) -> str:
    """Per scenario and engine.preset: the largest total, law part and solve part (the
    scenarios' :func:`harness.report.fragments.split_view`, in the order of
    :func:`harness.report.views.split_rows`); "" when there is no row."""
    scenarios, labels = split_order(results)
    if not scenarios:
        return ""
    body = []
    for scenario in scenarios:
        split = prepared.views[scenario]["split"]
        law_part = split["law_part"]
        cells = [escape_html(scenario), fmt_departure(math.nan if law_part is None
                                                      else law_part)]
        for label in labels:
            solve = split["solve"].get(label)
            cells.append(fmt_departure(math.nan if solve is None else solve))
        body.append(cells)
    return html_table(["scenario", "law part [newton-lcp vs Poisson]",
                       *[f"solve part [{label}]" for label in labels]], body)


def headline_summary(names: Sequence[str], prepared: Prepared) -> str:
    """What the folded headline section says: per headline law, the largest departure over
    every scenario's single impacts and where (the scenarios' views,
    :func:`harness.report.fragments.scenario_view`)."""
    found = []
    for law in HEADLINE_LAWS:
        cells = [(cell[0], label, name) for name in names
                 if prepared.views[name].get("engine")
                 for label, cell in zip(prepared.labels, prepared.views[name][law])
                 if not cell[2] and math.isfinite(cell[0])]
        if cells:
            value, label, name = max(cells)
            found.append(f"from {LAW_STYLE[law][2]} up to {fmt_departure(value)} "
                         f"({escape_html(label)}, {escape_html(name)})")
    return "largest departure " + "; ".join(found) if found else "no engine run to compare"


def flagged_scenarios(names: Sequence[str], prepared: Prepared) -> int:
    """How many scenarios have a run an engine flagged (any headline cell marked)."""
    return sum(any(cell[1] for cell in prepared.views[name][HEADLINE_LAWS[0]])
               for name in names)


def split_summary(names: Sequence[str], prepared: Prepared) -> str:
    """What the folded law-vs-solve section says: the largest law part and solve part."""
    splits = [prepared.views[name]["split"] for name in names if prepared.views[name]["split"]]
    law = [s["law_part"] for s in splits if s["law_part"] is not None]
    solve = [v for s in splits for v in s["solve"].values() if v is not None]
    if not law and not solve:
        return ""
    return (f"law part up to {fmt_departure(max(law, default=math.nan))}, solve part up to "
            f"{fmt_departure(max(solve, default=math.nan))}")


def gates_summary(provenance: dict) -> str:
    """What the folded gates section says: how many passed, or failed."""
    gates = provenance.get("gates", [])
    failed = sum(g["status"] == "FAIL" for g in gates)
    if not gates:
        return "none declared"
    if failed:
        return f"<span class='fail'>{failed} of {len(gates)} FAILED</span>"
    passed = sum(g["status"] == "pass" for g in gates)
    return f"<span class='pass'>{passed} of {len(gates)} passed</span>"
