"""Verdicts of engine runs (harness/run/verdicts/, docs/verdicts.md).

Unit checks build an engine run's numbers by hand around an exact ``newton-lcp`` solution
(what a perfect sequential-impulse engine returns) and break one thing at a time. The tilted
sweeps of the library are then run through the engines and every verdict is held against an
independent physical criterion: whether the engine's contact lasted past the moment the
second feature strikes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.run import plan, point_records, runner, tasks, verdicts
from harness.run.verdicts import RunNumbers, StepContacts, Tolerances, judge
from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.scene import Body, Box, Disk, Rod, Scene, geometry

DISK = Scene((Body("disk", Disk(0.1), 1.0, (0.0, 0.1), velocity=(1.0, -2.0),
                   angular_velocity=3.0),), restitution=0.5, friction=0.3, ground=True)
ROD_ENERGY = load_scenario(SCENARIO_DIR / "rod-50-newton-energy-gain.toml")


def problem_of(scene):
    contact = geometry.scene_contact(scene)
    return geometry.impact_problem(scene, contact.point, contact.normal)


def exact_run(scene, engine="pymunk", **changes) -> RunNumbers:
    """A perfect newton-lcp engine: its velocities and the impulse that produced them."""
    problem = problem_of(scene)
    result = problem.solve(mu=scene.friction, e=scene.restitution, law="newton-lcp")
    fields = {"engine": engine, "status": "ok", "u_after": result.u_after,
              "max_penetration": 0.0, "normal_impulse": result.normal_impulse,
              "tangential_impulse": result.tangential_impulse, "impulse_source": "engine",
              **changes}
    return RunNumbers(**fields)


def names(verdict):
    return [reason.name for reason in verdict.failing]


def test_an_exact_single_impact_fails_no_check():
    verdict = judge(DISK, problem_of(DISK), exact_run(DISK))
    assert verdict.single_impact and verdict.reasons == () and verdict.status("ok") == "ok"


def test_still_approaching_at_the_end_is_not_separated():
    problem = problem_of(DISK)
    verdict = judge(DISK, problem, exact_run(DISK, u_after=problem.u.copy(),
                                             normal_impulse=None))
    assert names(verdict) == ["not-separated"]
    assert verdict.status("ok") == "not-separated"  # never ok
    reason = verdict.failing[0]
    # v_n^S = v_n^A = -2 m/s against a bound of 1e-3 of |v_n^A|
    assert reason.value == pytest.approx(-2.0, rel=1e-15)
    assert reason.tolerance == pytest.approx(-2e-3, rel=1e-15)


def test_penetration_bound_is_a_fraction_of_the_body_extent():
    problem = problem_of(DISK)
    bound = Tolerances().penetration * 0.1  # the disk's extent is its radius
    assert not judge(DISK, problem, exact_run(DISK, max_penetration=0.9 * bound)).reasons
    assert names(judge(DISK, problem, exact_run(DISK, max_penetration=1.1 * bound))) == [
        "penetration"]


def test_impulse_the_velocities_do_not_imply_is_a_mismatch():
    run = exact_run(DISK)
    doubled = exact_run(DISK, normal_impulse=2.0 * run.normal_impulse)
    assert names(judge(DISK, problem_of(DISK), doubled)) == ["impulse-mismatch"]
    # from momentum (m_B Δv_B) the engine's impulse is no independent measure: not compared
    momentum = exact_run(DISK, normal_impulse=2.0 * run.normal_impulse,
                         impulse_source="momentum")
    assert judge(DISK, problem_of(DISK), momentum).single_impact


def test_a_change_of_speed_no_contact_impulse_explains_is_a_residual():
    # A disk's spin can only change with a tangential impulse, which also changes v_x: a
    # spin change alone is not an impulse at the contact point.
    run = exact_run(DISK)
    spun = run.u_after + np.array([0.0, 0.0, 5.0])
    verdict = judge(DISK, problem_of(DISK), exact_run(DISK, u_after=spun,
                                                      impulse_source="momentum"))
    assert "impulse-residual" in names(verdict)


@pytest.mark.parametrize("engine, clipped", [("pybullet", True), ("pymunk", False),
                                             ("mujoco", False)])
def test_speeds_at_the_measured_cap_are_clipped(engine, clipped):
    fast = Scene((Body("disk", Disk(0.1), 1.0, (0.0, 0.1), velocity=(0.0, -1e6)),),
                 restitution=0.5, friction=0.0, ground=True)
    # what pybullet 3.2.7 returned for this scene (docs/verdicts.md, 'Velocity caps')
    capped = np.array([0.0, 100.0, 0.0])
    verdict = judge(fast, problem_of(fast), exact_run(fast, engine=engine, u_after=capped,
                                                      normal_impulse=None))
    assert ("clipped" in names(verdict)) is clipped
    assert "not-separated" not in names(verdict)


def test_energy_gain_the_law_predicts_is_reported_not_failed():
    point = ROD_ENERGY.point_list()[0]
    scene, problem = ROD_ENERGY.scene(point), ROD_ENERGY.analytic_problem(point)
    lcp = problem.solve(mu=scene.friction, e=scene.restitution, law="newton-lcp")
    assert lcp.energy_change > 0  # the file's premise
    run = exact_run(scene)
    verdict = judge(scene, problem, run, law_energy_change=lcp.energy_change)
    assert verdict.single_impact
    (gain,) = verdict.reasons
    assert (gain.name, gain.attribution, gain.fails) == ("energy-gain", "law", False)
    # Unattributed (no law energy given) the same gain is the numerics' and fails.
    assert names(judge(scene, problem, run)) == ["energy-gain"]
    # A gain well beyond the law's is the numerics' too.
    more = judge(scene, problem, exact_run(scene, u_after=1.2 * lcp.u_after,
                                           impulse_source="momentum"),
                 law_energy_change=lcp.energy_change)
    gain = next(r for r in more.reasons if r.name == "energy-gain")
    assert (gain.attribution, gain.fails) == ("numerics", True)


BOX = Scene((Body("box", Box(1.0, 0.2), 1.0, (0.0, 0.0), angle=math.radians(1.0),
                  velocity=(0.5, -1.0)),), restitution=0.5, friction=0.3, ground=True)
BOX = Scene((geometry.place_on_ground(BOX.bodies[0]),), 0.5, 0.3, ground=True)


def corner_world(body, index):
    vertex = body.shape.vertices()[index]
    return geometry.rotation(body.angle) @ vertex + np.asarray(body.position)


def test_a_second_corner_in_the_contact_records_is_multi_contact_with_feature_and_step():
    body = BOX.bodies[0]
    state = (*body.position, body.angle, *body.velocity, body.angular_velocity)
    first, far = corner_world(body, 0), corner_world(body, 1)
    records = (StepContacts(1, ((first[0], first[1], 1e-4),), (state,)),
               StepContacts(2, ((first[0], first[1], 2e-4),), (state,)),
               StepContacts(3, ((first[0], first[1], 1e-4), (far[0], far[1], 1e-4)), (state,)))
    verdict = judge(BOX, problem_of(BOX), exact_run(BOX, contacts=records))
    assert names(verdict) == ["multi-contact"]
    reason = verdict.failing[0]
    assert reason.value == 3 and "corner 1" in reason.detail and "step 3" in reason.detail
    # the same corner in every step is one contact
    assert judge(BOX, problem_of(BOX), exact_run(BOX, contacts=records[:2])).single_impact


def test_the_struck_corner_is_the_contact_even_when_the_first_point_reads_as_a_face():
    """Box2D ``defaults`` on box-corner-spin: its first point, computed before the step and
    given with the pose after it, lay 0.028 m from the struck corner (read as a face); the
    corner's next point was a false ``multi-contact``. The scene's contact fixes the corner."""
    scenario = load_scenario(SCENARIO_DIR / "box-corner-spin.toml")
    scene = scenario.scene(scenario.point_list()[0])
    body = scene.bodies[0]
    struck = verdicts.contact_features(scene)[0]
    assert struck >= 0
    corner = corner_world(body, struck)
    state = (*body.position, body.angle, *body.velocity, body.angular_velocity)
    along_face = corner + 0.028 * (corner_world(body, (struck + 1) % 4) - corner) / np.linalg.norm(
        corner_world(body, (struck + 1) % 4) - corner)
    records = (StepContacts(1, ((along_face[0], along_face[1], 0.0),), (state,)),
               StepContacts(2, ((corner[0], corner[1], 1e-3),), (state,)))
    assert judge(scene, problem_of(scene), exact_run(scene, contacts=records)).single_impact
    # another corner after a face point still is a second feature
    other = corner_world(body, (struck + 2) % 4)
    records = (records[0], StepContacts(2, ((other[0], other[1], 1e-3),), (state,)))
    assert names(judge(scene, problem_of(scene), exact_run(scene, contacts=records))) == [
        "multi-contact"]


def test_a_disk_counted_twice_in_one_step_is_one_contact():
    # A 3-D engine's cylinder can report two points in a step; a disk has one feature.
    verdict = judge(DISK, problem_of(DISK), exact_run(DISK, status="multi-contact"))
    assert verdict.single_impact and verdict.status("multi-contact") == "ok"
    rod = Scene((Body("rod", Rod(1.0, 0.01), 1.0, (0.0, 0.3), angle=0.6,
                      velocity=(0.0, -1.0)),), 0.5, 0.3, ground=True)
    rod = Scene((geometry.place_on_ground(rod.bodies[0]),), 0.5, 0.3, ground=True)
    kept = judge(rod, problem_of(rod), exact_run(rod, status="multi-contact"))
    assert names(kept) == ["multi-contact"] and kept.status("multi-contact") == "multi-contact"


def test_engine_statuses_are_reasons_and_skipped_runs_are_not_judged():
    verdict = judge(DISK, problem_of(DISK), exact_run(DISK, status="no-separation"))
    assert names(verdict) == ["no-separation"]
    assert judge(DISK, problem_of(DISK), exact_run(DISK, status="skipped: x")).reasons == ()


# --------------------------------------------------------------------------------------------
# The library's tilted sweeps through the engines
# --------------------------------------------------------------------------------------------
TILTED = [load_scenario(SCENARIO_DIR / f"sweep-tilted-{kind}.toml") for kind in ("box", "rod")]
# Engines whose post-impact motion is newton-lcp's (mujoco.defaults is soft and ignores e:
# its far end comes down on another schedule, so the criterion below does not apply to it).
NEWTON_LCP_ENGINES = ("pymunk.defaults", "pymunk.accurate", "pybullet.defaults",
                      "pybullet.accurate", "mujoco.matched-bounce")


@pytest.fixture(scope="module")
def tilted_records():
    return runner.run(TILTED, cache=None, workers=1, log=None).records


def test_every_tilted_run_of_an_exact_engine_runs_the_whole_sequence(tilted_records):
    """Independent criterion: at the end of the run every core point (box corner, rod end
    cap) leaves the ground or rests on it (``v_y + ω r_x ≥ −1e-3 |v_y^A|`` at the scene's
    pose, which the short sequence barely turns), and the run sits on the sequence's final
    state, not on a cut of it (sequence scenes run until the sequence's last impact,
    ``Scene.run_until``; a run that stopped after the first impact left the far corner
    coming down at about 1 m/s)."""
    exact = ("pymunk.defaults", "pymunk.accurate", "pybullet.accurate", "box2d.accurate")
    checked = 0
    for record in tilted_records:
        if record.source == "analytic" or record.label not in exact:
            continue
        scenario = next(s for s in TILTED if s.name == record.scenario)
        scene = scenario.scene(scenario.point_list()[record.point["index"]])
        world, _ = geometry.world_core(scene.bodies[0])
        v_x, v_y, omega = record.u_after[:3]
        lever = world[:, 0] - scene.bodies[0].position[0]
        assert np.all(v_y + omega * lever >= -1e-3 * abs(scene.bodies[0].velocity[1])), record
        assert record.verdict == verdicts.SINGLE_IMPACT, (record.label, record.reasons)
        reference = record.diagnostics["reference"]
        assert reference["nearest_cut"][0] == reference["primary"] == "event-driven/newton-lcp"
        assert reference["departure_from_primary"] < 1e-2
        checked += 1
    assert checked == 2 * 6 * len(exact)


def test_a_run_of_only_the_first_impact_is_truncated_and_not_counted():
    """The same engine run stopped at its first separation (no ``run_until``: how every run
    of a tilt ended before) is labelled ``truncated-sequence``, keeps no clean departure
    and fails no gate: at 3° pymunk then sat 1e-13 from single-contact Poisson's first impact
    and 1.09 from the sequence it is compared with."""
    from harness.engines import load_engine
    from harness.report.views import worst_departure

    scenario = TILTED[0]
    point = scenario.point_list()[-1]  # 3°
    whole = plan.engine_scene(scenario, point)
    assert whole.run_until is not None and whole.run_until > 0
    first_only = scenario.scene(point)
    engine = load_engine("pymunk")
    problem = scenario.analytic_problem(point)
    struck = verdicts.sequence_contacts(scenario, first_only)
    assert len(struck) == 2
    short = engine.run(first_only, preset="accurate")
    verdict = judge(first_only, problem, verdicts.numbers_from_run(short), contacts=struck,
                    sequence=True)
    assert "truncated-sequence" in names(verdict) and not verdict.single_impact
    assert verdict.status("ok") == "truncated-sequence"
    full = engine.run(whole, preset="accurate")
    assert full.steps > short.steps
    assert judge(whole, problem, verdicts.numbers_from_run(full), contacts=struck,
                 sequence=True).single_impact
    # through the runner's records: flagged, out of the worst departure and of the gates
    item = {"output": tasks.engine_task({"engine": "pymunk", "scene": first_only,
                                          "settings": engine.settings("accurate")})}
    record = point_records.engine_record(scenario, point_records.point_dict(point), "pymunk",
                                         "accurate", item, problem, {}, scene=first_only,
                                         contacts=struck, sequence=True)
    assert record.verdict == verdicts.FLAGGED and record.status == "truncated-sequence"
    value, any_flagged, _ = worst_departure([record], "newton-lcp")
    assert any_flagged and math.isnan(value)


def test_tilted_runs_carry_only_the_sequence_references_and_flagged_ones_show_as_flagged(
        tilted_records):
    """A tilt's engine records hold departures from its event-driven references only (never
    the single-contact laws, which do not describe a sequence); the heat map and the
    summary's law tables leave the tilt out, and its own table shows a flagged run as
    flagged, with its reasons, never as a departure."""
    from harness.report import contacts
    from harness.report.views import engine_scenarios, worst_departure
    from harness.run.records import Results

    engine_records = [r for r in tilted_records if r.source != "analytic"]
    for record in engine_records:
        assert record.departure and all(name.startswith("event-driven/")
                                        for name in record.departure), record.departure
    flagged = [r for r in engine_records if r.verdict == verdicts.FLAGGED]
    assert flagged and all(r.status != "ok" and r.failing_reasons for r in flagged)
    assert {"truncated-sequence"} <= {name for r in flagged for name in r.failing_reasons}
    for label in {r.label for r in flagged}:
        value, any_flagged, _ = worst_departure([r for r in engine_records if r.label == label],
                                                "poisson")
        assert any_flagged and math.isnan(value)
    results = Results(list(tilted_records))
    assert engine_scenarios(results) == []
    table = contacts._rows(TILTED[0].name, {"references": [
        {"point": r.point["label"], "kind": "event-driven", "primary": "event-driven/newton-lcp"}
        for r in tilted_records if r.scenario == TILTED[0].name and r.law == "poisson"]},
        [r for r in tilted_records if r.scenario == TILTED[0].name])
    cells = [cell for row in table[1] for cell in row]
    shown = [c for c in cells if c.startswith("flagged: ")]
    assert len(shown) == sum(1 for r in flagged if r.scenario == TILTED[0].name)
