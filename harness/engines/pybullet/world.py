"""One impact's world in a pybullet client, and what a step reads of it: the bodies' joint
states (poses and rates in one call per body) and the contact (force, points, normal) from
Bullet's contact points. Both are called at every contact step of every impact, so the
common cases are written out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from harness.engines.contract import RawContacts
from harness.engines.quiet import import_quietly

p = import_quietly("pybullet")  # not `import pybullet as p`: it prints its build time


@dataclass(slots=True)
class _World:
    client: int  # -1 once released (its client may serve another world)
    settings_key: tuple  # the engine settings (which idle clients it may take and give back)
    plane: int | None
    bodies: list[int]
    extents: tuple[float, ...]  # m, body_extent of each body (out-of-plane drift)
    scale: float  # m, size of the scene's bodies (where bodies are parked)
    pair_values: tuple | None = None  # (e, μ) last set
    dirty: bool = True  # contacts may remain from the previous run
    threshold: float = 0.02
    dt: float = 1.0 / 240.0  # s, the world's time step
    offset: float = 0.0  # m, the bases' y (run_many: each impact at its own)
    # Steps taken (one list per client use: a batch's impacts share their batch's), and the
    # velocities read with the poses at step velocities_at: the run reads the poses of a
    # contact step and then often its velocities, which one getJointStates call gives.
    clock: list = field(default_factory=lambda: [0])
    velocities_at: int = -1
    velocities: tuple = ()


_get_states = p.getJointStates
_reset_joints = p.resetJointStatesMultiDof
_JOINTS = (0, 1, 2)


def _read_joints(world: _World) -> tuple:
    """Per body the joints' positions as the scene's ``(x, y, θ)`` (the revolute joint
    turns the other way); the rates, read in the same calls, are kept on the world as
    ``(v_x, v_y, ω)`` for :meth:`PybulletEngine._read_velocities` of the same step.

    Called at every contact step of every impact: one body and two are written out (no
    lists, no loop), the survey's only cases besides none.
    """
    client, bodies = world.client, world.bodies
    (x, v_x, _, _), (z, v_z, _, _), (angle, rate, _, _) = _get_states(bodies[0], _JOINTS,
                                                                       client)
    world.velocities_at = world.clock[0]
    if len(bodies) == 1:
        world.velocities = ((v_x, v_z, -rate),)
        return ((x, z, -angle),)
    (x_b, v_x_b, _, _), (z_b, v_z_b, _, _), (angle_b, rate_b, _, _) = _get_states(
        bodies[1], _JOINTS, client)  # a scene has one body or two
    world.velocities = ((v_x, v_z, -rate), (v_x_b, v_z_b, -rate_b))
    return ((x, z, -angle), (x_b, z_b, -angle_b))


def _set_joints(client: int, bodies, joints) -> None:
    """Every body's joint positions and rates (``_prepare``'s form), one call per body:
    the first reset of a new body's joints is costly per call where a plane is in the
    world, so all three joints go in one call."""
    for uid, (x, v_x, z, v_z, angle, rate) in zip(bodies, joints):
        # Lists: pybullet 3.2.7 crashes (segmentation fault) on tuples of values here.
        _reset_joints(uid, _JOINTS, [[x], [z], [angle]], [[v_x], [v_z], [rate]],
                      physicsClientId=client)


def _contact_of(points, body_b: int, dt: float) -> RawContacts:
    """One impact's contact from its points (``getContactPoints`` tuples, Bullet's order).

    Called at every contact step of every impact: the first point (most steps' only one)
    is written out; the sums start from ``0.0 +`` as a loop from 0.0 would (a -0.0 term
    gives 0.0).
    """
    # Force on body A: normal force along n (the normal on B, towards A) plus the two
    # lateral friction forces along their directions.
    (_, body_a, _, _, _, on_a, _, n, distance, force_n,
     friction_1, direction_1, friction_2, direction_2) = points[0]
    sign = 1.0 if body_a == body_b else -1.0
    n_x, _, n_z = n
    step_normal = 0.0 + force_n
    step_x = 0.0 + sign * (force_n * n_x + friction_1 * direction_1[0]
                           + friction_2 * direction_2[0])
    step_z = 0.0 + sign * (force_n * n_z + friction_1 * direction_1[2]
                           + friction_2 * direction_2[2])
    length = math.hypot(n_x, n_z)
    normal = (sign * n_x / length, sign * n_z / length)
    if len(points) == 1:
        return (((on_a[0], on_a[2], -distance),), normal, (step_x * dt, step_z * dt),
                step_normal * dt)
    contact_points = [(on_a[0], on_a[2], -distance)]
    for cp in points[1:]:
        (_, body_a, _, _, _, on_a, _, n, distance, force_n,
         friction_1, direction_1, friction_2, direction_2) = cp
        sign = 1.0 if body_a == body_b else -1.0
        step_normal += force_n
        step_x += sign * (force_n * n[0] + friction_1 * direction_1[0]
                          + friction_2 * direction_2[0])
        step_z += sign * (force_n * n[2] + friction_1 * direction_1[2]
                          + friction_2 * direction_2[2])
        contact_points.append((on_a[0], on_a[2], -distance))
    return (tuple(contact_points), normal, (step_x * dt, step_z * dt), step_normal * dt)
