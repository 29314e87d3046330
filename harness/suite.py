"""``impact-harness suite``: the validation suite that ``make validate`` runs.

Four steps, each timed on stderr::

    1. the paper's Table 3     -> <out>/paper-table3.md, <out>/paper-table3.png
    2. every scenario run      -> <out>/results.json  (runs cached: `impact-harness cache info`)
    3. a quick survey          -> <out>/survey/summary.md, <out>/survey/*.parquet
       (:data:`SURVEY_SAMPLES` samples of every population, the selected engines and
       presets; harness/survey/), kept as it is while its inputs are unchanged
       (:func:`survey_inputs`)
    4. the report              -> <out>/index.html, <out>/summary.md, <out>/figures/
       (with the survey's section and figures, harness/report/survey.py)

Options select scenarios and engines exactly as for ``impact-harness run`` (``--tags quick``
for a fast subset, ``--out`` for another directory). The exit status (see :mod:`harness.cli`)
is 1 when a scenario's gate fails or the paper's table has a miss no known erratum explains,
2 for bad options or scenario files, 3 for an internal error, 4 when an engine run of the
scenarios or of the survey ended in an error (each an ``ENGINE ERROR:`` line), else 0; the
report is written whenever the run wrote results.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

from harness import report
from harness.report import add_experiments_data_argument
from harness.report import table3 as paper
from harness.report.progress import Progress
from harness.report.survey import read_settings
from harness.run import command, plan
from harness.run.provenance import PACKAGES, package_versions
from harness.run.records import read_results
from harness.store.cache_directory import output_seal
from harness.store.files import make_output_directory, output_directory_problem, remove_written
from harness.store.identity import cached_code_sources, code_version_of
from harness.survey.cli import (
    SETTINGS_FILE,
    SUITE_SAMPLES,
    WRITTEN_BY_SURVEY,
    run_survey,
    write_survey,
)
from harness.survey.population import resolve_populations

#: Samples per population in the suite's survey: 7 populations x 20 = 140 impacts per engine
#: and preset, a few seconds with every engine (the distributions' tails need
#: ``impact-harness survey``'s default 2,000). Kept beside the survey's command, whose help
#: gives the command that computes the same tables (``suite_survey_command``).
SURVEY_SAMPLES = SUITE_SAMPLES


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", type=Path, default=Path("reports"),
                        help="output directory (default: reports)")
    command.add_common_arguments(parser)
    add_experiments_data_argument(parser)


def main(args) -> int:
    out: Path = args.out
    started = time.perf_counter()
    problem = output_directory_problem(out)
    if problem:
        problem = f"--out {out}: {problem}"
    else:
        make_output_directory(out)  # the directory asked for (itself only)
        problem = command.check_arguments(args, out / "results.json")
    if not problem:
        problem = report.experiments_data_problem(args.experiments_data)
        if problem:
            problem = f"--experiments-data {args.experiments_data}: {problem}"
    if problem:  # before any work, the Table 3 included
        print(f"impact-harness suite: {problem}", file=sys.stderr)
        return command.EXIT_BAD_INPUT

    tick = time.perf_counter()
    markdown, rows = paper.write_report(out)
    cells = [cell for row in rows for cell in row["cells"]]
    missed = [cell for cell in cells if not cell.reproduced]
    unexplained = [cell for cell in missed if cell.reason.startswith("UNEXPLAINED")]
    print(f"[1/4] Table 3: {len(cells) - len(missed)}/{len(cells)} printed cells reproduced, "
          f"{len(missed)} known errata, {len(unexplained)} unexplained -> {markdown} "
          f"({time.perf_counter() - tick:.1f} s)", file=sys.stderr, flush=True)

    tick = time.perf_counter()
    results_path = out / "results.json"
    status, outcome = command.execute(args, json_path=results_path,
                                     command=["impact-harness", "suite", *sys.argv[2:]])
    if outcome is None:
        return status
    print(f"[2/4] run: {outcome.record_count} records -> {results_path} "
          f"({time.perf_counter() - tick:.1f} s)", file=sys.stderr, flush=True)

    tick = time.perf_counter()
    summary, surveyed = quick_survey(args, out / "survey")
    print(f"[3/4] survey: {SURVEY_SAMPLES} samples per population -> {summary} "
          + ("" if surveyed else "(unchanged: same populations, settings, versions and code) ")
          + f"({time.perf_counter() - tick:.1f} s)", file=sys.stderr, flush=True)

    survey_errors = read_settings(out / "survey").get("engine_errors") or {}
    if survey_errors.get("runs"):  # listed in its summary and the report; 4 outranks 1
        print(f"ENGINE ERROR: survey: {survey_errors['runs']} engine runs raised (listed in "
              f"{summary})", file=sys.stderr)
        if status in (command.EXIT_OK, command.EXIT_GATE_FAILED):
            status = command.EXIT_ENGINE_ERROR

    tick = time.perf_counter()
    with Progress(label="[4/4] report") as progress:  # once it has taken two seconds
        written = report.write_report(read_results(results_path), out,
                                      experiments_data=args.experiments_data,
                                      progress=progress)
    print(f"[4/4] report: {written['html']}, {written['summary']}, "
          f"{len(written['figures'])} figures ({time.perf_counter() - tick:.1f} s)",
          file=sys.stderr, flush=True)

    failed = outcome.failed_gates
    print(f"suite finished in {time.perf_counter() - started:.1f} s: "
          + (f"{len(failed)} gate(s) FAILED" if failed else "all gates passed")
          + (f", {len(unexplained)} unexplained Table 3 miss(es)" if unexplained else ""),
          file=sys.stderr)
    if status >= 2:  # bad input (2) or an internal error (3) outranks a failed check
        return status
    return 1 if failed or unexplained else status


def quick_survey(args, out: Path) -> tuple[Path, bool]:
    """The survey of every population at :data:`SURVEY_SAMPLES` samples through the engines
    and presets the run selected; returns the written ``summary.md`` and whether the survey
    ran (False: the one in ``out`` was made from the same inputs, :func:`survey_inputs`, and
    is kept as it is)."""
    engines = plan.parse_engines(args.engines)
    presets = plan.parse_presets(args.preset)
    populations = resolve_populations([])
    inputs = survey_inputs(populations, engines, presets)
    if _survey_is_current(out, inputs):
        return out / "summary.md", False
    survey = run_survey(populations, SURVEY_SAMPLES, 0, engines, presets,
                        echo=lambda _: None)
    settings = {"samples": SURVEY_SAMPLES, "seed": 0,
                "engines": [name for name in engines if name not in survey["skipped"]],
                "presets": list(presets), "skipped": survey["skipped"],
                "left_out": survey["left_out"], "inputs": inputs}
    # no key over files half rewritten: removed, only as the survey wrote it (its manifest)
    remove_written(out, WRITTEN_BY_SURVEY, SETTINGS_FILE, output_seal())
    write_survey(survey, out, settings, figures=False)
    return out / "summary.md", True


def survey_inputs(populations, engines, presets) -> str:
    """The digest of what the quick survey's tables depend on: the populations (their files'
    text), :data:`SURVEY_SAMPLES`, the seed, the engines and presets asked for, the installed
    versions of Python, numpy, pyarrow and the engines (an engine installed since is run),
    and the code -- what the run cache's entries depend on (the engines, scenes, verdicts,
    metrics, ``planar_impact``: :func:`harness.store.identity.cached_code_sources`) and
    ``harness/survey/``. Any edit to that code runs the survey again: coarse, and cheap to
    get right."""
    survey_code = Path(__file__).resolve().parent / "survey"
    code = code_version_of((*cached_code_sources(), survey_code))
    text = json.dumps({
        "populations": [[population.name, Path(population.path).read_text(encoding="utf-8")
                         if population.path else repr(population)]
                        for population in populations],
        "samples": SURVEY_SAMPLES, "seed": 0, "engines": list(engines),
        "presets": list(presets), "versions": package_versions((*PACKAGES, "pyarrow")),
        "code": code}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _survey_is_current(out: Path, inputs: str) -> bool:
    """Whether ``out`` holds a quick survey written from the inputs whose digest is
    ``inputs``, every table of it present."""
    settings = read_settings(out)  # {} when missing, unreadable or not an object
    tables = ["summary.md", "samples.parquet"]
    if settings.get("engines"):
        tables += ["runs.parquet", "statistics.parquet"]
    return settings.get("inputs") == inputs and all((out / name).is_file() for name in tables)


__all__ = ["SURVEY_SAMPLES", "add_arguments", "main", "quick_survey", "survey_inputs"]
