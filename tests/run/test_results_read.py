"""Reading a results file: the records as written, each with its line of the file."""

from __future__ import annotations

import json
import math
import pickle

import pytest

from harness.run import records as records_module
from harness.run.records import (
    Record,
    RecordBlock,
    Results,
    companion_path,
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
# The companion (harness.run.records.companion_path): the records pickled beside the file
# --------------------------------------------------------------------------------------------
def _without_companion(path, tmp_path):
    copy = tmp_path / "copy.json"  # the same text, no companion beside it
    copy.write_text(path.read_text(encoding="utf-8"), encoding="utf-8")
    assert not companion_path(copy).exists()
    return read_results(copy)


def test_a_file_read_through_its_companion_equals_the_file_parsed(tmp_path, monkeypatch):
    path = write_results(tmp_path / "r.json", _records(), {"run": 1}, {"a": {"tags": []}})
    assert companion_path(path).is_file()
    parsed = _without_companion(path, tmp_path)
    monkeypatch.setattr(records_module, "_split_records", None)  # the JSON's records unparsed
    results = read_results(path)
    assert results.records == parsed.records
    assert results.record_lines() == parsed.record_lines()
    assert (results.provenance, results.scenarios) == (parsed.provenance, parsed.scenarios)


def test_the_companion_of_another_text_is_never_used(tmp_path):
    path = write_results(tmp_path / "r.json", _records(), {}, {})
    companion = companion_path(path).read_bytes()
    text = path.read_text(encoding="utf-8").replace('"status":"ok"', '"status":"edited"', 1)
    path.write_text(text, encoding="utf-8")
    companion_path(path).write_bytes(companion)
    assert read_results(path).records[0].status == "edited"


def test_records_known_only_as_lines_are_in_the_new_companion(tmp_path, monkeypatch):
    path = write_results(tmp_path / "r.json", _records(), {}, {})
    lines = read_results(path).record_lines()
    write_results(path, [None] * len(lines), {}, {}, lines=lines)
    parsed = _without_companion(path, tmp_path)
    monkeypatch.setattr(records_module, "_split_records", None)  # only the companion serves
    results = read_results(path)
    assert results.records == parsed.records
    assert results.record_lines() == lines


def test_blocks_are_written_as_the_records_of_one_file(tmp_path):
    records = _records()
    whole = write_results(tmp_path / "whole.json", records, {"run": 1}, {"a": {"tags": []}})
    datas = [record.as_dict() for record in records]
    blocks = [RecordBlock.of_lines([record_line(data) for data in part], part)
              for part in (datas[:1], [], datas[1:])]
    parts = write_result_blocks(tmp_path / "parts.json", blocks, {"run": 1},
                                {"a": {"tags": []}})
    assert parts.read_bytes() == whole.read_bytes()
    assert read_results(parts).records == read_results(whole).records
    assert read_results(parts).record_lines() == read_results(whole).record_lines()


def test_a_companion_holding_anything_but_plain_values_is_not_unpickled(tmp_path):
    path = write_results(tmp_path / "r.json", _records(), {}, {})
    header, _ = _companion_parts(path)
    called = []
    tampered = pickle.dumps(header) + pickle.dumps([_Trap(called)] * 3)
    companion_path(path).write_bytes(tampered)
    assert read_results(path).records == _without_companion(path, tmp_path).records
    assert not called


class _Trap:
    """Unpickling one would call ``list.append`` (a global looked up): a plain unpickler
    refuses."""

    def __init__(self, called):
        self.called = called

    def __reduce__(self):
        return (self.called.append, ("unpickled",))


def _companion_parts(path):
    with open(companion_path(path), "rb") as handle:
        header = pickle.load(handle)
        return header, handle.read()


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
    parsed = _without_companion(path, tmp_path)
    monkeypatch.setattr(records_module, "_split_records", None)  # the companion is read
    read = read_results(path)
    assert read.records == parsed.records
    assert [type(v) for v in (read.records[0].status, read.records[0].collision_type,
                              *read.records[0].u_after)] == [str, int, float, int]
