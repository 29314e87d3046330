"""Derived bounds for the two-phase Poisson law's answers (planar_impact.multicontact), for the
tests that compare its two methods, the enumeration and Lemke's algorithm (docs/verdicts.md,
'Same answers on every CPU'; docs/multi-contact.md, 'A two-phase Poisson law for m
contacts').

The two methods may end a phase in different modes (stick against slide with zero slip) and
a flat face's tangential split between its corners is not unique, so no bound on a phase's
own basis bounds the speeds. What both must reach is the same end state: each phase ends in
conditions on its total impulses, one per normal and one per tangential row, that the exact
law's answer satisfies whatever the path (the pieces the slip is followed in):

* a contact that recedes at the phase's end took exactly its base (``P_n = b``: it took at
  least ``b``, and the phase is complementary, which the library checks); else it ends at
  ``v_n = 0``;
* a contact whose slip kept its sign from the phase's start to its end had its friction
  held against that slip in every piece (``P_t = −s μ P_n``, ``s`` the slip's sign); one
  that ends with no slip ends at ``v_t = 0``; one that took no normal impulse took no
  friction (``P_t = 0``); a contact that ends sliding from no slip is ``P_t = −s μ P_n``
  only where the phase was one piece (no cut; checked: other paths are not covered here).

Sliding, receding and sticking are decisions on the computed end state, each taken with the
library's band (``SIGN_TOLERANCE`` of the speed scale): the exact solution of the chosen
conditions is then checked to take the same decisions, exactly (a receding contact recedes,
an active one took at least its base, a held slip kept its sign, a stick is inside its
cone).

Both phases together are one linear system ``A z = b`` in ``z = (P_c, P_r)`` (the
restitution starts where the compression ended, ``v^A + W P_c``, with the base
``λ e_i P_nc,i``), built exactly in Fractions from the floats both methods read (W, v^A, μ,
e, λ). Its solutions may form a family (the corners' tangential split: W has two equal
columns), but every member gives the same ``Δu = X (P_c + P_r)`` with ``X`` the library's
``M⁻¹ w`` columns (checked exactly: X maps the family's directions to zero). So:

* each method's exact answer ``u* = u + X (P*_c + P*_r)`` is known exactly, and the two
  methods' exact answers are compared exactly (equal: the same end state);
* each computed ``u_after = fl(u + fl(X P̂))`` is within ``|X (P̂ − P*)|`` (the computed
  impulses' exact residual ``A P̂ − b`` pushed through the exact solve of ``A d = r``,
  evaluated exactly) plus the rounding of ``Δu`` (``γ_(2m) Σ_k |X_jk P̂_k|``: a sum of 2m
  products, any order; Higham eq. (3.5)) and of the addition (``u |u_after_j|``) of ``u*``.

No constant of a solver's backward error enters (the enumeration's pseudo-inverse, Lemke's
pivots): the residuals are those of the answers the methods returned. The bound is therefore
only as small as they are: each is checked against the library's own promise for a phase it
keeps (``RESIDUAL_TOLERANCE`` of the phase's scales, a decision band: ``residual_share``), so
an answer off its end state cannot pass inside its own bound.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from planar_impact.multicontact.phase import RESIDUAL_TOLERANCE, SIGN_TOLERANCE
from tests.error_bounds import U, gamma


def exact(x) -> Fraction:
    return Fraction(float(x))


def _solve_exact(matrix, rhs):
    """``(x, null)``: a solution of ``A x = b`` (free unknowns 0) and a basis of A's null
    space, by Gauss–Jordan in Fractions (exact); ValueError where inconsistent."""
    rows = [list(row) + [b] for row, b in zip(matrix, rhs)]
    size = len(matrix[0])
    pivots = []
    r = 0
    for k in range(size):
        pivot = next((i for i in range(r, len(rows)) if rows[i][k] != 0), None)
        if pivot is None:
            continue
        rows[r], rows[pivot] = rows[pivot], rows[r]
        rows[r] = [x / rows[r][k] for x in rows[r]]
        for i in range(len(rows)):
            if i != r and rows[i][k] != 0:
                rows[i] = [a - rows[i][k] * b for a, b in zip(rows[i], rows[r])]
        pivots.append(k)
        r += 1
    if any(row[-1] != 0 for row in rows[r:]):
        raise ValueError("the phases' end conditions are inconsistent")
    solution = [Fraction(0)] * size
    for i, k in enumerate(pivots):
        solution[k] = rows[i][-1]
    null = []
    for free in (k for k in range(size) if k not in pivots):
        vector = [Fraction(0)] * size
        vector[free] = Fraction(1)
        for i, k in enumerate(pivots):
            vector[k] = -rows[i][free]
        null.append(vector)
    return solution, null


@dataclass(frozen=True)
class ExactAnswer:
    """One method's answer rebuilt exactly: ``u_after`` (Fractions), ``error`` per component
    of ``u`` a float bound on the computed ``u_after``'s distance from it, ``exact_error``
    its part ``|X (P̂ − P*)|`` (rounded up), ``kinds`` the end conditions chosen per
    phase and contact ``(normal, friction)``, and ``residual_share`` the computed impulses'
    largest exact residual in those conditions as a share of the library's own promise
    (``RESIDUAL_TOLERANCE`` of the speed scale in a velocity row, of the impulse scale in
    an impulse row): the a posteriori part of ``error`` is only as small as that residual,
    and a share above 1 is an answer the library should not have returned."""

    u_after: tuple
    error: tuple
    exact_error: tuple
    kinds: tuple
    residual_share: float


def _columns(system):
    """X: the library's ``M⁻¹ w`` columns, per impulse row (n0, t0, n1, …), exact."""
    return [[exact(x) for x in system.inverse_rows[k // 2][:, k % 2]]
            for k in range(2 * system.count)]


def rebuild(system, answer) -> ExactAnswer:
    """The exact answer of ``answer`` (a ``TwoPhaseSolution`` of ``system``) and the bound
    on its computed ``u_after`` (module docstring)."""
    size = 2 * system.count
    delassus = [[exact(x) for x in row] for row in system.delassus]
    approach = [exact(x) for x in system.approach]
    mu, e = [exact(x) for x in system.mu], [exact(x) for x in system.e]
    scale = exact(answer.restitution_scale)
    band = SIGN_TOLERANCE * system.speed_scale()

    def unit(k):
        row = [Fraction(0)] * (2 * size)
        row[k] = Fraction(1)
        return row

    def velocity(phase, k):
        """``v_k`` at the end of ``phase`` (0 compression, 1 restitution) as ``(row, c)``:
        ``row · z + c``."""
        row = [Fraction(0)] * (2 * size)
        for p in range(phase + 1):
            for m in range(size):
                row[p * size + m] += delassus[k][m]
        return row, approach[k]

    def base(phase, i):
        """The base ``b_i`` as ``(row, c)``: 0 in the compression, ``λ e_i P_nc,i`` after."""
        row = [Fraction(0)] * (2 * size)
        if phase == 1:
            row[2 * i] = scale * e[i]
        return row, Fraction(0)

    matrix, rhs, kinds, checks = [], [], [], []
    speed = system.speed_scale()
    impulse = speed / min(float(x) for x in system.delassus.diagonal())
    row_scales = []  # per condition: the scale its residual is in (a speed or an impulse)
    phases = (answer.compression, answer.restitution)
    starts = (system.approach, answer.compression.velocities)
    for phase, (solution, start) in enumerate(zip(phases, starts)):
        phase_kinds = []
        for i in range(system.count):
            n, t = 2 * i, 2 * i + 1
            p_n, p_t = unit(phase * size + n), unit(phase * size + t)
            b_row, b_const = base(phase, i)
            if solution.velocities[n] > band:  # receding at the end: took its base
                normal = "base"
                matrix.append([a - b for a, b in zip(p_n, b_row)])
                rhs.append(b_const)
                row_scales.append(impulse)
            else:
                normal = "active"
                row, constant = velocity(phase, n)
                matrix.append(row)
                rhs.append(-constant)
                row_scales.append(speed)
            start_slip, end_slip = float(start[t]), float(solution.velocities[t])
            if normal == "base" and solution.impulses[n] == 0.0 and (
                    phase == 0 or answer.compression.impulses[n] == 0.0):
                friction, sense = "none", 0  # no normal impulse: no friction
                matrix.append(p_t)
                rhs.append(Fraction(0))
                row_scales.append(impulse)
            elif abs(end_slip) <= band:
                friction, sense = "stick", 0
                row, constant = velocity(phase, t)
                matrix.append(row)
                rhs.append(-constant)
                row_scales.append(speed)
            else:
                sense = 1 if end_slip > 0 else -1
                held = abs(start_slip) > band and (start_slip > 0) == (end_slip > 0)
                if not held and solution.cuts:
                    raise NotImplementedError(
                        f"phase {phase}, contact {i}: slides from no slip after a cut")
                friction = "held" if held else "slide"
                matrix.append([a + sense * mu[i] * b for a, b in zip(p_t, p_n)])
                rhs.append(Fraction(0))
                row_scales.append(impulse)
            phase_kinds.append((normal, friction))
            checks.append((phase, i, normal, friction, sense))
        kinds.append(tuple(phase_kinds))

    solution, null = _solve_exact(matrix, rhs)
    columns = _columns(system)

    def delta_u(z):
        total = [z[k] + z[size + k] for k in range(size)]
        return [sum(columns[k][j] * total[k] for k in range(size))
                for j in range(len(system.u))]

    # The family's directions change no speed: the exact answer is unique.
    assert all(x == 0 for vector in null for x in delta_u(vector)), "Δu not unique"
    _check_decisions(system, solution, checks, delassus, approach, mu, e, scale)

    u_exact = [exact(x) + d for x, d in zip(system.u, delta_u(solution))]
    computed = [exact(x) for x in answer.compression.impulses] + [
        exact(x) for x in answer.restitution.impulses]
    exact_error = [abs(a - b) for a, b in zip(delta_u(computed), delta_u(solution))]
    residual_share = max(float(abs(sum(a * z for a, z in zip(row, computed)) - b))
                         / (RESIDUAL_TOLERANCE * scale_)
                         for row, b, scale_ in zip(matrix, rhs, row_scales))
    totals = answer.compression.impulses + answer.restitution.impulses
    assert answer.u_after.tolist() == (system.u + system.delta_u(totals)).tolist()
    rounding = [gamma(size) * sum(abs(float(columns[k][j]) * float(totals[k]))
                                  for k in range(size)) * (1 + 4 * U)
                + U * abs(float(answer.u_after[j])) for j in range(len(system.u))]
    exact_float = tuple(float(x) * (1 + 2 * U) for x in exact_error)
    # The computed impulses' exact Δu is within ``exact_error`` of Δu*; fl(X P̂) and the
    # addition within ``rounding`` of it.
    return ExactAnswer(tuple(u_exact), tuple(a + b for a, b in zip(exact_float, rounding)),
                       exact_float, tuple(kinds), residual_share)


def _check_decisions(system, z, checks, delassus, approach, mu, e, scale):
    """The exact solution takes the decisions the conditions were chosen by (exactly)."""
    size = 2 * system.count
    for phase, i, normal, friction, sense in checks:
        n, t = 2 * i, 2 * i + 1
        impulses = z[phase * size:(phase + 1) * size]
        ends = [approach[k] + sum(delassus[k][m] * (z[m] + (z[size + m] if phase else 0))
                                  for m in range(size)) for k in range(size)]
        base = scale * e[i] * z[n] if phase else Fraction(0)
        if normal == "base":
            assert ends[n] > 0, (phase, i, "receding", ends[n])
        else:
            assert impulses[n] >= base, (phase, i, "active", impulses[n], base)
        if friction in ("held", "slide"):
            assert sense * ends[t] >= 0, (phase, i, friction, ends[t])
        elif friction == "stick":
            # Sticking corners share their tangential row (a flat face: W's columns equal),
            # so only their total is fixed; it must fit in their cones' total.
            group = [c for p, c, _, f, _ in checks if p == phase and f == "stick"]
            assert all(delassus[2 * c + 1] == delassus[t] for c in group), "stick rows differ"
            total_t = sum(impulses[2 * c + 1] for c in group)
            assert abs(total_t) <= sum(mu[c] * impulses[2 * c] for c in group), (
                phase, i, "outside the cone", total_t)
