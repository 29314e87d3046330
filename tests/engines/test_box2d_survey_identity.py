"""Box2D's runs of survey scenes are bit for bit the runs of the adapter before session 6's
speed-ups (in-place reads, shared shapes, batches by speed class, inline geometry).

The stored file (see tests/engines/survey_identity.py) holds 350 survey scenes and, per
preset, a fingerprint of each of their runs -- velocities, status, steps, impulses, the
contact record, derived values and notes -- recorded with the adapter at commit 41a1da8
(``run_many``, batches of scenes in a row).
"""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("Box2D", reason="Box2D not installed (pip install box2d==2.3.10)")

STORED = Path(__file__).parent.parent / "data" / "box2d-survey-runs-41a1da8.json"


# pins of stored engine runs: run again on other kernels (tests/conftest.py)
pytestmark = pytest.mark.kernel_sensitive


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_survey_runs_are_bit_identical_to_stored(survey_identity, load_or_skip, preset):
    survey_identity.assert_runs_unchanged(load_or_skip("box2d"), STORED, preset)
