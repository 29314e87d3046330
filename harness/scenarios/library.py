"""The scenario library: files under ``scenarios/``, loaded together, selected by tags."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

from harness.engines import EngineNotInstalled, engine_names, load_engine
from harness.processes import default_workers, map_forked
from harness.scenarios import checks
from harness.scenarios.errors import OptionError, ScenarioError, suggest
from harness.scenarios.model import Scenario
from harness.scenarios.reader import passed_before, read_scenario_text, scenario_from_text
from harness.scenarios.schema import SCENARIO_DIR


def scenario_files(paths_or_dir=None) -> list[Path]:
    """The ``.toml`` files named by ``paths_or_dir`` (files or directories; default: scenarios/)."""
    if paths_or_dir is None:
        paths_or_dir = [SCENARIO_DIR]
    elif isinstance(paths_or_dir, (str, Path)):
        paths_or_dir = [paths_or_dir]
    files = []
    for entry in paths_or_dir:
        entry = Path(entry)
        try:
            is_directory = entry.is_dir()
        except OSError:  # a name too long, a loop of links: reading it says so, per file
            is_directory = False
        if is_directory:
            files += sorted(entry.glob("*.toml"))
        else:
            files.append(entry)
    return files


def parse_tags(tags) -> tuple[str, ...] | None:
    """``"quick,slip-reversal"`` or an iterable of names -> a tuple; None/empty -> None."""
    if tags is None:
        return None
    if isinstance(tags, str):
        tags = tags.split(",")
    tags = tuple(t.strip() for t in tags if t and t.strip())
    return tags or None


def load_scenarios_reporting(paths_or_dir=None, tags=None, *, workers: int | None = 1
                             ) -> tuple[list[Scenario], list[ScenarioError]]:
    """The good scenarios under ``paths_or_dir`` and one error per problem in the others.

    Like :func:`load_scenarios`, but a bad file costs only itself: the runner runs the good
    files and reports the bad ones (each error is one line naming the file, the key, the
    value and what is allowed). A scenario whose name another file already used is an error
    and is left out. An unknown tag is an error and selects nothing. ``workers`` > 1 (None:
    every local core): the files to check, when there are many, are checked on that many
    forked workers, at most one per local core (the same scenarios and errors, in the same
    order).
    """
    scenarios, errors = [], []
    for outcome in _load_files(scenario_files(paths_or_dir), workers):
        if isinstance(outcome, ScenarioError):
            errors += outcome.errors
        else:
            scenarios.append(outcome)
    checks.passed_checks.save()  # the texts that passed, for the next run (when enabled)
    seen: dict[str, Scenario] = {}
    unique = []
    for scenario in scenarios:
        if scenario.name in seen:
            errors.append(ScenarioError(f"the name is already used by {seen[scenario.name].path}",
                                        path=scenario.path, key="name", value=scenario.name,
                                        allowed="a name unique in the library"))
            continue
        seen[scenario.name] = scenario
        unique.append(scenario)
    wanted = parse_tags(tags)
    if wanted is None or "all" in wanted:
        return unique, errors
    known = tag_sets(unique)
    for tag in wanted:
        if tag not in known:
            errors.append(OptionError(f"no scenario has this tag{suggest(tag, known)}",
                                      key="--tags", value=tag,
                                      allowed=", ".join(sorted(known))))
    return [s for s in unique if set(s.tags) & set(wanted)], errors


#: Fewer files to check than this are checked in this process: forking the workers and
#: sending the scenarios back would cost more than checking them (about a millisecond each).
FORKED_CHECKS_MIN_FILES = 64
#: The files to check are dealt (one each in turn: a library's files of one kind lie
#: together, and a sweep costs its points) into this many pieces per worker.
PIECES_PER_WORKER = 4


def _load_files(files: list[Path], workers: int | None) -> list[Scenario | ScenarioError]:
    """Per file in turn, its :class:`Scenario` or the :class:`ScenarioError` reading it
    raised (:func:`harness.scenarios.reader.load_scenario`): the texts that passed the
    checks before (:data:`harness.scenarios.checks.passed_checks`) taken from there, the
    others checked here or, many of them and ``workers`` > 1, on forked workers."""
    outcomes: list[Scenario | ScenarioError | None] = [None] * len(files)
    to_check = []  # (index, path, text, checks key)
    for index, path in enumerate(files):
        path = Path(path)
        try:
            text = read_scenario_text(path)
        except ScenarioError as error:
            outcomes[index] = error
            continue
        passed, key = passed_before(text, path)
        if passed is not None:
            outcomes[index] = passed
        else:
            to_check.append((index, path, text, key))
    forked = workers != 1 and len(to_check) >= FORKED_CHECKS_MIN_FILES
    if forked:
        workers = min(workers or default_workers(), default_workers())
        forked = workers > 1
    if not forked:
        for index, path, text, key in to_check:
            outcomes[index] = _checked(path, text, key)
        return outcomes
    _load_engines()  # imported here once, not by each worker
    count = min(workers * PIECES_PER_WORKER, len(to_check))
    pieces = [to_check[start::count] for start in range(count)]
    for piece, data in zip(pieces, map_forked(_check_piece, pieces, workers)):
        for (index, _, _, key), (outcome, scenes) in zip(piece, data):
            outcomes[index] = outcome
            if isinstance(outcome, Scenario):  # passed: remembered here, not in the worker
                checks.passed_checks.add(key, outcome)
                outcome.keep_scenes(scenes)
    return outcomes


def _checked(path: Path, text: str, key: str | None) -> Scenario | ScenarioError:
    try:
        return scenario_from_text(text, path, key)
    except ScenarioError as error:
        return error


def _check_piece(piece: list[tuple]) -> list:
    """A worker's outcomes of a piece of :func:`_load_files` (the pool carries them back;
    scenarios' read-only mappings travel as harness/scenarios/checks.py registers), each with
    the scenes its checks built (a scenario's pickle leaves them out; sent, they cost a
    tenth of building them anew)."""
    outcomes = [_checked(path, text, key) for _, path, text, key in piece]
    return [(outcome, outcome.kept_scenes() if isinstance(outcome, Scenario) else {})
            for outcome in outcomes]


def _load_engines() -> None:
    """Import the installed engines' adapters (the checks ask them for settings)."""
    for name in engine_names():
        try:
            load_engine(name)
        except EngineNotInstalled:
            pass


def load_scenarios(paths_or_dir=None, tags=None) -> list[Scenario]:
    """Load every scenario under ``paths_or_dir`` (default: ``scenarios/``).

    ``tags`` (a comma-separated string or an iterable) keeps the scenarios having any of
    them; ``"all"`` keeps everything. Every file is read before any error is raised, and
    the error lists every bad file. Unknown tags and duplicate names are errors too.
    """
    scenarios, errors = load_scenarios_reporting(paths_or_dir, tags)
    if errors:
        raise ScenarioError(errors=errors)
    return scenarios


def tag_sets(scenarios: Iterable[Scenario]) -> dict[str, tuple[str, ...]]:
    """Tag -> scenario names, with the derived set ``"all"`` (every scenario)."""
    scenarios = list(scenarios)
    sets: dict[str, list[str]] = {"all": [s.name for s in scenarios]}
    for scenario in scenarios:
        for tag in scenario.tags:
            sets.setdefault(tag, []).append(scenario.name)
    return {tag: tuple(names) for tag, names in sets.items()}
