"""Several simultaneous contacts on one system (the paper's Section 5, eq. (75)).

With ``m`` contacts the impulse–momentum balance (A12) becomes (75),
``M Δu = Σ_i (w_n^(i) I_n^(i) + w_t^(i) I_t^(i))``, and each contact's velocity change picks
up the other contacts' impulses through the cross terms of the Delassus matrix
``W = J M⁻¹ Jᵀ`` (``J`` stacks the rows ``w_n^(i)``, ``w_t^(i)``). Three readings are built
here (docs/multi-contact.md explains each, with a worked example):

* :func:`coherent_solutions`: the paper's proposal after (75). Every combination of the
  collision types (five for Poisson and the paper's Stronge, three for Newton) is evaluated
  and tested for coherence; all coherent combinations are returned. By default
  (``coupling="literal"``, the paper's) each contact's type formulas are explicit in its own
  ``v^A(i)``: 5^m evaluations, kept where the paper's three tests hold. The named extension
  ``coupling="effective"`` applies them at ``v^A(i) + Σ_{j≠i} W_ij I^(j)``, a fixed point of
  ``m`` single-contact laws, which counts restitution twice.
* :func:`newton_coulomb` / :func:`newton_coulomb_solutions`: the velocity-level
  Newton–Coulomb law sequential-impulse engines solve, by exact enumeration of the contact
  modes, counted by post-impact velocity; :func:`projected_gauss_seidel` is the engines'
  iteration, for the cross-check and as the second method where no mode holds.
* :func:`sequential_impacts` / :func:`all_orders`: the contacts taken one at a time with the
  single-contact solver, in a given order, until none approaches.

The package, one reading or piece a module: :mod:`.system` (the contacts, one answer, what
the readings share), :mod:`.type_map` and :mod:`.screen` (a combination's solve, and the
screen that drops combinations that cannot be coherent) under :mod:`.coherent` (the
paper's proposal), :mod:`.newton_coulomb` (with projected Gauss–Seidel),
:mod:`.sequential`, and :mod:`.random_systems` (random two-contact problems and the count
of their coherent solutions; ``python -m planar_impact.simultaneous [problems] [seed]``).
"""

from __future__ import annotations

from .admissible import (
    ADMISSIBLE_ENERGY,
    ADMISSIBLE_IMPULSE,
    ADMISSIBLE_SPEED,
    COMPRESSION,
    IMPACT,
    NEWTON,
    RESTITUTION,
    Phase,
    promises_no_gain,
    solution_phases,
    violations,
)
from .coherent import coherent_solutions
from .newton_coulomb import (
    LCP_FORWARD,
    LCP_REVERSE,
    LCP_SEPARATE,
    LCP_STICK,
    NC_GAUSS_SEIDEL_SWEEPS,
    NC_NONE,
    NC_SEVERAL,
    NC_SPLIT_NOT_UNIQUE,
    NC_STATUSES,
    NC_UNIQUE,
    GaussSeidelResult,
    NewtonCoulombResult,
    newton_coulomb,
    newton_coulomb_solutions,
    projected_gauss_seidel,
    restitution_targets,
)
from .random_systems import coherent_count_distribution, random_two_contact_system
from .screen import SCREEN_CONDITION, SCREEN_MARGIN, SCREEN_SINGULAR_CONDITION, SINGULAR_CUT
from .sequential import SequentialResult, all_orders, sequential_impacts
from .system import (
    AFFINE_LAWS,
    BOUNDARY_BAND,
    FIXED_POINT_TOLERANCE,
    ROUNDING_RESIDUAL,
    SEPARATING,
    TYPE_LAWS,
    VELOCITY_TOLERANCE,
    ContactSystem,
    MultiContactSolution,
    contact_system,
)
from .type_map import COUPLINGS, EFFECTIVE, LITERAL

__all__ = ["ADMISSIBLE_ENERGY", "ADMISSIBLE_IMPULSE", "ADMISSIBLE_SPEED", "AFFINE_LAWS",
           "BOUNDARY_BAND", "COMPRESSION", "COUPLINGS", "EFFECTIVE", "FIXED_POINT_TOLERANCE",
           "IMPACT", "LCP_FORWARD", "LCP_REVERSE", "LCP_SEPARATE", "LCP_STICK", "LITERAL",
           "NC_GAUSS_SEIDEL_SWEEPS", "NC_NONE", "NC_SEVERAL", "NC_SPLIT_NOT_UNIQUE",
           "NC_STATUSES", "NC_UNIQUE", "NEWTON", "RESTITUTION", "ROUNDING_RESIDUAL",
           "SCREEN_CONDITION", "SCREEN_MARGIN", "SCREEN_SINGULAR_CONDITION", "SEPARATING",
           "SINGULAR_CUT", "TYPE_LAWS", "VELOCITY_TOLERANCE", "all_orders",
           "coherent_count_distribution", "coherent_solutions", "contact_system", "ContactSystem",
           "GaussSeidelResult", "MultiContactSolution", "newton_coulomb",
           "newton_coulomb_solutions", "NewtonCoulombResult", "Phase", "projected_gauss_seidel",
           "promises_no_gain", "random_two_contact_system", "restitution_targets",
           "sequential_impacts", "SequentialResult", "solution_phases", "violations"]
