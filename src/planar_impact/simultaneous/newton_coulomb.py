"""The velocity-level Newton–Coulomb law on ``m`` contacts: what sequential-impulse engines
solve (docs/multi-contact.md, 'Newton–Coulomb for m contacts').

:func:`newton_coulomb_solutions` enumerates the ``4^m`` contact modes exactly and counts the
solutions by post-impact velocity; :func:`newton_coulomb` names the outcome;
:func:`projected_gauss_seidel` is the engines' own iteration, for the cross-check and as the
second method where no mode holds.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass

import numpy as np

from .system import (
    VELOCITY_TOLERANCE,
    ContactSystem,
    MultiContactSolution,
    assemble,
    frame_sign,
    lstsq_rows,
    speed_of,
)

# Newton–Coulomb contact modes (newton-lcp numbering, plus 0 for a contact that separates).
LCP_SEPARATE, LCP_STICK, LCP_REVERSE, LCP_FORWARD = 0, 1, 2, 3


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
    solution = assemble(system, "newton-coulomb", (0,) * system.count, impulses, True)
    for i in range(system.count):
        _mnn, mnt, _mtt = system.single_terms(i)
        sign = frame_sign(float(system.approach[2 * i + 1]), mnt)
        signs.append(sign)
        if solution.normal_impulse[i] <= impulse_tolerance:
            modes.append(LCP_SEPARATE)
        elif abs(solution.vt_separation[i]) <= tolerance:
            modes.append(LCP_STICK)
        else:
            modes.append(LCP_FORWARD if sign * solution.vt_separation[i] > 0 else LCP_REVERSE)
    solution = assemble(system, "newton-coulomb", modes, impulses, True)
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
            sign = frame_sign(float(approach[2 * i + 1]), mnt)
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
    solved = lstsq_rows(np.array([matrix for matrix, _, _ in systems]),
                         np.array([rhs for _, rhs, _ in systems]), rcond=1e-12)
    for modes, (matrix, rhs, signs), impulses, rank in zip(every_mode, systems, *solved):
        if np.max(np.abs(matrix @ impulses - rhs)) > tolerance * (1.0 + np.max(np.abs(matrix))):
            continue  # singular and inconsistent: this mode has no solution
        solution = assemble(system, "newton-coulomb", modes, impulses, rank == 2 * count)
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
        if np.max(np.abs(other.delta_u - solution.delta_u)) <= 1e-9 * speed_of(system):
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


__all__ = ["GaussSeidelResult", "LCP_FORWARD", "LCP_REVERSE", "LCP_SEPARATE", "LCP_STICK",
           "NC_GAUSS_SEIDEL_SWEEPS", "NC_NONE", "NC_SEVERAL", "NC_SPLIT_NOT_UNIQUE", "NC_STATUSES",
           "NC_UNIQUE", "NewtonCoulombResult", "newton_coulomb", "newton_coulomb_solutions",
           "projected_gauss_seidel", "restitution_targets"]
