"""The solver benchmark checks its own answers and measures what it says (no timing asserts)."""

import dataclasses

import numpy as np
import pytest

import planar_impact as pi
from harness.bench import solver as bench
from harness.scene.random_problems import random_problems


def test_check_against_process_accepts_the_solver():
    sample = random_problems(50, seed=11)
    for law in pi.LAWS:
        bench._check_against_process(law, sample)


def test_check_against_process_rejects_a_wrong_answer(monkeypatch):
    real = pi.solve_batch

    def wrong(*args, **kwargs):
        result = real(*args, **kwargs)
        return dataclasses.replace(result, normal_impulse=result.normal_impulse * (1 + 1e-6))

    monkeypatch.setattr(pi, "solve_batch", wrong)
    with pytest.raises(AssertionError, match="disagrees with the impulse process"):
        bench._check_against_process("poisson", random_problems(50, seed=12))


def test_output_write_covers_every_array_of_a_batch_result():
    result = pi.solve_batch([1.0, 2.0], 0.0, 1.0, -1.0, 0.5, 0.3, 0.5)
    arrays = [v for v in result.as_dict().values() if isinstance(v, np.ndarray)]
    assert len(arrays) == 12  # status + the 11 result fields
    assert sorted(map(str, bench.result_dtypes())) == sorted(str(v.dtype) for v in arrays)
    # ... which is what the solver allocates per result, from its own table.
    from planar_impact import solver
    assert sorted(map(str, bench.result_dtypes())) == sorted(
        str(np.dtype(d)) for d in solver._BATCH_DTYPES.values())
    assert bench.output_write_time(10, repeat=1) > 0


@pytest.mark.parametrize("keep", [True, False])
def test_numpy_passes_time_is_positive(keep):
    assert bench.numpy_passes_time(1000, repeat=1, keep=keep) > 0
