"""Property tests (hypothesis) of the laws, and the errors every bad input gets."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import planar_impact as pi
from planar_impact import errors, laws
from planar_impact.solver import energy_gain_decision

PROCESS_LAWS = ("newton", "poisson", "stronge")

finite = dict(allow_nan=False, allow_infinity=False)
mass_term = st.floats(0.1, 10.0, **finite)
correlation = st.floats(-0.99, 0.99, **finite)  # m_nt / √(m_nn m_tt): keeps Δ > 0
approach = st.floats(-10.0, -0.01, **finite)
slip = st.floats(-10.0, 10.0, **finite)
friction = st.floats(0.0, 2.0, **finite)
restitution = st.floats(0.0, 1.0, **finite)


@st.composite
def problems(draw, vt=slip, mu=friction, e=restitution):
    mnn, mtt, rho = draw(mass_term), draw(mass_term), draw(correlation)
    return dict(mnn=mnn, mnt=rho * math.sqrt(mnn * mtt), mtt=mtt, vn=draw(approach),
                vt=draw(vt), mu=draw(mu), e=draw(e))


def solve(problem, law):
    result = pi.solve_batch(**problem, law=law)
    assert result.status == 0, errors.STATUS_MESSAGES[int(result.status)]
    return result


def impulse_scale(p):
    return abs(p["vn"]) / p["mnn"] + abs(p["vt"]) / p["mtt"]


# --- energy ------------------------------------------------------------------------------

@settings(max_examples=400, deadline=None)
@given(problems())
def test_poisson_and_exact_stronge_never_gain_energy(problem):
    for law in ("poisson", "stronge"):
        result = solve(problem, law)
        # Exact laws dissipate: no gain by the solver's decision (the bar, beyond (A29)'s
        # derived rounding band; inside the band no gain is claimed).
        gained, _ = energy_gain_decision(
            result.energy_change, result.normal_impulse, result.tangential_impulse,
            result.vn_approach, result.vt_approach, problem["mnn"], problem["mnt"],
            problem["mtt"])
        assert not gained, law


def test_newton_energy_gain_is_reported_where_it_occurs():
    """Newton's law gains energy in a few percent of problems (Part A); the
    solver reports the gain (positive ΔE, ``energy_gained``), it does not hide it."""
    from harness.scene.random_problems import random_problems

    draws = random_problems(20_000, seed=11)
    newton = pi.solve_batch(**draws, law="newton")
    poisson = pi.solve_batch(**draws, law="poisson")
    terms = [draws[k] for k in ("mnn", "mnt", "mtt")]
    gained, _ = energy_gain_decision(newton.energy_change, newton.normal_impulse,
                                     newton.tangential_impulse, newton.vn_approach,
                                     newton.vt_approach, *terms)
    poisson_gained, _ = energy_gain_decision(poisson.energy_change, poisson.normal_impulse,
                                             poisson.tangential_impulse, poisson.vn_approach,
                                             poisson.vt_approach, *terms)
    # docs/theory.md, 'Newton's law': about 3% of the problems with reversal.
    assert 0.005 < gained.mean() < 0.1
    # Forward sliding is Poisson's Type 5 exactly (comment f), so never a gain there.
    assert pi.laws.NEWTON_FORWARD not in set(np.unique(newton.collision_type[gained]))
    assert not poisson_gained[gained].any()


def test_energy_gained_flag_on_a_known_case():
    # Case 3 (m_nt < 0, μ < −m_nt/m_tt), e = 1, v_t^A moderate: Newton's reverse sliding
    # ends with more energy than it started (Part A's inconsistency).
    matrix = np.eye(2)
    # Contact-space terms m_nn = 1, m_nt = −0.9, m_tt = 1 from w_n, w_t on the identity M.
    wn = np.array([1.0, 0.0])
    wt = np.array([-0.9, math.sqrt(1 - 0.81)])
    for vt_target in np.linspace(0.05, 2.0, 40):
        # Choose u with w_n·u = −1 and w_t·u = vt_target.
        u = np.linalg.solve(np.stack([wn, wt]), [-1.0, vt_target])
        newton = pi.solve(mass_matrix=matrix, wn=wn, wt=wt, u=u, mu=0.2, e=1.0, law="newton")
        if newton.energy_gained:
            poisson = pi.solve(mass_matrix=matrix, wn=wn, wt=wt, u=u, mu=0.2, e=1.0)
            assert newton.energy_change > 0 and newton.collision_type == pi.laws.NEWTON_REVERSE
            assert not poisson.energy_gained
            return
    pytest.fail("no energy gain found on a Case 3 line where Part A predicts one")


# --- continuity at the type boundaries (comment a) -----------------------------------------

@settings(max_examples=300, deadline=None)
@given(problems(vt=st.just(1.0)), st.sampled_from([1.0, "1+e"]),
       st.sampled_from(["poisson", "stronge", "stronge-paper", "newton"]))
def test_continuity_across_type_boundaries(problem, boundary, law):
    if law == "stronge-paper":
        # The paper's mapping is continuous only for e_e > 0 and, at α = (1+e)r_m, only for
        # m_nt ≥ 0 (see the two pinned tests below); near e_e = 0 its slope grows like 1/e_e.
        assume(problem["e"] >= 0.05)
        assume(boundary == 1.0 or problem["mnt"] >= 0)
    terms = pi.laws.ContactTerms(*(np.float64(problem[k])
                                   for k in ("mnn", "mnt", "mtt", "vn", "vt", "mu")))
    assume(terms.case in (1, 2, 3) and terms.r_m > 0.05)
    factor = 1.0 if boundary == 1.0 else 1.0 + problem["e"]
    alpha_boundary = factor * float(terms.r_m)
    results = []
    for side in (1 - 1e-9, 1 + 1e-9):
        p = dict(problem, vt=alpha_boundary * side * abs(problem["vn"]))
        results.append(solve(p, law))
    below, above = results
    scale = impulse_scale(dict(problem, vt=alpha_boundary * abs(problem["vn"])))
    # A jump would be O(scale); α moved by 2e-9 relative moves a continuous answer by
    # O(1e-9·scale·condition). 1e-6 separates the two by orders of magnitude.
    for name in ("normal_impulse", "tangential_impulse"):
        assert abs(float(getattr(below, name)) - float(getattr(above, name))) <= 1e-6 * scale, name


# --- special cases the paper names ----------------------------------------------------------

@settings(max_examples=200, deadline=None)
@given(problems(mu=st.just(0.0)))
def test_frictionless_laws_coincide(problem):
    """μ = 0: no tangential impulse; Newton, Poisson and Stronge coincide (comment b)."""
    results = {law: solve(problem, law) for law in PROCESS_LAWS + ("stronge-paper",)}
    scale = impulse_scale(problem)
    for result in results.values():
        assert result.tangential_impulse == 0.0
        assert float(result.normal_impulse) == pytest.approx(
            float(results["poisson"].normal_impulse), abs=1e-12 * scale)


@settings(max_examples=200, deadline=None)
@given(problems())
def test_balanced_collision(problem):
    """m_nt = 0: no reverse sliding, I_n = (1 + e)|v_n^A|/m_nn and v_n^S = e|v_n^A| for every
    law (comment e)."""
    problem = dict(problem, mnt=0.0)
    for law in pi.LAWS:
        result = solve(problem, law)
        expected = (1 + problem["e"]) * abs(problem["vn"]) / problem["mnn"]
        assert float(result.normal_impulse) == pytest.approx(expected, rel=1e-12)
        assert float(result.vn_separation) == pytest.approx(
            problem["e"] * abs(problem["vn"]), rel=1e-12, abs=1e-12 * abs(problem["vn"]))
        assert result.collision_type not in ((2,) if law.startswith("newton") else (3, 4))


@settings(max_examples=200, deadline=None)
@given(problems(e=st.just(0.0)))
def test_plastic_impact_ends_at_rest_normally(problem):
    """e = 0: v_n^S = 0 for every law and type (comment c). Not for the paper's Stronge
    mapping: see the next test."""
    for law in ("newton", "poisson", "stronge", "newton-lcp"):
        result = solve(problem, law)
        assert abs(float(result.vn_separation)) <= 1e-12 * abs(problem["vn"]) * (
            1 + abs(problem["vt"]) / abs(problem["vn"]))


def test_paper_stronge_mapping_jumps_at_zero_restitution():
    """A property of the paper's Section 4, pinned so that nobody "fixes" it silently.

    With e_e = 0, (63) reads (1 + r) e_i² + r e_i = 0, whose '+√' root (64) is
    e_i = −r/(1 + r) > 0 when r = α m_nt/m_tt < 0: a plastic Stronge impact bounces
    (v_n^S = e_i (1 + r)|v_n^A| > 0). Just above α = r_m the type is 5 and (74) gives
    e_i = e_e = 0, so the mapping jumps there. The exact energetic law has neither defect.
    """
    problem = dict(mnn=1.0, mnt=-0.5, mtt=1.0, vn=-1.0, mu=1.0, e=0.0)
    r_m = (1.0 * 1.0 + 0.5) / (1.0 - 1.0 * -0.5)  # g/h with g = μ m_tt − m_nt, h = m_nn − μ m_nt
    below = solve(dict(problem, vt=0.999 * r_m), "stronge-paper")
    above = solve(dict(problem, vt=1.001 * r_m), "stronge-paper")
    r = 0.999 * r_m * -0.5 / 1.0
    assert int(below.collision_type) == 1 and int(above.collision_type) == 5
    assert float(below.restitution_poisson) == pytest.approx(-r / (1 + r), rel=1e-12)
    assert float(below.vn_separation) > 0.4  # bounces although e_e = 0
    assert float(above.restitution_poisson) == 0.0
    exact = solve(dict(problem, vt=0.999 * r_m), "stronge")
    assert abs(float(exact.vn_separation)) < 1e-12


def test_paper_stronge_mapping_jumps_at_the_forward_sliding_boundary_when_mnt_negative():
    """Pinned property of the paper's Section 4: at α = (1+e_e) r_m, e_i = e_e is a root of
    (66), as the paper says, but for m_nt < 0 (r < 0, y > 0) the other root is larger and the
    '+√' root of (67) picks it, so e_i jumps from ≈ 1 (Type 2) to e_e (Type 5)."""
    problem = dict(mnn=1.0, mnt=-0.75, mtt=1.0, vn=-1.0, mu=1.0, e=0.5)
    r_m = (1.0 + 0.75) / (1.0 + 0.75)  # g/h
    below = solve(dict(problem, vt=(1 - 1e-6) * 1.5 * r_m), "stronge-paper")
    above = solve(dict(problem, vt=(1 + 1e-6) * 1.5 * r_m), "stronge-paper")
    assert (int(below.collision_type), int(above.collision_type)) == (2, 5)
    assert float(below.restitution_poisson) == pytest.approx(1.0, abs=1e-4)  # α 1e-6 off
    assert float(above.restitution_poisson) == 0.5
    exact = [solve(dict(problem, vt=f * 1.5 * r_m), "stronge") for f in (1 - 1e-6, 1 + 1e-6)]
    assert float(exact[0].normal_impulse) == pytest.approx(float(exact[1].normal_impulse), rel=1e-5)


@settings(max_examples=200, deadline=None)
@given(problems(vt=st.just(0.0)))
def test_direct_impact_types(problem):
    """v_t^A = 0: only types 1, 3 and 5 (comment d)."""
    assert int(solve(problem, "poisson").collision_type) in (1, 3, 5)


@settings(max_examples=300, deadline=None)
@given(problems(), st.sampled_from(pi.LAWS))
def test_flipping_t_mirrors_the_result(problem, law):
    straight = solve(problem, law)
    flipped = solve(dict(problem, mnt=-problem["mnt"], vt=-problem["vt"]), law)
    scale = impulse_scale(problem)
    assert float(flipped.normal_impulse) == pytest.approx(float(straight.normal_impulse),
                                                          abs=1e-12 * scale)
    assert float(flipped.tangential_impulse) == pytest.approx(
        -float(straight.tangential_impulse), abs=1e-12 * scale)
    assert float(flipped.vt_separation) == pytest.approx(
        -float(straight.vt_separation), abs=1e-12 * (1 + abs(problem["vt"])))
    assert flipped.collision_type == straight.collision_type


def rotate(vector, angle):
    c, s = math.cos(angle), math.sin(angle)
    return (c * vector[0] - s * vector[1], s * vector[0] + c * vector[1])


@settings(max_examples=200, deadline=None)
@given(st.floats(-math.pi, math.pi), st.floats(0.2, 5.0), st.floats(0.2, 5.0),
       st.floats(-2, 2), st.floats(-2, 2), st.floats(-3, 3), st.floats(0.0, 1.5),
       st.floats(0.0, 1.0), st.sampled_from(pi.LAWS))
def test_rotating_a_rigid_body_scene_leaves_the_result_unchanged(angle, mass_a, mass_b, vx, vy,
                                                                  omega, mu, e, law):
    point = (0.3, -0.1)
    normal = (0.28, 0.96)

    def scene(theta):
        a = pi.PlanarBody(mass_a, 0.1 * mass_a, rotate((-0.5, -0.6), theta),
                          rotate((0.2, 0.4), theta), 0.5)
        b = pi.PlanarBody(mass_b, 0.2 * mass_b, rotate((0.6, 0.5), theta),
                          rotate((vx, vy - 3.0), theta), omega)
        return pi.builders.two_bodies(a, b, rotate(point, theta), rotate(normal, theta))

    # A stated band (rel 1e-9, abs 1e-12), not derived: the turned scene is another problem,
    # its inputs rounded by cos, sin (libm) and the turn, solved through Cholesky, and the
    # two answers are compared on this machine's kernel (not kernel_sensitive: no CPU's
    # last bits come near it). Measured at most 0.53 % of the band on 2,000 seeded draws of
    # this family. The geometry's turns are checked bit for bit elsewhere
    # (tests/scene/test_turns.py); here it is the law's invariance that is tested.
    base, turned = scene(0.0), scene(angle)
    assume(base.wn @ base.u < -1e-3)
    first = base.solve(mu=mu, e=e, law=law)
    second = turned.solve(mu=mu, e=e, law=law)
    for name in ("normal_impulse", "tangential_impulse", "vn_separation", "vt_separation",
                 "energy_change"):
        assert getattr(second, name) == pytest.approx(getattr(first, name), rel=1e-9, abs=1e-12)
    # Velocities turn with the scene; angular velocities do not change.
    for body in (0, 1):
        vx0, vy0, w0 = first.u_after[3 * body: 3 * body + 3]
        expected = (*rotate((vx0, vy0), angle), w0)
        np.testing.assert_allclose(second.u_after[3 * body: 3 * body + 3], expected, rtol=1e-9,
                                   atol=1e-12)


# --- unreachable jams: why the status codes exist but cannot trigger with Δ > 0 --------------

@settings(max_examples=500, deadline=None)
@given(problems())
def test_no_jam_and_positive_q_in_reverse_sliding_when_delta_positive(problem):
    """h ≤ 0 and g ≤ 0 together would need m_nn m_tt ≤ m_nt² (Δ ≤ 0); p < 0 forces
    q > Δ/m_tt > 0. The solver keeps both checks (statuses 6 and 7) for rounding at Δ → 0."""
    terms = pi.laws.ContactTerms(*(np.float64(problem[k])
                                   for k in ("mnn", "mnt", "mtt", "vn", "vt", "mu")))
    assert not (terms.h <= 0 and terms.g <= 0)
    if terms.p < 0:
        assert terms.q > 0


# --- bad input ------------------------------------------------------------------------------

GOOD = dict(mass_matrix=np.eye(3), wn=[0.0, 1.0, 0.1], wt=[1.0, 0.0, -0.2], u=[0.5, -1.0, 0.3],
            mu=0.3, e=0.5)


@pytest.mark.parametrize(
    "change, words",
    [
        (dict(mass_matrix=np.ones((3, 2))), ["mass_matrix", "square", "(3, 2)"]),
        (dict(mass_matrix=[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]), ["mass_matrix", "symmetric"]),
        (dict(mass_matrix=np.diag([1.0, -1.0, 1.0])), ["mass_matrix", "positive definite"]),
        (dict(mass_matrix=np.diag([1.0, np.nan, 1.0])), ["mass_matrix", "finite"]),
        (dict(wn=[0.0, 1.0]), ["wn", "length 2", "size 3"]),
        (dict(u=[0.5, np.inf, 0.3]), ["u", "finite"]),
        (dict(mu=-0.1), ["mu", "-0.1", "≥ 0"]),
        (dict(mu=float("nan")), ["mu", "nan"]),
        (dict(e=1.5), ["e", "1.5", "[0.0, 1.0]"]),
        (dict(e=-0.01), ["e", "-0.01", "[0.0, 1.0]"]),
        (dict(u=[0.5, 1.0, 0.3]), ["v_n^A", "approach"]),
        (dict(wt=[0.0, 2.0, 0.2]), ["Δ", "wn and wt"]),
        (dict(law="hertz"), ["law", "hertz", "poisson"]),
        (dict(u=[0.5, -1e160, 0.3]), ["u", "-1e+160", "float64", "rescale"]),
    ],
)
def test_bad_input_gets_a_clear_error(change, words):
    with pytest.raises(pi.ImpactInputError) as caught:
        pi.solve(**{**GOOD, **change})
    assert isinstance(caught.value, ValueError)
    for word in words:
        assert word in str(caught.value), (word, str(caught.value))


def test_batch_flags_bad_rows_and_solves_the_others():
    good = dict(mnn=1.2, mnt=-0.3, mtt=0.8, vn=-1.0, vt=0.4, mu=0.3, e=0.6)
    bad_rows = [
        (dict(mnn=np.nan), errors.NON_FINITE),
        (dict(vt=np.inf), errors.NON_FINITE),
        (dict(mnn=-1.0), errors.NOT_POSITIVE_DEFINITE),
        (dict(mnt=1.0), errors.NOT_POSITIVE_DEFINITE),  # Δ = 0.96 − 1 < 0
        (dict(mu=-0.2), errors.NEGATIVE_FRICTION),
        (dict(e=1.2), errors.RESTITUTION_OUT_OF_RANGE),
        (dict(vn=0.0), errors.NO_APPROACH),
        (dict(vn=-1e300), errors.OUTPUT_OVERFLOW),  # finite inputs, energy ~ 1e600
    ]
    columns = {k: [] for k in good}
    for position in range(2 * len(bad_rows) + 1):
        row = dict(good) if position % 2 == 0 else {**good, **bad_rows[position // 2][0]}
        for k in good:
            columns[k].append(row[k])
    for law in pi.LAWS:
        batch = pi.solve_batch(**{k: np.array(v) for k, v in columns.items()}, law=law)
        alone = pi.solve_batch(**good, law=law)
        for position in range(len(columns["mnn"])):
            if position % 2 == 0:
                assert batch.status[position] == 0
                assert batch.normal_impulse[position] == alone.normal_impulse  # bit-identical
                assert batch.vt_separation[position] == alone.vt_separation
            else:
                expected = bad_rows[position // 2][1]
                assert batch.status[position] == expected, (law, position)
                assert np.isnan(batch.normal_impulse[position])
                assert np.isnan(batch.energy_change[position])
                assert batch.collision_type[position] == 0
                assert batch.status_message(position) == errors.STATUS_MESSAGES[expected]


@pytest.mark.parametrize("field", ["mnn", "mnt", "mtt", "vn", "vt", "mu", "e"])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_every_non_finite_input_is_flagged_in_a_batch(field, value):
    # The batch's fast screen lets most rows skip the full input check; no non-finite input
    # may slip through it as solved.
    good = dict(mnn=1.2, mnt=-0.3, mtt=0.8, vn=-1.0, vt=0.4, mu=0.3, e=0.6)
    column = np.array([good[field], value, good[field]])
    for law in pi.LAWS:
        batch = pi.solve_batch(**{**good, field: column}, law=law)
        assert list(batch.status) == [0, errors.NON_FINITE, 0], law
        assert np.isnan(batch.normal_impulse[1]) and np.isfinite(batch.normal_impulse[[0, 2]]).all()


def test_batch_broadcasts_and_keeps_shape():
    result = pi.solve_batch(1.0, 0.2, np.array([[0.5], [1.0]]), -1.0, np.array([0.0, 0.3, -0.3]),
                            0.4, 0.7)
    assert result.normal_impulse.shape == (2, 3) and result.status.shape == (2, 3)
    scalar = pi.solve_batch(1.0, 0.2, 0.5, -1.0, 0.3, 0.4, 0.7)
    assert scalar.normal_impulse.shape == ()


def test_unknown_law_in_batch_names_the_allowed_laws():
    with pytest.raises(pi.ImpactInputError,
                       match="allowed: newton, poisson, stronge, stronge-paper, newton-lcp"):
        pi.solve_batch(1.0, 0.0, 1.0, -1.0, 0.0, 0.3, 0.5, law="Poisson")


def test_solve_never_returns_nan():
    """newton-lcp has no Poisson e_i; the scalar API says None instead of a silent NaN."""
    result = pi.solve(**GOOD, law="newton-lcp")
    assert result.restitution_poisson is None
    values = [result.normal_impulse, result.tangential_impulse, result.vn_separation,
              result.vt_separation, result.energy_change, *result.u_after, *result.delta_u]
    assert all(math.isfinite(v) for v in values)


def test_a_row_does_not_depend_on_its_neighbours_even_in_the_sign_of_zero():
    # v_t = −0.0 with m_nt = −0.0: the row's zero tangential impulse must carry the same sign
    # alone as beside a row whose tangent is flipped (same chunk).
    alone = pi.solve_batch(1.0, -0.0, 1.0, -1.0, -0.0, 0.3, 0.5)
    beside = pi.solve_batch([1.0, 1.0], [-0.0, 0.2], [1.0, 1.0], -1.0, [-0.0, -1.0], 0.3, 0.5)
    for name in ("normal_impulse", "tangential_impulse", "vt_separation", "energy_change"):
        assert (np.asarray(getattr(alone, name)).tobytes()
                == getattr(beside, name)[:1].tobytes()), name


def test_kernels_accept_zero_dimensional_arrays():
    values = (1.2, -0.3, 0.8, -1.0, 0.4, 0.3)
    from_arrays = laws.ContactTerms(*(np.array(x) for x in values))
    from_scalars = laws.ContactTerms(*(np.float64(x) for x in values))
    assert from_arrays.case == from_scalars.case
    assert (laws.poisson_type(from_arrays, np.array(0.5))
            == laws.poisson_type(from_scalars, np.float64(0.5)))


@pytest.mark.parametrize(
    "a, b, c, expected",
    [(1.0, 0.0, 1.0, None), (1.0, 1.0, 1.0, None), (1.0, 0.0, 0.0, 0.0), (1.0, 2.0, 1.0, -1.0),
     (2.0, -3.0, 1.0, 1.0), (1.0, 3.0, -4.0, 1.0)],
)
def test_positive_root_is_the_plus_root_or_nan(a, b, c, expected):
    # x² + 1 and x² + x + 1 have no real root: NaN (stronge-paper then flags the row), for
    # scalars and arrays alike.
    with np.errstate(invalid="ignore"):  # as the solver runs its kernels
        answers = (laws._positive_root(np.float64(a), np.float64(b), np.float64(c)),
                   laws._positive_root(np.full(300, a), np.full(300, b), np.full(300, c))[0])
    for got in answers:
        if expected is None:
            assert np.isnan(got)
        else:
            # small integer coefficients: one rounding at most
            assert got == pytest.approx(expected, abs=1e-15)
