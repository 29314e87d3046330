"""The point features of a shape: where, in its own frame, a body can strike with a corner or
an end cap rather than a face (the scenario checks of a tilt's second strike, the verdicts'
contact geometry)."""

from __future__ import annotations

import numpy as np


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
    vertices = np.asarray(shape.vertices(), dtype=float)
    return vertices, 0.0, tuple(f"corner {i}" for i in range(len(vertices)))


__all__ = ["feature_points"]
