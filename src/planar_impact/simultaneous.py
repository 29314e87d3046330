"""Several simultaneous contacts on one system (the paper's Section 5, eq. (75)).

With ``m`` contacts the impulse–momentum balance (A12) becomes (75),
``M Δu = Σ_i (w_n^(i) I_n^(i) + w_t^(i) I_t^(i))``, and each contact's velocity change picks
up the other contacts' impulses through the cross terms of the Delassus matrix
``W = J M⁻¹ Jᵀ`` (``J`` stacks the rows ``w_n^(i)``, ``w_t^(i)``). Three readings are built
here (docs/multi-contact.md explains each, with a worked example):

* :func:`coherent_solutions`: the paper's proposal after (75). Every combination of the
  collision types (five for Poisson and the paper's Stronge, three for Newton) is evaluated
  and tested for coherence; all coherent combinations are returned. By default
  (``coupling="literal"``, the paper's) each contact's type formulas are explicit in its own
  ``v^A(i)``: 5^m evaluations, kept where the paper's three tests hold. The named extension
  ``coupling="effective"`` applies them at ``v^A(i) + Σ_{j≠i} W_ij I^(j)``, a fixed point of
  ``m`` single-contact laws, which counts restitution twice.
* :func:`newton_coulomb` / :func:`newton_coulomb_solutions`: the velocity-level
  Newton–Coulomb law sequential-impulse engines solve, by exact enumeration of the contact
  modes, counted by post-impact velocity; :func:`projected_gauss_seidel` is the engines'
  iteration, for the cross-check and as the second method where no mode holds.
* :func:`sequential_impacts` / :func:`all_orders`: the contacts taken one at a time with the
  single-contact solver, in a given order, until none approaches.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np

from . import errors, laws, solver
from .errors import ImpactInputError

#: Laws of :func:`coherent_solutions` and their collision types (Newton numbers its three).
TYPE_LAWS: dict[str, tuple[int, ...]] = {
    "poisson": (1, 2, 3, 4, 5),
    "stronge-paper": (1, 2, 3, 4, 5),
    "newton": (1, 2, 3),
}
#: The laws whose type formulas are affine in the approach velocities (and so their maps in
#: the impulses): screened before their solve by :func:`_affine_screen`.
AFFINE_LAWS = ("poisson", "newton")
#: Type code of a contact that takes no impulse (only with ``allow_separating=True``).
SEPARATING = 0

# Newton–Coulomb contact modes (newton-lcp numbering, plus 0 for a contact that separates).
LCP_SEPARATE, LCP_STICK, LCP_REVERSE, LCP_FORWARD = 0, 1, 2, 3

# Relative tolerances. Impulses of one combination are the fixed point of an affine map
# (Poisson, Newton) found to rounding, or of a smooth map (stronge-paper) found by Newton
# iterations: 1e-10 of the impulse scale separates "converged" from "no fixed point" with
# orders of magnitude to spare on both sides. Sign tests on velocities allow 1e-9 of the
# approach speed: a velocity that should be exactly 0 (a sticking contact) comes out as a
# sum of 2m products, each rounded to ~1e-16 of the approach speed times the condition of W.
FIXED_POINT_TOLERANCE = 1e-10
VELOCITY_TOLERANCE = 1e-9
#: A fixed-point iteration stops at a residual this far below the bound: a few units of
#: double rounding (~1.1e-16 each), where a further Newton step can no longer shrink it.
ROUNDING_RESIDUAL = 1e-15
#: The boundary band of a coherence decision, relative
#: (docs/multi-contact.md, 'Decisions at a boundary'). Table 1's type at an effective
#: approach is at the boundary when a point within BOUNDARY_BAND of the approach speed has
#: another type (the type depends on α = v_t/|v_n| and the signs of g, h, p, q only); the
#: tangent orientation when |v_t| is within it; the strict test I_n > 0 when |I_n| is
#: within BOUNDARY_BAND of the impulse scale. Rounding moves these by ~1e-16 times W's
#: condition (≲ 1e-12 here), so a decision outside the band cannot flip on the last bit;
#: inside it the solution is reported with ``at_boundary`` and both candidates named,
#: instead of being kept or dropped by the last bit. At a type boundary the two types'
#: closed forms agree (comment a of Table 1) for Poisson and Newton; the paper's Stronge's
#: jump at α = (1+e) r_m.
BOUNDARY_BAND = 1e-9


@dataclass(frozen=True)
class ContactSystem:
    """``m`` contacts on one system in generalized speeds, with the (A20) terms per pair.

    ``delassus[2i + a, 2j + b]`` is ``w_a^(i) · M⁻¹ w_b^(j)`` with ``a, b`` = 0 (normal),
    1 (tangent); ``approach[2i]``, ``approach[2i + 1]`` are ``v_n^A(i)``, ``v_t^A(i)``.
    ``inverse_rows[i]`` holds ``M⁻¹ w_n^(i)`` and ``M⁻¹ w_t^(i)`` as columns, computed as
    :func:`planar_impact.solve` computes them (so that ``m = 1`` matches it bit for bit).
    """

    mass_matrix: np.ndarray
    wn: np.ndarray  # (m, p)
    wt: np.ndarray  # (m, p)
    u: np.ndarray  # (p,)
    mu: np.ndarray  # (m,)
    e: np.ndarray  # (m,)
    inverse_rows: tuple[np.ndarray, ...]
    delassus: np.ndarray  # (2m, 2m)
    approach: np.ndarray  # (2m,)
    terms: tuple[tuple[float, float, float], ...]  # (m_nn, m_nt, m_tt) per contact (A20)
    deltas: tuple[float, ...]  # Δ per contact (A20), formed as planar_impact.solve forms it

    @property
    def count(self) -> int:
        return self.wn.shape[0]

    def single_terms(self, i: int) -> tuple[float, float, float]:
        """``(m_nn, m_nt, m_tt)`` of contact ``i`` alone (A20), exactly as ``solve`` has them."""
        return self.terms[i]

    def effective_approach(self, i: int, impulses: np.ndarray) -> tuple[float, float]:
        """``v^A(i) + Σ_{j≠i} W_ij I^(j)``: contact ``i``'s velocities once the other
        contacts' impulses are applied, by (75) through (A16), (A22) and (A23)."""
        vn, vt = self._plain[0][i]
        for j, (w_nn, w_nt, w_tn, w_tt) in self._plain[1][i]:
            normal, tangential = float(impulses[2 * j]), float(impulses[2 * j + 1])
            vn += w_nn * normal + w_nt * tangential
            vt += w_tn * normal + w_tt * tangential
        return vn, vt

    @functools.cached_property
    def _plain(self):
        """Per contact: ``(v_n^A, v_t^A)`` and the other contacts' blocks of W as
        ``(j, (w_nn, w_nt, w_tn, w_tt))``, plain floats (the same products and sums as on
        the arrays' numpy scalars, without their cost per operation)."""
        approach = [(float(self.approach[2 * i]), float(self.approach[2 * i + 1]))
                    for i in range(self.count)]
        blocks = [[(j, tuple(self.delassus[2 * i:2 * i + 2, 2 * j:2 * j + 2].ravel().tolist()))
                   for j in range(self.count) if j != i] for i in range(self.count)]
        return approach, blocks

    def delta_u(self, impulses: np.ndarray) -> np.ndarray:
        """``Δu = Σ_i M⁻¹ (w_n^(i) I_n^(i) + w_t^(i) I_t^(i))``, (75)."""
        total = None
        for i, inverse in enumerate(self.inverse_rows):
            term = inverse[:, 0] * impulses[2 * i] + inverse[:, 1] * impulses[2 * i + 1]
            total = term if total is None else total + term
        return total

    def impulse_scale(self) -> float:
        """A size for impulses: the largest approach speed over the smallest diagonal of W."""
        return self._scales[0]

    def speed_scale(self) -> float:
        return self._scales[1]

    @functools.cached_property
    def checked_contacts(self) -> tuple[solver.CheckedContact, ...]:
        """Each contact as :func:`planar_impact.solve` prepares it (checked at assembly), for
        :func:`solver.solve_contact`: one contact at many speeds, as :func:`sequential_impacts`
        strikes it."""
        return tuple(solver.checked_contact(self.mass_matrix, self.wn[i], self.wt[i])
                     for i in range(self.count))

    @functools.cached_property
    def _scales(self) -> tuple[float, float]:
        """:meth:`impulse_scale` and :meth:`speed_scale`, formed once (asked per check)."""
        speed = float(np.max(np.abs(self.approach)))
        impulse = speed / float(np.min(np.diag(self.delassus))) if speed > 0 else 1.0
        return impulse, max(speed, 1e-300)


def contact_system(*, mass_matrix, wn, wt, u, mu, e) -> ContactSystem:
    """Check and assemble ``m`` contacts: ``wn``, ``wt`` are ``(m, p)`` (one row per contact),
    ``mu`` and ``e`` scalars or length ``m``. Raises :class:`ImpactInputError`."""
    matrix = solver.check_mass_matrix(mass_matrix)
    size = matrix.shape[0]
    try:
        np.linalg.cholesky(matrix)
    except np.linalg.LinAlgError:
        raise ImpactInputError("mass_matrix: must be positive definite (Cholesky failed)") from None
    wn_rows = np.atleast_2d(np.asarray(wn, dtype=float))
    wt_rows = np.atleast_2d(np.asarray(wt, dtype=float))
    if wn_rows.shape != wt_rows.shape or wn_rows.ndim != 2 or wn_rows.shape[1] != size:
        raise ImpactInputError(
            f"wn, wt: expected two (m, {size}) arrays, got {wn_rows.shape} and {wt_rows.shape}")
    count = wn_rows.shape[0]
    if count == 0 or not (np.isfinite(wn_rows).all() and np.isfinite(wt_rows).all()):
        raise ImpactInputError("wn, wt: need at least one contact, all entries finite")
    speeds = solver.as_vector("u", u, size)
    mus = np.broadcast_to(np.asarray(mu, dtype=float), (count,)).copy()
    restitutions = np.broadcast_to(np.asarray(e, dtype=float), (count,)).copy()
    for i in range(count):
        mus[i] = solver.check_scalar(f"mu[{i}]", mus[i], 0.0, np.inf)
        restitutions[i] = solver.check_scalar(f"e[{i}]", restitutions[i], 0.0, 1.0)
    # One solve per contact, as planar_impact.solve does it (bit identity for m = 1).
    inverse_rows = tuple(np.linalg.solve(matrix, np.stack([wn_rows[i], wt_rows[i]], axis=1))
                         for i in range(count))
    rows = [wn_rows[i // 2] if i % 2 == 0 else wt_rows[i // 2] for i in range(2 * count)]
    columns = [inverse_rows[j // 2][:, j % 2] for j in range(2 * count)]
    delassus = np.array([[float(row @ column) for column in columns] for row in rows])
    approach = np.array([float(row @ speeds) for row in rows])
    terms = tuple((float(wn_rows[i] @ inverse[:, 0]), float(wn_rows[i] @ inverse[:, 1]),
                   float(wt_rows[i] @ inverse[:, 1])) for i, inverse in enumerate(inverse_rows))
    deltas = tuple(solver.contact_terms(matrix, wn_rows[i], wt_rows[i])[3] for i in range(count))
    return ContactSystem(matrix, wn_rows, wt_rows, speeds, mus, restitutions, inverse_rows,
                         delassus, approach, terms, deltas)


@dataclass(frozen=True)
class MultiContactSolution:
    """One answer for ``m`` contacts. Arrays are per contact, in the caller's ``t``.

    ``types``: the collision type per contact (Poisson/Stronge 1–5, Newton and Newton–Coulomb
    1 stick, 2 reverse, 3 forward; 0 separating, no impulse). ``determinate`` is False where
    the impulses of this combination are not unique (a one-parameter family, e.g. two sticking
    contacts on one face of one body); then the minimum-norm correction is returned.
    """

    law: str
    types: tuple[int, ...]
    normal_impulse: np.ndarray
    tangential_impulse: np.ndarray
    delta_u: np.ndarray
    u_after: np.ndarray
    vn_approach: np.ndarray
    vt_approach: np.ndarray
    vn_separation: np.ndarray
    vt_separation: np.ndarray
    energy_change: float
    determinate: bool
    #: The literal reading only: whether every contact's type is the one Table 1 picks at its
    #: own ``v^A(i)`` (the single-contact law's type); None under the other readings.
    table1_types: bool | None = None
    #: Decisions of this solution that lie inside the boundary band (BOUNDARY_BAND), each
    #: naming both candidates (e.g. "contact 0: Table 1 type 4 | 5"); empty when every
    #: decision is clear.
    boundary: tuple[str, ...] = ()

    @property
    def at_boundary(self) -> bool:
        """True when some decision of this solution is inside the boundary band."""
        return bool(self.boundary)

    def impulses(self) -> np.ndarray:
        """``(I_n^(1), I_t^(1), I_n^(2), ...)``."""
        return np.ravel(np.column_stack([self.normal_impulse, self.tangential_impulse]))


# ------------------------------------------------------------------------------------------
# The paper's proposal: type combinations tested for coherence
# ------------------------------------------------------------------------------------------
def _frame_sign(vt: float, mnt: float) -> float:
    """The single-contact solver's orientation of ``t``: −1 flips it so that ``v_t^A ≥ 0``
    (and ``m_nt ≥ 0`` where ``v_t^A = 0``), as in ``solve_batch``."""
    return -1.0 if vt < 0 or (vt == 0 and mnt < 0) else 1.0


def _type_impulses(law, terms, e, ctype):
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


def _contact_map(system, law, types, signs, coupling="effective"):
    """The map ``I ↦ (forced impulses of every contact at its effective approach)`` for many
    combinations at once; with ``coupling="literal"`` every contact sees its own ``v^A`` and
    the map is constant.

    ``types``, ``signs`` (``(N, m)``): one combination per row. The returned
    :class:`_ContactMap` maps rows of impulses ``(R, 2m)``, row ``r`` by combination
    ``rows[r]``. Each element takes the operations of one contact's formulas
    (:func:`_type_impulses` at :meth:`ContactSystem.effective_approach`) in the same order:
    a combination's answer does not depend on the batch it is in, bit for bit.
    """
    if law not in TYPE_LAWS:  # the kernels below are those laws'
        raise ValueError(f"_contact_map serves {', '.join(TYPE_LAWS)}, not {law!r}")
    return _ContactMap(system, law, types, signs, coupling)


class _ContactMap:
    """:func:`_contact_map`'s map. All contacts' formulas run in one batched call of
    :func:`_type_impulses` (the contact's terms, μ and e given per element), so that numpy's
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
        flattened element), for every contact in one batch of :func:`_type_impulses`: a list
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
            normal, tangential = _type_impulses(self.law, terms, e, np.concatenate(type_parts))
        separating = np.concatenate(separating_parts)
        values = np.column_stack([np.where(separating, 0.0, normal),
                                  np.where(separating, 0.0, sign * tangential)])
        return np.split(values, np.cumsum(sizes)[:-1])


def _map_and_jacobian(mapping, impulses, rows, step):
    """``mapping`` at ``impulses`` (rows ``(R, 2m)``) and the Jacobian of ``I − mapping(I)``
    there by central differences of half-width ``step`` (per row), from one batched call.

    Column ``k`` is ``e_k − (map(I + step e_k) − map(I − step e_k)) / (2 step)``, formed as
    :func:`_fixed_points` needs it. Contact ``i``'s impulses
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


def _fixed_points(system, law, combinations, coupling="effective", max_iterations=30):
    """Solve ``I = map(I)`` (:func:`_contact_map`) for each combination by Newton's method
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
    mapping = _contact_map(system, law, types, signs, coupling)
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
            mapped, jacobian = _map_and_jacobian(mapping, current, rows, 1e-6 * bound)
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
        correction, rank = _lstsq_rows(jacobian[going], -residual[going], rcond=1e-9)
        determinate[rows[going]] = rank == size
        impulses[rows[going]] = current[going] + correction
    rows = np.flatnonzero(running)  # out of iterations: accept below the tolerance
    if rows.size:
        current = impulses[rows]
        residual = np.max(np.abs(current - mapping(current, rows)), axis=1)
        bound = scale + np.max(np.abs(current), axis=1)
        converged[rows] = residual <= FIXED_POINT_TOLERANCE * bound
    return impulses, converged, determinate


def _lstsq_failed(*_args):
    raise np.linalg.LinAlgError("SVD did not converge in Linear Least Squares")


def _lstsq_rows(matrices, rhs, rcond):
    """:func:`numpy.linalg.lstsq` of each matrix ``matrices[k]`` ``(N, r, c)`` and right-hand
    side ``rhs[k]`` ``(N, r)``: the solutions ``(N, c)`` and the ranks ``(N,)``.

    ``np.linalg.lstsq`` takes one matrix per call and spends ~45 µs around LAPACK's ~15 µs
    for a 4 × 4; its own gufunc (``numpy.linalg._umath_linalg.lstsq``, the same ``gelsd``
    call on each matrix, with the same workspace for matrices of one shape) takes the stack
    at once and gives each row ``np.linalg.lstsq``'s answer bit for bit
    (tests/theory/test_simultaneous_lstsq.py). A numpy without that gufunc, or whose gufunc
    takes other arguments, gets the loop.
    """
    if len(matrices) == 0:
        return np.empty((0, matrices.shape[-1])), np.empty(0, dtype=np.int64)
    gufunc = getattr(getattr(np.linalg, "_umath_linalg", None), "lstsq", None)
    if gufunc is not None:
        try:
            with np.errstate(call=_lstsq_failed, invalid="call", over="ignore",
                             divide="ignore", under="ignore"):  # as np.linalg.lstsq calls it
                solution, _, rank, _ = gufunc(matrices, rhs[..., None], rcond,
                                              signature="ddd->ddid")
            return solution[..., 0], rank
        except TypeError:  # a numpy whose gufunc takes other arguments: the loop
            pass
    answers = [np.linalg.lstsq(matrix, side, rcond=rcond) for matrix, side in zip(matrices, rhs)]
    return (np.array([answer[0] for answer in answers]),
            np.array([answer[2] for answer in answers], dtype=np.int64))


def _law_at(system, law, i, vn, vt, sign):
    """Contact ``i``'s own single-contact law at approach ``(vn, vt)``, in frame ``sign``:
    the solver's contact-space kernel, or None where it has no answer."""
    mnn, mnt, mtt = system.single_terms(i)
    delta = np.float64(system.deltas[i])
    if not vn < 0 or not delta > 0:
        return None
    scalars = [np.float64(x) for x in (mnn, sign * mnt, mtt, vn, sign * vt,
                                       system.mu[i], system.e[i])]
    with np.errstate(all="ignore"):
        out = solver.contact_space_solution(law, *scalars, delta=delta)
        status = int(solver.answer_status(law, errors.SOLVED, out))
    return out if status == errors.SOLVED else None


def _assemble(system, law, types, impulses, determinate):
    """Velocities (A22)/(A23) per contact with (75)'s cross terms, Δu and (A29) summed."""
    count = system.count
    vn_s, vt_s = np.empty(count), np.empty(count)
    for i in range(count):
        mnn, mnt, mtt = system.single_terms(i)
        vn, vt = system.effective_approach(i, impulses)
        normal, tangential = impulses[2 * i], impulses[2 * i + 1]
        # Same expressions as solve() (there with v^A in place of the effective approach).
        vn_s[i] = vn + (mnn * normal + mnt * tangential)  # (A22)
        vt_s[i] = vt + (mnt * normal + mtt * tangential)  # (A23)
    vn_a, vt_a = system.approach[0::2], system.approach[1::2]
    normal, tangential = impulses[0::2].copy(), impulses[1::2].copy()
    energy = None  # (A29) summed over contacts: ½ Σ I·(v^S + v^A) = change of ½uᵀMu
    for i in range(count):
        term = normal[i] * (vn_s[i] + vn_a[i]) + tangential[i] * (vt_s[i] + vt_a[i])
        energy = term if energy is None else energy + term
    delta_u = system.delta_u(impulses)
    return MultiContactSolution(
        law=law, types=tuple(int(t) for t in types), normal_impulse=normal,
        tangential_impulse=tangential, delta_u=delta_u, u_after=system.u + delta_u,
        vn_approach=vn_a.copy(), vt_approach=vt_a.copy(), vn_separation=vn_s,
        vt_separation=vt_s, energy_change=float(0.5 * energy), determinate=bool(determinate))


def _paper_coherent(law, ctype, sign, solution, i, tolerance, impulse_band):
    """The paper's tests after (75): ``I_n > 0``, ``v_n^S ≥ 0`` and a ``v_t^S`` that fits the
    type (0 sticking, against the initial slip reversing, with it forward).

    True or False; or, where the strict ``I_n > 0`` is decided inside ``impulse_band`` (an
    impulse that is zero to rounding), a string naming both candidates. The non-strict
    tests pass within ``tolerance`` of their cut: a value that is zero to rounding passes
    them whichever its last bit, so they are never at a boundary.
    """
    if ctype == SEPARATING:
        return bool(solution.vn_separation[i] >= -tolerance)
    normal = solution.normal_impulse[i]
    if not normal > -impulse_band or solution.vn_separation[i] < -tolerance:
        return False
    if not normal > impulse_band:
        return ("I_n = 0 within the band (an impulse, or a separating contact)"
                if _slip_fits(law, ctype, sign, solution, i, tolerance) else False)
    return _slip_fits(law, ctype, sign, solution, i, tolerance)


def _slip_fits(law, ctype, sign, solution, i, tolerance) -> bool:
    slip = sign * solution.vt_separation[i]
    if law == "newton":
        kind = {1: "stick", 2: "reverse", 3: "forward"}[ctype]
    else:
        kind = {1: "stick", 2: "stick", 3: "reverse", 4: "reverse", 5: "forward"}[ctype]
    if kind == "stick":
        return bool(abs(slip) <= tolerance)
    return bool(slip <= tolerance if kind == "reverse" else slip >= -tolerance)


def coherent_solutions(system: ContactSystem, law: str = "poisson", *,
                       coupling: str = LITERAL, allow_separating: bool = False
                       ) -> list[MultiContactSolution]:
    """Every coherent combination of collision types, the paper's proposal after (75).

    ``coupling="literal"`` (default, the paper's proposal): for each type tuple
    ``(T_1 … T_m)`` contact ``i``'s impulses are type ``T_i``'s formulas at its own
    ``v^A(i)`` (tangent oriented as ``solve`` orients it); ``Δu`` by (75); the combination
    is coherent when the paper's three tests hold at every contact with the final
    velocities: ``I_n > 0``, ``v_n^S ≥ 0``, ``v_t^S`` fitting the type. Table 1 does not
    filter (``table1_types`` marks the combination it would pick).

    ``coupling="effective"`` (an extension, not the paper's; it counts restitution twice):
    contact ``i``'s impulses are type ``T_i``'s formulas at its effective approach
    ``v^A(i) + Σ_{j≠i} W_ij I^(j)``; the ``m`` contacts' formulas together fix the impulses
    (a linear system for Poisson and Newton, a smooth one for ``"stronge-paper"``), and the
    combination is coherent when, at every contact, the single-contact law picks type
    ``T_i`` by Table 1 for that effective approach, the orientation is the one ``solve``
    would use, and the paper's tests hold. docs/multi-contact.md, 'The paper's proposal',
    gives the reasons.

    Decisions inside the band :data:`BOUNDARY_BAND` (Table 1's type, the orientation at
    ``v_t = 0``, ``I_n = 0``) keep the solution with ``at_boundary`` and both candidates in
    ``boundary`` (docs/multi-contact.md, 'Decisions at a boundary').

    ``allow_separating`` adds type 0 (no impulse, needs ``v_n^S ≥ 0``) at each contact; the
    paper requires ``I_n > 0`` everywhere, so it is off by default.

    Combinations that cannot pass are dropped before their solve (:func:`_candidates`: the
    literal reading's one orientation per contact; a batched screen with margins for the
    effective one of Poisson and Newton) or, for the paper's Stronge under the effective
    reading, after it and before the checks (:func:`_coherent_within_margin` at the fixed
    points); the rest are
    solved and checked as without a screen, so the answer is the same bit for bit
    (tests/theory/test_simultaneous_screen.py compares with the unscreened path).

    Returns the coherent solutions, distinct impulses only (combinations that coincide, as
    across a type boundary where the closed forms agree, are listed once: the first in
    enumeration order), sorted by type tuple. For ``m = 1`` the effective reading's list is
    the single answer of :func:`planar_impact.solve` with the same law, bit for bit, and so
    is the literal reading's solution with ``table1_types``.
    """
    if law not in TYPE_LAWS:
        raise ImpactInputError(f"law: {law!r}; allowed: {', '.join(TYPE_LAWS)}")
    if coupling not in COUPLINGS:
        raise ImpactInputError(f"coupling: {coupling!r}; allowed: {', '.join(COUPLINGS)}")
    choices = ((SEPARATING,) if allow_separating else ()) + TYPE_LAWS[law]
    tolerance = VELOCITY_TOLERANCE * system.speed_scale()
    found: list[MultiContactSolution] = []
    candidates = _candidates(system, law, choices, coupling, tolerance)
    if not candidates:
        return found
    impulses, converged, determinate = _fixed_points(system, law, candidates, coupling)
    if law not in AFFINE_LAWS and coupling == EFFECTIVE and system.count > 1:
        # The paper's Stronge is screened after its solve, at the fixed points themselves.
        rows = np.flatnonzero(converged)  # finite: their residual passed the tolerance
        converged[rows] = _coherent_within_margin(
            system, law, [candidates[k] for k in rows], impulses[rows], tolerance)
    fixed = zip(impulses, converged, determinate)
    for (types, signs), (impulses, converged, determinate) in zip(candidates, fixed):
        if not converged:
            continue
        solution = _check_combination(system, law, types, signs, impulses, bool(determinate),
                                      tolerance, coupling)
        if solution is not None and not _already_found(found, solution, system):
            found.append(solution)
    return found


def _combinations(choices, count):
    """Every (types, signs) in enumeration order: type tuples outer, orientations inner;
    a separating contact takes only ``+1`` (the orientation does not matter without impulse)."""
    for types in itertools.product(choices, repeat=count):
        for signs in itertools.product((1.0, -1.0), repeat=count):
            if not any(t == SEPARATING and s < 0 for t, s in zip(types, signs)):
                yield types, signs


def _candidates(system, law, choices, coupling, tolerance):
    """The combinations that :func:`_check_combination` could accept, in enumeration order.

    Every combination it could accept is kept (so the solutions, solved and checked by the
    same code as before, are the same bit for bit); most of the others are dropped unsolved:

    * ``coupling="literal"``: each contact sees its own ``v^A(i)``, which fixes its tangent's
      orientation: the ``types^m`` type tuples, one orientation each (the paper's ``5^m``).
    * ``coupling="effective"`` with Poisson or Newton: the map is affine, and one batched
      linear solve per combination screens it (:func:`_affine_screen`).
    * ``coupling="effective"`` with the paper's Stronge: every combination. Its map is not
      affine: a screen would run the Newton iteration of :func:`_fixed_points` itself, and
      with that iteration batched the full solve of every combination costs about as much
      as such a screen alone. :func:`coherent_solutions` screens the converged ones at their
      fixed points instead (:func:`_coherent_within_margin`, necessary tests with margins).
    """
    if coupling == LITERAL:
        # Each contact's tangent is oriented by its own v^A(i) (as solve() orients it); every
        # type tuple is a candidate, the paper's tests decide (_check_combination).
        signs = tuple(_frame_sign(float(system.approach[2 * i + 1]), system.single_terms(i)[1])
                      for i in range(system.count))
        return [(types, tuple(1.0 if t == SEPARATING else sign for t, sign in zip(types, signs)))
                for types in itertools.product(choices, repeat=system.count)]
    combinations = list(_combinations(choices, system.count))
    if system.count == 1 or law not in AFFINE_LAWS:
        return combinations
    keep = _affine_screen(system, law, combinations, tolerance)
    return [combination for combination, kept in zip(combinations, keep) if kept]


#: Screening bounds of :func:`_affine_screen`. A combination whose matrix ``1 − K`` has
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
    :func:`_contact_map` equal to ``c + G (v − v^A(i))`` at effective approach ``v``.

    Poisson's closed forms ((26), (29), (36), (44), (49)) and Newton's two phases ((A30),
    (A58)) are affine in ``(v_n, v_t)`` with the contact's terms fixed, so ``G`` is the
    difference quotient over one whole approach speed: exact up to rounding, no truncation.
    """
    step = system.speed_scale()
    pieces = {}
    typed = [ctype for ctype in choices if ctype != SEPARATING]
    keys = [(ctype, sign) for ctype in typed for sign in (1.0, -1.0)]
    # Every contact's every (type, sign) at v^A(i) and one speed step along v_n and along
    # v_t, in one batch of _type_impulses (element by element the scalar answers).
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
        normal, tangential = _type_impulses(law, terms, e, ctypes.astype(np.int64))
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


def _affine_screen(system, law, combinations, tolerance):
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
        # _fixed_points' first step from I_0 = c: I_1 = c + (1 − K)⁺ (K c), with the
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
    keep[index[finite_ends]] = _coherent_within_margin(
        system, law, [combinations[k] for k in index[finite_ends]], impulses[finite_ends],
        tolerance)
    return keep


def _coherent_within_margin(system, law, combinations, impulses, tolerance):
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
    """Whether Table 1 (the law's own type, as :func:`_law_at` finds it) could give every
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
        out = solver.contact_space_solution(
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


def _check_combination(system, law, types, signs, impulses, determinate, tolerance,
                       coupling="effective"):
    """The coherent solution of one combination at its fixed point, or None; with its
    decisions inside the boundary band named (``boundary``)."""
    final = impulses.copy()
    boundary: list[str] = []
    seen = impulses if coupling == EFFECTIVE else np.zeros_like(impulses)
    for i, (ctype, sign) in enumerate(zip(types, signs)):
        if ctype == SEPARATING:
            continue
        if coupling == LITERAL:  # the type's formulas at v^A(i) are the impulses: no Table 1
            vt = float(system.approach[2 * i + 1])
            if _frame_sign(vt, system.single_terms(i)[1]) != sign or not (
                    np.isfinite(impulses[2 * i]) and np.isfinite(impulses[2 * i + 1])):
                return None
            continue
        _mnn, mnt, _mtt = system.single_terms(i)
        vn, vt = system.effective_approach(i, seen)
        band = BOUNDARY_BAND * (abs(vn) + abs(vt))
        if _frame_sign(vt, mnt) != sign:
            if abs(vt) > band:
                return None
            boundary.append(f"contact {i}: v_t = 0 within the band (either orientation)")
        own = _law_at(system, law, i, vn, vt, sign)
        if own is None:
            return None
        near = _types_near(system, law, i, vn, vt, sign, band)
        own_type = int(own["collision_type"])
        if ctype not in near:
            return None
        if len(near) > 1:  # Table 1 within the band gives several types: name them
            boundary.append(f"contact {i}: Table 1 type "
                            + " | ".join(str(t) for t in sorted(near)))
        if own_type != ctype:
            # Table 1 picks the neighbouring type inside the band: the combination's own
            # formulas (the fixed point) stand, both types named. Poisson's closed forms agree
            # across a boundary (comment a); the paper's Stronge's need not (docs/theory.md,
            # 'Findings', 3), so its two candidates may both be listed.
            continue
        # The law's own impulses at this effective approach: equal to the fixed point to
        # its tolerance, and for m = 1 exactly what solve() returns.
        normal, tangential = float(own["normal_impulse"]), sign * float(own["tangential_impulse"])
        scale = system.impulse_scale() + abs(normal) + abs(tangential)
        if max(abs(normal - impulses[2 * i]), abs(tangential - impulses[2 * i + 1])) > (
                FIXED_POINT_TOLERANCE * scale):
            return None
        final[2 * i], final[2 * i + 1] = normal, tangential
    solution = _assemble(system, law, types, final, determinate)
    for i, (ctype, sign) in enumerate(zip(types, signs)):
        verdict = _paper_coherent(law, ctype, sign, solution, i, tolerance,
                                  BOUNDARY_BAND * system.impulse_scale())
        if verdict is False:
            return None
        if verdict is not True:
            boundary.append(f"contact {i}: {verdict}")
    if coupling == LITERAL:
        solution = dataclasses.replace(solution, table1_types=_table1_types(system, law, types))
    return dataclasses.replace(solution, boundary=tuple(boundary)) if boundary else solution


def _types_near(system, law, i, vn, vt, sign, band) -> set[int]:
    """The types Table 1 gives contact ``i`` at ``(vn, vt)`` and at the four corners of the
    box of half-width ``band`` around it (on the same side of ``v_t = 0``, approaching): α
    is extreme at the corners, so these are the types within the band."""
    found = set()
    for dn, dt in ((0.0, 0.0), (-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)):
        corner_vn, corner_vt = vn + dn * band, vt + dt * band
        if sign * corner_vt < 0:
            corner_vt = 0.0
        out = _law_at(system, law, i, corner_vn, corner_vt, sign)
        if out is not None:
            found.add(int(out["collision_type"]))
    return found


def _table1_types(system, law, types) -> bool:
    """Whether each contact's type is the single-contact law's at its own ``v^A(i)``."""
    for i, ctype in enumerate(types):
        if ctype == SEPARATING:
            continue
        vn, vt = float(system.approach[2 * i]), float(system.approach[2 * i + 1])
        own = _law_at(system, law, i, vn, vt, _frame_sign(vt, system.single_terms(i)[1]))
        if own is None or int(own["collision_type"]) != ctype:
            return False
    return True


def _already_found(found, solution, system) -> bool:
    """Whether ``solution`` repeats one in ``found`` (same impulses, or same ``Δu`` within a
    family); a repeat's boundary notes are merged into the kept one (``found`` is updated),
    so that which combination came first cannot change what is reported."""
    scale = system.impulse_scale()
    for k, other in enumerate(found):
        same = np.max(np.abs(other.impulses() - solution.impulses())) <= 1e-9 * scale
        family = not (other.determinate and solution.determinate)
        if same or family and np.max(np.abs(other.delta_u - solution.delta_u)) <= (
                1e-9 * _speed_of(system)):
            notes = tuple(dict.fromkeys(other.boundary + solution.boundary))
            if notes != other.boundary:
                found[k] = dataclasses.replace(other, boundary=notes)
            return True
    return False


def _speed_of(system) -> float:
    return float(np.max(np.abs(system.u))) + system.speed_scale()


# ------------------------------------------------------------------------------------------
# Velocity-level Newton–Coulomb law (what sequential-impulse engines solve)
# ------------------------------------------------------------------------------------------
def restitution_targets(system: ContactSystem) -> np.ndarray:
    """``e_i |v_n^A(i)|`` where contact ``i`` approaches, else 0: the engines' targets."""
    vn = system.approach[0::2]
    return system.e * np.maximum(-vn, 0.0)


#: Outcomes of :func:`newton_coulomb` (docs/multi-contact.md, 'Newton–Coulomb for m contacts').
NC_UNIQUE = "unique"
NC_SPLIT_NOT_UNIQUE = "velocities unique, impulse split not unique"
NC_SEVERAL = "several velocities"
NC_NONE = "no solution"
NC_STATUSES = (NC_UNIQUE, NC_SPLIT_NOT_UNIQUE, NC_SEVERAL, NC_NONE)
#: Sweeps of projected Gauss–Seidel tried where the enumeration finds no mode that holds.
NC_GAUSS_SEIDEL_SWEEPS = 2000


@dataclass(frozen=True)
class NewtonCoulombResult:
    """The Newton–Coulomb law's answer on ``m`` contacts, counted by post-impact velocity.

    ``solutions``: one per distinct ``u_after`` (relative 1e-9 of the speed scale), each
    with ``determinate`` False where the impulses giving it are not unique (several modes,
    or a family within one mode: a flat face's W is rank-deficient). ``status`` is one of
    :data:`NC_STATUSES`; ``explanation`` says why in one line, and for ``"no solution"``
    what the second method (projected Gauss–Seidel from zero) did. ``gauss_seidel`` is
    that second method's result where it was run (only when the enumeration found none).
    """

    solutions: tuple[MultiContactSolution, ...]
    status: str
    explanation: str
    gauss_seidel: GaussSeidelResult | None = None


def newton_coulomb(system: ContactSystem) -> NewtonCoulombResult:
    """:func:`newton_coulomb_solutions` with its outcome named (:class:`NewtonCoulombResult`).

    Where no mode holds, projected Gauss–Seidel (the engines' iteration) is run from zero as
    a second method: a converged iterate that satisfies the law is a solution the
    enumeration missed and is returned (status by the same rule); otherwise the status is
    ``"no solution"`` and the explanation gives how far the iterate grew.
    """
    found = newton_coulomb_solutions(system)
    if found:
        return NewtonCoulombResult(tuple(found), *_nc_status(found))
    iteration = projected_gauss_seidel(system, max_sweeps=NC_GAUSS_SEIDEL_SWEEPS)
    if iteration.converged:
        solution = _as_lcp_solution(system, iteration.impulses)
        if solution is not None:
            status, why = _nc_status([solution])
            return NewtonCoulombResult((solution,), status, why + "; found by projected "
                                       "Gauss–Seidel, not by the enumeration", iteration)
    size = float(np.max(np.abs(iteration.impulses))) / system.impulse_scale()
    how = ("converged to an iterate that violates the law" if iteration.converged else
           f"did not converge in {iteration.sweeps} sweeps (largest impulse "
           f"{size:.3g} impulse scales)")
    return NewtonCoulombResult(
        (), NC_NONE, f"none of the 4^{system.count} contact modes holds (each mode's linear "
        f"system solved and its inequalities tested, tolerance 1e-9 of the speed and impulse "
        f"scales); projected Gauss–Seidel from zero {how}", iteration)


def _nc_status(found) -> tuple[str, str]:
    if len(found) > 1:
        return NC_SEVERAL, f"{len(found)} solutions with distinct post-impact velocities"
    if not found[0].determinate:
        return NC_SPLIT_NOT_UNIQUE, ("one post-impact velocity; the impulses that give it form "
                                     "a family (W is rank-deficient)")
    return NC_UNIQUE, "one solution, impulses unique"


def _as_lcp_solution(system, impulses):
    """``impulses`` as a Newton–Coulomb solution when some mode's inequalities hold there."""
    targets = restitution_targets(system)
    tolerance = VELOCITY_TOLERANCE * system.speed_scale()
    impulse_tolerance = 1e-9 * system.impulse_scale()
    modes, signs = [], []
    solution = _assemble(system, "newton-coulomb", (0,) * system.count, impulses, True)
    for i in range(system.count):
        _mnn, mnt, _mtt = system.single_terms(i)
        sign = _frame_sign(float(system.approach[2 * i + 1]), mnt)
        signs.append(sign)
        if solution.normal_impulse[i] <= impulse_tolerance:
            modes.append(LCP_SEPARATE)
        elif abs(solution.vt_separation[i]) <= tolerance:
            modes.append(LCP_STICK)
        else:
            modes.append(LCP_FORWARD if sign * solution.vt_separation[i] > 0 else LCP_REVERSE)
    solution = _assemble(system, "newton-coulomb", modes, impulses, True)
    active_ok = all(mode == LCP_SEPARATE or abs(solution.vn_separation[i] - targets[i])
                    <= tolerance for i, mode in enumerate(modes))
    return solution if active_ok and _lcp_holds(system, modes, signs, solution, targets,
                                                tolerance) else None


def newton_coulomb_solutions(system: ContactSystem) -> list[MultiContactSolution]:
    """All solutions of the Newton–Coulomb contact law with distinct post-impact velocities,
    by enumerating the 4^m modes.

    Per contact: either it separates (``I = 0``, ``v_n^S ≥ e|v_n^A|``), or ``v_n^S =
    e|v_n^A|`` (A30) with ``I_n ≥ 0`` and Coulomb friction at the end state: stick
    (``v_t^S = 0``, ``|I_t| ≤ μ I_n``) or slide against the final slip (``I_t = −μ I_n
    sign(v_t^S)``). Each mode is a linear system in the 2m impulses (W's rows); its
    inequalities decide whether it holds. Types: 0 separate, 1 stick, 2 reverse, 3 forward
    (slip with or against the contact's approach slip, oriented as ``solve`` orients it).
    For ``m = 1`` equals ``solve(..., law="newton-lcp")`` to rounding (a general
    2×2 solve here, the closed form there).

    Solutions are counted by post-impact velocity: modes whose solutions give the same
    ``Δu`` (relative 1e-9 of the speed scale) are one solution, listed once (the first in
    enumeration order), with ``determinate`` False when their impulses differ (relative
    1e-9 of the impulse scale) or the mode's system is singular. A flat face of one body has
    a rank-deficient W, and its impulse split between the corners is then not unique while
    the velocities are. :func:`newton_coulomb` names the outcome.
    """
    count = system.count
    targets = restitution_targets(system)
    tolerance = VELOCITY_TOLERANCE * system.speed_scale()
    delassus, approach = system.delassus, system.approach
    found: list[MultiContactSolution] = []
    every_mode = list(itertools.product((LCP_STICK, LCP_FORWARD, LCP_REVERSE, LCP_SEPARATE),
                                        repeat=count))
    systems = []  # per mode: its matrix, right-hand side and orientations
    for modes in every_mode:
        matrix = np.zeros((2 * count, 2 * count))
        rhs = np.zeros(2 * count)
        signs = []
        for i, mode in enumerate(modes):
            _mnn, mnt, _mtt = system.single_terms(i)
            sign = _frame_sign(float(approach[2 * i + 1]), mnt)
            signs.append(sign)
            n, t = 2 * i, 2 * i + 1
            if mode == LCP_SEPARATE:
                matrix[n, n] = matrix[t, t] = 1.0
                continue
            matrix[n] = delassus[n]  # v_n^S = e|v_n^A|
            rhs[n] = targets[i] - approach[n]
            if mode == LCP_STICK:
                matrix[t] = delassus[t]  # v_t^S = 0
                rhs[t] = -approach[t]
            else:  # I_t = ∓μ I_n, forward slides along +sign·t
                slide = sign if mode == LCP_FORWARD else -sign
                matrix[t, t] = 1.0
                matrix[t, n] = slide * system.mu[i]
        systems.append((matrix, rhs, signs))
    # Every mode's least-squares solve in one call (each np.linalg.lstsq's answer, bit for bit).
    solved = _lstsq_rows(np.array([matrix for matrix, _, _ in systems]),
                         np.array([rhs for _, rhs, _ in systems]), rcond=1e-12)
    for modes, (matrix, rhs, signs), impulses, rank in zip(every_mode, systems, *solved):
        if np.max(np.abs(matrix @ impulses - rhs)) > tolerance * (1.0 + np.max(np.abs(matrix))):
            continue  # singular and inconsistent: this mode has no solution
        solution = _assemble(system, "newton-coulomb", modes, impulses, rank == 2 * count)
        if not _lcp_holds(system, modes, signs, solution, targets, tolerance):
            continue
        same = _same_velocity(found, solution, system)
        if same is None:
            found.append(solution)
        elif np.max(np.abs(found[same].impulses() - solution.impulses())) > (
                1e-9 * system.impulse_scale()) and found[same].determinate:
            # Another mode reaches the same velocities with other impulses: the split of the
            # impulses between the contacts is not unique.
            found[same] = dataclasses.replace(found[same], determinate=False)
    return found


def _same_velocity(found, solution, system) -> int | None:
    """The index of a solution in ``found`` with the same ``Δu`` (relative 1e-9), or None."""
    for k, other in enumerate(found):
        if np.max(np.abs(other.delta_u - solution.delta_u)) <= 1e-9 * _speed_of(system):
            return k
    return None


def _lcp_holds(system, modes, signs, solution, targets, tolerance) -> bool:
    for i, (mode, sign) in enumerate(zip(modes, signs)):
        normal, tangential = solution.normal_impulse[i], solution.tangential_impulse[i]
        slip = sign * solution.vt_separation[i]
        if mode == LCP_SEPARATE:
            if solution.vn_separation[i] < targets[i] - tolerance:
                return False
            continue
        impulse_tolerance = 1e-9 * system.impulse_scale()
        if normal < -impulse_tolerance:
            return False
        if mode == LCP_STICK:
            if abs(tangential) > system.mu[i] * normal + impulse_tolerance:
                return False
        elif mode == LCP_FORWARD and slip < -tolerance or mode == LCP_REVERSE and slip > tolerance:
            return False
    return True


@dataclass(frozen=True)
class GaussSeidelResult:
    impulses: np.ndarray  # (I_n^(1), I_t^(1), ...)
    converged: bool
    sweeps: int


def projected_gauss_seidel(system: ContactSystem, max_sweeps: int = 100_000,
                           tolerance: float = 1e-13) -> GaussSeidelResult:
    """The engines' sequential-impulse iteration on the Newton–Coulomb law.

    Each sweep visits the contacts in order: the normal impulse is corrected toward
    ``v_n^S = e|v_n^A|`` and clamped at 0, then the tangential one toward ``v_t^S = 0`` and
    clamped to ``|I_t| ≤ μ I_n``. Converged when a sweep changes no impulse by more than
    ``tolerance`` times the impulse scale.
    """
    count = system.count
    delassus, approach = system.delassus, system.approach
    targets = restitution_targets(system)
    impulses = np.zeros(2 * count)
    scale = system.impulse_scale()
    for sweep in range(1, max_sweeps + 1):
        largest = 0.0
        for i in range(count):
            n, t = 2 * i, 2 * i + 1
            vn = approach[n] + delassus[n] @ impulses
            new_n = max(0.0, impulses[n] - (vn - targets[i]) / delassus[n, n])
            largest = max(largest, abs(new_n - impulses[n]))
            impulses[n] = new_n
            vt = approach[t] + delassus[t] @ impulses
            limit = system.mu[i] * impulses[n]
            new_t = min(limit, max(-limit, impulses[t] - vt / delassus[t, t]))
            largest = max(largest, abs(new_t - impulses[t]))
            impulses[t] = new_t
        if largest <= tolerance * scale:
            return GaussSeidelResult(impulses, True, sweep)
    return GaussSeidelResult(impulses, False, max_sweeps)


# ------------------------------------------------------------------------------------------
# Sequential reading: one contact at a time
# ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SequentialResult:
    """The contacts taken one at a time in ``order`` (repeated rounds) with one law.

    ``impacts`` lists ``(contact, collision type)`` in the order they happened; ``capped``
    is True when ``max_impacts`` stopped the sequence while a contact still approached.
    """

    order: tuple[int, ...]
    law: str
    impacts: tuple[tuple[int, int], ...]
    u_after: np.ndarray
    delta_u: np.ndarray
    vn_separation: np.ndarray
    vt_separation: np.ndarray
    energy_change: float
    capped: bool


def sequential_impacts(system: ContactSystem, law: str, order, max_impacts: int = 10_000
                       ) -> SequentialResult:
    """Rounds over ``order``: each contact that approaches (``v_n < −10⁻¹²·speed``) gets a
    single-contact impact by :func:`planar_impact.solve` with the current speeds; stop after
    a round with no impact, or at ``max_impacts``."""
    order = tuple(int(i) for i in order)
    if sorted(order) != list(range(system.count)):
        raise ImpactInputError(
            f"order: {order} is not a permutation of the {system.count} contacts")
    speeds = system.u.copy()
    threshold = -1e-12 * system.speed_scale()  # below rounding, above any real approach
    impacts: list[tuple[int, int]] = []
    capped = False
    while True:
        struck = False
        for i in order:
            if float(system.wn[i] @ speeds) >= threshold:
                continue
            if len(impacts) >= max_impacts:
                capped = True
                break
            solver.check_law(law)  # as solve() would, at the first impact
            # solve() of contact i, its M⁻¹ w and (A20) terms formed once per system.
            result = solver.solve_contact(system.checked_contacts[i], speeds,
                                          float(system.mu[i]), float(system.e[i]), law)
            speeds = result.u_after
            impacts.append((i, result.collision_type))
            struck = True
        if capped or not struck:
            break
    delta_u = speeds - system.u
    kinetic = 0.5 * (speeds @ system.mass_matrix @ speeds
                     - system.u @ system.mass_matrix @ system.u)
    return SequentialResult(order=order, law=law, impacts=tuple(impacts), u_after=speeds,
                            delta_u=delta_u, vn_separation=system.wn @ speeds,
                            vt_separation=system.wt @ speeds, energy_change=float(kinetic),
                            capped=capped)


def all_orders(system: ContactSystem, law: str, max_impacts: int = 10_000
               ) -> tuple[list[SequentialResult], float]:
    """:func:`sequential_impacts` for every order of the contacts, and the spread: the
    largest difference in any component of ``u_after`` between two orders."""
    results = [sequential_impacts(system, law, order, max_impacts)
               for order in itertools.permutations(range(system.count))]
    finals = np.array([r.u_after for r in results])
    spread = float(np.max(finals.max(axis=0) - finals.min(axis=0)))
    return results, spread


# ------------------------------------------------------------------------------------------
# How many coherent solutions do random two-contact problems have?
# ------------------------------------------------------------------------------------------
def random_two_contact_system(rng: np.random.Generator, family: str = "generic") -> ContactSystem:
    """One random approaching two-contact problem.

    ``"generic"``: 4 generalized speeds, a random SPD mass matrix and random contact rows
    (W is then regular). ``"body"``: one free rigid body (u = v_x, v_y, ω) touching two
    obstacles at random points with random normals (W has rank 3: one rigid body cannot
    have four independent contact velocities in the plane). μ ∈ [0, 1], e ∈ [0, 1] per
    contact; ``u`` is redrawn until both contacts approach.
    """
    if family == "generic":
        root = rng.normal(size=(4, 4))
        mass_matrix = root @ root.T + 0.1 * np.eye(4)
        wn, wt = rng.normal(size=(2, 4)), rng.normal(size=(2, 4))
    elif family == "body":
        mass, inertia = 10 ** rng.uniform(-0.5, 0.5), 10 ** rng.uniform(-1.5, 0.5)
        mass_matrix = np.diag([mass, mass, inertia])
        wn, wt = np.empty((2, 3)), np.empty((2, 3))
        for i in range(2):
            angle = rng.uniform(0, 2 * math.pi)
            n = np.array([math.cos(angle), math.sin(angle)])
            t = np.array([n[1], -n[0]])
            r = rng.normal(size=2)
            wn[i] = (n[0], n[1], r[0] * n[1] - r[1] * n[0])
            wt[i] = (t[0], t[1], r[0] * t[1] - r[1] * t[0])
    else:
        raise ImpactInputError(f"family: {family!r}; allowed: generic, body")
    while True:
        u = rng.normal(size=mass_matrix.shape[0])
        if np.all(wn @ u < 0):
            break
    return contact_system(mass_matrix=mass_matrix, wn=wn, wt=wt, u=u,
                          mu=rng.uniform(0, 1, 2), e=rng.uniform(0, 1, 2))


def coherent_count_distribution(problems: int = 1000, seed: int = 0, family: str = "generic",
                                coupling: str = LITERAL,
                                laws_to_count=("poisson", "stronge-paper", "newton",
                                               "newton-coulomb")) -> dict[str, dict[str, int]]:
    """For ``problems`` random two-contact systems, how often each law has 0, 1 or 2+
    clearly coherent solutions (for ``"newton-coulomb"``, solutions with distinct post-impact
    velocities), how often some solution is at the boundary of a decision (key
    ``"boundary"``, not in the 0/1/2+ count), and how often a solution gains energy (key
    ``"gains"``, relative 1e-9 of ``½uᵀMu``)."""
    rng = np.random.default_rng(seed)
    counts = {law: {"0": 0, "1": 0, "2+": 0, "boundary": 0, "gains": 0}
              for law in laws_to_count}
    for _ in range(problems):
        system = random_two_contact_system(rng, family)
        energy = 0.5 * float(system.u @ system.mass_matrix @ system.u)
        for law in laws_to_count:
            if law == "newton-coulomb":
                found = newton_coulomb_solutions(system)
            else:
                found = coherent_solutions(system, law, coupling=coupling)
            number = sum(not s.at_boundary for s in found)
            counts[law]["0" if number == 0 else "1" if number == 1 else "2+"] += 1
            counts[law]["boundary"] += any(s.at_boundary for s in found)
            counts[law]["gains"] += any(s.energy_change > 1e-9 * energy for s in found)
    return counts


if __name__ == "__main__":  # python -m planar_impact.simultaneous [problems] [seed]
    import sys

    count = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    for family in ("generic", "body"):
        for coupling in COUPLINGS:
            table = coherent_count_distribution(count, seed, family, coupling)
            print(f"{family} coupling={coupling}: {table}")
