"""The departure does not depend on the frame (docs/verdicts.md, 'A frame-free departure').

Every shipped ``bodies`` scenario point is boosted (a common velocity added to every free
body: only without ground, where that is a symmetry) and rotated (the scene, the contact
normal and, with ground, the ground itself turned by an angle), and both. The laws are
solved in each frame; every departure between two laws must stay the same to 1e-12
(absolute, on departures of order 0.01 to 1: the solves in a turned frame differ by rounding
of a few ulps of each speed).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.run import metrics
from harness.scenarios import load_scenarios
from harness.scene import geometry
from planar_impact import builders

BODIES = [s for s in load_scenarios() if s.system == "bodies"]
CASES = [pytest.param(s, p, id=f"{s.name}-{p.index}") for s in BODIES for p in s.point_list()]
TOLERANCE = 1e-12
BOOST = np.array([5.0, -3.0])  # m/s, added to every free body
ANGLE = 0.7  # rad


def turned(vector, angle):
    return tuple(geometry.rotation(angle) @ np.asarray(vector, dtype=float))


def problem_in_frame(scene, boost, angle):
    """The scene's impact seen in a frame moving at ``-boost`` and turned by ``angle``."""
    contact = geometry.scene_contact(scene)
    bodies = [builders.PlanarBody(mass=b.mass, inertia=b.moment_of_inertia,
                                  position=turned(b.position, angle),
                                  velocity=turned(np.asarray(b.velocity) + boost, angle),
                                  angular_velocity=b.angular_velocity)
              for b in scene.bodies]
    point, normal = turned(contact.point, angle), turned(contact.normal, angle)
    if scene.ground:
        return builders.rigid_body_against_ground(bodies[0], point, normal=normal)
    return builders.two_bodies(bodies[0], bodies[1], point, normal)


def all_departures(laws, mu, e, problem, free_bodies):
    """``{(law a, law b): departure of a from b}`` for every pair of laws that solve."""
    speeds = {}
    for law in laws:
        try:
            speeds[law] = problem.solve(mu=mu, e=e, law=law).u_after
        except ValueError:
            continue
    return {(a, b): metrics.departure(problem.mass_matrix, speeds[a], speeds[b], problem.u,
                                      free_bodies=free_bodies)
            for a in speeds for b in speeds if a < b}


@pytest.mark.parametrize("scenario, point", CASES)
def test_departures_between_laws_are_unchanged_by_boost_and_rotation(scenario, point):
    fixed = scenario.at(point)
    mu, e = fixed.friction, fixed.restitution
    scene = scenario.scene(point)
    free = not scene.ground
    reference = all_departures(scenario.laws, mu, e,
                               problem_in_frame(scene, np.zeros(2), 0.0), free)
    frames = [(np.zeros(2), ANGLE)]
    if not scene.ground:  # a boost is a symmetry only without the fixed ground
        frames += [(BOOST, 0.0), (BOOST, ANGLE)]
    assert reference
    for boost, angle in frames:
        moved = all_departures(scenario.laws, mu, e, problem_in_frame(scene, boost, angle),
                               free)
        assert moved.keys() == reference.keys()
        for pair, value in reference.items():
            assert math.isclose(moved[pair], value, rel_tol=0.0, abs_tol=TOLERANCE), (
                pair, boost.tolist(), angle, value, moved[pair])


def test_the_ground_frame_norm_was_not_frame_free():
    """The defect the frame-free scale fixes: ``‖u_before‖_M`` of two free bodies changes
    under a boost, so the old departure moved with the frame."""
    scenario = next(s for s in BODIES if s.name == "two-disks-off-centre")
    scene = scenario.scene(scenario.point_list()[0])
    still = problem_in_frame(scene, np.zeros(2), 0.0)
    moving = problem_in_frame(scene, BOOST, 0.0)
    assert metrics.ke_norm(still.mass_matrix, still.u) != pytest.approx(
        metrics.ke_norm(moving.mass_matrix, moving.u), rel=1e-3)
    assert metrics.frame_free_scale(still.mass_matrix, still.u, free_bodies=True) == (
        pytest.approx(metrics.frame_free_scale(moving.mass_matrix, moving.u,
                                               free_bodies=True), rel=1e-13))
