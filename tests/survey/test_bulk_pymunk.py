"""The bulk pymunk path gives the adapter's answer bit for bit: velocities, status, steps."""

from __future__ import annotations

import numpy as np
import pytest

from harness.engines import load_engine
from harness.survey.bulk_pymunk import compare_with_adapter, run_bulk
from harness.survey.engines import run_engine
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population


@pytest.fixture(scope="module")
def scenes():
    # 40 ground and 3 × 12 two-body scenes: more than one space per kind (CHUNK = 32).
    return [s.scene for p in resolve_populations()
            for s in sample_population(p, 12 if not p.ground else 10, seed=21).samples]


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_bulk_is_bit_identical_to_one_by_one(scenes, preset):
    result = compare_with_adapter(scenes, preset)
    assert result["bit_identical"], result
    assert result["same_status"] and result["same_steps"], result


def test_chunk_size_does_not_change_the_answer(scenes):
    settings = load_engine("pymunk").settings("accurate")
    whole = run_bulk(scenes, settings)
    one_each = run_bulk(scenes, settings, chunk=1)
    assert np.array_equal(whole[0], one_each[0]) and np.array_equal(whole[1], one_each[1])


def test_the_survey_swap_point_returns_the_same_results(scenes):
    single = run_engine("pymunk", "defaults", scenes)
    bulk = run_engine("pymunk", "defaults", scenes, bulk=True)
    assert np.array_equal(single.velocities, bulk.velocities)
    assert np.array_equal(single.status, bulk.status)


def test_chunk_beyond_the_category_bits_is_refused():
    with pytest.raises(ValueError, match="one category bit per impact"):
        run_bulk([], {}, chunk=33)
