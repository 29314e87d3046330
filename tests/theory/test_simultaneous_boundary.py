"""Coherence decisions that do not flip on rounding (planar_impact.simultaneous.BOUNDARY_BAND).

A problem whose exact answer sits on a decision's boundary (the symmetric flat box under the
effective reading: each corner's effective approach lies exactly on Table 1's Type 4 | 5
boundary, α = (1+e) r_m) is perturbed by a few ulps in every input: the reported counts of
clearly coherent solutions and of solutions at the boundary must not change. Without the
band the same perturbations do flip the count (checked, so that the test can fail).
"""

from __future__ import annotations

import numpy as np
import pytest

from planar_impact import simultaneous as sim
from planar_impact.simultaneous import coherent

ULP = 2.0 ** -52


def flat_box_problem(width=1.0, height=0.5, mass=2.0, velocity=(0.0, -1.0), omega=0.0,
                     mu=0.5, e=0.5):
    inertia = mass * (width ** 2 + height ** 2) / 12.0
    corners = [(-width / 2, -height / 2), (width / 2, -height / 2)]
    return dict(mass_matrix=np.diag([mass, mass, inertia]),
                wn=np.array([(0.0, 1.0, rx) for rx, _ in corners]),
                wt=np.array([(1.0, 0.0, -ry) for _, ry in corners]),
                u=np.array([velocity[0], velocity[1], omega]), mu=mu, e=e)


def perturbed(problem, rng, ulps=3):
    """Every float input times ``1 + k ulp``, ``k`` uniform in ``[−ulps, ulps]``."""
    def shake(value):
        value = np.asarray(value, dtype=float)
        return value * (1.0 + rng.integers(-ulps, ulps + 1, size=value.shape) * ULP)
    out = {key: shake(value) for key, value in problem.items()}
    out["mass_matrix"] = np.diag(np.diag(out["mass_matrix"]))  # stays diagonal, symmetric
    return out


def decisions(problem):
    system = sim.contact_system(**problem)
    out = {}
    for law in sim.TYPE_LAWS:
        for coupling in sim.COUPLINGS:
            found = sim.coherent_solutions(system, law, coupling=coupling)
            out[law, coupling] = (sum(not s.at_boundary for s in found),
                                  sum(s.at_boundary for s in found))
    return out


PROBLEMS = {
    "symmetric flat box": flat_box_problem(),
    "symmetric flat box, μ = 0": flat_box_problem(mu=0.0),
    # The library's flat-box-receding-end (one end recedes: |ω| w/2 > |v_y|).
    "receding end": flat_box_problem(1.347, 0.089, 1.0, (-0.967, -0.536), 2.477, 0.729, 0.607),
}


@pytest.mark.parametrize("name", PROBLEMS)
def test_a_few_ulps_do_not_flip_the_reported_decisions(name):
    problem = PROBLEMS[name]
    expected = decisions(problem)
    rng = np.random.default_rng(7)
    for _ in range(12):
        assert decisions(perturbed(problem, rng)) == expected


def test_the_symmetric_flat_box_is_reported_at_the_boundary_with_both_types_named():
    found = sim.coherent_solutions(sim.contact_system(**flat_box_problem()), "poisson",
                                   coupling="effective")
    (solution,) = found
    assert solution.at_boundary
    assert "contact 0: Table 1 type 4 | 5" in solution.boundary
    assert "contact 1: Table 1 type 4 | 5" in solution.boundary


def test_without_the_band_the_same_perturbations_flip_the_count(monkeypatch):
    """The test above can fail: with a zero band the last bit decides."""
    monkeypatch.setattr(coherent, "BOUNDARY_BAND", 0.0)  # where the checks read it
    problem = flat_box_problem()
    rng = np.random.default_rng(7)
    counts = set()
    for _ in range(40):
        system = sim.contact_system(**perturbed(problem, rng))
        counts.add(len(sim.coherent_solutions(system, "poisson", coupling="effective")))
    assert len(counts) > 1


def test_one_ulp_moves_a_decision_only_inside_the_band():
    """Random two-contact problems: one ulp on every input changes a solution's count or
    its boundary status only where a decision lies inside the band."""
    rng = np.random.default_rng(11)
    for k in range(40):
        system = sim.random_two_contact_system(rng, "generic" if k % 2 else "body")
        problem = dict(mass_matrix=system.mass_matrix, wn=system.wn, wt=system.wt, u=system.u,
                       mu=system.mu, e=system.e)
        before = decisions(problem)
        shaken = perturbed(problem, rng, ulps=1)
        shaken["mass_matrix"] = 0.5 * (problem["mass_matrix"] * (1 + ULP)
                                       + (problem["mass_matrix"] * (1 + ULP)).T)
        after = decisions(shaken)
        for key in before:
            if before[key] != after[key]:  # allowed only when something is at the boundary
                assert before[key][1] or after[key][1], (k, key, before[key], after[key])
