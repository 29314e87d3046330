"""``Engine.run_many``: the runs of ``Engine.run``, bit for bit, for every installed engine.

``EngineRun`` equality compares every field but the wall time (velocities, status, contact
records, impulses, energies) as exact floats: a batched impact must be the single impact.
"""

from __future__ import annotations

import pytest

from harness.engines import ENGINE_NAMES, Status, UnsupportedScene
from harness.scene.reference import reference_scenes
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

SAMPLES = 40  # per population: several pymunk chunks of each kind (32 ground, 31 two-body)


@pytest.fixture(scope="module")
def population_scenes():
    return [sample.scene for population in resolve_populations([])
            for sample in sample_population(population, SAMPLES, seed=3).samples]


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_pymunk_batched_equals_single_on_every_population(load_or_skip, population_scenes, preset):
    engine = load_or_skip("pymunk")
    settings = engine.settings(preset)
    batched = engine.run_many(population_scenes, settings)
    single = [engine.run(scene, settings) for scene in population_scenes]
    assert len(batched) == len(single)
    mismatched = [scene.name for scene, a, b in zip(population_scenes, batched, single) if a != b]
    assert not mismatched
    # More than one chunk of each kind, and both kinds interleaved in the input order.
    assert sum(scene.ground for scene in population_scenes) > 32
    assert sum(not scene.ground for scene in population_scenes) > 31


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_every_engine_batched_equals_single_on_the_reference_scenes(load_or_skip, name):
    engine = load_or_skip(name)
    for preset in ("defaults", "accurate"):
        # the scenes it supports: one it refuses (UnsupportedScene) is skipped, as by
        # check_engine and tests/engines/test_contract.py
        single, scenes = [], []
        for scene, _, _ in reference_scenes().values():
            try:
                single.append(engine.run(scene, preset=preset))
            except UnsupportedScene:
                continue
            scenes.append(scene)
        batched = engine.run_many(scenes, preset=preset)
        assert batched == single
        assert all(run.preset == preset for run in batched)


def test_pymunk_batched_step_cap_and_no_contact_equal_single(load_or_skip, population_scenes):
    engine = load_or_skip("pymunk")
    scenes = population_scenes[::10]
    for overrides in ({"max_steps": 1}, {"max_steps": 2, "approach_steps": 5.0}):
        batched = engine.run_many(scenes, overrides=overrides)
        single = [engine.run(scene, overrides=overrides) for scene in scenes]
        assert batched == single
        assert {run.status for run in batched} & {Status.NO_SEPARATION, Status.NO_CONTACT}


def test_run_many_of_nothing_is_empty(load_or_skip):
    assert load_or_skip("pymunk").run_many([]) == []
