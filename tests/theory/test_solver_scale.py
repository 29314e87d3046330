"""The solver at every scale (issue 10, item 5).

Every law is homogeneous: approach velocities times ``s`` give impulses and separation
velocities times ``s`` and an energy change times ``s²``; inverse-inertia terms times ``k``
give impulses times ``1/k`` and an energy change times ``1/k`` (A22)/(A23)/(A29). Scaling by a
power of two is exact in binary floating point and the solver itself scales by powers of two
(docs/theory.md, 'Contact terms'), so for power-of-two factors the answers must be the
moderate-scale answers scaled, bit for bit, wherever those scaled answers are representable
(np.ldexp of the moderate answer, one rounding, the same as the solver's).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import planar_impact as pi
from harness.scene.random_problems import random_problems
from planar_impact import builders, errors
from planar_impact.contact_space import contact_space_solution

FIELDS = ("normal_impulse", "tangential_impulse", "vn_separation", "vt_separation",
          "energy_change")
CONTINUOUS_LAWS = ("newton", "poisson", "stronge", "newton-lcp")  # stronge-paper jumps

finite = {"allow_nan": False, "allow_infinity": False}
moderate_mass = st.floats(0.1, 10.0, **finite)
# |ρ| = |m_nt|/√(m_nn m_tt) is 0 or ≥ 1e-6: a subnormal m_nt would make the moderate problem
# itself inexact under scaling.
correlation = st.one_of(st.just(0.0), st.floats(1e-6, 0.99), st.floats(-0.99, -1e-6))


@st.composite
def moderate_problems(draw):
    """Well-scaled problems. |v_t^A|, μ, e and |ρ| are 0 or not tiny, so that no
    intermediate of the moderate problem is subnormal."""
    mnn, mtt, rho = draw(moderate_mass), draw(moderate_mass), draw(correlation)
    vt = draw(st.one_of(st.just(0.0), st.floats(1e-3, 10.0), st.floats(-10.0, -1e-3)))
    return {"mnn": mnn, "mnt": rho * math.sqrt(mnn * mtt), "mtt": mtt,
            "vn": -draw(st.floats(0.1, 10.0)), "vt": vt,
            "mu": draw(st.one_of(st.just(0.0), st.floats(1e-6, 2.0))),
            "e": draw(st.one_of(st.sampled_from([0.0, 1.0]), st.floats(1e-6, 1.0)))}


def scaled_problem(problem, velocity_factor, mass_factor):
    return dict(problem, mnn=problem["mnn"] * mass_factor, mnt=problem["mnt"] * mass_factor,
                mtt=problem["mtt"] * mass_factor, vn=problem["vn"] * velocity_factor,
                vt=problem["vt"] * velocity_factor)


# 2^±996 ≈ 1e±300.
exponent = st.integers(-996, 996)


@settings(max_examples=300, deadline=None)
@given(problem=moderate_problems(), law=st.sampled_from(pi.LAWS),
       velocity_exponent=exponent, mass_exponent=exponent)
def test_power_of_two_scaling_is_exact_from_1e_minus_300_to_1e300(
        problem, law, velocity_exponent, mass_exponent):
    scaled_inputs = scaled_problem(problem, 2.0**velocity_exponent, 2.0**mass_exponent)
    # The scaling of the inputs themselves must be exact (a small m_nt or v_t can turn
    # subnormal): the claim is about the solver, not about rounding its inputs.
    assume(all(math.ldexp(scaled_inputs[name], -exponent) == problem[name]
               for name, exponent in (("mnn", mass_exponent), ("mnt", mass_exponent),
                                      ("mtt", mass_exponent), ("vn", velocity_exponent),
                                      ("vt", velocity_exponent))))
    base = pi.solve_batch(**problem, law=law)
    scaled = pi.solve_batch(**scaled_inputs, law=law)
    if base.status != errors.SOLVED:  # a jam or an inconsistent law is scale-free too
        assert scaled.status == base.status
        return
    exponents = {"normal_impulse": velocity_exponent - mass_exponent,
                 "tangential_impulse": velocity_exponent - mass_exponent,
                 "vn_separation": velocity_exponent, "vt_separation": velocity_exponent,
                 "energy_change": 2 * velocity_exponent - mass_exponent}
    with np.errstate(over="ignore"):
        expected = {name: np.ldexp(getattr(base, name), exponents[name]) for name in FIELDS}
    if not all(np.isfinite(value) for value in expected.values()):
        assert scaled.status == errors.OUTPUT_OVERFLOW
        return
    assert scaled.status == errors.SOLVED
    for name in FIELDS:
        assert getattr(scaled, name) == expected[name], name
    assert scaled.collision_type == base.collision_type
    assert scaled.case == base.case
    np.testing.assert_array_equal(scaled.restitution_poisson, base.restitution_poisson)


def times_ten_to(value, exponent):
    """``value·10^exponent`` in two steps, so that no factor overflows or turns subnormal
    on its own (|exponent| ≤ 750); three roundings, ~3e-16 relative."""
    half = 10.0 ** (exponent / 2)
    return value * half * half


@settings(max_examples=200, deadline=None)
@given(problem=moderate_problems(), law=st.sampled_from(CONTINUOUS_LAWS),
       velocity_log=st.floats(-300, 300), mass_log=st.floats(-150, 150))
def test_any_scale_factor_scales_the_answer(problem, law, velocity_log, mass_log):
    """Factors 10^x, not powers of two: the scaled inputs carry one rounding each (relative
    2^-53 ≈ 1.1e-16), and these laws are continuous with derivatives bounded by the
    conditioning of the draws (|ρ| ≤ 0.99, so 1/(1 − ρ²) ≤ 51, times the 100:1 spread of
    the terms): 1e-10 relative to the output's scale leaves a margin of about 1e3 over that.
    Energies ~ v²/m stay inside float64 for |log s| ≤ 300 only if |log k| ≤ 150 is not
    also extreme; rows whose answer leaves the range must report status 9."""
    s, k = 10.0**velocity_log, 10.0**mass_log
    base = pi.solve_batch(**problem, law=law)
    scaled = pi.solve_batch(**scaled_problem(problem, s, k), law=law)
    if base.status != errors.SOLVED:
        assert scaled.status == base.status
        return
    # Sizes of the scaled answers, in log10 so that they cannot overflow here; an exact 0
    # (no energy change at e = 1, μ = 0) stays 0 at any scale: no size.
    def log_size(value, exponent):
        return math.log10(value) + exponent if value > 0 else -math.inf

    # A rounding-level energy change (|ΔE| below 1e-12 of v²/m_nn) is noise: scaled, it may
    # round to 0 or overflow; nothing is claimed where that noise would pass 1e290.
    speed = abs(problem["vn"]) + abs(problem["vt"])
    energy_unit_log = math.log10(speed * speed / problem["mnn"]) + 2 * velocity_log - mass_log
    if abs(base.energy_change) <= 1e-12 * speed * speed / problem["mnn"]:
        assume(energy_unit_log < 290)
    impulse_size = abs(base.normal_impulse) + abs(base.tangential_impulse)
    log_sizes = [log_size(impulse_size, velocity_log - mass_log),
                 log_size(abs(base.vn_separation) + abs(base.vt_separation), velocity_log),
                 log_size(abs(base.energy_change), 2 * velocity_log - mass_log)]
    if max(log_sizes) > 308.3:  # beyond float64's 1.8e308: must be flagged
        assert scaled.status == errors.OUTPUT_OVERFLOW
        return
    # Near the edges (inputs' own rounding may tip the answer over, or subnormal answers
    # carry absolute rather than relative errors) nothing is claimed.
    assume(max(log_sizes) < 307.9 and min(log_sizes[0], log_sizes[2]) > -290)
    impulse_scale = times_ten_to(speed / problem["mnn"], velocity_log - mass_log)
    velocity_scale = speed * s
    energy_scale = times_ten_to(speed * speed / problem["mnn"], 2 * velocity_log - mass_log)
    assert scaled.status == errors.SOLVED
    impulse_log, energy_log = velocity_log - mass_log, 2 * velocity_log - mass_log
    for name, scale, log_factor in (("normal_impulse", impulse_scale, impulse_log),
                                    ("tangential_impulse", impulse_scale, impulse_log),
                                    ("vn_separation", velocity_scale, velocity_log),
                                    ("vt_separation", velocity_scale, velocity_log),
                                    ("energy_change", energy_scale, energy_log)):
        expected = times_ten_to(float(getattr(base, name)), log_factor)
        assert abs(float(getattr(scaled, name)) - expected) <= 1e-10 * scale, name


def test_tiny_approach_under_stronge_keeps_its_separation_speed():
    """Frictionless (μ = 0) impacts separate at e|v_n^A| under every law; before the
    scaling, Stronge's work (~v²) underflowed and v_n^S came back 0."""
    for law in pi.LAWS:
        result = pi.solve_batch(1.0, 0.0, 1.0, -1e-162, 0.0, 0.0, 0.5, law)
        assert result.status == errors.SOLVED, law
        # 4 ulps: (1 + e)|v_n^A|/m_nn then v_n^A + m_nn I_n, a few roundings.
        assert result.vn_separation == pytest.approx(5e-163, rel=4 * 2.0**-52, abs=0.0), law


def test_large_impulse_under_stronge_is_solved_not_overflowed():
    """|I_n| ~ 1e210 (v ~ 1e60, m ~ 1e-150): the energy, ~1e270, is representable, so the
    row is solved; it is the problem (1, 0, 1, −1, 0.5, 0.3, 0.5) scaled by s = 1e60 and
    k = 1e-150. Tolerance 1e-14: inputs rounded once each (1.1e-16) on a problem whose
    terms are all of order 1."""
    big = pi.solve_batch(1e-150, 0.0, 1e-150, -1e60, 0.5e60, 0.3, 0.5, "stronge")
    unit = pi.solve_batch(1.0, 0.0, 1.0, -1.0, 0.5, 0.3, 0.5, "stronge")
    assert big.status == errors.SOLVED
    assert big.normal_impulse == pytest.approx(unit.normal_impulse * 1e210, rel=1e-14)
    assert big.tangential_impulse == pytest.approx(unit.tangential_impulse * 1e210, rel=1e-14)
    assert big.vn_separation == pytest.approx(unit.vn_separation * 1e60, rel=1e-14)
    assert big.energy_change == pytest.approx(unit.energy_change * 1e270, rel=1e-14)


def test_rows_inside_the_safe_range_are_solved_as_given():
    """Scaling applies only outside 2^±64: ordinary rows keep the bits of the unscaled
    kernels (contact_space_solution on the same rows)."""
    draws = random_problems(5000, seed=21)
    draws["vt"] = np.abs(draws["vt"])
    draws["mnt"] = np.where(draws["vt"] == 0, np.abs(draws["mnt"]), draws["mnt"])  # no flip
    for law in pi.LAWS:
        batch = pi.solve_batch(**draws, law=law)
        solved = batch.status == errors.SOLVED
        with np.errstate(all="ignore"):
            kernel = contact_space_solution(law, *draws.values())
        for name in FIELDS:
            np.testing.assert_array_equal(getattr(batch, name)[solved], kernel[name][solved])


def test_answers_beyond_float64_still_report_overflow():
    result = pi.solve_batch(1.0, 0.0, 1.0, -1e200, 0.0, 0.0, 0.5, "stronge")  # ΔE ~ 1e400
    assert result.status == errors.OUTPUT_OVERFLOW
    assert np.isnan(result.normal_impulse)


# --- Δ without cancellation -------------------------------------------------------------

ROD = {"mass": 1e9, "inertia": 1e-9, "half_length": 0.5}


def rod_problem(angle):
    """A rod of mass 1e9 kg and inertia 1e-9 kg m² striking the ground at its lower end."""
    half = ROD["half_length"]
    body = builders.PlanarBody(ROD["mass"], ROD["inertia"], (0.0, half * math.sin(angle)),
                               velocity=(0.3, -1.0), angular_velocity=0.0)
    return builders.rigid_body_against_ground(body, (-half * math.cos(angle), 0.0))


ANGLES = [0.3, 0.45, 0.9, 1.05, 1.25]  # angles at which m_nn m_tt − m_nt² came out ≤ 0


@pytest.mark.parametrize("angle", ANGLES)
def test_rod_contact_terms_have_the_true_delta(angle):
    """For one body against the ground, m_nn = 1/m + (r×n)²/I, m_tt = 1/m + (r×t)²/I,
    m_nt = (r×n)(r×t)/I, so Δ = 1/m² + |r|²/(mI) by hand: 0.25 here, where the
    difference of products gave −2.0. Tolerance 1e-12: Δ is a sum of squares of minors each
    computed to a few ulps."""
    problem = rod_problem(angle)
    _, _, _, delta = pi.solver.contact_terms(problem.mass_matrix, problem.wn, problem.wt)
    mass, inertia, half = ROD["mass"], ROD["inertia"], ROD["half_length"]
    assert delta == pytest.approx(1 / mass**2 + half**2 / (mass * inertia), rel=1e-12)


def exact_stick(problem, e):
    """newton-lcp's sticking answer in exact rational arithmetic from the exact floats of
    M, w_n, w_t, u (M diagonal): (A22)/(A23) with v_n^S = e|v_n^A|, v_t^S = 0."""
    diag = [Fraction(x) for x in np.diag(problem.mass_matrix)]
    wn, wt, u = ([Fraction(x) for x in v] for v in (problem.wn, problem.wt, problem.u))
    mnn = sum(a * a / m for a, m in zip(wn, diag))
    mnt = sum(a * b / m for a, b, m in zip(wn, wt, diag))
    mtt = sum(b * b / m for b, m in zip(wt, diag))
    vn = sum(a * x for a, x in zip(wn, u))
    vt = sum(b * x for b, x in zip(wt, u))
    closing = (1 + Fraction(e)) * -vn
    delta = mnn * mtt - mnt * mnt
    return (mtt * closing + mnt * vt) / delta, -(mnn * vt + mnt * closing) / delta


@pytest.mark.parametrize("angle", ANGLES)
def test_every_law_solves_the_heavy_rod(angle):
    """Before: every law refused these rods (Δ ≤ 0 from rounding). Now all solve, and
    newton-lcp with a sticking friction (μ = 10) matches the exact rational answer. The
    stick formulas are ratios of two-term sums of the contact terms, each correct to a few
    ulps once Δ is; 1e-12 relative allows a thousandfold amplification by cancellation in
    the numerators (measured: below 1e-15). With the old Δ the error was unbounded."""
    problem = rod_problem(angle)
    for law in pi.LAWS:
        problem.solve(mu=10.0, e=0.5, law=law)  # raises if refused
    result = problem.solve(mu=10.0, e=0.5, law="newton-lcp")
    normal, tangential = exact_stick(problem, 0.5)
    assert result.collision_type == pi.laws.NEWTON_STICK
    assert result.normal_impulse == pytest.approx(float(normal), rel=1e-12, abs=0.0)
    assert result.tangential_impulse == pytest.approx(float(tangential), rel=1e-12, abs=0.0)


@pytest.mark.kernel_sensitive  # through LAPACK and two paths: a stated band (the docstring)
@settings(max_examples=100, deadline=None)
@given(problem=moderate_problems(), law=st.sampled_from(pi.LAWS),
       velocity_exponent=st.integers(-996, 996), mass_exponent=st.integers(-500, 500))
def test_scalar_solve_scales_with_the_mass_matrix(problem, law, velocity_exponent,
                                                  mass_exponent):
    """``solve`` in generalized speeds: u times s = 2^a and M times k = 2^b give impulses
    times s·k (the inverse-inertia terms scale by 1/k), velocities times s, energy times
    s²·k. The moderate problem is built on M = I with w_n, w_t spanning the contact terms.
    A stated band, relative 1e-13, not derived and not bit for bit: for an odd mass
    exponent Cholesky's √k = 2^c √2 is rounded (another problem by an ulp), and at any
    exponent the two solves may take different paths (the fast path of plain floats for
    the moderate problem, numpy's path with its BLAS products for the scaled one: under
    OpenBLAS's SkylakeX kernel m_tt came out 1 − 2⁻⁵³ on one and exact on the other), so
    their contact terms round differently. Measured at most 8.9e-16 of the impulses on
    1,500 seeded problems (0.9 % of the band); the batch solver's power-of-two scaling,
    one path, is bit for bit (test_power_of_two_scaling_is_exact_from_1e_minus_300_to_1e300)."""
    mnn, mnt, mtt = problem["mnn"], problem["mnt"], problem["mtt"]
    # w_n, w_t in R² with w_n·w_n = m_nn, w_n·w_t = m_nt, w_t·w_t = m_tt (M = I).
    wn = np.array([math.sqrt(mnn), 0.0])
    wt = np.array([mnt / math.sqrt(mnn), math.sqrt(max(mtt - mnt * mnt / mnn, 0.0))])
    u = np.linalg.solve(np.stack([wn, wt]), [problem["vn"], problem["vt"]])
    kwargs = {"mu": problem["mu"], "e": problem["e"], "law": law}
    try:
        base = pi.solve(mass_matrix=np.eye(2), wn=wn, wt=wt, u=u, **kwargs)
    except pi.ImpactInputError:
        return  # a jam or an inconsistent law: not a scale question
    s, k = 2.0**velocity_exponent, 2.0**mass_exponent
    energy_exponent = 2 * velocity_exponent + mass_exponent
    with np.errstate(over="ignore"):
        impulse_scale = float(np.ldexp(abs(base.normal_impulse) + abs(base.tangential_impulse),
                                       velocity_exponent + mass_exponent))
        energy_scale = float(np.ldexp(abs(base.energy_change) + 1.0, energy_exponent))
    if not (impulse_scale < 1e300 and energy_scale < 1e300) or impulse_scale < 1e-290:
        return  # beyond or at the edge of float64: covered by the batch tests
    scaled = pi.solve(mass_matrix=np.eye(2) * k, wn=wn, wt=wt, u=u * s, **kwargs)
    assert scaled.normal_impulse == pytest.approx(base.normal_impulse * s * k, rel=1e-13,
                                                  abs=1e-13 * impulse_scale)
    assert scaled.tangential_impulse == pytest.approx(base.tangential_impulse * s * k,
                                                      rel=1e-13, abs=1e-13 * impulse_scale)
    # v_n^S = v_n^A + m_nn I_n + m_nt I_t: a separation near zero (e = 0) is the difference
    # of terms as large as the impulse's, so its rounding is relative to them, not to v_n^A
    # (hypothesis found -2.8e-14 against 2.8e-17 with I_n = 231, v_n^A = -0.25)
    cancelled = (abs(base.vn_approach) + mnn * abs(base.normal_impulse)
                 + abs(mnt) * abs(base.tangential_impulse))
    assert scaled.vn_separation == pytest.approx(base.vn_separation * s, rel=1e-13,
                                                 abs=1e-13 * s * cancelled)
