"""bench --executors: the kept scenario files are exactly those of the benchmarked tasks."""

from __future__ import annotations

from harness.bench.executors import INCLUDED, engine_tasks, format_report
from harness.scenarios import load_scenarios


def test_kept_files_are_the_tasks_scenarios(tmp_path):
    tasks = engine_tasks(40, keep=tmp_path / "files")
    kept = load_scenarios(sorted((tmp_path / "files").iterdir()))
    assert {scenario.name for scenario in kept} == {task["scene"].name for task in tasks}


def test_the_report_says_what_each_time_holds():
    seconds = {"local": [1.0], "dask": [1.2], "dask shutdown": [0.1], "dask running": [1.0]}
    report = {"tasks": 2000, "engines": ["pymunk"], "workers": 2, "repeats": 1,
              "seconds": seconds, "median": {way: values[0] for way, values in seconds.items()},
              "ratio": 1.2, "ratio_running": 1.0, "ratio_per_task": None}
    text = format_report(report)
    held = text.split("times hold:\n", 1)[1]
    for way in ("local", "dask", "dask running"):
        assert f"    {way}: {INCLUDED[way]}" in held
    assert "run dask" not in held  # no end-to-end commands were timed
    assert "LocalCluster start" in INCLUDED["dask"] and "not its shutdown" in INCLUDED["dask"]
