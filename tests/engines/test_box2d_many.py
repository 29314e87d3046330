"""Box2D's ``run_many`` (many impacts per b2World) gives the runs of ``run`` bit for bit.

``EngineRun`` equality compares every field but the wall time (velocities, status, steps,
contact records, impulses, derived values, notes) as exact floats. The batches put impacts of
different velocity scales, ground and two-body scenes, and impacts of different lengths
side by side (docs/engines.md, Box2D).
"""

from __future__ import annotations

import pytest

pytest.importorskip("Box2D", reason="Box2D not installed (pip install box2d==2.3.10)")

from harness.engines import Status, UnsupportedScene, box2d, load_engine
from harness.scenarios.library import load_scenarios
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

SAMPLES = 30  # per population: 210 impacts, several batches of MANY_CHUNK


@pytest.fixture(scope="module")
def engine():
    return load_engine("box2d")


@pytest.fixture(scope="module")
def population_scenes():
    return [sample.scene for population in resolve_populations([])
            for sample in sample_population(population, SAMPLES, seed=5).samples]


def _library_scenes(engine) -> list:
    """Every scene of the library's scenarios that run Box2D and that it can build."""
    scenes = []
    for scenario in load_scenarios():
        if scenario.analytic_only or (scenario.engines and "box2d" not in scenario.engines):
            continue
        for _, scene in scenario.points():
            try:
                engine.run(scene, preset="accurate")
            except UnsupportedScene:
                continue
            scenes.append(scene)
    return scenes


def _mismatched(engine, scenes, settings) -> list[str]:
    batched = engine.run_many(scenes, settings)
    single = [engine.run(scene, settings) for scene in scenes]
    assert len(batched) == len(single)
    return [scene.name for scene, a, b in zip(scenes, batched, single) if a != b]


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_batched_equals_single_on_every_population(engine, population_scenes, preset,
                                                   plans_of):
    # The populations' samples taken in turn, so that batches of impacts in a row hold
    # ground and two-body scenes together (a batch is a time step's impacts in their order).
    mixed = [population_scenes[index] for start in range(SAMPLES)
             for index in range(start, len(population_scenes), SAMPLES)]
    assert not _mismatched(engine, mixed, engine.settings(preset))
    # The batches are real ones: several chunks, ground and two-body scenes in each.
    chunks = engine._many_chunks(plans_of(engine, mixed, preset))
    assert len(chunks) > 2
    assert any({mixed[index].ground for index in chunk} == {True, False} for chunk in chunks)


def _contiguous_chunks(self, plans) -> list[range]:
    """Batches of MANY_CHUNK impacts in a row, whatever their time steps."""
    return [range(begin, min(begin + box2d.MANY_CHUNK, len(plans)))
            for begin in range(0, len(plans), box2d.MANY_CHUNK)]


def test_batches_of_mixed_velocity_scales_equal_single(monkeypatch, engine, population_scenes):
    # "auto" gives impacts of one batch different Box2D time steps (one world each).
    monkeypatch.setattr(box2d.Box2DEngine, "_many_chunks", _contiguous_chunks)
    worlds = []
    build_many = box2d.Box2DEngine._build_many

    def counting(self, plans):
        batch, views, derived = build_many(self, plans)
        worlds.append(len(batch.worlds))
        return batch, views, derived

    monkeypatch.setattr(box2d.Box2DEngine, "_build_many", counting)
    batched = box2d.Box2DEngine()
    assert not _mismatched(batched, population_scenes, batched.settings("accurate"))
    assert max(worlds) > 2


def test_batches_hold_impacts_of_one_box2d_time_step(engine, population_scenes, plans_of):
    # "auto" gives impacts different velocity scales, so different Box2D time steps: a
    # batch is one world, so it holds the impacts of one time step (the plans' own), every
    # impact in one batch, at most MANY_CHUNK to a batch.
    chunks = engine._many_chunks(plans_of(engine, population_scenes, "accurate"))
    assert sorted(index for chunk in chunks for index in chunk) == list(
        range(len(population_scenes)))
    runs = engine.run_many(population_scenes, preset="accurate")
    assert len({run.derived["box2d_time_step"] for run in runs}) > 2
    for chunk in chunks:
        assert 0 < len(chunk) <= box2d.MANY_CHUNK
        assert len({runs[index].derived["box2d_time_step"] for index in chunk}) == 1


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_batched_equals_single_on_the_library(engine, preset):
    scenes = _library_scenes(engine)
    assert len(scenes) > 20
    assert not _mismatched(engine, scenes, engine.settings(preset))


def test_batched_equals_single_at_the_step_cap_and_without_contact(engine, population_scenes):
    scenes = population_scenes[::7]
    for overrides in ({"max_steps": 1}, {"max_steps": 3, "approach_steps": 20.0}):
        for preset in ("defaults", "accurate"):
            settings = engine.settings(preset, overrides)
            assert not _mismatched(engine, scenes, settings)
            statuses = {run.status for run in engine.run_many(scenes, settings)}
            assert statuses & {Status.NO_SEPARATION, Status.NO_CONTACT}


def test_batched_equals_single_with_sleeping_and_warm_starting(engine, population_scenes):
    # Sleeping, warm starting and time-of-impact sub-steps act per island, with "auto"
    # scales (several worlds a batch).
    scenes = population_scenes[::5]
    overrides = {"allow_sleeping": True, "warm_starting": True, "continuous_physics": True}
    assert not _mismatched(engine, scenes, engine.settings("accurate", overrides))


def test_sub_stepping_runs_one_by_one(population_scenes):
    # sub_stepping leaves a world's step unfinished for the next Step: a lone run then
    # depends on what its world ran before, and shared worlds would mix impacts. run_many
    # runs the impacts in order, as run does: two fresh engines give the same runs.
    scenes = population_scenes[::5]
    batched_engine, single_engine = box2d.Box2DEngine(), box2d.Box2DEngine()
    settings = batched_engine.settings("accurate", {"sub_stepping": True})
    assert batched_engine.run_many(scenes, settings) == [
        single_engine.run(scene, settings) for scene in scenes]


def test_batched_notes_and_derived_come_from_each_impacts_own_run(engine, population_scenes):
    # Every run measures Box2D's impact speed itself: slow impacts get the threshold's
    # note, fast ones none, within one batch.
    scenes = population_scenes[:box2d.MANY_CHUNK]
    runs = engine.run_many(scenes, preset="defaults")
    cleared = [run.derived["restitution_threshold_cleared"] for run in runs]
    assert True in cleared and False in cleared
    for scene, run in zip(scenes, runs):
        slow = run.derived["box2d_impact_speed"] <= box2d.VELOCITY_THRESHOLD
        assert run.derived["restitution_threshold_cleared"] == (not slow)
        assert (box2d.THRESHOLD_NOTE in run.notes) == (slow and scene.restitution > 0)


def test_an_impact_stepped_on_past_its_end_changes_no_other(monkeypatch, engine,
                                                            population_scenes):
    # A batch may step an impact on after its run ended (what stepping impacts ahead
    # undecided would do): its own island, contacts and proxies' pairs never reach another
    # impact's. Here no impact is retired: each steps on awake until its batch ends.
    # defaults: runs of 2 to ~100 steps side by side (accurate's end together, at step 2).
    settings = engine.settings("defaults")
    retired = engine.run_many(population_scenes, settings)
    ended: list = []
    moved = []
    release_many = box2d.Box2DEngine._release_many

    def left_awake(self, batch, slot):
        bodies = batch.slots[slot].bodies
        ended.append((bodies, [tuple(b2_body.position) for b2_body in bodies]))

    def releasing(self, batch):
        moved.extend([tuple(b2_body.position) for b2_body in bodies] != positions
                     for bodies, positions in ended)
        ended.clear()
        release_many(self, batch)

    monkeypatch.setattr(box2d.Box2DEngine, "_retire", left_awake)
    monkeypatch.setattr(box2d.Box2DEngine, "_release_many", releasing)
    awake = box2d.Box2DEngine().run_many(population_scenes, settings)
    assert awake == retired
    # The finished impacts did step on (most moved after their end).
    assert sum(moved) > len(population_scenes) // 2
