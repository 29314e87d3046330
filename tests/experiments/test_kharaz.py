"""The Kharaz et al. (2001) disk: the laws' curves against the rigid-body closed forms."""

from __future__ import annotations

import numpy as np
import pytest

import planar_impact as pi
from harness.experiments import kharaz

ANGLES = np.arange(5.0, 86.0, 2.5)


@pytest.mark.parametrize("law", pi.LAWS)
def test_curves_follow_the_rolling_and_sliding_closed_forms(law):
    """Sliding throughout: Δv_x = −μ(1+e)v_n, ω' = 5/2 μ(1+e) v_n / r (I = 2/5 m r²);
    rolling at separation: v_x' = 5/7 v_x, ω' = v_x'/r. m_nt = 0, so every law agrees."""
    curves = kharaz.curves(law, ANGLES)
    assert np.all(curves.status == 0)
    theta = np.radians(ANGLES)
    vn, vt = kharaz.SPEED * np.cos(theta), kharaz.SPEED * np.sin(theta)
    impulse = kharaz.MU * (1 + kharaz.E) * vn  # tangential speed the sliding friction removes
    sliding = 3.5 * impulse < vt  # the slip falls by 7/2 of the centre's change
    expected_et = np.where(sliding, 1 - impulse / vt, 5 / 7)
    expected_spin = np.where(sliding, 2.5 * impulse, 2 / 7 * vt * 2.5) / kharaz.RADIUS
    np.testing.assert_allclose(curves.tangential_restitution, expected_et, rtol=1e-12)
    np.testing.assert_allclose(curves.spin, expected_spin, rtol=1e-10)
    rebound = np.degrees(np.arctan2(expected_et * vt, kharaz.E * vn))
    np.testing.assert_allclose(curves.rebound_deg, rebound, rtol=1e-10)
    limit = kharaz.sticking_limit_deg()
    assert np.all(sliding == (ANGLES > limit))


def test_the_cited_digitisation_agrees_with_the_second_one():
    """Two digitisations of the same figures (kharaz.SOURCE, kharaz.CROSS_CHECK_SOURCE),
    point by point: a slip in copying either table shows here. The bounds are the reading of
    a figure: a quarter of a degree along the incidence axis, and on the values about the
    width of a marker."""
    bounds = {"tangential_restitution": 0.002, "rebound_deg": 0.25, "spin": 2.0}
    gaps = kharaz.digitisation_gaps()
    for quantity in kharaz.QUANTITIES:
        first, second = kharaz.MEASURED[quantity], kharaz.CROSS_CHECK[quantity]
        assert first.quantity == second.quantity == quantity
        assert len(first.incidence_deg) == len(first.values) == len(second.values)
        assert list(first.incidence_deg) == sorted(first.incidence_deg)
        assert 0 <= first.incidence_deg[0] and first.incidence_deg[-1] < 90
        incidence_gap, value_gap = gaps[quantity]
        assert incidence_gap <= 0.25 and value_gap <= bounds[quantity], quantity


def test_every_quantity_has_a_cited_source():
    assert "write_usr0.f" in kharaz.SOURCE and "aa5da90" in kharaz.SOURCE
    assert "lethe" in kharaz.CROSS_CHECK_SOURCE and "255b519" in kharaz.CROSS_CHECK_SOURCE
    assert set(kharaz.MEASURED) == set(kharaz.CROSS_CHECK) == set(kharaz.QUANTITIES)
