"""Reading a results file: the records as written, each with its line of the file."""

from __future__ import annotations

import json
import math

import pytest

from harness.run.records import (
    Record,
    Results,
    collector_paused,
    read_results,
    record_line,
    write_results,
)


def _records() -> list[Record]:
    return [
        Record(scenario="a", point={"index": 0, "label": "x"}, source="analytic",
               law="poisson", u_before=[1.0, -0.5, 0.25], u_after=[0.1, 2e-17, math.nan],
               departure={"poisson": 0.0}, diagnostics={"mnn": 1.5, "note": "a \"quoted\",\n"}),
        Record(scenario="b", point={"index": 0, "label": "y"}, source="pymunk",
               preset="defaults", u_after=[1, 2, 3], wall_time_s=0.125, cached=True,
               status="flagged: two impacts", reasons=[{"name": "x", "fails": True}],
               diagnostics={"engine_wall_time_s": 0.5, "history": {"normal_impulse": []}}),
        Record(scenario="a", point={"index": 1, "label": "z ✓"}, source="mujoco",
               preset="accurate", verdict="single-impact"),
    ]


def _plain(path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


def test_read_gives_the_records_as_the_whole_file_parsed_with_their_lines(tmp_path):
    path = write_results(tmp_path / "r.json", _records(), {"run": 1}, {"a": {"tags": []}})
    results = read_results(path)
    document = _plain(path)
    assert results.records == [Record(**data) for data in document["records"]]
    assert results.provenance == {"run": 1} and results.scenarios == {"a": {"tags": []}}
    lines = results.record_lines()
    assert lines == [record_line(record.as_dict()) for record in results.records]
    assert [json.loads(line) for line in lines] == document["records"]


def test_no_records_and_another_layout_read_alike_without_lines(tmp_path):
    empty = read_results(write_results(tmp_path / "empty.json", [], {}))
    assert empty.records == [] and empty.record_lines() == []
    path = write_results(tmp_path / "r.json", _records(), {}, {})
    indented = tmp_path / "indented.json"  # the same document, every record indented
    indented.write_text(json.dumps(_plain(path), indent=1), encoding="utf-8")
    other = read_results(indented)
    assert other.records == read_results(path).records
    assert other.record_lines() is None
    compact = tmp_path / "compact.json"
    compact.write_text(json.dumps(_plain(path)), encoding="utf-8")
    assert read_results(compact).records == other.records


def test_lines_are_forgotten_when_the_records_change(tmp_path):
    results = read_results(write_results(tmp_path / "r.json", _records(), {}))
    results.records.pop()
    assert results.record_lines() is None
    results = read_results(tmp_path / "r.json")
    results.records = list(results.records)
    assert results.record_lines() is None
    assert Results(_records()).record_lines() is None


def test_a_broken_file_is_still_refused(tmp_path):
    path = write_results(tmp_path / "r.json", _records(), {})
    text = path.read_text(encoding="utf-8")
    (tmp_path / "cut.json").write_text(text[:len(text) // 2] + "\n ]\n}\n", encoding="utf-8")
    with pytest.raises(ValueError, match="not a readable results file"):
        read_results(tmp_path / "cut.json")


def test_from_dict_keeps_missing_fields_an_error_and_defaults_fresh():
    with pytest.raises(TypeError):
        Record.from_dict({"scenario": "a", "point": {}})
    first = Record.from_dict({"scenario": "a", "point": {}, "source": "x", "extra": 1})
    second = Record.from_dict({"scenario": "a", "point": {}, "source": "x"})
    first.departure["poisson"] = 1.0
    assert second.departure == {} and first.reasons is not second.reasons
    whole = _records()[1].as_dict()
    assert Record.from_dict(whole) == _records()[1]


def test_the_collector_is_paused_inside_and_restored_after():
    import gc

    assert gc.isenabled()
    with collector_paused():
        assert not gc.isenabled()
    assert gc.isenabled()
    gc.disable()
    try:
        with collector_paused():
            pass
        assert not gc.isenabled()  # off before: left off
    finally:
        gc.enable()
