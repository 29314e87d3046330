"""The scenario library: files under ``scenarios/``, loaded together, selected by tags."""

from __future__ import annotations

from pathlib import Path
from typing import Iterable

from harness.scenarios import checks
from harness.scenarios.errors import ScenarioError, suggest
from harness.scenarios.model import Scenario
from harness.scenarios.reader import load_scenario
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
        if entry.is_dir():
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


def load_scenarios_reporting(paths_or_dir=None, tags=None
                             ) -> tuple[list[Scenario], list[ScenarioError]]:
    """The good scenarios under ``paths_or_dir`` and one error per problem in the others.

    Like :func:`load_scenarios`, but a bad file costs only itself: the runner runs the good
    files and reports the bad ones (each error is one line naming the file, the key, the
    value and what is allowed). A scenario whose name another file already used is an error
    and is left out. An unknown tag is an error and selects nothing.
    """
    scenarios, errors = [], []
    for path in scenario_files(paths_or_dir):
        try:
            scenario = load_scenario(path)
        except ScenarioError as error:
            errors += error.errors
            continue
        scenarios.append(scenario)
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
            errors.append(ScenarioError(f"no scenario has this tag{suggest(tag, known)}",
                                        key="tags", value=tag,
                                        allowed=", ".join(sorted(known))))
    return [s for s in unique if set(s.tags) & set(wanted)], errors


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
