"""The contract's per-impact fast paths equal the plain definitions they replace.

``start_states`` and the plan's energy, speed scale and point tolerance are computed in
one pass each (harness/engines/contract.py); these tests hold them to the definitions
(:func:`free_flight_poses`, :func:`energy_before`, :func:`body_extent`), bit for bit.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.engines import contract, load_engine, scene_setup
from harness.engines.contract import StepTiming
from harness.scene import Body, Box, Disk, Polygon, Scene
from harness.scene.reference import reference_scenes
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

TIMINGS = [StepTiming(), StepTiming(lead_steps=1.0, overlap=1e-9, recentre_y=False),
           StepTiming(lead_steps=0.5, overlap=0.25, recentre_y=True)]


@pytest.fixture(scope="module")
def scenes():
    sampled = [sample.scene for population in resolve_populations([])
               for sample in sample_population(population, 6, seed=5).samples]
    return sampled + [scene for scene, _, _ in reference_scenes().values()]


def _start_states_by_definition(scene, settings, timing):
    """The run frame and start states as the contract's docstring defines them."""
    count = len(scene.bodies)
    shift_x = -sum(b.position[0] for b in scene.bodies) / count
    recentre_y = timing.recentre_y and not scene.ground
    shift_y = -sum(b.position[1] for b in scene.bodies) / count if recentre_y else 0.0
    rewind = -((settings["approach_steps"] + timing.lead_steps) - timing.overlap) * float(
        settings["time_step"])
    states = []
    for body, (x, y, angle) in zip(scene.bodies, contract.free_flight_poses(scene, rewind)):
        if timing.recentre_y:
            y = y + shift_y
        states.append((float(x + shift_x), float(y), float(angle), float(body.velocity[0]),
                       float(body.velocity[1]), float(body.angular_velocity)))
    return (shift_x, shift_y), tuple(states)


@pytest.mark.parametrize("timing", TIMINGS)
@pytest.mark.parametrize("approach_steps", [0.0, 3.0])
def test_start_states_are_the_rewound_free_flight(scenes, timing, approach_steps):
    settings = {"time_step": 1.0 / 240.0, "approach_steps": approach_steps}
    for scene in scenes:
        expected = _start_states_by_definition(scene, settings, timing)
        assert contract.start_states(scene, settings, timing) == expected, scene.name


def test_plan_values_equal_their_definitions(scenes):
    pytest.importorskip("pymunk")
    engine = load_engine("pymunk")
    settings = engine.settings("defaults")
    for scene in scenes:
        plan = engine._new_plan(scene, settings, None, None, contract.check_scene("pymunk", scene))
        assert plan.weights == contract.energy_weights(scene)
        assert plan.before == contract.energy_before(scene)
        assert plan.speed_scale == max(1e-300, max(abs(v) for v in scene.state()))
        assert plan.same_point == contract.SAME_POINT_RELATIVE * max(
            max(contract.body_extent(body.shape) for body in scene.bodies), 1e-12)
        assert plan.shift == contract.start_states(scene, settings, engine.timing)[0]


def test_an_adapters_drift_and_run_notes_hooks_are_called():
    # The base skips its own "nothing to say" hooks; an adapter's own must still be called.
    pytest.importorskip("pymunk")
    from harness.engines.pymunk_engine import PymunkEngine

    class Remarking(PymunkEngine):
        def _out_of_plane_drift(self, world) -> float:
            return 2.0e-9

        def _run_notes(self, world) -> tuple[str, ...]:
            return ("remark",)

    triangle = Polygon(((-0.1, -0.05), (0.1, -0.05), (0.0, 0.1)))
    scene = Scene((Body("a", triangle, 2.0, (0.0, 0.05), velocity=(0.1, -1.0)),), 0.5, 0.3,
                  ground=True)
    engine, plain = Remarking(), PymunkEngine()
    for run in (engine.run(scene), *engine.run_many([scene, scene])):
        assert run.out_of_plane_drift == 2.0e-9
        assert run.status == contract.Status.OUT_OF_PLANE
        assert "remark" in run.notes
    alone = plain.run(scene)
    assert alone.out_of_plane_drift is None and "remark" not in alone.notes
    scene_two = Scene((Body("a", Disk(0.1), 1.0, (0.0, 0.0), velocity=(1.0, 0.0)),
                       Body("b", Disk(0.1), 1.0, (0.2, 0.0), velocity=(-1.0, 0.0))), 1.0, 0.0)
    assert plain.run_many([scene_two]) == [plain.run(scene_two)]


@pytest.mark.parametrize("field", ["mass", "position", "angle", "velocity", "angular_velocity",
                                   "inertia"])
@pytest.mark.parametrize("bad", [float("inf"), float("-inf"), float("nan")])
def test_check_scene_refuses_any_non_finite_value(field, bad):
    # The check adds the values first (a finite sum means finite values): one bad value
    # anywhere must still be found.
    good = Body("a", Disk(0.1), 1.0, (0.0, 0.1), velocity=(0.0, -1.0), inertia=0.01)
    value = (bad, 0.0) if field in ("position", "velocity") else bad
    scene = Scene((good.moved(**{field: value}),), 0.5, 0.3, ground=True)
    with pytest.raises(contract.UnsupportedScene, match="finite"):
        contract.check_scene("pymunk", scene)


def test_check_scene_accepts_finite_values_whose_sum_overflows():
    body = Body("a", Disk(0.1), 1.0e308, (0.0, 0.1), velocity=(1.0e308, -1.0), inertia=1.0e308)
    scene = Scene((body,), 0.5, 0.3, ground=True)
    assert contract.check_scene("pymunk", scene) == ((1.0e308, 1.0e308),)


def _extent_by_definition(shape) -> float:
    """Largest distance of a point of ``shape`` from its origin, from its vertices."""
    vertices = shape.vertices()
    return float(np.max(np.hypot(vertices[:, 0], vertices[:, 1])))


def test_remembered_extents_are_each_shapes_own(scenes):
    """body_extent remembers a box's or polygon's extent per shape value: every sampled
    shape's is its own (asked twice: computed, then remembered), and a shape equal in value
    but another object gets the same."""
    shapes = [body.shape for scene in scenes for body in scene.bodies
              if body.shape.kind in ("box", "polygon")]
    assert {shape.kind for shape in shapes} == {"box", "polygon"}
    scene_setup._EXTENTS.clear()
    for shape in shapes:
        assert contract.body_extent(shape) == _extent_by_definition(shape)
        assert contract.body_extent(shape) == _extent_by_definition(shape)
        copy = dataclasses.replace(shape)
        assert copy is not shape and contract.body_extent(copy) == _extent_by_definition(shape)
    assert len(scene_setup._EXTENTS) == len(set(shapes))


def test_a_shape_that_does_not_hash_is_measured_each_time():
    """A polygon whose points are lists cannot be remembered: it is measured every time."""
    shape = Polygon([[0.2, 0.0], [0.0, 0.3], [-0.1, -0.1]])
    with pytest.raises(TypeError):
        hash(shape)
    assert contract.body_extent(shape) == _extent_by_definition(shape)
    shape.points[1][1] = 0.5  # the same object, other vertices: measured again
    assert contract.body_extent(shape) == _extent_by_definition(shape) == pytest.approx(0.5)


def test_the_remembered_extents_are_bounded():
    scene_setup._EXTENTS.clear()
    boxes = [Box(0.1 + index * 1e-3, 0.2) for index in range(scene_setup._MAX_EXTENTS + 5)]
    for box in boxes:
        contract.body_extent(box)
    assert len(scene_setup._EXTENTS) <= scene_setup._MAX_EXTENTS
    assert contract.body_extent(boxes[0]) == _extent_by_definition(boxes[0])
