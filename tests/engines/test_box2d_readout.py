"""Box2D's per-step readout: Box2D's structs read at their addresses give what pybox2d's
getters give, and a run measures its first contact's speed as the probe run would.

The adapter reads b2Body, b2ContactEdge and b2Contact (with its b2Manifold) in the layouts it
checks at import, and falls back to the getters when they do not match
(harness/engines/box2d/readout.py): both must give the same runs.
"""

from __future__ import annotations

import importlib
import pkgutil
import struct

import pytest

pytest.importorskip("Box2D", reason="Box2D not installed (pip install box2d==2.3.10)")

from harness.engines import box2d
from harness.engines.box2d import Box2DEngine, manifold, readout, scaling
from harness.engines.box2d import world as box2d_world
from harness.scenarios.library import load_scenarios
from harness.scene.reference import reference_scenes
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

SAMPLES = 8  # per population: 56 impacts, two batches
GETTERS = (readout._state_by_getters, readout._touching_by_getters)


def _box2d_modules() -> list:
    return [importlib.import_module(f"{box2d.__name__}.{info.name}")
            for info in pkgutil.iter_modules(box2d.__path__)]


@pytest.fixture(scope="module")
def population_scenes():
    return [sample.scene for population in resolve_populations([])
            for sample in sample_population(population, SAMPLES, seed=11).samples]


def test_the_pinned_pybox2d_is_read_in_memory():
    # Else every run silently takes the getters' path, several times slower.
    assert readout._IN_MEMORY
    assert readout._READERS[0] is readout._state_in_memory


@pytest.mark.parametrize("name, wrong", [
    ("_BODY", struct.Struct("@16x4f24xf4x3f")),  # the transform 4 bytes late
    ("_BODY_CONTACTS", 128),  # another pointer of the body
    ("_EDGE", struct.Struct("@P8xP8x")),  # other and prev for contact and next
    ("_CONTACT", struct.Struct("@8xI12xP64x2P12x2f2f4x2f2f4x2f2fiI")),  # manifold 4 late
])
def test_the_layout_check_refuses_a_wrong_layout(monkeypatch, name, wrong):
    assert readout._layout_matches()
    monkeypatch.setattr(readout, name, wrong)
    assert not readout._layout_matches()


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_memory_and_getters_give_the_same_runs(monkeypatch, population_scenes, preset):
    in_memory = Box2DEngine()
    settings = in_memory.settings(preset)
    # The library's flat landings (two-point manifolds) and a contact of several steps,
    # under either preset.
    scenes = population_scenes + [scene for scenario in load_scenarios()
                                  if scenario.name in ("flat-box", "flat-rod",
                                                       "flat-box-receding-end")
                                  for _, scene in scenario.points()]
    batched = in_memory.run_many(scenes, settings)
    single = [in_memory.run(scene, settings) for scene in scenes]
    # Every module of the package that reads through _READERS binds it itself.
    reading = [module for module in _box2d_modules() if hasattr(module, "_READERS")]
    assert {box2d_world, manifold} <= set(reading)
    for module in reading:
        monkeypatch.setattr(module, "_READERS", GETTERS)
    by_getters = Box2DEngine()
    assert by_getters.run_many(scenes, settings) == batched
    assert [by_getters.run(scene, settings) for scene in scenes] == single
    # Contact steps of every kind were read: several contacts, two-point manifolds.
    assert max(run.max_contact_points for run in batched) >= 2
    assert sum(run.contact_steps for run in batched) > len(batched)


def test_states_and_contacts_read_in_memory_are_the_getters(population_scenes):
    engine = Box2DEngine()
    settings = engine.settings("defaults")
    compared = 0
    for scene in population_scenes[::4]:
        plan = engine._plan_for(scene, engine._resolve(settings, "defaults", None)[0])
        world = plan.world
        engine._reset(world, plan.prepared)
        for _ in range(3):
            engine._step(world)
            memory = readout._Memory()  # fresh buffers: none made before this step
            for b2_body, address in world.dynamic:
                state = readout._state_in_memory(b2_body, address, memory)
                assert state[:8] == readout._state_by_getters(b2_body, address, memory)[:8]
                touching = readout._touching_in_memory(b2_body, state, memory)
                assert ([readout._used(values) for values in touching]
                        == [readout._used(values) for values in
                            readout._touching_by_getters(b2_body, state, memory)])
                compared += len(touching)
            # The world's contacts are its body B's (the readout walks that body's list).
            assert ([readout._used(values) for values in readout._touching_in_memory(
                world.body_b, readout._state_in_memory(world.body_b, world.body_b_id,
                                                       memory), memory)]
                    == [readout._used(readout._contact_values(contact))
                        for contact in world.world.contacts if contact.touching])
    assert compared > 0


def test_the_speed_box2d_saw_is_the_computed_first_touch_speed(population_scenes):
    # Two methods: Box2D's v_rel read after the run's first collision pass (float32 state,
    # the scaled world, the start 2^-22 extents deep) against first_touch_speed (the scene,
    # double precision). Reason for the tolerance: float32 rounding of the velocities and the
    # lever arm, a few roundings of 6e-8 of the terms' sizes, plus the start depth: the pose
    # is advanced by t = depth / speed, turning a lever arm by ω t.
    engine = Box2DEngine()
    scenes = [entry[0] for entry in reference_scenes().values()] + population_scenes
    runs = engine.run_many(scenes, engine.settings("accurate"))
    for scene, run in zip(scenes, runs):
        speed, bound = scaling.first_touch_speed(scene)
        measured = run.derived["box2d_impact_speed"] / run.derived["velocity_scale"]
        size = sum(abs(body.velocity[0]) + abs(body.velocity[1])
                   + abs(body.angular_velocity) * scaling._extent(scene)
                   for body in scene.bodies)
        turned = (scaling._TOUCH_EXTENTS * scaling._extent(scene) / speed
                  * max(abs(body.angular_velocity) for body in scene.bodies))
        allowed = 1e-6 * size + turned * size + bound
        assert abs(measured - speed) <= allowed, (scene.name, measured, speed, allowed)


def test_the_bare_stepper_does_not_measure():
    engine = Box2DEngine()
    scene = reference_scenes()["rod-45"][0]
    stepper = engine.bare_stepper(scene, engine.settings("defaults"))
    try:
        stepper.reset()
        stepper.step(3)
        assert stepper._world.speed_probe is None
        assert stepper._world.world.contactListener is None
    finally:
        stepper.close()


def _contact_by_geometry(touching: list, world):
    """``_contact_of`` with each contact's geometry from ``_manifold_geometry`` (the
    reference the readout writes out inline)."""
    length, velocity, body_b = world.length, world.velocity, world.body_b_id
    step_x = step_y = 0.0
    points, normal = [], None
    for values in touching:
        count = values[17]
        if not count:
            continue
        padding_a, radius_a, body_a_id = world.fixtures[values[2]]
        padding_b, radius_b, contact_body_b = world.fixtures[values[3]]
        (n_x, n_y), contact_points = manifold._manifold_geometry(
            values, world.start[body_a_id], world.start[contact_body_b], radius_a, radius_b)
        sign = 1.0 if contact_body_b == body_b else -1.0
        for first in range(6, 6 + 4 * count, 4):
            p_n, p_t = values[first], values[first + 1]
            step_x += sign * (p_n * n_x + p_t * n_y)
            step_y += sign * (p_n * n_y - p_t * n_x)
        points += [(x / length, y / length, -(separation + padding_a + padding_b) / length)
                   for x, y, separation in contact_points]
        if normal is None:
            normal = (sign * n_x, sign * n_y)
    if normal is None:
        return None
    step_x, step_y = step_x / velocity, step_y / velocity
    return (tuple(points), normal, (step_x, step_y),
            abs(step_x * normal[0] + step_y * normal[1]))


def test_the_contact_readout_is_the_manifold_geometrys(monkeypatch):
    # More samples than the module's: a face-B manifold (two polygons, the reference face
    # on fixture B) is rare.
    scenes = [sample.scene for population in resolve_populations([])
              for sample in sample_population(population, 30, seed=11).samples]
    kinds = []
    readout_of = manifold._contact_of

    def compared(touching, world):
        raw = readout_of(touching, world)
        assert raw == _contact_by_geometry(touching, world)
        kinds.extend(values[16] for values in touching if values[17])
        return raw

    monkeypatch.setattr(box2d_world, "_contact_of", compared)
    engine = Box2DEngine()
    for preset in ("defaults", "accurate"):
        engine.run_many(scenes, preset=preset)
    # Circle, face-A and face-B manifolds were all read.
    assert set(kinds) == {0, 1, 2}
