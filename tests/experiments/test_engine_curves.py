"""The Kharaz disk through an engine: judged runs, and pymunk (whose sequential impulses
solve Newton–Coulomb, equal to every law when m_nt = 0) on the rigid curves."""

from __future__ import annotations

import numpy as np

from harness.experiments import engine_curves, kharaz

ANGLES = np.array([10.0, 30.0, 45.0, 80.0])


def test_pymunk_follows_the_rigid_curves(load_or_skip):
    engine = load_or_skip("pymunk")
    curves = engine_curves.engine_curves(engine, "accurate", ANGLES)
    assert curves.verdicts == ("ok",) * ANGLES.size
    law = kharaz.curves("poisson", ANGLES)
    np.testing.assert_allclose(curves.tangential_restitution, law.tangential_restitution,
                               rtol=1e-6)
    np.testing.assert_allclose(curves.spin, law.spin, rtol=1e-6)
    np.testing.assert_allclose(curves.rebound_deg, law.rebound_deg, rtol=1e-6)


def test_a_flagged_run_keeps_its_reason_and_no_number(load_or_skip):
    """Box2D caps rotation per step at π/2: the small sphere's spin (hundreds of rad/s) is
    beyond it at the default step, and the verdict says so instead of scoring the run."""
    engine = load_or_skip("box2d")
    curves = engine_curves.engine_curves(engine, "defaults", [30.0])
    assert curves.verdicts == ("clipped",)
    assert np.isnan(curves.tangential_restitution[0]) and np.isnan(curves.spin[0])
