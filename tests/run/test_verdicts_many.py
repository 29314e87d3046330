"""The batched verdicts (``verdicts.judge_many``) give ``judge``'s status and reasons, run by run.

Every engine and preset over scenes sampled from every population, at the default tolerances
and at strict and wide ones (every check fires on some run), with and without the law's
energy change; and at tolerances set exactly on a run's own values, where the batch must
leave the run to ``judge`` (its roundings could decide otherwise).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.engines import ENGINE_NAMES, PRESET_ROLES, load_engine
from harness.run import verdicts
from harness.run.verdicts import DEFAULT_TOLERANCES, Tolerances, touching
from harness.survey import laws as survey_laws
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

PAIRS = [(engine, preset) for engine in ENGINE_NAMES for preset in PRESET_ROLES]
SAMPLES = 6  # per population
STRICT = Tolerances(separation=1e-9, penetration=1e-3, impulse_residual=1e-12, impulse=1e-12,
                    energy=1e-15, energy_beyond_law=1e-3, cap=0.999)
WIDE = Tolerances(penetration=0.5)


@pytest.fixture(scope="module")
def survey_scenes():
    samples = [sample for population in resolve_populations([])
               for sample in sample_population(population, SAMPLES, 2).samples]
    terms = survey_laws.contact_terms(samples)
    lcp = survey_laws.solve_laws(terms)["newton-lcp"].batch.energy_change
    scenes = [sample.scene for sample in samples]
    prepared = verdicts.prepare_many(scenes, terms.problems)
    return scenes, terms.problems, np.asarray(lcp), prepared


def one_by_one(scenes, problems, runs, prepared, lcp, tolerances):
    judged = []
    for row, run in enumerate(runs):
        verdict = verdicts.judge(scenes[row], problems[row], verdicts.numbers_from_run(run),
                                 law_energy_change=None if lcp is None else float(lcp[row]),
                                 tolerances=tolerances, terms=prepared[row])
        judged.append((verdict.status(run.status.value), ",".join(verdict.names)))
    return judged


def speeds(runs) -> np.ndarray:
    padded = np.zeros((len(runs), verdicts.ARRAY_WIDTH))
    for row, run in enumerate(runs):
        padded[row, :len(run.u_after)] = run.u_after
    return padded


@pytest.mark.parametrize(("engine_name", "preset"), PAIRS)
def test_judge_many_is_judge_run_by_run(load_or_skip, engine_name, preset, survey_scenes):
    engine = load_or_skip(engine_name)
    scenes, problems, lcp, prepared = survey_scenes
    runs = engine.run_many(scenes, engine.settings(preset))
    arrays = verdicts.term_arrays(problems, prepared)
    seen = set()
    for tolerances in (DEFAULT_TOLERANCES, STRICT, WIDE):
        for gain in (lcp, None):
            expected = one_by_one(scenes, problems, runs, prepared, gain, tolerances)
            batched = verdicts.judge_many(scenes, problems, runs, speeds(runs), prepared,
                                          arrays, law_energy_change=gain,
                                          tolerances=tolerances)
            assert batched == expected
            seen.update(name for _, names in expected for name in names.split(",") if name)
    assert "impulse-residual" in seen, seen  # the strict bound: every check ran


def test_a_value_on_its_bound_is_left_to_judge(survey_scenes):
    """Tolerances set to a run's own separation, residual, mismatch and energy gain (each
    value then lies on its bound, within the batch's roundings): the same verdicts."""
    engine = load_engine("pymunk")
    scenes, problems, lcp, prepared = survey_scenes
    runs = engine.run_many(scenes, engine.settings("defaults"))
    arrays = verdicts.term_arrays(problems, prepared)
    row = next(i for i, run in enumerate(runs) if run.status.value == "ok")
    numbers = verdicts.numbers_from_run(runs[row])
    scales, problem = prepared[row].scales, problems[row]
    normal, tangential, residual = verdicts.impulse_from_velocities(
        problem, numbers.u_after, scales.speed_norm)
    separation = -float(problem.wn @ numbers.u_after) / scales.approach_speed
    gap = np.hypot(numbers.normal_impulse - normal,
                   (numbers.tangential_impulse or 0.0) - tangential) / scales.impulse
    for field, value in (("separation", separation), ("impulse_residual", residual),
                         ("impulse", gap)):
        tolerances = dataclasses.replace(DEFAULT_TOLERANCES, **{field: float(value)})
        expected = one_by_one(scenes, problems, runs, prepared, lcp, tolerances)
        assert verdicts.judge_many(scenes, problems, runs, speeds(runs), prepared, arrays,
                                   law_energy_change=lcp, tolerances=tolerances) == expected


@pytest.mark.parametrize(("engine_name", "preset"), PAIRS)
def test_second_features_of_many_runs_are_each_runs(load_or_skip, engine_name, preset,
                                                    survey_scenes):
    """The batched second-feature check reads every run's raw records at once: the same
    answer as the check of each run's own track, for every run (runs without contact and of
    one point included), at the default tolerances and a tight penetration reach, and with
    the runs shuffled (runs of one and of two bodies interleaved)."""
    engine = load_or_skip(engine_name)
    scenes, _, _, prepared = survey_scenes
    runs = engine.run_many(scenes, engine.settings(preset))
    shuffled = np.random.default_rng(0).permutation(len(runs)).tolist()
    for tolerances in (DEFAULT_TOLERANCES, Tolerances(penetration=1e-3)):
        for order in (range(len(runs)), shuffled):
            records = [runs[row].contact_record for row in order]
            features = [prepared[row].features for row in order]
            expected = [bool(touching.second_features(
                scenes[row], verdicts.ContactTrack.from_record(record), tolerances, bodies))
                for row, record, bodies in zip(order, records, features)]
            assert touching.second_features_many(records, features, tolerances,
                                                  [scenes[row] for row in order]) == expected


def _terms_bits(terms) -> tuple:
    """Every number of a ``SceneTerms``, exactly (``repr`` of a float round-trips)."""
    return (repr(terms.scales), repr(terms.delassus), repr(terms.norm_before),
            terms.one_feature, [(body.centres.tobytes(), body.radius, body.names, body.extent)
                                for body in terms.features])


def test_prepare_many_is_prepare_scene_by_scene(survey_scenes):
    """The stacked Delassus solves of ``prepare_many`` (one body against the ground and two
    bodies mixed) give ``prepare``'s terms to the last bit."""
    scenes, problems, _, prepared = survey_scenes
    assert {len(problem.u) for problem in problems} == {3, 6}
    expected = [_terms_bits(verdicts.prepare(scene, problem))
                for scene, problem in zip(scenes, problems)]
    assert [_terms_bits(terms) for terms in prepared] == expected
    shuffled = np.random.default_rng(1).permutation(len(scenes)).tolist()
    assert ([_terms_bits(terms) for terms in verdicts.prepare_many(
        [scenes[row] for row in shuffled], [problems[row] for row in shuffled])]
            == [expected[row] for row in shuffled])
