"""The survey in parts: each part sampled, solved, run through every engine and preset and
judged by one process (harness/survey/cli.py ``run_survey``).

A part is a range of sample indices, the same range of every population. Sample ``i`` of a
population does not depend on the other samples (harness/survey/sampling.py), nor does a
row of the contact terms, of newton-lcp's ``solve_batch`` or an engine run depend on the
other rows (``run_many`` equals ``run`` scene by scene), so the parts joined in (population,
index) order are the survey of one process, for any number of parts
(tests/survey/test_parts.py).

With several workers the parts run in a pool of forked processes, each part sampled where it
runs: a worker is sent a range and sends back arrays (the contact terms' columns and the
runs' speeds, statuses and reasons), never scenes or impact problems, which cost more to
pickle than to sample. Every part runs every engine and preset, so the parts cost alike and
each worker's engine caches (worlds, compiled models) stay warm from one part to the next;
the first parts are the largest and the last the smallest (each a ``1/(2·workers)`` share of
the samples still to go), so the workers finish together.
"""

from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from harness.processes import map_forked
from harness.run import verdicts
from harness.scenarios.errors import ScenarioError
from harness.survey import laws as survey_laws
from harness.survey.engines import EngineResults, bare_stepping, run_engine
from harness.survey.laws import ContactTerms
from harness.survey.sampling import REJECTIONS, sample_range

#: The fewest samples per population of a part (but the last). The engines' start-up per
#: ``run_many`` call does not show at this size (eight calls of 56 scenes took no more CPU
#: time than one of 448, for every pair), and the last parts, which decide when the workers
#: finish, stay short.
MIN_PART = 8
#: What the forked workers read: ``(populations, seed, pairs, overrides)``.
_SHARED: tuple = ()


class SampleRow(NamedTuple):
    """What the samples table needs of one sample (harness/survey/cli.py ``sample_columns``)."""

    population: str
    index: int
    attempts: int
    parameters: dict


@dataclass(frozen=True)
class PartResult:
    """One part: its samples population by population, then index by index."""

    rows: list[SampleRow]
    rejections: list[dict]  # per population, {reason: draws}
    terms: ContactTerms  # without ``problems``
    results: list[EngineResults]  # per pair
    timings: dict  # stage -> seconds on one core
    refused: tuple | None = None  # (population, sample, ScenarioError fields) when refused
    worker: tuple[int, float] = (0, 0.0)  # (process id, CPU seconds of this part)


@dataclass(frozen=True)
class Survey:
    """Every part joined, in (population, index) order."""

    rows: list[SampleRow]
    rejections: list[dict]
    terms: ContactTerms
    results: list[EngineResults]
    timings: dict  # stage -> seconds on one core, summed over the parts
    parts: int
    worker_cpu: dict = dataclasses.field(default_factory=dict)  # process id -> CPU seconds


def part_bounds(samples: int, workers: int) -> list[tuple[int, int]]:
    """``[(begin, end), …]``: the sample ranges of the parts, largest first (one part for one
    worker)."""
    if workers <= 1:
        return [(0, samples)]
    bounds, begin = [], 0
    while begin < samples:
        size = max(MIN_PART, -(-(samples - begin) // (2 * workers)))
        bounds.append((begin, min(samples, begin + size)))
        begin = bounds[-1][1]
    return bounds


def run_parts(populations, samples: int, seed: int, pairs, workers: int = 1,
              overrides: dict | None = None) -> Survey:
    """Every part of ``samples`` per population through every ``(engine, preset)`` pair, on
    ``workers`` processes, joined; ``overrides``: ``engine -> {setting: value}`` (``--set``)
    applied over every preset of that engine. Raises the :class:`ScenarioError` of the first
    sample (in population, then index order) that needs too many draws."""
    global _SHARED
    bounds = part_bounds(samples, workers)
    _SHARED = (tuple(populations), seed, tuple(pairs), dict(overrides or {}))
    try:
        parts = map_forked(run_part, bounds, min(workers, len(bounds)))
    finally:
        _SHARED = ()
    refused = [part.refused for part in parts if part.refused is not None]
    if refused:
        _, sample, fields = min(refused, key=lambda found: found[:2])
        error = ScenarioError(**fields)
        error.sample = sample
        raise error
    return _join(parts, [end - begin for begin, end in bounds], len(populations), len(pairs))


def run_part(bounds: tuple[int, int]) -> PartResult:
    """:func:`compute_part` of ``bounds`` with the survey's shared settings (forked workers)."""
    populations, seed, pairs, overrides = _SHARED
    return compute_part(populations, seed, pairs, overrides, bounds)


def compute_part(populations, seed: int, pairs, overrides: dict, bounds: tuple[int, int],
                 bare: bool = False) -> PartResult:
    """Samples ``bounds`` of every population, their contact terms, newton-lcp's energy
    change (the verdicts' attribution of a gain), every pair's runs and verdicts; with
    ``bare``, also each pair's bare stepping of the same scenes (timings ``bare …``)."""
    begin, end = bounds
    clock = time.perf_counter
    cpu = time.process_time()
    tick = clock()
    sets = []
    for position, population in enumerate(populations):
        try:
            sets.append(sample_range(population, begin, end, seed))
        except ScenarioError as error:
            fields = {"message": error.problem, "path": error.path, "key": error.key,
                      "value": error.value, "allowed": error.allowed}
            return PartResult([], [], None, [], {}, (position, error.sample, fields))
    every = [sample for sample_set in sets for sample in sample_set.samples]
    timings = {"sampling": clock() - tick}
    tick = clock()
    terms = survey_laws.contact_terms(every)
    energy = survey_laws.solve_laws(terms, ("newton-lcp",))["newton-lcp"].batch.energy_change
    timings["laws"] = clock() - tick
    tick = clock()
    scenes = [sample.scene for sample in every]
    prepared = verdicts.prepare_many(scenes, terms.problems)
    arrays = verdicts.term_arrays(terms.problems, prepared)
    timings["verdict terms"] = clock() - tick
    results = [run_engine(engine, preset, scenes, terms.problems, energy, prepared, arrays,
                          overrides.get(engine))
               for engine, preset in pairs]
    if bare:
        for result in results:
            times = bare_stepping(result.engine, result.preset, scenes, result.steps,
                                  overrides.get(result.engine))
            timings[f"bare {result.engine} {result.preset} (steps only)"] = times["bare_s"]
            timings[f"bare {result.engine} {result.preset} (reset + steps)"] = \
                times["bare_reset_s"]
    return PartResult([SampleRow(s.population, s.index, s.attempts, s.parameters)
                       for s in every],
                      [sample_set.rejections for sample_set in sets],
                      dataclasses.replace(terms, problems=()), results, timings,
                      worker=(os.getpid(), time.process_time() - cpu))


def _join(parts: list[PartResult], sizes: list[int], populations: int, pairs: int) -> Survey:
    """The parts' rows in (population, index) order: part ``k`` holds, population after
    population, ``sizes[k]`` rows of each."""
    starts = np.cumsum([0] + [size * populations for size in sizes])
    order = np.concatenate([np.arange(size) + start + position * size
                            for position in range(populations)
                            for start, size in zip(starts, sizes)]).astype(np.int64)
    rows = [row for part in parts for row in part.rows]
    terms = ContactTerms(**{
        field.name: (() if field.name == "problems" else
                     np.concatenate([getattr(part.terms, field.name) for part in parts])[order])
        for field in dataclasses.fields(ContactTerms)})
    results = []
    for pair in range(pairs):
        slices = [part.results[pair] for part in parts]
        first = slices[0]
        results.append(EngineResults(
            first.engine, first.engine_version, first.preset,
            *(np.concatenate([getattr(part, name) for part in slices])[order]
              for name in ("velocities", "engine_status", "status", "reasons", "steps")),
            sum(part.wall_s for part in slices), sum(part.judge_s for part in slices),
            next((part.skipped_why for part in slices if part.skipped_why), ""),
            np.concatenate([part.errors for part in slices])[order]))
    rejections = [{reason: sum(part.rejections[position][reason] for part in parts)
                   for reason in REJECTIONS} for position in range(populations)]
    timings = {stage: sum(part.timings[stage] for part in parts) for stage in parts[0].timings}
    worker_cpu: dict[int, float] = {}
    for part in parts:
        worker_cpu[part.worker[0]] = worker_cpu.get(part.worker[0], 0.0) + part.worker[1]
    return Survey([rows[i] for i in order.tolist()], rejections, terms, results, timings,
                  len(parts), worker_cpu)
