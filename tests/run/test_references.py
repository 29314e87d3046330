"""Which reference a run is compared with (harness/run/references.py), the m-contact geometry
it needs (harness/scene/geometry.py), and the scenario checks for flat faces.

Numbers worked by hand are compared within derived bounds (the arithmetic replayed on Tracked
numbers) or bit for bit (see the comment above pytestmark).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from harness.run import references, runner
from harness.scenarios import ScenarioError, load_scenario
from harness.scenarios.reader import parse_scenario
from harness.scene import Body, Box, Rod, Scene, geometry
from planar_impact import simultaneous as sim
from tests.error_bounds import Tracked, U
from tests.theory import flat_face_bounds as ffb
from tests.theory import two_phase_bounds as tpb

# coherent counts and the references' decisions: run again on other kernels (conftest.py).
# Kinds (docs/verdicts.md, 'Same answers on every CPU'): counts are decisions, checked not to
# move under a few ulps of every input (a band found by perturbing, not by trying kernels);
# the flat box's Newton–Coulomb and two-phase Poisson speeds against the hand answer, and
# the ground contacts' gaps, points and rows: derived bounds (assert_hand_speeds,
# placed_ground_replay: measured 8 to 11 % and 8 to 27 % of the bound); the box on a wider
# box's normal: exact (derived); its two points: derived (Tracked replay from the exact
# decimals, IEEE operations only, no BLAS; measured 13 to 44 % of the bound); the
# sequential orders' mirror: bit for bit (mirrored arithmetic); the two-phase Poisson
# speeds against Lemke's: exact (the same exact end state, each method's end conditions
# rebuilt and solved in Fractions) and a derived bound (tests/theory/two_phase_bounds.py:
# each computed answer's exact residual, then γ-bounds of Δu; measured at most 47 % per
# component, except where one answer is exact, flat-box's v_x: there the difference is the
# other's own error, all of its part of the bound).
pytestmark = pytest.mark.kernel_sensitive


def flat_box_doc(**top) -> dict:
    doc = {"name": "flat", "restitution": 0.5, "friction": 0.3, "ground": {},
           "body": [{"name": "box", "shape": "box", "width": 1.0, "height": 0.2, "mass": 1.0,
                     "velocity": [0.0, -1.0]}]}
    doc.update(top)
    return doc


# ---------------------------------------------------------------------- geometry
# The ground contacts of a body at angle 0 (cos 0 = 1, sin 0 = 0 exactly: the turn is exact)
# placed on the ground, replayed on Tracked numbers (tests/error_bounds.py) from the exact
# decimal sizes, each value checked equal to the library's bit for bit: its carried error
# bounds the distance from the exact contact (derived bound, not HAND); at most half of it
# may be used.
def placed_ground_replay(body, core_y, radius):
    """``(placed body, its centre's y, the lowest core point's gap)``, the last two Tracked:
    ``place_on_ground`` then ``scene_contacts``' gap ``(y + c_y) − r``, with the lowest core
    point's exact body-frame ``c_y`` and the exact ``radius`` (fractions)."""
    assert body.angle == 0.0 and Fraction(float(body.position[1])) == int(body.position[1])
    points, radius_float = geometry.local_core(body.shape)
    lowest_y = float(points[:, 1].min())
    centre = Tracked(float(body.position[1]))
    c_y = Tracked(lowest_y, ffb.rounding(lowest_y, core_y))
    r = Tracked(radius_float, ffb.rounding(radius_float, radius))
    lowest = (centre + c_y) - r
    assert lowest.value == geometry.lowest_point(body)
    placed = geometry.place_on_ground(body)
    y = centre - lowest
    assert y.value == placed.position[1]
    return placed, y, (y + c_y) - r


def assert_within(value, exact, replayed):
    """``value`` is the replayed one, and the exact hand value lies within half its bound."""
    assert value == replayed.value
    assert abs(Fraction(value) - Fraction(exact)) <= Fraction(replayed.error) / 2, (
        value, exact, replayed)


def test_a_flat_box_has_its_two_bottom_corners_as_contacts():
    body, _, gap = placed_ground_replay(Body("b", Box(1.0, 0.2), 1.0, (0.0, 3.0)),
                                        Fraction(-1, 10), 0)
    contacts = geometry.scene_contacts(Scene((body,), 0.5, 0.3, ground=True))
    assert [c.point[0] for c in contacts] == [-0.5, 0.5]
    assert all(c.point_count == 1 for c in contacts)
    for contact in contacts:
        assert_within(contact.gap, 0, gap)


def test_a_tilt_above_the_tolerance_leaves_one_contact():
    # 0.01° on a 1 m box lifts the far corner by 1.75e-4 m > 1e-4 m.
    body = geometry.place_on_ground(Body("b", Box(1.0, 0.2), 1.0, (0.0, 3.0),
                                         angle=math.radians(0.01)))
    scene = Scene((body,), 0.5, 0.3, ground=True)
    assert len(geometry.scene_contacts(scene, tolerance=1e-4)) == 1
    assert len(geometry.scene_contacts(scene, tolerance=1e-3)) == 2


def test_a_flat_rod_touches_under_both_end_caps():
    body, _, gap = placed_ground_replay(Body("r", Rod(1.0, 0.05), 1.0, (0.0, 3.0)), 0,
                                        Fraction(1, 20))
    contacts = geometry.scene_contacts(Scene((body,), 0.5, 0.3, ground=True))
    assert [c.point[0] for c in contacts] == [-0.5, 0.5]  # ±length/2 + 0: exact
    for contact in contacts:  # midway between the ground and the surface: 0.5 gap, exact
        assert_within(contact.point[1], 0, 0.5 * gap)


def test_a_box_resting_flat_on_a_wider_box_touches_at_the_ends_of_the_shared_face():
    lower = Body("a", Box(2.0, 0.2), 1.0, (0.0, 0.0))
    upper = Body("b", Box(1.0, 0.2), 1.0, (0.3, 0.2), velocity=(0.0, -1.0))
    contacts = geometry.scene_contacts(Scene((lower, upper), 0.5, 0.3))
    # Derived bound, not HAND: at angle 0 (cos 0 = 1, sin 0 = 0 exactly) each world corner is
    # x_local + p, one rounding; the normal is exactly (0, 1) (below), so the tangent is
    # (1, −0) and every projection on it or on the normal, the mid-plane offset and the
    # ends placed along the tangent are exact (products by 0 and 1, sums with ±0): the
    # points are (the shared interval's ends, the upper's bottom corners' x, since
    # −1 < −0.2 and 0.8 < 1; the mid-plane, ½(top of the lower + bottom of the upper)).
    # Replayed on Tracked numbers from the exact decimals (0.3, 0.2, and the local corners
    # ±1/2, ±1/10 each within its rounding), each value checked equal to the library's bit
    # for bit; at most half the carried bound (a few 1e-17 m) may be used.
    corners, _ = geometry.local_core(upper.shape)
    half_width = Tracked(float(corners[:, 0].max()))  # 1.0 / 2: exact
    assert Fraction(half_width.value) == Fraction(1, 2)
    half_height = float(corners[:, 1].max())
    upper_y = Tracked(half_height, ffb.rounding(half_height, Fraction(1, 10)))
    x = Tracked(float(upper.position[0]), ffb.rounding(upper.position[0], Fraction(3, 10)))
    y = Tracked(float(upper.position[1]), ffb.rounding(upper.position[1], Fraction(1, 5)))
    lower_top = Tracked(0.0) + upper_y  # the lower box's local top is the same ±0.1 float
    assert float(geometry.local_core(lower.shape)[0][:, 1].max()) == half_height
    middle = (lower_top + (y - upper_y)) * 0.5
    for contact, end, exact_x in zip(contacts, (x - half_width, x + half_width),
                                     (Fraction(-1, 5), Fraction(4, 5))):
        assert_within(contact.point[0], exact_x, end)
        assert_within(contact.point[1], Fraction(1, 10), middle)
    # Derived: exact. At angle 0 both ends of the upper face are p_y + h/2, the same float,
    # so the edge (d_x, 0) gives the normal (0, −d_x)/|d_x| = (0, ±1) with no rounding.
    assert [c.normal.tolist() for c in contacts] == [[0.0, 1.0]] * 2


def test_contact_rows_of_a_flat_box_are_the_hand_rows():
    """w_n = (0, 1, r_x), w_t = (1, 0, −r_y) at r = (∓0.5, −0.1) (docs/multi-contact.md,
    'Worked example: a box landing flat', with this box's half-height)."""
    body, y, gap = placed_ground_replay(Body("b", Box(1.0, 0.2), 1.0, (0.0, 0.0)),
                                        Fraction(-1, 10), 0)
    scene = Scene((body,), 0.5, 0.3, ground=True)
    wn, wt = geometry.contact_rows(scene, geometry.scene_contacts(scene))
    # n = (0, 1) and t = (1, −0) exactly, r_x = ∓0.5 − 0 exactly: those entries are exact;
    # w_t's last, −r_y = −(0.5 gap − y), within its replay's bound of 1/10.
    assert wn.tolist() == [[0, 1, -0.5], [0, 1, 0.5]]
    assert wt[:, :2].tolist() == [[1, 0], [1, 0]]
    for entry in wt[:, 2]:
        assert_within(float(entry), Fraction(1, 10), -(0.5 * gap - y))


# ---------------------------------------------------------------------- scenario checks
def test_an_undeclared_flat_face_is_refused_and_the_message_names_the_way_out():
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(flat_box_doc())
    text = str(caught.value)
    assert "2 contact points" in text and 'contacts = "simultaneous"' in text


def test_a_declared_flat_face_is_accepted():
    assert parse_scenario(flat_box_doc(contacts="simultaneous")).contacts == "simultaneous"


def test_a_declared_flat_face_that_touches_at_one_point_is_refused():
    doc = flat_box_doc(contacts="simultaneous")
    doc["body"][0]["angle_deg"] = 5.0
    with pytest.raises(ScenarioError, match="declares a flat face, but a single point touches"):
        parse_scenario(doc)


def test_a_flat_face_and_a_sequence_cannot_both_be_declared():
    with pytest.raises(ScenarioError, match="contradicts"):
        parse_scenario(flat_box_doc(contacts="simultaneous", expect_sequence=True))


def test_a_flat_face_where_no_point_approaches_is_refused():
    doc = flat_box_doc(contacts="simultaneous")
    doc["body"][0]["velocity"] = [0.0, 1.0]
    with pytest.raises(ScenarioError, match="no contact point approaches"):
        parse_scenario(doc)


def test_an_unknown_contacts_value_is_refused():
    with pytest.raises(ScenarioError, match="unknown value"):
        parse_scenario(flat_box_doc(contacts="two"))


# ---------------------------------------------------------------------- references
def test_single_contact_scenes_keep_the_single_contact_laws():
    reference = references.point_reference(load_scenario("scenarios/box-corner.toml"), None)
    assert reference["kind"] == "single-contact" and reference["primary"] == "newton-lcp"


def test_a_flat_box_without_slip_is_compared_with_newton_coulomb_which_is_symmetric():
    """Both corners stick and restitute e·|v_n^A| = 0.5 m/s: by symmetry the box leaves at
    v_y = 0.5 m/s without slip or spin (docs/multi-contact.md, 'Worked example: a box landing
    flat', 'Newton–Coulomb' paragraph)."""
    scenario = load_scenario("scenarios/flat-box.toml")
    reference = references.point_reference(scenario, None)
    assert reference["kind"] == "simultaneous" and reference["contacts"] == 2
    assert reference["primary"] == "newton-coulomb"
    assert reference["solutions"]["newton-coulomb"] == 1
    system = flat_system(scenario)
    (solution,) = sim.newton_coulomb(system).solutions
    assert_hand_speeds(system, solution.impulses(), reference["speeds"]["newton-coulomb"])
    # The two orders of the sequential reading are mirror images: v_x and ω change sign, bit
    # for bit (mirrored arithmetic: the box's M is diagonal and its corners' rows mirror
    # each other, so each single-contact impact is the same operations on equal or negated
    # operands, and fl(−x) = −fl(x); tests/theory/test_simultaneous.py, assert_mirror).
    one, other = (np.array(reference["speeds"][f"sequential/poisson/{o}"]) for o in ("0-1", "1-0"))
    assert np.array_equal(one * [-1, 1, -1], other), (one, other)
    assert reference["departure_from_primary"]["newton-coulomb"] == 0.0


#: scenarios/flat-box.toml's exact inputs: 1 kg, (1² + 0.2²)/12 = 13/150 kg m², corners at
#: (∓1/2, −1/10) from the centre.
FLAT_BOX_SCENE = ffb.HandProblem(Fraction(1), Fraction(13, 150), tuple(
    ((0, 1, rx), (1, 0, Fraction(1, 10))) for rx in (Fraction(-1, 2), Fraction(1, 2))))


def flat_system(scenario):
    scene = scenario.scene(None)
    wn, wt = geometry.contact_rows(scene, geometry.scene_contacts(scene))
    return sim.contact_system(mass_matrix=scene.mass_matrix(), wn=wn, wt=wt, u=scene.state(),
                              mu=scene.friction, e=scene.restitution)


def assert_hand_speeds(system, impulses, speeds):
    """Derived bound: the reference's speeds are ``u + Δu`` of the method's impulses (checked
    bit for bit); both corners stick and leave at e·1 m/s, so the exact answer is u' = (0,
    0.5, 0), and Δu is within tests/theory/flat_face_bounds.py's bound of it (Tracked replay
    from the exact inputs, FLAT_BOX_SCENE; the residual of the impulses evaluated a
    posteriori through ‖J⁺‖₂), plus the addition's rounding; at most half of it is used."""
    u_after = system.u + system.delta_u(impulses)
    assert u_after.tolist() == list(speeds)
    residual = ffb.computed_residual_bound(system, impulses, FLAT_BOX_SCENE)
    bound = (ffb.delta_u_bound(system, impulses, residual, FLAT_BOX_SCENE)
             + U * float(np.linalg.norm(u_after)))
    assert np.linalg.norm(u_after - [0.0, 0.5, 0.0]) <= bound / 2, (u_after, bound)


FLAT_SCENES = ("flat-box", "flat-box-slip", "flat-box-spin", "flat-rod",
               "flat-box-receding-end")


@pytest.mark.parametrize("name", FLAT_SCENES)
def test_flat_faces_are_compared_with_the_two_phase_poisson_law_too(name):
    """One answer on each library flat face (one body lying flat: the normal split is
    unique), the same exact end state as Lemke's on the same contact rows, and the two
    computed speeds within the sum of their derived bounds (tests/theory/two_phase_bounds.py).
    """
    from planar_impact import multicontact as mc

    scenario = load_scenario(f"scenarios/{name}.toml")
    reference = references.point_reference(scenario, None)
    assert reference["solutions"][references.TWO_PHASE_POISSON] == 1
    system = flat_system(scenario)
    (two_phase,) = mc.poisson_two_phase(system)
    (lemke,) = mc.poisson_two_phase(system, "lemke")
    speeds = reference["speeds"][references.TWO_PHASE_POISSON]
    assert two_phase.u_after.tolist() == speeds  # the reference is the enumeration's answer
    # Derived bound (two_phase_bounds.rebuild): each method's end conditions rebuilt exactly
    # in Fractions from the floats both read, solved exactly, their decisions (recedes,
    # sticks, slip held) checked exactly; the two exact answers are equal (Lemke may end a
    # phase sliding with no slip where the enumeration sticks, and split the friction
    # between the corners otherwise: the same speeds). Each computed u_after is within the
    # exact Δu of its impulses' residual plus γ_4 of Δu's sum and u of the addition of
    # its exact answer. Measured: the bound's exact part is each answer's own error (a
    # posteriori), so where Lemke's answer is exact the difference is the enumeration's
    # error and uses all of its component (flat-box's v_x, 2.5e-17 m/s); elsewhere at most
    # 47 % per component, and at most 4e-15 against the old stated band's 1e-9 m/s.
    exact_lemke = tpb.rebuild(system, lemke)
    exact_two_phase = tpb.rebuild(system, two_phase)
    assert exact_lemke.u_after == exact_two_phase.u_after
    # The a posteriori part is small because the residuals are: each within the library's
    # promise for a phase it keeps (RESIDUAL_TOLERANCE, a decision band; measured ≤ 1.1e-6 of
    # it), so an answer off its end state cannot hide in its own bound.
    assert exact_lemke.residual_share < 1 and exact_two_phase.residual_share < 1
    for answer, rebuilt in ((lemke, exact_lemke), (two_phase, exact_two_phase)):
        distance = [abs(Fraction(float(x)) - y) for x, y in zip(answer.u_after,
                                                                 rebuilt.u_after)]
        assert all(d <= bound for d, bound in zip(distance, rebuilt.error)), (
            distance, rebuilt.error)
    bound = np.add(exact_lemke.error, exact_two_phase.error)
    assert np.all(np.abs(lemke.u_after - two_phase.u_after) <= bound), (
        lemke.u_after - two_phase.u_after, bound)
    if name == "flat-box":  # symmetric: e|v_y| = 0.5 m/s, no slip, no spin
        assert_hand_speeds(system, two_phase.impulses(), speeds)


def test_every_coherent_solution_is_listed_and_counted():
    reference = references.point_reference(load_scenario("scenarios/flat-rod.toml"), None)
    for law in references.COHERENT_LAWS:
        for coupling in references.COUPLINGS:
            stem = f"coherent/{law}/{coupling}"
            listed = [n for n in reference["speeds"] if n == stem or n.startswith(stem + "#")]
            assert len(listed) == reference["solutions"][stem]


def test_a_tilt_is_compared_with_the_event_driven_sequence():
    scenario = load_scenario("scenarios/sweep-tilted-box.toml")
    point = scenario.point_list()[0]
    reference = references.point_reference(scenario, point)
    assert reference["kind"] == "event-driven"
    assert reference["primary"] == "event-driven/newton-lcp"
    impacts = reference["sequences"]["newton-lcp"]["impacts"]
    assert [impact[0] for impact in impacts][:2] == [0, 1]  # the low corner, then the other
    assert reference["contacts"] == 2 and "at-pose/newton-coulomb" in reference["speeds"]


def test_the_runner_says_which_reference_it_used(tmp_path):
    scenarios = [load_scenario("scenarios/flat-box.toml"),
                 load_scenario("scenarios/box-corner.toml")]
    outcome = runner.run(scenarios, engines=("pymunk",), presets=("accurate",), log=None)
    kinds = {name: [r["kind"] for r in info["references"]]
             for name, info in outcome.scenarios.items()}
    assert kinds == {"flat-box": ["simultaneous"], "box-corner": ["single-contact"]}
    flat_engine_runs = 0
    for record in outcome.records:
        summary = record.diagnostics["reference"]
        if record.source == "analytic":
            assert summary["applies"] == (record.scenario == "box-corner")
        elif record.scenario == "flat-box" and record.u_after is not None:
            flat_engine_runs += 1
            assert summary["primary"] == "newton-coulomb"
            assert math.isfinite(summary["departure_from_primary"])
            assert math.isfinite(record.departure[references.TWO_PHASE_POISSON])
    assert flat_engine_runs > 0


def test_the_library_flat_scenes_counts_are_clear_or_said_to_be_at_a_boundary():
    """flat-box has no clearly coherent Poisson solution in either reading (the effective
    one has one at the boundary of Table 1's types 4 | 5); flat-box-receding-end has none
    under the paper's proposal and one clear plus two at the boundary under the effective
    reading (docs/multi-contact.md, 'Counting on flat landings')."""
    counts = {name: references.point_reference(
        load_scenario(f"scenarios/{name}.toml"), None)["solutions"]
        for name in ("flat-box", "flat-box-receding-end")}
    flat, receding = counts["flat-box"], counts["flat-box-receding-end"]
    assert (flat["coherent/poisson/literal"], flat["coherent/poisson/literal/at-boundary"]) == (
        0, 0)
    assert (flat["coherent/poisson/effective"],
            flat["coherent/poisson/effective/at-boundary"]) == (0, 1)
    assert receding["coherent/poisson/literal"] == 0
    assert (receding["coherent/poisson/effective"],
            receding["coherent/poisson/effective/at-boundary"]) == (1, 2)


def test_random_flat_landings_are_flat_and_approach():
    from harness.reference.flat_faces import flat_system, random_flat_scene

    rng = np.random.default_rng(1)
    for _ in range(20):
        scene = random_flat_scene(rng)
        system = flat_system(scene)
        assert system.count == 2 and min(system.approach[0::2]) < 0.0


@pytest.mark.parametrize("name", ["flat-box", "flat-box-slip", "flat-box-spin", "flat-rod",
                                  "flat-box-receding-end"])
def test_library_flat_scene_counts_do_not_move_under_a_few_ulps(name):
    """Every library flat scene's counts (clearly coherent, at the boundary; Newton–Coulomb's
    outcome) are the same when every input of its contact system moves by up to 3 ulps
    (docs/multi-contact.md, 'Decisions at a boundary'): they sit clear of the band, or say
    that they are at a boundary."""
    from harness.scenarios.schema import ONE_POINT_TOLERANCE
    from planar_impact import simultaneous as sim

    scenario = load_scenario(f"scenarios/{name}.toml")
    point = scenario.point_list()[0]
    scene, fixed = scenario.scene(point), scenario.at(point)
    wn, wt = geometry.contact_rows(scene, geometry.scene_contacts(
        scene, tolerance=ONE_POINT_TOLERANCE))
    problem = dict(mass_matrix=scene.mass_matrix(), wn=wn, wt=wt, u=scene.state(),
                   mu=fixed.friction, e=fixed.restitution)

    def counts(problem):
        system = sim.contact_system(**problem)
        out = {"newton-coulomb": sim.newton_coulomb(system).status}
        for law in sim.TYPE_LAWS:
            for coupling in sim.COUPLINGS:
                found = sim.coherent_solutions(system, law, coupling=coupling)
                out[law, coupling] = (sum(not s.at_boundary for s in found),
                                      sum(s.at_boundary for s in found))
        return out

    expected = counts(problem)
    rng = np.random.default_rng(3)
    for _ in range(4):
        shaken = {key: np.asarray(value, dtype=float) * (1.0 + rng.integers(
            -3, 4, size=np.shape(value)) * 2.0 ** -52) for key, value in problem.items()}
        shaken["mass_matrix"] = np.diag(np.diag(shaken["mass_matrix"]))  # one body: diagonal
        assert counts(shaken) == expected


# ---------------------------------------------------------------------- admissibility
@pytest.mark.parametrize("name", ["flat-box", "flat-box-receding-end", "flat-rod"])
def test_every_flat_reference_solution_is_checked_and_the_primary_is_admissible(name):
    """Each solution's breaks are recorded under ``inadmissible`` (law: what broke); the
    effective reading's impulse at the receding end and its energy gains are named; the
    primary is never one of them."""
    reference = references.point_reference(load_scenario(f"scenarios/{name}.toml"), None)
    broken = reference["inadmissible"]
    assert reference["primary"] == "newton-coulomb" and reference["primary"] not in broken
    assert set(broken) <= set(reference["speeds"])
    assert not any(key.startswith(("newton-coulomb", "two-phase")) for key in broken)
    effective = [lines for key, lines in broken.items() if "/effective" in key]
    assert effective and all(line.split(":")[0] in ("poisson", "stronge-paper", "newton")
                             for lines in effective for line in lines)
    if name == "flat-box-receding-end":
        assert any("recedes at the start" in line for lines in effective for line in lines)
    else:
        assert any("energy gain" in line for lines in effective for line in lines)


def test_an_inadmissible_newton_coulomb_solution_is_never_primary(monkeypatch):
    """Where Newton–Coulomb broke a check, the two-phase Poisson law is primary and the
    reference's ``why`` says so; where both broke, there is no primary."""
    real = references.sim.violations

    def breaking(stems):
        def violations(system, phases, *, promises_no_gain):
            kinds = {phase.kind for phase in phases}
            if ("newton" in kinds and "newton-coulomb" in stems
                    or "compression" in kinds and "two-phase" in stems):
                return ("made up for the test",)
            return real(system, phases, promises_no_gain=promises_no_gain)
        return violations

    scenario = load_scenario("scenarios/flat-box.toml")
    monkeypatch.setattr(references.sim, "violations", breaking({"newton-coulomb"}))
    reference = references.point_reference(scenario, None)
    assert reference["primary"] == "two-phase/poisson"
    assert "newton-coulomb" in reference["inadmissible"]
    monkeypatch.setattr(references.sim, "violations", breaking({"newton-coulomb", "two-phase"}))
    reference = references.point_reference(scenario, None)
    assert reference["primary"] is None and "no primary reference" in reference["why"]
