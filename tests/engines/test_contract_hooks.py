"""The contract's hooks for adapters: ``_runs_alone``, the weights ``_prepare`` is given,
the collector paused in ``run_many``, and ``count_planar_points``'s two-point path."""

from __future__ import annotations

import gc
import math

import pytest

from harness.engines import contract
from harness.engines.contract import Engine, count_planar_points
from harness.scene.reference import reference_scenes


@pytest.fixture(scope="module")
def scenes():
    return [scene for scene, _, _ in reference_scenes().values()][:6]


# ---------------------------------------------------------------------- count_planar_points
TOLERANCE = 1e-6
PAIRS = [
    ((0.0, 0.0), (0.0, 0.0)),
    ((0.5, 0.25), (0.5, -0.25)),
    ((1.0, 2.0), (1.0 + TOLERANCE, 2.0 - TOLERANCE)),  # at the tolerance: one point
    ((1.0, 2.0), (1.0 + 2 * TOLERANCE, 2.0)),
    ((1.0, 2.0), (1.0, 2.0 + 2 * TOLERANCE)),
    ((-3.0, 0.1), (3.0, 0.1)),
    ((math.nan, 0.0), (0.0, 0.0)),  # a comparison with nan is False: as the general loop
    ((0.0, 0.0), (math.inf, 0.0)),
]


@pytest.mark.parametrize(("first", "second"), PAIRS)
def test_two_points_count_as_the_general_loop_counts_them(first, second):
    # A tuple and an iterator take the general loop; the list of two the fast path.
    general = count_planar_points(iter([first, second]), TOLERANCE)
    assert count_planar_points((first, second), TOLERANCE) == general
    assert count_planar_points([first, second], TOLERANCE) == general
    assert count_planar_points([second, first], TOLERANCE) == general


def test_two_points_apart_are_two_and_close_are_one():
    assert count_planar_points([(0.0, 0.0), (0.0, 0.5 * TOLERANCE)], TOLERANCE) == 1
    assert count_planar_points([(0.0, 0.0), (0.0, 3.0 * TOLERANCE)], TOLERANCE) == 2


# ---------------------------------------------------------------------- _runs_alone
def test_the_base_never_runs_alone(load_or_skip):
    engine = load_or_skip("pymunk")
    assert engine._runs_alone(engine.settings("accurate")) is False


def test_run_many_runs_one_by_one_where_the_adapter_says_so(load_or_skip, scenes, monkeypatch):
    engine = load_or_skip("pymunk")
    settings = engine.settings("accurate")
    single = [engine.run(scene, settings) for scene in scenes]

    def no_batch(plans):
        raise AssertionError("batched although _runs_alone said no")

    monkeypatch.setattr(engine, "_runs_alone", lambda resolved: resolved is not None)
    monkeypatch.setattr(engine, "_build_many", no_batch)
    assert engine.run_many(scenes, settings) == single


def test_box2d_leaves_run_many_to_the_base_and_runs_sub_stepping_alone(load_or_skip):
    engine = load_or_skip("box2d")
    assert type(engine).run_many is Engine.run_many
    assert engine._runs_alone(engine.settings("accurate", {"sub_stepping": True}))
    assert not engine._runs_alone(engine.settings("accurate", {"sub_stepping": False}))


# ---------------------------------------------------------------------- the collector
@pytest.mark.parametrize("name", ["pymunk", "mujoco"])  # batched, and one by one
@pytest.mark.parametrize("enabled_before", [True, False])
def test_run_many_pauses_the_collector_and_restores_it(load_or_skip, name, enabled_before, scenes,
                                                       monkeypatch):
    engine = load_or_skip(name)
    seen = []
    step = engine._step_many if type(engine)._build_many is not Engine._build_many else None
    if step is not None:
        monkeypatch.setattr(engine, "_step_many",
                            lambda *args: seen.append(gc.isenabled()) or step(*args))
    else:
        one = engine._step
        monkeypatch.setattr(engine, "_step", lambda world: seen.append(gc.isenabled())
                            or one(world))
    was = gc.isenabled()
    try:
        (gc.enable if enabled_before else gc.disable)()
        engine.run_many(scenes, preset="accurate")
        assert gc.isenabled() is enabled_before
    finally:
        (gc.enable if was else gc.disable)()
    assert seen and not any(seen)


# ---------------------------------------------------------------------- _prepare's weights
def test_mujoco_prepare_takes_the_weights_it_is_given(load_or_skip, scenes):
    # The geometry is built from the checked inertias passed in, not recomputed or read
    # from the base's caches: different weights give a different geometry key.
    engine = load_or_skip("mujoco")
    settings = engine.settings("accurate")
    scene = scenes[0]
    weights = contract.check_scene("mujoco", scene)
    start = contract.start_states(scene, settings, engine.timing)[1]
    prepared = engine._prepare(None, scene, settings, start, weights)
    doubled = tuple((mass, 2.0 * inertia) for mass, inertia in weights)
    other = engine._prepare(None, scene, settings, start, doubled)
    assert prepared[-1].key != other[-1].key
    assert engine._prepare(None, scene, settings, start, weights)[-1].key == prepared[-1].key
