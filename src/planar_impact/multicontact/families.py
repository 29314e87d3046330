"""Broad families of flat landings, and every m-contact law's solutions on them checked for
admissibility (docs/multi-contact.md, 'Admissible references'):
``python -m planar_impact.multicontact admissible [draws] [seed]``.

A flat landing is one rigid body lying on the ground on two points of a flat face: a box
(centre of mass at its centre), a rod (two end caps) or a convex polygon with a flat bottom
edge (its centre of mass anywhere over that edge, its inertia that of a uniform polygon).
Masses and sizes are log-uniform over four decades, the speeds and spin random, ``μ_i`` in
``[0, 1.5]`` and ``e_i`` in ``[0, 1]`` per contact.
"""

from __future__ import annotations

import numpy as np

from ..errors import ImpactInputError
from ..simultaneous import (
    ContactSystem,
    all_orders,
    coherent_solutions,
    contact_system,
    newton_coulomb_solutions,
    promises_no_gain,
    solution_phases,
    violations,
)
from ..simultaneous.admissible import ADMISSIBLE_ENERGY, IMPACT, Phase, energy_change
from .two_phase import poisson_two_phase, two_phase_phases

SHAPES = ("box", "rod", "polygon")


def _log_uniform(rng, low, high):
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


def _polygon(rng, width):
    """A convex polygon with a bottom edge from ``(0, 0)`` to ``(width, 0)``: its vertices,
    area, centroid and polar second moment about the centroid per unit mass."""
    top = np.sort(rng.uniform(-0.5 * width, 1.5 * width, rng.integers(1, 5)))[::-1]
    heights = rng.uniform(0.05, 1.0, len(top)) * width * rng.uniform(0.2, 2.0)
    points = np.array([(0.0, 0.0), (width, 0.0)] + list(zip(top, heights)))
    centre = points.mean(axis=0)
    angles = np.arctan2(points[:, 1] - centre[1], points[:, 0] - centre[0])
    hull = _convex_hull(points[np.argsort(angles)])
    area, first, second = 0.0, np.zeros(2), 0.0
    for k in range(len(hull)):  # triangles from the origin: shoelace sums
        (x0, y0), (x1, y1) = hull[k], hull[(k + 1) % len(hull)]
        cross = x0 * y1 - x1 * y0
        area += cross / 2
        first += cross * np.array([x0 + x1, y0 + y1]) / 6
        second += cross * (x0 * x0 + x0 * x1 + x1 * x1 + y0 * y0 + y0 * y1 + y1 * y1) / 12
    centroid = first / area
    return hull, centroid, second / area - float(centroid @ centroid)


def _convex_hull(points):
    """Andrew's monotone chain, counter-clockwise."""
    ordered = sorted(map(tuple, points))

    def half(sequence):
        chain: list[tuple[float, float]] = []
        for p in sequence:
            while len(chain) >= 2 and ((chain[-1][0] - chain[-2][0]) * (p[1] - chain[-2][1])
                                       - (chain[-1][1] - chain[-2][1]) * (p[0] - chain[-2][0])
                                       ) <= 0:
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(ordered), half(ordered[::-1])
    return np.array(lower[:-1] + upper[:-1])


def random_flat_body(rng: np.random.Generator, shape: str | None = None) -> ContactSystem:
    """One flat landing of the family (module docstring); ``shape`` one of :data:`SHAPES`
    (random when None). ``n = +y``, ``t = +x``; at least one contact approaches."""
    shape = SHAPES[rng.integers(3)] if shape is None else shape
    size, mass = _log_uniform(rng, 0.01, 100.0), _log_uniform(rng, 0.01, 100.0)
    if shape == "box":
        height = size * _log_uniform(rng, 0.02, 5.0)
        corners = [(-size / 2, -height / 2), (size / 2, -height / 2)]
        gyration = (size**2 + height**2) / 12
    elif shape == "rod":
        radius = size * _log_uniform(rng, 0.002, 0.2)
        corners = [(-size / 2, -radius), (size / 2, -radius)]
        gyration = size**2 / 12 + radius**2 / 4
    elif shape == "polygon":
        _, centroid, gyration = _polygon(rng, size)
        corners = [(-centroid[0], -centroid[1]), (size - centroid[0], -centroid[1])]
    else:
        raise ImpactInputError(f"shape: {shape!r}; allowed: {', '.join(SHAPES)}")
    speed = _log_uniform(rng, 0.01, 100.0)
    while True:
        u = speed * np.array([rng.uniform(-1, 1), rng.uniform(-1, -0.05),
                              rng.uniform(-3, 3) / size])
        if min(u[1] + u[2] * x for x, _ in corners) < 0:  # an end approaches
            break
    wn = np.array([(0.0, 1.0, x) for x, _ in corners])
    wt = np.array([(1.0, 0.0, -y) for _, y in corners])
    return contact_system(mass_matrix=np.diag([mass, mass, mass * gyration]), wn=wn, wt=wt,
                          u=u, mu=rng.uniform(0, 1.5, 2), e=rng.uniform(0, 1, 2))


def reference_solutions(system: ContactSystem):
    """Every m-contact reference's solutions on ``system`` as ``(name, law, phases)``: the
    same laws the harness lists at a flat face (Newton–Coulomb, the two-phase Poisson law,
    the paper's proposal and its effective extension, the sequential reading)."""
    out = []
    for solution in newton_coulomb_solutions(system):
        out.append(("newton-coulomb", "newton-coulomb", solution_phases(system, solution)))
    for answer in poisson_two_phase(system):
        out.append(("two-phase/poisson", "two-phase/poisson", two_phase_phases(system, answer)))
    for law in ("poisson", "stronge-paper", "newton"):
        for coupling in ("literal", "effective"):
            try:
                found = coherent_solutions(system, law, coupling=coupling)
            except ImpactInputError:
                found = []
            out += [(f"coherent/{law}/{coupling}", law, solution_phases(system, s))
                    for s in found]
    for law in ("newton-lcp", "poisson"):
        for result in all_orders(system, law)[0]:
            out.append((f"sequential/{law}", law,
                        tuple(Phase(IMPACT, start, impulse) for start, impulse in result.steps)))
    return out


def scan(draws: int = 1000, seed: int = 0) -> dict[str, dict[str, int]]:
    """Per reference: its solutions, the inadmissible ones (a break of any check), those
    that gain energy (for a law that does not promise otherwise a property, not a break),
    the draws with a solution that gains (``draws-gaining``) and the draws with several
    solutions (``draws-several``; the sequential reading: more than its two orders)."""
    rng = np.random.default_rng(seed)
    table: dict[str, dict[str, int]] = {}
    for _ in range(draws):
        system = random_flat_body(rng)
        kinetic = 0.5 * float(system.u @ system.mass_matrix @ system.u)
        gaining, solved = set(), []
        for name, law, phases in reference_solutions(system):
            row = table.setdefault(name, dict.fromkeys(
                ("solutions", "inadmissible", "gains", "draws-gaining", "draws-several"), 0))
            row["solutions"] += 1
            solved.append(name)
            row["inadmissible"] += bool(violations(system, phases,
                                                   promises_no_gain=promises_no_gain(law)))
            if energy_change(system, phases) > ADMISSIBLE_ENERGY * kinetic:
                row["gains"] += 1
                gaining.add(name)
        for name in gaining:
            table[name]["draws-gaining"] += 1
        for name in set(solved):  # the sequential reading: one solution per order
            table[name]["draws-several"] += solved.count(name) > (
                2 if name.startswith("sequential/") else 1)
    return table


__all__ = ["SHAPES", "random_flat_body", "reference_solutions", "scan"]
