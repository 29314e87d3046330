"""``impact-harness run``: every scenario through every law and every engine that applies.

::

    impact-harness run                                  # every scenario, every engine, both presets
    impact-harness run --tags quick --engines pymunk --preset accurate
    impact-harness run scenarios/rod-45-slip-reversal.toml --json /tmp/rod.json
    impact-harness run --no-cache --executor dask --scheduler tcp://host:8786
    impact-harness run --set pymunk.iterations=50 --set mujoco.integrator=Euler --json /tmp/x.json

Options are checked before any scenario is read (bad input: one line, exit 2); the run itself
is :func:`harness.run.runner.run`.

Settings overrides
    ``--set ENGINE.KEY=VALUE`` (repeatable, also on ``suite``) overrides one setting in every
    run of that engine, on top of the preset and of the scenario's ``[engine_settings]``. It
    shows where a scenario's overrides do: the record's ``settings_overrides`` (the report's
    labels), the complete settings in the cache key, and the provenance
    (``settings_overrides``; ``engine_settings`` lists the presets as run). A bad engine, key
    or value is bad input, checked before any work.

Cache
    Each engine run is looked up in the result cache (:class:`harness.store.cache.ResultCache`)
    and only the misses run; each scenario's finished records are kept whole
    (:mod:`harness.run.scenario_records`). The cache also remembers which scenario texts
    passed their point checks (:mod:`harness.store.passed_checks`). ``--no-cache``: nothing
    read, nothing kept. The misses travel in chunks of one engine and settings
    (:func:`harness.run.tasks.task_group`), each one :meth:`Engine.run_many` call
    (:func:`harness.run.tasks.engine_chunk`), whose runs equal one :meth:`Engine.run` each bit
    for bit (``--chunk-size 1``: one ``run`` per task). A cache entry that fails
    :func:`harness.run.tasks.check_engine_output` is a miss and is reported.

Bounds
    Each engine task has a time limit (:data:`harness.run.tasks.TASK_TIME_LIMIT_S`,
    ``--task-time-limit``); a task over it gets the status ``"error: time limit: stopped after
    N s ..."`` and the run goes on. The local executor enforces it by ending the worker
    process running the task (:func:`harness.run.executor.run_tasks`; a run without a pool
    then runs its tasks in one child process): a signal never interrupts an engine's step in
    C. Dask workers are not stopped. A chunk gets one task's limit as a whole; a chunk over
    it, or one whose ``run_many`` raises, runs again task by task, each with its own limit, so
    only the task at fault gets the error and the others their results. A task whose worker
    dies (an engine crash) gets ``"error: worker died ..."``. Sweep sizes and engine step caps
    are bounded when the scenario is read (:data:`harness.scenarios.schema.LIMITS`).

Where the results go
    ``--json PATH`` when given. Without it ``reports/results.json``, but only when that file
    is absent or was written from the same selection (files, tags, engines, presets): a run
    of other scenarios refuses (exit 2) rather than silently replace the suite's results;
    ``--force`` replaces it anyway.

Exit status (see :mod:`harness.cli`)
    0 ok; 1 a scenario's ``[expect.gate]`` failed (each failing gate is named on stderr);
    2 bad input: bad options or scenario files (each bad file is one line on stderr; the
    good files still run and their results are written); 3 internal error (a record with
    status ``"error: internal: ..."``, or an exception of the harness itself); 4 an engine
    run ended in an error (an exception of the engine, a time limit): the results are
    written, without it.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Sequence, TextIO

from harness import bounds
from harness.engines import ENGINE_NAMES, engine_names, parse_overrides, preset_choices
from harness.engines.facts import fingerprints_remembered
from harness.run import runner
from harness.run.executor import DaskNotInstalled
from harness.run.executor import check_arguments as check_executor
from harness.run.plan import parse_engines, parse_presets
from harness.run.records import DEFAULT_RESULTS, check_writable, write_result_blocks
from harness.run.runner import RunOutcome
from harness.run.tasks import TASK_TIME_LIMIT_S
from harness.scenarios import PRESETS, parse_tags
from harness.scenarios.checks import use_passed_checks
from harness.scenarios.library import load_scenarios_reporting
from harness.store.cache import ResultCache
from harness.store.cache_directory import default_cache_dir

#: Exit statuses (documented in harness.cli): EXIT_ENGINE_ERROR when an engine run ended in
#: an error (an exception of the engine, a time limit): the results are written, but lack it.
EXIT_OK, EXIT_GATE_FAILED, EXIT_BAD_INPUT, EXIT_INTERNAL, EXIT_ENGINE_ERROR = 0, 1, 2, 3, 4
#: At most this many engine errors are printed one per line (then how many more).
SHOWN_ENGINE_ERRORS = 20


def add_common_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``run`` and ``suite``."""
    parser.add_argument("--tags", default=None,
                        help="comma-separated tags (e.g. quick); scenarios with any of them")
    parser.add_argument("--engines", default=None,
                        help="comma-separated engines, or all (the default: "
                             f"{', '.join(engine_names())})")
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
                 "engines": [name for name in engine_names()
                             if name in parse_engines(args.engines)],
                 "presets": list(parse_presets(args.preset))}
    overrides = getattr(args, "settings_overrides", None)
    if overrides:  # only then: a --set experiment never silently replaces the suite's results
        selection["settings_overrides"] = sorted(overrides)
    return selection


def parse_tags_text(text) -> list[str] | None:
    tags = parse_tags(text)
    return None if tags is None else sorted(tags)


def _describe_selection(selection: dict) -> str:
    files = selection.get("files")
    what = "the whole library" if not files else ", ".join(Path(f).name for f in files[:3]) + (
        f" and {len(files) - 3} more" if len(files) > 3 else "")
    if selection.get("tags"):
        what += f" tagged {','.join(selection['tags'])}"
    engines = selection.get("engines") or engine_names()
    described = (f"{what}; engines {','.join(engines)}; presets "
                 f"{','.join(selection.get('presets') or PRESETS)}")
    if selection.get("settings_overrides"):
        described += f"; --set {' '.join(selection['settings_overrides'])}"
    return described


def _existing_selection(path: Path) -> dict | None:
    """The selection recorded in an existing results file (files before it: the default)."""
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
        recorded = document["provenance"].get("selection")
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None  # unreadable: nothing worth keeping is lost by replacing it
    if recorded is None:  # written before selections were recorded: by the suite
        # the suite then ran the shipped engines, the only ones there were
        recorded = {"files": None, "tags": None, "engines": list(ENGINE_NAMES),
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
    with fingerprints_remembered():
        return _execute(args, json_path=json_path, command=command, log=log, guard=guard)


def _execute(args, *, json_path: Path, command: Sequence[str] | None,
             log: TextIO | None | str, guard: bool) -> tuple[int, RunOutcome | None]:
    log = sys.stderr if log == "stderr" else log
    problem = check_arguments(args, json_path)
    if problem:
        return _fail(problem), None
    selection = selection_of(args)
    if guard and json_path.exists() and not getattr(args, "force", False):
        problem = _other_selection(json_path, selection)
        if problem:
            return _fail(problem), None
    scenarios, errors = _read_scenarios(args, log)
    if not scenarios:
        if not errors:
            print("impact-harness run: no scenario selected", file=sys.stderr)
        return EXIT_BAD_INPUT, None
    cache = None if args.no_cache else ResultCache(root=args.cache_dir)
    try:
        engines = parse_engines(args.engines)
        outcome = runner.run(
            scenarios, engines=engines, presets=parse_presets(args.preset), cache=cache,
            executor=args.executor, workers=args.workers, scheduler=args.scheduler, log=log,
            command=command, time_limit_s=args.task_time_limit, selection=selection,
            overrides=parse_overrides(getattr(args, "settings_overrides", None) or (), engines),
            history=getattr(args, "history", None), chunk_size=getattr(args, "chunk_size", None))
    except ConnectionError as error:  # an unreachable Dask scheduler
        return _fail(str(error)), None
    try:
        write_result_blocks(json_path, outcome.blocks, outcome.provenance, outcome.scenarios)
    except OSError as error:
        print(f"impact-harness run: cannot write {json_path}: {error.strerror or error}; the "
              "engine results are in the cache, a rerun simulates nothing again",
              file=sys.stderr)
        return EXIT_INTERNAL, outcome
    _report(outcome, json_path, len(scenarios), log)
    return _exit_status(outcome, bad_files=bool(errors)), outcome


def _other_selection(json_path: Path, selection: dict) -> str | None:
    """Why ``json_path`` must not be replaced by this run's results: it holds those of
    another selection (None: it may be)."""
    existing = _existing_selection(json_path)
    if existing is None or existing == selection:
        return None
    return (f"{json_path} holds the results of another selection "
            f"({_describe_selection(existing)}); write this run elsewhere with "
            f"--json PATH, or replace them with --force")


def _read_scenarios(args, log: TextIO | None) -> tuple[list, list]:
    """The selected scenarios and the errors of the bad files (each printed, one line). The
    cache also remembers which scenario texts passed the point checks (--no-cache: every
    file is checked again); the files are checked on the local cores (as many as the run's
    workers)."""
    passed = use_passed_checks(None if args.no_cache else (args.cache_dir or default_cache_dir()))
    try:
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
    return scenarios, errors


def _report(outcome: RunOutcome, json_path: Path, scenario_count: int,
            log: TextIO | None) -> None:
    """What was written (to ``log``), the failed gates and the errors (to stderr)."""
    stats = outcome.provenance["cache"]
    if log is not None:
        scenarios = "scenario" if scenario_count == 1 else "scenarios"
        print(f"wrote {json_path}: {outcome.record_count} records from {scenario_count} "
              f"{scenarios}; {stats['simulated']} engine runs simulated, {stats['hits']} from the "
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


def _exit_status(outcome: RunOutcome, *, bad_files: bool) -> int:
    """The run's exit status, the worst first (see the module docstring)."""
    if outcome.internal_errors:
        return EXIT_INTERNAL
    if bad_files:
        return EXIT_BAD_INPUT
    if outcome.engine_errors:
        return EXIT_ENGINE_ERROR
    return EXIT_GATE_FAILED if outcome.failed_gates else EXIT_OK


def main(args) -> int:
    guard = args.json is None
    json_path = DEFAULT_RESULTS if guard else args.json
    status, _ = execute(args, json_path=json_path, guard=guard,
                        command=["impact-harness", "run", *sys.argv[2:]])
    return status


__all__ = ["EXIT_BAD_INPUT", "EXIT_ENGINE_ERROR", "EXIT_GATE_FAILED", "EXIT_INTERNAL",
           "EXIT_OK", "add_arguments", "add_common_arguments", "check_arguments", "execute",
           "main", "selection_of"]
