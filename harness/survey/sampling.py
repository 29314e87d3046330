"""Seeded sampling of a population into :class:`harness.scene.Scene` objects.

Sample ``i`` of population ``P`` at seed ``s`` is drawn from its own generator,
``numpy.random.default_rng([s, crc32(P.name), i])``: it does not depend on how many samples
are asked for, nor on the other populations. A draw that fails a check is redrawn from the
same generator and counted under its reason (:data:`REJECTIONS`); nothing is dropped
silently. The checks are a scenario point's (harness/scenarios/checks.py): the bodies touch
(|gap| within the default gap tolerance), at one point (no second closest point within the
one-point tolerance) and approach (``v_n < 0``).

Placement. A ground body is turned by its angle and lowered onto ``y = 0``. Body A of a
two-body scene sits at the origin; body B is brought towards it along the placement
direction until they touch. The distance between two convex bodies is a convex function of
B's offset along a line, so Newton's iteration from the separated side converges to the
touching offset without overshoot (and in one step where one feature pair stays in contact).
Velocities are given in the contact frame found there: B's centre of mass moves at
``speed · (sin d · t − cos d · n)`` relative to A, which is at rest apart from its spin.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, field

import numpy as np

from harness.scenarios.errors import ScenarioError
from harness.scenarios.schema import DEFAULT_GAP_TOLERANCE, ONE_POINT_TOLERANCE
from harness.scene import Body, Box, Disk, Polygon, Rod, Scene, geometry
from harness.survey.population import Population

#: Why a draw was redrawn: reason -> what failed.
REJECTIONS = {
    "no-touch": "the bodies could not be placed touching within the gap tolerance",
    "two-points": "a second closest point within the one-point tolerance (a face lies flat)",
    "not-approaching": "the contact point's normal velocity is not negative",
}
#: Newton iterations allowed for the touching offset; each is exact for a vertex-face pair.
_PLACEMENT_ITERATIONS = 60
#: Gap (m) at which the placement stops: far below the 1e-6 m gap tolerance of scenarios.
_PLACEMENT_GAP = 1e-13


@dataclass(frozen=True)
class Sample:
    """One accepted draw: its scene, its contact and the drawn parameters."""

    population: str
    index: int
    scene: Scene
    contact: object  # harness.scene.Contact
    parameters: dict  # name -> drawn value (for the results table)
    attempts: int  # draws this sample took (1 = accepted at once)


@dataclass
class SampleSet:
    """The accepted samples of one population and the rejected draws, by reason."""

    population: Population
    seed: int
    samples: list[Sample] = field(default_factory=list)
    rejections: dict[str, int] = field(default_factory=lambda: {k: 0 for k in REJECTIONS})


def sample_generator(seed: int, population_name: str, index: int) -> np.random.Generator:
    """The generator of sample ``index`` (see the module docstring)."""
    return np.random.default_rng([int(seed), zlib.crc32(population_name.encode()), int(index)])


def _draw(distribution, rng):
    """``distribution.draw(rng)``: the same value from the same generator state, cheaper.

    ``Generator.uniform(low, high)`` is numpy's ``low + (high − low) · U`` with ``U`` the
    generator's next double, which ``Generator.random()`` gives without the argument handling
    that costs three times the draw (tests/survey/test_sampling.py compares every kind).
    """
    kind, values = distribution.kind, distribution.values
    if kind == "uniform":
        low = float(values[0])
        return low + (float(values[1]) - low) * rng.random()
    if kind == "log_uniform":
        low = math.log(values[0])
        return math.exp(low + (math.log(values[1]) - low) * rng.random())
    return distribution.draw(rng)  # fixed (no draw) and choice


def _shape(kind: str, values: dict):
    if kind == "disk":
        return Disk(values["radius"])
    if kind == "rod":
        return Rod(values["length"], values["radius"])
    if kind == "box":
        return Box(values["width"], values["height"])
    sides, radius = int(values["sides"]), values["circumradius"]
    # A regular polygon, counter-clockwise about its centre (its centre of mass).
    points = tuple((radius * math.cos(2 * math.pi * k / sides),
                    radius * math.sin(2 * math.pi * k / sides)) for k in range(sides))
    return Polygon(points)


def _draw_body(spec, rng, drawn: dict, mass: float | None = None) -> Body:
    """Draw one body of ``spec``; its drawn parameters go into ``drawn`` under the body's own
    name as the population file writes it (``hex.sides``, ``box.width``)."""
    prefix = spec.name
    values = {key: _draw(distribution, rng) for key, distribution in spec.shape_parameters}
    mass = _draw(spec.mass, rng) if mass is None else mass
    angle_deg = _draw(spec.angle_deg, rng)
    spin = _draw(spec.angular_velocity, rng)
    drawn.update({f"{prefix}.{key}": float(value) for key, value in values.items()})
    drawn.update({f"{prefix}.mass": mass, f"{prefix}.angle_deg": angle_deg,
                  f"{prefix}.angular_velocity": spin})
    return Body(spec.name, _shape(spec.shape, values), float(mass), (0.0, 0.0),
                math.radians(angle_deg), (0.0, 0.0), float(spin))


def _touch(core_a: np.ndarray, radius_a: float, turned_b: np.ndarray, radius_b: float,
           start: float, direction: np.ndarray):
    """Where B touches A along ``direction`` from A's centre (Newton from ``start``, outside):
    B's position and world core there and the cores' separation
    (:func:`geometry.core_separation`).

    On the cores: B's turned core plus its position is its world core
    (:func:`geometry.world_core`) and the gap is the separation less both radii (as
    :func:`geometry.core_contact` finds it), so no body is built and no contact finished
    per step.
    """
    offset = start
    for _ in range(_PLACEMENT_ITERATIONS):
        position = (float(offset * direction[0]), float(offset * direction[1]))
        core_b = turned_b + np.asarray(position, dtype=float)
        separation = geometry.core_separation(core_a, core_b)
        gap = separation[0] - radius_a - radius_b
        if abs(gap) <= _PLACEMENT_GAP:
            break
        closing = float(separation[1] @ direction)  # d gap / d offset
        if not closing > 0.0:
            break
        offset -= gap / closing
    return position, core_b, separation


def _extent(body: Body) -> float:
    if isinstance(body.shape, Disk):  # its core is the centre: hypot 0.0, then the radius
        return 0.0 + float(body.shape.radius)
    core, radius = geometry.local_core(body.shape)
    return float(np.max(np.hypot(core[:, 0], core[:, 1]))) + radius


def _velocity(speed: float, direction_deg: float, normal) -> tuple[float, float]:
    """``speed · (sin d · t − cos d · n)`` with ``t = (n_y, −n_x)``."""
    d = math.radians(direction_deg)
    n_x, n_y = float(normal[0]), float(normal[1])
    t_x, t_y = n_y, -n_x
    return (speed * (math.sin(d) * t_x - math.cos(d) * n_x),
            speed * (math.sin(d) * t_y - math.cos(d) * n_y))


def draw_scene(population: Population, rng):
    """One draw: ``(scene, its exact contact, drawn parameters, rejection reason or None)``.

    The same scenes and contacts as building each body and calling
    :func:`geometry.place_on_ground`, :func:`geometry.body_contact` and
    :func:`geometry.scene_contact`, from the cores those compute
    (tests/survey/test_sampling.py draws both ways and compares them bit for bit).
    """
    drawn: dict = {}
    e = _draw(population.restitution, rng)
    mu = _draw(population.friction, rng)
    speed = _draw(population.speed, rng)
    direction = _draw(population.direction_deg, rng)
    drawn.update(restitution=e, friction=mu, speed=speed, direction_deg=direction)
    if population.ground:
        body = _draw_body(population.bodies[0], rng, drawn)
        turned, radius = geometry.turned_core(body)
        # geometry.place_on_ground: lowered by its lowest point (its world core at the origin).
        lowest = float((turned + np.zeros(2))[:, 1].min()) - radius
        position = (0.0, 0.0 - lowest)
        core = turned + np.asarray(position, dtype=float)
        normal = geometry.GROUND_NORMAL
        body = body.moved(position=position, velocity=_velocity(speed, direction, normal))
        drawn["mass_ratio"] = math.nan
        scene = Scene((body,), float(e), float(mu), ground=True, name=population.name)
        exact = geometry.core_ground_contact(core, radius)
        one_point = geometry.core_ground_contact(core, radius, ONE_POINT_TOLERANCE)
    else:
        body_a = _draw_body(population.bodies[0], rng, drawn)
        ratio = _draw(population.mass_ratio, rng) if population.mass_ratio is not None else None
        body_b = _draw_body(population.bodies[1], rng, drawn,
                           mass=None if ratio is None else ratio * body_a.mass)
        drawn["mass_ratio"] = body_b.mass / body_a.mass
        placement = math.radians(_draw(population.placement_deg, rng))
        drawn["placement_deg"] = math.degrees(placement)
        unit = np.array([math.cos(placement), math.sin(placement)])
        core_a, radius_a = geometry.world_core(body_a)
        turned_b, radius_b = geometry.turned_core(body_b)
        start = 2.0 * (_extent(body_a) + _extent(body_b)) + 1e-3  # surely apart
        position, core_b, separation = _touch(core_a, radius_a, turned_b, radius_b, start, unit)
        exact, one_point = geometry.core_contacts(
            core_a, radius_a, core_b, radius_b,
            (geometry.DEFAULT_TOLERANCE, ONE_POINT_TOLERANCE), separation)
        body_b = body_b.moved(position=position,
                              velocity=_velocity(speed, direction, exact.normal))
        scene = Scene((body_a, body_b), float(e), float(mu), ground=False, name=population.name)
        # Velocities do not move the contact: the one found by the placement is the scene's.
    return scene, exact, drawn, check_scene(scene, exact, one_point.point_count)


def check_scene(scene: Scene, exact=None, one_point_count: int | None = None) -> str | None:
    """The first :data:`REJECTIONS` reason ``scene`` fails, or None when it passes
    (``exact``: the scene's contact at the default tolerance, ``one_point_count``: its
    contact's point count at the one-point tolerance, when already known)."""
    exact = geometry.scene_contact(scene) if exact is None else exact
    if not abs(exact.gap) <= DEFAULT_GAP_TOLERANCE:
        return "no-touch"
    if one_point_count is None:
        one_point_count = geometry.scene_contact(scene, ONE_POINT_TOLERANCE).point_count
    if one_point_count > 1:
        return "two-points"
    vn, _ = geometry.contact_velocity(scene, exact)
    if not vn < 0.0:
        return "not-approaching"
    return None


def sample_population(population: Population, count: int, seed: int) -> SampleSet:
    """``count`` accepted samples of ``population``; raises :class:`ScenarioError` when a
    sample needs more than ``population.max_attempts`` draws (the file names the remedy)."""
    return sample_range(population, 0, count, seed)


def sample_range(population: Population, begin: int, end: int, seed: int) -> SampleSet:
    """Samples ``begin`` to ``end − 1`` of ``population`` (those of :func:`sample_population`:
    each from its own generator) and the draws they rejected. A :class:`ScenarioError` for a
    sample that needs too many draws carries its index as ``sample``."""
    result = SampleSet(population, seed)
    for index in range(begin, end):
        rng = sample_generator(seed, population.name, index)
        reasons: dict[str, int] = {}
        for attempt in range(1, population.max_attempts + 1):  # noqa: B007 - read after the loop
            scene, contact, drawn, reason = draw_scene(population, rng)
            if reason is None:
                break
            result.rejections[reason] += 1
            reasons[reason] = reasons.get(reason, 0) + 1
        else:
            worst = max(reasons, key=reasons.get)
            error = ScenarioError(
                f"sample {index} (seed {seed}) was rejected {population.max_attempts} times, "
                f"mostly {worst!r}: {REJECTIONS[worst]}", path=population.path,
                key="max_attempts", value=population.max_attempts,
                allowed="narrower distributions that give touching, approaching, one-point "
                        "contacts, or a larger max_attempts")
            error.sample = index
            raise error
        result.samples.append(Sample(population.name, index, scene, contact, drawn, attempt))
    return result
