"""Chunked dispatch: engine tasks in chunks (``Engine.run_many``) give the per-task results,
bit for bit, in task order; a task that fails or overruns inside a chunk costs only itself."""

from __future__ import annotations

import math
import pickle
import time

import pytest

import harness.engines as engines_module
from harness.engines import load_engine
from harness.run import runner
from harness.run import tasks as worker_tasks
from harness.run.executor import call_chunk, chunk_size_for, make_chunks, run_tasks
from harness.scenarios import SCENARIO_DIR, load_scenario, load_scenarios

SWEEP = load_scenario(SCENARIO_DIR / "sweep-disk-alpha.toml")  # 9 points
TIMING_KEYS = ("wall_time_s", "engine_wall_time_s")  # a batched run's are its chunk's share


def without_times(output: dict) -> dict:
    return {key: value for key, value in output.items() if key not in TIMING_KEYS}


def library_tasks(limit: int | None = None) -> list[dict]:
    """The runner's engine tasks of the library's ``bodies`` scenarios (both presets)."""
    tasks = []
    for scenario in load_scenarios(None):
        for point in scenario.point_list():
            for name in scenario.engines_among(("pymunk", "pybullet", "mujoco", "box2d")):
                try:
                    engine = load_engine(name)
                except engines_module.EngineNotInstalled:
                    continue
                for preset in ("defaults", "accurate"):
                    tasks.append({"engine": name, "scene": scenario.scene(point),
                                  "settings": engine.settings(
                                      preset, scenario.engine_settings.get(name, {})),
                                  "time_limit_s": 60.0})
    return tasks[:limit]


def record_fields(outcome) -> list[dict]:
    """Every record as written, but for the wall times."""
    rows = []
    for record in outcome.records:
        row = record.as_dict()
        row.pop("wall_time_s", None)
        if isinstance(row.get("diagnostics"), dict):
            row["diagnostics"].pop("engine_wall_time_s", None)
        rows.append(row)
    return rows


# --------------------------------------------------------------------------------------------
# Chunks equal single tasks
# --------------------------------------------------------------------------------------------
def test_engine_chunk_equals_engine_task_output_for_output():
    tasks = library_tasks()
    chunks = make_chunks(tasks, 16, worker_tasks.task_group)
    assert any(len(chunk) > 1 for chunk in chunks)
    finished = 0
    for chunk in chunks:
        chunk_tasks = [tasks[index] for index in chunk]
        batched = worker_tasks.engine_chunk(chunk_tasks)
        single = [worker_tasks.engine_task(task) for task in chunk_tasks]
        assert [without_times(out) for out in batched] == [without_times(out) for out in single]
        finished += sum("velocities" in out for out in batched)
    assert finished == len(tasks)  # every library task is a finished run, none skipped


@pytest.mark.parametrize("workers", [1, 2])
def test_chunked_run_equals_unchunked_run_record_for_record(workers):
    scenarios = [SWEEP, load_scenario(SCENARIO_DIR / "rod-45-slip-reversal.toml")]
    options = {"cache": None, "workers": workers, "log": None}
    unchunked = runner.run(scenarios, chunk_size=1, **options)
    chunked = runner.run(scenarios, chunk_size=4, **options)
    automatic = runner.run(scenarios, **options)
    assert record_fields(chunked) == record_fields(unchunked)
    assert record_fields(automatic) == record_fields(unchunked)
    assert any(r.u_after for r in chunked.records if r.source == "pymunk")


def test_a_chunk_never_mixes_engines_or_settings_and_keeps_every_task_once():
    tasks = library_tasks()
    for size in (1, 3, 64):
        chunks = make_chunks(tasks, size, worker_tasks.task_group)
        assert sorted(index for chunk in chunks for index in chunk) == list(range(len(tasks)))
        for chunk in chunks:
            assert 1 <= len(chunk) <= size and chunk == sorted(chunk)
            assert len({worker_tasks.task_group(tasks[index]) for index in chunk}) == 1
    with pytest.raises(ValueError, match="share engine and settings"):
        worker_tasks.engine_chunk([tasks[0], {**tasks[0], "engine": "box2d"}])


def test_chunk_size_balances_small_runs_and_caps_large_ones():
    assert chunk_size_for(2000, 2) == 64
    assert chunk_size_for(40, 2) == 5  # 4 chunks per worker: both busy to the end
    assert chunk_size_for(3, 2) == 1
    assert chunk_size_for(2000, 2, batched=False) == 125  # the pool's former pickling chunks


# --------------------------------------------------------------------------------------------
# A failing task inside a chunk loses nothing else
# --------------------------------------------------------------------------------------------
def square_unless_three(task: int) -> int:
    if task == 3:
        raise RuntimeError("task 3 failed")
    return task * task


def squares_unless_three(tasks: list[int]) -> list[int]:
    if 3 in tasks:
        raise RuntimeError("a chunk holding 3 fails as a whole")
    return [task * task for task in tasks]


@pytest.mark.parametrize("workers", [1, 2])
def test_a_raising_task_in_a_chunk_costs_only_itself(workers):
    delivered = {}
    with pytest.raises(RuntimeError, match="task 3 failed"):
        run_tasks(square_unless_three, range(8), workers=workers, batch=squares_unless_three,
                  chunk_size=8, on_result=delivered.__setitem__)
    assert delivered == {task: task * task for task in range(8) if task != 3}


def test_call_chunk_falls_back_one_by_one_and_names_the_first_failure():
    results, failure = call_chunk(square_unless_three, squares_unless_three, [2, 3, 4])
    assert results == [4, None, 16]
    assert failure[0] == 1 and str(failure[1]) == "task 3 failed"
    assert call_chunk(square_unless_three, squares_unless_three, [2, 4]) == ([4, 16], None)


class FaultyEngine:
    """The real pymunk adapter, but the marked scene raises or never ends: alone in ``run``,
    and it takes the whole ``run_many`` with it."""

    def __init__(self, marked, fault):
        self.real, self.fault = load_engine("pymunk"), fault
        self.marked = pickle.dumps(marked)  # a task run in a child process holds a copy

    def _is_marked(self, scene):
        return pickle.dumps(scene) == self.marked

    def __getattr__(self, name):
        return getattr(self.real, name)

    def _trip(self):
        if self.fault == "raise":
            raise RuntimeError("the engine failed on this scene")
        time.sleep(30)

    def run(self, scene, settings):
        if self._is_marked(scene):
            self._trip()
        return self.real.run(scene, settings)

    def run_many(self, scenes, settings):
        if any(self._is_marked(scene) for scene in scenes):
            self._trip()
        return self.real.run_many(scenes, settings)


@pytest.mark.parametrize("fault", ["raise", "time limit"])
def test_an_engine_failure_inside_a_chunk_is_reported_and_the_others_are_kept(monkeypatch,
                                                                               fault):
    pytest.importorskip("pymunk")
    engine = load_engine("pymunk")
    settings = engine.settings("defaults")
    scenes = [SWEEP.scene(point) for point in SWEEP.point_list()]
    tasks = [{"engine": "pymunk", "scene": scene, "settings": settings, "time_limit_s": 0.5}
             for scene in scenes]
    clean = [without_times(worker_tasks.engine_task(task)) for task in tasks]
    monkeypatch.setattr(engines_module, "load_engine",
                        lambda name: FaultyEngine(scenes[4], fault))
    delivered = {}
    outputs = run_tasks(worker_tasks.engine_task, tasks, workers=1,
                        batch=worker_tasks.engine_chunk, group=worker_tasks.task_group,
                        chunk_size=9, on_result=delivered.__setitem__,
                        time_limit=worker_tasks.task_time_limit, stopped=worker_tasks.stopped_task)
    expected = "error: time limit" if fault == "time limit" else "error: RuntimeError"
    assert outputs[4]["status"].startswith(expected)
    assert [without_times(out) for i, out in enumerate(outputs) if i != 4] == clean[:4] + clean[5:]
    assert sorted(delivered) == list(range(9))


# --------------------------------------------------------------------------------------------
# Dask: chunks, and the local pool below the threshold
# --------------------------------------------------------------------------------------------
def test_dask_below_the_threshold_runs_locally_and_says_so():
    pytest.importorskip("distributed", reason='dask is not installed (pip install -e ".[dask]")')
    notes = []
    results = run_tasks(square_unless_three, [1, 2], executor="dask", workers=2,
                        dask_min_tasks=10, note=notes.append)
    assert results == [1, 4]
    assert len(notes) == 1 and "local" in notes[0] and "10" in notes[0]


def test_dask_chunks_of_engine_tasks_equal_the_local_pool_bit_for_bit():
    pytest.importorskip("distributed", reason='dask is not installed (pip install -e ".[dask]")')
    tasks = library_tasks(limit=120)
    chunked = {"batch": worker_tasks.engine_chunk, "group": worker_tasks.task_group,
               "chunk_size": 16}
    local = run_tasks(worker_tasks.engine_task, tasks, workers=1, **chunked)
    delivered = []
    distributed = run_tasks(worker_tasks.engine_task, tasks, executor="dask", workers=2,
                            dask_min_tasks=0, on_result=lambda index, _: delivered.append(index),
                            **chunked)
    assert [without_times(out) for out in distributed] == [without_times(out) for out in local]
    assert sorted(delivered) == list(range(len(tasks)))


# --------------------------------------------------------------------------------------------
# A task's contact steps, read from the run's raw records, equal its typed view's
# --------------------------------------------------------------------------------------------
def typed_view_steps(run) -> list[dict]:
    """The contact steps as ``EngineRun.contacts`` gives them, made plain."""
    return [{"step": int(s.step), "points": [[float(v) for v in p] for p in s.points],
             "bodies": [[float(v) for v in pose] for pose in s.poses],
             "impulse": None if s.impulse is None else [float(v) for v in s.impulse]}
            for s in run.contacts]


def exact(value):
    """``value`` with every float spelled in hex and every type named: equal only when
    bit-identical (``-0.0`` and ``0.0`` differ, a NaN equals itself)."""
    if isinstance(value, dict):
        return {key: exact(item) for key, item in value.items()}
    if isinstance(value, list):
        return [exact(item) for item in value]
    if isinstance(value, float):
        return ("float", "nan" if math.isnan(value) else value.hex())
    return (type(value).__name__, value)


def test_contact_steps_equal_the_typed_view_bit_for_bit():
    tasks = library_tasks()
    seen = {"shifted": 0, "impulses": 0, "several points": 0, "several bodies": 0}
    for task in tasks[::7]:
        run = load_engine(task["engine"]).run(task["scene"], task["settings"])
        steps = worker_tasks._contact_steps(run)
        assert exact(steps) == exact(typed_view_steps(run))
        seen["shifted"] += run.contact_record[0] != (0.0, 0.0) and bool(steps)
        seen["impulses"] += any(step["impulse"] is not None for step in steps)
        seen["several points"] += any(len(step["points"]) > 1 for step in steps)
        seen["several bodies"] += any(len(step["bodies"]) > 1 for step in steps)
    assert all(seen.values()), seen  # every case met
