"""harness.report.findings against independent computations on a small sample."""

from __future__ import annotations

import numpy as np
import pytest

import planar_impact as pi
from harness.report import findings
from harness.scene.random_problems import random_problems, row
from planar_impact.process import impulse_process, newton_lcp_modes, sequential_impulses

SAMPLE = random_problems(3000, seed=5)


# the findings' counts and flags: run again on other kernels (tests/conftest.py).
# Kinds (docs/verdicts.md, 'Same answers on every CPU'): gain flags are decisions with a band
# (1e-9 of the threshold's scale, where the two computations may fall either side); the
# jump's 1e-6 is derived in its test's docstring (the 1e-9 offset times conditioning ≤ 1e3);
# the quadratic's residual (1e-9 of its terms) is a stated band, NOT derived.
pytestmark = pytest.mark.kernel_sensitive


def test_vectorised_pgs_agrees_with_the_scalar_loop():
    """The module's per-problem verdict equals the scalar sequential_impulses' (does it
    return before its last iteration?) on 120 sliding problems, spread over the ratios."""
    divergence = findings.pgs_divergence(SAMPLE)
    order = np.argsort(divergence["ratio"])
    picked = order[np.linspace(0, order.size - 1, 120).astype(int)]
    for k in picked:
        r = row(SAMPLE, int(divergence["index"][k]))
        _, _, iterations = sequential_impulses(**r, tolerance=findings.PGS_TOLERANCE,
                                               max_iterations=findings.PGS_ITERATIONS)
        assert (iterations == findings.PGS_ITERATIONS) == divergence["failed"][k], r


def test_pgs_fails_beyond_mu_mnt_equal_mnn_and_not_below():
    """The README's claim itself: diverges when μ|m_nt| > m_nn. Margins of 10% either side
    keep out the slowly converging rows near a contraction rate of 1."""
    divergence = findings.pgs_divergence(SAMPLE)
    ratio, failed = divergence["ratio"], divergence["failed"]
    assert failed[ratio > 1.1].all()
    assert not failed[ratio < 0.9].any()
    assert (ratio > 1.1).sum() > 10 and (ratio < 0.9).sum() > 100  # both sides are sampled


def test_stronge_paper_jump_matches_the_paper_formulas():
    """Just below α = (1+e) r_m the type is 2 (Case 1–2) or 4 (Case 3) with I_n = (1+e_i)
    |v_n^A|/h ((29), (40)); just above it is 5 with I_n = (1+e)|v_n^A|/h (48), so the jump
    is |e_i − e|/(1 + e) up to the 1e-9 offset. And e_i solves (67) or (73). Tolerances:
    1e-6 absolute on the jump (the offset moves I_n by ~1e-9 relative times the problem's
    conditioning, ≤ 1e3 here); the quadratic's residual within 1e-9 of its terms' size."""
    jump = findings.stronge_paper_jump(SAMPLE)
    for k in np.flatnonzero(np.isfinite(jump["jump"]))[:200]:
        r = row(SAMPLE, int(jump["index"][k]))
        e_i, e_e = jump["e_below"][k], r["e"]
        assert jump["jump"][k] == pytest.approx(abs(e_i - e_e) / (1 + e_e), abs=1e-6)
        g = r["mu"] * r["mtt"] - r["mnt"]
        h = r["mnn"] - r["mu"] * r["mnt"]
        alpha = (1 + e_e) * g / h * (1 - findings.BOUNDARY_OFFSET)
        if r["mu"] * r["mtt"] + r["mnt"] >= 0:  # p ≥ 0: Type 2, (62), (65)
            linear = alpha * r["mnt"] / r["mtt"]
            shift = r["mnt"] / r["mtt"] * (g / h - alpha)
        else:  # Type 4, (68), (71)
            linear = 2 * r["mu"] * r["mnt"] * alpha / g
            shift = 2 * r["mu"] * r["mnt"] / g * (g / h - alpha)
        terms = [(1 + linear + shift) * e_i * e_i, (linear + 2 * shift) * e_i, shift, -e_e**2]
        assert abs(sum(terms)) <= 1e-9 * max(map(abs, terms)), r


def energy_by_process(r, law, e_i=None):
    """ΔE of one problem computed without the batch solver."""
    if law == "newton":
        return impulse_process(**r, law="newton").energy_change
    if law == "stronge-paper":  # Poisson's process with the mapped e_i
        return impulse_process(**dict(r, e=e_i), law="poisson").energy_change
    (_, normal, tangential), = newton_lcp_modes(**r)  # newton-lcp: its one consistent mode
    vn_after = r["vn"] + r["mnn"] * normal + r["mnt"] * tangential  # (A22)
    vt_after = r["vt"] + r["mnt"] * normal + r["mtt"] * tangential  # (A23)
    return 0.5 * normal * (vn_after + r["vn"]) + 0.5 * tangential * (vt_after + r["vt"])  # (A29)


@pytest.mark.parametrize("law", ["newton", "newton-lcp", "stronge-paper"])
def test_energy_gain_flags_match_the_impulse_process(law):
    """Gains counted by the module agree with ΔE from the exact process walk (or, for
    newton-lcp, from enumerating its modes) on 400 problems, except within 1e-9 of the
    threshold's scale, where the two computations' rounding may fall either side."""
    sample = {name: values[:400] for name, values in SAMPLE.items()}
    gained, solved = findings.energy_gain(sample, law)
    batch = pi.solve_batch(**sample, law=law)
    for i in np.flatnonzero(solved):
        r = row(sample, int(i))
        if law == "newton-lcp" and len(newton_lcp_modes(**r)) != 1:
            continue
        energy = energy_by_process(r, law, float(batch.restitution_poisson[i]))
        scale = (abs(r["vn"]) * batch.normal_impulse[i]
                 + abs(r["vt"] * batch.tangential_impulse[i]))
        if abs(energy - findings.GAIN_THRESHOLD * scale) > 1e-9 * scale:
            assert (energy > findings.GAIN_THRESHOLD * scale) == gained[i], r


def test_markdown_reports_the_measured_counts():
    measured = findings.measure(2000, seed=3)
    text = findings.markdown(measured)
    for law, counts in measured["energy"].items():
        assert f"| {law} | {counts['solved']} | {counts['gained']} |" in text
    assert sum(b["problems"] for b in measured["pgs_bins"]) > 0
