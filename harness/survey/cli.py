"""``impact-harness survey``: departure distributions over families of impacts.

``impact-harness survey [POPULATION…] [--samples N] [--seed S] [--engines E,…] [--preset P,…]
[--out DIR] [--quick] [--bare] [--no-figures]``

Every sample of every population goes through every law (one ``solve_batch`` call per law)
and every engine and preset; the tables, the summary and the figures go to ``--out``
(harness/survey/outputs.py lists them). ``--bare`` also times the engines' bare stepping of
the same impacts, in the same run, and prints it beside the survey's time.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from harness import bounds
from harness.engines import (
    PRESET_ROLES,
    EngineNotInstalled,
    engine_names,
    engine_trait,
    load_engine,
    parse_overrides,
    preset_choices,
    preset_label,
    preset_role,
    renamed_roles,
    source_label,
)
from harness.run.executor import EXECUTORS, DaskNotInstalled, check_arguments
from harness.run.provenance import package_versions
from harness.scenarios.errors import ScenarioError
from harness.store.cache_directory import output_seal
from harness.store.files import (
    inner_directory_problem,
    keep_manifest,
    make_output_directory,
    output_directory_problem,
    replaceable_problem,
    write_text_atomically,
)
from harness.survey import laws as survey_laws
from harness.survey import outputs, statistics, stream
from harness.survey.engines import ERROR, SKIPPED, bare_stepping
from harness.survey.parts import run_parts
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population
from harness.survey.stream import sample_columns

DEFAULT_SAMPLES = 2000
#: ``--quick``: a default survey (its pairs, so MuJoCo's matched-bounce left out, and its
#: figures) at this many samples per family, a first look in seconds. Not ``make
#: validate``'s survey: that is :data:`SUITE_SAMPLES` (:func:`suite_survey_command`).
QUICK_SAMPLES = 40
#: Samples per population of ``impact-harness suite``'s survey (``make validate``'s step 3,
#: harness/suite.py): every population, engine and preset, matched-bounce included, seed 0,
#: no figures (its report draws them).
SUITE_SAMPLES = 20
DEFAULT_OUT = Path("reports") / "survey"
#: The survey's manifest in its --out: the files it wrote there, with their SHA-256.
WRITTEN_BY_SURVEY = ".written-by-survey.json"
#: What a survey wrote down of its settings, beside its tables (harness/survey/outputs.py).
SETTINGS_FILE = "settings.json"
#: The files a survey writes in its directory under fixed names.
SURVEY_FILES = ("samples.parquet", "runs.parquet", "statistics.parquet", "summary.md",
                SETTINGS_FILE, WRITTEN_BY_SURVEY)
#: Errored runs printed as ``ENGINE ERROR:`` lines on stderr (as ``run`` prints its own); the
#: rest are counted there, and all are in the summary's count and ``runs.parquet``.
SHOWN_ENGINE_ERRORS = 10
#: The exit status of a survey whose tables were written but an engine run raised, or whose
#: chunks were stopped (``run``'s: harness/run/command.py EXIT_ENGINE_ERROR).
EXIT_ENGINE_ERROR = 4


def default_left_out(engines) -> dict[tuple[str, str], str]:
    """``{(engine, preset role): why}``: the pairs of ``engines`` a survey leaves out unless
    ``--preset`` names presets, as each engine's class declares them (``survey_left_out``;
    MuJoCo's matched-bounce: hundreds of steps of a stiff soft contact per impact), each with
    the ``--preset`` that runs it (:func:`including_option`)."""
    return {(engine, role): f"{why}; naming presets leaves no pair out, so "
                            f"{including_option(engine)} runs it"
            for engine in engines
            for role, why in engine_trait(engine, "survey_left_out").items()}


def including_option(engine: str) -> str:
    """The ``--preset`` that runs every preset of ``engine``, a left-out pair too, under the
    names the summary shows (``--preset defaults,matched-bounce`` for MuJoCo). The default
    presets' names alone would read as a no-op: they are the presets the summary says ran;
    what includes the pair is naming presets at all, which leaves nothing out."""
    names = ",".join(preset_label(engine, role) for role in PRESET_ROLES)
    return f"`--preset {names}`"


def suite_survey_command(out: str = "DIR") -> str:
    """The ``impact-harness survey`` command that computes the tables of ``impact-harness
    suite``'s survey (harness/suite.py runs ``run_survey`` itself): its samples, every
    population, engine and preset at the default seed, and no figures. The presets are named
    because naming them leaves no pair out, as the suite leaves none."""
    return (f"impact-harness survey --samples {SUITE_SAMPLES} --preset "
            f"{','.join(PRESET_ROLES)} --no-figures --out {out}")


def _names(values, allowed, option) -> list[str]:
    """The names of a comma-separated option; ``ValueError`` (bad input) for an unknown one."""
    names = [name.strip() for value in values or () for name in value.split(",")
             if name.strip()]
    if values is not None and not names:  # `--engines ''` ran every engine
        raise ValueError(f"{option} {values[-1]!r} names none; allowed: one or more of "
                         f"{', '.join(allowed)} (leave the option out for all)")
    bad = [name for name in names if name not in allowed]
    if bad:
        raise ValueError(f"{option}: unknown {bad}; allowed: {', '.join(allowed)}")
    return list(dict.fromkeys(names))


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("populations", nargs="*", metavar="POPULATION",
                        help="population names (files of populations/) or paths; default all")
    parser.add_argument("--samples", type=bounds.option("samples"), default=None,
                        help=f"samples per population (default {DEFAULT_SAMPLES}; "
                             f"--quick {QUICK_SAMPLES})")
    parser.add_argument("--seed", type=bounds.option("seed"),
                        default=0, help="sampling seed (default 0)")
    parser.add_argument("--engines", action="append", metavar="E[,E…]",
                        help="engines (default every installed one of "
                             f"{', '.join(engine_names())})")
    renamed = [f"{engine} calls {role} {name}" for engine in engine_names()
               for role, name in renamed_roles(engine).items()]
    parser.add_argument("--preset", action="append", metavar="P[,P…]",
                        help=f"presets (default {', '.join(PRESET_ROLES)}, without the pairs "
                        "an engine leaves out of a default survey, which the summary lists "
                        "with why; naming presets leaves no pair out"
                        + "".join(f"; {text}" for text in renamed)
                        + (", and either name selects it" if renamed else "") + ")")
    parser.add_argument("--out", type=Path, default=None,
                        help=f"output directory (default {DEFAULT_OUT}; there a survey of other "
                             "populations, samples, seed, engines, presets or settings is not "
                             "replaced: see --force)")
    parser.add_argument("--force", action="store_true",
                        help=f"without --out, replace the survey in {DEFAULT_OUT} even when it "
                             "surveyed something else")
    parser.add_argument("--set", dest="settings_overrides", action="append", default=[],
                        metavar="ENGINE.KEY=VALUE",
                        help="change one engine setting from every preset, as `run --set` "
                             "(repeatable); the tables and summary record it")
    parser.add_argument("--quick", action="store_true",
                        help=f"the default survey at {QUICK_SAMPLES} samples per population: "
                             "every population, engine and preset but the pairs a default "
                             "survey leaves out (the summary names them), with the figures. "
                             f"`make validate`'s survey differs ({SUITE_SAMPLES} samples, no "
                             "pair left out, no figures); "
                             f"`{suite_survey_command()}` computes its tables")
    parser.add_argument("--bare", action="store_true",
                        help="also time the engines' bare stepping of the same impacts")
    parser.add_argument("--no-figures", action="store_true", help="skip the figures")
    parser.add_argument("--workers", type=bounds.option("workers"), default=None,
                        help="processes for the engine runs (default: every core; the "
                             "results do not depend on it)")
    parser.add_argument("--executor", choices=EXECUTORS, default="local",
                        help="where the chunks run: local processes (default) or a Dask "
                             "cluster (a LocalCluster of --workers processes, or the one at "
                             "--scheduler); the results do not depend on it")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="a running Dask scheduler (tcp://host:8786), with --executor dask")
    parser.add_argument("--task-time-limit", type=float, default=stream.CHUNK_TIME_LIMIT_S,
                        metavar="SECONDS",
                        help="wall-clock seconds one chunk (at most "
                             f"{stream.CHUNK_IMPACTS} impacts) may run (default "
                             f"{stream.CHUNK_TIME_LIMIT_S:g}); a chunk over it is stopped, "
                             "the others go on, and the survey exits 4 with the finished "
                             "chunks kept (local executor; Dask workers are not stopped)")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress lines on stderr")


def run_survey(populations, samples: int, seed: int, engines, presets, *, bare: bool = False,
               left_out=None, workers: int | None = None, echo=print,
               overrides: dict | None = None) -> dict:
    """The survey in memory: ``{"samples", "runs", "statistics", "rejections", "timings",
    "engine_results", "skipped", "left_out"}`` (columns as ``{name: array}``).

    ``left_out``: ``{(engine, preset): why}`` pairs not run (:func:`default_left_out` when
    the user named no preset); they are listed in the summary, not dropped silently.
    ``workers``: processes (default: every core; the result does not depend on it,
    harness/survey/parts.py): each samples, solves, runs and judges parts of the samples.
    The sampling, laws, verdict-terms and per-pair ``engine`` and ``verdicts`` timings are
    seconds on one core, summed over the parts. ``timings``: ``{stage: (seconds, engine
    runs)}``, the engine runs being those the stage covers (one per impact and engine/preset
    pair; 0 for the stages before the engines), so a stage over every pair is not read per
    impact of one (harness/survey/outputs.py divides every row by the impacts too).
    """
    left_out = dict(left_out or {})
    clock = time.perf_counter
    pairs, skipped = installed_pairs(engines, presets, left_out, echo)
    begin = clock()
    survey = run_parts(populations, samples, seed, pairs, workers or os.cpu_count() or 1,
                       overrides)
    wall = clock() - begin
    impacts = samples * len(populations)
    terms, results = survey.terms, survey.results
    # The busiest worker's CPU time against the parts' wall time: what the workers lose to
    # each other and to the machine's other work (the parts' own cost is the CPU time).
    echo(f"sampled {impacts} impacts from {len(populations)} populations in "
         f"{survey.timings['sampling']:.2f} s; {survey.parts} parts in {wall:.2f} s on "
         f"{len(survey.worker_cpu)} processes (CPU "
         + ", ".join(f"{seconds:.2f}" for seconds in sorted(survey.worker_cpu.values()))
         + " s)")
    begin = clock()
    law_results = survey_laws.solve_laws(terms)
    routh = survey_laws.routh_coordinates(terms)
    timings: dict[str, tuple[float, int]] = {
        "sampling": (survey.timings["sampling"], 0),
        "laws (contact terms + solve_batch × 5)": (survey.timings["laws"] + clock() - begin, 0),
        "verdict terms (once per scene)": (survey.timings["verdict terms"], 0),
        "parts (wall: sampling, laws, engines, verdicts)": (wall, impacts * len(results)),
    }
    scenes = survey_scenes(populations, samples, seed) if bare and results else None
    for result in results:
        engine, preset = result.engine, result.preset
        shown = preset_label(engine, preset)  # the name users see, not the role
        timings[f"engine {engine} {shown}"] = (result.wall_s, impacts)
        timings[f"verdicts {engine} {shown}"] = (result.judge_s, impacts)
        echo(f"{engine} {shown}: {impacts} impacts in {result.wall_s:.2f} s "
             f"({result.wall_s / impacts * 1e6:.0f} µs each), verdicts "
             f"{result.judge_s:.2f} s")
        if bare:
            bare_times = bare_stepping(engine, preset, scenes, result.steps,
                                       (overrides or {}).get(engine))
            timings[f"bare {engine} {shown} (steps only)"] = (bare_times["bare_s"], impacts)
            timings[f"bare {engine} {shown} (reset + steps)"] = (
                bare_times["bare_reset_s"], impacts)
            echo(f"  bare stepping of the same impacts: {bare_times['bare_s']:.3f} s, "
                 f"with the reset {bare_times['bare_reset_s']:.3f} s")

    begin = clock()
    family = np.asarray([row.population for row in survey.rows])
    index = np.asarray([row.index for row in survey.rows])
    runs = statistics.run_columns(family, index, terms, law_results, routh, results)
    stats = statistics.statistics(runs) if results else {}
    timings["departures + statistics"] = (clock() - begin, impacts * len(results))
    return {
        "samples": sample_columns(survey.rows, terms, law_results, routh),
        "runs": runs,
        "statistics": stats,
        "rejections": {population.name: rejected
                       for population, rejected in zip(populations, survey.rejections)},
        "timings": timings,
        "engine_results": results,
        "skipped": skipped,
        "left_out": {source_label(engine, preset): why
                     for (engine, preset), why in left_out.items()
                     if engine in engines and preset in presets and engine not in skipped},
    }


def installed_pairs(engines, presets, left_out: dict, echo=print) -> tuple[list, dict]:
    """``(pairs, skipped)``: the ``(engine, preset)`` pairs to run, those of an engine not
    installed left out and named in ``skipped`` (engine -> why)."""
    pairs, skipped = [], {}
    for engine in engines:
        try:
            load_engine(engine)
        except EngineNotInstalled as error:
            skipped[engine] = str(error)
            echo(f"skipping {engine}: {error}")
            continue
        pairs += [(engine, preset) for preset in presets if (engine, preset) not in left_out]
    return pairs, skipped


def survey_scenes(populations, samples: int, seed: int) -> list:
    """The scenes of the survey's samples, in its row order (for the bare stepping)."""
    return [sample.scene for population in populations
            for sample in sample_population(population, samples, seed).samples]


def table_metadata(settings: dict) -> dict:
    """What every survey table carries in its Parquet metadata: what was surveyed (samples,
    seed, engines, presets), the installed versions and each engine's preset settings as
    run, so a table read alone says where it came from."""
    engine_settings = {}
    for name in settings.get("engines", []):
        engine = load_engine(name)
        overrides = settings.get("overrides", {}).get(name)
        engine_settings[name] = {preset: engine.settings(preset, overrides)
                                 for preset in settings.get("presets", [])}
    return {"format": "impact-harness-survey", "settings": settings,
            "versions": package_versions(), "engine_settings": engine_settings}


def write_survey(survey: dict, out: Path, settings: dict, figures: bool = True) -> list[Path]:
    """Write the tables, the summary and (unless ``figures`` is False) the figures."""
    out.mkdir(parents=True, exist_ok=True)
    about = table_metadata(settings)
    written = [outputs.write_parquet(survey["samples"], out / "samples.parquet",
                                     {**about, "table": "samples"})]
    if survey["engine_results"]:
        written.append(outputs.write_parquet(survey["runs"], out / "runs.parquet",
                                             {**about, "table": "runs"}))
        written.append(outputs.write_parquet(survey["statistics"], out / "statistics.parquet",
                                             {**about, "table": "statistics"}))
    if figures and survey["engine_results"]:
        begin = time.perf_counter()
        written += outputs.figures(survey["runs"], out / outputs.FIGURES_DIRECTORY)
        survey["timings"]["figures"] = (time.perf_counter() - begin, 0)
    summary = out / "summary.md"
    errors = errors_in_memory(survey)
    write_text_atomically(summary, outputs.summary_markdown(
        survey["statistics"], survey["rejections"], survey["timings"], settings,
        skipped_runs=skipped_in_memory(survey), engine_errors=errors))
    # What was surveyed, for the report (harness/report/survey.py) to read without Parquet.
    shown = {**settings, "families": list(survey["rejections"]),
             "skipped": settings.get("skipped", survey["skipped"]),
             "left_out": settings.get("left_out", survey["left_out"]),
             "engine_errors": errors_setting(errors)}
    settings_path = out / SETTINGS_FILE
    write_text_atomically(settings_path, json.dumps(shown, indent=1) + "\n")
    written += [summary, settings_path]
    # An earlier survey's tables this one did not write (no engine ran) would be read as
    # this one's: removed, but only those the manifest says a survey wrote, as written.
    keep_manifest(out, WRITTEN_BY_SURVEY, [path.name for path in written
                                           if path.parent == out], (".parquet",),
                  output_seal())
    return written


def skipped_in_memory(survey: dict) -> dict:
    """The summary's skipped runs (``outputs.summary_markdown``) of a survey held in memory:
    ``{"engine preset": ({family: runs}, why)}``."""
    found: dict[str, tuple[dict, str]] = {}
    runs = survey["runs"]
    if not survey["engine_results"]:
        return found
    skipped = np.flatnonzero(np.asarray(runs["status"]) == SKIPPED)
    why = {f"{result.engine} {result.preset}": result.skipped_why
           for result in survey["engine_results"]}
    for row in skipped.tolist():
        pair = f"{runs['engine'][row]} {runs['preset'][row]}"
        counts, _ = found.setdefault(pair, ({}, why.get(pair, "")))
        counts[runs["family"][row]] = counts.get(runs["family"][row], 0) + 1
    return found


def errors_in_memory(survey: dict) -> list[list]:
    """The runs whose engine raised in a survey held in memory, as
    :func:`harness.survey.stream.totals` lists them: ``[pair, family, sample, why]`` by
    pair, family (the survey's order) and sample."""
    if not survey["engine_results"]:
        return []
    runs = survey["runs"]
    place = {family: position for position, family in enumerate(survey["rejections"])}
    found = [[f"{runs['engine'][row]} {runs['preset'][row]}", str(runs["family"][row]),
              int(runs["sample"][row]), str(runs["error"][row])]
             for row in np.flatnonzero(np.asarray(runs["status"]) == ERROR).tolist()]
    return sorted(found, key=lambda error: (error[0], place.get(error[1], 0), error[2]))


def errors_setting(errors: list) -> dict:
    """``settings.json``'s ``engine_errors``: how many runs raised and the first
    :data:`harness.survey.outputs.SHOWN_ERRORS` of them (for the report's survey section)."""
    return {"runs": len(errors), "shown": [list(error) for error in
                                           errors[:outputs.SHOWN_ERRORS]]}


def print_engine_errors(errors: list, out: Path) -> None:
    """Each errored run as an ``ENGINE ERROR:`` line on stderr (the first
    :data:`SHOWN_ENGINE_ERRORS`; the others counted), as ``impact-harness run`` prints its."""
    for pair, family, sample, why in errors[:SHOWN_ENGINE_ERRORS]:
        print(f"ENGINE ERROR: {pair} {family} sample {sample}: {why}", file=sys.stderr)
    if len(errors) > SHOWN_ENGINE_ERRORS:
        print(f"ENGINE ERROR: {len(errors) - SHOWN_ENGINE_ERRORS} more (in "
              f"{out / 'summary.md'} and runs.parquet, status error)", file=sys.stderr)


def check_options(args: argparse.Namespace) -> tuple[list[str], list[str], int]:
    """``(engines, presets, samples)`` of the options, each checked before any work (the
    numbers against :data:`harness.bounds.BOUNDS`, as ``run``'s); ``ValueError`` names the
    first bad one."""
    engines = _names(args.engines, engine_names(), "--engines") or list(engine_names())
    # A preset's shown name (matched-bounce) selects its role for every engine.
    presets = [preset_role(None, name) for name in
               _names(args.preset, preset_choices(), "--preset")] or list(PRESET_ROLES)
    presets = list(dict.fromkeys(presets))
    samples = (QUICK_SAMPLES if args.quick else DEFAULT_SAMPLES) if args.samples is None \
        else args.samples
    for option, value in (("samples", samples), ("workers", args.workers),
                          ("seed", args.seed),
                          ("task-time-limit", getattr(args, "task_time_limit", None))):
        if value is not None:
            bounds.check(f"--{option} {value}", option, value)
    try:
        check_arguments(getattr(args, "executor", "local"), args.workers,
                        getattr(args, "scheduler", None))
    except DaskNotInstalled as error:
        raise ValueError(str(error)) from error
    out = DEFAULT_OUT if args.out is None else Path(args.out)
    problem = (output_directory_problem(out)
               or inner_directory_problem(out, outputs.FIGURES_DIRECTORY)
               or next((f"{name}: {why}" for name in SURVEY_FILES
                        if (why := replaceable_problem(out / name))), None))
    if problem is not None:  # a link at a file it writes: refused now, not after the work
        raise ValueError(f"--out {out}: {problem}")
    return engines, presets, samples


def main(args: argparse.Namespace) -> int:
    try:
        engines, presets, samples = check_options(args)
    except ValueError as error:
        print(f"impact-harness survey: {error}", file=sys.stderr)
        return 2
    left_out = {} if args.preset else default_left_out(engines)
    try:
        overrides = parse_overrides(args.settings_overrides, engines)
    except ValueError as error:
        print(f"impact-harness survey: {error}", file=sys.stderr)
        return 2
    out = DEFAULT_OUT if args.out is None else args.out
    try:
        populations = resolve_populations(args.populations)
    except ScenarioError as error:
        print(f"impact-harness survey: {error}", file=sys.stderr)
        return 2
    if args.out is None and not args.force:
        other = other_survey(out, populations, samples, args.seed, engines, presets, overrides)
        if other:
            print(f"impact-harness survey: {out} holds a survey of {other}; write this one "
                  "elsewhere with --out DIR, or replace it with --force", file=sys.stderr)
            return 2
    pairs, skipped = installed_pairs(engines, presets, left_out)
    settings = {"samples": samples, "seed": args.seed,
                "engines": [r for r in engines if r not in skipped],
                "presets": presets,
                "left_out": {source_label(engine, preset): why
                             for (engine, preset), why in left_out.items()
                             if engine in engines and preset in presets
                             and engine not in skipped},
                "skipped": skipped, "overrides": overrides}
    make_output_directory(out)  # the directory asked for (itself only)
    try:
        streamed = stream.stream_survey(
            populations, samples, args.seed, pairs, out, table_metadata(settings),
            overrides=overrides, workers=args.workers,
            executor=getattr(args, "executor", "local"),
            scheduler=getattr(args, "scheduler", None),
            time_limit_s=getattr(args, "task_time_limit", stream.CHUNK_TIME_LIMIT_S),
            bare=args.bare, progress=not getattr(args, "quiet", False))
    except ScenarioError as error:
        print(f"impact-harness survey: {error} (the chunks done are kept in "
              f"{out / stream.DATASET})", file=sys.stderr)
        return 2
    if streamed["stopped"]:
        for index, why in sorted(streamed["stopped"].items()):
            begin, end = stream.chunk_bounds(samples, len(populations))[index]
            print(f"SURVEY CHUNK STOPPED: chunk {index} (samples {begin}-{end - 1} of every "
                  f"population): {why}", file=sys.stderr)
        print(f"impact-harness survey: {len(streamed['stopped'])} of {streamed['chunks']} "
              f"chunks stopped; the {streamed['chunks'] - len(streamed['stopped'])} done are "
              f"kept in {streamed['dataset']}: the same command runs only the others "
              "(a larger --task-time-limit, or narrower distributions)", file=sys.stderr)
        return EXIT_ENGINE_ERROR
    written = write_streamed(streamed["dataset"], populations, pairs, out, settings,
                             figures=not args.no_figures, wall_s=streamed["wall_s"])
    print(f"wrote {len(written)} files to {out}")
    errors = stream.totals(streamed["dataset"], populations)["errors"]
    if errors:  # the tables are written; the errored runs are in them, in no statistic
        print_engine_errors(errors, out)
        return EXIT_ENGINE_ERROR
    return 0


def write_streamed(dataset: Path, populations, pairs, out: Path, settings: dict, *,
                   figures: bool = True, wall_s: float = 0.0) -> list[Path]:
    """The survey's tables, summary, settings and figures from its dataset
    (harness/survey/stream.py), in bounded memory: the statistics a group at a time, the
    whole tables a chunk file at a time, the figures from the first samples."""
    clock = time.perf_counter
    families = [population.name for population in populations]
    done = stream.totals(dataset, populations)
    impacts = done["impacts"]
    about = table_metadata(settings)
    begin = clock()
    stats = stream.dataset_statistics(dataset, pairs, families)
    statistics_s = clock() - begin
    timings: dict[str, tuple[float, int]] = {
        "sampling": (done["timings"].get("sampling", 0.0), 0),
        "laws (contact terms + solve_batch × 5)": (done["timings"].get("laws", 0.0), 0),
        "verdict terms (once per scene)": (done["timings"].get("verdict terms", 0.0), 0),
        "parts (wall: sampling, laws, engines, verdicts)": (wall_s, impacts * len(pairs)),
    }
    for engine, preset in pairs:
        shown = preset_label(engine, preset)
        for stage in ("engine", "verdicts"):
            timings[f"{stage} {engine} {shown}"] = (
                done["timings"].get(f"{stage} {engine} {preset}", 0.0), impacts)
        for kind in ("steps only", "reset + steps"):
            key = f"bare {engine} {preset} ({kind})"
            if key in done["timings"]:
                timings[f"bare {engine} {shown} ({kind})"] = (done["timings"][key], impacts)
    timings["departures + statistics"] = (statistics_s, impacts * len(pairs))
    written = [stream.concatenate(dataset, [], families, out / "samples.parquet", about,
                                  "samples")]
    if pairs:
        written.append(stream.concatenate(dataset, pairs, families, out / "runs.parquet",
                                          about, "runs"))
        written.append(outputs.write_parquet(stats, out / "statistics.parquet",
                                             {**about, "table": "statistics"}))
    else:
        for stale in ("runs.parquet", "statistics.parquet"):
            (out / stale).unlink(missing_ok=True)
    if figures and pairs:
        begin = clock()
        written += outputs.figures(stream.figure_runs(dataset, pairs, families),
                                   out / "figures")
        timings["figures"] = (clock() - begin, 0)
    summary = out / "summary.md"
    write_text_atomically(summary, outputs.summary_markdown(
        stats, done["rejections"], timings, settings, skipped_runs=done["skipped_runs"],
        engine_errors=done["errors"]))
    shown = {**settings, "families": families, "engine_errors": errors_setting(done["errors"])}
    settings_path = out / SETTINGS_FILE
    write_text_atomically(settings_path, json.dumps(shown, indent=1) + "\n")
    return written + [summary, settings_path]


def other_survey(out: Path, populations, samples: int, seed: int, engines, presets,
                 overrides: dict) -> str:
    """What differs between the survey in ``out`` and the one asked for, as a phrase
    (``"samples 20 (asked: 1000)"``); "" when ``out`` holds none, or the same survey."""
    try:
        found = json.loads((out / SETTINGS_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return ""
    if not isinstance(found, dict):
        return ""
    asked = {"families": [p.name for p in populations], "samples": samples, "seed": seed,
             "engines": list(engines), "presets": list(presets), "overrides": overrides}
    found.setdefault("overrides", {})
    found["engines"] = list(found.get("engines", [])) + list(found.get("skipped", {}))
    differ = [f"{key} {json.dumps(found.get(key))} (asked: {json.dumps(value)})"
              for key, value in asked.items()
              if (sorted(found.get(key) or []) if isinstance(value, list) else found.get(key))
              != (sorted(value) if isinstance(value, list) else value)]
    return "; ".join(differ)
