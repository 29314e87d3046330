"""The HTML page of the report (``index.html``): its sections in order, the table of
contents, and the appendices (Table 3 of the paper, versions and settings). The pieces live
beside it: :mod:`~harness.report.markup` (style, tables, figures),
:mod:`~harness.report.overview` (the sections made of every run) and
:mod:`~harness.report.scenario_sections` (one per scenario)."""

from __future__ import annotations

import json
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from harness.engines import preset_label, renamed_roles
from harness.report import table3
from harness.report.contacts import contacts_section
from harness.report.experiments import experiments_section
from harness.report.figure_cache import solver_digest, table3_inputs
from harness.report.fragments import Prepared, prepare
from harness.report.markup import figure_html, folded, html_table, page_head, report_figure
from harness.report.overview import (
    cached_departure_table,
    flagged_scenarios,
    gates_html,
    gates_summary,
    headline_summary,
    record_counts,
    split_summary,
    split_table,
    why_html,
)
from harness.report.reading import scenarios_digest
from harness.report.scenario_sections import cached_section
from harness.report.survey import cached_survey_section
from harness.report.views import (
    TYPE_NAMES,
    command_overrides,
    escape_html,
    has_library_scenarios,
    setting_unit,
    slug,
)
from harness.run.metrics import SCIENTIFIC_BELOW_PERCENT
from harness.run.records import Results
from harness.store.files import write_text_atomically


def cached_contacts(results: Results, prepared: Prepared) -> str:
    """The HTML of :func:`harness.report.contacts.contacts_section`, kept in the report's
    cache under what it reads: every record and what the runner says of each scenario."""
    key = f"contacts\0{prepared.records_digest}\0{scenarios_digest(results)}"
    return prepared.cache.get(key, lambda: contacts_section(results)[0])


def cached_table3(figure: str | None, prepared: Prepared) -> str:
    """:func:`table3_html`, kept in the report's cache under what it reads: ``table3`` and
    its data (:func:`harness.report.figure_cache.table3_inputs`), the solver's code and
    ``figure``."""
    key = f"table3\0{table3_inputs()}\0{solver_digest()}\0{figure}"
    return prepared.cache.get(key, lambda: table3_html(figure))


def table3_html(figure: str | None) -> str:
    """The section of the paper's Table 3 reproduced, from the structured rows of ``table3``,
    folded under how many printed cells it reproduces."""
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
    cells = [cell for row in rows for cell in row["cells"]]
    unexplained = sum(cell.reason.startswith("UNEXPLAINED") for cell in cells)
    headline = (f"{sum(cell.reproduced for cell in cells)} of {len(cells)} printed cells "
                "reproduced; " + (f"<span class='fail'>{unexplained} misses unexplained</span>"
                                  if unexplained else "every miss a known erratum"))
    return folded("table3", "Table 3 of Djerassi (2009, Part B) reproduced", "\n".join(parts),
                  headline)


def settings_table(provenance: dict) -> str:
    settings = provenance.get("engine_settings", {})
    parts = []
    for engine, presets in settings.items():
        names = [preset_label(engine, role) for role in presets]
        keys = list(dict.fromkeys(k for p in presets.values() for k in p))
        rows = []
        for key in keys:
            values = [presets[p].get(key) for p in presets]
            cells = [escape_html(setting_text(v, engine)) for v in values]
            if len(set(map(json_short, values))) > 1:
                cells = [f"<b>{c}</b>" for c in cells]
            rows.append([f"<code>{escape_html(key)}</code>", escape_html(setting_unit(key)),
                         *cells])
        version = provenance.get("engine_versions", {}).get(engine, "")
        parts.append(f"<h4>{escape_html(engine)} {escape_html(version)}</h4>")
        parts.append(html_table(["setting", "unit", *names], rows, left=2))
    return "\n".join(parts) or "<p>No engine ran.</p>"


def setting_text(value, engine: str) -> str:
    """A setting's value in the settings table: ``None`` (not set) as the engine's own
    default, ``true``/``false`` as on/off, numbers short."""
    if value is None:
        return f"{engine}'s default"
    if isinstance(value, bool):
        return "on" if value else "off"
    return json_short(value)


def json_short(value) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return json.dumps(value) if not isinstance(value, str) else value


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


def scenario_links(names: Sequence[str]) -> str:
    """The scenarios as a list of links to their sections."""
    return "".join(f"<li><a href='#{escape_html(slug(n))}'>{escape_html(n)}</a></li>"
                   for n in names)


#: The page's sections as the contents name them; the contents list those present, in the
#: order they appear on the page (:func:`page_sections`).
SECTION_TITLES = {"headline": "Departure of every engine from the laws",
                  "why": "Why: what each engine and preset solves",
                  "split": "Law vs solve", "gates": "Gates", "contacts": "Several contacts",
                  "scenarios": "Scenarios", "table3": "Table 3 of the paper",
                  "survey": "Survey", "experiments": "Against experiments",
                  "versions": "Versions and settings"}


def page_sections(parts: Sequence[str]) -> list[str]:
    """The anchors of :data:`SECTION_TITLES` present in the page's ``parts``, in page
    order."""
    page = "\n".join(parts)
    found = [(page.find(f"id='{anchor}'"), anchor) for anchor in SECTION_TITLES]
    return [anchor for at, anchor in sorted(found) if at >= 0]


def contents_html(names: Sequence[str], pages: dict, sections: Sequence[str],
                  groups: dict[str, list[str]] | None = None,
                  stale: dict[str, str] | None = None) -> str:
    """The table of contents at the top of the page: ``sections`` (anchors of
    :data:`SECTION_TITLES`, in page order) with the scenarios under theirs, then the other
    pages; with ``groups`` (``{tag: names}``, a report of many scenarios) the scenarios are
    folded per tag. ``stale``: ``{title: why}`` of the pages not linked (older than the
    results)."""
    if groups:
        scenarios = "".join(
            f"<li><details><summary>{escape_html(tag)} ({len(members)})</summary>"
            f"<ol class='scenarios'>{scenario_links(members)}</ol></details></li>"
            for tag, members in groups.items())
    else:
        scenarios = scenario_links(names)
    out = ["<nav class='contents'><b>Contents</b><ol>"]
    for anchor in sections:
        out.append(f"<li><a href='#{anchor}'>{escape_html(SECTION_TITLES[anchor])}</a>")
        if anchor == "scenarios":
            kind = "groups" if groups else "scenarios"
            out.append(f"<ol class='{kind}'>{scenarios}</ol>")
        out.append("</li>")
    for file, title in pages.items():
        out.append(f"<li><a href='{escape_html(file)}'>{escape_html(title)}</a> "
                   "<span class='muted'>(separate page)</span></li>")
    for title, why in (stale or {}).items():
        out.append(f"<li>{escape_html(title)} <span class='muted'>(not linked: "
                   f"{why})</span></li>")
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


@dataclass
class Page:
    """What every section of the page reads, gathered once (:func:`page_data`): the results
    and their prepared pieces, the figures' names, and the facts the sections share."""

    results: Results
    out_dir: Path
    figures: dict
    prepared: Prepared
    names: list[str]
    labels: list[str]
    engines: list[str]
    #: the engines shown that call their accurate role by a name of their own (the
    #: registry's preset names), e.g. "mujoco <i>matched-bounce</i>": HTML
    renamed: str
    #: ``[records, engine runs, flagged engine runs, skipped engine runs]``
    counts: list[int]

    @property
    def provenance(self) -> dict:
        return self.results.provenance


def page_data(results: Results, out_dir: Path, figures: dict,
              prepared: Prepared | None = None) -> Page:
    prepared = prepare(results) if prepared is None else prepared
    labels = prepared.labels
    engines = list(dict.fromkeys(label.split(".")[0] for label in labels))
    renamed = "; ".join(f"{escape_html(engine)} <i>{escape_html(name)}</i>"
                        for engine in engines
                        for role, name in renamed_roles(engine).items() if role == "accurate")
    # counts of every record: kept while no record changed (they are all read otherwise)
    counts = prepared.whole("counts", lambda: record_counts(results))
    return Page(results, out_dir, figures, prepared, results.scenario_names(), labels,
                engines, renamed, counts)


def html_page(results: Results, out_dir: Path, figures: dict, pages: dict | None = None,
              prepared: Prepared | None = None,
              experiments_data: str | os.PathLike | None = None,
              stale_pages: dict[str, str] | None = None) -> str:
    """The text of ``index.html`` (:func:`write_html`); reads nothing of the figures but
    their names in ``figures``, so that it can be built while they are drawn.
    ``experiments_data``: the Fazeli drops' directory (else the environment variable's);
    ``stale_pages``: ``{title: why}`` of the pages named but not linked
    (:func:`harness.report.pages.write_pages`).

    In one pass: the page's data, then each section in page order (each folded under its
    name and headline: the overview unfolded, the long ones folded), then the contents of
    the sections present, then the page.
    """
    page = page_data(results, out_dir, figures, prepared)
    sections = [headline_section(page), why_section(page), split_section(page),
                gates_section(page), cached_contacts(results, page.prepared),
                scenarios_section(page)]
    if has_library_scenarios(results):
        sections.append(cached_table3(figures.get("table3"), page.prepared))
    # the survey in out_dir/survey (impact-harness suite's quick one), when there is one
    sections.append(cached_survey_section(out_dir, figures, page.prepared))
    sections.append(experiments_section(out_dir, experiments_data))
    sections.append(versions_section(page))
    contents = contents_html(page.names, pages or {}, page_sections(sections),
                             figures.get("groups"), stale_pages)
    generated = time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())
    return "\n".join([
        page_head("Planar impact with friction: engines against the exact laws"),
        "<h1>Planar impact with friction: physics engines against the exact laws</h1>",
        *opening(page), contents, *sections,
        f"<p class='muted'>Report generated {generated} "
        "by <code>impact-harness report</code>.</p></body></html>"])


def opening(page: Page) -> list[str]:
    """What the page is, its counts and, for a run with ``--set``, that its numbers are not
    the presets'."""
    prov = page.provenance
    gates = prov.get("gates", [])
    failed = [g for g in gates if g["status"] == "FAIL"]
    records, engine_runs, flagged, skipped = page.counts
    git = prov.get("git", {})
    parts = [
        '<p class="lead">Every scenario here is one planar rigid-body impact with Coulomb '
        "friction (a disk, rod, box or polygon hitting the ground or another body). Each is "
        "solved exactly under five impact laws by <code>planar_impact</code> (Poisson's and "
        "Stronge's hypotheses after Djerassi 2009, Newton's, and the velocity-level "
        "<code>newton-lcp</code> law that sequential-impulse engines solve) and simulated by "
        f"the physics engines {escape_html(', '.join(page.engines) or '(none)')} with their "
        "out-of-the-box <i>defaults</i> and with <i>accurate</i> settings"
        + (f" (for {page.renamed}: its own name where <i>accurate</i> would mislead, see the "
           "engine's preset below)" if page.renamed else "") + ". The "
        "<b>departure</b> of an engine from a law is the error of its post-impact velocities "
        "in the kinetic-energy norm, relative to the motion before the impact measured in a "
        "frame no common velocity or rotation changes (the ground's, or the centre of mass's "
        "for two free bodies): "
        "‖u<sub>engine</sub> − u<sub>law</sub>‖<sub>M</sub> / ‖u<sub>before</sub>‖<sub>M, "
        "frame-free</sub>, in percent throughout (0 = identical, 10% = a tenth of the motion "
        f"is wrong; decimals down to {SCIENTIFIC_BELOW_PERCENT:g}%, scientific notation "
        "below it). Only single impacts have a departure: a run that fails a verdict check "
        "(docs/verdicts.md) is shown with its reason and counted, never averaged in.</p>",
        f'<p class="facts"><b>{len(page.names)}</b> scenarios, <b>{records}</b> '
        f"records; engine runs: <b>{engine_runs}</b> "
        f"({flagged} flagged, {skipped} skipped); gates: "
        + (f'<span class="fail">{len(failed)} of {len(gates)} FAILED</span>' if failed
           else f'<span class="pass">{len(gates)} passed</span>')
        + f"; commit <code>{escape_html(str(git.get('commit'))[:10])}</code>, "
        f"{escape_html(prov.get('created_utc', ''))}.</p>"]
    command = command_overrides(prov)
    if command:  # shared alone, the page would pass for the presets' numbers
        parts.append("<p class='override'>Not the presets as shipped: this run set "
                     f"<code>{escape_html(command)}</code> on the command line "
                     "(<code>--set</code>), in every preset of those engines; every number "
                     "of theirs below is with those settings.</p>")
    return parts


def headline_section(page: Page) -> str:
    """The heat map of departures (a row per scenario, or per family with a table per
    family when there are many), with what its cells mean."""
    figures, skipped = page.figures, page.counts[3]
    caption = (
        "Departure from Poisson (top row) and from exact Stronge (bottom row), "
        "engines out of the box (<i>defaults</i>) and tuned (<i>accurate</i>"
        + (f"; {page.renamed}" if page.renamed else "") + "). Sweeps show "
        "their largest departure over the sweep's single impacts. A <b>hatched</b> cell "
        "holds flagged runs (not single impacts: multi-contact, not separated, …; "
        "docs/verdicts.md), counted by “(k!)” (“(k of n!)” of a sweep's n runs) and never "
        "in the value: its colour and "
        "number are those of the other runs, and “flagged (k!)” on grey means every run "
        "was flagged. “*”: the runs' settings differ from the preset's, by the scenario's "
        "<code>[engine_settings]</code> or the command line's <code>--set</code> (see its "
        "section); “skipped” on grey: the engine did not run"
        + (f" ({skipped} runs)" if skipped else " (none was)") + ". Light = agrees, "
        "dark red = far off.")
    groups = figures.get("groups") or {}
    if groups:  # many scenarios: a row per family in the figure, the scenarios in tables
        caption = ("One row per family of scenarios (its first tag that is not a selection "
                   "tag such as <i>quick</i>; how many in brackets): the colour is the median "
                   "over the family's scenarios of each one's largest departure, the text "
                   "<i>median / max</i>. " + caption)
    body = []
    if "heatmap" in figures:
        body.append(report_figure(figures, figures["heatmap"], "departure heat map",
                                  caption=caption))
    if groups:
        body.append("<p>Every scenario's departures, per family (unfold one):</p>")
        for tag, members in groups.items():
            body.append(f"<details><summary>{escape_html(tag)} ({len(members)} scenarios)"
                        "</summary>" + cached_departure_table(members, page.prepared)
                        + "</details>")
    return folded("headline", "Departure of every engine from the laws", "\n".join(body),
                  headline_summary(page.names, page.prepared), unfolded=True)


def why_section(page: Page) -> str:
    why = (
        "<p>Most of the departure of pymunk and pybullet is the <b>law</b>, not the solver: "
        "they solve <code>newton-lcp</code> (restitution as a target on the normal velocity, "
        "Coulomb friction at the end state), which differs from Poisson and Stronge wherever "
        "the slip stops or reverses during the impact. MuJoCo and Drake solve no rigid impact "
        "law at all (their contacts are compliant). Per engine and preset (details and "
        "measurements: <code>docs/engines.md</code>):</p>"
        + page.prepared.whole("why", lambda: why_html(page.results)))
    return folded("why", "Why: what each engine and preset solves", why,
                  f"{escape_html(', '.join(page.engines))}; {len(page.labels)} engine presets"
                  if page.labels else "no engine ran", unfolded=True)


def split_section(page: Page) -> str:
    split = [
        "<p>Each point is one engine run. <b>Law part</b>: how far the engines' own law "
        "(<code>newton-lcp</code>) is from Poisson at that impact; <b>solve part</b>: how far "
        "the engine is from <code>newton-lcp</code>. The total departure from Poisson is at "
        "most their sum.</p>"]
    if "split" in page.figures:
        split.append(report_figure(page.figures, page.figures["split"], "departure split"))
    numbers = page.prepared.whole("split", lambda: split_table(page.results, page.prepared))
    if numbers:
        split.append("<details><summary>the numbers (largest over sweep points)</summary>"
                     + numbers + "</details>")
    return folded("split", "Law vs solve: the law they solve against how well they "
                  "solve it", "\n".join(split), split_summary(page.names, page.prepared),
                  unfolded=True)


def gates_section(page: Page) -> str:
    prov = page.provenance
    return folded("gates", "Gates", "<p>Tolerance gates declared by the scenarios "
                  "(<code>[expect.gate]</code>); a failing gate makes <code>impact-harness "
                  "run</code> exit non-zero.</p>" + gates_html(prov), gates_summary(prov),
                  unfolded=True)


def scenarios_section(page: Page) -> str:
    """Each scenario's section (folded per family when there are many), with what their
    tables and figures show."""
    figures, names, renamed = page.figures, page.names, page.renamed
    scenarios = [
        "<p>Per scenario (each folded under its runs' counts; unfold one): post-impact "
        "speeds of "
        "every law and engine (engine rows shaded; red when the engine flagged the "
        "run), contact velocities after the impact (v<sub>n</sub>, v<sub>t</sub>, in "
        "the contact frame), energy change, collision type (Poisson/Stronge 1–5: "
        + "; ".join(f"{k} {v}" for k, v in TYPE_NAMES.items())
        + "; Newton laws and engines: 1 stick, 2 reverse slide, 3 forward slide) and "
        "each engine run's status beside its departures (its notes numbered under "
        "the table). "
        "The impulse diagram is Routh's graph (the paper's Fig. 1): the path of each "
        "law's impulse and every end point; filled engine markers are "
        "<i>accurate</i>" + (f" ({renamed})" if renamed else "") + ", hollow <i>defaults</i>, and "
        "engines that land on the same "
        "point are drawn side by side. Sweeps show post-impact quantities against "
        "the swept parameter instead, laws as lines and engines as points (flagged "
        "runs ringed in red), with the points where the Poisson collision type "
        "changes dashed. Every figure links to its SVG.</p>"]
    if figures.get("many") and figures.get("scenario_figures") != "all":
        scenarios.append(f"<p class='muted'>With {len(names)} scenarios the per-scenario "
                         "figures are not drawn (they would take minutes); <code>impact-harness"
                         " report --figures-for 'PATTERN'</code> draws those of the scenarios "
                         "matching a pattern, <code>--scenario-figures all</code> every one."
                         "</p>")
    for tag, members in (figures.get("groups") or {"": names}).items():
        if tag:  # many scenarios: folded per tag
            scenarios.append(f"<details class='group'><summary><b>{escape_html(tag)}</b> "
                             f"({len(members)} scenarios)</summary>")
        for name in members:
            scenarios.append(cached_section(name, page.results, figures, page.prepared))
        if tag:
            scenarios.append("</details>")
    with_flags = flagged_scenarios(names, page.prepared)
    return folded("scenarios", "Scenarios", "\n".join(scenarios),
                  f"{len(names)} scenarios"
                  + (f", {with_flags} with flagged runs" if with_flags else ""), unfolded=True)


def versions_section(page: Page) -> str:
    prov = page.provenance
    git = prov.get("git", {})
    versions = (versions_html(prov) + "<h3>Engine settings per preset</h3><p>Bold where the "
                "presets differ. The table is the presets as run, with the command line's "
                "<code>--set</code> overrides; scenario files may override settings too "
                "(<code>[engine_settings.&lt;engine&gt;]</code>); such runs carry the "
                "overrides in their labels and in each record's diagnostics in "
                "<code>results.json</code>.</p>" + settings_table(prov))
    return folded("versions", "Versions and settings", versions,
                  f"commit <code>{escape_html(str(git.get('commit'))[:10])}</code>, "
                  f"results of {escape_html(prov.get('created_utc', ''))}")
