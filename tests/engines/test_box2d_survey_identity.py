"""Box2D's runs of survey scenes are the runs of the adapter at commit fc059af, to the
bound of tests/engines/survey_identity.py (bit for bit on the machine that recorded them).

The stored file (see tests/engines/survey_identity.py) holds 350 survey scenes and, per
preset, the values of each of their runs -- velocities, status, steps, impulses, the
contact record, derived values and notes -- recorded with the adapter at commit fc059af
(``run_many``). It replaced the pin of commit 41a1da8 (the adapter before session 6's
speed-ups) when ``accurate``'s velocity scale and start depth came to be computed from the
scene instead of a probe run: ``defaults`` the same runs bit for bit; ``accurate`` the same
statuses, steps and notes, velocities within 2e-6 of the largest speed (the start depth
from the computed speed), three velocity scales other where the probe had misread the
speed, and ``derived`` with ``velocity_scale_at_boundary``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("Box2D", reason="Box2D not installed (pip install box2d==2.3.10)")

STORED = Path(__file__).parent.parent / "data" / "box2d-survey-runs-fc059af.json"


# pins of stored engine runs: run again on other kernels (tests/conftest.py). Kind: a
# decision with a tolerance band (survey_identity.RELATIVE says why it is no derived bound);
# statuses, counts and layouts exactly.
pytestmark = pytest.mark.kernel_sensitive


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_survey_runs_are_those_stored_within_the_bound(survey_identity, load_or_skip, preset):
    survey_identity.assert_runs_unchanged(load_or_skip("box2d"), STORED, preset)


def test_the_bound_takes_the_last_bits_and_catches_a_change(survey_identity):
    import copy

    import numpy as np

    stored = survey_identity.read_stored(STORED)
    then = next(run for run in stored.runs["defaults"] if run["status"] == "ok")
    scale = survey_identity.speed_scale(stored.scenes[0], then)

    def changed(change):
        now = copy.deepcopy(then)
        change(now)
        return survey_identity.differences(now, then, scale)

    def last_bit(now):
        now["velocities"] = [[float(np.nextafter(x, np.inf)) for x in body]
                             for body in now["velocities"]]
        now["normal_impulse"] = float(np.nextafter(now["normal_impulse"], np.inf))

    assert changed(lambda now: None) == [] and changed(last_bit) == []
    assert changed(lambda now: now["velocities"][0].__setitem__(0, then["velocities"][0][0]
                                                                * (1 + 1e-6) + 1e-6))
    assert changed(lambda now: now.update(status="flagged"))
    assert changed(lambda now: now.update(steps=now["steps"] + 1))
    assert changed(lambda now: now["contact_record"].update(layout="another"))
