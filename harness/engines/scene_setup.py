"""What the base class works out from a scene alone, before any engine steps it.

The checks every adapter relies on (:func:`check_scene`, :class:`UnsupportedScene`), the
run frame and the start state rewound by free flight (:func:`start_states`,
:class:`StepTiming`), the masses and inertias (:func:`energy_weights`) and what an engine
model depends on (:func:`geometry_key`); the bodies' extents are the scene's
(:func:`harness.scene.features.body_extent`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from harness.engines.run_result import BodyState
from harness.scene import Scene


class UnsupportedScene(ValueError):
    """The engine cannot build this scene (the reason is in the message)."""


@dataclass(frozen=True)
class StepTiming:
    """Where an engine detects contacts within a step, and so where a run starts.

    The bodies start ``approach_steps + lead_steps - overlap`` steps of free flight before
    the touching pose. ``lead_steps = 1`` for an engine that moves before it detects (the
    contact is found after the first move); ``overlap`` (a fraction of a step) makes the
    first detection see a hair of overlap where the engine ignores an exact touch, or be
    short of it. ``recentre_y``: the run frame also centres y when there is no ground.
    """

    lead_steps: float = 0.0
    overlap: float = 0.0
    recentre_y: bool = True


def start_states(scene: Scene, settings: Mapping[str, Any],
                 timing: StepTiming) -> tuple[tuple[float, float], tuple[BodyState, ...]]:
    """``(shift, states)``: the run frame's offset from the scene frame, and every body's
    start state in the run frame (rewound by free flight, see :class:`StepTiming`)."""
    bodies = scene.bodies
    count = len(bodies)
    sum_x = sum_y = 0  # as sum() adds
    for body in bodies:
        sum_x += body.position[0]
        sum_y += body.position[1]
    shift_x = -sum_x / count
    recentre_y = timing.recentre_y
    shift_y = -sum_y / count if recentre_y and not scene.ground else 0.0
    approach = settings["approach_steps"]
    rewind = -((approach + timing.lead_steps) - timing.overlap) * float(settings["time_step"])
    states = []
    for body in bodies:  # free_flight_poses, inlined
        (x, y), (vx, vy), rate = body.position, body.velocity, body.angular_velocity
        x = x + vx * rewind
        y = y + vy * rewind
        if recentre_y:
            y = y + shift_y  # adds 0.0 with ground, as the 3-D adapters always did
        # Plain floats: a value a C setter refuses (a numpy array, say) fails here.
        states.append((float(x + shift_x), float(y), float(body.angle + rate * rewind),
                       float(vx), float(vy), float(rate)))
    return (shift_x, shift_y), tuple(states)


def free_flight_poses(scene: Scene, time_s: float) -> list[tuple[float, float, float]]:
    """Poses ``(x, y, θ)`` of every body after ``time_s`` of free flight (negative: before)."""
    poses = []
    for body in scene.bodies:
        vx, vy = body.velocity
        poses.append(
            (
                body.position[0] + vx * time_s,
                body.position[1] + vy * time_s,
                body.angle + body.angular_velocity * time_s,
            )
        )
    return poses


def ke_norm(scene: Scene, u: Sequence[float] | np.ndarray) -> float:
    """Kinetic-energy norm ``sqrt(uᵀ M u)`` of generalised speeds ``u`` of ``scene``."""
    total = 0.0
    for index, body in enumerate(scene.bodies):
        vx, vy, omega = (float(v) for v in u[3 * index : 3 * index + 3])
        total += body.mass * (vx * vx + vy * vy) + body.moment_of_inertia * omega * omega
    return math.sqrt(total)


def geometry_key(scene: Scene) -> tuple:
    """What an engine model depends on: ground or not, and per body its shape, mass and
    inertia (not its state, ``e`` or ``μ``)."""
    parts = []
    for body in scene.bodies:
        shape = body.shape
        if shape.kind == "disk":
            geometry = (shape.radius,)
        elif shape.kind == "rod":
            geometry = (shape.length, shape.radius)
        elif shape.kind == "ellipse":  # with its stand-in's placement: another polygon
            geometry = (shape.semi_x, shape.semi_y, shape.vertex_at)
        else:
            geometry = tuple(map(tuple, shape.vertices().tolist()))
        parts.append((shape.kind, geometry, float(body.mass), float(body.moment_of_inertia)))
    return (scene.ground, tuple(parts))


def energy_weights(scene: Scene) -> tuple[tuple[float, float], ...]:
    """``(mass, moment of inertia)`` per body."""
    return tuple((body.mass, body.moment_of_inertia) for body in scene.bodies)


def energy_before(scene: Scene, weights: Sequence[tuple[float, float]] | None = None) -> float:
    """Twice the kinetic energy of the scene's input state (the blow-up reference);
    ``weights``: :func:`energy_weights` of the scene when already computed."""
    before = 0.0
    for body, (mass, inertia) in zip(scene.bodies, weights or energy_weights(scene)):
        (ux, uy), uw = body.velocity, body.angular_velocity
        before += mass * (ux * ux + uy * uy) + inertia * uw * uw
    return before


def is_immutable(scene: Scene) -> bool:
    """Whether ``scene`` hashes, i.e. holds only immutable values (tuples, numbers, str)."""
    try:
        hash(scene)
    except TypeError:
        return False
    return True


def check_scene(engine: str, scene: Scene) -> tuple[tuple[float, float], ...]:
    """Raise :class:`UnsupportedScene` unless every adapter can build ``scene``; return its
    :func:`energy_weights` (the masses and inertias checked)."""
    weights = []
    for body in scene.bodies:
        if body.shape.kind not in ("disk", "rod", "box", "polygon", "ellipse"):
            raise UnsupportedScene(f"engine {engine!r}: unknown shape {body.shape.kind!r}")
        if body.shape.kind == "ellipse" and not scene.ground:
            raise UnsupportedScene(f"engine {engine!r}: body {body.name!r}: an ellipse "
                                   "touches only the ground (a scene with ground)")
        if len(body.position) != 2 or len(body.velocity) != 2:
            for name in ("position", "velocity"):
                vector = getattr(body, name)
                if len(vector) != 2:
                    raise UnsupportedScene(
                        f"engine {engine!r}: body {body.name!r} {name} must be (x, y) in the "
                        f"plane, got {tuple(vector)!r}"
                    )
        inertia = body.moment_of_inertia  # computed once: a polygon's is not cheap
        values = (body.mass, inertia, *body.position, body.angle, *body.velocity,
                  body.angular_velocity)
        # A finite sum means finite values (one inf or nan makes it non-finite); only an
        # overflowing sum of finite values needs the values checked one by one.
        finite = math.isfinite(sum(values)) or all(math.isfinite(v) for v in values)
        if not finite or body.mass <= 0 or inertia <= 0:
            raise UnsupportedScene(
                f"engine {engine!r}: body {body.name!r} needs finite state and positive mass "
                f"and inertia (mass {body.mass}, inertia {inertia})"
            )
        weights.append((body.mass, inertia))
    if not (0.0 <= scene.restitution <= 1.0) or scene.friction < 0:
        raise UnsupportedScene(
            f"engine {engine!r}: needs 0 <= e <= 1 and μ >= 0, got e {scene.restitution}, "
            f"μ {scene.friction}"
        )
    return tuple(weights)

