"""One phase of the two-phase law, as both methods see it: the mode codes, the tolerances,
a phase's answer (:class:`PhaseSolution`), and the scaling to unit speed and impulse in which
the tolerances are plain numbers (the package's docstring has the law)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ImpactInputError

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
    #: Following the slip: False where the pieces' sum broke the phase's complementarity (a
    #: contact that took impulse in one piece receded by the phase's end) and the phase was
    #: solved instead as one velocity-level problem (docs/multi-contact.md, 'A two-phase
    #: Poisson law for m contacts').
    slip_followed: bool = True



@dataclass(frozen=True)
class ScaledPhases:
    """Phases of ``N`` problems with ``m`` contacts each, in units where each problem's
    speed scale and its impulse are 1 (tolerances are then plain numbers)."""

    delassus: np.ndarray  # (N, 2m, 2m): W / w_min
    start: np.ndarray  # (N, 2m): v_start / V
    base: np.ndarray  # (N, m): b / (V / w_min)
    mu: np.ndarray  # (N, m)
    speed: np.ndarray  # (N,): V
    impulse: np.ndarray  # (N,): V / w_min
    sense: np.ndarray  # (N, m): +1/−1 friction held against that slip, 0 free


def scaled_phases(delassus, start, base, mu, speed, sense=None) -> ScaledPhases:
    """The ``N`` phases scaled; arguments as :func:`.enumeration.phases_by_enumeration`'s."""
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
    return ScaledPhases(delassus / w_min[:, None, None], np.asarray(start) / speed[:, None],
                        np.asarray(base, dtype=float) / impulse[:, None], mu, speed, impulse, sense)


def unscaled(problem: ScaledPhases, row: int, impulses, velocities, modes) -> PhaseSolution:
    """Problem ``row``'s answer back in the caller's units."""
    return PhaseSolution(impulses * problem.impulse[row], velocities * problem.speed[row],
                         tuple((int(a), int(b)) for a, b in modes))


def distinct(found: list[PhaseSolution], candidate: PhaseSolution, speed, impulse) -> bool:
    """Whether ``candidate`` differs from every answer in ``found`` (:data:`SAME_ANSWER`)."""
    for other in found:
        if np.max(np.abs(other.velocities - candidate.velocities)) > SAME_ANSWER * speed:
            continue
        normals = np.abs(other.impulses[0::2] - candidate.impulses[0::2])
        if np.max(normals) <= SAME_ANSWER * impulse:
            return False
    return True


def complementary(solution: PhaseSolution, base, speed: float, impulse: float) -> bool:
    """Whether a phase's total impulses and end velocities are complementary: no contact
    both takes more than its base normal impulse and recedes at the phase's end (beyond
    :data:`SIGN_TOLERANCE` of the speed and impulse scales)."""
    owed = solution.impulses[0::2] - np.asarray(base, dtype=float)
    receding = solution.velocities[0::2] > SIGN_TOLERANCE * speed
    return not bool(np.any(receding & (owed > SIGN_TOLERANCE * impulse)))


def check_method(method: str) -> str:
    """``method`` if it is one of :data:`METHODS`; else a clear error."""
    if method not in METHODS:
        raise ImpactInputError(f"method: {method!r}; allowed: {', '.join(METHODS)}")
    return method
