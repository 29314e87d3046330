"""Adding a scenario never breaks the tests (issue 14, item 6).

``impact-harness new`` writes into the current directory unless told (``--out``,
``--library``) and prints the path. A fresh scenario without ``[expect]`` dropped into a copy
of the library must pass the library's tests (tests/scenarios/test_library.py) and the suite's
invariants (tests/run/test_suite_invariants.py): they check what a scenario declares.
"""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

import pytest

from harness import cli
from harness.engines import engine_names
from harness.run import runner
from harness.scenarios import PRESETS, SCENARIO_DIR, load_scenarios

TESTS = Path(__file__).resolve().parents[1]


def load_module(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def call(test, *args):
    """Run one test function; a skip (nothing declared to check) counts as passing."""
    try:
        test(*args)
    except pytest.skip.Exception:
        pass


def test_new_writes_into_the_current_directory_and_prints_the_path(tmp_path, monkeypatch,
                                                                     capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["new", "draft"]) == 0
    written = tmp_path / "draft.toml"
    assert written.exists()
    assert str(written.resolve()) in capsys.readouterr().out
    assert not (SCENARIO_DIR / "draft.toml").exists()


@pytest.mark.parametrize("shape, kind", [("rod", "--ground"), ("box", "--two-body")])
def test_a_fresh_scenario_in_a_copy_of_the_library_passes_its_tests(tmp_path, capsys, shape,
                                                                    kind):
    library = tmp_path / "scenarios"
    shutil.copytree(SCENARIO_DIR, library)
    assert cli.main(["new", "user-draft", "--shape", shape, kind, "--out", str(library)]) == 0
    capsys.readouterr()
    scenarios = load_scenarios([library])
    [fresh] = [s for s in scenarios if s.name == "user-draft"]
    assert not fresh.expect.collision_type and fresh.expect.case is None  # declares nothing

    # The library's tests, applied to the fresh scenario.
    library_tests = load_module(TESTS / "scenarios" / "test_library.py", "library_tests")
    library_tests.SCENARIOS = scenarios
    call(library_tests.test_every_file_validates, fresh.path)
    call(library_tests.test_library_size_and_names_are_unique)
    call(library_tests.test_expected_types_match_the_solver, fresh)
    call(library_tests.test_every_law_is_expected_unless_a_known_issue, fresh)
    for point in fresh.point_list():
        call(library_tests.test_expected_case_matches_table_1_by_hand, fresh, point)
        call(library_tests.test_poisson_type_follows_table_1_by_hand, fresh, point)

    # The suite's invariants over the fresh scenario's runs.
    invariants = load_module(TESTS / "run" / "test_suite_invariants.py", "suite_invariants")
    invariants.SCENARIOS = [fresh]
    runs = (runner.run([fresh], cache=None, workers=1, log=None).records,
            runner.run([fresh], cache=None, workers=1, log=None).records)
    engines = fresh.engines or engine_names()
    sources = [("analytic", None)] + [(engine, preset) for engine in engines
                                      for preset in PRESETS]
    for source, preset in sources:
        call(invariants.test_finite_numbers_or_a_reported_status, runs, fresh.name, source,
             preset)
        call(invariants.test_reruns_are_bit_identical, runs, fresh.name, source, preset)
    call(invariants.test_poisson_and_stronge_never_gain_energy, runs, fresh)
    call(invariants.test_every_engine_case_of_the_library_has_a_record, runs)
