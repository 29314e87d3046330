"""``run``: every scenario through every law and every engine that applies, in four steps.

0. Whole scenarios whose finished records the result cache holds are read as they are
   (:mod:`harness.run.scenario_records`: one entry per scenario, the records' lines of the
   results file with the summary a run needs of them, so a warm run reads, parses and checks
   no record).
1. The others' engine runs are planned (:mod:`harness.run.plan`): one per (scenario, point,
   engine, preset), looked up in the cache (key: the scene at the point, the engine and its
   version, the complete settings and the code version); each several-contact point's
   reference is read from the cache or becomes a task.
2. The misses run through the executor (:mod:`harness.run.tasks`, local process pool or
   Dask), in chunks of one engine and settings, each stored the moment it finishes, so a run
   killed half-way keeps its finished chunks. A cache that cannot be written (removed,
   read-only) costs the cache, not the run: a warning says so.
3. Each scenario's records are built (:mod:`harness.run.point_records`: departures,
   verdicts, contact histories; on forked workers for a large run), its gates checked
   (:mod:`harness.run.gates`) and its entry stored; then the provenance.

For each scenario and sweep point, every law of the scenario (``planar_impact``, cheap, in
this process) and, for ``bodies`` systems, every selected engine × preset. Analytic-only
systems (``two-sled``, ``matrix``) never start an engine. An engine that is not installed or
cannot build the scene gives a record with status ``"skipped: <reason>"``; an engine that
blows up or never separates keeps the engine's status (``"blow-up"``, ``"no-separation"``
…). Nothing is dropped silently. The command line is :mod:`harness.run.command`.
"""

from __future__ import annotations

import json
import sys
import time
from contextlib import nullcontext
from dataclasses import asdict, dataclass, field
from typing import Mapping, Sequence, TextIO

from harness import engines as registry
from harness.collector import collector_paused
from harness.engines import engine_names
from harness.run import plan, scenario_records
from harness.run.gates import GateResult
from harness.run.provenance import provenance
from harness.run.records import FORMAT, FORMAT_VERSION, Record, RecordBlock
from harness.run.scenario_records import BuiltScenario
from harness.run.tasks import (
    REFERENCE_TASK_WEIGHT,
    STORE_FAILED_IN_WORKER,
    STORED_BY_WORKER,
    TASK_TIME_LIMIT_S,
    run_engine_tasks,
)
from harness.scenarios import PRESETS, Scenario
from harness.scenarios.schema import recorded_path
from harness.store.packs import PendingPuts


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
        "path": None if scenario.path is None else recorded_path(scenario.path),
        "analytic_only": scenario.analytic_only,
        "laws": list(scenario.laws),
        "sweep": None if scenario.sweep is None else {
            "parameter": scenario.sweep.parameter, "values": list(scenario.sweep.values)},
        "speed_labels": speed_labels(scenario),
        "gates": [{"gate": g.source, "law": g.law, "max_departure": g.max_departure}
                  for g in scenario.expect.gates],
    }


def run(
    scenarios: Sequence[Scenario],
    *,
    engines: Sequence[str] | None = None,
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

    ``engines``: the engines run (None: every engine registered now,
    :func:`harness.engines.engine_names`). ``cache`` is a
    :class:`harness.store.cache.ResultCache` (None: no cache). ``log`` gets the
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
    warnings = _clean_temporaries(cache)
    wanted_engines = [name for name in engine_names() if engines is None or name in engines]
    needs_engines = any(s.engines_among(wanted_engines) for s in scenarios)
    versions, missing, preset_settings = (plan.engine_status(wanted_engines, cache)
                                          if needs_engines else ({}, {}, {}))

    # The lookups below find most entries absent on a cold run: read from listings of the
    # cache's directories (ResultCache.listed), not by opening each file.
    with cache.listed() if cache is not None else nullcontext():
        # 0. Whole scenarios whose finished records the cache holds.
        stored = _stored_scenarios(scenarios, cache, versions, missing, wanted_engines,
                                   presets, command_overrides, history)
        to_build = [s for s in scenarios if s.name not in stored.built]
        # 1. Engine runs: planned, looked up in the cache. On the local pool each worker
        # stores the results it simulates (as each chunk finishes); Dask's may lie elsewhere.
        store_in_worker = (None if cache is None or not cache.enabled or executor != "local"
                           else (str(cache.root), cache.version))
        work = plan.plan_engine_runs(
            to_build, wanted_engines=wanted_engines, presets=presets, missing=missing,
            command_overrides=command_overrides, history=history, cache=cache,
            time_limit_s=time_limit_s, store_in_worker=store_in_worker)
        # Several-contact references the records will need and the cache lacks: tasks of the
        # same executor, ahead of the engine runs (each takes up to a second).
        # Stored by this process, a pack at a time (a worker computes one in a chunk).
        reference_work = _ReferenceWork(*plan.reference_tasks(to_build, cache))
        if cache is not None:
            warnings += [f"cache entry rejected (simulated again): {entry}"
                         for entry in cache.rejected]

    # 2. Run the misses; store each in the cache as it finishes (those the workers did not
    # store a pack at a time, the last when the work ends, however it ends).
    warnings += _simulate(work, reference_work, cache, stored_runs=stored.engine_runs,
                          executor=executor, workers=workers, scheduler=scheduler, log=log,
                          chunk_size=chunk_size)
    if log is not None:
        for warning in warnings:
            print(f"warning: {warning}", file=log, flush=True)

    # 3. Records, scenario by scenario: those not read whole from the cache built (on forked
    # workers for a large run), each scenario's entry stored as it is built.
    by_scenario: dict[str, list] = {}
    for entry in work.entries:
        by_scenario.setdefault(entry[0].name, []).append(entry)
    built = scenario_records.build_scenarios(
        to_build, by_scenario, cache, reference_work.found, stored.keys,
        workers=1 if executor == "local" and workers == 1 else workers)
    gathered = _gather(scenarios, {**built, **stored.built}, log)

    # 4. The provenance: what ran, how, with what.
    settings_table = {  # the presets as run: with the command line's --set overrides
        name: (preset_settings[name] if name not in command_overrides else
               {preset: registry.load_engine(name).settings(preset, command_overrides[name])
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
        cache={**stats, "root": None if cache is None else recorded_path(cache.root),
               "engine_runs": len(work.entries) + stored.engine_runs,
               "simulated": len(work.tasks)},
        selection=selection,
        settings_overrides=command_overrides,
        history="scenarios without a sweep" if history is None else history,
        task_time_limit_s=time_limit_s,
        gates=[asdict(g) for g in gathered.gates],
        wall_time_s=time.perf_counter() - started,
    )
    return RunOutcome(records=gathered.records, gates=gathered.gates, provenance=info,
                      scenarios=gathered.infos, cache_stats=stats, warnings=warnings,
                      blocks=gathered.blocks, internal=gathered.internal,
                      engine_errors=gathered.engine_errors)


def _clean_temporaries(cache) -> list[str]:
    """Remove the temporaries killed writers left in ``cache``; the warning when it cannot."""
    if cache is None:
        return []
    try:
        cache.clean_temporaries()
    except OSError as error:
        return [f"cache {cache.root}: cannot clean temporaries: {error}"]
    return []


@dataclass
class _StoredScenarios:
    """The scenarios whose finished records the cache holds whole (``built``, by name), every
    scenario's key of them (``keys``; None: not kept) and how many engine runs they hold."""

    keys: dict[str, str | None]
    built: dict[str, BuiltScenario]
    engine_runs: int


def _stored_scenarios(scenarios: Sequence[Scenario], cache, versions: dict, missing: dict,
                      wanted_engines: Sequence[str], presets: Sequence[str],
                      command_overrides: dict, history: bool | None) -> _StoredScenarios:
    """Step 0 of :func:`run`: each scenario's records read whole from the cache where it
    holds them (one entry each, its lines kept as text, the results file's lines, beside the
    summary the run needs of them); each counted as the engine runs it spared."""
    stored = _StoredScenarios(keys={}, built={}, engine_runs=0)
    for scenario in scenarios:
        key = stored.keys[scenario.name] = scenario_records.scenario_key(
            scenario, cache, versions, missing, wanted_engines, presets, command_overrides,
            history)
        found = scenario_records.stored_scenario(scenario, cache, key, presets,
                                                 len(scenario.engines_among(wanted_engines)))
        if found is not None:
            stored.built[scenario.name] = found
            runs = found.summary["counts"]["engine_runs"]
            cache.hits += runs  # each an engine run the cache spared, as read one by one
            stored.engine_runs += runs
    return stored


@dataclass
class _ReferenceWork:
    """The reference tasks of a run, their cache keys, and the references ``found`` (read
    from the cache, then computed by the tasks), by ``(scenario name, point index)``."""

    tasks: list[dict]
    keys: list
    found: dict


class _Collector:
    """Takes each finished task's output from the executor (``on_result``): an engine run's
    into its slot of the plan, a reference into the references found; each stored in the
    cache unless its worker did, a pack at a time (:class:`PendingPuts`; :meth:`flush` when
    the work ends). A cache that cannot be written costs the cache, not the run:
    :attr:`failed` says so once."""

    def __init__(self, cache, work: plan.EnginePlan, reference_work: _ReferenceWork) -> None:
        self.cache, self.work, self.reference_work = cache, work, reference_work
        self.failed: list[str] = []
        self.pending = PendingPuts(cache)

    def __call__(self, index: int, output: dict) -> None:
        references_count = len(self.reference_work.tasks)
        if index < references_count:
            self._reference(index, output)
            return
        self._engine_run(index - references_count, output)

    def _reference(self, index: int, output: dict) -> None:
        task = self.reference_work.tasks[index]
        if "reference" not in output:  # built inline, where its error is reported
            return
        self.reference_work.found[task["scenario"], task["point"]] = output["reference"]
        stored = output.pop(STORED_BY_WORKER, False)
        self._note_failure(output.pop(STORE_FAILED_IN_WORKER, None))
        key = self.reference_work.keys[index]
        if not (stored or self.failed or key is None):
            try:
                self.pending.put(key, output["reference"])
            except OSError as error:  # the run goes on without the cache
                self._note_failure(error)

    def _engine_run(self, index: int, output: dict) -> None:
        stored = output.pop(STORED_BY_WORKER, False)
        problem = output.pop(STORE_FAILED_IN_WORKER, None)
        self.work.slots[index]["output"], self.work.slots[index]["cached"] = output, False
        self._note_failure(problem)
        if (stored or self.cache is None or self.failed
                or output["status"].startswith(("skipped", "error"))):
            return
        try:
            self.pending.put(self.work.keys[index], output)
        except OSError as error:  # the run goes on without the cache
            self._note_failure(error)

    def flush(self) -> None:
        """Store what still waits (called when the work ends, however it ends)."""
        try:
            self.pending.flush()
        except OSError as error:
            self._note_failure(error)

    def _note_failure(self, problem) -> None:
        if problem is not None and not self.failed:
            self.failed.append(f"cache {self.cache.root}: cannot store results ({problem}); "
                               "the run goes on without the cache")


def _simulate(work: plan.EnginePlan, reference_work: _ReferenceWork, cache, *,
              stored_runs: int, executor: str, workers: int | None, scheduler: str | None,
              log: TextIO | None, chunk_size: int | None) -> list[str]:
    """Step 2 of :func:`run`: the engine runs and references to compute, through the
    executor, each kept as it finishes (:class:`_Collector`); the cache's warnings."""
    collect = _Collector(cache, work, reference_work)
    if not (work.tasks or reference_work.tasks):
        return collect.failed
    if log is not None:
        print(f"engine runs: {len(work.tasks)} to simulate, "
              f"{len(work.entries) + stored_runs - len(work.tasks)} cached or "
              f"skipped; {len(reference_work.tasks)} several-contact references to compute",
              file=log, flush=True)
    simulating = time.perf_counter()
    try:
        run_engine_tasks(reference_work.tasks + work.tasks, executor=executor,
                         workers=workers, scheduler=scheduler, log=log, on_result=collect,
                         chunk_size=chunk_size,
                         weight=len(work.tasks) + REFERENCE_TASK_WEIGHT * len(reference_work.tasks))
    finally:
        collect.flush()
    if log is not None:
        print(f"engine runs: {len(work.tasks)} simulated, {len(reference_work.tasks)} "
              f"references computed in {time.perf_counter() - simulating:.2f} s", file=log,
              flush=True)
    return collect.failed


@dataclass
class _Gathered:
    """Every scenario's records in run order (None: held as a line), their blocks, the
    positions of internal and engine errors, the gates and each scenario's info."""

    records: list[Record | None] = field(default_factory=list)
    blocks: list[RecordBlock] = field(default_factory=list)
    internal: list[int] = field(default_factory=list)
    engine_errors: list[int] = field(default_factory=list)
    gates: list[GateResult] = field(default_factory=list)
    infos: dict[str, dict] = field(default_factory=dict)


def _gather(scenarios: Sequence[Scenario], results: dict[str, BuiltScenario],
            log: TextIO | None) -> _Gathered:
    """Step 3 of :func:`run`: the scenarios' records (``results``: built, or read whole) in
    run order, with their gates and info; one progress line per scenario."""
    gathered = _Gathered()
    for number, scenario in enumerate(scenarios, 1):
        info = gathered.infos[scenario.name] = scenario_info(scenario)
        result = results[scenario.name]
        offset = len(gathered.records)
        gathered.internal += [offset + position for position in result.internal]
        gathered.engine_errors += [offset + position for position in result.engine_errors]
        gathered.records += (result.records if result.records is not None
                             else [None] * result.block.count)
        gathered.blocks.append(result.block)
        info["references"] = result.summary["references"]
        scenario_gates = [GateResult(**gate) for gate in result.summary["gates"]]
        gathered.gates += scenario_gates
        if log is not None:
            print(_progress_line(number, len(scenarios), scenario, result.summary["counts"],
                                 scenario_gates), file=log, flush=True)
    return gathered


def _progress_line(number, total, scenario, counts: Mapping, gates) -> str:
    """One scenario's line of the log from its records' counts (its summary's,
    :mod:`harness.run.scenario_records`)."""
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


__all__ = ["RunOutcome", "run", "scenario_info", "speed_labels"]
