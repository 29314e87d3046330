"""Is an m-contact solution physically admissible? Checked on every solution of every
reference at run time (docs/multi-contact.md, 'Admissible references').

A solution is given as its phases (:class:`Phase`): the contact velocities at the phase's
start and the impulses of the phase; each phase's end velocities are recomputed here from
``W`` (:class:`ContactSystem`), never taken from the law. The checks, per phase and contact,
with the stated tolerances (:data:`ADMISSIBLE_SPEED` of the system's speed scale,
:data:`ADMISSIBLE_IMPULSE` of its impulse scale, :data:`ADMISSIBLE_ENERGY` of ``½uᵀMu``):

* the friction cone: ``P_n ≥ 0`` and ``|P_t| ≤ μ_i P_n``;
* no penetration at the phase's end: ``v_n ≥ 0`` (for a Newton phase ``v_n ≥ e_i |v_n^A|``
  where the contact approached); for a per-contact impact, at the contacts it strikes and,
  after the last one, at every contact (a sequence strikes the others next);
* complementarity at the phase's end: a contact that takes more normal impulse than it is
  owed does not recede (``P_n − b > 0`` ⇒ ``v_n = b'``: compression ``b = 0``, ``b' = 0``;
  restitution ``b = e_i P_nc``, ``b' = 0``; Newton ``b = 0``, ``b' = e_i |v_n^A|``);
* no impulse at a contact that does not approach at its start, in a phase of a law that
  applies per-contact formulas (:data:`IMPACT`: the paper's proposal, a sequential impact);
  under a complementarity law such a contact may take only the impulse that holds it, which
  the complementarity test checks;
* no energy gain where the law promises none: ``ΔE = Σ_phases ½ P·(v_start + v_end)``
  ((A29) summed) ``≤ 0`` for Poisson's law and Stronge's exact law (``e_i ≤ 1``).

:func:`violations` returns a tuple of one-line descriptions, empty when the solution is
admissible; numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .system import ContactSystem

#: Phase kinds: a compression (complementary at ``v_n = 0``), a restitution (complementary
#: above the base ``e_i P_nc``), a Newton impact (complementary at ``e_i |v_n^A|``) and a
#: per-contact law's impact (no complementarity; no impulse where a contact does not
#: approach at the start).
COMPRESSION, RESTITUTION, NEWTON, IMPACT = "compression", "restitution", "newton", "impact"
KINDS = (COMPRESSION, RESTITUTION, NEWTON, IMPACT)

#: Tolerances, relative to the system's speed scale (the largest approach speed), its
#: impulse scale (that speed over W's smallest diagonal entry) and ``½uᵀMu``. The laws solve
#: to rounding (a few 1e-16 times W's condition, ≲ 1e-12 here); a break is a wrong answer,
#: orders of magnitude above these.
ADMISSIBLE_SPEED = 1e-8
ADMISSIBLE_IMPULSE = 1e-8
ADMISSIBLE_ENERGY = 1e-9

#: Laws that promise no energy gain for ``e_i ≤ 1`` (Poisson's law, its two-phase form for m
#: contacts, Stronge's exact energetic law). Newton's law, Newton–Coulomb, ``newton-lcp``
#: and the paper's Stronge mapping can gain: their gains are reported, not a break.
NO_GAIN_LAWS = ("poisson", "two-phase/poisson", "stronge")


@dataclass(frozen=True)
class Phase:
    """One phase of a solution: its kind (:data:`KINDS`), the contact velocities at its start
    ``(v_n^(1), v_t^(1), v_n^(2), …)`` and its impulses in the same order; ``base`` the
    normal impulse each contact is owed (a restitution's ``e_i P_nc``), else zeros."""

    kind: str
    start: np.ndarray
    impulses: np.ndarray
    base: np.ndarray | None = None


def energy_change(system: ContactSystem, phases) -> float:
    """``Σ_phases ½ P·(v_start + v_end)``, (A29) summed over contacts and phases: the change
    of ``½uᵀMu`` over the solution."""
    total = 0.0
    for phase in phases:
        impulses = np.asarray(phase.impulses, dtype=float)
        end = np.asarray(phase.start, dtype=float) + system.delassus @ impulses
        total += 0.5 * float(impulses @ (np.asarray(phase.start, dtype=float) + end))
    return total


def violations(system: ContactSystem, phases, *, promises_no_gain: bool) -> tuple[str, ...]:
    """What ``phases`` (a solution of ``system``) breaks, one line each; empty when
    admissible (module docstring)."""
    speed = ADMISSIBLE_SPEED * system.speed_scale()
    impulse = ADMISSIBLE_IMPULSE * system.impulse_scale()
    found: list[str] = []
    for k, phase in enumerate(phases):
        if phase.kind not in KINDS:
            raise ValueError(f"phase kind: {phase.kind!r}; allowed: {', '.join(KINDS)}")
        start = np.asarray(phase.start, dtype=float)
        impulses = np.asarray(phase.impulses, dtype=float)
        end = start + system.delassus @ impulses
        base = np.zeros(system.count) if phase.base is None else np.asarray(phase.base, float)
        name = phase.kind if len(phases) == 1 else f"{phase.kind} (phase {k + 1})"
        for i in range(system.count):
            normal, tangential = impulses[2 * i], impulses[2 * i + 1]
            vn_start, vn_end = start[2 * i], end[2 * i]
            if normal < -impulse or abs(tangential) > system.mu[i] * normal + impulse:
                found.append(f"{name}: contact {i} outside the friction cone "
                             f"(I_n = {normal:.6g}, I_t = {tangential:.6g}, μ = "
                             f"{system.mu[i]:.6g})")
            target = (system.e[i] * max(-vn_start, 0.0)) if phase.kind == NEWTON else 0.0
            # A per-contact impact leaves the others as they come (a sequence strikes them
            # next): only the struck contacts, and every contact at the solution's end.
            struck = phase.kind != IMPACT or normal > impulse or k == len(phases) - 1
            if struck and vn_end < target - speed:
                found.append(f"{name}: contact {i} penetrates at the end "
                             f"(v_n = {vn_end:.6g}, at least {target:.6g})")
            if phase.kind == IMPACT:
                if vn_start > speed and normal > impulse:
                    found.append(f"{name}: impulse I_n = {normal:.6g} at contact {i}, which "
                                 f"recedes at the start (v_n = {vn_start:.6g})")
            elif normal - base[i] > impulse and vn_end > target + speed:
                what = ("impulse while receding" if vn_start > speed
                        else "complementarity broken")
                found.append(f"{name}: {what} at contact {i}: I_n = {normal:.6g}"
                             + (f" (owed {base[i]:.6g})" if base[i] else "")
                             + f", v_n = {vn_end:.6g} at the end"
                             + (f" (target {target:.6g})" if target else ""))
    if promises_no_gain:
        kinetic = 0.5 * float(system.u @ system.mass_matrix @ system.u)
        gain = energy_change(system, phases)
        if gain > ADMISSIBLE_ENERGY * kinetic:
            found.append(f"energy gain ΔE = +{gain:.6g} J ({gain / kinetic:.3g} of ½uᵀMu) "
                         f"where the law promises none")
    return tuple(found)


def solution_phases(system: ContactSystem, solution) -> tuple[Phase, ...]:
    """The phases of a :class:`MultiContactSolution`: one Newton phase for Newton–Coulomb
    (``law == "newton-coulomb"``), else one per-contact impact (the paper's proposal)."""
    kind = NEWTON if solution.law == "newton-coulomb" else IMPACT
    return (Phase(kind, system.approach.copy(), solution.impulses()),)


def promises_no_gain(law: str) -> bool:
    """Whether ``law`` promises no energy gain for ``e_i ≤ 1`` (:data:`NO_GAIN_LAWS`)."""
    return law in NO_GAIN_LAWS


__all__ = ["ADMISSIBLE_ENERGY", "ADMISSIBLE_IMPULSE", "ADMISSIBLE_SPEED", "COMPRESSION",
           "IMPACT", "KINDS", "NEWTON", "NO_GAIN_LAWS", "RESTITUTION", "Phase",
           "energy_change", "promises_no_gain", "solution_phases", "violations"]
