"""The ellipse's lowest point and contact Jacobian, and the polygons that stand in for it."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from harness.scene import ellipse
from tests.error_bounds import gamma

A, B = 0.035, 0.025  # m, the Fazeli et al. (2017) ellipse's semi-axes


@given(st.floats(-np.pi, np.pi), st.floats(0.005, 0.1), st.floats(0.005, 0.1))
def test_lowest_point_is_the_lowest_of_a_dense_sample(theta, a, b):
    _, px, py = ellipse.lowest_point(theta, a, b)
    phis = np.linspace(0.0, 2 * np.pi, 200_001)
    x, y = a * np.cos(phis), b * np.sin(phis)
    heights = x * np.sin(theta) + y * np.cos(theta)
    k = np.argmin(heights)
    assert py <= heights[k] + 1e-15  # the closed form is the least height ...
    assert py == pytest.approx(heights[k], abs=1e-8 * max(a, b))  # ... to the sample spacing
    assert px == pytest.approx(x[k] * np.cos(theta) - y[k] * np.sin(theta), abs=1e-4 * a)


def test_jacobian_rows_give_the_contact_point_velocity():
    """w·u against the velocity of the lowest point, v + ω × p, formed directly."""
    rng = np.random.default_rng(3)
    theta = rng.uniform(-np.pi, np.pi, 50)
    speeds = rng.normal(size=(50, 3))
    wn, wt = ellipse.jacobians(theta, A, B)
    _, px, py = ellipse.lowest_point(theta, A, B)
    velocity = speeds[:, :2] + speeds[:, 2:3] * np.stack([-py, px], axis=1)
    # A derived bound (docs/verdicts.md, 'Same answers on every CPU'): w_n = (0, 1, p_x) and
    # w_t = (1, 0, −p_y) exactly, so both sides are v_y + ω p_x (v_x − ω p_y): one product and
    # one sum beside exact ones, in any order, fused or not (einsum's SIMD loops), each within
    # γ_2 (|v| + |ω p|) of the exact value (Higham (3.5)); the two sides within twice that.
    assert np.array_equal(wn[:, 2], px) and np.array_equal(wt[:, 2], -py)
    for w, got, v, arm in ((wn, velocity[:, 1], speeds[:, 1], px),
                           (wt, velocity[:, 0], speeds[:, 0], -py)):
        bound = 2 * gamma(2) * (np.abs(v) + np.abs(speeds[:, 2] * arm))
        assert np.all(np.abs(np.einsum("ij,ij->i", w, speeds) - got) <= bound)


def test_a_fixed_32_gon_looks_close_but_moves_the_moment_arm():
    """The issue's figures: a fixed inscribed 32-gon is within 0.2 mm of the ellipse but
    moves the contact's moment arm by up to 3.4 mm; a placed one is exact at the contact."""
    errors = ellipse.moment_arm_error(A, B, 32)
    assert errors["shape_gap"] < 0.2e-3
    assert 3.3e-3 < errors["fixed_moment_arm"] < 3.5e-3
    assert errors["placed_moment_arm"] < 1e-12 and errors["placed_height"] < 1e-12
    # more vertices: smaller gap and arm error, and a smaller clearance to a second contact
    finer = ellipse.moment_arm_error(A, B, 64)
    assert finer["shape_gap"] < errors["shape_gap"]
    assert finer["fixed_moment_arm"] < errors["fixed_moment_arm"]
    assert finer["placed_clearance_min"] < errors["placed_clearance_min"]


# --------------------------------------------------------------------------------------------
# The Ellipse shape in the scene model and its geometry
# --------------------------------------------------------------------------------------------
def _ellipse_body(angle: float, **changes):
    from harness.scene import Body, Ellipse, geometry

    body = Body("e", Ellipse(A, B), 0.0364, (0.01, 0.0), angle, (0.2, -2.5), 4.0, **changes)
    return geometry.place_stand_in(geometry.place_on_ground(body))


def test_ellipse_inertia_is_the_limit_of_fine_inscribed_polygons():
    """(a² + b²)/4 per unit mass, against a 4096-gon's exact polygon formula."""
    from harness.scene import Ellipse, Polygon

    phis = 2 * np.pi * np.arange(4096) / 4096
    polygon = Polygon(tuple(zip((A * np.cos(phis)).tolist(), (B * np.sin(phis)).tolist())))
    shape = Ellipse(A, B)
    assert shape.inertia_per_mass() == pytest.approx(polygon.inertia_per_mass(), rel=1e-5)
    assert shape.area() == pytest.approx(polygon.area(), rel=1e-5)


@given(st.floats(-np.pi, np.pi))
def test_ground_contact_is_the_lowest_point_and_the_stand_in_vertex(angle):
    """The scene's contact is the closed-form lowest point; the placed stand-in's first
    vertex is there, and every other vertex lies at least 4 mm higher (an 8-gon on this
    ellipse: 7.3 mm at worst, 'placed_clearance')."""
    from harness.scene import Scene, geometry

    body = _ellipse_body(angle)
    contact = geometry.scene_contact(Scene((body,), 0.5, 0.3, ground=True))
    _, px, py = ellipse.lowest_point(angle, A, B)
    assert contact.gap == pytest.approx(0.0, abs=1e-15)
    assert contact.point_count == 1
    assert contact.point[0] == pytest.approx(body.position[0] + float(px), abs=1e-15)
    assert body.position[1] == pytest.approx(-float(py), abs=1e-15)
    vertices = body.shape.stand_in().vertices() @ geometry.rotation(angle).T
    heights = vertices[:, 1] + body.position[1]
    assert abs(heights[0]) < 1e-15 and np.all(heights[1:] > 4e-3)
    assert abs(vertices[0, 0] + body.position[0] - contact.point[0]) < 1e-15
    # centrally symmetric: the stand-in's centroid is the ellipse's centre
    assert np.abs(body.shape.stand_in().centroid()).max() < 1e-15


def test_scene_jacobian_is_the_closed_form_one():
    """The reference's contact terms (impact_problem at the scene's contact) carry the
    ellipse's w_n, w_t (ellipse.jacobians), so the laws see the true moment arm."""
    from harness.scene import Scene, geometry

    for angle in np.linspace(-3.0, 3.0, 13).tolist():
        scene = Scene((_ellipse_body(angle),), 0.5, 0.3, ground=True)
        contact = geometry.scene_contact(scene)
        problem = geometry.impact_problem(scene, contact.point, contact.normal)
        wn, wt = ellipse.jacobians(angle, A, B)
        np.testing.assert_allclose(problem.wn, wn, atol=1e-15, rtol=0)
        np.testing.assert_allclose(problem.wt, wt, atol=1e-15, rtol=0)
        assert problem.mass_matrix[2, 2] == pytest.approx(0.0364 * (A * A + B * B) / 4)


def test_an_ellipse_touches_only_the_ground():
    from harness.scene import Body, Disk, geometry

    body = _ellipse_body(0.3)
    disk = Body("d", Disk(0.01), 0.01, (0.0, 0.2))
    with pytest.raises(ValueError, match="an ellipse touches only the ground"):
        geometry.body_contact(disk, body)
    with pytest.raises(TypeError, match="no polygonal core"):
        geometry.local_core(body.shape)


def test_placing_moves_the_stand_in_only_for_an_ellipse():
    from harness.scene import Body, Disk, geometry

    disk = Body("d", Disk(0.01), 0.01, (0.0, 0.01))
    assert geometry.place_stand_in(disk) is disk
    body = _ellipse_body(1.0)
    assert body.shape.vertex_at == pytest.approx(float(ellipse.lowest_point(1.0, A, B)[0]))
