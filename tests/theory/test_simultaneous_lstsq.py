"""``_lstsq_rows`` (one call for a stack of least-squares problems) gives each problem
``np.linalg.lstsq``'s answer and rank bit for bit, with numpy's gufunc and without it."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from planar_impact.simultaneous import system


def stacks(seed=0):
    """Square, rank-deficient, tall and wide stacks with their right-hand sides."""
    rng = np.random.default_rng(seed)
    square = rng.normal(size=(40, 4, 4))
    deficient = square.copy()
    deficient[:, 3] = deficient[:, 0] + 1e-11 * rng.normal(size=(40, 4))  # rank 3 below rcond
    deficient[::2, 2] = 0.0  # rank 2 for half of them
    scaled = square * 10.0 ** rng.uniform(-8, 8, size=(40, 1, 1))
    for matrices in (square, deficient, scaled, rng.normal(size=(10, 6, 4)),
                     rng.normal(size=(10, 3, 5))):
        yield matrices, rng.normal(size=matrices.shape[:2])


@pytest.mark.parametrize("rcond", [1e-9, 1e-12])
@pytest.mark.parametrize("gufunc", ["numpy's", "missing", "other arguments"])
def test_each_row_is_np_linalg_lstsq_bit_for_bit(rcond, gufunc, monkeypatch):
    if gufunc == "missing":  # a numpy without the private gufunc takes the loop
        monkeypatch.setattr(np.linalg, "_umath_linalg", None)
    elif gufunc == "other arguments":  # so does one whose gufunc is called otherwise

        def refuse(*_args, **_keywords):
            raise TypeError("lstsq() takes other arguments")

        monkeypatch.setattr(np.linalg, "_umath_linalg", SimpleNamespace(lstsq=refuse))
    ranks_seen = set()
    for matrices, rhs in stacks():
        solutions, ranks = system.lstsq_rows(matrices, rhs, rcond=rcond)
        assert solutions.shape == (len(matrices), matrices.shape[2])
        for matrix, side, solution, rank in zip(matrices, rhs, solutions, ranks):
            expected, _, expected_rank, _ = np.linalg.lstsq(matrix, side, rcond=rcond)
            assert solution.tobytes() == expected.tobytes()
            assert rank == expected_rank
            ranks_seen.add(int(rank))
    assert {2, 3, 4} <= ranks_seen


def test_an_empty_stack_gives_empty_answers():
    solutions, ranks = system.lstsq_rows(np.zeros((0, 4, 4)), np.zeros((0, 4)), rcond=1e-9)
    assert solutions.shape == (0, 4) and ranks.shape == (0,)
