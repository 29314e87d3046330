"""A large library's files checked on forked workers (``load_scenarios_reporting(...,
workers=2)``): the same scenarios and the same errors, word for word and in the same order,
as checked one by one in this process."""

from __future__ import annotations

import shutil

import pytest

from harness.bench import many_scenarios
from harness.scenarios import SCENARIO_DIR, checks, library
from harness.scenarios.library import load_scenarios_reporting


def bad_files(directory):
    """Files with problems of every stage: unreadable, not UTF-8, not TOML, bad keys and
    values, a physics check failing (a tilted sweep without its opt-in), a name used twice."""
    (directory / "a-directory.toml").mkdir()
    (directory / "b-latin1.toml").write_bytes(b'name = "x\xe9"\n')
    (directory / "c-not-toml.toml").write_text("name = [unclosed\n", encoding="utf-8")
    disk = (SCENARIO_DIR / "disk-oblique.toml").read_text(encoding="utf-8")
    (directory / "d-bad-values.toml").write_text(
        disk.replace('name = "disk-oblique"', 'name = "bad values"\nfrobnicate = 1')
        .replace("friction = ", "friction = -"), encoding="utf-8")
    tilted = (SCENARIO_DIR / "sweep-tilted-rod.toml").read_text(encoding="utf-8")
    (directory / "e-tilted.toml").write_text(tilted.replace("expect_sequence = true", ""),
                                             encoding="utf-8")
    shutil.copy(SCENARIO_DIR / "disk-oblique.toml", directory / "f-first.toml")
    shutil.copy(SCENARIO_DIR / "disk-oblique.toml", directory / "g-same-name.toml")


def described(outcome):
    scenarios, errors = outcome
    return scenarios, [(str(e), e.path, e.key, e.value, e.allowed, e.problem) for e in errors]


@pytest.fixture
def library_dir(tmp_path, monkeypatch):
    """Enough files to fork for, on two workers however many cores the machine has."""
    monkeypatch.setattr(library, "default_workers", lambda: 2)  # where the library looks it up
    directory = tmp_path / "scenarios"
    many_scenarios.write_copies(directory, library.FORKED_CHECKS_MIN_FILES + 10, seed=3)
    bad_files(directory)
    return directory


def test_forked_checks_give_the_scenarios_and_errors_of_checks_in_order(library_dir,
                                                                        monkeypatch):
    forked = []

    def spy(function, items, workers):
        forked.append(len(items))
        return map_forked(function, items, workers)

    map_forked = library.map_forked
    inline = described(load_scenarios_reporting(library_dir, workers=1))
    monkeypatch.setattr(library, "map_forked", spy)
    assert described(load_scenarios_reporting(library_dir, workers=2)) == inline
    assert described(load_scenarios_reporting(library_dir, workers=None)) == inline
    assert forked == [2 * library.PIECES_PER_WORKER] * 2  # the forked path was taken
    scenarios, errors = inline
    assert len(scenarios) == library.FORKED_CHECKS_MIN_FILES + 11
    assert {e[2] for e in errors} >= {None, "name", "friction", "expect_sequence"}
    assert len(errors) > 8  # every bad file's errors, the tilted sweep's one per point


def test_scenarios_checked_on_workers_are_remembered_as_passed(library_dir, tmp_path):
    inline = described(load_scenarios_reporting(library_dir, workers=1))
    try:
        checks.use_passed_checks(tmp_path / "cache")
        assert described(load_scenarios_reporting(library_dir, workers=2)) == inline
        store = checks.use_passed_checks(tmp_path / "cache")  # read back from the file
        assert len(store._load()) == len(inline[0])  # the copy named twice: the same text
        assert described(load_scenarios_reporting(library_dir, workers=2)) == inline
        assert all(s.definition_digest for s in inline[0])
    finally:
        checks.use_passed_checks(None)


def test_the_scenes_the_workers_built_come_back_with_their_scenarios(library_dir):
    scenarios, _ = load_scenarios_reporting(library_dir, workers=2)
    bodies = [s for s in scenarios if not s.analytic_only]
    assert bodies
    for scenario in bodies:
        kept = scenario.kept_scenes()
        assert sorted(kept) == [point.index for point in scenario.point_list()]
        fresh = scenario.located(scenario.path)  # a copy: keeps none
        assert all(fresh.scene(index) == scene for index, scene in kept.items())
