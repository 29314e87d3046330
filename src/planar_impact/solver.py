"""The public solver: ``solve`` for one problem in generalized speeds, ``solve_batch`` for
arrays of contact-space problems.

Both screen their input, flip the tangent where ``v_t^A < 0`` (the theory assumes
``v_t^A ≥ 0``; results come back in the caller's ``t``), run one law from
:mod:`planar_impact.laws`, and complete the answer with (A22), (A23) and (A29).

Every law is homogeneous: scaling the approach velocities by ``s`` scales the separation
velocities and impulses by ``s``, and scaling ``m_nn, m_nt, m_tt`` by ``k`` scales the
impulses by ``1/k`` (docs/theory.md, 'Contact terms', (A22)/(A23)). Rows whose velocities or
inverse-inertia terms lie outside ``2^±SAFE_EXPONENT`` are solved scaled by powers of two to
unit size and scaled back, so that intermediate products (Stronge's work ``~ v²/m``) neither
overflow nor underflow; powers of two make both scalings exact. Rows inside the range are
solved as given, bit for bit as before the scaling existed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np

from . import errors, fastpath, laws
from .errors import ImpactInputError

LAWS: tuple[str, ...] = ("newton", "poisson", "stronge", "stronge-paper", "newton-lcp")


def check_law(law: str) -> str:
    if law not in LAWS:
        raise ImpactInputError(
            f"law: unknown law {law!r}; allowed: {', '.join(LAWS)}"
        )
    return law


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
    terms = laws.ContactTerms(mnn, mnt, mtt, vn, vt, mu, delta)
    consistent = np.True_
    at_boundary, alternative = np.False_, np.int8(0)  # laws not decided by Table 1
    if law == "poisson":
        ctype = laws.poisson_type(terms, e)
        at_boundary, alternative = laws.poisson_type_boundary(terms, e, ctype)
        normal, tangential = laws.poisson_impulses(terms, e, ctype)
        e_poisson = e
    elif law == "stronge-paper":
        # Type from Table 1 with e_e in place of e (end of the paper's Section 4), then
        # e_i by (64)/(67)/(70)/(73)/(74), then Poisson's closed forms with e_i.
        ctype = laws.poisson_type(terms, e)
        at_boundary, alternative = laws.poisson_type_boundary(terms, e, ctype)
        e_poisson = laws.stronge_paper_restitution(terms, e, ctype)
        consistent = np.isfinite(e_poisson)
        normal, tangential = laws.poisson_impulses(terms, e_poisson, ctype)
    elif law == "newton-lcp":
        normal, tangential, ctype, consistent = laws.newton_lcp(terms, e)
        e_poisson = np.float64(np.nan)  # not a process law: no I_nr/I_nc (NaN on every row)
    else:
        process = laws.TwoPhaseProcess(terms)
        run = process.newton if law == "newton" else process.stronge
        normal, tangential, ctype, compression = run(e)
        # Poisson's e of the process each law runs, I_nr/I_nc (6).
        e_poisson = (normal - compression) / compression
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
    q_fails = _reverse_sliding(law, out["collision_type"]) & (out["q"] <= 0)
    answer = where(np.logical_not(out["consistent"]), errors.NO_CONSISTENT_SOLUTION, errors.SOLVED)
    answer = where(q_fails, errors.REVERSE_SLIDING_Q_NONPOSITIVE, answer)
    answer = where(jam, errors.PAINLEVE_JAM, answer)
    return laws.as_type_code(where(solved, answer, status))


@dataclass(frozen=True)
class BatchResult:
    """Arrays of one shape (the broadcast of the inputs); NaN where ``status != 0``.

    ``status`` codes are in :data:`planar_impact.errors.STATUS_MESSAGES`.
    ``collision_type`` and ``case`` are 0 where the row is not solved.
    ``restitution_in_range`` is False where the ``e_i`` used leaves [0, 1] (the paper's
    Table 2 for ``"stronge-paper"``). ``type_at_boundary`` is True where Table 1's type is
    decided inside its band (:data:`planar_impact.laws.TYPE_BAND`: a point that close has
    another type), ``alternative_type`` that other type (0 elsewhere); only ``poisson`` and
    ``stronge-paper`` take their type from Table 1 (False and 0 for the other laws).
    """

    law: str
    status: np.ndarray
    normal_impulse: np.ndarray
    tangential_impulse: np.ndarray
    vn_approach: np.ndarray
    vn_separation: np.ndarray
    vt_approach: np.ndarray
    vt_separation: np.ndarray
    energy_change: np.ndarray
    collision_type: np.ndarray
    case: np.ndarray
    restitution_poisson: np.ndarray
    restitution_in_range: np.ndarray
    type_at_boundary: np.ndarray
    alternative_type: np.ndarray

    def status_message(self, index) -> str:
        return errors.STATUS_MESSAGES[int(self.status[index])]

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


def solve_batch(mnn, mnt, mtt, vn, vt, mu, e, law: str = "poisson", *,
                delta=None) -> BatchResult:
    """Solve many contact-space problems at once (vectorised; inputs broadcast).

    Parameters are the (A20) inverse-inertia terms ``m_nn, m_nt, m_tt``, the approach
    velocities ``v_n^A`` (must be < 0) and ``v_t^A`` (either sign: results are in the
    caller's ``t``), friction ``μ ≥ 0`` and restitution ``e ∈ [0, 1]``. ``delta``, optional,
    is ``Δ = m_nn m_tt − m_nt²`` (A20) formed without cancellation (:func:`contact_terms`);
    without it ``Δ`` is formed from the three terms.

    A bad row never spoils the others: it gets a non-zero ``status`` and NaN outputs.
    Rows of any scale are solved (see the module docstring); ``status`` 9 marks only
    answers that leave float64's range. An unknown ``law`` raises
    :class:`ImpactInputError` (it concerns every row).
    """
    check_law(law)
    values = [mnn, mnt, mtt, vn, vt, mu, e] + ([] if delta is None else [delta])
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in values))
    shape = arrays[0].shape
    # Work on flat 1-D arrays (0-d inputs included), reshape the answers at the end.
    flat = [np.ravel(a) for a in arrays]
    size = flat[0].size
    result = {name: np.empty(size, dtype=dtype) for name, dtype in _BATCH_DTYPES.items()}
    # Chunks small enough that the kernels' temporaries stay in cache (measured at 10^6 rows:
    # 8192 rows is the fastest, 1.2x faster than 65536 and 2x faster than 1024).
    for start in range(0, size, BATCH_CHUNK):
        rows = slice(start, start + BATCH_CHUNK)
        chunk = [a[rows] for a in flat] + [None] * (8 - len(flat))
        _solve_chunk(law, chunk, {k: v[rows] for k, v in result.items()})
    status = result.pop("status")
    result = {name: np.reshape(values, shape) for name, values in result.items()}
    return BatchResult(law=law, status=np.reshape(status, shape), **result)


BATCH_CHUNK = 8192

# Rows with |v_n^A|, m_nn and m_tt in [2^-64, 2^64] and |v_t^A| < 2^64 are solved as given:
# every intermediate (at most ~v²/m times a conditioning factor) stays far inside float64.
# Others are scaled by powers of two first (_solve_scaled).
SAFE_EXPONENT = 64
_SAFE_LOW, _SAFE_HIGH = 2.0**-SAFE_EXPONENT, 2.0**SAFE_EXPONENT
_BATCH_DTYPES = {
    "status": np.int8, "normal_impulse": float, "tangential_impulse": float, "vn_approach": float,
    "vn_separation": float, "vt_approach": float, "vt_separation": float, "energy_change": float,
    "collision_type": np.int8, "case": np.int8, "restitution_poisson": float,
    "restitution_in_range": bool, "type_at_boundary": bool, "alternative_type": np.int8,
}


def _solve_chunk(law, inputs, out):
    """Solve one chunk of rows, writing into the views ``out``."""
    mnn, mnt, mtt, vn, vt, mu, e, given_delta = inputs
    # The theory's t makes v_t^A ≥ 0. Where v_t^A = 0 it also takes m_nt ≥ 0, so that a
    # slip that develops runs along +t ("forward"): types then do not depend on the caller's t.
    flipped = (vt < 0) | ((vt == 0) & (mnt < 0))
    any_flipped = bool(flipped.any())
    if any_flipped:  # t → −t: m_nt and v_t change sign, the rest does not.
        # Multiplying by ±1 is exact, and far cheaper than a masked negative; ±1 by
        # arithmetic, as np.where branches on every row.
        sign = 1.0 - 2.0 * flipped
        mnt = mnt * sign
    # |v_t| also on rows not flipped: v_t = −0.0 becomes +0.0 whatever its neighbours.
    vt_pos = np.abs(vt)
    with np.errstate(all="ignore"):
        solution = contact_space_solution(law, mnn, mnt, mtt, vn, vt_pos, mu, e, out,
                                          given_delta)
        # Fast screen: valid rows inside the safe range. NaN fails every comparison; inf in
        # m_nt makes Δ inf or NaN, inf in μ shows in the sum. Rows failing it (invalid, or
        # outside the range) are solved again by _solve_scaled, which checks them in full.
        delta = solution["delta"]
        ok = (vn < -_SAFE_LOW) & (vn > -_SAFE_HIGH) & (vt_pos < _SAFE_HIGH)
        ok &= (mnn > _SAFE_LOW) & (mnn < _SAFE_HIGH) & (mtt > _SAFE_LOW) & (mtt < _SAFE_HIGH)
        ok &= (mu >= 0) & (e >= 0) & (e <= 1) & (delta > 0)
        ok &= np.isfinite(delta + mu)
        # Rows answer_status would flag (exactly its tests, so that it runs only when needed).
        trouble = (solution["h"] <= 0) & (solution["g"] <= 0)
        trouble |= _reverse_sliding(law, solution["collision_type"]) & (solution["q"] <= 0)
        if solution["consistent"] is not np.True_:
            trouble |= ~solution["consistent"]
    status = out["status"]
    status[...] = errors.SOLVED
    if trouble.any():
        status[...] = answer_status(law, status, solution)
    # vn_separation, vt_separation and energy_change are already in out.
    out["normal_impulse"][...] = solution["normal_impulse"]
    if any_flipped:
        np.multiply(solution["tangential_impulse"], sign, out=out["tangential_impulse"])
        out["vt_separation"] *= sign
    else:
        out["tangential_impulse"][...] = solution["tangential_impulse"]
    out["vn_approach"][...] = vn
    out["vt_approach"][...] = vt
    out["collision_type"][...] = solution["collision_type"]
    out["case"][...] = solution["case"]
    out["type_at_boundary"][...] = solution["type_at_boundary"]
    out["alternative_type"][...] = solution["alternative_type"]
    e_poisson = solution["restitution_poisson"]
    out["restitution_poisson"][...] = e_poisson
    if e_poisson is e:  # Poisson: e passed the screen wherever the row is solved
        out["restitution_in_range"][...] = True
    else:
        out["restitution_in_range"][...] = (e_poisson >= 0) & (e_poisson <= 1)
    if not ok.all():
        rows = np.flatnonzero(~ok)
        _solve_rows_scaled(law, rows, (mnn, mnt, mtt, vn, vt_pos, mu, e, given_delta),
                           sign if any_flipped else None, out)
    # Finite inputs whose answer passes float64's range: flagged, not returned as a silent
    # inf. The energy change multiplies impulses and velocities, so it overflows first and
    # is non-finite whenever any of them is (rows scaled back are checked in full).
    finite_answer = np.isfinite(out["energy_change"])
    if ok.all() and not trouble.any() and finite_answer.all():
        return
    status[(status == errors.SOLVED) & ~finite_answer] = errors.OUTPUT_OVERFLOW
    bad = status != errors.SOLVED
    if bad.any():
        for name, values in out.items():
            if name == "status" or name.endswith("approach"):
                continue
            values[bad] = (False if values.dtype == bool
                           else (0 if values.dtype.kind == "i" else np.nan))


def _scale_exponents(mnn, mtt, vn, vt):
    """Exponents ``(a, b)`` such that ``v·2^-a`` and ``m·2^-b`` are of order 1: ``a`` from
    the larger of ``|v_n^A|, |v_t^A|``, ``b`` from the geometric mean of ``m_nn, m_tt``."""
    speed_exponent = np.frexp(np.maximum(np.abs(vn), np.abs(vt)))[1]
    mass_exponent = (np.frexp(mnn)[1] + np.frexp(mtt)[1]) // 2
    return speed_exponent, mass_exponent


def _solve_scaled(law, mnn, mnt, mtt, vn, vt, mu, e, speed_exponent, mass_exponent,
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


def _solve_rows_scaled(law, rows, inputs, sign, out):
    """Solve ``rows`` of a chunk scaled to unit size, check their inputs in full, and write
    their answers and status into ``out`` (tangent already flipped in ``inputs``)."""
    mnn, mnt, mtt, vn, vt, mu, e, given_delta = (
        None if a is None else a[rows] for a in inputs
    )
    finite = np.isfinite(mnn) & np.isfinite(mnt) & np.isfinite(mtt)
    finite &= np.isfinite(vn) & np.isfinite(vt) & np.isfinite(mu) & np.isfinite(e)
    with np.errstate(all="ignore"):
        speed_exponent, mass_exponent = _scale_exponents(mnn, mtt, vn, vt)
        scaled_delta = None
        if given_delta is not None:
            finite &= np.isfinite(given_delta)
            scaled_delta = np.ldexp(given_delta, -2 * mass_exponent)
        solution, scaled_delta = _solve_scaled(law, mnn, mnt, mtt, vn, vt, mu, e,
                                               speed_exponent, mass_exponent, scaled_delta)
        scaled_mnn, scaled_mnt, scaled_mtt = (np.ldexp(m, -mass_exponent) for m in (mnn, mnt, mtt))
        status = input_status(scaled_mnn, scaled_mnt, scaled_mtt, vn, vt, mu, e, finite=finite,
                              delta=scaled_delta)
        status = answer_status(law, status, solution)
    tangential, vt_separation = solution["tangential_impulse"], solution["vt_separation"]
    if sign is not None:
        tangential, vt_separation = tangential * sign[rows], vt_separation * sign[rows]
    out["status"][rows] = status
    out["normal_impulse"][rows] = solution["normal_impulse"]
    out["tangential_impulse"][rows] = tangential
    out["vn_separation"][rows] = solution["vn_separation"]
    out["vt_separation"][rows] = vt_separation
    out["energy_change"][rows] = solution["energy_change"]
    out["collision_type"][rows] = solution["collision_type"]
    out["case"][rows] = solution["case"]
    out["type_at_boundary"][rows] = solution["type_at_boundary"]
    out["alternative_type"][rows] = solution["alternative_type"]
    e_poisson = solution["restitution_poisson"]
    out["restitution_poisson"][rows] = e_poisson
    out["restitution_in_range"][rows] = (e_poisson >= 0) & (e_poisson <= 1)
    # An impulse can overflow where the energy does not (v < 1 with m < v/1.8e308).
    answers = ("normal_impulse", "tangential_impulse", "vn_separation", "vt_separation")
    finite_answer = np.isfinite(solution["energy_change"])
    for name in answers:
        finite_answer &= np.isfinite(solution[name])
    overflow = (status == errors.SOLVED) & ~finite_answer
    out["status"][rows[overflow]] = errors.OUTPUT_OVERFLOW


def _reverse_sliding(law, ctype):
    if law in ("newton", "newton-lcp"):
        return ctype == laws.NEWTON_REVERSE
    return (ctype == laws.REVERSE_FROM_COMPRESSION) | (ctype == laws.REVERSE_FROM_RESTITUTION)


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
        """True where the law created kinetic energy (Newton's law can, Table 1 of Part A)."""
        scale = (abs(self.vn_approach) * self.normal_impulse
                 + abs(self.vt_approach * self.tangential_impulse))
        return self.energy_change > 1e-12 * scale


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
    fields = fastpath.fast_solve(mass_matrix, wn, wt, u, mu, e, law, _SAFE_LOW, _SAFE_HIGH)
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
        fields = fastpath.fast_solve(mass_matrix, wn, wt, u, mu, e, law, _SAFE_LOW, _SAFE_HIGH)
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
    in_range = (_SAFE_LOW < -vn < _SAFE_HIGH and abs(vt) < _SAFE_HIGH
                and _SAFE_LOW < mnn < _SAFE_HIGH and _SAFE_LOW < mtt < _SAFE_HIGH)
    if in_range:
        delta = np.float64(math.fsum(minor * minor for minor in minors))  # (A20), Gram form
    else:
        speed_exponent, mass_exponent = _scale_exponents(scalars[0], scalars[2], scalars[3],
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
                out, _ = _solve_scaled(law, *scalars, speed_exponent, mass_exponent,
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
        restitution_poisson=None if law == "newton-lcp" else e_poisson,
        restitution_in_range=law == "newton-lcp" or 0.0 <= e_poisson <= 1.0,
        mnn=mnn,
        mnt=mnt,
        mtt=mtt,
        type_at_boundary=bool(out["type_at_boundary"]),
        alternative_type=int(out["alternative_type"]),
    )
