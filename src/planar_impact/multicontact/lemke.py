"""One phase by Lemke's algorithm: the phase as a linear complementarity problem in the
planar friction cone's two edges (Anitescu & Potra's velocity-level form), solved by
complementary pivoting with a lexicographic ratio test."""

from __future__ import annotations

import numpy as np

from .phase import (
    NORMAL_ACTIVE,
    NORMAL_BASE,
    SIGN_TOLERANCE,
    SLIDE_NEGATIVE,
    SLIDE_POSITIVE,
    STICK,
    PhaseSolution,
    scaled_phases,
    unscaled,
)


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
    problem = scaled_phases(np.asarray(delassus, dtype=float)[None], np.asarray(start)[None],
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
    return unscaled(problem, 0, impulses, velocities, modes)
