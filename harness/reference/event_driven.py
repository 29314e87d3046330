"""Event-driven reference for nearly simultaneous contacts of one body on the ground.

A rigid-body answer for a body whose second feature (box corner, rod end cap) strikes just
after the first: a sequence of single-contact impacts with exact free flight between them.
The harness simulates impact windows without gravity, so free flight is
``x(t) = x0 + v t``, ``θ(t) = θ0 + ω t``; a feature's height is then
``y0 + v_y t + r_y(t) − radius``, with ``r`` rotating at ``ω``, and its next contact is the
first root of that function, found by a sampled bracket and bisection to rounding.

At each impact the single-contact law of :func:`planar_impact.solve` is applied at the
feature's ground point. Features touching the ground *and* approaching at the same instant
(an exactly flat face) are struck one after another in index order, and the result says so
(``simultaneous``): that situation belongs to :mod:`planar_impact.simultaneous`.
docs/multi-contact.md, 'Event-driven reference', describes the method and its limits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import planar_impact as pi
from harness.scene import Body, Scene
from harness.scene.geometry import local_core, turn

# A feature counts as touching when its gap is below this fraction of the body's size: the
# event times are found to rounding (~1e-16 of the size), so 1e-12 separates "touching" from
# "just above the ground" with margin on both sides.
TOUCH_TOLERANCE = 1e-12
# A feature approaches when v_n < -1e-12 × the body's speed scale (rounding of v_n is ~1e-16
# of it; engines' and the laws' velocities are compared to 1e-6 at best).
APPROACH_TOLERANCE = 1e-12


@dataclass(frozen=True)
class ImpactEvent:
    feature: int  # index of the core point (box corner, rod end cap)
    time: float  # s since the start of the scene
    collision_type: int  # the law's type (Poisson/Stronge 1–5; Newton 1–3)
    vn_approach: float
    vt_approach: float
    simultaneous: bool  # another feature touched and approached at the same instant
    # (v_x, v_y, ω) just after this impact: the speeds of the sequence cut here
    # (event_sequence with max_impacts = the impact's number), without running it again.
    speeds_after: tuple[float, float, float]


@dataclass(frozen=True)
class EventSequence:
    """The impacts in order, the final speeds ``(v_x, v_y, ω)`` and pose, and whether the
    sequence ended because every feature separates (``finished``) rather than at a cap."""

    law: str
    events: tuple[ImpactEvent, ...]
    velocity: tuple[float, float]
    angular_velocity: float
    position: tuple[float, float]
    angle: float
    time: float
    finished: bool

    def speeds(self) -> np.ndarray:
        return np.array([*self.velocity, self.angular_velocity])


def _feature_state(body: Body, position, angle):
    points, radius = local_core(body.shape)
    # elementwise, the same bits on every CPU (geometry.turn; a BLAS product is not)
    world = turn(points, angle) + np.asarray(position, dtype=float)
    return world, radius


def _height(points_local, radius, position, angle, velocity, omega, t, k):
    """Height above the ground of feature ``k``'s lowest surface point after free flight t."""
    c, s = math.cos(angle + omega * t), math.sin(angle + omega * t)
    x, y = points_local[k]
    return position[1] + velocity[1] * t + (s * x + c * y) - radius


def _first_contact(points_local, radius, position, angle, velocity, omega, horizon, size):
    """Earliest ``t`` in ``(0, horizon]`` at which a feature reaches the ground from above,
    with its index; ``(None, None)`` if none does."""
    # Samples fine enough that no root pair fits between two of them: the body turns by at
    # most 0.05 rad per sample.
    samples = max(64, math.ceil(abs(omega) * horizon / 0.05) + 1)
    times = np.linspace(0.0, horizon, samples + 1)
    turns = angle + omega * times  # _height's terms as arrays: the same floats
    lifts = position[1] + velocity[1] * times
    # Heights by numpy's cosine and sine, which may differ from math's (that _height takes)
    # by a few ulps: a difference below 4e-15 of the lift and size. They only pick the
    # sample intervals that may bracket a root, with a margin 250 times that; each picked
    # interval is then tested on _height's own values, bit for bit as one scan with math.
    margins = 1e-12 * (size + np.abs(lifts))
    x, y = points_local[:, 0, None], points_local[:, 1, None]
    heights = lifts + (np.sin(turns) * x + np.cos(turns) * y) - radius  # (features, samples + 1)
    maybe = ((heights[:, :-1] > TOUCH_TOLERANCE * size - margins[:-1])
             & (heights[:, 1:] <= margins[1:]))
    first_bracket = {}
    for k, a in zip(*(index.tolist() for index in np.nonzero(maybe))):  # k, then a, in order
        if k in first_bracket:
            continue
        x_k, y_k = (float(v) for v in points_local[k])
        h_low, h_high = (lifts[b] + (math.sin(turns[b]) * x_k + math.cos(turns[b]) * y_k)
                         - radius for b in (a, a + 1))
        # The first sample interval of feature k that starts above the touch tolerance and
        # ends on or below the ground: the bracket of its first root.
        if h_low > TOUCH_TOLERANCE * size and h_high <= 0.0:
            first_bracket[k] = a
    best_time, best_feature = None, None
    # _height's terms as plain floats: the same IEEE operations in the same order as on numpy
    # float64 scalars, bit for bit, without numpy's cost per scalar operation (the bisection
    # takes ~55 steps per root).
    lift, rise, angle, omega = float(position[1]), float(velocity[1]), float(angle), float(omega)
    radius = float(radius)
    for k, a in sorted(first_bracket.items()):
        low, high = float(times[a]), float(times[a + 1])
        if best_time is not None and low >= best_time:  # it cannot strike first
            continue
        x_k, y_k = (float(v) for v in points_local[k])
        for _ in range(200):  # bisection to rounding
            middle = 0.5 * (low + high)
            if middle in (low, high):
                break
            turn = angle + omega * middle  # _height at middle, inline
            if lift + rise * middle + (math.sin(turn) * x_k + math.cos(turn) * y_k) - radius > 0.0:
                low = middle
            else:
                high = middle
        if best_time is None or high < best_time:
            best_time, best_feature = high, k
    return best_time, best_feature


def event_sequence(scene: Scene, law: str = "poisson", max_impacts: int = 1000,
                   horizon: float | None = None, *, shared: dict | None = None) -> EventSequence:
    """Impacts and free flights of one body against the ground until every feature separates.

    ``horizon`` (s) bounds the search for the next contact; by default the time for the body
    to rise by its size at its current upward speed, or one turn when it does not rise.
    ``shared``: a dict the caller passes to the sequences of one scene under several laws,
    which share their start: a flight or an impact problem already worked out for another
    law (the same inputs, bit for bit) is taken from it, not worked out again.
    """
    if not scene.ground:
        raise ValueError("event_sequence: only one body against the ground is built so far")
    body = scene.bodies[0]
    points_local, radius = local_core(body.shape)
    size = float(np.max(np.linalg.norm(points_local, axis=1))) + radius
    position = np.asarray(body.position, dtype=float)
    angle = float(body.angle)
    velocity = np.asarray(body.velocity, dtype=float)
    omega = float(body.angular_velocity)
    clock = 0.0
    events: list[ImpactEvent] = []
    finished = False
    while len(events) < max_impacts:
        world, _ = _feature_state(body, position, angle)
        heights = world[:, 1] - radius
        speed_scale = max(float(np.hypot(*velocity)) + abs(omega) * size, 1e-300)
        struck = False
        touching = [k for k in range(len(world)) if heights[k] <= TOUCH_TOLERANCE * size]
        for k in touching:
            point = np.array([world[k, 0], 0.0])
            problem = pi.builders.rigid_body_against_ground(
                pi.PlanarBody(mass=body.mass, inertia=body.moment_of_inertia,
                              position=tuple(position), velocity=tuple(velocity),
                              angular_velocity=omega), point)
            vn = float(problem.wn @ problem.u)
            if vn >= -APPROACH_TOLERANCE * speed_scale:
                continue
            others = [j for j in touching if j != k and _approach(problem, body, position,
                      velocity, omega, world[j], radius) < -APPROACH_TOLERANCE * speed_scale]
            result = _law_solver(problem, scene.friction, scene.restitution, shared)(law)
            velocity = result.u_after[:2].copy()
            omega = float(result.u_after[2])
            events.append(ImpactEvent(k, clock, result.collision_type, result.vn_approach,
                                      result.vt_approach, bool(others),
                                      (float(velocity[0]), float(velocity[1]), omega)))
            struck = True
            break
        if struck:
            continue
        limit = horizon
        if limit is None:
            rise = velocity[1]
            limit = (2.0 * size / rise) if rise > 0 else 2.0 * math.pi / max(abs(omega), 1e-3)
        when, _feature = _shared(shared, "flight", _first_contact, points_local, radius,
                                 position, angle, velocity, omega, limit, size)
        if when is None:
            finished = True
            break
        position = position + velocity * when
        angle = angle + omega * when
        clock += when
    return EventSequence(law=law, events=tuple(events), velocity=(float(velocity[0]),
                         float(velocity[1])), angular_velocity=omega,
                         position=(float(position[0]), float(position[1])), angle=angle,
                         time=clock, finished=finished)


def _shared(shared: dict | None, tag: str, function, *args):
    """``function(*args)`` (floats and float arrays), kept in ``shared`` under ``tag`` and
    the exact float64 bits of ``args`` when ``shared`` is a dict, and taken from there when
    it holds it (bits, not values: -0.0 and 0.0, equal as keys, may give other answers)."""
    if shared is None:
        return function(*args)
    key = (tag, *(np.shape(arg) for arg in args),
           *(np.asarray(arg, dtype=float).tobytes() for arg in args))
    found = shared.get(key)
    if found is None:
        found = shared[key] = function(*args)
    return found


def _law_solver(problem, mu, e, shared: dict | None):
    """``problem.law_solver(mu=mu, e=e)`` (the problem checked once for every law), kept in
    ``shared``: the sequences of a scene under several laws start with the same impact."""
    return _shared(shared, "impact", _problem_solver, problem.mass_matrix, problem.wn,
                   problem.wt, problem.u, mu, e)


def _problem_solver(mass_matrix, wn, wt, u, mu, e):
    return pi.builders.ImpactProblem(mass_matrix, wn, wt, u).law_solver(mu=mu, e=e)


def _approach(problem, body, position, velocity, omega, feature_point, radius):
    """Normal velocity of the ground point under feature ``feature_point`` (m/s)."""
    r_x = feature_point[0] - position[0]
    return float(velocity[1] + omega * r_x)


@dataclass(frozen=True)
class SequenceOutline:
    """What an engine run of a tilt needs from its reference sequence (``newton-lcp`` at each
    impact, the primary reference): the features it strikes, in order of first strike, and
    the time of its last impact after the first (s)."""

    features: tuple[int, ...]
    last_impact: float
    finished: bool


def sequence_outline(scene: Scene, law: str = "newton-lcp") -> SequenceOutline:
    """The :class:`SequenceOutline` of ``scene``'s event sequence under ``law``."""
    sequence = event_sequence(scene, law)
    features = tuple(dict.fromkeys(event.feature for event in sequence.events))
    last = sequence.events[-1].time if sequence.events else 0.0
    return SequenceOutline(features, float(last), sequence.finished)


def next_strike(body: Body, approach: float) -> tuple[int, float] | None:
    """The first feature of ``body`` (its pose and speeds as given, in free flight) to strike
    the ground, and when (s; 0 for a feature on or below the ground that approaches now);
    None when none does within :func:`event_sequence`'s horizon.

    A strike counts only when the feature meets the ground faster than ``approach`` (m/s,
    > 0): a run's end state carries its engine's rounding, and a resting corner creeping
    down at 1e-7 of the speeds is not another impact.
    """
    points_local, radius = local_core(body.shape)
    size = float(np.max(np.linalg.norm(points_local, axis=1))) + radius
    position = np.asarray(body.position, dtype=float)
    angle, omega = float(body.angle), float(body.angular_velocity)
    velocity = np.asarray(body.velocity, dtype=float)
    world, _ = _feature_state(body, position, angle)

    def normal_speed(k: int, when: float) -> float:
        turn = angle + omega * when
        x, y = points_local[k]
        return float(velocity[1] + omega * (math.cos(turn) * x - math.sin(turn) * y))

    for k in range(len(world)):
        if world[k, 1] - radius <= TOUCH_TOLERANCE * size and normal_speed(k, 0.0) < -approach:
            return k, 0.0
    rise = velocity[1]
    limit = (2.0 * size / rise) if rise > 0 else 2.0 * math.pi / max(abs(omega), 1e-3)
    when, feature = _first_contact(points_local, radius, position, angle, velocity, omega,
                                   limit, size)
    if when is None or normal_speed(feature, when) >= -approach:
        return None
    return int(feature), float(when)
