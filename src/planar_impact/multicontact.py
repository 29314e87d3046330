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

Both phases are one problem with a base normal impulse ``b`` (0 for the compression,
``e P_nc`` for the restitution), solved two independent ways:
:func:`phase_by_enumeration` (every stick / slide / separate mode, a linear system each, all
solutions kept) and :func:`phase_by_lemke` (the phase as a linear complementarity problem in
the planar friction cone's two edges, Lemke's complementary pivoting with a lexicographic
ratio test). ``W`` may be singular (a flat face: 4 constraints on 3 speeds): velocities are
then unique where the impulse split is not, and the two methods are compared on velocities.

Coulomb's law at a phase's end only is not the paper's process where the slip reverses
inside a phase (its Types 3 and 4). So by default each phase follows the slip
(:func:`phase_following_slip`): it is taken in straight pieces, sliding contacts' friction
held against their slip, cut where a held slip reaches zero. For one contact this is the
paper's process, and the law equals ``solve(..., law="poisson")`` in all five types;
``follow_slip=False`` gives one velocity-level problem per phase (equal in Types 1, 2, 5
only). docs/multi-contact.md, 'A two-phase Poisson law for m contacts'.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import numpy as np

from .errors import ImpactInputError
from .simultaneous import ContactSystem, contact_system, random_two_contact_system

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
    #: Following the slip: how many times the phase was cut, and False where it was cut
    #: :data:`CUTS_PER_CONTACT` times per contact and its rest was one velocity-level problem.
    cuts: int = 0
    slip_followed_to_end: bool = True


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
    """Phases of ``N`` problems with ``m`` contacts each, in units where each problem's
    speed scale and its impulse are 1 (tolerances are then plain numbers)."""

    delassus: np.ndarray  # (N, 2m, 2m): W / w_min
    start: np.ndarray  # (N, 2m): v_start / V
    base: np.ndarray  # (N, m): b / (V / w_min)
    mu: np.ndarray  # (N, m)
    speed: np.ndarray  # (N,): V
    impulse: np.ndarray  # (N,): V / w_min
    sense: np.ndarray  # (N, m): +1/−1 friction held against that slip, 0 free


def _scaled(delassus, start, base, mu, speed, sense=None) -> _Scaled:
    """The ``N`` phases scaled; arguments as :func:`phases_by_enumeration`'s."""
    delassus = np.asarray(delassus, dtype=float)
    w_min = np.min(np.diagonal(delassus, axis1=-2, axis2=-1), axis=-1)
    if not np.all(w_min > 0):
        raise ImpactInputError(f"delassus: diagonal must be positive, smallest is "
                               f"{float(np.min(w_min))}")
    speed = np.asarray(speed, dtype=float)
    if not np.all(speed > 0):
        raise ImpactInputError(f"speed: must be positive, got {float(np.min(speed))}")
    impulse = speed / w_min
    mu = np.asarray(mu, dtype=float)
    sense = np.zeros_like(mu) if sense is None else np.asarray(sense, dtype=float)
    return _Scaled(delassus / w_min[:, None, None], np.asarray(start) / speed[:, None],
                   np.asarray(base, dtype=float) / impulse[:, None], mu, speed, impulse, sense)


def _modes_hold(problem: _Scaled, normal_modes, friction_modes, impulses, velocities):
    """``(N, K)``: whether the phase's inequalities hold at mode ``k``'s candidate (scaled
    units): ``Λ ≥ 0``, ``v_n ≥ 0`` where ``Λ = 0``, the cone where sticking, the slip's sign
    where sliding."""
    tolerance = SIGN_TOLERANCE
    normal, tangential = impulses[..., 0::2], impulses[..., 1::2]  # (N, K, m)
    vn, vt = velocities[..., 0::2], velocities[..., 1::2]
    base, mu = problem.base[:, None, :], problem.mu[:, None, :]
    holds = normal >= base - tolerance
    holds &= (normal_modes == NORMAL_ACTIVE) | (vn >= -tolerance)
    held = problem.sense[:, None, :] != 0  # friction held: at the cone's edge by construction
    holds &= held | (friction_modes != STICK) | (np.abs(tangential) <= mu * normal + tolerance)
    holds &= held | (friction_modes != SLIDE_POSITIVE) | (vt >= -tolerance)
    holds &= held | (friction_modes != SLIDE_NEGATIVE) | (vt <= tolerance)
    return holds.all(axis=-1)


def _mode_systems(problem: _Scaled, normal_modes, friction_modes):
    """Per problem and mode (the ``(K, m)`` mode codes) the linear system: 2m equations in
    the 2m scaled impulses, ``(N, K, 2m, 2m)`` and ``(N, K, 2m)``."""
    kinds, count = normal_modes.shape
    problems = problem.delassus.shape[0]
    matrices = np.zeros((problems, kinds, 2 * count, 2 * count))
    rhs = np.zeros((problems, kinds, 2 * count))
    for i in range(count):
        n, t = 2 * i, 2 * i + 1
        base = normal_modes[:, i] == NORMAL_BASE
        active, stick = ~base, friction_modes[:, i] == STICK
        matrices[:, base, n, n] = 1.0  # P_n = b
        rhs[:, base, n] = problem.base[:, i, None]
        matrices[:, active, n] = problem.delassus[:, None, n]  # v_n = 0
        rhs[:, active, n] = -problem.start[:, n, None]
        matrices[:, stick, t] = problem.delassus[:, None, t]  # v_t = 0
        rhs[:, stick, t] = -problem.start[:, t, None]
        matrices[:, ~stick, t, t] = 1.0  # P_t = ∓μ P_n, against the end slip
        sense = np.where(friction_modes[~stick, i] == SLIDE_POSITIVE, 1.0, -1.0)
        matrices[:, ~stick, t, n] = problem.mu[:, i, None] * sense
        held = problem.sense[:, i] != 0  # every mode: P_t = −sense μ P_n
        matrices[held, :, t] = 0.0
        matrices[held, :, t, t] = 1.0
        matrices[held, :, t, n] = (problem.sense[held, i] * problem.mu[held, i])[:, None]
        rhs[held, :, t] = 0.0
    return matrices, rhs


def _unscaled(problem: _Scaled, row: int, impulses, velocities, modes) -> PhaseSolution:
    return PhaseSolution(impulses * problem.impulse[row], velocities * problem.speed[row],
                         tuple((int(a), int(b)) for a, b in modes))


def _distinct(found: list[PhaseSolution], candidate: PhaseSolution, speed, impulse) -> bool:
    for other in found:
        if np.max(np.abs(other.velocities - candidate.velocities)) > SAME_ANSWER * speed:
            continue
        normals = np.abs(other.impulses[0::2] - candidate.impulses[0::2])
        if np.max(normals) <= SAME_ANSWER * impulse:
            return False
    return True


def phases_by_enumeration(delassus, start, base, mu, speed, sense=None
                          ) -> list[list[PhaseSolution]]:
    """Every solution of each of ``N`` phases with ``m`` contacts, by the ``6^m`` modes
    (normal: ``Λ = 0`` or ``v_n = 0``; friction: stick, slide with ``v_t ≥ 0``, slide with
    ``v_t ≤ 0``), all problems' modes solved in one batched call.

    ``delassus`` ``(N, 2m, 2m)``; ``start`` ``(N, 2m)`` the contact velocities at the
    phase's start; ``base`` ``(N, m)`` the normal impulse each contact takes at least;
    ``mu`` ``(N, m)``; ``speed`` ``(N,)`` positive speed scales (the largest approach
    speed); ``sense`` ``(N, m)``, optional: where ±1, that contact's friction is held at
    ``P_t = ∓μ P_n`` (against a slip of that sign) whatever its end slip. A singular mode
    is solved by the pseudo-inverse and kept when consistent; where a mode's solutions are
    a family, its minimum-norm member is tested, and the family's ends are other modes (a
    friction or normal bound reached). Answers with the same velocities and normal impulses
    are listed once.
    """
    problem = _scaled(delassus, start, base, mu, speed, sense)
    problems, count = problem.mu.shape
    normal_modes, friction_modes = _every_mode(count)
    matrices, rhs = _mode_systems(problem, normal_modes, friction_modes)
    solutions = np.einsum("nkij,nkj->nki", np.linalg.pinv(matrices, rcond=RANK_CUT), rhs)
    residuals = np.max(np.abs(np.einsum("nkij,nkj->nki", matrices, solutions) - rhs), axis=-1)
    velocities = problem.start[:, None, :] + np.einsum("nij,nkj->nki", problem.delassus,
                                                        solutions)
    kept = residuals <= RESIDUAL_TOLERANCE * (1.0 + np.abs(rhs).max(axis=-1))
    kept &= _modes_hold(problem, normal_modes, friction_modes, solutions, velocities)
    answers: list[list[PhaseSolution]] = [[] for _ in range(problems)]
    for row, k in zip(*np.nonzero(kept)):
        candidate = _unscaled(problem, row, solutions[row, k], velocities[row, k],
                              zip(normal_modes[k], friction_modes[k]))
        if _distinct(answers[row], candidate, problem.speed[row], problem.impulse[row]):
            answers[row].append(candidate)
    return answers


def phase_by_enumeration(delassus, start, base, mu, speed, sense=None) -> list[PhaseSolution]:
    """:func:`phases_by_enumeration` of one phase (``delassus`` ``(2m, 2m)``, ``start``
    ``(2m,)``, ``base``, ``mu``, ``sense`` ``(m,)``, ``speed`` a positive float)."""
    return phases_by_enumeration(
        np.asarray(delassus, dtype=float)[None], np.asarray(start, dtype=float)[None],
        np.asarray(base, dtype=float)[None], np.asarray(mu, dtype=float)[None], [speed],
        None if sense is None else np.asarray(sense, dtype=float)[None])[0]


@functools.lru_cache(maxsize=8)
def _every_mode(count: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``6^count`` modes as two ``(6^count, count)`` arrays of normal and friction codes."""
    per_contact = list(itertools.product((NORMAL_BASE, NORMAL_ACTIVE),
                                         (STICK, SLIDE_POSITIVE, SLIDE_NEGATIVE)))
    modes = np.array(list(itertools.product(per_contact, repeat=count)), dtype=np.int8)
    modes.setflags(write=False)
    return modes[:, :, 0], modes[:, :, 1]


def phase_lcp(delassus, start, base, mu, sense=None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The phase as an LCP ``w = M z + q ≥ 0, z ≥ 0, zᵀw = 0`` (Anitescu & Potra's
    velocity-level form; in the plane the friction cone has two edges, so it is exact).

    ``z = (Λ, β⁺, β⁻, λ)``: ``P_n = b + Λ`` per contact; for a contact with free friction
    (``sense`` 0) ``P_t = β⁺ − β⁻`` and ``λ`` its slip speed, ``w = (v_n, λ + v_t, λ − v_t,
    μ P_n − β⁺ − β⁻)``; a contact whose friction is held (``sense`` ±1) has
    ``P_t = ∓μ P_n`` and no ``β⁺, β⁻, λ``. Returns ``(M, q, G, P_0)`` with the impulses
    ``P = P_0 + G z[:m + 2f]`` (``f`` free contacts).
    """
    delassus, start = np.asarray(delassus, dtype=float), np.asarray(start, dtype=float)
    base, mu = np.asarray(base, dtype=float), np.asarray(mu, dtype=float)
    count = len(mu)
    sense = np.zeros(count) if sense is None else np.asarray(sense, dtype=float)
    free = np.flatnonzero(sense == 0)
    f = len(free)
    held = sense * mu  # P_t = −held·P_n where held ≠ 0
    constant = np.zeros(2 * count)
    constant[0::2], constant[1::2] = base, -held * base
    mapping = np.zeros((2 * count, count + 2 * f))
    mapping[np.arange(0, 2 * count, 2), np.arange(count)] = 1.0
    mapping[np.arange(1, 2 * count, 2), np.arange(count)] = -held
    mapping[2 * free + 1, count + np.arange(f)] = 1.0
    mapping[2 * free + 1, count + f + np.arange(f)] = -1.0
    response = delassus @ mapping  # velocities per unit of (Λ, β⁺, β⁻)
    velocity = start + delassus @ constant
    normal_rows, slip_rows = response[0::2], response[2 * free + 1]
    size = count + 3 * f
    matrix = np.zeros((size, size))
    q = np.zeros(size)
    matrix[:count, :count + 2 * f] = normal_rows
    q[:count] = velocity[0::2]
    plus, minus, cone = (slice(count + k * f, count + (k + 1) * f) for k in range(3))
    matrix[plus, :count + 2 * f], q[plus] = slip_rows, velocity[2 * free + 1]
    matrix[minus, :count + 2 * f], q[minus] = -slip_rows, -velocity[2 * free + 1]
    matrix[plus, cone] = matrix[minus, cone] = np.eye(f)
    matrix[cone, free] = np.diag(mu[free])
    matrix[cone, plus] = matrix[cone, minus] = -np.eye(f)
    q[cone] = mu[free] * base[free]
    return matrix, q, mapping, constant


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
        factors = tableau[:, entering].copy()
        factors[row] = 0.0
        tableau -= np.outer(factors, tableau[row])
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


def phase_by_lemke(delassus, start, base, mu, speed, sense=None) -> PhaseSolution | None:
    """One solution of one phase (arguments as :func:`phase_by_enumeration`'s) by
    :func:`lemke` on :func:`phase_lcp`, scaled to unit speed and impulse; None where
    Lemke's algorithm ends on a ray."""
    problem = _scaled(np.asarray(delassus, dtype=float)[None], np.asarray(start)[None],
                      np.asarray(base, dtype=float)[None], np.asarray(mu, dtype=float)[None],
                      [speed], None if sense is None else np.asarray(sense, dtype=float)[None])
    delassus, start, base, mu, sense = (problem.delassus[0], problem.start[0],
                                        problem.base[0], problem.mu[0], problem.sense[0])
    count = len(mu)
    matrix, q, mapping, constant = phase_lcp(delassus, start, base, mu, sense)
    z = lemke(matrix, q)
    if z is None:
        return None
    impulses = constant + mapping @ z[:mapping.shape[1]]
    velocities = start + delassus @ impulses
    modes = []
    for i in range(count):
        normal_mode = NORMAL_ACTIVE if z[i] > SIGN_TOLERANCE else NORMAL_BASE
        vt = velocities[2 * i + 1]
        friction_mode = (SLIDE_POSITIVE if vt > SIGN_TOLERANCE else
                         SLIDE_NEGATIVE if vt < -SIGN_TOLERANCE else STICK)
        modes.append((normal_mode, friction_mode))
    return _unscaled(problem, 0, impulses, velocities, modes)


#: Most times a phase is cut where a held slip reaches zero, per contact (plus a few):
#: two contacts can take turns (one's slip stops while the other slides, then the other way
#: round), with cuts that shrink geometrically; past this, the rest of the phase is one
#: velocity-level problem, and the answer says so (``slip_followed_to_end``).
CUTS_PER_CONTACT = 16
#: Most pieces one phase solves, over all its branches (a piece with several solutions
#: branches): past this, every open branch ends at velocity level, as past the cuts.
PIECES_PER_PHASE = 64


def phase_following_slip(delassus, start, base, mu, speed, method: str = "enumeration"
                         ) -> list[PhaseSolution]:
    """One phase with the slip followed, as the paper's process follows it for one contact.

    The phase is taken in straight pieces. In each piece a contact that slides at its start
    has its friction held against that slip (``P_t = −μ P_n sign(v_t)``), a contact that does
    not slide is free (stick, or slide either way, decided at the piece's end), and the
    piece solves what remains of the phase (the base normal impulse not yet given, then the
    complementarity). Along the piece the speeds are linear in the fraction of its impulse;
    where a held slip reaches zero first, the piece is cut there, that slip is set to zero,
    and the rest of the phase is solved again from that state. For one contact the pieces
    are the process's forward-sliding segment ending at ``P_G`` (A58) and its stick or
    reverse-sliding segment: the paper's (25)–(51) in all five types.

    Every piece is solved by ``method`` (:data:`METHODS`); where it has several solutions,
    each is followed. Returns the phase's solutions (impulses summed over its pieces).
    """
    delassus = np.asarray(delassus, dtype=float)
    count = len(mu)
    slip_zero = SIGN_TOLERANCE * speed
    limit = CUTS_PER_CONTACT * count + 4
    branches = [(np.asarray(start, dtype=float), np.zeros(2 * count), 0)]
    found: list[PhaseSolution] = []
    impulse_scale = speed / float(np.min(np.diag(delassus)))
    solved = 0
    while branches:
        velocities, given, cuts = branches.pop()
        solved += 1
        slips = velocities[1::2]
        sense = np.where(np.abs(slips) > slip_zero, np.sign(slips), 0.0)
        remaining = np.maximum(np.asarray(base, dtype=float) - given[0::2], 0.0)
        capped = cuts >= limit or solved > PIECES_PER_PHASE
        if capped:
            sense = np.zeros(count)
        pieces = _pieces(delassus, velocities, remaining, mu, speed, sense, method)
        if not pieces and sense.any():
            # Held friction cannot end the phase (the approach grows while the slip lasts,
            # the paper's h ≤ 0): the rest is one velocity-level problem, as for one contact
            # whose slip stops and then sticks (Type 1: the same end conditions).
            sense = np.zeros(count)
            pieces = _pieces(delassus, velocities, remaining, mu, speed, sense, method)
        for piece in pieces:
            end_slips = piece.velocities[1::2]
            crossing = (sense * end_slips < -slip_zero)
            if not crossing.any():
                solution = PhaseSolution(given + piece.impulses, piece.velocities, piece.modes,
                                         cuts, not capped)
                if _distinct(found, solution, speed, impulse_scale):
                    found.append(solution)
                continue
            fractions = np.where(crossing, slips / np.where(crossing, slips - end_slips, 1.0),
                                 np.inf)
            first = int(np.argmin(fractions))
            fraction = float(fractions[first])
            cut = velocities + fraction * (piece.velocities - velocities)
            cut[2 * first + 1] = 0.0  # the held slip has reached zero here
            branches.append((cut, given + fraction * piece.impulses, cuts + 1))
    return found


def _pieces(delassus, velocities, remaining, mu, speed, sense, method):
    if method == "enumeration":
        return phase_by_enumeration(delassus, velocities, remaining, mu, speed, sense)
    piece = phase_by_lemke(delassus, velocities, remaining, mu, speed, sense)
    return [] if piece is None else [piece]


def _check_method(method: str) -> str:
    if method not in METHODS:
        raise ImpactInputError(f"method: {method!r}; allowed: {', '.join(METHODS)}")
    return method


# ------------------------------------------------------------------------------------------
# The two-phase law
# ------------------------------------------------------------------------------------------
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
    _check_method(method)
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
    for compression in phase_following_slip(system.delassus, system.approach,
                                            np.zeros(system.count), system.mu, speed, method):
        base = system.e * compression.impulses[0::2]
        for restitution in phase_following_slip(system.delassus, compression.velocities, base,
                                                system.mu, speed, method):
            answer = _assemble(system, compression, restitution, unique_split)
            if all(np.max(np.abs(answer.u_after - other.u_after)) > scale for other in answers):
                answers.append(answer)
    return answers


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


# ------------------------------------------------------------------------------------------
# Measurements on random problems (docs/multi-contact.md quotes them)
# ------------------------------------------------------------------------------------------
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
    unique, and how many first answers are more than 1e-6 of the speeds from every
    Newton–Coulomb solution (``newton-coulomb-apart``)."""
    from .simultaneous import newton_coulomb_solutions

    rng = np.random.default_rng(seed)
    table = {}
    for family in ("generic", "body", "flat"):
        systems = [random_flat_face(rng) if family == "flat"
                   else random_two_contact_system(rng, family) for _ in range(problems)]
        counts = dict.fromkeys(("0", "1", "2+", "lemke-agrees", "lemke-ray", "lemke-other",
                                "gains", "split-unique", "newton-coulomb-apart",
                                "slip-not-followed-to-end"), 0)
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
    from . import solver

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


if __name__ == "__main__":  # python -m planar_impact.multicontact [problems] [seed] [plain]
    import sys

    arguments = [int(a) for a in sys.argv[1:3]]
    plain = sys.argv[3:4] == ["plain"]  # one velocity-level problem per phase
    for family, counts in measure(*arguments, follow_slip=not plain).items():
        print(f"{family}: {counts}")
