"""Sampling: seeded and reproducible, every sample a touching, approaching one-point contact,
rejected draws counted, a population that cannot be sampled refused with its file named."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from harness.scenarios.errors import ScenarioError
from harness.scenarios.schema import DEFAULT_GAP_TOLERANCE, ONE_POINT_TOLERANCE
from harness.scene import Body, Scene, geometry
from harness.survey import sampling
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
    assert all(s.parameters["box.angle_deg"] == 30.0 for s in sample_set.samples)
    assert sample_set.rejections["two-points"] == sum(s.attempts - 1 for s in sample_set.samples)
    assert sample_set.rejections["two-points"] > 0


def test_a_population_that_never_gives_one_point_is_refused_naming_the_file():
    population = parse_population(tomllib.loads(BOX.replace("ANGLE", "0.0")), "flat.toml")
    with pytest.raises(ScenarioError) as caught:
        sample_population(population, 1, seed=1)
    assert caught.value.path == "flat.toml" and caught.value.key == "max_attempts"
    assert "two-points" in str(caught.value)


# ------------------------------------------------------------- the straightforward drawing
# sampling.py draws from world cores and computes each contact once; this is the same
# drawing with whole bodies and the geometry functions, as the survey first wrote it. Both
# must give the same samples bit for bit: same scenes, contacts, parameters and rejections.
def reference_touch(body_a, body_b, direction):
    extent = {body: float(np.max(np.hypot(*geometry.local_core(body.shape)[0].T)))
              + geometry.local_core(body.shape)[1] for body in (body_a, body_b)}
    offset = 2.0 * (extent[body_a] + extent[body_b]) + 1e-3
    for _ in range(sampling._PLACEMENT_ITERATIONS):
        moved = body_b.moved(position=(float(offset * direction[0]),
                                       float(offset * direction[1])))
        contact = geometry.body_contact(body_a, moved)
        if abs(contact.gap) <= sampling._PLACEMENT_GAP:
            break
        closing = float(np.asarray(contact.normal) @ direction)
        if not closing > 0.0:
            break
        offset -= contact.gap / closing
    return moved, contact


def reference_body(spec, rng, prefix, drawn, mass=None):
    values = {key: distribution.draw(rng) for key, distribution in spec.shape_parameters}
    mass = spec.mass.draw(rng) if mass is None else mass
    angle_deg = spec.angle_deg.draw(rng)
    spin = spec.angular_velocity.draw(rng)
    drawn.update({f"{prefix}.{key}": float(value) for key, value in values.items()})
    drawn.update({f"{prefix}.mass": mass, f"{prefix}.angle_deg": angle_deg,
                  f"{prefix}.angular_velocity": spin})
    return Body(spec.name, sampling._shape(spec.shape, values), float(mass), (0.0, 0.0),
                math.radians(angle_deg), (0.0, 0.0), float(spin))


def reference_draw_scene(population, rng):
    drawn = {}
    e, mu = population.restitution.draw(rng), population.friction.draw(rng)
    speed, direction = population.speed.draw(rng), population.direction_deg.draw(rng)
    drawn.update(restitution=e, friction=mu, speed=speed, direction_deg=direction)
    if population.ground:
        body = geometry.place_on_ground(
            reference_body(population.bodies[0], rng, population.bodies[0].name, drawn))
        body = body.moved(velocity=sampling._velocity(speed, direction, geometry.GROUND_NORMAL))
        drawn["mass_ratio"] = math.nan
        scene = Scene((body,), float(e), float(mu), ground=True, name=population.name)
        exact = geometry.ground_contact(body)
    else:
        body_a = reference_body(population.bodies[0], rng, population.bodies[0].name, drawn)
        ratio = population.mass_ratio.draw(rng) if population.mass_ratio is not None else None
        body_b = reference_body(population.bodies[1], rng, population.bodies[1].name, drawn,
                                mass=None if ratio is None else ratio * body_a.mass)
        drawn["mass_ratio"] = body_b.mass / body_a.mass
        placement = math.radians(population.placement_deg.draw(rng))
        drawn["placement_deg"] = math.degrees(placement)
        unit = np.array([math.cos(placement), math.sin(placement)])
        body_b, exact = reference_touch(body_a, body_b, unit)
        body_b = body_b.moved(velocity=sampling._velocity(speed, direction, exact.normal))
        scene = Scene((body_a, body_b), float(e), float(mu), ground=False, name=population.name)
    reason = None
    if not abs(exact.gap) <= DEFAULT_GAP_TOLERANCE:
        reason = "no-touch"
    elif geometry.scene_contact(scene, tolerance=ONE_POINT_TOLERANCE).point_count > 1:
        reason = "two-points"
    elif not geometry.contact_velocity(scene, exact)[0] < 0.0:
        reason = "not-approaching"
    return scene, exact, drawn, reason


def contact_bits(contact):
    return (np.asarray(contact.point, dtype=float).tobytes(),
            np.asarray(contact.normal, dtype=float).tobytes(),
            np.float64(contact.gap).tobytes(), contact.point_count)


def assert_same_draws(population, seed, count):
    """Every draw of ``count`` samples, accepted or rejected, both ways."""
    reasons = {"fast": [], "reference": []}
    for index in range(count):
        fast_rng = sampling.sample_generator(seed, population.name, index)
        reference_rng = sampling.sample_generator(seed, population.name, index)
        for _ in range(population.max_attempts):
            scene, contact, drawn, reason = sampling.draw_scene(population, fast_rng)
            expected = reference_draw_scene(population, reference_rng)
            # repr shows every float to the last digit (and the sign of a zero).
            assert repr(scene) == repr(expected[0]) and scene == expected[0]
            assert contact_bits(contact) == contact_bits(expected[1])
            assert repr(drawn) == repr(expected[2])
            assert reason == expected[3]
            reasons["fast"].append(reason)
            reasons["reference"].append(expected[3])
            if reason is None:
                break
        # Both generators are where the next draw would start.
        assert fast_rng.bit_generator.state == reference_rng.bit_generator.state
    return reasons["fast"]


@pytest.mark.parametrize("name", [p.name for p in resolve_populations()])
def test_every_draw_is_the_straightforward_draw_bit_for_bit(name):
    population = resolve_populations([name])[0]
    reasons = []
    for seed in (0, 2026):
        reasons += assert_same_draws(population, seed, 300)
    assert reasons.count(None) == 600


def test_rejected_draws_are_the_straightforward_ones_too():
    # Flat faces (two points: a choice of angles, one an integer) and spins fast enough to
    # lift the touching corner (not approaching), through both paths.
    text = BOX.replace("ANGLE", "{ choice = [0.0, 30.0, 90] }\nangular_velocity = "
                       "{ uniform = [-40, 40] }").replace(
        "direction_deg = 0.0", "direction_deg = { uniform = [-89, 89] }")
    reasons = assert_same_draws(parse_population(tomllib.loads(text)), 3, 200)
    assert {"two-points", "not-approaching", None} <= set(reasons)


def test_cheap_draws_are_the_distributions_own():
    from harness.survey.population import Distribution
    distributions = [Distribution("uniform", (0.0, 1.0)), Distribution("uniform", (-75, 75)),
                     Distribution("uniform", (0.05, 0.3)), Distribution("log_uniform", (0.3, 3.0)),
                     Distribution("log_uniform", (1, 10)), Distribution("fixed", (0.2,)),
                     Distribution("choice", (3, 5, 6, 8))]
    for distribution in distributions:
        fast, reference = np.random.default_rng(5), np.random.default_rng(5)
        for _ in range(2000):
            value = sampling._draw(distribution, fast)
            expected = distribution.draw(reference)
            assert type(value) is type(expected) and repr(value) == repr(expected)
