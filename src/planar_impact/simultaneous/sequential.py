"""The sequential reading of ``m`` contacts: one contact at a time with the single-contact
solver, in a given order, until none approaches (:func:`sequential_impacts`; every order:
:func:`all_orders`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from .. import contact_space, solver
from ..errors import ImpactInputError
from .system import (
    ContactSystem,
)


@dataclass(frozen=True)
class SequentialResult:
    """The contacts taken one at a time in ``order`` (repeated rounds) with one law.

    ``impacts`` lists ``(contact, collision type)`` in the order they happened; ``capped``
    is True when ``max_impacts`` stopped the sequence while a contact still approached.
    """

    order: tuple[int, ...]
    law: str
    impacts: tuple[tuple[int, int], ...]
    u_after: np.ndarray
    delta_u: np.ndarray
    vn_separation: np.ndarray
    vt_separation: np.ndarray
    energy_change: float
    capped: bool
    #: Per impact, the contact velocities at its start and its impulses, both
    #: ``(v_n^(1), v_t^(1), …)``-ordered (zero but at the struck contact): the phases that
    #: :func:`planar_impact.simultaneous.admissible.violations` checks.
    steps: tuple[tuple[np.ndarray, np.ndarray], ...] = ()


def sequential_impacts(system: ContactSystem, law: str, order, max_impacts: int = 10_000
                       ) -> SequentialResult:
    """Rounds over ``order``: each contact that approaches (``v_n < −10⁻¹²·speed``) gets a
    single-contact impact by :func:`planar_impact.solve` with the current speeds; stop after
    a round with no impact, or at ``max_impacts``."""
    order = tuple(int(i) for i in order)
    if sorted(order) != list(range(system.count)):
        raise ImpactInputError(
            f"order: {order} is not a permutation of the {system.count} contacts")
    speeds = system.u.copy()
    threshold = -1e-12 * system.speed_scale()  # below rounding, above any real approach
    impacts: list[tuple[int, int]] = []
    steps: list[tuple[np.ndarray, np.ndarray]] = []
    capped = False
    while True:
        struck = False
        for i in order:
            if float(system.wn[i] @ speeds) >= threshold:
                continue
            if len(impacts) >= max_impacts:
                capped = True
                break
            contact_space.check_law(law)  # as solve() would, at the first impact
            # solve() of contact i, its M⁻¹ w and (A20) terms formed once per system.
            result = solver.solve_contact(system.checked_contacts[i], speeds,
                                          float(system.mu[i]), float(system.e[i]), law)
            impulse = np.zeros(2 * system.count)
            impulse[2 * i], impulse[2 * i + 1] = result.normal_impulse, result.tangential_impulse
            start = np.ravel(np.column_stack([system.wn @ speeds, system.wt @ speeds]))
            steps.append((start, impulse))
            speeds = result.u_after
            impacts.append((i, result.collision_type))
            struck = True
        if capped or not struck:
            break
    delta_u = speeds - system.u
    kinetic = 0.5 * (speeds @ system.mass_matrix @ speeds
                     - system.u @ system.mass_matrix @ system.u)
    return SequentialResult(order=order, law=law, impacts=tuple(impacts), u_after=speeds,
                            delta_u=delta_u, vn_separation=system.wn @ speeds,
                            vt_separation=system.wt @ speeds, energy_change=float(kinetic),
                            capped=capped, steps=tuple(steps))


def all_orders(system: ContactSystem, law: str, max_impacts: int = 10_000
               ) -> tuple[list[SequentialResult], float]:
    """:func:`sequential_impacts` for every order of the contacts, and the spread: the
    largest difference in any component of ``u_after`` between two orders."""
    results = [sequential_impacts(system, law, order, max_impacts)
               for order in itertools.permutations(range(system.count))]
    finals = np.array([r.u_after for r in results])
    spread = float(np.max(finals.max(axis=0) - finals.min(axis=0)))
    return results, spread


__all__ = ["SequentialResult", "all_orders", "sequential_impacts"]
