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

The libm functions are not IEEE operations: glibc documents ``cos`` and ``sin`` within 1 ulp
on x86-64 (its manual, 'Known Maximum Errors in Math Functions'), i.e. relative error at most
``2 u`` (:data:`LIBM_RELATIVE`); two machines' libms may round them differently.
"""

from __future__ import annotations

import math

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
