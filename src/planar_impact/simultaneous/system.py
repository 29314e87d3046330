"""The ``m`` contacts of one system (the paper's Section 5, eq. (75)) and one answer on them.

:class:`ContactSystem` holds the contacts' rows with the (A20) terms per pair and the
Delassus matrix ``W``; :func:`contact_system` checks and assembles it;
:class:`MultiContactSolution` is one answer. Here too is what every reading shares: the
laws' collision types, the tolerances and the boundary band, the single-contact solver's
orientation of ``t`` (:func:`frame_sign`), a contact's own single-contact law
(:func:`law_at`), a solution's velocities and energy from its impulses by (A22)/(A23), (75)
and (A29) (:func:`assemble`), and many least-squares solves at once (:func:`lstsq_rows`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .. import contact_space, errors, solver
from ..errors import ImpactInputError

#: Laws of :func:`coherent_solutions` and their collision types (Newton numbers its three).
TYPE_LAWS: dict[str, tuple[int, ...]] = {
    "poisson": (1, 2, 3, 4, 5),
    "stronge-paper": (1, 2, 3, 4, 5),
    "newton": (1, 2, 3),
}


#: The laws whose type formulas are affine in the approach velocities (and so their maps in
#: the impulses): screened before their solve by :func:`affine_screen`.
AFFINE_LAWS = ("poisson", "newton")


#: Type code of a contact that takes no impulse (only with ``allow_separating=True``).
SEPARATING = 0


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


def frame_sign(vt: float, mnt: float) -> float:
    """The single-contact solver's orientation of ``t``: −1 flips it so that ``v_t^A ≥ 0``
    (and ``m_nt ≥ 0`` where ``v_t^A = 0``), as in ``solve_batch``."""
    return -1.0 if vt < 0 or (vt == 0 and mnt < 0) else 1.0


def _lstsq_failed(*_args):
    raise np.linalg.LinAlgError("SVD did not converge in Linear Least Squares")


def lstsq_rows(matrices, rhs, rcond):
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


def law_at(system, law, i, vn, vt, sign):
    """Contact ``i``'s own single-contact law at approach ``(vn, vt)``, in frame ``sign``:
    the solver's contact-space kernel, or None where it has no answer."""
    mnn, mnt, mtt = system.single_terms(i)
    delta = np.float64(system.deltas[i])
    if not vn < 0 or not delta > 0:
        return None
    scalars = [np.float64(x) for x in (mnn, sign * mnt, mtt, vn, sign * vt,
                                       system.mu[i], system.e[i])]
    with np.errstate(all="ignore"):
        out = contact_space.contact_space_solution(law, *scalars, delta=delta)
        status = int(contact_space.answer_status(law, errors.SOLVED, out))
    return out if status == errors.SOLVED else None


def assemble(system, law, types, impulses, determinate):
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


def speed_of(system) -> float:
    return float(np.max(np.abs(system.u))) + system.speed_scale()


__all__ = ["AFFINE_LAWS", "BOUNDARY_BAND", "ContactSystem", "FIXED_POINT_TOLERANCE",
           "MultiContactSolution", "ROUNDING_RESIDUAL", "SEPARATING", "TYPE_LAWS",
           "VELOCITY_TOLERANCE", "assemble", "contact_system", "frame_sign", "law_at", "lstsq_rows",
           "speed_of"]
