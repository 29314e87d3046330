"""The map between MuJoCo's contact damping and restitution (``e <-> ζ``).

MuJoCo has no restitution coefficient: its contact is a unilateral spring-damper whose
bounce follows from the damping ratio alone (package docstring). These functions give the
restitution of a damping ratio, its inverse, and the direct ``solref`` that gives ``e`` over
a chosen number of steps; the ``matched-bounce`` preset uses them.
"""

from __future__ import annotations

import functools
import math

from harness.engines.bisection import decreasing_inverse

# Smallest restitution the unilateral spring-damper is asked for: e = 0 needs ζ = ∞.
MIN_RESTITUTION = 1e-3


# ---------------------------------------------------------------------- e <-> ζ
def contact_time_factor(damping_ratio: float) -> float:
    """``ω₀·T``: duration ``T`` of a unilateral spring-damper contact times its ``ω₀ = sqrt(k)``.

    The penetration obeys ``r'' + 2ζω₀ r' + ω₀² r = 0`` from ``r = 0, r' = v₀`` until the
    contact force ``2ζω₀ r' + ω₀² r`` returns to 0 (it cannot pull).
    """
    zeta = float(damping_ratio)
    if zeta < 0:
        raise ValueError(f"damping ratio must be >= 0, got {zeta}")
    if zeta == 0.0:
        return math.pi
    if zeta < 1.0:
        s = math.sqrt(1.0 - zeta * zeta)
        return math.atan2(2.0 * zeta * s, -(1.0 - 2.0 * zeta * zeta)) / s
    if zeta == 1.0:
        return 2.0
    sigma = math.sqrt(zeta * zeta - 1.0)
    return math.atanh(2.0 * zeta * sigma / (2.0 * zeta * zeta - 1.0)) / sigma


def restitution_of_damping_ratio(damping_ratio: float) -> float:
    """Restitution of the unilateral spring-damper: ``e = exp(-ζ·ω₀T(ζ))``.

    Closed form: in the underdamped case the force vanishes at phase
    ``φ = atan2(2ζs, 2ζ² - 1)`` (``s = sqrt(1 - ζ²)``), where the exit speed is
    ``v₀·exp(-ζφ/s)``; the overdamped branch is its analytic continuation.
    ``e(0.2553) = 0.5``, ``e(1) = exp(-2)``, ``e → 1/(4ζ²)`` for large ``ζ``.
    """
    zeta = float(damping_ratio)
    return math.exp(-zeta * contact_time_factor(zeta))


def damping_ratio_for_restitution(restitution: float) -> float:
    """Inverse of :func:`restitution_of_damping_ratio` (bisection to rounding).

    ``e`` is clamped to ``[MIN_RESTITUTION, 1]``: ``e = 0`` would need ``ζ = ∞``.
    """
    e = min(max(float(restitution), MIN_RESTITUTION), 1.0)
    if e == 1.0:
        return 0.0
    return decreasing_inverse(restitution_of_damping_ratio, e)


def restitution_solref(
    restitution: float, time_step: float, contact_steps: float
) -> tuple[float, float, float]:
    """Direct ``solref = (-k, -b)`` giving restitution ``e`` over ``contact_steps`` steps.

    Returns ``(-k, -b, ζ)``. With ``d`` the (flat) impedance MuJoCo's constraint space follows
    ``r'' = -b r' - k r`` (its ``K = k/d²``, ``B = b/d`` are scaled back by ``d``).
    """
    zeta = damping_ratio_for_restitution(restitution)
    omega = contact_time_factor(zeta) / (contact_steps * time_step)
    return (-omega * omega, -2.0 * zeta * omega, zeta)



# Per-run constants computed once: the solve for ζ is a root search, pure in its arguments.
@functools.lru_cache(maxsize=256)
def _restitution_terms(restitution: float, time_step: float, contact_steps: float) -> tuple:
    """``(solref, ζ, restitution of ζ)`` of :func:`restitution_solref`."""
    stiffness, damping, zeta = restitution_solref(restitution, time_step, contact_steps)
    return [stiffness, damping], zeta, restitution_of_damping_ratio(zeta)
