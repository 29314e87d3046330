"""Departures in percent in one style (harness/run/metrics.py): decimals down to a stated
cut-off, scientific notation only below it, and a quantile with its interval written alike."""

from __future__ import annotations

import math

from harness.run.metrics import (
    SCIENTIFIC_BELOW_PERCENT,
    SHARED_SCIENTIFIC_BELOW_PERCENT,
    fmt_departure,
    fmt_departures,
)


def scientific(text: str) -> bool:
    return "e" in text


def test_decimals_down_to_the_cut_off_and_scientific_only_below_it():
    # between the cut-off and 0.01% a departure was written 8e-03% beside 0.0118%
    assert fmt_departure(8.12e-5) == "0.00812%" and fmt_departure(1.18e-4) == "0.0118%"
    at_cut_off = SCIENTIFIC_BELOW_PERCENT / 100
    assert not scientific(fmt_departure(at_cut_off))
    assert not scientific(fmt_departure(0.99996 * at_cut_off))  # rounds to the cut-off
    assert scientific(fmt_departure(0.5 * at_cut_off))
    # zero and agreement to round-off read as before
    assert fmt_departure(0.0) == "0%" and fmt_departure(3e-14) == "3e-12%"
    assert fmt_departure(math.nan) == "n/a" and fmt_departure(None) == "n/a"


def test_a_quantile_and_its_interval_share_one_style():
    small = SCIENTIFIC_BELOW_PERCENT / 100
    # all below the shared limit, the low end below the cut-off: all three scientific
    median, low, high = fmt_departures([12 * small, 0.1 * small, 93 * small])
    assert all(scientific(text) for text in (median, low, high))
    assert median == "1.2e-02%" and low == "1e-04%"
    # all at or above the cut-off: all decimals, as fmt_departure writes each
    values = [12 * small, 8 * small, 93 * small]
    assert fmt_departures(values) == [fmt_departure(v) for v in values]
    assert not any(scientific(text) for text in fmt_departures(values))
    # an interval reaching the shared limit keeps each number readable (never 1.61e+00%)
    wide = [0.0228 / 100, 2e-7, 1.2 * SHARED_SCIENTIFIC_BELOW_PERCENT / 100]
    assert fmt_departures(wide) == [fmt_departure(v) for v in wide]
    # zero and a missing bound stay as they are
    assert fmt_departures([0.0, 0.1 * small, math.nan])[::2] == ["0%", "n/a"]


def test_the_band_just_below_the_cut_off_is_written_at_it_or_in_scientific_notation():
    """Below the cut-off a value is scientific, unless its one digit rounds up to the cut-off:
    then it is the cut-off itself (never 0.000995%, a decimal below the stated cut-off)."""
    cut_off = SCIENTIFIC_BELOW_PERCENT / 100
    assert fmt_departure(0.995 * cut_off) == "0.001%"
    assert fmt_departure(0.9 * cut_off) == "9e-04%"
    for factor in (0.9, 0.949, 0.95, 0.995, 0.99996):
        text = fmt_departure(factor * cut_off)
        assert scientific(text) or text == "0.001%", (factor, text)


def test_an_interval_just_below_the_shared_limit_as_written_is_never_1e00():
    limit = SHARED_SCIENTIFIC_BELOW_PERCENT / 100
    texts = fmt_departures([1e-9, 0.995 * limit, 0.99999 * limit])
    assert not any("e+00" in text for text in texts), texts
