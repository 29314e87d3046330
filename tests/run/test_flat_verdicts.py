"""Verdicts of runs on a face lying flat, judged against its declared contacts
(harness/run/verdicts/, docs/verdicts.md, 'Declared simultaneous contacts').

Unit checks build a run's numbers by hand around the exact Newton–Coulomb solution of
``planar_impact.simultaneous`` (what pymunk ``accurate`` returns on a flat face, to 1e-6) and
break one thing at a time. The flat library scenes are then run through the engines: pymunk
``accurate`` must be judged a clean impact, pybullet ``accurate`` flagged for what it does
(it resolves one corner per step and stops with the corner it struck first coming down again).
"""

from __future__ import annotations

import numpy as np
import pytest

from harness.run import metrics, runner, verdicts
from harness.run.verdicts import RunNumbers, StepContacts, judge
from harness.scenarios import load_scenarios
from harness.scenarios.schema import ONE_POINT_TOLERANCE
from harness.scene import Body, Box, Scene, geometry
from planar_impact import simultaneous as sim

#: A box lying flat on the ground, turning: both bottom corners approach (at 1.25, 0.75 m/s).
FLAT_BOX = Scene((geometry.place_on_ground(Body("box", Box(1.0, 0.2), 1.0, (0.0, 0.0),
                                                velocity=(0.3, -1.0),
                                                angular_velocity=0.5)),),
                 restitution=0.5, friction=0.3, ground=True)
#: A small box lying flat on a wide one, both free: the 4 contact columns do not span the 6
#: speeds, so a change of speed no pair of contact impulses makes leaves a residual.
STACK = Scene((Body("base", Box(3.0, 0.4), 2.0, (0.0, 0.0)),
               Body("box", Box(1.0, 0.2), 1.0, (0.0, 0.3), velocity=(0.5, -1.0),
                    angular_velocity=0.3)),
              restitution=0.5, friction=0.3, ground=False)


def problem_of(scene):
    contact = geometry.scene_contact(scene)
    return geometry.impact_problem(scene, contact.point, contact.normal)


def declared(scene):
    return tuple(geometry.scene_contacts(scene, tolerance=ONE_POINT_TOLERANCE))


def newton_coulomb(scene):
    contacts = declared(scene)
    wn, wt = geometry.contact_rows(scene, contacts)
    system = sim.contact_system(mass_matrix=scene.mass_matrix(), wn=wn, wt=wt, u=scene.state(),
                                mu=scene.friction, e=scene.restitution)
    (solution,) = sim.newton_coulomb_solutions(system)
    return solution


def exact_run(scene, **changes) -> RunNumbers:
    """A perfect Newton–Coulomb engine: its speeds and its summed impulse."""
    solution = newton_coulomb(scene)
    fields = {"engine": "pymunk", "status": "multi-contact", "u_after": solution.u_after,
              "max_penetration": 0.0,
              "normal_impulse": float(np.sum(solution.normal_impulse)),
              "tangential_impulse": float(np.sum(solution.tangential_impulse)),
              "impulse_source": "engine", **changes}
    return RunNumbers(**fields)


def verdict_of(scene, run, **keywords):
    return judge(scene, problem_of(scene), run, contacts=declared(scene), **keywords)


def names(verdict):
    return [reason.name for reason in verdict.failing]


def corner_world(body, index):
    vertex = body.shape.vertices()[index]
    return geometry.rotation(body.angle) @ vertex + np.asarray(body.position)


def test_the_scenes_declare_two_contacts_and_newton_coulomb_pushes_at_both():
    for scene in (FLAT_BOX, STACK):
        assert len(declared(scene)) == 2
        assert np.all(newton_coulomb(scene).normal_impulse > 0)


@pytest.mark.parametrize("scene", [FLAT_BOX, STACK], ids=["flat-box", "stack"])
def test_an_exact_newton_coulomb_run_fails_no_check_and_drops_the_point_count(scene):
    verdict = verdict_of(scene, exact_run(scene))
    assert verdict.reasons == () and verdict.status("multi-contact") == "ok"
    # Judged as one impact at the middle of the face, the same numbers fail: two impulses at
    # the corners are not one at the middle, and the engine's count of points stays a reason.
    single = judge(scene, problem_of(scene), exact_run(scene))
    assert names(single) == ["multi-contact", "impulse-residual"]


def test_the_declared_corners_in_the_records_are_one_contact_and_a_third_is_not():
    body = FLAT_BOX.bodies[0]
    state = (*body.position, body.angle, *body.velocity, body.angular_velocity)
    corners = [corner_world(body, k) for k in range(4)]
    bottom = sorted(range(4), key=lambda k: corners[k][1])[:2]
    top = next(k for k in range(4) if k not in bottom)
    records = [StepContacts(1, tuple((corners[k][0], corners[k][1], 1e-4) for k in bottom),
                            (state,)),
               StepContacts(2, ((corners[bottom[0]][0], 0.0, 2e-4),), (state,))]
    assert verdict_of(FLAT_BOX, exact_run(FLAT_BOX, contacts=tuple(records))).single_impact
    records.append(StepContacts(3, ((corners[top][0], corners[top][1], 1e-4),), (state,)))
    verdict = verdict_of(FLAT_BOX, exact_run(FLAT_BOX, contacts=tuple(records)))
    assert names(verdict) == ["multi-contact"]
    reason = verdict.failing[0]
    assert reason.value == 3 and f"corner {top}" in reason.detail and "step 3" in reason.detail
    assert all(f"corner {k}" in reason.detail for k in bottom)  # the declared ones, listed
    assert verdict.status("multi-contact") == "multi-contact"


def test_a_declared_contact_still_closing_is_named():
    solution = newton_coulomb(FLAT_BOX)
    u_after = solution.u_after.copy()
    u_after[2] = -2.0  # spin the box down at its +x end; ΣI_n (= m Δv_y) is unchanged
    wn, _ = geometry.contact_rows(FLAT_BOX, declared(FLAT_BOX))
    closing = wn @ u_after
    assert closing[1] < 0 < closing[0]  # contacts are ordered along x: the +x end closes
    verdict = verdict_of(FLAT_BOX, exact_run(FLAT_BOX, u_after=u_after))
    assert names(verdict) == ["not-separated"]
    reason = verdict.failing[0]
    assert reason.value == pytest.approx(closing[1], rel=1e-12)
    assert "contact 2 of 2 at (0.5, 0)" in reason.detail


def test_with_one_contact_the_impulses_are_the_single_contact_ones():
    problem = problem_of(FLAT_BOX)
    u_after = newton_coulomb(FLAT_BOX).u_after + np.array([0.01, -0.02, 0.3])
    single_n, single_t, single_rest = verdicts.impulse_from_velocities(problem, u_after, 1.0)
    impulses, rest = verdicts.declared_impulses(problem.mass_matrix, problem.wn[None],
                                                problem.wt[None], problem.u, u_after, 1.0)
    # Two solutions of the same 2x2 system: agree to rounding of O(1) impulses.
    np.testing.assert_allclose(impulses[:, 0], [single_n, single_t], atol=1e-12)
    assert rest == pytest.approx(single_rest, rel=1e-9)


def test_on_the_ground_the_summed_impulse_is_the_momentum_change():
    # Four columns in three speeds: the split between corners is not unique, the sums are.
    scene = FLAT_BOX
    wn, wt = geometry.contact_rows(scene, declared(scene))
    u_after = newton_coulomb(scene).u_after + np.array([0.2, 0.1, -0.4])
    impulses, rest = verdicts.declared_impulses(scene.mass_matrix(), wn, wt, scene.state(),
                                                u_after, 1.0)
    mass = scene.bodies[0].mass
    delta = u_after - scene.state()
    np.testing.assert_allclose(impulses.sum(axis=1), [mass * delta[1], mass * delta[0]],
                               atol=1e-12)
    assert rest < 1e-12  # every change of speed is some pair of corner impulses


def test_a_change_no_contact_impulses_make_is_a_residual():
    solution = newton_coulomb(STACK)
    u_after = solution.u_after.copy()
    u_after[2] += 0.5  # the base alone turns faster: no force on the box could do that
    verdict = verdict_of(STACK, exact_run(STACK, u_after=u_after))
    assert "impulse-residual" in names(verdict)
    residual = next(r for r in verdict.failing if r.name == "impulse-residual")
    assert residual.value > 10 * residual.tolerance


def test_the_engines_summed_impulse_is_compared_with_the_sum_of_the_contacts():
    solution = newton_coulomb(FLAT_BOX)
    one_corner = float(solution.normal_impulse[0])  # only one contact's share
    verdict = verdict_of(FLAT_BOX, exact_run(FLAT_BOX, normal_impulse=one_corner))
    assert names(verdict) == ["impulse-mismatch"]


def test_an_energy_gain_is_the_laws_when_newton_coulomb_gains_too():
    u_after = np.array([0.3, 1.0, 1.5])  # bounces with e = 1 and spins up: both ends open
    run = exact_run(FLAT_BOX, u_after=u_after, normal_impulse=2.0, tangential_impulse=0.0)
    gain = metrics.energy_change(FLAT_BOX.mass_matrix(), FLAT_BOX.state(), u_after)
    assert gain > 0
    by_law = verdict_of(FLAT_BOX, run, law_energy_change=gain)
    reason = next(r for r in by_law.reasons if r.name == "energy-gain")
    assert (reason.attribution, reason.fails) == ("law", False) and by_law.single_impact
    assert "Newton–Coulomb gains" in reason.detail
    by_numerics = verdict_of(FLAT_BOX, run, law_energy_change=-0.1)
    assert names(by_numerics) == ["energy-gain"]


def test_engine_statuses_other_than_the_point_count_stay_reasons():
    verdict = verdict_of(FLAT_BOX, exact_run(FLAT_BOX, status="no-separation"))
    assert names(verdict) == ["no-separation"]
    assert verdict_of(FLAT_BOX, exact_run(FLAT_BOX, status="skipped: x")).reasons == ()


# --------------------------------------------------------------------------------------------
# The flat library scenes through the engines
# --------------------------------------------------------------------------------------------
FLAT = [s for s in load_scenarios() if s.contacts == "simultaneous"]


def test_declared_corners_struck_at_different_steps_are_not_simultaneous():
    """A run in which one declared corner strikes a step after the other did a sequence of
    impacts, not the simultaneous impact declared; the residual cannot tell (for one body on
    the ground it is zero by construction), the first strikes of the declared contacts do."""
    body = FLAT_BOX.bodies[0]
    state = (*body.position, body.angle, *body.velocity, body.angular_velocity)
    corners = [corner_world(body, k) for k in range(4)]
    bottom = sorted(range(4), key=lambda k: corners[k][1])[:2]
    left, right = sorted(bottom, key=lambda k: corners[k][0])
    at_once = (StepContacts(1, tuple((corners[k][0], 0.0, 1e-4) for k in (left, right)),
                            (state,)),)
    staggered = (StepContacts(1, ((corners[left][0], 0.0, 1e-4),), (state,)),
                 StepContacts(2, ((corners[right][0], 0.0, 1e-4),), (state,)),
                 StepContacts(3, ((corners[left][0], 0.0, 1e-4),), (state,)))
    contacts = declared(FLAT_BOX)
    assert verdicts.first_strikes(FLAT_BOX, contacts, at_once) == [1, 1]
    assert verdicts.first_strikes(FLAT_BOX, contacts, staggered) == [1, 2]
    assert verdict_of(FLAT_BOX, exact_run(FLAT_BOX, contacts=at_once)).single_impact
    verdict = verdict_of(FLAT_BOX, exact_run(FLAT_BOX, contacts=staggered))
    assert names(verdict) == ["not-simultaneous"]
    assert verdict.failing[0].value == 1 and "step 2" in verdict.failing[0].detail
    assert verdict.status("multi-contact") == "not-simultaneous"
    # a declared contact never struck is not a stagger (its separation is checked instead)
    one = (StepContacts(1, ((corners[left][0], 0.0, 1e-4),), (state,)),)
    assert verdicts.first_strikes(FLAT_BOX, contacts, one) == [1, None]
    assert "not-simultaneous" not in names(verdict_of(FLAT_BOX,
                                                      exact_run(FLAT_BOX, contacts=one)))


def test_a_near_flat_face_declared_simultaneous_is_flagged_when_engines_do_a_sequence(
        load_or_skip):
    """A face 0.005° from flat (its far corner 4e-5 m up: within the one-point tolerance, so
    it may be declared simultaneous) lands corner after corner in pybullet ``accurate``: the
    run is flagged ``not-simultaneous``, never a clean departure from Newton–Coulomb."""
    engine = load_or_skip("pybullet")
    body = FLAT_BOX.bodies[0].moved(angle=np.radians(-0.005))
    scene = Scene((geometry.place_on_ground(body),), 0.5, 0.3, ground=True)
    contacts = declared(scene)
    assert len(contacts) == 2
    run = engine.run(scene, preset="accurate")
    strikes = verdicts.first_strikes(scene, contacts, verdicts.numbers_from_run(run).contacts)
    assert None not in strikes and len(set(strikes)) == 2
    verdict = judge(scene, problem_of(scene), verdicts.numbers_from_run(run), contacts=contacts)
    assert "not-simultaneous" in names(verdict) and not verdict.single_impact


def approaching(scenario) -> np.ndarray:
    """Which declared contacts approach at the start (``v_n^A(i) < 0``)."""
    scene = scenario.scene()
    wn, _ = geometry.contact_rows(scene, declared(scene))
    return wn @ scene.state() < 0


#: Both ends approach; and one end recedes at the start (flat-box-receding-end).
CLOSING = [s for s in FLAT if approaching(s).all()]
OPENING = [s for s in FLAT if not approaching(s).all()]


@pytest.fixture(scope="module")
def flat_records():
    return [r for r in runner.run(FLAT, engines=("pymunk", "pybullet"), presets=("accurate",),
                                  cache=None, workers=1, log=None).records
            if r.source != "analytic"]


def test_the_declared_contacts_are_those_of_the_reference(flat_records):
    for scenario in FLAT:
        reference = next(r for r in flat_records if r.scenario == scenario.name)
        # a flat face: two corners (a box) or two ends (a rod) touch at once
        assert len(verdicts.declared_contacts(scenario, scenario.scene())) == 2
        assert reference.diagnostics["reference"]["kind"] == "simultaneous"


def test_pymunk_accurate_is_a_clean_impact_on_every_flat_scene_whose_ends_both_approach(
        flat_records):
    runs = [r for r in flat_records if r.source == "pymunk"]
    assert len(runs) == len(FLAT)
    for record in runs:
        if any(record.scenario == s.name for s in CLOSING):
            assert (record.status, record.verdict, record.reasons) == (
                "ok", "single-impact", []), (record.scenario, record.reasons)
        else:  # the receding end comes down and strikes a step later: a sequence
            assert record.failing_reasons == ["not-simultaneous"], record.reasons


def test_pybullet_accurate_stops_with_the_corner_it_struck_first_coming_down(flat_records,
                                                                          load_or_skip):
    """Independent criterion: pybullet's first step reports one point; the verdict must name
    that corner as the declared contact still closing at the end (pybullet resolved the other
    corner in its second step, inside the ground, and its run ended when that one opened)."""
    engine = load_or_skip("pybullet")
    assert CLOSING
    for scenario in CLOSING:
        scene = scenario.scene()
        contacts = declared(scene)
        wn, _ = geometry.contact_rows(scene, contacts)
        first = engine.run(scene, engine.settings("accurate", {"max_steps": 1}))
        ((point,),) = [step.points for step in first.contacts]
        struck = min(range(len(contacts)), key=lambda i: abs(contacts[i].point[0] - point.x))
        record = next(r for r in flat_records
                      if r.scenario == scenario.name and r.source == "pybullet")
        # one corner per step: a sequence, not the simultaneous impact declared
        assert record.failing_reasons == ["not-simultaneous", "not-separated"], (
            scenario.name, record.reasons)
        reason = record.reasons[1]
        assert f"contact {struck + 1} of 2" in reason["detail"], (scenario.name, reason)
        vn_after = wn[struck] @ np.asarray(record.u_after)
        assert reason["value"] == pytest.approx(vn_after, rel=1e-12)


def test_pybullet_accurate_misses_a_face_whose_far_end_recedes(flat_records):
    """Pinned in tests/run/test_flat_engines.py: pybullet takes the receding corner as its one
    point and returns the approach speeds; the approaching end is named, still closing at its
    approach speed (to the rounding of O(1) speeds)."""
    assert OPENING
    for scenario in OPENING:
        scene = scenario.scene()
        wn, _ = geometry.contact_rows(scene, declared(scene))
        (closing,) = np.flatnonzero(approaching(scenario))
        record = next(r for r in flat_records
                      if r.scenario == scenario.name and r.source == "pybullet")
        assert record.failing_reasons == ["not-separated"], (scenario.name, record.reasons)
        reason = record.reasons[0]
        assert f"contact {closing + 1} of 2" in reason["detail"]
        assert reason["value"] == pytest.approx(wn[closing] @ scene.state(), abs=1e-12)


def test_flat_face_records_carry_no_single_contact_law_departures(flat_records):
    """The single-contact laws do not describe a flat face (their five departures were all
    equal there): an engine record holds departures from the m-contact references only,
    and its departure from the primary one, Newton–Coulomb, among them."""
    import planar_impact as pi

    for record in flat_records:
        assert record.departure, record.scenario
        assert not set(record.departure) & set(pi.LAWS), sorted(record.departure)
        primary = record.diagnostics["reference"]["primary"]
        assert primary.startswith("newton-coulomb")
        assert record.departure[primary] == record.diagnostics["reference"][
            "departure_from_primary"]
