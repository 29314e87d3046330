"""The survey's figures' tick labels (harness/survey/outputs.py)."""

from __future__ import annotations

import pytest

from harness.survey import outputs


@pytest.mark.parametrize(("value", "label"), [
    (0.001, "1e-03"), (0.01, "0.01"), (0.1, "0.1"), (1.0, "1"), (100.0, "100"),
    (1000.0, "1000"), (1e4, "1e+04")])
def test_the_maps_ratio_axis_reads_as_decimals_where_short(value, label):
    assert outputs._decade_label(value) == label


def _ranks_from_top(phrase: str) -> set[int]:
    """The ranks from the top a :func:`outputs.p90_runs` phrase names (1 the largest)."""
    import re

    ranks = {int(number) for number in re.findall(r"(\d+)(?:st|nd|rd|th)", phrase)}
    return ranks | ({1} if phrase.endswith("the largest") or phrase == "the only run" else set())


@pytest.mark.parametrize("count", [*range(1, 45), 111, 2000])
def test_the_p90_phrase_names_the_runs_numpys_p90_lies_at_or_between(count):
    import numpy as np

    values = np.arange(count, dtype=float)  # value = rank from the bottom, 0 the smallest
    p90 = float(np.quantile(values, 0.9))
    ranks = _ranks_from_top(outputs.p90_runs(count))
    touching = {count - int(np.floor(p90 + 1e-9)), count - int(np.ceil(p90 - 1e-9))}
    assert ranks == touching


def test_the_p90_note_follows_the_tables_run_counts():
    stats = {"engine": ["a", "a", "a"], "poisson_type": [0, 1, 5], "n": [40, 12, 1],
             "n_ok": [38, 12, 1]}
    every = outputs.p90_note(stats, "all")
    assert "38 to 40 runs" in every and outputs.p90_runs(40) in every
    assert "20" not in every
    each = outputs.p90_note(stats, "each")
    assert "1 to 12 runs" in each and "the only run" in each and outputs.p90_runs(12) in each
    assert outputs.p90_note({"engine": ["a"], "poisson_type": [0], "n": [20], "n_ok": [20]},
                            "all") == f"Every p90 here is of 20 runs: {outputs.p90_runs(20)}."
