"""The collision types' formulas as a map of the impulses, and its fixed points: the solve
of one combination of types in the paper's proposal after (75).

A combination fixes each contact's collision type and tangent orientation. Contact ``i``'s
impulses are then its type's formulas (:func:`type_impulses`) at its own ``v^A(i)``
(``coupling="literal"``, the paper's) or at its effective approach
``v^A(i) + Σ_{j≠i} W_ij I^(j)`` (``coupling="effective"``, the named extension).
:func:`contact_map` is that map for many combinations at once, :func:`fixed_points` solves
``I = map(I)`` for each by Newton's method (docs/multi-contact.md, 'The paper's proposal').
"""

from __future__ import annotations

import math

import numpy as np

from .. import laws
from .system import (
    FIXED_POINT_TOLERANCE,
    ROUNDING_RESIDUAL,
    SEPARATING,
    TYPE_LAWS,
    lstsq_rows,
)


def type_impulses(law, terms, e, ctype):
    """``(I_n, I_t)`` of a contact by the formulas of collision type ``ctype``, in a frame
    with ``v_t ≥ 0`` (not checked: the coherence test does). Affine in ``(v_n, v_t)`` for
    Poisson and Newton; homogeneous of degree 1 for the paper's Stronge.

    ``terms``: a :class:`~planar_impact.laws.ContactTerms` of numpy scalars or arrays
    (``ctype`` then an array of types). Every element takes the same operations in the same
    order, so a batch gives each element's scalar answer bit for bit. Call under
    ``np.errstate(all="ignore")``.
    """
    if law == "poisson":  # (26), (29), (36), (44), (49)
        return laws.poisson_impulses(terms, e, ctype)
    if law == "stronge-paper":  # e_i by (64), (67), (70), (73), (74), then Poisson
        e_i = laws.stronge_paper_restitution(terms, e, ctype)
        return laws.poisson_impulses(terms, e_i, ctype)
    # Newton (Part A): docs/theory.md, 'Newton's law', two phases with the type forced.
    mnt, mtt, mu = terms.mnt, terms.mtt, terms.mu
    vn_abs, target = terms.vn_abs, e * terms.vn_abs  # ends where v_n = e|v_n^A| (A30)
    forward = ctype == laws.NEWTON_FORWARD
    forward_normal = (target + vn_abs) / terms.h  # forward sliding throughout
    p_g = terms.vt / terms.g  # (A58), with v_t^A for the misprinted v_n^A
    vn_g = terms.h * p_g - vn_abs
    sticks = ctype == laws.NEWTON_STICK
    slope_n = laws.where(sticks, terms.delta / mtt, terms.q)
    slope_t = laws.where(sticks, -mnt / mtt, mu)
    normal = p_g + (target - vn_g) / slope_n
    return (laws.where(forward, forward_normal, normal),
            laws.where(forward, -mu * forward_normal, -mu * p_g + slope_t * (normal - p_g)))


#: How a type's formulas see the other contacts (docs/multi-contact.md, 'The paper's proposal').
LITERAL, EFFECTIVE = "literal", "effective"


#: The paper's proposal first (the default), then the named extension.
COUPLINGS = (LITERAL, EFFECTIVE)


def contact_map(system, law, types, signs, coupling="effective"):
    """The map ``I ↦ (forced impulses of every contact at its effective approach)`` for many
    combinations at once; with ``coupling="literal"`` every contact sees its own ``v^A`` and
    the map is constant.

    ``types``, ``signs`` (``(N, m)``): one combination per row. The returned
    :class:`ContactMap` maps rows of impulses ``(R, 2m)``, row ``r`` by combination
    ``rows[r]``. Each element takes the operations of one contact's formulas
    (:func:`type_impulses` at :meth:`ContactSystem.effective_approach`) in the same order:
    a combination's answer does not depend on the batch it is in, bit for bit.
    """
    if law not in TYPE_LAWS:  # the kernels below are those laws'
        raise ValueError(f"contact_map serves {', '.join(TYPE_LAWS)}, not {law!r}")
    return ContactMap(system, law, types, signs, coupling)


class ContactMap:
    """:func:`contact_map`'s map. All contacts' formulas run in one batched call of
    :func:`type_impulses` (the contact's terms, μ and e given per element), so that numpy's
    fixed cost per operation is paid once per evaluation, not once per contact."""

    def __init__(self, system, law, types, signs, coupling):
        self.system, self.law, self.coupling = system, law, coupling
        self.signs = signs
        self.separating = types == SEPARATING
        self.safe_types = np.where(self.separating, 1, types)
        count = system.count
        # Per contact: m_nn, m_nt, m_tt (A20), μ, Δ (A20), e; one column per contact.
        self.constants = np.array([[*system.single_terms(i), system.mu[i], system.deltas[i],
                                    system.e[i]] for i in range(count)]).T
        # v^A(i) and the other contacts' blocks of W per contact, in the order
        # effective_approach sums them, as floats (the same products as the arrays' entries).
        self.approach, self.blocks = system._plain

    def __call__(self, impulses, rows):
        """The map at ``impulses`` ``(R, 2m)``, row ``r`` by combination ``rows[r]``."""
        count = self.system.count
        forced = self.forced([impulses] * count, [rows] * count)
        out = np.empty_like(impulses)
        for i, values in enumerate(forced):
            out[:, 2 * i:2 * i + 2] = values
        return out

    def forced(self, points, rows):
        """Contact ``i``'s forced ``(I_n, I_t)`` at the impulses ``points[i]`` ``(R_i, 2m)``
        (row ``r`` by combination ``rows[i][r]``), for every contact ``i`` in one batch:
        a list of ``(R_i, 2)`` arrays."""
        approaches = []
        for i in range(self.system.count):
            impulses = points[i]
            if self.coupling == LITERAL:
                impulses = np.zeros_like(impulses)
            approaches.append(self.effective(i, [impulses[:, k] for k in range(impulses.shape[1])],
                                             len(impulses)))
        return self.at_approach(approaches, rows)

    def effective(self, i, columns, length):
        """Contact ``i``'s effective approach ``(v_n, v_t)`` from the impulse columns
        ``columns`` (``columns[k]`` the ``k``-th impulse component, arrays of one shape):
        ``v^A(i) + Σ_{j≠i} W_ij I^(j)``, summed as :meth:`ContactSystem.effective_approach`."""
        vn, vt = self.approach[i]
        if not self.blocks[i]:  # no other contact: v^A(i) on every element
            return np.full(length, vn), np.full(length, vt)
        for j, (w_nn, w_nt, w_tn, w_tt) in self.blocks[i]:
            normal, tangential = columns[2 * j], columns[2 * j + 1]
            # v + (…) with v the scalar v^A(i) first: the same additions as np.full's array.
            vn = vn + (w_nn * normal + w_nt * tangential)
            vt = vt + (w_tn * normal + w_tt * tangential)
        return vn, vt

    def at_approach(self, approaches, rows):
        """Contact ``i``'s forced ``(I_n, I_t)`` at the effective approach ``approaches[i]``
        (two arrays, any shape, flattened in C order) of the combinations ``rows[i]`` (one per
        flattened element), for every contact in one batch of :func:`type_impulses`: a list
        of ``(size_i, 2)`` arrays."""
        vn_parts, vt_parts, sign_parts, type_parts, separating_parts = [], [], [], [], []
        for i, ((vn, vt), contact_rows) in enumerate(zip(approaches, rows)):
            vn_parts.append(np.ravel(vn))
            vt_parts.append(np.ravel(vt))
            sign_parts.append(self.signs[contact_rows, i])
            type_parts.append(self.safe_types[contact_rows, i])
            separating_parts.append(self.separating[contact_rows, i])
        sizes = [len(part) for part in vn_parts]
        mnn, mnt, mtt, mu, delta, e = np.repeat(self.constants, sizes, axis=1)
        sign = np.concatenate(sign_parts)
        with np.errstate(all="ignore"):
            terms = laws.ContactTerms(mnn, sign * mnt, mtt, np.concatenate(vn_parts),
                                      sign * np.concatenate(vt_parts), mu, delta)
            normal, tangential = type_impulses(self.law, terms, e, np.concatenate(type_parts))
        separating = np.concatenate(separating_parts)
        values = np.column_stack([np.where(separating, 0.0, normal),
                                  np.where(separating, 0.0, sign * tangential)])
        return np.split(values, np.cumsum(sizes)[:-1])


def map_and_jacobian(mapping, impulses, rows, step):
    """``mapping`` at ``impulses`` (rows ``(R, 2m)``) and the Jacobian of ``I − mapping(I)``
    there by central differences of half-width ``step`` (per row), from one batched call.

    Column ``k`` is ``e_k − (map(I + step e_k) − map(I − step e_k)) / (2 step)``, formed as
    :func:`fixed_points` needs it. Contact ``i``'s impulses
    depend on the other contacts' only (its effective approach, (75)): a shift of its own
    two components leaves its inputs, and so its outputs, unchanged bit for bit, and its
    difference there is ``map(I) − map(I)`` (0, or NaN where the map is not finite); only
    the other contacts' shifts are evaluated. The shifted points are never built whole:
    contact ``i``'s effective approach takes, per impulse component, the column of every
    evaluation (``I``, then ``I ± step e_k`` for each other column ``k``) as one array, with
    the values ``I + step e_k`` has (``I_c + 0.0`` in the columns ``c ≠ k``).
    """
    number, size = impulses.shape
    count = size // 2
    others = [[k for k in range(size) if k // 2 != i] for i in range(count)]
    plain = impulses.T  # [column, row]
    # I ± step e_k off column k: I + 0.0 (−0.0 + 0.0 is +0.0) and I − 0.0 (which is I).
    unshifted = plain + 0.0
    raised, lowered = plain + step, plain - step
    approaches, tiled = [], []
    for i, columns in enumerate(others):
        shifts = len(columns)
        stacked = []
        for c in range(size):
            if c // 2 == i:  # contact i's own components do not enter its approach
                stacked.append(None)
                continue
            # Evaluation 0 at I, 1..n at I + step e_k, n+1..2n at I − step e_k (k in columns).
            evaluations = np.empty((1 + 2 * shifts, number))
            evaluations[0] = plain[c]
            evaluations[1:1 + shifts] = unshifted[c]
            evaluations[1 + shifts:] = plain[c]
            where_c = columns.index(c)
            evaluations[1 + where_c] = raised[c]
            evaluations[1 + shifts + where_c] = lowered[c]
            stacked.append(evaluations)
        if mapping.coupling == LITERAL:  # as forced: every contact sees its own v^A
            stacked = [None if block is None else np.zeros_like(block) for block in stacked]
        approaches.append(mapping.effective(i, stacked, (1 + 2 * shifts) * number))
        tiled.append(np.tile(rows, 1 + 2 * shifts))
    forced = mapping.at_approach(approaches, tiled)
    mapped = np.empty_like(impulses)
    differences = np.empty((number, size, size))  # [row, output, column k]
    for i, (columns, values) in enumerate(zip(others, forced)):
        values = values.reshape(1 + 2 * len(columns), number, 2)
        mapped[:, 2 * i:2 * i + 2] = values[0]
        shifted = values[1:1 + len(columns)] - values[1 + len(columns):]  # [k, row, output]
        differences[:, 2 * i:2 * i + 2, columns] = shifted.transpose(1, 2, 0)
        differences[:, 2 * i:2 * i + 2, 2 * i:2 * i + 2] = (values[0] - values[0])[:, :, None]
    jacobian = np.eye(size) - differences / (2 * step)[:, None, None]
    return mapped, jacobian


def fixed_points(system, law, combinations, coupling="effective", max_iterations=30):
    """Solve ``I = map(I)`` (:func:`contact_map`) for each combination by Newton's method
    with a central-difference Jacobian. Returns ``(I, converged, determinate)`` per row.

    Starts from ``map(0)``, the contacts' answers with no coupling; for ``m = 1`` that is
    already the fixed point (the effective approach does not depend on ``I``), exactly.
    Every row iterates on its own (its own stopping and its own least-squares step); the
    combinations share only the batched evaluations of the map, so a row's result does not
    depend on the others, bit for bit.
    """
    number, size = len(combinations), 2 * system.count
    types = np.array([t for t, _ in combinations], dtype=np.int64).reshape(number, -1)
    signs = np.array([s for _, s in combinations], dtype=float).reshape(number, -1)
    mapping = contact_map(system, law, types, signs, coupling)
    scale = system.impulse_scale()
    impulses = mapping(np.zeros((number, size)), np.arange(number))
    converged = np.zeros(number, dtype=bool)
    determinate = np.ones(number, dtype=bool)
    previous = np.full(number, math.inf)
    running = np.ones(number, dtype=bool)
    for _ in range(max_iterations):
        running &= np.isfinite(impulses).all(axis=1)  # a non-finite iterate: not converged
        rows = np.flatnonzero(running)
        if rows.size == 0:
            break
        current = impulses[rows]
        bound = scale + np.max(np.abs(current), axis=1)
        if coupling == LITERAL:  # a constant map: the first residual is 0 and ends it
            # Its value anywhere is map(0), the current iterate, bit for bit: no evaluation.
            mapped, jacobian = current.copy(), None
        else:  # the map and, from the same call, its Jacobian (most rows go on)
            mapped, jacobian = map_and_jacobian(mapping, current, rows, 1e-6 * bound)
        residual = current - mapped
        size_now = np.max(np.abs(residual), axis=1)
        # Iterate to rounding (an affine map needs one or two steps), stop when that stalls;
        # accept when the residual is below the tolerance.
        stops = (size_now <= ROUNDING_RESIDUAL * bound) | (size_now > 0.5 * previous[rows])
        converged[rows[stops]] = size_now[stops] <= FIXED_POINT_TOLERANCE * bound[stops]
        running[rows[stops]] = False
        previous[rows] = size_now
        going = np.flatnonzero(~stops)
        if going.size == 0:
            continue
        if jacobian is None:  # a constant map went on: no fixed point to find
            running[rows[going]] = False
            continue
        finite = np.isfinite(jacobian[going]).all(axis=(1, 2))
        running[rows[going[~finite]]] = False
        going = going[finite]
        # Each row's own least-squares step (np.linalg.lstsq's, bit for bit), in one call.
        correction, rank = lstsq_rows(jacobian[going], -residual[going], rcond=1e-9)
        determinate[rows[going]] = rank == size
        impulses[rows[going]] = current[going] + correction
    rows = np.flatnonzero(running)  # out of iterations: accept below the tolerance
    if rows.size:
        current = impulses[rows]
        residual = np.max(np.abs(current - mapping(current, rows)), axis=1)
        bound = scale + np.max(np.abs(current), axis=1)
        converged[rows] = residual <= FIXED_POINT_TOLERANCE * bound
    return impulses, converged, determinate


__all__ = ["COUPLINGS", "ContactMap", "EFFECTIVE", "LITERAL", "contact_map", "fixed_points",
           "map_and_jacobian", "type_impulses"]
