"""``impact-harness bench --survey``: the survey and the engines' bare stepping of the same
impacts, on the same number of processes, in CPU time.

The machine is shared, so every figure is CPU time (``time.process_time``, plus the CPU time
of the worker processes a side forked and waited for), never wall time, and the two sides of
every comparison run in turn, round after round (``rounds``): a drift of the machine's speed
then hits both alike. The median of the rounds is reported.

* End to end -- ``survey_cpu_s``: the survey as ``impact-harness survey --no-figures`` runs
  it (:func:`streamed_survey`: sampling, the laws, every pair through ``Engine.run_many``,
  the verdicts, the dataset streamed to files, the tables and statistics read back) on
  ``workers`` processes, against ``bare_cpu_s``: a user's loop (below) of every pair it ran,
  its scenes split over the same ``workers`` processes. ``ratio = survey_cpu_s /
  bare_cpu_s``. Like the command, with the default presets it leaves out the pairs each
  engine's ``survey_left_out`` names (Drake's and MuJoCo's ``accurate``); their per-pair
  ratios below still count. ``end_to_end_samples`` sets its size apart from the per-pair
  comparisons': the survey's statistics and files cost a fixed amount per family and pair,
  which a survey of a few dozen samples measures instead of its cost per impact.
* Per engine and preset, on this one process -- ``contract_s``: ``Engine.run_many`` of every
  scene (the contract's run: set-up, stepping with the per-step contact records, read-out,
  status, the :class:`EngineRun`); ``judged_s``: the survey's whole per-pair work,
  :func:`harness.survey.engines.run_engine` (``run_many`` plus the verdict checks and the
  gathering of the columns); ``bare_s``: the engine's own per-impact reset and as many of its
  own step calls as the contract's run took, in a tight loop (``Engine.bare_stepper``, each
  scene's world built outside the timed region): the least any Python driver spends.
  ``contract_ratio = contract_s / bare_s`` and ``judged_ratio = judged_s / bare_s``.
  ``bare_world_s``: a user's own loop, the same bare stepping with each scene's world built
  and freed and the velocities read, timed too (the survey's shapes are all different, so
  the contract's run builds a world, or the bodies of a batch world, for every impact), the
  harness's preparation of the run (checks, start state, Box2D's speed probe) left out;
  ``world_ratio = contract_s / bare_world_s``.

An untimed survey runs first, so that every round finds the engines' caches (MuJoCo's
compiled polygons, say) equally warm. Every ratio's target is :data:`RATIO_TARGET`.

A scene whose engine run raises (the survey records it ``error``: Drake's discrete solver
failing to converge under ``accurate``) has no run to time and no step count for the bare
stepping: the untimed survey finds them, and each pair's comparisons (contract, survey's
per-pair work, bare stepping, user loop, and the user loops of the end-to-end comparison)
leave that pair's errored scenes out of both sides, counted (``errored``) and printed with
the first reason. The end-to-end survey side cannot leave them out (it samples the
populations itself): it includes their raising runs and the reruns of their slices scene by
scene, a cost counted against the survey.
"""

from __future__ import annotations

import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

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
from harness.survey import cli as survey_cli
from harness.survey import laws as survey_laws
from harness.survey import stream
from harness.survey.cli import run_survey
from harness.survey.engines import ERROR, SLICE, run_engine
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

#: Each engine/preset pair's CPU time against a user's own loop of the same impacts (each
#: scene's world built and freed, the same steps, the velocities read): at most this.
RATIO_TARGET = 1.5
#: The survey end to end (streamed, tables and statistics written) against every pair's
#: user loop of its impacts on as many processes: at most this.
END_TO_END_TARGET = 1.0
#: The contract's run against the bare stepping that never builds a world: no target (a
#: survey of different scenes builds one per impact), a tripwire for regressions in the run
#: loop -- above it, something in the per-step bookkeeping grew. Measured 1.4-7.4 (MuJoCo's
#: matched-bounce to Box2D's accurate, 500 samples, 3 rounds, the 2-core machine loaded).
CONTRACT_TRIPWIRE = 10.0
#: Peak memory of a survey of MEMORY_SIZES[1] samples against one of MEMORY_SIZES[0] (one
#: population, one engine/preset pair): at most this, i.e. flat.
MEMORY_TARGET = 1.3
MEMORY_SIZES = (2000, 40000)
QUICK_MEMORY_SIZES = (500, 10000)
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
    steps, and a user's own loop: the same with the building and freeing of each scene's
    world (a world of its own per scene, :meth:`Engine.bare_stepper`) and the velocities read
    after the steps -- what any driver spends when every impact has a shape of its own, as
    the survey's have. The run's preparation is not the user's (``BareStepper.build_cpu_s``
    times the world alone): a user's loop knows its settings, where the harness may first
    measure the scene (Box2D's speed probe, a second simulation, would flatter the ratio)."""
    clock = time.process_time
    stepping = with_world = 0.0
    for scene, count in zip(scenes, steps):
        stepper = engine.bare_stepper(scene, settings)
        built = stepper.build_cpu_s
        try:
            tick = clock()
            stepper.reset()
            stepper.step(count)
            stepping += clock() - tick
            tick = clock()
            stepper.velocities()  # what a user's loop reads after its steps
            built += clock() - tick
        finally:
            tick = clock()
            stepper.close()
            with_world += built + clock() - tick
    return stepping, stepping + with_world


# The bare stepping's work for the forked workers: read from module state, never pickled.
_BARE_WORK: dict = {}


def _bare_part(part: tuple[int, int, int]) -> float:
    """One worker's share of the end-to-end user loops: pair ``part[0]``, its scenes
    ``part[1]:part[2]``, each scene's world built and freed; its CPU seconds."""
    pair, begin, end = part
    engine, settings, scenes, steps = _BARE_WORK["pairs"][pair]
    return _bare_cpu(engine, settings, scenes[begin:end], steps[begin:end])[1]


def _bare_all_cpu(pairs, workers: int) -> float:
    """CPU seconds of every pair's user loop (worlds built, steps, velocities read) over its
    scenes (``pairs``: ``(engine, settings, scenes, steps)``), split over ``workers``."""
    _BARE_WORK.update(pairs=pairs)
    parts = []
    for pair, (_, _, scenes, _) in enumerate(pairs):
        share = max(1, -(-len(scenes) // max(workers, 1)))
        parts += [(pair, begin, min(begin + share, len(scenes)))
                  for begin in range(0, len(scenes), share)]
    try:
        return sum(map_forked(_bare_part, parts, workers))
    finally:
        _BARE_WORK.clear()


def streamed_survey(populations, samples: int, seed: int, engines, presets, workers: int,
                    out: Path, left_out: dict | None = None) -> None:
    """``impact-harness survey --no-figures --quiet`` into ``out``, without its option
    checks: chunks streamed to the dataset on ``workers`` processes, then the tables,
    statistics and summary read back from it (``left_out``: the pairs not run, as
    :func:`harness.survey.cli.default_left_out` gives them)."""
    left_out = dict(left_out or {})
    pairs, _ = survey_cli.installed_pairs(engines, presets, left_out, echo=lambda _: None)
    settings = {"samples": samples, "seed": seed, "engines": list(engines),
                "presets": list(presets),
                "left_out": {source_label(engine, preset): why
                             for (engine, preset), why in left_out.items()},
                "skipped": {}, "overrides": {}}
    done = stream.stream_survey(populations, samples, seed, pairs, out,
                                survey_cli.table_metadata(settings), workers=workers,
                                time_limit_s=None, progress=False, echo=lambda _: None)
    survey_cli.write_streamed(done["dataset"], populations, pairs, out, settings,
                              figures=False, wall_s=done["wall_s"])


def _user_loop_work(result, engine, settings, scenes) -> tuple:
    """``(engine, settings, scenes, steps)`` of a user's loop of one pair's impacts, from
    that pair's ``result`` (:class:`harness.survey.engines.EngineResult`) in a survey of
    ``scenes``: the scenes whose run raised left out (they have no steps to take)."""
    kept = [row for row in range(len(scenes)) if result.status[row] != ERROR]
    return engine, settings, [scenes[row] for row in kept], [int(result.steps[row])
                                                           for row in kept]


def run(samples: int, engines=None, presets=None, seed: int = 0,
        rounds: int = ROUNDS, workers: int = 1, end_to_end_samples: int | None = None) -> dict:
    """``{"samples", "impacts", "engines", "presets", "rounds", "workers", "survey_cpu_s",
    "bare_cpu_s", "ratio", "end_to_end_samples", "end_to_end_pairs", "end_to_end_left_out",
    "pairs": {label: {"contract_s", "judged_s", "bare_s", "contract_ratio", "judged_ratio",
    "steps", "errored", "error"}}}`` (medians over ``rounds``; ``errored``: the scenes where
    the pair's engine raised, left out of both sides of its comparisons, ``error`` the first
    one's reason); ``engines`` None: every registered one.

    The end to end is the survey a user runs: with the default presets, the pairs each
    engine's ``survey_left_out`` leaves out of a default survey are left out of it too (and
    listed), as ``impact-harness survey`` leaves them out; named presets (``presets`` not
    None, the default ones too, as ``--preset defaults,accurate``) leave none out.
    It runs ``end_to_end_samples`` per population (default ``samples``): the survey's cost
    per family and pair (statistics, files) is fixed, so a small survey measures that, not
    the cost per impact."""
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
    # As the command: naming presets at all leaves no pair out, the default ones included.
    left_out = survey_cli.default_left_out(installed) if presets is None else {}
    presets = tuple(PRESET_ROLES if presets is None else presets)
    pair_names = [(name, preset) for name in installed for preset in presets]
    end_pairs = [pair for pair in pair_names if pair not in left_out]
    end_samples = samples if end_to_end_samples is None else end_to_end_samples
    measured = {pair: {"contract_s": [], "judged_s": [], "bare_s": [], "bare_world_s": []}
                for pair in pair_names}
    survey_cpu, bare_cpu = [], []
    # One untimed pass first: the engines' caches (MuJoCo's compiled polygons, extents) are
    # then as warm for the first round as for the others, whichever side it times first.
    warm = run_survey(populations, samples, seed, installed, presets, workers=1,
                      echo=lambda _: None)
    # Its errored runs (rows in the order of `scenes`): left out of both sides per pair.
    errored = {(result.engine, result.preset): result
               for result in warm["engine_results"]}
    kept_work = {}
    for pair in pair_names:
        result = errored[pair]
        kept = [row for row in range(len(scenes)) if result.status[row] != ERROR]
        kept_problems, kept_terms = [problems[row] for row in kept], [scene_terms[row]
                                                                       for row in kept]
        kept_work[pair] = ([scenes[row] for row in kept], kept_problems, energy[kept],
                           kept_terms, verdicts.term_arrays(kept_problems, kept_terms))
    # The user loops of the end to end: each pair's impacts of the survey it times, with
    # the steps its runs took (an untimed survey of that size, unless it is this one).
    end_warm, end_scenes = warm, scenes
    if end_samples != samples:
        end_warm = run_survey(populations, end_samples, seed, installed, presets,
                              left_out=left_out, workers=1, echo=lambda _: None)
        end_scenes = survey_cli.survey_scenes(populations, end_samples, seed)
    end_results = {(result.engine, result.preset): result
                   for result in end_warm["engine_results"]}
    end_work = []
    for name, preset in end_pairs:
        engine = load_engine(name)
        end_work.append(_user_loop_work(end_results[(name, preset)], engine,
                                        engine.settings(preset), end_scenes))
    for _ in range(max(rounds, 1)):
        # Per pair, on this process: the contract's run, the survey's per-pair work, bare.
        for name, preset in pair_names:
            engine = load_engine(name)
            settings = engine.settings(preset)
            pair_scenes, pair_problems, pair_energy, pair_terms, pair_arrays = \
                kept_work[(name, preset)]
            contract_s, steps = _contract_cpu(engine, settings, pair_scenes)
            tick = time.process_time()
            with collector_paused():
                run_engine(name, preset, pair_scenes, pair_problems, pair_energy, pair_terms,
                           pair_arrays)
            judged_s = time.process_time() - tick
            bare_s, bare_world_s = _bare_cpu(engine, settings, pair_scenes, steps)
            entry = measured[(name, preset)]
            entry["contract_s"].append(contract_s)
            entry["judged_s"].append(judged_s)
            entry["bare_s"].append(bare_s)
            entry["bare_world_s"].append(bare_world_s)
            entry.setdefault("steps", steps)
        # End to end, both sides on `workers` processes: the survey as the command runs
        # it (streamed to its dataset, then the tables and summary; no figures).
        with tempfile.TemporaryDirectory(prefix="bench-survey-") as directory:
            tick = _cpu_with_children()
            streamed_survey(populations, end_samples, seed, installed, presets, workers,
                            Path(directory), left_out)
            survey_cpu.append(_cpu_with_children() - tick)
        bare_cpu.append(_bare_all_cpu(end_work, workers))
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
            "steps": int(sum(entry["steps"])),
            "errored": len(scenes) - len(kept_work[(name, preset)][0]),
            "error": next((why for why in errored[(name, preset)].errors if why), ""),
        }
    survey_s, bare_s = statistics.median(survey_cpu), statistics.median(bare_cpu)
    return {"samples": samples, "impacts": len(scenes), "engines": installed,
            "presets": list(presets), "rounds": max(rounds, 1), "workers": workers,
            "survey_cpu_s": survey_s, "bare_cpu_s": bare_s,
            "ratio": survey_s / bare_s if bare_s > 0 else float("nan"),
            "end_to_end_samples": end_samples,
            "end_to_end_impacts": len(end_scenes),
            "end_to_end_pairs": [source_label(name, preset) for name, preset in end_pairs],
            "end_to_end_left_out": {source_label(name, preset): why
                                    for (name, preset), why in left_out.items()
                                    if (name, preset) in pair_names},
            "survey_cpu_rounds": survey_cpu, "bare_cpu_rounds": bare_cpu, "pairs": pairs}


def format_report(report: dict) -> str:
    """The printed table: end to end, then every engine and preset."""
    impacts, samples = report["impacts"], report["samples"]
    end_samples = report.get("end_to_end_samples", samples)
    end_impacts = report.get("end_to_end_impacts", impacts)
    end_pairs = report.get("end_to_end_pairs", list(report["pairs"]))
    workers = report["workers"]
    processes = "one process" if workers == 1 else f"{workers} processes each"
    def verdict(ratio: float, target: float, word: str = "met") -> str:
        return word if ratio <= target else ("MISSED" if word == "met" else "TRIPPED")

    lines = [
        (f"survey: {report['samples']} samples x {impacts // report['samples']} populations"
         f" = {impacts} impacts, {len(report['pairs'])} engine/preset pairs; CPU seconds, "
         f"median of {report['rounds']} alternating round(s)"),
        (f"  end to end on {processes}, {end_samples} samples x {impacts // samples} "
         f"populations = {end_impacts} impacts, the survey's {len(end_pairs)} "
         f"pair{'' if len(end_pairs) == 1 else 's'}: survey "
         f"(streamed, tables and statistics written) {report['survey_cpu_s']:.2f} s, a "
         f"user's loops of those pairs (worlds built, steps, velocities read) "
         f"{report['bare_cpu_s']:.2f} s, ratio {report['ratio']:.2f} "
         f"(target <= {END_TO_END_TARGET}: {verdict(report['ratio'], END_TO_END_TARGET)})"),
        *(f"    left out as a default survey leaves it out: {pair} ({why})"
          for pair, why in report.get("end_to_end_left_out", {}).items()),
        "  per engine and preset, one process: contract = Engine.run_many; user loop = "
        "each scene's world built and freed, the same steps, the velocities read",
        f"  (target: contract / user loop <= {RATIO_TARGET}; contract / bare stepping without "
        f"worlds is a tripwire at {CONTRACT_TRIPWIRE}, not a target; survey = run_many + "
        "verdicts + columns)",
        f"    {'pair':<24} {'steps':>7} {'user s':>7} {'contract s':>10} {'ratio':>6} "
        f"{'target':>7} {'bare s':>7} {'ratio':>6} {'wire':>7} {'survey s':>8}",
    ]
    lines += [f"    {pair:<24} {entry['steps']:7d} {entry['bare_world_s']:7.3f} "
              f"{entry['contract_s']:10.3f} {entry['world_ratio']:6.2f} "
              f"{verdict(entry['world_ratio'], RATIO_TARGET):>7} {entry['bare_s']:7.3f} "
              f"{entry['contract_ratio']:6.2f} "
              f"{verdict(entry['contract_ratio'], CONTRACT_TRIPWIRE, 'ok'):>7} "
              f"{entry['judged_s']:8.3f}"
              for pair, entry in report["pairs"].items()]
    errored = {pair: entry for pair, entry in report["pairs"].items() if entry.get("errored")}
    if errored:
        lines.append("  scenes where the engine raised, left out of both sides of the pair's "
                     "comparisons and of its user loops end to end (the survey side keeps "
                     "them):")
        lines += [f"    {pair}: {entry['errored']} of {impacts} ({entry['error']})"
                  for pair, entry in errored.items()]
    if "memory" in report:
        lines.append("  " + format_memory(report["memory"]))
    return "\n".join(lines)


def survey_peak_rss_kb(samples: int, out: Path, population: str = "rod-ground",
                       engine: str = "pymunk", preset: str = "defaults",
                       workers: int = 1) -> int:
    """Peak resident memory (KB) of ``impact-harness survey POPULATION --samples N`` run as
    a command, over its process and the workers it forks (``wait4``'s ``ru_maxrss``: the
    largest of them, as ``/usr/bin/time -v`` reports it)."""
    command = [sys.executable, "-m", "harness.cli", "survey", population, "--samples",
               str(samples), "--engines", engine, "--preset", preset, "--no-figures",
               "--quiet", "--workers", str(workers), "--out", str(out)]
    # Started by a small Python of its own: a process's peak RSS keeps the peak of the
    # process it was forked from until its exec (this benchmark's, hundreds of MB).
    found = subprocess.run([sys.executable, "-c", _PEAK_OF_COMMAND, *command], check=False,
                           capture_output=True, text=True)
    status, peak = (found.stdout.split() + ["?", "?"])[:2]
    if found.returncode != 0 or status != "0":
        raise RuntimeError(f"{' '.join(command)}: exit status {status}: {found.stderr}")
    return int(peak)


#: Runs the command in its arguments and prints its exit status and peak RSS (KB, the
#: largest of it and its waited-for children, from ``wait4``).
_PEAK_OF_COMMAND = (
    "import os, subprocess, sys\n"
    "child = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL)\n"
    "_, status, usage = os.wait4(child.pid, 0)\n"
    "print(os.waitstatus_to_exitcode(status), usage.ru_maxrss)\n")


def memory(sizes=MEMORY_SIZES, workers: int = 1) -> dict:
    """``{"sizes", "peak_kb", "ratio"}``: the peak memory of a survey at two sizes (each in a
    fresh directory) and the larger's against the smaller's (target
    :data:`MEMORY_TARGET`)."""
    peaks = []
    for samples in sizes:
        with tempfile.TemporaryDirectory(prefix="bench-survey-memory-") as directory:
            peaks.append(survey_peak_rss_kb(samples, Path(directory) / "out", workers=workers))
    return {"sizes": list(sizes), "peak_kb": peaks, "ratio": peaks[-1] / peaks[0]}


def format_memory(report: dict) -> str:
    small, large = report["sizes"]
    verdict = "met" if report["ratio"] <= MEMORY_TARGET else "MISSED"
    return (f"survey memory (rod-ground, pymunk defaults, --no-figures): peak RSS "
            f"{report['peak_kb'][0] / 1024:.0f} MB at "
            f"{small:,} samples, {report['peak_kb'][1] / 1024:.0f} MB at {large:,}; ratio "
            f"{report['ratio']:.2f} (target <= {MEMORY_TARGET}: {verdict})")
