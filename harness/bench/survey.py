"""``impact-harness bench --survey``: the survey end to end beside the engines' bare stepping.

One run, two measurements on the same impacts:

* ``survey_s`` -- :func:`harness.survey.cli.run_survey` in memory on one process (and
  ``survey_cores_s`` with a worker per core), everything but writing
  files: sampling and checking every scene, the contact terms and the five laws
  (``solve_batch``), every engine and preset (``Engine.run_many``), the verdict checks of
  every run, the departures and the statistics;
* ``bare_s`` -- for every engine and preset, the engine's own stepping of the same scenes
  (as many steps as the survey's run took) with its own per-impact reset
  (:func:`harness.survey.engines.bare_stepping`, ``bare_reset_s``): the least any Python
  driver spends on these impacts. Worlds are built outside the timed region.

``ratio = survey_s / bare_s`` (target :data:`RATIO_TARGET`), ``ratio_cores`` the same with
every core at work on the survey (the bare stepping stays on one). The stages' own times are
printed too, so the gap is attributed.
"""

from __future__ import annotations

import os
import time

from harness.engines import (
    PRESET_ROLES,
    EngineNotInstalled,
    engine_names,
    load_engine,
    source_label,
)
from harness.survey.cli import run_survey, survey_scenes
from harness.survey.engines import bare_stepping
from harness.survey.population import resolve_populations

RATIO_TARGET = 1.5
SAMPLES = 500  # per population
QUICK_SAMPLES = 60


def run(samples: int, engines=None, presets=PRESET_ROLES, seed: int = 0) -> dict:
    """``{"samples", "impacts", "survey_s", "bare_s", "ratio", "survey_cores_s",
    "ratio_cores", "cores", "stages", "bare"}``; ``engines`` None: every registered one."""
    installed = []
    for name in engine_names() if engines is None else engines:
        try:
            load_engine(name)
            installed.append(name)
        except EngineNotInstalled:
            continue
    populations = resolve_populations([])
    begin = time.perf_counter()
    survey = run_survey(populations, samples, seed, installed, presets, workers=1,
                        echo=lambda _: None)
    survey_s = time.perf_counter() - begin
    cores = os.cpu_count() or 1
    begin = time.perf_counter()
    run_survey(populations, samples, seed, installed, presets, workers=cores,
               echo=lambda _: None)
    survey_cores_s = time.perf_counter() - begin
    scenes = survey_scenes(populations, samples, seed)
    bare = {}
    for result in survey["engine_results"]:
        bare[source_label(result.engine, result.preset)] = bare_stepping(
            result.engine, result.preset, scenes, result.steps)["bare_reset_s"]
    bare_s = sum(bare.values())
    return {"samples": samples, "impacts": len(scenes), "engines": installed,
            "presets": list(presets), "survey_s": survey_s, "bare_s": bare_s,
            "ratio": survey_s / bare_s if bare_s > 0 else float("nan"),
            "cores": cores, "survey_cores_s": survey_cores_s,
            "ratio_cores": survey_cores_s / bare_s if bare_s > 0 else float("nan"),
            "stages": {stage: seconds for stage, (seconds, _) in survey["timings"].items()},
            "bare": bare}


def format_report(report: dict) -> str:
    """The printed table: the totals, then every stage and every engine's bare stepping."""
    impacts = report["impacts"]
    runs = impacts * len(report["bare"])
    lines = [
        (f"survey: {report['samples']} samples x {impacts // report['samples']} populations"
         f" = {impacts} impacts, {len(report['bare'])} engine/preset pairs ({runs} engine "
         "runs)"),
        f"  survey end to end, one process      {report['survey_s']:8.2f} s",
        (f"  survey end to end, {report['cores']} worker processes "
         f"{report['survey_cores_s']:8.2f} s"),
        f"  bare stepping (reset + steps, same impacts, one process) {report['bare_s']:8.3f} s",
        f"  ratio {report['ratio']:.1f} on one process, {report['ratio_cores']:.1f} with "
        f"{report['cores']} workers (target <= {RATIO_TARGET})",
        "  stages (one process; engine and verdict lines are seconds on one core):",
    ]
    lines += [f"    {stage:<44} {seconds:8.3f} s" for stage, seconds in report["stages"].items()]
    lines.append("  bare stepping per engine and preset:")
    lines += [f"    {pair:<44} {seconds:8.3f} s ({seconds / impacts * 1e6:.1f} µs/impact)"
              for pair, seconds in report["bare"].items()]
    return "\n".join(lines)
