"""pybullet's ``run_many``: many impacts in one client, the runs of ``run`` bit for bit.

A batch puts each impact in its own slice of the engine's y (out of the scene's plane): the
x-z arithmetic is the lone run's, the slices never meet in the broad phase, and the
impacts share only the static plane, which joins no simulation islands. ``EngineRun``
equality compares every field but the wall time (velocities, status, steps, contact records
with their impulses and poses, energies, drift) as exact floats.
"""

from __future__ import annotations

import pytest

pytest.importorskip("pybullet", reason="pybullet not installed (pip install pybullet==3.2.7)")

from harness.engines import Status, load_engine  # noqa: E402
from harness.engines.pybullet import adapter, clients  # noqa: E402
from harness.scenarios.library import load_scenarios  # noqa: E402
from harness.scene.reference import reference_scenes  # noqa: E402
from harness.survey.population import resolve_populations  # noqa: E402
from harness.survey.sampling import sample_population  # noqa: E402

SAMPLES = 40  # per population: more than MANY_IMPACTS ground and two-body scenes each
PRESETS = ("defaults", "accurate")


@pytest.fixture(scope="module")
def engine():
    engine = load_engine("pybullet")
    yield engine
    engine.close()


@pytest.fixture(scope="module")
def population_scenes():
    return [sample.scene for population in resolve_populations([])
            for sample in sample_population(population, SAMPLES, seed=3).samples]


def mismatches(scenes, batched, single) -> list[str]:
    assert len(batched) == len(single) == len(scenes)
    return [scene.name for scene, a, b in zip(scenes, batched, single) if a != b]


@pytest.mark.parametrize("preset", PRESETS)
def test_batched_equals_single_on_every_population(engine, population_scenes, preset):
    settings = engine.settings(preset)
    batched = engine.run_many(population_scenes, settings)
    single = [engine.run(scene, settings) for scene in population_scenes]
    assert not mismatches(population_scenes, batched, single)
    # Several batches of each kind (ground scenes and two-body scenes go apart).
    assert sum(scene.ground for scene in population_scenes) > adapter.MANY_IMPACTS
    assert sum(not scene.ground for scene in population_scenes) > adapter.MANY_IMPACTS
    # Not only quick one-point bounces: steps with two points, and (defaults: the early
    # contact and slop biases) impacts still in contact at the step cap, so the batch
    # steps on long after most of its impacts were retired.
    assert any(run.max_contact_points > 1 for run in batched)
    if preset == "defaults":
        assert any(run.status is Status.NO_SEPARATION for run in batched)


@pytest.mark.parametrize("preset", PRESETS)
def test_batched_equals_single_on_the_library_and_reference_scenes(engine, preset):
    scenes = [scene for scenario in load_scenarios()
              if "pybullet" in scenario.engines and not scenario.analytic_only
              for _, scene in scenario.points()]
    scenes += [scene for scene, _, _ in reference_scenes().values()]
    assert len(scenes) > 50
    batched = engine.run_many(scenes, preset=preset)
    single = [engine.run(scene, preset=preset) for scene in scenes]
    assert not mismatches(scenes, batched, single)
    assert all(run.preset == preset for run in batched)


def test_batched_equals_single_at_the_step_cap_and_without_contact(engine, population_scenes):
    scenes = population_scenes[::5]
    for overrides in ({"max_steps": 1}, {"max_steps": 2, "approach_steps": 5.0}):
        batched = engine.run_many(scenes, overrides=overrides)
        single = [engine.run(scene, overrides=overrides) for scene in scenes]
        assert not mismatches(scenes, batched, single)
        assert {run.status for run in batched} & {Status.NO_SEPARATION, Status.NO_CONTACT}


@pytest.mark.parametrize("overrides", [
    {"num_sub_steps": 2, "time_step": 1.0 / 120.0},  # kept by a client across resets
    {"contact_breaking_threshold": 0.05, "approach_steps": 0.5},  # process-wide in Bullet
    {"contact_breaking_threshold": 20.0},  # contacts found farther than adapter._MANY_GAP
])
def test_batched_equals_single_under_other_settings(engine, population_scenes, overrides):
    scenes = population_scenes[::5]
    settings = engine.settings("defaults", overrides)
    batched = engine.run_many(scenes, settings)
    single = [engine.run(scene, settings) for scene in scenes]
    assert not mismatches(scenes, batched, single)


def test_batched_equals_a_fresh_adapters_single_runs(population_scenes):
    # The batch client is emptied and reused for the next batch of its settings, and kept
    # apart from the single runs' clients: a fresh adapter's lone runs are the reference.
    scenes = population_scenes[::7]
    settings = adapter.PybulletEngine().settings("defaults")
    batching = adapter.PybulletEngine()
    try:
        first = batching.run_many(scenes, settings)
        again = batching.run_many(scenes[::-1], settings)[::-1]
    finally:
        batching.close()
    fresh = adapter.PybulletEngine()
    try:
        single = [fresh.run(scene, settings) for scene in scenes]
    finally:
        fresh.close()
    assert not mismatches(scenes, first, single)
    assert not mismatches(scenes, again, single)


def test_chunks_keep_ground_and_two_body_scenes_apart(engine, population_scenes, plans_of):
    chunks = engine._many_chunks(plans_of(engine, population_scenes, "defaults"))
    assert sorted(index for chunk in chunks for index in chunk) == list(
        range(len(population_scenes)))
    for chunk in chunks:
        assert 0 < len(chunk) <= adapter.MANY_IMPACTS
        assert len({population_scenes[index].ground for index in chunk}) == 1


@pytest.mark.parametrize("count", [1, 2, 5, 8, 32, 33])
def test_slices_keep_their_gap_and_are_made_far_from_the_last(count):
    sizes = [0.05 + 0.37 * ((7 * slot) % 11) for slot in range(count)]
    gap = 1.04
    offsets = clients._slice_offsets(sizes, gap)
    assert len(offsets) == count and offsets[0] == 0.0
    # Every two slices at least their sizes plus the gap apart, to the sums' rounding (they
    # never meet: the gap holds twice the contact threshold with a metre to spare) ...
    along = sorted(range(count), key=offsets.__getitem__)
    for below, above in zip(along, along[1:]):
        assert offsets[above] - offsets[below] >= sizes[below] + sizes[above] + gap - 1e-12
    # ... laid out in bit-reversed order of making (made in order along y, the broad
    # phase's tree became a chain): the second slice made lies in the far half, and with
    # a power of two the k-th made sits at place bit-reversed k.
    place = {slot: rank for rank, slot in enumerate(along)}
    if count > 2:
        assert place[1] >= count // 2
    if count & (count - 1) == 0:
        bits = (count - 1).bit_length()
        assert all(place[slot] == int(format(slot, f"0{bits}b")[::-1] or "0", 2)
                   for slot in range(count))
