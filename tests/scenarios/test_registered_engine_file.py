"""A scenario file may name an engine registered at run time (issue 26): its ``engines``
list is checked against the registry when the file is read, so the toy of
tests/engines/toy_engine.py (the ``toy_engine`` fixture of tests/conftest.py) is allowed
while it is registered and refused, with the file, the field, the value and the registered
names, when it is not."""

from __future__ import annotations

import pytest

from harness.engines import engine_names
from harness.run import runner
from harness.scenarios import SCENARIO_DIR, ScenarioError, load_scenario

# disk-direct with an engines line naming the toy
TOY_FILE = (SCENARIO_DIR / "disk-direct.toml").read_text(encoding="utf-8").replace(
    'friction = 0.3\n', 'friction = 0.3\nengines = ["toy"]\n', 1)


def write_toy_file(directory):
    assert 'engines = ["toy"]' in TOY_FILE  # the library file still has the line replaced
    path = directory / "disk-direct-toy.toml"
    path.write_text(TOY_FILE, encoding="utf-8")
    return path


def test_a_file_naming_the_registered_toy_reads_and_runs(tmp_path, toy_engine):
    scenario = load_scenario(write_toy_file(tmp_path))
    assert scenario.engines == (toy_engine,)
    records = runner.run([scenario], cache=None, workers=1, log=None).records
    runs = [r for r in records if r.source != "analytic"]
    assert {(r.source, r.preset) for r in runs} == {(toy_engine, "defaults"),
                                                    (toy_engine, "accurate")}
    assert all(r.status == "ok" for r in runs)


def test_a_file_naming_an_engine_not_registered_names_the_file_field_value_and_allowed(
        tmp_path):
    path = write_toy_file(tmp_path)
    assert "toy" not in engine_names()
    with pytest.raises(ScenarioError) as raised:
        load_scenario(path)
    message = str(raised.value)
    assert path.name in message and "engines" in message and "'toy'" in message
    assert ", ".join(engine_names()) in message  # the registered engines, as allowed


def test_the_library_reads_the_same_with_the_toy_registered_beside_it():
    """A file naming no engines runs every registered one; its definition (and digest)
    spells which. With the shipped engines alone it is the library's as shipped."""
    from harness import engines as registry
    from tests.engines.toy_engine import ToyEngine

    shipped = load_scenario(SCENARIO_DIR / "disk-direct.toml")
    assert shipped.engines == registry.ENGINE_NAMES
    registry.register_engine("toy", ToyEngine)
    try:
        with_toy = load_scenario(SCENARIO_DIR / "disk-direct.toml")
    finally:
        registry.unregister_engine("toy")
    assert with_toy.engines == (*registry.ENGINE_NAMES, "toy")
    assert with_toy.definition_digest != shipped.definition_digest
    assert load_scenario(SCENARIO_DIR / "disk-direct.toml").definition_digest == \
        shipped.definition_digest
