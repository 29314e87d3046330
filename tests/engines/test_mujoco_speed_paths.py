"""MuJoCo: the adapter's shortcuts give what the plain computations give, bit for bit."""

from __future__ import annotations

import math
import random

import pytest

pytest.importorskip("mujoco", reason="mujoco not installed (pip install mujoco==4.0.0)")

from harness.engines.mujoco_engine import (  # noqa: E402
    MIN_RESTITUTION,
    _bisect_damping_ratio,
    _sure_bracket,
    damping_ratio_for_restitution,
    restitution_of_damping_ratio,
)


def _restitutions(count: int) -> list[float]:
    """Uniform and log-uniform restitutions over [MIN_RESTITUTION, 1), some just below 1,
    and the ends and the critical point (ζ = 1)."""
    rng = random.Random(12)
    values = [rng.uniform(MIN_RESTITUTION, 1.0) for _ in range(count)]
    values += [10.0 ** rng.uniform(math.log10(MIN_RESTITUTION), 0.0) for _ in range(count)]
    values += [1.0 - 10.0 ** rng.uniform(-15.0, -1.0) for _ in range(count // 4)]
    values += [MIN_RESTITUTION, math.nextafter(MIN_RESTITUTION, 1.0), math.exp(-2.0),
               math.nextafter(math.exp(-2.0), 0.0), 0.5, math.nextafter(1.0, 0.0)]
    return values


def test_damping_ratio_shortcut_matches_the_full_bisection():
    for e in _restitutions(1500):
        assert damping_ratio_for_restitution(e) == _bisect_damping_ratio(e), e


@pytest.mark.parametrize("e", [MIN_RESTITUTION, 0.004, 0.05, math.exp(-2.0), 0.3, 0.7, 0.95,
                               0.999])
def test_sure_bracket_brackets_the_root_and_sides_hold(e):
    below, above = _sure_bracket(e)
    assert 0.0 < below < above < math.inf  # made sure (no fallback) at these e
    root = _bisect_damping_ratio(e)
    assert below < root < above
    # What the bisection takes for granted outside the bracket, checked on points near it.
    for step in range(1, 200):
        assert restitution_of_damping_ratio(below * (1.0 - 1e-9 * step)) > e
        assert restitution_of_damping_ratio(above * (1.0 + 1e-9 * step)) <= e
