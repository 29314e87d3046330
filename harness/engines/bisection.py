"""Inverting a decreasing map of a soft contact's dissipation to its restitution, shared by
the engines that match ``e`` through a damping knob (MuJoCo's solref damping ratio, Drake's
Hunt–Crossley dissipation)."""
from __future__ import annotations

from collections.abc import Callable


def decreasing_inverse(function: Callable[[float], float], target: float) -> float:
    """The ``x >= 0`` where ``function`` (decreasing from ``function(0) >= target``) falls to
    ``target``: the bracket ``[0, 1]`` doubled until it holds the root, then bisected to
    rounding (relative 1e-15 of the bracket's top, at most 200 halvings)."""
    low, high = 0.0, 1.0
    while function(high) > target:
        high *= 2.0
    for _ in range(200):
        middle = 0.5 * (low + high)
        if function(middle) > target:
            low = middle
        else:
            high = middle
        if high - low <= 1e-15 * high:
            break
    return 0.5 * (low + high)
