"""Every law by two independent methods on thousands of random problems.

Closed forms (:mod:`planar_impact.laws`, vectorised, what ``solve_batch`` and ``solve`` run)
against the exact impulse process walked segment by segment
(:func:`planar_impact.impulse_process`), and ``newton-lcp`` against projected Gauss–Seidel
(:func:`planar_impact.sequential_impulses`), the way sequential-impulse engines solve it.
"""

from __future__ import annotations

import numpy as np
import pytest

import planar_impact as pi
from harness.scene.random_problems import random_problems, row
from planar_impact.process import (
    impulse_process,
    newton_lcp_modes,
    process_collision_type,
    sequential_impulses,
)

COUNT = 12_000  # the issue asks for ≥ 10,000 per law

# Tolerance on impulses, relative to the impulse scale |v_n^A|/m_nn + |v_t^A|/m_tt.
# Both methods are exact up to rounding; with Δ/(m_nn m_tt) ≥ 1e-3 in the draws the
# rounding error is amplified by at most ~1/Δ' = 1e3, and the largest error seen on 200,000
# draws was 9e-11. 1e-9 leaves a margin of 10 while still catching any wrong formula.
# Kind (docs/verdicts.md, 'Same answers on every CPU'): two implementations on one machine
# within a stated band, NOT yet a derived bound: the factor 1e3 is derived (the draws'
# conditioning), the count of roundings it multiplies is not (issue 35 lists it). Collision
# types: a decision with a band (near_type_boundary, laws.TYPE_BAND); PGS below: its stopping
# rule's bound (derived, 2e-12) with a margin of 50.
IMPULSE_RTOL = 1e-9


# collision types and laws decided two ways: run again on other kernels (tests/conftest.py)
pytestmark = pytest.mark.kernel_sensitive


@pytest.fixture(scope="module")
def problems():
    return random_problems(COUNT, seed=20261121)


def impulse_scale(r):
    return abs(r["vn"]) / r["mnn"] + abs(r["vt"]) / r["mtt"]


def degenerate_tangent(r):
    """With v_t^A = 0 and m_nt = 0 no tangential impulse arises: all types coincide."""
    return r["vt"] == 0.0 and r["mnt"] == 0.0


def near_type_boundary(batch, index, r, rel=1e-9):
    """α within ``rel`` of r_m or (1+e)r_m, or slip stopping where the law ends: the type
    is a matter of rounding there (the results are continuous, comment a)."""
    sign = -1.0 if r["vt"] < 0 else 1.0  # the theory's t makes v_t^A ≥ 0
    terms = pi.laws.ContactTerms(np.float64(r["mnn"]), sign * r["mnt"], r["mtt"], r["vn"],
                                 sign * r["vt"], r["mu"])
    reported_e = batch.restitution_poisson[index]
    e = reported_e if np.isfinite(reported_e) else r["e"]
    alpha, r_m = terms.alpha, terms.r_m
    return any(abs(alpha - b) <= rel * max(abs(b), abs(alpha), 1e-300)
               for b in (r_m, (1 + e) * r_m))


@pytest.mark.parametrize("law", ["newton", "poisson", "stronge"])
def test_closed_form_equals_impulse_process(problems, law):
    batch = pi.solve_batch(**problems, law=law)
    assert np.all(batch.status == 0)
    type_mismatches = []
    for index in range(COUNT):
        r = row(problems, index)
        # With v_t^A = 0 the theory orients t so that m_nt ≥ 0 (a developing slip is then
        # "forward"); the walker, which names directions after the caller's t, gets the same t.
        sign = -1.0 if r["vt"] == 0.0 and r["mnt"] < 0 else 1.0
        walked = impulse_process(**{**r, "mnt": sign * r["mnt"]}, law=law)
        scale = impulse_scale(r)
        assert abs(walked.normal_impulse - batch.normal_impulse[index]) <= IMPULSE_RTOL * scale, r
        assert (abs(sign * walked.tangential_impulse - batch.tangential_impulse[index])
                <= IMPULSE_RTOL * scale), r
        walked_type = process_collision_type(walked, newton_numbering=law == "newton")
        if walked_type != batch.collision_type[index] and not degenerate_tangent(r):
            if not near_type_boundary(batch, index, r):
                type_mismatches.append((r, walked_type, batch.collision_type[index]))
    assert type_mismatches == []


def test_every_type_and_case_is_drawn(problems):
    """The cross-check means something only if the draws reach every branch."""
    poisson = pi.solve_batch(**problems, law="poisson")
    assert set(np.unique(poisson.collision_type)) == {1, 2, 3, 4, 5}
    assert set(np.unique(poisson.case)) == {1, 2, 3, 4, 5}
    newton = pi.solve_batch(**problems, law="newton")
    assert set(np.unique(newton.collision_type)) == {1, 2, 3}


def test_stronge_paper_is_poisson_with_the_mapped_restitution(problems):
    """The paper's mapping, checked two ways: the Poisson process run with the reported e_i
    gives the same impulses, and the result satisfies Stronge's definition as the paper
    evaluates it, e_e² = 1 − (1 + e_i)(1 − e_v) (61), with e_v = v_n^S/|v_n^A| (A30)."""
    batch = pi.solve_batch(**problems, law="stronge-paper")
    solved = np.flatnonzero(batch.status == 0)
    assert solved.size > 0.99 * COUNT
    for index in solved:
        r = row(problems, index)
        e_i = float(batch.restitution_poisson[index])
        walked = impulse_process(**{**r, "e": e_i}, law="poisson")
        scale = impulse_scale(r)
        assert abs(walked.normal_impulse - batch.normal_impulse[index]) <= IMPULSE_RTOL * scale
        assert (abs(walked.tangential_impulse - batch.tangential_impulse[index])
                <= IMPULSE_RTOL * scale)
        e_v = batch.vn_separation[index] / abs(r["vn"])
        # (61) mixes e_i and e_v, both O(1): absolute rounding tolerance, amplified by 1/Δ'.
        assert abs(1 - (1 + e_i) * (1 - e_v) - r["e"] ** 2) <= 1e-8, r


def test_stronge_paper_flags_e_i_outside_unit_interval(problems):
    batch = pi.solve_batch(**problems, law="stronge-paper")
    solved = batch.status == 0
    outside = solved & ((batch.restitution_poisson > 1) | (batch.restitution_poisson < 0))
    assert outside.any(), "the draws should reach the paper's Table 2 limits"
    assert np.array_equal(batch.restitution_in_range[solved], ~outside[solved])


def test_newton_lcp_equals_the_unique_consistent_mode(problems):
    """Enumerate stick, slide+ and slide−; exactly one is consistent, and it is the answer."""
    batch = pi.solve_batch(**problems, law="newton-lcp")
    assert np.all(batch.status == 0)
    assert set(np.unique(batch.collision_type)) == {1, 2, 3}
    for index in range(COUNT):
        r = row(problems, index)
        modes = newton_lcp_modes(**r)
        # A slide mode with zero final slip is the stick mode itself (a boundary): drop it.
        if len(modes) > 1:
            modes = [m for m in modes if m[0] == "stick"]
        assert len(modes) == 1, (r, modes)
        _, normal, tangential = modes[0]
        scale = impulse_scale(r)
        assert abs(normal - batch.normal_impulse[index]) <= IMPULSE_RTOL * scale, r
        assert abs(tangential - batch.tangential_impulse[index]) <= IMPULSE_RTOL * scale, r


def test_newton_lcp_equals_projected_gauss_seidel():
    """Where PGS converges it lands on the closed form. Its normal step contracts by
    |1 − h/m_nn| = μ|m_nt|/m_nn while sliding, so keep μ|m_nt| < m_nn; and keep
    Δ/(m_nn m_tt) ≥ 0.05 so that the stick iteration (rate ρ² ≤ 0.95) converges quickly."""
    problems = random_problems(COUNT, seed=7, min_conditioning=0.05)
    converging = problems["mu"] * np.abs(problems["mnt"]) < 0.9 * problems["mnn"]
    problems = {name: values[converging] for name, values in problems.items()}
    batch = pi.solve_batch(**problems, law="newton-lcp")
    assert np.all(batch.status == 0)
    assert set(np.unique(batch.collision_type)) == {1, 2, 3}
    for index in range(len(problems["mnn"])):
        r = row(problems, index)
        normal, tangential, iterations = sequential_impulses(**r)
        assert iterations < 100_000
        scale = impulse_scale(r)
        # PGS stops at a relative step of 1e-13 (a tighter stop can cycle on rounding); with
        # contraction ≤ 0.95 the error left is below 1e-13/(1 − 0.95) = 2e-12 of the impulse.
        assert abs(normal - batch.normal_impulse[index]) <= 1e-10 * scale, r
        assert abs(tangential - batch.tangential_impulse[index]) <= 1e-10 * scale, r


@pytest.mark.parametrize("law", pi.LAWS)
def test_scalar_solve_equals_batch(law):
    """``solve`` (numpy scalars, generalized speeds) and ``solve_batch`` (arrays) agree."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        size = 4
        root = rng.normal(size=(size, size))
        matrix = root @ root.T + size * np.eye(size)
        wn, wt, u = rng.normal(size=(3, size))
        if wn @ u >= 0:
            u = -u
        mu, e = rng.uniform(0, 1.5), rng.uniform(0, 1)
        try:
            single = pi.solve(mass_matrix=matrix, wn=wn, wt=wt, u=u, mu=mu, e=e, law=law)
        except pi.ImpactInputError:
            continue  # the batch check below must then flag the row as well
        batch = pi.solve_batch(single.mnn, single.mnt, single.mtt, single.vn_approach,
                               single.vt_approach, mu, e, law=law)
        assert batch.status == 0
        for name in ("normal_impulse", "tangential_impulse", "vn_separation", "vt_separation",
                     "energy_change"):
            assert getattr(single, name) == pytest.approx(float(getattr(batch, name)),
                                                          rel=1e-12, abs=1e-12)
        # (A16): M Δu = w_n I_n + w_t I_t, and the energy change is that of ½ uᵀMu (A29).
        np.testing.assert_allclose(matrix @ single.delta_u,
                                   wn * single.normal_impulse + wt * single.tangential_impulse,
                                   rtol=1e-10, atol=1e-12)
        kinetic = 0.5 * single.u_after @ matrix @ single.u_after - 0.5 * u @ matrix @ u
        assert single.energy_change == pytest.approx(kinetic, rel=1e-9, abs=1e-12)
