"""The screen of the paper's proposal: combinations of collision types that cannot be
coherent, dropped before their solve (Poisson and Newton under the effective reading:
:func:`affine_screen`) or before their checks (:func:`coherent_within_margin`).

Every test is a necessary test of the checks widened by ``SCREEN_MARGIN``, so no coherent
combination is dropped, and the combinations kept are solved and checked as without the
screen: the answer is the same bit for bit (tests/theory/test_simultaneous_screen.py).
"""

from __future__ import annotations

import numpy as np

from .. import contact_space, laws
from .system import (
    SEPARATING,
)
from .type_map import type_impulses

#: Screening bounds of :func:`affine_screen`. A combination whose matrix ``1 − K`` has
#: ``‖(1 − K)⁻¹‖₂`` above ``SCREEN_CONDITION`` goes to the full path unscreened. Below it, the
#: fixed point the full path accepts (residual ≤ FIXED_POINT_TOLERANCE of the bound) lies
#: within ``SCREEN_CONDITION · FIXED_POINT_TOLERANCE = 1e-6`` of the bound from the screen's
#: solution; ``SCREEN_MARGIN`` (1e-4) leaves a factor 100 on top of that.
SCREEN_CONDITION = 1e4


SCREEN_MARGIN = 1e-4


#: Singular ``1 − K`` (two contacts of one body: W has rank 3): singular values below
#: ``SINGULAR_CUT`` of the largest are its null space; the rest must be at least
#: ``SCREEN_SINGULAR_CONDITION`` for the screen, because the old path's pseudo-inverse, of a
#: Jacobian blurred by ~1e-10, then differs from the exact one by ≲ 3e-10/0.01² = 3e-6 ≪
#: SCREEN_MARGIN. Values in between are ambiguous and the combination is kept unscreened.
SINGULAR_CUT = 1e-12


SCREEN_SINGULAR_CONDITION = 1e-2


def _affine_pieces(system, law, choices):
    """Per contact ``i`` and (type, sign): ``(c, G)`` with the forced impulses of
    :func:`contact_map` equal to ``c + G (v − v^A(i))`` at effective approach ``v``.

    Poisson's closed forms ((26), (29), (36), (44), (49)) and Newton's two phases ((A30),
    (A58)) are affine in ``(v_n, v_t)`` with the contact's terms fixed, so ``G`` is the
    difference quotient over one whole approach speed: exact up to rounding, no truncation.
    """
    step = system.speed_scale()
    pieces = {}
    typed = [ctype for ctype in choices if ctype != SEPARATING]
    keys = [(ctype, sign) for ctype in typed for sign in (1.0, -1.0)]
    # Every contact's every (type, sign) at v^A(i) and one speed step along v_n and along
    # v_t, in one batch of type_impulses (element by element the scalar answers).
    columns = []  # per element: m_nn, sign, m_tt, v_n, v_t, μ, Δ, e, type
    for i in range(system.count):
        mnn, _mnt, mtt = system.single_terms(i)
        vn0, vt0 = float(system.approach[2 * i]), float(system.approach[2 * i + 1])
        points = ((vn0, vt0), (vn0 + step, vt0), (vn0, vt0 + step))
        columns += [(mnn, sign, mtt, vn, vt, system.mu[i], system.deltas[i], system.e[i], ctype)
                    for ctype, sign in keys for vn, vt in points]
    mnn, signs, mtt, vn, vt, mu, delta, e, ctypes = np.array(columns).T
    mnt = np.repeat([system.single_terms(i)[1] for i in range(system.count)], 3 * len(keys))
    with np.errstate(all="ignore"):
        terms = laws.ContactTerms(mnn, signs * mnt, mtt, vn, signs * vt, mu, delta)
        normal, tangential = type_impulses(law, terms, e, ctypes.astype(np.int64))
    values = np.column_stack([normal, signs * tangential]).reshape(system.count, len(keys), 3, 2)
    # G's columns: the difference quotients along v_n and along v_t.
    slopes = ((values[:, :, 1:] - values[:, :, :1]) / step).transpose(0, 1, 3, 2)
    for i in range(system.count):
        if SEPARATING in choices:
            for sign in (1.0, -1.0):
                pieces[i, SEPARATING, sign] = (np.zeros(2), np.zeros((2, 2)))
        for k, (ctype, sign) in enumerate(keys):
            pieces[i, ctype, sign] = (values[i, k, 0], slopes[i, k])
    return pieces


def affine_screen(system, law, combinations, tolerance):
    """For the effective reading with an affine law: which combinations may be coherent.

    Contact ``i``'s impulses are ``c_i + G_i Σ_{j≠i} W_ij I^(j)`` (its type's formulas at the
    effective approach of (75)), so a combination's fixed point solves ``(1 − K) I = c`` with
    ``K_ij = G_i W_ij`` (``j ≠ i``), one batched solve for all combinations. A combination is
    dropped only when that solution fails a necessary test of :func:`_check_combination` by
    more than ``SCREEN_MARGIN`` of its scale: the orientation (``sign·v_t ≥ 0`` at the
    effective approach), an approaching contact (``v_n < 0``), ``I_n > 0``, ``v_n^S ≥ 0``
    and the type's slip, (A22)/(A23). Singular, ill-conditioned or non-finite systems are
    kept. Returns a boolean per combination.
    """
    count, size = system.count, 2 * system.count
    choices = sorted({t for types, _ in combinations for t in types})
    pieces = _affine_pieces(system, law, choices)
    number = len(combinations)
    offsets = np.zeros((number, size))
    slopes = np.zeros((number, size, size))  # block-diagonal G
    for i in range(count):  # contact i's piece of every combination, gathered
        keys = [(ctype, sign) for (contact, ctype, sign) in pieces if contact == i]
        which = {key: k for k, key in enumerate(keys)}
        chosen = [which[types[i], signs[i]] for types, signs in combinations]
        offsets[:, 2 * i:2 * i + 2] = np.array([pieces[i, c, s][0] for c, s in keys])[chosen]
        slopes[:, 2 * i:2 * i + 2, 2 * i:2 * i + 2] = np.array(
            [pieces[i, c, s][1] for c, s in keys])[chosen]
    coupling = system.delassus.copy()
    for i in range(count):
        coupling[2 * i:2 * i + 2, 2 * i:2 * i + 2] = 0.0  # only the other contacts, (75)
    matrices = np.eye(size) - slopes @ coupling
    keep = np.ones(number, dtype=bool)
    finite = np.isfinite(matrices).all(axis=(1, 2)) & np.isfinite(offsets).all(axis=1)
    if not finite.any():
        return keep
    index = np.flatnonzero(finite)
    matrices, offsets = matrices[index], offsets[index]
    with np.errstate(all="ignore"):
        left, values, right = np.linalg.svd(matrices)
        # Singular values below SINGULAR_CUT of the largest are the null space (the old
        # path's lstsq cuts at 1e-9; its difference-quotient Jacobian blurs them to ~1e-10).
        # A row is screened when every other singular value is clearly regular.
        null = values < SINGULAR_CUT * values[:, :1]
        weakest_kept = np.min(np.where(null, np.inf, values), axis=1)
        screened = weakest_kept >= np.where(null.any(axis=1), SCREEN_SINGULAR_CONDITION,
                                            1.0 / SCREEN_CONDITION)
        # fixed_points' first step from I_0 = c: I_1 = c + (1 − K)⁺ (K c), with the
        # pseudo-inverse's cut; for a regular matrix that is (1 − K)⁻¹ c, the fixed point.
        inverse_values = np.where(null, 0.0, 1.0 / values)
        pushed = offsets - np.einsum("kij,kj->ki", matrices, offsets)  # K c = c − (1 − K) c
        impulses = offsets + np.einsum("kji,kj,klj,kl->ki", right, inverse_values, left,
                                       pushed)
        residual = np.einsum("kij,kj->ki", matrices, impulses) - offsets
    bound = system.impulse_scale() + np.max(np.abs(impulses), axis=1)
    # No fixed point: the least-squares residual, which no iterate of the old path beats,
    # stays far above its acceptance (FIXED_POINT_TOLERANCE of the bound).
    consistent = np.max(np.abs(residual), axis=1) <= SCREEN_MARGIN * bound
    index, impulses = index[screened], impulses[screened]
    keep[index[~consistent[screened]]] = False
    index, impulses = index[consistent[screened]], impulses[consistent[screened]]
    finite_ends = np.isfinite(impulses).all(axis=1)
    keep[index[finite_ends]] = coherent_within_margin(
        system, law, [combinations[k] for k in index[finite_ends]], impulses[finite_ends],
        tolerance)
    return keep


def coherent_within_margin(system, law, combinations, impulses, tolerance):
    """Whether each combination, at its (approximate, finite) fixed point ``impulses``,
    passes the necessary tests of :func:`_check_combination` and :func:`_paper_coherent`
    widened by ``SCREEN_MARGIN``: the orientation (``sign·v_t ≥ 0`` at the effective
    approach), an approaching contact (``v_n < 0``), ``I_n > 0``, ``v_n^S ≥ 0`` and the
    type's slip, with ``v^S`` by (A22)/(A23) and (75).

    ``impulses`` are the affine screen's solutions (within ``SCREEN_CONDITION ·
    FIXED_POINT_TOLERANCE`` of the bound from the fixed point the full path accepts), or,
    for the paper's Stronge, the full path's fixed points themselves (within
    ``FIXED_POINT_TOLERANCE`` of the impulses :func:`_check_combination` takes): far inside
    the margins either way."""
    count = system.count
    coupling = system.delassus.copy()
    for i in range(count):
        coupling[2 * i:2 * i + 2, 2 * i:2 * i + 2] = 0.0
    effective = system.approach + impulses @ coupling.T  # v^A(i) + Σ_{j≠i} W_ij I^(j)
    after = system.approach + impulses @ system.delassus.T  # v^S
    bound = system.impulse_scale() + np.max(np.abs(impulses), axis=1)
    impulse_margin = SCREEN_MARGIN * bound
    row_sum = float(np.max(np.sum(np.abs(system.delassus), axis=1)))
    speed_margin = tolerance + row_sum * impulse_margin
    types = np.array([t for t, _ in combinations], dtype=np.int64).reshape(-1, count)
    signs = np.array([s for _, s in combinations], dtype=float).reshape(-1, count)
    # Per combination and contact: 0 stick, 1 reverse, 2 forward (the paper's tests).
    kinds = np.array([0, 0, 1, 2]) if law == "newton" else np.array([0, 0, 0, 1, 1, 2])
    kind = kinds[types]  # a separating contact's entry is unused
    margin_i, margin_v = impulse_margin[:, None], speed_margin[:, None]
    slip = signs * after[:, 1::2]
    slip_ok = np.where(kind == 0, np.abs(slip) <= margin_v,
                       np.where(kind == 1, slip <= margin_v, slip >= -margin_v))
    typed_ok = ((signs * effective[:, 1::2] >= -margin_v) & (effective[:, 0::2] < margin_v)
                & (impulses[:, 0::2] > -margin_i) & (after[:, 0::2] >= -margin_v) & slip_ok)
    passes = np.where(types == SEPARATING, after[:, 0::2] >= -margin_v, typed_ok).all(axis=1)
    rows = np.flatnonzero(passes)
    if rows.size:
        passes[rows[~_types_within_margin(system, law, types[rows], signs[rows],
                                          effective[rows], speed_margin[rows])]] = False
    return passes


def _types_within_margin(system, law, types, signs, effective, margin):
    """Whether Table 1 (the law's own type, as :func:`law_at` finds it) could give every
    contact its type of the combination anywhere within ``margin`` of its effective
    approach: one boolean per combination (``types``, ``signs`` ``(N, m)``, ``effective``
    ``(N, 2m)``, ``margin`` ``(N,)``).

    The type depends on the direction of the approach only (every law's formulas are
    homogeneous of degree 1 in ``(v_n, v_t)``), through ``α = v_t/|v_n|`` (A34) in ordered
    regions (Table 1 with (53)–(57); Newton's (A58)); ``α`` over the box of half-width
    ``margin`` is extreme at its corners. So a contact is rejected only when the centre and
    the four corners, all approaching and on the combination's side of ``v_t = 0``, agree on
    one other type. Separating contacts pass. Every contact's corners go through one batched
    call of the solver's kernel (element by element its scalar answer).
    """
    own = np.ones(len(types), dtype=bool)
    offsets = np.array([(0.0, 0.0), (-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)])
    parts = []  # per contact: its clear rows, their approaches and its terms
    for i in range(system.count):
        vn = effective[:, 2 * i][:, None] + offsets[:, 0] * margin[:, None]
        vt = signs[:, i, None] * (effective[:, 2 * i + 1][:, None]
                                  + offsets[:, 1] * margin[:, None])
        clear = (types[:, i] != SEPARATING) & (vn < 0).all(axis=1) & (vt >= 0).all(axis=1)
        rows = np.flatnonzero(clear)
        if rows.size:
            parts.append((i, rows, vn[rows], vt[rows]))
    if not parts:
        return own
    shapes = [(rows.size, len(offsets)) for _, rows, _, _ in parts]
    terms = [(system.single_terms(i), system.mu[i], system.e[i], system.deltas[i])
             for i, _, _, _ in parts]

    def stacked(per_contact):
        return np.concatenate([np.broadcast_to(value, shape).reshape(-1)
                               for value, shape in zip(per_contact, shapes)])

    signs_of = [signs[rows, i, None] for i, rows, _, _ in parts]
    with np.errstate(all="ignore"):
        out = contact_space.contact_space_solution(
            law, stacked([t[0][0] for t in terms]),
            stacked([sign * t[0][1] for sign, t in zip(signs_of, terms)]),
            stacked([t[0][2] for t in terms]), stacked([vn for _, _, vn, _ in parts]),
            stacked([vt for _, _, _, vt in parts]), stacked([t[1] for t in terms]),
            stacked([t[2] for t in terms]), delta=stacked([t[3] for t in terms]))
    found = np.split(np.asarray(out["collision_type"], dtype=np.int64),
                     np.cumsum([rows * columns for rows, columns in shapes])[:-1])
    for (i, rows, _, _), shape, contact_found in zip(parts, shapes, found):
        contact_found = contact_found.reshape(shape)
        agree = ((contact_found == contact_found[:, :1]).all(axis=1)
                 & (contact_found[:, 0] != types[rows, i]))
        own[rows[agree]] = False
    return own


__all__ = ["SCREEN_CONDITION", "SCREEN_MARGIN", "SCREEN_SINGULAR_CONDITION", "SINGULAR_CUT",
           "affine_screen", "coherent_within_margin"]
