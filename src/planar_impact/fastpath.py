"""The scalar fast path of :func:`planar_impact.solve`: one problem in plain Python floats.

numpy's fixed cost per call (~1 µs a ufunc, ~10 µs a LAPACK call) made ``solve`` cost
120–200 µs; here the same steps run on floats and lists:

* Contact terms (A20) by a Cholesky factor ``M = L Lᵀ`` written out for the few speeds of
  planar bodies (``p ≤ MAX_SPEEDS``): ``a = L⁻¹ w_n``, ``b = L⁻¹ w_t``,
  ``M⁻¹ w = L⁻ᵀ a``; ``m_nn = w_n·M⁻¹w_n`` etc. and ``Δ`` as the sum of the squared minors
  ``a_i b_j − a_j b_i`` (Lagrange's identity, as :func:`planar_impact.solver.contact_terms`).
  The order of the operations differs from LAPACK's, so these terms (and ``Δu``) agree with
  the numpy path within rounding, not bit for bit: ``|Δm| ≤ 4 p ε κ(M) (m_nn m_tt)^½``
  (backward-stable Cholesky and triangular solves; tests/theory/test_fastpath.py checks
  ``1e-12`` relative on well-conditioned draws).
* The law, given those terms: its scalar solver in :mod:`planar_impact.law_branches` (from
  ``law_table.LAW_TABLE``), the very expressions of :mod:`planar_impact.laws` in the same
  order, evaluated for the selected branch only. IEEE float64 ``+ − × ÷ √`` are correctly
  rounded in Python as in numpy, so the answer equals :func:`planar_impact.solve_batch` on
  the same ``(m_nn, m_nt, m_tt, v_n^A, v_t^A, μ, e, Δ)`` bit for bit (checked over thousands
  of random problems of every law and type, also under ``OPENBLAS_CORETYPE=Prescott``).

Anything else goes to the numpy path, which then raises or answers exactly as before:
inputs that are not plain finite arrays of matching size, ``M`` not symmetric bit for bit
(the tolerance check) or not positive definite, more than ``MAX_SPEEDS`` speeds, any error
status (no approach, ``Δ ≤ 0``, a Painlevé jam, ``q ≤ 0`` in reverse sliding, no consistent
``newton-lcp`` or ``stronge-paper`` answer), speeds or terms outside ``2^±64`` (scaled
there), and any division by zero. Near Table 1's band (``laws.TYPE_BAND``: mostly
``v_t^A = 0``) the batch's candidate search runs on numpy scalars, slower but the same.
:func:`fast_solve` returns None for the declined cases.

The last ``M``'s check and factor are kept, keyed on its bytes (a function of ``M`` alone,
so reusing it changes no result): a body's ``M`` stays while its contact and speeds change.
The factor keeps only its non-zero entries (planar bodies' ``M`` are diagonal or
block-diagonal). Likewise the last contact's terms (``m_nn``, ``m_nt``, ``m_tt``, ``Δ``,
``M⁻¹w``), keyed on that factor and the bytes of ``w_n`` and ``w_t`` given as float
arrays: a fit, a sweep or a law solver solves one contact at many speeds, ``μ``, ``e`` and
laws, and then pays only for the approach velocities, the law and the result. Measured per
call: docs/performance.md, 'Measured speed (`make bench` = `impact-harness bench --quick`)'.
"""

from __future__ import annotations

import math

import numpy as np

from . import laws
from .contact_space import missing_branch
from .law_table import LAW_TABLE

#: Most generalized speeds solved here (two free planar bodies have 6); beyond, numpy's
#: O(p³) kernels win.
MAX_SPEEDS = 8


def _floats(value, size):
    """``value`` as a list of ``size`` finite floats, or None (the numpy path reports why)."""
    if type(value) is not np.ndarray or value.dtype is not _FLOAT:
        value = np.asarray(value, dtype=float)
    if value.shape != (size,):
        return None
    values = value.tolist()
    total = sum(values)  # inf or NaN if any value is (or if the sum overflows: numpy path)
    return values if total - total == 0.0 else None


def fast_solve(mass_matrix, wn, wt, u, mu, e, law, safe_low, safe_high):
    """The fields of :class:`planar_impact.solver.ImpactResult` as a dict, or None where the
    numpy path must decide (see the module docstring). ``law`` is already checked."""
    matrix = mass_matrix
    if type(matrix) is not np.ndarray or matrix.dtype is not _FLOAT:
        matrix = np.asarray(matrix, dtype=float)
    if matrix.ndim != 2:
        return None
    size = matrix.shape[0]
    if size == 0 or size > MAX_SPEEDS or matrix.shape[1] != size:
        return None
    key = matrix.tobytes()
    cached_key, factor = _last_factor
    if key != cached_key:  # a new M: check it, and factor it
        rows = matrix.tolist()
        total = sum(map(sum, rows))
        if not total - total == 0.0 or list(map(list, zip(*rows))) != rows:  # finite, symmetric
            return None
        factor = _cholesky(rows, size)
        if factor is None:
            return None
        factor = _sparse(factor, size)
        _remember(key, factor)
    last = _last_contact
    if (last[0] is factor and type(wn) is np.ndarray and type(wt) is np.ndarray
            and wn.ndim == 1 and wt.ndim == 1 and wn.dtype is _FLOAT and wt.dtype is _FLOAT
            and wn.tobytes() == last[1] and wt.tobytes() == last[2]):
        terms = last[3]  # this M's contact at these w_n, w_t: its terms as worked out before
    else:
        terms = None
        keys = (wn.tobytes() if type(wn) is np.ndarray and wn.dtype is _FLOAT else None,
                wt.tobytes() if type(wt) is np.ndarray and wt.dtype is _FLOAT else None)
        wn, wt = _floats(wn, size), _floats(wt, size)
    u = _floats(u, size)
    # μ and e: numbers in their ranges (NaN fails), else the numpy path decides
    if not (isinstance(mu, (float, int)) and isinstance(e, (float, int))):
        return None  # numpy's floats are floats too
    mu, e = float(mu), float(e)
    if (terms is None and (wn is None or wt is None)) or u is None or not (
            0.0 <= mu <= _LARGEST and 0.0 <= e <= 1.0):  # NaN fails too
        return None
    try:
        if terms is None:
            terms = (wn, wt, *_contact_terms(factor, size, wn, wt))
            if None not in keys:
                _remember_contact(factor, *keys, terms)
        return _solve(terms, u, mu, e, law, safe_low, safe_high)
    except (ZeroDivisionError, ValueError, OverflowError):  # a branch numpy answers with inf
        return None


_LARGEST = 1.7976931348623157e308
_FLOAT = np.dtype(float)


# The factor of the last M checked here (a function of M's bytes alone, so reusing it changes
# no result): a body's M stays while its contact and speeds change, as in a simulation or a
# fit that solves one impact at a time.
_last_factor: tuple = (None, None)


def _remember(key, factor):
    global _last_factor
    _last_factor = (key, factor)  # one assignment: another thread sees the old pair or the new


# The last contact's terms: ``(factor, w_n's bytes, w_t's bytes, (w_n, w_t, m_nn, m_nt, m_tt,
# Δ, M⁻¹w_n, M⁻¹w_t))``, a function of M (its factor, this very object) and of w_n, w_t
# alone, so reusing them changes no result: a fit or a sweep solves one contact at many
# speeds, μ, e and laws.
_last_contact: tuple = (None, None, None, None)


def _remember_contact(factor, wn_key, wt_key, terms):
    global _last_contact
    _last_contact = (factor, wn_key, wt_key, terms)  # one assignment, as _remember


def _solve(terms, u, mu, e, law, safe_low, safe_high):
    wn, wt, mnn, mnt, mtt, delta, inv_wn, inv_wt = terms
    vn = vt = 0.0
    for x, y, speed in zip(wn, wt, u):
        vn += x * speed
        vt += y * speed
    if not (safe_low < -vn < safe_high and abs(vt) < safe_high
            and safe_low < mnn < safe_high and safe_low < mtt < safe_high and delta > 0):
        return None  # out of range (the numpy path rescales), or no approach, or Δ ≤ 0
    sign = -1.0 if vt < 0 or (vt == 0 and mnt < 0) else 1.0  # t → −t as in solve_batch
    out = law_answer(law, mnn, sign * mnt, mtt, vn, abs(vt), mu, e, delta)
    if out is None:
        return None
    (normal, tangential, vn_separation, vt_separation, energy_change, ctype, case,
     e_poisson, at_boundary, alternative) = out
    tangential *= sign
    delta_u = [x * normal + y * tangential for x, y in zip(inv_wn, inv_wt)]  # (A16)
    total = sum(delta_u) + energy_change
    if not total - total == 0.0:
        return None
    # One array for both (two rows that never overlap): one numpy call fewer.
    delta_u, u_after = np.array([delta_u, [x + y for x, y in zip(u, delta_u)]])
    has_e = _POISSON_RESTITUTION[law]
    return {
        "law": law, "normal_impulse": normal, "tangential_impulse": tangential,
        "delta_u": delta_u, "u_after": u_after, "vn_approach": vn,
        "vn_separation": vn_separation, "vt_approach": vt,
        "vt_separation": sign * vt_separation, "energy_change": energy_change,
        "collision_type": ctype, "case": case,
        "restitution_poisson": e_poisson if has_e else None,
        "restitution_in_range": not has_e or 0.0 <= e_poisson <= 1.0,
        "mnn": mnn, "mnt": mnt, "mtt": mtt,
        "type_at_boundary": at_boundary, "alternative_type": alternative,
    }


def _cholesky(rows, size):
    """Lower factor ``L`` of ``M = L Lᵀ`` as lists of rows, or None where a pivot is not
    positive (``M`` not positive definite: the numpy path raises)."""
    factor = []
    for i in range(size):
        row, factor_i = rows[i], []
        for j in range(i):
            factor_j = factor[j]
            value = row[j]
            for k in range(j):
                value -= factor_i[k] * factor_j[k]
            factor_i.append(value / factor_j[j])
        pivot = row[i]
        for k in range(i):
            pivot -= factor_i[k] * factor_i[k]
        if not pivot > 0:
            return None
        factor_i.append(math.sqrt(pivot))
        factor.append(factor_i)
    return factor


def _sparse(factor, size):
    """``L`` as :func:`_contact_terms` reads it: ``(rows, columns, diagonal, pairs)``, per row
    ``i`` the pairs ``(k, L_ik)``, ``k < i``, per column ``i`` (last first) ``(i, L_ii)`` and
    the pairs ``(k, L_ki)``, ``k > i``, of its non-zero entries, the diagonal, and the index
    pairs ``i < j`` of Δ's minors; ``rows`` and ``columns`` are None for a diagonal ``L``.
    The bodies' ``M`` are diagonal or block-diagonal; a term ``0·x`` left out (``x``
    finite) changes no value, at most the sign of a zero."""
    rows = [tuple((k, factor[i][k]) for k in range(i) if factor[i][k] != 0.0)
            for i in range(size)]
    columns = [tuple((k, factor[k][i]) for k in range(i + 1, size) if factor[k][i] != 0.0)
               for i in range(size)]
    diagonal = [factor[i][i] for i in range(size)]
    pairs = tuple((i, j) for i in range(size) for j in range(i + 1, size))
    if not any(rows):  # L diagonal (so are its columns): divisions only
        return None, None, diagonal, pairs
    return (tuple(zip(diagonal, rows)),
            tuple((i, diagonal[i], columns[i]) for i in range(size - 1, -1, -1)),
            diagonal, pairs)


def _contact_terms(factor, size, wn, wt):
    """``(m_nn, m_nt, m_tt, Δ, M⁻¹w_n, M⁻¹w_t)`` (A20) from ``M``'s factor
    (:func:`_sparse`): ``a = L⁻¹ w_n``, ``b = L⁻¹ w_t`` in one pass, then ``M⁻¹ w = L⁻ᵀ a``
    (resp. ``b``). A diagonal ``L`` takes the same divisions without the loops."""
    rows, columns, diagonal, pairs = factor
    if rows is None:
        a = [x / d for x, d in zip(wn, diagonal)]
        b = [y / d for y, d in zip(wt, diagonal)]
        inv_wn = [x / d for x, d in zip(a, diagonal)]
        inv_wt = [y / d for y, d in zip(b, diagonal)]
    else:
        a, b = [], []
        for x, y, (d, entries) in zip(wn, wt, rows):
            for k, entry in entries:
                x -= entry * a[k]
                y -= entry * b[k]
            a.append(x / d)
            b.append(y / d)
        inv_wn, inv_wt = [0.0] * size, [0.0] * size
        for i, d, entries in columns:
            x, y = a[i], b[i]
            for k, entry in entries:
                x -= entry * inv_wn[k]
                y -= entry * inv_wt[k]
            inv_wn[i], inv_wt[i] = x / d, y / d
    mnn = mnt = mtt = 0.0
    for x, y, inverse_n, inverse_t in zip(wn, wt, inv_wn, inv_wt):
        mnn += x * inverse_n
        mnt += x * inverse_t
        mtt += y * inverse_t
    # Δ by Lagrange's identity: the sum of the squared minors a_i b_j − a_j b_i (no
    # cancellation, as planar_impact.solver.contact_terms).
    minors = [a[i] * b[j] - a[j] * b[i] for i, j in pairs]
    return mnn, mnt, mtt, math.fsum([minor * minor for minor in minors]), inv_wn, inv_wt


def law_answer(law, mnn, mnt, mtt, vn, vt, mu, e, delta):
    """:func:`planar_impact.contact_space.contact_space_solution` of one row in the theory's ``t``
    (``v_t ≥ 0``), bit for bit, as floats (a tuple in :data:`LAW_FIELDS` order); None where
    the row is not cleanly solved (an error status, or a division by zero). The law's own
    part is its ``row`` solver of :data:`planar_impact.law_table.LAW_TABLE`."""
    row = _ROW_SOLVERS.get(law)
    if row is None:  # a name in LAWS without its table entry must not run another law
        raise NotImplementedError(missing_branch(law, "fastpath.law_answer"))
    vn_abs = -vn
    mu_mtt, mu_mnt = mu * mtt, mu * mnt
    g, h = mu_mtt - mnt, mnn - mu_mnt  # (A35)
    p, q = mu_mtt + mnt, mnn + mu_mnt
    if h <= 0 and g <= 0:  # Painlevé jam
        return None
    case = laws.table1_case(g, h, p, q)
    answer = row(mnn, mnt, mtt, vn, vt, mu, e, delta, vn_abs, g, h, p, q, case)
    if answer is None:
        return None
    normal, tangential, ctype, e_poisson, at_boundary, alternative, reverse = answer
    if reverse and q <= 0:
        return None
    vn_separation = vn + (mnn * normal + mnt * tangential)  # (A22)
    vt_separation = vt + (mnt * normal + mtt * tangential)  # (A23)
    energy_change = 0.5 * (normal * (vn_separation + vn)
                           + tangential * (vt_separation + vt))  # (A29)
    return (normal, tangential, vn_separation, vt_separation, energy_change, ctype, case,
            e_poisson, at_boundary, alternative)


#: Each law's scalar solver, looked up once per call (LAW_TABLE's ``row``).
_ROW_SOLVERS = {name: solvers.row for name, solvers in LAW_TABLE.items()}
#: Whether each law reports a Poisson restitution e_i (LAW_TABLE's ``poisson_restitution``).
_POISSON_RESTITUTION = {name: solvers.poisson_restitution
                        for name, solvers in LAW_TABLE.items()}

#: What :func:`law_answer` returns, in order (names of :class:`planar_impact.BatchResult`).
LAW_FIELDS = ("normal_impulse", "tangential_impulse", "vn_separation", "vt_separation",
              "energy_change", "collision_type", "case", "restitution_poisson",
              "type_at_boundary", "alternative_type")
