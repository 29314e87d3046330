"""One phase by enumeration: every stick / slide / separate mode of the ``m`` contacts, a
linear system each, all problems' modes solved in one batched call, every solution kept."""

from __future__ import annotations

import functools
import itertools

import numpy as np

from .phase import (
    NORMAL_ACTIVE,
    NORMAL_BASE,
    RANK_CUT,
    RESIDUAL_TOLERANCE,
    SIGN_TOLERANCE,
    SLIDE_NEGATIVE,
    SLIDE_POSITIVE,
    STICK,
    PhaseSolution,
    ScaledPhases,
    distinct,
    scaled_phases,
    unscaled,
)


def _modes_hold(problem: ScaledPhases, normal_modes, friction_modes, impulses, velocities):
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


def _mode_systems(problem: ScaledPhases, normal_modes, friction_modes):
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
    problem = scaled_phases(delassus, start, base, mu, speed, sense)
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
        candidate = unscaled(problem, row, solutions[row, k], velocities[row, k],
                              zip(normal_modes[k], friction_modes[k]))
        if distinct(answers[row], candidate, problem.speed[row], problem.impulse[row]):
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
