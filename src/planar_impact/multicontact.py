"""A two-phase Poisson law for ``m`` simultaneous contacts, at velocity level.

Poisson's hypothesis splits an impact into a compression phase, which ends when the normal
approach has stopped, (1)–(2), and a restitution phase whose normal impulse is ``e`` times
the compression's, (3)–(6). The paper's closed forms (25)–(51) apply it to one contact by
following the impulse process; after (75) it leaves several contacts open. This module
applies the same two phases to ``m`` contacts in the manner of Glocker and Pfeiffer's
two-phase impact law (Pfeiffer & Glocker, *Multibody Dynamics with Unilateral Contacts*,
1996) and of the velocity-level linear complementarity problems of Anitescu and Potra
(*Nonlinear Dynamics* 14, 1997), with the Coulomb law applied to each phase's impulse at the
phase's end velocity:

* **Compression** (1)–(5): impulses ``P_c`` with ``v̄ = v^A + W P_c`` (75 with (A22)/(A23))
  and, per contact, ``0 ≤ P_nc ⟂ v̄_n ≥ 0`` (the approach ends where an impulse acts),
  ``|P_tc| ≤ μ P_nc`` and maximal dissipation (``P_tc = −μ P_nc sign(v̄_t)`` where
  ``v̄_t ≠ 0``).
* **Restitution** (6): impulses ``P_r`` with ``v^S = v̄ + W P_r``, per contact
  ``P_nr = e P_nc + Λ`` with ``0 ≤ Λ ⟂ v_n^S ≥ 0``, and Coulomb as above with ``P_nr``.
  The extra ``Λ`` is Glocker and Pfeiffer's: it acts only where ``e P_nc`` alone would leave a
  contact penetrating (never for one contact, where ``Λ = 0`` and ``P_nr = e P_nc`` is (6)).

Both phases are one problem, :func:`solve_phase`, with a base normal impulse ``b`` (0 for the
compression, ``e P_nc`` for the restitution). Each is solved two independent ways:
:func:`phase_by_enumeration` (every stick / slide / separate mode, a linear system each, all
solutions kept) and :func:`phase_by_lemke` (the phase as a linear complementarity problem in
the planar friction cone's two edges, Lemke's complementary pivoting with a lexicographic
ratio test). ``W`` may be singular (a flat face: 4 constraints on 3 speeds): velocities are
then unique where the impulse split is not, and the two methods are compared on velocities.

What this law is not: the velocity-level Coulomb law sees only a phase's end velocity, so
where the paper's process reverses the slip inside a phase (its Types 3 and 4) the friction
impulse differs from (36)/(44). For one contact it equals ``solve(..., law="poisson")`` in
Types 1, 2 and 5 (docs/multi-contact.md, 'A two-phase Poisson law for m contacts').
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from .errors import ImpactInputError
from .simultaneous import ContactSystem

#: Per contact and phase: how its normal impulse is fixed.
NORMAL_BASE, NORMAL_ACTIVE = 0, 1  # P_n = b (Λ = 0) / v_n = 0 at the phase's end
#: Per contact and phase: how its friction impulse is fixed.
STICK, SLIDE_POSITIVE, SLIDE_NEGATIVE = 0, 1, 2  # v_t = 0 / v_t ≥ 0, P_t = −μP_n / v_t ≤ 0

#: Sign and complementarity tests, relative to the problem's own scales (speeds over the
#: approach speed, impulses over that speed divided by the smallest diagonal of W): zeros
#: come out as sums of 2m rounded products, a few 1e-16 times W's condition.
SIGN_TOLERANCE = 1e-9
#: A mode's linear system is consistent when its scaled residual is below this.
RESIDUAL_TOLERANCE = 1e-9
#: Singular values of a mode's matrix below this fraction of the largest count as zero.
RANK_CUT = 1e-12
#: Two answers are one when their contact velocities (and, for a compression, normal
#: impulses) agree to this fraction of the scales.
SAME_ANSWER = 1e-8

METHODS = ("enumeration", "lemke")


@dataclass(frozen=True)
class PhaseSolution:
    """One phase's answer, in the caller's units.

    ``impulses``: ``(P_n^(1), P_t^(1), P_n^(2), …)``; ``velocities``: contact velocities at
    the phase's end in the same order; ``modes``: per contact ``(normal, friction)`` codes.
    """

    impulses: np.ndarray
    velocities: np.ndarray
    modes: tuple[tuple[int, int], ...]


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

    def impulses(self) -> np.ndarray:
        return np.ravel(np.column_stack([self.normal_impulse, self.tangential_impulse]))


# ------------------------------------------------------------------------------------------
# One phase
# ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Scaled:
    """A phase in units where the approach speed and its impulse are 1 (tolerances are then
    plain numbers)."""

    delassus: np.ndarray  # W / w_min
    start: np.ndarray  # v_start / V
    base: np.ndarray  # b / (V / w_min), per contact
    mu: np.ndarray
    speed: float  # V
    impulse: float  # V / w_min


def _scaled(delassus, start, base, mu, speed) -> _Scaled:
    w_min = float(np.min(np.diag(delassus)))
    if not w_min > 0:
        raise ImpactInputError(f"delassus: diagonal must be positive, smallest is {w_min}")
    impulse = speed / w_min
    return _Scaled(np.asarray(delassus) / w_min, np.asarray(start) / speed,
                   np.asarray(base, dtype=float) / impulse, np.asarray(mu, dtype=float),
                   speed, impulse)


def _phase_holds(problem: _Scaled, modes, impulses, velocities) -> bool:
    """The phase's inequalities at a candidate (scaled units)."""
    tolerance = SIGN_TOLERANCE
    for i, (normal_mode, friction_mode) in enumerate(modes):
        normal, tangential = impulses[2 * i], impulses[2 * i + 1]
        vn, vt = velocities[2 * i], velocities[2 * i + 1]
        if normal < problem.base[i] - tolerance:  # Λ ≥ 0
            return False
        if normal_mode == NORMAL_BASE and vn < -tolerance:  # v_n ≥ 0 where Λ = 0
            return False
        limit = problem.mu[i] * normal
        if friction_mode == STICK and abs(tangential) > limit + tolerance:
            return False
        if friction_mode == SLIDE_POSITIVE and vt < -tolerance:
            return False
        if friction_mode == SLIDE_NEGATIVE and vt > tolerance:
            return False
    return True


def _mode_systems(problem: _Scaled, every_mode):
    """Per mode the linear system (2m equations in the 2m scaled impulses)."""
    count = len(problem.mu)
    matrices = np.zeros((len(every_mode), 2 * count, 2 * count))
    rhs = np.zeros((len(every_mode), 2 * count))
    for k, modes in enumerate(every_mode):
        for i, (normal_mode, friction_mode) in enumerate(modes):
            n, t = 2 * i, 2 * i + 1
            if normal_mode == NORMAL_BASE:  # P_n = b
                matrices[k, n, n] = 1.0
                rhs[k, n] = problem.base[i]
            else:  # v_n = 0
                matrices[k, n] = problem.delassus[n]
                rhs[k, n] = -problem.start[n]
            if friction_mode == STICK:  # v_t = 0
                matrices[k, t] = problem.delassus[t]
                rhs[k, t] = -problem.start[t]
            else:  # P_t = ∓μ P_n, against the end slip
                matrices[k, t, t] = 1.0
                matrices[k, t, n] = problem.mu[i] if friction_mode == SLIDE_POSITIVE else (
                    -problem.mu[i])
    return matrices, rhs


def _unscaled(problem: _Scaled, impulses, velocities, modes) -> PhaseSolution:
    return PhaseSolution(impulses * problem.impulse, velocities * problem.speed,
                         tuple((int(a), int(b)) for a, b in modes))


def _distinct(found: list[PhaseSolution], candidate: PhaseSolution, speed, impulse,
              count) -> bool:
    for other in found:
        if np.max(np.abs(other.velocities - candidate.velocities)) > SAME_ANSWER * speed:
            continue
        normals = np.abs(other.impulses[0::2] - candidate.impulses[0::2])
        if np.max(normals) <= SAME_ANSWER * impulse:
            return False
    return True


def phase_by_enumeration(delassus, start, base, mu, speed) -> list[PhaseSolution]:
    """Every solution of one phase, by its ``6^m`` modes (normal: ``Λ = 0`` or ``v_n = 0``;
    friction: stick, slide with ``v_t ≥ 0``, slide with ``v_t ≤ 0``).

    ``delassus`` ``(2m, 2m)``, ``start`` ``(2m,)`` the contact velocities at the phase's
    start, ``base`` ``(m,)`` the normal impulse each contact takes at least, ``speed`` a
    positive speed scale (the largest approach speed). A singular mode is solved by the
    pseudo-inverse and kept when consistent; where a mode's solutions are a family, its
    minimum-norm member is tested, and the family's ends are other modes (a friction or
    normal bound reached). Answers with the same velocities and normal impulses are listed
    once.
    """
    problem = _scaled(delassus, start, base, mu, speed)
    count = len(problem.mu)
    per_contact = list(itertools.product((NORMAL_BASE, NORMAL_ACTIVE),
                                         (STICK, SLIDE_POSITIVE, SLIDE_NEGATIVE)))
    every_mode = list(itertools.product(per_contact, repeat=count))
    matrices, rhs = _mode_systems(problem, every_mode)
    solutions = np.einsum("kij,kj->ki", np.linalg.pinv(matrices, rcond=RANK_CUT), rhs)
    residuals = np.max(np.abs(np.einsum("kij,kj->ki", matrices, solutions) - rhs), axis=1)
    velocities = problem.start + solutions @ problem.delassus.T
    found: list[PhaseSolution] = []
    for k in np.flatnonzero(residuals <= RESIDUAL_TOLERANCE * (1.0 + np.abs(rhs).max(axis=1))):
        if not _phase_holds(problem, every_mode[k], solutions[k], velocities[k]):
            continue
        candidate = _unscaled(problem, solutions[k], velocities[k], every_mode[k])
        if _distinct(found, candidate, problem.speed, problem.impulse, count):
            found.append(candidate)
    return found


def phase_lcp(delassus, start, base, mu) -> tuple[np.ndarray, np.ndarray]:
    """The phase as an LCP ``w = M z + q ≥ 0, z ≥ 0, zᵀw = 0`` (Anitescu & Potra's
    velocity-level form; in the plane the friction cone has two edges, so it is exact).

    ``z = (Λ, β⁺, β⁻, λ)`` per block of ``m``: ``P_n = b + Λ``, ``P_t = β⁺ − β⁻``, ``λ`` the
    slip speed; ``w = (v_n, λ + v_t, λ − v_t, μ P_n − β⁺ − β⁻)``.
    """
    delassus, start = np.asarray(delassus, dtype=float), np.asarray(start, dtype=float)
    base, mu = np.asarray(base, dtype=float), np.asarray(mu, dtype=float)
    count = len(mu)
    normal, tangent = np.arange(0, 2 * count, 2), np.arange(1, 2 * count, 2)
    w_nn = delassus[np.ix_(normal, normal)]
    w_nt = delassus[np.ix_(normal, tangent)]
    w_tn = delassus[np.ix_(tangent, normal)]
    w_tt = delassus[np.ix_(tangent, tangent)]
    identity, zero = np.eye(count), np.zeros((count, count))
    matrix = np.block([
        [w_nn, w_nt, -w_nt, zero],
        [w_tn, w_tt, -w_tt, identity],
        [-w_tn, -w_tt, w_tt, identity],
        [np.diag(mu), -identity, -identity, zero],
    ])
    vn0 = start[normal] + w_nn @ base  # velocities with the base impulses applied
    vt0 = start[tangent] + w_tn @ base
    return matrix, np.concatenate([vn0, vt0, -vt0, mu * base])


def lemke(matrix, q, max_pivots: int | None = None, pivot_tolerance: float = 1e-12):
    """Lemke's complementary pivoting for ``w = M z + q``, covering vector of ones, with a
    lexicographic minimum-ratio test (no cycling on degenerate problems).

    Returns ``z``, or None on a secondary ray or after ``max_pivots``.
    """
    matrix, q = np.asarray(matrix, dtype=float), np.asarray(q, dtype=float)
    size = len(q)
    if np.all(q >= 0):
        return np.zeros(size)
    # Tableau for  I w − M z − 1 z0 = q; columns: w (size), z (size), z0, rhs.
    tableau = np.hstack([np.eye(size), -matrix, -np.ones((size, 1)), q[:, None]])
    basis = list(range(size))  # w_i basic
    z0 = 2 * size
    row = int(np.argmin(q))
    entering = z0
    limit = max_pivots if max_pivots is not None else 50 * size
    for _ in range(limit):
        tableau[row] /= tableau[row, entering]
        for other in range(size):
            if other != row:
                tableau[other] -= tableau[other, entering] * tableau[row]
        leaving, basis[row] = basis[row], entering
        if leaving == z0:
            break
        entering = leaving + size if leaving < size else leaving - size  # its complement
        column = tableau[:, entering]
        scale = max(1.0, float(np.max(np.abs(column))))
        candidates = np.flatnonzero(column > pivot_tolerance * scale)
        if candidates.size == 0:
            return None  # secondary ray
        row = _lexicographic_min(tableau, candidates, column, basis, z0, size)
    else:
        return None
    values = np.zeros(2 * size + 1)
    values[basis] = tableau[:, -1]
    return values[size:2 * size]


def _lexicographic_min(tableau, candidates, column, basis, z0, size) -> int:
    """The leaving row: smallest ratio rhs/column, ties broken by z0 leaving first, then
    lexicographically on the rows of the basis inverse (the tableau's w-columns)."""
    ratios = tableau[candidates, -1] / column[candidates]
    best = float(np.min(ratios))
    tied = candidates[ratios <= best + 1e-12 * max(1.0, abs(best))]
    for r in tied:
        if basis[r] == z0:
            return int(r)
    for j in range(size):
        if tied.size == 1:
            break
        values = tableau[tied, j] / column[tied]
        tied = tied[values <= np.min(values) + 1e-12 * max(1.0, float(np.max(np.abs(values))))]
    return int(tied[0])


def phase_by_lemke(delassus, start, base, mu, speed) -> PhaseSolution | None:
    """One solution of the phase by :func:`lemke` on :func:`phase_lcp` (scaled to unit speed
    and impulse), or None where Lemke's algorithm ends on a ray."""
    problem = _scaled(delassus, start, base, mu, speed)
    count = len(problem.mu)
    z = lemke(*phase_lcp(problem.delassus, problem.start, problem.base, problem.mu))
    if z is None:
        return None
    impulses = np.empty(2 * count)
    impulses[0::2] = problem.base + z[:count]
    impulses[1::2] = z[count:2 * count] - z[2 * count:3 * count]
    velocities = problem.start + problem.delassus @ impulses
    modes = []
    for i in range(count):
        normal_mode = NORMAL_ACTIVE if z[i] > SIGN_TOLERANCE else NORMAL_BASE
        vt = velocities[2 * i + 1]
        friction_mode = (SLIDE_POSITIVE if vt > SIGN_TOLERANCE else
                         SLIDE_NEGATIVE if vt < -SIGN_TOLERANCE else STICK)
        modes.append((normal_mode, friction_mode))
    return _unscaled(problem, impulses, velocities, modes)


def solve_phase(delassus, start, base, mu, speed, method: str = "enumeration"
                ) -> list[PhaseSolution]:
    """One phase by ``method`` (:data:`METHODS`): every solution by enumeration, the one
    Lemke's algorithm reaches (or none) by ``"lemke"``."""
    if method == "enumeration":
        return phase_by_enumeration(delassus, start, base, mu, speed)
    if method == "lemke":
        found = phase_by_lemke(delassus, start, base, mu, speed)
        return [] if found is None else [found]
    raise ImpactInputError(f"method: {method!r}; allowed: {', '.join(METHODS)}")


# ------------------------------------------------------------------------------------------
# The two-phase law
# ------------------------------------------------------------------------------------------
def normal_split_unique(system: ContactSystem) -> bool:
    """False where ``W`` has a null vector with a normal component (relative 1e-9)."""
    _, singular, right = np.linalg.svd(system.delassus)
    null = right[singular <= 1e-10 * singular[0]]
    return bool(null.size == 0 or np.max(np.abs(null[:, 0::2])) <= 1e-9)


def poisson_two_phase(system: ContactSystem, method: str = "enumeration"
                      ) -> list[TwoPhaseSolution]:
    """The two-phase Poisson law for the ``m`` contacts of ``system`` (module docstring).

    Every answer by ``"enumeration"`` (a compression's every solution followed by each of
    its restitutions; answers with the same speeds after listed once), the one Lemke's
    algorithm reaches by ``"lemke"``. Contacts that do not approach take part too: the
    complementarity decides whether they take an impulse.
    """
    speed = system.speed_scale()
    delassus, approach = system.delassus, system.approach
    unique_split = normal_split_unique(system)
    answers: list[TwoPhaseSolution] = []
    for compression in solve_phase(delassus, approach, np.zeros(system.count), system.mu,
                                   speed, method):
        base = system.e * compression.impulses[0::2]
        for restitution in solve_phase(delassus, compression.velocities, base, system.mu,
                                       speed, method):
            answer = _assemble(system, compression, restitution, unique_split)
            if all(np.max(np.abs(answer.u_after - other.u_after)) > SAME_ANSWER * (
                    speed + float(np.max(np.abs(system.u)))) for other in answers):
                answers.append(answer)
    return answers


def _kinetic(system: ContactSystem, speeds) -> float:
    return 0.5 * float(speeds @ system.mass_matrix @ speeds)


def _assemble(system, compression, restitution, unique_split) -> TwoPhaseSolution:
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
        normal_split_unique=unique_split)
