"""Derived bounds for a body lying flat on two contacts whose answer is known by hand (exact
rationals): tests/theory/test_simultaneous.py (the flat box) and tests/run/test_references.py
(the flat-box scenario) compare the library's several-contact answers with it
(docs/verdicts.md, 'Same answers on every CPU').

The hand problem's inputs are exact (a :class:`HandProblem`: the mass, the inertia and the
contact rows as fractions; the speeds small integers); the library's floats are those inputs
rounded once. The library's straight-line arithmetic is replayed on
:class:`tests.error_bounds.Tracked` numbers (running error analysis, each IEEE operation
within u of its result), in the library's own order, from the exact inputs, each input
carrying its rounding: every replayed value is checked equal to the library's, bit for bit,
so its carried error bounds the library's distance from the exact answer. The mass matrix
must be diagonal (checked): LAPACK's LU of it has no swap and zero multipliers, so each
entry of ``M⁻¹ w`` is one division.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from tests.error_bounds import Tracked, U


@dataclass(frozen=True)
class HandProblem:
    """The exact inputs of a hand-worked flat face: ``mass`` and ``inertia`` (the diagonal
    of M, kg and kg m²) and per contact the exact rows ``(w_n, w_t)``."""

    mass: Fraction
    inertia: Fraction
    rows: tuple


def rounding(value, exact) -> float:
    """``|value − exact|`` (exact, then rounded up to a float: at most 2u relative above)."""
    return float(abs(Fraction(float(value)) - Fraction(exact))) * (1 + 4 * U)


def tracked_dot(a, b):
    """``Σ a_k b_k`` in index order (numpy's order on 3 terms; the tests check the value)."""
    total = a[0] * b[0]
    for x, y in zip(a[1:], b[1:]):
        total = total + x * y
    return total


def tracked_rows(system, hand):
    """The rows ``w_n``, ``w_t`` per contact as Tracked, each within its rounding of the
    hand problem's exact row (``hand.rows``: per contact, the exact ``(w_n, w_t)``)."""
    return [[[Tracked(float(x), rounding(x, exact)) for x, exact in zip(row, exact_row)]
             for row, exact_row in zip((system.wn[i], system.wt[i]), hand.rows[i])]
            for i in range(system.count)]


def tracked_inverse(system, hand):
    """``M⁻¹ w`` per contact and row (``[i][0]`` normal, ``[i][1]`` tangential) as Tracked,
    within their bound of the exact hand problem's: the mass matrix diagonal (checked), its
    inertia within its rounding of ``hand.inertia``, the rows of ``hand.rows``, the masses
    and speeds exact (checked); each value checked against the library's."""
    matrix = system.mass_matrix
    assert np.array_equal(matrix, np.diag(np.diag(matrix)))  # a diagonal M: LU is division
    inertia = float(matrix[2, 2])
    assert Fraction(float(matrix[0, 0])) == Fraction(float(matrix[1, 1])) == hand.mass
    assert all(Fraction(float(x)) == x for x in system.u)  # the hand speeds: small integers
    diagonal = [Tracked(float(matrix[0, 0])), Tracked(float(matrix[1, 1])),
                Tracked(inertia, rounding(inertia, hand.inertia))]
    # LAPACK's getrf on a diagonal matrix: no swap, zero multipliers, so getrs's solve is one
    # division per entry (the zeros' products are exact).
    inverse = [[[w / d for w, d in zip(row, diagonal)] for row in rows]
               for rows in tracked_rows(system, hand)]
    for i, columns in enumerate(inverse):
        assert [[x.value for x in column] for column in columns] == (
            system.inverse_rows[i].T.tolist())
    return inverse


def tracked_delassus(system, hand):
    """W's entries ``w_kᵀ M⁻¹ w_l`` (rows n0, t0, n1, t1 as the library orders them) and
    the approach speeds ``w_kᵀ u``, Tracked from the exact hand problem (tracked_inverse),
    each value checked equal to the library's."""
    inverse = tracked_inverse(system, hand)
    contact_rows = tracked_rows(system, hand)
    rows = [contact_rows[k // 2][k % 2] for k in range(2 * system.count)]
    columns = [inverse[k // 2][k % 2] for k in range(2 * system.count)]
    delassus = [[tracked_dot(row, column) for column in columns] for row in rows]
    assert [[x.value for x in row] for row in delassus] == system.delassus.tolist()
    approach = [tracked_dot(row, [Tracked(float(x)) for x in system.u]) for row in rows]
    assert [x.value for x in approach] == system.approach.tolist()
    return delassus, approach


def computed_residual_bound(system, impulses, hand):
    """A bound on each component of the exact ``W I + v^A − v^S`` (both contacts stick:
    ``v^S = (e|v_n^A|, 0, …)``) at the float impulses ``I``, from its evaluation on Tracked
    numbers (the entries of W and v^A within their bounds)."""
    delassus, approach = tracked_delassus(system, hand)
    targets = [Tracked(float(system.e[k // 2])) * -approach[k] if k % 2 == 0 else 0.0
               for k in range(2 * system.count)]
    residual = [tracked_dot(row, impulses.tolist()) + a - target
                for row, a, target in zip(delassus, approach, targets)]
    return np.array([abs(r.value) + r.error for r in residual])


def pgs_residual_bound(system, impulses, hand, tolerance=1e-13):
    """A bound on each component of the exact residual at PGS's last iterate, from its
    stopping criterion: each component's last update moved it by at most
    ``δ = tolerance × impulse scale`` and, unclamped, set its own computed residual to 0
    (a clamped one, ``|I_t| = μ I_n`` or ``I_n = 0``, says nothing of its residual: there the
    residual is evaluated a posteriori, computed_residual_bound), and the later updates of
    the sweep moved that residual by at most ``Σ_(l≠k) |W_kl| δ``; the computed residual is
    within the Tracked bound of its evaluation (W, v^A, the target and the dot product),
    and the update's own rounding
    (``I − r/W_kk``: a quotient and a difference) within ``2u (|I_k| + |r/W_kk|)`` of
    ``I_k``, i.e. ``|W_kk|`` times that in the residual."""
    step = tolerance * system.impulse_scale()
    normal, tangential = impulses[0::2], impulses[1::2]
    clamped = np.zeros(len(impulses), dtype=bool)
    clamped[0::2] = normal <= 0
    clamped[1::2] = np.abs(tangential) >= system.mu * normal
    evaluated_bound = computed_residual_bound(system, impulses, hand)
    delassus, approach = tracked_delassus(system, hand)
    size = 2 * system.count
    bound = np.empty(size)
    for k in range(size):
        moved = sum(abs(delassus[k][m].value) + delassus[k][m].error
                    for m in range(size) if m != k) * step
        target = (Tracked(float(system.e[k // 2])) * -approach[k] if k % 2 == 0
                  else Tracked(0.0))
        evaluated = tracked_dot(delassus[k], impulses.tolist()) + approach[k] - target
        diagonal = abs(delassus[k][k].value) + delassus[k][k].error
        update = 2 * U * (diagonal * (abs(impulses[k]) + step)
                                       + abs(evaluated.value) + evaluated.error)
        bound[k] = (evaluated_bound[k] if clamped[k]
                    else moved + 2 * evaluated.error + update)
    return bound


def delta_u_bound(system, impulses, residual, hand):
    """‖Δu(I) − Δu*‖₂ for the library's Δu of the float impulses ``I``: its rounding and
    M⁻¹'s (Tracked replay of ContactSystem.delta_u) plus ‖J⁺‖₂ ‖r‖₂, r the exact
    residual (within ``residual``): the exact d = M⁻¹Jᵀ I has J d − J Δu* = W I − (v^S −
    v^A) = r, and J (the four rows wn, wt, 4 × 3) has full column rank."""
    inverse = tracked_inverse(system, hand)
    delta_u = None
    for i in range(system.count):
        term = [x_n * float(impulses[2 * i]) + x_t * float(impulses[2 * i + 1])
                for x_n, x_t in zip(inverse[i][0], inverse[i][1])]
        delta_u = term if delta_u is None else [a + b for a, b in zip(delta_u, term)]
    assert [x.value for x in delta_u] == system.delta_u(impulses).tolist()
    jacobian = np.array([row for i in range(system.count)
                         for row in (system.wn[i], system.wt[i])])
    pseudo_inverse_norm = 1.0 / float(np.linalg.svd(jacobian, compute_uv=False)[-1])
    # (the singular value's own rounding: a relative O(u) of the bound, second order)
    return (float(np.linalg.norm([x.error for x in delta_u]))
            + pseudo_inverse_norm * float(np.linalg.norm(residual)))
