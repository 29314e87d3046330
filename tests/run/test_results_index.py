"""``Results.for_scenario`` and ``scenario_names`` through the scenario index."""

from __future__ import annotations

from harness.run.records import Record, Results


def _record(scenario: str, source: str) -> Record:
    return Record(scenario=scenario, point={}, source=source)


def test_records_by_scenario_in_run_order_and_after_the_list_changes():
    records = [_record("b", "analytic"), _record("a", "analytic"), _record("b", "pymunk")]
    results = Results(records)
    assert results.scenario_names() == ["b", "a"]
    assert [r.source for r in results.for_scenario("b")] == ["analytic", "pymunk"]
    assert results.for_scenario("missing") == []
    results.for_scenario("b").clear()  # a copy: the index is not the caller's to change
    assert len(results.for_scenario("b")) == 2
    results.records.append(_record("c", "mujoco"))
    assert results.scenario_names() == ["b", "a", "c"]
    results.records = [_record("d", "analytic")]
    assert results.scenario_names() == ["d"] and results.for_scenario("b") == []
    assert Results([_record("a", "x")]) == Results([_record("a", "x")])
