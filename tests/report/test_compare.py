"""``impact-harness compare``: matching, the threshold and its exit codes, the CSV export.

The results files are built by hand, so every expected change is known exactly: a
departure of 10% becoming 11.5% is a change of +1.5 percentage points.
"""

from __future__ import annotations

import csv
import json

import pytest

from harness import cli
from harness.report import compare
from harness.run.records import ANALYTIC, Record, write_results

U_BEFORE = [3.0, -4.0, 0.0]  # Euclidean norm 5


def engine_record(departure: float, u_after=(1.0, 2.0, 0.0), status: str = "ok",
                  scenario: str = "disk", preset: str = "defaults") -> Record:
    return Record(scenario=scenario, point={"index": 0, "label": "", "value": None},
                  source="pymunk", preset=preset, u_before=list(U_BEFORE),
                  u_after=list(u_after), status=status,
                  departure={"poisson": departure, "stronge": departure})


def law_record(scenario: str = "disk") -> Record:
    return Record(scenario=scenario, point={"index": 0, "label": "", "value": None},
                  source=ANALYTIC, law="poisson", u_before=list(U_BEFORE),
                  u_after=[1.0, 2.0, 0.0], departure={"poisson": 0.0, "stronge": 0.0})


def results_file(tmp_path, name, records):
    return write_results(tmp_path / name, records, {"gates": []}, {})


def run_compare(*argv) -> int:
    return cli.main(["compare", *map(str, argv)])


def test_threshold_parsing():
    assert compare.parse_threshold("1%") == pytest.approx(0.01)
    assert compare.parse_threshold("0.002") == pytest.approx(0.002)
    for bad in ("x", "-1%", "nan"):
        with pytest.raises(ValueError):
            compare.parse_threshold(bad)


def test_a_change_below_the_threshold_passes_and_above_fails(tmp_path):
    before = results_file(tmp_path, "a.json", [law_record(), engine_record(0.100)])
    after = results_file(tmp_path, "b.json", [law_record(), engine_record(0.115)])
    # +1.5 percentage points on both departures; the speeds are unchanged.
    assert run_compare(before, after, "--fail-above", "2%") == 0
    assert run_compare(before, after, "--fail-above", "1%") == 1
    assert run_compare(before, after, "--fail-above", "0.014") == 1
    assert run_compare(before, before) == 0  # identical files never fail


def test_speed_change_is_relative_to_the_speeds_before(tmp_path):
    before = results_file(tmp_path, "a.json", [engine_record(0.1, u_after=(1.0, 2.0, 0.0))])
    after = results_file(tmp_path, "b.json", [engine_record(0.1, u_after=(1.0, 2.1, 0.0))])
    changes, _, _ = compare.compare(*(compare.read_results(p) for p in (before, after)))
    assert changes[0].speed_change == pytest.approx(0.1 / 5.0)  # |Δu| 0.1 over |u_before| 5
    assert run_compare(before, after, "--fail-above", "2.5%") == 0
    assert run_compare(before, after, "--fail-above", "1.5%") == 1


def test_a_status_change_fails_whatever_the_threshold(tmp_path):
    before = results_file(tmp_path, "a.json", [engine_record(0.1)])
    after = results_file(tmp_path, "b.json", [engine_record(0.1, status="multi-contact")])
    assert run_compare(before, after, "--fail-above", "100%") == 1


def test_records_in_one_file_only_are_listed_but_do_not_fail(tmp_path, capsys):
    before = results_file(tmp_path, "a.json", [engine_record(0.1)])
    after = results_file(tmp_path, "b.json",
                         [engine_record(0.1), engine_record(0.5, scenario="rod")])
    assert run_compare(before, after) == 0
    assert "1 records only in B" in capsys.readouterr().out


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
    after = results_file(tmp_path, "b.json", [law_record(), engine_record(0.115)])
    out = tmp_path / "diff.csv"
    assert run_compare(before, after, "--csv", out) == 1
    rows = list(csv.DictReader(out.open()))
    assert sorted(row["source"] for row in rows) == ["poisson", "pymunk.defaults"]
    engine = next(row for row in rows if row["source"] == "pymunk.defaults")
    assert float(engine["departure_poisson_a"]) == pytest.approx(0.100)
    assert float(engine["departure_poisson_b"]) == pytest.approx(0.115)
    assert float(engine["departure_poisson_change"]) == pytest.approx(0.015)
    assert float(engine["speed_change"]) == 0.0
    assert engine["status_a"] == engine["status_b"] == "ok"


def test_help_documents_the_exit_status(capsys):
    with pytest.raises(SystemExit):
        cli.main(["compare", "--help"])
    text = capsys.readouterr().out
    assert "Exit status: 0" in text and "1 when" in text and "2 on bad input" in text
    assert "--fail-above" in text and "--csv" in text
