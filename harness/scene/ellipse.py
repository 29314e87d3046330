"""The ellipse as the laws and the engines see it: its lowest point and contact Jacobian at
an angle, in closed form, and the error a polygon in its place makes.

Only MuJoCo takes an ellipse (ellipsoid geom); pymunk, pybullet and Box2D take polygons
(:meth:`harness.scene.Ellipse.stand_in`). Two ways to make the polygon:

* a fixed inscribed N-gon (vertices at equal parameter steps): close to the ellipse
  everywhere, but its lowest vertex is not the ellipse's lowest point, so the contact's
  moment arm — the horizontal offset of the contact from the centre, ``w_n``'s third
  entry — moves with the angle;
* a placed N-gon, rotated in parameter so that one vertex is the ellipse's lowest point at
  the scene's angle: every vertex is on the ellipse, which lies above its tangent at that
  point, so that vertex is the polygon's lowest and the moment arm is exact (the
  harness's stand-in).

The scalar forms (:func:`lowest_parameter`, :func:`lowest_offset`) serve the scene's
geometry; the array forms the analyses over many angles.
"""

from __future__ import annotations

import math

import numpy as np


def lowest_parameter(angle: float, a: float, b: float) -> float:
    """The parameter φ of the lowest point of the ellipse (semi-axes ``a`` along the body's
    x, ``b`` along its y) turned by ``angle`` (rad): :func:`lowest_point`'s, by :mod:`math`."""
    return math.atan2(-b * math.cos(angle), -a * math.sin(angle))


def lowest_offset(angle: float, a: float, b: float) -> tuple[float, float]:
    """``(p_x, p_y)``: the lowest point of the turned ellipse, from its centre (m)."""
    phi = lowest_parameter(angle, a, b)
    x, y = a * math.cos(phi), b * math.sin(phi)
    c, s = math.cos(angle), math.sin(angle)
    return c * x - s * y, s * x + c * y


def lowest_point(theta, a: float, b: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(φ, p_x, p_y)``: the parameter and the offset from the centre of the lowest point of
    the ellipse (semi-axes a along the body's x, b along its y) turned by ``theta``.

    A point is ``R(θ)(a cos φ, b sin φ)``; its height ``a cos φ sin θ + b sin φ cos θ`` is
    least where ``(cos φ, sin φ) ∝ −(a sin θ, b cos θ)``."""
    theta = np.asarray(theta, dtype=float)
    phi = np.arctan2(-b * np.cos(theta), -a * np.sin(theta))
    px, py = _point(theta, phi, a, b)
    return phi, px, py


def _point(theta, phi, a, b):
    x, y = a * np.cos(phi), b * np.sin(phi)
    return x * np.cos(theta) - y * np.sin(theta), x * np.sin(theta) + y * np.cos(theta)


def jacobians(theta, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """``w_n, w_t`` (rows (..., 3) for speeds v_x, v_y, ω) of the lowest point on a flat
    ground with upward normal: the point moves with ``(v_x − ω p_y, v_y + ω p_x)``."""
    _, px, py = lowest_point(theta, a, b)
    ones, zeros = np.ones_like(px), np.zeros_like(px)
    return np.stack([zeros, ones, px], axis=-1), np.stack([ones, zeros, -py], axis=-1)


def polygon_lowest_point(theta, a: float, b: float, vertices: int,
                         offset=0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(p_x, p_y)`` of the lowest vertex of the inscribed polygon with vertices at
    parameters ``offset + 2πk/vertices`` (per angle; ``offset`` broadcasts with θ)."""
    theta = np.asarray(theta, dtype=float)[..., None]
    phis = np.asarray(offset, dtype=float)[..., None] + 2 * np.pi * np.arange(vertices) / vertices
    px, py = _point(theta, phis, a, b)
    lowest = np.argmin(py, axis=-1)[..., None]
    return np.take_along_axis(px, lowest, -1)[..., 0], np.take_along_axis(py, lowest, -1)[..., 0]


def placed_clearance(theta, a: float, b: float, vertices: int) -> np.ndarray:
    """Per angle, how far the placed polygon's second-lowest vertex sits above its lowest
    (the contact): an engine with a contact margin larger than this sees two contacts."""
    theta = np.asarray(theta, dtype=float)
    phi, _, _ = lowest_point(theta, a, b)
    phis = phi[..., None] + 2 * np.pi * np.arange(vertices) / vertices
    _, py = _point(theta[..., None], phis, a, b)
    heights = np.sort(py, axis=-1)
    return heights[..., 1] - heights[..., 0]


def inscribed_gap(a: float, b: float, vertices: int, offset: float = 0.0,
                  samples: int = 64) -> float:
    """Largest distance from the ellipse to the inscribed polygon's edges (its shape error),
    sampled on every edge."""
    phis = offset + 2 * np.pi * np.arange(vertices + 1) / vertices
    start = np.stack([a * np.cos(phis[:-1]), b * np.sin(phis[:-1])], axis=1)
    end = np.stack([a * np.cos(phis[1:]), b * np.sin(phis[1:])], axis=1)
    t = np.linspace(0.0, 1.0, samples)[:, None, None]
    arc = phis[:-1] + t[..., 0] * (phis[1:] - phis[:-1])
    curve = np.stack([a * np.cos(arc), b * np.sin(arc)], axis=-1)
    edge = end - start
    length = np.hypot(edge[:, 0], edge[:, 1])[:, None]
    normal = np.stack([edge[:, 1], -edge[:, 0]], axis=1) / length
    return float(np.max(np.abs(np.sum((curve - start) * normal, axis=-1))))


def moment_arm_error(a: float, b: float, vertices: int, angles: int = 20_001) -> dict:
    """The fixed inscribed N-gon against the ellipse over every angle: the largest error of
    the contact's horizontal offset (moment arm) and of its height (where the body touches),
    and the placed N-gon's (exact by construction, measured all the same)."""
    theta = np.linspace(-np.pi, np.pi, angles)
    phi, px, py = lowest_point(theta, a, b)
    fixed_x, fixed_y = polygon_lowest_point(theta, a, b, vertices)
    placed_x, placed_y = polygon_lowest_point(theta, a, b, vertices, offset=phi)
    return {
        "vertices": vertices,
        "shape_gap": inscribed_gap(a, b, vertices),
        "fixed_moment_arm": float(np.max(np.abs(fixed_x - px))),
        "fixed_height": float(np.max(np.abs(fixed_y - py))),
        "placed_moment_arm": float(np.max(np.abs(placed_x - px))),
        "placed_height": float(np.max(np.abs(placed_y - py))),
        "placed_clearance_min": float(np.min(placed_clearance(theta, a, b, vertices))),
    }
