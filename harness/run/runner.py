"""``impact-harness run``: every scenario through every law and every engine that applies.

::

    impact-harness run                                  # every scenario, every engine, both presets
    impact-harness run --tags quick --engines pymunk --preset accurate
    impact-harness run scenarios/rod-45-slip-reversal.toml --json /tmp/rod.json
    impact-harness run --no-cache --executor dask --scheduler tcp://host:8786
    impact-harness run --set pymunk.iterations=50 --set mujoco.integrator=Euler --json /tmp/x.json

Settings overrides
    ``--set ENGINE.KEY=VALUE`` (repeatable, also on ``suite``) overrides one setting in every
    run of that engine, on top of the preset and of the scenario's ``[engine_settings]``. It
    shows where a scenario's overrides do: the record's ``settings_overrides`` (the report's
    labels), the complete settings in the cache key, and the provenance
    (``settings_overrides``; ``engine_settings`` lists the presets as run). A bad engine, key
    or value is bad input, checked before any work.

What runs
    For each scenario and sweep point, every law of the scenario (``planar_impact``, cheap, in
    this process) and, for ``bodies`` systems, every selected engine × preset. Analytic-only
    systems (``two-sled``, ``matrix``) never start an engine. An engine that is not installed
    or cannot build the scene gives a record with status ``"skipped: <reason>"``; an engine
    that blows up or never separates keeps the engine's status (``"blow-up"``,
    ``"no-separation"`` …). Nothing is dropped silently.

Parallelism and cache
    One task per (scenario, point, engine, preset). Each is looked up in the result cache
    (:class:`harness.store.cache.ResultCache`, key: the scene at the point, the engine and its
    version, the complete settings and the code version); only the misses run, through
    :func:`harness.run.executor.run_tasks` (local process pool, or Dask), and are stored. The
    cache holds the engine's raw output, and each scenario's finished records whole
    (:func:`_scenario_key`: one entry per scenario, the records' lines of the results file
    with the summary a run needs of them, so a warm run reads, parses and checks no record).
    A large run builds the records (departures, verdicts, contact histories) of the other
    scenarios on forked workers (:func:`_build_scenarios`), which store their entries and
    send back lines only. The misses travel in chunks of one engine and
    settings (:func:`task_group`), each one :meth:`Engine.run_many` call
    (:func:`engine_chunk`), whose runs equal one :meth:`Engine.run` each bit for bit
    (``--chunk-size 1``: one ``run`` per task). It also keeps each several-contact point's
    reference (:func:`point_reference_cached`: up to a second of m-contact solving per
    point), outside the hit and miss counts. The references it lacks are tasks of the same
    executor (:func:`reference_task`, one chunk each, submitted ahead of the engine runs),
    stored as each finishes; they equal the ones computed inline bit for bit.

    Each simulated result is stored in the cache the moment its chunk finishes, so a run
    killed half-way keeps its finished chunks and the rerun simulates only the rest. A cache that
    cannot be written (removed, read-only) costs the cache, not the run: a warning says so.
    A cache entry that fails :func:`check_engine_output` is a miss and is reported.

Bounds
    Each engine task has a time limit (:data:`TASK_TIME_LIMIT_S`, ``--task-time-limit``);
    a task over it gets the status ``"error: time limit: stopped after N s ..."`` and the run
    goes on. The local executor enforces it by ending the worker process running the task
    (:func:`harness.run.executor.run_tasks`; a run without a pool then runs its tasks in one
    child process): a signal never interrupts an engine's step in C. Dask workers are not
    stopped. A chunk gets one task's limit as a whole; a chunk over it, or one whose
    ``run_many`` raises, runs again task by task, each with its own limit, so only the task
    at fault gets the error and the others their results. A task whose worker dies (an
    engine crash) gets ``"error: worker died ..."``.
    Sweep sizes and engine step caps are bounded when the scenario is read
    (:data:`harness.scenarios.schema.LIMITS`).

Where the results go
    ``--json PATH`` when given. Without it ``reports/results.json``, but only when that file
    is absent or was written from the same selection (files, tags, engines, presets): a run
    of other scenarios refuses (exit 2) rather than silently replace the suite's results;
    ``--force`` replaces it anyway.

Exit status (see :mod:`harness.cli`)
    0 ok; 1 a scenario's ``[expect.gate]`` failed (each failing gate is named on stderr);
    2 bad input: bad options or scenario files (each bad file is one line on stderr; the
    good files still run and their results are written); 3 internal error (a record with
    status ``"error: internal: ..."``, or an exception of the harness itself).
"""

from __future__ import annotations

import argparse
import gc
import json
import math
import sys
import time
from contextlib import nullcontext
from dataclasses import asdict, dataclass, field, fields, replace
from functools import lru_cache
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence, TextIO

import numpy as np

from harness import bounds
from harness.collector import collector_paused
from harness.engines import engine_names, load_engine, parse_overrides, preset_choices, preset_role
from harness.run import metrics, references
from harness.run.history import contact_history
from harness.run.provenance import provenance
from harness.run.records import (
    ANALYTIC,
    DEFAULT_RESULTS,
    FORMAT,
    FORMAT_VERSION,
    Record,
    RecordBlock,
    check_writable,
    plain_value,
    record_line,
    write_result_blocks,
)
from harness.scenarios import ENGINES, PRESETS, Scenario, load_scenarios
from harness.store.identity import Spelled

# harness.run.verdicts and harness.run.executor (a process pool's modules) are imported where
# used: a warm run, whose records come whole from the cache, needs neither.

#: Below this many engine runs to do, the pool's start-up costs more than it saves.
MIN_PARALLEL_TASKS = 200
#: Wall-clock limit (s) of one engine task. The slowest library task (MuJoCo ``accurate``,
#: 10 µs steps) takes about a second; a task 100 times slower is stuck, not working.
TASK_TIME_LIMIT_S = 120.0
#: The ``kind`` of a cache entry holding a whole scenario's records (:func:`_scenario_key`).
SCENARIO_RECORDS = "scenario-records"
#: The ``kind`` of a point's reference, as a task of the engine runs' executor and in the cache.
POINT_REFERENCE = "point-reference"
#: A reference task counts as this many engine runs when choosing the pool over inline work:
#: a several-contact reference takes 0.1-1 s, an engine run about a millisecond.
REFERENCE_TASK_WEIGHT = 100
#: Exit statuses (documented in harness.cli): EXIT_ENGINE_ERROR when an engine run ended in
#: an error (an exception of the engine, a time limit): the results are written, but lack it.
EXIT_OK, EXIT_GATE_FAILED, EXIT_BAD_INPUT, EXIT_INTERNAL, EXIT_ENGINE_ERROR = 0, 1, 2, 3, 4
#: At most this many engine errors are printed one per line (then how many more).
SHOWN_ENGINE_ERRORS = 20


# --------------------------------------------------------------------------------------------
# The engine task (runs in a worker process)
# --------------------------------------------------------------------------------------------
def engine_task(task: dict) -> dict:
    """Simulate one (scene, engine, settings) task; a plain JSON-able dict comes back.

    Top-level and picklable for the executor. The engine adapter (its clients and models)
    is loaded once per worker process and reused. An engine that is missing here or cannot
    build the scene gives ``{"status": "skipped: …"}``; any other exception
    ``{"status": "error: …"}``, so a task never takes the run down.
    """
    if task.get("kind") == POINT_REFERENCE:  # shares the engine runs' pool (the runner)
        return reference_task(task)
    from harness.engines import EngineNotInstalled, UnsupportedScene, load_engine

    start = time.perf_counter()
    try:
        engine = load_engine(task["engine"])
        run = engine.run(task["scene"], task["settings"])
    except EngineNotInstalled as error:
        return {"status": f"skipped: {error}", "wall_time_s": time.perf_counter() - start}
    except UnsupportedScene as error:
        return {"status": f"skipped: engine cannot build the scene: {error}",
                "wall_time_s": time.perf_counter() - start}
    except Exception as error:  # reported in the record, never dropped
        return {"status": f"error: {type(error).__name__}: {error}",
                "wall_time_s": time.perf_counter() - start}
    return _stored_by_worker(task, _task_output(engine, run, time.perf_counter() - start))


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
    from harness.engines import load_engine

    start = time.perf_counter()
    first = tasks[0]
    if any(task["engine"] != first["engine"] or task["settings"] != first["settings"]
           for task in tasks):
        raise ValueError("engine_chunk: tasks of one chunk must share engine and settings")
    engine = load_engine(first["engine"])
    runs = engine.run_many([task["scene"] for task in tasks], first["settings"])
    share = (time.perf_counter() - start) / len(tasks)
    return [_stored_by_worker(task, _task_output(engine, run, share))
            for task, run in zip(tasks, runs)]


#: Keys of an engine task's output, popped by the runner: the worker stored it in the cache,
#: or could not (why) (:func:`_stored_by_worker`).
STORED_BY_WORKER, STORE_FAILED_IN_WORKER = "stored_by_worker", "store_failed_in_worker"


def _stored_by_worker(task: dict, output: dict) -> dict:
    """``output``, stored in the result cache by the process that ran the task when the
    task says where (``task["store"]``: root, code version and key; the local pool), and
    marked so (:data:`STORED_BY_WORKER`, or why not: :data:`STORE_FAILED_IN_WORKER`). A
    skipped or failed run is never stored."""
    where = task.get("store")
    if where is None or output["status"].startswith(("skipped", "error")):
        return output
    root, version, key = where
    try:
        _worker_cache(root, version).put(key, output)
    except OSError as error:
        output[STORE_FAILED_IN_WORKER] = str(error)
        return output
    output[STORED_BY_WORKER] = True
    return output


@lru_cache(maxsize=4)
def _worker_cache(root, version: str):
    """The :class:`~harness.store.cache.ResultCache` a worker stores its runs in: one per
    cache and code version, made at the first task (a put keeps no state in it)."""
    from harness.store.cache import ResultCache

    return ResultCache(root, version=version)


def task_group(task: dict) -> str:
    """The chunk key of an engine task: its engine and settings (one ``run_many`` each). A
    point's reference task (:func:`reference_task`, up to a second) is a chunk of its own."""
    import json

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


# --------------------------------------------------------------------------------------------
# Selecting what to run
# --------------------------------------------------------------------------------------------
@dataclass
class GateResult:
    """One ``[expect.gate]`` checked against one engine record."""

    scenario: str
    gate: str  # "pymunk.accurate" or "pymunk"
    law: str
    max_departure: float
    point: str
    record: str  # engine.preset
    departure: float | None
    status: str  # "pass", "FAIL" or "not checked: <why>"

    @property
    def failed(self) -> bool:
        return self.status == "FAIL"

    def describe(self) -> str:
        where = f" at {self.point}" if self.point else ""
        value = "n/a" if self.departure is None else f"{self.departure:.3g}"
        return (f"scenario {self.scenario!r} [expect.gate] \"{self.gate}\" ({self.record}{where}): "
                f"departure from {self.law} {value} vs max {self.max_departure:g}: {self.status}")


class RunOutcome:
    """What :func:`run` returns: the records, the gates, the provenance, each scenario's info.

    ``blocks``: the records as the results file holds them, one
    :class:`harness.run.records.RecordBlock` per scenario, in order. A record read from the
    cache, or built on a forked worker, travels in its block only and is parsed the first time
    :attr:`records` is asked for (a warm run that only writes the results file never decodes
    them).
    """

    def __init__(self, records: Sequence[Record | None], gates: list[GateResult],
                 provenance: dict, scenarios: dict, cache_stats: dict | None = None,
                 warnings: list[str] | None = None, blocks: Sequence[RecordBlock] = (),
                 internal: Sequence[int] = (), engine_errors: Sequence[int] = ()) -> None:
        self._records = list(records)
        self.gates = gates
        self.provenance = provenance
        self.scenarios = scenarios
        self.cache_stats = {} if cache_stats is None else cache_stats
        self.warnings = [] if warnings is None else warnings  # cache problems, one line each
        self.blocks = list(blocks)
        if sum(block.count for block in self.blocks) != len(self._records):
            raise ValueError(f"{sum(block.count for block in self.blocks)} lines for "
                             f"{len(self._records)} records")
        self._internal = list(internal)  # positions of the internal-error records
        self._engine_errors = list(engine_errors)  # positions of the engine-error records
        self._lines: list[str] | None = None

    @property
    def record_lines(self) -> list[str]:
        """Each record's line of the results file (:func:`harness.run.records.record_line`),
        in run order: the blocks' lines, decoded once."""
        if self._lines is None:
            self._lines = [line for block in self.blocks for line in block.lines()]
        return self._lines

    @property
    def records(self) -> list[Record]:
        """Every record, in run order (those held as lines parsed now, once)."""
        if any(record is None for record in self._records):
            with collector_paused():
                self._records = [self._record_at(i) for i in range(len(self._records))]
        return self._records

    def _record_at(self, index: int) -> Record:
        record = self._records[index]
        if record is None:
            record = Record.from_dict(json.loads(self.record_lines[index]))
        return record

    @property
    def record_count(self) -> int:
        return len(self._records)

    @property
    def failed_gates(self) -> list[GateResult]:
        return [gate for gate in self.gates if gate.failed]

    @property
    def internal_errors(self) -> list[Record]:
        """Records the harness itself failed to compute (a bug: exit status 3)."""
        return [self._record_at(index) for index in self._internal]

    @property
    def engine_errors(self) -> list[Record]:
        """Engine runs that ended in an error (an exception of the engine, a time limit):
        exit status 4, the results written without them."""
        return [self._record_at(index) for index in self._engine_errors]


def select_scenarios(files: Sequence[str | Path] | None = None,
                     tags: str | Iterable[str] | None = None) -> list[Scenario]:
    """The scenarios of ``files`` (files or directories; default the library) with ``tags``."""
    return load_scenarios(list(files) if files else None, tags=tags or None)


def parse_engines(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """``"pymunk,mujoco"`` (or a list) -> engine names; raises ``ValueError`` for unknown ones."""
    if text is None:
        return ENGINES
    items = text.split(",") if isinstance(text, str) else [
        part for item in text for part in str(item).split(",")]
    names = tuple(dict.fromkeys(item.strip() for item in items if item.strip()))
    unknown = [name for name in names if name not in ENGINES]
    if unknown:
        raise ValueError(f"--engines: unknown engine(s) {unknown}; allowed: {', '.join(ENGINES)}")
    return names


def parse_presets(text: str | None) -> tuple[str, ...]:
    """``--preset``: ``all``, a preset role, or an engine's name for one (``matched-bounce``
    selects the role MuJoCo gives that name, ``accurate``, for every engine)."""
    if text in (None, "all"):
        return PRESETS
    try:
        return (preset_role(None, text),)
    except ValueError:
        raise ValueError(f"--preset: {text!r}; allowed: {', '.join(preset_choices())}, all") \
            from None


def speed_labels(scenario: Scenario) -> list[str]:
    """Names of the generalized speeds, in the order of ``u``."""
    if scenario.system == "two-sled":
        return ["u1 [m/s]", "u3 [rad/s]", "u4 [m/s]", "u6 [rad/s]"]
    if scenario.system == "matrix":
        return [f"u{i + 1}" for i in range(len(scenario.matrix.u))]
    return [f"{spec.name}.{q}" for spec in scenario.bodies
            for q in ("v_x [m/s]", "v_y [m/s]", "ω [rad/s]")]


def scenario_info(scenario: Scenario) -> dict:
    """What the reports need to know about a scenario besides its records (``definition``:
    the digest of every field of its file, what the report's digests take its records to be
    made from: :func:`harness.report.reading.inputs_digests`)."""
    return {
        "description": scenario.description,
        "definition": scenario.definition_digest,
        "tags": list(scenario.tags),
        "system": scenario.system,
        "path": None if scenario.path is None else str(scenario.path),
        "analytic_only": scenario.analytic_only,
        "laws": list(scenario.laws),
        "sweep": None if scenario.sweep is None else {
            "parameter": scenario.sweep.parameter, "values": list(scenario.sweep.values)},
        "speed_labels": speed_labels(scenario),
        "gates": [{"gate": g.source, "law": g.law, "max_departure": g.max_departure}
                  for g in scenario.expect.gates],
    }


# --------------------------------------------------------------------------------------------
# The run
# --------------------------------------------------------------------------------------------
def _point_dict(point) -> dict:
    return {"index": point.index, "parameter": point.parameter, "value": point.value,
            "label": point.label}


def _scene_payload(scene):
    """The scene as a cache key's payload holds it: the dataclass itself, hashed field by
    field (:func:`harness.store.identity.canonical_json`), never copied."""
    return scene


def _settings_of(engine, preset: str, overrides: dict, memo: dict) -> dict | str:
    """``engine.settings(preset, overrides)``, or the ``ValueError``'s message; computed
    once per engine, preset and overrides (a deep copy and a check each: thousands of tasks
    share a handful)."""
    key = (engine.name, preset, json.dumps(overrides, sort_keys=True, default=repr))
    if key not in memo:
        try:
            memo[key] = engine.settings(preset, overrides)
        except ValueError as error:
            memo[key] = str(error)
    return memo[key]


def _engine_status(engines: Sequence[str], cache=None) -> tuple[dict, dict, dict]:
    """``({engine: version}, {engine: reason it is skipped}, {engine: {preset: settings}})``
    of the installed engines, without importing those whose facts ``cache`` keeps
    (:mod:`harness.engines.facts`)."""
    from harness.engines.facts import engine_facts

    facts = engine_facts(engines, cache)
    return facts.versions, facts.missing, facts.settings


def run(
    scenarios: Sequence[Scenario],
    *,
    engines: Sequence[str] = ENGINES,
    presets: Sequence[str] = PRESETS,
    cache=None,
    executor: str = "local",
    workers: int | None = None,
    scheduler: str | None = None,
    log: TextIO | None | str = "stderr",
    command: Sequence[str] | None = None,
    time_limit_s: float | None = TASK_TIME_LIMIT_S,
    selection: dict | None = None,
    overrides: dict[str, dict] | None = None,
    history: bool | None = None,
    chunk_size: int | None = None,
) -> RunOutcome:
    """Run ``scenarios`` and return the records, the gates and the provenance.

    ``cache`` is a :class:`harness.store.cache.ResultCache` (None: no cache). ``log`` gets the
    progress lines (a stream; ``"stderr"``, the default: ``sys.stderr`` at call time; None:
    quiet). ``time_limit_s`` bounds each engine task (None: no limit); ``selection`` (what
    was asked for) goes into the provenance. ``overrides`` (``{engine: {key: value}}``, from
    ``--set``) apply to every run of that engine on top of the scenario's
    ``[engine_settings]``; they land in each record's ``settings_overrides``, in the complete
    settings hashed into the cache key, and in the provenance. ``history``: record the
    per-step contact history (:mod:`harness.run.history`) in every engine record (True), in
    none (False), or (None) in those of the scenarios without a sweep, whose impact the
    report draws step by step. ``chunk_size``: engine tasks per ``Engine.run_many`` call
    (None: :func:`harness.run.executor.chunk_size_for`; 1: one ``Engine.run`` per task).
    """
    log = sys.stderr if log == "stderr" else log
    command_overrides = {name: dict(values) for name, values in (overrides or {}).items()}
    started = time.perf_counter()
    warnings: list[str] = []
    if cache is not None:
        try:
            cache.clean_temporaries()
        except OSError as error:
            warnings.append(f"cache {cache.root}: cannot clean temporaries: {error}")
    wanted_engines = [name for name in engine_names() if name in engines]
    needs_engines = any(s.engines_among(wanted_engines) for s in scenarios)
    versions, missing, preset_settings = (_engine_status(wanted_engines, cache) if needs_engines
                                          else ({}, {}, {}))

    # The lookups below find most entries absent on a cold run: read from listings of the
    # cache's directories (ResultCache.listed), not by opening each file.
    with cache.listed() if cache is not None else nullcontext():
        # 0. Whole scenarios whose finished records the cache holds: one entry each, its lines
        # kept as text (the results file's lines) beside the summary the run needs of them.
        scenario_keys: dict[str, str | None] = {}
        stored: dict[str, _Built] = {}
        stored_runs = 0  # engine runs of the scenarios read whole from the cache
        for scenario in scenarios:
            key = scenario_keys[scenario.name] = _scenario_key(
                scenario, cache, versions, missing, wanted_engines, presets, command_overrides,
                history)
            found = _stored_scenario(scenario, cache, key, presets,
                                     len(scenario.engines_among(wanted_engines)))
            if found is not None:
                stored[scenario.name] = found
                runs = found.summary["counts"]["engine_runs"]
                cache.hits += runs  # each an engine run the cache spared, as read one by one
                stored_runs += runs

        # 1. Engine tasks: build, look up in the cache. On the local pool each worker stores the
        # results it simulates (in parallel, as each chunk finishes); Dask's may lie elsewhere.
        store_in_worker = (None if cache is None or not cache.enabled or executor != "local"
                           else (str(cache.root), cache.version))
        settings_memo: dict = {}
        # ResultCache.slot_key by engine and id of settings_memo's values
        keys_of: dict = {}
        # (scenario, point, engine, preset, item)
        plan: list[tuple[Scenario, Any, str, str, dict]] = []
        tasks, task_keys, task_slots = [], [], []
        for scenario in scenarios:
            if scenario.analytic_only or scenario.name in stored:
                continue
            for point in scenario.point_list():
                scene = None
                for engine_name in scenario.engines_among(wanted_engines):
                    for preset in presets:
                        item: dict = {}
                        plan.append((scenario, point, engine_name, preset, item))
                        if engine_name in missing:
                            item["output"] = {"status": f"skipped: {missing[engine_name]}"}
                            continue
                        engine = load_engine(engine_name)  # loaded once, for runs to build
                        overrides = {**scenario.engine_settings.get(engine_name, {}),
                                     **command_overrides.get(engine_name, {})}
                        item["overrides"] = overrides
                        item["history"] = (scenario.sweep is None if history is None
                                           else history)
                        settings = _settings_of(engine, preset, overrides, settings_memo)
                        if isinstance(settings, str):
                            item["output"] = {"status": f"error: settings: {settings}"}
                            continue
                        if scene is None:
                            scene = engine_scene(scenario, point)
                            # spelled once for the keys of all the point's engine runs
                            spelled_scene = (None if cache is None
                                             else Spelled(_scene_payload(scene)))
                        key = None
                        if cache is not None:  # the key's text around the scene made once
                            key_of = keys_of.get((engine_name, id(settings)))
                            if key_of is None:
                                key_of = keys_of[engine_name, id(settings)] = cache.slot_key(
                                    {"kind": "engine-run", "engine": engine_name,
                                     "engine_version": engine.version,
                                     "settings": Spelled(settings)}, "scene")
                            key = key_of(spelled_scene)
                        item["key"] = key
                        speeds = 3 * len(scene.bodies)
                        cached = None if cache is None else cache.get(
                            key, check=lambda output, speeds=speeds: check_engine_output(output,
                                                                                       speeds))
                        if cached is not None:
                            item["output"], item["cached"] = cached, True
                            continue
                        tasks.append({"engine": engine_name, "settings": settings, "scene": scene,
                                      "time_limit_s": time_limit_s,
                                      "store": None if store_in_worker is None
                                      else (*store_in_worker, key)})
                        task_keys.append(key)
                        task_slots.append(item)
        # Several-contact references the records will need and the cache lacks: tasks of the
        # same executor, ahead of the engine runs (each takes up to a second).
        reference_tasks, reference_keys, computed_references = _reference_tasks(
            [s for s in scenarios if s.name not in stored], cache)
        if store_in_worker is not None:  # each stored by the worker computing it, as runs
            for task, key in zip(reference_tasks, reference_keys):
                task["store"] = None if key is None else (*store_in_worker, key)
        if cache is not None:
            warnings += [f"cache entry rejected (simulated again): {entry}"
                         for entry in cache.rejected]

    # 2. Run the misses; store each in the cache as it finishes.
    cache_failed: list[str] = []

    def store(index: int, output: dict) -> None:
        if index < len(reference_tasks):
            task = reference_tasks[index]
            if "reference" in output:  # else built inline, where its error is reported
                computed_references[task["scenario"], task["point"]] = output["reference"]
                stored = output.pop(STORED_BY_WORKER, False)
                problem = output.pop(STORE_FAILED_IN_WORKER, None)
                if problem is not None and not cache_failed:
                    cache_failed.append(f"cache {cache.root}: cannot store results ({problem}); "
                                        "the run goes on without the cache")
                if not (stored or cache_failed or reference_keys[index] is None):
                    _store_reference(cache, reference_keys[index], output["reference"])
            return
        index -= len(reference_tasks)
        stored = output.pop(STORED_BY_WORKER, False)
        problem = output.pop(STORE_FAILED_IN_WORKER, None)
        task_slots[index]["output"], task_slots[index]["cached"] = output, False
        if problem is not None and not cache_failed:
            cache_failed.append(f"cache {cache.root}: cannot store results ({problem}); "
                                "the run goes on without the cache")
        if (stored or cache is None or cache_failed
                or output["status"].startswith(("skipped", "error"))):
            return
        try:
            cache.put(task_keys[index], output)
        except OSError as error:  # the run goes on without the cache
            cache_failed.append(f"cache {cache.root}: cannot store results ({error}); "
                                "the run goes on without the cache")

    if tasks or reference_tasks:
        if log is not None:
            print(f"engine runs: {len(tasks)} to simulate, "
                  f"{len(plan) + stored_runs - len(tasks)} cached or "
                  f"skipped; {len(reference_tasks)} several-contact references to compute",
                  file=log, flush=True)
        simulating = time.perf_counter()
        _run_tasks(reference_tasks + tasks, executor=executor, workers=workers,
                   scheduler=scheduler, log=log, on_result=store, chunk_size=chunk_size,
                   weight=len(tasks) + REFERENCE_TASK_WEIGHT * len(reference_tasks))
        if log is not None:
            print(f"engine runs: {len(tasks)} simulated, {len(reference_tasks)} references "
                  f"computed in {time.perf_counter() - simulating:.2f} s", file=log, flush=True)
    warnings += cache_failed
    if log is not None:
        for warning in warnings:
            print(f"warning: {warning}", file=log, flush=True)

    # 3. Records, scenario by scenario: those not read whole from the cache built (on forked
    # workers for a large run), each scenario's entry stored as it is built.
    by_scenario: dict[str, list] = {}
    for entry in plan:
        by_scenario.setdefault(entry[0].name, []).append(entry)
    built = _build_scenarios([s for s in scenarios if s.name not in stored], by_scenario,
                             cache, computed_references, scenario_keys,
                             workers=1 if executor == "local" and workers == 1 else workers)
    records: list[Record | None] = []
    blocks: list[RecordBlock] = []
    internal: list[int] = []
    engine_errors: list[int] = []
    gates: list[GateResult] = []
    infos: dict[str, dict] = {}
    for number, scenario in enumerate(scenarios, 1):
        infos[scenario.name] = scenario_info(scenario)
        result = stored.get(scenario.name) or built[scenario.name]
        internal += [len(records) + position for position in result.internal]
        engine_errors += [len(records) + position for position in result.engine_errors]
        records += (result.records if result.records is not None
                    else [None] * result.block.count)
        blocks.append(result.block)
        infos[scenario.name]["references"] = result.summary["references"]
        scenario_gates = [GateResult(**gate) for gate in result.summary["gates"]]
        gates += scenario_gates
        if log is not None:
            print(_progress_line(number, len(scenarios), scenario, result.summary["counts"],
                                 scenario_gates), file=log, flush=True)

    settings_table = {  # the presets as run: with the command line's --set overrides
        name: (preset_settings[name] if name not in command_overrides else
               {preset: load_engine(name).settings(preset, command_overrides[name])
                for preset in PRESETS})
        for name in versions
    }
    stats = cache.stats if cache is not None else {"enabled": False, "hits": 0, "misses": 0}
    info = provenance(
        FORMAT, FORMAT_VERSION,
        engine_settings=settings_table,
        command=command,
        engine_versions=dict(versions),
        engines_missing=missing,
        engines=list(wanted_engines),
        presets=list(presets),
        executor={"executor": executor, "workers": workers, "scheduler": scheduler},
        cache={**stats, "root": None if cache is None else str(cache.root),
               "engine_runs": len(plan) + stored_runs, "simulated": len(tasks)},
        selection=selection,
        settings_overrides=command_overrides,
        history="scenarios without a sweep" if history is None else history,
        task_time_limit_s=time_limit_s,
        gates=[asdict(g) for g in gates],
        wall_time_s=time.perf_counter() - started,
    )
    return RunOutcome(records=records, gates=gates, provenance=info, scenarios=infos,
                      cache_stats=stats, warnings=warnings, blocks=blocks, internal=internal,
                      engine_errors=engine_errors)


def _scenario_key(scenario: Scenario, cache, versions: Mapping, missing: Mapping,
                  wanted_engines: Sequence[str], presets: Sequence[str],
                  command_overrides: Mapping, history: bool | None) -> str | None:
    """The cache key of a scenario's finished records, or None when they are not kept.

    A warm run of a large library spent most of its time looking up each engine run, each
    point's records and reference (tens of thousands of small files) and computing their
    keys (the settings, the scene at every point). A scenario's records depend only on its
    definition (not its path), the engines that apply with their versions, the presets, the
    ``--set`` overrides and the history flag (under the code version every key holds), which
    make this key: one entry per scenario (the definition by its digest,
    :attr:`Scenario.definition_digest`, spelled once per scenario text). Not kept when an
    engine of the scenario is missing (its runs are skipped, and a skipped run is never
    cached).
    """
    if cache is None or not cache.enabled:
        return None
    engines = scenario.engines_among(wanted_engines)
    if any(name in missing or name not in versions for name in engines):
        return None
    try:
        return cache.key({"kind": SCENARIO_RECORDS, "scenario": scenario.definition_digest,
                          "engines": [[name, versions[name]] for name in engines],
                          "presets": list(presets),
                          "overrides": {name: command_overrides.get(name, {})
                                        for name in engines},
                          "history": history})
    except TypeError:  # a definition holding a value without a canonical spelling: not kept
        return None


@dataclass
class _Built:
    """A scenario's finished records: as the results file holds them (``block``), the
    records themselves when built in this process (None: read from the
    cache or built on a worker, parsed from the block when asked for), the ``summary`` the
    run needs of them (:func:`_summary`) and the positions of internal-error records."""

    block: RecordBlock
    summary: dict
    records: list[Record] | None = None
    internal: list[int] = field(default_factory=list)
    engine_errors: list[int] = field(default_factory=list)  # positions, internal ones apart


def _stored_scenario(scenario: Scenario, cache, key: str | None, presets: Sequence[str],
                     engine_count: int) -> _Built | None:
    """The scenario's finished records from its cache entry (:func:`_scenario_key`), as the
    results file holds them (neither decoded nor parsed) with their summary,
    or None.

    The entry was checked when it was stored (:func:`_store_scenario`) and its checksum
    shows it unchanged since; it is used only when it holds one line per law and engine
    run of every point and a summary of the expected shape. Any other is a miss, listed in
    the cache's ``rejected`` (the run's warnings) and rebuilt.
    """
    if key is None:
        return None
    expected = len(scenario.point_list()) * (len(scenario.laws) + engine_count * len(presets))
    gate_fields = {f.name for f in fields(GateResult)}

    def check(summary) -> str | None:
        if not (isinstance(summary, dict) and isinstance(summary.get("references"), list)
                and isinstance(summary.get("gates"), list)
                and all(isinstance(g, dict) and g.keys() == gate_fields
                        for g in summary["gates"])
                and isinstance(summary.get("counts"), dict)
                and summary["counts"].keys() == set(_COUNTS)
                and all(isinstance(v, int) for v in summary["counts"].values())):
            return "no summary of the records"
        if summary["counts"]["records"] != expected:
            return f"not {expected} records"
        return None

    entry = cache.get_block(key, check_summary=check)
    if entry is None:
        return None
    summary, text, count, parts = entry
    if count != expected or parts:
        cache.rejected.append(f"{cache.lines_path(key)}: {count} lines and {len(parts)} "
                              f"parts, not {expected} and none")
        return None
    return _Built(block=RecordBlock(text, count), summary=summary)


#: The counts of a scenario's records its summary keeps (for the progress line, the hits).
_COUNTS = ("records", "points", "laws", "laws_ok", "engine_runs", "cached", "skipped",
           "flagged")


def _summary(scenario: Scenario, records: Sequence[Record]) -> dict:
    """What the run needs of a scenario's records besides the records: each point's
    reference (its scenario info), its gates (:func:`check_gates`) and the counts of the
    progress line; plain JSON values, kept in the scenario's cache entry."""
    laws = [r for r in records if r.source == ANALYTIC]
    engines = [r for r in records if r.source != ANALYTIC]
    counts = {"records": len(records), "points": len(scenario.point_list()),
              "laws": len(laws), "laws_ok": sum(r.ok for r in laws),
              "engine_runs": len(engines), "cached": sum(r.cached for r in engines),
              "skipped": sum(r.skipped for r in engines),
              "flagged": sum(not r.ok and not r.skipped for r in engines)}
    return plain_value({"references": references.collect(records),
                      "gates": [asdict(gate) for gate in check_gates(scenario, records)],
                      "counts": counts})


#: Below this many records to build, forking workers costs more than it saves.
MIN_PARALLEL_RECORDS = 1000
#: What the forked record builders read (:func:`_build_job`): set around the pool only.
_BUILD_STATE: tuple | None = None


def _build_scenarios(scenarios: Sequence[Scenario], by_scenario: Mapping[str, list], cache,
                     computed_references: Mapping, scenario_keys: Mapping, *,
                     workers: int | None = None) -> dict[str, _Built]:
    """:func:`_build_scenario` of each scenario, by name.

    A large run (:data:`MIN_PARALLEL_RECORDS`) builds them on ``workers`` forked processes
    (None: every core), which read the engine outputs and references from this process's
    memory and send back the records' lines and summaries only (the records are parsed from
    the lines when asked for: :attr:`RunOutcome.records`); each stores its scenarios' cache
    entries. Records are the same either way (built by the same code from the same values).
    """
    global _BUILD_STATE
    if not scenarios:  # a warm run's: every scenario's records read whole from the cache
        return {}
    from harness.processes import default_workers, map_forked

    workers = default_workers() if workers is None else workers
    size = sum(len(s.point_list()) * len(s.laws) + len(by_scenario.get(s.name, ()))
               for s in scenarios)  # records to build
    if workers <= 1 or size < MIN_PARALLEL_RECORDS:
        return {s.name: _build_scenario(s, by_scenario.get(s.name, []), cache,
                                        computed_references, scenario_keys.get(s.name))
                for s in scenarios}
    # Small blocks, handed out as workers free up: scenarios differ a thousandfold in cost.
    block = max(1, len(scenarios) // (workers * 16))
    blocks = [list(range(start, min(start + block, len(scenarios))))
              for start in range(0, len(scenarios), block)]
    _BUILD_STATE = (scenarios, by_scenario, cache, computed_references, scenario_keys)
    gc.freeze()  # the workers' collector never walks (and so copies) the inherited objects
    try:
        done = map_forked(_build_job, blocks, workers)
    finally:
        gc.unfreeze()
        _BUILD_STATE = None
    return {scenarios[index].name: result for indices, results in zip(blocks, done)
            for index, result in zip(indices, results)}


def _build_job(indices: list[int]) -> list[_Built]:
    """The scenarios ``indices`` of :data:`_BUILD_STATE` built on a forked worker, without
    their records (only lines travel back)."""
    scenarios, by_scenario, cache, computed_references, scenario_keys = _BUILD_STATE
    with collector_paused():  # a short-lived worker: nothing it builds is garbage yet
        results = []
        for index in indices:
            scenario = scenarios[index]
            result = _build_scenario(scenario, by_scenario.get(scenario.name, []), cache,
                                     computed_references, scenario_keys.get(scenario.name))
            result.records = None
            results.append(result)
        return results


def _build_scenario(scenario: Scenario, entries: Sequence, cache, computed_references: Mapping,
                    key: str | None) -> _Built:
    """A scenario's records from its engine entries (``(scenario, point, engine, preset,
    item)`` of the run's plan) and its points' references, with their lines and summary;
    its cache entry stored when ``key`` (:func:`_store_scenario`)."""
    by_point: dict[int, list] = {}
    for entry in entries:
        by_point.setdefault(entry[1].index, []).append(entry)
    records: list[Record] = []
    for point in scenario.point_list():
        records += _point_records_or_errors(
            scenario, point, by_point.get(point.index, []), cache=cache,
            reference=computed_references.get((scenario.name, point.index)))
    summary = _summary(scenario, records)
    datas = [record.as_dict() for record in records]
    lines = [record_line(data) for data in datas]
    block = RecordBlock.of_lines(lines)
    internal = [i for i, r in enumerate(records) if r.status.startswith("error: internal")]
    engine_errors = [i for i, r in enumerate(records) if r.source != ANALYTIC
                     and r.status.startswith("error:")
                     and not r.status.startswith("error: internal")]
    if not internal:
        _store_scenario(cache, key, entries, records, datas, lines, summary)
    return _Built(block=block, summary=summary, records=records, internal=internal,
                  engine_errors=engine_errors)


def _finite_speeds(after, before) -> bool:
    """``after`` is a list of finite numbers as long as the list ``before``."""
    return (isinstance(after, list) and isinstance(before, list) and len(after) == len(before)
            and all(isinstance(value, (int, float)) and not isinstance(value, bool)
                    and math.isfinite(value) for value in after))


def _store_scenario(cache, key: str | None, engine_entries: Sequence, records: Sequence[Record],
                    datas: Sequence[dict], lines: Sequence[str], summary: dict) -> None:
    """Keep a scenario's records under ``key`` when every engine run was cacheable (none
    skipped or failed) and none is an ok record without finite speeds (a record the lookup
    would reject every run); as a warm run reads them back: every engine record ``cached``
    (``datas``: each record's :meth:`Record.as_dict`, ``lines`` their lines). Stored as the
    results file holds them (:class:`RecordBlock`), with the ``summary``, so a warm run
    writes them as read."""
    if key is None or cache is None or not cache.enabled:
        return
    if not all(isinstance(item.get("output"), dict) and item.get("key") is not None
               and not str(item["output"].get("status", "")).startswith(("skipped", "error"))
               for _, _, _, _, item in engine_entries):
        return
    if any(record.ok and not _finite_speeds(record.u_after, record.u_before)
           for record in records):
        return
    stored_datas = [data if record.source == ANALYTIC or record.cached
                    else {**data, "cached": True} for record, data in zip(records, datas)]
    stored_lines = [line if stored is data else _cached_line(line, stored)
                    for data, stored, line in zip(datas, stored_datas, lines)]
    counts = summary["counts"]
    stored_summary = {**summary, "counts": {**counts, "cached": counts["engine_runs"]}}
    try:
        cache.put_lines(key, stored_lines, stored_summary)
    except OSError:  # the run goes on without the cache (the engine runs' store warns)
        pass


#: A not-cached record's line, from its field ``cached`` on (:class:`Record`'s field order).
_NOT_CACHED = ',"cached":false'


def _cached_line(line: str, stored: dict) -> str:
    """:func:`record_line` of ``stored``, the record of ``line`` with ``cached`` true, by
    editing the line where the field is the line's only match (a key ``cached`` inside a
    dict field, ``point`` or ``departure``, would match too: then, as for a line of another
    layout, the line is spelled in full)."""
    marker = f'{_NOT_CACHED},"diagnostics":'
    at = line.find(marker)
    if at < 0 or line.find(marker, at + 1) >= 0:
        return record_line(stored)
    return f'{line[:at]},"cached":true{line[at + len(_NOT_CACHED):]}'


def _point_records_or_errors(scenario: Scenario, point, engine_entries: Sequence, *,
                             cache=None, reference: dict | None = None) -> list[Record]:
    """:func:`point_records`, or, when the harness fails on this point, one record per law
    and engine run with status ``"error: internal: ..."``: one bad point costs its records,
    not the run."""
    try:
        return point_records(scenario, point, engine_entries, cache=cache,
                             reference=reference)
    except Exception as error:  # noqa: BLE001 - a harness bug: in the records, exit status 3
        status = f"error: internal: {type(error).__name__}: {error}"
        info = _point_dict(point)
        return ([Record(scenario=scenario.name, point=info, source=ANALYTIC, law=law,
                        status=status) for law in scenario.laws]
                + [Record(scenario=scenario.name, point=info, source=engine_name, preset=preset,
                          status=status, cached=bool(item.get("cached", False)))
                   for _, _, engine_name, preset, item in engine_entries])


def _run_tasks(tasks, *, executor, workers, scheduler, log, on_result=None,
               chunk_size=None, weight: int | None = None) -> list[dict]:
    """The engine tasks through the executor: in chunks of one engine and settings, each one
    :func:`engine_chunk` (``Engine.run_many``) call; ``chunk_size=1``: one :func:`engine_task`
    (``Engine.run``) each, as before chunks. Reference tasks (:func:`reference_task`) go one
    per chunk. ``weight``: the work in engine runs (default: one per task); below
    :data:`MIN_PARALLEL_TASKS` the local executor runs inline."""
    from harness.run.executor import progress_printer, run_tasks

    weight = len(tasks) if weight is None else weight
    if executor == "local" and workers is None and weight < MIN_PARALLEL_TASKS:
        workers = 1
    progress = progress_printer("engine runs", stream=log) if log is not None else None
    note = None if log is None else (lambda text: print(text, file=log, flush=True))
    batch = None if chunk_size == 1 else engine_chunk
    return run_tasks(engine_task, tasks, executor=executor, workers=workers,
                     scheduler=scheduler, progress=progress, on_result=on_result,
                     batch=batch, group=task_group, chunk_size=chunk_size, note=note,
                     time_limit=task_time_limit, stopped=stopped_task)


def point_records(scenario: Scenario, point, engine_entries: Sequence, *,
                  cache=None, reference: dict | None = None) -> list[Record]:
    """The law records and the engine records of one sweep point.

    ``cache`` (a :class:`harness.store.cache.ResultCache`, or None) keeps the point's
    reference (:func:`point_reference_cached`) between runs. ``reference``: the point's
    reference already computed (a :func:`reference_task` of the run); None: read from the
    cache or computed here.
    """
    from harness.run import verdicts

    fixed = scenario.at(point)
    mu, e = fixed.friction, fixed.restitution
    problem = scenario.analytic_problem(point)
    mass_matrix, u_before = problem.mass_matrix, problem.u
    free_bodies = fixed.system == "bodies" and not fixed.ground
    vn_approach, vt_approach = metrics.contact_velocities(problem, u_before)
    point_info = _point_dict(point)
    mnn, mnt, mtt = metrics.delassus(problem)
    contact_space = {"mnn": mnn, "mnt": mnt, "mtt": mtt, "mu": mu, "e": e}

    law_records: list[Record] = []
    law_speeds: dict[str, np.ndarray | None] = {}
    law_gains: dict[str, float] = {}  # the energy change of each law solved
    solve_law = problem.law_solver(mu=mu, e=e)  # problem.solve, the problem checked once
    for law in scenario.laws:
        tick = time.perf_counter()
        try:
            result = solve_law(law)
        except ValueError as error:
            law_speeds[law] = None
            law_records.append(Record(
                scenario=scenario.name, point=point_info, source=ANALYTIC, law=law,
                u_before=u_before.tolist(), vn_approach=vn_approach, vt_approach=vt_approach,
                status=f"error: {error}", wall_time_s=time.perf_counter() - tick,
                diagnostics=dict(contact_space)))
            continue
        law_speeds[law] = result.u_after
        law_gains[law] = result.energy_change
        law_records.append(Record(
            scenario=scenario.name, point=point_info, source=ANALYTIC, law=law,
            u_before=u_before.tolist(), u_after=result.u_after.tolist(),
            vn_approach=result.vn_approach, vt_approach=result.vt_approach,
            vn_separation=result.vn_separation, vt_separation=result.vt_separation,
            energy_change=result.energy_change, collision_type=result.collision_type,
            normal_impulse=result.normal_impulse, tangential_impulse=result.tangential_impulse,
            status="ok", wall_time_s=time.perf_counter() - tick,
            diagnostics={**contact_space, "case": result.case,
                         "restitution_poisson": result.restitution_poisson,
                         "restitution_in_range": result.restitution_in_range}))
    for record, law in zip(law_records, scenario.laws):
        if law_speeds[law] is not None:
            record.departure = metrics.departures(mass_matrix, law_speeds[law], law_speeds,
                                                  u_before, free_bodies=free_bodies)

    if reference is None:
        reference = point_reference_cached(scenario, point, cache)
    reference = references.annotate(scenario, point, law_records, reference, keep_full=True)
    if not engine_entries:
        return law_records
    scene = engine_scene(scenario, point)
    if "newton-lcp" in law_speeds:  # solved above (or failed: the same solve fails again)
        lcp_gain = law_gains.get("newton-lcp")
    else:
        try:  # the engines' own law, to attribute an energy gain (docs/verdicts.md)
            lcp_gain = solve_law("newton-lcp").energy_change
        except ValueError:
            lcp_gain = None
    declared = verdicts.declared_contacts(scenario, scene)  # a flat face: judged against all
    struck = verdicts.sequence_contacts(scenario, scene)  # a tilt: the features its sequence
    sequence = struck is not None  # strikes, the run judged on finishing it
    if sequence:
        declared = struck
    if declared is not None:  # a gain is the law's when the m-contact or sequence reference
        lcp_gain = reference.get("energy_change", {}).get(reference.get("primary"))  # gains
    # What judging any run of the point's scene needs: worked out once, not once per run.
    terms = verdicts.prepare(scene, problem) if declared is None else None
    engine_records = [
        engine_record(scenario, point_info, engine_name, preset, item, problem, law_speeds,
                      scene=scene, law_energy_change=lcp_gain, contacts=declared,
                      terms=terms, sequence=sequence)
        for _, _, engine_name, preset, item in engine_entries
    ]
    references.annotate(scenario, point, engine_records, reference)
    return law_records + engine_records


def engine_scene(scenario: Scenario, point):
    """The scene the engines run at ``point``: ``scenario.scene(point)``, and for a tilt whose
    reference is a sequence of impacts (``expect_sequence``) with ``run_until`` set to the
    sequence's last impact (``newton-lcp``, the primary reference), so that every engine runs
    the whole sequence, not only its first impact (harness/engines/contract.py, 'The loop')."""
    scene = scenario.scene(point)
    if references.kind_of(scenario) != references.EVENT_DRIVEN or not scene.ground:
        return scene
    from harness.reference.event_driven import sequence_outline

    outline = sequence_outline(scene)
    if len(outline.features) < 2 and outline.last_impact == 0.0:
        return scene  # one impact: the first separation ends it
    return replace(scene, run_until=outline.last_impact)


def point_reference_cached(scenario: Scenario, point, cache=None) -> dict:
    """:func:`harness.run.references.point_reference`, read from ``cache`` when it holds it.

    A several-contact reference (a flat face's m-contact laws, a tilt's event sequence) costs
    up to a second per point, far more than the engine runs it judges; it depends only on
    the scene at the point, its μ, e and laws and the situation the scenario declares, which
    make the key. A single-contact reference costs nothing and is not stored.
    """
    key = _reference_key(scenario, point, cache)
    if key is None:
        return references.point_reference(scenario, point)
    cached = _stored_reference(cache, key)
    if cached is not None:
        return cached
    reference = references.point_reference(scenario, point)
    _store_reference(cache, key, reference)
    return reference


def _reference_key(scenario: Scenario, point, cache) -> str | None:
    """The cache key of a point's several-contact reference (:func:`point_reference_cached`);
    None without a cache or for a single-contact point (never stored)."""
    kind = references.kind_of(scenario)
    if cache is None or kind == references.SINGLE:
        return None
    from harness.scenarios.schema import ONE_POINT_TOLERANCE

    fixed = scenario.at(point)
    return cache.key({"kind": POINT_REFERENCE, "situation": kind,
                      "scene": _scene_payload(scenario.scene(point)),
                      "friction": fixed.friction, "restitution": fixed.restitution,
                      "laws": list(fixed.laws), "one_point_tolerance": ONE_POINT_TOLERANCE})


def _stored_reference(cache, key: str) -> dict | None:
    return cache.get(key, check=lambda stored: None if isinstance(stored.get("kind"), str)
                     else "no reference kind", count=False)


def _store_reference(cache, key: str, reference: dict) -> None:
    try:
        cache.put(key, reference)
    except OSError:  # the run goes on without the cache (the engine runs' store warns)
        pass


def _reference_tasks(scenarios: Sequence[Scenario], cache
                     ) -> tuple[list[dict], list, dict[tuple[str, int], dict]]:
    """The reference tasks (:func:`reference_task`) of the several-contact points of
    ``scenarios`` whose reference the cache does not hold, their cache keys (None without a
    cache), and the references the cache holds, by ``(scenario name, point index)`` (read
    once here, handed to the records)."""
    tasks, keys, found = [], [], {}
    for scenario in scenarios:
        if references.kind_of(scenario) == references.SINGLE:
            continue
        for point in scenario.point_list():
            key = _reference_key(scenario, point, cache)
            stored = None if key is None else _stored_reference(cache, key)
            if stored is not None:
                found[scenario.name, point.index] = stored
                continue
            tasks.append({"kind": POINT_REFERENCE, "scenario": scenario.name,
                          "point": point.index, "situation": references.kind_of(scenario),
                          "scene": scenario.scene(point),
                          "laws": references.PointLaws.of(scenario.at(point))})
            keys.append(key)
    return tasks, keys, found


def reference_task(task: dict) -> dict:
    """The several-contact reference of one point, computed in a worker process.

    ``task`` holds the situation (``situation``, :func:`harness.run.references.kind_of`), the
    ``scene`` at the point and its ``laws`` (:class:`harness.run.references.PointLaws`): a
    scenario does not pickle; ``store`` where the worker keeps the reference (or None). The
    result is ``{"reference": …}``
    (:func:`harness.run.references.scene_reference`, the very dict the main process would
    compute) or, when it raises, ``{"error": "…"}``: the main process then builds the
    reference inline, where the exception becomes the point's internal-error records as
    before (:func:`_point_records_or_errors`).
    """
    from harness.processes import one_blas_thread

    one_blas_thread()  # a Dask worker has no pool initializer
    try:
        reference = references.scene_reference(task["situation"], task["scene"], task["laws"])
    except Exception as error:  # noqa: BLE001 - raised again, and reported, in the main process
        return {"error": f"{type(error).__name__}: {error}"}
    return _reference_stored_by_worker(task, {"reference": reference})


def _reference_stored_by_worker(task: dict, output: dict) -> dict:
    """:func:`_stored_by_worker` of a reference task's output: the reference stored under
    ``task["store"]`` when given (the local pool: the main process then spells and writes
    none of them)."""
    where = task.get("store")
    if where is None:
        return output
    from harness.store.cache import ResultCache

    root, version, key = where
    try:
        ResultCache(root, version=version).put(key, output["reference"])
    except OSError as error:
        output[STORE_FAILED_IN_WORKER] = str(error)
        return output
    output[STORED_BY_WORKER] = True
    return output


def engine_record(scenario: Scenario, point_info: dict, engine_name: str, preset: str,
                  item: dict, problem, law_speeds: dict, *, scene=None,
                  law_energy_change: float | None = None, contacts=None,
                  terms=None, sequence: bool = False) -> Record:
    """An engine's record from its raw output and the point's law solutions.

    With ``scene`` (the engine's scene at this point) the record gets its verdict
    (:func:`harness.run.verdicts.judge`): ``verdict`` and ``reasons``, and a run that fails
    a check has the first failing reason as its ``status`` (never ``ok``).
    ``law_energy_change`` is ``newton-lcp``'s energy change, to attribute a gain;
    ``contacts``: a flat face's declared contacts (:func:`verdicts.declared_contacts`), or
    with ``sequence`` the features a tilt's sequence strikes (:func:`verdicts.sequence_contacts`);
    ``terms``: ``verdicts.prepare(scene, problem)`` when the caller has it (None: worked out
    by the verdict).
    """
    from harness.run import verdicts

    output = item["output"]
    free_bodies = scene is not None and not scene.ground
    mass_matrix, u_before = problem.mass_matrix, problem.u
    vn_approach, vt_approach = metrics.contact_velocities(problem, u_before)
    record = Record(scenario=scenario.name, point=point_info, source=engine_name, preset=preset,
                    u_before=u_before.tolist(), vn_approach=vn_approach,
                    vt_approach=vt_approach, status=output["status"],
                    wall_time_s=float(output.get("wall_time_s", 0.0)),
                    cached=bool(item.get("cached", False)))
    if "velocities" not in output:
        return record
    u_after = np.array([value for body in output["velocities"] for value in body], dtype=float)
    record.u_after = u_after.tolist()
    finite = all(map(math.isfinite, record.u_after))  # np.isfinite(u_after).all(), cheaper
    diagnostics = {key: output.get(key) for key in (
        "steps", "contact_steps", "first_contact_step", "max_contact_points", "max_penetration",
        "separated", "step_cap_hit", "out_of_plane_drift", "contact_normal",
        "engine_normal_impulse", "engine_tangential_impulse", "derived", "notes",
        "engine_wall_time_s")}
    diagnostics["settings_overrides"] = item.get("overrides", {})
    implied = None  # the impulse Δu implies, for the verdict when its residual is finite
    if finite and item.get("history") and scene is not None:
        diagnostics["history"] = contact_history(problem, output, scene,
                                                 float(output.get("time_step") or 0.0))
    if finite:
        vn, vt = metrics.contact_velocities(problem, u_after)
        record.vn_separation, record.vt_separation = vn, vt
        record.energy_change = metrics.energy_change(mass_matrix, u_before, u_after)
        record.collision_type = metrics.classify_end_state(vt_approach, vt, vn_approach)
        normal, tangential, residual = metrics.impulses_from_velocities(
            problem, u_after, free_bodies=free_bodies)
        diagnostics["impulse_from_velocities"] = [normal, tangential]
        diagnostics["impulse_residual"] = residual
        if math.isfinite(residual):
            implied = normal, tangential, residual
        if output.get("engine_normal_impulse") is not None:
            record.normal_impulse = output["engine_normal_impulse"]
            record.tangential_impulse = output.get("engine_tangential_impulse")
            diagnostics["impulse_source"] = "engine"
        else:
            record.normal_impulse, record.tangential_impulse = normal, tangential
            diagnostics["impulse_source"] = "velocities"
    record.departure = metrics.departures(mass_matrix, u_after, law_speeds, u_before,
                                          free_bodies=free_bodies)
    record.diagnostics = diagnostics
    if scene is not None:
        verdict = verdicts.judge(scene, problem,
                                 verdicts.numbers_from_output(engine_name, output),
                                 law_energy_change=law_energy_change, contacts=contacts,
                                 terms=terms, implied=implied, sequence=sequence)
        record.verdict, record.reasons = verdict.label, verdict.as_list()
        record.status = verdict.status(record.status)
    return record


def check_gates(scenario: Scenario, records: Sequence[Record]) -> list[GateResult]:
    """Every ``[expect.gate]`` of ``scenario`` against its engine records."""
    from harness.run import verdicts

    results = []
    for gate in scenario.expect.gates:
        matching = [r for r in records if r.source == gate.engine
                    and (gate.preset is None or r.preset == gate.preset)]
        if not matching:
            results.append(GateResult(scenario.name, gate.source, gate.law, gate.max_departure,
                                      "", gate.source, None,
                                      "not checked: engine or preset not run"))
            continue
        for record in matching:
            value = record.departure.get(gate.law)
            situation = ((record.diagnostics or {}).get("reference") or {}).get(
                "kind", references.SINGLE)
            if record.skipped:
                status = f"not checked: {record.status}"
            elif record.verdict == verdicts.FLAGGED:  # not a single impact: no departure
                status = f"not checked: flagged ({', '.join(record.failing_reasons)})"
            elif situation != references.SINGLE and value is None:  # a law that does not apply
                status = (f"not checked: {gate.law} does not apply to a {situation} point "
                          "(its references: docs/multi-contact.md)")
            elif value is None or not math.isfinite(value):
                status = "FAIL"
            else:
                status = "pass" if value <= gate.max_departure else "FAIL"
            results.append(GateResult(scenario.name, gate.source, gate.law, gate.max_departure,
                                      record.point["label"], record.label,
                                      None if value is None or not math.isfinite(value)
                                      else float(value), status))
    return results


def _progress_line(number, total, scenario, counts: Mapping, gates) -> str:
    """One scenario's line of the log from its records' counts (:func:`_summary`)."""
    points, cached = counts["points"], counts["cached"]
    parts = [f"{points} point{'s' if points != 1 else ''}",
             f"{counts['laws_ok']}/{counts['laws']} law solutions"]
    if scenario.analytic_only:
        parts.append("analytic only")
    else:
        parts.append(f"{counts['engine_runs']} engine runs ({cached} cached, "
                     f"{counts['skipped']} skipped, {counts['flagged']} flagged)")
    if gates:
        failed = sum(g.failed for g in gates)
        parts.append(f"gates {'FAILED ' + str(failed) if failed else 'ok'}")
    width = len(str(total))
    return f"[{number:>{width}}/{total}] {scenario.name}: " + ", ".join(parts)


# --------------------------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------------------------
def add_common_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``run`` and ``suite``."""
    from harness.store.cache import default_cache_dir

    parser.add_argument("--tags", default=None,
                        help="comma-separated tags (e.g. quick); scenarios with any of them")
    parser.add_argument("--engines", default=None,
                        help=f"comma-separated engines (default: all of {', '.join(ENGINES)})")
    parser.add_argument("--preset", default="all", choices=(*preset_choices(), "all"),
                        help="engine preset(s) to run (default: all); matched-bounce is "
                        "MuJoCo's name for its accurate role and selects that role")
    parser.add_argument("--no-cache", action="store_true",
                        help="simulate every engine run, ignoring and not filling the cache")
    parser.add_argument("--cache-dir", type=Path, default=None,
                        help=f"result cache directory (default: {default_cache_dir()}; "
                        "see `impact-harness cache info`)")
    parser.add_argument("--executor", default="local", choices=("local", "dask"),
                        help="local process pool (default) or a Dask cluster")
    parser.add_argument("--scheduler", default=None,
                        help="Dask scheduler address (with --executor dask; default: a local "
                        "cluster)")
    parser.add_argument("--workers", type=int, default=None,
                        help="local worker processes (default: all cores; small runs run inline)")
    parser.add_argument("--set", dest="settings_overrides", action="append", default=[],
                        metavar="ENGINE.KEY=VALUE",
                        help="override one engine setting in every run of that engine, on top "
                        "of the preset and the scenario's [engine_settings] (repeatable; VALUE "
                        "is JSON, else a string: --set pymunk.iterations=50 --set "
                        "mujoco.integrator=Euler)")
    parser.add_argument("--history", action=argparse.BooleanOptionalAction, default=None,
                        help="record each engine run's per-step contact history (v_n, v_t, "
                        "impulses, penetration, energy) in its record (default: only for "
                        "scenarios without a sweep, the ones the report draws step by step)")
    parser.add_argument("--chunk-size", type=int, default=None, metavar="N",
                        help="engine runs per Engine.run_many call and per task sent to a "
                        "worker (default: chosen from the run's size, at most "
                        "64; 1: one Engine.run per task)")
    parser.add_argument("--task-time-limit", type=float, default=TASK_TIME_LIMIT_S,
                        metavar="SECONDS",
                        help=f"wall-clock limit of one engine run (default: {TASK_TIME_LIMIT_S:g})")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("files", nargs="*", metavar="FILE",
                        help="scenario files or directories (default: the library in scenarios/)")
    add_common_arguments(parser)
    parser.add_argument("--json", type=Path, default=None,
                        help=f"results file to write (default: {DEFAULT_RESULTS}, unless it "
                        "holds another selection's results: see --force)")
    parser.add_argument("--force", action="store_true",
                        help=f"replace {DEFAULT_RESULTS} even when it holds the results of "
                        "another selection of scenarios, engines or presets")


def _fail(message: str) -> int:
    print(f"impact-harness run: {message}", file=sys.stderr)
    return EXIT_BAD_INPUT


def check_arguments(args, json_path: Path | None) -> str | None:
    """The first problem with the options, checked before any work; ``None`` when fine."""
    from harness.run.executor import DaskNotInstalled
    from harness.run.executor import check_arguments as check_executor

    try:
        parse_engines(args.engines)
        parse_presets(args.preset)
        check_executor(args.executor, args.workers, args.scheduler)
        parse_overrides(getattr(args, "settings_overrides", None) or (),
                        parse_engines(args.engines))
    except (ValueError, DaskNotInstalled) as error:
        return str(error)
    try:
        for option, value in (("workers", args.workers),
                              ("chunk-size", getattr(args, "chunk_size", None)),
                              ("task-time-limit", args.task_time_limit)):
            if value is not None:
                bounds.check(f"--{option} {value}", option, value)
    except bounds.OutOfBounds as error:
        return str(error)
    if json_path is not None:
        reason = check_writable(json_path, make_parent=json_path == DEFAULT_RESULTS)
        if reason:
            return f"--json {json_path}: {reason}"
    if not args.no_cache:  # made and marked as the harness's, or refused when not its own
        from harness.store.cache import ResultCache

        reason = ResultCache(args.cache_dir, version="").prepare()
        if reason:
            return f"--cache-dir {ResultCache(args.cache_dir, version='').root}: {reason}"
    return None


def selection_of(args) -> dict:
    """What a run was asked for: files (resolved; None for the library), tags, engines, presets
    and, when any, the ``--set`` overrides."""
    files = getattr(args, "files", None) or None
    tags = parse_tags_text(args.tags)
    selection = {"files": None if files is None else sorted(str(Path(f).resolve()) for f in files),
                 "tags": tags,
                 "engines": [name for name in ENGINES if name in parse_engines(args.engines)],
                 "presets": list(parse_presets(args.preset))}
    overrides = getattr(args, "settings_overrides", None)
    if overrides:  # only then: a --set experiment never silently replaces the suite's results
        selection["settings_overrides"] = sorted(overrides)
    return selection


def parse_tags_text(text) -> list[str] | None:
    from harness.scenarios import parse_tags

    tags = parse_tags(text)
    return None if tags is None else sorted(tags)


def _describe_selection(selection: dict) -> str:
    files = selection.get("files")
    what = "the whole library" if not files else ", ".join(Path(f).name for f in files[:3]) + (
        f" and {len(files) - 3} more" if len(files) > 3 else "")
    if selection.get("tags"):
        what += f" tagged {','.join(selection['tags'])}"
    described = (f"{what}; engines {','.join(selection.get('engines') or ENGINES)}; presets "
                 f"{','.join(selection.get('presets') or PRESETS)}")
    if selection.get("settings_overrides"):
        described += f"; --set {' '.join(selection['settings_overrides'])}"
    return described


def _existing_selection(path: Path) -> dict | None:
    """The selection recorded in an existing results file (files before it: the default)."""
    import json

    try:
        document = json.loads(path.read_text(encoding="utf-8"))
        recorded = document["provenance"].get("selection")
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None  # unreadable: nothing worth keeping is lost by replacing it
    if recorded is None:  # written before selections were recorded: by the suite
        recorded = {"files": None, "tags": None, "engines": list(ENGINES),
                    "presets": list(PRESETS)}
    return recorded


def execute(args, *, json_path: Path, command: Sequence[str] | None = None,
            log: TextIO | None | str = "stderr",
            guard: bool = False) -> tuple[int, RunOutcome | None]:
    """Run with parsed options; write the results file. Returns (exit status, outcome).

    Options are checked before any scenario is read. ``guard``: refuse to replace
    ``json_path`` when it holds the results of another selection (``run`` without ``--json``).
    Bad scenario files are reported one line each; the others still run (exit status 2).
    """
    from harness.engines.facts import fingerprints_remembered

    with fingerprints_remembered():
        return _execute(args, json_path=json_path, command=command, log=log, guard=guard)


def _execute(args, *, json_path: Path, command: Sequence[str] | None,
             log: TextIO | None | str, guard: bool) -> tuple[int, RunOutcome | None]:
    from harness.scenarios.library import load_scenarios_reporting

    log = sys.stderr if log == "stderr" else log
    problem = check_arguments(args, json_path)
    if problem:
        return _fail(problem), None
    selection = selection_of(args)
    if guard and json_path.exists() and not getattr(args, "force", False):
        existing = _existing_selection(json_path)
        if existing is not None and existing != selection:
            return _fail(f"{json_path} holds the results of another selection "
                         f"({_describe_selection(existing)}); write this run elsewhere with "
                         f"--json PATH, or replace them with --force"), None
    from harness.scenarios.checks import use_passed_checks
    from harness.store.cache import default_cache_dir

    # The cache also remembers which scenario texts passed the point checks (--no-cache:
    # every file is checked again).
    passed = use_passed_checks(None if args.no_cache else (args.cache_dir or default_cache_dir()))
    try:  # the files to check on the local cores (as many as the run's workers)
        scenarios, errors = load_scenarios_reporting(getattr(args, "files", None) or None,
                                                     tags=args.tags or None,
                                                     workers=args.workers)
    finally:
        use_passed_checks(None)
    if log is not None:
        for problem in passed.problems:
            print(f"warning: scenario checks store {problem} (the files were checked again)",
                  file=log, flush=True)
    for error in errors:
        print(f"impact-harness run: {error}", file=sys.stderr)
    if not scenarios:
        if not errors:
            print("impact-harness run: no scenario selected", file=sys.stderr)
        return EXIT_BAD_INPUT, None
    cache = None
    if not args.no_cache:
        from harness.store.cache import ResultCache

        cache = ResultCache(root=args.cache_dir)
    try:
        engines = parse_engines(args.engines)
        outcome = run(scenarios, engines=engines,
                      presets=parse_presets(args.preset), cache=cache, executor=args.executor,
                      workers=args.workers, scheduler=args.scheduler, log=log, command=command,
                      time_limit_s=args.task_time_limit, selection=selection,
                      overrides=parse_overrides(getattr(args, "settings_overrides", None) or (),
                                                engines),
                      history=getattr(args, "history", None),
                      chunk_size=getattr(args, "chunk_size", None))
    except ConnectionError as error:  # an unreachable Dask scheduler
        return _fail(str(error)), None
    try:
        write_result_blocks(json_path, outcome.blocks, outcome.provenance, outcome.scenarios)
    except OSError as error:
        print(f"impact-harness run: cannot write {json_path}: {error.strerror or error}; the "
              "engine results are in the cache, a rerun simulates nothing again",
              file=sys.stderr)
        return EXIT_INTERNAL, outcome
    stats = outcome.provenance["cache"]
    if log is not None:
        print(f"wrote {json_path}: {outcome.record_count} records from {len(scenarios)} "
              f"scenarios; {stats['simulated']} engine runs simulated, {stats['hits']} from the "
              f"cache; {outcome.provenance['wall_time_s']:.2f} s", file=log)
        for name, reason in outcome.provenance["engines_missing"].items():
            print(f"skipped engine {name}: {reason}", file=log)
    for gate in outcome.failed_gates:
        print(f"GATE FAILED: {gate.describe()}", file=sys.stderr)
    for record in outcome.internal_errors:
        print(f"INTERNAL ERROR: {record.scenario} {record.point['label']} {record.label}: "
              f"{record.status}", file=sys.stderr)
    engine_errors = outcome.engine_errors
    for record in engine_errors[:SHOWN_ENGINE_ERRORS]:
        print(f"ENGINE ERROR: {record.scenario} {record.point['label']} {record.label}: "
              f"{record.status}", file=sys.stderr)
    if len(engine_errors) > SHOWN_ENGINE_ERRORS:
        print(f"ENGINE ERROR: {len(engine_errors) - SHOWN_ENGINE_ERRORS} more (their records "
              f"in {json_path})", file=sys.stderr)
    if outcome.internal_errors:
        return EXIT_INTERNAL, outcome
    if errors:
        return EXIT_BAD_INPUT, outcome
    if engine_errors:
        return EXIT_ENGINE_ERROR, outcome
    return (EXIT_GATE_FAILED if outcome.failed_gates else EXIT_OK), outcome


def main(args) -> int:
    guard = args.json is None
    json_path = DEFAULT_RESULTS if guard else args.json
    status, _ = execute(args, json_path=json_path, guard=guard,
                        command=["impact-harness", "run", *sys.argv[2:]])
    return status


__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_ENGINE_ERROR",
    "EXIT_GATE_FAILED",
    "EXIT_INTERNAL",
    "EXIT_OK",
    "TASK_TIME_LIMIT_S",
    "GateResult",
    "RunOutcome",
    "add_arguments",
    "add_common_arguments",
    "check_arguments",
    "check_engine_output",
    "check_gates",
    "engine_record",
    "engine_chunk",
    "engine_task",
    "execute",
    "main",
    "parse_engines",
    "parse_presets",
    "point_records",
    "run",
    "scenario_info",
    "select_scenarios",
    "selection_of",
    "task_group",
]
