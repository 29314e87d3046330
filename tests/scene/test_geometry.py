"""Contact geometry: closed-form distances for simple pairs, flat faces flagged, invariances.

Tolerances: the geometry is a handful of floating-point operations on O(1 m) numbers, so
results agree with the closed forms to a few ulps; ``TOL = 1e-12`` m leaves a wide margin.
Every ``assert_allclose`` passes ``rtol=0``: numpy's default ``rtol=1e-7`` would otherwise
allow a unit normal 1e-7 off, five orders above ``TOL``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness.scene import Body, Box, Disk, Polygon, Rod, Scene
from harness.scene.geometry import (
    body_contact,
    contact_velocity,
    ground_contact,
    lowest_point,
    place_on_ground,
    scene_contact,
    world_core,
)

TOL = 1e-12  # m; see the module docstring


def disk(position, radius=0.1, name="disk", **kw):
    return Body(name, Disk(radius), 1.0, tuple(position), **kw)


def test_disk_disk_off_centre_touching():
    angle = math.radians(30)
    a = disk((0.0, 0.0), 0.1, "a")
    b = disk((0.25 * math.cos(angle), 0.25 * math.sin(angle)), 0.15, "b")
    contact = body_contact(a, b)
    assert contact.gap == pytest.approx(0.0, abs=TOL)
    np.testing.assert_allclose(contact.normal, [math.cos(angle), math.sin(angle)], atol=TOL, rtol=0)
    np.testing.assert_allclose(contact.point, 0.1 * contact.normal, atol=TOL, rtol=0)
    assert contact.point_count == 1


def test_disk_disk_gap_and_overlap_are_signed():
    a = disk((0.0, 0.0), 0.1, "a")
    assert body_contact(a, disk((0.0, 0.3), 0.1, "b")).gap == pytest.approx(0.1, abs=TOL)
    overlap = body_contact(a, disk((0.0, 0.15), 0.1, "b"))
    assert overlap.gap == pytest.approx(-0.05, abs=TOL)
    np.testing.assert_allclose(overlap.normal, [0.0, 1.0], atol=TOL, rtol=0)
    # The point is midway between the two surfaces: y = (0.1 + 0.05) / 2.
    np.testing.assert_allclose(overlap.point, [0.0, 0.075], atol=TOL, rtol=0)


def test_normal_points_from_a_into_b():
    a, b = disk((0.0, 0.0), 0.1, "a"), disk((0.2, 0.0), 0.1, "b")
    np.testing.assert_allclose(body_contact(a, b).normal, [1.0, 0.0], atol=TOL, rtol=0)
    np.testing.assert_allclose(body_contact(b, a).normal, [-1.0, 0.0], atol=TOL, rtol=0)


def test_disk_on_rod_middle_and_end():
    rod = Body("rod", Rod(1.0, 0.02), 1.0, (0.0, 0.0))
    middle = body_contact(rod, disk((0.2, 0.12)))
    assert middle.gap == pytest.approx(0.0, abs=TOL)
    np.testing.assert_allclose(middle.normal, [0.0, 1.0], atol=TOL, rtol=0)
    np.testing.assert_allclose(middle.point, [0.2, 0.02], atol=TOL, rtol=0)
    # Beyond the end cap the normal is radial from the cap centre (0.5, 0).
    direction = np.array([math.cos(0.7), math.sin(0.7)])
    end = body_contact(rod, disk(np.array([0.5, 0.0]) + 0.12 * direction))
    assert end.gap == pytest.approx(0.0, abs=TOL)
    np.testing.assert_allclose(end.normal, direction, atol=TOL, rtol=0)
    assert end.point_count == 1


@pytest.mark.parametrize("angle_deg", [10, 30, 45, 60, 80, 100, 135, -30, -60])
def test_rod_on_ground_at_angles(angle_deg):
    length, radius = 1.0, 0.01
    angle = math.radians(angle_deg)
    rod = Body("rod", Rod(length, radius), 1.0, (0.3, 2.0), angle=angle)
    contact = ground_contact(rod)
    drop = 0.5 * length * abs(math.sin(angle))
    assert contact.gap == pytest.approx(2.0 - drop - radius, abs=TOL)
    np.testing.assert_allclose(contact.normal, [0.0, 1.0])
    placed = ground_contact(place_on_ground(rod))
    assert placed.gap == pytest.approx(0.0, abs=TOL)
    assert placed.point_count == 1
    # The lowest cap centre is the end whose y is lowest; the contact is right below it.
    end_x = 0.3 - math.copysign(1.0, math.sin(angle)) * 0.5 * length * math.cos(angle)
    np.testing.assert_allclose(placed.point, [end_x, 0.0], atol=TOL, rtol=0)


def test_flat_rod_and_flat_box_give_two_points():
    assert ground_contact(place_on_ground(Body("r", Rod(1.0, 0.01), 1.0, (0, 1)))).point_count == 2
    box = place_on_ground(Body("b", Box(0.4, 0.2), 1.0, (0, 1), angle=math.pi / 2))
    contact = ground_contact(box)
    assert contact.point_count == 2
    assert contact.gap == pytest.approx(0.0, abs=TOL)
    np.testing.assert_allclose(contact.point, [0.0, 0.0], atol=TOL, rtol=0)


def test_box_corner_on_ground():
    angle = math.radians(30)
    box = place_on_ground(Body("box", Box(0.2, 0.1), 1.0, (0.0, 1.0), angle=angle))
    contact = ground_contact(box)
    assert contact.point_count == 1
    assert contact.gap == pytest.approx(0.0, abs=TOL)
    corners, _ = world_core(box)
    lowest = corners[np.argmin(corners[:, 1])]
    np.testing.assert_allclose(contact.point, lowest, atol=TOL, rtol=0)
    # Corner (-w/2, -h/2) rotated by 30° is the lowest one.
    expected = np.array([-0.1 * math.cos(angle) + 0.05 * math.sin(angle), 0.0])
    np.testing.assert_allclose(contact.point, expected, atol=TOL, rtol=0)


def test_box_face_on_box_face_gives_two_points_and_corner_gives_one():
    a = Body("a", Box(0.4, 0.2), 1.0, (0.0, 0.0))
    b = Body("b", Box(0.2, 0.2), 1.0, (0.05, 0.2))
    contact = body_contact(a, b)
    assert contact.point_count == 2
    assert contact.gap == pytest.approx(0.0, abs=TOL)
    np.testing.assert_allclose(contact.normal, [0.0, 1.0], atol=TOL, rtol=0)
    np.testing.assert_allclose(contact.point, [0.05, 0.1], atol=TOL, rtol=0)
    # B turned by 45° rests on A's top face with one corner.
    half_diagonal = 0.1 * math.sqrt(2.0)
    corner = Body("b", Box(0.2, 0.2), 1.0, (0.05, 0.1 + half_diagonal), angle=math.pi / 4)
    contact = body_contact(a, corner)
    assert contact.point_count == 1
    assert contact.gap == pytest.approx(0.0, abs=TOL)
    np.testing.assert_allclose(contact.point, [0.05, 0.1], atol=TOL, rtol=0)


def test_overlapping_boxes_report_penetration():
    a = Body("a", Box(0.4, 0.2), 1.0, (0.0, 0.0))
    b = Body("b", Box(0.2, 0.2), 1.0, (0.0, 0.17))
    contact = body_contact(a, b)
    assert contact.gap == pytest.approx(-0.03, abs=TOL)
    np.testing.assert_allclose(contact.normal, [0.0, 1.0], atol=TOL, rtol=0)


def test_polygons():
    triangle = Polygon(((-0.1, -0.05), (0.1, -0.05), (0.0, 0.1)))
    square = Polygon(((-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)))
    base = Body("base", square, 1.0, (0.0, 0.0), angle=math.pi / 4)
    top_corner = 0.1 * math.sqrt(2.0)
    # An upside-down triangle whose apex rests on the square's top corner, slightly off axis.
    apex = Body("tri", triangle, 1.0, (0.0, top_corner + 0.1), angle=math.pi + 0.2)
    contact = body_contact(base, apex)
    assert contact.point_count == 1
    assert contact.gap > 0.0
    # A triangle corner on the ground.
    on_ground = place_on_ground(Body("tri", triangle, 1.0, (0.0, 1.0), angle=0.3))
    contact = ground_contact(on_ground)
    assert contact.point_count == 1 and contact.gap == pytest.approx(0.0, abs=TOL)
    assert lowest_point(on_ground) == pytest.approx(0.0, abs=TOL)


def test_disk_on_box_corner_and_crossing_rods():
    box = Body("box", Box(0.2, 0.2), 1.0, (0.0, 0.0))
    direction = np.array([1.0, 1.0]) / math.sqrt(2.0)
    ball = disk(np.array([0.1, 0.1]) + 0.05 * direction, 0.05)
    contact = body_contact(box, ball)
    np.testing.assert_allclose(contact.normal, direction, atol=TOL, rtol=0)
    assert contact.gap == pytest.approx(0.0, abs=TOL)
    a = Body("a", Rod(1.0, 0.01), 1.0, (0.0, 0.0))
    b = Body("b", Rod(1.0, 0.01), 1.0, (0.0, 0.0), angle=math.pi / 2)
    crossing = body_contact(a, b)
    assert crossing.gap < -0.02  # cores cross: at least both radii of overlap


def test_scene_contact_and_contact_velocity():
    body = place_on_ground(disk((0.0, 1.0), 0.1, velocity=(1.0, -1.0), angular_velocity=2.0))
    scene = Scene((body,), restitution=0.5, friction=0.3, ground=True)
    contact = scene_contact(scene)
    vn, vt = contact_velocity(scene, contact)
    # Contact point r = (0, -0.1): v = (vx - ω r_y, vy + ω r_x) = (1 + 0.2, -1).
    assert vn == pytest.approx(-1.0, abs=TOL)
    assert vt == pytest.approx(1.0 + 2.0 * 0.1, abs=TOL)
    a = disk((0.0, 0.0), 0.1, "a", velocity=(0.0, 1.0))
    b = disk((0.0, 0.2), 0.1, "b", velocity=(0.5, -1.0))
    vn, vt = contact_velocity(Scene((a, b), 0.5, 0.3), body_contact(a, b))
    assert vn == pytest.approx(-2.0, abs=TOL)
    assert vt == pytest.approx(0.5, abs=TOL)  # t = (n_y, -n_x) = (1, 0)


@settings(max_examples=200, deadline=None)
@given(
    st.floats(-math.pi, math.pi),
    st.floats(-math.pi, math.pi),
    st.floats(-2.0, 2.0),
    st.floats(-2.0, 2.0),
    st.floats(0.0, 2 * math.pi),
)
def test_rigid_motion_moves_the_contact_with_it(angle_a, angle_b, x, y, turn):
    """Rotating and translating both bodies rotates the normal and moves the point alike."""
    a = Body("a", Box(0.3, 0.1), 1.0, (0.0, 0.0), angle=angle_a)
    b = Body("b", Rod(0.5, 0.02), 1.0, (x, y), angle=angle_b)
    before = body_contact(a, b)
    rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    shift = np.array([0.7, -0.4])

    def moved(body):
        return body.moved(
            position=tuple(rot @ np.asarray(body.position) + shift), angle=body.angle + turn
        )

    after = body_contact(moved(a), moved(b))
    # A handful of operations on O(1) numbers: 1e-9 covers rounding with a wide margin.
    assert after.gap == pytest.approx(before.gap, abs=1e-9)
    if before.point_count == 1 and before.gap > 1e-6:  # overlap normals can tie
        np.testing.assert_allclose(after.normal, rot @ before.normal, atol=1e-9)
        np.testing.assert_allclose(after.point, rot @ before.point + shift, atol=1e-9)


def test_parallel_rods_touch_along_a_line():
    a = Body("a", Rod(1.0, 0.02), 1.0, (0.0, 0.0))
    b = Body("b", Rod(0.6, 0.03), 1.0, (0.3, 0.05))
    contact = body_contact(a, b)
    assert contact.point_count == 2 and contact.gap == pytest.approx(0.0, abs=TOL)


def _sampled_core(body, samples=200):
    """Points along a body's core (its edges, its segment or its point): a brute-force
    reference independent of the contact code."""
    core, _ = world_core(body)
    if len(core) > 2:
        edges = [(core[i], core[(i + 1) % len(core)]) for i in range(len(core))]
    else:
        edges = [(core[0], core[-1])]
    t = np.linspace(0.0, 1.0, samples)[:, None]
    return np.vstack([a + t * (b - a) for a, b in edges])


@settings(max_examples=60, deadline=None)
@given(
    st.sampled_from(["box", "rod", "disk", "triangle"]),
    st.sampled_from(["box", "rod", "disk", "triangle"]),
    st.floats(-math.pi, math.pi),
    st.floats(-math.pi, math.pi),
    st.floats(0.0, 2 * math.pi),
    st.floats(0.5, 1.0),
)
def test_gap_of_separated_bodies_matches_brute_force(kind_a, kind_b, angle_a, angle_b,
                                                     direction, distance):
    """Separated bodies: gap = (minimum distance between densely sampled cores) − both radii.

    The sampled minimum exceeds the exact core distance by at most half the sample spacing
    (edges ≤ 0.4 m, 200 samples: ≤ 1.0e-3 m), and is never below it (up to rounding,
    1e-12 m). Centres at least 0.5 m apart keep the bodies (extents ≤ 0.23 m) separated."""
    shapes = {"box": Box(0.3, 0.1), "rod": Rod(0.4, 0.03), "disk": Disk(0.1),
              "triangle": Polygon(((-0.1, -0.05), (0.1, -0.05), (0.0, 0.1)))}
    a = Body("a", shapes[kind_a], 1.0, (0.0, 0.0), angle=angle_a)
    b = Body("b", shapes[kind_b], 1.0,
             (distance * math.cos(direction), distance * math.sin(direction)), angle=angle_b)
    core_a, core_b = _sampled_core(a), _sampled_core(b)
    differences = core_a[:, None, :] - core_b[None, :, :]
    radii = world_core(a)[1] + world_core(b)[1]
    sampled = float(np.sqrt((differences**2).sum(axis=2)).min()) - radii
    contact = body_contact(a, b)
    assert contact.gap <= sampled + 1e-12
    assert contact.gap > 0.0
    assert contact.gap >= sampled - 1.01e-3
