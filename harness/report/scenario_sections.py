"""Each scenario's section of ``index.html``: its description, the post-impact velocities of
every law and engine side by side (each engine run's status, verdict and notes as numbered
footnotes), its impulse diagram or sweep figure, and its contact history."""

from __future__ import annotations

import json
from collections.abc import Sequence

from harness.engines import PRESET_ROLES, engine_names
from harness.report.fragments import Prepared
from harness.report.markup import folded, html_table, report_figure
from harness.report.views import (
    LAW_ORDER,
    LAW_STYLE,
    TYPE_NAMES,
    escape_html,
    fmt_departure,
    fmt_number,
    fmt_overrides,
    overrides_of,
    record_label,
    run_notes,
    run_verdict,
    scenario_overrides,
    slug,
    split_overrides,
    worst_record,
)
from harness.run.records import ANALYTIC, Record, Results


def sorted_point_records(records: Sequence[Record]) -> list[Record]:
    laws = sorted((r for r in records if r.source == ANALYTIC),
                  key=lambda r: LAW_ORDER.index(r.law) if r.law in LAW_ORDER else 99)
    ENGINES, PRESETS = engine_names(), PRESET_ROLES

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
    """One scenario's section, folded (:func:`harness.report.markup.folded`: the page has
    one per scenario, and their tables and figures made it 48,000 px tall) under a summary
    of its runs (:func:`scenario_headline`); ``command``: the run's ``--set`` overrides
    (provenance)."""
    parts = []
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
    return folded(slug(name), name, "\n".join(part for part in parts if part),
                  scenario_headline(records), level=3, css_class="fold scenario")


def scenario_headline(records: Sequence[Record]) -> str:
    """What a scenario's folded section says of its runs: how many engine runs, how many
    flagged and skipped, and the largest departure from Poisson over the single impacts
    (with the run that makes it)."""
    runs = [r for r in records if r.source != ANALYTIC]
    if not runs:
        return "the laws only (no engine ran)"
    points = len({r.point["index"] for r in records})
    flagged = sum(1 for r in runs if not r.ok and not r.skipped)
    skipped = sum(1 for r in runs if r.skipped)
    text = f"{len(runs)} engine runs" + (f" at {points} points" if points > 1 else "")
    if flagged:
        text += f", <span class='fail'>{flagged} flagged</span>"
    if skipped:
        text += f", {skipped} skipped"
    worst = worst_record(runs, "poisson")
    if worst is not None:
        text += (f"; largest departure from Poisson {fmt_departure(worst.departure['poisson'])}"
                 f" ({escape_html(record_label(worst))})")
    return text
