"""pymunk's batches own Chipmunk's bodies and shapes: freed once, also when half built.

A batch's bodies and shapes are made through pymunk's C library, without pymunk's wrappers
(harness/engines/pymunk_engine.py ``_fill_batch``), so the batch frees them itself. A
mistake there (a shape removed twice, a body freed while in the space) makes Chipmunk
abort() or corrupts memory: the failure cases run in a child process, so that a regression
shows as a failed test, not a crashed worker.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

pytest.importorskip("pymunk")

from harness.engines import load_engine  # noqa: E402
from harness.engines.pymunk_engine import MANY_GROUND  # noqa: E402
from harness.survey.population import resolve_populations  # noqa: E402
from harness.survey.sampling import sample_population  # noqa: E402


def test_a_batch_that_fails_while_built_is_freed_and_the_engine_runs_on(tmp_path):
    # The 5th shape fails: the batch holds whole impacts, one body without its shape, and
    # nothing more; freeing it must take out only what is in the space.
    script = tmp_path / "half_built.py"
    script.write_text(
        "from harness.scene.reference import reference_scenes\n"
        "from harness.engines import load_engine, pymunk_engine\n"
        "engine = load_engine('pymunk')\n"
        "scenes = [scene for scene, _, _ in reference_scenes().values()]\n"
        "real = pymunk_engine._new_shape_ptr\n"
        "made = []\n"
        "def failing(body_ptr, shape):\n"
        "    if len(made) == 4:\n"
        "        raise RuntimeError('shape failed')\n"
        "    made.append(shape)\n"
        "    return real(body_ptr, shape)\n"
        "pymunk_engine._new_shape_ptr = failing\n"
        "try:\n"
        "    engine.run_many(scenes, preset='defaults')\n"
        "    raise SystemExit('no failure')\n"
        "except RuntimeError:\n"
        "    pass\n"
        "pymunk_engine._new_shape_ptr = real\n"
        "single = [engine.run(scene, preset='defaults') for scene in scenes]\n"
        "assert engine.run_many(scenes, preset='defaults') == single\n"
        "print('usable')\n"
    )
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and "usable" in done.stdout, done.stderr[-2000:]


def test_release_frees_retired_and_running_impacts_once():
    # Retire some impacts (out of the space), then free the batch (the rest still in it):
    # every impact taken out once; freeing twice does nothing.
    engine = load_engine("pymunk")
    settings = engine.settings("defaults")
    scenes = [sample.scene for population in resolve_populations([])
              for sample in sample_population(population, 3, seed=1).samples]
    scenes = [scene for scene in scenes if scene.ground][:MANY_GROUND]
    plans = [engine._new_plan(scene, settings, None, None, tuple(
        (body.mass, body.moment_of_inertia) for body in scene.bodies)) for scene in scenes]
    batch, worlds, _ = engine._build_many(plans)
    engine._step_many(batch, range(len(plans)))
    for slot in range(0, len(plans), 2):
        engine._retire(batch, slot)
        engine._retire(batch, slot)  # a second retire is a no-op
    assert [world.in_space for world in worlds] == [slot % 2 == 1 for slot in range(len(plans))]
    engine._release_many(batch)
    assert not any(world.in_space for world in worlds) and batch.slots == []
    engine._release_many(batch)
    assert engine.run_many(scenes, settings) == [engine.run(scene, settings) for scene in scenes]


def test_the_batch_space_serves_the_next_batches_whatever_their_settings():
    # Every batch after the first steps in the first one's space (emptied, its ground kept):
    # two-body impacts after ground ones, other iterations, another time step -- each run
    # still the single run, bit for bit.
    engine = load_engine("pymunk")
    scenes = [sample.scene for population in resolve_populations([])
              for sample in sample_population(population, 5, seed=2).samples]
    ground_first = sorted(scenes, key=lambda scene: not scene.ground)
    engine.run_many(ground_first[:1], preset="defaults")
    space = engine._batch_space
    assert space is not None and space.ground
    for preset, overrides in (("defaults", None), ("accurate", None),
                              ("accurate", {"time_step": 1.0 / 120.0, "iterations": 7})):
        batched = engine.run_many(ground_first, preset=preset, overrides=overrides)
        single = [engine.run(scene, preset=preset, overrides=overrides)
                  for scene in ground_first]
        assert batched == single
        assert engine._batch_space is space
