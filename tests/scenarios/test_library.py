"""The scenario library: every file validates, states what the solver gives, covers the theory.

Expected collision types are integers, so they are compared exactly. Numeric comparisons
state their tolerance where they are made.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import planar_impact as pi
from harness.engines import ENGINE_NAMES
from harness.scenarios import (
    LAWS,
    SCENARIO_DIR,
    Point,
    Scenario,
    ScenarioError,
    check_expectations,
    load_scenario,
    load_scenarios,
    tag_sets,
)
from harness.scenarios.schema import PROJECT_DIR, recorded_location, recorded_path
from harness.scene import Scene, geometry

FILES = sorted(SCENARIO_DIR.glob("*.toml"))
SCENARIOS = load_scenarios()
BY_NAME = {s.name: s for s in SCENARIOS}
# Flat faces (contacts = "simultaneous") are outside the single-contact laws: they have no
# [expect] types and are checked against the m-contact laws in tests/run/test_references.py.
ONE_POINT = [s for s in SCENARIOS if s.contacts == "one"]
FLAT = [s for s in SCENARIOS if s.contacts == "simultaneous"]

# Solver behaviour that disagrees with a scenario's physics: (scenario, law) -> reason. The
# file then leaves that law out of [expect] and says why; none at present.
KNOWN_SOLVER_ISSUES: dict[tuple[str, str], str] = {}


def all_points():
    for scenario in ONE_POINT:
        for point in scenario.point_list():
            yield pytest.param(scenario, point, id=f"{scenario.name}[{point.label}]"
                               if point.label else scenario.name)


def solve_all(scenario: Scenario, point: Point) -> dict:
    problem = scenario.analytic_problem(point)
    fixed = scenario.at(point)
    results = {}
    for law in pi.LAWS:
        if (scenario.name, law) in KNOWN_SOLVER_ISSUES:
            continue
        results[law] = problem.solve(mu=fixed.friction, e=fixed.restitution, law=law)
    return results


# --------------------------------------------------------------------------------------------
# The library validates and agrees with the solver
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_every_file_validates(path):
    scenario = load_scenario(path)
    assert scenario.name == path.stem, "file names follow scenario names"


def test_library_size_and_names_are_unique():
    assert len(SCENARIOS) >= 16
    assert len({s.name for s in SCENARIOS}) == len(SCENARIOS)


def test_laws_match_the_solver():
    assert LAWS == tuple(pi.LAWS)


@pytest.mark.parametrize("scenario", ONE_POINT, ids=[s.name for s in ONE_POINT])
def test_expected_types_match_the_solver(scenario):
    # What a scenario declares in [expect] must hold; a user's scenario may declare nothing.
    assert check_expectations(scenario) == []


@pytest.mark.parametrize("scenario", ONE_POINT, ids=[s.name for s in ONE_POINT])
def test_every_law_is_expected_unless_a_known_issue(scenario):
    stated = set(scenario.expect.collision_type)
    if not stated:
        pytest.skip("declares no [expect] collision types (a user's scenario)")
    missing = {law for law in scenario.laws if law not in stated}
    assert missing == {law for (name, law) in KNOWN_SOLVER_ISSUES if name == scenario.name}


def theory_tangent(wn, wt, u, inverse):
    """docs/theory.md, 'Conventions': t makes v_t^A >= 0; where v_t^A = 0 the solver also
    takes m_nt >= 0, so that a slip developing from a direct impact counts as forward sliding."""
    vt, mnt = wt @ u, wn @ inverse @ wt
    return -wt if vt < 0 or (vt == 0 and mnt < 0) else wt


def theory_terms(scenario, point):
    """``(m_nn, m_nt, m_tt, α)`` of a scenario point by hand (A20, A34), in the theory's t."""
    problem = scenario.analytic_problem(point)
    inverse = np.linalg.inv(problem.mass_matrix)
    wn, u = problem.wn, problem.u
    wt = theory_tangent(wn, problem.wt, u, inverse)
    alpha = (wt @ u) / abs(wn @ u)
    return wn @ inverse @ wn, wn @ inverse @ wt, wt @ inverse @ wt, alpha


@pytest.mark.parametrize("scenario, point", list(all_points()))
def test_expected_case_matches_table_1_by_hand(scenario, point):
    """Cross-check the solver's Table 1 row with the signs of g, h, p, q.

    docs/theory.md, 'Contact terms'.
    """
    if scenario.expected_case(point) is None:
        pytest.skip("declares no [expect] case")
    mnn, mnt, mtt, _ = theory_terms(scenario, point)
    mu = scenario.at(point).friction
    g, h, p, q = mu * mtt - mnt, mnn - mu * mnt, mu * mtt + mnt, mnn + mu * mnt
    # Exact zeros (mu = 0 disk: g = p = 0) are rounding-level otherwise; 1e-12 relative.
    eps = 1e-12 * max(mnn, mtt)
    if g <= eps:
        case = 5
    elif h <= eps:
        case = 4
    elif p < -eps:
        case = 3
    elif q < -eps:
        case = 2
    else:
        case = 1
    assert scenario.expected_case(point) == case


@pytest.mark.parametrize("scenario, point", list(all_points()))
def test_poisson_type_follows_table_1_by_hand(scenario, point):
    """The stated Poisson type from alpha against r_m and (1 + e) r_m.

    docs/theory.md, 'Poisson's law'.
    """
    if (scenario.expected_case(point) is None
            or scenario.expected_collision_type("poisson", point) is None):
        pytest.skip("declares no [expect] case or Poisson type")
    mnn, mnt, mtt, alpha = theory_terms(scenario, point)
    fixed = scenario.at(point)
    mu, e = fixed.friction, fixed.restitution
    g, h = mu * mtt - mnt, mnn - mu * mnt
    case = scenario.expected_case(point)
    if case == 4:
        expected = 1
    elif case == 5:
        expected = 5
    else:
        r_m = g / h
        stick, reverse = (1, 2) if case in (1, 2) else (3, 4)
        expected = stick if alpha <= r_m else reverse if alpha <= (1 + e) * r_m else 5
    assert scenario.expected_collision_type("poisson", point) == expected


# --------------------------------------------------------------------------------------------
# Coverage of the theory (issue 4's list)
# --------------------------------------------------------------------------------------------
def _coverage():
    cases, types, gain, direct, grazing, frictionless, e_values = set(), set(), False, False, \
        False, False, set()
    for scenario in SCENARIOS:
        for point in scenario.point_list():
            results = solve_all(scenario, point)
            fixed = scenario.at(point)
            cases.add(results["poisson"].case)
            types.add(results["poisson"].collision_type)
            gain |= results["newton"].energy_change > 0.0
            alpha = results["poisson"].vt_approach / abs(results["poisson"].vn_approach)
            direct |= alpha == 0.0
            grazing |= alpha >= 50.0
            frictionless |= fixed.friction == 0.0
            e_values.add(fixed.restitution)
    return cases, types, gain, direct, grazing, frictionless, e_values


def test_library_covers_the_theory():
    cases, types, gain, direct, grazing, frictionless, e_values = _coverage()
    assert cases == {1, 2, 3, 4, 5}
    assert types == {1, 2, 3, 4, 5}
    assert gain, "some scenario shows Newton's energy gain"
    assert direct and grazing and frictionless
    assert {0.0, 1.0} <= e_values


def test_library_has_the_named_families():
    shapes = {spec.shape.kind for s in SCENARIOS for spec in s.bodies}
    assert shapes == {"disk", "rod", "box", "polygon", "ellipse"}
    assert any(s.system == "two-sled" for s in SCENARIOS)
    assert any(s.system == "matrix" for s in SCENARIOS)
    assert any(not s.ground and s.system == "bodies" for s in SCENARIOS)
    assert any(spec.inertia is not None for s in SCENARIOS for spec in s.bodies)  # dumbbell
    assert any(s.bodies and s.bodies[0].angular_velocity for s in SCENARIOS)  # spin
    assert sum(1 for s in SCENARIOS if s.sweep) >= 3
    sets = tag_sets(SCENARIOS)
    assert set(sets["all"]) == set(BY_NAME)
    assert 4 <= len(sets["quick"]) < len(SCENARIOS)
    assert "slip-reversal" in sets


@pytest.mark.parametrize("row, delta, mu, types", [
    (1, 0.2, 0.3, {"newton": 3, "poisson": 5, "stronge": 5}),
    (2, 0.85, 0.3, {"newton": 2, "poisson": 3, "stronge": 3}),
    (3, 0.85, 0.7, {"newton": 1, "poisson": 1, "stronge": 1}),
])
def test_two_sled_rows_are_table_3(row, delta, mu, types):
    scenario = BY_NAME[f"two-sled-row{row}"]
    assert scenario.analytic_only and scenario.scene() is None and scenario.engines == ()
    assert (scenario.parameters["gamma"], scenario.parameters["delta"]) == (0.2, delta)
    assert (scenario.friction, scenario.restitution) == (mu, 0.8)
    for law, collision_type in types.items():  # Table 3's printed types
        assert scenario.expected_collision_type(law) == collision_type
        assert scenario.expected_collision_type("stronge-paper") == types["stronge"]


@pytest.mark.parametrize("name", ["matrix-rod-45", "rod-45-slip-reversal"])
def test_rod_45_reproduces_engines_md(name):
    """The rod of docs/engines.md, 'The reference scenes': post-impact velocities.

    They are printed there to 4 decimals: tolerance 5e-5.
    """
    scenario = BY_NAME[name]
    printed = {"poisson": (0.5449, -0.4127, -2.2988), "stronge": (0.5488, -0.3995, -2.3379),
               "newton": (0.5595, -0.3638, -2.4432), "newton-lcp": (0.7202, -0.2660, -2.1666)}
    for law, velocities in printed.items():
        np.testing.assert_allclose(scenario.solve(law=law).u_after, velocities, atol=5e-5)


def test_geometry_path_equals_the_matrix_given_by_hand():
    """The rod built from the scene (contact geometry + builder) and the hand-written matrix
    are one problem: equal to rounding (1e-14 on O(1) entries)."""
    built = BY_NAME["rod-45-slip-reversal"].analytic_problem()
    given = BY_NAME["matrix-rod-45"].analytic_problem()
    for field in ("mass_matrix", "wn", "wt", "u"):
        np.testing.assert_allclose(getattr(built, field), getattr(given, field), rtol=0,
                                   atol=1e-14)


# --------------------------------------------------------------------------------------------
# Engine scenes are one-point, touching, approaching
# --------------------------------------------------------------------------------------------
ENGINE_POINTS = [p for p in all_points() if not p.values[0].analytic_only]


@pytest.mark.parametrize("scenario, point", ENGINE_POINTS)
def test_engine_scenes_touch_at_one_point_and_approach(scenario, point):
    scene = scenario.scene(point)
    assert isinstance(scene, Scene)
    contact = geometry.scene_contact(scene, tolerance=1e-4)  # 0.1 mm: see ONE_POINT_TOLERANCE
    assert contact.point_count == 1
    assert abs(contact.gap) <= scenario.gap_tolerance
    vn, _ = geometry.contact_velocity(scene, contact)
    assert vn < 0.0
    # Moderate speeds keep default-preset engines representative (issue 4).
    speeds = [math.hypot(*b.velocity) for b in scene.bodies]
    assert max(speeds) <= 2.5


@pytest.mark.parametrize("scenario", FLAT, ids=[s.name for s in FLAT])
def test_flat_scenes_touch_at_two_points_one_approaching_and_expect_no_single_law(scenario):
    scene = scenario.scene()
    contacts = geometry.scene_contacts(scene, tolerance=1e-4)  # ONE_POINT_TOLERANCE
    assert len(contacts) == 2 and all(abs(c.gap) <= scenario.gap_tolerance for c in contacts)
    assert min(geometry.contact_velocity(scene, c)[0] for c in contacts) < 0.0
    assert not scenario.expect.collision_type and not scenario.expect_sequence


def test_library_has_the_flat_scenes_of_issue_13():
    """A box landing flat without slip, with slip, with spin, and a rod landing flat."""
    shapes = {(s.bodies[0].shape.kind, s.bodies[0].velocity[0] != 0,
               s.bodies[0].angular_velocity != 0) for s in FLAT}
    assert {("box", False, False), ("box", True, False), ("box", False, True)} <= shapes
    assert any(kind == "rod" for kind, _, _ in shapes)


def test_engine_scenes_list_engines_and_analytic_ones_none():
    for scenario in SCENARIOS:
        if scenario.analytic_only:
            assert scenario.engines == () and not scenario.expect.gates
        else:
            assert scenario.engines == ENGINE_NAMES


def test_gates_are_read():
    gates = BY_NAME["rod-45-slip-reversal"].gates_for("pymunk", "accurate")
    assert [(g.law, g.max_departure, g.source) for g in gates] == [
        ("newton-lcp", 1e-6, "pymunk.accurate")]
    assert BY_NAME["rod-45-slip-reversal"].gates_for("pymunk", "defaults") == ()


# --------------------------------------------------------------------------------------------
# Points, scenes and problems
# --------------------------------------------------------------------------------------------
def test_points_of_a_sweep():
    scenario = BY_NAME["sweep-disk-alpha"]
    points = scenario.points()
    assert [p.value for p, _ in points] == pytest.approx(np.linspace(0.0, 2.0, 9).tolist())
    assert points[4][0].label == "body.disk.velocity.x=1"
    scene = points[4][1]
    assert scene.bodies[0].velocity == (1.0, -1.0)
    assert scenario.scene(4) == scene and scenario.scene(points[4][0]) == scene
    with pytest.raises(ScenarioError, match="say which point"):
        scenario.scene()
    with pytest.raises(ScenarioError, match="out of range"):
        scenario.scene(9)


def test_points_of_a_single_scenario_and_of_analytic_systems():
    (point, scene), = BY_NAME["disk-oblique"].points()
    assert point == Point(0) and point.label == ""
    assert scene.ground and scene.restitution == 0.5 and scene.friction == 0.3
    assert scene.bodies[0].position == pytest.approx((0.0, 0.1), abs=1e-15)  # placed
    (point, problem), = BY_NAME["two-sled-row2"].points()
    assert isinstance(problem, pi.ImpactProblem) and problem.u.shape == (4,)


def test_friction_sweep_changes_only_friction():
    scenario = BY_NAME["sweep-rod-45-friction"]
    assert [scenario.friction_at(i) for i in range(3)] == pytest.approx([0.0, 0.1, 0.2])
    assert scenario.restitution_at(2) == 0.5
    assert scenario.scene(3).friction == pytest.approx(0.3)


def test_angle_sweep_places_each_point_on_the_ground():
    scenario = BY_NAME["sweep-rod-angle"]
    for point, scene in scenario.points():
        assert math.degrees(scene.bodies[0].angle) == pytest.approx(point.value)
        # place_on_ground: a few operations on O(1 m) numbers, 1e-12 m.
        assert geometry.lowest_point(scene.bodies[0]) == pytest.approx(0.0, abs=1e-12)


def test_two_sled_sweep_builds_the_paper_rows():
    """delta = 0.85 of the sweep is Table 3 row 2's problem exactly (same builder call)."""
    sweep = BY_NAME["sweep-two-sled-delta"]
    index = sweep.sweep.values.index(0.85)
    a, b = sweep.analytic_problem(index), BY_NAME["two-sled-row2"].analytic_problem()
    np.testing.assert_array_equal(a.mass_matrix, b.mass_matrix)
    np.testing.assert_array_equal(a.wn, b.wn)


def test_analytic_problem_of_a_ground_scene_uses_the_contact_geometry():
    scenario = BY_NAME["rod-45-slip-reversal"]
    problem = scenario.analytic_problem()
    contact = scenario.contact()
    body = scenario.scene().bodies[0]
    r = contact.point - np.asarray(body.position)
    # w_n = (n_x, n_y, r_x n_y - r_y n_x) with n = (0, 1) (docs/theory.md, 'Conventions');
    # exact arithmetic.
    np.testing.assert_allclose(problem.wn, [0.0, 1.0, r[0]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(problem.wt, [1.0, 0.0, -r[1]], rtol=0, atol=1e-15)
    assert problem.mass_matrix[2, 2] == body.moment_of_inertia


def test_two_body_problem_orders_bodies_as_in_the_file():
    scenario = BY_NAME["two-disks-off-centre"]
    problem = scenario.analytic_problem()
    np.testing.assert_array_equal(problem.u, [1.0, 0.0, 0.0, 0.0, -1.0, 5.0])
    np.testing.assert_array_equal(np.diag(problem.mass_matrix)[[0, 3]], [1.0, 2.0])
    contact = scenario.contact()
    # Normal from a into b along the line of centres at 60°; a few roundings: 1e-12.
    np.testing.assert_allclose(contact.normal, [0.5, math.sqrt(3) / 2], atol=1e-12)


# --------------------------------------------------------------------------------------------
# Tags
# --------------------------------------------------------------------------------------------
def test_load_by_tags():
    quick = load_scenarios(tags="quick")
    assert quick and all("quick" in s.tags for s in quick)
    both = load_scenarios(tags="box,polygon")
    assert {s.name for s in both} == {"box-corner", "box-corner-spin", "triangle-corner",
                                      "flat-box", "flat-box-slip", "flat-box-spin",
                                      "flat-box-receding-end"}
    assert len(load_scenarios(tags=["all"])) == len(SCENARIOS)
    with pytest.raises(ScenarioError, match="no scenario has this tag.*did you mean 'quick'"):
        load_scenarios(tags="quik")


def test_load_a_list_of_files():
    loaded = load_scenarios([FILES[0], FILES[1]])
    assert [s.path for s in loaded] == FILES[:2]


def test_results_record_library_paths_relative_to_the_project(tmp_path):
    """A committed results file names no machine's directory: a library file's path is
    recorded relative to the project and found again from there; a file elsewhere keeps its
    absolute path."""
    library_file = next(SCENARIO_DIR.glob("*.toml"))
    recorded = recorded_path(library_file)
    assert recorded == f"scenarios/{library_file.name}"
    assert recorded_location(recorded) == library_file
    elsewhere = tmp_path / "mine.toml"
    assert recorded_path(elsewhere) == str(elsewhere.resolve())
    assert recorded_location(recorded_path(elsewhere)) == elsewhere.resolve()


def test_the_committed_results_name_no_machines_directory():
    """The committed results file records the library's files and the result cache by paths
    relative to the project, never by the directory of the machine that wrote them."""
    results = json.loads((PROJECT_DIR / "reports" / "results.json").read_text())
    recorded = [entry["path"] for entry in results["scenarios"].values()]
    recorded.append(results["provenance"]["cache"]["root"])
    assert recorded and all(not Path(path).is_absolute() for path in recorded), recorded
