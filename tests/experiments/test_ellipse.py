"""The ellipse's lowest point and contact Jacobian, and the polygons that stand in for it."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from harness.experiments import ellipse, fazeli

A, B = fazeli.SEMI_AXES


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
    np.testing.assert_allclose(np.einsum("ij,ij->i", wn, speeds), velocity[:, 1], atol=1e-14)
    np.testing.assert_allclose(np.einsum("ij,ij->i", wt, speeds), velocity[:, 0], atol=1e-14)


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
