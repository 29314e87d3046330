"""The last answer :func:`metrics.frame_free_scale` and :func:`metrics.delassus` keep.

They keep their last answer keyed by the bits of their inputs: asked again with the same
inputs they give the same float, and an input changed in place (same array object, new
numbers) or of another dtype gives the freshly worked-out answer, never the kept one.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from harness.run import metrics


def random_case(rng, bodies):
    size = 3 * bodies
    root = rng.normal(size=(size, size))
    mass_matrix = root @ root.T + size * np.eye(size)
    return mass_matrix, rng.normal(size=size), rng.normal(size=size), rng.normal(size=size)


def fresh_delassus(mass_matrix, wn, wt):
    """(A20) worked out as before the kept answer."""
    inverse_w = np.linalg.solve(mass_matrix, np.stack([wn, wt], axis=1))
    return (float(wn @ inverse_w[:, 0]), float(wn @ inverse_w[:, 1]),
            float(wt @ inverse_w[:, 1]))


@pytest.mark.parametrize("free_bodies", [False, True])
def test_scale_is_fresh_after_an_in_place_change(free_bodies):
    rng = np.random.default_rng(3)
    for _ in range(200):
        mass_matrix, u_before, _, _ = random_case(rng, 2)
        first = metrics.frame_free_scale(mass_matrix, u_before, free_bodies=free_bodies)
        assert first == metrics._frame_free_scale(mass_matrix, u_before, free_bodies)
        assert metrics.frame_free_scale(mass_matrix, u_before, free_bodies=free_bodies) == first
        u_before[rng.integers(6)] += 0.5  # same object, new numbers
        assert (metrics.frame_free_scale(mass_matrix, u_before, free_bodies=free_bodies)
                == metrics._frame_free_scale(mass_matrix, u_before, free_bodies))
        mass_matrix[0, 0] *= 2.0
        assert (metrics.frame_free_scale(mass_matrix, u_before, free_bodies=free_bodies)
                == metrics._frame_free_scale(mass_matrix, u_before, free_bodies))


def test_scale_depends_on_the_frame_asked():
    mass_matrix, u_before, _, _ = random_case(np.random.default_rng(4), 2)
    ground = metrics.frame_free_scale(mass_matrix, u_before)
    centre = metrics.frame_free_scale(mass_matrix, u_before, free_bodies=True)
    assert ground != centre
    assert metrics.frame_free_scale(mass_matrix, u_before) == ground


def test_delassus_is_fresh_after_an_in_place_change():
    rng = np.random.default_rng(5)
    for bodies in (1, 2) * 100:
        mass_matrix, _, wn, wt = random_case(rng, bodies)
        problem = SimpleNamespace(mass_matrix=mass_matrix, wn=wn, wt=wt)
        assert metrics.delassus(problem) == fresh_delassus(mass_matrix, wn, wt)
        assert metrics.delassus(problem) == fresh_delassus(mass_matrix, wn, wt)
        wt[0] += 1.0
        assert metrics.delassus(problem) == fresh_delassus(mass_matrix, wn, wt)
        mass_matrix[1, 1] += 1.0
        assert metrics.delassus(problem) == fresh_delassus(mass_matrix, wn, wt)


def test_delassus_keys_on_the_dtype():
    wn, wt = np.array([0.0, 1.0, 0.5]), np.array([1.0, 0.0, -0.5])
    exact = SimpleNamespace(mass_matrix=np.diag([3.0, 3.0, 0.7]), wn=wn, wt=wt)
    single = SimpleNamespace(mass_matrix=np.diag([3.0, 3.0, 0.7]).astype(np.float32),
                             wn=wn, wt=wt)
    assert metrics.delassus(exact) == fresh_delassus(exact.mass_matrix, wn, wt)
    assert metrics.delassus(single) == fresh_delassus(single.mass_matrix, wn, wt)
    assert metrics.delassus(exact) == fresh_delassus(exact.mass_matrix, wn, wt)
