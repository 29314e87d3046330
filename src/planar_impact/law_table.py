"""The laws planar_impact solves: one line per law, naming its solvers and whether it has a
Poisson restitution e_i, and nothing else.

:data:`LAWS` (``pi.LAWS``) is this table's names in its order; ``check_law``,
:func:`planar_impact.contact_space.contact_space_solution` (arrays: ``solve_batch`` and
``solve``'s numpy path) and :func:`planar_impact.fastpath.law_answer` (``solve``'s scalar
path) read it, so a law is its module of solvers plus its line here (docs/theory.md, 'The
law registry and adding a law'). What the harness shows of a law (order, style, promises) is
``harness/laws.py``'s, checked against this table by ``tests/test_laws.py``.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

from . import law_branches as branches
from . import laws


class LawSolvers(NamedTuple):
    """One law's solvers (contracts in :mod:`planar_impact.law_branches`)."""

    rows: Callable  # contact-space arrays: (terms, e) -> I_n, I_t, type, e_i, consistent, ...
    row: Callable  # one row on floats, the same bits: (...) -> I_n, I_t, type, ... or None
    reverse_types: tuple[int, ...]  # its collision types that slide in reverse (need q > 0)
    #: It amounts to a Poisson restitution ``e_i = I_nr/I_nc`` (6) (a process law, or Poisson's
    #: closed forms at ``e_i``), which ``solve`` reports with whether it lies in [0, 1];
    #: False for a velocity-level law with no compression phase (``restitution_poisson`` None,
    #: ``restitution_in_range`` True: no ``e_i`` to leave the range).
    poisson_restitution: bool


_TABLE1_REVERSE = (laws.REVERSE_FROM_COMPRESSION, laws.REVERSE_FROM_RESTITUTION)

LAW_TABLE: dict[str, LawSolvers] = {
    "newton": LawSolvers(branches.newton_rows, branches.newton_row, (laws.NEWTON_REVERSE,),
                         poisson_restitution=True),
    "poisson": LawSolvers(branches.poisson_rows, branches.poisson_row, _TABLE1_REVERSE,
                          poisson_restitution=True),
    "stronge": LawSolvers(branches.stronge_rows, branches.stronge_row, _TABLE1_REVERSE,
                          poisson_restitution=True),
    "stronge-paper": LawSolvers(branches.stronge_paper_rows, branches.stronge_paper_row,
                                _TABLE1_REVERSE, poisson_restitution=True),
    "newton-lcp": LawSolvers(branches.newton_lcp_rows, branches.newton_lcp_row,
                             (laws.NEWTON_REVERSE,), poisson_restitution=False),
}

LAWS: tuple[str, ...] = tuple(LAW_TABLE)
