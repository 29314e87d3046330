"""The laws on contact-space rows, shared by :func:`planar_impact.solve` (one problem) and
:func:`planar_impact.solve_batch` (arrays): the law's name checked, one law from
:mod:`planar_impact.laws` run and its answer completed with (A22), (A23) and (A29), each
row's status, and the scaling of rows of any size.

Every law is homogeneous: scaling the approach velocities by ``s`` scales the separation
velocities and impulses by ``s``, and scaling ``m_nn, m_nt, m_tt`` by ``k`` scales the
impulses by ``1/k`` (docs/theory.md, 'Contact terms', (A22)/(A23)). Rows whose velocities or
inverse-inertia terms lie outside ``2^±SAFE_EXPONENT`` are solved scaled by powers of two to
unit size and scaled back, so that intermediate products (Stronge's work ``~ v²/m``) neither
overflow nor underflow; powers of two make both scalings exact. Rows inside the range are
solved as given, bit for bit as before the scaling existed.
"""

from __future__ import annotations

import numpy as np

from . import errors, laws
from .errors import ImpactInputError
from .law_table import LAW_TABLE, LAWS


def check_law(law: str) -> str:
    if law not in LAWS:
        raise ImpactInputError(
            f"law: unknown law {law!r}; allowed: {', '.join(LAWS)}"
        )
    return law


def missing_branch(law: str, where: str) -> str:
    """The error of a law in :data:`LAWS` that ``where`` finds no solver of."""
    return (f"law {law!r} is in planar_impact's LAWS but {where} finds no solver of it "
            "in law_table.LAW_TABLE "
            "(docs/theory.md, 'The law registry and adding a law')")


def contact_space_solution(law, mnn, mnt, mtt, vn, vt, mu, e, out=None, delta=None):
    """Run one law on contact-space arrays (vt ≥ 0, rows assumed valid).

    Returns a dict of arrays: impulses, separation velocities (A22)/(A23), energy change
    (A29), collision type, Table 1 case, the Poisson restitution used (``e_i``) and
    ``consistent`` (False where the law has no consistent answer); ``consistent`` and
    ``restitution_poisson`` may be numpy scalars standing for every row. With ``out`` (a dict of
    arrays), the separation velocities and the energy change are written there, saving a
    copy each. ``delta`` is ``Δ`` (A20) when the caller has it more accurately than
    ``m_nn m_tt − m_nt²``.
    """
    solver = LAW_TABLE.get(law)
    if solver is None:  # a name in LAWS without its table entry must not run another law
        raise NotImplementedError(missing_branch(law, "contact_space.contact_space_solution"))
    terms = laws.ContactTerms(mnn, mnt, mtt, vn, vt, mu, delta)
    (normal, tangential, ctype, e_poisson, consistent, at_boundary,
     alternative) = solver.rows(terms, e)
    if out is None:
        out = {"vn_separation": None, "vt_separation": None, "energy_change": None}
    vn_separation = np.add(vn, mnn * normal + mnt * tangential, out=out["vn_separation"])  # (A22)
    vt_separation = np.add(vt, mnt * normal + mtt * tangential, out=out["vt_separation"])  # (A23)
    energy_change = np.multiply(  # (A29)
        0.5, normal * (vn_separation + vn) + tangential * (vt_separation + vt),
        out=out["energy_change"],
    )
    return {
        "normal_impulse": normal,
        "tangential_impulse": tangential,
        "vn_separation": vn_separation,
        "vt_separation": vt_separation,
        "energy_change": energy_change,
        "collision_type": ctype,
        "case": terms.case,
        "restitution_poisson": e_poisson,
        "consistent": consistent,
        "type_at_boundary": at_boundary,
        "alternative_type": alternative,
        "delta": terms.delta,
        "h": terms.h,
        "g": terms.g,
        "q": terms.q,
        "p": terms.p,
    }


def input_status(mnn, mnt, mtt, vn, vt, mu, e, finite=None, delta=None):
    """Status code of the inputs per row (0 = solvable); the first failing check wins.

    Works on arrays and on numpy scalars alike. ``finite`` (whether the caller's inputs are
    all finite) and ``delta`` replace the values computed here, for inputs that were scaled.
    """
    if finite is None:
        finite = np.isfinite(mnn) & np.isfinite(mnt) & np.isfinite(mtt)
        finite &= np.isfinite(vn) & np.isfinite(vt) & np.isfinite(mu) & np.isfinite(e)
    if delta is None:
        with np.errstate(invalid="ignore", over="ignore"):
            delta = mnn * mtt - mnt * mnt
    where = laws.where
    with np.errstate(invalid="ignore", over="ignore"):
        status = where(vn >= 0, errors.NO_APPROACH, errors.SOLVED)
        status = where((e < 0) | (e > 1), errors.RESTITUTION_OUT_OF_RANGE, status)
        status = where(mu < 0, errors.NEGATIVE_FRICTION, status)
        not_pd = (mnn <= 0) | (mtt <= 0) | (delta <= 0)
        status = where(not_pd, errors.NOT_POSITIVE_DEFINITE, status)
        status = where(finite, status, errors.NON_FINITE)
    return laws.as_type_code(status)


def answer_status(law, status, out):
    """Status after solving: problems with no admissible answer show only once the terms
    are known (a Painlevé-type jam, reverse sliding with ``q ≤ 0``, an inconsistent law)."""
    where = laws.where
    solved = status == errors.SOLVED
    jam = (out["h"] <= 0) & (out["g"] <= 0)
    q_fails = reverse_sliding(law, out["collision_type"]) & (out["q"] <= 0)
    answer = where(np.logical_not(out["consistent"]), errors.NO_CONSISTENT_SOLUTION, errors.SOLVED)
    answer = where(q_fails, errors.REVERSE_SLIDING_Q_NONPOSITIVE, answer)
    answer = where(jam, errors.PAINLEVE_JAM, answer)
    return laws.as_type_code(where(solved, answer, status))

# Rows with |v_n^A|, m_nn and m_tt in [2^-64, 2^64] and |v_t^A| < 2^64 are solved as given:
# every intermediate (at most ~v²/m times a conditioning factor) stays far inside float64.
# Others are scaled by powers of two first (solve_scaled).
SAFE_EXPONENT = 64
SAFE_LOW, SAFE_HIGH = 2.0**-SAFE_EXPONENT, 2.0**SAFE_EXPONENT


def scale_exponents(mnn, mtt, vn, vt):
    """Exponents ``(a, b)`` such that ``v·2^-a`` and ``m·2^-b`` are of order 1: ``a`` from
    the larger of ``|v_n^A|, |v_t^A|``, ``b`` from the geometric mean of ``m_nn, m_tt``."""
    speed_exponent = np.frexp(np.maximum(np.abs(vn), np.abs(vt)))[1]
    mass_exponent = (np.frexp(mnn)[1] + np.frexp(mtt)[1]) // 2
    return speed_exponent, mass_exponent


def solve_scaled(law, mnn, mnt, mtt, vn, vt, mu, e, speed_exponent, mass_exponent,
                  scaled_delta=None):
    """:func:`contact_space_solution` on the problem scaled by ``2^-speed_exponent`` in
    velocity and ``2^-mass_exponent`` in ``m``, with its answers scaled back.

    The laws are homogeneous (A22)/(A23): impulses scale as ``v/m``, velocities as ``v``,
    the energy (A29) as ``v²/m``. ``np.ldexp`` scales exactly, with one rounding where the
    answer is subnormal, and gives ±inf where it overflows. ``scaled_delta`` is ``Δ`` of the
    scaled terms when the caller has it; without it it is formed from them. Returns the
    solution (answers scaled back; signs of ``h, g, p, q`` and ``Δ`` of the scaled
    problem) and the scaled ``Δ``.
    """
    mnn, mnt, mtt = (np.ldexp(m, -mass_exponent) for m in (mnn, mnt, mtt))
    vn, vt = np.ldexp(vn, -speed_exponent), np.ldexp(vt, -speed_exponent)
    if scaled_delta is None:
        scaled_delta = mnn * mtt - mnt * mnt  # (A20)
    solution = contact_space_solution(law, mnn, mnt, mtt, vn, vt, mu, e,
                                      delta=scaled_delta)
    impulse_exponent = speed_exponent - mass_exponent
    for name, exponent in (("normal_impulse", impulse_exponent),
                           ("tangential_impulse", impulse_exponent),
                           ("vn_separation", speed_exponent), ("vt_separation", speed_exponent),
                           ("energy_change", 2 * speed_exponent - mass_exponent)):
        solution[name] = np.ldexp(solution[name], exponent)
    return solution, scaled_delta


def reverse_sliding(law, ctype):
    """Where the law's type slides in reverse (law_table's ``reverse_types``)."""
    first, *others = LAW_TABLE[law].reverse_types
    sliding = ctype == first
    for other in others:
        sliding = sliding | (ctype == other)
    return sliding
