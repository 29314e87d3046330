"""Measurements of the two-phase law on random problems (docs/multi-contact.md quotes them;
``python -m planar_impact.multicontact [problems] [seed] [plain]``)."""

from __future__ import annotations

import numpy as np

from .. import solver
from ..errors import ImpactInputError
from ..simultaneous import (
    ContactSystem,
    contact_system,
    newton_coulomb_solutions,
    random_two_contact_system,
)
from .phase import SAME_ANSWER
from .two_phase import normal_split_unique, poisson_two_phase, poisson_two_phase_many


def random_flat_face(rng: np.random.Generator) -> ContactSystem:
    """One box lying flat on the ground on its two lower corners (a rod's end caps sit the
    same way): width 0.2–2 m, height 0.02–1 m, mass 0.2–5 kg, ``v_x`` ∈ [−1, 1],
    ``v_y`` ∈ [−2, −0.2] m/s, ``ω`` ∈ [−3, 3] rad/s (redrawn until an end approaches), ``μ``
    and ``e`` ∈ [0, 1] per corner. ``n = +y``, ``t = +x``: W is 4×4 of rank 3."""
    width, height, mass = rng.uniform(0.2, 2.0), rng.uniform(0.02, 1.0), rng.uniform(0.2, 5.0)
    while True:
        u = np.array([rng.uniform(-1, 1), rng.uniform(-2, -0.2), rng.uniform(-3, 3)])
        if u[1] - abs(u[2]) * width / 2 < 0:
            break
    inertia = mass * (width**2 + height**2) / 12.0
    corners = [(-width / 2, -height / 2), (width / 2, -height / 2)]
    wn = np.array([(0.0, 1.0, rx) for rx, _ in corners])  # (n_x, n_y, r_x n_y − r_y n_x)
    wt = np.array([(1.0, 0.0, -ry) for _, ry in corners])
    return contact_system(mass_matrix=np.diag([mass, mass, inertia]), wn=wn, wt=wt, u=u,
                          mu=rng.uniform(0, 1, 2), e=rng.uniform(0, 1, 2))


def measure(problems: int = 1000, seed: int = 0, follow_slip: bool = True
            ) -> dict[str, dict[str, int]]:
    """Per family of random two-contact problems (``generic``, ``body``: those of
    :func:`planar_impact.simultaneous.random_two_contact_system`; ``flat``:
    :func:`random_flat_face`): how many answers the enumeration finds (0, 1, 2+), whether
    Lemke's answer is one of them (``lemke-agrees``; ``lemke-ray``: it ended on a ray), how
    many answers gain energy (relative 1e-9 of ``½uᵀMu``), where the normal split is
    unique, where an answer's restitution was scaled down not to gain energy
    (``restitution-capped``), and how many first answers are more than 1e-6 of the speeds
    from every Newton–Coulomb solution (``newton-coulomb-apart``)."""
    rng = np.random.default_rng(seed)
    table = {}
    for family in ("generic", "body", "flat"):
        systems = [random_flat_face(rng) if family == "flat"
                   else random_two_contact_system(rng, family) for _ in range(problems)]
        counts = dict.fromkeys(("0", "1", "2+", "lemke-agrees", "lemke-ray", "lemke-other",
                                "gains", "split-unique", "newton-coulomb-apart",
                                "slip-not-followed-to-end", "restitution-capped"), 0)
        for system, found, reached in zip(
                systems, poisson_two_phase_many(systems, follow_slip=follow_slip),
                poisson_two_phase_many(systems, "lemke", follow_slip=follow_slip)):
            counts["0" if not found else "1" if len(found) == 1 else "2+"] += 1
            scale = SAME_ANSWER * (system.speed_scale() + float(np.max(np.abs(system.u))))
            if not reached:
                counts["lemke-ray"] += 1
            elif any(np.max(np.abs(a.u_after - reached[0].u_after)) <= scale for a in found):
                counts["lemke-agrees"] += 1
            else:
                counts["lemke-other"] += 1
            energy = 0.5 * float(system.u @ system.mass_matrix @ system.u)
            counts["gains"] += any(a.energy_change > 1e-9 * energy for a in found)
            counts["split-unique"] += normal_split_unique(system)
            counts["slip-not-followed-to-end"] += any(
                not (a.compression.slip_followed_to_end and a.restitution.slip_followed_to_end)
                for a in found)
            counts["restitution-capped"] += any(a.restitution_scale < 1.0 for a in found)
            speed = float(np.max(np.abs(system.u)))
            counts["newton-coulomb-apart"] += bool(found) and all(
                np.max(np.abs(found[0].u_after - other.u_after)) > 1e-6 * speed
                for other in newton_coulomb_solutions(system))
        table[family] = counts
    table["one-contact"] = measure_one_contact(problems, rng, follow_slip)
    return table


def measure_one_contact(problems: int, rng: np.random.Generator, follow_slip: bool = True
                        ) -> dict[str, int]:
    """On ``problems`` random one-contact problems (3 speeds, random SPD M and rows, μ ∈
    [0, 1.5], e ∈ [0, 1]) with a Poisson answer: per paper type, how many, and in how many
    this law's speeds after equal ``solve(..., law="poisson")``'s to 1e-10 of the speeds;
    and the median gap where they differ (``‖Δu‖_∞`` over ``‖u‖_∞``, in 1e-6)."""
    counts: dict[str, int] = {}
    gaps = []
    while sum(v for k, v in counts.items() if k.endswith("problems")) < problems:
        root = rng.normal(size=(3, 3))
        mass_matrix = root @ root.T + 0.1 * np.eye(3)
        wn, wt, u = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        if wn @ u >= 0:
            u = -u
        mu, e = rng.uniform(0, 1.5), rng.uniform(0, 1)
        try:
            poisson = solver.solve(mass_matrix=mass_matrix, wn=wn, wt=wt, u=u, mu=mu, e=e,
                                   law="poisson")
        except ImpactInputError:  # a jam: no Poisson answer
            continue
        system = contact_system(mass_matrix=mass_matrix, wn=wn[None], wt=wt[None], u=u,
                                mu=mu, e=e)
        (answer,) = poisson_two_phase(system, follow_slip=follow_slip)
        gap = float(np.max(np.abs(answer.u_after - poisson.u_after) / np.max(np.abs(u))))
        key = f"type {poisson.collision_type}"
        counts[f"{key} problems"] = counts.get(f"{key} problems", 0) + 1
        counts[f"{key} equal"] = counts.get(f"{key} equal", 0) + (gap <= 1e-10)
        if gap > 1e-10:
            gaps.append(gap)
    counts["median gap where they differ (1e-6)"] = (
        round(float(np.median(gaps)) * 1e6) if gaps else 0)
    return dict(sorted(counts.items()))
