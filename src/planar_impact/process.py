"""The impulse process on Routh's graph, walked exactly, segment by segment.

This is the second, independent implementation of the laws (the first is the closed forms
of :mod:`planar_impact.laws`). It knows nothing of Table 1, collision types or ``α``: it
only follows the impulse process of docs/theory.md, 'Routh's diagram and collision types'.
With the normal impulse ``P`` as the clock, the contact velocities are linear in ``P`` inside
each phase:

    dv_n/dP = m_nn + m_nt s,    dv_t/dP = m_nt + m_tt s,    s = dI_t/dP,

with ``s = −μ sign(v_t)`` while sliding and, at ``v_t = 0``, ``s = −m_nt/m_tt`` (sticking) if
``|m_nt| ≤ μ m_tt``, else sliding restarts in the direction ``sign(m_nt)``. Each phase is a
straight segment, so the next event (slip stops, compression ends, the law terminates) is
found in closed form and the walk is exact: no time step, no ODE tolerance. It works for
either sign of ``v_t^A`` and returns the path, the vertices of Fig. 1's impulse diagram.

:func:`sequential_impulses` is the independent method for ``newton-lcp``: projected
Gauss–Seidel on the two contact rows, as sequential-impulse engines solve it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import ImpactInputError

PROCESS_LAWS = ("newton", "poisson", "stronge")


@dataclass(frozen=True)
class PathVertex:
    """One vertex of the impulse path. ``mode`` is the phase that *starts* here."""

    normal_impulse: float  # P
    tangential_impulse: float  # I_t
    vn: float  # contact normal velocity
    vt: float  # contact tangential velocity (slip)
    normal_work: float  # ∫ v_n dP from the start
    mode: str  # "slide+", "slide-", "stick" or "end"


@dataclass(frozen=True)
class ProcessResult:
    normal_impulse: float
    tangential_impulse: float
    vn_separation: float
    vt_separation: float
    energy_change: float
    compression_impulse: float  # I_nc, where v_n = 0
    slip_stop_impulse: float | None  # P where the initial slip first vanished (None: never)
    mode_after_stop: str | None  # "stick", "forward" or "reverse" (relative to the initial slip)
    path: tuple[PathVertex, ...]


def _phase(vt: float, mnt: float, mtt: float, mu: float) -> tuple[str, float]:
    """Tangential mode at slip ``vt`` and its ``s = dI_t/dP``."""
    if vt > 0.0:
        return "slide+", -mu
    if vt < 0.0:
        return "slide-", mu
    if abs(mnt) <= mu * mtt:
        return "stick", -mnt / mtt
    direction = 1.0 if mnt > 0 else -1.0
    return ("slide+" if direction > 0 else "slide-"), -mu * direction


def impulse_process(mnn, mnt, mtt, vn, vt, mu, e, law, max_segments: int = 16) -> ProcessResult:
    """Walk the impulse process until ``law`` ("newton", "poisson", "stronge") ends it.

    Newton ends where ``v_n = e|v_n^A|``; Poisson at ``P = (1 + e) I_nc``; Stronge when the
    normal work since maximum compression equals ``−e²`` times the work in compression.
    Raises :class:`ImpactInputError` for a Painlevé-type jam (``v_n`` can never recover).
    """
    if law not in PROCESS_LAWS:
        raise ImpactInputError(f"law: {law!r} is not a process law; allowed: {PROCESS_LAWS}")
    if not vn < 0:
        raise ImpactInputError(f"vn: {vn!r}; allowed: v_n^A < 0 (approach)")
    impulse, tangential, work = 0.0, 0.0, 0.0
    vn_approach, vt_approach = vn, vt
    newton_target = e * -vn
    compression_impulse = None
    compression_work = None
    initial_sign = 1.0 if vt >= 0 else -1.0
    slip_stop, mode_after_stop = None, None
    if vt == 0.0:  # no initial slip: the "stop" is at the start
        slip_stop, mode_after_stop = 0.0, _relative(_phase(0.0, mnt, mtt, mu)[0], initial_sign)
    path = []
    for _ in range(max_segments):
        mode, slope_t = _phase(vt, mnt, mtt, mu)
        path.append(PathVertex(impulse, tangential, vn, vt, work, mode))
        dvn = mnn + mnt * slope_t
        # sticking, s = −m_nt/m_tt makes dv_t/dP exactly 0: its rounded form (an ulp either
        # way) would let the slip drift off the sticking line and the next phase slide
        dvt = 0.0 if mode == "stick" else mnt + mtt * slope_t
        # Distance in P to each candidate event; math.inf where it never happens.
        stick_at = -vt / dvt if vt != 0.0 and vt * dvt < 0 else math.inf
        if compression_impulse is None:
            compress_at = -vn / dvn if dvn > 0 else math.inf
            end_at = math.inf
            if law == "newton" and newton_target == 0.0:
                end_at = compress_at  # e = 0: v_n reaches 0 = e|v_n^A|
        else:
            compress_at = math.inf
            if law == "poisson":
                end_at = (1.0 + e) * compression_impulse - impulse
            elif law == "newton":
                if vn >= newton_target:
                    end_at = 0.0
                else:
                    end_at = (newton_target - vn) / dvn if dvn > 0 else math.inf
            else:  # stronge: v_n x + ½ dv_n x² = remaining restitution work (≥ 0)
                remaining = -(e * e) * compression_work - (work - compression_work)
                end_at = 0.0 if remaining <= 0.0 else _work_step(vn, dvn, remaining)
        step = min(stick_at, compress_at, end_at)
        if not math.isfinite(step):
            raise ImpactInputError(
                f"Painlevé-type jam: v_n = {vn!r} with dv_n/dP = {dvn!r} in mode {mode} never "
                "recovers (no admissible continuation)"
            )
        impulse += step
        tangential += slope_t * step
        work += vn * step + 0.5 * dvn * step * step
        vn += dvn * step
        vt += dvt * step
        if step == stick_at:
            vt = 0.0  # land exactly on the sticking line
            if slip_stop is None:
                slip_stop = impulse
                mode_after_stop = _relative(_phase(0.0, mnt, mtt, mu)[0], initial_sign)
        if step == compress_at:
            vn = 0.0
            compression_impulse, compression_work = impulse, work
        if step == end_at and compression_impulse is not None:
            if law == "newton":
                vn = newton_target
            path.append(PathVertex(impulse, tangential, vn, vt, work, "end"))
            # (A29)
            energy = 0.5 * impulse * (vn + vn_approach) + 0.5 * tangential * (vt + vt_approach)
            return ProcessResult(
                normal_impulse=impulse,
                tangential_impulse=tangential,
                vn_separation=vn,
                vt_separation=vt,
                energy_change=energy,
                compression_impulse=compression_impulse,
                slip_stop_impulse=slip_stop,
                mode_after_stop=mode_after_stop,
                path=tuple(path),
            )
    raise ImpactInputError(f"impulse process did not end within {max_segments} segments")


def _work_step(vn: float, dvn: float, remaining: float) -> float:
    """Smallest x ≥ 0 with ``vn·x + ½·dvn·x² = remaining`` (> 0); the rationalised root
    ``2R/(v + √(v² + 2kR))`` stays accurate when ``v² ≫ kR``."""
    disc = vn * vn + 2.0 * dvn * remaining
    if disc < 0:
        return math.inf
    denominator = vn + math.sqrt(disc)
    return 2.0 * remaining / denominator if denominator > 0 else math.inf


def _relative(mode: str, initial_sign: float) -> str:
    """Name a mode relative to the initial slip: "stick", "forward" or "reverse"."""
    if mode == "stick":
        return "stick"
    direction = 1.0 if mode == "slide+" else -1.0
    return "forward" if direction == initial_sign else "reverse"


def process_collision_type(result: ProcessResult, newton_numbering: bool = False) -> int:
    """Collision type read off the path: where the initial slip stopped and what followed.

    Poisson/Stronge numbering 1–5 (stick/reverse from compression or restitution, forward);
    Newton numbering 1 stick, 2 reverse, 3 forward. With ``v_t^A = 0`` and no sticking,
    sliding starts along ``sign(m_nt)``; "forward" is the orientation of ``t``.
    """
    after = result.mode_after_stop
    if result.slip_stop_impulse is None or after == "forward":
        return 3 if newton_numbering else 5
    if newton_numbering:
        return 1 if after == "stick" else 2
    in_compression = result.slip_stop_impulse <= result.compression_impulse
    if after == "stick":
        return 1 if in_compression else 2
    return 3 if in_compression else 4


def sequential_impulses(mnn, mnt, mtt, vn, vt, mu, e, tolerance=1e-13, max_iterations=100_000):
    """``newton-lcp`` by projected Gauss–Seidel, as sequential-impulse engines solve it.

    Alternately: the normal impulse that brings ``v_n`` to ``e|v_n^A|`` (clamped ≥ 0), then
    the tangential impulse that stops the slip, clamped to the cone ``|I_t| ≤ μ I_n``.
    Returns ``(I_n, I_t, iterations)``; converges linearly, at a rate set by
    ``m_nt²/(m_nn m_tt)``.
    """
    target = e * -vn
    normal, tangential = 0.0, 0.0
    for iteration in range(1, max_iterations + 1):
        vn_now = vn + mnn * normal + mnt * tangential
        new_normal = max(0.0, normal + (target - vn_now) / mnn)
        vt_now = vt + mnt * new_normal + mtt * tangential
        bound = mu * new_normal
        new_tangential = min(bound, max(-bound, tangential - vt_now / mtt))
        change = abs(new_normal - normal) + abs(new_tangential - tangential)
        normal, tangential = new_normal, new_tangential
        if change <= tolerance * (abs(normal) + abs(tangential)):
            return normal, tangential, iteration
    return normal, tangential, max_iterations


def newton_lcp_modes(mnn, mnt, mtt, vn, vt, mu, e):
    """Every consistent mode of the ``newton-lcp`` complementarity problem, by enumeration.

    Tries sticking and sliding in both directions, each a linear 2×2 problem, and keeps those
    that satisfy all of Coulomb's conditions. Returns ``[(mode, I_n, I_t), …]``; the law is
    well posed where exactly one mode is returned. (PGS, :func:`sequential_impulses`, may
    fail to converge: while sliding its normal step multiplies the error by
    ``|1 − h/m_nn| = μ|m_nt|/m_nn``, above 1 when ``μ|m_nt| > m_nn``; measured by
    ``impact-harness findings``.)
    """
    closing = (1.0 + e) * -vn
    modes = []
    delta = mnn * mtt - mnt * mnt
    stick_n = (mtt * closing + mnt * vt) / delta
    stick_t = -(mnn * vt + mnt * closing) / delta
    if stick_n >= 0 and abs(stick_t) <= mu * stick_n:
        modes.append(("stick", stick_n, stick_t))
    for direction in (1.0, -1.0):  # final slip along +t or −t, friction against it
        slope = mnn - direction * mu * mnt
        if slope <= 0:
            continue
        normal = closing / slope
        tangential = -direction * mu * normal
        slip = vt + mnt * normal + mtt * tangential
        if direction * slip > 0:
            modes.append(("slide+" if direction > 0 else "slide-", normal, tangential))
    return modes
