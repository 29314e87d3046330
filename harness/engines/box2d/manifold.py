"""A contact's world manifold (normal, points, separations) computed from Box2D's local one.

pybox2d's problem: ``contact.worldManifold`` returned an uninitialised normal here. So
b2WorldManifold::Initialize is redone in Python from the manifold's local fields and the
bodies' poses at the step's start (the poses the manifold was computed at), with the
separations of the skinned shapes: :func:`_manifold_geometry` as the reference,
:func:`_contact_of` written out for every step of every impact, and the approach speed a
PreSolve sees (:func:`_approach_speed`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from harness.engines.box2d.readout import _B2, _CIRCLES, _FACE_A, _READERS
from harness.engines.contract import RawContacts

if TYPE_CHECKING:
    from harness.engines.box2d.world import _Readout

# b2Body::GetLinearVelocityFromWorldPoint and a b2Vec2's fields, SWIG's functions.
_velocity_at = _B2.b2Body_GetLinearVelocityFromWorldPoint
_x_of, _y_of = _B2.b2Vec2_x_get, _B2.b2Vec2_y_get

# ---------------------------------------------------------------------- contact readout
def _manifold_geometry(values: tuple, pose_a: tuple, pose_b: tuple, radius_a: float,
                       radius_b: float) -> tuple[tuple[float, float], list]:
    """``(normal from fixture A to B, points (x, y, separation))`` of a contact, in world
    frame.

    b2WorldManifold::Initialize redone in Python (pybox2d's ``worldManifold`` returned an
    uninitialised normal), with the separations of the skinned shapes (Box2D's, negative
    within the summed skins). ``values``: the contact as :data:`_CONTACT` unpacks it;
    ``pose_a``, ``pose_b``: the bodies' ``(x, y, cos θ, sin θ)`` when the manifold was
    computed (the start of the step: after the step the bodies have moved, which would turn
    a circle pair's normal); ``radius_a``, ``radius_b``: the fixtures' shape radii.
    """
    pa_x, pa_y, ca, sa = pose_a
    pb_x, pb_y, cb, sb = pose_b
    kind, count = values[16], values[17]
    points = []
    if kind == _CIRCLES:
        lx, ly = values[14], values[15]  # the manifold's localPoint
        ax, ay = ca * lx - sa * ly + pa_x, sa * lx + ca * ly + pa_y
        lx, ly = values[4], values[5]  # its point's localPoint
        bx, by = cb * lx - sb * ly + pb_x, sb * lx + cb * ly + pb_y
        dx, dy = bx - ax, by - ay
        distance = math.hypot(dx, dy)
        normal = (dx / distance, dy / distance) if distance > 0.0 else (1.0, 0.0)
        c_ax, c_ay = ax + radius_a * normal[0], ay + radius_a * normal[1]
        c_bx, c_by = bx - radius_b * normal[0], by - radius_b * normal[1]
        points.append((0.5 * (c_ax + c_bx), 0.5 * (c_ay + c_by), distance - radius_a - radius_b))
        return normal, points
    face_a = kind == _FACE_A
    (c_ref, s_ref, p_ref_x, p_ref_y, r_ref) = (ca, sa, pa_x, pa_y, radius_a) if face_a else (
        cb, sb, pb_x, pb_y, radius_b)
    (c_inc, s_inc, p_inc_x, p_inc_y, r_inc) = (cb, sb, pb_x, pb_y, radius_b) if face_a else (
        ca, sa, pa_x, pa_y, radius_a)
    lx, ly = values[12], values[13]  # localNormal
    nx, ny = c_ref * lx - s_ref * ly, s_ref * lx + c_ref * ly
    lx, ly = values[14], values[15]  # localPoint
    plane_x = c_ref * lx - s_ref * ly + p_ref_x
    plane_y = s_ref * lx + c_ref * ly + p_ref_y
    for first in range(4, 4 + 4 * count, 4):
        lx, ly = values[first], values[first + 1]
        qx = c_inc * lx - s_inc * ly + p_inc_x
        qy = s_inc * lx + c_inc * ly + p_inc_y
        height = (qx - plane_x) * nx + (qy - plane_y) * ny
        c_ref_x, c_ref_y = qx + (r_ref - height) * nx, qy + (r_ref - height) * ny
        c_inc_x, c_inc_y = qx - r_inc * nx, qy - r_inc * ny
        points.append((0.5 * (c_ref_x + c_inc_x), 0.5 * (c_ref_y + c_inc_y),
                       height - r_ref - r_inc))
    if not face_a:
        nx, ny = -nx, -ny  # Box2D's normal points from fixture A to fixture B
    return (nx, ny), points


def _approach_speed(values: tuple, view: _Readout, poses: dict | None = None) -> float:
    """The normal approach speed at a touching contact's fastest point, computed as the
    solver computes ``v_rel`` (from the velocities before the step: call from PreSolve).
    ``values``: the contact (:func:`_contact_in`); ``view``: its impact's :class:`_Readout`
    (the fixtures and bodies); ``poses``: the bodies' ``(x, y, cos θ, sin θ)`` by
    :data:`_body_id` when known to be those now (None: read now; a PreSolve inside a
    time-of-impact pass sees other poses than the step's start)."""
    _, radius_a, body_a_id = view.fixtures[values[2]]
    _, radius_b, body_b_id = view.fixtures[values[3]]
    body_a, body_b = view.by_id[body_a_id], view.by_id[body_b_id]
    if poses is None:
        memory = view.memory
        x_a, y_a, sin_a, cos_a = _READERS[0](body_a, body_a_id, memory)[:4]  # the poses now
        x_b, y_b, sin_b, cos_b = _READERS[0](body_b, body_b_id, memory)[:4]
        pose_a, pose_b = (x_a, y_a, cos_a, sin_a), (x_b, y_b, cos_b, sin_b)
    else:
        pose_a, pose_b = poses[body_a_id], poses[body_b_id]
    (normal_x, normal_y), points = _manifold_geometry(values, pose_a, pose_b, radius_a,
                                                      radius_b)
    fastest = 0.0
    for x, y, _ in points:
        # Box2D's own float32 arithmetic, through SWIG's functions (pybox2d's methods and
        # a vector's indexing each add a Python-level call).
        va = _velocity_at(body_a, (x, y))
        vb = _velocity_at(body_b, (x, y))
        approach = -((_x_of(vb) - _x_of(va)) * normal_x + (_y_of(vb) - _y_of(va)) * normal_y)
        if approach > fastest:  # noqa: PLR1730 - as max() kept the first of equals
            fastest = approach
    return fastest



def _speed_after_collide(view: _Readout) -> float | None:
    """The approach speed a PreSolve listener would have measured at the impact's first
    touching contact in the collision pass just made (``b2ContactManager::Collide`` called
    alone, outside a step), or None when none touches.

    b2World::Step begins with that pass (after looking for new pairs, which placing the
    bodies did), and the pass calls PreSolve for every touching contact in the world's
    contact list order, newest first, before any velocity or pose changes: read after it,
    the manifolds, poses and velocities are those PreSolve sees, and no listener (a Python
    call per contact and step, through SWIG's director) is needed. The step that follows
    redoes the pass at the same poses with the same results (the contacts are updated from
    themselves, their impulses still 0). ``view``: the impact's :class:`_Readout`.
    """
    state = _READERS[0](view.body_b, view.body_b_id, view.memory)
    touching = _READERS[1](view.body_b, state, view.memory)  # oldest first
    for values in reversed(touching):
        if values[17]:
            # The poses the bodies were placed at, read then (a collision pass moves none).
            return _approach_speed(values, view, view.start)
    return None


def _contact_of(touching: list, world) -> RawContacts | None:
    """The step's contact of one impact from its ``touching`` Box2D contacts (oldest
    first, as :data:`_CONTACT` tuples); ``world``: its :class:`_World` or :class:`_Slot`
    (scales, body B, the poses at the step's start, the fixtures).

    Each contact's geometry is :func:`_manifold_geometry`'s, written out here (the hot
    path: every step of every impact), operation for operation."""
    length, velocity, body_b = world.length, world.velocity, world.body_b_id
    poses, fixtures = world.start, world.fixtures
    step_x = step_y = 0.0
    points: list = []
    normal = None
    for values in touching:
        # Both points' localPoint and impulses (the second's unused with one point), the
        # manifold's localNormal, localPoint, type and point count.
        (_, _, fixture_a, fixture_b, l0_x, l0_y, n0, t0, l1_x, l1_y, n1, t1, normal_x,
         normal_y, local_x, local_y, kind, count) = values
        if not count:
            continue
        padding_a, radius_a, body_a_id = fixtures[fixture_a]
        padding_b, radius_b, contact_body_b = fixtures[fixture_b]
        pa_x, pa_y, ca, sa = poses[body_a_id]
        pb_x, pb_y, cb, sb = poses[contact_body_b]
        # Overlap of the scene's outlines: the skins are padding, not the bodies.
        padding = padding_a + padding_b
        # The impulse on scene body B (Box2D applies +P to fixture B's body).
        sign = 1.0 if contact_body_b == body_b else -1.0
        if kind == _CIRCLES:
            ax, ay = ca * local_x - sa * local_y + pa_x, sa * local_x + ca * local_y + pa_y
            bx, by = cb * l0_x - sb * l0_y + pb_x, sb * l0_x + cb * l0_y + pb_y
            dx, dy = bx - ax, by - ay
            distance = math.hypot(dx, dy)
            if distance > 0.0:
                n_x, n_y = dx / distance, dy / distance
            else:
                n_x, n_y = 1.0, 0.0
            c_ax, c_ay = ax + radius_a * n_x, ay + radius_a * n_y
            c_bx, c_by = bx - radius_b * n_x, by - radius_b * n_y
            points.append((0.5 * (c_ax + c_bx) / length, 0.5 * (c_ay + c_by) / length,
                           -(distance - radius_a - radius_b + padding) / length))
            # Box2D's tangent is cross(n, 1) = (n_y, -n_x).
            step_x += sign * (n0 * n_x + t0 * n_y)
            step_y += sign * (n0 * n_y - t0 * n_x)
        else:
            if kind == _FACE_A:
                c_ref, s_ref, p_ref_x, p_ref_y, r_ref = ca, sa, pa_x, pa_y, radius_a
                c_inc, s_inc, p_inc_x, p_inc_y, r_inc = cb, sb, pb_x, pb_y, radius_b
            else:
                c_ref, s_ref, p_ref_x, p_ref_y, r_ref = cb, sb, pb_x, pb_y, radius_b
                c_inc, s_inc, p_inc_x, p_inc_y, r_inc = ca, sa, pa_x, pa_y, radius_a
            n_x, n_y = c_ref * normal_x - s_ref * normal_y, s_ref * normal_x + c_ref * normal_y
            plane_x = c_ref * local_x - s_ref * local_y + p_ref_x
            plane_y = s_ref * local_x + c_ref * local_y + p_ref_y
            # Box2D's normal points from fixture A to fixture B: the impulses' normal.
            f_x, f_y = (n_x, n_y) if kind == _FACE_A else (-n_x, -n_y)
            for lx, ly, p_n, p_t in ((l0_x, l0_y, n0, t0), (l1_x, l1_y, n1, t1))[:count]:
                qx = c_inc * lx - s_inc * ly + p_inc_x
                qy = s_inc * lx + c_inc * ly + p_inc_y
                height = (qx - plane_x) * n_x + (qy - plane_y) * n_y
                c_ref_x, c_ref_y = qx + (r_ref - height) * n_x, qy + (r_ref - height) * n_y
                c_inc_x, c_inc_y = qx - r_inc * n_x, qy - r_inc * n_y
                points.append((0.5 * (c_ref_x + c_inc_x) / length,
                               0.5 * (c_ref_y + c_inc_y) / length,
                               -(height - r_ref - r_inc + padding) / length))
                step_x += sign * (p_n * f_x + p_t * f_y)
                step_y += sign * (p_n * f_y - p_t * f_x)
            n_x, n_y = f_x, f_y
        if normal is None:
            normal = (sign * n_x, sign * n_y)
    if normal is None:
        return None
    step_x, step_y = step_x / velocity, step_y / velocity
    return (tuple(points), normal, (step_x, step_y),
            abs(step_x * normal[0] + step_y * normal[1]))
