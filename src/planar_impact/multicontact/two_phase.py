"""The two-phase Poisson law for ``m`` contacts: a compression phase, then a restitution
phase whose base normal impulse is ``e`` times the compression's (the package's docstring)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..simultaneous import ContactSystem, Phase
from ..simultaneous.admissible import COMPRESSION, RESTITUTION
from .enumeration import phase_by_enumeration, phases_by_enumeration
from .lemke import phase_by_lemke
from .phase import SAME_ANSWER, PhaseSolution, check_method, complementary, distinct
from .slip import phase_following_slip


@dataclass(frozen=True)
class TwoPhaseSolution:
    """One answer of the two-phase Poisson law; arrays per contact, caller's ``t``.

    ``normal_split_unique`` is False where ``W`` has a null vector with a normal component:
    then the compression's normal impulses are a family, and so is the restitution that
    scales them (velocities after the impact need not be unique). On one body lying flat the
    null vectors are tangential only (the friction split), and this is True.
    """

    compression: PhaseSolution
    restitution: PhaseSolution
    normal_impulse: np.ndarray
    tangential_impulse: np.ndarray
    delta_u: np.ndarray
    u_after: np.ndarray
    vn_separation: np.ndarray
    vt_separation: np.ndarray
    energy_change: float  # J: ½ u'ᵀMu' − ½ uᵀMu
    energy_change_compression: float
    normal_split_unique: bool
    #: The common factor ``λ`` of the restitution's base impulses ``λ e_i P_nc,i``: 1 (Poisson's
    #: hypothesis) unless that restitution would gain energy, then the largest ``λ`` found
    #: that does not (docs/multi-contact.md, 'A two-phase Poisson law for m contacts').
    restitution_scale: float = 1.0

    def impulses(self) -> np.ndarray:
        return np.ravel(np.column_stack([self.normal_impulse, self.tangential_impulse]))



def normal_split_unique(system: ContactSystem) -> bool:
    """False where ``W`` has a null vector with a normal component (relative 1e-9)."""
    _, singular, right = np.linalg.svd(system.delassus)
    null = right[singular <= 1e-10 * singular[0]]
    return bool(null.size == 0 or np.max(np.abs(null[:, 0::2])) <= 1e-9)


def poisson_two_phase(system: ContactSystem, method: str = "enumeration", *,
                      follow_slip: bool = True) -> list[TwoPhaseSolution]:
    """The two-phase Poisson law for the ``m`` contacts of ``system`` (module docstring).

    Every answer by ``"enumeration"`` (a compression's every solution followed by each of
    its restitutions; answers with the same speeds after listed once), the one Lemke's
    algorithm reaches (or none, where it ends on a ray) by ``"lemke"``. Contacts that do
    not approach take part too: the complementarity decides whether they take an impulse.

    ``follow_slip`` (default): each phase follows the slip (:func:`phase_following_slip`),
    which makes the law the paper's Poisson law for one contact in all five types. Without
    it each phase is one velocity-level problem (Coulomb at the phase's end only), as in
    Glocker and Pfeiffer: the same answer wherever no slip reverses inside a phase.
    """
    return poisson_two_phase_many([system], method, follow_slip=follow_slip)[0]


def poisson_two_phase_many(systems, method: str = "enumeration", *, follow_slip: bool = True
                           ) -> list[list[TwoPhaseSolution]]:
    """:func:`poisson_two_phase` of many systems; by enumeration without ``follow_slip``, the
    systems with the same number of contacts have each phase's modes solved in one batched
    call."""
    check_method(method)
    if follow_slip:
        return [_following_slip(system, method) for system in systems]
    systems = list(systems)
    compressions: list[list[PhaseSolution]] = [[] for _ in systems]
    for rows, phases in _phases(systems, method, [(i, s.approach, np.zeros(s.count))
                                                  for i, s in enumerate(systems)]):
        for row, found in zip(rows, phases):
            compressions[row] = found
    starts = [(i, phase.velocities, systems[i].e * phase.impulses[0::2])
              for i, found in enumerate(compressions) for phase in found]
    pairs = [(i, phase) for i, found in enumerate(compressions) for phase in found]
    restitutions: list[list[PhaseSolution]] = [[] for _ in pairs]
    for rows, phases in _phases(systems, method, starts):
        for row, found in zip(rows, phases):
            restitutions[row] = found
    answers: list[list[TwoPhaseSolution]] = [[] for _ in systems]
    unique_split = [normal_split_unique(system) for system in systems]
    for (i, compression), found in zip(pairs, restitutions):
        system = systems[i]
        scale = SAME_ANSWER * (system.speed_scale() + float(np.max(np.abs(system.u))))
        for restitution in found:
            answer = _assemble(system, compression, restitution, unique_split[i])
            if all(np.max(np.abs(answer.u_after - other.u_after)) > scale
                   for other in answers[i]):
                answers[i].append(answer)
    return answers


def _following_slip(system: ContactSystem, method: str) -> list[TwoPhaseSolution]:
    speed = system.speed_scale()
    unique_split = normal_split_unique(system)
    scale = SAME_ANSWER * (speed + float(np.max(np.abs(system.u))))
    answers: list[TwoPhaseSolution] = []
    for compression in _complementary_phase(system, system.approach, np.zeros(system.count),
                                            method):
        base = system.e * compression.impulses[0::2]
        restitutions = _complementary_phase(system, compression.velocities, base, method)
        factor = 1.0
        if not _loses_energy(system, compression, restitutions):
            factor, restitutions = _energy_capped(system, compression, base, method)
        for restitution in restitutions:
            answer = _assemble(system, compression, restitution, unique_split, factor)
            if all(np.max(np.abs(answer.u_after - other.u_after)) > scale for other in answers):
                answers.append(answer)
    return answers


#: Bisection steps for the restitution's energy cap: λ to 2⁻⁴⁰ ≈ 1e-12.
CAP_STEPS = 40
#: A gain up to this fraction of ½uᵀMu is rounding (½u'ᵀMu' is formed to ~1e-16 of it), not
#: a gain: an elastic impact (ΔE = 0) keeps λ = 1.
ENERGY_ROUNDING = 1e-12


def _loses_energy(system: ContactSystem, compression, restitutions) -> bool:
    """Whether every restitution ends with no more kinetic energy than before the impact,
    to rounding (:data:`ENERGY_ROUNDING`), and there is one."""
    before = _kinetic(system, system.u)
    return bool(restitutions) and all(
        _kinetic(system, system.u + system.delta_u(compression.impulses + r.impulses))
        <= before * (1.0 + ENERGY_ROUNDING) for r in restitutions)


def _energy_capped(system: ContactSystem, compression, base, method: str):
    """``(λ, restitutions)`` with the base ``λ·base``: the largest ``λ ∈ [0, 1]`` found by
    bisection whose restitutions lose energy. ``λ = 0`` always does: its base is nothing, the
    compression's end is complementary (``v̄_n ≥ 0``), so the restitution gives nothing and
    the impact's energy change is the compression's, ``≤ 0`` (proved)."""
    low, high = 0.0, 1.0
    kept = _complementary_phase(system, compression.velocities, 0.0 * base, method)
    for _ in range(CAP_STEPS):
        middle = 0.5 * (low + high)
        found = _complementary_phase(system, compression.velocities, middle * base, method)
        if _loses_energy(system, compression, found):
            low, kept = middle, found
        else:
            high = middle
    return low, kept


def _complementary_phase(system: ContactSystem, start, base, method: str
                         ) -> list[PhaseSolution]:
    """A phase with the slip followed (:func:`phase_following_slip`), its solutions that are
    complementary at the phase's end; a solution that is not (a contact took impulse in one
    piece and recedes at the end) is dropped, and where none is left the phase is solved as
    one velocity-level problem, complementary by construction (``slip_followed`` False)."""
    speed = system.speed_scale()
    impulse = speed / float(np.min(np.diag(system.delassus)))
    followed = phase_following_slip(system.delassus, start, base, system.mu, speed, method)
    kept = [phase for phase in followed if complementary(phase, base, speed, impulse)]
    if kept or not followed:
        return kept
    if method == "enumeration":
        plain = phase_by_enumeration(system.delassus, start, base, system.mu, speed)
    else:
        found = phase_by_lemke(system.delassus, start, base, system.mu, speed)
        plain = [] if found is None else [found]
    for phase in plain:
        phase = dataclasses.replace(phase, slip_followed=False)
        if distinct(kept, phase, speed, impulse):
            kept.append(phase)
    return kept


def _phases(systems, method, starts):
    """Each phase of ``starts`` (``(system index, start velocities, base)``), grouped by
    contact count: yields ``(positions in starts, their solutions)``."""
    groups: dict[int, list[int]] = {}
    for position, (i, _, _) in enumerate(starts):
        groups.setdefault(systems[i].count, []).append(position)
    for positions in groups.values():
        chosen = [starts[p] for p in positions]
        owners = [systems[i] for i, _, _ in chosen]
        if method == "enumeration":
            yield positions, phases_by_enumeration(
                np.array([s.delassus for s in owners]), np.array([v for _, v, _ in chosen]),
                np.array([b for _, _, b in chosen]), np.array([s.mu for s in owners]),
                np.array([s.speed_scale() for s in owners]))
        else:
            found = [phase_by_lemke(s.delassus, v, b, s.mu, s.speed_scale())
                     for s, (_, v, b) in zip(owners, chosen)]
            yield positions, [[] if phase is None else [phase] for phase in found]


def _kinetic(system: ContactSystem, speeds) -> float:
    return 0.5 * float(speeds @ system.mass_matrix @ speeds)


def _assemble(system, compression, restitution, unique_split, factor=1.0) -> TwoPhaseSolution:
    total = compression.impulses + restitution.impulses
    delta_u = system.delta_u(total)  # (75)
    u_after = system.u + delta_u
    before = _kinetic(system, system.u)
    after_compression = _kinetic(system, system.u + system.delta_u(compression.impulses))
    return TwoPhaseSolution(
        compression=compression, restitution=restitution,
        normal_impulse=total[0::2].copy(), tangential_impulse=total[1::2].copy(),
        delta_u=delta_u, u_after=u_after,
        vn_separation=system.wn @ u_after, vt_separation=system.wt @ u_after,
        energy_change=_kinetic(system, u_after) - before,
        energy_change_compression=after_compression - before,
        normal_split_unique=unique_split, restitution_scale=factor)


def two_phase_phases(system: ContactSystem, answer: TwoPhaseSolution) -> tuple[Phase, ...]:
    """The answer's compression and restitution as the phases that
    :func:`planar_impact.simultaneous.violations` checks (the restitution owed
    ``λ e_i P_nc``, ``λ`` its :attr:`~TwoPhaseSolution.restitution_scale`)."""
    compression = answer.compression.impulses
    start = system.approach + system.delassus @ compression
    return (Phase(COMPRESSION, system.approach.copy(), compression.copy()),
            Phase(RESTITUTION, start, answer.restitution.impulses.copy(),
                  answer.restitution_scale * system.e * compression[0::2]))
