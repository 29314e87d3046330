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
  difference of two nearby points is as good as that difference divided by their distance.

The libm functions are not IEEE operations: glibc documents ``cos`` and ``sin`` within 1 ulp
on x86-64 (its manual, 'Known Maximum Errors in Math Functions'), i.e. relative error at most
``2 u`` (:data:`LIBM_RELATIVE`); two machines' libms may round them differently.
"""

from __future__ import annotations

import math

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


def dot_bound(a, b) -> float:
    """Forward error bound of ``Σ a_i b_i`` in floating point, any summation order:
    ``γ_n Σ|a_i b_i|`` (Higham eq. (3.5))."""
    a, b = list(a), list(b)
    if len(a) != len(b):
        raise ValueError(f"dot_bound: {len(a)} terms against {len(b)}")
    return gamma(len(a)) * math.fsum(abs(x * y) for x, y in zip(a, b))


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
