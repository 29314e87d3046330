"""``summary.md``: the report's headline numbers as a Markdown page."""

from __future__ import annotations

import re
from pathlib import Path

from harness.report.contacts import contacts_section
from harness.report.fragments import Prepared, prepare
from harness.report.views import (
    HEADLINE_LAWS,
    LAW_STYLE,
    command_overrides,
    fmt_departure,
    row_name,
)
from harness.run.records import ANALYTIC, Results
from harness.run.verdicts import REASONS, reason_counts
from harness.store.files import write_text_atomically

_MARKDOWN_SPECIAL = re.compile(r"([\\`*_{}\[\]()#+!|~])")


def escape(text) -> str:
    """``text`` as literal Markdown: special characters backslash-escaped, ``<``/``>``/``&``
    as entities, line breaks as spaces (a name from results.json cannot format the page)."""
    text = str(text).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return _MARKDOWN_SPECIAL.sub(r"\\\1", " ".join(text.splitlines()))


def runs_lines(results: Results) -> list[str]:
    """The lines of ``summary.md`` on the engine runs: how many are single impacts, the runs
    per reason and every run not ok."""
    flagged = [r for r in results.records if r.source != ANALYTIC and not r.ok]
    engine_runs = [r for r in results.records if r.source != ANALYTIC and not r.skipped]
    counts = reason_counts([r.reasons for r in engine_runs])
    lines = ["", "## Verdicts", "",
             f"{sum(r.ok for r in engine_runs)} of {len(engine_runs)} engine runs are single "
             f"impacts; runs per reason (a run can fail several checks):", ""]
    # each with what it says: 'no-separation' (the engine's status) and 'not-separated' (a
    # check of the speeds after) are easily taken for one another
    lines += [f"- {name}: {count}" + (f" ({escape(REASONS[name])})" if name in REASONS else "")
              for name, count in sorted(counts.items())] or ["- none"]
    lines += ["", "## Runs not ok", ""]
    lines += [f"- {run_not_ok_line(r)}" for r in flagged] or ["None."]
    return lines


def run_not_ok_line(record) -> str:
    """``scenario point source: status (reasons)``: a single-point scenario's empty point
    label and the reasons that only repeat the status (an engine's ``penetration`` is also
    its reason) left out."""
    where = " ".join(escape(part) for part in (record.scenario, record.point["label"],
                                               record.label) if part)
    reasons = [reason for reason in record.failing_reasons if reason != record.status]
    return (f"{where}: {escape(record.status)}"
            + (f" ({escape(', '.join(reasons))})" if reasons else ""))


def write_summary(results: Results, out_dir: Path, prepared: Prepared | None = None) -> Path:
    """Write ``summary.md``; ``prepared``: the scenarios' views
    (:func:`harness.report.fragments.prepare`, computed here when not given)."""
    prov = results.provenance
    prepared = prepare(results) if prepared is None else prepared
    labels = prepared.labels
    lines = ["# Planar impact with friction: engines against the exact laws", "",
             "Departure of each engine (and preset) from the exact laws, "
             "`‖u_engine − u_law‖_M / ‖u_before‖_M` with `u_before` in the ground's frame, or "
             "the centre of mass's for two free bodies (relative error of the post-impact "
             "velocities in the kinetic-energy norm; sweeps: the largest over the sweep). "
             "`(k!)` counts the flagged runs, `(k of n!)` of a sweep's n (not single impacts: the "
             "engine's status or a failed verdict check, docs/verdicts.md), never included "
             "in the value; `*` marks "
             "runs whose settings differ from the preset's (a scenario's `[engine_settings]` "
             "or the command line's `--set`), `skipped` an engine that did not run. "
             "Figures, per-scenario tables and settings: [index.html](index.html)"
             + ("; the paper's Table 3: [paper-table3.md](paper-table3.md)"
                if (out_dir / "paper-table3.md").is_file() else "") + ".", ""]
    command = command_overrides(prov)
    if command:  # the columns are not the presets' numbers
        lines += [f"**Not the presets as shipped**: this run set `{escape(command)}` on the "
                  "command line (`--set`), in every preset of those engines; their columns "
                  "(marked `--set`) are the departures with those settings.", ""]
    given = prov.get("settings_overrides") or {}
    headers = [label + (" (--set)" if given.get(label.split(".")[0]) else "")
               for label in labels]
    # the heat map's rows (views.engine_scenarios)
    names = [name for name, view in prepared.views.items() if view["engine"]]
    for law in HEADLINE_LAWS:
        lines += [f"## Departure from {LAW_STYLE[law][2]}", "",
                  "| scenario | " + " | ".join(headers) + " |",
                  "|---|" + "---:|" * len(labels)]
        for name in names:
            cells = [cell[3] for cell in prepared.views[name][law]]  # views.departure_cell
            lines.append(f"| {escape(row_name(results, name))} | " + " | ".join(cells) + " |")
        lines.append("")
    # flat faces and tilts: departures from the references that apply to them only

    contacts = prepared.whole("summary-contacts", lambda: contacts_section(results)[1])
    if contacts:
        lines += [contacts, ""]
    gates = prov.get("gates", [])
    lines += ["## Gates", ""]
    if gates:
        points = any(g.get("point") for g in gates)  # a sweep's rows told apart
        lines += ["| scenario | " + ("point | " if points else "")
                  + "gate | record | law | departure | max | result |",
                  "|---|" + ("---|" if points else "") + "---|---|---|---:|---:|---|"]
        for g in gates:
            lines.append(f"| {escape(g['scenario'])} | "
                         + (f"{escape(g.get('point') or '')} | " if points else "")
                         + f"{escape(g['gate'])} | "
                         f"{escape(g['record'])} | {escape(g['law'])} | "
                         f"{fmt_departure(g['departure'])} | {fmt_departure(g['max_departure'])}"
                         f" | {escape(g['status'])} |")
    else:
        lines.append("No gates in this run.")
    # kept while no record changed: these read every record
    lines += prepared.whole("summary-runs", lambda: runs_lines(results))
    versions = prov.get("versions", {})
    git = prov.get("git", {})
    lines += ["", "## Versions", "",
              ", ".join(f"{k} {v}" for k, v in versions.items() if v is not None) + ".",
              f"Commit `{git.get('commit')}`" + (" (uncommitted changes)" if git.get("dirty")
                                                  else "")
              + f"; results written {prov.get('created_utc', '')}.", ""]
    path = out_dir / "summary.md"
    write_text_atomically(path, "\n".join(lines))  # over a regular file only
    return path
