"""The forward error bounds of tests/error_bounds.py hold: each against exact rational
arithmetic (:class:`fractions.Fraction`) on random and adversarial inputs, summed in several
orders as different kernels would, and each is tight enough to mean something."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.error_bounds import (
    LIBM_RELATIVE,
    Exact,
    Tracked,
    U,
    bilinear_bound,
    direction_bound,
    dot_bound,
    every_branch,
    gamma,
    solve_backward_bounds,
    sqrt_bracket,
    widened,
)

finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)


def test_gamma_is_n_u_over_one_minus_n_u_and_refuses_nonsense():
    assert gamma(0) == 0.0
    assert gamma(1) == pytest.approx(U, rel=1e-15)
    assert gamma(3) == 3 * U / (1 - 3 * U)
    assert gamma(2) + gamma(3) + gamma(2) * gamma(3) <= gamma(5)  # Higham Lemma 3.3
    assert LIBM_RELATIVE == 2 * U
    with pytest.raises(ValueError, match="n u < 1"):
        gamma(-1)
    with pytest.raises(ValueError, match="n u < 1"):
        gamma(2 ** 53)


def sums(a, b):
    """``Σ a_i b_i`` as kernels form it: left to right, right to left, pairwise, and with
    fused multiply-adds (each product exact, one rounding per addition)."""
    products = [x * y for x, y in zip(a, b)]
    left = 0.0
    for value in products:
        left += value
    right = 0.0
    for value in reversed(products):
        right += value
    pairwise = list(products)
    while len(pairwise) > 1:
        pairwise = [pairwise[i] + pairwise[i + 1] if i + 1 < len(pairwise) else pairwise[i]
                    for i in range(0, len(pairwise), 2)]
    fused = 0.0
    for x, y in zip(a, b):
        fused = float(Fraction(x) * Fraction(y) + Fraction(fused))  # fma: one rounding
    return [left, right, pairwise[0], fused]


@given(st.lists(st.tuples(finite, finite), min_size=1, max_size=12))
def test_dot_bound_holds_in_every_order(pairs):
    a, b = [x for x, _ in pairs], [y for _, y in pairs]
    exact = sum(Fraction(x) * Fraction(y) for x, y in pairs)
    bound = Fraction(dot_bound(a, b))
    for value in sums(a, b):
        assert abs(Fraction(value) - exact) <= bound, (value, float(exact), float(bound))


def test_dot_bound_is_reached_within_a_small_factor_where_terms_cancel():
    # Cancellation is where the bound matters: a sum near zero of large terms. The error of
    # some random draws must come within a factor 100 of γ_n Σ|a_i b_i| (the bound is sharp
    # to first order; a bound 1e6 too loose would catch nothing).
    rng = np.random.default_rng(35)
    worst = 0.0
    for _ in range(2000):
        a = rng.uniform(-1, 1, 4).tolist()
        b = rng.uniform(-1, 1, 4).tolist()
        b[-1] = -sum(x * y for x, y in zip(a[:-1], b[:-1])) / a[-1]  # exact sum near 0
        exact = sum(Fraction(x) * Fraction(y) for x, y in zip(a, b))
        error = abs(Fraction(sums(a, b)[0]) - exact)
        worst = max(worst, float(error) / dot_bound(a, b))
    assert 0.01 < worst <= 1.0


def test_dot_bound_refuses_unequal_lengths():
    with pytest.raises(ValueError, match="3 terms against 2"):
        dot_bound([1.0, 2.0, 3.0], [1.0, 2.0])


@given(st.floats(min_value=1e-3, max_value=1e3), st.floats(min_value=-math.pi, max_value=math.pi),
       st.floats(min_value=0.0, max_value=0.3), st.floats(min_value=-math.pi, max_value=math.pi))
def test_direction_bound_holds(length, angle, relative_error, error_angle):
    exact = np.array([length * math.cos(angle), length * math.sin(angle)])
    error = relative_error * length
    computed = exact + error * np.array([math.cos(error_angle), math.sin(error_angle)])
    computed_length = float(np.hypot(*computed))
    moved = np.hypot(*(computed / computed_length - exact / length))
    # the bound takes the computed length (all a program knows) and the error's size
    assert moved <= direction_bound(error, computed_length) * (1 + 1e-12) + 4 * U


def test_direction_bound_is_infinite_where_no_direction_is_known():
    assert direction_bound(1.0, 1.0) == math.inf
    assert direction_bound(1e-3, 1.0) == pytest.approx(2e-3 / (1 - 1e-3))


def exact_solve(matrix, rhs):
    """``M⁻¹ b`` in rational arithmetic (Gauss–Jordan on Fractions)."""
    size = len(matrix)
    rows = [[Fraction(v) for v in row] + [Fraction(b)] for row, b in zip(matrix, rhs)]
    for k in range(size):
        pivot = next(i for i in range(k, size) if rows[i][k] != 0)
        rows[k], rows[pivot] = rows[pivot], rows[k]
        for i in range(size):
            if i != k:
                factor = rows[i][k] / rows[k][k]
                rows[i] = [a - factor * b for a, b in zip(rows[i], rows[k])]
    return [rows[i][size] / rows[i][i] for i in range(size)]


def cholesky_solve(matrix, rhs):
    """``M⁻¹ b`` by the Cholesky factor ``L`` and two substitutions, ``L y = b``, ``Lᵀ x = y``."""
    factor = np.linalg.cholesky(matrix).tolist()
    size = len(factor)
    y = []
    for i in range(size):
        y.append((rhs[i] - sum(factor[i][k] * y[k] for k in range(i))) / factor[i][i])
    x = [0.0] * size
    for i in reversed(range(size)):
        x[i] = (y[i] - sum(factor[k][i] * x[k] for k in range(i + 1, size))) / factor[i][i]
    return np.array(x)


def test_bilinear_bound_holds_for_both_solves_against_exact_rationals():
    # w_iᵀ M⁻¹ w_j by numpy's LU solve and by a Cholesky solve, each within its own bound of
    # the exact value, on random SPD matrices up to κ ~ 1e6 (graded diagonals).
    rng = np.random.default_rng(9)
    worst = 0.0
    for _ in range(200):
        size = int(rng.integers(2, 7))
        root = rng.normal(size=(size, size)) * 10.0 ** rng.uniform(-3, 0, size)
        matrix = root @ root.T + 1e-3 * np.eye(size)
        wi, wj = rng.normal(size=(2, size))
        backward = solve_backward_bounds(matrix)
        exact = sum(Fraction(a) * b for a, b in zip(wi.tolist(), exact_solve(matrix.tolist(),
                                                                               wj.tolist())))
        solves = {"lu": np.linalg.solve(matrix, wj), "cholesky": cholesky_solve(matrix, wj)}
        x_i = np.linalg.solve(matrix, wi)
        for method, x_j in solves.items():
            bound = bilinear_bound(backward[method], x_i, x_j, wi)
            error = abs(Fraction(float(wi @ x_j)) - exact)
            assert error <= Fraction(bound), (method, float(error), bound)
            worst = max(worst, float(error) / bound)
    assert worst > 1e-4  # the bound is not vacuous: some draws come within 1e4 of it


def exact_sqrt(value: Fraction) -> Fraction:
    """``√value`` to 80 significant digits (decimal), far below a double's rounding."""
    from decimal import Context, Decimal

    context = Context(prec=80)
    quotient = context.divide(Decimal(value.numerator), Decimal(value.denominator))
    return Fraction(context.sqrt(quotient))


def test_tracked_bounds_hold_against_exact_rationals():
    # Random straight-line programs of + − × ÷ √ over exact inputs and inputs known within a
    # bound (their exact value drawn inside it): every intermediate within its Tracked error
    # of the exact value, computed with Fractions (√ to 80 digits).
    rng = np.random.default_rng(35)
    checked = 0
    for _ in range(300):
        pool = []
        for _ in range(4):
            value = float(rng.normal() * 10.0 ** rng.uniform(-3, 3))
            error = 0.0 if rng.random() < 0.5 else abs(value) * 10.0 ** rng.uniform(-16, -6)
            exact = Fraction(value) + Fraction(float(rng.uniform(-1, 1))) * Fraction(error)
            pool.append((Tracked(value, error), exact))
        for _ in range(12):
            (a, exact_a), (b, exact_b) = (pool[int(i)] for i in rng.integers(len(pool), size=2))
            operation = int(rng.integers(5))
            if operation == 0:
                result = (a + b, exact_a + exact_b)
            elif operation == 1:
                result = (a - b, exact_a - exact_b)
            elif operation == 2:
                result = (a * b, exact_a * exact_b)
            elif operation == 3 and exact_b != 0 and b.value != 0.0:
                result = (a / b, exact_a / exact_b)
            elif operation == 4 and exact_a > 0 and a.value > 0.0:
                result = (a.sqrt(), exact_sqrt(exact_a))
            else:
                continue
            got, exact = result
            if not (math.isfinite(got.value) and abs(got.value) < 1e100):
                continue
            assert abs(Fraction(got.value) - exact) <= Fraction(got.error), (got, float(exact))
            # the same float as plain arithmetic gives
            pool.append(result)
            checked += 1
    assert checked > 2500


def test_tracked_values_are_plain_floats_and_the_bound_is_tight_for_a_sum():
    a, b = 0.1, 0.7
    assert (Tracked(a) * b - a / b).value == a * b - a / b
    assert (Tracked(a) + b).sqrt().value == math.sqrt(a + b)
    assert (1.0 - Tracked(a)).value == 1.0 - a and (-Tracked(a)).error == 0.0
    # n positive terms summed left to right: at most γ_(n−1) of their sum (Higham (3.5)),
    # the running bound being Σ u |partial sums|.
    terms = np.random.default_rng(1).uniform(0, 1, 50).tolist()
    total = Tracked(0.0)
    for term in terms:
        total = total + term
    assert total.error <= gamma(49) * math.fsum(terms)
    assert total.error >= 0.5 * U * math.fsum(terms)  # not absurdly loose either
    assert (Tracked(1.0) / Tracked(1e-20, 1e-20)).error == math.inf


@given(finite, finite, st.floats(min_value=0.5, max_value=4.0))
def test_exact_keeps_float_constants_exact(a, b, c):
    """Fraction * float is a float; Exact * float stays exact, through every operation and
    comparison the laws' formulas use."""
    x, y = Exact(a), Exact(b)
    expected = (Fraction(a) + 2 * Fraction(b)) / Fraction(c) - Fraction(1, 10)
    got = (x + 2.0 * y) / c - Fraction(1, 10)
    assert type(got) is Exact and got.value == expected
    assert (1.0 - x).value == 1 - Fraction(a) and (-x).value == -Fraction(a)
    assert abs(x).value == abs(Fraction(a)) and (c / Exact(c)).value == 1
    assert (x < y) == (a < b) and (x <= b) == (a <= b) and (x == a) and not (x != a)
    assert float(x * 0.1) == float(Fraction(a) * Fraction(0.1))
    assert Exact(x).value == Fraction(a)


@given(st.fractions(min_value=0, max_value=10**6, max_denominator=10**9))
def test_sqrt_bracket_holds_exactly_and_is_narrow(value):
    lo, hi = sqrt_bracket(value, bits=64)
    assert lo * lo <= value <= hi * hi  # a bracket, compared exactly
    assert hi - lo <= Fraction(1, 2**64 * Fraction(value).denominator)
    # the float root of the float radicand lies within 2u of the bracket (the conversion's
    # u, halved by the root, and the root's own u): a check that can fail
    root = math.sqrt(float(value))
    assert lo * (1 - 2 * Fraction(U)) <= Fraction(root) <= hi * (1 + 2 * Fraction(U))


def test_sqrt_bracket_is_a_point_on_rational_squares_and_refuses_negatives():
    assert sqrt_bracket(Fraction(121, 400)) == (Fraction(11, 20), Fraction(11, 20))
    assert sqrt_bracket(0) == (0, 0)
    lo, hi = sqrt_bracket(2)
    assert lo < hi and lo * lo < 2 < hi * hi
    with pytest.raises(ValueError):
        sqrt_bracket(Fraction(-1, 3))


def clamped_ramp(x: Tracked, y: Tracked):
    """A continuous function with a branch: ``x − y`` where ``x > y``, else ``(x − y)/4``
    (the two pieces meet at x = y), the branch decided on the computed values."""
    gap = x - y
    return {"value": gap if x > y else gap / 4}


@given(st.floats(0.1, 10), st.integers(-3, 3), st.floats(1e-15, 1e-13))
def test_every_branch_covers_the_exact_answer_where_the_floats_branch_the_other_way(
        x, ulps, error):
    """x and y within their errors of each other: the floats may take the other branch than
    exact arithmetic; the widened bound holds against the exact answer of the exact inputs
    (the Tracked inputs' exact values are x and y shifted inside their errors)."""
    y = x
    for _ in range(abs(ulps)):
        y = math.nextafter(y, math.inf if ulps > 0 else -math.inf)
    tx, ty = Tracked(x, error * x), Tracked(y, error * x)
    paths = every_branch(lambda: clamped_ramp(tx, ty))
    assert Tracked.flipped == frozenset() and Tracked.close_decisions == 0  # restored
    assert len(paths) == 2  # the comparison is close: both branches followed
    value = widened([p["value"] for p in paths])
    assert value.value == clamped_ramp(Tracked(x), Tracked(y))["value"].value
    for shift_x, shift_y in ((-1, 1), (1, -1), (0, 0), (1, 1)):  # exact inputs in the errors
        exact_x = Fraction(x) + shift_x * Fraction(error * x)
        exact_y = Fraction(y) + shift_y * Fraction(error * x)
        gap = exact_x - exact_y
        exact = gap if exact_x > exact_y else gap / 4
        assert abs(Fraction(value.value) - exact) <= Fraction(value.error), (exact, value)


def test_every_branch_counts_failed_paths_and_refuses_too_many():
    def failing():
        x = Tracked(1.0, 1e-16)
        return {"value": Tracked(1.0) / Tracked(0.0, 1.0) if x > 1.0 else Tracked(1.0)}

    paths = every_branch(failing)
    assert len(paths) == 2
    assert widened([p and p["value"] for p in paths]).error == math.inf
    assert widened([Tracked(2.0, 0.5)]).error == 0.5  # one path: unchanged

    def many():
        x = Tracked(1.0, 1e-16)
        return sum(1 for _ in range(10) if x > 1.0)

    with pytest.raises(RuntimeError):
        every_branch(many, limit=64)
    assert Tracked.flipped == frozenset()
