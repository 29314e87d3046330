"""``metrics.departure_batch`` against ``metrics.departure`` row by row.

Tolerance: the batch sums ``uᵀMu`` with einsum where the scalar form multiplies ``(u @ M) @ u``;
the sums of at most 6 products then differ in rounding only (a few ulp), and the centre-of-mass
subtraction of a two-body row loses at most the digits the scalar form loses too, so the two
agree to 1e-12 relative on these well-scaled random rows.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.run import metrics

RELATIVE = 1e-12


def _rows(rng, count, size):
    mass = rng.uniform(0.1, 5.0, (count, size))
    u_before, u, u_law = (rng.normal(0.0, 2.0, (count, size)) for _ in range(3))
    return mass, u, u_law, u_before


@pytest.mark.parametrize("size,free", [(3, False), (6, False), (6, True)])
def test_batch_equals_departure_row_by_row_diagonal_and_full(size, free):
    rng = np.random.default_rng(7)
    mass, u, u_law, u_before = _rows(rng, 200, size)
    batch = metrics.departure_batch(mass, u, u_law, u_before, free_bodies=free)
    full = np.stack([np.diag(row) for row in mass])
    batch_full = metrics.departure_batch(full, u, u_law, u_before, free_bodies=free)
    single = np.array([metrics.departure(full[i], u[i], u_law[i], u_before[i], free_bodies=free)
                       for i in range(len(u))])
    np.testing.assert_allclose(batch, single, rtol=RELATIVE, atol=0)
    np.testing.assert_allclose(batch_full, single, rtol=RELATIVE, atol=0)


def test_per_row_frames_padding_and_nan_rows_match_departure():
    rng = np.random.default_rng(11)
    mass, u, u_law, u_before = _rows(rng, 60, 6)
    free = np.arange(60) % 2 == 0
    # Odd rows are one body against the ground: 3 speeds, padded with zeros and unit mass.
    for array in (u, u_law, u_before):
        array[~free, 3:] = 0.0
    mass[~free, 3:] = 1.0
    u_law[5, 1] = math.nan  # a law without an answer
    u[8, 0] = math.inf  # an engine that blew up
    u_before[10] = 0.0  # nothing moves: no scale
    batch = metrics.departure_batch(mass, u, u_law, u_before, free_bodies=free)
    for row in range(60):
        dofs = 6 if free[row] else 3
        expected = metrics.departure(np.diag(mass[row, :dofs]), u[row, :dofs],
                                     u_law[row, :dofs], u_before[row, :dofs],
                                     free_bodies=bool(free[row]))
        if math.isnan(expected):
            assert math.isnan(batch[row]), row
        else:
            assert batch[row] == pytest.approx(expected, rel=RELATIVE, abs=0), row
    assert np.isnan(batch[[5, 8, 10]]).all()


def test_the_centre_of_mass_frame_ignores_a_common_velocity():
    rng = np.random.default_rng(3)
    mass, u, u_law, u_before = _rows(rng, 20, 6)
    boost = rng.normal(0.0, 5.0, (20, 2))
    shift = np.zeros((20, 6))
    shift[:, [0, 3]] = boost[:, [0]]
    shift[:, [1, 4]] = boost[:, [1]]
    plain = metrics.departure_batch(mass, u, u_law, u_before, free_bodies=True)
    boosted = metrics.departure_batch(mass, u + shift, u_law + shift, u_before + shift,
                                      free_bodies=True)
    np.testing.assert_allclose(boosted, plain, rtol=1e-10)
    ground_frame = metrics.departure_batch(mass, u + shift, u_law + shift, u_before + shift)
    assert not np.allclose(ground_frame, plain, rtol=1e-3)
