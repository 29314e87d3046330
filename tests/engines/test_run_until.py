"""``Scene.run_until``: the contract runs a sequence of impacts through, for every engine.

A tilt's reference is a sequence of impacts (the far corner strikes a few steps after the
first); an engine run that ended at its first separation was only the first impact. With
``run_until`` set, a separation ends the run only from ``ceil(run_until / time_step) +
SEQUENCE_MARGIN_STEPS`` steps after the first contact on, in ``run`` and ``run_many`` alike.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from harness.engines import ENGINE_NAMES
from harness.engines.contract import SEQUENCE_MARGIN_STEPS
from harness.reference.event_driven import sequence_outline
from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.scene import Scene

TILTED = load_scenario(SCENARIO_DIR / "sweep-tilted-box.toml")


def tilted_scene(index: int) -> Scene:
    return TILTED.scene(TILTED.point_list()[index])


def test_run_until_must_be_a_finite_time():
    for bad in (-1.0, math.inf, math.nan):
        with pytest.raises(ValueError, match="run_until"):
            replace(tilted_scene(0), run_until=bad)


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_every_engine_runs_through_separations_until_the_time(load_or_skip, name):
    engine = load_or_skip(name)
    scene = tilted_scene(-1)  # 3°: the far corner strikes about 3 steps of 1/60 s later
    outline = sequence_outline(scene)
    assert outline.features == (0, 1) and outline.last_impact > 0.0
    through = replace(scene, run_until=outline.last_impact)
    for preset in ("defaults", "accurate"):
        settings = engine.settings(preset)
        short, whole = engine.run(scene, settings), engine.run(through, settings)
        assert whole.first_contact_step is not None
        wanted = math.ceil(outline.last_impact / settings["time_step"]) + SEQUENCE_MARGIN_STEPS
        assert whole.steps >= min(whole.first_contact_step + wanted, settings["max_steps"])
        assert whole.steps > short.steps
        assert whole.separated or whole.step_cap_hit
        # run_many is run, bit for bit, with and without the time
        assert engine.run_many([through, scene, through], settings) == [whole, short, whole]
