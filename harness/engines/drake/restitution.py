"""The map between Drake's Hunt–Crossley dissipation and restitution (``e <-> d·v``).

Drake's point contact pushes with ``f = k·x·(1 + d·ẋ)`` (``x`` the penetration, ``ẋ`` its
rate, clamped at 0: it cannot pull). For one degree of freedom of mass ``m`` the energy-like
integral of ``m·ẋ·dẋ/dx = -k·x·(1 + d·ẋ)`` from first touch (``ẋ = v``) to separation
(``ẋ = -e·v``) gives, with ``a = d·v``,

    a - ln(1 + a) = -e·a - ln(1 - e·a)

which ties ``e`` to ``a = d·v`` alone, neither ``k`` nor ``m`` (the linear spring of Hunt
and Crossley 1975, integrated as Marhefka and Orin 1999 do). ``e → 1 - 2a/3`` for small ``a``,
``e → 1/a`` for large ``a``. So ``d = a(e) / v``: the dissipation that gives the scene's ``e``
depends on its normal approach speed ``v`` (one value per run).

Drake's discrete contact (SAP's ``similar`` and ``lagged`` approximations, and TAMSI within
1e-5 on the drops measured) is implicit: on one degree of freedom it is backward Euler on
that law (``m·(u₁ - u₀) = -h·k·x₁·(1 + d·u₁)``,
``x₁ = x₀ + h·u₁``; :func:`discrete_restitution` reproduces Drake's measured bounces to
their printed digits), which removes energy of its own: with ``d = 0`` over a contact of
``N = π/(ω·h)`` steps the bounce keeps ``exp(-π²/(2N))`` (0.9877 at N = 400). Dimensionless,
the recurrence depends on ``a`` and ``N`` alone; :func:`discrete_dissipation` inverts it, so
that the discrete bounce of a central drop is ``e`` exactly wherever ``e`` is reachable
(``e <= exp(-π²/(2N))`` roughly; above it ``a = 0`` and the bounce falls short).
"""
from __future__ import annotations

import functools
import math

from harness.engines.bisection import decreasing_inverse

# Smallest restitution asked of the Hunt–Crossley contact: e = 0 needs d = ∞ (a = ∞).
MIN_RESTITUTION = 1e-3


def restitution_of_dissipation(a: float) -> float:
    """Restitution of the linear Hunt–Crossley contact at ``a = d·v`` (``a >= 0``):
    the root ``b = e·a`` in ``[0, 1)`` of ``-b - ln(1 - b) = a - ln(1 + a)``, by bisection."""
    a = float(a)
    if not a >= 0.0 or not math.isfinite(a):
        raise ValueError(f"d·v must be finite and >= 0, got {a}")
    if a == 0.0:
        return 1.0
    target = a - math.log1p(a)
    # In L = ln(1 - b) (b near 1 for large a is lost to rounding): g = e^L - 1 - L falls
    # from ∞ to 0 on (-∞, 0], and g(-(target + 1)) > target.
    low, high = -(target + 1.0), 0.0
    for _ in range(200):
        middle = 0.5 * (low + high)
        if math.expm1(middle) - middle > target:
            low = middle
        else:
            high = middle
        if high - low <= 1e-16 * max(1.0, -low):
            break
    return -math.expm1(0.5 * (low + high)) / a


@functools.lru_cache(maxsize=256)
def dissipation_for_restitution(restitution: float) -> float:
    """``a = d·v`` giving restitution ``e`` (inverse of :func:`restitution_of_dissipation`;
    ``e`` clamped to ``[MIN_RESTITUTION, 1]``)."""
    e = min(max(float(restitution), MIN_RESTITUTION), 1.0)
    if e == 1.0:
        return 0.0
    return decreasing_inverse(restitution_of_dissipation, e)


def discrete_restitution(a: float, contact_steps: float) -> float:
    """The bounce of Drake's discrete Hunt–Crossley contact on one degree of freedom:
    backward Euler (SAP's step) on ``x'' = -ω²·x·(1 + a·x'/v)`` from ``x = 0``, ``x' = v``
    with ``ω·h = π / contact_steps``, until the penetration is gone; the exit speed over
    ``v``. In units of ``v`` and ``h`` (``x`` in ``v·h``, ``u`` in ``v``)."""
    wh2 = (math.pi / float(contact_steps)) ** 2  # (ω·h)², the spring's step stiffness
    a = float(a)
    x, u = 0.0, 1.0
    for _ in range(1_000_000):
        # (u₁ - u) = -wh2·(x + u₁)·(1 + a·u₁) with the force >= 0: a quadratic in u₁
        quadratic, linear, constant = wh2 * a, 1.0 + wh2 * (1.0 + a * x), wh2 * x - u
        if quadratic > 0.0:
            u_next = 2.0 * -constant / (linear + math.sqrt(linear * linear
                                                           - 4.0 * quadratic * constant))
        else:
            u_next = -constant / linear
        if x + u_next <= 0.0 or 1.0 + a * u_next <= 0.0:  # the contact cannot pull
            u_next = u
        x, u = x + u_next, u_next
        if x <= 0.0:
            return -u
    raise ArithmeticError(f"no separation within 1e6 steps (a = {a}, N = {contact_steps})")


@functools.lru_cache(maxsize=4096)
def discrete_dissipation(restitution: float, contact_steps: float) -> float:
    """``a = d·v`` whose discrete bounce (:func:`discrete_restitution`) is ``e``; 0 where
    even ``a = 0`` falls short of ``e`` (the implicit step's own loss). Regula falsi
    (Illinois) between 0 and the continuous law's ``a``, which falls short too."""
    e = min(max(float(restitution), MIN_RESTITUTION), 1.0)
    low, high = 0.0, dissipation_for_restitution(e)
    f_low = discrete_restitution(low, contact_steps) - e
    if f_low <= 0.0:
        return 0.0
    f_high = discrete_restitution(high, contact_steps) - e
    side = 0
    for _ in range(100):
        if f_high >= 0.0 or high - low <= 1e-12 * high:
            break
        middle = (low * f_high - high * f_low) / (f_high - f_low)
        f_middle = discrete_restitution(middle, contact_steps) - e
        if abs(f_middle) <= 1e-12:
            return middle
        if f_middle > 0.0:
            low, f_low = middle, f_middle
            if side == 1:
                f_high *= 0.5
            side = 1
        else:
            high, f_high = middle, f_middle
            if side == -1:
                f_low *= 0.5
            side = -1
    return high if f_high >= 0.0 else (low + high) / 2
