"""pybullet's runs of survey scenes are the runs of the adapter before session 8's speed-ups
of ``run_many`` (fewer calls and less Python per impact), to the bound of
tests/engines/survey_identity.py (bit for bit on the machine that recorded them).

The stored file (see tests/engines/survey_identity.py) holds 350 survey scenes and, per
preset, the values of each of their runs -- velocities, status, steps, impulses, energies,
drift, the contact record, derived values and notes -- recorded with the adapter at commit
c267d83 (``run_many``, the survey's batches). The file first held the scenes' digests only;
the scenes themselves were written in later from the same sampling (their digests checked
equal), the runs' fingerprints kept as recorded at c267d83; later still their values, each
run checked to have its fingerprint.
"""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("pybullet", reason="pybullet not installed (pip install pybullet==3.2.7)")

STORED = Path(__file__).parent.parent / "data" / "pybullet-survey-runs-c267d83.json"


# pins of stored engine runs: run again on other kernels (tests/conftest.py). Kind: a
# decision with a tolerance band (survey_identity.RELATIVE says why it is no derived bound);
# statuses, counts and layouts exactly.
pytestmark = pytest.mark.kernel_sensitive


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_survey_runs_are_those_stored_within_the_bound(survey_identity, load_or_skip, preset):
    survey_identity.assert_runs_unchanged(load_or_skip("pybullet"), STORED, preset)
