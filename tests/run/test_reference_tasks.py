"""Several-contact references computed as tasks of the engine runs' executor
(harness/run/plan.py, ``reference_tasks``; harness/run/tasks.py, ``reference_task``): the same
references, bit for bit, as the ones computed inline, kept in the cache as each finishes."""

from __future__ import annotations

import json

import pytest

from harness.run import plan, references, runner
from harness.run import tasks as worker_tasks
from harness.run.executor import run_tasks
from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.store.cache import ResultCache

#: Flat faces (m-contact laws) and tilts (event sequences), one to six points each.
SEVERAL_CONTACT = [load_scenario(SCENARIO_DIR / f"{name}.toml") for name in (
    "flat-rod", "flat-box-spin", "flat-box-receding-end", "sweep-tilted-rod")]
SINGLE_CONTACT = load_scenario(SCENARIO_DIR / "box-corner.toml")


def _exact(value) -> str:
    """``value`` spelled so that two floats are equal only when their bits are (repr is exact;
    a NaN equals a NaN)."""
    return json.dumps(value, sort_keys=True)


def _without_timing(record) -> dict:
    data = record.as_dict()
    data.pop("wall_time_s", None)
    (data.get("diagnostics") or {}).pop("engine_wall_time_s", None)
    return data


def test_only_the_several_contact_points_get_a_task():
    tasks, keys, found = plan.reference_tasks([SINGLE_CONTACT, *SEVERAL_CONTACT], None)
    expected = [(s.name, p.index) for s in SEVERAL_CONTACT for p in s.point_list()]
    assert [(task["scenario"], task["point"]) for task in tasks] == expected
    assert keys == [None] * len(tasks) and found == {}


def test_references_computed_in_the_pool_equal_the_inline_ones_bit_for_bit():
    tasks, _, _ = plan.reference_tasks(SEVERAL_CONTACT, None)
    pooled = run_tasks(worker_tasks.engine_task, tasks, workers=2, batch=worker_tasks.engine_chunk,
                       group=worker_tasks.task_group)
    by_name = {scenario.name: scenario for scenario in SEVERAL_CONTACT}
    kinds = set()
    for task, output in zip(tasks, pooled):
        scenario = by_name[task["scenario"]]
        point = scenario.point_list()[task["point"]]
        inline = references.point_reference(scenario, point)
        assert _exact(output["reference"]) == _exact(inline)
        kinds.add(inline["kind"])
    assert kinds == {references.SIMULTANEOUS, references.EVENT_DRIVEN}


def test_each_reference_task_is_a_chunk_of_its_own():
    tasks, _, _ = plan.reference_tasks(SEVERAL_CONTACT, None)
    assert len({worker_tasks.task_group(task) for task in tasks}) == len(tasks)


@pytest.mark.parametrize("use_cache", [False, True])
def test_a_run_gives_the_same_records_as_with_references_computed_inline(
        tmp_path, monkeypatch, use_cache):
    scenarios = [*SEVERAL_CONTACT, SINGLE_CONTACT]
    options = dict(engines=("pymunk",), workers=2, log=None)
    pooled = runner.run(scenarios, cache=ResultCache(tmp_path / "pooled") if use_cache else None,
                        **options)
    monkeypatch.setattr(plan, "reference_tasks", lambda scenarios, cache: ([], [], {}))
    inline = runner.run(scenarios, cache=ResultCache(tmp_path / "inline") if use_cache else None,
                        **options)
    assert ([_exact(_without_timing(r)) for r in pooled.records]
            == [_exact(_without_timing(r)) for r in inline.records])
    assert _exact(pooled.scenarios) == _exact(inline.scenarios)


@pytest.mark.parametrize("workers", [1, 2])
def test_each_reference_is_in_the_cache_once_the_run_is_over(tmp_path, monkeypatch, workers):
    cache = ResultCache(tmp_path)
    in_main = []
    real = plan.store_reference
    monkeypatch.setattr(plan, "store_reference",
                        lambda *args: in_main.append(args[1]) or real(*args))
    runner.run(SEVERAL_CONTACT[:2], engines=("pymunk",), workers=workers, log=None, cache=cache)
    # on the local executor each task stores its reference where it ran (a worker, or inline)
    assert in_main == []

    def never(*args):
        raise AssertionError("computed again, not read from the cache")

    monkeypatch.setattr(references, "point_reference", never)
    for scenario in SEVERAL_CONTACT[:2]:
        for point in scenario.point_list():
            stored = plan.point_reference_cached(scenario, point, cache)
            assert stored["kind"] == references.SIMULTANEOUS
    # and a second run has no reference left to compute: each read once, for the records
    tasks, keys, found = plan.reference_tasks(SEVERAL_CONTACT[:2], cache)
    assert (tasks, keys) == ([], [])
    assert sorted(found) == sorted((s.name, p.index) for s in SEVERAL_CONTACT[:2]
                                   for p in s.point_list())
    assert all(reference["kind"] == references.SIMULTANEOUS for reference in found.values())


def test_a_reference_that_raises_in_its_task_gives_the_points_internal_error_records(
        monkeypatch):
    def broken(kind, scene, fixed):
        raise RuntimeError("broken reference")

    monkeypatch.setattr(references, "scene_reference", broken)
    scenario = load_scenario(SCENARIO_DIR / "flat-rod.toml")
    assert worker_tasks.reference_task(plan.reference_tasks([scenario], None)[0][0]) == {
        "error": "RuntimeError: broken reference"}
    outcome = runner.run([scenario], engines=("pymunk",), workers=1, log=None)
    assert outcome.records
    assert all(record.status == "error: internal: RuntimeError: broken reference"
               for record in outcome.records)


def test_the_progress_names_references_where_they_are_among_the_tasks(monkeypatch):
    """The runner announces "N engine runs to simulate; K references"; the progress counts
    both, so its label says so (else "engine runs: 0/N+K" reads as a different count)."""
    labels = []

    def fake_run_tasks(function, tasks, *, progress, **options):
        progress(0, len(tasks))
        return [None] * len(tasks)

    monkeypatch.setattr(worker_tasks, "run_tasks", fake_run_tasks)
    monkeypatch.setattr(worker_tasks, "progress_printer",
                        lambda label, stream=None: lambda done, total: labels.append(label))
    references_only, _, _ = plan.reference_tasks(SEVERAL_CONTACT[:1], None)
    engine_like = [{"engine": "pymunk"}]
    worker_tasks.run_engine_tasks(engine_like, executor="local", workers=1, scheduler=None,
                                  log=object())
    worker_tasks.run_engine_tasks(references_only + engine_like, executor="local", workers=1,
                                  scheduler=None, log=object())
    assert labels == ["engine runs", "engine runs and references"]
