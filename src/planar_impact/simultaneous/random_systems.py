"""Random two-contact problems, and how many coherent solutions each law has on them
(:func:`coherent_count_distribution`; ``python -m planar_impact.simultaneous [problems]
[seed]`` prints it for both families and both readings).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ImpactInputError
from .coherent import coherent_solutions
from .newton_coulomb import newton_coulomb_solutions
from .system import (
    ContactSystem,
    contact_system,
)
from .type_map import LITERAL


def random_two_contact_system(rng: np.random.Generator, family: str = "generic") -> ContactSystem:
    """One random approaching two-contact problem.

    ``"generic"``: 4 generalized speeds, a random SPD mass matrix and random contact rows
    (W is then regular). ``"body"``: one free rigid body (u = v_x, v_y, ω) touching two
    obstacles at random points with random normals (W has rank 3: one rigid body cannot
    have four independent contact velocities in the plane). μ ∈ [0, 1], e ∈ [0, 1] per
    contact; ``u`` is redrawn until both contacts approach.
    """
    if family == "generic":
        root = rng.normal(size=(4, 4))
        mass_matrix = root @ root.T + 0.1 * np.eye(4)
        wn, wt = rng.normal(size=(2, 4)), rng.normal(size=(2, 4))
    elif family == "body":
        mass, inertia = 10 ** rng.uniform(-0.5, 0.5), 10 ** rng.uniform(-1.5, 0.5)
        mass_matrix = np.diag([mass, mass, inertia])
        wn, wt = np.empty((2, 3)), np.empty((2, 3))
        for i in range(2):
            angle = rng.uniform(0, 2 * math.pi)
            n = np.array([math.cos(angle), math.sin(angle)])
            t = np.array([n[1], -n[0]])
            r = rng.normal(size=2)
            wn[i] = (n[0], n[1], r[0] * n[1] - r[1] * n[0])
            wt[i] = (t[0], t[1], r[0] * t[1] - r[1] * t[0])
    else:
        raise ImpactInputError(f"family: {family!r}; allowed: generic, body")
    while True:
        u = rng.normal(size=mass_matrix.shape[0])
        if np.all(wn @ u < 0):
            break
    return contact_system(mass_matrix=mass_matrix, wn=wn, wt=wt, u=u,
                          mu=rng.uniform(0, 1, 2), e=rng.uniform(0, 1, 2))


def coherent_count_distribution(problems: int = 1000, seed: int = 0, family: str = "generic",
                                coupling: str = LITERAL,
                                laws_to_count=("poisson", "stronge-paper", "newton",
                                               "newton-coulomb")) -> dict[str, dict[str, int]]:
    """For ``problems`` random two-contact systems, how often each law has 0, 1 or 2+
    clearly coherent solutions (for ``"newton-coulomb"``, solutions with distinct post-impact
    velocities), how often some solution is at the boundary of a decision (key
    ``"boundary"``, not in the 0/1/2+ count), and how often a solution gains energy (key
    ``"gains"``, relative 1e-9 of ``½uᵀMu``)."""
    rng = np.random.default_rng(seed)
    counts = {law: {"0": 0, "1": 0, "2+": 0, "boundary": 0, "gains": 0}
              for law in laws_to_count}
    for _ in range(problems):
        system = random_two_contact_system(rng, family)
        energy = 0.5 * float(system.u @ system.mass_matrix @ system.u)
        for law in laws_to_count:
            if law == "newton-coulomb":
                found = newton_coulomb_solutions(system)
            else:
                found = coherent_solutions(system, law, coupling=coupling)
            number = sum(not s.at_boundary for s in found)
            counts[law]["0" if number == 0 else "1" if number == 1 else "2+"] += 1
            counts[law]["boundary"] += any(s.at_boundary for s in found)
            counts[law]["gains"] += any(s.energy_change > 1e-9 * energy for s in found)
    return counts


__all__ = ["coherent_count_distribution", "random_two_contact_system"]
