"""The HTML page of the report (``index.html``): self-contained, inline CSS, no scripts."""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import re
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from harness.engines import ENGINE_NAMES, PRESET_ROLES, preset_label, source_label
from harness.report.fragments import Prepared, prepare, split_order
from harness.report.reading import scenarios_digest
from harness.report.views import (
    FIGURES,
    HEADLINE_LAWS,
    HEAT_MAX,
    HEAT_MIN,
    LAW_ORDER,
    LAW_STYLE,
    TYPE_NAMES,
    engine_roles,
    engine_why,
    escape_html,
    fmt_departure,
    fmt_number,
    fmt_overrides,
    has_library_scenarios,
    overrides_of,
    preset_why,
    record_label,
    run_notes,
    run_verdict,
    scenario_overrides,
    slug,
    split_overrides,
)
from harness.run.files import write_text_atomically
from harness.run.records import ANALYTIC, Record, Results

CSS = """
body{font-family:-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:0 auto;max-width:1280px;
padding:0 18px 40px;color:#222;line-height:1.45}
h1{font-size:1.7em;margin:.6em 0 .2em}
h2{border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:1.6em}
h3{margin:1.4em 0 .3em} .lead{font-size:1.04em;max-width:62em}
.facts{color:#555;font-size:.92em} .facts b{color:#222}
table{border-collapse:collapse;font-size:.8em;margin:.4em 0 .8em}
th,td{border:1px solid #ddd;padding:2px 6px;text-align:right;white-space:nowrap}
th{background:#f4f4f4} td.l,th.l,th.wrap{text-align:left}
tr.engine td{background:#fbfbf6} tr.flag td{background:#fff1f0}
img{max-width:100%;height:auto} figure{margin:.6em 0} figcaption{font-size:.85em;color:#555}
.pair{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start}
.pair img.diagram{width:380px;max-width:100%}
.fail{color:#b00;font-weight:bold} .pass{color:#070} .muted{color:#777}
nav.contents{font-size:.9em;background:#f8f8f8;border:1px solid #e4e4e4;padding:6px 12px;
margin:.8em 0} nav.contents ol{margin:.2em 0;padding-left:1.4em}
nav.contents ol.scenarios{columns:3;font-size:.92em} code{background:#f4f4f4;padding:0 3px}
details{margin:.3em 0 .8em} summary{cursor:pointer;color:#335}
.scroll{overflow-x:auto;max-width:100%}
.pair{flex-wrap:wrap;gap:10px} .pair>div{flex:0 1 auto;min-width:0}
.pair>figure{flex:0 0 auto;margin:0}
td.note,th.note{white-space:normal;min-width:11em;max-width:22em;text-align:left}
td.wrap{white-space:normal;text-align:left;overflow-wrap:anywhere;max-width:70em}
p.notes{font-size:.8em;color:#733;margin:-.4em 0 .8em;max-width:60em}
.why dt{font-weight:bold;margin-top:.6em} .why dd{margin:.2em 0 .2em 1.2em;max-width:62em}
.override{color:#a40;font-weight:bold} .back{font-size:.85em}
nav.contents ol.groups{columns:4;font-size:.92em} nav.contents ol.groups ol{columns:1}
details.group>summary{font-size:1.1em;margin:.4em 0}
span.heat{display:block;margin:-2px -6px;padding:2px 6px}
"""


def header_cell(text: str) -> str:
    """A header with its unit (``"v_x [m/s]"``) on a second line, and a long body name
    (``"dumbbell.v_x"``) broken after its dot, to keep columns narrow."""
    return _header_cell(text) if isinstance(text, str) else _header_cell.__wrapped__(text)


@functools.lru_cache(maxsize=1024)
def _header_cell(text) -> str:
    """:func:`header_cell`, each header formatted once (a page of 1,000 scenarios has 2,400
    velocity tables of a dozen headers, nearly all alike)."""
    name, bracket, unit = str(text).partition(" [")
    body, dot, speed = name.rpartition(".")
    head = (escape_html(body + dot) + "<br>" + escape_html(speed) if dot and len(name) > 8
            else escape_html(name))
    return head + (f"<br><span class='muted'>[{escape_html(unit)}</span>" if bracket else "")


def html_table(header: Sequence[str], rows: Sequence[Sequence], left: int = 1,
               row_classes: Sequence[str] | None = None,
               column_classes: Sequence[str] | None = None) -> str:
    """A table in a horizontally scrolling wrapper; cells are HTML already.

    The first ``left`` columns are left-aligned; ``column_classes`` (one per column, "" for
    none) overrides a column's class (e.g. ``"note"`` for wrapped text).
    """
    def cell_open(i: int) -> str:  # a column's opening tag, made once per table
        cls = column_classes[i] if column_classes and column_classes[i] else (
            "l" if i < left else "")
        return f'<td class="{cls}">' if cls else "<td>"

    def head(i: int, text) -> str:
        cls = column_classes[i] if column_classes and column_classes[i] in (
            "note", "l", "wrap") else ("l" if i < left else "")
        cell = header_cell(text)
        return f'<th class="{cls}">{cell}</th>' if cls else f"<th>{cell}</th>"

    out = ['<div class="scroll"><table><tr>' + "".join(head(i, h) for i, h in enumerate(header))
           + "</tr>"]
    rows = [row if isinstance(row, list | tuple) else list(row) for row in rows]
    opens = [cell_open(i) for i in range(max(map(len, rows), default=0))]
    for k, row in enumerate(rows):
        cls = f' class="{row_classes[k]}"' if row_classes and row_classes[k] else ""
        out.append(f"<tr{cls}>" + "".join([f"{start}{content}</td>"
                                           for start, content in zip(opens, row)]) + "</tr>")
    out.append("</table></div>")
    return "\n".join(out)


def sorted_point_records(records: Sequence[Record]) -> list[Record]:
    laws = sorted((r for r in records if r.source == ANALYTIC),
                  key=lambda r: LAW_ORDER.index(r.law) if r.law in LAW_ORDER else 99)
    ENGINES, PRESETS = ENGINE_NAMES, PRESET_ROLES

    engines = sorted((r for r in records if r.source != ANALYTIC),
                     key=lambda r: (PRESETS.index(r.preset) if r.preset in PRESETS else 9,
                                    ENGINES.index(r.source) if r.source in ENGINES else 9))
    return laws + engines


def status_cell(record: Record, footnotes: dict[str, int]) -> str:
    """A run's status (and verdict, when the results carry one), with footnote marks for
    its notes and the verdict's reasons; ``footnotes`` maps each text to its number."""
    if record.source == ANALYTIC:
        return "" if record.ok else escape_html(record.status)
    verdict, reasons = run_verdict(record)
    words = [] if verdict is None else [f"<b>{escape_html(verdict)}</b>"]
    if not record.ok or not words:
        words.append(f"<b>{escape_html(record.status)}</b>" if not record.ok else "ok")
    marks = []
    for text in [*reasons, *run_notes(record)]:
        number = footnotes.setdefault(text, len(footnotes) + 1)
        marks.append(f"<sup>{number}</sup>")
    return ", ".join(words) + ("&#8202;" + "".join(marks) if marks else "")


def footnotes_html(footnotes: dict[str, int]) -> str:
    """The notes under a table, numbered as the marks in its status column."""
    if not footnotes:
        return ""
    return ("<p class='notes'>" + "<br>".join(
        f"<sup>{number}</sup> {escape_html(text)}" for text, number in footnotes.items())
        + "</p>")


def velocity_table(records: Sequence[Record], speed_labels: Sequence[str]) -> str:
    """Post-impact speeds of every law and engine at one point, side by side; each engine
    run's status and verdict beside its departures, its notes as numbered footnotes."""
    ordered = sorted_point_records(records)
    size = len(ordered[0].u_before) if ordered and ordered[0].u_before else len(speed_labels)
    labels = list(speed_labels) if len(speed_labels) == size else [f"u{i + 1}" for i in range(size)]
    header = ["source", *labels, "v_n after [m/s]", "v_t after [m/s]", "ΔE [J]", "type",
              "from Poisson", "from Stronge", "status"]
    rows, classes, footnotes = [], [], {}
    if ordered and ordered[0].u_before:
        rows.append(["<i>before</i>", *(fmt_number(v) for v in ordered[0].u_before),
                     fmt_number(ordered[0].vn_approach), fmt_number(ordered[0].vt_approach),
                     "", "", "", "", ""])
        classes.append("")
    for r in ordered:
        speeds = r.u_after or [None] * size
        if r.source == ANALYTIC:
            name = LAW_STYLE.get(r.law, (None, None, r.law))[2]
        else:
            name = f"<b>{escape_html(record_label(r))}</b>"
            if overrides_of(r):
                shown = escape_html(fmt_overrides(overrides_of(r)))
                name += (f"<br><span class='override'>[{shown}]"
                         "</span>")
        rows.append([name, *(fmt_number(v) for v in speeds), fmt_number(r.vn_separation),
                     fmt_number(r.vt_separation), fmt_number(r.energy_change),
                     "–" if r.collision_type is None else str(r.collision_type),
                     fmt_departure(r.departure.get("poisson")),
                     fmt_departure(r.departure.get("stronge")),
                     status_cell(r, footnotes)])
        classes.append("" if r.source == ANALYTIC else ("engine" if r.ok else "engine flag"))
    column_classes = [""] * (len(header) - 1) + ["l"]
    if all(r.source == ANALYTIC and r.ok for r in ordered):  # laws only: no status to show
        header, rows, column_classes = header[:-1], [row[:-1] for row in rows], None
    return (html_table(header, rows, row_classes=classes, column_classes=column_classes)
            + footnotes_html(footnotes))


def overrides_paragraph(records: Sequence[Record], command: dict | None = None) -> str:
    """What the runs of a scenario changed from the presets, by where it was set (the
    command line's ``--set``, the scenario's ``[engine_settings]``), or "" when nothing."""
    found = scenario_overrides(records)
    if not found:
        return ""
    by_command, by_scenario = {}, {}
    for engine in found:
        run = next(r for r in records if r.source == engine and overrides_of(r))
        from_command, from_scenario = split_overrides(run, command or {})
        if from_command:
            by_command[engine] = from_command
        if from_scenario:
            by_scenario[engine] = from_scenario
    sentences = []
    for where, values in (("on the command line (<code>--set</code>)", by_command),
                          ("by this scenario (<code>[engine_settings]</code>)", by_scenario)):
        if values:
            items = "; ".join(f"{escape_html(engine)}: <code>{escape_html(fmt_overrides(v))}"
                              "</code>" for engine, v in values.items())
            sentences.append(f"Engine settings overridden {where}: {items}.")
    return (f"<p class='override'>{' '.join(sentences)} These runs are not the presets: "
            "their labels carry the overrides, and the headline cells are marked “*”.</p>")


#: What :func:`scenario_section` reads of a scenario's description (``Results.scenarios``).
SECTION_INFO = ("description", "system", "tags", "sweep", "speed_labels")


def record_counts(results: Results) -> list[int]:
    """``[records, engine runs, flagged engine runs, skipped engine runs]``, as the page's
    facts line counts them."""
    engine_records = [r for r in results.records if r.source != ANALYTIC]
    return [len(results.records), len(engine_records),
            sum(not r.ok and not r.skipped for r in engine_records),
            sum(r.skipped for r in engine_records)]


def cached_contacts(results: Results, prepared: Prepared) -> str:
    """The HTML of :func:`harness.report.contacts.contacts_section`, kept in the report's
    cache under what it reads: every record and what the runner says of each scenario."""
    from harness.report.contacts import contacts_section  # several contacts (issue 13)

    key = f"contacts\0{prepared.records_digest}\0{scenarios_digest(results)}"
    return prepared.cache.get(key, lambda: contacts_section(results)[0])


def cached_section(name: str, results: Results, figures: dict, prepared: Prepared) -> str:
    """:func:`scenario_section`, kept in the report's cache under what it reads: the
    scenario's records (their digest), its description and its figures' files."""
    info = results.scenarios.get(name, {})
    files = [[kind, figures.get(kind, {}).get(name)] for kind in ("impulse", "sweep", "history")]
    svg = figures.get("svg", ())
    read = {key: info[key] for key in SECTION_INFO if key in info}  # not the references
    command = (results.provenance or {}).get("settings_overrides") or {}
    inputs = json.dumps([read, [[kind, file, file in svg] for kind, file in files], command],
                        sort_keys=True, default=str)
    key = f"section\0{name}\0{prepared.digests.get(name, '')}\0{inputs}"
    return prepared.cache.get(key, lambda: scenario_section(
        name, info, results.for_scenario(name), figures, command))


def scenario_section(name: str, info: dict, records: Sequence[Record], figures: dict,
                     command: dict | None = None) -> str:
    """One scenario's section; ``command``: the run's ``--set`` overrides (provenance)."""
    parts = [f'<div class="scenario" id="{escape_html(slug(name))}">',
             f"<h3>{escape_html(name)}</h3>"]
    tags = ", ".join(info.get("tags", []))
    parts.append(f"<p>{escape_html(info.get('description', ''))} <span class='muted'>"
                 f"[{escape_html(info.get('system', ''))}; tags: {escape_html(tags)}]</span></p>")
    parts.append(overrides_paragraph(records, command))
    laws = [r for r in records if r.source == ANALYTIC and r.law == "poisson" and r.ok]
    if info.get("sweep"):
        if name in figures.get("sweep", {}):
            parts.append(report_figure(figures, figures["sweep"][name],
                                       f"sweep of {name}"))
        points = list(dict.fromkeys(r.point["index"] for r in records))
        in_order = sorted(laws, key=lambda r: r.point["index"])
        types = " → ".join(str(r.collision_type) for r in in_order)
        parts.append(f"<p>Poisson types along the sweep: {escape_html(types)}.</p>")
        flagged = [r for r in records if r.source != ANALYTIC and not r.ok and not r.skipped]
        if flagged:
            parts.append("<p>Flagged by the engine (drawn ringed in red): "
                         + "; ".join(escape_html(f"{r.label} at {r.point['label']}: {r.status}")
                                     for r in flagged) + ".</p>")
        parts.append(f"<details><summary>post-impact velocities at each of the {len(points)} "
                     "points</summary>")
        for index in points:
            subset = [r for r in records if r.point["index"] == index]
            parts.append(f"<p><b>{escape_html(subset[0].point['label'])}</b></p>")
            parts.append(velocity_table(subset, info.get("speed_labels", [])))
        parts.append("</details>")
    else:
        if laws:
            d = laws[0].diagnostics or {}
            ctype = laws[0].collision_type
            parts.append(f"<p>Poisson: type {ctype} ({escape_html(TYPE_NAMES.get(ctype, ''))}), "
                         f"Table 1 case {d.get('case')}; μ = {fmt_number(d.get('mu'))}, "
                         f"e = {fmt_number(d.get('e'))}.</p>")
        diagram = ""
        if name in figures.get("impulse", {}):
            diagram = report_figure(figures, figures["impulse"][name],
                                    f"impulse diagram of {name}", css_class="diagram")
        table = velocity_table(records, info.get("speed_labels", []))
        # Up to four speeds leave room for the diagram beside the table; two bodies' six do
        # not at 1400 px, so the diagram goes below.
        layout = "pair" if len(info.get("speed_labels", [])) <= 4 else "stack"
        parts.append(f'<div class="{layout}"><div>{table}</div>{diagram}</div>')
        if name in figures.get("history", {}):  # the contact in time (report/history.py)
            parts.append(report_figure(figures, figures["history"][name],
                                       f"contact history of {name}",
                                       caption="The contact step by step against each law's "
                                       "impulse process (the paper's Fig. 1 in engine steps)."))
    parts.append("</div>")
    return "\n".join(parts)


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
                if skipped or not math.isfinite(value):
                    rows[i].append("<span class='muted'>"
                                   + ("skipped" if skipped else "n/a") + "</span>")
                    continue
                colour = "#{:02x}{:02x}{:02x}".format(*rgb[i, j])
                ink = "#fff" if value > 0.08 else "#000"  # as on the figure
                text = escape_html(text)
                if flagged:
                    text = f"<b>{text}</b>"
                rows[i].append(f"<span class='heat' style='background:{colour};"
                               f"color:{ink}'>{text}</span>")
    return html_table(header, rows)


def cached_departure_table(names: Sequence[str], prepared: Prepared) -> str:
    """:func:`departure_table_html`, kept in the report's cache under its scenarios' names
    and records digests (a family's table changes only with its scenarios' records)."""
    inputs = json.dumps([[name, prepared.digests.get(name, "")] for name in names])
    key = f"departures\0{hashlib.sha256(inputs.encode()).hexdigest()}"
    return prepared.cache.get(key, lambda: departure_table_html(names, prepared))


def figure_html(file: str, alt: str, css_class: str = "", caption: str = "",
                svg: bool = True) -> str:
    """A figure's PNG, linked to its SVG (the vector version for a paper) when ``svg``.
    Loaded eagerly: a lazy image not yet scrolled to is left out of a printed page, and a
    report holds at most a few hundred figures (per-scenario figures stop at 60 scenarios)."""
    vector = Path(file).with_suffix(".svg").name
    cls = f' class="{css_class}"' if css_class else ""
    image = (f'<img{cls} src="{FIGURES}/{escape_html(file)}" '
             f'alt="{escape_html(alt)}">')
    if svg:
        image = f'<a href="{FIGURES}/{escape_html(vector)}">{image}</a>'
    link = f" <a href='{FIGURES}/{escape_html(vector)}'>SVG</a>" if svg else ""
    return ("<figure>" + image
            + (f"<figcaption>{caption}{link}</figcaption>" if caption else "") + "</figure>")


def report_figure(figures: dict, file: str, alt: str, css_class: str = "",
                  caption: str = "") -> str:
    """:func:`figure_html` for one of the report's figures, linked to its SVG when the
    report wrote one (``figures["svg"]``)."""
    return figure_html(file, alt, css_class=css_class, caption=caption,
                       svg=file in figures.get("svg", ()))


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


def cached_table3(figure: str | None, prepared: Prepared) -> str:
    """:func:`table3_html`, kept in the report's cache under what it reads: ``table3`` and
    its data (:func:`harness.report.figures.table3_inputs`), the solver's code and
    ``figure``."""
    from harness.report.figures import solver_digest, table3_inputs

    key = f"table3\0{table3_inputs()}\0{solver_digest()}\0{figure}"
    return prepared.cache.get(key, lambda: table3_html(figure))


def table3_html(figure: str | None) -> str:
    """The paper's Table 3 reproduced, from the structured rows of ``table3``."""
    from harness.report import table3

    rows = table3.reproduce_table3()
    parts = [f"<p>{escape_html(table3.table3_intro(rows))}</p>"]
    if figure:
        parts.append(figure_html(figure, "impulse diagrams of the Table 3 rows with δ = 0.85",
                                 caption="Impulse paths of each law for the two δ = 0.85 rows; "
                                 "the cross is where the paper's printed Stronge Δu puts the "
                                 "end of the impact."))
    for section in table3.table3_sections(rows):
        parts.append(f"<h4>{escape_html(section.title)}</h4>")
        parts += [f"<p>{escape_html(text)}</p>" for text in section.before]
        body = []
        for cells, missed in zip(section.rows, section.missed):
            body.append([("<span class='fail'>no</span>" if missed and cell == "no"
                          else escape_html(cell)) for cell in cells])
        left = sum(1 for a in section.alignments[:2] if a == "l")
        column_classes = ["l" if a == "l" else "" for a in section.alignments]
        if section.header[-1] == "reason for a miss":
            column_classes[-1] = "note"
        parts.append(html_table(section.header, body, left=left,
                                row_classes=["flag" if m else "" for m in section.missed],
                                column_classes=column_classes))
        parts += [f"<p>{escape_html(text)}</p>" for text in section.after]
    return "\n".join(parts)


def markdown_to_html(text: str, heading_shift: int = 1) -> str:
    """The small Markdown subset the harness writes: headings, paragraphs, tables, images,
    lists, ``code`` and **bold**."""
    def inline(line: str) -> str:
        line = escape_html(line)
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
            out.append(html_table(header, [[inline(c) for c in r] for r in body]))
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


def settings_table(provenance: dict) -> str:
    settings = provenance.get("engine_settings", {})
    parts = []
    for engine, presets in settings.items():
        names = [preset_label(engine, role) for role in presets]
        keys = list(dict.fromkeys(k for p in presets.values() for k in p))
        rows = []
        for key in keys:
            values = [presets[p].get(key) for p in presets]
            cells = [escape_html(json_short(v)) for v in values]
            if len(set(map(json_short, values))) > 1:
                cells = [f"<b>{c}</b>" for c in cells]
            rows.append([f"<code>{escape_html(key)}</code>", *cells])
        version = provenance.get("engine_versions", {}).get(engine, "")
        parts.append(f"<h4>{escape_html(engine)} {escape_html(version)}</h4>")
        parts.append(html_table(["setting", *names], rows))
    return "\n".join(parts) or "<p>No engine ran.</p>"


def json_short(value) -> str:
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
        rows.append([escape_html(g["scenario"]), escape_html(g["gate"]),
                     escape_html(g["record"]), escape_html(g["law"]),
                     fmt_departure(g["departure"]), fmt_departure(g["max_departure"]),
                     f'<span class="{cls}">{escape_html(g["status"])}</span>'])
    return html_table(["scenario", "gate", "record", "law", "departure", "max", "result"], rows,
                  left=4)


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


def versions_html(provenance: dict) -> str:
    versions = provenance.get("versions", {})
    git = provenance.get("git", {})
    machine = provenance.get("machine", {})
    cache = provenance.get("cache", {})
    rows = [[escape_html(k), escape_html(v if v is not None else "not installed")]
            for k, v in versions.items()]
    rows += [["git commit", escape_html(f"{git.get('commit')}" + (" (uncommitted changes)"
                                                          if git.get("dirty") else ""))],
             ["code version", escape_html(str(provenance.get("code_version", ""))[:16])],
             ["machine", escape_html(f"{machine.get('platform')}, "
                                     f"{machine.get('cpu_count')} cores")],
             ["results written", escape_html(provenance.get("created_utc", ""))],
             ["command", f"<code>{escape_html(' '.join(provenance.get('command', [])))}</code>"],
             ["engine runs", escape_html(f"{cache.get('engine_runs')} ({cache.get('simulated')} "
                                  f"simulated, {cache.get('hits')} from the cache)")],
             ["run wall time", escape_html(f"{provenance.get('wall_time_s', 0):.2f} s")]]
    for engine, reason in provenance.get("engines_missing", {}).items():
        rows.append([escape_html(f"skipped {engine}"), escape_html(reason)])
    return html_table(["item", "value"], rows, left=2, column_classes=["l", "wrap"])


PAGE_HEAD = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
             "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
             "<title>{title}</title><style>{css}</style></head><body>")


def page_head(title: str) -> str:
    return PAGE_HEAD.format(title=escape_html(title), css=CSS)


def scenario_links(names: Sequence[str]) -> str:
    """The scenarios as a list of links to their sections."""
    return "".join(f"<li><a href='#{escape_html(slug(n))}'>{escape_html(n)}</a></li>"
                   for n in names)


def contents_html(names: Sequence[str], pages: dict,
                  groups: dict[str, list[str]] | None = None,
                  extra: Sequence[tuple[str, str]] = (), table3: bool = True) -> str:
    """The table of contents at the top of the page (sections, scenarios, other pages);
    with ``groups`` (``{tag: names}``, a report of many scenarios) the scenarios are folded
    per tag."""
    if groups:
        scenarios = "".join(
            f"<li><details><summary>{escape_html(tag)} ({len(members)})</summary>"
            f"<ol class='scenarios'>{scenario_links(members)}</ol></details></li>"
            for tag, members in groups.items())
    else:
        scenarios = scenario_links(names)
    items = [("#headline", "Departure of every engine from the laws"),
             ("#why", "Why: what each engine and preset solves"),
             ("#split", "Law vs solve"), ("#gates", "Gates"),
             ("#scenarios", "Scenarios")]
    out = ["<nav class='contents'><b>Contents</b><ol>"]
    for href, text in items:
        out.append(f"<li><a href='{href}'>{text}</a>")
        if href == "#scenarios":
            kind = "groups" if groups else "scenarios"
            out.append(f"<ol class='{kind}'>{scenarios}</ol>")
        out.append("</li>")
    for href, text in extra:  # sections present only in some reports
        out.append(f"<li><a href='{href}'>{escape_html(text)}</a></li>")
    if table3:
        out.append("<li><a href='#table3'>Table 3 of the paper</a></li>")
    out.append("<li><a href='#versions'>Versions and settings</a></li>")
    for file, title in pages.items():
        out.append(f"<li><a href='{escape_html(file)}'>{escape_html(title)}</a> "
                   "<span class='muted'>(separate page)</span></li>")
    out.append("</ol></nav>")
    return "\n".join(out)


def write_html(results: Results, out_dir: Path, figures: dict, pages: dict | None = None,
               prepared: Prepared | None = None,
               experiments_data: str | os.PathLike | None = None) -> Path:
    """Write ``index.html``; ``pages`` maps further pages of the report (``bench.html`` …)
    to their titles, linked from the contents; ``prepared``: the scenarios' pieces
    (:func:`harness.report.fragments.prepare`, computed here when not given), whose cache
    keeps each scenario's section for the next report."""
    path = out_dir / "index.html"
    write_text_atomically(path, html_page(results, out_dir, figures, pages, prepared,
                                          experiments_data))
    return path


def html_page(results: Results, out_dir: Path, figures: dict, pages: dict | None = None,
              prepared: Prepared | None = None,
              experiments_data: str | os.PathLike | None = None) -> str:
    """The text of ``index.html`` (:func:`write_html`); reads nothing of the figures but
    their names in ``figures``, so that it can be built while they are drawn.
    ``experiments_data``: the Fazeli drops' directory (else the environment variable's)."""
    pages = pages or {}
    prepared = prepare(results) if prepared is None else prepared
    prov = results.provenance
    names = results.scenario_names()
    gates = prov.get("gates", [])
    failed = [g for g in gates if g["status"] == "FAIL"]
    # counts of every record: kept while no record changed (they are all read otherwise)
    records, engine_runs, flagged, skipped = prepared.whole("counts",
                                                            lambda: record_counts(results))
    labels = prepared.labels
    engines = list(dict.fromkeys(label.split(".")[0] for label in labels))
    git = prov.get("git", {})
    parts = [page_head("Planar impact with friction: engines against the exact laws"),
             "<h1>Planar impact with friction: physics engines against the exact laws</h1>"]
    parts.append(
        '<p class="lead">Every scenario here is one planar rigid-body impact with Coulomb '
        "friction (a disk, rod, box or polygon hitting the ground or another body). Each is "
        "solved exactly under five impact laws by <code>planar_impact</code> (Poisson's and "
        "Stronge's hypotheses after Djerassi 2009, Newton's, and the velocity-level "
        "<code>newton-lcp</code> law that sequential-impulse engines solve) and simulated by "
        f"the physics engines {escape_html(', '.join(engines) or '(none)')} with their "
        "out-of-the-box <i>defaults</i> and with <i>accurate</i> settings (for MuJoCo "
        "<i>matched-bounce</i>: it matches the bounce, not a dissipative law). The "
        "<b>departure</b> of an engine from a law is the error of its post-impact velocities "
        "in the kinetic-energy norm, relative to the motion before the impact measured in a "
        "frame no common velocity or rotation changes (the ground's, or the centre of mass's "
        "for two free bodies): "
        "‖u<sub>engine</sub> − u<sub>law</sub>‖<sub>M</sub> / ‖u<sub>before</sub>‖<sub>M, "
        "frame-free</sub>, in percent throughout (0 = identical, 10% = a tenth of the motion "
        "is wrong). Only single impacts have a departure: a run that fails a verdict check "
        "(docs/verdicts.md) is shown with its reason and counted, never averaged in.</p>")
    parts.append(
        f'<p class="facts"><b>{len(names)}</b> scenarios, <b>{records}</b> '
        f"records; engine runs: <b>{engine_runs}</b> "
        f"({flagged} flagged, {skipped} skipped); gates: "
        + (f'<span class="fail">{len(failed)} of {len(gates)} FAILED</span>' if failed
           else f'<span class="pass">{len(gates)} passed</span>')
        + f"; commit <code>{escape_html(str(git.get('commit'))[:10])}</code>, "
        f"{escape_html(prov.get('created_utc', ''))}.</p>")
    contents_at = len(parts)  # filled in at the end: some sections appear only when present
    parts.append("")
    parts.append("<h2 id='headline'>Departure of every engine from the laws</h2>")
    caption = (
        "Departure from Poisson (left pair) and from exact Stronge (right pair), "
        "engines out of the box (<i>defaults</i>) and tuned (<i>accurate</i>; MuJoCo: "
        "<i>matched-bounce</i>). Sweeps show "
        "their largest departure over the sweep's single impacts. “(k!)”: k runs were "
        "flagged (multi-contact, not separated, …) and are not in the value; “*”: the "
        "runs' settings differ from the preset's, by the scenario's <code>[engine_settings]"
        "</code> or the command line's <code>--set</code> (see its section); grey cells were "
        "skipped. Light = agrees, "
        "dark red = far off.")
    groups = figures.get("groups") or {}
    if groups:  # many scenarios: a row per family in the figure, the scenarios in tables
        caption = ("One row per family of scenarios (its first tag that is not a selection "
                   "tag such as <i>quick</i>; how many in brackets): the colour is the median "
                   "over the family's scenarios of each one's largest departure, the text "
                   "<i>median / max</i>. " + caption)
    if "heatmap" in figures:
        parts.append(report_figure(figures, figures["heatmap"], "departure heat map",
                                   caption=caption))
    if groups:
        parts.append("<p>Every scenario's departures, per family (unfold one):</p>")
        for tag, members in groups.items():
            parts.append(f"<details><summary>{escape_html(tag)} ({len(members)} scenarios)"
                         "</summary>" + cached_departure_table(members, prepared) + "</details>")
    parts.append("<h2 id='why'>Why: what each engine and preset solves</h2>")
    parts.append(
        "<p>Most of the departure of pymunk and pybullet is the <b>law</b>, not the solver: "
        "they solve <code>newton-lcp</code> (restitution as a target on the normal velocity, "
        "Coulomb friction at the end state), which differs from Poisson and Stronge wherever "
        "the slip stops or reverses during the impact. MuJoCo solves no rigid impact law at "
        "all. Per engine and preset (details and measurements: <code>docs/engines.md</code>):"
        "</p>" + prepared.whole("why", lambda: why_html(results)))
    parts.append("<h2 id='split'>Law vs solve: the law they solve against how well they "
                 "solve it</h2>")
    parts.append(
        "<p>Each point is one engine run. <b>Law part</b>: how far the engines' own law "
        "(<code>newton-lcp</code>) is from Poisson at that impact; <b>solve part</b>: how far "
        "the engine is from <code>newton-lcp</code>. The total departure from Poisson is at "
        "most their sum.</p>")
    if "split" in figures:
        parts.append(report_figure(figures, figures["split"], "departure split"))
    numbers = prepared.whole("split", lambda: split_table(results, prepared))
    if numbers:
        parts.append("<details><summary>the numbers (largest over sweep points)</summary>"
                     + numbers + "</details>")
    parts.append("<h2 id='gates'>Gates</h2><p>Tolerance gates declared by the scenarios "
                 "(<code>[expect.gate]</code>); a failing gate makes <code>impact-harness "
                 "run</code> exit non-zero.</p>" + gates_html(prov))
    parts.append(cached_contacts(results, prepared))
    parts.append("<h2 id='scenarios'>Scenarios</h2><p>Per scenario: post-impact speeds of "
                 "every law and engine (engine rows shaded; red when the engine flagged the "
                 "run), contact velocities after the impact (v<sub>n</sub>, v<sub>t</sub>, in "
                 "the contact frame), energy change, collision type (Poisson/Stronge 1–5: "
                 + "; ".join(f"{k} {v}" for k, v in TYPE_NAMES.items())
                 + "; Newton laws and engines: 1 stick, 2 reverse slide, 3 forward slide) and "
                 "each engine run's status beside its departures (its notes numbered under "
                 "the table). "
                 "The impulse diagram is Routh's graph (the paper's Fig. 1): the path of each "
                 "law's impulse and every end point; filled engine markers are "
                 "<i>accurate</i> (MuJoCo <i>matched-bounce</i>), hollow <i>defaults</i>, and "
                 "engines that land on the same "
                 "point are drawn side by side. Sweeps show post-impact quantities against "
                 "the swept parameter instead, laws as lines and engines as points (flagged "
                 "runs ringed in red), with the points where the Poisson collision type "
                 "changes dashed. Every figure links to its SVG.</p>")
    if "legend" in figures:
        parts.append(report_figure(figures, figures["legend"],
                                   "key of the impulse diagrams"))
    if figures.get("many") and figures.get("scenario_figures") != "all":
        parts.append(f"<p class='muted'>With {len(names)} scenarios the per-scenario figures "
                     "are not drawn (they would take minutes); <code>impact-harness report "
                     "--figures-for 'PATTERN'</code> draws those of the scenarios matching a "
                     "pattern, <code>--scenario-figures all</code> every one.</p>")
    groups = figures.get("groups") or {"": names}
    for tag, members in groups.items():
        if tag:  # many scenarios: folded per tag
            parts.append(f"<details class='group'><summary><b>{escape_html(tag)}</b> "
                         f"({len(members)} scenarios)</summary>")
        for name in members:
            parts.append(cached_section(name, results, figures, prepared))
        if tag:
            parts.append("</details>")
    library = has_library_scenarios(results)
    if library:
        parts.append("<h2 id='table3'>Table 3 of Djerassi (2009, Part B) reproduced</h2>")
        parts.append(cached_table3(figures.get("table3"), prepared))
    # the survey in out_dir/survey (impact-harness suite's quick one), when there is one
    from harness.report.survey import cached_survey_section

    parts.append(cached_survey_section(out_dir, figures, prepared))
    from harness.report.experiments import experiments_section  # issue 25

    parts.append(experiments_section(out_dir, experiments_data))
    parts.append("<h2 id='versions'>Versions and settings</h2>" + versions_html(prov))
    parts.append("<h3>Engine settings per preset</h3><p>Bold where the presets differ. "
                 "The table is the presets as run, with the command line's <code>--set</code> "
                 "overrides; scenario files may override settings too "
                 "(<code>[engine_settings.&lt;engine&gt;]</code>); such runs carry the "
                 "overrides in their labels and in each record's diagnostics in "
                 "<code>results.json</code>.</p>" + settings_table(prov))
    generated = time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())
    parts.append(f"<p class='muted'>Report generated {generated} "
                 "by <code>impact-harness report</code>.</p></body></html>")
    extra = [(href, title) for href, title in (("#contacts", "Several contacts"),
                                               ("#survey", "Survey"),
                                               ("#experiments", "Against experiments"))
             if any(f"id='{href[1:]}'" in part for part in parts)]
    parts[contents_at] = contents_html(names, pages, figures.get("groups"), extra, library)
    return "\n".join(parts)
