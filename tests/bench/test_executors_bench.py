"""bench --executors: the kept scenario files are exactly those of the benchmarked tasks."""

from __future__ import annotations

from harness.bench.executors import engine_tasks
from harness.scenarios import load_scenarios


def test_kept_files_are_the_tasks_scenarios(tmp_path):
    tasks = engine_tasks(40, keep=tmp_path / "files")
    kept = load_scenarios(sorted((tmp_path / "files").iterdir()))
    assert {scenario.name for scenario in kept} == {task["scene"].name for task in tasks}
