"""Sampling: seeded and reproducible, every sample a touching, approaching one-point contact,
rejected draws counted, a population that cannot be sampled refused with its file named."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from harness.scenarios.errors import ScenarioError
from harness.scenarios.schema import DEFAULT_GAP_TOLERANCE, ONE_POINT_TOLERANCE
from harness.scene import geometry
from harness.survey.population import parse_population, resolve_populations
from harness.survey.sampling import sample_population

COUNT = 12


@pytest.fixture(scope="module")
def sample_sets():
    return {p.name: sample_population(p, COUNT, seed=7) for p in resolve_populations()}


def test_every_sample_touches_at_one_point_and_approaches(sample_sets):
    for sample_set in sample_sets.values():
        assert len(sample_set.samples) == COUNT
        for sample in sample_set.samples:
            scene = sample.scene
            exact = geometry.scene_contact(scene)
            assert abs(exact.gap) <= DEFAULT_GAP_TOLERANCE
            assert geometry.scene_contact(scene, ONE_POINT_TOLERANCE).point_count == 1
            vn, _ = geometry.contact_velocity(scene, exact)
            assert vn < 0.0


def test_drawn_values_lie_in_the_declared_ranges(sample_sets):
    for name, sample_set in sample_sets.items():
        population = sample_set.population
        for sample in sample_set.samples:
            scene = sample.scene
            assert population.friction.low <= scene.friction <= population.friction.high
            assert population.restitution.low <= scene.restitution <= population.restitution.high
            body_b = scene.bodies[-1]
            relative = np.asarray(body_b.velocity) - np.asarray(scene.bodies[0].velocity
                                                                if not scene.ground else 0.0)
            speed = float(np.hypot(*relative))
            # Speed and direction are drawn in the contact frame: |v_B − v_A| is the speed.
            assert population.speed.low * (1 - 1e-12) <= speed <= population.speed.high * (
                1 + 1e-12), name
            if population.mass_ratio is not None:
                ratio = body_b.mass / scene.bodies[0].mass
                assert population.mass_ratio.low <= ratio * (1 + 1e-12)
                assert ratio <= population.mass_ratio.high * (1 + 1e-12)


def test_the_direction_is_measured_from_the_inward_normal(sample_sets):
    for sample_set in sample_sets.values():
        for sample in sample_set.samples:
            scene, normal = sample.scene, np.asarray(sample.contact.normal)
            tangent = np.array([normal[1], -normal[0]])
            velocity = np.asarray(scene.bodies[-1].velocity)
            angle = math.degrees(math.atan2(velocity @ tangent, -(velocity @ normal)))
            assert angle == pytest.approx(sample.parameters["direction_deg"], abs=1e-9)


def test_same_seed_same_scenes_and_sample_i_does_not_depend_on_the_count():
    population = resolve_populations(["disk-rod"])[0]
    first = sample_population(population, 6, seed=11).samples
    again = sample_population(population, 3, seed=11).samples
    other = sample_population(population, 3, seed=12).samples
    assert [s.scene for s in first[:3]] == [s.scene for s in again]
    assert [s.scene for s in other] != [s.scene for s in again]


BOX = """
name = "flat-box"
restitution = 0.5
friction = 0.5
max_attempts = 50
[ground]
[approach]
speed = 1.0
direction_deg = 0.0
[[body]]
name = "box"
shape = "box"
width = 0.4
height = 0.2
mass = 1.0
angle_deg = ANGLE
"""


def test_rejected_draws_are_counted_by_reason():
    # Half the draws lay the box flat on the ground: two contact points, redrawn.
    population = parse_population(tomllib.loads(BOX.replace("ANGLE", "{ choice = [0.0, 30.0] }")))
    sample_set = sample_population(population, 20, seed=1)
    assert all(s.parameters["b.angle_deg"] == 30.0 for s in sample_set.samples)
    assert sample_set.rejections["two-points"] == sum(s.attempts - 1 for s in sample_set.samples)
    assert sample_set.rejections["two-points"] > 0


def test_a_population_that_never_gives_one_point_is_refused_naming_the_file():
    population = parse_population(tomllib.loads(BOX.replace("ANGLE", "0.0")), "flat.toml")
    with pytest.raises(ScenarioError) as caught:
        sample_population(population, 1, seed=1)
    assert caught.value.path == "flat.toml" and caught.value.key == "max_attempts"
    assert "two-points" in str(caught.value)
