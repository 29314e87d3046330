"""The survey in parts on several worker processes equals the survey of one, to the bit."""

from __future__ import annotations

import contextlib
import os
import tomllib

import numpy as np
import pytest

from harness.scenarios.errors import ScenarioError
from harness.survey import parts as survey_parts
from harness.survey.cli import run_survey
from harness.survey.population import parse_population, resolve_populations
from harness.survey.sampling import sample_population, sample_range

SAMPLES = 5  # per population


def same_columns(one: dict, other: dict) -> None:
    assert list(one) == list(other)
    for name in one:
        np.testing.assert_array_equal(one[name], other[name], err_msg=name)  # NaNs alike


def test_parts_on_two_workers_join_to_the_survey_of_one_process(monkeypatch):
    pytest.importorskip("pymunk")
    pytest.importorskip("Box2D")
    populations = resolve_populations([])
    arguments = (populations, SAMPLES, 3, ["pymunk", "box2d"], ["defaults", "accurate"])
    one = run_survey(*arguments, workers=1, echo=lambda _: None)
    # parts of 2, 2 and 1 samples per population
    monkeypatch.setattr(survey_parts, "MIN_PART", 2)
    assert survey_parts.part_bounds(SAMPLES, 2) == [(0, 2), (2, 4), (4, 5)]
    two = run_survey(*arguments, workers=2, echo=lambda _: None)
    for table in ("samples", "runs", "statistics"):
        same_columns(one[table], two[table])
    assert one["rejections"] == two["rejections"]
    for single, joined in zip(one["engine_results"], two["engine_results"], strict=True):
        np.testing.assert_array_equal(single.velocities, joined.velocities)
    # the rows are the samples of one process, in population then index order
    every = [sample for population in populations
             for sample in sample_population(population, SAMPLES, 3).samples]
    assert two["samples"]["family"].tolist() == [sample.population for sample in every]
    assert two["samples"]["sample"].tolist() == [sample.index for sample in every]


def test_the_parts_cpu_time_is_counted_per_process(monkeypatch):
    """One process runs the single part itself; two workers' parts run in forked processes,
    and their CPU times add up per process."""
    pytest.importorskip("pymunk")
    populations = resolve_populations([])[:2]
    one = survey_parts.run_parts(populations, 4, 0, [("pymunk", "defaults")], workers=1)
    assert list(one.worker_cpu) == [os.getpid()] and one.worker_cpu[os.getpid()] > 0
    monkeypatch.setattr(survey_parts, "MIN_PART", 1)
    two = survey_parts.run_parts(populations, 4, 0, [("pymunk", "defaults")], workers=2)
    assert two.parts == 4 and 1 <= len(two.worker_cpu) <= 2
    assert os.getpid() not in two.worker_cpu and all(s > 0 for s in two.worker_cpu.values())


def test_parts_cover_the_samples_largest_first():
    for samples in (1, 15, 16, 17, 500, 2000):
        for workers in (1, 2, 3, 8):
            bounds = survey_parts.part_bounds(samples, workers)
            assert bounds[0][0] == 0 and bounds[-1][1] == samples
            assert all(end == begin for (_, end), (begin, _) in zip(bounds, bounds[1:]))
            sizes = [end - begin for begin, end in bounds]
            assert sizes == sorted(sizes, reverse=True) and min(sizes) > 0
            assert len(bounds) == 1 or workers > 1


FLAT = """
name = "flat"
restitution = 0.5
friction = 0.5
max_attempts = 3
[ground]
[approach]
speed = 1.0
direction_deg = 0.0
[[body]]
name = "box"
shape = "box"
width = 0.4
height = 0.2
mass = 1.0
angle_deg = { choice = [0.0, 0.0, 0.0, 30.0] }
"""


def test_a_refused_sample_is_the_same_error_on_any_number_of_workers(monkeypatch):
    """The first sample (in population, then index order) that needs too many draws names
    the error, whichever part drew it."""
    monkeypatch.setattr(survey_parts, "MIN_PART", 1)
    population = parse_population(tomllib.loads(FLAT), "flat.toml")
    errors = []
    for workers in (1, 2):
        with pytest.raises(ScenarioError) as caught:
            run_survey([population], 12, 1, [], ["defaults"], workers=workers,
                       echo=lambda _: None)
        errors.append(caught.value)
    assert str(errors[0]) == str(errors[1]) and errors[0].sample == errors[1].sample
    # more than one part refused a sample: the first one's is the error
    refused = []
    for begin, end in survey_parts.part_bounds(12, 2):
        with contextlib.suppress(ScenarioError):
            sample_range(population, begin, end, 1)
            continue
        refused.append((begin, end))
    assert len(refused) > 1 and refused[0][0] <= errors[0].sample < refused[0][1]
    assert errors[0].path == "flat.toml" and errors[0].key == "max_attempts"
