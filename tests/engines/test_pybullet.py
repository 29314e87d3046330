"""pybullet against its own law (planar_impact's newton-lcp), and its defaults predicted."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

pytest.importorskip("pybullet", reason="pybullet not installed (pip install pybullet==3.2.7)")

from harness.engines import ke_norm, load_engine  # noqa: E402
from harness.scene import Body, Disk, Polygon, Scene, geometry  # noqa: E402
from harness.scene.reference import newton_lcp_velocities, reference_scenes  # noqa: E402

SCENES = reference_scenes()
DT = 1.0 / 240.0  # pybullet's default fixedTimeStep, kept by both presets
DEFAULT_SLOP = 1e-5  # m, Bullet's default contactSlop


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


# ---------------------------------------------------------------------- defaults predicted
# Under `defaults` a touching impact takes two steps: the contact step (impulse) and one
# without impulse, which ends the run. Two effects make it depart from newton-lcp, and both
# follow from Bullet's model, not from the runs:
# * link damping: every step, before its contact solve, a btMultiBody link's velocity gets
#   the explicit damping force -m·v·(k + k·|v|) (and -I·ω·(k + k·|ω|)), k = 0.04 1/s:
#   v <- v·(1 - k·(1 + |v|)·dt), a linear and a quadratic term of the same coefficient;
# * the contactSlop bias: a touching contact counts as a gap of contactSlop, so the normal
#   row aims at e·|v_n| - contactSlop/dt (v_n the damped approach speed) -- newton-lcp with
#   e replaced by e - (contactSlop/dt)/|v_n|. The friction row is plain Coulomb.
DEFAULT_DAMPING = 0.04  # 1/s, btMultiBody's linear and angular damping (the defaults keep it)


def damped(speeds, damping=DEFAULT_DAMPING):
    """Generalized speeds ``(v_x, v_y, ω)`` per body after one step of Bullet's link damping."""
    speeds = np.array(speeds, dtype=float)
    for body in speeds.reshape(-1, 3):
        body[:2] *= 1.0 - damping * (1.0 + math.hypot(*body[:2])) * DT
        body[2] *= 1.0 - damping * (1.0 + abs(body[2])) * DT
    return speeds


def defaults_prediction(scene, contact, normal, damping=DEFAULT_DAMPING, slop=DEFAULT_SLOP):
    """``u_after`` under ``defaults`` from the model above: damp, solve newton-lcp with the
    slop-shifted normal target, damp again (the step that ends the run)."""
    problem = geometry.impact_problem(scene, contact, normal)
    approach = dataclasses.replace(problem, u=damped(problem.u, damping))
    approach_speed = -float(approach.wn @ approach.u)
    shifted_e = scene.restitution - slop / DT / approach_speed
    law = approach.solve(mu=scene.friction, e=shifted_e, law="newton-lcp")
    return damped(law.u_after, damping)


@pytest.mark.parametrize("scene_name", ["disk", "disk-spin", "rod-45", "box-corner", "two-disks"])
def test_defaults_are_newton_lcp_with_slop_bias_and_damping(engine, scene_name):
    # Reason for 1e-10: the model is exact (closed-form damping, the one-contact LCP that
    # Bullet's PGS solves to convergence here), so only rounding is left (measured
    # <= 2e-14); leaving out either effect misses by more than 1e-4 (checked below), and
    # the departure from newton-lcp itself is ~2e-3.
    scene, contact, normal = SCENES[scene_name]
    run = engine.run(scene, preset="defaults")
    assert run.status == "ok" and run.steps == 2
    scale = ke_norm(scene, scene.state())

    def miss(predicted):
        return ke_norm(scene, run.u_after - predicted) / scale

    assert miss(defaults_prediction(scene, contact, normal)) <= 1e-10
    assert departure(scene, run, newton_lcp_velocities(scene, contact, normal)) > 1e-3
    assert miss(defaults_prediction(scene, contact, normal, damping=0.0)) > 1e-4
    assert miss(defaults_prediction(scene, contact, normal, slop=0.0)) > 1e-4


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
    # Above the threshold: v_after = e·v − contactSlop/dt with v damped before the solve,
    # and the bounce damped once more by the step that ends the run (the model above).
    # Reason for 1e-12 m/s: rounding (measured <= 5e-16); the damping alone is ~3e-4·v.
    run = engine.run(drop(speed), preset="defaults")
    expected = damped((0.0, 0.5 * damped((0.0, speed, 0.0))[1] - DEFAULT_SLOP / DT, 0.0))[1]
    assert run.velocities[0][1] == pytest.approx(expected, abs=1e-12)
    assert abs(run.velocities[0][1] - (0.5 * speed - DEFAULT_SLOP / DT)) > 1e-5


def test_defaults_early_contact_bias(engine):
    # docs/engines.md, 'pybullet': the contact is found up to 0.02 m early and the solver
    # aims at e·|v| − (gap + contactSlop)/dt. Starting a quarter step before touch at 1 m/s,
    # the gap at detection is dt/4·v exactly (free flight), so the bounce is
    # e·v − v/4 − contactSlop/dt, damped as above: 0.247, not 0.5. Reason for 1e-12 m/s:
    # rounding (measured ~1e-15). `accurate` ignores the phase.
    run = engine.run(drop(1.0), preset="defaults", overrides={"approach_steps": 0.25})
    assert run.steps == 2
    aimed = 0.5 * damped((0.0, 1.0, 0.0))[1] - 0.25 - DEFAULT_SLOP / DT
    assert run.velocities[0][1] == pytest.approx(damped((0.0, aimed, 0.0))[1], abs=1e-12)
    exact = engine.run(drop(1.0), preset="accurate", overrides={"approach_steps": 0.25})
    assert exact.velocities[0][1] == pytest.approx(0.5, abs=1e-12)  # rounding


def test_defaults_early_contact_half_a_step_ends_at_rest(engine):
    # Half a step early the aim e·v − v/2 − contactSlop/dt is just below zero: the disk
    # keeps closing at that speed (2.6 mm/s), below restitutionVelocityThreshold, so from
    # the next step restitution is 0 and the solver only keeps the gap from closing faster
    # than in one step: the disk settles on the ground instead of bouncing. Reason for
    # 1e-9 m/s: the run ends only once the point no longer closes faster than 1e-9 of the
    # scene's speed (docs/engines.md, 'The engine contract'), and Bullet leaves no rebound
    # (measured ~1e-15).
    run = engine.run(drop(1.0), preset="defaults", overrides={"approach_steps": 0.5})
    assert run.status == "ok"
    assert abs(run.velocities[0][1]) <= 1e-9
    exact = engine.run(drop(1.0), preset="accurate", overrides={"approach_steps": 0.5})
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

    from harness.engines.pybullet import adapter

    scenes = [scene for scene, _, _ in SCENES.values()] + [triangle_scene()[0]] + survey_scenes()
    if order == "reverse":
        scenes.reverse()
    assert len(scenes) > 2 * adapter._MAX_WORLDS  # worlds are evicted, clients reused
    connect = pybullet.connect
    shared_connects = []
    shared = adapter.PybulletEngine()
    sub_stepped = shared.settings("accurate", {"num_sub_steps": 2, "time_step": 1.0 / 120.0})
    try:
        for settings in (sub_stepped, shared.settings("accurate"), shared.settings("defaults")):
            for scene in scenes:
                fresh = adapter.PybulletEngine()
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
    assert len(shared_connects) <= 3 * (adapter._MAX_WORLDS + 1)
