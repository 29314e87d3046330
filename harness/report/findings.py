"""``impact-harness findings``: re-measure the solver claims the README makes.

On seeded random contact-space problems (:func:`harness.scene.random_problems.random_problems`)
it measures, and prints as Markdown tables:

(a) projected Gauss–Seidel (the ``newton-lcp`` law as sequential-impulse engines solve it,
    :func:`planar_impact.process.sequential_impulses`) on problems whose ``newton-lcp``
    answer slides: the fraction that does not converge, in bins of ``μ|m_nt|/m_nn``. Once
    the tangential row sits on the cone's edge, ``I_t = ∓μ I_n`` and the normal step maps
    ``I_n`` to ``C/m_nn ± (μ m_nt/m_nn) I_n``: it diverges when ``μ|m_nt| > m_nn``.
(b) the paper's Stronge mapping (``stronge-paper``) at ``α = (1+e) r_m`` (A34)/(A36) for
    ``m_nt < 0``, where Type 2 or 4 meets Type 5
    (docs/theory.md, 'The paper's Stronge mapping'): how often ``I_n`` jumps by more than
    1%, the median ``e_i`` just below the boundary, and the median relative jump of ``I_n``.
(c) the fraction of random problems in which each law gains kinetic energy (A29).

``impact-harness findings`` (:mod:`harness.report.findings_command`) prints the table.
"""

from __future__ import annotations

import itertools

import numpy as np

import planar_impact as pi
from harness.laws import LAW_NAMES
from harness.scene.random_problems import random_problems
from planar_impact.solver import ENERGY_GAIN_BAR, energy_gain_decision

# PGS: iterations allowed, and the relative change below which it has converged (as in
# planar_impact.process.sequential_impulses, whose defaults are 1e-13 and 100,000).
PGS_ITERATIONS = 2000
PGS_TOLERANCE = 1e-13
PGS_BINS = (0.0, 0.5, 0.9, 1.0, 1.1, 1.5, 2.0, np.inf)

# (b): relative offset either side of α = (1+e) r_m, and the jump counted as large.
BOUNDARY_OFFSET = 1e-9
LARGE_JUMP = 0.01

# (c): an energy change above ENERGY_GAIN_BAR of |v_n^A I_n| + |v_t^A I_t|, beyond (A29)'s
# derived rounding band, is a gain: the solver's own ImpactResult.energy_gained decision
# (planar_impact.solver.energy_gain_decision); a row inside the band is at the boundary.

ENERGY_LAWS = LAW_NAMES  # every law, in the law registry's order (harness/laws.py)


def pgs_converges(mnn, mnt, mtt, vn, vt, mu, e, iterations=PGS_ITERATIONS,
                  tolerance=PGS_TOLERANCE):
    """Vectorised :func:`planar_impact.process.sequential_impulses`: per row, whether PGS
    reaches a relative change ``≤ tolerance`` within ``iterations`` sweeps."""
    target = -e * vn
    normal = np.zeros_like(mnn)
    tangential = np.zeros_like(mnn)
    converged = np.zeros(mnn.shape, dtype=bool)
    with np.errstate(all="ignore"):
        for _ in range(iterations):
            vn_now = vn + mnn * normal + mnt * tangential
            new_normal = np.maximum(0.0, normal + (target - vn_now) / mnn)
            vt_now = vt + mnt * new_normal + mtt * tangential
            bound = mu * new_normal
            new_tangential = np.minimum(bound, np.maximum(-bound, tangential - vt_now / mtt))
            change = np.abs(new_normal - normal) + np.abs(new_tangential - tangential)
            done = change <= tolerance * (np.abs(new_normal) + np.abs(new_tangential))
            # A row stops at its first convergence, as the scalar loop returns there.
            normal = np.where(converged, normal, new_normal)
            tangential = np.where(converged, tangential, new_tangential)
            converged |= done
            if converged.all():
                break
    return converged


def pgs_divergence(problems: dict) -> dict:
    """(a): per sliding problem, ``μ|m_nt|/m_nn`` and whether PGS failed to converge."""
    lcp = pi.solve_batch(**problems, law="newton-lcp")
    sliding = (lcp.status == 0) & (lcp.collision_type != pi.laws.NEWTON_STICK)
    sample = {name: values[sliding] for name, values in problems.items()}
    ratio = sample["mu"] * np.abs(sample["mnt"]) / sample["mnn"]
    failed = ~pgs_converges(**sample)
    return {"ratio": ratio, "failed": failed, "index": np.flatnonzero(sliding)}


def stronge_paper_jump(problems: dict) -> dict:
    """(b): problems with ``m_nt < 0``, ``g > 0``, ``h > 0`` and ``e > 0``, solved with
    ``v_t^A`` just below and just above ``(1+e) r_m |v_n^A|``; returns ``e_i`` below and
    the relative jump of ``I_n`` (relative to the value above), NaN where either side has
    no consistent answer."""
    mnn, mnt, mtt, mu, e = (problems[k] for k in ("mnn", "mnt", "mtt", "mu", "e"))
    g, h = mu * mtt - mnt, mnn - mu * mnt  # (A35)
    chosen = (mnt < 0) & (g > 0) & (h > 0) & (e > 0)
    sample = {name: values[chosen] for name, values in problems.items()}
    boundary = (1.0 + sample["e"]) * (g[chosen] / h[chosen]) * -sample["vn"]  # (A36)
    below = pi.solve_batch(**dict(sample, vt=boundary * (1 - BOUNDARY_OFFSET)),
                           law="stronge-paper")
    above = pi.solve_batch(**dict(sample, vt=boundary * (1 + BOUNDARY_OFFSET)),
                           law="stronge-paper")
    both = (below.status == 0) & (above.status == 0)
    jump = np.where(both, np.abs(below.normal_impulse - above.normal_impulse)
                    / above.normal_impulse, np.nan)
    e_below = np.where(both, below.restitution_poisson, np.nan)
    return {"e_below": e_below, "jump": jump, "index": np.flatnonzero(chosen)}


def energy_gain(problems: dict, law: str) -> np.ndarray:
    """(c): per problem, True where ``law`` gains energy, False where it does not, and
    False for rows it cannot solve (returned with them in ``solved``)."""
    result = pi.solve_batch(**problems, law=law)
    solved = result.status == 0
    mnn, mnt, mtt = (np.broadcast_to(problems[name], solved.shape)
                     for name in ("mnn", "mnt", "mtt"))
    gained, _ = energy_gain_decision(
        result.energy_change, result.normal_impulse, result.tangential_impulse,
        result.vn_approach, result.vt_approach, mnn, mnt, mtt)
    return solved & gained, solved


def measure(count: int, seed: int) -> dict:
    """All three findings on ``count`` problems drawn with ``seed``."""
    problems = random_problems(count, seed)
    divergence = pgs_divergence(problems)
    bins = []
    for low, high in itertools.pairwise(PGS_BINS):
        inside = (divergence["ratio"] >= low) & (divergence["ratio"] < high)
        bins.append({"low": low, "high": high, "problems": int(inside.sum()),
                     "failed": int(divergence["failed"][inside].sum())})
    jump = stronge_paper_jump(problems)
    valid = np.isfinite(jump["jump"])
    large = valid & (jump["jump"] > LARGE_JUMP)
    energy = {}
    for law in ENERGY_LAWS:
        gained, solved = energy_gain(problems, law)
        energy[law] = {"gained": int(gained.sum()), "solved": int(solved.sum())}
    return {
        "count": count, "seed": seed, "pgs_bins": bins,
        "jump": {"problems": int(valid.sum()), "large": int(large.sum()),
                 "median_e_below": float(np.median(jump["e_below"][large])) if large.any()
                 else float("nan"),
                 "median_jump": float(np.median(jump["jump"][large])) if large.any()
                 else float("nan")},
        "energy": energy,
    }


def markdown(findings: dict) -> str:
    """The findings as Markdown tables."""
    lines = [
        (f"Findings on {findings['count']:,} random problems "
         f"(`harness.scene.random_problems`, seed {findings['seed']})."),
        "",
        (f"(a) Projected Gauss–Seidel on problems whose `newton-lcp` answer slides "
         f"({PGS_ITERATIONS} sweeps, relative change ≤ {PGS_TOLERANCE:g}):"),
        "",
        "| μ·abs(m_nt)/m_nn | sliding problems | not converged | fraction |",
        "|---|---:|---:|---:|",
    ]
    for b in findings["pgs_bins"]:
        fraction = f"{b['failed'] / b['problems']:.1%}" if b["problems"] else "–"
        high = "∞" if not np.isfinite(b["high"]) else f"{b['high']:g}"
        lines.append(f"| [{b['low']:g}, {high}) | {b['problems']} | {b['failed']} | {fraction} |")
    j = findings["jump"]
    share = f"{j['large'] / j['problems']:.1%}" if j["problems"] else "–"
    lines += [
        "",
        (f"(b) `stronge-paper` at α = (1+e)·r_m, m_nt < 0, g > 0, h > 0, e > 0 "
         f"(α × (1 ∓ {BOUNDARY_OFFSET:g})):"),
        "",
        "| problems | I_n jumps > 1% | share | median e_i just below | median I_n jump |",
        "|---:|---:|---:|---:|---:|",
        (f"| {j['problems']} | {j['large']} | {share} | {j['median_e_below']:.3g} | "
         f"{j['median_jump']:.0%} |"),
        "",
        (f"(c) Energy gain (ΔE > {ENERGY_GAIN_BAR:g}·(abs(v_n^A)·I_n + abs(v_t^A·I_t)) "
         "beyond (A29)'s rounding bound), "
         "among the problems each law solves:"),
        "",
        "| law | solved | gain energy | fraction |",
        "|---|---:|---:|---:|",
    ]
    for law, counts in findings["energy"].items():
        fraction = counts["gained"] / counts["solved"] if counts["solved"] else float("nan")
        lines.append(f"| {law} | {counts['solved']} | {counts['gained']} | {fraction:.2%} |")
    return "\n".join(lines) + "\n"


__all__ = ["markdown", "measure"]
