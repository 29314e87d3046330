"""The report's section on several contacts: flat faces and tilts (issue 13).

One table per scenario whose reference is not the single-contact laws (the runner's
``references`` in the scenario info, :mod:`harness.run.references`): per sweep point, the
reference used, how many solutions each m-contact law has, and each engine's departure from
the reference (``‖u − u_ref‖_M`` over the frame-free scale, docs/verdicts.md). For a tilt the
table also gives how far the simultaneous Newton–Coulomb answer and the sequential reading at
the tilted pose are from the event sequence, and which cut of the sequence each engine run is
nearest. :func:`contacts_section` returns the HTML fragment and the same tables in Markdown.
"""

from __future__ import annotations

import math
from html import escape

from harness.report.markup import folded
from harness.report.views import fmt_departure, single_contact

TITLE = "Several contacts: flat faces and tilts"

#: Solution counts shown, in this order: (key in the reference's "solutions", column title).
COUNTS = (("newton-coulomb", "N–C"), ("two-phase/poisson", "P 2φ"),
          ("coherent/poisson/literal", "P"), ("coherent/stronge-paper/literal", "S"),
          ("coherent/newton/literal", "N"), ("coherent/poisson/effective", "P eff*"),
          ("coherent/stronge-paper/effective", "S eff*"), ("coherent/newton/effective", "N eff*"))

INTRO = (
    "Scenes with several contacts are compared with the reference that matches them "
    "(docs/multi-contact.md, 'Which reference a run is compared with'): a face lying flat "
    "(contacts = \"simultaneous\") with the m-contact Newton–Coulomb law, the engines' law; a "
    "tilt (expect_sequence) with the event-driven sequence of single impacts (newton-lcp at "
    "each). Counts are the solutions of each m-contact law: Newton–Coulomb (N–C, solutions "
    "with distinct post-impact velocities), the two-phase Poisson law for m contacts (P 2φ: "
    "compression to zero approach, then e times each contact's compression impulse, Coulomb "
    "friction in both phases) and the coherent combinations of the paper's "
    "proposal after eq. (75) for Poisson (P), the paper's Stronge (S) and Newton (N): each "
    "contact's type formulas at its own approach, 5^m (3^m) combinations, kept where the "
    "paper's three tests hold. *eff: the effective reading, an extension, not the paper's: "
    "each contact's formulas see the other contacts' whole impulses in their approach, so "
    "restitution is counted twice (it gains energy on a symmetric flat box even with μ = 0). "
    "\"+k at boundary\": solutions with a decision (Table 1's type, I_n > 0) inside the "
    "rounding band, counted apart from the clearly coherent ones. Every solution is checked "
    "for admissibility as it is computed (docs/multi-contact.md, 'Admissible references'): "
    "\"k inadmissible\" counts those that break a check (an impulse at a contact that "
    "recedes at its start, complementarity at a phase's end, the friction cone, an energy "
    "gain where the law promises none); none is ever the reference. Newton–Coulomb can gain "
    "energy, a property of Newton's law (on a few percent of random flat landings: "
    "docs/multi-contact.md, 'Where Newton–Coulomb gains energy'): the reference column says "
    "so where it does, and an engine's gain is excused only up to the reference's own. "
    "Engine columns: departure from the reference (in percent, as everywhere in the "
    "report); for a tilt, in brackets, the cut of the "
    "sequence the run is nearest (full: all impacts; after-k: only the first k, with the "
    "departure from that cut); for a flat face, after 'P 2φ:', the departure from the "
    "two-phase Poisson law. A flagged run is shown as 'flagged' with its reasons and its "
    "number in square brackets, never as a departure: a tilt's runs run until the sequence's "
    "last impact and one that stops short is truncated-sequence; a flat face struck corner "
    "after corner is not-simultaneous (docs/verdicts.md). N–C at pose, sequential at pose: "
    "departure of those answers, taken at the tilted pose on the struck features, from the "
    "event sequence.")


def _count_text(value) -> str:
    """A number of solutions; ``n/a`` where the law was not solved."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return str(value)


def _rows(name: str, info: dict, records) -> tuple[list[str], list[list[str]]] | None:
    references = [r for r in info.get("references", []) if r.get("kind") != "single-contact"]
    if not references:
        return None
    # each run under the name users see for its preset (mujoco.matched-bounce), as elsewhere
    engines = sorted({r.label for r in records if r.source != "analytic"})
    tilt = any(r["kind"] == "event-driven" for r in references)
    header = ["point", "reference", *[title for _, title in COUNTS]]
    if tilt:
        header += ["N–C at pose", "sequential at pose"]
    header += engines
    rows = []
    for reference in references:
        label = reference.get("point") or "(single point)"
        counts = reference.get("solutions", {})
        primary = reference.get("primary")
        gains = " (gains energy)" if primary in reference.get("gains_energy", ()) else ""
        row = [label, f"{reference['kind']}: {primary}{gains}"]
        row += [_count(counts, key, reference.get("inadmissible", {})) for key, _ in COUNTS]
        if tilt:
            gaps = reference.get("departure_from_primary", {})
            order = "-".join(str(i) for i in sorted(
                {impact[0] for impact in reference.get("sequences", {}).get(
                    "newton-lcp", {}).get("impacts", [])}, key=lambda f: _first_strike(
                        reference, f)))
            row += [fmt_departure(gaps.get("at-pose/newton-coulomb")),
                    fmt_departure(gaps.get(f"at-pose/sequential/newton-lcp/{order}"))]
        by_engine = {r.label: r for r in records
                     if r.source != "analytic" and r.point.get("label", "") == reference.get(
                         "point", "")}
        for engine in engines:
            record = by_engine.get(engine)
            summary = (record.diagnostics or {}).get("reference", {}) if record else {}
            # every value in an engine cell is a departure (harness/run/references.py)
            cell = fmt_departure(summary.get("departure_from_primary"))
            if summary.get("nearest_cut"):
                cut, value = summary["nearest_cut"]
                cut = cut.rsplit("/", 1)[-1]
                cell += " (full)" if cut == "newton-lcp" else f" ({cut}: {fmt_departure(value)})"
            two_phase = (record.departure or {}).get("two-phase/poisson") if record else None
            if reference["kind"] == "simultaneous" and two_phase is not None:
                cell += f" [P 2φ: {fmt_departure(two_phase)}]"
            if record is not None and record.skipped:
                cell = "skipped"
            elif record is not None and not record.ok:  # not the situation: never a departure
                cell = f"flagged: {', '.join(record.failing_reasons) or record.status} [{cell}]"
            row.append(cell)
        rows.append(row)
    return header, rows


def _count(counts: dict, key: str, inadmissible: dict) -> str:
    """A law's number of solutions, those at the boundary of a decision apart, and how many
    of all of them break admissibility."""
    text = _count_text(counts.get(key))
    notes = []
    if counts.get(f"{key}/at-boundary"):
        notes.append(f"+{counts[f'{key}/at-boundary']} at boundary")
    broken = sum(name == key or name.startswith((f"{key}#", f"{key}/at-boundary"))
                 for name in inadmissible)
    if broken:
        notes.append(f"{broken} inadmissible")
    return f"{text} ({'; '.join(notes)})" if notes else text


def _first_strike(reference: dict, feature: int) -> float:
    impacts = reference.get("sequences", {}).get("newton-lcp", {}).get("impacts", [])
    return min(time for f, time, _ in impacts if f == feature)


def contacts_section(results) -> tuple[str, str]:
    """``(html, markdown)`` of the section; both empty when no scene has several contacts.
    The HTML is folded under how many scenarios, runs and flagged runs it shows.

    ``results`` is the report's :class:`harness.report.Results` (``scenarios`` with the
    runner's per-point ``references``, ``for_scenario(name)`` its records)."""
    html_parts, markdown_parts = [], []
    runs = flagged = 0
    for name, info in results.scenarios.items():
        records = results.for_scenario(name)
        table = _rows(name, info, records)
        if table is None:
            continue
        judged = [r for r in records if r.source != "analytic" and not single_contact(r)
                  and not r.skipped]
        runs += len(judged)
        flagged += sum(not r.ok for r in judged)
        header, rows = table
        # In a scrolling wrapper, as every table of the page: these have a column per engine.
        html_parts.append(f"<h3>{escape(name)}</h3><div class=\"scroll\"><table><tr>"
                          + "".join(f"<th>{escape(h)}</th>" for h in header) + "</tr>"
                          + "".join("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in row)
                                    + "</tr>" for row in rows) + "</table></div>")
        markdown_parts.append(f"### {name}\n\n| " + " | ".join(header) + " |\n|"
                              + "---|" * len(header) + "\n"
                              + "".join("| " + " | ".join(row) + " |\n" for row in rows))
    if not html_parts:
        return "", ""
    headline = (f"{len(html_parts)} scenarios, {runs} engine runs"
                + (f", <span class='fail'>{flagged} flagged</span>" if flagged else ""))
    html = folded("contacts", TITLE, "<p>" + escape(INTRO) + "</p>" + "\n".join(html_parts),
                  headline)
    markdown = f"## {TITLE}\n\n" + INTRO + "\n\n" + "\n".join(
        markdown_parts)
    return html, markdown


__all__ = ["contacts_section"]
