"""The paper's proposal after (75): every combination of collision types, solved and tested
for coherence (:func:`coherent_solutions`; docs/multi-contact.md, 'The paper's proposal').

Each combination's impulses come from :mod:`.type_map` (its fixed point), the combinations
that cannot pass are dropped first by :mod:`.screen`, and the paper's three tests (``I_n >
0``, ``v_n^S ≥ 0``, a ``v_t^S`` that fits the type) decide, with the decisions inside the
boundary band named (docs/multi-contact.md, 'Decisions at a boundary').
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from ..errors import ImpactInputError
from .screen import affine_screen, coherent_within_margin
from .system import (
    AFFINE_LAWS,
    BOUNDARY_BAND,
    FIXED_POINT_TOLERANCE,
    SEPARATING,
    TYPE_LAWS,
    VELOCITY_TOLERANCE,
    ContactSystem,
    MultiContactSolution,
    assemble,
    frame_sign,
    law_at,
    speed_of,
)
from .type_map import COUPLINGS, EFFECTIVE, LITERAL, fixed_points


def _paper_coherent(law, ctype, sign, solution, i, tolerance, impulse_band):
    """The paper's tests after (75): ``I_n > 0``, ``v_n^S ≥ 0`` and a ``v_t^S`` that fits the
    type (0 sticking, against the initial slip reversing, with it forward).

    True or False; or, where the strict ``I_n > 0`` is decided inside ``impulse_band`` (an
    impulse that is zero to rounding), a string naming both candidates. The non-strict
    tests pass within ``tolerance`` of their cut: a value that is zero to rounding passes
    them whichever its last bit, so they are never at a boundary.
    """
    if ctype == SEPARATING:
        return bool(solution.vn_separation[i] >= -tolerance)
    normal = solution.normal_impulse[i]
    if not normal > -impulse_band or solution.vn_separation[i] < -tolerance:
        return False
    if not normal > impulse_band:
        return ("I_n = 0 within the band (an impulse, or a separating contact)"
                if _slip_fits(law, ctype, sign, solution, i, tolerance) else False)
    return _slip_fits(law, ctype, sign, solution, i, tolerance)


def _slip_fits(law, ctype, sign, solution, i, tolerance) -> bool:
    slip = sign * solution.vt_separation[i]
    if law == "newton":
        kind = {1: "stick", 2: "reverse", 3: "forward"}[ctype]
    else:
        kind = {1: "stick", 2: "stick", 3: "reverse", 4: "reverse", 5: "forward"}[ctype]
    if kind == "stick":
        return bool(abs(slip) <= tolerance)
    return bool(slip <= tolerance if kind == "reverse" else slip >= -tolerance)


def coherent_solutions(system: ContactSystem, law: str = "poisson", *,
                       coupling: str = LITERAL, allow_separating: bool = False
                       ) -> list[MultiContactSolution]:
    """Every coherent combination of collision types, the paper's proposal after (75).

    ``coupling="literal"`` (default, the paper's proposal): for each type tuple
    ``(T_1 … T_m)`` contact ``i``'s impulses are type ``T_i``'s formulas at its own
    ``v^A(i)`` (tangent oriented as ``solve`` orients it); ``Δu`` by (75); the combination
    is coherent when the paper's three tests hold at every contact with the final
    velocities: ``I_n > 0``, ``v_n^S ≥ 0``, ``v_t^S`` fitting the type. Table 1 does not
    filter (``table1_types`` marks the combination it would pick).

    ``coupling="effective"`` (an extension, not the paper's; it counts restitution twice):
    contact ``i``'s impulses are type ``T_i``'s formulas at its effective approach
    ``v^A(i) + Σ_{j≠i} W_ij I^(j)``; the ``m`` contacts' formulas together fix the impulses
    (a linear system for Poisson and Newton, a smooth one for ``"stronge-paper"``), and the
    combination is coherent when, at every contact, the single-contact law picks type
    ``T_i`` by Table 1 for that effective approach, the orientation is the one ``solve``
    would use, and the paper's tests hold. docs/multi-contact.md, 'The paper's proposal',
    gives the reasons.

    Decisions inside the band :data:`BOUNDARY_BAND` (Table 1's type, the orientation at
    ``v_t = 0``, ``I_n = 0``) keep the solution with ``at_boundary`` and both candidates in
    ``boundary`` (docs/multi-contact.md, 'Decisions at a boundary').

    ``allow_separating`` adds type 0 (no impulse, needs ``v_n^S ≥ 0``) at each contact; the
    paper requires ``I_n > 0`` everywhere, so it is off by default.

    Combinations that cannot pass are dropped before their solve (:func:`_candidates`: the
    literal reading's one orientation per contact; a batched screen with margins for the
    effective one of Poisson and Newton) or, for the paper's Stronge under the effective
    reading, after it and before the checks (:func:`coherent_within_margin` at the fixed
    points); the rest are
    solved and checked as without a screen, so the answer is the same bit for bit
    (tests/theory/test_simultaneous_screen.py compares with the unscreened path).

    Returns the coherent solutions, distinct impulses only (combinations that coincide, as
    across a type boundary where the closed forms agree, are listed once: the first in
    enumeration order), sorted by type tuple. For ``m = 1`` the effective reading's list is
    the single answer of :func:`planar_impact.solve` with the same law, bit for bit, and so
    is the literal reading's solution with ``table1_types``.
    """
    if law not in TYPE_LAWS:
        raise ImpactInputError(f"law: {law!r}; allowed: {', '.join(TYPE_LAWS)}")
    if coupling not in COUPLINGS:
        raise ImpactInputError(f"coupling: {coupling!r}; allowed: {', '.join(COUPLINGS)}")
    choices = ((SEPARATING,) if allow_separating else ()) + TYPE_LAWS[law]
    tolerance = VELOCITY_TOLERANCE * system.speed_scale()
    found: list[MultiContactSolution] = []
    candidates = _candidates(system, law, choices, coupling, tolerance)
    if not candidates:
        return found
    impulses, converged, determinate = fixed_points(system, law, candidates, coupling)
    if law not in AFFINE_LAWS and coupling == EFFECTIVE and system.count > 1:
        # The paper's Stronge is screened after its solve, at the fixed points themselves.
        rows = np.flatnonzero(converged)  # finite: their residual passed the tolerance
        converged[rows] = coherent_within_margin(
            system, law, [candidates[k] for k in rows], impulses[rows], tolerance)
    fixed = zip(impulses, converged, determinate)
    for (types, signs), (impulses, converged, determinate) in zip(candidates, fixed):
        if not converged:
            continue
        solution = _check_combination(system, law, types, signs, impulses, bool(determinate),
                                      tolerance, coupling)
        if solution is not None and not _already_found(found, solution, system):
            found.append(solution)
    return found


def _combinations(choices, count):
    """Every (types, signs) in enumeration order: type tuples outer, orientations inner;
    a separating contact takes only ``+1`` (the orientation does not matter without impulse)."""
    for types in itertools.product(choices, repeat=count):
        for signs in itertools.product((1.0, -1.0), repeat=count):
            if not any(t == SEPARATING and s < 0 for t, s in zip(types, signs)):
                yield types, signs


def _candidates(system, law, choices, coupling, tolerance):
    """The combinations that :func:`_check_combination` could accept, in enumeration order.

    Every combination it could accept is kept (so the solutions, solved and checked by the
    same code as before, are the same bit for bit); most of the others are dropped unsolved:

    * ``coupling="literal"``: each contact sees its own ``v^A(i)``, which fixes its tangent's
      orientation: the ``types^m`` type tuples, one orientation each (the paper's ``5^m``).
    * ``coupling="effective"`` with Poisson or Newton: the map is affine, and one batched
      linear solve per combination screens it (:func:`affine_screen`).
    * ``coupling="effective"`` with the paper's Stronge: every combination. Its map is not
      affine: a screen would run the Newton iteration of :func:`fixed_points` itself, and
      with that iteration batched the full solve of every combination costs about as much
      as such a screen alone. :func:`coherent_solutions` screens the converged ones at their
      fixed points instead (:func:`coherent_within_margin`, necessary tests with margins).
    """
    if coupling == LITERAL:
        # Each contact's tangent is oriented by its own v^A(i) (as solve() orients it); every
        # type tuple is a candidate, the paper's tests decide (_check_combination). A contact
        # that does not approach (v_n^A ≥ 0) has no impact: no impulse, type 0 only (the
        # types' formulas at |v_n^A| would push a receding contact).
        signs = tuple(frame_sign(float(system.approach[2 * i + 1]), system.single_terms(i)[1])
                      for i in range(system.count))
        per_contact = [choices if system.approach[2 * i] < 0 else (SEPARATING,)
                       for i in range(system.count)]
        return [(types, tuple(1.0 if t == SEPARATING else sign for t, sign in zip(types, signs)))
                for types in itertools.product(*per_contact)]
    combinations = list(_combinations(choices, system.count))
    if system.count == 1 or law not in AFFINE_LAWS:
        return combinations
    keep = affine_screen(system, law, combinations, tolerance)
    return [combination for combination, kept in zip(combinations, keep) if kept]


def _check_combination(system, law, types, signs, impulses, determinate, tolerance,
                       coupling="effective"):
    """The coherent solution of one combination at its fixed point, or None; with its
    decisions inside the boundary band named (``boundary``)."""
    final = impulses.copy()
    boundary: list[str] = []
    seen = impulses if coupling == EFFECTIVE else np.zeros_like(impulses)
    for i, (ctype, sign) in enumerate(zip(types, signs)):
        if ctype == SEPARATING:
            continue
        if coupling == LITERAL:  # the type's formulas at v^A(i) are the impulses: no Table 1
            vt = float(system.approach[2 * i + 1])
            if frame_sign(vt, system.single_terms(i)[1]) != sign or not (
                    np.isfinite(impulses[2 * i]) and np.isfinite(impulses[2 * i + 1])):
                return None
            continue
        _mnn, mnt, _mtt = system.single_terms(i)
        vn, vt = system.effective_approach(i, seen)
        band = BOUNDARY_BAND * (abs(vn) + abs(vt))
        if frame_sign(vt, mnt) != sign:
            if abs(vt) > band:
                return None
            boundary.append(f"contact {i}: v_t = 0 within the band (either orientation)")
        own = law_at(system, law, i, vn, vt, sign)
        if own is None:
            return None
        near = _types_near(system, law, i, vn, vt, sign, band)
        own_type = int(own["collision_type"])
        if ctype not in near:
            return None
        if len(near) > 1:  # Table 1 within the band gives several types: name them
            boundary.append(f"contact {i}: Table 1 type "
                            + " | ".join(str(t) for t in sorted(near)))
        if own_type != ctype:
            # Table 1 picks the neighbouring type inside the band: the combination's own
            # formulas (the fixed point) stand, both types named. Poisson's closed forms agree
            # across a boundary (comment a); the paper's Stronge's need not (docs/theory.md,
            # 'Findings', 3), so its two candidates may both be listed.
            continue
        # The law's own impulses at this effective approach: equal to the fixed point to
        # its tolerance, and for m = 1 exactly what solve() returns.
        normal, tangential = float(own["normal_impulse"]), sign * float(own["tangential_impulse"])
        scale = system.impulse_scale() + abs(normal) + abs(tangential)
        if max(abs(normal - impulses[2 * i]), abs(tangential - impulses[2 * i + 1])) > (
                FIXED_POINT_TOLERANCE * scale):
            return None
        final[2 * i], final[2 * i + 1] = normal, tangential
    solution = assemble(system, law, types, final, determinate)
    for i, (ctype, sign) in enumerate(zip(types, signs)):
        verdict = _paper_coherent(law, ctype, sign, solution, i, tolerance,
                                  BOUNDARY_BAND * system.impulse_scale())
        if verdict is False:
            return None
        if verdict is not True:
            boundary.append(f"contact {i}: {verdict}")
    if coupling == LITERAL:
        solution = dataclasses.replace(solution, table1_types=_table1_types(system, law, types))
    return dataclasses.replace(solution, boundary=tuple(boundary)) if boundary else solution


def _types_near(system, law, i, vn, vt, sign, band) -> set[int]:
    """The types Table 1 gives contact ``i`` at ``(vn, vt)`` and at the four corners of the
    box of half-width ``band`` around it (on the same side of ``v_t = 0``, approaching): α
    is extreme at the corners, so these are the types within the band."""
    found = set()
    for dn, dt in ((0.0, 0.0), (-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)):
        corner_vn, corner_vt = vn + dn * band, vt + dt * band
        if sign * corner_vt < 0:
            corner_vt = 0.0
        out = law_at(system, law, i, corner_vn, corner_vt, sign)
        if out is not None:
            found.add(int(out["collision_type"]))
    return found


def _table1_types(system, law, types) -> bool:
    """Whether each contact's type is the single-contact law's at its own ``v^A(i)``."""
    for i, ctype in enumerate(types):
        if ctype == SEPARATING:
            continue
        vn, vt = float(system.approach[2 * i]), float(system.approach[2 * i + 1])
        own = law_at(system, law, i, vn, vt, frame_sign(vt, system.single_terms(i)[1]))
        if own is None or int(own["collision_type"]) != ctype:
            return False
    return True


def _already_found(found, solution, system) -> bool:
    """Whether ``solution`` repeats one in ``found`` (same impulses, or same ``Δu`` within a
    family); a repeat's boundary notes are merged into the kept one (``found`` is updated),
    so that which combination came first cannot change what is reported."""
    scale = system.impulse_scale()
    for k, other in enumerate(found):
        same = np.max(np.abs(other.impulses() - solution.impulses())) <= 1e-9 * scale
        family = not (other.determinate and solution.determinate)
        if same or family and np.max(np.abs(other.delta_u - solution.delta_u)) <= (
                1e-9 * speed_of(system)):
            notes = tuple(dict.fromkeys(other.boundary + solution.boundary))
            if notes != other.boundary:
                found[k] = dataclasses.replace(other, boundary=notes)
            return True
    return False


__all__ = ["coherent_solutions"]
