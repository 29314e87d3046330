"""The verdicts' fast path gives the judge's decisions (harness/run/verdicts/).

The survey judges thousands of engine runs, so the verdicts work out what a scene alone
determines once (``prepare``, ``SceneTerms``), place every contact point of a run against
every feature at once (``ContactTrack``), and judge a whole batch as arrays (``judge_many``,
``run_engine``'s columns). None of it may change a verdict. The judge's decisions themselves
are held against the physics in ``tests/run/test_verdict_decisions.py`` (each check's bound
worked out by hand, on both sides and within its rounding band); here real engine runs (every
engine and preset, scenes sampled from every population and every point of the library) are
judged by every path the harness has, and all must agree:

* the judge given the scene's terms and the runs' contact records as arrays (the survey's
  inputs) against the judge working everything out from per-step records;
* the judge's ``multi-contact`` decision against the rule docs/verdicts.md states
  ('Multi-contact: features, not point counts'), spelled out point by point below;
* ``run_engine``'s status and reasons against the judge, run by run;
* the runner's path (task output -> ``numbers_from_output``) against the survey's
  (``EngineRun`` -> ``numbers_from_run``), declared flat faces included.

Each at the default tolerances and at strict ones that make every check fire.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness import engines as engines_module
from harness.engines import ENGINE_NAMES, PRESET_ROLES, UnsupportedScene, body_extent
from harness.run import tasks, verdicts
from harness.run.verdicts import (
    DEFAULT_TOLERANCES,
    RunNumbers,
    StepContacts,
    Tolerances,
    Verdict,
)
from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.scene import features as scene_features
from harness.scene import geometry
from harness.scene.features import feature_points
from harness.survey import laws as survey_laws
from harness.survey.engines import run_engine
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

PAIRS = [(engine, preset) for engine in ENGINE_NAMES for preset in PRESET_ROLES]


def overrides_of(engine, preset) -> dict:
    """Drake's accurate contact lasts 500 steps (ten times MuJoCo's 50), each placed point by
    point by the rule below: Drake is judged on 50 steps of the same 0.5 ms contact (its own
    ``time_step_overrides``), through the same verdict paths."""
    if engine.name == "drake" and preset == "accurate":
        return engine.time_step_overrides(preset, 1e-5)
    return {}


SAMPLES = 8  # per population
#: Every bound tight enough that every check fires on some run (and multi-contact's reach
#: small, so a point counts at a feature only very near it).
STRICT = Tolerances(separation=1e-9, penetration=1e-3, impulse_residual=1e-12, impulse=1e-12,
                    energy=1e-15, energy_beyond_law=1e-3, cap=0.999)
#: A wide reach: points count at a feature far from it, so more runs touch a second one.
WIDE = Tolerances(penetration=0.5)
TOLERANCES = (DEFAULT_TOLERANCES, STRICT, WIDE)


def plain_numbers(run) -> RunNumbers:
    """An ``EngineRun``'s numbers with its contact records as per-step tuples (what the
    judge takes from any caller), not the arrays ``numbers_from_run`` builds."""
    numbers = verdicts.numbers_from_run(run)
    steps = tuple(StepContacts(step.step, tuple(tuple(p) for p in step.points), step.poses)
                  for step in run.contacts)
    return dataclasses.replace(numbers, contacts=steps)


#: The rule's band: a point whose distance from a feature lies within this of its reach
#: (relative to the body's extent) is placed either way by the last bits of a turn (the
#: judge's and the rule's turns round differently); such runs are not compared.
REACH_BAND = 1e-9


def rule_feature(shape, state, point, depth, tolerances) -> tuple[int | None, bool]:
    """The feature (corner, end cap) of a body of ``shape`` in pose ``state`` that ``point``
    touches: the nearest one within ``penetration · extent`` plus the point's depth, else
    None (a face); and whether a distance lies within :data:`REACH_BAND` of the reach."""
    centres, radius, _ = feature_points(shape)
    x, y, angle = state[0], state[1], state[2]
    c, s = math.cos(angle), math.sin(angle)
    extent = body_extent(shape)
    reach = tolerances.penetration * extent + max(depth, 0.0)
    found, near = None, False
    for index, (cx, cy) in enumerate(np.asarray(centres, dtype=float).tolist()):
        distance = math.hypot(x + c * cx - s * cy - point[0], y + s * cx + c * cy - point[1])
        distance -= radius
        near |= abs(distance - reach) <= REACH_BAND * extent
        if distance <= reach and (found is None or distance < found[0]):
            found = (distance, index)
    return (None if found is None else found[1]), near


def rule_second_feature(scene, steps, tolerances) -> tuple[tuple[int, str] | None, bool]:
    """docs/verdicts.md's rule: the scene's contact point (in its pose) and the first
    recorded point fix the contact's features; a later point at another corner or end cap
    of a body is ``multi-contact``. ``((step, feature name) or None, whether a placement was
    within the band)``."""
    near = False
    point = geometry.scene_contact(scene).point
    at_contact = []
    for body in scene.bodies:
        feature, close = rule_feature(body.shape, (*body.position, body.angle), point, 0.0,
                                      tolerances)
        at_contact.append(feature)
        near |= close
    first = None
    for step in steps:
        for point in step.points:
            touched = []
            for body, state in zip(scene.bodies, step.poses):
                feature, close = rule_feature(body.shape, state, point[:2], point[2], tolerances)
                touched.append(feature)
                near |= close
            if first is None:
                first = touched
                continue
            for body, now, then, own in zip(scene.bodies, touched, first, at_contact):
                if now is not None and now != then and now != own:
                    return (step.step, feature_points(body.shape)[2][now]), near
    return None, near


def multi_contact_of(verdict: Verdict) -> tuple[int, str] | None:
    reason = next((r for r in verdict.failing if r.name == "multi-contact"), None)
    if reason is None:
        return None
    return int(reason.value), reason.detail


@pytest.fixture(scope="module")
def survey_scenes():
    """Scenes of every population, their impacts and newton-lcp's energy changes."""
    samples = [sample for population in resolve_populations([])
               for sample in sample_population(population, SAMPLES, 0).samples]
    terms = survey_laws.contact_terms(samples)
    lcp = survey_laws.solve_laws(terms)["newton-lcp"].batch.energy_change
    return [sample.scene for sample in samples], terms.problems, np.asarray(lcp)


@pytest.mark.parametrize(("engine_name", "preset"), PAIRS)
def test_survey_runs_get_one_verdict_by_the_fast_and_the_plain_inputs(
        engine_name, preset, survey_scenes, load_or_skip):
    """Every reason, remarks included, with the same numbers (``repr`` tells every float
    apart), from the scene's prepared terms and the records as arrays as from nothing
    prepared and per-step records; and ``multi-contact`` where the rule puts it."""
    engine = load_or_skip(engine_name)
    scenes, problems, lcp = survey_scenes
    runs = engine.run_many(scenes, engine.settings(preset, overrides_of(engine, preset)))
    prepared = verdicts.prepare_many(scenes, problems)
    seen, placed, second, banded = set(), 0, 0, 0
    for row, run in enumerate(runs):
        fast, plain = verdicts.numbers_from_run(run), plain_numbers(run)
        if not prepared[row].one_feature:
            placed += len(fast.contacts.points)
        for tolerances in TOLERANCES:
            for gain in (float(lcp[row]), None):
                expected = verdicts.judge(scenes[row], problems[row], plain,
                                          law_energy_change=gain, tolerances=tolerances)
                got = verdicts.judge(scenes[row], problems[row], fast, law_energy_change=gain,
                                     tolerances=tolerances, terms=prepared[row])
                assert repr(got) == repr(expected), (row, scenes[row].name)
                seen.update(reason.name for reason in expected.reasons)
            if run.status.value not in ("ok", "multi-contact") or prepared[row].one_feature:
                continue
            rule, near = rule_second_feature(scenes[row], run.contacts, tolerances)
            if near:
                banded += 1
                continue
            judged = multi_contact_of(expected)
            assert (judged is None) == (rule is None), (row, scenes[row].name, rule, judged)
            if rule is not None:
                second += 1
                step, name = rule
                assert judged[0] == step and f"'s {name} touched" in judged[1], (rule, judged)
    # the runs exercise what the fast path rewrote: points placed at corners and end caps
    # (more than one per run), the implied impulse; the rule decided nearly every run
    assert placed > len(runs) and "impulse-residual" in seen, (placed, seen)
    assert banded <= len(runs) // 20, banded


@pytest.mark.parametrize(("engine_name", "preset"), PAIRS)
def test_the_survey_columns_are_the_judges_verdicts(engine_name, preset, survey_scenes,
                                                    load_or_skip):
    """``run_engine``'s status and reasons, judged with the scene terms it works out or is
    given (as the survey's parts give them), are the judge's run by run (runs are
    deterministic: ``run_many`` again)."""
    engine = load_or_skip(engine_name)
    scenes, problems, lcp = survey_scenes
    overrides = overrides_of(engine, preset)
    results = run_engine(engine_name, preset, scenes, problems, lcp, overrides=overrides)
    again = run_engine(engine_name, preset, scenes, problems, lcp,
                       verdicts.prepare_many(scenes, problems), overrides=overrides)
    runs = engine.run_many(scenes, engine.settings(preset, overrides))
    for row, run in enumerate(runs):
        expected = verdicts.judge(scenes[row], problems[row], plain_numbers(run),
                                  law_energy_change=float(lcp[row]))
        for result in (results, again):
            assert result.status[row] == expected.status(run.status.value)
            assert result.reasons[row] == ",".join(expected.names)


class Replay:
    """An engine whose ``run`` returns a run already made (so the runner's task output and
    the run itself come from one simulation)."""

    def __init__(self, engine, run):
        self.timing, self.recorded = engine.timing, run

    def run(self, scene, settings):
        return self.recorded


def library_points():
    for path in sorted(SCENARIO_DIR.glob("*.toml")):
        scenario = load_scenario(path)
        if scenario.analytic_only:
            continue
        for point in scenario.point_list():
            yield scenario, point


@pytest.mark.slow
@pytest.mark.parametrize(("engine_name", "preset"), PAIRS)
def test_the_runners_and_the_surveys_numbers_get_one_verdict(engine_name, preset, monkeypatch,
                                                             load_or_skip):
    """Every library point (declared flat faces through ``judge_declared``): the verdict of
    the runner's task output is that of the run itself, and of its per-step records."""
    engine = load_or_skip(engine_name)
    settings = engine.settings(preset, overrides_of(engine, preset))
    judged = declared_judged = 0
    for scenario, point in library_points():
        scene = scenario.scene(point)
        problem = scenario.analytic_problem(point)
        try:
            run = engine.run(scene, settings)
        except UnsupportedScene:
            continue
        monkeypatch.setattr(engines_module, "load_engine", lambda name, run=run: Replay(
            engine, run))
        output = tasks.engine_task({"engine": engine_name, "scene": scene,
                                     "settings": settings})
        assert output["status"] == run.status
        declared = verdicts.declared_contacts(scenario, scene)
        try:
            lcp = problem.solve(mu=scene.friction, e=scene.restitution,
                                law="newton-lcp").energy_change
        except ValueError:
            lcp = None
        for tolerances in TOLERANCES:
            for gain in {lcp, None}:
                expected = verdicts.judge(scene, problem, plain_numbers(run),
                                          law_energy_change=gain, tolerances=tolerances,
                                          contacts=declared)
                for numbers in (verdicts.numbers_from_run(run),
                                verdicts.numbers_from_output(engine_name, output)):
                    got = verdicts.judge(scene, problem, numbers, law_energy_change=gain,
                                         tolerances=tolerances, contacts=declared)
                    assert repr(got) == repr(expected), (scenario.name, point)
        judged += 1
        declared_judged += declared is not None
    assert judged and declared_judged, (judged, declared_judged)


@pytest.mark.parametrize("shape", ["box", "rod", "disk"])
def test_feature_at_is_the_rule_one_point_at_a_time(shape):
    """The public one-point ``feature_at`` against the rule, at points all around the body in
    many poses and reaches (near corners and end caps, on faces, far away)."""
    from harness.scene import Box, Disk, Rod

    body = {"box": Box(0.3, 0.1), "rod": Rod(0.4, 0.02), "disk": Disk(0.1)}[shape]
    rng = np.random.default_rng(7)
    centres = feature_points(body)[0]
    extent = body_extent(body)
    found, compared = set(), 0
    for _ in range(400):
        state = (*rng.normal(size=2), rng.uniform(-7, 7))
        near = (centres[rng.integers(len(centres))] if len(centres) else np.zeros(2))
        c, s = math.cos(state[2]), math.sin(state[2])
        point = (near @ np.array([[c, s], [-s, c]]) + state[:2]
                 + rng.normal(scale=rng.choice([1e-4, 1e-2, 0.2]), size=2))
        share = float(rng.choice([0.0, 1e-3, 0.02, 0.5]) / extent)
        expected, close = rule_feature(body, state, point, 0.0, Tolerances(penetration=share))
        if close:
            continue
        assert scene_features.feature_at(body, state, point, share * extent) == expected
        found.add(expected)
        compared += 1
    assert compared > 390
    assert len(found) == (1 if shape == "disk" else len(centres) + 1)  # every one, and None
