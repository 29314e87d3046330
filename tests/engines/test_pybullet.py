"""pybullet against its own law (planar_impact's newton-lcp), and its defaults pinned."""

from __future__ import annotations

import pytest

pytest.importorskip("pybullet", reason="pybullet not installed (pip install pybullet==3.2.7)")

from harness.engines import ke_norm, load_engine  # noqa: E402
from harness.scene import Body, Disk, Polygon, Scene  # noqa: E402
from harness.scene.reference import newton_lcp_velocities, reference_scenes  # noqa: E402

SCENES = reference_scenes()
DT = 1.0 / 240.0  # pybullet's default fixedTimeStep, kept by both presets
DEFAULT_SLOP = 1e-5  # m, Bullet's default contactSlop (measured through its bias below)


@pytest.fixture(scope="module")
def engine():
    return load_engine("pybullet")


def departure(scene, run, law) -> float:
    return ke_norm(scene, run.u_after - law.u_after) / ke_norm(scene, scene.state())


def drop(speed, e=0.5, mu=0.0):
    body = Body("d", Disk(0.1), 1.0, (0.0, 0.1), 0.0, (0.0, -speed), 0.0)
    return Scene((body,), e, mu, ground=True, name="drop")


@pytest.mark.parametrize("scene_name", ["disk", "disk-spin", "rod-45", "box-corner", "two-disks"])
def test_accurate_equals_newton_lcp(engine, scene_name):
    scene, contact, normal = SCENES[scene_name]
    law = newton_lcp_velocities(scene, contact, normal)
    run = engine.run(scene, preset="accurate")
    # Reason for 1e-6 (the gate): measured <= 1e-15, rounding.
    assert departure(scene, run, law) <= 1e-6
    # Reason for 1e-9 N s: Bullet reports force = impulse/dt, rounding only.
    assert run.normal_impulse == pytest.approx(law.normal_impulse, abs=1e-9)
    assert run.tangential_impulse == pytest.approx(law.tangential_impulse, abs=1e-9)


def triangle_scene():
    """A triangle corner against the ground, and its contact point."""
    import math

    triangle = Polygon(((-0.2, -0.1), (0.2, -0.1), (0.0, 0.2)))
    c, s = math.cos(0.3), math.sin(0.3)
    low = min(((c * x - s * y, s * x + c * y) for x, y in triangle.points), key=lambda p: p[1])
    body = Body("tri", triangle, 1.0, (0.0, -low[1]), 0.3, (0.4, -1.0), 0.0)
    return Scene((body,), 0.5, 0.3, ground=True, name="triangle"), (low[0], 0.0)


def test_polygon_hull_margin_is_a_pinned_departure(engine):
    # pybullet 3.2.7 keeps a link's convex-hull collision margin at 0.001 m (changeDynamics
    # collisionMargin only acts on a base), so the contact point sits 1 mm below the vertex
    # and the lever arm is off by 1 mm: measured departure 1.0677e-3 from newton-lcp.
    # Reason for 2%: deterministic; the value scales with margin / body size.
    scene, contact = triangle_scene()
    law = newton_lcp_velocities(scene, contact, (0.0, 1.0))
    run = engine.run(scene, preset="accurate")
    assert departure(scene, run, law) == pytest.approx(1.0677e-3, rel=0.02)
    assert run.max_penetration == pytest.approx(1e-3, rel=1e-9)  # the margin, seen as depth
    assert any("margin" in note for note in run.notes)


@pytest.mark.parametrize(
    "scene_name, measured",
    [("disk", 2.0528e-03), ("rod-45", 1.8061e-03), ("box-corner", 2.2122e-03),
     ("two-disks", 1.8330e-03)],
)
def test_defaults_departure_pinned(engine, scene_name, measured):
    # Defaults depart by ~2e-3, touching at the start: the default contactSlop bias
    # (1e-5 m / dt = 2.4 mm/s off the normal speed) and the default 0.04 1/s link damping.
    # Reason for 5%: deterministic values; room for another platform's rounding.
    scene, contact, normal = SCENES[scene_name]
    law = newton_lcp_velocities(scene, contact, normal)
    assert departure(scene, engine.run(scene, preset="defaults"), law) == pytest.approx(
        measured, rel=0.05
    )


@pytest.mark.parametrize("speed", [0.05, 0.1, 0.19])
def test_defaults_restitution_threshold_zeroes_slow_bounces(engine, speed):
    # Below restitutionVelocityThreshold (0.2 m/s) Bullet's restitution is 0: the disk stops.
    # Reason for 1e-12 m/s: the normal velocity is solved to rounding.
    run = engine.run(drop(speed), preset="defaults")
    assert abs(run.velocities[0][1]) < 1e-12
    accurate = engine.run(drop(speed), preset="accurate")
    assert accurate.velocities[0][1] == pytest.approx(0.5 * speed, abs=1e-12)


@pytest.mark.parametrize("speed", [0.21, 0.5, 1.0, 2.0])
def test_defaults_bounce_is_e_v_minus_slop_bias(engine, speed):
    # Above the threshold: v_after = e·v − contactSlop/dt, less the default link damping.
    # Reason for 1e-3·v + 5e-5 m/s: the damping (0.04 1/s over two 1/240 s steps, ~3.5e-4·v)
    # is not modelled here.
    run = engine.run(drop(speed), preset="defaults")
    expected = 0.5 * speed - DEFAULT_SLOP / DT
    assert run.velocities[0][1] == pytest.approx(expected, abs=1e-3 * speed + 5e-5)


@pytest.mark.parametrize("approach, measured", [(0.25, 0.24738), (0.5, 0.0)])
def test_defaults_early_contact_bias(engine, approach, measured):
    # docs/engines.md, 'pybullet': the contact is found up to 0.02 m early and the solver aims at
    # e·|v| − gap/dt. Starting `approach` steps before touch at 1 m/s the gap at detection is
    # approach·dt·v, so the bounce is 0.5 − approach (floored at 0), minus the slop bias.
    # Reason for 5e-4 m/s: the slop/damping terms above. `accurate` ignores the phase.
    run = engine.run(drop(1.0), preset="defaults", overrides={"approach_steps": approach})
    assert run.velocities[0][1] == pytest.approx(measured, abs=5e-4)
    assert run.velocities[0][1] == pytest.approx(
        max(0.5 - approach - DEFAULT_SLOP / DT, 0.0), abs=5e-4
    )
    exact = engine.run(drop(1.0), preset="accurate", overrides={"approach_steps": approach})
    assert exact.velocities[0][1] == pytest.approx(0.5, abs=1e-12)  # rounding


def test_product_rule_gives_the_pair_exactly_e_and_mu(engine):
    # A sliding disk (spin against the motion): I_t = −μ·I_n exactly, I_n = (1+e)·m·v.
    scene = SCENES["disk-spin"][0]
    run = engine.run(scene, preset="accurate")
    assert run.normal_impulse == pytest.approx(1.5, abs=1e-12)  # rounding
    assert run.tangential_impulse == pytest.approx(-0.3 * 1.5, abs=1e-12)


def test_rerun_after_its_world_was_evicted(engine):
    # At most 8 worlds stay connected: a run whose remembered world was disconnected (least
    # recently used) gets a new one and the same, bit-identical result.
    scene = SCENES["disk-spin"][0]
    settings = engine.settings("accurate")
    first = engine.run(scene, settings)
    for radius in range(9):  # 9 other geometries with the same settings: 9 other worlds
        other = drop(1.0)
        body = other.bodies[0].moved(shape=Disk(0.11 + 0.01 * radius),
                                     position=(0.0, 0.11 + 0.01 * radius))
        engine.run(Scene((body,), 0.5, 0.0, ground=True, name="drop"), settings)
    assert engine.run(scene, settings) == first


def survey_scenes(count_per_population=2):
    """A few sampled survey scenes of every population (each a geometry of its own)."""
    from harness.survey.population import resolve_populations
    from harness.survey.sampling import sample_population

    return [sample.scene
            for population in resolve_populations()
            for sample in sample_population(population, count_per_population, 7).samples]


@pytest.mark.parametrize("order", ["forward", "reverse"])
def test_reused_clients_equal_fresh_adapters(order, monkeypatch):
    # A new geometry is built in an emptied (resetSimulation) client of an evicted world
    # when one is idle. Every run through one adapter, over more geometries than it keeps
    # worlds, must equal bit for bit (EngineRun equality: every field but the wall time) a
    # run in a fresh adapter, whose clients are new: body ids, contact order, warm starts
    # and per-client settings must not carry over from the client's earlier worlds. The
    # sub-stepped settings go first: a client keeps numSubSteps and fixedTimeStep across
    # resetSimulation, so it must not serve the presets (which leave sub-steps unset).
    import pybullet

    from harness.engines import pybullet_engine

    scenes = [scene for scene, _, _ in SCENES.values()] + [triangle_scene()[0]] + survey_scenes()
    if order == "reverse":
        scenes.reverse()
    assert len(scenes) > 2 * pybullet_engine._MAX_WORLDS  # worlds are evicted, clients reused
    connect = pybullet.connect
    shared_connects = []
    shared = pybullet_engine.PybulletEngine()
    sub_stepped = shared.settings("accurate", {"num_sub_steps": 2, "time_step": 1.0 / 120.0})
    try:
        for settings in (sub_stepped, shared.settings("accurate"), shared.settings("defaults")):
            for scene in scenes:
                fresh = pybullet_engine.PybulletEngine()
                try:
                    expected = fresh.run(scene, settings)
                finally:
                    fresh.close()
                monkeypatch.setattr(pybullet, "connect",
                                    lambda *args: shared_connects.append(1) or connect(*args))
                got = shared.run(scene, settings)
                monkeypatch.setattr(pybullet, "connect", connect)
                assert got == expected, (settings, scene.name)
    finally:
        shared.close()
    # The reuse path was taken: per settings, one client per kept world and one idle.
    assert len(shared_connects) <= 3 * (pybullet_engine._MAX_WORLDS + 1)
