"""A verdict check whose value sits within its rounding band of the bound is named as at the
boundary (a remark, never a failure), whichever way the last bit decides it."""

from __future__ import annotations

import math

from harness.run import verdicts
from harness.run.verdicts import checks


def test_a_value_on_its_bound_is_remarked_with_both_outcomes():
    bound = 1e-3
    for value in (bound, math.nextafter(bound, 0.0), math.nextafter(bound, 1.0)):
        (remark,) = checks.boundary_remarks("penetration", value, bound, "deepest overlap", "m")
        assert remark.name == "at-boundary" and not remark.fails
        assert "passes | fails penetration" in remark.detail


def test_a_value_outside_the_band_gets_no_remark():
    assert checks.boundary_remarks("penetration", 1e-3 * (1 + 1e-6), 1e-3, "overlap", "m") == []
    assert checks.boundary_remarks("energy-gain", math.nan, 1.0, "ΔE", "J") == []


def test_a_remark_is_not_a_reason_and_does_not_flag_the_run():
    remark = checks.boundary_remarks("energy-gain", 2e-6, 2e-6, "ΔE", "J")
    verdict = verdicts.Verdict(tuple(remark))
    assert verdict.single_impact and verdict.names == ()
    assert "at-boundary" not in verdicts.REASONS and "at-boundary" in verdicts.REMARKS
