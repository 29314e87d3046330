"""The judge's decisions, each worked out from the physics of a hand-built run
(harness/run/verdicts/, docs/verdicts.md, 'The verdict', 'Tolerances', 'Decisions at a
boundary').

Every bound below is derived here, by hand, from the scene and the rule docs/verdicts.md
states, never read back from the judge: a 1 kg disk of radius 0.1 m striking the ground at
``u = (1, −2, 3)`` (``I = m r²/2 = 0.005``, ``w_n = (0, 1, 0)``, ``w_t = ±(1, 0, r)``), two
disks in free flight, and a box landing on a corner. Each check gets runs on either side of
its bound, far from it (the decision with no remark) and within the rounding band
``BOUNDARY_BAND = 1e-9`` (the comparison's own decision, plus an ``at-boundary`` remark that
never fails the run: another CPU may decide it the other way, so the decision must not flip
into a failure of its own).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.run import verdicts
from harness.run.verdicts import (
    DEFAULT_TOLERANCES,
    REASONS,
    RunNumbers,
    StepContacts,
    judge,
)
from harness.scene import Body, Box, Disk, Scene, geometry

TOL = DEFAULT_TOLERANCES

# ---- A disk on the ground, by hand ----------------------------------------------------------
MASS, RADIUS = 1.0, 0.1
INERTIA = 0.5 * MASS * RADIUS * RADIUS  # a uniform disk, kg m²
U_BEFORE = (1.0, -2.0, 3.0)  # (v_x, v_y, ω) at first touch
DISK = Scene((Body("disk", Disk(RADIUS), MASS, (0.0, RADIUS), velocity=U_BEFORE[:2],
                   angular_velocity=U_BEFORE[2]),), restitution=0.5, friction=0.3, ground=True)
APPROACH = 2.0  # |v_n^A| = |w_n·u|, m/s
SPEED_NORM = math.sqrt(MASS * (1.0 + 4.0) + INERTIA * 9.0)  # ‖u‖_M: the ground fixes the frame
ENERGY = 0.5 * SPEED_NORM**2  # 2.5225 J
IMPULSE_SCALE = APPROACH * MASS  # |v_n^A|/m_nn with m_nn = w_n M⁻¹ w_n = 1/m, N s
#: A clean single impact: a normal impulse of 3 N s turns v_y = −2 into +1 (e = 0.5, no
#: friction), v_x and ω unchanged. Δu = (0, 3, 0) = M⁻¹ w_n · 3: no residual, and it loses
#: 1.5 J.
CLEAN_AFTER = (1.0, 1.0, 3.0)
CLEAN_IMPULSE = 3.0
#: A change of speeds no contact impulse makes: M-orthogonal to M⁻¹w_n and M⁻¹w_t, i.e.
#: w_n·d = 0 and w_t·d = 0 (d_y = 0, d_x + r d_ω = 0).
NO_IMPULSE = np.array([-RADIUS, 0.0, 1.0])
NO_IMPULSE_NORM = math.sqrt(MASS * RADIUS * RADIUS + INERTIA)  # ‖d‖_M


def problem_of(scene):
    contact = geometry.scene_contact(scene)
    return geometry.impact_problem(scene, contact.point, contact.normal)


def run_of(u_after, **changes) -> RunNumbers:
    fields = {"engine": "pymunk", "status": "ok", "u_after": np.asarray(u_after, dtype=float),
              "max_penetration": 0.0, "normal_impulse": None, **changes}
    return RunNumbers(**fields)


def failing(verdict) -> list[str]:
    return [reason.name for reason in verdict.failing]


def remarks(verdict) -> list[str]:
    """The checks an ``at-boundary`` remark names (from its detail, 'CHECK: ...')."""
    return [reason.detail.split(":")[0] for reason in verdict.reasons
            if reason.name == "at-boundary"]


def test_the_disk_is_the_hand_worked_impact_and_the_clean_run_passes():
    problem = problem_of(DISK)
    np.testing.assert_array_equal(problem.mass_matrix, np.diag([MASS, MASS, INERTIA]))
    np.testing.assert_array_equal(problem.wn, [0.0, 1.0, 0.0])
    assert np.abs(problem.wt).tolist() == [1.0, 0.0, RADIUS]
    assert problem.wn @ NO_IMPULSE == 0.0 and problem.wt @ NO_IMPULSE == 0.0
    scales = verdicts.scene_scales(DISK, problem)
    assert scales.approach_speed == APPROACH and scales.size == RADIUS
    assert scales.speed_norm == pytest.approx(SPEED_NORM, rel=1e-15)
    assert scales.energy == pytest.approx(ENERGY, rel=1e-15)
    assert scales.impulse == pytest.approx(IMPULSE_SCALE, rel=1e-15)
    verdict = judge(DISK, problem, run_of(CLEAN_AFTER, normal_impulse=CLEAN_IMPULSE,
                                          tangential_impulse=0.0, impulse_source="engine"))
    assert verdict.reasons == () and verdict.single_impact and verdict.status("ok") == "ok"


# ---- not-separated: v_n^S < −separation·|v_n^A| ---------------------------------------------
SEPARATION_BOUND = TOL.separation * APPROACH  # 2e-3 m/s


@pytest.mark.parametrize(("vn_after", "fails", "at_boundary"), [
    (-1.01 * SEPARATION_BOUND, True, False),
    (-0.99 * SEPARATION_BOUND, False, False),
    (-SEPARATION_BOUND, False, True),  # on the bound: v_n^S < −bound is false
    (math.nextafter(-SEPARATION_BOUND, -1.0), True, True),  # one ulp beyond
    (0.5, False, False),
])
def test_not_separated_is_decided_at_a_thousandth_of_the_approach_speed(vn_after, fails,
                                                                        at_boundary):
    # a pure normal impulse (Δu along M⁻¹w_n): only the separation is in question
    verdict = judge(DISK, problem_of(DISK), run_of((1.0, vn_after, 3.0)))
    assert failing(verdict) == (["not-separated"] if fails else [])
    assert remarks(verdict) == (["not-separated"] if at_boundary else [])
    if fails:
        reason = verdict.failing[0]
        assert (reason.value, reason.tolerance) == (vn_after, -SEPARATION_BOUND)
        assert verdict.status("ok") == "not-separated"


# ---- penetration: deepest overlap > penetration·(smallest body extent) ----------------------
PENETRATION_BOUND = TOL.penetration * RADIUS  # a disk's extent is its radius


@pytest.mark.parametrize(("depth", "fails", "at_boundary"), [
    (1.01 * PENETRATION_BOUND, True, False),
    (0.99 * PENETRATION_BOUND, False, False),
    (PENETRATION_BOUND, False, True),
    (math.nextafter(PENETRATION_BOUND, 1.0), True, True),
    (PENETRATION_BOUND * (1 - 1e-12), False, True),
])
def test_penetration_is_decided_at_a_tenth_of_the_radius(depth, fails, at_boundary):
    verdict = judge(DISK, problem_of(DISK), run_of(CLEAN_AFTER, max_penetration=depth))
    assert failing(verdict) == (["penetration"] if fails else [])
    assert remarks(verdict) == (["penetration"] if at_boundary else [])
    if at_boundary:
        return
    # the bound is relative to the body's size: a disk ten times smaller, sinking a tenth
    small = Scene((dataclasses.replace(DISK.bodies[0], shape=Disk(RADIUS / 10),
                                       position=(0.0, RADIUS / 10)),), 0.5, 0.3, ground=True)
    small_run = run_of(CLEAN_AFTER, max_penetration=depth / 10)
    assert failing(judge(small, problem_of(small), small_run)) == (
        ["penetration"] if fails else [])


# ---- impulse-residual: ‖Δu − M⁻¹(w_n I_n + w_t I_t)‖_M / s > impulse_residual -----------------
@pytest.mark.parametrize(("share", "fails", "at_boundary"), [
    (1.01, True, False), (0.99, False, False),
    (1 + 1e-12, True, True), (1 - 1e-12, False, True),  # the band: 1e-9 of 0.02
    (-1.01, True, False),
])
def test_a_change_no_contact_impulse_makes_is_a_residual_of_the_speed_norm(share, fails,
                                                                           at_boundary):
    """Δu = (0, 3, 0) + α d with d M-orthogonal to both contact directions: all of α d is
    residual, ``|α| ‖d‖_M / s``. α is set to put it at ``share`` of the tolerance."""
    alpha = share * TOL.impulse_residual * SPEED_NORM / NO_IMPULSE_NORM
    u_after = np.array(CLEAN_AFTER) + alpha * NO_IMPULSE
    verdict = judge(DISK, problem_of(DISK), run_of(u_after))
    assert failing(verdict) == (["impulse-residual"] if fails else [])
    assert remarks(verdict) == (["impulse-residual"] if at_boundary else [])
    if fails:
        assert verdict.failing[0].value == pytest.approx(abs(share) * TOL.impulse_residual,
                                                         rel=1e-13)


# ---- impulse-mismatch: |I_engine − I_implied| > impulse·|v_n^A|/m_nn ------------------------
@pytest.mark.parametrize(("offset", "fails"), [
    ((1.01, 0.0), True), ((0.99, 0.0), False), ((0.0, 1.01), True), ((0.0, -0.99), False),
    ((0.6 * 1.01, 0.8 * 1.01), True), ((0.6 * 0.99, -0.8 * 0.99), False),
])
def test_an_engine_impulse_off_the_implied_one_is_a_mismatch_of_the_plastic_impulse(offset,
                                                                                   fails):
    """Δu = (0, 3, 0) implies (I_n, I_t) = (3, 0) N s by (A22)/(A23); the engine's is moved by
    ``offset`` times the tolerance of the plastic frictionless impulse, 0.05 · 2 N s."""
    step = TOL.impulse * IMPULSE_SCALE
    engine = (CLEAN_IMPULSE + offset[0] * step, offset[1] * step)
    run = run_of(CLEAN_AFTER, normal_impulse=engine[0], tangential_impulse=engine[1],
                 impulse_source="engine")
    verdict = judge(DISK, problem_of(DISK), run)
    assert failing(verdict) == (["impulse-mismatch"] if fails else [])
    if fails:
        assert verdict.failing[0].value == pytest.approx(math.hypot(*offset) * TOL.impulse,
                                                         rel=1e-12)
    # an impulse rebuilt from momentum measures nothing of its own: never compared
    assert judge(DISK, problem_of(DISK), dataclasses.replace(
        run, impulse_source="momentum")).reasons == ()


# ---- energy-gain: ΔE > energy·E, the law's when newton-lcp gains and the run not much more --
ENERGY_BOUND = TOL.energy * ENERGY


def gaining(gain: float) -> np.ndarray:
    """The disk leaving with ``gain`` J more than it came with, by a normal impulse alone
    (½ m (v_y'² − v_y²) = gain): no residual, separating."""
    return np.array([1.0, math.sqrt(4.0 + 2.0 * gain / MASS), 3.0])


@pytest.mark.parametrize(("share", "fails", "at_boundary"), [
    (1.01, True, False), (0.99, False, False),
    # the band is 1e-9 of 2E (the energies ΔE is the difference of), 2e-3 of the bound
    (1 + 1e-4, True, True), (1 - 1e-4, False, True), (1 + 1e-2, True, False),
])
def test_an_energy_gain_is_decided_at_a_millionth_of_the_kinetic_energy(share, fails,
                                                                       at_boundary):
    verdict = judge(DISK, problem_of(DISK), run_of(gaining(share * ENERGY_BOUND)))
    assert failing(verdict) == (["energy-gain"] if fails else [])
    assert remarks(verdict) == (["energy-gain"] if at_boundary else [])
    if fails:
        reason = verdict.failing[0]
        assert reason.attribution == "numerics"
        assert reason.value == pytest.approx(share * ENERGY_BOUND, rel=1e-8)
        assert reason.tolerance == pytest.approx(ENERGY_BOUND, rel=1e-15)


@pytest.mark.parametrize(("law_gain", "beyond", "attribution"), [
    (None, 0.0, "numerics"),  # no law given
    (0.5 * ENERGY_BOUND, 0.0, "numerics"),  # the law gains less than the bound: no gain
    (2 * ENERGY_BOUND, 0.99, "law"),  # within energy_beyond_law·E of the law's gain
    (2 * ENERGY_BOUND, 1.01, "numerics"),  # beyond it
    (0.3, 0.99, "law"), (0.3, 1.01, "numerics"),
])
def test_a_gain_is_the_laws_only_within_a_hundredth_of_the_energy_of_the_laws_gain(
        law_gain, beyond, attribution):
    gain = ((law_gain or 0.0) + beyond * TOL.energy_beyond_law * ENERGY if beyond
            else 1.5 * ENERGY_BOUND)
    verdict = judge(DISK, problem_of(DISK), run_of(gaining(gain)), law_energy_change=law_gain)
    (reason,) = (r for r in verdict.reasons if r.name == "energy-gain")
    assert reason.attribution == attribution
    assert reason.fails is (attribution == "numerics")
    assert verdict.single_impact is (attribution == "law")


TWO = Scene((Body("a", Disk(0.1), 1.0, (0.0, 0.0), velocity=(2.0, 0.5)),
             Body("b", Disk(0.2), 3.0, (0.3, 0.0), velocity=(-1.0, 0.0))), 0.5, 0.3,
            ground=False)
REDUCED_MASS = 1.0 * 3.0 / (1.0 + 3.0)
#: The kinetic energy in the centre of mass's frame, ½ μ |v_b − v_a|², J (docs/verdicts.md,
#: 'A frame-free departure'): 3.46875 J, whatever common velocity the scene is written with.
TWO_ENERGY = 0.5 * REDUCED_MASS * (3.0**2 + 0.5**2)


def two_disks(boost, gain: float) -> tuple[Scene, np.ndarray]:
    """The two disks boosted by ``boost`` and their speeds after a pair of normal impulses
    along x that gains ``gain`` J (½ μ (v_n'² − v_n²), the tangential part unchanged)."""
    scene = Scene(tuple(dataclasses.replace(body, velocity=tuple(
        np.add(body.velocity, boost).tolist())) for body in TWO.bodies), 0.5, 0.3, ground=False)
    vn_after = math.sqrt(3.0**2 + 2.0 * gain / REDUCED_MASS)  # separating
    impulse = (vn_after + 3.0) * REDUCED_MASS  # J (1/m_a + 1/m_b) = Δv_n
    u = np.array([*scene.bodies[0].velocity, 0.0, *scene.bodies[1].velocity, 0.0])
    return scene, u + np.array([-impulse / 1.0, 0, 0, impulse / 3.0, 0, 0])


@pytest.mark.parametrize("boost", [(0.0, 0.0), (5.0, -7.0), (-40.0, 0.0)])
@pytest.mark.parametrize(("share", "fails"), [(1.01, True), (0.99, False)])
def test_two_free_bodies_gain_against_their_centre_of_mass_energy(boost, share, fails):
    """Without ground no frame is fixed: the bound is 1e-6 of the energy in the centre of
    mass's frame, so a common velocity changes no decision (a lab-frame energy would pass a
    gain of 1.01 bounds at a boost of 40 m/s)."""
    scene, u_after = two_disks(boost, share * TOL.energy * TWO_ENERGY)
    verdict = judge(scene, problem_of(scene), run_of(u_after))
    assert failing(verdict) == (["energy-gain"] if fails else [])
    assert verdicts.scene_scales(scene, problem_of(scene)).energy == pytest.approx(
        TWO_ENERGY, rel=1e-12)


# ---- clipped: a speed at an engine's cap ------------------------------------------------------
@pytest.mark.parametrize(("below", "clipped"), [(0.5e-9, True), (2e-9, False), (0.0, True)])
def test_a_speed_within_a_billionth_of_pybullets_cap_is_clipped(below, clipped):
    """pybullet clamps each joint speed at 100 (docs/verdicts.md, 'Velocity caps'): a speed
    counts as at it from (1 − cap)·100, before or after."""
    at = 100.0 * (1.0 - below)
    for u_after in ((1.0, 1.0, at), (1.0, at, 3.0), (-at, 1.0, 3.0)):
        verdict = judge(DISK, problem_of(DISK), run_of(u_after, engine="pybullet"))
        assert ("clipped" in failing(verdict)) is clipped, u_after
    # pymunk has no cap
    assert "clipped" not in failing(judge(DISK, problem_of(DISK), run_of((1.0, 1.0, 100.0))))


@pytest.mark.parametrize(("below", "clipped"), [(0.5e-6, True), (2e-6, False)])
def test_a_run_reported_cap_is_on_the_bodys_speed_within_a_millionth(below, clipped):
    """Box2D caps |v| and |ω| per body at values of the run's settings, held in float32: a
    speed counts as at its cap from RUN_CAP_BAND = 1e-6 below."""
    speed = math.hypot(3.0, 4.0)
    run = run_of((3.0, 4.0, 3.0), engine="box2d", speed_caps=(speed / (1.0 - below), 1e3))
    assert ("clipped" in failing(judge(DISK, problem_of(DISK), run))) is clipped
    run = run_of(CLEAN_AFTER, engine="box2d", speed_caps=(1e3, 3.0 / (1.0 - below)))
    assert failing(judge(DISK, problem_of(DISK), run)) == (["clipped"] if clipped else [])


# ---- multi-contact: another corner within reach of a recorded point ------------------------
BOX = Scene((geometry.place_on_ground(Body("box", Box(1.0, 0.2), 1.0, (0.0, 0.0),
                                           angle=math.radians(1.0), velocity=(0.5, -1.0))),),
            0.5, 0.3, ground=True)
#: A corner's reach: penetration · the box's extent (its half diagonal) plus the point's depth.
BOX_REACH = TOL.penetration * math.hypot(0.5, 0.1)


def corner(index: int) -> np.ndarray:
    body = BOX.bodies[0]
    return geometry.rotation(body.angle) @ body.shape.vertices()[index] + body.position


@pytest.mark.parametrize("as_track", [False, True])
@pytest.mark.parametrize(("share", "depth", "second"), [
    (0.9, 0.0, True), (1.1, 0.0, False),
    (1.1, 0.2 * BOX_REACH, True),  # a point reported 0.2 reaches deep reaches further
    (1.25, 0.2 * BOX_REACH, False),
])
def test_a_point_within_reach_of_a_second_corner_is_multi_contact(share, depth, second,
                                                                  as_track):
    """The box lands on corner 0 (the lower one at +1°); at step 3 a point lies
    ``share`` of a corner's reach (without depth) beyond corner 1, outwards from the box's
    centre."""
    body = BOX.bodies[0]
    assert geometry.scene_contact(BOX).point == pytest.approx(corner(0), abs=1e-12)
    state = (*body.position, body.angle, *body.velocity, body.angular_velocity)
    outwards = (corner(1) - body.position) / np.linalg.norm(corner(1) - body.position)
    far = corner(1) + share * BOX_REACH * outwards
    records = (StepContacts(1, ((*corner(0), 1e-4),), (state,)),
               StepContacts(3, ((*corner(0), 1e-4), (*far, depth)), (state,)))
    contacts = verdicts.ContactTrack.from_steps(records) if as_track else records
    problem = problem_of(BOX)
    result = problem.solve(mu=BOX.friction, e=BOX.restitution, law="newton-lcp")
    verdict = judge(BOX, problem, run_of(result.u_after, contacts=contacts))
    assert failing(verdict) == (["multi-contact"] if second else [])
    if second:
        reason = verdict.failing[0]
        assert reason.value == 3 and "corner 1" in reason.detail and "step 3" in reason.detail


def test_several_failures_are_listed_in_the_registrys_order_and_the_first_is_the_status():
    """Penetrating, still approaching, gaining energy and pushed by no contact impulse at
    once: every reason, in REASONS's order, and the status is the first."""
    u_after = np.array([1.0, -0.5, 3.0]) + 0.5 * NO_IMPULSE
    gain = 0.5 * (MASS * (u_after[0] ** 2 + u_after[1] ** 2) + INERTIA * u_after[2] ** 2) - ENERGY
    assert gain < 0  # the residual's direction loses energy here: no gain
    verdict = judge(DISK, problem_of(DISK), run_of(u_after, max_penetration=0.02,
                                                   engine="pybullet", status="no-separation"))
    expected = ["no-separation", "not-separated", "penetration", "impulse-residual"]
    assert failing(verdict) == expected
    assert [REASONS.get(name) is not None for name in expected] == [True] * 4
    assert verdict.status("no-separation") == "no-separation"
    assert verdict.status("ok") == "no-separation"
    assert judge(DISK, problem_of(DISK), run_of(u_after, max_penetration=0.02)).status(
        "ok") == "not-separated"
