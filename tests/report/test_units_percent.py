"""Departures in percent in one style (harness/run/metrics.py): decimals down to a stated
cut-off, scientific notation only below it, each number alike wherever it stands (a quantile
beside its interval too)."""

from __future__ import annotations

import math

from harness.run.metrics import (
    SCIENTIFIC_BELOW_PERCENT,
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


def test_a_quantile_and_its_interval_are_each_written_as_alone():
    """A row once wrote a median 1.19e-02% [5e-09%, 9.31e-02%] beside the same median alone,
    0.0119%: each number is written as fmt_departure writes it, wherever it stands."""
    small = SCIENTIFIC_BELOW_PERCENT / 100
    values = [11.9 * small, 5e-11, 93.1 * small]
    assert fmt_departures(values) == ["0.0119%", "5e-09%", "0.0931%"]
    assert fmt_departures(values)[0] == fmt_departure(values[0])
    # zero and a missing bound stay as they are
    assert fmt_departures([0.0, 0.1 * small, math.nan]) == ["0%", "1e-04%", "n/a"]


def test_the_band_just_below_the_cut_off_is_written_at_it_or_in_scientific_notation():
    """Below the cut-off a value is scientific, unless its one digit rounds up to the cut-off:
    then it is the cut-off itself (never 0.000995%, a decimal below the stated cut-off)."""
    cut_off = SCIENTIFIC_BELOW_PERCENT / 100
    assert fmt_departure(0.995 * cut_off) == "0.001%"
    assert fmt_departure(0.9 * cut_off) == "9e-04%"
    for factor in (0.9, 0.949, 0.95, 0.995, 0.99996):
        text = fmt_departure(factor * cut_off)
        assert scientific(text) or text == "0.001%", (factor, text)
