"""A scenario's finished records, whole: built from its engine outputs and references (on
forked workers for a large run), kept in the result cache as the results file holds them, and
read back whole by a warm run, which then reads, parses and checks no record.

The entry's key (:func:`scenario_key`) is what the records depend on: the scenario's
definition, the engines that apply with their versions, the presets, the ``--set`` overrides
and the history flag; its summary (:func:`_summary`) is what the run needs of them without
reading them (each point's reference, the gates, the counts of the progress line).
"""

from __future__ import annotations

import gc
import math
from dataclasses import asdict, dataclass, field, fields
from typing import Mapping, Sequence

from harness.collector import collector_paused
from harness.processes import default_workers, map_forked
from harness.run import references
from harness.run.gates import GateResult, check_gates
from harness.run.point_records import point_records_or_errors
from harness.run.records import ANALYTIC, Record, RecordBlock, plain_value, record_line
from harness.scenarios import Scenario

#: The ``kind`` of a cache entry holding a whole scenario's records (:func:`scenario_key`).
SCENARIO_RECORDS = "scenario-records"


def scenario_key(scenario: Scenario, cache, versions: Mapping, missing: Mapping,
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
class BuiltScenario:
    """A scenario's finished records: as the results file holds them (``block``), the
    records themselves when built in this process (None: read from the
    cache or built on a worker, parsed from the block when asked for), the ``summary`` the
    run needs of them (:func:`_summary`) and the positions of internal-error records."""

    block: RecordBlock
    summary: dict
    records: list[Record] | None = None
    internal: list[int] = field(default_factory=list)
    engine_errors: list[int] = field(default_factory=list)  # positions, internal ones apart


def stored_scenario(scenario: Scenario, cache, key: str | None, presets: Sequence[str],
                     engine_count: int) -> BuiltScenario | None:
    """The scenario's finished records from its cache entry (:func:`scenario_key`), as the
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
    return BuiltScenario(block=RecordBlock(text, count), summary=summary)


#: The counts of a scenario's records its summary keeps (for the progress line, the hits).
_COUNTS = ("records", "points", "laws", "laws_ok", "engine_runs", "cached", "skipped",
           "flagged")


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


def build_scenarios(scenarios: Sequence[Scenario], by_scenario: Mapping[str, list], cache,
                     computed_references: Mapping, scenario_keys: Mapping, *,
                     workers: int | None = None) -> dict[str, BuiltScenario]:
    """:func:`_build_scenario` of each scenario, by name.

    A large run (:data:`MIN_PARALLEL_RECORDS`) builds them on ``workers`` forked processes
    (None: every core), which read the engine outputs and references from this process's
    memory and send back the records' lines and summaries only (the records are parsed from
    the lines when asked for: :attr:`harness.run.runner.RunOutcome.records`); each stores
    its scenarios' cache entries. Records are the same either way (built by the same code
    from the same values).
    """
    global _BUILD_STATE
    if not scenarios:  # a warm run's: every scenario's records read whole from the cache
        return {}
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


def _build_job(indices: list[int]) -> list[BuiltScenario]:
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
                    key: str | None) -> BuiltScenario:
    """A scenario's records from its engine entries (``(scenario, point, engine, preset,
    item)`` of the run's plan) and its points' references, with their lines and summary;
    its cache entry stored when ``key`` (:func:`_store_scenario`)."""
    by_point: dict[int, list] = {}
    for entry in entries:
        by_point.setdefault(entry[1].index, []).append(entry)
    records: list[Record] = []
    for point in scenario.point_list():
        records += point_records_or_errors(
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
    return BuiltScenario(block=block, summary=summary, records=records, internal=internal,
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


__all__ = ["MIN_PARALLEL_RECORDS", "SCENARIO_RECORDS", "BuiltScenario", "build_scenarios",
           "scenario_key", "stored_scenario"]
