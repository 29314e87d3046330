"""``impact-harness bench --executors``: the same engine tasks through the local pool and Dask.

One run, interleaved repeats, every way on the same :data:`TASKS` engine tasks (the runner's
tasks of perturbed copies of the library, :mod:`harness.bench.many_scenarios`: every
installed engine, both presets), each through :func:`harness.run.executor.run_tasks` with
:data:`WORKERS` workers:

* ``local`` -- the local process pool, in chunks (``Engine.run_many``), as ``run`` does;
* ``dask`` -- a ``LocalCluster`` of 2 single-threaded workers started for the call, in
  chunks (futures carrying bundles of them), until every result is delivered (cluster
  start included); the cluster then stops in the background (``dask shutdown``, timed
  apart: ``run`` spends it building and writing its records);
* ``dask running`` -- a cluster already running (``--scheduler``): the dispatch alone, its
  workers warm from an earlier run;
* ``dask per task`` -- a started cluster, one ``Engine.run`` per task (``chunk_size=1``, as
  before chunks; the futures carry bundles of them) (skipped with ``--quick``).

And what a user waits for: ``impact-harness run --no-cache`` end to end (a fresh interpreter,
exit included, so the background shutdown is paid where it is not overlapped) on the
scenario files behind those tasks, with ``--executor local`` and ``--executor dask``; and,
apart, what importing dask.distributed adds to a fresh interpreter (``import distributed``:
the harness's imports with and without it), which only the Dask command pays.

``ratio = dask / local`` (target :data:`RATIO_TARGET`; ``dask running / local`` and the
command's ``run dask / run local`` too). The outputs of every way are checked equal to the
local pool's, bit for bit, before any time is reported.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness.bench.many_scenarios import write_copies
from harness.engines import EngineNotInstalled, engine_names, load_engine
from harness.run.command import EXIT_ENGINE_ERROR, EXIT_GATE_FAILED, EXIT_OK
from harness.run.executor import run_tasks, start_local_cluster, wait_for_shutdowns
from harness.run.tasks import TASK_TIME_LIMIT_S, engine_chunk, engine_task, task_group
from harness.scenarios import PRESETS, load_scenarios
from harness.store.files import write_text_atomically

RATIO_TARGET = 1.2
TASKS = 2000
WORKERS = 2
REPEATS = 3
QUICK_REPEATS = 1


def engine_tasks(count: int = TASKS, directory: Path | None = None,
                 keep: Path | None = None) -> list[dict]:
    """``count`` engine tasks as the runner builds them: the library's perturbed copies, every
    point, installed engine and preset (at most 10 copies of each file's tasks).

    ``keep``: a directory that receives the scenario files whose tasks these are (the first
    files up to the last one contributing a task).
    """
    engines = {}
    for name in engine_names():
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
            sources = []  # the file of each task
            for scenario in load_scenarios(paths):
                for point in scenario.point_list():
                    names = [n for n in scenario.engines_among(list(engines)) if n in engines]
                    scene = scenario.scene(point) if names else None
                    for name in names:
                        for preset in PRESETS:
                            settings = engines[name].settings(
                                preset, scenario.engine_settings.get(name, {}))
                            tasks.append({"engine": name, "settings": settings, "scene": scene,
                                          "time_limit_s": TASK_TIME_LIMIT_S})
                            sources.append(scenario.path)
            if files > 20 * count:
                raise RuntimeError("the library yields no engine tasks")
        if keep is not None:
            keep.mkdir(parents=True, exist_ok=True)
            for path in dict.fromkeys(sources[:count]):
                write_text_atomically(keep / path.name, path.read_text(encoding="utf-8"))
    return tasks[:count]


def _comparable(outputs: list[dict]) -> list:
    return [(out["status"], out.get("velocities"), out.get("steps"), out.get("contacts"))
            for out in outputs]


def run(count: int = TASKS, repeats: int = REPEATS, per_task: bool = True,
        end_to_end: bool = True) -> dict:
    """``{"tasks", "engines", "seconds": {way: [s, ...]}, "median", "ratio", ...}``."""
    with tempfile.TemporaryDirectory() as folder:
        files = Path(folder) / "scenarios"
        tasks = engine_tasks(count, keep=files)
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
        seconds: dict[str, list[float]] = {
            way: [] for way in [*ways, "dask shutdown", "dask running"]}
        cluster = start_local_cluster(WORKERS)
        try:
            address = cluster.scheduler_address
            ways["dask running"] = lambda: run_tasks(engine_task, tasks, executor="dask",
                                                     scheduler=address, **chunked)
            reference = _comparable(ways["local"]())
            ways["dask running"]()  # the running cluster's workers import the engines once
            wait_for_shutdowns()
            for _ in range(repeats):
                for way, call in ways.items():
                    begin = time.perf_counter()
                    outputs = call()
                    seconds[way].append(time.perf_counter() - begin)
                    begin = time.perf_counter()
                    wait_for_shutdowns()  # not overlapped here: timed apart, not in the next way
                    if way == "dask":
                        seconds["dask shutdown"].append(time.perf_counter() - begin)
                    if _comparable(outputs) != reference:
                        raise AssertionError(f"{way}: the outputs differ from the local pool's")
        finally:
            cluster.close()
        if end_to_end:
            command_ways = {f"run {executor}": _run_command(files, Path(folder), executor)
                            for executor in ("local", "dask")}
            command_ways["import distributed"] = _import_cost("distributed")
            for way in command_ways:
                seconds[way] = []
            for _ in range(repeats):
                for way, call in command_ways.items():
                    seconds[way].append(call())
        file_count = len(list(files.iterdir()))
    median = {way: statistics.median(values) for way, values in seconds.items()}
    engines = sorted({task["engine"] for task in tasks})
    return {"tasks": len(tasks), "engines": engines, "workers": WORKERS, "repeats": repeats,
            "files": file_count,
            "seconds": seconds, "median": median,
            "ratio": median["dask"] / median["local"],
            "ratio_running": median["dask running"] / median["local"],
            "ratio_per_task": (median["dask per task"] / median["local"]
                               if "dask per task" in median else None),
            "ratio_command": (median["run dask"] / median["run local"]
                              if "run dask" in median else None)}


def _run_command(files: Path, folder: Path, executor: str):
    """A timer of ``impact-harness run FILES --no-cache --executor EXECUTOR`` in a fresh
    interpreter (its exit waits for the cluster's shutdown)."""
    command = [sys.executable, "-m", "harness.cli", "run", str(files), "--no-cache",
               "--workers", str(WORKERS), "--executor", executor,
               "--json", str(folder / f"results-{executor}.json")]

    def call() -> float:
        begin = time.perf_counter()
        finished = subprocess.run(command, capture_output=True, text=True, check=False)
        seconds = time.perf_counter() - begin
        # complete runs: 1 a gate failed, 4 an engine run ended in an error its record
        # reports (Drake's TAMSI on a perturbed rod): timed as any other run
        if finished.returncode not in (EXIT_OK, EXIT_GATE_FAILED, EXIT_ENGINE_ERROR):
            raise RuntimeError(f"{' '.join(command)} exited {finished.returncode}: "
                               f"{finished.stderr.strip()[-2000:]}")
        return seconds

    return call


def _import_cost(module: str):
    """A timer of what importing ``module`` adds to a fresh interpreter that imports the
    runner: the wall time of both imports less that of the runner's alone."""
    base = [sys.executable, "-c", "import harness.run.runner"]
    both = [sys.executable, "-c", f"import harness.run.runner, {module}"]

    def wall(command: list[str]) -> float:
        begin = time.perf_counter()
        subprocess.run(command, capture_output=True, check=True)
        return time.perf_counter() - begin

    return lambda: wall(both) - wall(base)


#: What each way's time holds, printed under the table.
INCLUDED = {
    "local": "pool start (forked workers), every chunk, every result delivered, pool shutdown",
    "dask": "LocalCluster start (scheduler, forked workers), the chunks, every result "
            "delivered; not its shutdown (after, in the background: dask shutdown)",
    "dask running": "the chunks on a cluster already running (no start, no shutdown)",
    "run local": "a fresh interpreter end to end: imports, reading the files, the run, "
                 "records, exit",
    "run dask": "the same with --executor dask: also importing distributed, the cluster's "
                "start and, at exit, the end of its shutdown",
}


def format_report(report: dict) -> str:
    """The printed table: each way's median and spread, then the ratios."""
    lines = [f"executors: {report['tasks']} engine tasks ({', '.join(report['engines'])}; both "
             f"presets), {report['workers']} workers, {report['repeats']} interleaved repeats"]
    for way, values in report["seconds"].items():
        lines.append(f"  {way:<18} {report['median'][way]:7.2f} s  (min {min(values):.2f}, max "
                     f"{max(values):.2f})")
    lines.append("  times hold:")
    lines.extend(f"    {way}: {what}" for way, what in INCLUDED.items()
                 if way in report["seconds"])
    lines.append(f"  ratio dask / local {report['ratio']:.2f} (target <= {RATIO_TARGET}); "
                 f"running cluster / local {report['ratio_running']:.2f}")
    if report.get("ratio_command") is not None:
        lines.append(f"  impact-harness run --no-cache on the {report['files']} files of those "
                     f"tasks, end to end: dask / local {report['ratio_command']:.2f} (importing "
                     f"distributed alone adds {report['median']['import distributed']:.2f} s)")
    if report["ratio_per_task"] is not None:
        lines.append(f"  one Engine.run per task (chunk size 1) / local "
                     f"{report['ratio_per_task']:.2f}")
    return "\n".join(lines)
