"""A shape's point features (harness/scene/features.py): what the scenario checks of a tilt's
second strike use. The verdicts keep their own copy until their split moves theirs down
here (issue 26): the two must agree on every kind of shape."""

from __future__ import annotations

import numpy as np
import pytest

from harness.run import verdicts
from harness.scene import Box, Disk, Polygon, Rod
from harness.scene.features import feature_points

SHAPES = [Disk(0.05), Rod(0.4, 0.01), Box(0.3, 0.1),
          Polygon(((0.0, 0.1), (-0.1, -0.05), (0.1, -0.05)))]


def test_a_box_has_its_corners_a_rod_its_caps_a_disk_none():
    centres, radius, names = feature_points(Box(0.3, 0.1))
    assert radius == 0.0 and len(names) == 4
    assert sorted(map(tuple, np.abs(centres))) == [(0.15, 0.05)] * 4
    centres, radius, names = feature_points(Rod(0.4, 0.01))
    assert radius == 0.01 and centres.tolist() == [[-0.2, 0.0], [0.2, 0.0]]
    assert feature_points(Disk(0.05))[2] == () and feature_points(Disk(0.05))[0].shape == (0, 2)


@pytest.mark.parametrize("shape", SHAPES, ids=lambda shape: type(shape).__name__)
def test_the_scene_and_the_verdicts_agree(shape):
    ours, theirs = feature_points(shape), verdicts.feature_points(shape)
    assert ours[1:] == theirs[1:]
    assert np.array_equal(ours[0], theirs[0])
