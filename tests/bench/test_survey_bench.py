"""``impact-harness bench --survey``: both sides measured on the same impacts."""

from __future__ import annotations

import pytest

from harness.bench import survey as bench_survey


def test_survey_bench_times_the_survey_and_the_bare_stepping_of_its_impacts():
    pytest.importorskip("pymunk")
    report = bench_survey.run(3, engines=("pymunk",))
    assert report["impacts"] == 3 * 7  # every population
    assert set(report["bare"]) == {"pymunk.defaults", "pymunk.accurate"}
    assert report["bare_s"] == pytest.approx(sum(report["bare"].values()))
    assert 0 < report["bare_s"] and 0 < report["survey_s"]
    assert report["ratio"] == pytest.approx(report["survey_s"] / report["bare_s"])
    assert report["ratio_cores"] == pytest.approx(report["survey_cores_s"] / report["bare_s"])
    assert "engine pymunk accurate" in report["stages"]
    text = bench_survey.format_report(report)
    assert "ratio" in text and "pymunk.accurate" in text
