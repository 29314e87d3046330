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


def test_pymunk_on_synthetic_drops_solves_newton_coulomb(load_or_skip, synthetic_copy):
    """A drop as an engine scene: the placed polygon at the Jacobian's angle carries the
    drop's contact exactly, so pymunk (sequential impulses) lands on the newton-lcp law."""
    from harness.experiments import drops_engines, fazeli, predict

    engine = load_or_skip("pymunk")
    directory, _ = synthetic_copy
    data = fazeli.load(directory, check_hashes=False)
    impacts = data.impacts.subset(np.arange(12))
    thetas, residual = drops_engines.jacobian_angles(impacts, data.pre_impact_angles[:12])
    assert residual.max() < 1e-6
    law = predict.predict(impacts, "newton-lcp", 0.3, 0.7).speeds_after
    for i in range(len(impacts)):
        scene = drops_engines.drop_scene(impacts, i, float(thetas[i]), 0.3, 0.7)
        run = engine.run(scene, preset="accurate")
        assert engine_curves.judged(run, scene) == "ok"
        np.testing.assert_allclose(np.asarray(run.u_after)[:3], law[i], rtol=1e-4, atol=1e-5)
