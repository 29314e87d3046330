"""The five impact laws in closed form, vectorised over numpy arrays.

Every function here takes the contact-space description of a problem (the paper's (A20)
inverse-inertia terms ``m_nn, m_nt, m_tt``, the approach velocities ``v_n^A < 0`` and
``v_t^A ≥ 0``, ``μ`` and ``e``) as arrays of one shape, and returns arrays of that shape.
Rows are independent; invalid rows are screened by the caller (:mod:`planar_impact.solver`),
which also turns the impulses into velocities and energies, and runs these kernels under
``np.errstate(all="ignore")`` (branches not taken may divide by zero). The same kernels
accept numpy float64 scalars, which is how the scalar solver stays fast.

Equation numbers are the paper's (Djerassi, Part B); "A" numbers are Part A's, restated in
docs/theory.md, 'Conventions'. The independent check of every law is
:mod:`planar_impact.process`, which walks the impulse process segment by segment.

Throughout, ``P`` is the normal impulse used as the clock of the impulse process; the
process has at most two tangential phases
(docs/theory.md, 'Routh's diagram and collision types'): forward sliding
(``dI_t/dP = −μ``) until the slip vanishes at ``P_G = v_t^A/g`` (A58, with ``v_t^A`` for
the misprinted ``v_n^A``), then sticking (``dI_t/dP = −m_nt/m_tt``, if ``p ≥ 0``) or
reverse sliding (``dI_t/dP = +μ``, if ``p < 0``), both of which last to the end of the
impact.
"""

from __future__ import annotations

import numpy as np


def where(condition, if_true, if_false):
    """``np.where``'s answer, bit for bit; a plain conditional for scalars, where numpy's
    fixed cost would dominate (the scalar :func:`planar_impact.solve` runs these same
    kernels on numpy float64 scalars).

    For arrays it selects through a bit mask, ``false ^ ((true ^ false) & mask)`` on the
    values' bits, with ``mask`` all ones where the condition holds: ``np.where`` branches
    on every element, and with the unpredictable conditions of real rows that costs about three
    times the four branch-free passes (``impact-harness bench`` times the laws).
    """
    if type(condition) is not np.ndarray:
        return if_true if condition else if_false
    dtype = np.result_type(if_true, if_false)
    small = condition.size < _MASKED_SELECT_MIN_SIZE
    if small or condition.dtype != np.bool_ or dtype.kind not in "biuf":
        return np.where(condition, if_true, if_false)
    bits = np.dtype(f"i{dtype.itemsize}")
    true_bits = np.asarray(if_true, dtype).view(bits)
    false_bits = np.asarray(if_false, dtype).view(bits)
    selected = np.bitwise_and(true_bits ^ false_bits, np.negative(condition, dtype=bits))
    selected ^= false_bits
    return selected.view(dtype)


# Below this many rows np.where's single pass is cheaper than the masked selection's four.
_MASKED_SELECT_MIN_SIZE = 256


def as_type_code(values):
    """Collision types and cases as int8 arrays, or Python ints for scalars."""
    if type(values) is np.ndarray:
        return values.astype(np.int8)
    return int(values)

# Collision types (Poisson and Stronge numbering, the paper's Section 2).
STICK_IN_COMPRESSION = 1
STICK_IN_RESTITUTION = 2
REVERSE_FROM_COMPRESSION = 3
REVERSE_FROM_RESTITUTION = 4
FORWARD_SLIDING = 5

# Newton's law (Part A; Table 3's Newton rows) and newton-lcp number their types this way.
NEWTON_STICK = 1
NEWTON_REVERSE = 2
NEWTON_FORWARD = 3


class ContactTerms:
    """The derived scalars of the paper shared by every law, computed once per batch.

    ``delta`` (A20), ``g, h, p, q`` (A35), ``alpha`` (A34), ``r_m`` (A36) and the Table 1
    ``case`` (1–5). ``alpha`` and ``r_m`` are computed on first use: only the Poisson-type
    laws need them. ``delta`` may be given: ``m_nn m_tt − m_nt²`` cancels catastrophically
    when ``M⁻¹`` is dominated by one direction (a rod with ``m = 1e9``, ``I = 1e-9``), and a
    caller holding the generalized speeds can form it without cancellation
    (:func:`planar_impact.solver.contact_terms`).
    """

    __slots__ = ("mnn", "mnt", "mtt", "vn_abs", "vt", "mu", "delta", "g", "h", "p", "q",
                 "_alpha", "_r_m", "case")

    def __init__(self, mnn, mnt, mtt, vn, vt, mu, delta=None):
        self.mnn, self.mnt, self.mtt, self.mu = mnn, mnt, mtt, mu
        self.vn_abs = -vn
        self.vt = vt
        self.delta = mnn * mtt - mnt * mnt if delta is None else delta  # (A20)
        mu_mtt = mu * mtt
        mu_mnt = mu * mnt
        self.g = mu_mtt - mnt  # (A35)
        self.h = mnn - mu_mnt
        self.p = mu_mtt + mnt
        self.q = mnn + mu_mnt
        self._alpha = self._r_m = None
        self.case = table1_case(self.g, self.h, self.p, self.q)

    @property
    def alpha(self):
        if self._alpha is None:
            self._alpha = self.vt / self.vn_abs  # (A34)
        return self._alpha

    @property
    def r_m(self):
        if self._r_m is None:
            self._r_m = self.g / self.h  # (A36)
        return self._r_m


# Table 1 rows in priority order: the first condition that holds decides (g ≤ 0 → 5, else
# h ≤ 0 → 4, else p < 0 → 3, else q < 0 → 2, else 1; comment g of the paper lets equal signs
# join the remaining inequalities). Priority equals the row number, so the row is the largest
# number whose condition holds, which numpy computes without a branch or a gather.

# Poisson type by (case, region of α), flattened as ``3·case + region``: region 0 is α ≤ r_m
# (from compression), 1 is r_m < α ≤ (1+e) r_m (from restitution), 2 is beyond (forward
# sliding). Cases 1-2 stick, Case 3 reverses; Case 4 is Type 1 for every α > 0 (57) and
# Case 5 Type 5 (55).
POISSON_TYPE_BY_CASE_REGION: tuple[int, ...] = (
    0, 0, 0, 1, 2, 5, 1, 2, 5, 3, 4, 5, 1, 1, 1, 5, 5, 5)
_POISSON_TYPE_BY_CASE_REGION = np.array(POISSON_TYPE_BY_CASE_REGION, dtype=np.int8)


def table1_case(g, h, p, q):
    """Table 1 row (1–5) from the signs of ``g, h, p, q`` (A35)."""
    if type(g) is not np.ndarray or g.ndim == 0:
        return 5 if g <= 0 else 4 if h <= 0 else 3 if p < 0 else 2 if q < 0 else 1
    case = np.multiply(g <= 0, 5, dtype=np.int8)
    np.maximum(case, np.multiply(h <= 0, 4, dtype=np.int8), out=case)
    np.maximum(case, np.multiply(p < 0, 3, dtype=np.int8), out=case)
    np.maximum(case, np.multiply(q < 0, 2, dtype=np.int8), out=case)
    return np.maximum(case, 1, out=case)


def poisson_type(terms: ContactTerms, e):
    """Collision type (1–5) under Poisson's law by Table 1 (with (53)–(57)).

    Equality at a region boundary does not matter: the results are continuous there
    (comment a).
    """
    alpha, r_m = terms.alpha, terms.r_m
    if type(alpha) is not np.ndarray or alpha.ndim == 0:
        region = int(alpha > r_m) + int(alpha > (1.0 + e) * r_m)
        return int(_POISSON_TYPE_BY_CASE_REGION[3 * terms.case + region])
    index = np.multiply(terms.case, 3, dtype=np.int8)
    index += alpha > r_m
    index += alpha > (1.0 + e) * r_m
    return _POISSON_TYPE_BY_CASE_REGION.take(index)


#: Table 1's boundary band (docs/theory.md, 'Decisions at a boundary'): the type is at the
#: boundary where a sign of ``g, h, p, q`` (A35) is within TYPE_BAND of its scale
#: (``μ m_tt + |m_nt|`` for g and p, ``m_nn + μ|m_nt|`` for h and q), or ``α`` (A34) within
#: TYPE_BAND·(1 + |α|) of ``r_m``, of ``(1+e) r_m`` (53)–(57) or of 0 (the orientation of
#: ``t``), and a point inside that band has another type. Rounding moves these by a few
#: 1e-16 of their scale; 1e-9 leaves a factor 10^6 for the conditioning of the inputs.
TYPE_BAND = 1e-9


def poisson_type_boundary(terms: ContactTerms, e, ctype, band=TYPE_BAND):
    """``(at_boundary, alternative)`` for the Table 1 types ``ctype`` of :func:`poisson_type`:
    whether some point within ``band`` (see :data:`TYPE_BAND`) has another type, and the
    smallest such type (0 where none). For Poisson the other type's closed forms agree with
    ``ctype``'s at the boundary (comment a); the paper's Stronge mapping jumps at
    ``α = (1+e) r_m`` (docs/theory.md, 'Findings', 3), so there the two candidates differ.

    Rows far from every boundary are screened with a few comparisons; the candidates are
    evaluated only on the rows near one (arrays), so a batch pays little for it.
    """
    g, h, p, q, alpha, r_m = terms.g, terms.h, terms.p, terms.q, terms.alpha, terms.r_m
    upper = (1.0 + e) * r_m
    # A superset of the rows near a boundary (twice the band), in few passes: with μ ≥ 0,
    # max(|g|, |p|) = μ m_tt + |m_nt| and max(|h|, |q|) = m_nn + μ|m_nt| (A35), the scales
    # of the case signs; α's band is widened to cover both region thresholds at once.
    wide = 2.0 * band
    abs_g, abs_p, abs_h, abs_q = abs(g), abs(p), abs(h), abs(q)
    near = np.minimum(abs_g, abs_p) <= wide * np.maximum(abs_g, abs_p)
    near |= np.minimum(abs_h, abs_q) <= wide * np.maximum(abs_h, abs_q)
    width = wide * (1.0 + abs(alpha) + abs(upper) + abs(r_m))
    near |= (abs(alpha - r_m) <= width) | (abs(alpha - upper) <= width) | (alpha <= width)
    if type(near) is not np.ndarray or near.ndim == 0:
        if not near:
            return False, 0
        alternative = _nearby_types(terms, e, ctype, band, None)
        return bool(alternative), int(alternative)
    at_boundary = np.zeros(near.shape, dtype=bool)
    alternative = np.zeros(near.shape, dtype=np.int8)
    rows = np.flatnonzero(near)
    if rows.size:
        found = _nearby_types(terms, e, ctype, band, rows)
        at_boundary[rows] = found != 0
        alternative[rows] = found
    return at_boundary, alternative


def _nearby_types(terms, e, ctype, band, rows):
    """The smallest type other than ``ctype`` within ``band`` (0 where none), on ``rows``
    (None: scalars). Candidates: ``α ± width`` with the case as it is; each of ``g, h, p, q``
    at ``±`` its band with ``α`` as it is; and, where ``α`` is within the band of 0, the
    other orientation of ``t`` (``m_nt → −m_nt`` at ``α = 0``)."""
    def pick(value):
        if rows is None or np.ndim(value) == 0:
            return value
        return np.asarray(value)[rows]

    g, h, p, q = (pick(x) for x in (terms.g, terms.h, terms.p, terms.q))
    mnn, mnt, mtt, mu = (pick(x) for x in (terms.mnn, terms.mnt, terms.mtt, terms.mu))
    alpha, r_m, e, ctype = pick(terms.alpha), pick(terms.r_m), pick(e), pick(ctype)
    scale_gp = band * (mu * mtt + abs(mnt))
    scale_hq = band * (mnn + mu * abs(mnt))
    width = band * (1.0 + abs(alpha))
    case = table1_case(g, h, p, q)

    def type_of(case, alpha, r_m):
        region = (np.asarray(alpha > r_m, dtype=np.int8)
                  + np.asarray(alpha > (1.0 + e) * r_m, dtype=np.int8))
        return _POISSON_TYPE_BY_CASE_REGION.take(3 * np.asarray(case, dtype=np.int8) + region)

    candidates = [type_of(case, alpha + width, r_m), type_of(case, np.maximum(alpha - width, 0.0),
                                                             r_m)]
    for shift in (-1.0, 1.0):
        candidates.append(type_of(table1_case(g + shift * scale_gp, h, p, q), alpha, r_m))
        candidates.append(type_of(table1_case(g, h + shift * scale_hq, p, q), alpha, r_m))
        candidates.append(type_of(table1_case(g, h, p + shift * scale_gp, q), alpha, r_m))
        candidates.append(type_of(table1_case(g, h, p, q + shift * scale_hq), alpha, r_m))
    # The other orientation of t at α = 0: m_nt → −m_nt swaps g and p, and h and q (A35).
    flipped = type_of(table1_case(p, q, g, h), np.zeros_like(alpha), p / q)
    candidates.append(np.where(alpha <= width, flipped, ctype))
    best = np.full(np.shape(ctype), 127, dtype=np.int16)
    for candidate in candidates:
        other = np.asarray(candidate, dtype=np.int16)
        best = np.where((other != ctype) & (other < best), other, best)
    best = np.where(best == 127, 0, best).astype(np.int8)
    return best if rows is not None else int(best)


def poisson_impulses(terms: ContactTerms, e, ctype):
    """``(I_n, I_t)`` by the paper's closed forms for the given collision types.

    All five types share ``I_n = (1 + e) I_nc`` ((26), (29), (36), (44), (49)) and an
    ``I_t`` affine in ``I_n``; they differ in ``I_nc`` and in that line:

    * Type 1: ``I_nc = (m_tt + α m_nt)|v_n^A|/Δ`` (25); ``I_t = −(m_nt I_n + v_t^A)/m_tt`` (26).
    * Type 2: ``I_n = (1 + e)|v_n^A|/h`` (29); ``I_t`` as Type 1 (29).
    * Type 3: ``I_nc = [1 + 2μ m_nt α/g]|v_n^A|/q`` (34); ``I_t = μ I_n − 2μ v_t^A/g`` (36).
    * Type 4: ``I_nc = |v_n^A|/h`` (40); ``I_t`` as Type 3 (44).
    * Type 5: ``I_nc = |v_n^A|/h`` (48); ``I_t = −μ I_n`` (49).
    """
    mnt, mtt, mu, vt = terms.mnt, terms.mtt, terms.mu, terms.vt
    vn_abs = terms.vn_abs
    reverse = (ctype == REVERSE_FROM_COMPRESSION) | (ctype == REVERSE_FROM_RESTITUTION)
    reverse_offset = 2.0 * mu * vt / terms.g  # 2μ v_t^A/g, in (34), (36) and (44)
    # (25) and (34) multiplied through by |v_n^A| (α|v_n^A| = v_t^A): same values, and no
    # overflow of α when |v_n^A| is tiny (near-grazing impacts).
    compression = where(
        ctype == STICK_IN_COMPRESSION,
        (mtt * vn_abs + mnt * vt) / terms.delta,  # (25)
        where(
            ctype == REVERSE_FROM_COMPRESSION,
            (vn_abs + mnt * reverse_offset) / terms.q,  # (34)
            vn_abs / terms.h,  # (29), (40), (48)
        ),
    )
    normal_impulse = (1.0 + e) * compression
    friction_limit = mu * normal_impulse
    tangential_impulse = where(
        ctype <= STICK_IN_RESTITUTION,
        -(mnt * normal_impulse + vt) / mtt,  # (26), (29)
        where(reverse, friction_limit - reverse_offset, -friction_limit),  # (36)/(44), (49)
    )
    return normal_impulse, tangential_impulse


class TwoPhaseProcess:
    """The impulse process in closed form: ``v_n`` piecewise linear in ``P`` (docs/theory.md,
    'Routh's diagram and collision types').

    Phase 1 (forward sliding) has ``dv_n/dP = h`` and lasts until ``P_G = v_t^A/g`` (A58)
    (forever if ``g ≤ 0``: Case 5). Phase 2 has ``dv_n/dP = Δ/m_tt`` when sticking
    (``p ≥ 0``) or ``q`` when reverse sliding (``p < 0``), with ``dI_t/dP = −m_nt/m_tt`` or ``+μ``.
    """

    def __init__(self, terms: ContactTerms):
        self.terms = terms
        sticks = terms.p >= 0
        self.sticks = sticks
        self.reverses = np.logical_not(sticks)  # not ~: safe on Python bools too
        quotient = terms.vt / terms.g  # P_G (A58) where g > 0
        # P_G is infinite where g ≤ 0 (Case 5: the forward slip never vanishes) and where the
        # quotient overflows; those rows stay in phase 1 throughout.
        finite_g = (terms.g > 0) & np.isfinite(quotient)
        self.finite_g, self.infinite_g = finite_g, np.logical_not(finite_g)
        # P_G and v_n(P_G) = v_n^A + h P_G, with 0 for an infinite P_G: the phase-2 formulas
        # use them, and rows with an infinite P_G take phase 1 wherever they are used.
        self.p_g = where(finite_g, quotient, 0.0)
        self.vn_g = terms.h * self.p_g - terms.vn_abs
        self.slope_n1 = terms.h
        self.slope_n2 = where(sticks, terms.delta / terms.mtt, terms.q)
        self.slope_t2 = where(sticks, -terms.mnt / terms.mtt, terms.mu)

    def impulse_where_vn_reaches(self, target):
        """Smallest ``P`` at which ``v_n(P) = target`` (target ≥ 0 > v_n^A), and whether
        that is in phase 1."""
        in_phase1 = self.infinite_g | (self.vn_g >= target)
        phase1 = (target + self.terms.vn_abs) / self.slope_n1
        phase2 = self.p_g + (target - self.vn_g) / self.slope_n2
        return where(in_phase1, phase1, phase2), in_phase1

    def compression_impulse(self):
        """``P_c``, the end of compression (``v_n = 0``): :meth:`impulse_where_vn_reaches`
        at target 0, with the zero terms left out."""
        in_phase1 = self.infinite_g | (self.vn_g >= 0.0)
        phase1 = self.terms.vn_abs / self.slope_n1
        phase2 = self.p_g - self.vn_g / self.slope_n2
        return where(in_phase1, phase1, phase2), in_phase1

    def tangential_impulse(self, normal_impulse):
        """``I_t(P)``: ``−μ P`` up to ``P_G``, then ``−μ P_G + slope_t2 (P − P_G)``."""
        mu, p_g = self.terms.mu, self.p_g
        in_phase1 = self.infinite_g | (normal_impulse <= p_g)
        phase2 = self.slope_t2 * (normal_impulse - p_g) - mu * p_g
        return where(in_phase1, -mu * normal_impulse, phase2)

    def newton(self, e):
        """Newton's law (A30) along the process: it ends where ``v_n = e|v_n^A|``."""
        normal_impulse, forward = self.impulse_where_vn_reaches(e * self.terms.vn_abs)
        # Stick (1) or reverse (2) after the slip vanishes; forward sliding (3) throughout.
        ctype = where(forward, NEWTON_FORWARD, NEWTON_STICK + as_type_code(self.reverses))
        compression, _ = self.compression_impulse()
        return normal_impulse, self.tangential_impulse(normal_impulse), ctype, compression

    def stronge(self, e):
        """Stronge's energetic law, exact: the normal work in restitution ``∫ v_n dP`` equals
        ``e²`` times minus the normal work in compression (Stronge 2000; the paper's (60) with
        the work integrated along the piecewise-linear path rather than by ½ I (v^S + v^A)·n).
        """
        t = self.terms
        compression, compression_in_phase1 = self.compression_impulse()
        p_g, vn_g = self.p_g, self.vn_g
        # Work of v_n from P_c to P_G, a triangle (v_n = 0 at P_c): ≥ 0 whichever comes first.
        work_to_g = 0.5 * vn_g * (p_g - compression)
        # Minus the work of the normal impulse in compression (≥ 0): trapezoids of v_n over P.
        absorbed = where(
            compression_in_phase1,
            0.5 * t.vn_abs * compression,  # phase 1: v_n from v_n^A to 0
            0.5 * (t.vn_abs - vn_g) * p_g + work_to_g,  # v_n^A → v_n(P_G), then v_n(P_G) → 0
        )
        work_target = (e * e) * absorbed  # restitution work to reach, ≥ 0
        # If the slip vanishes during restitution, the work done before it does.
        ends_in_phase1 = compression_in_phase1 & (self.infinite_g | (work_to_g >= work_target))
        # In phase 1 after compression v_n = h (P − P_c): ½ h x² = target.
        end_phase1 = compression + np.sqrt(2.0 * work_target / self.slope_n1)
        # In phase 2 from P0 with v0 ≥ 0 and slope k: v0 x + ½ k x² = remaining work; the
        # rationalised root 2R/(v0 + √(v0² + 2kR)) stays accurate when v0² ≫ kR.
        start = where(compression_in_phase1, p_g, compression)
        v_start = where(compression_in_phase1, vn_g, 0.0)
        remaining = where(compression_in_phase1, work_target - work_to_g, work_target)
        # remaining is NaN where the compression work overflowed: fmax makes it 0, so that
        # row's step is 0.
        twice_remaining = 2.0 * np.fmax(remaining, 0.0)
        root = np.sqrt(v_start * v_start + self.slope_n2 * twice_remaining)
        # v0 = 0 with a subnormal remaining work (e ≈ 1e-162) makes 2kR, and the root,
        # underflow to 0: there the step is √(2R/k), which does not underflow.
        denominator = v_start + root
        step = where(denominator > 0, twice_remaining / denominator,
                     np.sqrt(twice_remaining / self.slope_n2))
        normal_impulse = where(ends_in_phase1, end_phase1, start + step)
        # Types 1-4 are 1 + (slip vanished in restitution) + 2·(reverse sliding after it).
        ctype = where(
            ends_in_phase1,
            FORWARD_SLIDING,
            STICK_IN_COMPRESSION + as_type_code(compression_in_phase1)
            + 2 * as_type_code(self.reverses),
        )
        return normal_impulse, self.tangential_impulse(normal_impulse), ctype, compression


def _positive_root(a, b, c):
    """The '+√' root of ``a x² + b x + c = 0`` (a > 0), computed without cancellation; NaN
    where there is no real root."""
    discriminant = b * b - 4.0 * a * c
    root = np.sqrt(discriminant)  # NaN where the discriminant is negative
    b_plus_root = b + root
    # b + root = 0 only when b = 0 and c = 0 (e_e = 0 with r or s = 0): the root is 0.
    # 0·root keeps a NaN root NaN there (b + NaN > 0 is False).
    stable = where(b_plus_root > 0, -2.0 * c / b_plus_root, 0.0 * root)
    return where(b >= 0, stable, (root - b) / (2.0 * a))


def stronge_paper_restitution(terms: ContactTerms, e_energetic, ctype):
    """The paper's Section 4 map from Stronge's ``e_e`` to Poisson's ``e_i``, per type.

    Type 1 (64): ``(1+r) e_i² + r e_i − e_e² = 0``, ``r = α m_nt/m_tt`` (62).
    Type 2 (67): ``(1+r+y) e_i² + (r+2y) e_i + y − e_e² = 0``, ``y = r(r_m/α − 1)`` (65)
    (the paper prints ``m_m`` for ``r_m``), written ``y = (m_nt/m_tt)(r_m − α)`` so that α = 0
    is harmless.
    Type 3 (70): as Type 1 with ``s = 2μ m_nt α/g`` (68).
    Type 4 (73): as Type 2 with ``s`` and ``z = s(r_m/α − 1) = (2μ m_nt/g)(r_m − α)`` (71).
    Type 5 (74): ``e_i = e_e``.
    NaN where the quadratic has no real root.
    """
    t = terms
    e2 = e_energetic * e_energetic
    sticking = ctype <= STICK_IN_RESTITUTION
    ratio = where(sticking, t.mnt / t.mtt, 2.0 * t.mu * t.mnt / t.g)  # r/α or s/α
    linear = ratio * t.alpha  # r (62) or s (68)
    in_restitution = (ctype == STICK_IN_RESTITUTION) | (ctype == REVERSE_FROM_RESTITUTION)
    shift = where(in_restitution, ratio * (t.r_m - t.alpha), 0.0)  # y (65) or z (71)
    e_i = _positive_root(1.0 + linear + shift, linear + 2.0 * shift, shift - e2)
    return where(ctype == FORWARD_SLIDING, e_energetic, e_i)


def newton_lcp(terms: ContactTerms, e):
    """The velocity-level Newton–Coulomb law of sequential-impulse engines.

    ``v_n^S = e|v_n^A|`` (A30) with Coulomb friction at the end state: stick (``v_t^S = 0``)
    if the cone ``|I_t| ≤ μ I_n`` allows it; else slide against the final slip,
    ``I_t = −μ·sign(v_t^S)·I_n``. Forward sliding needs ``h > 0`` and ``v_t^S ≥ 0``; reverse
    sliding ``q > 0`` and ``v_t^S ≤ 0``; for ``μ > 0`` at most one of the two is consistent
    (their conditions differ by ``2μΔ > 0``). Returns ``(I_n, I_t, type, consistent)``.
    """
    t = terms
    closing = (1.0 + e) * t.vn_abs  # required change of v_n
    # Sticking: m_nn I_n + m_nt I_t = (1+e)|v_n^A|, m_nt I_n + m_tt I_t = −v_t^A (A22, A23).
    stick_n = (t.mtt * closing + t.mnt * t.vt) / t.delta
    stick_t = -(t.mnn * t.vt + t.mnt * closing) / t.delta
    # Each test allows rounding (1e-12 of its terms): on the cone's edge, |m_nt| = μ m_tt,
    # stick and slide coincide and exact tests could both fail by an ulp.
    rounding = 1e-12
    cone = t.mu * stick_n
    stick_size = np.abs(stick_t)
    stick_ok = (stick_n >= 0) & (stick_size <= cone + rounding * (stick_size + cone))
    forward_n = closing / t.h
    reverse_n = closing / t.q
    slide_terms = np.abs(t.mnt) + t.mu * t.mtt
    forward_ok = (t.h > 0) & (
        t.vt - t.g * forward_n >= -rounding * (t.vt + slide_terms * forward_n))
    reverse_ok = (t.q > 0) & (t.vt + t.p * reverse_n <= rounding * (t.vt + slide_terms * reverse_n))
    slide_n = where(forward_ok, forward_n, reverse_n)
    normal_impulse = where(stick_ok, stick_n, slide_n)
    # Sliding: I_t = −μ·sign(v_t^S)·I_n, −μ forward and +μ reverse.
    tangential_impulse = where(stick_ok, stick_t, where(forward_ok, -t.mu, t.mu) * slide_n)
    # Stick 1; else reverse 2 or forward 3 (NEWTON_REVERSE + 1).
    ctype = where(stick_ok, NEWTON_STICK, NEWTON_REVERSE + as_type_code(forward_ok))
    consistent = stick_ok | forward_ok | reverse_ok
    return normal_impulse, tangential_impulse, ctype, consistent
