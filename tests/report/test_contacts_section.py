"""The report's section on several contacts (harness/report/contacts.py)."""

from __future__ import annotations

from harness.report.contacts import COUNTS, contacts_section
from harness.run import runner
from harness.run.records import Results
from harness.scenarios import load_scenario


def test_a_flat_scene_gets_a_table_and_a_single_contact_scene_none():
    scenarios = [load_scenario("scenarios/flat-box.toml"),
                 load_scenario("scenarios/box-corner.toml")]
    outcome = runner.run(scenarios, engines=("pymunk",), presets=("accurate",), log=None)
    results = Results(records=outcome.records, provenance=outcome.provenance,
                      scenarios=outcome.scenarios)
    html, markdown = contacts_section(results)
    assert "<h3>flat-box</h3>" in html and "box-corner" not in html
    # every table scrolls in its own wrapper: a wide one must not widen the page
    assert html.count("<table>") == html.count('<div class="scroll"><table>') > 0
    row = next(line for line in markdown.splitlines() if line.startswith("| (single point)"))
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert cells[1] == "simultaneous: newton-coulomb"
    counts = outcome.scenarios["flat-box"]["references"][0]["solutions"]
    # The reference's own counts; those at the boundary of a decision apart (docs/multi-contact.md,
    # 'Decisions at a boundary'): flat-box's effective Poisson solution sits on Types 4 | 5.
    shown = cells[2:2 + len(COUNTS)]
    assert shown == [str(counts[key]) + (
        f" (+{counts[key + '/at-boundary']} at boundary)"
        if counts.get(key + "/at-boundary") else "") for key, _ in COUNTS]
    assert "0 (+1 at boundary)" in shown
    # pymunk.accurate against Newton–Coulomb, then against the two-phase Poisson law (on the
    # symmetric flat box both leave at e|v_y| without spin: the same answer)
    departure, two_phase = cells[-1].split(" [P 2φ: ")
    assert float(departure) <= 1e-6 and float(two_phase.rstrip("]")) <= 1e-6
