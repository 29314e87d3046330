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
(``Tracked.close_decisions``), the two answers are within the sum of their bounds; where one
did, :func:`branched` follows it along every path the exact computation could take and widens
each bound to cover them all (infinite where that cannot be settled: a decision at a boundary).

The modules' ``math.sqrt`` is swapped for :meth:`Tracked.math_sqrt` while they run (it gives
the same bits for floats, and keeps a ``Tracked`` tracked), and the close calls of Table 1's
band screen are not counted (it decides ``type_at_boundary``, not the answer).
"""

from __future__ import annotations

import math
import types
from collections.abc import Iterator
from contextlib import contextmanager
from fractions import Fraction
from functools import partial

import numpy as np

from planar_impact import fastpath, law_branches, process
from tests.error_bounds import (
    Exact,
    Tracked,
    U,
    bilinear_bound,
    dot_bound,
    every_branch,
    exact_inverse,
    gamma,
    solve_backward_bounds,
    widened,
)

FIELDS = ("normal_impulse", "tangential_impulse", "vn_separation", "vt_separation",
          "energy_change")


#: ``math`` with :meth:`Tracked.math_sqrt` for its ``sqrt``.
_TRACKED_MATH = types.SimpleNamespace(**{name: getattr(math, name) for name in dir(math)
                                         if not name.startswith("_")})
_TRACKED_MATH.sqrt = Tracked.math_sqrt


@contextmanager
def tracked_sqrt() -> Iterator[None]:
    """The laws' scalar solvers' and process's ``math`` with :meth:`Tracked.math_sqrt`, for
    the ``with``."""
    shim = _TRACKED_MATH
    saved = law_branches.math, process.math, law_branches._near_table1_boundary

    def screen(*arguments):
        # Table 1's band screen decides only whether to look for the type at a boundary
        # (type_at_boundary), never the impulses: its close calls are not the answer's
        before = Tracked.close_decisions
        near = saved[2](*arguments)
        Tracked.close_decisions = before
        return near

    law_branches.math = process.math = shim
    law_branches._near_table1_boundary = screen
    try:
        yield
    finally:
        law_branches.math, process.math, law_branches._near_table1_boundary = saved


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


#: Paths of a replay followed before it counts as undecided (a few dozen at a boundary).
BRANCH_LIMIT = 256


def branched(replay) -> dict:
    """``replay()`` (a function returning a dict of ``Tracked`` fields, such as
    :func:`closed_form` or :func:`walked` of one row) where it compared values within their
    errors (``Tracked.close_decisions``): followed along every path an exact computation
    could take (error_bounds.every_branch), each ``Tracked`` field widened to a bound
    whichever path the exact computation takes (error_bounds.widened). Its error is infinite
    where a path fails or the replay branches more than :data:`BRANCH_LIMIT` ways: a decision
    at a boundary that the test cannot settle. The values are the floats' path's."""
    try:
        paths = every_branch(replay, limit=BRANCH_LIMIT)
    except RuntimeError:
        paths = [replay(), None]
    first = paths[0]
    return {name: widened([path and path[name] for path in paths])
            if type(value) is Tracked else value for name, value in first.items()}


def fraction(one: Tracked, other: Tracked) -> float:
    """How much of the two bounds' sum ``e_a + e_b`` the distance ``|a − b|`` of two
    computations of one exact quantity uses (at most 1 where both bounds hold)."""
    gap = abs(one.value - other.value)
    return 0.0 if gap == 0.0 else gap / (one.error + other.error)


def term_bounds(matrix, wn, wt, method: str) -> dict[str, float]:
    """How far one path's contact terms ``w_iᵀ M⁻¹ w_j`` can be from the exact ones, its
    ``M⁻¹w`` from ``method``'s solve (``"cholesky"``, ``"lu"``: solve_backward_bounds)."""
    w = {"n": np.asarray(wn, dtype=float), "t": np.asarray(wt, dtype=float)}
    x = {key: np.linalg.solve(matrix, value) for key, value in w.items()}
    backward = solve_backward_bounds(matrix)[method]
    return {name: bilinear_bound(backward, x[name[1]], x[name[2]], w[name[1]])
            for name in ("mnn", "mnt", "mtt")}


def delta_u_bound(matrix, inverse, replay, method: str) -> np.ndarray:
    """How far one path's ``Δu = x̂_n I_n + x̂_t I_t`` can be from the exact one, per speed:
    its ``x̂ = M⁻¹w`` solves ``(M + ΔM) x̂ = w``, so ``M (x̂ − x) = −ΔM x̂`` and
    ``|x̂ − x| <= ‖M⁻¹‖₂ ‖ΔM‖₂ |x̂|`` in each component (``method``'s backward bound,
    solve_backward_bounds); the impulses are within their replays' errors; each component's
    two products and sum round by ``γ_2`` of its terms."""
    matrix_inverse_norm = 1.0 / float(np.linalg.eigvalsh(matrix)[0])  # M is SPD
    backward = solve_backward_bounds(matrix)[method]
    bound = 0.0
    for x, impulse in zip(inverse, (replay["normal_impulse"], replay["tangential_impulse"])):
        x = np.abs(np.asarray(x, dtype=float))
        solve_error = matrix_inverse_norm * backward * float(np.linalg.norm(x))
        bound = (bound + solve_error * abs(impulse.value) + (x + solve_error) * impulse.error
                 + gamma(2) * x * abs(impulse.value))
    return bound


def replayed_law(law, fields, delta, bounds, speed_bounds, mu, e):
    """One path of ``solve``'s law fields replayed (:func:`closed_form`) from its own contact
    terms and speeds ``fields`` and Gram ``delta``: the terms within ``bounds``
    (:func:`term_bounds`), the speeds within ``speed_bounds``, and ``Δ`` within its distance
    from ``m_nn m_tt − m_nt²`` plus that product's own bound."""
    m = {name: Tracked(float(fields[name]), bounds[name]) for name in ("mnn", "mnt", "mtt")}
    product = m["mnn"] * m["mtt"] - m["mnt"] * m["mnt"]  # within product.error of the exact Δ
    gram = Tracked(float(delta), abs(float(delta) - product.value) + product.error)
    return closed_form(law, m["mnn"], m["mnt"], m["mtt"],
                       Tracked(float(fields["vn_approach"]), speed_bounds[0]),
                       Tracked(float(fields["vt_approach"]), speed_bounds[1]), mu, e,
                       delta=gram)


def kinetic_bound(matrix, u, u_after, u_after_error) -> float:
    """How far ``½ u'ᵀ M u' − ½ uᵀ M u``, computed as numpy computes it (``(0.5 u') @ M``, then
    ``@ u'``; the same for ``u``; ``u`` exact), can be from the exact change of kinetic energy
    to the exact ``u'*``, ``|u' − u'*| <= u_after_error`` per speed: the products' rounding
    (:func:`dot_bound` of each column, carried through the second product) and the
    subtraction's, plus ``|K(u') − K(u'*)| = ½ |(u' − u'*)ᵀ M (u' + u'*)|``."""
    matrix = np.asarray(matrix, dtype=float)
    rounding = 0.0
    for speeds in (np.asarray(u_after, dtype=float), np.asarray(u, dtype=float)):
        half = 0.5 * speeds  # exact
        row = half @ matrix
        row_error = np.array([dot_bound(half.tolist(), column) for column in matrix.T.tolist()])
        rounding += (float(np.abs(speeds) @ row_error)
                     + dot_bound(row.tolist(), speeds.tolist()))
    kinetic = 0.5 * u_after @ matrix @ u_after - 0.5 * u @ matrix @ u
    rounding += U * abs(kinetic)
    distance = np.asarray(u_after_error, dtype=float)
    moved = 0.5 * float(distance @ (np.abs(matrix) @ (2.0 * np.abs(u_after) + distance)))
    return rounding + moved


def solve_with_delta_u_bound(problem, mu, e, law):
    """``problem.solve``'s answer (an ``ImpactProblem``, solved by the fast path) and a
    derived bound per speed on its Δu's distance from the exact Δu of the same float inputs:
    the law replayed on Tracked numbers from the fast path's own contact terms, known within
    their solves' backward errors and dot products' rounding (:func:`replayed_law`; widened
    by :func:`branched` where it branches close), then Δu = x̂_n I_n + x̂_t I_t's bound
    (:func:`delta_u_bound`)."""
    result = problem.solve(mu=mu, e=e, law=law)
    _, wn_key, _, kept = fastpath._last_contact  # noqa: SLF001 - the terms it solved with
    assert wn_key == problem.wn.tobytes() and kept[2] == result.mnn
    fields = {name: getattr(result, name) for name in
              ("mnn", "mnt", "mtt", "vn_approach", "vt_approach")}
    speed_bounds = (dot_bound(problem.wn.tolist(), problem.u.tolist()),
                    dot_bound(problem.wt.tolist(), problem.u.tolist()))
    replay = partial(replayed_law, law, fields, kept[5],
                     term_bounds(problem.mass_matrix, problem.wn, problem.wt, "cholesky"),
                     speed_bounds, mu, e)
    Tracked.close_decisions = 0
    replayed = replay()
    assert replayed["normal_impulse"].value == result.normal_impulse
    assert replayed["tangential_impulse"].value == result.tangential_impulse
    if Tracked.close_decisions:
        replayed = branched(replay)
    bound = delta_u_bound(problem.mass_matrix, (kept[6], kept[7]), replayed, "cholesky")
    return result, bound


def exact_u_after(problem, mu, e, law) -> list:
    """The exact ``u_after`` (Fractions) of ``problem``, its float inputs taken as exact, under
    a law without square roots (Poisson, Newton, newton-lcp): ``X = M⁻¹ [w_n w_t]`` solved in
    Fractions, the contact terms and speeds formed exactly, the law's closed form
    (fastpath.law_answer) run on error_bounds.Exact numbers, so the exact computation takes
    its own branches, then ``u + X (I_n, I_t)``."""
    assert law in ("poisson", "newton", "newton-lcp"), law
    inverse = exact_inverse(problem.mass_matrix.tolist())
    rows = [[Fraction(x) for x in problem.wn], [Fraction(x) for x in problem.wt]]
    speeds = [Fraction(x) for x in problem.u]
    columns = [[sum(a * w for a, w in zip(line, row)) for line in inverse] for row in rows]
    mnn, mnt, mtt = (sum(a * b for a, b in zip(rows[i], columns[j]))
                     for i, j in ((0, 0), (0, 1), (1, 1)))
    vn, vt = (sum(a * b for a, b in zip(row, speeds)) for row in rows)
    sign = -1 if vt < 0 or (vt == 0 and mnt < 0) else 1  # as closed_form turns t
    inputs = [Exact(x) for x in (mnn, sign * mnt, mtt, vn, sign * vt, Fraction(mu), Fraction(e))]
    out = fastpath.law_answer(law, *inputs, inputs[0] * inputs[2] - inputs[1] * inputs[1])
    assert out is not None
    normal, tangential = Exact(out[0]).value, sign * Exact(out[1]).value
    return [s + x_n * normal + x_t * tangential
            for s, x_n, x_t in zip(speeds, columns[0], columns[1])]
