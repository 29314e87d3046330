"""The survey's engine runs on several worker processes equal those on one, scene by scene."""

from __future__ import annotations

import numpy as np
import pytest

from harness.survey import engines as survey_engines
from harness.survey import laws as survey_laws
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population


def test_slices_on_two_workers_join_to_the_runs_of_one_process(monkeypatch):
    pytest.importorskip("pymunk")
    pytest.importorskip("Box2D")
    every = [sample for population in resolve_populations([])
             for sample in sample_population(population, 5, 3).samples]
    terms = survey_laws.contact_terms(every)
    energy = survey_laws.solve_laws(terms)["newton-lcp"].batch.energy_change
    scenes = [sample.scene for sample in every]
    pairs = [("pymunk", "accurate"), ("box2d", "defaults")]
    one = survey_engines.run_pairs(pairs, scenes, terms.problems, energy, workers=1)
    # slices of 7 scenes: several per pair, the last one short
    monkeypatch.setattr(survey_engines, "PAIR_SLICE", 7)
    two = survey_engines.run_pairs(pairs, scenes, terms.problems, energy, workers=2)
    assert [(r.engine, r.preset) for r in two] == pairs
    for single, joined in zip(one, two):
        assert len(joined.status) == len(scenes)
        np.testing.assert_array_equal(single.velocities, joined.velocities)  # bit for bit
        for field in ("engine_status", "status", "reasons", "steps"):
            np.testing.assert_array_equal(getattr(single, field), getattr(joined, field))
