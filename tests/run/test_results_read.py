"""Reading a results file: the records as written, each with its line of the file."""

from __future__ import annotations

import json
import math

import pytest

from harness.run import records as records_module
from harness.run.records import (
    Record,
    RecordBlock,
    Results,
    read_results,
    record_line,
    write_result_blocks,
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


# --------------------------------------------------------------------------------------------
# The file is the results' only form, and a file not of this format is refused (issue 23)
# --------------------------------------------------------------------------------------------
def _parsed(path, tmp_path):
    copy = tmp_path / "copy.json"  # the same text, read through the whole-document path
    copy.write_text(path.read_text(encoding="utf-8"), encoding="utf-8")
    return read_results(copy)


def test_nothing_but_the_results_file_is_written(tmp_path):
    write_results(tmp_path / "r.json", _records(), {}, {})
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]  # no pickle beside it


def test_records_known_only_as_lines_are_written_as_those_lines(tmp_path):
    path = write_results(tmp_path / "r.json", _records(), {}, {})
    first = read_results(path)
    lines = first.record_lines()
    write_results(path, [None] * len(lines), {}, {}, lines=lines)
    results = read_results(path)
    assert results.records == first.records and results.record_lines() == lines


@pytest.mark.parametrize("version", [0, 2, "1", None])
def test_a_file_of_another_format_version_is_refused(tmp_path, version):
    path = write_results(tmp_path / "r.json", _records(), {}, {})
    document = _plain(path)
    document["format_version"] = version
    path.write_text(json.dumps(document), encoding="utf-8")
    with pytest.raises(ValueError, match="results format version"):
        read_results(path)


@pytest.mark.parametrize("field", records_module.REQUIRED_FIELDS)
def test_a_record_missing_a_required_field_is_refused(tmp_path, field):
    path = write_results(tmp_path / "r.json", _records(), {}, {})
    text = path.read_text(encoding="utf-8")
    document = _plain(path)
    del document["records"][1][field]
    for damaged in (json.dumps(document),  # read whole
                    text.replace(record_line(_records()[1].as_dict()),
                                 record_line(document["records"][1]))):  # as laid out
        path.write_text(damaged, encoding="utf-8")
        with pytest.raises(ValueError, match=f"record 1: no {field} "):
            read_results(path)


@pytest.mark.parametrize("value", ["fast", 3, {"x": 1}, True])
def test_a_record_with_speeds_of_another_type_is_refused(tmp_path, value):
    path = write_results(tmp_path / "r.json", _records(), {}, {})
    document = _plain(path)
    document["records"][0]["u_after"] = value
    path.write_text(json.dumps(document), encoding="utf-8")
    with pytest.raises(ValueError, match="record 0: u_after = .*: not a list or null"):
        read_results(path)


def test_blocks_are_written_as_the_records_of_one_file(tmp_path):
    records = _records()
    whole = write_results(tmp_path / "whole.json", records, {"run": 1}, {"a": {"tags": []}})
    datas = [record.as_dict() for record in records]
    blocks = [RecordBlock.of_lines([record_line(data) for data in part])
              for part in (datas[:1], [], datas[1:])]
    parts = write_result_blocks(tmp_path / "parts.json", blocks, {"run": 1},
                                {"a": {"tags": []}})
    assert parts.read_bytes() == whole.read_bytes()
    assert read_results(parts).records == read_results(whole).records
    assert read_results(parts).record_lines() == read_results(whole).record_lines()


def test_subclasses_of_plain_types_are_written_as_their_plain_values(tmp_path, monkeypatch):
    import enum

    import numpy as np

    class Kind(enum.StrEnum):
        OK = "ok"

    class Level(enum.IntEnum):
        TWO = 2

    record = Record(scenario="a", point={"index": 0, "label": ""}, source="pymunk",
                    preset="defaults", status=Kind.OK, collision_type=Level.TWO,
                    u_after=[np.float64(0.5), np.int64(3)], diagnostics={"kind": Kind.OK})
    path = write_results(tmp_path / "r.json", [record], {}, {})
    parsed = _parsed(path, tmp_path)
    monkeypatch.setattr(records_module, "_split_records", lambda text: (None, None))
    read = read_results(path)  # the whole document parsed
    assert read.records == parsed.records
    assert [type(v) for v in (read.records[0].status, read.records[0].collision_type,
                              *read.records[0].u_after)] == [str, int, float, int]
