"""``impact-harness bench --survey``: the survey and the engines' bare stepping of the same
impacts, on the same number of processes, in CPU time.

The machine is shared, so every figure is CPU time (``time.process_time``, plus the CPU time
of the worker processes a side forked and waited for), never wall time, and the two sides of
every comparison run in turn, round after round (``rounds``): a drift of the machine's speed
then hits both alike. The median of the rounds is reported.

* End to end -- ``survey_cpu_s``: :func:`harness.survey.cli.run_survey` in memory on
  ``workers`` processes (sampling, the laws, every engine and preset through
  ``Engine.run_many``, the verdicts, the departures and statistics; no files), against
  ``bare_cpu_s``: the bare stepping (below) of every pair, its scenes split over the same
  ``workers`` processes. ``ratio = survey_cpu_s / bare_cpu_s``.
* Per engine and preset, on this one process -- ``contract_s``: ``Engine.run_many`` of every
  scene (the contract's run: set-up, stepping with the per-step contact records, read-out,
  status, the :class:`EngineRun`); ``judged_s``: the survey's whole per-pair work,
  :func:`harness.survey.engines.run_engine` (``run_many`` plus the verdict checks and the
  gathering of the columns); ``bare_s``: the engine's own per-impact reset and as many of its
  own step calls as the contract's run took, in a tight loop (``Engine.bare_stepper``, each
  scene's world built outside the timed region): the least any Python driver spends.
  ``contract_ratio = contract_s / bare_s`` and ``judged_ratio = judged_s / bare_s``.
  ``bare_world_s``: the same bare stepping with each scene's world built and freed, timed
  too (the survey's shapes are all different, so the contract's run builds a world, or
  the bodies of a batch world, for every impact); ``world_ratio = contract_s /
  bare_world_s``.

An untimed survey runs first, so that every round finds the engines' caches (MuJoCo's
compiled polygons, say) equally warm. Every ratio's target is :data:`RATIO_TARGET`.
"""

from __future__ import annotations

import resource
import statistics
import time

from harness.collector import collector_paused
from harness.engines import (
    PRESET_ROLES,
    EngineNotInstalled,
    engine_names,
    load_engine,
    source_label,
)
from harness.processes import map_forked
from harness.run import verdicts
from harness.survey import laws as survey_laws
from harness.survey.cli import run_survey
from harness.survey.engines import SLICE, run_engine
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

RATIO_TARGET = 1.5
SAMPLES = 500  # per population
QUICK_SAMPLES = 60
ROUNDS = 3
QUICK_ROUNDS = 1


def _cpu_with_children() -> float:
    """CPU seconds (user + system) of this process and of its waited-for children."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


def _contract_cpu(engine, settings, scenes) -> tuple[float, list[int]]:
    """CPU seconds of ``engine.run_many`` over ``scenes`` (in the survey's slices), and the
    steps each run took."""
    cpu = 0.0
    steps: list[int] = []
    for begin in range(0, len(scenes), SLICE):
        tick = time.process_time()
        runs = engine.run_many(scenes[begin:begin + SLICE], settings)
        cpu += time.process_time() - tick
        steps += [run.steps for run in runs]
        del runs
    return cpu, steps


def _bare_cpu(engine, settings, scenes, steps) -> tuple[float, float]:
    """``(stepping, with_world)``: CPU seconds of each scene's reset and ``steps[i]`` bare
    steps, and the same with the building and freeing of each scene's world (a world of its
    own per scene, :meth:`Engine.bare_stepper`): what any driver spends when every impact
    has a shape of its own, as the survey's have."""
    clock = time.process_time
    stepping = with_world = 0.0
    for scene, count in zip(scenes, steps):
        tick = clock()
        stepper = engine.bare_stepper(scene, settings)
        built = clock() - tick
        try:
            tick = clock()
            stepper.reset()
            stepper.step(count)
            stepping += clock() - tick
        finally:
            tick = clock()
            stepper.close()
            with_world += built + clock() - tick
    return stepping, stepping + with_world


# The bare stepping's work for the forked workers: read from module state, never pickled.
_BARE_WORK: dict = {}


def _bare_part(part: tuple[int, int, int]) -> float:
    """One worker's share of the end-to-end bare stepping: pair ``part[0]``, scenes
    ``part[1]:part[2]``; its CPU seconds in the timed regions."""
    pair, begin, end = part
    engine, settings, steps = _BARE_WORK["pairs"][pair]
    return _bare_cpu(engine, settings, _BARE_WORK["scenes"][begin:end], steps[begin:end])[0]


def _bare_all_cpu(pairs, scenes, workers: int) -> float:
    """CPU seconds of every pair's bare stepping of ``scenes``, split over ``workers``."""
    _BARE_WORK.update(pairs=pairs, scenes=scenes)
    share = -(-len(scenes) // max(workers, 1))
    parts = [(pair, begin, min(begin + share, len(scenes)))
             for pair in range(len(pairs)) for begin in range(0, len(scenes), share)]
    try:
        return sum(map_forked(_bare_part, parts, workers))
    finally:
        _BARE_WORK.clear()


def run(samples: int, engines=None, presets=PRESET_ROLES, seed: int = 0,
        rounds: int = ROUNDS, workers: int = 1) -> dict:
    """``{"samples", "impacts", "engines", "presets", "rounds", "workers", "survey_cpu_s",
    "bare_cpu_s", "ratio", "pairs": {label: {"contract_s", "judged_s", "bare_s",
    "contract_ratio", "judged_ratio", "steps"}}}`` (medians over ``rounds``); ``engines``
    None: every registered one."""
    installed = []
    for name in engine_names() if engines is None else engines:
        try:
            load_engine(name)
            installed.append(name)
        except EngineNotInstalled:
            continue
    populations = resolve_populations([])
    every = [sample for population in populations
             for sample in sample_population(population, samples, seed).samples]
    scenes = [sample.scene for sample in every]
    # What the survey works out once for every pair (outside the per-pair timings).
    terms = survey_laws.contact_terms(every)
    problems = terms.problems
    energy = survey_laws.solve_laws(terms, ("newton-lcp",))["newton-lcp"].batch.energy_change
    scene_terms = verdicts.prepare_many(scenes, problems)
    arrays = verdicts.term_arrays(problems, scene_terms)
    pair_names = [(name, preset) for name in installed for preset in presets]
    measured = {pair: {"contract_s": [], "judged_s": [], "bare_s": [], "bare_world_s": []}
                for pair in pair_names}
    survey_cpu, bare_cpu = [], []
    prepared: dict = {}
    # One untimed pass first: the engines' caches (MuJoCo's compiled polygons, extents) are
    # then as warm for the first round as for the others, whichever side it times first.
    run_survey(populations, samples, seed, installed, presets, workers=1, echo=lambda _: None)
    for _ in range(max(rounds, 1)):
        # Per pair, on this process: the contract's run, the survey's per-pair work, bare.
        for name, preset in pair_names:
            engine = load_engine(name)
            settings = engine.settings(preset)
            contract_s, steps = _contract_cpu(engine, settings, scenes)
            tick = time.process_time()
            with collector_paused():
                run_engine(name, preset, scenes, problems, energy, scene_terms, arrays)
            judged_s = time.process_time() - tick
            bare_s, bare_world_s = _bare_cpu(engine, settings, scenes, steps)
            entry = measured[(name, preset)]
            entry["contract_s"].append(contract_s)
            entry["judged_s"].append(judged_s)
            entry["bare_s"].append(bare_s)
            entry["bare_world_s"].append(bare_world_s)
            prepared[(name, preset)] = (engine, settings, steps)
        # End to end, both sides on `workers` processes.
        tick = _cpu_with_children()
        run_survey(populations, samples, seed, installed, presets, workers=workers,
                   echo=lambda _: None)
        survey_cpu.append(_cpu_with_children() - tick)
        bare_cpu.append(_bare_all_cpu([prepared[pair] for pair in pair_names], scenes,
                                      workers))
    pairs = {}
    for (name, preset), entry in measured.items():
        contract_s, judged_s, bare_s, bare_world_s = (
            statistics.median(entry[key])
            for key in ("contract_s", "judged_s", "bare_s", "bare_world_s"))
        pairs[source_label(name, preset)] = {
            "contract_s": contract_s, "judged_s": judged_s, "bare_s": bare_s,
            "bare_world_s": bare_world_s,
            "world_ratio": contract_s / bare_world_s if bare_world_s > 0 else float("nan"),
            "contract_ratio": contract_s / bare_s if bare_s > 0 else float("nan"),
            "judged_ratio": judged_s / bare_s if bare_s > 0 else float("nan"),
            "steps": int(sum(prepared[(name, preset)][2])),
        }
    survey_s, bare_s = statistics.median(survey_cpu), statistics.median(bare_cpu)
    return {"samples": samples, "impacts": len(scenes), "engines": installed,
            "presets": list(presets), "rounds": max(rounds, 1), "workers": workers,
            "survey_cpu_s": survey_s, "bare_cpu_s": bare_s,
            "ratio": survey_s / bare_s if bare_s > 0 else float("nan"),
            "survey_cpu_rounds": survey_cpu, "bare_cpu_rounds": bare_cpu, "pairs": pairs}


def format_report(report: dict) -> str:
    """The printed table: end to end, then every engine and preset."""
    impacts = report["impacts"]
    workers = report["workers"]
    processes = "one process" if workers == 1 else f"{workers} processes each"
    lines = [
        (f"survey: {report['samples']} samples x {impacts // report['samples']} populations"
         f" = {impacts} impacts, {len(report['pairs'])} engine/preset pairs; CPU seconds, "
         f"median of {report['rounds']} alternating round(s); target <= {RATIO_TARGET}"),
        (f"  end to end on {processes}: survey {report['survey_cpu_s']:.2f} s, bare stepping "
         f"{report['bare_cpu_s']:.2f} s, ratio {report['ratio']:.2f}"),
        "  per engine and preset, one process: contract = Engine.run_many, survey = "
        "run_many + verdicts + columns",
        "  (ratio: against the bare stepping; + world: against the bare stepping with each "
        "scene's world built and freed)",
        f"    {'pair':<24} {'steps':>7} {'bare s':>7} {'+world s':>8} {'contract s':>10} "
        f"{'ratio':>6} {'+world':>6} {'survey s':>8} {'ratio':>6}",
    ]
    lines += [f"    {pair:<24} {entry['steps']:7d} {entry['bare_s']:7.3f} "
              f"{entry['bare_world_s']:8.3f} {entry['contract_s']:10.3f} "
              f"{entry['contract_ratio']:6.2f} {entry['world_ratio']:6.2f} "
              f"{entry['judged_s']:8.3f} {entry['judged_ratio']:6.2f}"
              for pair, entry in report["pairs"].items()]
    return "\n".join(lines)
