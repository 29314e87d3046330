"""Forward error bounds of floating-point arithmetic, for the tests that compare results across
implementations, kernels or machines (docs/verdicts.md, 'Same answers on every CPU').

A tolerance between two computations of one quantity is the sum of both computations' forward
error bounds (each from the exact value of the same inputs): never a count of units in the
last place chosen because it passed. The bounds are the standard ones of Higham, *Accuracy and
Stability of Numerical Algorithms* (2nd ed., 2002), for IEEE double precision with rounding to
nearest, whatever order or fused multiply-adds a kernel uses:

* one operation ``x op y`` (``+ - * /``, ``sqrt``) is exact times ``(1 + δ)``, ``|δ| <= u``
  (Higham §2.2, eq. (2.4)), with the unit roundoff ``u = 2**-53`` (:data:`U`);
* ``n`` such factors together are ``1 + θ_n`` with ``|θ_n| <= γ_n = n u / (1 − n u)``
  (Higham Lemma 3.1; :func:`gamma`), and ``γ_m + γ_n + γ_m γ_n <= γ_(m+n)`` (Lemma 3.3);
* a dot product of ``n`` terms, summed in any order (BLAS kernels, FMA or not), is within
  ``γ_n Σ|a_i b_i|`` of the exact one (Higham eq. (3.5); :func:`dot_bound`);
* a unit vector ``v / |v|`` from a ``v`` known within ``δ`` (Euclidean) is within
  ``2 δ / |v|`` of the exact direction (:func:`direction_bound`): a normal taken from the
  difference of two nearby points is as good as that difference divided by their distance;
* a solve of an SPD ``M x = b`` (Cholesky, or LAPACK's LU with partial pivoting) is the exact
  solution of a nearby ``(M + ΔM) x̂ = b`` (Higham Theorems 10.4 and 9.4;
  :func:`solve_backward_bounds`), so a contact term ``w_iᵀ M⁻¹ w_j`` is within
  ``‖ΔM‖₂ |x_i| |x_j|`` plus its dot product's rounding (:func:`bilinear_bound`).

* a straight-line computation of a few scalars (a closed form, a root, a residual) carries its
  own bound as it goes (:class:`Tracked`: running error analysis, Higham §3.3): each result
  is ``fl(x op y)``, within ``u |fl(x op y)|`` of ``x op y`` (Higham eq. (2.5)), and the
  operands' bounds are carried through each operation exactly (not only to first order).

* a solve's or an iteration's answer ``x̂`` is within ``|A⁻¹| |A x̂ − b|`` of the exact
  solution of ``A x = b`` (a posteriori): with ``A``, ``b`` rebuilt exactly in Fractions from
  the floats the computation read, the residual and the inverse are exact, and no constant
  of the solver's backward error enters; :class:`Exact` runs the library's formulas (written
  with float constants) in exact arithmetic to build them.

* a square root inside such an exact evaluation (a quadratic's root at a computed point) is
  bracketed by two Fractions from an integer square root (:func:`sqrt_bracket`), exact where
  the radicand is a rational square.

The libm functions are not IEEE operations: glibc documents ``cos`` and ``sin`` within 1 ulp
on x86-64 (its manual, 'Known Maximum Errors in Math Functions'), i.e. relative error at most
``2 u`` (:data:`LIBM_RELATIVE`); two machines' libms may round them differently.
"""

from __future__ import annotations

import math
import operator
from fractions import Fraction

import numpy as np

#: Unit roundoff of IEEE double precision, rounding to nearest (Higham §2.1).
U = 2.0 ** -53

#: Relative error bound of libm's ``cos`` and ``sin``: 1 ulp, and 1 ulp of ``x`` is at most
#: ``2 u |x|``.
LIBM_RELATIVE = 2 * U


def gamma(n: int) -> float:
    """``γ_n = n u / (1 − n u)``: the bound of ``n`` roundings together (Higham Lemma 3.1)."""
    if n < 0 or n * U >= 1.0:
        raise ValueError(f"gamma({n}): n must be a count with n u < 1")
    return n * U / (1.0 - n * U)


#: The spacing of the subnormal numbers, twice the most a product that underflows is rounded
#: by (gradual underflow, outside the ``1 + δ`` model; sums of subnormals are exact). Half of
#: it, 2⁻¹⁰⁷⁵, is no float.
UNDERFLOW = 2.0 ** -1074


def dot_bound(a, b) -> float:
    """Forward error bound of ``Σ a_i b_i`` in floating point, any summation order:
    ``γ_n Σ|a_i b_i|`` (Higham eq. (3.5)), plus ``n`` times :data:`UNDERFLOW` for products
    that underflow (nothing at the tests' scales)."""
    a, b = list(a), list(b)
    if len(a) != len(b):
        raise ValueError(f"dot_bound: {len(a)} terms against {len(b)}")
    return (gamma(len(a)) * math.fsum(abs(x * y) for x, y in zip(a, b))
            + len(a) * UNDERFLOW)


def direction_bound(error: float, length: float) -> float:
    """How far ``v / |v|`` can be from the exact direction when the computed ``v`` (of length
    ``length``) is within ``error`` of the exact one (both Euclidean):
    ``2 error / (length − error)``.

    Why: ``|v̂/|v̂| − v/|v|| <= |v̂ − v|/|v| + |v̂| |1/|v̂| − 1/|v||``, the second term is
    ``||v| − |v̂||/|v| <= |v̂ − v|/|v|``, and the exact ``|v| >= length − error``. Infinite when
    ``length`` is not above ``error`` (no direction is then known)."""
    if not length > error:
        return math.inf
    return 2.0 * error / (length - error)


def _lu_partial_pivoting(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``L`` and ``U`` of Gaussian elimination with partial pivoting (the rows permuted as
    LAPACK's ``getrf`` permutes them; only their magnitudes are used)."""
    upper = np.array(matrix, dtype=float)
    size = len(upper)
    lower = np.eye(size)
    for k in range(size - 1):
        pivot = k + int(np.argmax(np.abs(upper[k:, k])))
        upper[[k, pivot]] = upper[[pivot, k]]
        lower[[k, pivot], :k] = lower[[pivot, k], :k]
        for i in range(k + 1, size):
            lower[i, k] = upper[i, k] / upper[k, k]
            upper[i, k:] -= lower[i, k] * upper[k, k:]
    return lower, np.triu(upper)


def solve_backward_bounds(matrix) -> dict[str, float]:
    """``‖ΔM‖₂`` bounds of a computed solution of ``M x = b`` that solves ``(M + ΔM) x̂ = b``
    exactly, for the two ways the library solves an SPD ``M`` of size ``p``:

    * ``"cholesky"``: ``|ΔM| <= γ_(3p+1) |R̂ᵀ| |R̂|`` (Higham Theorem 10.4), whatever the
      order of the factor's and the triangular solves' sums;
    * ``"lu"`` (``numpy.linalg.solve``, LAPACK's ``gesv``: partial pivoting):
      ``|ΔM| <= γ_(3p) |L̂| |Û|`` (Higham Theorem 9.4).

    The 2-norm of the componentwise bound bounds ``‖ΔM‖₂``; the factors are worked out here
    (their rounding moves the bound by a relative ``O(u)``, a second-order effect)."""
    matrix = np.asarray(matrix, dtype=float)
    size = len(matrix)
    factor = np.abs(np.linalg.cholesky(matrix))
    lower, upper = _lu_partial_pivoting(matrix)
    return {"cholesky": gamma(3 * size + 1) * float(np.linalg.norm(factor @ factor.T, 2)),
            "lu": gamma(3 * size) * float(np.linalg.norm(np.abs(lower) @ np.abs(upper), 2))}


def bilinear_bound(backward: float, x_i, x_j, w_i) -> float:
    """Forward error bound of ``w_iᵀ x̂_j`` where ``x̂_j`` solves ``(M + ΔM) x̂_j = w_j``,
    ``‖ΔM‖₂ <= backward``, against the exact ``w_iᵀ M⁻¹ w_j``: to first order
    ``|x_iᵀ ΔM x_j| + γ_p Σ|w_i x_j|`` (the perturbed inverse, ``M⁻¹ − (M + ΔM)⁻¹ ≈
    M⁻¹ ΔM M⁻¹``, then the dot product, :func:`dot_bound`); the second order is
    ``‖ΔM‖₂² |x_i| |x_j| / λ_min``, below ``u²κ²`` of the term."""
    x_i, x_j = np.asarray(x_i, dtype=float), np.asarray(x_j, dtype=float)
    return (backward * float(np.linalg.norm(x_i) * np.linalg.norm(x_j))
            + dot_bound(np.asarray(w_i, dtype=float).tolist(), x_j.tolist()))


_new = object.__new__


class Tracked:
    """A float ``value`` with ``error``, a bound on its distance from the exact value of the
    same expression of exact inputs (running error analysis, Higham §3.3).

    Arithmetic (``+ - * /`` with floats or other ``Tracked``, :meth:`sqrt`) rounds the value
    as IEEE does (each result is the float the same operation on plain floats gives, so a
    computation written with ``Tracked`` can be checked bit for bit against the code it
    follows) and bounds the new error by the operands' errors carried through the exact
    operation plus the rounding, ``u |result|`` (Higham eq. (2.5)):

    * ``a ± b``: ``e_a + e_b``;
    * ``a b``: ``|a| e_b + |b| e_a + e_a e_b``;
    * ``a / b``: ``(|a| e_b + |b| e_a) / (|b| (|b| − e_b))``, infinite unless ``|b| > e_b``;
    * ``√a`` (of an exact ``a >= 0``): ``min(√e_a, e_a / √a)``, since
      ``|√x − √y| = |x − y| / (√x + √y)`` and ``|√x − √y| <= √|x − y|``.

    A plain float is exact (error 0). The bound's own arithmetic rounds too: a relative
    ``O(u)`` of the bound, a second-order effect. Divisions by zero and NaNs are not
    handled: the bound is for the finite results the tests look at.

    Comparisons compare the values, so code written for floats takes the branches it takes
    on floats. The bound assumes the exact computation takes the same ones: a comparison
    whose sides are within their errors of each other could go the other way in exact
    arithmetic, and adds one to :attr:`Tracked.close_decisions` (reset it before a
    computation; where it is not 0 the bound is not established, and the result is a
    decision within its band). ``float()`` gives the value (a check such as
    ``math.isfinite``); ``math.sqrt`` would drop the error: use :meth:`sqrt`."""

    __slots__ = ("value", "error")

    #: Comparisons so far whose outcome the errors leave open (see above).
    close_decisions = 0
    #: The indices (in close_decisions' count) of the close comparisons to decide the other
    #: way: :func:`every_branch` follows each path an exact computation could take.
    flipped: frozenset[int] = frozenset()

    def __init__(self, value: float, error: float = 0.0):
        self.value, self.error = float(value), float(error)

    @staticmethod
    def of(x) -> Tracked:
        return x if type(x) is Tracked else Tracked(x)

    # The operations below are written out (no helper calls): the laws' replays run them a
    # few million times per test.
    def __add__(self, other):
        if type(other) is Tracked:
            value, carried = self.value + other.value, self.error + other.error
        else:
            value, carried = self.value + other, self.error
        result = _new(Tracked)
        result.value, result.error = value, carried + U * abs(value)
        return result

    __radd__ = __add__

    def __sub__(self, other):
        if other is self:  # x − x is 0 in exact arithmetic too
            return Tracked(0.0)
        if type(other) is Tracked:
            value, carried = self.value - other.value, self.error + other.error
        else:
            value, carried = self.value - other, self.error
        result = _new(Tracked)
        result.value, result.error = value, carried + U * abs(value)
        return result

    def __rsub__(self, other):
        value = other - self.value
        result = _new(Tracked)
        result.value, result.error = value, self.error + U * abs(value)
        return result

    def __mul__(self, other):
        if type(other) is Tracked:
            value = self.value * other.value
            carried = (abs(self.value) * other.error + abs(other.value) * self.error
                       + self.error * other.error)
        else:
            value, carried = self.value * other, abs(other) * self.error
        result = _new(Tracked)
        result.value, result.error = value, carried + U * abs(value)
        return result

    __rmul__ = __mul__

    def __truediv__(self, other):
        other = Tracked.of(other)
        if not abs(other.value) > other.error:
            return Tracked(self.value / other.value, math.inf)
        carried = ((abs(self.value) * other.error + abs(other.value) * self.error)
                   / (abs(other.value) * (abs(other.value) - other.error)))
        value = self.value / other.value
        return Tracked(value, carried + U * abs(value))

    def __rtruediv__(self, other):
        return Tracked(other) / self

    def __neg__(self):
        return Tracked(-self.value, self.error)  # exact

    def __abs__(self):
        return Tracked(abs(self.value), self.error)  # exact

    def __float__(self) -> float:
        return self.value

    def _decide(self, other, outcome) -> bool:
        """``outcome(a, b)`` of the values; a close comparison (see the class docstring) is
        counted, and decided the other way where its index is in :attr:`Tracked.flipped`."""
        if other is self:
            return outcome(self.value, self.value)
        if type(other) is Tracked:
            value, errors = other.value, self.error + other.error
        else:
            value, errors = other, self.error
        decided = outcome(self.value, value)
        if errors > 0.0 and abs(self.value - value) <= errors:
            if Tracked.close_decisions in Tracked.flipped:
                decided = not decided
            Tracked.close_decisions += 1
        return decided

    def __lt__(self, other):
        return self._decide(other, operator.lt)

    def __le__(self, other):
        return self._decide(other, operator.le)

    def __gt__(self, other):
        return self._decide(other, operator.gt)

    def __ge__(self, other):
        return self._decide(other, operator.ge)

    def __eq__(self, other):
        if not isinstance(other, (Tracked, float, int)):
            return NotImplemented
        return self._decide(other, operator.eq)

    def __ne__(self, other):
        if not isinstance(other, (Tracked, float, int)):
            return NotImplemented
        return self._decide(other, operator.ne)

    __hash__ = None

    @staticmethod
    def math_sqrt(x):
        """``math.sqrt`` that keeps a :class:`Tracked` tracked (for code that calls
        ``math.sqrt``: the tests put it in that module's ``math``)."""
        return x.sqrt() if isinstance(x, Tracked) else math.sqrt(x)

    def sqrt(self) -> Tracked:
        """``√a``, the exact ``a`` taken as ``>= 0`` (a real root exists)."""
        root = math.sqrt(self.value)
        carried = math.sqrt(self.error)
        if root > 0.0:
            carried = min(carried, self.error / root)
        return Tracked(root, carried + U * root)

    def __repr__(self) -> str:
        return f"Tracked({self.value!r}, error={self.error:.3g})"


class Exact:
    """A rational number whose arithmetic with floats is exact too (``Fraction`` turns
    ``Fraction * float`` into a float): the library's straight-line formulas, written with
    float constants such as ``2.0 * mu``, run on ``Exact`` inputs give the exact value of the
    same expression of the same inputs, for comparison with their float results. ``value``
    is the ``Fraction``."""

    __slots__ = ("value",)

    def __init__(self, value):
        self.value = value.value if type(value) is Exact else Fraction(value)

    @staticmethod
    def _of(other):
        if type(other) is Exact:
            return other.value
        if isinstance(other, (int, float, Fraction, np.floating, np.integer)):
            return Fraction(other)
        return NotImplemented

    def _apply(self, other, operation):
        other = Exact._of(other)
        if other is NotImplemented:
            return NotImplemented
        return Exact(operation(self.value, other))

    def __add__(self, other):
        return self._apply(other, lambda a, b: a + b)

    __radd__ = __add__

    def __sub__(self, other):
        return self._apply(other, lambda a, b: a - b)

    def __rsub__(self, other):
        return self._apply(other, lambda a, b: b - a)

    def __mul__(self, other):
        return self._apply(other, lambda a, b: a * b)

    __rmul__ = __mul__

    def __truediv__(self, other):
        return self._apply(other, lambda a, b: a / b)

    def __rtruediv__(self, other):
        return self._apply(other, lambda a, b: b / a)

    def __neg__(self):
        return Exact(-self.value)

    def __abs__(self):
        return Exact(abs(self.value))

    def _compare(self, other, operation):
        other = Exact._of(other)
        if other is NotImplemented:
            return NotImplemented
        return operation(self.value, other)

    def __lt__(self, other):
        return self._compare(other, lambda a, b: a < b)

    def __le__(self, other):
        return self._compare(other, lambda a, b: a <= b)

    def __gt__(self, other):
        return self._compare(other, lambda a, b: a > b)

    def __ge__(self, other):
        return self._compare(other, lambda a, b: a >= b)

    def __eq__(self, other):
        return self._compare(other, lambda a, b: a == b)

    def __ne__(self, other):
        return self._compare(other, lambda a, b: a != b)

    __hash__ = None

    def __float__(self) -> float:
        return float(self.value)

    def __repr__(self) -> str:
        return f"Exact({self.value})"


def sqrt_bracket(value, bits: int = 256) -> tuple[Fraction, Fraction]:
    """``(lo, hi)``, Fractions with ``lo <= √value <= hi`` and ``hi − lo <= 2**-bits / q`` for
    ``value = p/q >= 0`` in lowest terms; ``lo == hi`` exactly where ``value`` is the square of
    a rational. ``√(p/q) = √(p q)/q``, and ``s = isqrt(p q 4**bits)`` is the largest integer
    with ``s² <= p q 4**bits``: an exact-integer bracket, no rounding anywhere (for a root
    that enters exact arithmetic: a quadratic's root at a computed point)."""
    value = Fraction(value)
    if value < 0:
        raise ValueError(f"no real square root of {value}")
    p, q = value.numerator, value.denominator
    whole = math.isqrt(p * q)
    if whole * whole == p * q:  # a rational square: √(p/q) = √(pq)/q exactly
        return Fraction(whole, q), Fraction(whole, q)
    scaled = math.isqrt(p * q << (2 * bits))
    return Fraction(scaled, q << bits), Fraction(scaled + 1, q << bits)


def every_branch(replay, limit: int = 64) -> list:
    """``replay()``, a computation on :class:`Tracked` numbers with branches, along every
    path an exact computation could take: first as the floats decide, then with each close
    comparison (one whose sides are within their errors: :attr:`Tracked.close_decisions`)
    decided the other way (:attr:`Tracked.flipped`), recursively, the later close
    comparisons counted again on each path. Returns one result per path, the floats' path
    first; a path on which the replay raises (a flipped branch dividing by zero, say) gives
    None. Along a path each comparison that is not close goes as it would in exact
    arithmetic (its sides lie further apart than their errors) and the close ones are fixed,
    so the path's errors bound its distance from the exact computation along it, and the
    exact computation follows one of the paths: :func:`widened` turns that into a bound.
    More than ``limit`` paths raise (a replay that branches that often is no decision at a
    point)."""
    results, pending = [], [frozenset()]
    saved = Tracked.close_decisions, Tracked.flipped
    try:
        while pending:
            flipped = pending.pop(0)
            Tracked.close_decisions, Tracked.flipped = 0, flipped
            try:
                results.append(replay())
            except (ArithmeticError, ValueError):
                if not flipped:
                    raise
                results.append(None)
                continue
            start = max(flipped) + 1 if flipped else 0
            pending += [flipped | {index} for index in range(start, Tracked.close_decisions)]
            if len(results) + len(pending) > limit:
                raise RuntimeError(f"more than {limit} paths")
    finally:
        Tracked.close_decisions, Tracked.flipped = saved
    return results


def widened(values) -> Tracked:
    """The first of ``values`` (one quantity along each path of :func:`every_branch`, None
    where a path gave none) with a bound on its distance from the exact answer whichever path
    the exact computation takes: the largest, over the paths, of its distance from that
    path's value plus that path's error (rounded up; infinite where a path has no finite
    value). One path: the value itself."""
    first = values[0]
    if len(values) == 1:
        return first
    reach = first.error
    for other in values[1:]:
        if other is None or not (math.isfinite(other.value) and math.isfinite(other.error)):
            return Tracked(first.value, math.inf)
        reach = max(reach, (abs(first.value - other.value) + other.error) * (1 + 2 * U))
    return Tracked(first.value, reach)


def exact_inverse(matrix):
    """``A⁻¹`` by Gauss–Jordan in Fractions (exact; A nonsingular)."""
    size = len(matrix)
    rows = [[Fraction(x) for x in row] + [Fraction(int(i == j)) for j in range(size)]
            for i, row in enumerate(matrix)]
    for k in range(size):
        pivot = next(i for i in range(k, size) if rows[i][k] != 0)
        rows[k], rows[pivot] = rows[pivot], rows[k]
        rows[k] = [x / rows[k][k] for x in rows[k]]
        for i in range(size):
            if i != k and rows[i][k] != 0:
                rows[i] = [a - rows[i][k] * b for a, b in zip(rows[i], rows[k])]
    return [row[size:] for row in rows]
