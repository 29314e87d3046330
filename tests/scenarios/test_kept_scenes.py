"""A scenario keeps each point's scene once built (Scenario.scene): the same scene as built
anew, never in the scenario's pickles and copies (the store of passed checks)."""

from __future__ import annotations

import copy
import pickle

import numpy as np

from harness.scenarios import load_scenarios

SCENARIOS = [s for s in load_scenarios() if not s.analytic_only]


def test_a_kept_scene_is_the_scene_built_anew_at_each_point():
    swept = 0
    for scenario in SCENARIOS:
        for point in scenario.point_list():
            scene = scenario.scene(point)
            assert scenario.scene(point.index) is scene
            fresh = copy.copy(scenario)  # keeps nothing: builds again
            assert fresh.kept_scenes() == {}
            assert fresh.scene(point) == scene and fresh.scene(point) is not scene
            assert fresh.at(point).scene() == scene
        scenes = [scenario.scene(point) for point in scenario.point_list()]
        swept += len({id(scene) for scene in scenes}) == len(scenes) > 1
    assert swept >= 4  # sweeps keep one scene per point


def test_the_analytic_problem_is_the_kept_scenes():
    for scenario in SCENARIOS:
        for point in scenario.point_list():
            kept = scenario.analytic_problem(point)
            fresh = copy.copy(scenario).at(point).analytic_problem()
            for name in ("mass_matrix", "wn", "wt", "u"):
                assert np.array_equal(getattr(kept, name), getattr(fresh, name))


def test_pickles_and_copies_leave_the_scenes_out():
    scenario = next(s for s in SCENARIOS if s.sweep is not None)
    scenario.scene(1)
    assert 1 in scenario.kept_scenes()
    for other in (pickle.loads(pickle.dumps(scenario)), copy.copy(scenario),
                  scenario.located(None)):
        assert other == scenario.located(other.path) and other.kept_scenes() == {}


def test_scenes_kept_elsewhere_are_served_as_built_here():
    """``keep_scenes`` (the forked checks' scenes, sent back) makes ``scene`` serve them."""
    scenario = next(s for s in SCENARIOS if s.sweep is not None)
    built = {point.index: scenario.scene(point) for point in scenario.point_list()}
    fresh = copy.copy(scenario)
    fresh.keep_scenes(built)
    assert all(fresh.scene(index) is scene for index, scene in built.items())
    assert fresh.kept_scenes() == built and fresh.kept_scenes() is not built
