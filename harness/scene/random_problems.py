"""Random contact-space impact problems shared by the solver tests and benchmarks.

Draws cover every Table 1 case and every collision type: ``m_nt`` over its whole admissible
range ``|m_nt| < √(m_nn m_tt)``, friction from 0 to 2 (with exact zeros), restitution in
[0, 1] (with exact 0 and 1), tangential approach of both signs (with exact zeros).
"""

from __future__ import annotations

import decimal
import math

import numpy as np

# A draw is the same bits on every CPU only if each operation on it is: IEEE's + − × ÷ √ and
# numpy's rint and ldexp are (each correctly rounded or exact, whatever SIMD loop runs, and
# separate ufuncs never fuse into a multiply-add). numpy's array ``**`` and ``exp`` are not:
# they dispatch to SIMD loops that round otherwise (on an AVX-512 CPU ``10.0 ** x`` moved
# about 5 % of the draws by one unit in the last place against the baseline loops), and
# libm's pow and exp pick FMA variants by the CPU too. So ``10**x`` is built here from those
# operations alone, in a fixed order: ``t = x ln 10`` as an unevaluated sum ``t_high + t_low``
# (Dekker's exact product with Veltkamp's split, ln 10 in two doubles); ``t = n ln 2 + r``
# with ``n`` an integer and ``|r| ≤ ½ ln 2 + ε`` (Cody and Waite: ``n LN2_HIGH`` is exact,
# LN2_HIGH having 11 trailing zero bits and ``|n| < 2¹¹``); ``e^r`` by its Taylor polynomial
# to degree 17 (the remainder ``(½ ln 2)¹⁸/18! < 4e-24``, far below u), by Horner; then
# ``ldexp(·, n)``, exact. The draw is a fixed function of the uniform variate, the same bits
# everywhere, within a few u of the true ``10**x`` (tests/scene/test_random_problems.py).
_DIGITS = decimal.Context(prec=60)
#: ln 10 as a double and the double nearest the rest (Decimal's logarithm: exact software
#: arithmetic, the same everywhere), ln 2 split as Cody and Waite's leading 42 bits (so that
#: ``n LN2_HIGH`` is exact) and the double nearest the rest.
LN10_HIGH = float(_DIGITS.ln(decimal.Decimal(10)))
LN10_LOW = float(_DIGITS.subtract(_DIGITS.ln(decimal.Decimal(10)), decimal.Decimal(LN10_HIGH)))
LN2_HIGH = math.ldexp(math.floor(math.ldexp(float(_DIGITS.ln(decimal.Decimal(2))), 42)), -42)
LN2_LOW = float(_DIGITS.subtract(_DIGITS.ln(decimal.Decimal(2)), decimal.Decimal(LN2_HIGH)))
#: 1/k! for k = 0 … 17, each rounded once (math.factorial is an exact integer).
TAYLOR = tuple(1.0 / math.factorial(k) for k in range(18))
#: Veltkamp's splitter 2²⁷ + 1: ``a`` into two halves of 26 bits whose products are exact.
_SPLITTER = 134217729.0


def _split(a):
    c = _SPLITTER * a
    high = c - (c - a)
    return high, a - high


def power_of_ten(exponent) -> np.ndarray:
    """``10**exponent`` elementwise for ``|exponent| ≤ 300``, from IEEE operations only (the
    comment above): the same bits on every CPU, unlike numpy's ``10.0 ** exponent``."""
    exponent = np.asarray(exponent, dtype=float)
    scaled = exponent * LN10_HIGH
    x_high, x_low = _split(exponent)
    ln_high, ln_low = _split(LN10_HIGH)
    product_error = (((x_high * ln_high - scaled) + x_high * ln_low + x_low * ln_high)
                     + x_low * ln_low)  # Dekker: scaled + product_error = x LN10_HIGH
    scaled_low = product_error + exponent * LN10_LOW
    n = np.rint(scaled / LN2_HIGH)
    reduced = ((scaled - n * LN2_HIGH) + scaled_low) - n * LN2_LOW
    polynomial = np.full_like(reduced, TAYLOR[-1])
    for coefficient in TAYLOR[-2::-1]:
        polynomial = polynomial * reduced + coefficient
    return np.ldexp(polynomial, n.astype(np.int64))


def random_problems(count: int, seed: int, min_conditioning: float = 1e-3) -> dict:
    """``count`` problems as arrays ``mnn, mnt, mtt, vn, vt, mu, e``.

    ``min_conditioning`` bounds ``Δ/(m_nn m_tt) = 1 − ρ²`` from below, ρ being the
    correlation ``m_nt/√(m_nn m_tt)``: it keeps the problems away from singular ``M``,
    where any method's rounding error grows like 1/Δ.
    """
    rng = np.random.default_rng(seed)
    mnn = power_of_ten(rng.uniform(-1, 1, count))
    mtt = power_of_ten(rng.uniform(-1, 1, count))
    rho_max = np.sqrt(1.0 - min_conditioning)
    mnt = rng.uniform(-rho_max, rho_max, count) * np.sqrt(mnn * mtt)
    mnt[rng.random(count) < 0.03] = 0.0
    vn = -power_of_ten(rng.uniform(-1, 1, count))
    # numpy's normal (a ziggurat) calls libm's exp and log only to accept a wedge or tail
    # draw, a comparison a one-ulp difference flips with probability ~2⁻⁵² per such draw.
    vt = rng.normal(0.0, 1.0, count) * power_of_ten(rng.uniform(-1.5, 1, count))
    vt[rng.random(count) < 0.05] = 0.0
    mu = rng.uniform(0.0, 2.0, count)
    mu[rng.random(count) < 0.05] = 0.0
    e = rng.uniform(0.0, 1.0, count)
    special = rng.random(count)
    e[special < 0.05] = 0.0
    e[special > 0.95] = 1.0
    return dict(mnn=mnn, mnt=mnt, mtt=mtt, vn=vn, vt=vt, mu=mu, e=e)


def row(problems: dict, index: int) -> dict:
    return {name: float(values[index]) for name, values in problems.items()}
