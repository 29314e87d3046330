"""The point features of a shape: which corner or end cap of a body a contact point is at.

A box or polygon has its vertices (radius 0), a rod its two end-cap centres (its cap
radius), a disk none: its whole surface is one feature. The verdicts
(:mod:`harness.run.verdicts`) read which features an engine's contact points touch; the
scenario checks find the features of a body that reach its partner. A shape's extent (the
largest distance of its points from its body origin) scales the reach of a feature and the
verdicts' penetration bound; the engines size their models by it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


def body_extent(shape) -> float:
    """Largest distance (m) of a point of ``shape`` from its body origin."""
    kind = shape.kind
    if kind == "disk":
        return float(shape.radius)
    if kind == "rod":
        return float(shape.length / 2.0 + shape.radius)
    if kind == "ellipse":
        return float(max(shape.semi_x, shape.semi_y))
    # A box's or polygon's costs µs of numpy, and every run, check and adapter asks for it:
    # remembered per shape value (equal shapes, equal vertices, the same extent).
    try:
        return _EXTENTS[shape]
    except KeyError:
        pass
    except TypeError:  # a shape that does not hash: worked out each time
        return _vertex_extent(shape)
    if len(_EXTENTS) >= _MAX_EXTENTS:
        _EXTENTS.clear()
    extent = _EXTENTS[shape] = _vertex_extent(shape)
    return extent


def _vertex_extent(shape) -> float:
    """:func:`body_extent` of a shape with vertices (a box or polygon): numpy's hypot
    (libm's, which ``math.hypot`` is not bit for bit) of each vertex, the largest; a box's
    four are one (its vertices differ only in sign)."""
    if shape.kind == "box":
        return float(np.hypot(shape.width / 2.0, shape.height / 2.0))
    points = shape.points
    return float(np.max(np.hypot([float(x) for x, _ in points], [float(y) for _, y in points])))


_EXTENTS: dict = {}  # box or polygon -> its body_extent
_MAX_EXTENTS = 4096  # shapes remembered; emptied when full (a survey samples thousands)


def feature_points(shape) -> tuple[np.ndarray, float, tuple[str, ...]]:
    """Body-frame centres of a shape's point features, their radius (m) and names.

    A box or polygon has its vertices (radius 0), a rod its two end-cap centres (its cap
    radius), a disk none: its whole surface is one feature.
    """
    kind = shape.kind
    if kind == "disk":
        return np.zeros((0, 2)), float(shape.radius), ()
    if kind == "rod":
        half = shape.length / 2.0
        return (np.array([[-half, 0.0], [half, 0.0]]), float(shape.radius),
                ("end cap at -length/2", "end cap at +length/2"))
    # an ellipse: its stand-in polygon's vertices (MuJoCo's ellipsoid rolls far from them)
    vertices = np.asarray((shape.stand_in() if kind == "ellipse" else shape).vertices(),
                          dtype=float)
    return vertices, 0.0, tuple(f"corner {i}" for i in range(len(vertices)))


@dataclass(frozen=True)
class BodyFeatures:
    """One body's point features in its own frame (:func:`feature_points`) and its extent
    (:func:`body_extent`): what placing a contact point needs that no pose changes."""

    centres: np.ndarray  # (k, 2), m, body frame
    radius: float  # m
    names: tuple[str, ...]
    extent: float  # m


def body_features(shape) -> BodyFeatures:
    """The :class:`BodyFeatures` of ``shape``."""
    centres, radius, names = feature_points(shape)
    return BodyFeatures(centres, radius, names, body_extent(shape))


def feature_at(shape, state: Sequence[float], point: Sequence[float],
               reach: float) -> int | None:
    """Index of the point feature of ``shape`` (in pose ``state = (x, y, θ, …)``) within
    ``reach`` of ``point`` (m, beyond the feature's radius); None when the point lies on a
    face or side instead (or the shape is a disk)."""
    found = features_at(body_features(shape), np.array([state[:3]], dtype=float),
                        np.array([point[:2]], dtype=float), np.zeros(1, dtype=np.int64),
                        np.array([reach], dtype=float))
    return None if found[0] < 0 else int(found[0])


_SIGNS = np.array([-1.0, 1.0])


def pose_turns(poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each pose's ``(x, y, θ)`` cosine and sine of ``θ``, two arrays of shape ``(n,)``."""
    # math's cos and sin, one pose at a time: numpy's array ones may round differently
    angles = poses[:, 2].tolist()
    cos = np.fromiter(map(math.cos, angles), float, len(angles))
    sin = np.fromiter(map(math.sin, angles), float, len(angles))
    return cos, sin


def centres_at_poses(centres: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """Body-frame points ``centres`` (``(k, 2)``, or ``(n, k, 2)``: pose ``i``'s own) turned by
    each of the ``n`` poses' ``θ`` and moved to its ``(x, y)``: shape ``(n, k, 2)``.

    Written elementwise, ``(x cos θ − y sin θ + p_x, x sin θ + y cos θ + p_y)``, not as the
    stack of products ``centres @ R``: numpy's ``@`` goes through BLAS, whose kernels (FMA or
    not) round differently from CPU to CPU, while separate IEEE multiplies and additions give
    the same bits on every one (docs/verdicts.md, 'Same answers on every CPU')."""
    cos, sin = pose_turns(poses)
    # (x c, y c) + (y, x)·(−s, s): x c − y s and y c + x s, the negation exact, in few calls
    return ((centres * cos[:, None, None] + centres[..., ::-1] * (sin[:, None, None] * _SIGNS))
            + poses[:, None, :2])


def features_at(features: BodyFeatures, poses: np.ndarray, points: np.ndarray,
                pose_of: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """For every point ``points[i] = (x, y, …)`` with the body in pose
    ``poses[pose_of[i]] = (x, y, θ)``: the index of the body's point feature within
    ``reach[i]`` of it (beyond the feature's radius), or -1 (a face or side; always for a
    disk). The nearest feature is the one that counts, the first of equally near ones."""
    count = len(points)
    if not len(features.centres) or not count:
        return np.full(count, -1, dtype=np.int64)
    world = centres_at_poses(features.centres, poses)[pose_of]
    distances = np.hypot(world[:, :, 0] - points[:, None, 0],
                         world[:, :, 1] - points[:, None, 1]) - features.radius
    # the least distance is the nearest one's (NaN, as argmin's pick, when there is one)
    within = distances.min(axis=1) <= reach
    return np.where(within, np.argmin(distances, axis=1), -1)


__all__ = ["BodyFeatures", "body_extent", "body_features", "feature_at", "feature_points",
           "features_at", "centres_at_poses", "pose_turns"]
