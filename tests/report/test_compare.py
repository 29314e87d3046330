"""``impact-harness compare``: matching, the threshold and its exit codes, the CSV export.

The results files are built by hand, so every expected change is known exactly: a
departure of 10% becoming 11.5% is a change of +1.5 percentage points.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from harness import cli
from harness.report import compare
from harness.run.records import ANALYTIC, Record, write_results
from harness.scenarios import SCENARIO_DIR

U_BEFORE = [3.0, -4.0, 0.0]  # norm 5, Euclidean and in disk-direct's KE norm (1 kg)


def engine_record(departure: float, u_after=(1.0, 2.0, 0.0), status: str = "ok",
                  scenario: str = "disk-direct", preset: str = "defaults") -> Record:
    return Record(scenario=scenario, point={"index": 0, "label": "", "value": None},
                  source="pymunk", preset=preset, u_before=list(U_BEFORE),
                  u_after=list(u_after), status=status,
                  departure={"poisson": departure, "stronge": departure})


def law_record(scenario: str = "disk-direct") -> Record:
    return Record(scenario=scenario, point={"index": 0, "label": "", "value": None},
                  source=ANALYTIC, law="poisson", u_before=list(U_BEFORE),
                  u_after=[1.0, 2.0, 0.0], departure={"poisson": 0.0, "stronge": 0.0})


def results_file(tmp_path, name, records, provenance=None, scenarios=None):
    return write_results(tmp_path / name, records, {"gates": [], **(provenance or {})},
                         scenarios or {})


DISK_SPEEDS = {"disk-direct": {"speed_labels": ["disk.v_x [m/s]", "disk.v_y [m/s]",
                                                "disk.ω [rad/s]"]}}


def run_compare(*argv) -> int:
    return cli.main(["compare", *map(str, argv)])


def test_threshold_parsing():
    assert compare.parse_threshold("1%") == pytest.approx(0.01)
    assert compare.parse_threshold("0.2pp") == pytest.approx(0.002)
    assert compare.parse_threshold(" 5 PP ") == pytest.approx(0.05)
    assert compare.parse_threshold("0") == 0.0
    for bad in ("x", "-1%", "nan%", "inf pp", "%", "9" * 5000 + "%"):
        with pytest.raises(ValueError, match="allowed: a change in percentage points"):
            compare.parse_threshold(bad)


@pytest.mark.parametrize("bare", ["5", "0.05", "1e-2"])
def test_a_bare_threshold_is_refused_as_ambiguous(bare, tmp_path, capsys):
    """`--fail-above 5` meant 500 pp (a fraction) while the default printed 1%."""
    with pytest.raises(ValueError, match="ambiguous"):
        compare.parse_threshold(bare)
    good = results_file(tmp_path, "a.json", [engine_record(0.1)])
    capsys.readouterr()
    assert run_compare(good, good, "--fail-above", bare) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and "ambiguous" in err


def test_a_change_below_the_threshold_passes_and_above_fails(tmp_path):
    before = results_file(tmp_path, "a.json", [law_record(), engine_record(0.100)])
    after = results_file(tmp_path, "b.json", [law_record(), engine_record(0.115)])
    # +1.5 percentage points on both departures; the speeds are unchanged.
    assert run_compare(before, after, "--fail-above", "2%") == 0
    assert run_compare(before, after, "--fail-above", "1%") == 1
    assert run_compare(before, after, "--fail-above", "1.4pp") == 1
    assert run_compare(before, before) == 0  # identical files never fail


def test_speed_change_is_relative_to_the_speeds_before(tmp_path):
    before = results_file(tmp_path, "a.json", [engine_record(0.1, u_after=(1.0, 2.0, 0.0))])
    after = results_file(tmp_path, "b.json", [engine_record(0.1, u_after=(1.0, 2.1, 0.0))])
    changes, _, _ = compare.compare(*(compare.read_results(p) for p in (before, after)))
    assert changes[0].speed_change == pytest.approx(0.1 / 5.0)  # Δv_y 0.1 (1 kg) over 5
    assert run_compare(before, after, "--fail-above", "2.5%") == 0
    assert run_compare(before, after, "--fail-above", "1.5%") == 1


def test_a_status_change_fails_whatever_the_threshold(tmp_path):
    before = results_file(tmp_path, "a.json", [engine_record(0.1)])
    after = results_file(tmp_path, "b.json", [engine_record(0.1, status="multi-contact")])
    assert run_compare(before, after, "--fail-above", "100%") == 1


def test_records_new_in_b_are_listed_and_records_gone_from_b_fail(tmp_path, capsys):
    """A CI gate: a run that does more passes (its new records listed and counted); one
    that lost a record fails, whatever --fail-above (it no longer sees what it checked)."""
    before = results_file(tmp_path, "a.json", [engine_record(0.1)])
    after = results_file(tmp_path, "b.json",
                         [engine_record(0.1), engine_record(0.5, scenario="rod")])
    assert run_compare(before, after) == 0
    out = capsys.readouterr().out
    assert "1 records only in B (new" in out and "0 gone, 1 new" in out
    assert run_compare(after, before, "--fail-above", "100%") == 1
    out = capsys.readouterr().out
    assert "1 records only in A (gone" in out and "1 gone, 0 new" in out


@pytest.mark.parametrize("where", ["departure", "law"])
def test_a_law_the_registry_does_not_hold_is_refused(tmp_path, capsys, where):
    """A departure from a law the harness does not know was never weighed: a change in it
    passed the gate unseen. Refused as bad input, naming the file, record and law."""
    before = results_file(tmp_path, "a.json", [law_record(), engine_record(0.1)])
    document = json.loads(before.read_text(encoding="utf-8"))
    record = document["records"][0 if where == "law" else 1]
    if where == "law":
        record["law"] = "newton-typo"
    else:
        record["departure"]["newton-typo"] = 0.5
    after = tmp_path / "b.json"
    after.write_text(json.dumps(document), encoding="utf-8")
    for argv in ((before, after), (after, before)):
        assert run_compare(*argv) == 2
        err = capsys.readouterr().err
        assert str(after) in err and "newton-typo" in err and "allowed: poisson" in err


def test_bad_input_exits_2(tmp_path):
    good = results_file(tmp_path, "a.json", [engine_record(0.1)])
    other = results_file(tmp_path, "b.json", [engine_record(0.1, scenario="rod")])
    (tmp_path / "not-results.json").write_text(json.dumps({"format": "something else"}))
    (tmp_path / "broken.json").write_text("{")
    assert run_compare(good, tmp_path / "missing.json") == 2
    assert run_compare(good, tmp_path / "not-results.json") == 2
    assert run_compare(good, tmp_path / "broken.json") == 2
    assert run_compare(good, good, "--fail-above", "lots") == 2
    assert run_compare(good, other) == 2  # nothing in common


def test_csv_holds_both_values_and_the_change(tmp_path):
    before = results_file(tmp_path, "a.json", [law_record(), engine_record(0.100)])
    after = results_file(tmp_path, "b.json", [law_record(), engine_record(0.115)],
                         scenarios=DISK_SPEEDS)
    out = tmp_path / "diff.csv"
    assert run_compare(before, after, "--csv", out) == 1
    rows = list(csv.DictReader(out.open()))
    assert sorted(row["source"] for row in rows) == ["poisson", "pymunk.defaults"]
    engine = next(row for row in rows if row["source"] == "pymunk.defaults")
    # one unit with the terminal and the report: percent, and percentage points
    assert float(engine["departure_poisson_a_pct"]) == pytest.approx(10.0)
    assert float(engine["departure_poisson_b_pct"]) == pytest.approx(11.5)
    assert float(engine["departure_poisson_change_pp"]) == pytest.approx(1.5)
    assert float(engine["speed_change_pct"]) == 0.0
    # speeds named as the scenario names them, not u1, u2 …
    assert engine["speed_1_name"] == "disk.v_x [m/s]" and float(engine["speed_2_b"]) == 2.0
    assert engine["status_a"] == engine["status_b"] == "ok"


def test_summary_per_source_against_one_law_with_the_settings_that_differ(tmp_path, capsys):
    settings = {"pymunk": {"defaults": {"iterations": 10, "time_step": 0.01}}}
    before = results_file(
        tmp_path, "a.json",
        [law_record(), engine_record(0.100), engine_record(0.300, preset="accurate"),
         engine_record(0.2, scenario="disk-oblique")],
        {"versions": {"pymunk": "7.3.1"}, "engine_settings": settings})
    changed = {"pymunk": {"defaults": {"iterations": 2, "time_step": 0.01}}}
    after = results_file(
        tmp_path, "b.json",
        [law_record(), engine_record(0.115), engine_record(0.250, preset="accurate"),
         engine_record(0.1, scenario="rod-45-slip-reversal")],
        {"versions": {"pymunk": "7.4.0"}, "engine_settings": changed})
    rows, only_a, only_b = compare.compare(*map(compare.read_results, (before, after)))
    summary = {row.source: row for row in compare.summarise(rows, only_a, only_b, "poisson",
                                                            0.01)}
    defaults, accurate = summary["pymunk.defaults"], summary["pymunk.accurate"]
    assert (defaults.matched, defaults.worse, defaults.improved) == (1, 1, 0)
    assert defaults.worst_change == pytest.approx(0.015)
    assert (defaults.new, defaults.gone) == (1, 1)  # one scenario only in B, one only in A
    assert (accurate.improved, accurate.worse) == (1, 0)
    assert accurate.median_change == pytest.approx(-0.05)
    assert summary["poisson"].matched == 1 and summary["poisson"].worst_change == 0.0
    differences = compare.setting_differences(*map(compare.read_results, (before, after)))
    assert ("version of pymunk", "7.3.1", "7.4.0") in differences
    assert ("pymunk.defaults.iterations", "10", "2") in differences
    assert not any("time_step" in what for what, _, _ in differences)
    # the terminal and the page show the same: the summary, the differences, before/after
    page = tmp_path / "compare.html"
    assert run_compare(before, after, "--html", page, "--law", "stronge") == 1
    text = capsys.readouterr().out
    assert "departures from stronge" in text and "pymunk.defaults.iterations: 10 → 2" in text
    assert "10%" in text and "11.5%" in text and "+1.5 pp" in text
    html = page.read_text(encoding="utf-8")
    assert "Per source" in html and "pymunk.defaults.iterations" in html and "11.5%" in html
    # closer to the law chosen, never "improved" (closer is not better for a gate on another
    # law); the threshold in the unit of each thing it bounds
    for shown in (text, html):
        assert "closer to stronge" in shown and "further from stronge" in shown
        assert "improved" not in shown
        assert "more than 1 pp (a departure) or 1% of the motion (the speeds)" in shown


def test_help_documents_the_exit_status(capsys):
    with pytest.raises(SystemExit):
        cli.main(["compare", "--help"])
    text = capsys.readouterr().out
    assert "Exit status: 0" in text and "1 when" in text and "2 on bad input" in text
    assert "--fail-above" in text and "--csv" in text


ROD = "rod-45-slip-reversal"  # 1 kg, inertia 1/12 kg m^2, on the ground
TWO_DISKS = "two-disks-off-centre"  # free disks of 1 kg and 2 kg: a frame-free scale


def speeds_record(scenario, u_before, u_after) -> Record:
    return Record(scenario=scenario, point={"index": 0, "label": "", "value": None},
                  source="pymunk", preset="defaults", u_before=list(u_before),
                  u_after=list(u_after), departure={"poisson": 0.1})


def speed_change_of(tmp_path, scenario, u_before, u_a, u_b, scenarios=None) -> float:
    files = [write_results(tmp_path / name, [speeds_record(scenario, u_before, u)], {"gates": []},
                           scenarios or {})
             for name, u in (("a.json", u_a), ("b.json", u_b))]
    changes, _, _ = compare.compare(*(compare.read_results(f) for f in files))
    return changes[0].speed_change


def test_speed_change_weighs_the_speeds_by_the_mass_matrix(tmp_path):
    """A change of the rod's spin alone: weighed by its inertia (1/12 kg m^2), as the
    departures are, not counted as if rad/s were m/s."""
    before = [0.5, -1.0, 0.0]  # ‖u‖_M = sqrt(1.25): 1 kg, no spin
    change = speed_change_of(tmp_path, ROD, before, [0.1, 0.4, 1.0], [0.1, 0.4, 1.5],
                             {ROD: {"path": str(SCENARIO_DIR / f"{ROD}.toml")}})
    assert change == pytest.approx((1 / 12) ** 0.5 * 0.5 / 1.25 ** 0.5)
    assert change < 0.3 * 0.5 / 1.25 ** 0.5  # the Euclidean measure said 0.45


def test_speed_change_finds_a_moved_scenario_in_the_library(tmp_path):
    """A results file made elsewhere records a path that does not exist here."""
    moved = {ROD: {"path": "/elsewhere/scenarios/rod-45-slip-reversal.toml"}}
    change = speed_change_of(tmp_path, ROD, [0.5, -1.0, 0.0], [0.0, 0.0, 1.0],
                             [0.0, 0.0, 1.5], moved)
    assert change == pytest.approx((1 / 12) ** 0.5 * 0.5 / 1.25 ** 0.5)


def test_speed_change_is_frame_free_between_free_bodies(tmp_path):
    """A common velocity of both free disks changes neither the departures nor this."""
    before = [1.0, 0.0, 0.0, 0.0, -1.0, 5.0]
    u_a = [0.2, 0.3, 0.0, 0.4, -0.2, 4.0]
    u_b = [0.25, 0.3, 0.0, 0.4, -0.2, 4.0]
    common = [3.0, 1.0, 0.0, 3.0, 1.0, 0.0]

    def shifted(u):
        return [v + c for v, c in zip(u, common)]

    change = speed_change_of(tmp_path, TWO_DISKS, before, u_a, u_b)
    moving = speed_change_of(tmp_path, TWO_DISKS, shifted(before), shifted(u_a), shifted(u_b))
    assert change == pytest.approx(moving, rel=1e-12)
    # the scale: before, relative to the centre of mass (1 kg at (1, 0), 2 kg at (0, -1))
    centre = [1 / 3, -2 / 3]
    relative_energy = ((1 - centre[0]) ** 2 + centre[1] ** 2
                       + 2 * (centre[0] ** 2 + (-1 - centre[1]) ** 2)
                       + 0.5 * 2 * 0.1 ** 2 * 5.0 ** 2)  # disk b's spin: m r^2 / 2
    assert change == pytest.approx(0.05 / relative_energy ** 0.5)


def test_a_scenario_without_its_file_gets_no_speed_change(tmp_path, capsys):
    before = results_file(tmp_path, "a.json", [engine_record(0.1, scenario="gone")])
    after = results_file(tmp_path, "b.json",
                         [engine_record(0.1, u_after=(1.0, 9.0, 0.0), scenario="gone")])
    assert run_compare(before, after) == 0  # the departures did not change
    out = capsys.readouterr().out
    assert "speeds not compared for 1 scenarios" in out and "gone" in out


@pytest.mark.parametrize("rod_mass", [1.0, 2.0])
def test_speeds_are_weighed_only_by_a_file_with_the_runs_masses(tmp_path, capsys, rod_mass):
    """The records' energy change, ½uᵀMu after minus before, says which masses weighed the
    runs: a scenario file edited since (here, a rod of 2 kg) weighs no speeds."""
    mass_matrix = rod_mass * np.diag([1.0, 1.0, 1 / 12])  # the rod's, at rod_mass kg
    before, u_a, u_b = [0.5, -1.0, 0.0], [0.1, 0.4, 1.0], [0.1, 0.4, 1.5]
    paths = []
    for name, u_after in (("a.json", u_a), ("b.json", u_b)):
        record = speeds_record(ROD, before, u_after)
        record.energy_change = 0.5 * (np.dot(u_after, mass_matrix @ u_after)
                                      - np.dot(before, mass_matrix @ before))
        paths.append(write_results(tmp_path / name, [record], {"gates": []},
                                   {ROD: {"path": str(SCENARIO_DIR / f"{ROD}.toml")}}))
    assert run_compare(*paths, "--fail-above", "100%") == 0
    out = capsys.readouterr().out
    assert ("no longer has the masses" in out) == (rod_mass != 1.0)
    changes, _, _ = compare.compare(*(compare.read_results(path) for path in paths))
    if rod_mass == 1.0:
        assert changes[0].speed_change == pytest.approx((1 / 12) ** 0.5 * 0.5 / 1.25 ** 0.5)
    else:
        assert np.isnan(changes[0].speed_change)  # n/a


# Issue 37, item 7: a result that became NaN, duplicated records, speeds of the wrong length
@pytest.mark.parametrize("what", ["departure", "speeds"])
def test_a_result_that_became_not_finite_is_a_change_whatever_the_threshold(tmp_path, capsys,
                                                                             what):
    before = results_file(tmp_path, "a.json", [law_record(), engine_record(0.1)])
    broken = (engine_record(float("nan")) if what == "departure"
              else engine_record(0.1, u_after=(1.0, float("nan"), 0.0)))
    after = results_file(tmp_path, "b.json", [law_record(), broken])
    capsys.readouterr()
    assert run_compare(before, after, "--fail-above", "100%") == 1
    out = capsys.readouterr().out
    assert "1 changed by more than" in out
    assert ("0.1 → null" if what == "departure" else "speeds became not finite") in out
    assert "0 changed" not in out


def test_speeds_of_another_length_are_a_change_not_a_silent_na(tmp_path, capsys):
    before = results_file(tmp_path, "a.json", [engine_record(0.1)])
    after = results_file(tmp_path, "b.json", [engine_record(0.1, u_after=(1.0, 2.0))])
    capsys.readouterr()
    assert run_compare(before, after, "--fail-above", "100%") == 1
    assert "3 speeds → 2" in capsys.readouterr().out


def test_a_file_holding_a_run_twice_is_refused(tmp_path, capsys):
    good = results_file(tmp_path, "a.json", [engine_record(0.1)])
    twice = results_file(tmp_path, "b.json", [engine_record(0.1), engine_record(0.9)])
    capsys.readouterr()
    assert run_compare(good, twice) == 2
    err = capsys.readouterr().err
    assert "two records of one run" in err and "pymunk.defaults" in err


def test_the_rows_are_sorted_by_a_column_they_show(tmp_path, capsys):
    """The largest change of any law (stronge here) sorts the rows: it is shown."""
    def record(preset, poisson, stronge):
        made = engine_record(0.1, preset=preset)
        made.departure = {"poisson": poisson, "stronge": stronge}
        return made

    before = results_file(tmp_path, "a.json", [record("defaults", 0.1, 0.1),
                                               record("accurate", 0.1, 0.1)])
    after = results_file(tmp_path, "b.json", [record("defaults", 0.12, 0.12),
                                              record("accurate", 0.1, 0.15)])
    capsys.readouterr()
    run_compare(before, after, "--fail-above", "100%")
    out = capsys.readouterr().out
    table = out[out.index("largest changes"):]
    assert "largest" in table.splitlines()[1]
    accurate, defaults = table.index("pymunk.accurate"), table.index("pymunk.defaults")
    assert accurate < defaults and "5 pp" in table and "2 pp" in table


def test_csv_cells_never_start_a_formula(tmp_path):
    """A status is free text from the results file (a scenario's name is refused unless it
    is a scenario's name, which never starts a formula)."""
    name = '=HYPERLINK("http://example.invalid","x")'
    before = results_file(tmp_path, "a.json", [engine_record(0.1, status=name)])
    after = results_file(tmp_path, "b.json", [engine_record(0.2, status="+" + name)])
    out = tmp_path / "diff.csv"
    run_compare(before, after, "--csv", out, "--fail-above", "100%")
    (row,) = list(csv.DictReader(out.open()))
    assert row["status_a"] == "'" + name and row["status_b"] == "'+" + name


def test_speeds_that_are_not_those_of_their_own_energy_change_are_a_change(tmp_path, capsys):
    """B's speeds scaled (or 1e308) while its recorded energy change stays: B's record is
    malformed (A's speeds give A's energy change, so the scenario's masses are the runs')."""
    def record(u_after):
        made = engine_record(0.1, u_after=u_after)
        made.energy_change = -10.0  # ½(1 + 4) − ½·25 with disk-direct's 1 kg
        return made

    before = results_file(tmp_path, "a.json", [record((1.0, 2.0, 0.0))])
    for u_after in ((1e3, 2e3, 0.0), (1e308, 1e308, 0.0)):
        after = results_file(tmp_path, "b.json", [record(u_after)])
        capsys.readouterr()
        assert run_compare(before, after, "--fail-above", "100%") == 1
        said = capsys.readouterr()
        assert "speeds not those of its own energy change" in said.out and not said.err
