"""The HTML page of the report (``index.html``): self-contained, inline CSS, no scripts."""

from __future__ import annotations

import math
import re
import time
from pathlib import Path
from typing import Sequence

from harness.engines import ENGINE_NAMES, PRESET_NAMES
from harness.report.views import (
    FIGURES,
    LAW_ORDER,
    LAW_STYLE,
    TYPE_NAMES,
    escape_html,
    fmt_departure,
    fmt_number,
    slug,
)
from harness.run.records import ANALYTIC, Record, Results

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


def header_cell(text: str) -> str:
    """A header with its unit (``"v_x [m/s]"``) on a second line, to keep columns narrow."""
    name, bracket, unit = str(text).partition(" [")
    return escape_html(name) + (f"<br><span class='muted'>[{escape_html(unit)}</span>" if bracket else "")


def html_table(header: Sequence[str], rows: Sequence[Sequence], left: int = 1,
           row_classes: Sequence[str] | None = None) -> str:
    out = ["<table><tr>" + "".join(
        f'<th class="l">{header_cell(h)}</th>' if i < left else f"<th>{header_cell(h)}</th>"
        for i, h in enumerate(header)) + "</tr>"]
    for k, row in enumerate(rows):
        cls = f' class="{row_classes[k]}"' if row_classes and row_classes[k] else ""
        out.append(f"<tr{cls}>" + "".join(
            f'<td class="l">{cell}</td>' if i < left else f"<td>{cell}</td>"
            for i, cell in enumerate(row)) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def sorted_point_records(records: Sequence[Record]) -> list[Record]:
    laws = sorted((r for r in records if r.source == ANALYTIC),
                  key=lambda r: LAW_ORDER.index(r.law) if r.law in LAW_ORDER else 99)
    ENGINES, PRESETS = ENGINE_NAMES, PRESET_NAMES

    engines = sorted((r for r in records if r.source != ANALYTIC),
                     key=lambda r: (PRESETS.index(r.preset) if r.preset in PRESETS else 9,
                                    ENGINES.index(r.source) if r.source in ENGINES else 9))
    return laws + engines


def velocity_table(records: Sequence[Record], speed_labels: Sequence[str]) -> str:
    """Post-impact speeds of every law and engine at one point, side by side."""
    ordered = sorted_point_records(records)
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
                else f"<b>{escape_html(r.label)}</b>")
        status = escape_html(r.status if len(r.status) < 60 else r.status[:57] + "…")
        rows.append([name, *(fmt_number(v) for v in speeds), fmt_number(r.vn_separation),
                     fmt_number(r.vt_separation), fmt_number(r.energy_change),
                     "–" if r.collision_type is None else str(r.collision_type),
                     fmt_departure(r.departure.get("poisson")),
                     fmt_departure(r.departure.get("stronge")),
                     status if r.status != "ok" else "ok"])
        classes.append("" if r.source == ANALYTIC else ("engine" if r.ok else "engine flag"))
    if all(r.ok for r in ordered):  # every status "ok": the column says nothing
        header, rows = header[:-1], [row[:-1] for row in rows]
    return html_table(header, rows, row_classes=classes)


def scenario_section(name: str, info: dict, records: Sequence[Record], figures: dict) -> str:
    parts = [f'<div class="scenario" id="{escape_html(slug(name))}">',
             f"<h3>{escape_html(name)}</h3>"]
    tags = ", ".join(info.get("tags", []))
    parts.append(f"<p>{escape_html(info.get('description', ''))} <span class='muted'>"
                 f"[{escape_html(info.get('system', ''))}; tags: {escape_html(tags)}]</span></p>")
    laws = [r for r in records if r.source == ANALYTIC and r.law == "poisson" and r.ok]
    if info.get("sweep"):
        if name in figures.get("sweep", {}):
            parts.append(f'<figure><img src="{FIGURES}/{figures["sweep"][name]}" '
                         f'alt="sweep of {escape_html(name)}"></figure>')
        points = list(dict.fromkeys(r.point["index"] for r in records))
        types = " → ".join(str(r.collision_type) for r in sorted(laws, key=lambda r: r.point["index"]))
        parts.append(f"<p>Poisson types along the sweep: {escape_html(types)}.</p>")
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
            diagram = (f'<img class="diagram" src="{FIGURES}/{figures["impulse"][name]}" '
                       f'alt="impulse diagram of {escape_html(name)}">')
        parts.append(f'<div class="pair"><div>{velocity_table(records, info.get("speed_labels", []))}'
                     f"</div>{diagram}</div>")
    parts.append("</div>")
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
        names = list(presets)
        keys = list(dict.fromkeys(k for p in presets.values() for k in p))
        rows = []
        for key in keys:
            values = [presets[p].get(key) for p in names]
            cells = [escape_html(json_short(v)) for v in values]
            if len(set(map(json_short, values))) > 1:
                cells = [f"<b>{c}</b>" for c in cells]
            rows.append([f"<code>{escape_html(key)}</code>", *cells])
        version = provenance.get("engine_versions", {}).get(engine, "")
        parts.append(f"<h4>{escape_html(engine)} {escape_html(version)}</h4>")
        parts.append(html_table(["setting", *names], rows))
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
        rows.append([escape_html(g["scenario"]), escape_html(g["gate"]), escape_html(g["record"]), escape_html(g["law"]),
                     fmt_departure(g["departure"]), fmt_departure(g["max_departure"]),
                     f'<span class="{cls}">{escape_html(g["status"])}</span>'])
    return html_table(["scenario", "gate", "record", "law", "departure", "max", "result"], rows,
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
        cells = [escape_html(scenario), fmt_departure(law_part)]
        for label in labels:
            group = grouped.get((scenario, label), [])
            solve = max((r["solve_part"] for r in group if math.isfinite(r["solve_part"])),
                        default=math.nan)
            cells.append(fmt_departure(solve))
        body.append(cells)
    return html_table(["scenario", "law part (newton-lcp vs Poisson)",
                   *[f"solve: {label}" for label in labels]], body)


def versions_html(provenance: dict) -> str:
    versions = provenance.get("versions", {})
    git = provenance.get("git", {})
    machine = provenance.get("machine", {})
    cache = provenance.get("cache", {})
    rows = [[escape_html(k), escape_html(v if v is not None else "not installed")] for k, v in versions.items()]
    rows += [["git commit", escape_html(f"{git.get('commit')}" + (" (uncommitted changes)"
                                                          if git.get("dirty") else ""))],
             ["code version", escape_html(str(provenance.get("code_version", ""))[:16])],
             ["machine", escape_html(f"{machine.get('platform')}, {machine.get('cpu_count')} cores")],
             ["results written", escape_html(provenance.get("created_utc", ""))],
             ["command", f"<code>{escape_html(' '.join(provenance.get('command', [])))}</code>"],
             ["engine runs", escape_html(f"{cache.get('engine_runs')} ({cache.get('simulated')} "
                                  f"simulated, {cache.get('hits')} from the cache)")],
             ["run wall time", escape_html(f"{provenance.get('wall_time_s', 0):.2f} s")]]
    for engine, reason in provenance.get("engines_missing", {}).items():
        rows.append([escape_html(f"skipped {engine}"), escape_html(reason)])
    return html_table(["item", "value"], rows, left=2)


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
        f"the physics engines {escape_html(', '.join(engines) or '(none)')} with their out-of-the-box "
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
        + f"; commit <code>{escape_html(str(git.get('commit'))[:10])}</code>, "
        f"{escape_html(prov.get('created_utc', ''))}.</p>")
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
                 + "".join(f"&nbsp;&nbsp;<a href='#{escape_html(slug(n))}'>{escape_html(n)}</a><br>"
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
    survey = Path("survey", "summary.md")  # written by impact-harness suite
    if (out_dir / survey).exists():
        parts.append(f"<h2 id='survey'>Survey</h2><p>Departures over random families of "
                     f"impacts: <a href='{survey.as_posix()}'>the survey's summary</a> (a "
                     f"quick survey; <code>impact-harness survey</code> for the full one).</p>")
    parts.append("<h2 id='versions'>Versions and settings</h2>" + versions_html(prov))
    parts.append("<h3>Engine settings per preset</h3><p>Bold where the presets differ. "
                 "Scenario files may override settings "
                 "(<code>[engine_settings.&lt;engine&gt;]</code>); the overrides are in each "
                 "record's diagnostics in <code>results.json</code>.</p>" + settings_table(prov))
    parts.append(f"<p class='muted'>Report generated {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} "
                 "by <code>impact-harness report</code>.</p></body></html>")
    path = out_dir / "index.html"
    path.write_text("\n".join(parts), encoding="utf-8")
    return path
