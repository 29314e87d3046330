"""The report's section on several contacts (harness/report/contacts.py)."""

from __future__ import annotations

from harness.report.contacts import COUNTS, contacts_section
from harness.run import runner
from harness.run.metrics import fmt_departure
from harness.run.records import Record, Results
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
    # Each law's solutions that break admissibility are counted too (docs/multi-contact.md,
    # 'Admissible references'): the effective reading's at-boundary one gains energy.
    inadmissible = outcome.scenarios["flat-box"]["references"][0]["inadmissible"]
    shown = cells[2:2 + len(COUNTS)]

    def expected(key):
        notes = ([f"+{counts[key + '/at-boundary']} at boundary"]
                 if counts.get(key + "/at-boundary") else [])
        broken = [name for name in inadmissible if name.split("#")[0] in (
            key, key + "/at-boundary")]
        notes += [f"{len(broken)} inadmissible"] if broken else []
        return str(counts[key]) + (f" ({'; '.join(notes)})" if notes else "")

    assert shown == [expected(key) for key, _ in COUNTS]
    assert "0 (+1 at boundary; 1 inadmissible)" in shown
    # pymunk.accurate against Newton–Coulomb, then against the two-phase Poisson law (on the
    # symmetric flat box both leave at e|v_y| without spin: the same answer)
    departure, two_phase = cells[-1].split(" [P 2φ: ")
    assert float(departure.rstrip("%")) <= 1e-4 and float(two_phase.rstrip("]%")) <= 1e-4


def _engine_record(scenario, preset, departure, summary):
    return Record(scenario=scenario, point={}, source="mujoco", preset=preset,
                  departure=departure, diagnostics={"reference": summary})


def test_every_departure_in_the_tables_is_in_percent():
    """The page's opening says departures are in percent throughout: the several-contacts
    cells (the run's departure, a tilt's nearest cut and the at-pose answers, a flat face's
    two-phase Poisson departure) are written by the report's departure formatter, with %."""
    flat = {"references": [{"kind": "simultaneous", "primary": "newton-coulomb",
                            "solutions": {"newton-coulomb": 1}}]}
    tilt = {"references": [{"kind": "event-driven", "primary": "newton-lcp",
                            "solutions": {"newton-coulomb": 2},
                            "departure_from_primary": {"at-pose/newton-coulomb": 0.3125,
                                                       "at-pose/sequential/newton-lcp/": 0.0625},
                            "sequences": {"newton-lcp": {"impacts": []}}}]}
    records = [
        _engine_record("flat", "defaults", {"two-phase/poisson": 0.1375},
                       {"departure_from_primary": 0.4725}),
        _engine_record("tilt", "defaults", {}, {"departure_from_primary": 0.0825,
                                                "nearest_cut": ["newton-lcp/after-1", 0.0275]}),
    ]
    results = Results(records=records, scenarios={"flat": flat, "tilt": tilt})
    _, markdown = contacts_section(results)
    rows = [line for line in markdown.splitlines() if line.startswith("| (single point)")]
    flat_cells = rows[0].strip("|").split("|")
    tilt_cells = rows[1].strip("|").split("|")
    assert flat_cells[-1].strip() == (f"{fmt_departure(0.4725)} [P 2φ: "
                                      f"{fmt_departure(0.1375)}]")
    assert tilt_cells[-1].strip() == f"{fmt_departure(0.0825)} (after-1: {fmt_departure(0.0275)})"
    assert [c.strip() for c in tilt_cells[-3:-1]] == [fmt_departure(0.3125),
                                                      fmt_departure(0.0625)]
    assert "0.47" not in markdown and all("%" in c for c in (*tilt_cells[-3:], flat_cells[-1]))
