"""Each law's own part of a solution, for :data:`planar_impact.law_table.LAW_TABLE`.

Two solvers per law, one for each path, that give the same bits on every row both solve
(``tests/theory/test_fastpath.py``):

* ``<law>_rows(terms, e)`` on contact-space arrays (:class:`planar_impact.laws.ContactTerms`),
  for :func:`planar_impact.contact_space.contact_space_solution`; returns ``(I_n, I_t,
  collision type, Poisson's e_i, consistent, type_at_boundary, alternative_type)``, the last
  four possibly numpy scalars standing for every row.
* ``<law>_row(mnn, mnt, mtt, vn, vt, mu, e, delta, vn_abs, g, h, p, q, case)`` on floats of
  one row (``v_t ≥ 0``, no Painlevé jam; ``g, h, p, q`` (A35), ``case`` Table 1's), for
  :func:`planar_impact.fastpath.law_answer`: the very expressions of
  :mod:`planar_impact.laws` in the same order; returns ``(I_n, I_t, collision type, e_i,
  type_at_boundary, alternative_type, reverse)`` (``reverse``: the type slides in reverse,
  which needs ``q > 0``), or None where the law has no consistent answer.

What the paths share (the separation velocities (A22)/(A23), the energy (A29), the status)
stays with them.
"""

from __future__ import annotations

import math

import numpy as np

from . import laws

_POISSON_TYPES = laws.POISSON_TYPE_BY_CASE_REGION
# type_at_boundary, alternative_type of the laws Table 1 does not decide
_NOT_BY_TABLE1 = np.False_, np.int8(0)


def poisson_rows(terms, e):
    ctype = laws.poisson_type(terms, e)
    at_boundary, alternative = laws.poisson_type_boundary(terms, e, ctype)
    normal, tangential = laws.poisson_impulses(terms, e, ctype)
    return normal, tangential, ctype, e, np.True_, at_boundary, alternative


def stronge_paper_rows(terms, e):
    # Type from Table 1 with e_e in place of e (end of the paper's Section 4), then
    # e_i by (64)/(67)/(70)/(73)/(74), then Poisson's closed forms with e_i.
    ctype = laws.poisson_type(terms, e)
    at_boundary, alternative = laws.poisson_type_boundary(terms, e, ctype)
    e_poisson = laws.stronge_paper_restitution(terms, e, ctype)
    normal, tangential = laws.poisson_impulses(terms, e_poisson, ctype)
    return normal, tangential, ctype, e_poisson, np.isfinite(e_poisson), at_boundary, alternative


def newton_lcp_rows(terms, e):
    normal, tangential, ctype, consistent = laws.newton_lcp(terms, e)
    e_poisson = np.float64(np.nan)  # not a process law: no I_nr/I_nc (NaN on every row)
    return (normal, tangential, ctype, e_poisson, consistent, *_NOT_BY_TABLE1)


def newton_rows(terms, e):
    return _process_rows(laws.TwoPhaseProcess(terms).newton, e)


def stronge_rows(terms, e):
    return _process_rows(laws.TwoPhaseProcess(terms).stronge, e)


def _process_rows(run, e):
    normal, tangential, ctype, compression = run(e)
    # Poisson's e of the process each law runs, I_nr/I_nc (6).
    e_poisson = (normal - compression) / compression
    return (normal, tangential, ctype, e_poisson, np.True_, *_NOT_BY_TABLE1)


def stronge_paper_row(mnn, mnt, mtt, vn, vt, mu, e, delta, vn_abs, g, h, p, q, case):
    return poisson_row(mnn, mnt, mtt, vn, vt, mu, e, delta, vn_abs, g, h, p, q, case, True)


def poisson_row(mnn, mnt, mtt, vn, vt, mu, e, delta, vn_abs, g, h, p, q, case,
                stronge_paper=False):
    """Poisson's law, or with ``stronge_paper`` the paper's Stronge mapping, on one row
    (Poisson's called directly: one call less on ``solve``'s scalar path).
    Rows near Table 1's band run the batch's candidate search
    (:func:`planar_impact.laws.poisson_type_boundary`) on numpy scalars."""
    alpha, r_m = vt / vn_abs, g / h  # (A34), (A36)
    upper = (1.0 + e) * r_m
    ctype = _POISSON_TYPES[3 * case + int(alpha > r_m) + int(alpha > upper)]
    at_boundary, alternative = False, 0
    if _near_table1_boundary(g, h, p, q, alpha, r_m, upper):
        # Rare (α ≈ 0 mostly): the candidate search of the batch, on numpy scalars.
        terms = laws.ContactTerms(*(np.float64(x) for x in (mnn, mnt, mtt, vn, vt, mu)),
                                  np.float64(delta))
        with np.errstate(all="ignore"):
            at_boundary, alternative = laws.poisson_type_boundary(terms, np.float64(e),
                                                                  ctype)
    e_poisson = e
    if stronge_paper:
        e_poisson = _stronge_paper_restitution(mnt, mtt, mu, g, alpha, r_m, e, ctype)
        if not math.isfinite(e_poisson):
            return None
    normal, tangential = _poisson_impulses(mnt, mtt, mu, vn_abs, vt, g, h, q, delta,
                                           e_poisson, ctype)
    reverse = ctype in (laws.REVERSE_FROM_COMPRESSION, laws.REVERSE_FROM_RESTITUTION)
    return normal, tangential, ctype, e_poisson, at_boundary, alternative, reverse


def newton_lcp_row(mnn, mnt, mtt, vn, vt, mu, e, delta, vn_abs, g, h, p, q, case):
    answer = _newton_lcp(mnn, mnt, mtt, vt, mu, vn_abs, g, h, p, q, delta, e)
    if answer is None:
        return None
    normal, tangential, ctype = answer
    return (normal, tangential, ctype, math.nan, False, 0,  # not decided by Table 1
            ctype == laws.NEWTON_REVERSE)


def newton_row(mnn, mnt, mtt, vn, vt, mu, e, delta, vn_abs, g, h, p, q, case):
    normal, tangential, ctype, compression = _process(True, mnt, mtt, vt, mu, vn_abs, g, h,
                                                      p, q, delta, e)
    e_poisson = (normal - compression) / compression
    return (normal, tangential, ctype, e_poisson, False, 0, ctype == laws.NEWTON_REVERSE)


def stronge_row(mnn, mnt, mtt, vn, vt, mu, e, delta, vn_abs, g, h, p, q, case):
    normal, tangential, ctype, compression = _process(False, mnt, mtt, vt, mu, vn_abs, g, h,
                                                      p, q, delta, e)
    e_poisson = (normal - compression) / compression
    reverse = ctype in (laws.REVERSE_FROM_COMPRESSION, laws.REVERSE_FROM_RESTITUTION)
    return normal, tangential, ctype, e_poisson, False, 0, reverse


def _near_table1_boundary(g, h, p, q, alpha, r_m, upper, band=laws.TYPE_BAND):
    """laws.poisson_type_boundary's screen (a superset of the rows inside the band), on
    floats; the inputs are finite here, so Python's min/max equal numpy's."""
    wide = 2.0 * band
    abs_g, abs_p, abs_h, abs_q = abs(g), abs(p), abs(h), abs(q)
    width = wide * (1.0 + abs(alpha) + abs(upper) + abs(r_m))
    # min(x, y) <= wide·max(x, y), written out (x, y >= 0, never NaN: no builtin calls)
    return ((abs_g <= wide * abs_p if abs_g <= abs_p else abs_p <= wide * abs_g)
            or (abs_h <= wide * abs_q if abs_h <= abs_q else abs_q <= wide * abs_h)
            or abs(alpha - r_m) <= width or abs(alpha - upper) <= width or alpha <= width)


def _poisson_impulses(mnt, mtt, mu, vn_abs, vt, g, h, q, delta, e, ctype):
    """laws.poisson_impulses for one type: (25)/(34)/(29, 40, 48), (26)/(36, 44)/(49)."""
    if ctype == laws.STICK_IN_COMPRESSION:
        compression = (mtt * vn_abs + mnt * vt) / delta  # (25)
    elif ctype == laws.REVERSE_FROM_COMPRESSION:
        compression = (vn_abs + mnt * (2.0 * mu * vt / g)) / q  # (34)
    else:
        compression = vn_abs / h  # (29), (40), (48)
    normal = (1.0 + e) * compression
    if ctype <= laws.STICK_IN_RESTITUTION:
        tangential = -(mnt * normal + vt) / mtt  # (26), (29)
    elif ctype == laws.FORWARD_SLIDING:
        tangential = -(mu * normal)  # (49)
    else:
        tangential = mu * normal - 2.0 * mu * vt / g  # (36)/(44)
    return normal, tangential


def _stronge_paper_restitution(mnt, mtt, mu, g, alpha, r_m, e_energetic, ctype):
    """laws.stronge_paper_restitution for one type: (64)/(67)/(70)/(73)/(74)."""
    if ctype == laws.FORWARD_SLIDING:
        return e_energetic  # (74)
    e2 = e_energetic * e_energetic
    ratio = mnt / mtt if ctype <= laws.STICK_IN_RESTITUTION else 2.0 * mu * mnt / g
    linear = ratio * alpha  # r (62) or s (68)
    in_restitution = ctype in (laws.STICK_IN_RESTITUTION, laws.REVERSE_FROM_RESTITUTION)
    shift = ratio * (r_m - alpha) if in_restitution else 0.0  # y (65) or z (71)
    a, b, c = 1.0 + linear + shift, linear + 2.0 * shift, shift - e2
    discriminant = b * b - 4.0 * a * c
    if discriminant < 0:
        return math.nan
    root = math.sqrt(discriminant)
    if b >= 0:
        b_plus_root = b + root
        return -2.0 * c / b_plus_root if b_plus_root > 0 else 0.0 * root
    return (root - b) / (2.0 * a)


def _newton_lcp(mnn, mnt, mtt, vt, mu, vn_abs, g, h, p, q, delta, e):
    """laws.newton_lcp for one row: ``(I_n, I_t, type)``, or None where inconsistent."""
    closing = (1.0 + e) * vn_abs
    stick_n = (mtt * closing + mnt * vt) / delta
    stick_t = -(mnn * vt + mnt * closing) / delta
    rounding = 1e-12
    cone = mu * stick_n
    stick_size = abs(stick_t)
    if stick_n >= 0 and stick_size <= cone + rounding * (stick_size + cone):
        return stick_n, stick_t, laws.NEWTON_STICK
    slide_terms = abs(mnt) + mu * mtt
    if h > 0:
        forward_n = closing / h
        if vt - g * forward_n >= -rounding * (vt + slide_terms * forward_n):
            return forward_n, -mu * forward_n, laws.NEWTON_FORWARD
    if q > 0:
        reverse_n = closing / q
        if vt + p * reverse_n <= rounding * (vt + slide_terms * reverse_n):
            return reverse_n, mu * reverse_n, laws.NEWTON_REVERSE
    return None


def _process(newton, mnt, mtt, vt, mu, vn_abs, g, h, p, q, delta, e):
    """laws.TwoPhaseProcess.newton / .stronge for one row: ``(I_n, I_t, type, P_c)``."""
    sticks = p >= 0
    finite_g = False
    if g > 0:
        quotient = vt / g  # P_G (A58)
        finite_g = math.isfinite(quotient)
    p_g = quotient if finite_g else 0.0
    vn_g = h * p_g - vn_abs
    slope_n2 = delta / mtt if sticks else q
    compression_in_phase1 = not finite_g or vn_g >= 0.0
    compression = (vn_abs / h if compression_in_phase1
                   else p_g - vn_g / slope_n2)
    if newton:
        target = e * vn_abs
        forward = not finite_g or vn_g >= target
        normal = ((target + vn_abs) / h if forward
                  else p_g + (target - vn_g) / slope_n2)
        ctype = laws.NEWTON_FORWARD if forward else laws.NEWTON_STICK + int(not sticks)
    else:
        work_to_g = 0.5 * vn_g * (p_g - compression)
        absorbed = (0.5 * vn_abs * compression if compression_in_phase1
                    else 0.5 * (vn_abs - vn_g) * p_g + work_to_g)
        work_target = (e * e) * absorbed
        ends_in_phase1 = compression_in_phase1 and (not finite_g or work_to_g >= work_target)
        if ends_in_phase1:
            normal = compression + math.sqrt(2.0 * work_target / h)
            ctype = laws.FORWARD_SLIDING
        else:
            start = p_g if compression_in_phase1 else compression
            v_start = vn_g if compression_in_phase1 else 0.0
            remaining = work_target - work_to_g if compression_in_phase1 else work_target
            twice_remaining = 2.0 * (remaining if remaining >= 0.0 else 0.0)
            root = math.sqrt(v_start * v_start + slope_n2 * twice_remaining)
            denominator = v_start + root
            step = (twice_remaining / denominator if denominator > 0
                    else math.sqrt(twice_remaining / slope_n2))
            normal = start + step
            ctype = (laws.STICK_IN_COMPRESSION + int(compression_in_phase1)
                     + 2 * int(not sticks))
    if not finite_g or normal <= p_g:
        tangential = -mu * normal
    else:
        slope_t2 = -mnt / mtt if sticks else mu
        tangential = slope_t2 * (normal - p_g) - mu * p_g
    return normal, tangential, ctype, compression
