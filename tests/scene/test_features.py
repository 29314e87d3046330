"""A shape's point features and extent (harness/scene/features.py).

The extent of a box or polygon is remembered per shape value; these tests hold it to its
definition, bit for bit, and bound what is remembered (moved here with ``body_extent`` from
the engine contract's tests).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.scene import Box, Disk, Polygon, Rod, features
from harness.scene.features import feature_points
from harness.scene.reference import reference_scenes
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population


@pytest.fixture(scope="module")
def scenes():
    sampled = [sample.scene for population in resolve_populations([])
               for sample in sample_population(population, 6, seed=5).samples]
    return sampled + [scene for scene, _, _ in reference_scenes().values()]


def _extent_by_definition(shape) -> float:
    """Largest distance of a point of ``shape`` from its origin, from its vertices."""
    vertices = shape.vertices()
    return float(np.max(np.hypot(vertices[:, 0], vertices[:, 1])))


def test_remembered_extents_are_each_shapes_own(scenes):
    """body_extent remembers a box's or polygon's extent per shape value: every sampled
    shape's is its own (asked twice: computed, then remembered), and a shape equal in value
    but another object gets the same."""
    shapes = [body.shape for scene in scenes for body in scene.bodies
              if body.shape.kind in ("box", "polygon")]
    assert {shape.kind for shape in shapes} == {"box", "polygon"}
    features._EXTENTS.clear()
    for shape in shapes:
        assert features.body_extent(shape) == _extent_by_definition(shape)
        assert features.body_extent(shape) == _extent_by_definition(shape)
        copy = dataclasses.replace(shape)
        assert copy is not shape and features.body_extent(copy) == _extent_by_definition(shape)
    assert len(features._EXTENTS) == len(set(shapes))


def test_a_shape_that_does_not_hash_is_measured_each_time():
    """A polygon whose points are lists cannot be remembered: it is measured every time."""
    shape = Polygon([[0.2, 0.0], [0.0, 0.3], [-0.1, -0.1]])
    with pytest.raises(TypeError):
        hash(shape)
    assert features.body_extent(shape) == _extent_by_definition(shape)
    shape.points[1][1] = 0.5  # the same object, other vertices: measured again
    assert features.body_extent(shape) == _extent_by_definition(shape) == pytest.approx(0.5)


def test_the_remembered_extents_are_bounded():
    features._EXTENTS.clear()
    boxes = [Box(0.1 + index * 1e-3, 0.2) for index in range(features._MAX_EXTENTS + 5)]
    for box in boxes:
        features.body_extent(box)
    assert len(features._EXTENTS) <= features._MAX_EXTENTS
    assert features.body_extent(boxes[0]) == _extent_by_definition(boxes[0])


def test_a_box_has_its_corners_a_rod_its_caps_a_disk_none():
    centres, radius, names = feature_points(Box(0.3, 0.1))
    assert radius == 0.0 and len(names) == 4
    assert sorted(map(tuple, np.abs(centres))) == [(0.15, 0.05)] * 4
    centres, radius, names = feature_points(Rod(0.4, 0.01))
    assert radius == 0.01 and centres.tolist() == [[-0.2, 0.0], [0.2, 0.0]]
    assert feature_points(Disk(0.05))[2] == () and feature_points(Disk(0.05))[0].shape == (0, 2)


def _random_shapes(count: int) -> list:
    """Boxes and convex polygons of 3 to 20 vertices (points on a circle at sorted random
    angles, about their centroid), of sizes over six decades."""
    rng = np.random.default_rng(38)
    shapes = []
    for _ in range(count):
        size = 10.0 ** rng.uniform(-3.0, 3.0)
        shapes.append(Box(*(size * rng.uniform(0.05, 1.0, 2)).tolist()))
        angles = np.sort(rng.uniform(0.0, 2.0 * np.pi, rng.integers(3, 21)))
        points = size * np.column_stack([np.cos(angles), rng.uniform(0.2, 1.0) * np.sin(angles)])
        points -= Polygon(tuple(map(tuple, points.tolist()))).centroid()
        shapes.append(Polygon(tuple(map(tuple, points.tolist()))))
    return shapes


def test_extents_and_inertias_are_numpys_own_bit_for_bit():
    """A box's or polygon's extent and a polygon's inertia per mass, worked out in plain
    floats for speed, are what numpy's arrays give, bit for bit: its hypot (libm's, which
    math.hypot is not) and its sums (pairwise order)."""
    for shape in _random_shapes(2000):
        assert features._vertex_extent(shape) == _extent_by_definition(shape)
        if shape.kind == "polygon":
            x, y = shape.vertices().T
            x1, y1 = np.roll(x, -1), np.roll(y, -1)
            cross = x * y1 - x1 * y
            numerator = np.sum(cross * (x * x + x * x1 + x1 * x1 + y * y + y * y1 + y1 * y1))
            assert shape.inertia_per_mass() == float(numerator / (6.0 * np.sum(cross)))
