"""Drake: the Hunt–Crossley restitution maps (continuous and discrete, each checked against
an independent computation), the central drop under accurate, defaults ignoring e, the
conformance kit, and the message where Drake is not installed."""

from __future__ import annotations

import importlib.util
import math

import pytest

from harness import engines as registry
from harness.engines import EngineNotInstalled, ke_norm
from harness.scene import Body, Disk, Scene
from harness.scene.geometry import impact_problem, scene_contact

needs_drake = pytest.mark.skipif(
    importlib.util.find_spec("pydrake") is None,
    reason="pydrake not importable (pip install drake==1.51.1; wheels for glibc >= 2.34 "
           "x86_64/aarch64 Linux and macOS only)")


def drop(speed, e, mu=0.0, vx=0.0, radius=0.1, mass=1.0):
    body = Body("d", Disk(radius), mass, (0.0, radius), 0.0, (vx, -speed), 0.0)
    return Scene((body,), e, mu, ground=True, name="drop")


def poisson_after(scene):
    contact = scene_contact(scene)
    problem = impact_problem(scene, contact.point, contact.normal)
    result = problem.solve(mu=scene.friction, e=scene.restitution, law="poisson")
    return problem.u + result.delta_u


def departure(scene, u_after, u_law) -> float:
    return ke_norm(scene, u_after - u_law) / ke_norm(scene, scene.state())


# ---------------------------------------------------------------------- not installed
def test_not_installed_message_names_the_platform_problem(monkeypatch):
    """Where Drake has no wheel, the message every output shows says why."""
    monkeypatch.setitem(registry._PLATFORM_PROBLEMS, "drake",
                        lambda: "Drake's Linux wheels need glibc >= 2.34; this machine has "
                                "glibc 2.31")
    message = str(EngineNotInstalled("drake", "ModuleNotFoundError: No module named 'pydrake'"))
    assert "engine 'drake' is not installed" in message
    assert "glibc >= 2.34; this machine has glibc 2.31" in message
    assert "pip install drake" in message


def test_platform_problem_reads_this_machine(monkeypatch):
    import platform
    import sys

    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.setattr(platform, "machine", lambda: "x86_64")
    monkeypatch.setattr(platform, "libc_ver", lambda: ("glibc", "2.31"))
    assert "glibc >= 2.34" in registry._drake_platform_problem()
    monkeypatch.setattr(platform, "libc_ver", lambda: ("glibc", "2.36"))
    assert registry._drake_platform_problem() is None
    monkeypatch.setattr(platform, "machine", lambda: "ppc64le")
    assert "ppc64le" in registry._drake_platform_problem()


# ---------------------------------------------------------------------- the maps
# The maps themselves are plain math, but importing them runs the package's __init__, which
# imports the adapter and pydrake: without Drake (no wheel for the platform) they skip.
@needs_drake
def test_continuous_map_round_trip_and_limits():
    from harness.engines.drake.restitution import (
        dissipation_for_restitution,
        restitution_of_dissipation,
    )

    for e in (1e-3, 0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 0.999):
        a = dissipation_for_restitution(e)
        assert restitution_of_dissipation(a) == pytest.approx(e, rel=1e-9)
        if e < 0.1:  # 1 - b = exp(-a - 1) is lost to rounding in b
            continue
        b = e * a  # the closed relation itself, a second check of the root
        assert a - math.log1p(a) == pytest.approx(-b - math.log1p(-b), rel=1e-7, abs=1e-12)
    assert restitution_of_dissipation(1e-4) == pytest.approx(1 - 2e-4 / 3, abs=1e-8)
    assert restitution_of_dissipation(1e4) == pytest.approx(1e-4, rel=1e-3)
    assert dissipation_for_restitution(1.0) == 0.0


@needs_drake
def test_discrete_map_converges_to_the_continuous_one_and_inverts():
    from harness.engines.drake.restitution import (
        discrete_dissipation,
        discrete_restitution,
        dissipation_for_restitution,
    )

    a = dissipation_for_restitution(0.5)
    errors = [abs(discrete_restitution(a, steps) - 0.5) for steps in (50, 200, 800)]
    assert errors[0] > errors[1] > errors[2]  # first order in 1/steps
    assert errors[2] < 0.25 * errors[1] * 1.1 and errors[2] < 2e-3
    # with d = 0 the implicit step keeps exp(-π²/(2N)) of the bounce
    assert discrete_restitution(0.0, 500) == pytest.approx(math.exp(-math.pi ** 2 / 1000),
                                                           rel=2e-4)
    for e in (0.05, 0.3, 0.5, 0.8, 0.95, 0.985):
        assert discrete_restitution(discrete_dissipation(e, 500), 500) == pytest.approx(
            e, rel=1e-9)
    assert discrete_dissipation(0.999, 500) == 0.0  # beyond the step's own loss


# ---------------------------------------------------------------------- Drake itself
@pytest.fixture(scope="module")
def engine():
    pytest.importorskip("pydrake", reason="pydrake not importable")
    return registry.load_engine("drake")


@needs_drake
def test_discrete_map_is_drakes_own_step(engine):
    """The map's recurrence against Drake's SAP (lagged) on a central drop at a given d."""
    from harness.engines.drake.restitution import discrete_restitution

    for speed, a in ((1.0, 0.8), (3.0, 0.2)):
        scene = drop(speed, 0.5)
        run = engine.run(scene, preset="accurate",
                         overrides={"contact_steps": 40, "hunt_crossley_dissipation": a / speed})
        assert run.velocities[0][1] / speed == pytest.approx(discrete_restitution(a, 40),
                                                             rel=1e-5)


@needs_drake
@pytest.mark.parametrize("e", [0.0, 0.3, 0.8, 1.0])
def test_accurate_central_drop_departs_at_most_one_percent(engine, e):
    """Drake accurate within 1% of Poisson on a direct disk drop, e over [0, 1] (μ 0.3)."""
    scene = drop(2.0, e, mu=0.3, radius=0.05, mass=0.5)
    run = engine.run(scene, preset="accurate")
    assert run.status == "ok"
    gap = departure(scene, run.u_after, poisson_after(scene))
    assert gap <= 0.01, (e, gap, run.velocities)
    if 0.01 <= e <= 0.98:  # e reachable by d >= 0: matched to the map's rounding
        assert gap < 1e-4


@needs_drake
def test_defaults_ignore_restitution(engine):
    """Drake's own settings: stiffness and dissipation from the penetration allowance."""
    bounces = [engine.run(drop(1.0, e), preset="defaults").velocities[0][1] for e in (0.2, 0.9)]
    assert bounces[0] == bounces[1]
    assert 0.005 < bounces[0] < 0.05  # measured 0.0200
    assert any("restitution e not used" in note
               for note in engine.run(drop(1.0, 0.5), preset="defaults").notes)


@needs_drake
def test_stiffness_sets_the_contact_steps(engine):
    """k = m_nn·(π/(N·h))² with both geometries' values combined: a d = 0 contact lasts N."""
    run = engine.run(drop(1.0, 1.0, mass=3.0), preset="accurate",
                     overrides={"contact_steps": 60})
    step = engine.settings("accurate")["time_step"]
    assert run.derived["point_contact_stiffness"] == pytest.approx(
        3.0 * (math.pi / (60 * step)) ** 2)
    assert run.derived["hunt_crossley_dissipation"] == 0.0
    assert abs(len(run.contacts) - 60) <= 2


@needs_drake
def test_keeps_the_contract():
    from harness.engines.conformance import check_engine

    assert check_engine("drake") == []


@needs_drake
def test_sap_loses_the_normal_impulse_beside_a_large_tangential_speed(engine):
    """Why accurate uses TAMSI: SAP's stopping tolerance is relative to the whole velocity,
    so a frictionless disk grazing at v_t = 1 m/s and v_n = 1e-3 bounces short under SAP
    (lagged, measured 0.8793 of e·v) and at e·v under TAMSI."""
    scene = Scene((Body("d", Disk(0.1), 1.0, (0.0, 0.1), 0.0, (1.0, -1e-3), 0.0),), 0.5, 0.0,
                  ground=True, name="grazing")
    tamsi = engine.run(scene, preset="accurate")
    assert engine.settings("accurate")["discrete_contact_approximation"] == "tamsi"
    assert tamsi.velocities[0][1] == pytest.approx(0.5e-3, rel=1e-6)
    lagged = engine.run(scene, preset="accurate",
                        overrides={"discrete_contact_approximation": "lagged"})
    assert lagged.velocities[0][1] == pytest.approx(0.8793 * 0.5e-3, rel=1e-3)


@needs_drake
@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_one_pair_read_out_is_the_general_one_and_the_state_view_the_plants(engine, preset):
    """At every step of survey runs (a body on the ground, two bodies): the contact results
    the step read (the port's value, held, brought up to date by EvalAbstract) are the
    port's Eval; the one-pair read-out gives what the general one gives from them (which
    reads the pair's order at every pair, where the fast path keeps the run's first); and
    the view of the context's state vector holds GetPositions and GetVelocities (after a
    reset too)."""
    from harness.survey.population import resolve_populations
    from harness.survey.sampling import sample_population

    settings = engine.settings(preset)
    scenes = [sample.scene for population in resolve_populations([])
              for sample in sample_population(population, 2, seed=5).samples]
    assert {len(scene.bodies) for scene in scenes} == {1, 2}
    signs = set()
    for scene in scenes:
        plan = engine._plan_for(scene, settings)
        world = plan.world
        for _ in range(2):  # a second reset of the same world reads the same way
            engine._reset(world, plan.prepared)
            contact_steps = 0
            for _ in range(plan.max_steps):
                raw = engine._step(world)
                plant = world.plant
                assert world.state.tolist() == (plant.GetPositions(world.plant_context).tolist()
                                                + plant.GetVelocities(world.plant_context).tolist())
                if raw is None:
                    if contact_steps:
                        break
                    continue
                contact_steps += 1
                results = world.contact_results()
                assert results is world.results  # the held value is the port's
                assert raw == engine._several_pairs(world, results, 1)
                assert engine._read_poses(world) == tuple(
                    tuple(q) for q in world.positions().reshape(-1, 3).tolist())
            assert contact_steps > 0, scene.name
            signs.add(world.sign)
    assert signs == {1.0, -1.0}  # both orders of the pair met
