"""The work of a run's worker processes, and running it: one engine run per task, a chunk of
them through one :meth:`Engine.run_many` call, a several-contact point's reference.

Every function a worker calls is top-level and picklable, takes and returns plain data, and
never raises for a fault of the engine (it becomes the output's ``status``). On the local pool
the worker stores what it computed in the result cache itself (``task["store"]``), so the run
keeps each chunk the moment it finishes. :func:`run_engine_tasks` hands the tasks to the
executor (:func:`harness.run.executor.run_tasks`): in chunks of one engine and settings
(:func:`task_group`), each bounded by its time limit (:func:`task_time_limit`); a task the
executor stops gets :func:`stopped_task`'s output.
"""

from __future__ import annotations

import json
import math
import time
from functools import lru_cache

from harness import engines as registry
from harness.engines import EngineNotInstalled, UnsupportedScene
from harness.processes import one_blas_thread
from harness.run import references
from harness.run.executor import progress_printer, run_tasks
from harness.store.cache import ResultCache

#: Below this many engine runs to do, the pool's start-up costs more than it saves.
MIN_PARALLEL_TASKS = 200
#: Wall-clock limit (s) of one engine task. The slowest library task (MuJoCo ``accurate``,
#: 10 µs steps) takes about a second; a task 100 times slower is stuck, not working.
TASK_TIME_LIMIT_S = 120.0
#: The ``kind`` of a point's reference, as a task of the engine runs' executor and in the cache.
POINT_REFERENCE = "point-reference"
#: A reference task counts as this many engine runs when choosing the pool over inline work:
#: a several-contact reference takes 0.1-1 s, an engine run about a millisecond.
REFERENCE_TASK_WEIGHT = 100
#: Keys of an engine task's output, popped by the runner: the worker stored it in the cache,
#: or could not (why) (:func:`_stored_by_worker`).
STORED_BY_WORKER, STORE_FAILED_IN_WORKER = "stored_by_worker", "store_failed_in_worker"


def engine_task(task: dict) -> dict:
    """Simulate one (scene, engine, settings) task; a plain JSON-able dict comes back.

    Top-level and picklable for the executor. The engine adapter (its clients and models)
    is loaded once per worker process and reused. An engine that is missing here or cannot
    build the scene gives ``{"status": "skipped: …"}``; any other exception
    ``{"status": "error: …"}``, so a task never takes the run down.
    """
    if task.get("kind") == POINT_REFERENCE:  # shares the engine runs' pool (the runner)
        return reference_task(task)
    start = time.perf_counter()
    try:
        engine = registry.load_engine(task["engine"])  # looked up at call time (tests replace it)
        run = engine.run(task["scene"], task["settings"])
    except EngineNotInstalled as error:
        return {"status": f"skipped: {error}", "wall_time_s": time.perf_counter() - start}
    except UnsupportedScene as error:
        return {"status": f"skipped: engine cannot build the scene: {error}",
                "wall_time_s": time.perf_counter() - start}
    except Exception as error:  # reported in the record, never dropped
        return {"status": f"error: {type(error).__name__}: {error}",
                "wall_time_s": time.perf_counter() - start}
    return _stored_by_worker([task], [_task_output(engine, run, time.perf_counter() - start)])[0]


def engine_chunk(tasks: list[dict]) -> list[dict]:
    """:func:`engine_task` of every task, through one :meth:`Engine.run_many` call.

    The tasks share their engine and settings (the runner groups them so: :func:`task_group`);
    the outputs equal :func:`engine_task`'s but for the wall times (each task gets an equal
    share of the chunk's). The whole chunk has one task's time limit: a chunk is at most
    :data:`harness.run.executor.MAX_CHUNK` runs of about a millisecond (a second at worst),
    far under it. Anything else than finished runs raises (the time limit, a missing
    engine, a scene it cannot build, an engine error), and the executor then runs the
    chunk's tasks one by one through :func:`engine_task`, which names the task at fault and
    keeps the others' results.
    """
    start = time.perf_counter()
    first = tasks[0]
    if any(task["engine"] != first["engine"] or task["settings"] != first["settings"]
           for task in tasks):
        raise ValueError("engine_chunk: tasks of one chunk must share engine and settings")
    engine = registry.load_engine(first["engine"])  # looked up at call time, as above
    runs = engine.run_many([task["scene"] for task in tasks], first["settings"])
    share = (time.perf_counter() - start) / len(tasks)
    return _stored_by_worker(tasks, [_task_output(engine, run, share) for run in runs])


def _stored_by_worker(tasks: list[dict], outputs: list[dict]) -> list[dict]:
    """``outputs`` (of ``tasks``, one chunk's), stored in the result cache by the process
    that ran them when the tasks say where (``task["store"]``: root, code version and key;
    the local pool), all in one pack, and marked so (:data:`STORED_BY_WORKER`, or why not:
    :data:`STORE_FAILED_IN_WORKER`). A skipped or failed run is never stored."""
    kept = [(task["store"], output) for task, output in zip(tasks, outputs)
            if task.get("store") is not None
            and not output["status"].startswith(("skipped", "error"))]
    if not kept:
        return outputs
    root, version, _ = kept[0][0]
    try:
        _worker_cache(root, version).put_many([(where[2], output) for where, output in kept])
    except OSError as error:
        for _, output in kept:
            output[STORE_FAILED_IN_WORKER] = str(error)
        return outputs
    for _, output in kept:
        output[STORED_BY_WORKER] = True
    return outputs


@lru_cache(maxsize=4)
def _worker_cache(root, version: str):
    """The :class:`~harness.store.cache.ResultCache` a worker stores its runs in: one per
    cache and code version, made at the first task (a put keeps no state in it)."""
    return ResultCache(root, version=version)


def task_group(task: dict) -> str:
    """The chunk key of an engine task: its engine and settings (one ``run_many`` each). A
    point's reference task (:func:`reference_task`, up to a second) is a chunk of its own."""
    if task.get("kind") == POINT_REFERENCE:
        return json.dumps([POINT_REFERENCE, task["scenario"], task["point"]])
    return json.dumps([task["engine"], task["settings"], task.get("time_limit_s")],
                      sort_keys=True, default=repr)


def task_time_limit(task: dict) -> float | None:
    """The seconds a task may run (the executor stops it after them): an engine task's
    ``time_limit_s``; a point's reference task has none."""
    return None if task.get("kind") == POINT_REFERENCE else task.get("time_limit_s")


def stopped_task(task: dict, reason: str) -> dict:
    """The output of a task the executor stopped (``reason``: over its time limit, or its
    worker died), reported in its record as an error. A reference task's is empty: the
    reference is then computed where the records are built, which reports its error."""
    if task.get("kind") == POINT_REFERENCE:
        return {}
    over = reason.startswith("time limit")
    return {"status": f"error: {reason}" + (" (--task-time-limit)" if over else ""),
            "wall_time_s": float(task["time_limit_s"]) if over else 0.0}


def _task_output(engine, run, wall_time_s: float) -> dict:
    """The plain JSON-able output of one finished engine run (what the cache keeps)."""
    return {
        "status": run.status,
        "velocities": [list(v) for v in run.velocities],
        "steps": run.steps,
        "contact_steps": run.contact_steps,
        "first_contact_step": run.first_contact_step,
        "max_contact_points": run.max_contact_points,
        "max_penetration": run.max_penetration,
        "separated": run.separated,
        "step_cap_hit": run.step_cap_hit,
        "contact_normal": None if run.contact_normal is None else list(run.contact_normal),
        "engine_normal_impulse": run.normal_impulse,
        "engine_tangential_impulse": run.tangential_impulse,
        "impulse_source": getattr(run, "impulse_source", None),
        "out_of_plane_drift": run.out_of_plane_drift,
        "derived": dict(run.derived),
        "notes": list(run.notes),
        "contacts": _contact_steps(run),
        # For the contact history (harness.run.history): the step, and how many steps before
        # the touching pose the run started (free flight, harness.engines.contract).
        "time_step": float(run.settings["time_step"]),
        "start_offset_steps": float(run.settings["approach_steps"] + engine.timing.lead_steps
                                    - engine.timing.overlap),
        "engine_wall_time_s": run.wall_time_s,
        "wall_time_s": wall_time_s,
    }


def _contact_steps(run) -> list[dict]:
    """The run's per-step contact records as plain lists.

    An engine run keeps, per step with contact (its ``contacts``, the engines'
    ``ContactStep``): the step, the points ``(x, y, depth)``, every body's pose ``(x, y, θ)``
    after the step, the impulse on body B in the step or None, scene frame. They feed the
    verdict's second-feature check (:mod:`harness.run.verdicts`) and the contact history
    (:mod:`harness.run.history`). Read from the run's raw records (``contact_record``, run
    frame) moved to the scene frame by the very subtraction ``contacts`` makes, without
    building its typed steps first.
    """
    (shift_x, shift_y), raw = run.contact_record
    return [{"step": int(step),
             "points": [[float(x - shift_x), float(y - shift_y), float(depth)]
                        for x, y, depth in points],
             "bodies": [[float(x - shift_x), float(y - shift_y), float(angle)]
                        for x, y, angle in poses],
             "impulse": None if impulse is None else [float(v) for v in impulse]}
            for step, (points, _normal, impulse, _pressure), poses in raw]


def check_engine_output(output, speeds: int) -> str | None:
    """``None`` when ``output`` (a cached :func:`engine_task` result) is usable, else why not.

    ``speeds`` is the number of generalized speeds of the scene (3 per body). An ``ok``
    output must carry finite velocities; another engine status (a blow-up) may carry
    non-finite ones, which the record then reports.
    """
    if not isinstance(output, dict) or not isinstance(output.get("status"), str):
        return "no status"
    if output["status"].startswith(("skipped", "error")):
        return "a skipped or failed run is never cached"
    velocities = output.get("velocities")
    if (not isinstance(velocities, list) or len(velocities) * 3 != speeds
            or not all(isinstance(body, list) and len(body) == 3 for body in velocities)):
        return f"velocities {str(velocities)[:60]!r} are not {speeds // 3} lists of 3 numbers"
    values = [value for body in velocities for value in body]
    if not all(isinstance(value, (int, float)) and not isinstance(value, bool)
               for value in values):
        return "velocities hold a value that is not a number"
    if output["status"] == "ok" and not all(math.isfinite(value) for value in values):
        return "status ok with non-finite velocities"
    return None


def reference_task(task: dict) -> dict:
    """The several-contact reference of one point, computed in a worker process.

    ``task`` holds the situation (``situation``, :func:`harness.run.references.kind_of`), the
    ``scene`` at the point and its ``laws`` (:class:`harness.run.references.PointLaws`): a
    scenario does not pickle. The result is ``{"reference": …}``
    (:func:`harness.run.references.scene_reference`, the very dict the main process would
    compute) or, when it raises, ``{"error": "…"}``: the main process then builds the
    reference inline, where the exception becomes the point's internal-error records as
    before (:func:`harness.run.point_records.point_records_or_errors`).
    """
    one_blas_thread()  # a Dask worker has no pool initializer
    try:
        reference = references.scene_reference(task["situation"], task["scene"], task["laws"])
    except Exception as error:  # noqa: BLE001 - raised again, and reported, in the main process
        return {"error": f"{type(error).__name__}: {error}"}
    return {"reference": reference}  # stored by the main process, a pack at a time


def run_engine_tasks(tasks, *, executor, workers, scheduler, log, on_result=None,
               chunk_size=None, weight: int | None = None) -> list[dict]:
    """The engine tasks through the executor: in chunks of one engine and settings, each one
    :func:`engine_chunk` (``Engine.run_many``) call; ``chunk_size=1``: one :func:`engine_task`
    (``Engine.run``) each, as before chunks. Reference tasks (:func:`reference_task`) go one
    per chunk. ``weight``: the work in engine runs (default: one per task); below
    :data:`MIN_PARALLEL_TASKS` the local executor runs inline."""
    weight = len(tasks) if weight is None else weight
    if executor == "local" and workers is None and weight < MIN_PARALLEL_TASKS:
        workers = 1
    # The progress counts every task: say so where several-contact references are among them
    # (the runner's line before announced the two counts apart).
    label = ("engine runs and references"
             if any(task.get("kind") == POINT_REFERENCE for task in tasks) else "engine runs")
    progress = progress_printer(label, stream=log) if log is not None else None
    note = None if log is None else (lambda text: print(text, file=log, flush=True))
    batch = None if chunk_size == 1 else engine_chunk
    return run_tasks(engine_task, tasks, executor=executor, workers=workers,
                     scheduler=scheduler, progress=progress, on_result=on_result,
                     batch=batch, group=task_group, chunk_size=chunk_size, note=note,
                     time_limit=task_time_limit, stopped=stopped_task)


__all__ = ["MIN_PARALLEL_TASKS", "POINT_REFERENCE", "REFERENCE_TASK_WEIGHT", "STORED_BY_WORKER",
           "STORE_FAILED_IN_WORKER", "TASK_TIME_LIMIT_S", "check_engine_output", "engine_chunk",
           "engine_task", "reference_task", "run_engine_tasks", "stopped_task", "task_group",
           "task_time_limit"]
