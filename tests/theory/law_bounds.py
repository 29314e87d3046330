"""Derived forward error bounds of the two implementations of the laws, for the tests that
compare them (docs/verdicts.md, 'Same answers on every CPU').

Both are straight-line float code with branches: the closed forms of one row
(:func:`planar_impact.fastpath.law_answer`, which gives ``solve_batch``'s bits, checked in
tests/theory/test_fastpath.py) and the impulse process walked segment by segment
(:func:`planar_impact.process.impulse_process`), and ``newton-lcp``'s enumeration of modes
(:func:`planar_impact.process.newton_lcp_modes`). Run on :class:`tests.error_bounds.Tracked`
inputs (each float input exact), they return their usual values, bit for bit (the tests check
it against the library's own answers), each carrying a bound on its distance from the exact
answer of the exact problem (running error analysis, Higham §3.3). Both are exact in exact
arithmetic, so where neither took a decision its errors leave open
(``Tracked.close_decisions``), the two answers are within the sum of their bounds.

The modules' ``math.sqrt`` is swapped for :meth:`Tracked.math_sqrt` while they run (it gives
the same bits for floats, and keeps a ``Tracked`` tracked), and the close calls of Table 1's
band screen are not counted (it decides ``type_at_boundary``, not the answer).
"""

from __future__ import annotations

import math
import types
from collections.abc import Iterator
from contextlib import contextmanager

from planar_impact import fastpath, process
from tests.error_bounds import Tracked

FIELDS = ("normal_impulse", "tangential_impulse", "vn_separation", "vt_separation",
          "energy_change")


#: ``math`` with :meth:`Tracked.math_sqrt` for its ``sqrt``.
_TRACKED_MATH = types.SimpleNamespace(**{name: getattr(math, name) for name in dir(math)
                                         if not name.startswith("_")})
_TRACKED_MATH.sqrt = Tracked.math_sqrt


@contextmanager
def tracked_sqrt() -> Iterator[None]:
    """fastpath's and process's ``math`` with :meth:`Tracked.math_sqrt`, for the ``with``."""
    shim = _TRACKED_MATH
    saved = fastpath.math, process.math, fastpath._near_table1_boundary

    def screen(*arguments):
        # Table 1's band screen decides only whether to look for the type at a boundary
        # (type_at_boundary), never the impulses: its close calls are not the answer's
        before = Tracked.close_decisions
        near = saved[2](*arguments)
        Tracked.close_decisions = before
        return near

    fastpath.math = process.math = shim
    fastpath._near_table1_boundary = screen
    try:
        yield
    finally:
        fastpath.math, process.math, fastpath._near_table1_boundary = saved


def closed_form(law: str, mnn, mnt, mtt, vn, vt, mu, e, delta=None) -> dict[str, Tracked] | None:
    """The closed form's answer to one row in the caller's ``t`` (``solve_batch``'s: ``t``
    turned so that ``v_t ≥ 0``; ``Δ = m_nn m_tt − m_nt²`` unless given), its fields
    :data:`FIELDS` and ``restitution_poisson`` as ``Tracked``; None where the fast path
    declines the row. Inputs are floats (exact) or ``Tracked`` (known within their error)."""
    sign = -1.0 if vt < 0 or (vt == 0 and mnt < 0) else 1.0  # as solve_batch turns t
    tracked = [Tracked.of(x) for x in (mnn, mnt, mtt, vn, vt, mu, e)]
    tracked[4] = abs(tracked[4])  # turning t is exact
    if sign < 0:
        tracked[1] = -tracked[1]
    if delta is None:
        delta = tracked[0] * tracked[2] - tracked[1] * tracked[1]  # (A20), laws.ContactTerms
    with tracked_sqrt():
        out = fastpath.law_answer(law, *tracked, delta)
    if out is None:
        return None
    normal, tangential, vn_separation, vt_separation, energy = out[:5]
    if sign < 0:
        tangential, vt_separation = -tangential, -vt_separation
    return {"normal_impulse": normal, "tangential_impulse": tangential,
            "vn_separation": vn_separation, "vt_separation": vt_separation,
            "energy_change": energy, "restitution_poisson": Tracked.of(out[7])}


def walked(law: str, mnn, mnt, mtt, vn, vt, mu, e) -> dict[str, Tracked]:
    """:func:`impulse_process`'s answer, its fields :data:`FIELDS` as ``Tracked``."""
    with tracked_sqrt():
        result = process.impulse_process(*(Tracked(x) for x in (mnn, mnt, mtt, vn, vt, mu, e)),
                                         law=law)
    return {name: Tracked.of(getattr(result, name)) for name in FIELDS}


def lcp_modes(mnn, mnt, mtt, vn, vt, mu, e) -> list[tuple[str, Tracked, Tracked]]:
    """:func:`newton_lcp_modes` with ``Tracked`` impulses."""
    return process.newton_lcp_modes(*(Tracked(x) for x in (mnn, mnt, mtt, vn, vt, mu, e)))


def fraction(one: Tracked, other: Tracked) -> float:
    """How much of the two bounds' sum ``e_a + e_b`` the distance ``|a − b|`` of two
    computations of one exact quantity uses (at most 1 where both bounds hold)."""
    gap = abs(one.value - other.value)
    return 0.0 if gap == 0.0 else gap / (one.error + other.error)
