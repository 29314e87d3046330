"""``impact-harness bench --executors``: the same engine tasks through the local pool and Dask.

One run, interleaved repeats, every way on the same :data:`TASKS` engine tasks (the runner's
tasks of perturbed copies of the library, :mod:`harness.bench.many_scenarios`: every
installed engine, both presets), each through :func:`harness.run.executor.run_tasks` with
:data:`WORKERS` workers:

* ``local`` -- the local process pool, in chunks (``Engine.run_many``), as ``run`` does;
* ``dask`` -- a ``LocalCluster`` of 2 single-threaded workers started for the run, in
  chunks: what ``run --executor dask`` costs, cluster start and shut-down included;
* ``dask running`` -- a cluster already running (``--scheduler``): the dispatch alone, its
  workers warm from an earlier run;
* ``dask per task`` -- a started cluster, one future per task (``chunk_size=1``), as before
  chunks (skipped with ``--quick``).

``ratio = dask / local`` (target :data:`RATIO_TARGET`; ``dask running / local`` too). The
outputs of every way are checked equal to the local pool's, bit for bit, before any time is
reported.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

RATIO_TARGET = 1.2
TASKS = 2000
WORKERS = 2
REPEATS = 3
QUICK_REPEATS = 1


def engine_tasks(count: int = TASKS, directory: Path | None = None) -> list[dict]:
    """``count`` engine tasks as the runner builds them: the library's perturbed copies, every
    point, installed engine and preset (at most 10 copies of each file's tasks)."""
    from harness.bench.many_scenarios import write_copies
    from harness.engines import EngineNotInstalled, load_engine
    from harness.run.runner import TASK_TIME_LIMIT_S, _engines_of
    from harness.scenarios import ENGINES, PRESETS, load_scenarios

    engines = {}
    for name in ENGINES:
        try:
            engines[name] = load_engine(name)
        except EngineNotInstalled:
            continue
    with tempfile.TemporaryDirectory(dir=directory) as folder:
        tasks: list[dict] = []
        files = 0
        while len(tasks) < count:
            files = max(2 * files, 50)
            paths = write_copies(Path(folder) / str(files), files)
            tasks = []
            for scenario in load_scenarios(paths):
                for point in scenario.point_list():
                    names = [n for n in _engines_of(scenario, list(engines)) if n in engines]
                    scene = scenario.scene(point) if names else None
                    for name in names:
                        for preset in PRESETS:
                            settings = engines[name].settings(
                                preset, scenario.engine_settings.get(name, {}))
                            tasks.append({"engine": name, "settings": settings, "scene": scene,
                                          "time_limit_s": TASK_TIME_LIMIT_S})
            if files > 20 * count:
                raise RuntimeError("the library yields no engine tasks")
    return tasks[:count]


def _comparable(outputs: list[dict]) -> list:
    return [(out["status"], out.get("velocities"), out.get("steps"), out.get("contacts"))
            for out in outputs]


def run(count: int = TASKS, repeats: int = REPEATS, per_task: bool = True) -> dict:
    """``{"tasks", "engines", "seconds": {way: [s, ...]}, "median", "ratio", ...}``."""
    from distributed import LocalCluster

    from harness.run.executor import run_tasks
    from harness.run.runner import engine_chunk, engine_task, task_group

    tasks = engine_tasks(count)
    chunked = {"batch": engine_chunk, "group": task_group, "dask_min_tasks": 0}
    ways = {
        "local": lambda: run_tasks(engine_task, tasks, workers=WORKERS, **chunked),
        "dask": lambda: run_tasks(engine_task, tasks, executor="dask", workers=WORKERS,
                                  **chunked),
    }
    if per_task:
        ways["dask per task"] = lambda: run_tasks(engine_task, tasks, executor="dask",
                                                  workers=WORKERS, chunk_size=1,
                                                  dask_min_tasks=0)
    seconds: dict[str, list[float]] = {way: [] for way in [*ways, "dask running"]}
    cluster = LocalCluster(n_workers=WORKERS, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address=None)
    try:
        address = cluster.scheduler_address
        ways["dask running"] = lambda: run_tasks(engine_task, tasks, executor="dask",
                                                 scheduler=address, **chunked)
        reference = _comparable(ways["local"]())
        ways["dask running"]()  # the running cluster's workers import the engines once
        for _ in range(repeats):
            for way, call in ways.items():
                begin = time.perf_counter()
                outputs = call()
                seconds[way].append(time.perf_counter() - begin)
                if _comparable(outputs) != reference:
                    raise AssertionError(f"{way}: the outputs differ from the local pool's")
    finally:
        cluster.close()
    median = {way: statistics.median(values) for way, values in seconds.items()}
    engines = sorted({task["engine"] for task in tasks})
    return {"tasks": len(tasks), "engines": engines, "workers": WORKERS, "repeats": repeats,
            "seconds": seconds, "median": median,
            "ratio": median["dask"] / median["local"],
            "ratio_running": median["dask running"] / median["local"],
            "ratio_per_task": (median["dask per task"] / median["local"]
                               if "dask per task" in median else None)}


def format_report(report: dict) -> str:
    """The printed table: each way's median and spread, then the ratios."""
    lines = [f"executors: {report['tasks']} engine tasks ({', '.join(report['engines'])}; both "
             f"presets), {report['workers']} workers, {report['repeats']} interleaved repeats"]
    for way, values in report["seconds"].items():
        lines.append(f"  {way:<16} {report['median'][way]:7.2f} s  (min {min(values):.2f}, max "
                     f"{max(values):.2f})")
    lines.append(f"  ratio dask / local {report['ratio']:.2f} (target <= {RATIO_TARGET}); "
                 f"running cluster / local {report['ratio_running']:.2f}")
    if report["ratio_per_task"] is not None:
        lines.append(f"  one future per task (before chunks) / local "
                     f"{report['ratio_per_task']:.2f}")
    return "\n".join(lines)
