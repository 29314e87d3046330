"""A two-phase Poisson law for ``m`` simultaneous contacts, at velocity level.

Poisson's hypothesis splits an impact into a compression phase, which ends when the normal
approach has stopped, (1)–(2), and a restitution phase whose normal impulse is ``e`` times
the compression's, (3)–(6). The paper's closed forms (25)–(51) apply it to one contact by
following the impulse process; after (75) it leaves several contacts open. This module
applies the same two phases to ``m`` contacts in the manner of Glocker and Pfeiffer's
two-phase impact law (Pfeiffer & Glocker, *Multibody Dynamics with Unilateral Contacts*,
1996) and of the velocity-level linear complementarity problems of Anitescu and Potra
(*Nonlinear Dynamics* 14, 1997), with the Coulomb law applied to each phase's impulse at the
phase's end velocity:

* **Compression** (1)–(5): impulses ``P_c`` with ``v̄ = v^A + W P_c`` (75 with (A22)/(A23))
  and, per contact, ``0 ≤ P_nc ⟂ v̄_n ≥ 0`` (the approach ends where an impulse acts),
  ``|P_tc| ≤ μ P_nc`` and maximal dissipation (``P_tc = −μ P_nc sign(v̄_t)`` where
  ``v̄_t ≠ 0``).
* **Restitution** (6): impulses ``P_r`` with ``v^S = v̄ + W P_r``, per contact
  ``P_nr = e P_nc + Λ`` with ``0 ≤ Λ ⟂ v_n^S ≥ 0``, and Coulomb as above with ``P_nr``.
  The extra ``Λ`` is Glocker and Pfeiffer's: it acts only where ``e P_nc`` alone would leave a
  contact penetrating (never for one contact, where ``Λ = 0`` and ``P_nr = e P_nc`` is (6)).

Both phases are one problem with a base normal impulse ``b`` (0 for the compression,
``e P_nc`` for the restitution), solved two independent ways:
:func:`phase_by_enumeration` (every stick / slide / separate mode, a linear system each, all
solutions kept) and :func:`phase_by_lemke` (the phase as a linear complementarity problem in
the planar friction cone's two edges, Lemke's complementary pivoting with a lexicographic
ratio test). ``W`` may be singular (a flat face: 4 constraints on 3 speeds): velocities are
then unique where the impulse split is not, and the two methods are compared on velocities.

Coulomb's law at a phase's end only is not the paper's process where the slip reverses
inside a phase (its Types 3 and 4). So by default each phase follows the slip
(:func:`phase_following_slip`): it is taken in straight pieces, sliding contacts' friction
held against their slip, cut where a held slip reaches zero. For one contact this is the
paper's process, and the law equals ``solve(..., law="poisson")`` in all five types; a
contact receding at a piece's start takes no impulse in it, and a phase whose pieces' sum
is not complementary at its end is solved as one velocity-level problem instead.
``follow_slip=False`` gives one velocity-level problem per phase (equal in Types 1, 2, 5
only). docs/multi-contact.md, 'A two-phase Poisson law for m contacts'. Every answer is
checked by :func:`planar_impact.simultaneous.violations` where the harness uses it
(:func:`two_phase_phases` gives its phases).

The package, one job a module: :mod:`.phase` (a phase's answer, mode codes, tolerances and
scaling), :mod:`.enumeration` and :mod:`.lemke` (the two methods for one phase),
:mod:`.slip` (a phase with the slip followed), :mod:`.two_phase` (the law),
:mod:`.measure` (measurements on random problems;
``python -m planar_impact.multicontact [problems] [seed] [plain]``) and :mod:`.families`
(every m-contact reference checked on broad flat landings;
``python -m planar_impact.multicontact admissible [draws] [seed]``).
"""

from __future__ import annotations

from .enumeration import phase_by_enumeration, phases_by_enumeration
from .lemke import lemke, phase_by_lemke, phase_lcp
from .measure import measure, measure_one_contact, random_flat_face
from .phase import (
    METHODS,
    NORMAL_ACTIVE,
    NORMAL_BASE,
    RANK_CUT,
    RESIDUAL_TOLERANCE,
    SAME_ANSWER,
    SIGN_TOLERANCE,
    SLIDE_NEGATIVE,
    SLIDE_POSITIVE,
    STICK,
    PhaseSolution,
)
from .slip import CUTS_PER_CONTACT, PIECES_PER_PHASE, phase_following_slip
from .two_phase import (
    TwoPhaseSolution,
    normal_split_unique,
    poisson_two_phase,
    poisson_two_phase_many,
    two_phase_phases,
)

__all__ = ["CUTS_PER_CONTACT", "METHODS", "NORMAL_ACTIVE", "NORMAL_BASE", "PIECES_PER_PHASE",
           "RANK_CUT", "RESIDUAL_TOLERANCE", "SAME_ANSWER", "SIGN_TOLERANCE", "SLIDE_NEGATIVE",
           "SLIDE_POSITIVE", "STICK", "PhaseSolution", "TwoPhaseSolution", "lemke", "measure",
           "measure_one_contact", "normal_split_unique", "phase_by_enumeration",
           "phase_by_lemke", "phase_following_slip", "phase_lcp", "phases_by_enumeration",
           "poisson_two_phase", "poisson_two_phase_many", "random_flat_face",
           "two_phase_phases"]
