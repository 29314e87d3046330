"""One phase with the slip followed: taken in straight pieces, sliding contacts' friction
held against their slip, cut where a held slip reaches zero (for one contact, the paper's
process)."""

from __future__ import annotations

import numpy as np

from .enumeration import phase_by_enumeration
from .lemke import phase_by_lemke
from .phase import NORMAL_BASE, SIGN_TOLERANCE, STICK, PhaseSolution, distinct

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
    and the rest of the phase is solved again from that state. A contact that recedes at the
    piece's start and is owed no base takes no impulse in the piece; where the others drive
    it back to ``v_n = 0``, the piece is cut there too. For one contact the pieces
    are the process's forward-sliding segment ending at ``P_G`` (A58) and its stick or
    reverse-sliding segment: the paper's (25)–(51) in all five types.

    Every piece is solved by ``method`` (:data:`METHODS`); where it has several solutions,
    each is followed. Returns the phase's solutions (impulses summed over its pieces).
    """
    delassus, mu = np.asarray(delassus, dtype=float), np.asarray(mu, dtype=float)
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
        # A contact that recedes at the piece's start and is owed no base takes no impulse in
        # the piece: an impulse there would do positive work (docs/multi-contact.md, 'A
        # two-phase Poisson law for m contacts', its energy paragraph). If the others drive
        # it back to v_n = 0 inside the piece, the piece is cut there.
        receding = (velocities[0::2] > slip_zero) & (remaining <= 0.0) & (not capped)
        pieces = _pieces(delassus, velocities, remaining, mu, speed, sense, method, receding)
        if not pieces and sense.any():
            # Held friction cannot end the phase (the approach grows while the slip lasts,
            # the paper's h ≤ 0): the rest is one velocity-level problem, as for one contact
            # whose slip stops and then sticks (Type 1: the same end conditions).
            sense = np.zeros(count)
            pieces = _pieces(delassus, velocities, remaining, mu, speed, sense, method,
                             receding)
        for piece in pieces:
            end_slips = piece.velocities[1::2]
            crossing = np.zeros(2 * count, dtype=bool)
            crossing[1::2] = sense * end_slips < -slip_zero  # a held slip reverses
            crossing[0::2] = receding & (piece.velocities[0::2] < -slip_zero)  # comes back
            if not crossing.any():
                solution = PhaseSolution(given + piece.impulses, piece.velocities, piece.modes,
                                         cuts, not capped)
                if distinct(found, solution, speed, impulse_scale):
                    found.append(solution)
                continue
            # Where along the piece each crossing quantity (a held slip, a receding contact's
            # v_n) reaches zero; the first one cuts it.
            fractions = np.full(2 * count, np.inf)
            fractions[crossing] = velocities[crossing] / (velocities[crossing]
                                                          - piece.velocities[crossing])
            first = int(np.argmin(fractions))
            fraction = float(fractions[first])
            cut = velocities + fraction * (piece.velocities - velocities)
            cut[first] = 0.0  # the held slip, or the receding contact's v_n, is zero here
            branches.append((cut, given + fraction * piece.impulses, cuts + 1))
    return found


def _pieces(delassus, velocities, remaining, mu, speed, sense, method, receding):
    """The piece's solutions by ``method`` with the ``receding`` contacts left out (no
    impulse; their end velocities follow from the others' impulses through ``W``)."""
    taking = np.flatnonzero(~receding)
    if len(taking) == len(receding):  # every contact takes part: the method's own answers
        if method == "enumeration":
            return phase_by_enumeration(delassus, velocities, remaining, mu, speed, sense)
        piece = phase_by_lemke(delassus, velocities, remaining, mu, speed, sense)
        return [] if piece is None else [piece]
    if len(taking) == 0:  # nothing approaches and nothing is owed: the phase is over
        return [PhaseSolution(np.zeros(len(velocities)), velocities.copy(),
                              tuple((NORMAL_BASE, STICK) for _ in receding))]
    rows = np.ravel(np.column_stack([2 * taking, 2 * taking + 1]))
    reduced = (delassus[np.ix_(rows, rows)], velocities[rows], remaining[taking], mu[taking],
               speed, sense[taking])
    if method == "enumeration":
        found = phase_by_enumeration(*reduced)
    else:
        piece = phase_by_lemke(*reduced)
        found = [] if piece is None else [piece]
    pieces = []
    for piece in found:
        impulses = np.zeros(len(velocities))
        impulses[rows] = piece.impulses
        modes = [(NORMAL_BASE, STICK)] * len(receding)
        for k, i in enumerate(taking):
            modes[i] = piece.modes[k]
        pieces.append(PhaseSolution(impulses, velocities + delassus @ impulses, tuple(modes)))
    return pieces
