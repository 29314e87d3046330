"""The survey's figures' tick labels (harness/survey/outputs.py)."""

from __future__ import annotations

import pytest

from harness.survey import outputs


@pytest.mark.parametrize(("value", "label"), [
    (0.001, "1e-03"), (0.01, "0.01"), (0.1, "0.1"), (1.0, "1"), (100.0, "100"),
    (1000.0, "1000"), (1e4, "1e+04")])
def test_the_maps_ratio_axis_reads_as_decimals_where_short(value, label):
    assert outputs._decade_label(value) == label
