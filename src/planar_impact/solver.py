"""The public solver for one problem in generalized speeds: ``solve``, with the checks of its
inputs, the contact terms (A20) formed without cancellation, and ``law_solver`` /
``solve_contact`` for callers that solve one contact several times.

It screens its input, flips the tangent where ``v_t^A < 0`` (the theory assumes
``v_t^A ≥ 0``; results come back in the caller's ``t``), runs one law from
:mod:`planar_impact.laws` (:mod:`planar_impact.contact_space`, as ``solve_batch`` does), and
completes the answer with (A22), (A23) and (A29). The usual problem takes the fast path of
plain floats (:mod:`planar_impact.fastpath`), with the same answer.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import errors, fastpath
from .contact_space import (
    SAFE_HIGH,
    SAFE_LOW,
    answer_status,
    check_law,
    contact_space_solution,
    scale_exponents,
    solve_scaled,
)
from .errors import ImpactInputError
from .law_table import LAW_TABLE


@dataclass(frozen=True)
class ImpactResult:
    """One solved impact.

    Impulses act on body B (``−R`` on A); ``t`` is the caller's tangent. Units follow the
    inputs (SI: N·s, m/s, J). ``collision_type`` is 1–5 as in the paper for Poisson and
    Stronge, and 1 stick, 2 reverse sliding, 3 forward sliding for ``newton`` and
    ``newton-lcp``; ``case`` is the Table 1 row. ``restitution_poisson`` is the ``e_i`` of
    Poisson's definition (6) the law amounts to (``e`` itself for Poisson, the mapped value
    for ``stronge-paper``, ``I_nr/I_nc`` of the process for ``newton`` and ``stronge``, None
    for ``newton-lcp``, which is not a process).
    """

    law: str
    normal_impulse: float
    tangential_impulse: float
    delta_u: np.ndarray
    u_after: np.ndarray
    vn_approach: float
    vn_separation: float
    vt_approach: float
    vt_separation: float
    energy_change: float
    collision_type: int
    case: int
    restitution_poisson: float | None
    restitution_in_range: bool
    mnn: float
    mnt: float
    mtt: float
    #: Table 1's type decided inside its band (laws.TYPE_BAND), and the other candidate
    #: (0 when clear; only poisson and stronge-paper take their type from Table 1).
    type_at_boundary: bool = False
    alternative_type: int = 0

    @property
    def energy_gained(self) -> bool:
        """True where the law created kinetic energy (Newton's law can, Table 1 of Part A):
        ``ΔE`` above :data:`ENERGY_GAIN_BAR` of the work beyond (A29)'s rounding
        (:func:`energy_gain_decision`); False inside that band (``energy_gain_at_boundary``)."""
        return bool(self._energy_decision()[0])

    @property
    def energy_gain_at_boundary(self) -> bool:
        """True where ``ΔE`` lies within (A29)'s rounding bound of the gain bar: either
        answer is right, and another CPU's last bits may give the other one."""
        return bool(self._energy_decision()[1])

    def _energy_decision(self):
        return energy_gain_decision(self.energy_change, self.normal_impulse,
                                    self.tangential_impulse, self.vn_approach,
                                    self.vt_approach, self.mnn, self.mnt, self.mtt)


#: The gain bar, relative to the work ``|v_n^A I_n| + |v_t^A I_t|``: a stated judgement, not
#: a bound. It stands for the impulses' own error, which (A29) carries to ΔE and no a priori
#: bound covers for every law (the closed forms are good to a few units of 2⁻⁵³ relative);
#: (A29)'s own rounding, which can exceed it where the terms cancel, is the derived band
#: :func:`energy_rounding_bound` around it.
ENERGY_GAIN_BAR = 1e-12

#: Roundings along each term of (A29) as the library evaluates it (contact_space, fastpath):
#: ``m I`` (1), ``+ m I`` (2), ``+ v`` (3), ``+ v`` (4), ``× I`` (5), the two axes' sum (6);
#: the half is exact. One more covers the bound's own evaluation (a few u of a bound that is
#: itself ~6u of the terms).
ENERGY_ROUNDINGS = 7
_UNIT_ROUNDOFF = 2.0 ** -53
#: The subnormal spacing, per product (six) that may underflow outside the 1 + δ model.
_UNDERFLOW = 6 * 2.0 ** -1074


def energy_rounding_bound(normal, tangential, vn, vt, mnn, mnt, mtt):
    """Forward error bound of (A29) ``ΔE = ½ I_n (v_n' + v_n) + ½ I_t (v_t' + v_t)``, with
    ``v'`` from (A22), (A23), as evaluated from the impulses: ``γ_7 ½ Σ_axis |I| (|v| + |v|
    + |m_·n I_n| + |m_·t I_t|)`` (Higham (3.5): every term of the expanded sum rounded at
    most :data:`ENERGY_ROUNDINGS` times, in any order). Against the exact ΔE of the same
    floats; scalars or arrays. The solver's rescaling (``ldexp``) is exact save subnormals."""
    gamma = ENERGY_ROUNDINGS * _UNIT_ROUNDOFF / (1 - ENERGY_ROUNDINGS * _UNIT_ROUNDOFF)
    reach_n = 2 * abs(vn) + abs(mnn * normal) + abs(mnt * tangential)
    reach_t = 2 * abs(vt) + abs(mnt * normal) + abs(mtt * tangential)
    return gamma * 0.5 * (abs(normal) * reach_n + abs(tangential) * reach_t) + _UNDERFLOW


def energy_gain_decision(energy_change, normal, tangential, vn, vt, mnn, mnt, mtt):
    """``(gained, at_boundary)``: whether the law created energy, a decision with a derived
    band (docs/verdicts.md, 'Same answers on every CPU'). The cut is the bar
    ``ENERGY_GAIN_BAR · (|v_n I_n| + |v_t I_t|)``; the band is
    :func:`energy_rounding_bound`. ``gained`` where ΔE exceeds the cut by more than the band
    (the exact ΔE of these impulses is above the bar); ``at_boundary`` where ΔE lies within
    the band of the cut (then ``gained`` is False: no gain is claimed on rounding). Scalars
    or arrays (numpy's elementwise ``+ − ×``, the same bits on every CPU)."""
    work = abs(vn * normal) + abs(vt * tangential)
    cut = ENERGY_GAIN_BAR * work
    band = energy_rounding_bound(normal, tangential, vn, vt, mnn, mnt, mtt)
    gained = energy_change > cut + band
    at_boundary = abs(energy_change - cut) <= band
    return gained, at_boundary


def _impact_result(fields: dict) -> ImpactResult:
    """``ImpactResult(**fields)`` for a complete ``fields`` (the fast path's): the frozen
    dataclass's ``__init__`` sets each of its 20 fields through ``object.__setattr__``,
    a third of a fast call."""
    result = object.__new__(ImpactResult)
    result.__dict__.update(fields)
    return result


def as_vector(name: str, value, length: int | None = None) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.ndim != 1:
        raise ImpactInputError(f"{name}: expected a 1-D vector, got shape {array.shape}")
    if length is not None and array.shape[0] != length:
        raise ImpactInputError(
            f"{name}: length {array.shape[0]} does not match mass_matrix size {length}"
        )
    if not np.all(np.isfinite(array)):
        raise ImpactInputError(f"{name}: must be finite, got {array.tolist()}")
    return array


def check_scalar(name: str, value, low: float, high: float) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ImpactInputError(f"{name}: expected a number, got {value!r}") from None
    if not np.isfinite(number) or not (low <= number <= high):
        allowed = f"[{low}, {high}]" if np.isfinite(high) else f"≥ {low}"
        raise ImpactInputError(f"{name}: {number!r} is not allowed; allowed: {allowed}")
    return number


def check_mass_matrix(mass_matrix) -> np.ndarray:
    matrix = np.asarray(mass_matrix, dtype=float)
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1] or matrix.shape[0] == 0:
        raise ImpactInputError(f"mass_matrix: must be square, got shape {matrix.shape}")
    if not np.isfinite(matrix).all():
        raise ImpactInputError("mass_matrix: must be finite (contains NaN or inf)")
    if np.array_equal(matrix, matrix.T):  # the usual case, and the cheap test
        return matrix
    scale = np.max(np.abs(matrix))
    asymmetry = np.max(np.abs(matrix - matrix.T))
    if asymmetry > 1e-12 * scale:  # round-off of a symmetric assembly stays far below this
        raise ImpactInputError(
            f"mass_matrix: must be symmetric, largest |M − Mᵀ| is {asymmetry:.3g} "
            f"(scale {scale:.3g})"
        )
    return matrix


def _gram_minors(cholesky, inverse_w) -> np.ndarray:
    """The 2×2 minors ``a_i b_j − a_j b_i`` (i < j) of ``a = L⁻¹ w_n``, ``b = L⁻¹ w_t``,
    ``M = L Lᵀ``, formed as ``Lᵀ M⁻¹ w`` from ``inverse_w = M⁻¹ [w_n, w_t]`` (a product,
    several times cheaper than a second solve).

    ``m_nn = a·a``, ``m_nt = a·b``, ``m_tt = b·b`` (A20), so by Lagrange's identity
    ``Δ = |a|²|b|² − (a·b)²`` is the sum of the minors' squares: a sum of positive terms,
    free of the cancellation of ``m_nn m_tt − m_nt²`` (a rod of mass 1e9 kg and inertia
    1e-9 kg m² has ``m_nn m_tt ≈ 1e16`` and ``Δ ≈ 0.25``).
    """
    a, b = (cholesky.T @ inverse_w).T
    if a.shape[0] > 8:
        upper = np.triu_indices(a.shape[0], 1)
        return (np.multiply.outer(a, b) - np.multiply.outer(b, a))[upper]
    # Few speeds (3 per body): plain floats, several times cheaper than numpy's calls.
    a, b = a.tolist(), b.tolist()
    return [a[i] * b[j] - a[j] * b[i] for i in range(len(a)) for j in range(i + 1, len(a))]


def contact_terms(mass_matrix, wn, wt) -> tuple[float, float, float, float]:
    """``(m_nn, m_nt, m_tt, Δ)`` (A20) of a problem in generalized speeds, with ``Δ``
    formed without cancellation (see :func:`_gram_minors`); pass ``Δ`` to
    :func:`solve_batch` as ``delta``.

    ``Δ`` underflows to 0 where ``m_nn m_tt`` is below ~1e-308; :func:`solve` scales
    those problems first.
    """
    matrix = np.asarray(mass_matrix, dtype=float)
    wn, wt = np.asarray(wn, dtype=float), np.asarray(wt, dtype=float)
    inverse_w = np.linalg.solve(matrix, np.stack([wn, wt], axis=1))
    inv_wn, inv_wt = inverse_w.T
    minors = _gram_minors(np.linalg.cholesky(matrix), inverse_w)
    return (float(wn @ inv_wn), float(wn @ inv_wt), float(wt @ inv_wt),
            math.fsum(minor * minor for minor in minors))


def solve(*, mass_matrix, wn, wt, u, mu, e, law: str = "poisson") -> ImpactResult:
    """Solve one planar one-point impact with friction in generalized speeds.

    Parameters
    ----------
    mass_matrix : (p, p) symmetric positive definite, kinetic energy ``½ uᵀ M u``.
    wn, wt : (p,) the partial velocities of the contact ``v_r^R·n`` and ``v_r^R·t`` (A16);
        ``n`` points from body A into body B. ``t`` may have either orientation.
    u : (p,) generalized speeds just before the impact; must be approaching (``wn·u < 0``).
    mu : friction coefficient ``μ ≥ 0``.  e : restitution in [0, 1] (Stronge's ``e_e`` for
        the two Stronge laws).
    law : one of :data:`LAWS`.

    Raises :class:`ImpactInputError` (a ``ValueError``) naming the field, the value and
    what is allowed; never returns NaN or inf.
    """
    check_law(law)
    # Plain floats for the usual problem (planar_impact.fastpath: same answer as below, the
    # contact terms within rounding); None sends every other case down the numpy path.
    fields = fastpath.fast_solve(mass_matrix, wn, wt, u, mu, e, law, SAFE_LOW, SAFE_HIGH)
    if fields is not None:
        return _impact_result(fields)
    return solve_contact(*_checked_inputs(mass_matrix, wn, wt, u, mu, e), law)


def _checked_inputs(mass_matrix, wn, wt, u, mu, e) -> tuple:
    """What :func:`solve` checks and derives of its inputs besides the law, in its order:
    ``(CheckedContact, u, mu, e)``, or the :class:`ImpactInputError` of the first bad one."""
    matrix = check_mass_matrix(mass_matrix)
    size = matrix.shape[0]
    wn = as_vector("wn", wn, size)
    wt = as_vector("wt", wt, size)
    u = as_vector("u", u, size)
    mu = check_scalar("mu", mu, 0.0, np.inf)
    e = check_scalar("e", e, 0.0, 1.0)
    return checked_contact(matrix, wn, wt), u, mu, e


def law_solver(*, mass_matrix, wn, wt, u, mu, e) -> Callable[[str], ImpactResult]:
    """``solve_law(law)``, :func:`solve` of these inputs with ``law``, bit for bit, raising
    what it raises: the inputs are checked and ``M``'s factors worked out once for all the
    laws asked (a sweep point solves its problem with every law of the scenario)."""
    try:
        checked, failure = _checked_inputs(mass_matrix, wn, wt, u, mu, e), None
    except ValueError as error:  # ImpactInputError, or numpy's on a value not a number
        checked, failure = None, error

    def solve_law(law: str) -> ImpactResult:
        check_law(law)
        fields = fastpath.fast_solve(mass_matrix, wn, wt, u, mu, e, law, SAFE_LOW, SAFE_HIGH)
        if fields is not None:  # as solve does: the same answer where it answers
            return _impact_result(fields)
        if failure is not None:  # the error solve raises, raised anew for each law
            raise type(failure)(*failure.args)
        return solve_contact(*checked, law)

    return solve_law


@dataclass(frozen=True)
class CheckedContact:
    """What :func:`solve` derives from ``M``, ``w_n`` and ``w_t`` alone (:func:`checked_contact`),
    for a caller that solves one contact at several speeds (:func:`solve_contact`)."""

    matrix: np.ndarray
    wn: np.ndarray
    wt: np.ndarray
    inv_w: np.ndarray  # M⁻¹ w_n, M⁻¹ w_t as columns
    mnn: float  # (A20)
    mnt: float
    mtt: float
    minors: list  # _gram_minors: Δ (A20) is the sum of their squares


def checked_contact(matrix, wn, wt) -> CheckedContact:
    """The contact of :func:`solve` with its inputs already checked (float arrays of matching
    sizes, ``matrix`` symmetric and finite); raises :class:`ImpactInputError` where ``M`` is
    not positive definite."""
    try:
        cholesky = np.linalg.cholesky(matrix)  # also the positive-definiteness test
    except np.linalg.LinAlgError:
        raise ImpactInputError("mass_matrix: must be positive definite (Cholesky failed)") from None
    inv_w = np.linalg.solve(matrix, np.stack([wn, wt], axis=1))  # M⁻¹ w_n, M⁻¹ w_t
    inv_wn, inv_wt = inv_w[:, 0], inv_w[:, 1]
    mnn, mnt, mtt = float(wn @ inv_wn), float(wn @ inv_wt), float(wt @ inv_wt)  # (A20)
    return CheckedContact(matrix, wn, wt, inv_w, mnn, mnt, mtt, _gram_minors(cholesky, inv_w))


def solve_contact(contact: CheckedContact, u, mu: float, e: float, law: str) -> ImpactResult:
    """:func:`solve` of a :class:`CheckedContact` at speeds ``u`` (a finite float vector of
    its size), with ``mu``, ``e`` and ``law`` already checked: the same answer bit for bit."""
    matrix, wn, wt, inv_w = contact.matrix, contact.wn, contact.wt, contact.inv_w
    inv_wn, inv_wt = inv_w[:, 0], inv_w[:, 1]
    mnn, mnt, mtt = contact.mnn, contact.mnt, contact.mtt
    vn, vt = float(wn @ u), float(wt @ u)
    # The batch kernels on numpy float64 scalars: same code, without array overhead.
    sign = -1.0 if vt < 0 or (vt == 0 and mnt < 0) else 1.0  # t → −t as in solve_batch
    scalars = [np.float64(x) for x in (mnn, sign * mnt, mtt, vn, abs(vt), mu, e)]
    minors = contact.minors
    in_range = (SAFE_LOW < -vn < SAFE_HIGH and abs(vt) < SAFE_HIGH
                and SAFE_LOW < mnn < SAFE_HIGH and SAFE_LOW < mtt < SAFE_HIGH)
    if in_range:
        delta = np.float64(math.fsum(minor * minor for minor in minors))  # (A20), Gram form
    else:
        speed_exponent, mass_exponent = scale_exponents(scalars[0], scalars[2], scalars[3],
                                                         scalars[4])
        scaled = [math.ldexp(minor, -int(mass_exponent)) for minor in minors]
        delta = np.float64(math.fsum(minor * minor for minor in scaled))  # Δ·2^(-2·exponent)
    # μ, e, finiteness and M > 0 are checked above; what is left of input_status:
    if not vn < 0:
        status = errors.NO_APPROACH
    elif not delta > 0:  # M > 0 but w_n, w_t parallel
        status = errors.NOT_POSITIVE_DEFINITE
    else:
        with np.errstate(all="ignore"):
            if in_range:
                out = contact_space_solution(law, *scalars, delta=delta)
            else:
                out, _ = solve_scaled(law, *scalars, speed_exponent, mass_exponent,
                                       delta)
        status = int(answer_status(law, errors.SOLVED, out))
    if status != errors.SOLVED:
        detail = {
            errors.NO_APPROACH: f"u: v_n^A = wn·u = {vn!r}; allowed: v_n^A < 0 (approach)",
            errors.NOT_POSITIVE_DEFINITE: (
                f"wn, wt: m_nn = {mnn!r}, m_nt = {mnt!r}, m_tt = {mtt!r} give "
                f"Δ = {float(delta)!r}; allowed: Δ > 0 (wn and wt independent)"
            ),
        }.get(status, f"mu = {mu!r}, e = {e!r}: {errors.STATUS_MESSAGES[status]}")
        raise ImpactInputError(f"{detail} [{errors.STATUS_MESSAGES[status]}]")
    normal, tangential = float(out["normal_impulse"]), sign * float(out["tangential_impulse"])
    e_poisson = float(out["restitution_poisson"])
    has_e = LAW_TABLE[law].poisson_restitution  # a velocity-level law has no e_i
    delta_u = inv_wn * normal + inv_wt * tangential  # M Δu = w_n I_n + w_t I_t (A16)
    if not (math.isfinite(float(out["energy_change"])) and np.isfinite(delta_u).all()):
        raise ImpactInputError(
            f"u: approach velocities v_n^A = {vn!r}, v_t^A = {vt!r} with mass_matrix scale "
            f"{np.max(np.abs(matrix)):.3g} give energy change {float(out['energy_change'])!r} "
            f"[{errors.STATUS_MESSAGES[errors.OUTPUT_OVERFLOW]}]"
        )
    return ImpactResult(
        law=law,
        normal_impulse=normal,
        tangential_impulse=tangential,
        delta_u=delta_u,
        u_after=u + delta_u,
        vn_approach=vn,
        vn_separation=float(out["vn_separation"]),
        vt_approach=vt,
        vt_separation=sign * float(out["vt_separation"]),
        energy_change=float(out["energy_change"]),
        collision_type=int(out["collision_type"]),
        case=int(out["case"]),
        restitution_poisson=e_poisson if has_e else None,
        restitution_in_range=not has_e or 0.0 <= e_poisson <= 1.0,
        mnn=mnn,
        mnt=mnt,
        mtt=mtt,
        type_at_boundary=bool(out["type_at_boundary"]),
        alternative_type=int(out["alternative_type"]),
    )
